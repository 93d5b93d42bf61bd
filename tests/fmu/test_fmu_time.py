"""The FMU's time: a co-simulation trajectory does not depend on the start time, the FMU reports
the precision the double time loses, and fmi2DoStep takes a communication point only if it is
the FMU's time up to round-off, and never goes back in time."""

from __future__ import annotations

import math
from ctypes import POINTER, byref, c_double
from typing import Any

import numpy as np
import pytest
from fmi2_calls import (
    ERROR,
    OK,
    WARNING,
    MakeFmu,
    all_values,
    assert_same,
    cs_run,
    derivatives,
    setup_scene,
    states,
    step_status,
)
from fmpy.fmi2 import FMU2Slave, fmi2Boolean, fmi2True
from fmpy.model_description import ModelDescription

H_EXACT = 2.0**-10  # a step that the time 1e10 s represents exactly (ulp(1e10) = 2**-19 s)


def ulp(t: float) -> float:
    return math.nextafter(abs(t), math.inf) - abs(t)


# ------------------------------------------------------------------------------------------
# large start times


def realized_steps(t0: float, steps: list[float]) -> list[float]:
    """The steps a master that computes t_(k+1) = t_k + h_k in double really takes from t0:
    t_(k+1) - t_k, exact (the FMU integrates exactly these)."""
    out, t = [], t0
    for h in steps:
        out.append((t + h) - t)
        t = t + h
    return out


def shifted_runs(
    make_fmu: MakeFmu, vr: dict[str, int], t0: float, steps: list[float], **reals: float
) -> tuple[np.ndarray, np.ndarray, list[int], Any]:
    """A master's run from t0 with the given steps (t_(k+1) = t_k + h_k), and the reference: the
    run from 0 with the steps the first one really took (realized_steps). Returns the rows of
    both (states, energy, contact count), fmi2DoStep's statuses from t0, and its log."""
    ref, ref_log = make_fmu("CS")
    setup_scene(ref, vr, 0.0, **reals)
    reference = cs_run(ref, vr, 0.0, realized_steps(t0, steps))
    assert not ref_log.errors() and not [s for s, _, _ in ref_log.lines if s == WARNING]
    fmu, log = make_fmu("CS")
    setup_scene(fmu, vr, t0, **reals)
    rows, statuses, t = [], [], t0
    for h in steps:
        statuses.append(step_status(fmu, t, h))
        t = t + h
        count = fmu.getInteger([vr["contact.count"]])[0]
        rows.append([*states(fmu, vr), fmu.getReal([vr["energy.total"]])[0], count])
    return reference, np.array(rows), statuses, log


def assert_reproduces(shifted: np.ndarray, reference: np.ndarray) -> None:
    """To 1e-9 relative (per column, of its largest value)."""
    scale = np.max(np.abs(reference), axis=0)
    np.testing.assert_allclose(shifted, reference, rtol=0, atol=1e-9 * float(np.max(scale)))
    for j in range(reference.shape[1]):
        np.testing.assert_allclose(shifted[:, j], reference[:, j], rtol=0, atol=1e-9 * scale[j])


@pytest.mark.parametrize("t0", [1e10, 1e11, -3e9])
def test_cs_start_time_does_not_change_the_trajectory(
    make_fmu: MakeFmu, vr: dict[str, int], t0: float
) -> None:
    """A start time of 1e10 s reproduces the run from 0, shifted, to 1e-9 relative (CVODE in a
    local time from an origin the instance holds): 0.3 s of the csfh scene with several
    contacts, on a grid the double time represents exactly at t0. (CVODE in the absolute time
    would log "t + h = t", return fmi2OK and drift.)"""
    steps = [H_EXACT] * round(0.3 / H_EXACT)
    reference, shifted, statuses, log = shifted_runs(make_fmu, vr, t0, steps)
    assert reference[-1, -1] >= 2, "the window must contain contacts"
    assert_reproduces(shifted, reference)
    assert statuses == [OK] * len(steps) and not log.errors()


def conservative_energy(make_fmu: MakeFmu, vr: dict[str, int], t0: float) -> np.ndarray:
    """Energy over 0.5 s of a conservative run with impacts: LN_spheres with c_r = 1 (no
    damping), the conservative flexure, no friction; five contacts."""
    fmu, log = make_fmu("CS")
    fmu.setupExperiment(startTime=t0)
    fmu.enterInitializationMode()
    fmu.setInteger([vr["contact.law"]], [2])
    fmu.setBoolean([vr["flexure.conservative"], vr["friction.enabled"]], [True, False])
    fmu.setReal([vr["body1.x"], vr["body1.y"], vr["contact.cr"]], [0.01, 0.01, 1.0])
    fmu.exitInitializationMode()
    energy = [fmu.getReal([vr["energy.total"]])[0]]
    t = t0
    for _ in range(round(0.5 / H_EXACT)):
        fmu.doStep(t, H_EXACT)
        t += H_EXACT
        energy.append(fmu.getReal([vr["energy.total"]])[0])
    assert fmu.getInteger([vr["contact.count"]])[0] >= 4 and not log.errors()
    return np.array(energy)


def test_cs_conservative_run_keeps_its_energy_at_a_large_start_time(
    make_fmu: MakeFmu, vr: dict[str, int]
) -> None:
    """From t0 = 1e10 s the energy of a conservative run is the run from 0's, to 1e-9 relative,
    and so stays within the integration error (4e-4 of E at rtol 1e-6 through five impacts).
    (In the absolute time it gains 68 % from 1e10 s, and from 1e11 s the step fails after
    500000 CVODE steps.)"""
    reference = conservative_energy(make_fmu, vr, 0.0)
    assert np.max(np.abs(reference - reference[0])) < 1e-3 * abs(reference[0])
    for t0 in (1e10, 1e11):
        shifted = conservative_energy(make_fmu, vr, t0)
        np.testing.assert_allclose(shifted, reference, rtol=0, atol=1e-9 * abs(reference[0]))


def test_cs_steps_the_time_cannot_resolve_are_reported(
    make_fmu: MakeFmu, vr: dict[str, int], model_description: ModelDescription
) -> None:
    """At t = 1e10 s the double time resolves 1.9e-6 s: communication steps of 1e-3 s are taken
    as the master's t_(k+1) - t_k (0.0010004 or 0.0009985 s). Each such step is reported with
    fmi2Warning (logged once), and the trajectory is still the run from 0 on the same local
    grid. A step below the resolution (1e-7 s) is refused with fmi2Error and changes nothing."""
    t0 = 1e10
    steps = [1e-3] * 300
    assert max(abs(h - 1e-3) for h in realized_steps(t0, steps)) > 1e-7  # not what was meant
    reference, shifted, statuses, log = shifted_runs(make_fmu, vr, t0, steps)
    assert_reproduces(shifted, reference)
    assert set(statuses) == {WARNING}
    warnings = [m for s, _, m in log.lines if s == WARNING]
    assert len(warnings) == 1 and "resolves steps to" in warnings[0], warnings
    fmu, log = make_fmu("CS")
    setup_scene(fmu, vr, t0)
    before = all_values(fmu, model_description)
    assert step_status(fmu, t0, 1e-7) == ERROR
    assert any("below the resolution of the time" in m for m in log.errors())
    assert_same(all_values(fmu, model_description), before)
    assert step_status(fmu, t0, H_EXACT) == OK


def me_euler_statuses(make_fmu: MakeFmu, vr: dict[str, int], t0: float, h: float) -> list[int]:
    """fmi2CompletedIntegratorStep's statuses over 50 explicit Euler steps from t0 (the time
    set as t0 + k h, as an importer does)."""
    fmu, _ = make_fmu("ME")
    setup_scene(fmu, vr, t0)
    fmu.enterContinuousTimeMode()
    x = np.zeros(6)
    px = x.ctypes.data_as(POINTER(c_double))
    fmu.getContinuousStates(px, 6)
    statuses = []
    enter, terminate = fmi2Boolean(), fmi2Boolean()
    for k in range(1, 51):
        x += h * derivatives(fmu)
        fmu.setTime(t0 + k * h)
        fmu.setContinuousStates(px, 6)
        statuses.append(
            fmu.fmi2CompletedIntegratorStep(fmu.component, fmi2True, byref(enter), byref(terminate))
        )
    return statuses


@pytest.mark.parametrize(
    ("t0", "h", "expected"),
    [
        (0.0, 1e-5, OK),
        (5.0, 1e-7, OK),  # resolved to 9e-9 relative: below the 1e-6 floor, no noise
        (1e10, 1e-5, WARNING),
        (1e10, 1e-7, WARNING),
        (1e10, 10.0, OK),
    ],
)
def test_me_steps_the_time_cannot_resolve_are_reported(
    make_fmu: MakeFmu, vr: dict[str, int], t0: float, h: float, expected: int
) -> None:
    """Model exchange: the model is autonomous, so its values do not depend on the start time;
    what the FMU reports is the importer's time losing precision: integrator steps that the
    double time represents worse than the tolerance and 1e-6 (1e-5 s at 1e10 s: 19 % off;
    1e-7 s: the time does not move) give fmi2Warning from fmi2CompletedIntegratorStep, once
    logged."""
    statuses = me_euler_statuses(make_fmu, vr, t0, h)
    assert set(statuses) == {expected}, statuses


# ------------------------------------------------------------------------------------------
# the communication point: the FMU's time up to round-off, never backwards


ROUNDOFF = 16 * np.finfo(float).eps  # the rule of fmi2DoStep (fmu_step.c: COMM_POINT_ROUNDOFF)


def stepped_to(make_fmu: MakeFmu, vr: dict[str, int], t1: float) -> tuple[FMU2Slave, Any, float]:
    fmu, log = make_fmu("CS")
    setup_scene(fmu, vr)
    fmu.doStep(0.0, t1)
    t = fmu.getReal([vr["time"]])[0]
    assert t == t1
    return fmu, log, t


@pytest.mark.parametrize("t1", [0.3, 1e10 + 0.25])
@pytest.mark.parametrize("side", [-1.0, 1.0], ids=["behind", "ahead"])
def test_communication_point_within_round_off_is_taken(
    make_fmu: MakeFmu, vr: dict[str, int], t1: float, side: float
) -> None:
    """A communication point a few ulp off the FMU's time T (a master's t0 + k h against
    t_(k-1) + h) is taken: the FMU integrates from T to t + h, and its time never goes back."""
    if t1 > 1e9:
        fmu, log = make_fmu("CS")
        setup_scene(fmu, vr, 1e10)
        fmu.doStep(1e10, 0.25)
        T = fmu.getReal([vr["time"]])[0]
    else:
        fmu, log, T = stepped_to(make_fmu, vr, t1)
    t = T + side * 4 * ulp(T)
    assert t != T and abs(t - T) <= ROUNDOFF * max(abs(t), abs(T))
    h = 1e-3 if t1 < 1e9 else H_EXACT
    assert step_status(fmu, t, h) in (OK, WARNING)
    assert fmu.getReal([vr["time"]])[0] == t + h and t + h > T
    assert not log.errors()


@pytest.mark.parametrize("offset", [-1e-10, -1e-12, -64 * ulp(0.3), 1e-12, 64 * ulp(0.3)])
def test_communication_point_beyond_round_off_is_refused(
    make_fmu: MakeFmu, vr: dict[str, int], model_description: ModelDescription, offset: float
) -> None:
    """Behind the FMU's time by more than round-off (a rule of 1e-9 (1 + |t|) would take 1e-10 s
    at t = 0.3 s, and the time would go backwards) or ahead of it: fmi2Error, nothing changes,
    the instance goes on."""
    fmu, log, T = stepped_to(make_fmu, vr, 0.3)
    t = T + offset
    assert abs(t - T) > ROUNDOFF * max(abs(t), abs(T))
    before = all_values(fmu, model_description)
    assert step_status(fmu, t, 1e-3) == ERROR
    assert any("does not match the FMU time" in m for m in log.errors())
    assert_same(all_values(fmu, model_description), before)
    assert step_status(fmu, T, 1e-3) == OK


def test_time_never_goes_backwards(
    make_fmu: MakeFmu, vr: dict[str, int], model_description: ModelDescription
) -> None:
    """A point within round-off behind T with a step that ends before T would take the time
    back: refused, as is the point 1e-10 s behind with a step of 1e-11 s that a rule of
    1e-9 (1 + |t|) would take, setting the time to T - 9e-11."""
    fmu, _, T = stepped_to(make_fmu, vr, 0.3)
    t = T - 4 * ulp(T)
    before = all_values(fmu, model_description)
    assert step_status(fmu, t, 2 * ulp(T)) == ERROR
    assert_same(all_values(fmu, model_description), before)
    assert fmu.getReal([vr["time"]])[0] == T
    loose, _, T2 = stepped_to(make_fmu, vr, 0.3)  # what a rule of 1e-9 (1 + |t|) takes
    assert step_status(loose, T2 - 1e-10, 1e-11) == ERROR
    assert loose.getReal([vr["time"]])[0] == T2


def test_masters_time_arithmetic_is_accepted(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    """Masters compute t_k = t0 + k h, or t_k = t_(k-1) + h, or from integer nanoseconds: all
    within the round-off rule, over 2000 steps from 0 and from 1e6 s."""
    for t0 in (0.0, 1e6):
        for master in ("product", "sum", "nanoseconds"):
            fmu, log = make_fmu("CS")
            setup_scene(fmu, vr, t0)
            h, t = 1e-3, t0
            for k in range(2000):
                if master == "product":
                    t = t0 + k * h
                elif master == "nanoseconds":
                    t = (round(t0 * 1e9) + k * 1_000_000) * 1e-9
                assert step_status(fmu, t, h) in (OK, WARNING), (master, t0, k)
                if master == "sum":
                    t = t + h
            assert not log.errors()
