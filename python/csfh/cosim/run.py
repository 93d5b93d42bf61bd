"""Co-simulation of the hinge with its comb-drive actuator: the scene's [cosim] settings and the
entry point that runs them in the chosen engine (fmpy master loop or libcosimpy)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import SceneError
from ..model.cosim_section import CosimSettings, parse_cosim
from ..model.limits import check_horizon
from ..model.scene import Scene, load_scene
from ..progress import Progress
from ..runners.simulate import with_source
from ..trajectory import Trajectory
from .coupling import CosimError
from .fmpy_master import run_fmpy
from .libcosim_master import run_libcosimpy


def cosim_settings(scene: Scene, **overrides: Any) -> CosimSettings:
    """The scene's [cosim] settings, with overrides (engine=..., step=..., ordering=...)."""
    if not scene.cosim:
        raise SceneError(f"{scene.source or scene.name}: the scene has no [cosim] section")
    table = dict(scene.cosim)
    table.update({k: v for k, v in overrides.items() if v is not None})
    try:
        return parse_cosim(table, scene.inputs)
    except SceneError as exc:
        raise SceneError(f"{scene.source or scene.name}: {exc}") from None


RUNNERS: dict[str, Callable[..., Trajectory]] = {"fmpy": run_fmpy, "libcosimpy": run_libcosimpy}


def cosimulate(
    scene: Scene | str | Path,
    *,
    engine: str | None = None,
    step: float | None = None,
    ordering: str | None = None,
    stop_time: float | None = None,
    quiet: bool = True,
    voltage_in_fmu: bool = False,
) -> Trajectory:
    """Co-simulate the scene's hinge with its comb-drive actuator, as set up by the scene's
    ``[cosim]`` section (its keys: csfh.model.cosim_section), and return the
    :class:`Trajectory` of the hinge's outputs at the communication points, with the voltage
    ``V`` and the actuator's ``F_act``, ``F_x``, ``F_y``, ``M``. `scene` is a :class:`Scene`, a
    built-in scene's name (``combdrive``) or the path of a scene file.

    `engine` (``"fmpy"`` or ``"libcosimpy"``), `step` (s) and `ordering` (``"jacobi"`` or
    ``"gauss-seidel"``, fmpy only) override the scene's settings, `stop_time` its stop time.
    `voltage_in_fmu`: the actuator FMU evaluates the voltage ramp V(t) itself (its ramp.*
    parameters), as in the scene's SSP export (csfh.cosim.ssp), instead of the master setting
    its input V before each step.
    Raises :class:`SceneError` for bad settings and :class:`CosimError` when an FMU fails."""
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    settings = cosim_settings(scene, engine=engine, step=step, ordering=ordering)
    t_end = scene.stop_time if stop_time is None else stop_time
    where = scene.source or scene.name
    try:
        check_horizon(
            t_end,
            settings.step,
            stop_key="stop_time" if stop_time is None else "stop time",
            interval_key="cosim.step" if step is None else "step",
        )
    except SceneError as exc:
        raise SceneError(f"{where}: {exc}") from None
    progress = Progress(f"{scene.name}: cosim {settings.engine}", quiet=quiet)
    try:
        return RUNNERS[settings.engine](
            scene,
            settings,
            stop_time=stop_time,
            progress=progress,
            voltage_in_fmu=voltage_in_fmu,
        )
    except CosimError as exc:
        raise with_source(exc, scene) from None
    finally:
        progress.close()
