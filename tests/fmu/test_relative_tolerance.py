"""The relative tolerance an importer gives is checked where it gives it (fmi2SetupExperiment,
fmi3EnterInitializationMode): one the integrators cannot honour, outside [10 machine epsilons, 1),
is refused with an error status and a log line naming `tolerance` and its value, and changes
nothing; the tightest and the loosest accepted tolerances run with every method
(docs/guide/fmu.md, "Tolerance")."""

from __future__ import annotations

import math
import sys
from typing import Any

import pytest
from fmi2_calls import ERROR, METHODS, MakeFmu, names_value
from fmpy.fmi1 import FMICallException
from fmpy.model_description import ModelDescription
from test_fmi3 import Log, slave
from test_fmi3 import vr as vr3

TIGHTEST = 10 * sys.float_info.epsilon
REFUSED = [
    5e-324,
    0.0,
    -0.0,
    -1.0,
    math.nan,
    math.inf,
    -math.inf,
    2.0,
    1.0,
    TIGHTEST * (1 - sys.float_info.epsilon),
]
ACCEPTED = [TIGHTEST, 1e-14, 1e-6, 0.1]


def refused(call: Any, errors: Any, value: float) -> None:
    with pytest.raises(FMICallException) as info:
        call()
    assert info.value.status == ERROR
    assert any(names_value(m, "tolerance", value) for m in errors()), errors()


@pytest.mark.parametrize("tolerance", REFUSED)
def test_fmi2_setup_experiment_refuses_the_tolerance(make_fmu: MakeFmu, tolerance: float) -> None:
    fmu, log = make_fmu("CS")
    refused(lambda: fmu.setupExperiment(tolerance=tolerance, startTime=0.0), log.errors, tolerance)
    # nothing changed: the instance sets up and runs with a valid one
    fmu.setupExperiment(tolerance=1e-6, startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 1e-3)


@pytest.mark.parametrize("tolerance", REFUSED)
def test_fmi3_enter_initialization_mode_refuses_the_tolerance(
    md3: ModelDescription, unzipped3: str, tolerance: float
) -> None:
    log = Log()
    fmu = slave(md3, unzipped3, log, eventModeUsed=False, earlyReturnAllowed=False)
    try:
        refused(
            lambda: fmu.enterInitializationMode(tolerance=tolerance, startTime=0.0),
            log.errors,
            tolerance,
        )
        fmu.enterInitializationMode(tolerance=1e-6, startTime=0.0)
        fmu.exitInitializationMode()
        fmu.doStep(0.0, 1e-3)
    finally:
        fmu.freeInstance()


@pytest.mark.parametrize("method", list(METHODS))
@pytest.mark.parametrize("tolerance", ACCEPTED)
def test_accepted_tolerances_run(
    make_fmu: MakeFmu, vr: dict[str, int], tolerance: float, method: str
) -> None:
    """Through the first contact of the default scene (about 0.07 s) with each method."""
    fmu, log = make_fmu("CS")
    fmu.setupExperiment(tolerance=tolerance, startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setInteger([vr["solver.method"]], [METHODS[method]])
    fmu.exitInitializationMode()
    t = 0.0
    for _ in range(10):
        fmu.doStep(t, 0.01)
        t += 0.01
    assert fmu.getInteger([vr["contact.count"]])[0] >= 1
    assert all(math.isfinite(x) for x in fmu.getReal([vr["body1.x"], vr["body1.y"]]))
    assert not log.errors()


def test_fmi3_accepts_the_tightest_tolerance(md3: ModelDescription, unzipped3: str) -> None:
    log = Log()
    fmu = slave(md3, unzipped3, log, eventModeUsed=False, earlyReturnAllowed=False)
    try:
        fmu.enterInitializationMode(tolerance=TIGHTEST, startTime=0.0)
        fmu.exitInitializationMode()
        fmu.doStep(0.0, 0.1)
        assert math.isfinite(fmu.getFloat64([vr3(md3, "body1.y")])[0])
        assert not log.errors()
    finally:
        fmu.freeInstance()
