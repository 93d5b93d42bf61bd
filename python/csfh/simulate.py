"""One entry point for every model: `simulate(scene, model)`."""

from __future__ import annotations

from typing import Any

from . import model_info
from .fmu_runner import simulate_cs, simulate_me
from .moreau import moreau
from .progress import Progress
from .results import Trajectory
from .scene import Scene

INTERFACES = ("me", "cs")


def simulate(
    scene: Scene, model: str, *, interface: str = "me", quiet: bool = True, **options: Any
) -> Trajectory:
    """Run `model` on `scene` and return its :class:`Trajectory`.

    `model` is one of the FMU's contact laws (``LN_spheres``, ``LN_cylinders``, ``LN_ESDU``,
    ``HuntCrossley``, ``Flores``) or ``Moreau``. Event-driven laws run through the FMU, by model
    exchange with fmpy's CVode (``interface="me"``, default: every internal step is recorded,
    events are located by root finding on the gap) or by co-simulation with CVODE inside the
    FMU (``"cs"``); ``Moreau`` runs the time stepper of the C core (see :func:`moreau`).
    ``quiet=False`` shows a progress bar.

    Options (each defaults to the scene's value):

    * ``stop_time``: s; ``rtol``: CVODE's relative tolerance (FMU models);
    * ``output_interval`` (model exchange) or ``communication_step`` (co-simulation): s;
    * ``parameters``: a dict of FMU parameters applied on top of the scene's;
    * model exchange only: ``output_times`` (an increasing array instead of the grid),
      ``max_step_records`` (how many internal steps to record, default 200 000);
    * Moreau: the keyword arguments of :func:`moreau`.

    Raises ValueError for an unknown model or interface and :class:`SimulationError` when the
    integration fails."""
    if model not in model_info.MODELS:
        raise ValueError(f"unknown model {model!r} (known: {', '.join(model_info.MODELS)})")
    if interface not in INTERFACES:
        raise ValueError(f"unknown interface {interface!r} (known: {', '.join(INTERFACES)})")
    progress = Progress(f"{scene.name}: {model}", quiet=quiet)
    try:
        if model == "Moreau":
            return moreau(scene, **options)
        if interface == "cs":
            return simulate_cs(scene, model, progress=progress, **options)
        return simulate_me(scene, model, progress=progress, **options)
    finally:
        progress.close()
