"""The FMU under hostile input (issue 15): restored FMU states are checked like values set with
fmi2Set*, the co-simulation trajectory does not depend on the start time and the FMU reports the
precision the double time loses, and fmi2DoStep takes a communication point only if it is the
FMU's time up to round-off. (FMU states the importer never freed, and the random call-sequence
fuzzer under ASan + UBSan + LeakSanitizer: tests/fuzz/.)

FMU states are opaque bytes; the tests find a variable's bytes in a serialized state by its value
(a distinctive double) or by the difference between two states that differ in that variable only,
so they do not depend on the layout."""

from __future__ import annotations

import ctypes
import math
import re
import struct
from collections.abc import Callable
from ctypes import POINTER, byref, c_double
from typing import Any

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model, FMU2Slave, fmi2Boolean, fmi2True
from fmpy.model_description import ModelDescription

MakeFmu = Callable[..., tuple[Any, Any]]
FMU = FMU2Model | FMU2Slave

OK, WARNING, ERROR = 0, 1, 3
FMU_INITIALIZATION, FMU_EVENT, FMU_STEP_COMPLETE = 1 << 1, 1 << 2, 1 << 4  # fmu_instance.h
STATES = ["body1.x", "body1.y", "body1.theta", "body1.vx", "body1.vy", "body1.omega"]
MASS = 10.000000123  # a valid mass whose bytes occur once in a state
H_EXACT = 2.0**-10  # a step that the time 1e10 s represents exactly (ulp(1e10) = 2**-19 s)


# ------------------------------------------------------------------------------------------
# helpers


def ulp(t: float) -> float:
    return math.nextafter(abs(t), math.inf) - abs(t)


def serialized(fmu: FMU) -> bytes:
    state = fmu.getFMUstate()
    data = fmu.serializeFMUstate(state)
    fmu.freeFMUstate(state)
    return bytes(data)


def offset_of(data: bytes, packed: bytes) -> int:
    """Where `packed` occurs in data (exactly once)."""
    at = data.find(packed)
    assert at >= 0 and data.find(packed, at + 1) < 0, "the value must occur exactly once"
    return at


def patched(data: bytes, at: int, packed: bytes) -> bytes:
    return data[:at] + packed + data[at + len(packed) :]


def int_offset(fmu: FMU, set_int: Callable[[int], None], a: int, b: int) -> int:
    """Offset of an int field: the first byte where states with the values a and b differ."""
    set_int(a)
    first = serialized(fmu)
    set_int(b)
    second = serialized(fmu)
    diff = [i for i, (x, y) in enumerate(zip(first, second, strict=True)) if x != y]
    assert len(diff) == 1, diff  # a and b differ in their lowest byte only
    return diff[0]


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


# distinctive valid values: their bytes occur once in a state, which locates the variable
DISTINCT = {
    "body1.m": 10.000000123,
    "body1.x": 0.0100000001,
    "body1.y": 0.0100000002,
    "body1.vy": 0.0200000003,
    "F_ext[1]": 0.0300000004,
    "contact.cr": 0.900000005,
}
START = 0.0400000006  # the start time, as distinctive


def setup_scene(fmu: FMU, vr: dict[str, int], start: float = 0.0, **reals: float) -> None:
    """The csfh scene: q0 = [0.01, 0.01, 0], paper preset, plus the given reals."""
    fmu.setupExperiment(startTime=start)
    fmu.enterInitializationMode()
    values = {"body1.x": 0.01, "body1.y": 0.01, **reals}
    fmu.setReal([vr[k] for k in values], list(values.values()))
    fmu.exitInitializationMode()


def distinct_scene(fmu: FMU, vr: dict[str, int]) -> None:
    setup_scene(fmu, vr, START, **DISTINCT)


def restore(fmu: FMU, data: bytes, path: str) -> None:
    """Restore the bytes: through fmi2DeSerializeFMUstate + fmi2SetFMUstate ("deserialize"), or
    written over the memory of a state of this instance, then fmi2SetFMUstate ("memory": an
    importer that corrupted the state object)."""
    if path == "deserialize":
        state = fmu.deSerializeFMUstate(data)
        try:
            fmu.setFMUstate(state)
        finally:
            fmu.freeFMUstate(state)
        return
    state = fmu.getFMUstate()
    assert len(data) == len(fmu.serializeFMUstate(state))
    ctypes.memmove(state, data, len(data))
    try:
        fmu.setFMUstate(state)
    finally:
        fmu.freeFMUstate(state)


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


def assert_same(after: list[Any], before: list[Any]) -> None:
    np.testing.assert_array_equal(np.array(after, dtype=float), np.array(before, dtype=float))


def derivatives(fmu: FMU2Model) -> np.ndarray:
    dx = np.zeros(6)
    fmu.getDerivatives(dx.ctypes.data_as(POINTER(c_double)), 6)
    return dx


def assert_usable(make_fmu: MakeFmu, fmu: FMU, vr: dict[str, int], kind: str, data: bytes) -> None:
    """After a refused restore the instance goes on exactly like a twin that never saw it: the
    valid state restores, and the run from it (CS: 30 steps; ME: the derivatives) is the
    twin's, bit for bit."""
    twin, twin_log = make_fmu(kind)
    distinct_scene(twin, vr)
    for f in (fmu, twin):
        restore(f, data, "deserialize")
    if kind == "CS":
        steps = [1e-3] * 30
        np.testing.assert_array_equal(cs_run(fmu, vr, START, steps), cs_run(twin, vr, START, steps))
    else:
        np.testing.assert_array_equal(derivatives(fmu), derivatives(twin))
        assert np.all(np.isfinite(derivatives(fmu)))
    assert not twin_log.errors()


def step_status(fmu: FMU2Slave, t: float, h: float) -> int:
    """fmi2DoStep's status (fmpy raises for errors)."""
    try:
        return int(fmu.fmi2DoStep(fmu.component, t, h, fmi2True))
    except FMICallException as e:
        return int(e.status)


def cs_states(fmu: FMU2Slave, vr: dict[str, int]) -> list[float]:
    return fmu.getReal([vr[n] for n in STATES])


def cs_run(fmu: FMU2Slave, vr: dict[str, int], t: float, steps: list[float]) -> np.ndarray:
    """fmi2DoStep through the given steps from t; rows: states, energy, contact count."""
    rows = []
    for h in steps:
        fmu.doStep(t, h)
        t = t + h
        count = fmu.getInteger([vr["contact.count"]])[0]
        rows.append([*cs_states(fmu, vr), fmu.getReal([vr["energy.total"]])[0], count])
    return np.array(rows)


# ------------------------------------------------------------------------------------------
# 1. restored FMU states are checked like fmi2Set*


BAD_REALS = [
    ("body1.m", -10.0),
    ("body1.x", math.nan),
    ("body1.vy", math.inf),
    ("F_ext[1]", -math.inf),
    ("contact.cr", 1.5),
    ("time", math.nan),
]


@pytest.mark.parametrize("path", ["deserialize", "memory"])
@pytest.mark.parametrize("kind", ["ME", "CS"])
@pytest.mark.parametrize(("name", "bad"), BAD_REALS, ids=[n for n, _ in BAD_REALS])
def test_restored_state_with_a_bad_real_is_refused(
    make_fmu: MakeFmu,
    vr: dict[str, int],
    model_description: ModelDescription,
    kind: str,
    path: str,
    name: str,
    bad: float,
) -> None:
    """body1.m = -10 in the bytes of a state was accepted and the run exploded; a NaN state, an
    infinite input, c_r out of (0, 1], a NaN time likewise. Now: fmi2Error naming the variable
    and the value, the instance exactly as it was, and usable."""
    fmu, log = make_fmu(kind)
    distinct_scene(fmu, vr)
    data = serialized(fmu)
    if name == "time":  # the start time is also the release time of the (not yet) contact
        bad_data = data.replace(struct.pack("<d", START), struct.pack("<d", bad))
    else:
        where = offset_of(data, struct.pack("<d", DISTINCT[name]))
        bad_data = patched(data, where, struct.pack("<d", bad))
    before = all_values(fmu, model_description)
    with pytest.raises(FMICallException):
        restore(fmu, bad_data, path)
    assert any(names_value(m, name, bad) for m in log.errors()), log.errors()
    assert_same(all_values(fmu, model_description), before)
    assert_usable(make_fmu, fmu, vr, kind, data)


def int_field_state(
    fmu: FMU, vr: dict[str, int], name: str, setter: str, good: int, other: int
) -> tuple[bytes, int]:
    """A running state (event mode / step complete) with `name` = good, and the offset of that
    int field, found from two initialization-mode states with good and other."""
    fmu.setupExperiment(startTime=START)
    fmu.enterInitializationMode()
    fmu.setReal([vr["body1.x"], vr["body1.y"]], [0.01, 0.01])
    at = int_offset(fmu, lambda v: getattr(fmu, setter)([vr[name]], [v]), other, good)
    fmu.exitInitializationMode()
    return serialized(fmu), at


BAD_INTS = [
    ("contact.law", "setInteger", 2, 3, 77),
    ("contact.law", "setInteger", 2, 3, 0),
    ("contact.esdu_reading", "setInteger", 1, 2, -1),
    ("solver.method", "setInteger", 1, 2, 9),
    ("friction.enabled", "setBoolean", 1, 0, 2),
]


@pytest.mark.parametrize("path", ["deserialize", "memory"])
@pytest.mark.parametrize("kind", ["ME", "CS"])
@pytest.mark.parametrize(
    ("name", "setter", "good", "other", "bad"), BAD_INTS, ids=[f"{c[0]}={c[4]}" for c in BAD_INTS]
)
def test_restored_state_with_a_bad_enumeration_or_boolean_is_refused(
    make_fmu: MakeFmu,
    vr: dict[str, int],
    model_description: ModelDescription,
    kind: str,
    path: str,
    name: str,
    setter: str,
    good: int,
    other: int,
    bad: int,
) -> None:
    """contact.law = 77 in a state was accepted (the normal force then fell through every law)."""
    fmu, log = make_fmu(kind)
    data, at = int_field_state(fmu, vr, name, setter, good, other)
    assert struct.unpack_from("<i", data, at)[0] == good
    before = all_values(fmu, model_description)
    with pytest.raises(FMICallException):
        restore(fmu, patched(data, at, struct.pack("<i", bad)), path)
    assert any(names_value(m, name, bad) for m in log.errors()), log.errors()
    assert_same(all_values(fmu, model_description), before)
    restore(fmu, data, "deserialize")  # the good state still restores


def instance_state_offset(fmu: FMU, vr: dict[str, int], kind: str) -> tuple[bytes, int]:
    """A running state and the offset of its instance-state field: the 4-byte word that reads
    FMU_INITIALIZATION in a state taken in initialization mode and FMU_EVENT (ME) or
    FMU_STEP_COMPLETE (CS) in one taken after it."""
    fmu.setupExperiment(startTime=START)
    fmu.enterInitializationMode()
    fmu.setReal([vr["body1.x"], vr["body1.y"]], [0.01, 0.01])
    init = serialized(fmu)
    fmu.exitInitializationMode()
    running = serialized(fmu)
    after = FMU_EVENT if kind == "ME" else FMU_STEP_COMPLETE
    for at in range(0, 128, 4):
        if struct.unpack_from("<I", init, at)[0] == FMU_INITIALIZATION and (
            struct.unpack_from("<I", running, at)[0] == after
        ):
            return running, at
    raise AssertionError("no instance-state field found")


@pytest.mark.parametrize("path", ["deserialize", "memory"])
@pytest.mark.parametrize("kind", ["ME", "CS"])
@pytest.mark.parametrize("bad", [0, 3, 1 << 7, 1 << 20, 0xFFFFFFFF, "other-interface"])
def test_restored_state_with_a_bad_instance_state_is_refused(
    make_fmu: MakeFmu,
    vr: dict[str, int],
    model_description: ModelDescription,
    kind: str,
    path: str,
    bad: int | str,
) -> None:
    """An instance-state field of 0 was accepted and left the instance refusing every call but
    fmi2FreeInstance; two bits, the Error state (never entered by this FMU), a bit that is no
    state, or a state of the other interface (e.g. ContinuousTimeMode in a co-simulation
    instance) are refused likewise, and the instance goes on."""
    fmu, log = make_fmu(kind)
    data, at = instance_state_offset(fmu, vr, kind)
    if bad == "other-interface":
        bad = FMU_STEP_COMPLETE if kind == "ME" else FMU_EVENT
    before = all_values(fmu, model_description)
    with pytest.raises(FMICallException):
        restore(fmu, patched(data, at, struct.pack("<I", int(bad))), path)
    assert any("instance state" in m for m in log.errors()), log.errors()
    assert_same(all_values(fmu, model_description), before)
    assert_usable(make_fmu, fmu, vr, kind, data)


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_restored_state_recomputes_derived_quantities(
    make_fmu: MakeFmu, vr: dict[str, int], kind: str
) -> None:
    """The calculated parameters (contact.xi, contact.delta, ...) were read from the bytes of a
    restored state; now they are computed from its parameters, whatever the bytes say."""
    fmu, log = make_fmu(kind)
    distinct_scene(fmu, vr)
    xi, delta = fmu.getReal([vr["contact.xi"], vr["contact.delta"]])
    cr = DISTINCT["contact.cr"]
    assert xi == pytest.approx(0.75 * (1.0 - cr * cr), rel=1e-15)  # Eq. (xi) of the LN law
    data = serialized(fmu)
    # every copy of them (the law's parameters hold xi too)
    forged = data.replace(struct.pack("<d", xi), struct.pack("<d", 5.0))
    forged = forged.replace(struct.pack("<d", delta), struct.pack("<d", -1.0))
    assert forged != data
    for path in ("deserialize", "memory"):
        restore(fmu, forged, path)
        assert fmu.getReal([vr["contact.xi"], vr["contact.delta"]]) == [xi, delta]
    assert not log.errors()


def test_restored_state_with_cross_check_failure_is_refused(
    make_fmu: MakeFmu, vr: dict[str, int], model_description: ModelDescription
) -> None:
    """Each value in range, but R1 >= R2 (the model's cross-check, as at the end of
    initialization): refused after initialization."""
    fmu, log = make_fmu("CS")
    setup_scene(fmu, vr, START, **{"contact.R1": 0.180000007})
    r2 = fmu.getReal([vr["contact.R2"]])[0]
    data = serialized(fmu)
    bad = patched(data, offset_of(data, struct.pack("<d", 0.180000007)), struct.pack("<d", r2))
    before = all_values(fmu, model_description)
    with pytest.raises(FMICallException):
        restore(fmu, bad, "deserialize")
    assert any(names_value(m, "contact.R1", r2) for m in log.errors()), log.errors()
    assert_same(all_values(fmu, model_description), before)


def test_restored_state_with_a_negative_count_is_refused(
    make_fmu: MakeFmu, vr: dict[str, int]
) -> None:
    """Fields that are not parameters are checked too (the model's own check): a negative
    contact count."""
    fmu, log = make_fmu("CS")
    setup_scene(fmu, vr)
    t = 0.0
    while fmu.getInteger([vr["contact.count"]])[0] == 0:  # to the first contact
        fmu.doStep(t, 1e-3)
        t += 1e-3
    before = serialized(fmu)
    count = fmu.getInteger([vr["contact.count"]])[0]
    while fmu.getInteger([vr["contact.count"]])[0] == count:
        fmu.doStep(t, 1e-3)
        t += 1e-3
    # the first int field that went from count to count + 1 (little endian: its first byte)
    after = serialized(fmu)
    at = next(
        i
        for i in range(0, len(before) - 4)
        if struct.unpack_from("<i", before, i)[0] == count
        and struct.unpack_from("<i", after, i)[0] == count + 1
    )
    with pytest.raises(FMICallException):
        restore(fmu, patched(before, at, struct.pack("<i", -5)), "deserialize")
    assert any(names_value(m, "contact.count", -5) for m in log.errors()), log.errors()


# ------------------------------------------------------------------------------------------
# 2. large start times


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
        rows.append([*cs_states(fmu, vr), fmu.getReal([vr["energy.total"]])[0], count])
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
    contacts, on a grid the double time represents exactly at t0. Before, CVODE in the
    absolute time logged "t + h = t", returned fmi2OK and drifted."""
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
    Before: +68 % from 1e10 s; from 1e11 s the step failed after 500000 CVODE steps."""
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
# 3. the communication point: the FMU's time up to round-off, never backwards

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
    """Behind the FMU's time by more than round-off (1e-10 s at t = 0.3 s was taken before: the
    rule was 1e-9 (1 + |t|), and the time went backwards) or ahead of it: fmi2Error, nothing
    changes, the instance goes on."""
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
    back: refused. (Before: a point 1e-10 s behind with a step of 1e-11 s set the time to
    T - 9e-11.)"""
    fmu, _, T = stepped_to(make_fmu, vr, 0.3)
    t = T - 4 * ulp(T)
    before = all_values(fmu, model_description)
    assert step_status(fmu, t, 2 * ulp(T)) == ERROR
    assert_same(all_values(fmu, model_description), before)
    assert fmu.getReal([vr["time"]])[0] == T
    old_rule, _, T2 = stepped_to(make_fmu, vr, 0.3)  # what the old rule took
    assert step_status(old_rule, T2 - 1e-10, 1e-11) == ERROR
    assert old_rule.getReal([vr["time"]])[0] == T2


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


# ------------------------------------------------------------------------------------------
# found by the fuzzer (tests/fuzz)


def test_non_finite_event_indicator_is_an_error(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    """States at the edge of the double range (each finite, as any start value may be) give a
    gap of -inf: fmi2GetEventIndicators returned it with fmi2OK. Now fmi2Error naming the
    indicator and the state."""
    fmu, log = make_fmu("ME")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    # such a start is refused by the start check (test_tool_support.py); an importer can still
    # set such states in continuous-time mode
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    x = np.array([1.7e308, 1.7e308, 0.0, 0.0, 0.0, 0.0])
    fmu.setContinuousStates(x.ctypes.data_as(POINTER(c_double)), 6)
    z = np.zeros(1)
    with pytest.raises(FMICallException):
        fmu.getEventIndicators(z.ctypes.data_as(POINTER(c_double)), 1)
    assert any("non-finite event indicator z[0] = -inf" in m for m in log.errors())


# ------------------------------------------------------------------------------------------
# a rejected call changes nothing: fmi2Set* with several values is all or nothing


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_set_with_one_bad_value_changes_nothing(
    make_fmu: MakeFmu, vr: dict[str, int], model_description: ModelDescription, kind: str
) -> None:
    """fmi2SetReal([c_r, m], [0.5, -1]) applied c_r before it refused m; now nothing is set."""
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
