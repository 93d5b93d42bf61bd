"""The comb-drive actuator FMU (`combdrive.fmu`, modelDescription/combdrive.toml): its
parameters, and their validation for the [cosim.actuator] table of a scene: types and ranges
from the generated interface (csfh.model._combdrive_variables, no binary needed), then, where the
FMU is built, the FMU's own checks."""

from __future__ import annotations

import math
from typing import Any

from ..errors import ParameterError, SceneError
from ..paths import combdrive_fmu_path
from ._combdrive_variables import INTERFACE
from .fmus import Slave, description
from .interface import Variable
from .values import as_float, shown


def actuator_description() -> Any:
    """The built comb-drive FMU's model description (fmpy's ModelDescription)."""
    return description(str(combdrive_fmu_path()))


def actuator_parameters() -> dict[str, Variable]:
    """The comb-drive FMU's parameters by name."""
    return {v.name: v for v in INTERFACE.select("parameter")}


def check_actuator(values: dict[str, Any]) -> dict[str, float | int]:
    """Type- and range-check the actuator parameters (SceneError naming the key), then let the
    comb-drive FMU validate them, where it is built (derived quantities): its own message
    becomes the scene error."""
    params = actuator_parameters()
    out: dict[str, float | int] = {}
    for name, value in values.items():
        if params[name].type == "Integer":
            if isinstance(value, bool) or not isinstance(value, int):
                raise SceneError(f"cosim.actuator.{name} = {value!r} must be an integer")
            out[name] = value
        else:
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise SceneError(f"cosim.actuator.{name} = {value!r} must be a number")
            out[name] = as_float(value)
        if not math.isfinite(as_float(value)):
            raise SceneError(f"cosim.actuator.{name} = {shown(value)} must be a finite number")
        try:
            INTERFACE.check(name, out[name])
        except ParameterError as exc:
            raise SceneError(f"cosim.actuator: {exc}") from None
    try:
        path = str(combdrive_fmu_path())
    except FileNotFoundError:
        return out  # no build: the FMU makes the same checks when a co-simulation starts
    _check_in_fmu(path, out)
    return out


def _check_in_fmu(path: str, values: dict[str, float | int]) -> None:
    from fmpy.fmi1 import FMICallException

    slave = Slave(path, "combdrive")
    try:
        slave.fmu.setupExperiment(startTime=0.0)
        slave.fmu.enterInitializationMode()
        slave.set(values)
        slave.fmu.exitInitializationMode()
    except FMICallException as exc:
        detail = slave.log.errors[-1] if slave.log.errors else str(exc)
        detail = detail.split(": ", 1)[-1]  # drop the "fmi2SetReal: " prefix
        raise SceneError(f"cosim.actuator: {detail}") from None
    finally:
        slave.free()
