"""The FMU's event-driven integration (co-simulation: the integrator inside the FMU with its
default method, auto, which is the explicit Runge-Kutta 5(4) RK45 through flight and impacts;
contact onsets by root finding) against the paper's scheme (explicit RK4 with step bisection to
the event tolerance, in C with the same right-hand side), at equal error on the first three
contacts.

For each RK4 setting (the paper's h0 = 2e-4 s, 1e-4 m, and tighter ones) the error is the largest
contact-time error of the first three contacts against a reference (model exchange at rtol 1e-13).
The cheapest CS run (by RHS evaluations) with an error no larger is its match; the table gives
the ratios of RHS evaluations and of wall time. The contact-time error of a CS run does not fall
monotonically with rtol (each contact's error is a few steps' local errors, whose sum depends on
where the steps fall), so a match can be a lucky grid point: the last column gives the RHS ratio
of the steady match, the loosest rtol at which this and every tighter rtol of the grid meet the
error. The wall times are medians of repeats in which
RK4, the CS run from Python and the CS run from the compiled master take turns (the same machine
state for all three). Targets: >= 10x fewer RHS evaluations; wall time >= 10x from the C master
and >= 5x from Python.

CS wall time from Python is simulate_cs's stats["do_step_time"] on a 10 ms communication grid
(the FMU observed every 10 ms, to read the contact events): the time inside simulate_cs's
communication loop, which runs in C (csfh.runners.cs_steps: fmi2DoStep and the reads of the
outputs and contact events, all 42 steps in one ctypes call) and includes creating the
integrator at the first step of the fresh instance; RK4 runs entirely in C, in one call, writing
a record every 1e-4 s as the harness runs it. The matched CS run is timed
also in the compiled master (master/bench_cs_master.c, built as build/bench_cs_master; its loop
on a re-used instance after a warm-up run, reading the six states, the same 10 ms grid): the
wall time a C/C++ importer pays.

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
from csfh.runners.co_simulation import simulate_cs
from csfh.runners.model_exchange import simulate_me
from csfh.runners.rk4 import rk4_event
from csfh.studies.accuracy.metrics import contact_errors

RK4_SETTINGS = [(2e-4, 1e-4), (1e-4, 1e-5), (5e-5, 1e-6), (2.5e-5, 1e-7), (1.25e-5, 1e-8)]
CS_RTOLS = [
    1e-3,
    3e-4,
    1e-4,
    3e-5,
    1e-5,
    3e-6,
    1e-6,
    3e-7,
    1e-7,
    3e-8,
    1e-8,
    3e-9,
    1e-9,
    3e-10,
    1e-10,
]


def steady_match(
    cs_runs: list[tuple[float, float, int]], err: float
) -> tuple[float, float, int] | None:
    """The loosest run from which on every tighter rtol (cs_runs is loosest first) has an
    error no larger than err; None if the tightest does not."""
    match = None
    for run in reversed(cs_runs):
        if run[1] > err:
            break
        match = run
    return match


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
        f"{'RHS ratio':>9} {'wall ratio':>10} | {'C master':>9} {'wall ratio':>10} | "
        f"{'steady':>7} {'RHS ratio':>9}"
    )
    print(header)
    print("-" * len(header))
    for model in ("LN_spheres", "LN_cylinders", "LN_ESDU"):
        ref = simulate_me(scene, model, rtol=1e-13)
        cs_runs = []  # (rtol, error, RHS): deterministic, one run each
        for rtol in CS_RTOLS:
            tr = simulate_cs(scene, model, rtol=rtol, communication_step=1e-2)
            cs_runs.append(
                (rtol, contact_errors(tr, ref)["contact_time"], tr.stats["rhs_evaluations"])
            )
        for h0, tol in RK4_SETTINGS:
            tr = rk4_event(scene, model, h0=h0, tol=tol)
            err, rk4_rhs = contact_errors(tr, ref)["contact_time"], tr.stats["rhs_evaluations"]
            line = f"{model:<13} {f'{h0:g}, {tol:g}':<16} {err:9.2e} {rk4_rhs:8d} "
            ok = [c for c in cs_runs if c[1] <= err]
            if not ok:
                wall = statistics.median(
                    rk4_event(scene, model, h0=h0, tol=tol).stats["wall_time"]
                    for _ in range(args.repeats)
                )
                print(line + f"{wall:9.2e} | no CS run reaches this error")
                continue
            rtol, cerr, crhs = min(ok, key=lambda c: c[2])
            steady = steady_match(cs_runs, err)
            walls: dict[str, list[float]] = {"rk4": [], "cs": [], "c": []}
            for _ in range(args.repeats):  # in turns: the same machine state for all three
                walls["rk4"].append(rk4_event(scene, model, h0=h0, tol=tol).stats["wall_time"])
                walls["cs"].append(
                    simulate_cs(scene, model, rtol=rtol, communication_step=1e-2).stats[
                        "do_step_time"
                    ]
                )
                if master is not None:
                    walls["c"].append(
                        run_c_master(
                            master, scene, model, rtol=rtol, communication_step=1e-2, repeats=3
                        ).loop_seconds
                    )
            wall, cwall = statistics.median(walls["rk4"]), statistics.median(walls["cs"])
            c_wall = statistics.median(walls["c"]) if walls["c"] else math.nan
            print(
                line + f"{wall:9.2e} | {rtol:7.0e} {cerr:9.2e} {crhs:6d} {cwall:9.2e} | "
                f"{rk4_rhs / crhs:9.1f} {wall / cwall:10.2f} | "
                f"{c_wall:9.2e} {wall / c_wall:10.2f} | "
                + (f"{steady[0]:7.0e} {rk4_rhs / steady[2]:9.1f}" if steady else f"{'-':>7}")
            )
    print("\ntargets: RHS ratio >= 10; wall ratio >= 5 from Python, >= 10 from the C master")


if __name__ == "__main__":
    main()
