"""Co-simulation (the integrator inside the FMU, fmi2DoStep) against model exchange (fmpy's CVode
driving the same FMU through Python callbacks) on 1 s of the `csfh` scene: same FMU, same contact
law (LN_spheres), same relative tolerance, same output grid; every ratio is measured in one run
(medians of repeats, the variants interleaved). Target: CS >= 10x faster.

A. Complete runs with the harness drivers (instantiate, set the scene, simulate, free):
   ME: csfh.runners.model_exchange.simulate_me (one CVode step at a time, dense output onto the
       grid)
   CS: csfh.runners.co_simulation.simulate_cs (one fmi2DoStep per grid point, the loop in C)
   and fmpy's own two drivers, fmpy.simulate_fmu with fmi_type ModelExchange / CoSimulation.
B. The simulation loop alone, after initialization (what differs between the interfaces; the
   FMU loading and the parameter setting cost the same in both): fmpy's CVodeSolver stepping the
   model-exchange instance from grid point to grid point with event iteration (the loop of
   fmpy.simulate_fmu), against fmi2DoStep from grid point to grid point, with each of the FMU's
   co-simulation methods (solver.method: auto, the default, RK45 while not stiff and BDF where
   stiff; BDF, as fmpy's CVode; Adams; RK45 alone). Both
   read the six states at every grid point, ME with a direct fmi2GetReal call
   (benchmarks/direct_calls.py, ~1 us per call). The CS loop runs as csfh.simulate_cs runs it:
   in C, a chunk of communication steps per ctypes call (csfh.runners.cs_steps), here on the
   instance fmpy created. The column "auto, Python loop" is the CS loop in Python with one
   direct ctypes call per fmi2DoStep and per read (~1 us per call); "auto, fmpy calls"
   the same through fmpy's FMU2Slave methods, whose Python cost per call (~6-9 us) dominates on
   a fine grid; the column "auto, C master" is
   the same loop in a compiled master (benchmarks/master/bench_cs_master.c, built as
   build/bench_cs_master), as a C/C++ importer runs the FMU: no Python per communication point.
   Beside the times, the error of the first three contact times against model exchange at rtol
   1e-12 (same tolerance need not mean same error).

Run: python benchmarks/bench_cosim.py [--repeats 5] [--rtol 1e-6 1e-8] [--grid 1e-2 1e-3 1e-4]
     [--master build/bench_cs_master]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import c_master
import fmpy
import numpy as np
from c_master import default_master, run_c_master
from direct_calls import DirectCalls

from csfh import load_scene
from csfh.model import model_info
from csfh.model.scene import Scene
from csfh.runners.co_simulation import chunk_size, simulate_cs
from csfh.runners.cs_steps import CSteps
from csfh.runners.fmu import STATE_NAMES
from csfh.runners.model_exchange import simulate_me

LAW = "LN_spheres"
METHODS = {"auto": 1, "BDF": 2, "Adams": 3, "RK45": 4}  # solver.method (enumeration SolverMethod)


def interleaved(variants: dict[str, Callable[[], Any]], repeats: int) -> dict[str, float]:
    """Median wall time of each variant, the variants run in turn (same machine state)."""
    times: dict[str, list[float]] = {k: [] for k in variants}
    for _ in range(repeats):
        for name, fn in variants.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {k: statistics.median(v) for k, v in times.items()}


def start_values(scene: Scene) -> dict[str, Any]:
    return c_master.start_values(scene, LAW)


def _setup(fmu: Any, scene: Scene, rtol: float, extra: dict[str, Any] | None = None) -> None:
    variables = model_info.variables()
    fmu.setupExperiment(tolerance=rtol, startTime=0.0, stopTime=scene.stop_time)
    fmu.enterInitializationMode()
    for name, value in {**start_values(scene), **(extra or {})}.items():
        ref, kind = variables[name].valueReference, variables[name].type
        if kind == "Real":
            fmu.setReal([ref], [float(value)])
        elif kind == "Boolean":
            fmu.setBoolean([ref], [bool(value)])
        else:
            fmu.setInteger([ref], [int(value)])
    fmu.exitInitializationMode()


class Loops:
    """One model-exchange and one co-simulation instance, re-initialized (fmi2Reset) for every
    run; only the simulation loop is timed."""

    def __init__(self, scene: Scene) -> None:
        from fmpy.fmi2 import FMU2Model, FMU2Slave

        from csfh.paths import fmu_path

        md = model_info.model_description()
        directory = fmpy.extract(str(fmu_path()))
        self.scene = scene
        self.refs = [model_info.variables()[n].valueReference for n in STATE_NAMES]
        self.count = model_info.variables()["contact.count"].valueReference
        kw = {"guid": md.guid, "unzipDirectory": directory, "modelIdentifier": "csfh"}
        self.me = FMU2Model(instanceName="me", **kw)
        self.cs = FMU2Slave(instanceName="cs", **kw)
        self.me.instantiate()
        self.cs.instantiate()

    def run_me(self, rtol: float, dt: float) -> tuple[float, int]:
        from fmpy.sundials import CVodeSolver

        me = self.me
        me.reset()
        _setup(me, self.scene, rtol)
        while me.newDiscreteStates()[0]:
            pass
        me.enterContinuousTimeMode()

        class NoInput:
            def apply(self, t: float, **_: Any) -> None:
                return None

        solver = CVodeSolver(
            nx=6,
            nz=1,
            get_x=me.getContinuousStates,
            set_x=me.setContinuousStates,
            get_dx=me.getDerivatives,
            get_z=me.getEventIndicators,
            get_nominals=me.getNominalsOfContinuousStates,
            set_time=me.setTime,
            input=NoInput(),
            startTime=0.0,
            relativeTolerance=rtol,
            maxNumSteps=100000,
        )
        n = round(self.scene.stop_time / dt)
        read_states = DirectCalls(me).real_reader(self.refs)
        t0 = time.perf_counter()
        t, k = 0.0, 1
        while k <= n:
            t_next = k * dt
            event, _, t = solver.step(t, t_next)
            me.setTime(t)
            if event:
                me.enterEventMode()
                while me.newDiscreteStates()[0]:
                    pass
                me.enterContinuousTimeMode()
                solver.reset(t)
            if t >= t_next * (1 - 1e-12):
                read_states()
                k += 1
        wall = time.perf_counter() - t0
        contacts = me.getInteger([self.count])[0]
        del solver
        me.terminate()
        return wall, contacts

    def run_cs(self, rtol: float, dt: float, method: int = 1, loop: str = "c") -> tuple[float, int]:
        """The CS loop reading the six states at every grid point: loop "c" as simulate_cs runs
        it (csfh.runners.cs_steps: in C, a chunk of steps per ctypes call), "python" (one direct
        ctypes call per fmi2DoStep and per read), "fmpy" (fmpy's FMU2Slave methods)."""
        cs = self.cs
        cs.reset()
        _setup(cs, self.scene, rtol, {"solver.method": method})
        n = round(self.scene.stop_time / dt)
        direct = DirectCalls(cs)
        do_step, read_states = direct.do_step, direct.real_reader(self.refs)
        steps = CSteps(direct, dt, self.scene.stop_time, self.refs)
        size = chunk_size(n)
        t0 = time.perf_counter()
        if loop == "fmpy":
            for k in range(n):
                cs.doStep(k * dt, dt)
                cs.getReal(self.refs)
        elif loop == "python":
            for k in range(n):
                do_step(k * dt, dt)
                read_states()
        else:
            t = 0.0
            for k in range(0, n, size):
                t = float(steps.run(k, min(k + size, n), t).times[-1])
        wall = time.perf_counter() - t0
        contacts = cs.getInteger([self.count])[0]
        cs.terminate()
        return wall, contacts

    def run_c_master(self, master: Path, rtol: float, dt: float, repeats: int) -> tuple[float, int]:
        """The same CS loop (method auto) from the compiled master: median loop time."""
        run = run_c_master(
            master,
            self.scene,
            LAW,
            rtol=rtol,
            communication_step=dt,
            repeats=repeats,
            extra={"solver.method": METHODS["auto"]},
        )
        return run.loop_seconds, run.counts[0]

    def free(self) -> None:
        self.me.freeInstance()
        self.cs.freeInstance()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--rtol", type=float, nargs="+", default=[1e-6, 1e-8])
    ap.add_argument("--grid", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
    ap.add_argument(
        "--master",
        type=Path,
        default=default_master(),
        help="the compiled master (cmake --build build builds build/bench_cs_master)",
    )
    args = ap.parse_args()
    master = args.master if args.master.is_file() else None
    scene = load_scene("csfh")
    path = str(__import__("csfh").fmu_path())
    print(
        f"scene csfh, {scene.stop_time:g} s, law {LAW}; wall times in ms, median of "
        f"{args.repeats}; ratio = ME / CS"
    )

    print("\nA. complete runs (instantiate .. free)")
    print(
        f"  {'rtol':>6} {'grid [s]':>8} | {'simulate_me':>11} {'simulate_cs':>11} {'ratio':>6} "
        f"| {'fmpy ME':>8} {'fmpy CS':>8} {'ratio':>6} | CS vs fmpy ME"
    )
    for rtol in args.rtol:
        for dt in args.grid:
            fmpy_kw = {
                "stop_time": scene.stop_time,
                "relative_tolerance": rtol,
                "output_interval": dt,
                "start_values": start_values(scene),
                "output": ["body1.y"],
            }
            t = interleaved(
                {
                    "me": lambda r=rtol, d=dt: simulate_me(scene, LAW, rtol=r, output_interval=d),
                    "cs": lambda r=rtol, d=dt: simulate_cs(
                        scene, LAW, rtol=r, communication_step=d
                    ),
                    "fme": lambda kw=fmpy_kw: fmpy.simulate_fmu(
                        path, fmi_type="ModelExchange", **kw
                    ),
                    "fcs": lambda kw=fmpy_kw: fmpy.simulate_fmu(
                        path, fmi_type="CoSimulation", **kw
                    ),
                },
                args.repeats,
            )
            print(
                f"  {rtol:6.0e} {dt:8.0e} | {1e3 * t['me']:11.1f} {1e3 * t['cs']:11.1f} "
                f"{t['me'] / t['cs']:5.1f}x | {1e3 * t['fme']:8.1f} {1e3 * t['fcs']:8.1f} "
                f"{t['fme'] / t['fcs']:5.1f}x | {t['fme'] / t['cs']:5.1f}x"
            )

    print("\nB. the simulation loop alone (after initialization, same instances re-used)")
    print("   first-3-contact-time error [s] against ME at rtol 1e-12 in brackets")
    print(
        f"  {'rtol':>6} {'grid [s]':>8} | {'ME (fmpy CVode)':>24} | "
        + " | ".join(f"{'CS ' + m:>24} {'ratio':>6}" for m in METHODS)
        + f" | {'auto, Python loop':>17} | {'auto, fmpy calls':>17} | {'auto, C master':>17} "
        + "| contacts | target >= 10x (auto)"
    )
    reference = simulate_me(scene, LAW, rtol=1e-12).contact_records["t_onset"][:3]

    def error(tr: Any) -> float:
        onsets = tr.contact_records["t_onset"][:3]
        return float(np.max(np.abs(onsets - reference)))

    loops = Loops(scene)
    try:
        for rtol in args.rtol:
            for dt in args.grid:
                walls: dict[str, list[float]] = {
                    "me": [],
                    "python": [],
                    "fmpy": [],
                    **{m: [] for m in METHODS},
                }
                walls["c"] = []
                contacts = {}
                for _ in range(args.repeats):  # the variants in turn (same machine state)
                    wall, contacts["me"] = loops.run_me(rtol, dt)
                    walls["me"].append(wall)
                    for m, value in METHODS.items():
                        wall, contacts[m] = loops.run_cs(rtol, dt, value)
                        walls[m].append(wall)
                    wall, contacts["python"] = loops.run_cs(rtol, dt, METHODS["auto"], "python")
                    walls["python"].append(wall)
                    wall, contacts["fmpy"] = loops.run_cs(rtol, dt, METHODS["auto"], "fmpy")
                    walls["fmpy"].append(wall)
                    if master is not None:
                        wall, contacts["c"] = loops.run_c_master(master, rtol, dt, 1)
                        walls["c"].append(wall)
                if not walls["c"]:
                    walls["c"] = [math.nan]
                t = {k: float(np.median(v)) for k, v in walls.items()}
                err = {"me": error(simulate_me(scene, LAW, rtol=rtol, output_interval=dt))}
                for m, value in METHODS.items():
                    tr = simulate_cs(
                        scene,
                        LAW,
                        rtol=rtol,
                        communication_step=dt,
                        parameters={"solver.method": value},
                    )
                    err[m] = error(tr)
                cells = " | ".join(
                    f"{1e3 * t[m]:8.1f} ms [{err[m]:8.1e}] {t['me'] / t[m]:5.1f}x" for m in METHODS
                )
                ratio = t["me"] / t["auto"]
                counts = "/".join(
                    str(contacts.get(k, "-")) for k in ("me", *METHODS, "python", "fmpy", "c")
                )
                print(
                    f"  {rtol:6.0e} {dt:8.0e} | {1e3 * t['me']:8.1f} ms [{err['me']:8.1e}]     | "
                    f"{cells} | {1e3 * t['python']:8.1f} ms {t['me'] / t['python']:5.1f}x | "
                    f"{1e3 * t['fmpy']:8.1f} ms {t['me'] / t['fmpy']:5.1f}x | "
                    f"{1e3 * t['c']:8.1f} ms {t['me'] / t['c']:5.1f}x | {counts} | "
                    f"{'met' if ratio >= 10 else 'NOT met'}"
                )
    finally:
        loops.free()


if __name__ == "__main__":
    main()
