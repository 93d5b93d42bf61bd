"""Co-simulation of the hinge with the comb-drive actuator: the coupled system and its table
(coupling), the fmpy and libcosim masters, the entry point (run) and the figure."""
