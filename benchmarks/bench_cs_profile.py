"""The co-simulation's work per integrator step, counted: event-indicator evaluations, right-hand
sides and instructions per step of this FMU binary against another build (the baseline, e.g. the
main branch's), in the compiled master, on the first three contacts of the `central` scene for
the three event-driven laws (method auto: RK45 through flight and impacts), with wall times.

Counts come from valgrind's callgrind (exact and independent of the machine's load): the calls
of the integrator's root and right-hand-side callbacks (`roots`, `rhs` in
fmu_src/fmu/cosim/integration.c) and the instructions executed, of one run of the scene: the
master with two runs minus the master with one (the warm-up run and the start-up cancel). Steps
are the integrator's (diagnostics.integrator_steps). Wall times: medians of `--rounds` rounds in
which the two binaries take turns (each the median of `--repeats` runs on one re-used instance).
Ratios are baseline / this (> 1: this binary does less).

Run: python benchmarks/bench_cs_profile.py --baseline OTHER/csfh.so [--binary PATH]
     [--rtol 1e-4 1e-6] [--rounds 11] [--repeats 201] [--master build/bench_cs_master]
(rtol 1e-6 puts the contact times of the first three contacts within ~2e-6 s: docs/benchmarks.md)
"""

from __future__ import annotations

import argparse
import re
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

CALLBACKS = ("roots", "rhs")
FN = re.compile(r"^(c?fn)=\((\d+)\)(?: (.*))?$")


def callgrind_counts(command: list[str]) -> dict[str, int]:
    """Calls of CALLBACKS and the instructions (Ir) of one callgrind run of `command`."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "callgrind.out"
        subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", *command],
            check=True,
            capture_output=True,
        )
        names: dict[str, str] = {}
        counts = dict.fromkeys(CALLBACKS, 0)
        callee = None
        for line in out.read_text().splitlines():
            m = FN.match(line)
            if m:
                kind, ident, name = m.groups()
                if name:
                    names[ident] = name
                if kind == "cfn":
                    callee = names.get(ident, "").split(".")[0]
                continue
            if line.startswith("calls=") and callee in counts:
                counts[callee] += int(line.split()[0][6:])
            elif line.startswith("summary:"):
                counts["Ir"] = int(line.split()[1])
    return counts


def one_run(master: Path, binary: Path, scene: Scene, law: str, rtol: float) -> dict[str, int]:
    """The counts of one run of the scene (two runs minus one)."""
    two, one = (
        callgrind_counts(
            master_command(
                master, scene, law, rtol=rtol, communication_step=1e-2, repeats=n, binary=binary
            )
        )
        for n in (2, 1)
    )
    if not all(two[k] > 0 for k in CALLBACKS):
        # callgrind names the callbacks from the binary's symbols, which a stripped build lacks
        raise SystemExit(
            f"bench_cs_profile: no calls of {' or '.join(CALLBACKS)} seen in {binary}: a "
            "binary without symbols (the installed FMU's after tools/test.sh is the stripped "
            "cross build); pass --binary build/binaries/csfh/linux64/csfh.so"
        )
    return {k: two[k] - one[k] for k in two}


def walls(
    master: Path,
    binaries: dict[str, Path],
    scene: Scene,
    law: str,
    rtol: float,
    args: argparse.Namespace,
) -> tuple[dict[str, float], dict[str, int]]:
    """Median loop times of each binary (in turns) and their integrator steps per run."""
    times: dict[str, list[float]] = {name: [] for name in binaries}
    steps: dict[str, int] = {}
    for _ in range(args.rounds):
        for name, binary in binaries.items():
            run = run_c_master(
                master,
                scene,
                law,
                rtol=rtol,
                communication_step=1e-2,
                repeats=args.repeats,
                count=("diagnostics.integrator_steps",),
                binary=binary,
            )
            times[name].append(run.loop_seconds)
            steps[name] = run.counts[0]
    return {k: statistics.median(v) for k, v in times.items()}, steps


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_build_comparison_arguments(ap)
    ap.add_argument("--rtol", type=float, nargs="+", default=[1e-4, 1e-6])
    ap.add_argument("--rounds", type=int, default=11)
    ap.add_argument("--repeats", type=int, default=201)
    args = ap.parse_args()
    binaries, scene = compared_builds(args)
    print(
        f"scene {scene.name}, horizon {args.horizon} s, 10 ms grid, method auto; per run; "
        f"ratio = baseline / this; wall: medians of {args.rounds} rounds in turns\n"
    )
    header = (
        f"{'model':<13} {'rtol':>6} | {'steps':>9} | {'g evals':>9} {'ratio':>5} | "
        f"{'RHS':>9} {'ratio':>5} | {'Ir/step':>13} {'ratio':>5} | {'wall/step [ns]':>15} "
        f"{'ratio':>5}"
    )
    print(header)
    print("-" * len(header))
    for law in args.laws:
        for rtol in args.rtol:
            c = {k: one_run(args.master, b, scene, law, rtol) for k, b in binaries.items()}
            wall, steps = walls(args.master, binaries, scene, law, rtol, args)
            base, this = c["baseline"], c["this"]
            ir = {k: c[k]["Ir"] / steps[k] for k in c}
            ws = {k: 1e9 * wall[k] / steps[k] for k in c}
            print(
                f"{law:<13} {rtol:6.0e} | {steps['baseline']:>4}/{steps['this']:<4} | "
                f"{base['roots']:>4}/{this['roots']:<4} {base['roots'] / this['roots']:5.2f} | "
                f"{base['rhs']:>4}/{this['rhs']:<4} {base['rhs'] / this['rhs']:5.2f} | "
                f"{ir['baseline']:6.0f}/{ir['this']:<6.0f} {ir['baseline'] / ir['this']:5.2f} | "
                f"{ws['baseline']:7.0f}/{ws['this']:<7.0f} {ws['baseline'] / ws['this']:5.2f}"
            )


if __name__ == "__main__":
    main()
