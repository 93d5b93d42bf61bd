"""The result of a linearization: A, B, C, D at one operating point, its eigenvalues and modes."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .equilibrium import Equilibrium
from .jacobian import INPUTS, OUTPUTS, STATES, Jacobians
from .modes import Mode


@dataclass(frozen=True)
class Linearization:
    """A, B, C, D at one operating point, with its eigenvalues and oscillatory modes."""

    scene: str
    model: str
    at: str  # "start", "equilibrium" or "t = T s"
    jacobian: str  # the source's name
    jacobians: Jacobians
    operating_point: np.ndarray  # the states
    input_values: np.ndarray
    state_derivatives: np.ndarray  # dx/dt at the point (zero at an equilibrium)
    in_contact: bool
    eigenvalues: np.ndarray
    modes: list[Mode]
    equilibrium: Equilibrium | None = None
    time: float = 0.0  # s, the FMU's time at the point (that of the run for --at TIME)
    states: tuple[str, ...] = STATES
    inputs: tuple[str, ...] = INPUTS
    outputs: tuple[str, ...] = OUTPUTS

    @property
    def A(self) -> np.ndarray:
        return self.jacobians.A

    @property
    def B(self) -> np.ndarray:
        return self.jacobians.B

    @property
    def C(self) -> np.ndarray:
        return self.jacobians.C

    @property
    def D(self) -> np.ndarray:
        return self.jacobians.D

    @property
    def frequencies_hz(self) -> list[float]:
        return [m.frequency_hz for m in self.modes]

    @property
    def damping_ratios(self) -> list[float]:
        return [m.damping_ratio for m in self.modes]

    def to_json(self) -> dict[str, Any]:
        """The content of linearization.json (its keys in docs/guide/linearize.md)."""
        return {
            "scene": self.scene,
            "model": self.model,
            "at": self.at,
            "time": self.time,
            "jacobian": self.jacobian,
            "contact_mode": "contact" if self.in_contact else "flight",
            "states": list(self.states),
            "inputs": list(self.inputs),
            "outputs": list(self.outputs),
            "operating_point": self.operating_point.tolist(),
            "input_values": self.input_values.tolist(),
            "state_derivatives": self.state_derivatives.tolist(),
            "A": self.A.tolist(),
            "B": self.B.tolist(),
            "C": self.C.tolist(),
            "D": self.D.tolist(),
            "eigenvalues": [[float(z.real), float(z.imag)] for z in self.eigenvalues],
            "frequencies_hz": self.frequencies_hz,
            "damped_frequencies_hz": [m.damped_frequency_hz for m in self.modes],
            "damping_ratios": self.damping_ratios,
            "equilibrium": self.equilibrium.summary() if self.equilibrium else None,
        }
