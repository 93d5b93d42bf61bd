"""Co-simulation of the hinge with its comb-drive actuator: the scene's [cosim] settings and the
entry point that runs them in the chosen engine (fmpy master loop or libcosimpy)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..errors import SceneError
from ..model.cosim_section import CosimSettings, parse_cosim
from ..model.scene import Scene
from ..progress import Progress
from ..trajectory import Trajectory
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
    scene: Scene,
    *,
    engine: str | None = None,
    step: float | None = None,
    ordering: str | None = None,
    stop_time: float | None = None,
    quiet: bool = True,
) -> Trajectory:
    """Co-simulate the scene's hinge with its comb-drive actuator ([cosim] section)."""
    settings = cosim_settings(scene, engine=engine, step=step, ordering=ordering)
    progress = Progress(f"{scene.name}: cosim {settings.engine}", quiet=quiet)
    try:
        return RUNNERS[settings.engine](scene, settings, stop_time=stop_time, progress=progress)
    finally:
        progress.close()
