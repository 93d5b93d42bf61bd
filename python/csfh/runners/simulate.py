"""One entry point for every model: `simulate(scene, model)`, through the runners' registry."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..errors import SimulationError
from ..model.scene import Scene, load_scene
from ..progress import Progress
from ..trajectory import Trajectory
from .registry import runner_for

INTERFACES = ("me", "cs", "rk4", "core")


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
    exchange with CVODE (``interface="me"``, default: every internal step is recorded, events
    are located by root finding on the gap) or by co-simulation with the FMU's own integrator
    (``"cs"``; ``solver.method``, default ``auto``: RK45, BDF where the motion is stiff), or
    by the paper's RK4 with bisection in the C core (``"rk4"``); ``Moreau`` runs the time
    stepper of the C core whatever the interface (see :func:`moreau`). ``quiet=False`` shows a
    progress bar.

    Options (each defaults to the scene's value):

    * ``stop_time``: s; ``output_interval``: s (co-simulation: the communication step, also
      ``communication_step``); ``parameters``: a dict of FMU parameters applied on top of the
      scene's;
    * ``rtol``: the relative tolerance of the integrator (model exchange, co-simulation);
    * model exchange only: ``output_times`` (an increasing array instead of the grid),
      ``max_step_records`` (how many internal steps to record, default 200 000);
    * RK4: ``h0``, ``tol``; Moreau: the keyword arguments of :func:`moreau`.

    Raises :class:`ParameterError` for an unknown model, interface or option value and
    :class:`SimulationError` when the integration fails."""
    runner = runner_for(model, interface)
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    progress = Progress(f"{scene.name}: {model}", quiet=quiet)
    try:
        return runner.run(scene, model, progress=progress, **options)
    except SimulationError as exc:
        raise with_source(exc, scene) from None
    finally:
        progress.close()


def with_source(exc: Exception, scene: Scene) -> Exception:
    """The same error, its message prefixed with the scene's file (or name), so that a failed
    run says which scene failed."""
    where = scene.source if scene.source and scene.source != "<dict>" else f"scene {scene.name}"
    return type(exc)(f"{where}: {exc}")
