"""FMI 2.0 calls the FMU's conformance tests share: status codes and state names, an instance set
up from a scene or from the csfh scene's start, reading every variable, co-simulation steps, and
checks of the error a call returns and of the message it logs."""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from ctypes import POINTER, c_double
from typing import Any

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model, FMU2Slave, fmi2True
from fmpy.model_description import ModelDescription

from csfh.model.scene import Scene

MakeFmu = Callable[..., tuple[Any, Any]]
FMU = FMU2Model | FMU2Slave

OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3  # fmi2Status
STATES = ("body1.x", "body1.y", "body1.theta", "body1.vx", "body1.vy", "body1.omega")
STATE_SCALES = (0.01, 0.01, 0.1, 0.1, 0.1, 1.0)  # m, m, rad, m/s, m/s, rad/s
METHODS = {"auto": 1, "BDF": 2, "Adams": 3, "RK45": 4}  # enumeration SolverMethod
TIGHT = 1e-10  # the relative tolerance of the accurate runs (the FMU's integrator, fmpy's CVode)


# ------------------------------------------------------------------------------------------
# start-up


def initialized(make_fmu: MakeFmu, kind: str) -> tuple[Any, Any]:
    """An instance through initialization with the start values (ME: in event mode)."""
    fmu, log = make_fmu(kind)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    return fmu, log


def setup_scene(fmu: FMU, vr: dict[str, int], start: float = 0.0, **reals: float) -> None:
    """The csfh scene: q0 = [0.01, 0.01, 0], paper preset, plus the given reals."""
    fmu.setupExperiment(startTime=start)
    fmu.enterInitializationMode()
    values = {"body1.x": 0.01, "body1.y": 0.01, **reals}
    fmu.setReal([vr[k] for k in values], list(values.values()))
    fmu.exitInitializationMode()


def scene_start_values(
    scene: Scene, law: str, extra: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The scene's parameters for the law, its initial state and inputs, then `extra`."""
    values: dict[str, Any] = dict(scene.parameter_values(law))
    values.update(dict(zip(STATES, scene.x0, strict=True)))
    values.update(scene.inputs)
    values.update(extra or {})
    return values


def set_values(fmu: Any, md: ModelDescription, values: dict[str, Any]) -> None:
    """Each value with the setter of its variable's type."""
    types = {v.name: (v.valueReference, v.type) for v in md.modelVariables}
    for name, value in values.items():
        ref, kind = types[name]
        if kind == "Real":
            fmu.setReal([ref], [float(value)])
        elif kind == "Boolean":
            fmu.setBoolean([ref], [bool(value)])
        else:
            fmu.setInteger([ref], [int(value)])


def apply_scene(fmu: FMU2Slave, md: ModelDescription, scene: Scene, law: str) -> None:
    """The scene's parameters, initial state and inputs (in initialization mode)."""
    set_values(fmu, md, scene_start_values(scene, law))


# ------------------------------------------------------------------------------------------
# reading


def get_value(fmu: FMU, var: Any) -> Any:
    """Read one variable with the getter of its type."""
    if var.type == "Real":
        return fmu.getReal([var.valueReference])[0]
    if var.type == "Boolean":
        return bool(fmu.getBoolean([var.valueReference])[0])
    return fmu.getInteger([var.valueReference])[0]


def xml_start(var: Any) -> Any:
    """The start value modelDescription.xml declares, as the getter returns it."""
    if var.type == "Real":
        return float(var.start)
    if var.type == "Boolean":
        return var.start in ("true", "1")
    return int(var.start)


def all_values(fmu: FMU, md: ModelDescription) -> list[Any]:
    """Every variable the instance can report (time, states, parameters, outputs, counters)."""
    out: list[Any] = []
    for v in md.modelVariables:
        if v.type == "Real":
            out.append(fmu.getReal([v.valueReference])[0])
        elif v.type == "Boolean":
            out.append(fmu.getBoolean([v.valueReference])[0])
        elif v.type in ("Integer", "Enumeration"):
            out.append(fmu.getInteger([v.valueReference])[0])
    return out


def assert_same(after: list[Any], before: list[Any]) -> None:
    np.testing.assert_array_equal(np.array(after, dtype=float), np.array(before, dtype=float))


def derivatives(fmu: FMU2Model) -> np.ndarray:
    dx = np.zeros(6)
    fmu.getDerivatives(dx.ctypes.data_as(POINTER(c_double)), 6)
    return dx


def states(fmu: FMU2Slave, vr: dict[str, int]) -> np.ndarray:
    return np.array(fmu.getReal([vr[n] for n in STATES]))


# ------------------------------------------------------------------------------------------
# co-simulation


def cs_instance(
    make_fmu: MakeFmu,
    md: ModelDescription,
    scene: Scene,
    tolerance: float | None = TIGHT,
    law: str = "LN_spheres",
    extra: dict[str, float] | None = None,
    method: str | None = None,
) -> tuple[FMU2Slave, Any]:
    """An initialized co-simulation instance that logs its events (method: solver.method by
    name; None keeps the start value, auto)."""
    fmu, log = make_fmu("CS")
    fmu.setDebugLogging(True, ["logEvents"])
    fmu.setupExperiment(tolerance=tolerance, startTime=0.0)
    fmu.enterInitializationMode()
    apply_scene(fmu, md, scene, law)
    if extra:
        refs = {v.name: v.valueReference for v in md.modelVariables}
        fmu.setReal([refs[k] for k in extra], list(extra.values()))
    if method is not None:
        refs = {v.name: v.valueReference for v in md.modelVariables}
        fmu.setInteger([refs["solver.method"]], [METHODS[method]])
    fmu.exitInitializationMode()
    return fmu, log


def run(fmu: FMU2Slave, points: list[float] | np.ndarray, t: float = 0.0) -> float:
    """fmi2DoStep from t through every communication point."""
    for p in points:
        fmu.doStep(t, p - t)
        t = float(p)
    return t


def grid(h: float, t_end: float) -> np.ndarray:
    return np.arange(1, round(t_end / h) + 1) * h


def step_status(fmu: FMU2Slave, t: float, h: float) -> int:
    """fmi2DoStep's status (fmpy raises for errors)."""
    try:
        return int(fmu.fmi2DoStep(fmu.component, t, h, fmi2True))
    except FMICallException as e:
        return int(e.status)


def cs_run(fmu: FMU2Slave, vr: dict[str, int], t: float, steps: list[float]) -> np.ndarray:
    """fmi2DoStep through the given steps from t; rows: states, energy, contact count."""
    rows = []
    for h in steps:
        fmu.doStep(t, h)
        t = t + h
        count = fmu.getInteger([vr["contact.count"]])[0]
        rows.append([*states(fmu, vr), fmu.getReal([vr["energy.total"]])[0], count])
    return np.array(rows)


# ------------------------------------------------------------------------------------------
# errors


def names_value(message: str, name: str, value: float) -> bool:
    """Does the message say `name = <value>` (printed with %g, %.17g or %d)?"""
    for m in re.finditer(re.escape(name) + r" = ([^\s,;)]+)", message):
        try:
            printed = float(m.group(1))
        except ValueError:
            continue
        if printed == value or (math.isnan(value) and math.isnan(printed)):
            return True
        if math.isfinite(value) and math.isclose(printed, value, rel_tol=1e-6):
            return True
    return False


def assert_error_names(log: Any, name: str, value: float) -> None:
    errors = log.errors()
    assert any(names_value(m, name, value) for m in errors), (
        f"no error message names {name} = {value}: {errors}"
    )


def assert_fmi_error(call: Callable[[], object]) -> FMICallException:
    with pytest.raises(FMICallException) as info:
        call()
    assert info.value.status == ERROR
    return info.value
