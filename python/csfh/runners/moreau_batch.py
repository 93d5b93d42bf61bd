"""Batched Moreau runs: many parameter sets of one scene in one call into the C core
(csfh_api_moreau_batch, fmu_src/solvers/csfh_moreau_batch.c).

Each variant is integrated by the same C function as `csfh.moreau` (csfh_moreau_run), so a
batched trajectory is bitwise the single run's. What the batch saves is the per-run overhead of
Python and ctypes; with the stepper at ~0.1 us per step that overhead dominates short runs. The
caller chooses the batch size: the record buffers take n x rows x 16 doubles."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from ctypes import POINTER, c_double, c_int, c_longlong, c_size_t, c_void_p
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np

from ..errors import ParameterError, SimulationError
from ..model._csfh_variables import MOREAU_V_STICK
from ..model.core import N_STATES, CoreModel, library
from ..model.instance import core_model
from ..model.limits import moreau_step_counts
from ..model.scene import Scene
from ..trajectory import SIGNALS, Trajectory
from .moreau import _IMPACT, _RECORD, _STATS, STICK_RULES, trajectory_from_buffers

_dp = POINTER(c_double)


@cache
def _batch_fn() -> Any:
    fn = library().csfh_api_moreau_batch
    fn.restype = c_longlong
    fn.argtypes = [
        POINTER(c_void_p),  # models
        c_size_t,  # n
        c_double,  # h
        c_int,  # stick_rule
        c_double,  # v_eps
        c_double,  # v_stick
        c_double,  # g_tol
        c_double,  # t0
        _dp,  # x0 (n x 6)
        c_longlong,  # n_steps
        c_longlong,  # record_every
        _dp,  # records
        c_size_t,  # max_records
        _dp,  # impacts
        c_size_t,  # max_impacts
        _dp,  # x_end
        POINTER(c_longlong),  # stats (n x 9)
        POINTER(c_int),  # status
    ]
    return fn


@dataclass
class BatchResult:
    """Raw outputs of a batch: records[i, :n_records[i]] are the output rows of variant i (the
    columns of csfh.moreau's table), impacts[i, :n_impacts[i]] its contact onsets."""

    scene: Scene
    h: float
    stick_rule: str
    records: np.ndarray  # (n, max_records, 16)
    impacts: np.ndarray  # (n, max_impacts, 10)
    x_end: np.ndarray  # (n, N_STATES)
    stats: np.ndarray  # (n, 9)
    status: np.ndarray  # (n,)
    wall_time: float

    def __len__(self) -> int:
        return len(self.status)

    @property
    def steps(self) -> int:
        """Steps integrated by the whole batch (variant-steps)."""
        return int(self.stats[:, 0].sum())

    def n_records(self, i: int) -> int:
        return int(self.stats[i, 6])

    def n_impacts(self, i: int) -> int:
        return int(self.stats[i, 7])

    def column(self, i: int, name: str) -> np.ndarray:
        """One output column of variant i (a view into the batch buffer)."""
        return self.records[i, : self.n_records(i), _RECORD.index(name)]

    def impact_times(self, i: int) -> np.ndarray:
        return self.impacts[i, : self.n_impacts(i), _IMPACT.index("t")]

    def summary(self, i: int) -> dict[str, Any]:
        """Variant i as `Trajectory.summary` reports it: the first impact, the contact onsets,
        the largest F_N and abs(F_T) of its output rows (impulse / h), its steps."""
        t_imp = self.impact_times(i)
        return {
            "first_contact_time": float(t_imp[0]) if len(t_imp) else None,
            "contacts": int(self.stats[i, _STATS.index("onsets")]),
            "max_F_N": float(np.max(self.column(i, "F_N"))),
            "max_abs_F_T": float(np.max(np.abs(self.column(i, "F_T")))),
            "steps": int(self.stats[i, _STATS.index("steps")]),
        }

    def signals(self, i: int, grid: np.ndarray) -> dict[str, np.ndarray]:
        """Variant i's SIGNALS on `grid`, interpolated: its F_N and F_T rows are already the
        largest per-step values of each output interval."""
        t = self.column(i, "t")
        return {name: np.interp(grid, t, self.column(i, name)) for name in SIGNALS}

    def run_time(self, i: int) -> float:
        """The share of one variant in the batch's wall time."""
        return self.wall_time / max(1, len(self))

    def check(self, parameter_sets: Sequence[dict[str, Any] | None]) -> None:
        """SimulationError for the first variant whose state became non-finite, naming its
        parameters."""
        bad = np.flatnonzero(self.status != 0)
        if len(bad):
            overrides = parameter_sets[int(bad[0])] or {}
            raise SimulationError(f"Moreau: non-finite state for parameters {overrides}; reduce h")

    def trajectory(self, i: int) -> Trajectory:
        """Variant i as the Trajectory csfh.moreau would have returned."""
        st = {name: int(v) for name, v in zip(_STATS, self.stats[i], strict=True)}
        tr = trajectory_from_buffers(
            self.scene.name, self.h, self.stick_rule, self.records[i], self.impacts[i], st
        )
        tr.stats["integrator"] += " (batched)"
        return tr


def moreau_batch(
    scene: Scene,
    parameter_sets: Sequence[dict[str, Any] | None],
    *,
    h: float | None = None,
    stick_rule: str | None = None,
    output_interval: float | None = None,
    stop_time: float | None = None,
    v_eps: float | None = None,
    g_tol: float | None = None,
    max_impacts: int = 1000,
) -> BatchResult:
    """Run the Moreau stepper on `scene` once per parameter set (overrides of FMU parameters, as
    `csfh.moreau(scene, parameters=...)` takes them), all in one call into the C core. A variant
    whose state becomes non-finite has status -1 (its records stop there); the others are not
    affected. Raises ParameterError for an invalid parameter set before anything runs."""
    h = scene.integrator.moreau_h if h is None else h
    rule = scene.stick_rule if stick_rule is None else stick_rule
    if rule not in STICK_RULES:
        raise ParameterError(f"stick_rule = {rule!r} is not one of {', '.join(STICK_RULES)}")
    if not (h > 0 and math.isfinite(h)):
        raise ParameterError(f"h = {h!r} must be a positive step")
    t_end = scene.stop_time if stop_time is None else stop_time
    dt_out = scene.integrator.output_interval if output_interval is None else output_interval
    n_steps, record_every, max_records = moreau_step_counts(t_end, h, dt_out)
    n = len(parameter_sets)
    models: list[CoreModel] = [core_model(scene, p) for p in parameter_sets]
    handles = (c_void_p * max(n, 1))(*[m.handle for m in models])
    x0 = np.ascontiguousarray(np.tile(np.array(scene.x0, dtype=float), (n, 1)))
    records = np.zeros((n, max_records, len(_RECORD)))
    impacts = np.zeros((n, max_impacts, len(_IMPACT)))
    x_end = np.zeros((n, N_STATES))
    stats = np.zeros((n, len(_STATS)), dtype=np.int64)
    status = np.zeros(n, dtype=np.int32)
    wall = time.perf_counter()
    failed = _batch_fn()(
        handles,
        n,
        h,
        STICK_RULES[rule],
        scene.integrator.v_eps if v_eps is None else v_eps,
        MOREAU_V_STICK,
        scene.integrator.g_tol if g_tol is None else g_tol,
        0.0,
        x0.ctypes.data_as(_dp),
        n_steps,
        record_every,
        records.ctypes.data_as(_dp),
        max_records,
        impacts.ctypes.data_as(_dp),
        max_impacts,
        x_end.ctypes.data_as(_dp),
        stats.ctypes.data_as(POINTER(c_longlong)),
        status.ctypes.data_as(POINTER(c_int)),
    )
    wall = time.perf_counter() - wall
    if failed < 0:
        raise RuntimeError("csfh_api_moreau_batch rejected its arguments")
    del models  # the handles are only needed during the call
    return BatchResult(
        scene=scene,
        h=h,
        stick_rule=rule,
        records=records,
        impacts=impacts,
        x_end=x_end,
        stats=stats,
        status=status,
        wall_time=wall,
    )


def steps_per_second(result: BatchResult) -> float:
    """Variant-steps per second of wall time inside the C call."""
    return result.steps / result.wall_time if result.wall_time > 0 else math.inf


__all__ = ["BatchResult", "moreau_batch", "steps_per_second"]
