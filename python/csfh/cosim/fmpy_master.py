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


class _Master:
    """The two instances, their value references and the master's state over the loop."""

    def __init__(self, s: CosimSettings, voltage_in_fmu: bool) -> None:
        self.s, self.voltage_in_fmu = s, voltage_in_fmu
        self.c = Slave(str(fmu_path()), "csfh")
        self.a = Slave(str(combdrive_fmu_path()), "combdrive")
        self.current = self.c  # the instance of the call under way (for the error message)
        c, a = self.c, self.a
        links = [(o, i) for o, i in CONNECTIONS if s.moment or o != "M"]
        self.out_vrs = [a.vr(o) for o, _ in links]
        self.in_vrs = [c.vr(i) for _, i in links]
        self.theta_c, self.theta_a = c.vr("body1.theta"), a.vr("theta")
        self.act_vrs = [a.vr(name) for name in ACTUATOR_COLUMNS]
        self.csfh_vrs = [c.vr(name) for name in OUTPUT_NAMES.values()]
        self.count_vr = c.vr("contact.count")
        self.applied: list[float] = [0.0] * len(self.act_vrs)

    def exchange_theta(self) -> None:
        if self.s.moment:
            self.a.fmu.setReal([self.theta_a], self.c.fmu.getReal([self.theta_c]))

    def actuator_to_hinge(self) -> None:
        """theta to the actuator, its force (read) and the forces to the hinge."""
        self.exchange_theta()
        self.applied = self.a.fmu.getReal(self.act_vrs)
        self.current = self.c
        self.c.fmu.setReal(self.in_vrs, self.a.fmu.getReal(self.out_vrs))

    def initialise(self, scene: Scene, t_end: float, initial_exchange: bool) -> None:
        c, a = self.c, self.a
        c.fmu.setupExperiment(tolerance=self.s.tolerance, startTime=0.0, stopTime=t_end)
        a.fmu.setupExperiment(startTime=0.0, stopTime=t_end)
        c.fmu.enterInitializationMode()
        a.fmu.enterInitializationMode()
        c.set(csfh_start_values(scene))
        self.current = a
        a.set(actuator_start_values(self.s, self.voltage_in_fmu))
        # initial exchange (as libcosim's initialization): theta -> actuator, forces -> hinge
        if initial_exchange:
            self.actuator_to_hinge()
        self.current = c
        c.fmu.exitInitializationMode()
        self.current = a
        a.fmu.exitInitializationMode()

    def step(self, t: float, h: float) -> None:
        """Both FMUs from t over h; Jacobi: the outputs at t + h become the next inputs."""
        self.current = self.c
        self.c.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        self.current = self.a
        self.a.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        if self.s.ordering == "jacobi":
            self.applied = self.a.fmu.getReal(self.act_vrs)
            outputs = self.a.fmu.getReal(self.out_vrs)
            self.exchange_theta()
            self.current = self.c
            self.c.fmu.setReal(self.in_vrs, outputs)

    def loop(self, n: int, progress: Progress | None) -> tuple[Rows, list[int]]:
        """The communication points k = 0 .. n: the voltage, the Gauss-Seidel exchange, the
        hinge's outputs and the force acting on it, then the step to the next point."""
        s, c, a, h = self.s, self.c, self.a, self.s.step
        rows = Rows(COLUMNS)
        counts: list[int] = []
        for k in range(n + 1):
            t = k * h
            V = s.voltage(t)
            self.current = a
            if not self.voltage_in_fmu:
                a.fmu.setReal([a.vr("V")], [V])
            if s.ordering == "gauss-seidel":
                self.actuator_to_hinge()
            self.current = c
            rows.rows.append([t, *c.fmu.getReal(self.csfh_vrs), V, *self.applied])
            counts.append(c.fmu.getInteger([self.count_vr])[0])
            if k == n:
                break
            self.step(t, h)
            if progress is not None and k % 200 == 0:
                progress.update((k + 1) / n)
        return rows, counts


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

    t_end = scene.stop_time if stop_time is None else stop_time
    n = max(1, round(t_end / settings.step))
    wall = time.perf_counter()
    m = _Master(settings, voltage_in_fmu)
    try:
        m.initialise(scene, t_end, initial_exchange)
        rows, counts = m.loop(n, progress)
        m.current = m.c
        steps = m.c.fmu.getInteger([m.c.vr("diagnostics.integrator_steps")])[0]
        m.c.fmu.terminate()
        m.a.fmu.terminate()
    except FMICallException as exc:
        raise CosimError(m.current.message(exc)) from None
    finally:
        m.c.free()
        m.a.free()
    stats = {
        "engine": "fmpy",
        "communication_steps": n,
        "steps": int(steps),
        "wall_time": time.perf_counter() - wall,
    }
    return make_trajectory(scene, settings, rows.arrays(), np.array(counts), stats)
