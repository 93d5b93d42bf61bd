"""Co-simulation: the csfh FMU as a co-simulation slave, driven by the comb-drive actuator FMU.

A plain fixed-step master loop over fmpy's FMU2Slave couples the two FMUs as any master would
(libcosim, a SSP tool, your own loop): each communication step the master sets the drive voltage
and the hinge's rotation on the actuator, passes the actuator's force and moment to the hinge's
inputs F_ext[1], F_ext[2], M_ext, and steps both (actuator first: Gauss-Seidel ordering). The
hinge integrates with its own integrator inside fmi2DoStep (solver.method auto: RK45, BDF
where stiff) and locates every contact inside the step.

The scenario is the built-in `combdrive` scene: 333 V carry body 1's weight, a ramp to 500 V
drives it into the top of the bore. At the end the same coupling is run by the harness
(`csfh.cosimulate`), which must agree to round-off.

    python3 examples/cosim.py
"""

from __future__ import annotations

import math
import shutil
import tempfile

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

import csfh

STEP = 1e-3  # s, communication step
STOP = 0.4  # s
ACTUATOR = {  # comb-drive parameters (the `combdrive` scene)
    "fingers": 20000,
    "gap": 5e-6,
    "thickness": 0.025,
    "permittivity": 8.8541878128e-12,
    "direction": math.pi / 2,  # the force pulls along +Y
    "arm[1]": 0.02,  # m, applied 20 mm from G1 along body x: it also turns body 1
    "arm[2]": 0.0,
}
HINGE = {"body1.x": 0.0, "body1.y": 0.0}  # start at rest, centred; everything else: FMU defaults


def voltage(t: float) -> float:
    """333 V until 0.1 s, linear to 500 V at 0.2 s."""
    return 333.0 + (500.0 - 333.0) * min(1.0, max(0.0, (t - 0.1) / 0.1))


class Slave:
    """One FMU instance with access by variable name."""

    def __init__(self, path: str, name: str, unzip_root: str) -> None:
        md = read_model_description(path)
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=extract(path, unzipdir=f"{unzip_root}/{name}"),
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate()

    def set(self, values: dict[str, float]) -> None:
        for name, value in values.items():
            if isinstance(value, int) and not isinstance(value, bool):
                self.fmu.setInteger([self.vr[name]], [value])
            elif isinstance(value, bool):
                self.fmu.setBoolean([self.vr[name]], [value])
            else:
                self.fmu.setReal([self.vr[name]], [value])

    def get(self, *names: str) -> list[float]:
        return self.fmu.getReal([self.vr[n] for n in names])


def master(hinge_fmu: str, actuator_fmu: str) -> dict[str, np.ndarray]:
    unzip_root = tempfile.mkdtemp(prefix="csfh-example-")
    hinge = Slave(hinge_fmu, "csfh", unzip_root)
    act = Slave(actuator_fmu, "combdrive", unzip_root)
    try:
        for s in (hinge, act):
            s.fmu.setupExperiment(startTime=0.0, stopTime=STOP)  # hinge: default rtol 1e-6
            s.fmu.enterInitializationMode()
        hinge.set(HINGE)
        act.set(ACTUATOR)
        for s in (hinge, act):
            s.fmu.exitInitializationMode()
        rows = []
        n = round(STOP / STEP)
        for k in range(n + 1):
            t = k * STEP
            # actuator first: voltage and rotation now -> force and moment on the hinge
            act.set({"V": voltage(t), "theta": hinge.get("body1.theta")[0]})
            F_x, F_y, M = act.get("F_x", "F_y", "M")
            hinge.set({"F_ext[1]": F_x, "F_ext[2]": F_y, "M_ext": M})
            x, y, F_N = hinge.get("body1.x", "body1.y", "contact.F_N")
            count = hinge.fmu.getInteger([hinge.vr["contact.count"]])[0]
            rows.append((t, x, y, F_N, F_y, count))
            if k < n:
                hinge.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=STEP)
                act.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=STEP)
        for s in (hinge, act):
            s.fmu.terminate()
    finally:
        for s in (hinge, act):
            s.fmu.freeInstance()
        shutil.rmtree(unzip_root, ignore_errors=True)
    data = np.array(rows)
    return dict(zip(("t", "x", "y", "F_N", "F_y", "count"), data.T, strict=True))


def main() -> None:
    # the FMUs: csfh ships both (build/ in a source tree, or inside the installed package)
    hinge_fmu, actuator_fmu = str(csfh.fmu_path()), str(csfh.combdrive_fmu_path())
    r = master(hinge_fmu, actuator_fmu)
    hold = r["F_y"][0]
    print(f"actuator force at 333 V: {hold:.2f} N (body 1 weighs {10 * 9.81:.1f} N)")
    print(
        f"contacts by {STOP} s: {int(r['count'][-1])}, largest F_N {r['F_N'].max():.4g} N, "
        f"largest eccentricity {np.hypot(r['x'], r['y']).max() * 1e3:.3f} mm (clearance 20 mm)"
    )
    assert abs(hold - 98.1) < 1.0 and r["count"][-1] >= 1

    # the same coupling run by the harness (fmpy engine, Gauss-Seidel ordering)
    scene = csfh.load_scene("combdrive")
    tr = csfh.cosimulate(scene, step=STEP, ordering="gauss-seidel", stop_time=STOP)
    diff = max(np.max(np.abs(tr["x"] - r["x"])), np.max(np.abs(tr["y"] - r["y"])))
    print(f"csfh.cosimulate, same coupling: largest position difference {diff:.1e} m")
    assert diff < 1e-9


if __name__ == "__main__":
    main()
