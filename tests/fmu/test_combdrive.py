"""The comb-drive actuator FMU (build/combdrive.fmu): packaging, the force law F = n eps t V^2 / g,
bad input, the state machine, NULL arguments and FMU states. It is the generic FMI glue of the
csfh FMU with another model behind fmu_model.h, generated from modelDescription/combdrive.toml."""

from __future__ import annotations

import ctypes
import math
import re
import shutil
import struct
import subprocess
from collections.abc import Callable, Iterator
from ctypes import POINTER, byref, c_double, c_uint, c_void_p
from pathlib import Path
from typing import Any

import fmpy
import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.model_description import ModelDescription
from fmpy.validation import validate_fmu
from fmu_binaries import fmi2_functions
from fmu_instances import Instances, LogCapture, built, unzip
from oracles import EPS0

ERROR = 3


@pytest.fixture(scope="session")
def combdrive_path(fmu_path: Path) -> Path:
    from csfh.paths import combdrive_fmu_path

    return built(combdrive_fmu_path())


@pytest.fixture(scope="session")
def combdrive_md(combdrive_path: Path) -> ModelDescription:
    return read_model_description(str(combdrive_path))


@pytest.fixture(scope="session")
def combdrive_dir(combdrive_path: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    yield from unzip(combdrive_path, tmp_path_factory, "combdrive")


@pytest.fixture(scope="session")
def cvr(combdrive_md: ModelDescription) -> dict[str, int]:
    return {v.name: v.valueReference for v in combdrive_md.modelVariables}


@pytest.fixture
def make_actuator(combdrive_md: ModelDescription, combdrive_dir: str):
    """make_actuator(kind='CS'|'ME') -> (fmu, log), instantiated; freed at the end."""
    instances = Instances(combdrive_md, combdrive_dir, "actuator")

    def factory(kind: str = "CS") -> tuple[Any, LogCapture]:
        return instances.make(kind)

    yield factory
    instances.free()


MakeActuator = Callable[..., tuple[Any, LogCapture]]


def initialized(make: MakeActuator, cvr: dict[str, int], **values: float) -> tuple[Any, Any]:
    fmu, log = make("CS")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    for name, value in values.items():
        name = {"arm1": "arm[1]", "arm2": "arm[2]"}.get(name, name)
        if name == "fingers":
            fmu.setInteger([cvr[name]], [int(value)])
        else:
            fmu.setReal([cvr[name]], [float(value)])
    fmu.exitInitializationMode()
    return fmu, log


def outputs(fmu: Any, cvr: dict[str, int]) -> dict[str, float]:
    names = ("F", "F_x", "F_y", "M", "force_constant")
    return dict(zip(names, fmu.getReal([cvr[n] for n in names]), strict=True))


# ------------------------------------------------------------------------------------------
# packaging


def test_validate_fmu_finds_no_problem(combdrive_path: Path) -> None:
    assert validate_fmu(str(combdrive_path)) == []


def test_binary_exports_only_fmi2_and_links_only_libc_and_libm(combdrive_dir: str) -> None:
    binary = Path(combdrive_dir) / "binaries" / "linux64" / "combdrive.so"
    nm, ldd = shutil.which("nm"), shutil.which("ldd")
    if nm is None or ldd is None:
        pytest.skip("nm or ldd not available")
    out = subprocess.run(
        [nm, "-D", "--defined-only", str(binary)], check=True, capture_output=True, text=True
    ).stdout
    symbols = {line.split()[-1] for line in out.splitlines() if line.strip()}
    n_fmi2 = len(fmi2_functions())  # every fmi2 function of FMI 2.0 (ME and CS)
    assert len(symbols) == n_fmi2 and all(s.startswith("fmi2") for s in symbols), symbols
    out = subprocess.run([ldd, str(binary)], check=True, capture_output=True, text=True).stdout
    libraries = {Path(line.split()[0]).name for line in out.splitlines() if line.strip()}
    allowed = re.compile(r"^(linux-vdso\.so|libc\.so|libm\.so|ld-linux[-\w.]*\.so)")
    assert libraries and not [lib for lib in libraries if not allowed.match(lib)], out


def test_start_values_come_from_the_same_table(
    make_actuator: MakeActuator, combdrive_md: ModelDescription
) -> None:
    """What the binary reports before initialization is the XML's start value (one source)."""
    fmu, _ = make_actuator("CS")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    checked = 0
    for v in combdrive_md.modelVariables:
        if v.start is None:
            continue
        if v.type == "Integer":
            assert fmu.getInteger([v.valueReference])[0] == int(v.start), v.name
        else:
            assert fmu.getReal([v.valueReference])[0] == float(v.start), v.name
        checked += 1
    assert checked >= 9


# ------------------------------------------------------------------------------------------
# physics


@pytest.mark.parametrize(
    ("fingers", "eps", "thickness", "gap", "V"),
    [
        (20000, EPS0, 0.025, 5e-6, 400.0),
        (100, 3.5 * EPS0, 5e-5, 2e-6, 60.0),
        (1, EPS0, 1.0, 1.0, -7.0),
    ],
)
def test_force_is_n_eps_t_v2_over_g(
    make_actuator: MakeActuator,
    cvr: dict[str, int],
    fingers: int,
    eps: float,
    thickness: float,
    gap: float,
    V: float,
) -> None:
    fmu, log = initialized(
        make_actuator, cvr, fingers=fingers, permittivity=eps, thickness=thickness, gap=gap
    )
    fmu.setReal([cvr["V"]], [V])
    out = outputs(fmu, cvr)
    expected = fingers * eps * thickness * V**2 / gap
    assert out["F"] == pytest.approx(expected, rel=1e-14)
    assert out["force_constant"] == pytest.approx(fingers * eps * thickness / gap, rel=1e-14)
    # default direction +Y, arm at G1: a vertical force, no moment
    assert out["F_x"] == pytest.approx(0.0, abs=1e-15 * expected)
    assert out["F_y"] == pytest.approx(expected, rel=1e-14)
    assert out["M"] == 0.0
    fmu.doStep(0.0, 1e-3)  # the output follows the input held over the step
    fmu.setReal([cvr["V"]], [2 * V])
    assert outputs(fmu, cvr)["F"] == pytest.approx(4 * expected, rel=1e-14)
    assert not log.errors()


def test_direction_and_moment(make_actuator: MakeActuator, cvr: dict[str, int]) -> None:
    """F along `direction` (global frame); M = (A(theta) arm) x F about G1."""
    direction, arm, theta = math.radians(30.0), (0.05, -0.02), 0.3
    fmu, _ = initialized(make_actuator, cvr, direction=direction, arm1=arm[0], arm2=arm[1])
    fmu.setReal([cvr["V"], cvr["theta"]], [300.0, theta])
    out = outputs(fmu, cvr)
    F = np.array([math.cos(direction), math.sin(direction)]) * out["F"]
    c, s = math.cos(theta), math.sin(theta)
    a = np.array([c * arm[0] - s * arm[1], s * arm[0] + c * arm[1]])
    assert [out["F_x"], out["F_y"]] == pytest.approx(list(F), rel=1e-14)
    assert out["M"] == pytest.approx(a[0] * F[1] - a[1] * F[0], rel=1e-13)


def test_model_exchange_without_states(combdrive_path: Path) -> None:
    """The same FMU in model exchange (no states, no events) and co-simulation via fmpy."""
    for kind in ("ModelExchange", "CoSimulation"):
        result = fmpy.simulate_fmu(
            str(combdrive_path),
            fmi_type=kind,
            stop_time=0.01,
            start_values={"V": 100.0},
            output=["F"],
        )
        assert result["F"][-1] == pytest.approx(8.8541878128e-4 * 100.0**2, rel=1e-12), kind


# ------------------------------------------------------------------------------------------
# robustness


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("gap", 0.0),
        ("gap", -1e-6),
        ("gap", math.nan),
        ("thickness", -0.01),
        ("permittivity", 0.0),
        ("permittivity", math.inf),
        ("direction", math.nan),
        ("arm[1]", math.inf),
        ("fingers", 0),
        ("fingers", -5),
    ],
)
def test_bad_input_is_rejected(
    make_actuator: MakeActuator, cvr: dict[str, int], name: str, value: float
) -> None:
    fmu, log = make_actuator("CS")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    with pytest.raises(FMICallException) as info:
        if name == "fingers":
            fmu.setInteger([cvr[name]], [int(value)])
        else:
            fmu.setReal([cvr[name]], [value])
    assert info.value.status == ERROR
    printed = "nan" if math.isnan(value) else ("inf" if math.isinf(value) else None)
    pattern = re.escape(name) + r" = (\S+) "
    found = [m.group(1) for msg in log.errors() if (m := re.search(pattern, msg))]
    assert found, log.errors()
    if printed is not None:
        assert found[0] == printed
    else:
        assert float(found[0]) == value


def test_bad_input_after_initialization(make_actuator: MakeActuator, cvr: dict[str, int]) -> None:
    """NaN input, an overflowing force, a fixed parameter while running."""
    fmu, log = initialized(make_actuator, cvr)
    with pytest.raises(FMICallException):
        fmu.setReal([cvr["V"]], [math.nan])
    assert any("V = nan" in m for m in log.errors()), log.errors()
    fmu.setReal([cvr["V"]], [1e200])  # finite, but V^2 overflows
    with pytest.raises(FMICallException):
        fmu.getReal([cvr["F"]])
    assert any("non-finite force" in m for m in log.errors()), log.errors()
    with pytest.raises(FMICallException):
        fmu.setReal([cvr["gap"]], [1e-5])
    assert any("gap cannot be set" in m for m in log.errors()), log.errors()
    fmu.setReal([cvr["direction"]], [0.0])  # tunable: accepted while running
    fmu.setReal([cvr["V"]], [10.0])
    assert outputs(fmu, cvr)["F_x"] == pytest.approx(outputs(fmu, cvr)["F"], rel=1e-15)


def test_state_machine_and_null_arguments(
    make_actuator: MakeActuator, cvr: dict[str, int], combdrive_dir: str
) -> None:
    fmu, log = make_actuator("CS")
    with pytest.raises(FMICallException):
        fmu.doStep(0.0, 1e-3)  # before initialization
    assert any("illegal call in state Instantiated" in m for m in log.errors())
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 1e-3)
    with pytest.raises(FMICallException):
        fmu.doStep(0.5, 1e-3)  # not the FMU's time
    lib = ctypes.CDLL(str(Path(combdrive_dir) / "binaries" / "linux64" / "combdrive.so"))
    lib.fmi2GetReal.argtypes = [c_void_p, POINTER(c_uint), ctypes.c_size_t, POINTER(c_double)]
    lib.fmi2GetFMUstate.argtypes = [c_void_p, POINTER(c_void_p)]
    lib.fmi2DoStep.argtypes = [c_void_p, c_double, c_double, ctypes.c_int]
    ref = (c_uint * 1)(cvr["F"])
    assert lib.fmi2GetReal(fmu.component, ref, 1, None) == ERROR
    assert lib.fmi2GetReal(fmu.component, None, 1, (c_double * 1)()) == ERROR
    assert lib.fmi2GetFMUstate(fmu.component, None) == ERROR
    assert lib.fmi2GetReal(None, ref, 1, (c_double * 1)()) == ERROR
    assert lib.fmi2DoStep(None, 0.0, 1e-3, 1) == ERROR
    assert sum("is NULL" in m for m in log.errors()) == 3


def test_fmu_state_round_trip(make_actuator: MakeActuator, cvr: dict[str, int]) -> None:
    fmu, _ = initialized(make_actuator, cvr)
    fmu.setReal([cvr["V"]], [200.0])
    fmu.doStep(0.0, 0.1)
    data = fmu.serializeFMUstate(fmu.getFMUstate())
    fmu.setReal([cvr["V"]], [50.0])
    fmu.doStep(0.1, 0.1)
    state = fmu.deSerializeFMUstate(data)
    fmu.setFMUstate(state)
    fmu.freeFMUstate(state)
    assert fmu.getReal([cvr["time"], cvr["V"]]) == [0.1, 200.0]
    t = c_double()
    fmu.fmi2GetRealStatus(fmu.component, 2, byref(t))  # fmi2LastSuccessfulTime
    assert t.value == 0.1


@pytest.mark.parametrize(
    ("name", "good", "bad"),
    [
        ("gap", 5.00000012e-6, -1.0),
        ("direction", 1.50000013, math.nan),
        ("V", 123.000014, math.inf),
    ],
)
def test_restored_state_is_checked_like_set(
    make_actuator: MakeActuator, cvr: dict[str, int], name: str, good: float, bad: float
) -> None:
    """A state whose bytes say gap = -1 (or a NaN direction, an infinite voltage) is refused by
    fmi2DeSerializeFMUstate, naming the variable and the value; the instance is unchanged. The
    variable's bytes are found by its distinctive value."""
    fmu, log = initialized(make_actuator, cvr, **{name: good})
    fmu.doStep(0.0, 0.1)
    state = fmu.getFMUstate()
    data = bytes(fmu.serializeFMUstate(state))
    fmu.freeFMUstate(state)
    packed = struct.pack("<d", good)
    assert data.count(packed) == 1
    before = outputs(fmu, cvr)
    with pytest.raises(FMICallException):
        fmu.deSerializeFMUstate(data.replace(packed, struct.pack("<d", bad)))
    assert any(f"{name} = " in m and ("range" in m or "finite" in m) for m in log.errors())
    assert outputs(fmu, cvr) == before
    fmu.doStep(0.1, 0.1)  # still usable


def test_restored_state_recomputes_the_force_constant(
    make_actuator: MakeActuator, cvr: dict[str, int]
) -> None:
    """force_constant = n eps t / g comes from the restored parameters, not from the bytes."""
    fmu, log = initialized(make_actuator, cvr, V=200.0)
    fmu.doStep(0.0, 0.1)
    k = outputs(fmu, cvr)["force_constant"]
    state = fmu.getFMUstate()
    data = bytes(fmu.serializeFMUstate(state))
    fmu.freeFMUstate(state)
    forged = data.replace(struct.pack("<d", k), struct.pack("<d", 1e6))
    assert forged != data
    restored = fmu.deSerializeFMUstate(forged)
    fmu.setFMUstate(restored)
    fmu.freeFMUstate(restored)
    assert outputs(fmu, cvr)["force_constant"] == k
    assert outputs(fmu, cvr)["F"] == pytest.approx(k * 200.0**2, rel=1e-15)
    assert not log.errors()
