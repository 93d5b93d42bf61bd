"""The FMI 2.0 interface of the FMU: packaging, drift between modelDescription.xml and the C
variable table, the state machine, NULL arguments, and reads that follow new states. (Bad input:
test_fmi2_bad_input.py.)"""

from __future__ import annotations

import ctypes
import math
import re
import shutil
import subprocess
from collections.abc import Callable
from ctypes import POINTER, byref, c_char, c_char_p, c_double, c_int, c_size_t, c_uint, c_void_p
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fmi2_calls import (
    ERROR,
    OK,
    MakeFmu,
    assert_fmi_error,
    get_value,
    initialized,
    xml_start,
)
from fmpy.fmi2 import fmi2CallbackFunctions, fmi2EventInfo
from fmpy.model_description import ModelDescription
from fmpy.validation import validate_fmu
from fmu_binaries import fmi2_functions

ME, CS = 0, 1  # fmi2Type

# ------------------------------------------------------------------------------------------
# helpers


def shared_library(unzipped: str) -> Path:
    return Path(unzipped) / "binaries" / "linux64" / "csfh.so"


class Raw:
    """The exported C functions, called directly (NULL arguments, wrong instance types)."""

    _SIGNATURES: tuple[tuple[str, Any, tuple[Any, ...]], ...] = (
        (
            "fmi2Instantiate",
            c_void_p,
            (c_char_p, c_int, c_char_p, c_char_p, POINTER(fmi2CallbackFunctions), c_int, c_int),
        ),
        ("fmi2FreeInstance", None, (c_void_p,)),
        ("fmi2SetDebugLogging", c_int, (c_void_p, c_int, c_size_t, POINTER(c_char_p))),
        ("fmi2SetupExperiment", c_int, (c_void_p, c_int, c_double, c_double, c_int, c_double)),
        ("fmi2EnterInitializationMode", c_int, (c_void_p,)),
        ("fmi2ExitInitializationMode", c_int, (c_void_p,)),
        ("fmi2Terminate", c_int, (c_void_p,)),
        ("fmi2Reset", c_int, (c_void_p,)),
        ("fmi2GetReal", c_int, (c_void_p, POINTER(c_uint), c_size_t, POINTER(c_double))),
        ("fmi2GetInteger", c_int, (c_void_p, POINTER(c_uint), c_size_t, POINTER(c_int))),
        ("fmi2GetBoolean", c_int, (c_void_p, POINTER(c_uint), c_size_t, POINTER(c_int))),
        ("fmi2GetString", c_int, (c_void_p, POINTER(c_uint), c_size_t, POINTER(c_char_p))),
        ("fmi2SetReal", c_int, (c_void_p, POINTER(c_uint), c_size_t, POINTER(c_double))),
        ("fmi2SetInteger", c_int, (c_void_p, POINTER(c_uint), c_size_t, POINTER(c_int))),
        ("fmi2SetBoolean", c_int, (c_void_p, POINTER(c_uint), c_size_t, POINTER(c_int))),
        ("fmi2SetString", c_int, (c_void_p, POINTER(c_uint), c_size_t, POINTER(c_char_p))),
        ("fmi2GetFMUstate", c_int, (c_void_p, POINTER(c_void_p))),
        ("fmi2SetFMUstate", c_int, (c_void_p, c_void_p)),
        ("fmi2FreeFMUstate", c_int, (c_void_p, POINTER(c_void_p))),
        ("fmi2SerializedFMUstateSize", c_int, (c_void_p, c_void_p, POINTER(c_size_t))),
        ("fmi2SerializeFMUstate", c_int, (c_void_p, c_void_p, POINTER(c_char), c_size_t)),
        (
            "fmi2DeSerializeFMUstate",
            c_int,
            (c_void_p, POINTER(c_char), c_size_t, POINTER(c_void_p)),
        ),
        (
            "fmi2GetDirectionalDerivative",
            c_int,
            (
                c_void_p,
                POINTER(c_uint),
                c_size_t,
                POINTER(c_uint),
                c_size_t,
                POINTER(c_double),
                POINTER(c_double),
            ),
        ),
        ("fmi2EnterEventMode", c_int, (c_void_p,)),
        ("fmi2NewDiscreteStates", c_int, (c_void_p, POINTER(fmi2EventInfo))),
        ("fmi2EnterContinuousTimeMode", c_int, (c_void_p,)),
        ("fmi2CompletedIntegratorStep", c_int, (c_void_p, c_int, POINTER(c_int), POINTER(c_int))),
        ("fmi2SetTime", c_int, (c_void_p, c_double)),
        ("fmi2SetContinuousStates", c_int, (c_void_p, POINTER(c_double), c_size_t)),
        ("fmi2GetDerivatives", c_int, (c_void_p, POINTER(c_double), c_size_t)),
        ("fmi2GetEventIndicators", c_int, (c_void_p, POINTER(c_double), c_size_t)),
        ("fmi2GetContinuousStates", c_int, (c_void_p, POINTER(c_double), c_size_t)),
        ("fmi2GetNominalsOfContinuousStates", c_int, (c_void_p, POINTER(c_double), c_size_t)),
        (
            "fmi2SetRealInputDerivatives",
            c_int,
            (c_void_p, POINTER(c_uint), c_size_t, POINTER(c_int), POINTER(c_double)),
        ),
        (
            "fmi2GetRealOutputDerivatives",
            c_int,
            (c_void_p, POINTER(c_uint), c_size_t, POINTER(c_int), POINTER(c_double)),
        ),
        ("fmi2DoStep", c_int, (c_void_p, c_double, c_double, c_int)),
        ("fmi2CancelStep", c_int, (c_void_p,)),
        ("fmi2GetStatus", c_int, (c_void_p, c_int, POINTER(c_int))),
        ("fmi2GetRealStatus", c_int, (c_void_p, c_int, POINTER(c_double))),
        ("fmi2GetIntegerStatus", c_int, (c_void_p, c_int, POINTER(c_int))),
        ("fmi2GetBooleanStatus", c_int, (c_void_p, c_int, POINTER(c_int))),
        ("fmi2GetStringStatus", c_int, (c_void_p, c_int, POINTER(c_char_p))),
    )

    def __init__(self, path: Path) -> None:
        self.lib = ctypes.CDLL(str(path))
        self.f: dict[str, Any] = {}
        for name, restype, argtypes in self._SIGNATURES:
            fn = getattr(self.lib, name)
            fn.restype = restype
            fn.argtypes = list(argtypes)
            self.f[name] = fn

    def __call__(self, name: str, *args: Any) -> Any:
        return self.f[name](*args)


def vrs(*refs: int) -> Any:
    return (c_uint * len(refs))(*refs)


@pytest.fixture
def raw(unzipped: str) -> Raw:
    return Raw(shared_library(unzipped))


# ------------------------------------------------------------------------------------------
# packaging


def test_validate_fmu_finds_no_problem(fmu_path: Path) -> None:
    assert validate_fmu(str(fmu_path)) == []


def test_binary_exports_only_fmi2_symbols(unzipped: str) -> None:
    nm = shutil.which("nm")
    if nm is None:
        pytest.skip("nm not available")
    out = subprocess.run(
        [nm, "-D", "--defined-only", str(shared_library(unzipped))],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    symbols = {line.split()[-1] for line in out.splitlines() if line.strip()}
    assert symbols, out
    assert {s for s in symbols if not s.startswith("fmi2")} == set()
    assert symbols == fmi2_functions()


def test_binary_links_only_libc_and_libm(unzipped: str) -> None:
    ldd = shutil.which("ldd")
    if ldd is None:
        pytest.skip("ldd not available")
    out = subprocess.run(
        [ldd, str(shared_library(unzipped))], check=True, capture_output=True, text=True
    ).stdout
    allowed = re.compile(
        r"^(linux-vdso\.so|linux-gate\.so|libc\.so|libm\.so|ld-linux[-\w.]*\.so"
        r"|/lib(64|x32)?/ld-linux[-\w.]*\.so)"
    )
    libraries = [line.split()[0] for line in out.splitlines() if line.strip()]
    assert libraries, out
    assert [
        lib for lib in libraries if not allowed.match(Path(lib).name) and not allowed.match(lib)
    ] == [], out


# ------------------------------------------------------------------------------------------
# drift between modelDescription.xml and the C variable table


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_start_values_match_the_xml(
    make_fmu: MakeFmu, model_description: ModelDescription, kind: str
) -> None:
    fmu, log = make_fmu(kind)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    with_start = [v for v in model_description.modelVariables if v.start is not None]
    assert len(with_start) > 50
    mismatches = {
        v.name: (get_value(fmu, v), xml_start(v))
        for v in with_start
        if get_value(fmu, v) != xml_start(v)
    }
    assert mismatches == {}
    # vector reads give the same values as single reads
    reals = [v for v in with_start if v.type == "Real"]
    assert fmu.getReal([v.valueReference for v in reals]) == [float(v.start) for v in reals]
    fmu.exitInitializationMode()
    assert not log.errors()


@pytest.mark.parametrize("kind", ["ME", "CS"])
@pytest.mark.parametrize("phase", ["initialization", "running"])
def test_every_value_reference_is_accepted(
    make_fmu: MakeFmu, model_description: ModelDescription, kind: str, phase: str
) -> None:
    fmu, log = make_fmu(kind)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    if phase == "running":
        fmu.exitInitializationMode()
    for v in model_description.modelVariables:
        value = get_value(fmu, v)
        if v.type == "Real":
            assert math.isfinite(value), v.name
    assert not log.errors()


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_getter_of_another_type_is_rejected(
    make_fmu: MakeFmu, vr: dict[str, int], kind: str
) -> None:
    fmu, log = initialized(make_fmu, kind)
    assert_fmi_error(lambda: fmu.getReal([vr["contact.count"]]))
    assert_fmi_error(lambda: fmu.getInteger([vr["body1.x"]]))
    assert_fmi_error(lambda: fmu.getBoolean([vr["contact.law"]]))
    assert_fmi_error(lambda: fmu.setReal([vr["contact.law"]], [2.0]))
    assert f"unknown value reference {vr['contact.count']}" in log.text()


@pytest.mark.parametrize("kind", ["ME", "CS"])
@pytest.mark.parametrize("ref", [7, 17, 60, 94, 100, 129, 199, 9999, 2**32 - 1])
def test_unknown_value_reference_is_rejected(
    make_fmu: MakeFmu, model_description: ModelDescription, kind: str, ref: int
) -> None:
    assert ref not in {v.valueReference for v in model_description.modelVariables}
    fmu, log = initialized(make_fmu, kind)
    getters: list[Callable[[], object]] = [
        lambda: fmu.getReal([ref]),
        lambda: fmu.getInteger([ref]),
        lambda: fmu.getBoolean([ref]),
        lambda: fmu.setReal([ref], [1.0]),
        lambda: fmu.setInteger([ref], [1]),
        lambda: fmu.setBoolean([ref], [1]),
    ]
    for call in getters:
        before = len(log.errors())
        assert_fmi_error(call)
        new = log.errors()[before:]
        assert any(re.search(rf"\b{ref}\b", m) for m in new), new
    # a bad reference in the middle of a vector call is found as well
    assert_fmi_error(lambda: fmu.getReal([1, 2, ref, 3]))


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_calculated_parameters(make_fmu: MakeFmu, vr: dict[str, int], kind: str) -> None:
    fmu, _ = initialized(make_fmu, kind)

    def get(name: str) -> float:
        return fmu.getReal([vr[name]])[0]

    assert get("contact.delta") == pytest.approx(0.02, rel=1e-12)
    assert get("contact.K_spheres") == pytest.approx(4.73528e10, rel=2e-5)
    assert get("contact.K_cylinders") == pytest.approx(2.26562e9, rel=1e-4)
    assert get("flexure.sbar[1]") == pytest.approx(0.2920, abs=5e-5)
    assert get("flexure.sbar[2]") == pytest.approx(-0.02471, abs=5e-6)
    assert get("contact.xi") == pytest.approx(0.75 * (1.0 - 0.9 * 0.9), rel=1e-15)
    # docs/model.md §4.5: F* = 4 L dR / (sigma1 + sigma2) with sigma = (1 - nu^2)/(pi E) (E = 210
    # GPa, nu = 0.3, L = 0.025 m, dR = 0.02 m): 7.25e8 N, where d rho/dF of Eq. (18) vanishes
    sigma = (1 - 0.3**2) / (math.pi * 210e9)
    F_star = 4 * 0.025 * 0.02 / (2 * sigma)
    assert get("contact.esdu_F_max") == pytest.approx(F_star, rel=1e-12)


# ------------------------------------------------------------------------------------------
# illegal call sequences: fmi2Error, a log line, and the instance keeps working


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_illegal_calls_before_initialization(
    make_fmu: MakeFmu, vr: dict[str, int], kind: str
) -> None:
    fmu, log = make_fmu(kind)
    assert_fmi_error(fmu.exitInitializationMode)
    assert "fmi2ExitInitializationMode: illegal call in state Instantiated" in log.text()
    assert_fmi_error(lambda: fmu.getReal([vr["body1.x"]]))
    assert_fmi_error(fmu.terminate)
    if kind == "CS":
        assert_fmi_error(lambda: fmu.doStep(0.0, 1e-3))
    else:
        assert_fmi_error(fmu.enterEventMode)
        assert_fmi_error(fmu.enterContinuousTimeMode)
        assert_fmi_error(fmu.newDiscreteStates)
    # nothing was broken: the normal sequence still works
    fmu.setupExperiment(startTime=0.0)
    fmu.setupExperiment(startTime=0.0)  # repeated before initialization: allowed
    fmu.enterInitializationMode()
    assert_fmi_error(fmu.enterInitializationMode)
    assert_fmi_error(lambda: fmu.setupExperiment(startTime=0.0))
    fmu.exitInitializationMode()
    assert fmu.getReal([vr["body1.x"]]) == [0.01]


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_illegal_calls_after_initialization(
    make_fmu: MakeFmu, vr: dict[str, int], kind: str
) -> None:
    fmu, log = initialized(make_fmu, kind)
    assert_fmi_error(lambda: fmu.setupExperiment(startTime=0.0))
    assert "fmi2SetupExperiment: illegal call" in log.text()
    assert_fmi_error(fmu.enterInitializationMode)
    assert_fmi_error(fmu.exitInitializationMode)
    # fixed parameters, calculated parameters, state start values and outputs cannot be set
    for name, value in [
        ("contact.R1", 0.17),
        ("body1.m", 5.0),
        ("contact.delta", 0.01),
        ("body1.x", 0.0),
        ("contact.F_N", 1.0),
        ("energy.total", 0.0),
        ("der(body1.vx)", 0.0),
        ("time", 1.0),
    ]:
        before = fmu.getReal([vr[name]])
        assert_fmi_error(lambda name=name, value=value: fmu.setReal([vr[name]], [value]))
        assert f"variable {name} cannot be set" in log.text()
        assert fmu.getReal([vr[name]]) == before
    assert_fmi_error(lambda: fmu.setInteger([vr["contact.law"]], [3]))
    assert_fmi_error(lambda: fmu.setInteger([vr["contact.count"]], [5]))
    assert_fmi_error(lambda: fmu.setBoolean([vr["flexure.enabled"]], [False]))
    assert_fmi_error(lambda: fmu.setBoolean([vr["contact.active"]], [True]))
    assert fmu.getInteger([vr["contact.law"]]) == [2]
    # a parameter is no known of a directional derivative (docs/guide/fmu.md)
    assert_fmi_error(lambda: fmu.getDirectionalDerivative([vr["body1.x"]], [vr["body1.m"]], [1.0]))
    assert f"knowns[0] = {vr['body1.m']} (body1.m) is not" in log.text()


def test_illegal_model_exchange_sequences(make_fmu: MakeFmu, vr: dict[str, int], raw: Raw) -> None:
    fmu, log = initialized(make_fmu, "ME")  # event mode
    x = np.array([0.01, 0.01, 0.0, 0.0, 0.0, 0.0])
    px = x.ctypes.data_as(POINTER(c_double))
    assert_fmi_error(lambda: fmu.setContinuousStates(px, 6))
    assert "fmi2SetContinuousStates: illegal call in state EventMode" in log.text()
    assert_fmi_error(fmu.completedIntegratorStep)
    assert raw("fmi2DoStep", fmu.component, 0.0, 1e-3, 1) == ERROR
    assert raw("fmi2CancelStep", fmu.component) == ERROR
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    assert_fmi_error(fmu.newDiscreteStates)
    assert "fmi2NewDiscreteStates: illegal call in state ContinuousTimeMode" in log.text()
    assert_fmi_error(fmu.enterContinuousTimeMode)
    assert raw("fmi2DoStep", fmu.component, 0.0, 1e-3, 1) == ERROR
    assert_fmi_error(lambda: fmu.setContinuousStates(px, 5))  # wrong size
    assert_fmi_error(lambda: fmu.getDerivatives(px, 7))
    assert_fmi_error(lambda: fmu.setTime(math.nan))
    # still usable
    fmu.setTime(1e-3)
    fmu.setContinuousStates(px, 6)
    dx = np.zeros(6)
    fmu.getDerivatives(dx.ctypes.data_as(POINTER(c_double)), 6)
    assert np.all(np.isfinite(dx))
    fmu.terminate()
    assert_fmi_error(fmu.enterEventMode)
    assert_fmi_error(lambda: fmu.setTime(1.0))


def test_illegal_co_simulation_sequences(make_fmu: MakeFmu, vr: dict[str, int], raw: Raw) -> None:
    fmu, log = initialized(make_fmu, "CS")
    for fn in ("fmi2EnterEventMode", "fmi2EnterContinuousTimeMode"):
        assert raw(fn, fmu.component) == ERROR
    info = fmi2EventInfo()
    assert raw("fmi2NewDiscreteStates", fmu.component, byref(info)) == ERROR
    x = (c_double * 6)()
    assert raw("fmi2GetContinuousStates", fmu.component, x, 6) == ERROR
    assert raw("fmi2SetTime", fmu.component, 0.5) == ERROR
    assert "only for model exchange" in log.text() or "illegal call" in log.text()
    assert_fmi_error(lambda: fmu.doStep(0.0, -1e-3))  # rejected arguments: nothing happens
    assert_fmi_error(lambda: fmu.doStep(0.0, math.inf))
    assert_fmi_error(lambda: fmu.doStep(math.nan, 1e-3))
    assert_fmi_error(lambda: fmu.setRealInputDerivatives([vr["F_ext[1]"]], [1], [1.0]))
    fmu.doStep(0.0, 1e-3)  # still usable
    assert fmu.getReal([vr["time"]])[0] == pytest.approx(1e-3)
    # a communication point that does not match the FMU time is refused: nothing happens
    assert_fmi_error(lambda: fmu.doStep(0.5, 1e-3))
    assert "does not match the FMU time" in log.text()
    assert fmu.getReal([vr["time"]])[0] == pytest.approx(1e-3)
    fmu.doStep(1e-3, 1e-3)  # still usable
    # a step that really fails (non-finite derivative) leaves the FMU in StepFailed
    fmu.setReal([vr["F_ext[2]"]], [1e308])
    fmu.setReal([vr["F_ext[1]"]], [1e308])
    assert_fmi_error(lambda: fmu.doStep(2e-3, 1e-3))
    assert_fmi_error(lambda: fmu.doStep(2e-3, 1e-3))  # StepFailed: no further steps
    assert "illegal call in state StepFailed" in log.text()
    assert fmu.getReal([vr["time"]])[0] == pytest.approx(2e-3)  # reading is still allowed
    fmu.terminate()
    assert_fmi_error(lambda: fmu.doStep(1e-3, 1e-3))
    assert_fmi_error(lambda: fmu.setReal([vr["F_ext[1]"]], [1.0]))


def test_failed_step_blocks_further_steps(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    fmu, log = make_fmu("CS")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([vr["g"]], [1e308])  # legal, but m g overflows: non-finite derivative
    fmu.exitInitializationMode()
    assert_fmi_error(lambda: fmu.doStep(0.0, 1e-3))
    assert log.errors()
    assert_fmi_error(lambda: fmu.doStep(0.0, 1e-3))
    assert "illegal call in state StepFailed" in log.text()
    fmu.reset()  # reset brings it back
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 1e-3)


# ------------------------------------------------------------------------------------------
# NULL arguments and wrong GUID, through the C functions directly


def test_null_arguments_return_error(make_fmu: MakeFmu, vr: dict[str, int], raw: Raw) -> None:
    fmu, log = initialized(make_fmu, "ME")  # event mode
    c = fmu.component
    ref = vrs(vr["body1.x"])
    real = (c_double * 1)()
    integer = (c_int * 1)()
    null = None
    calls: list[tuple[str, tuple[Any, ...]]] = [
        ("fmi2GetReal", (c, null, 1, real)),
        ("fmi2GetReal", (c, ref, 1, null)),
        ("fmi2GetInteger", (c, null, 1, integer)),
        ("fmi2GetInteger", (c, vrs(vr["contact.count"]), 1, null)),
        ("fmi2GetBoolean", (c, null, 1, integer)),
        ("fmi2GetBoolean", (c, vrs(vr["contact.active"]), 1, null)),
        ("fmi2GetString", (c, null, 1, null)),
        ("fmi2SetReal", (c, null, 1, real)),
        ("fmi2SetReal", (c, vrs(vr["F_ext[1]"]), 1, null)),
        ("fmi2SetInteger", (c, null, 1, integer)),
        ("fmi2SetInteger", (c, vrs(vr["contact.law"]), 1, null)),
        ("fmi2SetBoolean", (c, null, 1, integer)),
        ("fmi2SetBoolean", (c, vrs(vr["friction.enabled"]), 1, null)),
        ("fmi2SetString", (c, null, 1, null)),
        ("fmi2SetDebugLogging", (c, 1, 2, null)),
        ("fmi2NewDiscreteStates", (c, null)),
        ("fmi2GetFMUstate", (c, null)),
        ("fmi2SetFMUstate", (c, null)),
        ("fmi2SerializedFMUstateSize", (c, null, byref(c_size_t()))),
        ("fmi2SerializeFMUstate", (c, null, ctypes.create_string_buffer(8), 8)),
        ("fmi2DeSerializeFMUstate", (c, null, 8, byref(c_void_p()))),
        ("fmi2GetDerivatives", (c, null, 6)),
        ("fmi2GetEventIndicators", (c, null, 1)),
        ("fmi2GetContinuousStates", (c, null, 6)),
        ("fmi2GetNominalsOfContinuousStates", (c, null, 6)),
    ]
    for name, args in calls:
        assert raw(name, *args) == ERROR, name
    assert "argument vr is NULL" in log.text() and "argument value is NULL" in log.text()
    assert "fmi2NewDiscreteStates: argument eventInfo is NULL" in log.text()
    assert "fmi2SetFMUstate: argument FMUstate is NULL" in log.text()

    # state functions with a valid state but NULL outputs
    state = c_void_p()
    assert raw("fmi2GetFMUstate", c, byref(state)) == OK
    assert raw("fmi2SerializedFMUstateSize", c, state, null) == ERROR
    assert raw("fmi2SerializeFMUstate", c, state, null, 1 << 20) == ERROR
    size = c_size_t()
    assert raw("fmi2SerializedFMUstateSize", c, state, byref(size)) == OK
    buffer = ctypes.create_string_buffer(size.value)
    assert raw("fmi2SerializeFMUstate", c, state, buffer, size.value - 1) == ERROR
    assert raw("fmi2SerializeFMUstate", c, state, buffer, size.value) == OK
    assert raw("fmi2DeSerializeFMUstate", c, buffer, size.value, null) == ERROR
    assert raw("fmi2DeSerializeFMUstate", c, buffer, size.value - 1, byref(c_void_p())) == ERROR
    garbage = ctypes.create_string_buffer(size.value)
    assert raw("fmi2DeSerializeFMUstate", c, garbage, size.value, byref(c_void_p())) == ERROR
    assert raw("fmi2FreeFMUstate", c, byref(state)) == OK
    assert state.value is None
    assert raw("fmi2FreeFMUstate", c, null) == OK  # FMI 2.0: a NULL state is ignored

    # continuous-time mode functions
    fmu.enterContinuousTimeMode()
    assert raw("fmi2SetContinuousStates", c, null, 6) == ERROR
    assert raw("fmi2CompletedIntegratorStep", c, 1, null, null) == ERROR
    flag = c_int()
    assert raw("fmi2CompletedIntegratorStep", c, 1, byref(flag), null) == ERROR

    # the instance survived all of this
    fmu.setTime(1e-3)
    assert fmu.getReal([vr["body1.x"]]) == [0.01]


def test_null_arguments_co_simulation(make_fmu: MakeFmu, vr: dict[str, int], raw: Raw) -> None:
    fmu, _ = initialized(make_fmu, "CS")
    c = fmu.component
    assert raw("fmi2GetReal", c, None, 1, (c_double * 1)()) == ERROR
    assert raw("fmi2SetReal", c, vrs(vr["F_ext[1]"]), 1, None) == ERROR
    assert raw("fmi2GetFMUstate", c, None) == ERROR
    assert raw("fmi2SetFMUstate", c, None) == ERROR
    assert raw("fmi2GetRealOutputDerivatives", c, None, 1, None, None) == ERROR
    assert raw("fmi2SetRealInputDerivatives", c, None, 1, None, None) == ERROR
    fmu.doStep(0.0, 1e-3)
    # nvr = 0 with NULL arrays is a legal no-op
    assert raw("fmi2GetReal", c, None, 0, None) == OK
    assert raw("fmi2SetReal", c, None, 0, None) == OK


def test_null_component_returns_error(raw: Raw) -> None:
    null = None
    real = (c_double * 6)()
    integer = (c_int * 1)()
    ref = vrs(1)
    calls: list[tuple[str, tuple[Any, ...]]] = [
        ("fmi2SetDebugLogging", (null, 1, 0, null)),
        ("fmi2SetupExperiment", (null, 0, 0.0, 0.0, 0, 0.0)),
        ("fmi2EnterInitializationMode", (null,)),
        ("fmi2ExitInitializationMode", (null,)),
        ("fmi2Terminate", (null,)),
        ("fmi2Reset", (null,)),
        ("fmi2GetReal", (null, ref, 1, real)),
        ("fmi2GetInteger", (null, ref, 1, integer)),
        ("fmi2GetBoolean", (null, ref, 1, integer)),
        ("fmi2GetString", (null, ref, 1, (c_char_p * 1)())),
        ("fmi2SetReal", (null, ref, 1, real)),
        ("fmi2SetInteger", (null, ref, 1, integer)),
        ("fmi2SetBoolean", (null, ref, 1, integer)),
        ("fmi2SetString", (null, ref, 1, (c_char_p * 1)())),
        ("fmi2GetFMUstate", (null, byref(c_void_p()))),
        ("fmi2SetFMUstate", (null, null)),
        ("fmi2FreeFMUstate", (null, byref(c_void_p()))),
        ("fmi2SerializedFMUstateSize", (null, null, byref(c_size_t()))),
        ("fmi2SerializeFMUstate", (null, null, null, 0)),
        ("fmi2DeSerializeFMUstate", (null, null, 0, byref(c_void_p()))),
        ("fmi2GetDirectionalDerivative", (null, ref, 1, ref, 1, real, real)),
        ("fmi2EnterEventMode", (null,)),
        ("fmi2NewDiscreteStates", (null, byref(fmi2EventInfo()))),
        ("fmi2EnterContinuousTimeMode", (null,)),
        ("fmi2CompletedIntegratorStep", (null, 1, byref(c_int()), byref(c_int()))),
        ("fmi2SetTime", (null, 0.0)),
        ("fmi2SetContinuousStates", (null, real, 6)),
        ("fmi2GetDerivatives", (null, real, 6)),
        ("fmi2GetEventIndicators", (null, real, 1)),
        ("fmi2GetContinuousStates", (null, real, 6)),
        ("fmi2GetNominalsOfContinuousStates", (null, real, 6)),
        ("fmi2SetRealInputDerivatives", (null, ref, 1, integer, real)),
        ("fmi2GetRealOutputDerivatives", (null, ref, 1, integer, real)),
        ("fmi2DoStep", (null, 0.0, 1e-3, 1)),
        ("fmi2CancelStep", (null,)),
        ("fmi2GetStatus", (null, 0, byref(c_int()))),
        ("fmi2GetRealStatus", (null, 2, byref(c_double()))),
        ("fmi2GetIntegerStatus", (null, 0, byref(c_int()))),
        ("fmi2GetBooleanStatus", (null, 3, byref(c_int()))),
        ("fmi2GetStringStatus", (null, 0, byref(c_char_p()))),
    ]
    failing = [name for name, args in calls if raw(name, *args) != ERROR]
    assert failing == []
    raw("fmi2FreeInstance", null)  # must not crash


def test_instantiate_checks_its_arguments(
    make_fmu: MakeFmu, model_description: ModelDescription, raw: Raw
) -> None:
    _, log = make_fmu("ME")  # only for its logging callbacks
    callbacks = byref(log.callbacks)
    guid = model_description.guid.encode()
    wrong = b"{00000000-0000-0000-0000-000000000000}"
    assert raw("fmi2Instantiate", b"raw", ME, wrong, b"", callbacks, 0, 0) is None
    assert raw("fmi2Instantiate", b"raw", CS, wrong, b"", callbacks, 0, 0) is None
    assert any("GUID" in m for m in log.errors())
    assert raw("fmi2Instantiate", b"raw", ME, None, b"", callbacks, 0, 0) is None
    assert raw("fmi2Instantiate", b"raw", ME, wrong, None, None, 0, 0) is None
    assert raw("fmi2Instantiate", b"raw", 7, guid, b"", callbacks, 0, 0) is None
    assert raw("fmi2Instantiate", None, ME, guid, b"", callbacks, 0, 0) is None
    assert raw("fmi2Instantiate", b"", ME, guid, b"", callbacks, 0, 0) is None
    # the right GUID works, also without callbacks, and the instance is usable
    for functions in (callbacks, None):
        c = raw("fmi2Instantiate", b"raw", CS, guid, None, functions, 0, 1)
        assert c is not None
        try:
            assert raw("fmi2SetupExperiment", c, 0, 0.0, 0.0, 0, 0.0) == OK
            assert raw("fmi2EnterInitializationMode", c) == OK
            assert raw("fmi2ExitInitializationMode", c) == OK
            assert raw("fmi2DoStep", c, 0.0, 1e-3, 1) == OK
            assert raw("fmi2ExitInitializationMode", c) == ERROR
        finally:
            raw("fmi2FreeInstance", c)


def test_instances_are_independent(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    a, _ = make_fmu("CS")
    b, _ = make_fmu("CS")
    for fmu, cr in ((a, 0.5), (b, 0.8)):
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setReal([vr["contact.cr"]], [cr])
        fmu.exitInitializationMode()
    assert a.getReal([vr["contact.cr"]]) == [0.5]
    assert b.getReal([vr["contact.cr"]]) == [0.8]


def test_reads_are_current_after_new_states(
    make_fmu: MakeFmu, model_description: ModelDescription, vr: dict[str, int]
) -> None:
    """fmi2GetReal brings what it reads up to date, per reference (fmu_get_values' table of what
    each reference needs): after new continuous states the derivatives read as variables equal
    fmi2GetDerivatives', contact.gap is delta - |r| of the new position (O1 = G1), the state
    reads are the new states, and one vector read of every variable of a type equals reads one
    at a time."""
    fmu, log = initialized(make_fmu, "ME")
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    der = [vr[f"der(body1.{n})"] for n in ("x", "y", "theta", "vx", "vy", "omega")]
    delta = fmu.getReal([vr["contact.delta"]])[0]
    assert delta > 0.0
    gaps = []
    for x in (
        np.array([0.0, 0.3, 0.01, 0.2, -0.1, 3.0]) * delta,
        np.array([0.1, -0.5, -0.02, -1.0, 0.4, 0.5]) * delta,
    ):
        fmu.setContinuousStates(x.ctypes.data_as(POINTER(c_double)), 6)
        values = fmu.getReal(
            [
                *der,
                vr["contact.gap"],
                *[vr[f"body1.{n}"] for n in ("x", "y", "theta", "vx", "vy", "omega")],
            ]
        )
        dx = np.zeros(6)
        fmu.getDerivatives(dx.ctypes.data_as(POINTER(c_double)), 6)
        assert values[:6] == list(dx)
        assert values[6] == pytest.approx(
            delta - math.hypot(x[0], x[1]), rel=1e-14, abs=1e-15 * delta
        )
        assert values[7:] == list(x)
        gaps.append(values[6])
        for kind, getter in (
            ("Real", fmu.getReal),
            ("Integer", fmu.getInteger),
            ("Boolean", fmu.getBoolean),
        ):
            refs = [v.valueReference for v in model_description.modelVariables if v.type == kind]
            assert len(refs) > 3, kind
            assert list(getter(refs)) == [getter([r])[0] for r in refs], kind
    assert gaps[0] != gaps[1]
    assert not log.errors()
