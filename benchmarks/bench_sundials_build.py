"""Our build of SUNDIALS (cmake/sundials.cmake: Debian's source package of 6.4.1 compiled with -O2
or better, static, in the FMU binary) against Debian's libsundials-dev (compiled without
optimisation), on the co-simulation loop of the compiled master (benchmarks/master/
bench_cs_master.c): the same FMU sources, the same scene, the same master, one run.

Variants (FMU binaries):
  debian   build/bench/debian_sundials/csfh.so: the FMU linked with Debian's libcvode.a
  ours     build/binaries/csfh/linux64/csfh.so: the host compiler (gcc) with our SUNDIALS
  shipped  binaries/linux64/csfh.so of build/csfh.fmu: what the FMU carries (zig, glibc 2.17,
           with our SUNDIALS, when built with CSFH_PLATFORMS=all)
Each row: 1 s of the scene with contact law LN_spheres, relative tolerance 1e-6, communication
step 1e-3 s, each solver.method; loop time = median over rounds of the master's median of
REPEATS loops, the variants interleaved round by round. "max diff" is the largest difference of
the final states against the debian variant, relative to each state's scale (0 = bitwise).

Run: python benchmarks/bench_sundials_build.py [--repeats 11] [--rounds 3]
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
from pathlib import Path

import c_master
from c_master import default_master, run_c_master

from csfh import load_scene

ROOT = Path(__file__).resolve().parents[1]
METHODS = {"auto": 1, "BDF": 2, "Adams": 3}  # solver.method
SCALES = (0.01, 0.01, 0.1, 0.1, 0.1, 1.0)  # x, y, theta, vx, vy, omega


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=11)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--master", type=Path, default=default_master())
    args = ap.parse_args()
    variants = {
        "debian": ROOT / "build" / "bench" / "debian_sundials" / "csfh.so",
        "ours": ROOT / "build" / "binaries" / "csfh" / "linux64" / "csfh.so",
        "shipped": Path(c_master._binary()),
    }
    for name, path in variants.items():
        if not path.is_file():
            raise SystemExit(f"bench_sundials_build: {name} binary {path} not built")
    print(
        "| scene | method | debian (ms) | ours (ms) | shipped (ms) | debian/ours "
        "| debian/shipped | contacts | max diff ours, shipped |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for scene_name in ("csfh", "central"):
        scene = dataclasses.replace(load_scene(scene_name), stop_time=1.0)
        for method, value in METHODS.items():
            times: dict[str, list[float]] = {k: [] for k in variants}
            finals: dict[str, list[float]] = {}
            counts: dict[str, list[int]] = {}
            for _ in range(args.rounds):
                for name, path in variants.items():
                    run = run_c_master(
                        args.master,
                        scene,
                        "LN_spheres",
                        rtol=1e-6,
                        communication_step=1e-3,
                        repeats=args.repeats,
                        extra={"solver.method": value},
                        binary=path,
                    )
                    times[name].append(run.loop_seconds)
                    finals[name], counts[name] = run.final, run.counts
            t = {k: statistics.median(v) for k, v in times.items()}
            diffs = [
                max(
                    abs(a - b) / s
                    for a, b, s in zip(finals[k], finals["debian"], SCALES, strict=True)
                )
                for k in ("ours", "shipped")
            ]
            same = counts["ours"] == counts["shipped"] == counts["debian"]
            print(
                f"| {scene_name} | {method} | {1e3 * t['debian']:.2f} | {1e3 * t['ours']:.2f} "
                f"| {1e3 * t['shipped']:.2f} | {t['debian'] / t['ours']:.2f}x "
                f"| {t['debian'] / t['shipped']:.2f}x "
                f"| {counts['debian'][0]}{'' if same else ' (differ!)'} "
                f"| {diffs[0]:.1e}, {diffs[1]:.1e} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
