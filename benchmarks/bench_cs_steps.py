"""The co-simulation integrator's work per step: this FMU binary against another build of it (the
baseline, e.g. the main branch's), in the compiled master, on the first three contacts of the
`central` scene for the three event-driven laws (method auto: RK45 through flight and impacts).

Each round runs the compiled master (master/bench_cs_master.c, built as build/bench_cs_master)
once with each binary, in turns (the same machine state for both); a run is `--repeats` runs of
the scene on one re-used instance, timed as the median of its repeats. The table gives the
medians over the rounds and the ratio baseline / this binary (> 1: this binary is faster), and
whether both binaries end in bitwise the same state (the six states, printed to 17 digits) with
the same counts; the integrator steps and right-hand sides of one run.

With --perf (needs `perf`): the top entries of a `perf record` profile of each binary for each
law (self time, the share of all samples of that master process; the master's parsing of the
start values before each run, e.g. __vfscanf_internal, is among them, outside the timed loop).

Build the baseline from another checkout, e.g.
    git worktree add --detach /tmp/csfh-main main
    cmake -S /tmp/csfh-main -B /tmp/csfh-main/build -G Ninja -DCSFH_PLATFORMS=host
    cmake --build /tmp/csfh-main/build
    (binary: /tmp/csfh-main/build/binaries/csfh/linux64/csfh.so)

Run: python benchmarks/bench_cs_steps.py --baseline PATH [--binary PATH] [--rounds 21]
     [--repeats 301] [--rtol 1e-6 1e-9] [--laws LN_spheres ...] [--perf]
     [--master build/bench_cs_master]
"""

from __future__ import annotations

import argparse
import math
import shutil
import statistics
import subprocess
import tempfile
from pathlib import Path

from c_master import (
    add_build_comparison_arguments,
    compared_builds,
    master_command,
    run_c_master,
)

from csfh.model.scene import Scene

# read at the end of a run (the counters restart with fmi2Reset): contacts, steps, RHS
COUNTS = ("contact.count", "diagnostics.integrator_steps", "diagnostics.rhs_evaluations")


def timed_rounds(
    master: Path,
    binaries: dict[str, Path],
    scene: Scene,
    law: str,
    rtol: float,
    rounds: int,
    repeats: int,
) -> tuple[dict[str, list[float]], bool, list[int]]:
    """Loop times of each binary, in turns; whether their final states and counts (COUNTS) are
    bitwise equal; the counts of the last binary."""
    walls: dict[str, list[float]] = {name: [] for name in binaries}
    finals: dict[str, list[float]] = {}
    counts: dict[str, list[int]] = {}
    for _ in range(rounds):
        for name, binary in binaries.items():
            run = run_c_master(
                master,
                scene,
                law,
                rtol=rtol,
                communication_step=1e-2,
                repeats=repeats,
                count=COUNTS,
                binary=binary,
            )
            walls[name].append(run.loop_seconds)
            finals[name] = run.final
            counts[name] = run.counts
    first, second = finals.values()
    same = [x.hex() for x in first] == [x.hex() for x in second]
    base_counts, this_counts = counts.values()
    return walls, same and base_counts == this_counts, this_counts


def perf_top(master: Path, binary: Path, scene: Scene, law: str, rtol: float, n: int) -> list[str]:
    """The top n self-time entries of a perf profile of the master on `binary`."""
    command = master_command(
        master, scene, law, rtol=rtol, communication_step=1e-2, repeats=20001, binary=binary
    )
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "perf.data"
        subprocess.run(
            ["perf", "record", "-q", "-o", str(data), "--", *command],
            check=True,
            capture_output=True,
        )
        report = subprocess.run(
            ["perf", "report", "-i", str(data), "--no-children", "--sort", "symbol", "--stdio"],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
    rows = [line.split() for line in report.splitlines() if line.strip()[:1].isdigit()]
    return [f"{row[0]:>7} {row[2]}" for row in rows[:n] if len(row) > 2]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_build_comparison_arguments(ap)
    ap.add_argument("--rounds", type=int, default=21)
    ap.add_argument("--repeats", type=int, default=301, help="runs of the scene per master run")
    ap.add_argument("--rtol", type=float, nargs="+", default=[1e-6, 1e-9])
    ap.add_argument("--perf", action="store_true", help="also the perf profiles' top entries")
    args = ap.parse_args()
    binaries, scene = compared_builds(args)
    print(
        f"scene {scene.name}, horizon {args.horizon} s, 10 ms grid, method auto; medians of "
        f"{args.rounds} rounds in turns, each the median of {args.repeats} runs\n"
    )
    header = (
        f"{'model':<13} {'rtol':>6} | {'baseline [us]':>13} {'this [us]':>10} | "
        f"{'ratio':>6} | {'bitwise':>7} | {'steps':>5} {'RHS':>5}"
    )
    print(header)
    print("-" * len(header))
    for law in args.laws:
        for rtol in args.rtol:
            walls, same, counts = timed_rounds(
                args.master, binaries, scene, law, rtol, args.rounds, args.repeats
            )
            base, this = (statistics.median(walls[k]) for k in ("baseline", "this"))
            ratio = base / this if this > 0 else math.nan
            print(
                f"{law:<13} {rtol:6.0e} | {1e6 * base:13.2f} {1e6 * this:10.2f} | "
                f"{ratio:6.3f} | {'yes' if same else 'NO':>7} | {counts[1]:5d} {counts[2]:5d}"
            )
    if args.perf:
        if shutil.which("perf") is None:
            print("\nno perf: no profiles")
            return
        for law in args.laws:
            for name, binary in binaries.items():
                print(f"\nperf, {law}, rtol {args.rtol[0]:g}, {name}: self time, top entries")
                for line in perf_top(args.master, binary, scene, law, args.rtol[0], 12):
                    print("  " + line)


if __name__ == "__main__":
    main()
