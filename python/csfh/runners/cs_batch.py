"""Batched co-simulation runs: many parameter sets of one scene and contact law in one call into
the batch master (libcsfh_batch.so, fmu_src/masters/csfh_cs_batch.c).

The master loads the FMU's own binary (the one `simulate_cs` loads) and drives it through its
fmi2 functions exactly as `simulate_cs` does: the same start values in the same order
(`csfh.runners.fmu.start_values`), the same tolerance, the same communication grid
min(k h, t_end), and its contact records kept by the same bookkeeping
(`csfh.runners.fmu.contact_bookkeeping`). A batched run is therefore the single run, bitwise
(tested). It returns per run
only reductions of chosen outputs over the communication points (the largest peak stress, the
final contact count, the first onset time, ...) and, on request, the outputs on the grid; what
it saves is Python's per-run and per-step overhead, which is most of a short run's time through
fmpy (`benchmarks/bench_cs_batch.py`)."""

from __future__ import annotations

import ctypes
import math
import pathlib
import time
from collections.abc import Sequence
from ctypes import POINTER, Structure, c_char_p, c_double, c_int, c_longlong, c_size_t, c_uint
from dataclasses import dataclass
from functools import cache, cached_property
from typing import Any

import numpy as np

from ..errors import InstallError, ParameterError, SimulationError
from ..model import model_info
from ..model.scene import Scene
from ..trajectory import Trajectory, signals_on_grid
from . import cs_steps
from .fmu import (
    CS_OUTPUT_NAMES,
    EVENT_NAMES,
    OUTPUT_NAMES,
    binary_path,
    check_law,
    contact_bookkeeping,
    cs_method_name,
    cs_trajectory,
    first_record,
    start_values,
    start_values_of_runs,
    unzipped_fmu,
)

REDUCTIONS = {"final": 0, "max": 1, "min": 2, "absmax": 3, "first_when": 4, "time_of_max": 5}
"""Reductions over the communication points (csfh_cs_batch.h): the final value, the largest, the
smallest, the largest magnitude, the value at the first point where another output is > 0, the
time of the (first) largest value."""
_TYPES = {"Real": 0, "Integer": 1, "Boolean": 2}
MESSAGE_SIZE = 512

Output = tuple[str, str] | tuple[str, str, str]
"""(FMU variable, reduction) or (FMU variable, "first_when", trigger variable)."""

SUMMARY_OUTPUTS: tuple[Output, ...] = (
    ("contact.count", "final"),
    ("contact.onset_time", "first_when", "contact.count"),
    ("contact.F_N_peak", "max"),
    ("contact.F_T_peak", "max"),
    ("contact.indentation_peak", "max"),
    ("flexure.stress_max_peak", "max"),
    ("flexure.stress_max_peak", "time_of_max"),
    ("contact.pressure_max_peak", "max"),
    ("contact.pressure_max_peak", "time_of_max"),
    ("diagnostics.integrator_steps", "final"),
    ("diagnostics.rhs_evaluations", "final"),
    ("contact.release_time", "final"),
    ("contact.active", "final"),
)
"""What every batched run returns: the quantities of `Trajectory.summary` of a co-simulation
run (contact count, first onset, largest peaks, steps), the stress peaks with their times, and
when the last contact ended (and whether one is still on at the end: the settling of a shock)."""

_EVENT_OUTPUTS = ("contact.count", "contact.active", *EVENT_NAMES)
TABLE_OUTPUTS: tuple[str, ...] = (
    *OUTPUT_NAMES.values(),
    *CS_OUTPUT_NAMES.values(),
    *_EVENT_OUTPUTS,
)
"""What a batched run records on the grid when asked for its trajectory: the columns of
`simulate_cs`'s table and the contact events it reads at every communication point."""


class _Spec(Structure):
    _fields_ = [
        ("binary", c_char_p),
        ("guid", c_char_p),
        ("resource_uri", c_char_p),
        ("instance_name", c_char_p),
        ("tolerance", c_double),
        ("stop_time", c_double),
        ("step", c_double),
        ("n_set", c_size_t),
        ("set_vr", POINTER(c_uint)),
        ("set_type", POINTER(c_int)),
        ("n_out", c_size_t),
        ("out_vr", POINTER(c_uint)),
        ("out_type", POINTER(c_int)),
        ("out_reduce", POINTER(c_int)),
        ("out_arg", POINTER(c_int)),
    ]


@cache
def library() -> Any:
    """The batch master (loaded once per process, its ABI checked: cs_steps.library)."""
    lib = cs_steps.library()
    lib.csfh_cs_batch_points.restype = c_longlong
    lib.csfh_cs_batch_points.argtypes = [c_double, c_double]
    lib.csfh_cs_batch_run.restype = c_longlong
    lib.csfh_cs_batch_run.argtypes = [
        POINTER(_Spec),
        c_size_t,
        POINTER(c_double),
        POINTER(c_double),
        POINTER(c_double),
        POINTER(c_int),
        c_char_p,
        c_size_t,
    ]
    return lib


@cache
def _binary() -> tuple[str, str, str]:
    """(path of the FMU binary for this platform, GUID, resource URI) of the unzipped FMU."""
    md = model_info.model_description()
    directory = pathlib.Path(unzipped_fmu())
    binary = pathlib.Path(binary_path(str(directory), md.coSimulation.modelIdentifier))
    if not binary.is_file():
        raise InstallError(f"csfh.fmu has no binary for this platform ({binary.name})")
    return str(binary), md.guid, (directory / "resources").as_uri()


def grid_times(stop_time: float, step: float) -> np.ndarray:
    """The communication points of a run, as `simulate_cs` and the master compute them:
    0, then min(k h, t_end) for k = 1 .. ceil(t_end / h - 1e-9)."""
    n = math.ceil(stop_time / step - 1e-9)
    return np.array([0.0, *(min((k + 1) * step, stop_time) for k in range(n))])


def _key(output: Output) -> str:
    return output[0] if output[1] == "final" else f"{output[0]}:{output[1]}"


@dataclass
class CsBatchResult:
    """The outputs of a batch: `value(i, name, reduction)` of run i; with records, every output
    of `outputs` at every communication point `times`."""

    scene: Scene
    law: str
    rtol: float
    step: float
    outputs: tuple[Output, ...]
    results: np.ndarray  # (n, n_outputs)
    records: np.ndarray | None  # (n, n_points, n_outputs)
    times: np.ndarray
    status: np.ndarray
    messages: list[str]
    wall_time: float
    parameter_sets: Sequence[dict[str, Any] | None]

    def __len__(self) -> int:
        return len(self.status)

    @cached_property
    def _positions(self) -> dict[tuple[str, str], int]:
        """(name, reduction) -> its column of `results` (the first, if an output repeats)."""
        positions: dict[tuple[str, str], int] = {}
        for j, out in enumerate(self.outputs):
            positions.setdefault((out[0], out[1]), j)
        return positions

    def _index(self, name: str, reduction: str = "final") -> int:
        j = self._positions.get((name, reduction))
        if j is None:
            raise KeyError(f"the batch did not reduce {name} by {reduction}")
        return j

    def value(self, i: int, name: str, reduction: str = "final") -> float:
        return float(self.results[i, self._index(name, reduction)])

    def values(self, name: str, reduction: str = "final") -> np.ndarray:
        """One reduction of every run."""
        return self.results[:, self._index(name, reduction)]

    def column(self, i: int, name: str) -> np.ndarray:
        """Output `name` of run i at every communication point (needs records)."""
        if self.records is None:
            raise ValueError("the batch ran without records")
        for j, out in enumerate(self.outputs):
            if out[0] == name:
                return self.records[i, :, j]
        raise KeyError(f"the batch did not record {name}")

    def summary(self, i: int) -> dict[str, Any]:
        """Run i as `Trajectory.summary` reports a co-simulation run (the same numbers)."""
        first = self.value(i, "contact.onset_time", "first_when")
        return {
            "first_contact_time": None if math.isnan(first) else first,
            "contacts": int(self.value(i, "contact.count")),
            "max_F_N": self.value(i, "contact.F_N_peak", "max"),
            "max_indentation": self.value(i, "contact.indentation_peak", "max"),
            "max_abs_F_T": self.value(i, "contact.F_T_peak", "max"),
            "max_flexure_stress": self.value(i, "flexure.stress_max_peak", "max"),
            "max_contact_pressure": self.value(i, "contact.pressure_max_peak", "max"),
            "steps": int(self.value(i, "diagnostics.integrator_steps")),
            "rhs_evaluations": int(self.value(i, "diagnostics.rhs_evaluations")),
            "last_release_time": self._last_release(i),
            "contact_at_end": int(self.value(i, "contact.active") > 0.0),
        }

    def _last_release(self, i: int) -> float | None:
        """When the last contact of run i that ended did (None: none ended)."""
        count = int(self.value(i, "contact.count"))
        if count == 0 or (count == 1 and self.value(i, "contact.active") > 0.0):
            return None
        return self.value(i, "contact.release_time")

    def trajectory(self, i: int) -> Trajectory:
        """Run i as the Trajectory `simulate_cs` returns (needs records of TABLE_OUTPUTS): the
        same table, contact onsets and releases, read from the same outputs at the same
        points."""
        table = {"t": self.times.copy()}
        for column, name in (*OUTPUT_NAMES.items(), *CS_OUTPUT_NAMES.items()):
            table[column] = self.column(i, name).copy()
        count = self.column(i, "contact.count")
        active = self.column(i, "contact.active") != 0
        events = np.column_stack([self.column(i, name) for name in EVENT_NAMES])
        records = first_record(int(count[0]), float(events[0, 1]))
        contact_bookkeeping(
            records, int(count[0]), bool(active[0]), count[1:], active[1:], events[1:]
        )
        tr = cs_trajectory(self.law, self.scene.name, table, records)
        tr.stats = {
            "integrator": f"{cs_method_name(self.scene, self.parameter_sets[i])} inside "
            f"the FMU (co-simulation, batched) rtol={self.rtol:g}, communication step "
            f"{self.step:g} s",
            "steps": int(self.value(i, "diagnostics.integrator_steps")),
            "rhs_evaluations": int(self.value(i, "diagnostics.rhs_evaluations")),
            "contact_count": int(count[-1]),
            "wall_time": self.wall_time / max(1, len(self)),
        }
        return tr

    def signals(self, i: int, grid: np.ndarray) -> dict[str, np.ndarray]:
        """Run i's output signals on `grid` (needs records), as a single run's."""
        return signals_on_grid(self.trajectory(i), grid)

    def run_time(self, i: int) -> float:
        """The share of one run in the batch's wall time."""
        return self.wall_time / max(1, len(self))

    def check(self) -> None:
        """Raise SimulationError for the first failed run, naming its parameters."""
        bad = np.flatnonzero(self.status < 0)
        if len(bad):
            i = int(bad[0])
            raise SimulationError(
                f"{self.law}: run {i} of the batch failed ({self.messages[i] or 'no message'}) "
                f"with parameters {self.parameter_sets[i] or {}}"
            )


def _vr_type(name: str) -> tuple[int, int]:
    """The value reference and the master's type number of an FMU variable."""
    variables = model_info.variables()
    if name not in variables:
        raise ParameterError(f"unknown FMU variable {name!r}")
    v = variables[name]
    return v.valueReference, _TYPES.get(v.type, 1)


def _output_spec(outs: Sequence[Output]) -> tuple[list[int], ...]:
    """The outputs' value references, types, reductions and trigger indices, checked."""
    names = [o[0] for o in outs]
    for o in outs:
        if o[1] not in REDUCTIONS or (o[1] == "first_when") != (len(o) == 3):
            raise ParameterError(
                f"bad output {o!r}: (name, reduction) or (name, 'first_when', trigger)"
            )
        if len(o) == 3 and o[2] not in names:
            raise ParameterError(f"{o!r}: the trigger must be one of the outputs")
    return (
        [_vr_type(n)[0] for n in names],
        [_vr_type(n)[1] for n in names],
        [REDUCTIONS[o[1]] for o in outs],
        [names.index(o[2]) if len(o) == 3 else 0 for o in outs],
    )


def _start_values(
    scene: Scene, law: str, parameter_sets: Sequence[dict[str, Any] | None]
) -> tuple[list[int], list[int], np.ndarray]:
    """The value references and types every run sets, and each run's values (one row each):
    every run must set the same variables in the same order (one spec per batch)."""
    rows = start_values_of_runs(scene, law, parameter_sets)
    first = rows[0] if rows else start_values(scene, law)
    order = [(name, kind) for name, kind, _ in first]
    for k, row in enumerate(rows):
        if [(name, kind) for name, kind, _ in row] != order:
            raise ParameterError(f"parameter set {k} sets other variables than parameter set 0")
    values = np.array([[float(v) for _, _, v in row] for row in rows], dtype=float)
    return (
        [_vr_type(name)[0] for name, _ in order],
        [_TYPES[kind] for _, kind in order],
        np.ascontiguousarray(values.reshape(len(rows), len(order))),
    )


def _array(ctype: Any, data: Sequence[int]) -> Any:
    return (ctype * max(1, len(data)))(*data)


def _spec(
    rtol: float,
    t_end: float,
    h: float,
    sets: tuple[list[int], list[int]],
    outputs: tuple[list[int], ...],
) -> _Spec:
    binary, guid, resources = _binary()
    (set_vr, set_type), (out_vr, out_type, out_reduce, out_arg) = sets, outputs
    return _Spec(
        binary.encode(),
        guid.encode(),
        resources.encode(),
        b"csfh",
        float(rtol),
        float(t_end),
        float(h),
        len(set_vr),
        _array(c_uint, set_vr),
        _array(c_int, set_type),
        len(out_vr),
        _array(c_uint, out_vr),
        _array(c_int, out_type),
        _array(c_int, out_reduce),
        _array(c_int, out_arg),
    )


def _run_master(
    spec: _Spec, values: np.ndarray, n_out: int, n_points: int, record: bool
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray, list[str], float]:
    """One call into the batch master: (results, records, status, messages, wall time)."""
    n = len(values)
    results = np.full((n, n_out), np.nan)
    records = np.zeros((n, n_points, n_out)) if record else None
    status = np.zeros(n, dtype=np.int32)
    messages = ctypes.create_string_buffer(max(1, n) * MESSAGE_SIZE)
    dp = POINTER(c_double)
    wall = time.perf_counter()
    failed = library().csfh_cs_batch_run(
        ctypes.byref(spec),
        n,
        values.ctypes.data_as(dp),
        results.ctypes.data_as(dp),
        records.ctypes.data_as(dp) if records is not None else None,
        status.ctypes.data_as(POINTER(c_int)),
        messages,
        MESSAGE_SIZE,
    )
    wall = time.perf_counter() - wall
    raw = messages.raw
    texts = [
        raw[i * MESSAGE_SIZE : (i + 1) * MESSAGE_SIZE].split(b"\0", 1)[0].decode(errors="replace")
        for i in range(max(1, n))
    ]
    if failed < 0:
        raise RuntimeError(texts[0] or "csfh_cs_batch_run rejected its arguments")
    return results, records, status, texts[:n], wall


def cs_batch(
    scene: Scene,
    law: str,
    parameter_sets: Sequence[dict[str, Any] | None],
    *,
    rtol: float | None = None,
    communication_step: float | None = None,
    stop_time: float | None = None,
    outputs: Sequence[Output] = SUMMARY_OUTPUTS,
    record: bool = False,
    check: bool = True,
) -> CsBatchResult:
    """Co-simulate `scene` with contact law `law` once per parameter set (overrides of FMU
    parameters, as `simulate_cs(scene, law, parameters=...)` takes them), all in one call into
    the batch master. `outputs` are reduced over the communication points; with `record` every
    output of `outputs` + TABLE_OUTPUTS is kept at every point (`CsBatchResult.trajectory`).
    Invalid parameter values raise ParameterError before anything runs; a run the FMU refuses
    or fails has status -1 and NaN results (with `check`, SimulationError)."""
    check_law(law)
    rtol = scene.integrator.rtol if rtol is None else rtol
    h = scene.integrator.output_interval if communication_step is None else communication_step
    t_end = scene.stop_time if stop_time is None else stop_time
    outs: list[Output] = list(outputs)
    if record:
        outs += [(name, "final") for name in TABLE_OUTPUTS if (name, "final") not in outs]
    out_spec = _output_spec(outs)
    set_vr, set_type, values = _start_values(scene, law, parameter_sets)
    n_points = int(library().csfh_cs_batch_points(t_end, h))
    if n_points < 1:
        raise ParameterError(f"bad horizon {t_end!r} s or communication step {h!r} s")
    spec = _spec(rtol, t_end, h, (set_vr, set_type), out_spec)
    results, records, status, messages, wall = _run_master(
        spec, values, len(outs), n_points, record
    )
    result = CsBatchResult(
        scene=scene,
        law=law,
        rtol=float(rtol),
        step=float(h),
        outputs=tuple(outs),
        results=results,
        records=records,
        times=grid_times(t_end, h),
        status=status,
        messages=messages,
        wall_time=wall,
        parameter_sets=list(parameter_sets),
    )
    if check:
        result.check()
    return result


def runs_per_second(result: CsBatchResult) -> float:
    """Runs per second of wall time inside the C call."""
    return len(result) / result.wall_time if result.wall_time > 0 else math.inf


__all__ = [
    "REDUCTIONS",
    "SUMMARY_OUTPUTS",
    "TABLE_OUTPUTS",
    "CsBatchResult",
    "cs_batch",
    "grid_times",
    "runs_per_second",
]
