"""What the model is: the FMUs' interfaces (model_info, actuator, fmus), the presets, the scenes and
their [cosim] section, and the C core of the physics (core, instance). Nothing here runs a
simulation."""
