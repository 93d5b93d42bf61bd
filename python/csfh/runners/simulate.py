"""One entry point for every model: `simulate(scene, model)`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..errors import SimulationError
from ..model import model_info
from ..model.scene import Scene, load_scene
from ..progress import Progress
from ..trajectory import Trajectory
from .fmu import simulate_cs, simulate_me
from .moreau import moreau

INTERFACES = ("me", "cs")


def simulate(
    scene: Scene | str | Path,
    model: str,
    *,
    interface: str = "me",
    quiet: bool = True,
    **options: Any,
) -> Trajectory:
    """Run `model` on `scene` and return its :class:`Trajectory`. `scene` is a :class:`Scene`, a
    built-in scene's name or the path of a scene file (see :func:`load_scene`).

    `model` is one of the FMU's contact laws (``LN_spheres``, ``LN_cylinders``, ``LN_ESDU``,
    ``HuntCrossley``, ``Flores``) or ``Moreau``. Event-driven laws run through the FMU, by model
    exchange with fmpy's CVode (``interface="me"``, default: every internal step is recorded,
    events are located by root finding on the gap) or by co-simulation with the FMU's own
    integrator (``"cs"``; ``solver.method``, default ``auto``: RK45, BDF where the motion is
    stiff); ``Moreau`` runs the time stepper of the C core (see :func:`moreau`).
    ``quiet=False`` shows a progress bar.

    Options (each defaults to the scene's value):

    * ``stop_time``: s; ``rtol``: the relative tolerance of the integrator (FMU models);
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
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    progress = Progress(f"{scene.name}: {model}", quiet=quiet)
    try:
        if model == "Moreau":
            return moreau(scene, **options)
        if interface == "cs":
            return simulate_cs(scene, model, progress=progress, **options)
        return simulate_me(scene, model, progress=progress, **options)
    except (SimulationError, FloatingPointError) as exc:
        raise with_source(exc, scene) from None
    finally:
        progress.close()


def with_source(exc: Exception, scene: Scene) -> Exception:
    """The same error, its message prefixed with the scene's file (or name), so that a failed
    run says which scene failed."""
    where = scene.source if scene.source and scene.source != "<dict>" else f"scene {scene.name}"
    return type(exc)(f"{where}: {exc}")
