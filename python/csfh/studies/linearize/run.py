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
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import ParameterError, SimulationError
from ...model import model_info
from ...model._csfh_variables import MAX_STOP_TIME
from ...model.scene import Scene, load_scene
from .equilibrium import Equilibrium, static_equilibrium
from .jacobian import INPUTS, STATES, Plant, check_names, source
from .modes import eigenvalues, oscillatory_modes
from .result import Linearization

AT_NAMES = ("start", "equilibrium")


def parse_at(at: str | float, what: str = "at") -> str | float:
    """ "start", "equilibrium" or a time in s (>= 0, at most MAX_STOP_TIME); ParameterError
    naming `what` and the value otherwise."""
    if isinstance(at, str) and at in AT_NAMES:
        return at
    try:
        t = float(at)
    except (TypeError, ValueError):
        t = math.nan
    if isinstance(at, bool) or not (0.0 <= t <= MAX_STOP_TIME):
        raise ParameterError(
            f"{what} = {at!r} must be start, equilibrium or a time in s in [0, {MAX_STOP_TIME:g}]"
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


def _triple(q: np.ndarray) -> tuple[float, float, float]:
    return (float(q[0]), float(q[1]), float(q[2]))


def _plant_at(scene: Scene, law: str, parameters: dict[str, Any] | None) -> Any:
    """q -> a context manager of a plant started at rest at q (for the equilibrium solve)."""
    from ...runners.model_exchange import instance_at

    @contextmanager
    def plant_at(q: np.ndarray) -> Iterator[Plant]:
        at_q = replace(scene, q0=_triple(q), u0=(0.0, 0.0, 0.0))
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
    out: str | Path | None = None,
    input: str = "F_ext[2]",
    output: str = "body1.y",
) -> Linearization:
    """The state-space model of `scene` (a Scene, a built-in scene's name or a scene file) with
    contact law `model` (default: the scene's) at `at`: ``"start"`` (the scene's initial
    state), a time in s (the state of a model-exchange run of the scene to that time), or
    ``"equilibrium"`` (the static equilibrium under the scene's constant inputs, from the
    scene's configuration; SimulationError when Newton's method does not converge).
    `jacobian`: ``"fd"`` (finite differences) or ``"directional"`` (the FMU's
    fmi2GetDirectionalDerivative); default: the FMU's where it provides them. `parameters`:
    FMU parameters on top of the scene's. With `out`, writes linearization.json, .npz, .md
    and bode.png (from `input` to `output`) into that directory."""
    from ...runners.model_exchange import instance_at

    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    point = parse_at(at)
    law = law_of(scene, model)
    check_names(input, output)
    src = source(jacobian)
    eq: Equilibrium | None = None
    start = scene
    if point == "equilibrium":
        u = np.array([scene.inputs.get(n, 0.0) for n in INPUTS])
        eq = static_equilibrium(_plant_at(scene, law, parameters), src, np.array(scene.q0), u)
        start = replace(scene, q0=_triple(eq.q), u0=(0.0, 0.0, 0.0))
    time = point if isinstance(point, float) else 0.0
    with instance_at(start, law, time, parameters=parameters) as fmu:
        plant = Plant(fmu)
        jac = src.jacobians(plant, plant.x, plant.u)
        xdot = plant.evaluate(plant.x, plant.u)[: len(STATES)]
        contact = plant.in_contact()
    if not all(np.all(np.isfinite(M)) for M in (jac.A, jac.B, jac.C, jac.D)):
        raise SimulationError(f"{scene.name}: the Jacobians at {at!r} are not finite")
    lam = eigenvalues(jac.A)
    lin = Linearization(
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
        modes=oscillatory_modes(lam, jac.A),
        equilibrium=eq,
        time=time,
    )
    if out is not None:
        from .report import write_linearization

        write_linearization(lin, Path(out), input, output)
    return lin
