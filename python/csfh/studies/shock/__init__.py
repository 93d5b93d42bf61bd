"""Shock survivability: half-sine pulses of the frame's acceleration (conditions), the study over
directions and models and its Monte Carlo over tolerances (study), and its report (report)."""

DEFAULT_DIRECTIONS = 24
"""Directions of the frame's acceleration of a sweep, evenly over 360 degrees."""
STEP_FACTOR = 10
"""The default communication step of the runs, in the scene's output intervals."""
