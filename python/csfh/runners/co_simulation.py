"""Co-simulation of the csfh FMU: its own integrator (solver.method) inside fmi2DoStep, one output
row per communication step.

The instance is ours (`fmi2_slave.Fmi2Slave`, the FMU's binary through ctypes); the
communication loop (fmi2DoStep, then reading the outputs and the contact events) runs in C, a
chunk of steps per call (`cs_steps.CSteps`, csfh_cs_steps in libcsfh_batch.so): Python's cost per
communication point (about 1.5 us of ctypes calls and cold caches) would be more than the FMU's
own work on a fine grid. The batch master (`cs_batch`) runs the same grid with the same start
values (`fmu.start_values`) and keeps its contact records with the same bookkeeping
(`fmu.contact_bookkeeping`), so a batched run is this run, bitwise."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..model import model_info
from ..model.limits import check_rows
from ..model.scene import Scene
from ..progress import Progress
from ..trajectory import Trajectory
from . import cs_steps
from .fmi2_slave import Fmi2Slave, FmiCallError
from .fmu import (
    CS_OUTPUT_NAMES,
    EVALUATION_PARTS,
    EVENT_NAMES,
    OUTPUT_NAMES,
    TABLE_COLUMNS,
    Table,
    check_law,
    contact_bookkeeping,
    cs_method_name,
    cs_trajectory,
    first_record,
    fmu_error,
    start_values,
    unzipped_fmu,
    vr,
)

CS_STEPS_CHUNK = (256, 4096)
"""The communication steps per C call of the loop: about 1 % of the run (for the progress shown
between calls), at least the first number and at most the second."""


def chunk_size(n: int) -> int:
    """Steps per C call for a run of n communication steps (CS_STEPS_CHUNK)."""
    lo, hi = CS_STEPS_CHUNK
    return max(1, min(hi, max(lo, math.ceil(n / 100))))


@dataclass(frozen=True)
class Grid:
    """The communication grid min((k + 1) h, t_end), k = 0 .. n - 1, and what is read at every
    point: the table's outputs, then the contact events; the contact count and active flag."""

    step: float
    stop_time: float
    n: int
    reals: tuple[int, ...] = tuple(
        vr(n) for n in (*OUTPUT_NAMES.values(), *CS_OUTPUT_NAMES.values(), *EVENT_NAMES)
    )
    count: int = vr("contact.count")
    active: int = vr("contact.active")

    @property
    def n_outputs(self) -> int:
        return len(self.reals) - len(EVENT_NAMES)


@dataclass
class LoopState:
    """What the loop carries from one communication point to the next: the time reached, the
    contact count and active flag, the contact records, and the wall time of its FMI calls."""

    count: int
    active: bool
    records: list[list[float]]
    t: float = 0.0
    seconds: float = 0.0
    rows: list[np.ndarray] = field(default_factory=list)

    def points(self, times: np.ndarray, reals: np.ndarray, counts: Any, actives: Any, n: int):
        """Add communication points: their times, real outputs (table, then events), counts and
        active flags."""
        self.t = float(times[-1])
        self.rows.append(np.column_stack([times, reals[:, :n]]))
        self.count, self.active = contact_bookkeeping(
            self.records, self.count, self.active, counts, actives, reals[:, n:]
        )


Loop = Callable[[Fmi2Slave, Grid, LoopState, "Progress | None"], None]
"""A communication loop over the grid, adding every point to the state."""


def c_loop(slave: Fmi2Slave, grid: Grid, state: LoopState, progress: Progress | None) -> None:
    """The loop in C, a chunk of steps per call (the module docstring)."""
    loop = cs_steps.CSteps(
        slave, grid.step, grid.stop_time, grid.reals, [grid.count], [grid.active]
    )
    size = chunk_size(grid.n)
    for k in range(0, grid.n, size):
        try:
            chunk = loop.run(k, min(k + size, grid.n), state.t)
        except FmiCallError as exc:
            state.t = exc.t if exc.t is not None else state.t
            raise
        state.seconds += chunk.seconds
        state.points(
            chunk.times,
            chunk.reals,
            chunk.integers[:, 0],
            chunk.booleans[:, 0] != 0,
            grid.n_outputs,
        )
        if progress is not None:
            progress.update(state.t / grid.stop_time)


def _initialise(
    slave: Fmi2Slave,
    scene: Scene,
    law: str,
    rtol: float,
    t_end: float,
    parameters: dict[str, Any] | None,
) -> None:
    slave.setup_experiment(rtol, t_end)
    slave.enter_initialization_mode()
    for name, kind, value in start_values(scene, law, parameters):
        slave.set(kind, [vr(name)], [value])
    slave.exit_initialization_mode()


def _start(slave: Fmi2Slave, grid: Grid) -> tuple[list[float], LoopState]:
    """The first row (t = 0) and the loop's state there."""
    row = [0.0, *slave.get("Real", grid.reals[: grid.n_outputs])]
    count = slave.get("Integer", [grid.count])[0]
    active = bool(slave.get("Boolean", [grid.active])[0])
    onset_speed = slave.get("Real", [vr("contact.onset_speed")])[0] if count else math.nan
    return row, LoopState(count, active, first_record(count, onset_speed))


def _finish(slave: Fmi2Slave) -> dict[str, Any]:
    """The FMU's integrator statistics and evaluation counters at the end of the run."""
    steps, rhs = slave.get(
        "Integer", [vr("diagnostics.integrator_steps"), vr("diagnostics.rhs_evaluations")]
    )
    counters = slave.get("Integer", [vr(f"diagnostics.{p}_evaluations") for p in EVALUATION_PARTS])
    slave.terminate()
    evaluations = dict(zip(EVALUATION_PARTS, (int(v) for v in counters), strict=True))
    return {"steps": int(steps), "rhs_evaluations": int(rhs), "evaluations": evaluations}


def simulate_cs(
    scene: Scene,
    law: str,
    *,
    rtol: float | None = None,
    communication_step: float | None = None,
    stop_time: float | None = None,
    parameters: dict[str, Any] | None = None,
    progress: Progress | None = None,
    loop: Loop = c_loop,
) -> Trajectory:
    """Co-simulation of the FMU with contact law `law` (its own integrator, solver.method): one
    output row per communication step (default: the scene's output_interval), the contact
    records from the FMU's event outputs, and statistics. stats["do_step_time"] is the wall time
    inside the loop's C calls (fmi2DoStep and the reads). `loop` runs the communication steps
    (tests compare it with a loop in Python)."""
    check_law(law)
    rtol = scene.integrator.rtol if rtol is None else rtol
    h = scene.integrator.output_interval if communication_step is None else communication_step
    t_end = scene.stop_time if stop_time is None else stop_time
    grid = Grid(h, t_end, check_rows(t_end, h, "communication_step"))
    wall = time.perf_counter()
    slave = Fmi2Slave(unzipped_fmu(), model_info.model_description())
    state = None
    try:
        _initialise(slave, scene, law, rtol, t_end, parameters)
        row, state = _start(slave, grid)
        loop(slave, grid, state, progress)
        stats = _finish(slave)
    except FmiCallError as exc:
        t = exc.t if exc.t is not None else (state.t if state is not None else 0.0)
        raise fmu_error(law, t, exc.function, slave.reason(str(exc))) from None
    finally:
        slave.free()
    table = Table((*TABLE_COLUMNS, *CS_OUTPUT_NAMES))
    table.add(row)
    table.add_block(np.concatenate(state.rows) if state.rows else np.zeros((0, len(table.names))))
    tr = cs_trajectory(law, scene.name, table.arrays(), state.records)
    tr.stats = {
        "integrator": f"{cs_method_name(scene, parameters)} inside the FMU "
        f"(co-simulation) rtol={rtol:g}, communication step {h:g} s",
        **stats,
        "contact_count": int(state.count),
        "wall_time": time.perf_counter() - wall,
        "do_step_time": state.seconds,
    }
    return tr
