"""Batched co-simulation runs: many parameter sets of one scene and contact law in one call into
the batch master (libcsfh_batch.so, fmu_src/masters/csfh_cs_batch.c).

The master loads the FMU's own binary (the one `simulate_cs` loads through fmpy) and drives it
through its fmi2 functions exactly as `simulate_cs` does: the same start values in the same order
(`csfh.runners.fmu.start_values`), the same tolerance, the same communication grid
min(k h, t_end). A batched run is therefore the single run, bitwise (tested). It returns per run
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
from functools import cache
from typing import Any

import numpy as np

from ..errors import SimulationError
from ..model import model_info
from ..model.scene import Scene
from ..trajectory import CONTACT_FIELDS, Trajectory
from . import cs_steps
from .fmu import CS_OUTPUT_NAMES, OUTPUT_NAMES, cs_method_name, start_values, unzipped_fmu

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
)
"""What every batched run returns: the quantities of `Trajectory.summary` of a co-simulation
run (contact count, first onset, largest peaks, steps) and the stress peaks with their times."""

_EVENT_OUTPUTS = (
    "contact.count",
    "contact.active",
    "contact.onset_time",
    "contact.onset_speed",
    "contact.release_time",
    "contact.release_speed",
)
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
    from fmpy import platform, sharedLibraryExtension

    md = model_info.model_description()
    directory = pathlib.Path(unzipped_fmu())
    identifier = md.coSimulation.modelIdentifier
    binary = directory / "binaries" / platform / f"{identifier}{sharedLibraryExtension}"
    if not binary.is_file():
        raise FileNotFoundError(f"csfh.fmu has no binary for {platform} ({binary.name})")
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

    def _index(self, name: str, reduction: str = "final") -> int:
        for j, out in enumerate(self.outputs):
            if out[0] == name and out[1] == reduction:
                return j
        raise KeyError(f"the batch did not reduce {name} by {reduction}")

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
        }

    def trajectory(self, i: int) -> Trajectory:
        """Run i as the Trajectory `simulate_cs` returns (needs records of TABLE_OUTPUTS): the
        same table, contact onsets and releases, read from the same outputs at the same
        points."""
        table = {"t": self.times.copy()}
        for column, name in (*OUTPUT_NAMES.items(), *CS_OUTPUT_NAMES.items()):
            table[column] = self.column(i, name).copy()
        count = self.column(i, "contact.count")
        active = self.column(i, "contact.active")
        t_on, v_on = self.column(i, "contact.onset_time"), self.column(i, "contact.onset_speed")
        t_off = self.column(i, "contact.release_time")
        v_off = self.column(i, "contact.release_speed")
        records: list[list[float]] = []
        if count[0]:
            records.append([0.0, float(v_on[0]), math.nan, math.nan, math.nan, math.nan])
        for k in range(1, len(count)):
            if count[k] > count[k - 1]:
                records.append(
                    [float(t_on[k]), float(v_on[k]), math.nan, math.nan, math.nan, math.nan]
                )
            if records and not active[k] and (count[k] > count[k - 1] or active[k - 1]):
                records[-1][2:4] = [float(t_off[k]), float(v_off[k])]
        data = np.array(records, dtype=float).reshape(-1, len(CONTACT_FIELDS))
        cr = {name: data[:, j].copy() for j, name in enumerate(CONTACT_FIELDS)}
        tr = Trajectory(
            model=self.law,
            scene=self.scene.name,
            table=table,
            contacts=cr["t_onset"],
            releases=cr["t_release"][np.isfinite(cr["t_release"])],
            contact_records=cr,
        )
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

    def check(self) -> None:
        """Raise SimulationError for the first failed run, naming its parameters."""
        bad = np.flatnonzero(self.status < 0)
        if len(bad):
            i = int(bad[0])
            raise SimulationError(
                f"{self.law}: run {i} of the batch failed ({self.messages[i] or 'no message'}) "
                f"with parameters {self.parameter_sets[i] or {}}"
            )


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
    Invalid parameter values raise ValueError before anything runs; a run the FMU refuses or
    fails has status -1 and NaN results (with `check`, SimulationError)."""
    if law not in model_info.LAWS:
        raise ValueError(f"law {law!r} is not an event-driven law ({', '.join(model_info.LAWS)})")
    rtol = scene.integrator.rtol if rtol is None else rtol
    h = scene.integrator.output_interval if communication_step is None else communication_step
    t_end = scene.stop_time if stop_time is None else stop_time
    outs: list[Output] = list(outputs)
    if record:
        outs += [(name, "final") for name in TABLE_OUTPUTS if (name, "final") not in outs]
    variables = model_info.variables()

    def vr_type(name: str) -> tuple[int, int]:
        if name not in variables:
            raise ValueError(f"unknown FMU variable {name!r}")
        v = variables[name]
        return v.valueReference, _TYPES.get(v.type, 1)

    for out in outs:
        if out[1] not in REDUCTIONS or (out[1] == "first_when") != (len(out) == 3):
            raise ValueError(
                f"bad output {out!r}: (name, reduction) or (name, 'first_when', trigger)"
            )
    names = [o[0] for o in outs]
    out_vr = [vr_type(n)[0] for n in names]
    out_type = [vr_type(n)[1] for n in names]
    out_reduce = [REDUCTIONS[o[1]] for o in outs]
    out_arg = [names.index(o[2]) if len(o) == 3 else 0 for o in outs]
    for o in outs:
        if len(o) == 3 and o[2] not in names:
            raise ValueError(f"{o!r}: the trigger must be one of the outputs")

    rows = [start_values(scene, law, p) for p in parameter_sets]
    first = rows[0] if rows else start_values(scene, law)
    order = [(name, kind) for name, kind, _ in first]
    for k, row in enumerate(rows):
        if [(name, kind) for name, kind, _ in row] != order:
            # every run must set the same variables in the same order (one spec per batch)
            raise ValueError(f"parameter set {k} sets other variables than parameter set 0")
    set_vr = [vr_type(name)[0] for name, _ in order]
    set_type = [_TYPES[kind] for _, kind in order]
    n = len(rows)
    values = np.array([[float(v) for _, _, v in row] for row in rows], dtype=float).reshape(
        n, len(order)
    )
    binary, guid, resources = _binary()
    lib = library()
    n_points = int(lib.csfh_cs_batch_points(t_end, h))
    if n_points < 1:
        raise ValueError(f"bad horizon {t_end!r} s or communication step {h!r} s")

    def arr(ctype: Any, data: Sequence[int]) -> Any:
        return (ctype * max(1, len(data)))(*data)

    spec = _Spec(
        binary.encode(),
        guid.encode(),
        resources.encode(),
        b"csfh",
        float(rtol),
        float(t_end),
        float(h),
        len(order),
        arr(c_uint, set_vr),
        arr(c_int, set_type),
        len(outs),
        arr(c_uint, out_vr),
        arr(c_int, out_type),
        arr(c_int, out_reduce),
        arr(c_int, out_arg),
    )
    values = np.ascontiguousarray(values)
    results = np.full((n, len(outs)), np.nan)
    records = np.zeros((n, n_points, len(outs))) if record else None
    status = np.zeros(n, dtype=np.int32)
    messages = ctypes.create_string_buffer(max(1, n) * MESSAGE_SIZE)
    dp = POINTER(c_double)
    wall = time.perf_counter()
    failed = lib.csfh_cs_batch_run(
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
        messages=texts[:n],
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
