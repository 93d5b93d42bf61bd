"""Moreau stepper throughput: 1 s of the `csfh` scene at h = 1e-5 s (100 000 steps), in the C core
through ctypes, against the targets of >= 200 000 steps/s and <= 0.5 s for the run.

The ratio column compares, in the same run, the stepper with free flight only (law-independent
minimum work per step: gravity and the flexure) to show what the contact handling costs.

Run: python benchmarks/bench_moreau.py
"""

from __future__ import annotations

import statistics
import time

from csfh import load_scene, moreau


def timed(scene, repeats: int = 7, **kw) -> tuple[float, dict]:
    times = []
    tr = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        tr = moreau(scene, **kw)
        times.append(time.perf_counter() - t0)
    return statistics.median(times), tr.stats


def main() -> None:
    scene = load_scene("csfh")
    wall, stats = timed(scene, h=1e-5)
    steps = stats["steps"]
    free = scene.with_parameters(**{"contact.R2": 10.0})  # clearance 9.8 m: never touches
    wall_free, _ = timed(free, h=1e-5)
    print("Moreau midpoint stepper, scene csfh, h = 1e-5 s, stop time 1 s (median of 7)")
    print(f"  steps                       {steps}")
    print(f"  active contact steps        {stats['active_steps']}")
    print(
        f"  wall time (incl. Python)    {wall:.4f} s      target <= 0.5 s: "
        f"{'met' if wall <= 0.5 else 'NOT met'}"
    )
    print(
        f"  throughput                  {steps / wall:,.0f} steps/s   target >= 200,000: "
        f"{'met' if steps / wall >= 2e5 else 'NOT met'}"
    )
    print(f"  same run without contacts   {wall_free:.4f} s   (ratio {wall / wall_free:.2f})")


if __name__ == "__main__":
    main()
