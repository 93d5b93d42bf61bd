"""Many runs of one scene, as tasks. A task is one model run of a scene with parameter overrides.
Its key is a hash of everything that determines the result (the scene's physics and integrator
settings, the model, the overrides, the horizon, the output grid, the FMU interface, the
binaries), so a re-run with the same output directory skips the tasks already done (see
`csfh.batch.store`), and the executor never matters (`csfh.batch.executors`): every task is
computed by the same function, `run_chunk`, from the same inputs, in whichever process.

Each task runs on the runner of its model and interface (csfh.runners.registry); the tasks of a
runner that batches (Moreau in the C core, co-simulation in the batch master, bitwise the single
runs) with the same scene and settings are grouped into chunks and run as one batch; the others
run one at a time."""

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
from contextlib import nullcontext
from dataclasses import asdict, dataclass, field
from functools import cache, cached_property
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InstallError
from ..model._csfh_variables import DEFAULT_STOP_TIME, OUTPUT_INTERVAL
from ..model.scene import Scene
from ..runners.registry import Runner, TrajectoryRuns, runner_for

SCHEMA = 4  # 2: forces of the event-driven runs as interval peaks; 3: co-simulation summaries
# from the FMU's peak outputs and contact count, stress peaks; 4: the last contact's end
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
        "interface": runner_for(task.model, task.interface).interface,
        "signals": task.signals,
    }
    text = json.dumps(spec, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_DIGITS]


def grid(stop_time: float, output_interval: float) -> np.ndarray:
    n = round(stop_time / output_interval)
    return np.arange(n + 1) * output_interval


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


def _settling(out: dict[str, Any], s: dict[str, Any]) -> dict[str, Any]:
    """A run's last contact, where its summary has it: when the last contact that ended did
    (None: none ended) and whether a contact is still on at the end (0 or 1)."""
    if "last_release_time" in s:
        last = s["last_release_time"]
        out["last_release"] = None if last is None else float(last)
        out["contact_at_end"] = int(s["contact_at_end"])
    return out


def _run_summary(s: dict[str, Any]) -> dict[str, Any]:
    """The task summary of a run summary (Trajectory.summary, CsBatchResult.summary)."""
    stresses = None
    if "max_flexure_stress" in s:
        stresses = (s["max_flexure_stress"], s["max_contact_pressure"])
    out = _summary(
        s["first_contact_time"], s["contacts"], s["max_F_N"], s["max_abs_F_T"], s["steps"], stresses
    )
    return _settling(out, s)


def _run_group(runner: Runner, tasks: Sequence[Task]) -> list[Result]:
    """Tasks of one scene, model, horizon and grid as one `run_many` of their runner: a batch,
    or runs one by one (the same results either way, tested)."""
    first = tasks[0]
    with _FMU_LOCK if runner.exclusive else nullcontext():
        runs = runner.run_many(
            first.scene,
            first.model,
            [t.overrides() for t in tasks],
            stop_time=first.stop_time,
            output_interval=first.output_interval,
            record=first.signals,
        )
    g = grid(first.stop_time, first.output_interval) if first.signals else None
    return [
        (
            task.key,
            _run_summary(runs.summary(i)),
            runs.signals(i, g) if g is not None else None,
            runs.run_time(i),
        )
        for i, task in enumerate(tasks)
    ]


def run_alone(task: Task) -> Result:
    """A task as one run of its runner (`Runner.run`) rather than in a batch, at the cost of one
    run per call: for co-simulation the result the batch master gives it (tested)."""
    runner = runner_for(task.model, task.interface)
    with _FMU_LOCK if runner.exclusive else nullcontext():
        tr = runner.run(
            task.scene,
            task.model,
            stop_time=task.stop_time,
            output_interval=task.output_interval,
            parameters=task.overrides(),
        )
    runs = TrajectoryRuns([tr])
    g = grid(task.stop_time, task.output_interval) if task.signals else None
    signals = runs.signals(0, g) if g is not None else None
    return task.key, _run_summary(runs.summary(0)), signals, runs.run_time(0)


def run_chunk(tasks: Sequence[Task]) -> list[Result]:
    """Run a chunk: tasks that form one batch of a runner that batches in one call, anything
    else one by one. This is the only function that computes results, whatever the executor."""
    if not tasks:
        return []
    here = binaries_fingerprint()
    if any(t.binaries != here for t in tasks):
        raise InstallError(
            f"this worker's csfh binaries ({here}) are not the submitter's "
            f"({tasks[0].binaries}): install the same csfh build on every worker"
        )
    runner = runner_for(tasks[0].model, tasks[0].interface)
    if runner.batches and batchable(tasks):
        return _run_group(runner, tasks)
    return [r for t in tasks for r in _run_group(runner_for(t.model, t.interface), [t])]


def batch_group(task: Task) -> tuple[Any, ...] | None:
    """The group of tasks that run together as one batch (None: alone): tasks of a runner that
    batches, of one scene, model and settings, and where the runner needs it (the batch master
    sets the same variables in every run) overriding the same parameters."""
    runner = runner_for(task.model, task.interface)
    if not runner.batches:
        return None
    names = tuple(sorted(k for k, _ in task.parameters)) if runner.same_parameters else ()
    base = (_fingerprint(task.scene)[1], task.stop_time, task.output_interval, task.signals)
    return (runner.interface, task.model, names, *base)


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
