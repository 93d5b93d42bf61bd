"""Sweep throughput: the batched Moreau stepper (variant-steps per second, target >= 1e7 on this
machine) and the event-driven runs of a sweep (runs per second), serial and on all cores.

* C batch, one core: one call of csfh_api_moreau_batch with 64 parameter sets of the `csfh`
  scene, 1 s each at h = 1e-5 s (6.4 million variant-steps), outputs decimated to 1 ms; timed
  inside the call, and with the Python set-up of the 64 models.
* All cores: the same batch in every worker process at once (pool started beforehand), timed
  from submission to the last result.
* End to end: `run_tasks` on Moreau tasks (the Monte Carlo kind: scalars only), local
  processes, with the result store; and event-driven sweep runs (LN_cylinders, 1 s each)
  serial and on all cores.

Run: python benchmarks/bench_sweep.py [--quick]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

TARGET = 1e7


def _batch(n: int, stop_time: float) -> tuple[int, float, float]:
    """One batch of n variants (body mass spread): (variant-steps, in-call s, total s)."""
    from csfh import load_scene
    from csfh.runners.moreau_batch import moreau_batch

    scene = load_scene("csfh")
    sets = [{"body1.m": 10.0 + 1e-3 * i} for i in range(n)]
    t0 = time.perf_counter()
    result = moreau_batch(scene, sets, stop_time=stop_time, output_interval=1e-3)
    return result.steps, result.wall_time, time.perf_counter() - t0


def _warm(_: int) -> int:
    import csfh.runners.moreau_batch  # noqa: F401  (import and load the core library once)

    return 0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller batches (CI smoke run)")
    args = parser.parse_args()
    from csfh import load_scene
    from csfh.batch.executors import default_workers, run_tasks
    from csfh.batch.store import ResultStore
    from csfh.batch.tasks import Task

    n, stop = (16, 0.25) if args.quick else (64, 1.0)
    workers = default_workers()
    print(f"Sweep throughput on {workers} cores (scene csfh, h = 1e-5 s)")

    runs = [_batch(n, stop) for _ in range(3)]
    steps = runs[0][0]
    in_call = statistics.median(r[1] for r in runs)
    total = statistics.median(r[2] for r in runs)
    print(f"  C batch, 1 core: {n} variants x {steps // n} steps")
    print(f"    inside the call           {steps / in_call:14,.0f} variant-steps/s")
    print(f"    with the Python set-up    {steps / total:14,.0f} variant-steps/s")

    with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as pool:
        list(pool.map(_warm, range(workers)))
        best = 0.0
        for _ in range(3):
            t0 = time.perf_counter()
            results = list(pool.map(_batch, [n] * workers, [stop] * workers))
            wall = time.perf_counter() - t0
            best = max(best, sum(r[0] for r in results) / wall)
    verdict = "met" if best >= TARGET else "NOT met"
    print(f"  C batch, {workers} processes at once")
    print(f"    aggregate                 {best:14,.0f} variant-steps/s   target >= 1e7: {verdict}")

    scene = load_scene("csfh")
    n_tasks = 4 * n * workers
    tasks = [
        Task(
            scene=scene,
            model="Moreau",
            parameters=(("body1.m", 10.0 + 1e-4 * i),),
            stop_time=stop,
            output_interval=1e-3,
            signals=False,
        )
        for i in range(n_tasks)
    ]
    with tempfile.TemporaryDirectory() as tmp:
        report = run_tasks(tasks, ResultStore(Path(tmp)), workers=workers, quiet=True)
    vs = n_tasks * round(stop / 1e-5) / report.wall_time
    print(f"  run_tasks, {n_tasks} Moreau tasks, {report.executor} (incl. start-up, store)")
    print(f"    end to end                {vs:14,.0f} variant-steps/s   ({report.wall_time:.2f} s)")

    n_fmu = 2 * workers if args.quick else 24 * workers
    fmu_tasks = [
        Task(
            scene=scene,
            model="LN_cylinders",
            parameters=(("body1.m", 10.0 + 1e-3 * i),),
            stop_time=stop,
            output_interval=1e-4,
        )
        for i in range(n_fmu)
    ]
    with tempfile.TemporaryDirectory() as tmp:
        serial = run_tasks(
            fmu_tasks[: max(2, n_fmu // 6)], ResultStore(Path(tmp)), workers=1, quiet=True
        )
    with tempfile.TemporaryDirectory() as tmp:
        par = run_tasks(fmu_tasks, ResultStore(Path(tmp)), workers=workers, quiet=True)
    print(f"  event-driven runs (LN_cylinders, model exchange, {stop:g} s simulated each)")
    print(f"    serial                    {serial.computed / serial.wall_time:14.2f} runs/s")
    print(
        f"    {workers} processes               {par.computed / par.wall_time:14.2f} runs/s "
        "(incl. start-up)"
    )


if __name__ == "__main__":
    main()
