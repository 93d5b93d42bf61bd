"""What the stress outputs cost in co-simulation (docs/model.md §14.5).

The stresses are never part of the right-hand side (build/bench_rhs times one evaluation apart
from it); they are evaluated with the outputs, once per communication point. Tracking the peak of
the flexure stress inside each communication step (parameter flexure.track_stress_peak) costs
more: the co-simulation stepper then evaluates the stress at the end of every CVODE step and
where a maximum lies inside it, in flight too, where the contact peaks cost nothing. This
benchmark runs 1 s of the `csfh` scene (LN_spheres, mostly in contact) and of the same scene
without a contact law (flight on the flexure only), with and without tracking, at a 1e-2 s
communication step (fmi2DoStep called directly, no Python between CVODE steps), interleaved, and
reports the median times, their ratio and the CVODE steps (the same: tracking does not change the
integration).

Run: python benchmarks/bench_stress_peak.py [--repeats 11]
"""

from __future__ import annotations

import argparse
import statistics
import time

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from csfh import fmu_path, load_scene

STATE_NAMES = ("body1.x", "body1.y", "body1.theta", "body1.vx", "body1.vy", "body1.omega")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=11)
    args = ap.parse_args()
    path = str(fmu_path())
    md = read_model_description(path)
    unzipped = extract(path)
    vr = {v.name: (v.valueReference, v.type) for v in md.modelVariables}
    scene = load_scene("csfh")

    def run(track: bool, law: int) -> tuple[float, int]:
        fmu = FMU2Slave(
            guid=md.guid, unzipDirectory=unzipped, modelIdentifier="csfh", instanceName="b"
        )
        fmu.instantiate()
        fmu.setupExperiment(tolerance=1e-6, startTime=0.0)
        fmu.enterInitializationMode()
        values = {
            **scene.parameter_values("LN_spheres"),
            **dict(zip(STATE_NAMES, scene.x0, strict=True)),
        }
        values.update({"contact.law": law, "flexure.track_stress_peak": track})
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
        t0 = time.perf_counter()
        for k in range(100):
            fmu.doStep(k * step, step)
            fmu.getReal([vr["flexure.stress_max_peak"][0]])
        elapsed = time.perf_counter() - t0
        steps = fmu.getInteger([vr["diagnostics.integrator_steps"][0]])[0]
        fmu.terminate()
        fmu.freeInstance()
        return elapsed, steps

    cases = {"csfh scene, LN_spheres": 2, "flight, contact.law none": 1}  # ContactLaw values
    print(f"1 s, communication step 1e-2 s, rtol 1e-6, medians of {args.repeats}")
    print(f"{'scene':28s} {'off [ms]':>9s} {'on [ms]':>9s} {'on/off':>7s} {'CVODE steps':>12s}")
    for label, law in cases.items():
        times: dict[bool, list[float]] = {False: [], True: []}
        steps: dict[bool, int] = {}
        for _ in range(args.repeats):
            for track in (False, True):
                elapsed, n = run(track, law)
                times[track].append(elapsed)
                steps[track] = n
        off, on = statistics.median(times[False]), statistics.median(times[True])
        print(
            f"{label:28s} {1e3 * off:9.2f} {1e3 * on:9.2f} {on / off:7.3f} "
            f"{steps[False]:6d} {steps[True]:5d}"
        )


if __name__ == "__main__":
    main()
