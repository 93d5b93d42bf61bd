"""Many runs of one scene: tasks, a resumable result store, and three executors that give
bitwise-identical results (serial, local processes, a Dask distributed cluster).

A task is one model run of a scene with parameter overrides. Its key is a hash of everything that
determines the result (the scene's physics and integrator settings, the model, the overrides, the
horizon, the output grid, the FMU interface), so a re-run with the same output directory skips the
tasks already done, and the executor never matters: every task is computed by the same function
(`run_chunk`) from the same inputs, in whichever process.

Moreau tasks of the same scene and settings are grouped into chunks and run as one batch in the C
core (csfh.moreau_batch); event-driven tasks run through the FMU one at a time.

Store layout (DIR): tasks.jsonl, one line per finished task
{"key", "model", "parameters", "summary", "signals"}; signals/KEY.npz with the output signals on
the grid (sweeps only). A line is appended (and fsync'ed) only after its signals are in place, so
an interrupted run leaves a consistent store; a torn last line is dropped on the next open."""

from __future__ import annotations

import hashlib
import json
import math
import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import asdict, dataclass, field
from functools import cache, cached_property
from pathlib import Path
from typing import Any

import numpy as np

from ..model.scene import Scene
from ..progress import Progress

SCHEMA = 2  # 2: forces of the event-driven runs as interval peaks
SIGNALS = ("x", "y", "theta", "F_N", "F_T")
"""Output signals kept on the grid for sweeps (m, m, rad, N, N). x, y, theta are the values at
the grid points; F_N and F_T the value of largest magnitude in each output interval (t_k-1, t_k]
(event-driven: over every integrator step; Moreau: the step with the largest impulse), so that an
impact peak does not depend on where the grid happens to cut it."""
_FMU_LOCK = threading.Lock()  # fmpy instances in one process: one run at a time (Dask threads)


@dataclass(frozen=True)
class Task:
    """One model run: `scene` with `parameters` overridden, up to `stop_time`, outputs on a grid
    of `output_interval` (kept only if `signals`)."""

    scene: Scene
    model: str
    parameters: tuple[tuple[str, float], ...] = ()
    stop_time: float = 1.0
    output_interval: float = 1e-4
    interface: str = "me"
    signals: bool = True
    meta: tuple[tuple[str, Any], ...] = field(default=(), compare=False)
    binaries: str = field(default_factory=lambda: binaries_fingerprint())

    @cached_property
    def key(self) -> str:
        return task_key(self)

    def overrides(self) -> dict[str, float]:
        return dict(self.parameters)


def scene_fingerprint(scene: Scene) -> dict[str, Any]:
    """Everything of a scene that can change a result (not its name, description or source)."""
    data = asdict(scene)
    for k in ("name", "description", "source", "models"):
        data.pop(k, None)
    return json.loads(json.dumps(data, sort_keys=True, default=list))


@cache
def binaries_fingerprint() -> str:
    """Hash of the FMU and the core library in use: a rebuilt model invalidates old results."""
    from ..paths import core_library_path, fmu_path

    h = hashlib.sha256()
    for path in (fmu_path(), core_library_path()):
        h.update(Path(path).read_bytes())
    return h.hexdigest()[:16]


def task_key(task: Task) -> str:
    spec = {
        "schema": SCHEMA,
        "binaries": task.binaries,
        "scene": scene_fingerprint(task.scene),
        "model": task.model,
        "parameters": sorted([k, float(v)] for k, v in task.parameters),
        "stop_time": float(task.stop_time),
        "output_interval": float(task.output_interval),
        "interface": task.interface if task.model != "Moreau" else "core",
        "signals": task.signals,
    }
    text = json.dumps(spec, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def grid(stop_time: float, output_interval: float) -> np.ndarray:
    n = round(stop_time / output_interval)
    return np.arange(n + 1) * output_interval


def interval_peaks(g: np.ndarray, at_grid: np.ndarray, t: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Per grid point k, the sample of largest magnitude among the grid value and every sample
    (t, f) with g[k-1] < t <= g[k]."""
    k = np.searchsorted(g, t, side="left")
    inside = (k >= 1) & (k < len(g))
    hi, lo = at_grid.copy(), at_grid.copy()
    np.maximum.at(hi, k[inside], f[inside])
    np.minimum.at(lo, k[inside], f[inside])
    return np.where(np.abs(lo) > np.abs(hi), lo, hi)


# ------------------------------------------------------------------------------------------
# running tasks (in any process)

Result = tuple[str, dict[str, Any], dict[str, np.ndarray] | None, float]
"""(task key, summary, signals or None, wall time in s). The wall time is kept apart: it is the
only part of a result that depends on where and when the task ran."""


def _summary(
    first: float | None, contacts: int, peak_fn: float, peak_ft: float, steps: int
) -> dict[str, Any]:
    return {
        "first_contact": first,
        "contacts": int(contacts),
        "peak_F_N": float(peak_fn),
        "peak_abs_F_T": float(peak_ft),
        "steps": int(steps),
    }


def _run_fmu(task: Task) -> Result:
    from ..runners.fmu import simulate_cs, simulate_me

    with _FMU_LOCK:
        wall = time.perf_counter()
        if task.interface == "cs":
            tr = simulate_cs(
                task.scene,
                task.model,
                stop_time=task.stop_time,
                communication_step=task.output_interval,
                parameters=task.overrides(),
            )
        else:
            tr = simulate_me(
                task.scene,
                task.model,
                stop_time=task.stop_time,
                output_interval=task.output_interval,
                parameters=task.overrides(),
                max_step_records=1_000_000,
            )
        wall = time.perf_counter() - wall
    s = tr.summary()
    summary = _summary(
        s["first_contact_time"], s["contacts"], s["max_F_N"], s["max_abs_F_T"], s["steps"]
    )
    sig = None
    if task.signals:
        g = grid(task.stop_time, task.output_interval)
        sig = {name: np.interp(g, tr.t, tr[name]) for name in SIGNALS}
        for name in ("F_N", "F_T"):
            t_all = np.concatenate([tr.t, tr.steps["t"]]) if tr.steps else tr.t
            f_all = np.concatenate([tr[name], tr.steps[name]]) if tr.steps else tr[name]
            sig[name] = interval_peaks(g, sig[name], t_all, f_all)
    return task.key, summary, sig, wall


def _run_moreau(tasks: Sequence[Task]) -> list[Result]:
    from ..runners.moreau_batch import moreau_batch

    first = tasks[0]
    batch = moreau_batch(
        first.scene,
        [t.overrides() for t in tasks],
        stop_time=first.stop_time,
        output_interval=first.output_interval,
    )
    if np.any(batch.status != 0):
        bad = int(np.flatnonzero(batch.status != 0)[0])
        raise FloatingPointError(
            f"Moreau: non-finite state for parameters {tasks[bad].overrides()}; reduce h"
        )
    wall = batch.wall_time / len(tasks)
    out: list[Result] = []
    g = grid(first.stop_time, first.output_interval) if first.signals else None
    for i, task in enumerate(tasks):
        t_imp = batch.impact_times(i)
        F_N, F_T = batch.column(i, "F_N"), batch.column(i, "F_T")
        summary = _summary(
            float(t_imp[0]) if len(t_imp) else None,
            int(batch.stats[i, 5]),
            float(np.max(F_N)),
            float(np.max(np.abs(F_T))),
            int(batch.stats[i, 0]),
        )
        sig = None
        if g is not None:
            t = batch.column(i, "t")
            sig = {name: np.interp(g, t, batch.column(i, name)) for name in SIGNALS}
        out.append((task.key, summary, sig, wall))
    return out


def run_chunk(tasks: Sequence[Task]) -> list[Result]:
    """Run a chunk: Moreau tasks of one scene and settings as one batch, anything else one by
    one. This is the only function that computes results, whatever the executor."""
    if not tasks:
        return []
    here = binaries_fingerprint()
    if any(t.binaries != here for t in tasks):
        raise RuntimeError(
            f"this worker's csfh binaries ({here}) are not the submitter's "
            f"({tasks[0].binaries}): install the same csfh build on every worker"
        )
    if tasks[0].model == "Moreau":
        return _run_moreau(tasks)
    return [_run_fmu(t) for t in tasks]


def _worker_init() -> None:
    # Ctrl-C goes to the whole process group: let the parent decide (it keeps what is done)
    signal.signal(signal.SIGINT, signal.SIG_IGN)


# ------------------------------------------------------------------------------------------
# the store


class ResultStore:
    """Per-task results in a directory, appended as they complete (see the module docstring)."""

    def __init__(self, directory: Path) -> None:
        self.directory = Path(directory)
        self.directory.mkdir(parents=True, exist_ok=True)
        self.index = self.directory / "tasks.jsonl"
        self.records: dict[str, dict[str, Any]] = {}
        self._load()

    def _load(self) -> None:
        if not self.index.exists():
            return
        data = self.index.read_bytes()
        good = 0
        for line in data.splitlines(keepends=True):
            if not line.endswith(b"\n"):
                break  # torn last line of an interrupted write
            try:
                rec = json.loads(line)
                key = rec["key"]
            except (ValueError, KeyError, TypeError):
                break
            if rec.get("signals") and not (self.directory / rec["signals"]).exists():
                break
            self.records[key] = rec
            good += len(line)
        if good != len(data):  # drop what cannot be read, so that appends stay line-aligned
            with open(self.index, "r+b") as fh:
                fh.truncate(good)

    def __contains__(self, key: str) -> bool:
        return key in self.records

    def __len__(self) -> int:
        return len(self.records)

    def add(
        self,
        task: Task,
        summary: dict[str, Any],
        signals: dict[str, np.ndarray] | None,
        wall_time: float = 0.0,
    ) -> None:
        self.add_many([(task, summary, signals, wall_time)])

    def add_many(
        self,
        results: Sequence[tuple[Task, dict[str, Any], dict[str, np.ndarray] | None, float]],
    ) -> None:
        """Store results: signal files first, then one index line each, one fsync for all."""
        lines, records = [], []
        for task, summary, signals, wall_time in results:
            rel = None
            if signals is not None:
                rel = f"signals/{task.key}.npz"
                (self.directory / "signals").mkdir(exist_ok=True)
                tmp = self.directory / f"signals/.{task.key}.tmp.npz"
                np.savez_compressed(tmp, **signals)
                os.replace(tmp, self.directory / rel)
            rec = {
                "key": task.key,
                "model": task.model,
                "parameters": dict(task.parameters),
                "stop_time": task.stop_time,
                "meta": dict(task.meta),
                "summary": summary,
                "signals": rel,
                "wall_time": wall_time,
            }
            lines.append(json.dumps(rec, sort_keys=True) + "\n")
            records.append(rec)
        if not lines:
            return
        with open(self.index, "a", encoding="utf-8") as fh:
            fh.write("".join(lines))
            fh.flush()
            os.fsync(fh.fileno())
        for rec in records:
            self.records[rec["key"]] = rec

    def summary(self, key: str) -> dict[str, Any]:
        return self.records[key]["summary"]

    def signals(self, key: str) -> dict[str, np.ndarray]:
        rel = self.records[key]["signals"]
        if rel is None:
            raise KeyError(f"task {key} has no signals")
        with np.load(self.directory / rel) as data:
            return {name: data[name] for name in data.files}


# ------------------------------------------------------------------------------------------
# executors


def default_workers() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def make_chunks(tasks: Sequence[Task], workers: int, batch: int = 64) -> list[list[Task]]:
    """Moreau tasks grouped by scene and settings into batches (at most `batch`, and small
    enough to keep every worker busy); event-driven tasks one per chunk. Deterministic."""
    groups: dict[tuple[Any, ...], list[Task]] = {}
    chunks: list[list[Task]] = []
    for t in tasks:
        if t.model == "Moreau":
            gk = (
                json.dumps(scene_fingerprint(t.scene), sort_keys=True),
                t.stop_time,
                t.output_interval,
                t.signals,
            )
            groups.setdefault(gk, []).append(t)
        else:
            chunks.append([t])
    for group in groups.values():
        size = max(1, min(batch, math.ceil(len(group) / max(1, workers))))
        chunks += [group[i : i + size] for i in range(0, len(group), size)]
    return chunks


@dataclass
class RunReport:
    total: int
    reused: int
    computed: int
    wall_time: float
    executor: str


def run_tasks(
    tasks: Sequence[Task],
    store: ResultStore,
    *,
    workers: int | None = None,
    dask_address: str | None = None,
    label: str = "tasks",
    quiet: bool = False,
    batch: int = 64,
    on_result: Callable[[int, int], None] | None = None,
) -> RunReport:
    """Compute the tasks not yet in `store` and add their results as they complete. workers=1
    runs serially in this process; more uses that many local processes (default: all cores);
    dask_address sends the chunks to a Dask distributed scheduler. Ctrl-C (KeyboardInterrupt)
    propagates after pending work is cancelled; everything finished so far is in the store."""
    unique: dict[str, Task] = {}
    for t in tasks:
        unique.setdefault(t.key, t)
    pending = [t for k, t in unique.items() if k not in store]
    reused = len(unique) - len(pending)
    n_workers = default_workers() if workers is None else max(1, workers)
    chunks = make_chunks(pending, n_workers if dask_address is None else max(n_workers, 8), batch)
    by_key = {t.key: t for t in pending}
    progress = Progress(label, quiet=quiet)
    done = 0
    wall = time.perf_counter()

    def accept(results: Iterable[Result]) -> None:
        nonlocal done
        batch = [(by_key[key], summary, sig, wall) for key, summary, sig, wall in results]
        store.add_many(batch)
        done += len(batch)
        progress.update(done / max(1, len(pending)))
        if on_result is not None:
            on_result(done, len(pending))

    try:
        if not chunks:
            executor = "none (all reused)"
        elif dask_address is not None:
            executor = f"dask {dask_address}"
            _run_dask(chunks, dask_address, accept)
        elif n_workers == 1 or len(chunks) == 1:
            executor = "serial"
            for chunk in chunks:
                accept(run_chunk(chunk))
        else:
            executor = f"{n_workers} local processes"
            _run_processes(chunks, n_workers, accept)
    finally:
        progress.close()
    return RunReport(
        total=len(unique),
        reused=reused,
        computed=done,
        wall_time=time.perf_counter() - wall,
        executor=executor,
    )


def _run_processes(
    chunks: list[list[Task]], workers: int, accept: Callable[[Iterable[Result]], None]
) -> None:
    ctx = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(
        max_workers=min(workers, len(chunks)), mp_context=ctx, initializer=_worker_init
    )
    futures: set[Future[list[Result]]] = set()
    try:
        # largest chunks first (Moreau batches, then runs), a bounded number in flight
        queue = sorted(chunks, key=len)
        while queue or futures:
            while queue and len(futures) < 2 * workers:
                futures.add(pool.submit(run_chunk, queue.pop()))
            finished, futures = wait(futures, return_when=FIRST_COMPLETED)
            for fut in finished:
                accept(fut.result())
    except BaseException:
        for fut in futures:
            fut.cancel()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


def _run_dask(
    chunks: list[list[Task]], address: str, accept: Callable[[Iterable[Result]], None]
) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise RuntimeError(
            "--dask needs dask.distributed: pip install 'dask[distributed]'"
        ) from exc
    try:
        client = Client(address, timeout="10s")
    except OSError as exc:
        raise OSError(f"cannot connect to the Dask scheduler at {address}: {exc}") from None
    futures = []
    try:
        for chunk in chunks:
            ckey = hashlib.sha256("".join(t.key for t in chunk).encode()).hexdigest()[:16]
            futures.append(client.submit(run_chunk, chunk, key=f"csfh-chunk-{ckey}", pure=False))
        for fut in as_completed(futures):
            accept(fut.result())
    except BaseException:
        client.cancel(futures)
        raise
    finally:
        client.close()
