"""Event-driven Monte Carlo throughput: the batch co-simulation master against today's per-run
path, side by side in one run, one core (everything serial in this process).

The runs are those of `csfh tolerance tolerance_csfh`: 0.5 s of the `csfh` scene (its flexure,
friction and the first six impacts), LN_cylinders, rtol 1e-6, communication grid 1 ms, each run
a different sample of the file's tolerances (contact radii, flexure height, radius, opening).

* per run, model exchange: `csfh.batch.tasks.run_chunk` on one task at a time with interface "me"
  (the default of `csfh tolerance` and `csfh sweep`): fmpy's CVode stepped from Python.
* per run, co-simulation: the per-run function of the task system (`csfh.batch.tasks.run_alone`)
  with interface "cs", one task at a time (fmpy's FMU2Slave, fmi2DoStep per grid point from
  Python): the path of `--interface cs` before the batch master.
* batched, inside the call: `csfh.runners.cs_batch` with all the samples in one call into
  libcsfh_batch.so, timed inside the C call (the FMU's own binary, driven through its fmi2
  functions, only the reductions returned).
* batched, task system: `run_chunk` on chunks of 64 tasks (what `csfh tolerance --interface cs`
  and `csfh shock` run in each worker), with the Python set-up and the summaries.
* batched, end to end: `run_tasks` serially into a result store (keys, the store's appends).

Targets: >= 100x the per-run path's runs per second, and >= 300 runs per second per
core. The ratio is reported against both per-run paths. The machine may be shared: each figure
is the best of three repetitions.

Against another build (e.g. main's, its installed package copied to DIR): --baseline DIR runs
the three batched paths in child processes, this build and the one in DIR (PYTHONPATH) in
turn, --pairs times, and reports this build's speed over the baseline's per path (the median
of the pairs' ratios) and whether the results are the same, bitwise.

Run: python benchmarks/bench_cs_batch.py [--quick] [--baseline DIR [--pairs N]]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

TARGET_RATIO = 100.0
TARGET_RATE = 300.0


def _setup(n_batch: int) -> tuple[Any, list[dict[str, float]], list[Any]]:
    """The study's scene and the first n_batch samples, and their co-simulation tasks."""
    from csfh.batch.tasks import Task
    from csfh.studies.tolerance.study import load_study, sample

    study = load_study("tolerance_csfh")
    samples = [sample(study, k) for k in range(n_batch)]
    tasks = [
        Task(
            scene=study.scene,
            model=LAW,
            parameters=tuple(sorted(s.items())),
            stop_time=STOP,
            output_interval=GRID,
            interface="cs",
            signals=False,
        )
        for s in samples
    ]
    return study.scene, samples, tasks


def _best_rate(fn: Callable[[], object], n: int, repeats: int = 3) -> float:
    return _best_rates(fn, n, repeats)[0]


def _best_rates(fn: Callable[[], object], n: int, repeats: int = 3) -> tuple[float, float]:
    """The best runs per second of wall time and of this process's CPU time (on a shared
    machine the CPU time is the steadier one)."""
    best, best_cpu = 0.0, 0.0
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        best = max(best, n / (time.perf_counter() - t0))
        best_cpu = max(best_cpu, n / max(time.process_time() - c0, 1e-9))
    return best, best_cpu


def batched_rates(n_batch: int) -> dict[str, object]:
    """Runs per second of the three batched paths (best of three), and a digest of the
    batch's results."""
    from csfh.batch.executors import run_tasks
    from csfh.batch.store import ResultStore
    from csfh.batch.tasks import run_chunk
    from csfh.runners.cs_batch import cs_batch

    scene, samples, batched = _setup(n_batch)
    # warm: load the batch library and unzip the FMU once (as any long study does)
    cs_batch(scene, LAW, samples[:2], stop_time=STOP, communication_step=GRID)
    in_call, in_call_cpu, digest = 0.0, 0.0, ""
    for _ in range(3):
        c0 = time.process_time()
        b = cs_batch(scene, LAW, samples, stop_time=STOP, communication_step=GRID)
        in_call_cpu = max(in_call_cpu, n_batch / max(time.process_time() - c0, 1e-9))
        in_call = max(in_call, n_batch / b.wall_time)
        digest = hashlib.sha256(b.results.tobytes() + b.status.tobytes()).hexdigest()[:16]
    chunks = [batched[i : i + 64] for i in range(0, n_batch, 64)]
    rate_chunks = _best_rates(lambda: [run_chunk(c) for c in chunks], n_batch)

    def end_to_end() -> None:
        with tempfile.TemporaryDirectory() as tmp:
            run_tasks(batched, ResultStore(Path(tmp)), workers=1, quiet=True)

    rate_e2e = _best_rates(end_to_end, n_batch)
    return {
        "in_call": in_call,
        "run_chunk": rate_chunks[0],
        "end_to_end": rate_e2e[0],
        "in_call_cpu": in_call_cpu,
        "run_chunk_cpu": rate_chunks[1],
        "end_to_end_cpu": rate_e2e[1],
        "results": digest,
    }


def against(baseline: str, n_batch: int, pairs: int) -> None:
    """This build against the one in `baseline`, child processes in turn (module docstring)."""

    def child(pythonpath: str | None) -> dict[str, object]:
        env = dict(os.environ)
        if pythonpath is not None:
            env["PYTHONPATH"] = os.pathsep.join(filter(None, [pythonpath, env.get("PYTHONPATH")]))
        out = subprocess.run(
            [sys.executable, __file__, "--child", str(n_batch)],
            env=env,
            check=True,
            capture_output=True,
            text=True,
        ).stdout
        return json.loads(out.splitlines()[-1])

    paths = ("in_call", "run_chunk", "end_to_end")
    ratios: dict[str, list[float]] = {p + cpu: [] for cpu in ("", "_cpu") for p in paths}
    rates: dict[str, dict[str, list[float]]] = {"this": {}, "base": {}}
    same = True
    for p in range(pairs):
        runs = {}
        for side in ("this", "base") if p % 2 == 0 else ("base", "this"):
            runs[side] = child(None if side == "this" else baseline)
        same = same and runs["this"]["results"] == runs["base"]["results"]
        for path in ratios:
            ratios[path].append(float(runs["this"][path]) / float(runs["base"][path]))
            for side in runs:
                rates[side].setdefault(path, []).append(float(runs[side][path]))
    print(
        f"This build against {baseline}: {n_batch} runs, {pairs} pairs in turn (median; "
        "_cpu: per second of the process's CPU time)"
    )
    print(f"  {'path':<14} {'this runs/s':>12} {'base runs/s':>12} {'ratio':>7} {'range':>14}")
    for path, r in ratios.items():
        this, base = statistics.median(rates["this"][path]), statistics.median(rates["base"][path])
        print(
            f"  {path:<14} {this:12.0f} {base:12.0f} {statistics.median(r):7.2f} "
            f"{min(r):6.2f}-{max(r):<6.2f}"
        )
    print(f"  results bitwise the same: {'yes' if same else 'NO'}")


LAW, STOP, GRID = "LN_cylinders", 0.5, 1e-3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer runs (CI smoke run)")
    parser.add_argument("--baseline", help="the csfh package of another build (directory)")
    parser.add_argument("--pairs", type=int, default=5, help="with --baseline: pairs of runs")
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child is not None:
        print(json.dumps(batched_rates(args.child)))
        return
    n_me, n_cs, n_batch = (2, 5, 64) if args.quick else (5, 30, 1000)
    if args.baseline is not None:
        against(args.baseline, n_batch, args.pairs)
        return
    from csfh.batch.tasks import run_alone, run_chunk

    scene, _, tasks = _setup(n_batch)
    me = [replace(t, interface="me") for t in tasks[:n_me]]
    cs = tasks[:n_cs]
    print(
        f"Monte Carlo throughput, one core: {LAW}, {STOP:g} s of scene {scene.name} "
        f"(tolerance_csfh samples), rtol {scene.integrator.rtol:g}, grid {GRID:g} s"
    )
    rate_me = _best_rate(lambda: [run_chunk([t]) for t in me], n_me, repeats=1)
    rate_cs = _best_rate(lambda: [run_alone(t) for t in cs], n_cs)
    batched = batched_rates(n_batch)
    in_call, rate_e2e = float(batched["in_call"]), float(batched["end_to_end"])
    rows = [
        (f"per run, model exchange (fmpy CVode), {n_me} runs", rate_me),
        (f"per run, co-simulation (fmpy FMU2Slave), {n_cs} runs", rate_cs),
        (f"batched, inside the C call, {n_batch} runs", in_call),
        (f"batched, run_chunk (64 per chunk), {n_batch} runs", float(batched["run_chunk"])),
        (f"batched, run_tasks + result store, {n_batch} runs", rate_e2e),
    ]
    print(f"  {'path':<56} {'runs/s':>9} {'x ME':>8} {'x CS':>8}")
    for name, rate in rows:
        print(f"  {name:<56} {rate:9.1f} {rate / rate_me:8.1f} {rate / rate_cs:8.1f}")
    print(
        f"  target >= {TARGET_RATE:g} runs/s per core inside the call: "
        f"{'met' if in_call >= TARGET_RATE else 'NOT met'} ({in_call:.0f}); "
        f"end to end {'met' if rate_e2e >= TARGET_RATE else 'NOT met'} ({rate_e2e:.0f})"
    )
    for label, base in (("model-exchange", rate_me), ("co-simulation", rate_cs)):
        ratio = rate_e2e / base
        print(
            f"  target >= {TARGET_RATIO:g}x the {label} per-run path (end to end): "
            f"{'met' if ratio >= TARGET_RATIO else 'NOT met'} ({ratio:.0f}x)"
        )


if __name__ == "__main__":
    main()
