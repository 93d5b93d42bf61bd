"""The FMI 3.0 build of both FMUs (build/fmi3/csfh.fmu, build/fmi3/combdrive.fmu): valid, the same
model as the FMI 2.0 build (model exchange and co-simulation reproduce it), early return of
fmi3DoStep at a contact event, and bad input refused with a message naming the variable."""

from __future__ import annotations

import math
import re
import shutil
import struct
import subprocess
import zipfile
from ctypes import POINTER, c_uint8, cast
from pathlib import Path
from typing import Any

import fmpy
import numpy as np
import pytest
from fmi2_calls import STATES
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Model, FMU3Slave, fmi3Boolean, fmi3Float64, fmi3ValueReference
from fmpy.model_description import ModelDescription
from fmpy.validation import validate_fmu, validate_model_description
from fmu_binaries import fmi3_functions, need, tool

import csfh
from csfh.model.scene import load_scene
from csfh.runners.fmu import start_values

OK, WARNING, ERROR = 0, 1, 3
SCENES = ["csfh", "central", "asymmetric"]


@pytest.fixture(scope="module")
def fmu2() -> Path:
    return csfh.fmu_path()


def fmu3_of(name: str) -> Path:
    return csfh.fmu_path(fmi_version=3) if name == "csfh" else csfh.combdrive_fmu_path(3)


# ------------------------------------------------------------------------------------------
# packaging


@pytest.mark.parametrize("name", ["csfh", "combdrive"])
def test_fmi3_fmus_are_valid(name: str) -> None:
    path = fmu3_of(name)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path), validate=True)
    assert (
        validate_model_description(md, validate_variable_names=True, validate_model_structure=True)
        == []
    )
    assert md.fmiVersion == "3.0"
    cs = md.coSimulation
    assert cs.hasEventMode and cs.mightReturnEarlyFromDoStep
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
    assert md.modelExchange is not None


@pytest.mark.parametrize("name", ["csfh", "combdrive"])
def test_fmi3_interface_is_the_fmi2_interface(name: str) -> None:
    """Same variables (names, value references, causality, start values, ranges), the same
    instantiation token, and the gap as the event indicator."""
    md2 = read_model_description(
        str(csfh.fmu_path() if name == "csfh" else csfh.combdrive_fmu_path())
    )
    md3 = read_model_description(str(fmu3_of(name)))
    assert md3.guid == md2.guid
    types = {
        "Real": "Float64",
        "Integer": "Int32",
        "Boolean": "Boolean",
        "Enumeration": "Enumeration",
    }
    v2 = {v.name: v for v in md2.modelVariables}
    v3 = {v.name: v for v in md3.modelVariables}
    assert v2.keys() == v3.keys()
    for n, a in v2.items():
        b = v3[n]
        assert (b.valueReference, b.causality, b.variability, b.type) == (
            a.valueReference,
            a.causality,
            a.variability,
            types[a.type],
        ), n
        assert (b.start, b.min, b.max, b.nominal) == (a.start, a.min, a.max, a.nominal), n
    assert len(md3.eventIndicators) == md2.numberOfEventIndicators
    if name == "csfh":
        assert [e.variable.name for e in md3.eventIndicators] == ["contact.gap"]


@pytest.mark.parametrize("name", ["csfh", "combdrive"])
def test_fmi3_binary_exports_exactly_the_fmi3_functions(name: str, tmp_path: Path) -> None:
    nm = shutil.which("nm")
    if nm is None:
        pytest.skip("nm not available")
    directory = Path(extract(str(fmu3_of(name)), unzipdir=str(tmp_path)))
    binaries = list((directory / "binaries" / "x86_64-linux").glob("*.so"))
    assert len(binaries) == 1, list(directory.rglob("*"))
    out = subprocess.run(
        [nm, "-D", "--defined-only", str(binaries[0])], check=True, capture_output=True, text=True
    ).stdout
    symbols = {line.split()[-1] for line in out.splitlines() if line.strip()}
    expected = fmi3_functions()
    assert len(expected) > 60
    assert symbols == expected


PLATFORMS = {
    "x86_64-linux": ".so",
    "x86_64-windows": ".dll",
    "x86_64-darwin": ".dylib",
    "aarch64-darwin": ".dylib",
}


@pytest.mark.parametrize("name", ["csfh", "combdrive"])
def test_fmi3_binaries_of_the_other_platforms_export_exactly_the_fmi3_functions(
    name: str, tmp_path: Path
) -> None:
    """The cross builds (cmake/platforms.cmake) give the FMI 3.0 FMUs a binary per FMI 3.0
    platform tuple; each exports exactly the fmi3* functions (win64: its export table; darwin:
    the Mach-O's global symbols), and the linux one needs glibc 2.17 at most."""
    names = set(zipfile.ZipFile(fmu3_of(name)).namelist())
    need(
        f"binaries/x86_64-windows/{name}.dll" in names,
        f"fmi3/{name}.fmu has no x86_64-windows binary (host-only build?)",
    )
    assert {f"binaries/{p}/{name}{suffix}" for p, suffix in PLATFORMS.items()} <= names
    directory = Path(extract(str(fmu3_of(name)), unzipdir=str(tmp_path)))
    expected = fmi3_functions()
    text = subprocess.run(
        [tool("objdump"), "-p", str(directory / "binaries/x86_64-windows" / f"{name}.dll")],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    table = text.split("[Ordinal/Name Pointer] Table", 1)[1].split("\n\n", 1)[0]
    assert set(re.findall(r"\]\s+(\S+)", table)) == expected
    for platform in ("x86_64-darwin", "aarch64-darwin"):
        text = subprocess.run(
            [
                tool("llvm-nm"),
                "-g",
                "--defined-only",
                str(directory / "binaries" / platform / f"{name}.dylib"),
            ],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
        symbols = {line.split()[-1] for line in text.splitlines() if line.strip()}
        assert symbols - {"__mh_dylib_header", "___dso_handle"} == {"_" + f for f in expected}
    text = subprocess.run(
        [tool("objdump"), "-T", str(directory / "binaries/x86_64-linux" / f"{name}.so")],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    versions = {tuple(int(p) for p in v.split(".")) for v in re.findall(r"GLIBC_([0-9.]+)", text)}
    assert versions and max(versions) <= (2, 17), sorted(versions)


# ------------------------------------------------------------------------------------------
# the same model: FMI 3.0 reproduces FMI 2.0


def scene_values(scene: str) -> dict[str, Any]:
    return {name: value for name, _, value in start_values(load_scene(scene), None)}


def run(path: Path, scene: str, fmi_type: str) -> np.ndarray:
    s = load_scene(scene)
    return fmpy.simulate_fmu(
        str(path),
        fmi_type=fmi_type,
        stop_time=s.stop_time,
        output_interval=2e-3,
        relative_tolerance=1e-8,
        start_values=scene_values(scene),
        output=[*STATES, "contact.gap", "contact.F_N", "contact.count"],
    )


@pytest.mark.parametrize("fmi_type", ["ModelExchange", "CoSimulation"])
@pytest.mark.parametrize("scene", SCENES)
def test_fmi3_reproduces_fmi2(fmu2: Path, fmu3: Path, scene: str, fmi_type: str) -> None:
    nominal = {v.name: v.nominal for v in read_model_description(str(fmu2)).modelVariables}
    r2 = run(fmu2, scene, fmi_type)
    r3 = run(fmu3, scene, fmi_type)
    assert len(r2) == len(r3)
    np.testing.assert_array_equal(r3["time"], r2["time"])
    assert r2["contact.count"][-1] >= 1  # the scene has impacts: events are compared too
    np.testing.assert_array_equal(r3["contact.count"], r2["contact.count"])
    for name in [*STATES, "contact.gap", "contact.F_N"]:
        # the quantity's scale: its largest value in the run, not below its nominal value
        # (a coordinate that stays 0 in a symmetric scene)
        scale = max(float(np.max(np.abs(r2[name]))), float(nominal[name] or 1.0))
        err = float(np.max(np.abs(r3[name] - r2[name])))
        assert err <= 1e-10 * scale, (name, err, scale)


# ------------------------------------------------------------------------------------------
# early return


class Log:
    def __init__(self) -> None:
        self.lines: list[tuple[int, str, str]] = []

    def __call__(self, env: object, status: int, category: bytes, message: bytes) -> None:
        self.lines.append((status, category.decode(), message.decode()))

    def errors(self) -> list[str]:
        return [m for s, _, m in self.lines if s >= ERROR]


def slave(md: ModelDescription, directory: str, log: Log, **kwargs: bool) -> FMU3Slave:
    fmu = FMU3Slave(
        guid=md.guid,
        unzipDirectory=directory,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="fmi3-test",
    )
    fmu.instantiate(logMessage=log, **kwargs)
    return fmu


def vr(md: ModelDescription, name: str) -> int:
    return next(v.valueReference for v in md.modelVariables if v.name == name)


def onset_time_fmi2_me(fmu2: Path, rtol: float) -> float:
    """The first contact onset of the default scene, located by fmpy's model-exchange solver
    (CVode root finding on the FMI 2.0 FMU's event indicator): the time of the first event row
    where contact.count goes 0 -> 1."""
    r = fmpy.simulate_fmu(
        str(fmu2),
        fmi_type="ModelExchange",
        stop_time=0.1,
        output_interval=1e-3,
        relative_tolerance=rtol,
        record_events=True,
        output=["contact.count"],
    )
    first = int(np.argmax(r["contact.count"] >= 1))
    assert r["contact.count"][first] == 1 and first > 0
    return float(r["time"][first])


def test_do_step_returns_early_at_the_contact_onset(
    fmu2: Path, md3: ModelDescription, unzipped3: str
) -> None:
    """One doStep over 0.1 s holding the first impact: with earlyReturnAllowed it ends at the
    onset (earlyReturn, lastSuccessfulTime = the FMI 2.0 ME event time within 1e-9 s, the gap
    there ~ 0, Event Mode requested); the master enters Event Mode, may set inputs, and goes on.
    Without earlyReturnAllowed the same step is not cut."""
    t_onset = onset_time_fmi2_me(fmu2, 1e-11)
    assert 0.0 < t_onset < 0.1
    for allowed in (True, False):
        log = Log()
        fmu = slave(md3, unzipped3, log, eventModeUsed=True, earlyReturnAllowed=allowed)
        try:
            fmu.enterInitializationMode(tolerance=1e-11, startTime=0.0)
            fmu.exitInitializationMode()
            fmu.updateDiscreteStates()
            fmu.enterStepMode()
            handling, terminate, early, t_last = fmu.doStep(0.0, 0.1)
            assert not terminate
            if not allowed:
                assert (handling, early, t_last) == (False, False, 0.1)
                assert fmu.getInt32([vr(md3, "contact.count")])[0] >= 1  # the impact is inside
                continue
            assert early and handling
            assert abs(t_last - t_onset) <= 1e-9, (t_last, t_onset)
            assert fmu.getInt32([vr(md3, "contact.count")])[0] == 1
            gap = fmu.getFloat64([vr(md3, "contact.gap")])[0]
            assert abs(gap) < 1e-9, gap  # at the onset the gap is zero (nominal 0.01 m)
            fmu.enterEventMode()
            fmu.setFloat64([vr(md3, "F_ext[2]")], [-1.0])  # the master's actuator update
            needs, _, _, _, _, _ = fmu.updateDiscreteStates()
            assert not needs
            fmu.enterStepMode()
            handling, _, early, t_next = fmu.doStep(t_last, 0.1 - t_last)
            assert t_next > t_last  # goes on: the next event (the release) or the end
            assert fmu.getFloat64([vr(md3, "F_ext[2]")])[0] == -1.0
            assert log.errors() == []
        finally:
            fmu.terminate()
            fmu.freeInstance()


def test_early_return_without_event_mode_stops_at_the_event(
    md3: ModelDescription, unzipped3: str
) -> None:
    """earlyReturnAllowed without eventModeUsed: the step ends at the event, no Event Mode is
    asked for; stepping on from there reaches the end with every event of the interval."""
    log = Log()
    fmu = slave(md3, unzipped3, log, eventModeUsed=False, earlyReturnAllowed=True)
    try:
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        t, returns = 0.0, 0
        while t < 0.3:
            handling, _, early, t_last = fmu.doStep(t, 0.3 - t)
            assert not handling
            returns += int(early)
            t = t_last if early else 0.3
            assert returns < 100
        count = fmu.getInt32([vr(md3, "contact.count")])[0]
        # every onset and every release ends a step (the last release may be still to come)
        assert count >= 2 and returns in (2 * count - 1, 2 * count), (returns, count)
    finally:
        fmu.terminate()
        fmu.freeInstance()


# ------------------------------------------------------------------------------------------
# bad input: fmi3Error, a message naming the variable and its value, the instance still usable


def started_slave(md: ModelDescription, directory: str, log: Log) -> FMU3Slave:
    fmu = slave(md, directory, log, eventModeUsed=False, earlyReturnAllowed=False)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    return fmu


def expect_error(log: Log, call: Any, *needles: str) -> None:
    with pytest.raises(FMICallException) as info:
        call()
    assert info.value.status == ERROR
    text = "\n".join(log.errors())
    for needle in needles:
        assert needle in text, (needle, text)


def test_bad_input_is_refused_and_the_instance_stays_usable(
    md3: ModelDescription, unzipped3: str
) -> None:
    log = Log()
    fmu = slave(md3, unzipped3, log, eventModeUsed=False, earlyReturnAllowed=False)
    try:
        m = vr(md3, "body1.m")
        expect_error(log, lambda: fmu.setFloat64([m], [-10.0]), "body1.m = -10", "out of range")
        expect_error(log, lambda: fmu.setFloat64([m], [math.nan]), "body1.m = nan", "not finite")
        law = vr(md3, "contact.law")
        expect_error(
            log, lambda: fmu.setInt64([law], [99]), "contact.law = 99", "not a valid enumeration"
        )
        expect_error(
            log, lambda: fmu.setInt64([law], [2**40]), f"contact.law = {2**40}", "enumeration"
        )
        # an enumeration is an Int64 in FMI 3.0, not an Int32
        expect_error(log, lambda: fmu.setInt32([law], [1]), f"unknown value reference {law}")
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        fmu.doStep(0.0, 0.01)  # still usable
        assert fmu.getFloat64([m])[0] == pytest.approx(md3_start(md3, "body1.m"))
        fmu.terminate()
    finally:
        fmu.freeInstance()


def md3_start(md: ModelDescription, name: str) -> float:
    return float(next(v.start for v in md.modelVariables if v.name == name))


def test_corrupted_serialized_state_is_refused(md3: ModelDescription, unzipped3: str) -> None:
    """A serialized state whose mass was overwritten with -10 kg is refused at deserialization
    with a message naming body1.m and the value; a good state of the same run restores."""
    log = Log()
    fmu = started_slave(md3, unzipped3, log)
    try:
        m = vr(md3, "body1.m")
        mass = 10.000000123  # bytes that occur once in the state
        fmu.terminate()
        fmu.reset()
        fmu.setFloat64([m], [mass])
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        fmu.doStep(0.0, 0.02)
        state = fmu.getFMUState()
        data = bytes(fmu.serializeFMUState(state))
        fmu.freeFMUState(state)
        packed = struct.pack("<d", mass)
        at = data.find(packed)
        assert at >= 0 and data.find(packed, at + 1) < 0
        bad = data[:at] + struct.pack("<d", -10.0) + data[at + 8 :]
        expect_error(log, lambda: fmu.deserializeFMUState(bad), "body1.m = -10")
        expect_error(log, lambda: fmu.deserializeFMUState(data[:-1]), "size")
        y = fmu.getFloat64([vr(md3, "body1.y")])[0]
        fmu.doStep(0.02, 0.01)
        good = fmu.deserializeFMUState(data)
        fmu.setFMUState(good)
        fmu.freeFMUState(good)
        assert fmu.getFloat64([vr(md3, "body1.y")])[0] == y
        fmu.doStep(0.02, 0.01)  # usable after the refused ones
    finally:
        fmu.terminate()
        fmu.freeInstance()


def test_model_exchange_event_indicator_is_the_gap(md3: ModelDescription, unzipped3: str) -> None:
    """FMI 3.0 model exchange: one event indicator, equal to contact.gap out of contact."""
    log = Log()
    fmu = FMU3Model(
        guid=md3.guid,
        unzipDirectory=unzipped3,
        modelIdentifier=md3.modelExchange.modelIdentifier,
        instanceName="fmi3-me",
    )
    fmu.instantiate(logMessage=log)
    try:
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        fmu.updateDiscreteStates()
        fmu.enterContinuousTimeMode()
        assert fmu.getNumberOfEventIndicators() == 1
        assert fmu.getNumberOfContinuousStates() == 6
        z = (fmi3Float64 * 1)()
        fmu.getEventIndicators(z, 1)
        gap = fmu.getFloat64([vr(md3, "contact.gap")])[0]
        assert z[0] == gap and gap > 0
        x = (fmi3Float64 * 6)(*([math.nan] * 6))
        expect_error(log, lambda: fmu.setContinuousStates(x, 6), "x[0] = nan")
    finally:
        fmu.terminate()
        fmu.freeInstance()


# ------------------------------------------------------------------------------------------
# foreign booleans: an importer's fmi3Boolean array is bytes, any nonzero one is true

BOOLEANS = (
    "friction.enabled",
    "flexure.enabled",
    "flexure.track_stress_peak",
    "initial.from_parameters",
)


def run_with_booleans(md: ModelDescription, directory: str, raw: list[int] | None) -> list[Any]:
    """Set the BOOLEANS (from the raw bytes, or as Python's True/False: fmpy's 0 and 1), then run
    0.1 s; what the instance reads back and its state at the end."""
    log = Log()
    fmu = slave(md, directory, log, eventModeUsed=False, earlyReturnAllowed=False)
    try:
        fmu.enterInitializationMode(startTime=0.0)
        refs = [vr(md, name) for name in BOOLEANS]
        if raw is None:
            fmu.setBoolean(refs, [True, True, True, False])
        else:
            data = (c_uint8 * len(raw))(*raw)
            fmu.fmi3SetBoolean(
                fmu.component,
                (fmi3ValueReference * len(refs))(*refs),
                len(refs),
                cast(data, POINTER(fmi3Boolean)),
                len(raw),
            )
        read = list(fmu.getBoolean(refs))
        fmu.exitInitializationMode()
        fmu.doStep(0.0, 0.1)
        assert not log.errors(), log.errors()
        return [*read, *fmu.getFloat64([vr(md, name) for name in STATES])]
    finally:
        fmu.freeInstance()


@pytest.mark.parametrize("true", [2, 0x7F, 0x80, 0xFF])
def test_foreign_boolean_bytes_are_true(md3: ModelDescription, unzipped3: str, true: int) -> None:
    """fmi3SetBoolean reads each value as its byte (never as C's bool, which may only hold 0 or
    1): a byte `true` is true, 0 is false, and the run is bit for bit the run with 1 and 0."""
    foreign = run_with_booleans(md3, unzipped3, [true, true, 1, 0])
    assert foreign[:4] == [True, True, True, False]
    assert foreign == run_with_booleans(md3, unzipped3, None)
