"""The C model of a scene: an instance of the core library set up with the scene's parameters,
inputs and initial state, as the Moreau and RK4 runners and the studies start from it."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from . import model_info
from .core import CoreModel
from .scene import Scene


def core_model(scene: Scene, parameters: dict[str, Any] | None = None) -> CoreModel:
    """A C model set up with the scene's parameters, inputs and initial state."""
    model = CoreModel()
    values = dict(scene.parameter_values())
    if parameters:
        values.update({k: model_info.coerce(k, v) for k, v in parameters.items()})
    for name, value in values.items():
        model.set(name, value)
    for name, value in scene.inputs.items():
        model.set(name, value)
    model.state = np.array(scene.x0)
    model.prepare()
    return model


def nominal_values(scene: Scene, names: Sequence[str]) -> dict[str, float]:
    """The scene's value of each FMU parameter (its override, the preset's, or the start)."""
    model = core_model(scene)
    return {n: model.get(n) for n in names}


def clearance(scene: Scene) -> float:
    """The radial clearance delta = R2 - R1 of the scene's hinge, m."""
    values = nominal_values(scene, ["contact.R1", "contact.R2"])
    return values["contact.R2"] - values["contact.R1"]
