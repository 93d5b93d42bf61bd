"""One run of one model on a scene, as a Trajectory: the FMU by model exchange or co-simulation
(fmu), the Moreau stepper and its batches (moreau, moreau_batch), the paper's RK4 scheme (rk4),
and one entry point for every model (simulate)."""
