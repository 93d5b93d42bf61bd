"""What the studies that run many tasks share (sweep, tolerance, shock): running the tasks into
their result store (serial, local processes or Dask; an interrupted study keeps what is done),
the warnings of a store whose records were skipped, and the run's bookkeeping for the reports."""

from __future__ import annotations

import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..batch.executors import RunReport, run_tasks
from ..batch.store import ResultStore
from ..batch.tasks import Task
from ..errors import ParameterError
from ..model import model_info
from ..output import results_dir

MAX_WARNINGS = 10
"""Skipped store records reported one by one; the rest are counted."""


@dataclass(frozen=True)
class Execution:
    """Where and how a study's tasks run: the output directory (the result store; None:
    results/STUDY/SCENE), local processes (None: all cores, 1: serial in this process) or a Dask
    scheduler's address."""

    out: Path | None = None
    workers: int | None = None
    dask: str | None = None
    quiet: bool = False

    def directory(self, study: str, scene: str) -> Path:
        return results_dir(self.out, study, scene)


def open_store(out: Path) -> ResultStore:
    """The result store of a study's output directory; its skipped records as warnings."""
    store = ResultStore(out)
    for problem in store.problems[:MAX_WARNINGS]:
        print(f"csfh: warning: {problem}", file=sys.stderr)
    if len(store.problems) > MAX_WARNINGS:
        print(
            f"csfh: warning: {len(store.problems) - MAX_WARNINGS} more records skipped "
            f"(all of them are in {out / 'tasks.rejected.jsonl'})",
            file=sys.stderr,
        )
    return store


def execute(tasks: Sequence[Task], store: ResultStore, how: Execution, label: str) -> RunReport:
    """Compute the tasks not yet in the store (csfh.batch.executors.run_tasks); on Ctrl-C, say
    that the finished runs are kept (in the store's directory) and how to resume, and stop."""
    try:
        return run_tasks(
            tasks, store, workers=how.workers, dask_address=how.dask, label=label, quiet=how.quiet
        )
    except KeyboardInterrupt:
        print(
            f"csfh: {len(store)} finished runs are kept in {store.directory}; run the same "
            "command again to resume",
            file=sys.stderr,
        )
        raise


def counts(report: RunReport) -> dict[str, Any]:
    """A run's task counts and executor, as the reports give them."""
    return {
        "tasks": report.total,
        "computed": report.computed,
        "reused": report.reused,
        "executor": report.executor,
    }


def run_time_sum(tasks: Sequence[Task], store: ResultStore) -> float:
    """Wall time of the runs themselves, summed over the tasks (whenever they were computed)."""
    keys = {t.key for t in tasks}
    return float(sum(store.records[k].get("wall_time", 0.0) for k in keys))


INTERFACE_TEXTS = {
    "cs": "co-simulation (the integrator inside the FMU; the runs batched in the FMU's own "
    "binary by the batch master)",
    "me": "model exchange with fmpy's CVode (BDF, events by root finding)",
}
"""How the event-driven models of a study run by each interface, for its report."""


def interface_text(interface: str, rtol: float) -> str:
    """How the event-driven models of a study run, for its report."""
    return f"{INTERFACE_TEXTS[interface]}, rtol {rtol:g}"


def check_models(models: Sequence[str] | None, default: tuple[str, ...]) -> tuple[str, ...]:
    """The models a study runs (each once, in the order given; none: `default`);
    ParameterError naming an unknown one."""
    if not models:
        return default
    for m in models:
        if m not in model_info.MODELS:
            raise ParameterError(f"unknown model {m!r} (known: {', '.join(model_info.MODELS)})")
    return tuple(dict.fromkeys(models))
