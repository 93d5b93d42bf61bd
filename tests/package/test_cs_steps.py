"""simulate_cs's communication loop in C (csfh.runners.cs_steps, csfh_cs_steps in
libcsfh_batch.so) against the same loop in Python (step_loop="python", one ctypes call per FMI
call): the same trajectory, bitwise, on the three scenes and on a grid whose last step is
shorter; the same error, naming the same call and time, for a run whose FMU fails mid-way; the
chunking does not change anything; without the library simulate_cs loops in Python. And the C
loop alone on a fake FMU (Python callbacks): its grid arithmetic is Python's, it stops at the
failing call and says which one and when."""

from __future__ import annotations

import re
from ctypes import CFUNCTYPE, POINTER, c_double, c_int, c_size_t, c_uint, c_void_p
from pathlib import Path
from typing import Any

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from csfh.errors import SimulationError
from csfh.model.scene import load_scene
from csfh.runners import cs_steps
from csfh.runners import fmu as fmu_runner
from csfh.runners.fmu import simulate_cs
from csfh.trajectory import Trajectory

STATS = ("steps", "rhs_evaluations", "evaluations", "contact_count")


def assert_identical(a: Trajectory, b: Trajectory) -> None:
    """Bitwise the same table, contact records, contacts, releases and integrator statistics."""
    assert a.table.keys() == b.table.keys()
    for name in a.table:
        assert a.table[name].tobytes() == b.table[name].tobytes(), name
    assert a.contact_records.keys() == b.contact_records.keys()
    for name in a.contact_records:
        assert a.contact_records[name].tobytes() == b.contact_records[name].tobytes(), name
    assert a.contacts.tobytes() == b.contacts.tobytes()
    assert a.releases.tobytes() == b.releases.tobytes()
    for key in STATS:
        assert a.stats[key] == b.stats[key], key


@pytest.mark.parametrize("scene_name", ["central", "asymmetric", "csfh"])
@pytest.mark.parametrize(
    ("law", "step", "stop_time"),
    [("LN_spheres", None, None), ("LN_cylinders", 3e-3, 0.5)],
    ids=["scene-grid", "last-step-shorter"],
)
def test_c_loop_is_the_python_loop_bitwise(
    scene_name: str, law: str, step: float | None, stop_time: float | None
) -> None:
    scene = load_scene(scene_name)
    kw: dict[str, Any] = {"communication_step": step, "stop_time": stop_time}
    python = simulate_cs(scene, law, step_loop="python", **kw)
    c = simulate_cs(scene, law, step_loop="c", **kw)
    assert_identical(python, c)
    t = c.table["t"]
    if step is not None:  # the last step is shorter than the others, and ends at the stop time
        assert t[-1] == stop_time and 0 < t[-1] - t[-2] < step * (1 - 1e-6)
    assert len(c.contacts) >= 3  # contacts were recorded (the bookkeeping was exercised)
    assert np.isfinite(c.contact_records["t_release"]).any()
    assert c.stats["do_step_time"] > 0


@pytest.mark.parametrize("chunk", [(1, 1), (7, 7), (300, 300)])
def test_chunking_does_not_change_the_run(monkeypatch: pytest.MonkeyPatch, chunk: tuple) -> None:
    scene = load_scene("asymmetric")
    default = simulate_cs(scene, "LN_spheres", stop_time=0.3, step_loop="c")
    monkeypatch.setattr(fmu_runner, "CS_STEPS_CHUNK", chunk)
    assert fmu_runner.chunk_size(3000) == chunk[0]
    chunked = simulate_cs(scene, "LN_spheres", stop_time=0.3, step_loop="c")
    assert_identical(default, chunked)
    assert len(default.contacts) >= 2


class Recorder:
    """A Progress that keeps what it was told."""

    def __init__(self) -> None:
        self.done: list[float] = []

    def update(self, done: float) -> None:
        self.done.append(done)


def test_progress_between_chunks(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fmu_runner, "CS_STEPS_CHUNK", (100, 100))
    progress = Recorder()
    run = simulate_cs(load_scene("central"), "LN_spheres", stop_time=0.1, progress=progress)  # type: ignore[arg-type]
    t = run.table["t"]
    assert len(t) == 1001  # 1000 steps of 1e-4 s: ten chunks
    assert progress.done == [t[100 * (i + 1)] / 0.1 for i in range(10)]
    assert progress.done[-1] == 1.0


MASSLESS = {"body1.m": 1e-30}
"""A body so light that the first impact's step size underflows: the FMU fails mid-way."""


@pytest.mark.parametrize("chunk", [None, (1, 1), (782, 782), (781, 781)])
def test_failure_mid_way_is_reported_as_by_the_python_loop(
    monkeypatch: pytest.MonkeyPatch, chunk: tuple | None
) -> None:
    scene = load_scene("central")
    kw: dict[str, Any] = {"stop_time": 0.2, "parameters": MASSLESS}
    with pytest.raises(SimulationError) as python:
        simulate_cs(scene, "LN_spheres", step_loop="python", **kw)
    if chunk is not None:  # the failing step first in a chunk (782), last in one (781)
        monkeypatch.setattr(fmu_runner, "CS_STEPS_CHUNK", chunk)
    with pytest.raises(SimulationError) as c:
        simulate_cs(scene, "LN_spheres", step_loop="c", **kw)
    assert str(c.value) == str(python.value)
    # the failed step's start, as the FMU logged it, is the time in the message
    logged = re.search(r"the step from t = (\S+) to", str(c.value))
    reported = re.search(r"failed at t = (\S+) s", str(c.value))
    assert logged and reported, str(c.value)
    assert "fmi2DoStep failed" in str(c.value)
    t_start = float(logged.group(1))
    assert 0.01 < t_start < 0.2  # mid-way
    assert float(reported.group(1)) == float(f"{t_start:.9g}")


def test_without_the_library_the_loop_is_python(monkeypatch: pytest.MonkeyPatch) -> None:
    scene = load_scene("central")
    c = simulate_cs(scene, "LN_spheres", stop_time=0.3)  # the default: the C loop

    def missing() -> Any:
        raise FileNotFoundError("libcsfh_batch.so not found")

    def no_c_loop(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError("the C loop ran without its library")

    monkeypatch.setattr("csfh.paths.batch_library_path", missing)
    monkeypatch.setattr(cs_steps, "CSteps", no_c_loop)
    assert not cs_steps.available()
    python = simulate_cs(scene, "LN_spheres", stop_time=0.3)
    assert_identical(c, python)
    with pytest.raises(ValueError, match="step_loop"):
        simulate_cs(scene, "LN_spheres", step_loop="fortran")


# ------------------------------------------------------------------------------------------
# the C loop alone, on a fake FMU whose fmi2 functions are Python callbacks

DO_STEP = CFUNCTYPE(c_int, c_void_p, c_double, c_double, c_int)
GET_REAL = CFUNCTYPE(c_int, c_void_p, POINTER(c_uint), c_size_t, POINTER(c_double))
GET_INT = CFUNCTYPE(c_int, c_void_p, POINTER(c_uint), c_size_t, POINTER(c_int))
FMI2_ERROR, FMI2_WARNING = 3, 1


class FakeSlave:
    """What CSteps takes from an fmpy FMU2Slave (dll with the fmi2 functions, component); its
    time advances with every fmi2DoStep, which fails at call `fail_step`; reading fails at step
    `fail_read` (0 based) for the call named there."""

    def __init__(self, fail_step: int = -1, fail_read: tuple[int, str] = (-1, "")) -> None:
        self.steps: list[tuple[float, float]] = []
        self.time = 0.0

        def do_step(c: Any, t: float, h: float, _: int) -> int:
            self.steps.append((t, h))
            if len(self.steps) - 1 == fail_step:
                return FMI2_ERROR
            self.time = t + h
            return FMI2_WARNING if len(self.steps) % 5 == 0 else 0  # warnings go through

        def reader(kind: str, fn_type: Any, value: Any) -> Any:
            def read(c: Any, vr: Any, n: int, out: Any) -> int:
                if fail_read == (len(self.steps) - 1, kind):
                    return FMI2_ERROR
                for i in range(n):
                    out[i] = value(vr[i])
                return 0

            return fn_type(read)

        class Dll:
            fmi2DoStep = DO_STEP(do_step)
            fmi2GetReal = reader("real", GET_REAL, lambda vr: vr * 1000.0 + self.time)
            fmi2GetInteger = reader("integer", GET_INT, lambda vr: vr + len(self.steps))
            fmi2GetBoolean = reader("boolean", GET_INT, lambda vr: len(self.steps) % 2)

        self.dll = Dll()
        self.component = 12345  # passed through, never dereferenced by the loop


def python_grid(k_first: int, k_last: int, h: float, t_end: float) -> list[float]:
    """simulate_cs's Python loop: t_next = min((k + 1) h, t_end)."""
    return [min((k + 1) * h, t_end) for k in range(k_first, k_last)]


def test_c_loop_grid_and_reads_on_a_fake_fmu() -> None:
    h, t_end = 0.1, 1.05  # 11 steps, the last one 0.05 s (up to round-off)
    fake = FakeSlave()
    loop = cs_steps.CSteps(fake, h, t_end, [1, 2], [3], [4])
    chunks = [loop.run(0, 4, 0.0)]
    chunks.append(loop.run(4, 11, float(chunks[-1].times[-1])))
    times = np.concatenate([c.times for c in chunks])
    grid = python_grid(0, 11, h, t_end)
    assert times.tolist() == grid  # bitwise
    starts = [0.0, *grid[:-1]]
    assert fake.steps == [(t, t_next - t) for t, t_next in zip(starts, grid, strict=True)]
    reals = np.concatenate([c.reals for c in chunks])
    assert reals.tolist() == [[1000.0 + t, 2000.0 + t] for t in grid]
    assert np.concatenate([c.integers for c in chunks])[:, 0].tolist() == [
        3 + k for k in range(1, 12)
    ]
    assert np.concatenate([c.booleans for c in chunks])[:, 0].tolist() == [
        k % 2 for k in range(1, 12)
    ]
    assert sum(c.done for c in chunks) == 11


@pytest.mark.parametrize(
    ("fail_step", "fail_read", "k_first", "call", "reached"),
    [
        (6, (-1, ""), 0, "fmi2DoStep", False),
        (0, (-1, ""), 4, "fmi2DoStep", False),  # the chunk's first step: the start time passed
        (-1, (6, "real"), 0, "fmi2GetReal", True),  # the step went through: the time reached
        (-1, (8, "integer"), 3, "fmi2GetInteger", True),
        (-1, (5, "boolean"), 0, "fmi2GetBoolean", True),
    ],
    ids=["do-step", "do-step-first", "get-real", "get-integer", "get-boolean"],
)
def test_c_loop_stops_at_the_failed_call(
    fail_step: int, fail_read: tuple[int, str], k_first: int, call: str, reached: bool
) -> None:
    h, t_end = 0.1, 2.0
    fake = FakeSlave(fail_step, fail_read)
    loop = cs_steps.CSteps(fake, h, t_end, [1], [2], [3])
    t_start = min(k_first * h, t_end)
    with pytest.raises(FMICallException) as info:
        loop.run(k_first, 20, t_start)
    exc: Any = info.value
    assert exc.function == call and exc.status == FMI2_ERROR
    failed = k_first + max(fail_step, fail_read[0])  # the step index of the failed call
    assert exc.chunk.done == failed - k_first
    # the time simulate_cs reports: where the failed step started, or reached if it went through
    assert exc.t == min((failed + reached) * h, t_end)
    # the steps before the failed one come back, on simulate_cs's grid, bitwise
    assert exc.chunk.times.tolist() == python_grid(k_first, failed, h, t_end)
    assert len(fake.steps) == failed - k_first + 1  # nothing called after the failure


def test_a_chunk_keeps_its_values_after_the_next_one() -> None:
    """The output buffers are re-used from one C call to the next; a returned chunk is its own
    copy (a smaller second chunk would otherwise overwrite the first one's rows)."""
    h, t_end = 0.1, 1.1
    loop = cs_steps.CSteps(FakeSlave(), h, t_end, [1, 2], [3], [4])
    first = loop.run(0, 6, 0.0)
    before = (first.times.copy(), first.reals.copy(), first.integers.copy(), first.booleans.copy())
    second = loop.run(6, 11, float(first.times[-1]))
    after = (first.times, first.reals, first.integers, first.booleans)
    for old, new in zip(before, after, strict=True):
        assert new.tobytes() == old.tobytes()
    assert second.times.tolist() == python_grid(6, 11, h, t_end)


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="needs Linux's /proc")
def test_the_fmu_binary_stays_loaded_between_runs() -> None:
    """fmpy unloads the FMU's binary at fmi2FreeInstance; the runners hold a reference, so that
    the next run does not load, relocate and bind it again: after a run has freed its instance,
    the binary is still mapped, and the next run on it gives the same trajectory."""
    scene = load_scene("central")
    first = simulate_cs(scene, "LN_spheres", stop_time=0.1)
    binary = Path(fmu_runner.unzipped_fmu(), "binaries", fmpy.platform, "csfh.so").resolve()
    assert str(binary) in Path("/proc/self/maps").read_text()
    assert_identical(first, simulate_cs(scene, "LN_spheres", stop_time=0.1))
