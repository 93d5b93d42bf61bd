"""Event-driven Monte Carlo throughput: the batch co-simulation master against today's per-run
path, side by side in one run, one core (everything serial in this process).

The runs are those of `csfh tolerance tolerance_csfh`: 0.5 s of the `csfh` scene (its flexure,
friction and the first six impacts), LN_cylinders, rtol 1e-6, communication grid 1 ms, each run
a different sample of the file's tolerances (contact radii, flexure height, radius, opening).

* per run, model exchange: `csfh.batch.tasks.run_chunk` on one task at a time with interface "me"
  (the default of `csfh tolerance` and `csfh sweep`): fmpy's CVode stepped from Python.
* per run, co-simulation: the per-run function of the task system (`csfh.batch.tasks._run_fmu`)
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

Run: python benchmarks/bench_cs_batch.py [--quick]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

TARGET_RATIO = 100.0
TARGET_RATE = 300.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer runs (CI smoke run)")
    args = parser.parse_args()
    from csfh.batch.executors import run_tasks
    from csfh.batch.store import ResultStore
    from csfh.batch.tasks import Task, _run_fmu, run_chunk
    from csfh.runners.cs_batch import cs_batch
    from csfh.studies.tolerance.study import load_study, sample

    study = load_study("tolerance_csfh")
    scene, stop, grid, law = study.scene, 0.5, 1e-3, "LN_cylinders"
    n_me, n_cs, n_batch = (2, 5, 64) if args.quick else (5, 30, 1000)
    samples = [sample(study, k) for k in range(n_batch)]

    def tasks(interface: str, n: int, offset: int = 0) -> list[Task]:
        return [
            Task(
                scene=scene,
                model=law,
                parameters=tuple(sorted(s.items())),
                stop_time=stop,
                output_interval=grid,
                interface=interface,
                signals=False,
            )
            for s in samples[offset : offset + n]
        ]

    def best_rate(fn, n: int, repeats: int = 3) -> float:
        best = 0.0
        for _ in range(repeats):
            t0 = time.perf_counter()
            fn()
            best = max(best, n / (time.perf_counter() - t0))
        return best

    print(
        f"Monte Carlo throughput, one core: {law}, {stop:g} s of scene {scene.name} "
        f"(tolerance_csfh samples), rtol {scene.integrator.rtol:g}, grid {grid:g} s"
    )
    me = tasks("me", n_me)
    cs = tasks("cs", n_cs)
    rate_me = best_rate(lambda: [run_chunk([t]) for t in me], n_me, repeats=1)
    rate_cs = best_rate(lambda: [_run_fmu(t) for t in cs], n_cs)
    # warm: load the batch library and unzip the FMU once (as any long study does)
    cs_batch(scene, law, samples[:2], stop_time=stop, communication_step=grid)
    in_call = 0.0
    for _ in range(3):
        b = cs_batch(scene, law, samples, stop_time=stop, communication_step=grid)
        in_call = max(in_call, n_batch / b.wall_time)
    batched = tasks("cs", n_batch)
    chunks = [batched[i : i + 64] for i in range(0, n_batch, 64)]
    rate_chunks = best_rate(lambda: [run_chunk(c) for c in chunks], n_batch)

    def end_to_end() -> None:
        with tempfile.TemporaryDirectory() as tmp:
            run_tasks(batched, ResultStore(Path(tmp)), workers=1, quiet=True)

    rate_e2e = best_rate(end_to_end, n_batch)
    rows = [
        (f"per run, model exchange (fmpy CVode), {n_me} runs", rate_me),
        (f"per run, co-simulation (fmpy FMU2Slave), {n_cs} runs", rate_cs),
        (f"batched, inside the C call, {n_batch} runs", in_call),
        (f"batched, run_chunk (64 per chunk), {n_batch} runs", rate_chunks),
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
