"""`csfh.linearize`: the state-space model of the hinge at an operating point of a scene.

    dx/dt = A dx + B du,   dy = C dx + D du

for the six states x = [q, u] (docs/model.md §0), the inputs F_ext[1], F_ext[2], M_ext,
a_base[1], a_base[2] and the outputs of `jacobian.OUTPUTS`, from the model-exchange FMU in the
contact mode it has at that point (docs/model.md §10.3: the mode is frozen between events, so a
point in contact carries the contact's stiffness and damping, one in flight none of it).

Operating points: the scene's start; the state of a model-exchange run at a time; or the static
equilibrium under the scene's constant inputs (equilibrium.py)."""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import ParameterError
from ...model import model_info
from ...model._csfh_variables import MAX_STOP_TIME
from ...model.scene import Scene, load_scene
from .equilibrium import Equilibrium, static_equilibrium
from .jacobian import INPUTS, OUTPUTS, STATES, Jacobians, Plant, source
from .modes import Mode, eigenvalues, oscillatory_modes

AT_NAMES = ("start", "equilibrium")


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


def parse_at(at: str | float) -> str | float:
    """"start", "equilibrium" or a time in s (>= 0, at most MAX_STOP_TIME); ParameterError
    naming the value otherwise."""
    if isinstance(at, str) and at in AT_NAMES:
        return at
    try:
        t = float(at)
    except (TypeError, ValueError):
        t = math.nan
    if isinstance(at, bool) or not (0.0 <= t <= MAX_STOP_TIME):
        raise ParameterError(
            f"at = {at!r} must be start, equilibrium or a time in s in [0, {MAX_STOP_TIME:g}]"
        )
    return t


def law_of(scene: Scene, model: str | None) -> str:
    """The contact law: `model`, else the scene's contact.law (the FMU's start value if the
    scene sets none). ParameterError for Moreau or an unknown law."""
    if model is None:
        values = scene.parameter_values()
        number = values.get("contact.law", model_info.variables()["contact.law"].start)
        names = {v: k for k, v in model_info.enumeration("ContactLaw").items()}
        return names[int(number)]  # type: ignore[arg-type]
    if model not in (*model_info.LAWS, "none"):
        raise ParameterError(
            f"model {model!r} cannot be linearized: one of {', '.join(model_info.LAWS)} or none "
            "(Moreau has no right-hand side)"
        )
    return model


def _plant_at(
    scene: Scene, law: str, parameters: dict[str, Any] | None
) -> Any:
    """q -> a context manager of a plant started at rest at q (for the equilibrium solve)."""
    from ...runners.model_exchange import instance_at

    @contextmanager
    def plant_at(q: np.ndarray) -> Iterator[Plant]:
        at_q = replace(scene, q0=tuple(float(v) for v in q), u0=(0.0, 0.0, 0.0))
        with instance_at(at_q, law, parameters=parameters) as fmu:
            yield Plant(fmu)

    return plant_at


def linearize(
    scene: Scene | str | Path,
    model: str | None = None,
    *,
    at: str | float = "start",
    jacobian: str | None = None,
    parameters: dict[str, Any] | None = None,
) -> Linearization:
    """The state-space model of `scene` (a Scene, a built-in scene's name or a scene file) with
    contact law `model` (default: the scene's) at `at`: ``"start"`` (the scene's initial
    state), a time in s (the state of a model-exchange run of the scene to that time), or
    ``"equilibrium"`` (the static equilibrium under the scene's constant inputs, from the
    scene's configuration; SimulationError when Newton's method does not converge).
    `jacobian`: ``"fd"`` (finite differences) or ``"directional"`` (the FMU's
    fmi2GetDirectionalDerivative); default: the FMU's where it provides them. `parameters`:
    FMU parameters on top of the scene's."""
    from ...runners.model_exchange import instance_at

    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    point = parse_at(at)
    law = law_of(scene, model)
    src = source(jacobian)
    eq: Equilibrium | None = None
    start = scene
    if point == "equilibrium":
        u = np.array([scene.inputs.get(n, 0.0) for n in INPUTS])
        eq = static_equilibrium(_plant_at(scene, law, parameters), src, np.array(scene.q0), u)
        start = replace(scene, q0=tuple(float(v) for v in eq.q), u0=(0.0, 0.0, 0.0))
    time = point if isinstance(point, float) else 0.0
    with instance_at(start, law, time, parameters=parameters) as fmu:
        plant = Plant(fmu)
        jac = src.jacobians(plant, plant.x, plant.u)
        xdot = plant.evaluate(plant.x, plant.u)[: len(STATES)]
        contact = plant.in_contact()
    lam = eigenvalues(jac.A)
    return Linearization(
        scene=scene.name,
        model=law,
        at=point if isinstance(point, str) else f"t = {point:g} s",
        jacobian=src.name,
        jacobians=jac,
        operating_point=plant.x,
        input_values=plant.u,
        state_derivatives=xdot,
        in_contact=contact,
        eigenvalues=lam,
        modes=oscillatory_modes(lam),
        equilibrium=eq,
    )
