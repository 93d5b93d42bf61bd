"""The fixed-step co-simulation master over fmpy's FMU2Slave: Jacobi (as libcosim) or
Gauss-Seidel ordering (see csfh.cosim.coupling)."""

from __future__ import annotations

import time

import numpy as np

from ..model.cosim_section import CONNECTIONS, CosimSettings
from ..model.fmus import Slave
from ..model.scene import Scene
from ..paths import combdrive_fmu_path, fmu_path
from ..progress import Progress
from ..runners.fmu import OUTPUT_NAMES
from ..trajectory import Trajectory
from .coupling import (
    ACTUATOR_COLUMNS,
    COLUMNS,
    CosimError,
    Rows,
    actuator_start_values,
    csfh_start_values,
    make_trajectory,
)


def run_fmpy(
    scene: Scene,
    settings: CosimSettings,
    *,
    stop_time: float | None = None,
    progress: Progress | None = None,
    voltage_in_fmu: bool = False,
    initial_exchange: bool = True,
) -> Trajectory:
    """Fixed-step master loop over fmpy's FMU2Slave (ordering from the settings).

    `voltage_in_fmu`: the actuator evaluates the voltage ramp itself (csfh.cosim.coupling).
    `initial_exchange` (default, as libcosim): at initialization theta goes to the actuator and
    its force to the hinge, so the force acts from t = 0; False: every connected input keeps its
    start value 0 over the first step, as in fmpy's SSP master (fmpy.ssp.simulation)."""
    from fmpy.fmi1 import FMICallException

    s = settings
    t_end = scene.stop_time if stop_time is None else stop_time
    n = max(1, round(t_end / s.step))
    h = s.step
    csfh_path, act_path = str(fmu_path()), str(combdrive_fmu_path())
    wall = time.perf_counter()
    c = Slave(csfh_path, "csfh")
    a = Slave(act_path, "combdrive")
    current = c
    try:
        c.fmu.setupExperiment(tolerance=s.tolerance, startTime=0.0, stopTime=t_end)
        a.fmu.setupExperiment(startTime=0.0, stopTime=t_end)
        c.fmu.enterInitializationMode()
        a.fmu.enterInitializationMode()
        c.set(csfh_start_values(scene))
        current = a
        a.set(actuator_start_values(s, voltage_in_fmu))
        links = [(o, i) for o, i in CONNECTIONS if s.moment or o != "M"]
        out_vrs = [a.vr(o) for o, _ in links]
        in_vrs = [c.vr(i) for _, i in links]
        theta_c, theta_a = c.vr("body1.theta"), a.vr("theta")
        act_vrs = [a.vr(name) for name in ACTUATOR_COLUMNS]
        csfh_vrs = [c.vr(name) for name in OUTPUT_NAMES.values()]
        count_vr = c.vr("contact.count")

        def exchange_theta() -> None:
            if s.moment:
                a.fmu.setReal([theta_a], c.fmu.getReal([theta_c]))

        # initial exchange (as libcosim's initialization): theta -> actuator, forces -> hinge
        if initial_exchange:
            exchange_theta()
            applied = a.fmu.getReal(act_vrs)
            c.fmu.setReal(in_vrs, a.fmu.getReal(out_vrs))
        else:
            applied = [0.0] * len(act_vrs)
        current = c
        c.fmu.exitInitializationMode()
        current = a
        a.fmu.exitInitializationMode()

        rows = Rows(COLUMNS)
        counts: list[int] = []
        for k in range(n + 1):
            t = k * h
            V = s.voltage(t)
            current = a
            if not voltage_in_fmu:
                a.fmu.setReal([a.vr("V")], [V])
            if s.ordering == "gauss-seidel":
                exchange_theta()
                applied = a.fmu.getReal(act_vrs)
                current = c
                c.fmu.setReal(in_vrs, a.fmu.getReal(out_vrs))
            current = c
            rows.rows.append([t, *c.fmu.getReal(csfh_vrs), V, *applied])
            counts.append(c.fmu.getInteger([count_vr])[0])
            if k == n:
                break
            c.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            current = a
            a.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            if s.ordering == "jacobi":
                # outputs at t_k+1 -> inputs for the next step
                applied = a.fmu.getReal(act_vrs)
                outputs = a.fmu.getReal(out_vrs)
                exchange_theta()
                current = c
                c.fmu.setReal(in_vrs, outputs)
            if progress is not None and k % 200 == 0:
                progress.update((k + 1) / n)
        current = c
        steps = c.fmu.getInteger([c.vr("diagnostics.integrator_steps")])[0]
        c.fmu.terminate()
        a.fmu.terminate()
    except FMICallException as exc:
        raise CosimError(current.message(exc)) from None
    finally:
        c.free()
        a.free()
    stats = {
        "engine": "fmpy",
        "communication_steps": n,
        "steps": int(steps),
        "wall_time": time.perf_counter() - wall,
    }
    return make_trajectory(scene, s, rows.arrays(), np.array(counts), stats)
