"""One run of one model on a scene, as a Trajectory, and many runs at once, behind one protocol
(registry: the runner of each model and interface): the FMU by model exchange (model_exchange,
with cvode) and by co-simulation (co_simulation, on our own instance of the FMU, fmi2_slave, its
loop in C, cs_steps), the batch master (cs_batch), the Moreau stepper and its batches (moreau,
moreau_batch), the paper's RK4 scheme (rk4); what the FMU runs share (fmu), and one entry point
for every model (simulate)."""
