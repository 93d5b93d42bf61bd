"""One entry point for every model: `simulate(scene, model)`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

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
    """Run `model` (a contact law of the FMU, or "Moreau") on `scene` (a Scene, a built-in
    scene's name or the path of a scene file).

    Event-driven laws run through the FMU, by model exchange with fmpy's CVode (interface "me",
    default) or by co-simulation with CVODE inside the FMU ("cs"); "Moreau" runs the time
    stepper of the C core. Options are passed to simulate_me / simulate_cs / moreau."""
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
    finally:
        progress.close()
