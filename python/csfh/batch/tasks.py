"""Many runs of one scene, as tasks. A task is one model run of a scene with parameter overrides.
Its key is a hash of everything that determines the result (the scene's physics and integrator
settings, the model, the overrides, the horizon, the output grid, the FMU interface, the
binaries), so a re-run with the same output directory skips the tasks already done (see
`csfh.batch.store`), and the executor never matters (`csfh.batch.executors`): every task is
computed by the same function, `run_chunk`, from the same inputs, in whichever process.

Moreau tasks of the same scene and settings are grouped into chunks and run as one batch in the C
core (csfh.runners.moreau_batch); so are event-driven co-simulation tasks (interface "cs"), run by
the batch master in the FMU's own binary (csfh.runners.cs_batch, bitwise the single runs);
model-exchange tasks run through fmpy one at a time."""

from __future__ import annotations

import ctypes
import hashlib
import json
import os
import signal
import sys
import threading
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from functools import cache, cached_property
from pathlib import Path
from typing import Any

import numpy as np

from ..model._csfh_variables import DEFAULT_STOP_TIME, OUTPUT_INTERVAL
from ..model.scene import Scene

SCHEMA = 3  # 2: forces of the event-driven runs as interval peaks; 3: co-simulation summaries
# from the FMU's peak outputs and contact count, stress peaks
SIGNALS = ("x", "y", "theta", "F_N", "F_T")
"""Output signals kept on the grid for sweeps (m, m, rad, N, N). x, y, theta are the values at
the grid points; F_N and F_T the value of largest magnitude in each output interval (t_k-1, t_k]
(event-driven: over every integrator step; Moreau: the step with the largest impulse), so that an
impact peak does not depend on where the grid happens to cut it."""
KEY_DIGITS = 24
"""Hexadecimal digits of a task key (`task_key`)."""
SUMMARY_KEYS = ("first_contact", "contacts", "peak_F_N", "peak_abs_F_T", "steps")
"""What every task summary holds (`_summary`; co-simulation adds the stress peaks): the first
contact time in s (None: no contact), the number of contacts, the peak normal and tangential
force in N, and the integrator steps."""
_FMU_LOCK = threading.Lock()  # fmpy instances in one process: one run at a time (Dask threads)


def _current_binaries() -> str:
    """The fingerprint of the binaries in use (binaries_fingerprint), a Task's default."""
    return binaries_fingerprint()


@dataclass(frozen=True)
class Task:
    """One model run: `scene` with `parameters` overridden, up to `stop_time`, outputs on a grid
    of `output_interval` (kept only if `signals`)."""

    scene: Scene
    model: str
    parameters: tuple[tuple[str, float], ...] = ()
    stop_time: float = DEFAULT_STOP_TIME
    output_interval: float = OUTPUT_INTERVAL
    interface: str = "me"
    signals: bool = True
    meta: tuple[tuple[str, Any], ...] = field(default=(), compare=False)
    binaries: str = field(default_factory=_current_binaries)

    @cached_property
    def key(self) -> str:
        return task_key(self)

    def overrides(self) -> dict[str, float]:
        return dict(self.parameters)


_FINGERPRINTS: dict[int, tuple[Scene, dict[str, Any], str]] = {}
"""Fingerprints of the scenes seen last, by identity (a study's thousands of tasks share one
Scene object; scenes are immutable): (the scene, its fingerprint, as sorted JSON)."""


def _fingerprint(scene: Scene) -> tuple[dict[str, Any], str]:
    hit = _FINGERPRINTS.get(id(scene))
    if hit is not None and hit[0] is scene:
        return hit[1], hit[2]
    data = asdict(scene)
    for k in ("name", "description", "source", "models"):
        data.pop(k, None)
    text = json.dumps(data, sort_keys=True, default=list)
    fingerprint = json.loads(text)
    if len(_FINGERPRINTS) > 256:
        _FINGERPRINTS.clear()
    _FINGERPRINTS[id(scene)] = (scene, fingerprint, json.dumps(fingerprint, sort_keys=True))
    return fingerprint, _FINGERPRINTS[id(scene)][2]


def scene_fingerprint(scene: Scene) -> dict[str, Any]:
    """Everything of a scene that can change a result (not its name, description or source).
    The dict is shared between the calls for one scene: do not modify it."""
    return _fingerprint(scene)[0]


@cache
def binaries_fingerprint() -> str:
    """Hash of the FMU, the core library and the batch master in use: a rebuilt model
    invalidates old results."""
    from ..paths import batch_library_path, core_library_path, fmu_path

    h = hashlib.sha256()
    for path in (fmu_path(), core_library_path()):
        h.update(Path(path).read_bytes())
    try:
        h.update(Path(batch_library_path()).read_bytes())
    except FileNotFoundError:  # a build without the FMU: no co-simulation batches
        pass
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
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_DIGITS]


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
    first: float | None,
    contacts: int,
    peak_fn: float,
    peak_ft: float,
    steps: int,
    stresses: tuple[float, float] | None = None,
) -> dict[str, Any]:
    values = (first, int(contacts), float(peak_fn), float(peak_ft), int(steps))
    out: dict[str, Any] = dict(zip(SUMMARY_KEYS, values, strict=True))
    if stresses is not None:  # co-simulation: the peak flexure stress and contact pressure, Pa
        out["peak_flexure_stress"] = float(stresses[0])
        out["peak_contact_pressure"] = float(stresses[1])
    return out


def _run_summary(s: dict[str, Any]) -> dict[str, Any]:
    """The task summary of a run summary (Trajectory.summary, CsBatchResult.summary)."""
    stresses = None
    if "max_flexure_stress" in s:
        stresses = (s["max_flexure_stress"], s["max_contact_pressure"])
    return _summary(
        s["first_contact_time"], s["contacts"], s["max_F_N"], s["max_abs_F_T"], s["steps"], stresses
    )


def _signals(task: Task, tr: Any) -> dict[str, np.ndarray] | None:
    """The output signals of a run on the task's grid (see SIGNALS), or None."""
    if not task.signals:
        return None
    g = grid(task.stop_time, task.output_interval)
    sig = {name: np.interp(g, tr.t, tr[name]) for name in SIGNALS}
    for name in ("F_N", "F_T"):
        t_all = np.concatenate([tr.t, tr.steps["t"]]) if tr.steps else tr.t
        f_all = np.concatenate([tr[name], tr.steps[name]]) if tr.steps else tr[name]
        sig[name] = interval_peaks(g, sig[name], t_all, f_all)
    return sig


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
    return task.key, _run_summary(tr.summary()), _signals(task, tr), wall


def _run_cs_batch(tasks: Sequence[Task]) -> list[Result]:
    """Co-simulation tasks of one scene, model, horizon and grid, with the same parameter
    names, as one call into the batch master: the same summaries and signals as _run_fmu gives
    each of them alone (bitwise, tested)."""
    from ..runners.cs_batch import cs_batch

    first = tasks[0]
    batch = cs_batch(
        first.scene,
        first.model,
        [t.overrides() for t in tasks],
        stop_time=first.stop_time,
        communication_step=first.output_interval,
        record=first.signals,
    )
    wall = batch.wall_time / len(tasks)
    out: list[Result] = []
    for i, task in enumerate(tasks):
        sig = _signals(task, batch.trajectory(i)) if task.signals else None
        out.append((task.key, _run_summary(batch.summary(i)), sig, wall))
    return out


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
    if tasks[0].interface == "cs" and batchable(tasks) and _batch_master_available():
        return _run_cs_batch(tasks)
    return [_run_fmu(t) for t in tasks]


def batch_group(task: Task) -> tuple[Any, ...] | None:
    """The group of tasks that run together as one batch (None: alone): Moreau tasks of one
    scene and settings; co-simulation tasks of one scene, model and settings that override the
    same parameters (the batch master sets the same variables in every run)."""
    base = (
        _fingerprint(task.scene)[1],
        task.stop_time,
        task.output_interval,
        task.signals,
    )
    if task.model == "Moreau":
        return ("Moreau", *base)
    if task.interface == "cs":
        return ("cs", task.model, tuple(sorted(k for k, _ in task.parameters)), *base)
    return None


@cache
def _batch_master_available() -> bool:
    """Whether libcsfh_batch.so is there (a build without it runs co-simulation tasks one by
    one through fmpy, with the same results)."""
    from ..paths import batch_library_path

    try:
        batch_library_path()
    except FileNotFoundError:
        return False
    return True


def batchable(tasks: Sequence[Task]) -> bool:
    """Whether the tasks form one batch."""
    group = batch_group(tasks[0])
    return group is not None and all(batch_group(t) == group for t in tasks)


def worker_init(parent: int | None = None) -> None:
    """Ctrl-C goes to the whole process group: a worker ignores it and the parent decides (it
    keeps what is done and ends the workers). The parent starts workers with SIGINT blocked, so
    that one during the start-up is discarded here too. With `parent` (the parent's process
    id) the worker also ends when its parent does (`end_with_parent`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    if parent is not None:
        end_with_parent(parent)


_PR_SET_PDEATHSIG = 1  # <sys/prctl.h>


def end_with_parent(parent: int) -> None:
    """End this process when the process `parent` ends, even by SIGKILL, which gives it no
    chance to end its workers: a worker would otherwise wait for work forever, and keep
    multiprocessing's resource tracker alive with it. On Linux at once (the kernel's
    parent-death signal, prctl PR_SET_PDEATHSIG); everywhere within a second (a thread that
    watches the parent's process id, which changes when the parent is gone)."""
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):  # no prctl: the thread alone
            pass
    if os.getppid() != parent:  # ended before the signal was asked for
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()


def _watch_parent(parent: int) -> None:
    while os.getppid() == parent:
        time.sleep(0.5)
    os._exit(1)
