"""Bad input to the FMI 2.0 interface: fmi2Error at the set call or at
fmi2ExitInitializationMode and a log line that names the variable and its value; a refused call
changes nothing (fmi2Set* with several values is all or nothing, tunable parameters are checked
together, a start deep in the bore is refused); non-finite values of the model are errors."""

from __future__ import annotations

import math
from ctypes import POINTER, c_double
from typing import Any

import numpy as np
import pytest
from fmi2_calls import (
    FMU,
    MakeFmu,
    all_values,
    assert_error_names,
    assert_fmi_error,
    assert_same,
    initialized,
    names_value,
    setup_scene,
)
from fmpy.fmi1 import FMICallException
from fmpy.model_description import ModelDescription


def variable(model_description: ModelDescription, name: str) -> Any:
    for v in model_description.modelVariables:
        if v.name == name:
            return v
    raise KeyError(name)


def set_value(fmu: FMU, model_description: ModelDescription, name: str, value: float) -> None:
    """Set one variable with the setter of its type."""
    v = variable(model_description, name)
    if v.type == "Real":
        fmu.setReal([v.valueReference], [value])
    elif v.type == "Boolean":
        fmu.setBoolean([v.valueReference], [int(value)])
    else:
        fmu.setInteger([v.valueReference], [int(value)])


# ------------------------------------------------------------------------------------------
# fmi2Error at the set call or at fmi2ExitInitializationMode, and a log line that
# names the variable and its value


NAN, INF = math.nan, math.inf


TWO_PI = 2.0 * math.pi


# (variables to set, the variable and value the error message must name)
BAD_INPUTS: list[tuple[list[tuple[str, float]], tuple[str, float]]] = [
    ([("contact.R1", 0.2), ("contact.R2", 0.2)], ("contact.R1", 0.2)),
    ([("contact.R1", 0.25)], ("contact.R1", 0.25)),
    ([("contact.R2", 0.1)], ("contact.R2", 0.1)),
    ([("contact.R1", 0.0)], ("contact.R1", 0.0)),
    ([("body1.m", 0.0)], ("body1.m", 0.0)),
    ([("body1.m", -10.0)], ("body1.m", -10.0)),
    ([("body1.I", 0.0)], ("body1.I", 0.0)),
    ([("body1.I", -0.1617)], ("body1.I", -0.1617)),
    ([("contact.cr", 0.0)], ("contact.cr", 0.0)),
    ([("contact.cr", 1.5)], ("contact.cr", 1.5)),
    ([("contact.cr", -0.5)], ("contact.cr", -0.5)),
    ([("contact.E1", 0.0)], ("contact.E1", 0.0)),
    ([("contact.E1", -210e9)], ("contact.E1", -210e9)),
    ([("contact.E2", 0.0)], ("contact.E2", 0.0)),
    ([("flexure.E", 0.0)], ("flexure.E", 0.0)),
    ([("flexure.E", -100e9)], ("flexure.E", -100e9)),
    ([("contact.nu1", 0.5)], ("contact.nu1", 0.5)),
    ([("contact.nu1", -1.0)], ("contact.nu1", -1.0)),
    ([("contact.nu2", 0.7)], ("contact.nu2", 0.7)),
    ([("flexure.nu", 0.5)], ("flexure.nu", 0.5)),
    ([("flexure.nu", -1.0)], ("flexure.nu", -1.0)),
    ([("flexure.nu", -1.5)], ("flexure.nu", -1.5)),
    ([("flexure.rho", 0.0)], ("flexure.rho", 0.0)),
    ([("flexure.rho", -0.144)], ("flexure.rho", -0.144)),
    ([("flexure.h", 0.0)], ("flexure.h", 0.0)),
    ([("flexure.h", -0.005)], ("flexure.h", -0.005)),
    ([("flexure.b", 0.0)], ("flexure.b", 0.0)),
    ([("flexure.b", -0.025)], ("flexure.b", -0.025)),
    ([("flexure.beta", 0.0)], ("flexure.beta", 0.0)),
    ([("flexure.beta", TWO_PI)], ("flexure.beta", TWO_PI)),
    ([("flexure.beta", 7.0)], ("flexure.beta", 7.0)),
    ([("flexure.kappa", 0.0)], ("flexure.kappa", 0.0)),
    ([("friction.v1", 1e-4)], ("friction.v1", 1e-4)),
    ([("friction.v1", 5e-5)], ("friction.v1", 5e-5)),
    ([("friction.v0", 0.02)], ("friction.v0", 0.02)),
    ([("friction.v1", 0.0)], ("friction.v1", 0.0)),
    ([("friction.fd", -0.1)], ("friction.fd", -0.1)),
    ([("g", -9.81)], ("g", -9.81)),
    ([("contact.L", 0.0)], ("contact.L", 0.0)),
    ([("contact.n_spheres", 0.0)], ("contact.n_spheres", 0.0)),
    ([("contact.v_min", 0.0)], ("contact.v_min", 0.0)),
    ([("contact.gap_hysteresis", 0.0)], ("contact.gap_hysteresis", 0.0)),
    ([("contact.K_spheres_given", -1.0)], ("contact.K_spheres_given", -1.0)),
    ([("contact.law", 0)], ("contact.law", 0)),
    ([("contact.law", 7)], ("contact.law", 7)),
    ([("solver.method", 0)], ("solver.method", 0)),
    ([("solver.method", 5)], ("solver.method", 5)),
    ([("contact.law", -1)], ("contact.law", -1)),
    ([("contact.esdu_reading", 0)], ("contact.esdu_reading", 0)),
    ([("contact.esdu_reading", 3)], ("contact.esdu_reading", 3)),
    # non-finite parameters (with and without a declared range)
    ([("body1.m", NAN)], ("body1.m", NAN)),
    ([("body1.m", INF)], ("body1.m", INF)),
    ([("contact.E1", -INF)], ("contact.E1", -INF)),
    ([("flexure.OF[1]", NAN)], ("flexure.OF[1]", NAN)),
    ([("flexure.OF[2]", INF)], ("flexure.OF[2]", INF)),
    ([("body1.s1[1]", -INF)], ("body1.s1[1]", -INF)),
    ([("flexure.phi_root", NAN)], ("flexure.phi_root", NAN)),
    # non-finite state start values
    ([("body1.x", NAN)], ("body1.x", NAN)),
    ([("body1.y", INF)], ("body1.y", INF)),
    ([("body1.omega", -INF)], ("body1.omega", -INF)),
    # non-finite inputs
    ([("F_ext[1]", NAN)], ("F_ext[1]", NAN)),
    ([("F_ext[2]", INF)], ("F_ext[2]", INF)),
    ([("M_ext", -INF)], ("M_ext", -INF)),
]


def _case_id(case: tuple[list[tuple[str, float]], tuple[str, float]]) -> str:
    return ",".join(f"{n}={v}" for n, v in case[0])


@pytest.mark.parametrize("kind", ["ME", "CS"])
@pytest.mark.parametrize("case", BAD_INPUTS, ids=[_case_id(c) for c in BAD_INPUTS])
def test_bad_input_is_rejected(
    make_fmu: MakeFmu,
    model_description: ModelDescription,
    kind: str,
    case: tuple[list[tuple[str, float]], tuple[str, float]],
) -> None:
    sets, (named, value) = case
    fmu, log = make_fmu(kind)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()

    def set_and_exit() -> None:
        for name, x in sets:
            set_value(fmu, model_description, name, x)
        fmu.exitInitializationMode()

    assert_fmi_error(set_and_exit)
    assert_error_names(log, named, value)


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_bad_start_value_can_be_corrected_before_exit(
    make_fmu: MakeFmu, vr: dict[str, int], kind: str
) -> None:
    """A rejected exitInitializationMode leaves the instance in initialization mode."""
    fmu, log = make_fmu(kind)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([vr["contact.R1"]], [0.2])
    assert_fmi_error(fmu.exitInitializationMode)
    assert_error_names(log, "contact.R1", 0.2)
    fmu.setReal([vr["contact.R1"]], [0.18])
    fmu.exitInitializationMode()
    assert fmu.getReal([vr["contact.delta"]])[0] == pytest.approx(0.02)


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_a_start_deep_in_the_bore_is_refused(
    make_fmu: MakeFmu, vr: dict[str, int], kind: str
) -> None:
    """q0 = [0.05, 0, 0] with the clearance 0.02 m is 0.03 m deep: fmi2ExitInitializationMode
    returns fmi2Error naming the state and the indentation (accepted, it would run silently
    with F_N = 2.5e8 N); at the limit it starts, and the limit is a parameter."""
    from fmpy.fmi1 import FMICallException

    fmu, log = make_fmu(kind)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([vr["body1.x"], vr["body1.y"]], [0.05, 0.0])
    with pytest.raises(FMICallException):
        fmu.exitInitializationMode()
    message = log.errors()[-1]
    assert "body1.x = 0.05 m, body1.y = 0 m, body1.theta = 0 rad" in message
    assert "contact.indentation = 0.03 m > contact.max_initial_indentation = 0.001 m" in message
    # just inside the limit: accepted; and a larger limit accepts the deep start
    for x, limit in ((0.02 + 0.999e-3, None), (0.05, 0.04)):
        fmu, log = make_fmu(kind)
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setReal([vr["body1.x"], vr["body1.y"]], [x, 0.0])
        if limit is not None:
            fmu.setReal([vr["contact.max_initial_indentation"]], [limit])
        fmu.exitInitializationMode()
        assert fmu.getBoolean([vr["contact.active"]])[0]


def enter_running(fmu: FMU, kind: str) -> None:
    """Event mode (ME) or step complete after one step (CS)."""
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    if kind == "CS":
        fmu.doStep(0.0, 1e-3)


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_tunable_parameter_after_initialization(
    make_fmu: MakeFmu, vr: dict[str, int], kind: str
) -> None:
    fmu, log = make_fmu(kind)
    enter_running(fmu, kind)
    cr, xi = vr["contact.cr"], vr["contact.xi"]
    xi0 = fmu.getReal([xi])[0]
    assert xi0 == pytest.approx(0.75 * (1.0 - 0.9 * 0.9))
    for bad in (0.0, 1.5, -0.1, NAN, INF):
        assert_fmi_error(lambda bad=bad: fmu.setReal([cr], [bad]))
        assert_error_names(log, "contact.cr", bad)
        assert fmu.getReal([cr, xi]) == [0.9, xi0]
    # a cross-check that fails on a tunable parameter rolls the value back
    assert_fmi_error(lambda: fmu.setReal([vr["friction.v1"]], [5e-5]))
    assert_error_names(log, "friction.v1", 5e-5)
    assert fmu.getReal([vr["friction.v1"]]) == [0.01]
    # a good value is accepted and updates the derived damping factor
    fmu.setReal([cr], [0.5])
    assert fmu.getReal([cr])[0] == 0.5
    assert fmu.getReal([xi])[0] == pytest.approx(0.75 * (1.0 - 0.25), rel=1e-15)
    # and the instance keeps running
    if kind == "CS":
        fmu.doStep(1e-3, 1e-3)
    else:
        fmu.newDiscreteStates()
        fmu.enterContinuousTimeMode()
        # tunable parameters cannot change in continuous-time mode
        assert_fmi_error(lambda: fmu.setReal([cr], [0.7]))
        assert fmu.getReal([cr])[0] == 0.5


@pytest.mark.parametrize("kind", ["ME", "CS"])
@pytest.mark.parametrize("bad", [NAN, INF, -INF])
def test_non_finite_input_after_initialization(
    make_fmu: MakeFmu, vr: dict[str, int], kind: str, bad: float
) -> None:
    fmu, log = make_fmu(kind)
    enter_running(fmu, kind)
    if kind == "ME":
        fmu.enterContinuousTimeMode()
    fmu.setReal([vr["F_ext[1]"]], [3.0])
    assert_fmi_error(lambda: fmu.setReal([vr["F_ext[1]"]], [bad]))
    assert_error_names(log, "F_ext[1]", bad)
    assert fmu.getReal([vr["F_ext[1]"]]) == [3.0]


# ------------------------------------------------------------------------------------------
# a refused call changes nothing: fmi2Set* with several values is all or nothing


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_set_with_one_bad_value_changes_nothing(
    make_fmu: MakeFmu, vr: dict[str, int], model_description: ModelDescription, kind: str
) -> None:
    """fmi2SetReal([c_r, m], [0.5, -1]) refuses m and sets nothing, not even c_r."""
    fmu, log = make_fmu(kind)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    before = all_values(fmu, model_description)
    with pytest.raises(FMICallException):
        fmu.setReal([vr["contact.cr"], vr["body1.m"]], [0.5, -1.0])
    assert any(names_value(m, "body1.m", -1.0) for m in log.errors())
    assert_same(all_values(fmu, model_description), before)


def test_tunable_parameters_are_checked_together(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    """While running, tunable parameters set in one call are cross-checked together (v0 < v1):
    moving both up at once is accepted, and a call that breaks the rule changes neither."""
    fmu, log = make_fmu("CS")
    setup_scene(fmu, vr)
    fmu.doStep(0.0, 1e-3)
    fmu.setReal([vr["friction.v0"], vr["friction.v1"]], [0.02, 0.03])  # v0 > the old v1 = 0.01
    assert fmu.getReal([vr["friction.v0"], vr["friction.v1"]]) == [0.02, 0.03]
    with pytest.raises(FMICallException):
        fmu.setReal([vr["friction.v1"], vr["friction.fd"]], [0.01, 0.06])
    assert any(names_value(m, "friction.v1", 0.01) for m in log.errors())
    assert fmu.getReal([vr["friction.v1"], vr["friction.fd"]]) == [0.03, 0.055]
    fmu.doStep(1e-3, 1e-3)


# ------------------------------------------------------------------------------------------
# non-finite values of the model


def test_non_finite_derivative_is_an_error(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    """g = 1e308 is inside the declared range [0, inf), but m g overflows to -inf in der(vy)."""
    fmu, log = make_fmu("ME")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([vr["g"]], [1e308])
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    dx = np.zeros(6)
    assert_fmi_error(lambda: fmu.getDerivatives(dx.ctypes.data_as(POINTER(c_double)), 6))
    assert any("non-finite derivative" in m for m in log.errors()), log.errors()
    assert_fmi_error(lambda: fmu.getReal([vr["der(body1.vy)"]]))
    assert_fmi_error(lambda: fmu.getReal([vr["energy.total"]]))
    assert any("non-finite output" in m for m in log.errors()), log.errors()
    # the states themselves are still readable
    assert fmu.getReal([vr["body1.y"]]) == [0.01]


def test_non_finite_contact_force_is_an_error(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    """A finite but absurd start position: the Hertz force K rho^1.5 overflows. (Such a start is
    refused unless contact.max_initial_indentation allows it:
    test_a_start_deep_in_the_bore_is_refused.)"""
    fmu, log = make_fmu("ME")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([vr["contact.max_initial_indentation"]], [1e300])
    fmu.setReal([vr["body1.x"]], [1e250])
    fmu.exitInitializationMode()
    assert fmu.getBoolean([vr["contact.active"]]) == [True]
    assert_fmi_error(lambda: fmu.getReal([vr["der(body1.vx)"]]))
    assert any("non-finite derivative" in m for m in log.errors()), log.errors()


def test_non_finite_event_indicator_is_an_error(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    """States at the edge of the double range (each finite, as any start value may be) give a
    gap of -inf: fmi2GetEventIndicators returns fmi2Error naming the indicator and the state,
    not the -inf with fmi2OK."""
    fmu, log = make_fmu("ME")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    # such a start is refused by the start check (test_a_start_deep_in_the_bore_is_refused); an
    # importer can still set such states in continuous-time mode
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    x = np.array([1.7e308, 1.7e308, 0.0, 0.0, 0.0, 0.0])
    fmu.setContinuousStates(x.ctypes.data_as(POINTER(c_double)), 6)
    z = np.zeros(1)
    with pytest.raises(FMICallException):
        fmu.getEventIndicators(z.ctypes.data_as(POINTER(c_double)), 1)
    assert any("non-finite event indicator z[0] = -inf" in m for m in log.errors())


@pytest.mark.parametrize("bad", [NAN, INF, -INF])
def test_set_continuous_states_rejects_non_finite(
    make_fmu: MakeFmu, vr: dict[str, int], bad: float
) -> None:
    fmu, log = initialized(make_fmu, "ME")
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    x = np.array([0.01, 0.01, 0.0, 0.0, bad, 0.0])
    assert_fmi_error(lambda: fmu.setContinuousStates(x.ctypes.data_as(POINTER(c_double)), 6))
    assert any("x[4]" in m and "not finite" in m for m in log.errors()), log.errors()
    assert fmu.getReal([vr["body1.vy"]]) == [0.0]  # unchanged
