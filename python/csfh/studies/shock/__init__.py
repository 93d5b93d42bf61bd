"""Shock survivability: half-sine pulses of the frame's acceleration (conditions), the study over
directions and models and its Monte Carlo over tolerances (study), and its report (report)."""
