"""Restored FMU states are checked like values set with fmi2Set*: a state whose bytes were
changed (deserialized, or written over the memory of a state of the instance) is refused with
fmi2Error naming the variable and its value, the instance stays exactly as it was and goes on.
(FMU states the importer never freed, and the random call-sequence fuzzer under ASan + UBSan +
LeakSanitizer: tests/fuzz/.)

FMU states are opaque bytes; the tests find a variable's bytes in a serialized state by its value
(a distinctive double) or by the difference between two states that differ in that variable only,
so they do not depend on the layout."""

from __future__ import annotations

import ctypes
import math
import struct
from collections.abc import Callable

import numpy as np
import pytest
from fmi2_calls import (
    FMU,
    MakeFmu,
    all_values,
    assert_same,
    cs_run,
    derivatives,
    names_value,
    setup_scene,
)
from fmpy.fmi1 import FMICallException
from fmpy.model_description import ModelDescription

FMU_INITIALIZATION, FMU_EVENT, FMU_STEP_COMPLETE = 1 << 1, 1 << 2, 1 << 4  # fmu_instance.h


# ------------------------------------------------------------------------------------------
# helpers


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


# ------------------------------------------------------------------------------------------
# a changed value of a variable


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
    """body1.m = -10 in the bytes of a state (accepted, the run would explode), a NaN state, an
    infinite input, c_r out of (0, 1], a NaN time: fmi2Error naming the variable and the value,
    the instance exactly as it was, and usable."""
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
    """contact.law = 77 in a state is refused (accepted, the normal force would fall through
    every law)."""
    fmu, log = make_fmu(kind)
    data, at = int_field_state(fmu, vr, name, setter, good, other)
    assert struct.unpack_from("<i", data, at)[0] == good
    before = all_values(fmu, model_description)
    with pytest.raises(FMICallException):
        restore(fmu, patched(data, at, struct.pack("<i", bad)), path)
    assert any(names_value(m, name, bad) for m in log.errors()), log.errors()
    assert_same(all_values(fmu, model_description), before)
    restore(fmu, data, "deserialize")  # the good state still restores


# ------------------------------------------------------------------------------------------
# the instance's own fields


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
    """An instance-state field of 0 (accepted, it would leave the instance refusing every call
    but fmi2FreeInstance), two bits, the Error state (never entered by this FMU), a bit that is
    no state, or a state of the other interface (e.g. ContinuousTimeMode in a co-simulation
    instance) is refused, and the instance goes on."""
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
    """The calculated parameters (contact.xi, contact.delta, ...) of a restored state are
    computed from its parameters, whatever its bytes say."""
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
