"""Linearization of the hinge: the Jacobian sources (jacobian), the static equilibrium
(equilibrium), the modes and the frequency response (modes), the state-space model at an
operating point (run) and its report (report)."""
