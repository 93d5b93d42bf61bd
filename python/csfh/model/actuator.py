"""The comb-drive actuator FMU (`combdrive.fmu`, modelDescription/combdrive.toml): its
parameters, and their validation by the FMU itself (ranges, finiteness) for the [cosim.actuator]
table of a scene."""

from __future__ import annotations

from typing import Any

from ..errors import SceneError
from ..paths import combdrive_fmu_path
from .fmus import Slave, description


def actuator_description() -> Any:
    """The comb-drive FMU's model description (fmpy's ModelDescription)."""
    return description(str(combdrive_fmu_path()))


def actuator_parameters() -> dict[str, Any]:
    """The comb-drive FMU's parameters (name -> ModelVariable)."""
    md = actuator_description()
    return {v.name: v for v in md.modelVariables if v.causality == "parameter"}


def check_actuator(values: dict[str, Any]) -> dict[str, float | int]:
    """Type-check the actuator parameters and let the comb-drive FMU validate them (ranges,
    finiteness): its own message becomes the scene error."""
    from fmpy.fmi1 import FMICallException

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
            out[name] = float(value)
    slave = Slave(str(combdrive_fmu_path()), "combdrive")
    try:
        slave.fmu.setupExperiment(startTime=0.0)
        slave.fmu.enterInitializationMode()
        slave.set(out)
        slave.fmu.exitInitializationMode()
    except FMICallException as exc:
        detail = slave.log.errors[-1] if slave.log.errors else str(exc)
        detail = detail.split(": ", 1)[-1]  # drop the "fmi2SetReal: " prefix
        raise SceneError(f"cosim.actuator: {detail}") from None
    finally:
        slave.free()
    return out
