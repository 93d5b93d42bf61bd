"""Co-simulation's BDF with the analytic Jacobian against CVODE's difference quotients
(solver.analytic_jacobian, docs/model.md §15).

Three runs where BDF is the method that pays: resting contact (the stress suite's "resting
contact, 10 s": the central drop that settles on the bore), sliding and rolling contact with
friction (the stress suite's "high friction f = 1", 0.5 s), and the `csfh` scene (1 s). Each is
run with solver.method = BDF at rtol 1e-6 and 1e-2 s communication steps (fmi2DoStep called
directly), both Jacobians interleaved, and reports per variant CVODE's steps, the right-hand
sides (diagnostics.rhs_evaluations: a difference-quotient Jacobian costs 6 of them), the
Jacobians formed, the median wall time, the ratios analytic / difference quotients, and the
largest state difference at the end relative to the tolerance (rtol x the state's scale),
beside the same difference between two difference-quotient runs whose tolerances differ by 1 %
(how far apart two equally valid integrations end: impacts and friction amplify every
difference of the Newton matrix or the step sequence alike).

Run: python benchmarks/bench_jacobian.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from csfh import fmu_path, load_scene
from csfh.model.scene import Scene
from csfh.studies.stress.cases import build_cases

STATES = ("body1.x", "body1.y", "body1.theta", "body1.vx", "body1.vy", "body1.omega")
COUNTS = ("integrator_steps", "rhs_evaluations", "jacobian_evaluations")
RTOL = 1e-6
BDF = 2  # SolverMethod


def stress_scene(name: str) -> Scene:
    return next(c.scene for c in build_cases() if c.name == name)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    path = str(fmu_path())
    md = read_model_description(path)
    unzipped = extract(path)
    vr = {v.name: (v.valueReference, v.type) for v in md.modelVariables}
    nominal = np.array(
        [float(next(v.nominal for v in md.modelVariables if v.name == s) or 1.0) for s in STATES]
    )

    def run(
        scene: Scene, t_end: float, analytic: bool, rtol: float = RTOL
    ) -> tuple[float, list[int], np.ndarray]:
        fmu = FMU2Slave(
            guid=md.guid, unzipDirectory=unzipped, modelIdentifier="csfh", instanceName="b"
        )
        fmu.instantiate()
        fmu.setupExperiment(tolerance=rtol, startTime=0.0)
        fmu.enterInitializationMode()
        values = {
            **scene.parameter_values("LN_spheres"),
            **dict(zip(STATES, scene.x0, strict=True)),
            "solver.method": BDF,
            "solver.analytic_jacobian": analytic,
        }
        for name, value in values.items():
            ref, kind = vr[name]
            if kind == "Real":
                fmu.setReal([ref], [float(value)])
            elif kind == "Boolean":
                fmu.setBoolean([ref], [bool(value)])
            else:
                fmu.setInteger([ref], [int(value)])
        fmu.exitInitializationMode()
        step = 1e-2
        n = round(t_end / step)
        t0 = time.perf_counter()
        for k in range(n):
            fmu.doStep(k * step, step)
        elapsed = time.perf_counter() - t0
        counts = fmu.getInteger([vr[f"diagnostics.{c}"][0] for c in COUNTS])
        x = np.array(fmu.getReal([vr[s][0] for s in STATES]))
        fmu.terminate()
        fmu.freeInstance()
        return elapsed, counts, x

    cases = {
        "resting contact, 10 s": (stress_scene("resting contact, 10 s"), 10.0),
        "high friction f = 1, 0.5 s": (stress_scene("high friction f = 1"), 0.5),
        "csfh scene, 1 s": (load_scene("csfh"), 1.0),
    }
    print(f"BDF, rtol {RTOL:g}, communication step 1e-2 s, medians of {args.repeats}")
    print(
        f"{'case':28s} {'Jacobian':9s} {'steps':>6s} {'RHS':>7s} {'Jacobians':>9s} "
        f"{'time [ms]':>9s}"
    )
    for label, (scene, t_end) in cases.items():
        times: dict[bool, list[float]] = {False: [], True: []}
        counts: dict[bool, list[int]] = {}
        final: dict[bool, np.ndarray] = {}
        for _ in range(args.repeats):
            for analytic in (False, True):
                elapsed, c, x = run(scene, t_end, analytic)
                times[analytic].append(elapsed)
                counts[analytic], final[analytic] = c, x
        med = {a: statistics.median(times[a]) for a in (False, True)}
        for analytic in (False, True):
            s, r, j = counts[analytic]
            name = "analytic" if analytic else "DQ"
            print(f"{label:28s} {name:9s} {s:6d} {r:7d} {j:9d} {1e3 * med[analytic]:9.1f}")
        ratio = [counts[True][k] / counts[False][k] for k in range(3)]
        _, _, other = run(scene, t_end, False, 0.99 * RTOL)
        spread = np.max(
            np.abs(other - final[False]) / (RTOL * np.maximum(nominal, np.abs(final[False])))
        )
        diff = np.max(
            np.abs(final[True] - final[False]) / (RTOL * np.maximum(nominal, np.abs(final[False])))
        )
        print(
            f"{'':28s} {'ratio':9s} {ratio[0]:6.3f} {ratio[1]:7.3f} {ratio[2]:9.3f} "
            f"{med[True] / med[False]:9.3f}   end state: {diff:.2g} x tolerance "
            f"(DQ at 0.99 rtol: {spread:.2g})"
        )


if __name__ == "__main__":
    main()
