"""The FMU's event-driven integration (co-simulation: CVODE inside the FMU with its default
method, auto; contact onsets by root finding) against the paper's scheme (explicit RK4 with step
bisection to the event tolerance, in C with the same right-hand side), at equal error on the
first three contacts.

For each RK4 setting (the paper's h0 = 2e-4 s, 1e-4 m, and tighter ones) the error is the largest
contact-time error of the first three contacts against a reference (model exchange at rtol 1e-13).
The cheapest CS run (by RHS evaluations) with an error no larger is its match; the table gives
the ratios of RHS evaluations and of wall time (medians of repeats, in one run). Targets: >= 10x
fewer RHS evaluations and >= 10x less wall time.

CS wall time is the time spent in fmi2DoStep with the FMU observed every 10 ms (to read the
contact events), which includes creating CVODE at the first step; RK4 runs entirely in C. Each
fmi2DoStep from Python costs more than the same call from C (the ctypes call, and CVODE's code
and data are no longer in the caches after the interpreter's work between calls), so the matched
CS run is timed also in the compiled master (master/bench_cs_master.c, built as
build/bench_cs_master; its loop after a warm-up run, the same 10 ms grid): the wall time a C/C++
importer pays.

Run: python benchmarks/bench_event_vs_rk4.py [--scene central] [--repeats 7]
     [--master build/bench_cs_master]
"""

from __future__ import annotations

import argparse
import math
import statistics
from dataclasses import replace
from pathlib import Path

from c_master import default_master, run_c_master

from csfh import load_scene
from csfh.runners.fmu import simulate_cs, simulate_me
from csfh.runners.rk4 import rk4_event
from csfh.studies.accuracy.metrics import contact_errors

RK4_SETTINGS = [(2e-4, 1e-4), (1e-4, 1e-5), (5e-5, 1e-6), (2.5e-5, 1e-7), (1.25e-5, 1e-8)]
CS_RTOLS = [1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 1e-8, 1e-9, 1e-10]


def median_run(fn, repeats: int, wall_key: str):
    walls, tr = [], None
    for _ in range(repeats):
        tr = fn()
        walls.append(tr.stats[wall_key])
    return tr, statistics.median(walls)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="central")
    ap.add_argument("--horizon", type=float, default=0.42, help="s (first three contacts)")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument(
        "--master",
        type=Path,
        default=default_master(),
        help="the compiled master (cmake --build build builds build/bench_cs_master)",
    )
    args = ap.parse_args()
    master = args.master if args.master.is_file() else None
    if master is None:
        print(f"no compiled master at {args.master}: the C-master columns are left empty")
    scene = replace(load_scene(args.scene), stop_time=args.horizon)
    print(f"scene {scene.name}, horizon {args.horizon} s, medians of {args.repeats} runs\n")
    header = (
        f"{'model':<13} {'RK4 h0, tol':<16} {'error [s]':>9} {'RHS':>8} {'wall':>9} | "
        f"{'CS rtol':>7} {'error [s]':>9} {'RHS':>6} {'wall':>9} | "
        f"{'RHS ratio':>9} {'wall ratio':>10} | {'C master':>9} {'wall ratio':>10}"
    )
    print(header)
    print("-" * len(header))
    for model in ("LN_spheres", "LN_cylinders", "LN_ESDU"):
        ref = simulate_me(scene, model, rtol=1e-13)
        cs_runs = []
        for rtol in CS_RTOLS:
            tr, wall = median_run(
                lambda rtol=rtol, model=model: simulate_cs(
                    scene, model, rtol=rtol, communication_step=1e-2
                ),
                args.repeats,
                "do_step_time",
            )
            cs_runs.append(
                (rtol, contact_errors(tr, ref)["contact_time"], tr.stats["rhs_evaluations"], wall)
            )
        for h0, tol in RK4_SETTINGS:
            tr, wall = median_run(
                lambda h0=h0, tol=tol, model=model: rk4_event(scene, model, h0=h0, tol=tol),
                args.repeats,
                "wall_time",
            )
            err = contact_errors(tr, ref)["contact_time"]
            ok = [c for c in cs_runs if c[1] <= err]
            line = (
                f"{model:<13} {f'{h0:g}, {tol:g}':<16} {err:9.2e} "
                f"{tr.stats['rhs_evaluations']:8d} {wall:9.2e} | "
            )
            if ok:
                rtol, cerr, crhs, cwall = min(ok, key=lambda c: c[2])
                c_wall = math.nan
                if master is not None:
                    c_wall = run_c_master(
                        master,
                        scene,
                        model,
                        rtol=rtol,
                        communication_step=1e-2,
                        repeats=args.repeats,
                    ).loop_seconds
                line += (
                    f"{rtol:7.0e} {cerr:9.2e} {crhs:6d} {cwall:9.2e} | "
                    f"{tr.stats['rhs_evaluations'] / crhs:9.1f} {wall / cwall:10.2f} | "
                    f"{c_wall:9.2e} {wall / c_wall:10.2f}"
                )
            else:
                line += "no CS run reaches this error"
            print(line)
    print("\ntargets: RHS ratio >= 10 and wall ratio >= 10")


if __name__ == "__main__":
    main()
