"""FMU state: get/set, serialize/deserialize and fmi2Reset, in model exchange and co-simulation.

Scene: flexure off, q0 = [0.01, 0.01, 0], friction on, law LN_spheres. Body 1 falls from rest and
hits the bore first at t ~ 0.075 s and again at t ~ 0.123 s, so the replay window [0.05, 0.15]
contains contact events (the discrete state changes there)."""

from __future__ import annotations

from ctypes import POINTER, c_double
from typing import Any

import numpy as np
import pytest
from fmi2_calls import METHODS, STATES, MakeFmu, get_value, xml_start
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.model_description import ModelDescription

T1 = 0.05
T2 = 0.15
CS_STEP = 1e-3
ME_STEP = 2e-5  # fixed-step RK4: the contact period is ~0.7 ms, omega dt ~ 0.2
ME_RECORD_EVERY = 25

REAL_OUTPUTS = [
    *STATES,
    "contact.F_N",
    "contact.F_T",
    "contact.gap",
    "contact.onset_speed",
    "energy.total",
]


# ------------------------------------------------------------------------------------------
# helpers


def setup_scene(fmu: FMU2Model | FMU2Slave, vr: dict[str, int]) -> None:
    """Instantiated -> initialized with the scene of this module."""
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setBoolean([vr["flexure.enabled"], vr["friction.enabled"]], [False, True])
    fmu.setInteger([vr["contact.law"]], [2])  # LN_spheres
    fmu.setReal([vr["body1.x"], vr["body1.y"], vr["body1.theta"]], [0.01, 0.01, 0.0])
    fmu.exitInitializationMode()


def record(fmu: FMU2Model | FMU2Slave, vr: dict[str, int], t: float) -> list[float]:
    """Time, real outputs, contact.count and contact.active as one row."""
    reals = fmu.getReal([vr[n] for n in REAL_OUTPUTS])
    count = fmu.getInteger([vr["contact.count"]])[0]
    active = fmu.getBoolean([vr["contact.active"]])[0]
    return [t, *reals, float(count), float(active)]


def discrete_state(fmu: FMU2Model | FMU2Slave, vr: dict[str, int]) -> tuple[int, bool, float]:
    count = fmu.getInteger([vr["contact.count"]])[0]
    active = bool(fmu.getBoolean([vr["contact.active"]])[0])
    onset = fmu.getReal([vr["contact.onset_speed"]])[0]
    return count, active, onset


class MERunner:
    """A deterministic fmpy-style model-exchange loop: fixed-step RK4, an event iteration when the
    event indicator changes sign. The FMU stays in continuous-time mode between calls."""

    def __init__(self, fmu: FMU2Model, vr: dict[str, int]) -> None:
        self.fmu = fmu
        self.vr = vr
        self.x = np.zeros(6)
        self.dx = np.zeros(6)
        self.z = np.zeros(1)
        self._px = self.x.ctypes.data_as(POINTER(c_double))
        self._pdx = self.dx.ctypes.data_as(POINTER(c_double))
        self._pz = self.z.ctypes.data_as(POINTER(c_double))

    def start(self) -> None:
        """After exitInitializationMode: event iteration, then continuous-time mode."""
        self._event_iteration()
        self.fmu.enterContinuousTimeMode()

    def _event_iteration(self) -> None:
        while self.fmu.newDiscreteStates()[0]:
            pass

    def _f(self, t: float, x: np.ndarray) -> np.ndarray:
        self.fmu.setTime(t)
        self.x[:] = x
        self.fmu.setContinuousStates(self._px, 6)
        self.fmu.getDerivatives(self._pdx, 6)
        return self.dx.copy()

    def _indicator(self) -> float:
        self.fmu.getEventIndicators(self._pz, 1)
        return float(self.z[0])

    def run(self, t: float, t_end: float) -> tuple[float, np.ndarray]:
        """Integrate from t (the FMU's time) to t_end; returns the end time and the rows recorded
        every ME_RECORD_EVERY steps."""
        fmu, h = self.fmu, ME_STEP
        fmu.getContinuousStates(self._px, 6)
        x = self.x.copy()
        z_old = self._indicator()
        n = round((t_end - t) / h)
        t0 = t
        rows: list[list[float]] = []
        for k in range(1, n + 1):
            k1 = self._f(t, x)
            k2 = self._f(t + 0.5 * h, x + 0.5 * h * k1)
            k3 = self._f(t + 0.5 * h, x + 0.5 * h * k2)
            k4 = self._f(t + h, x + h * k3)
            x = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            t = t0 + k * h
            fmu.setTime(t)
            self.x[:] = x
            fmu.setContinuousStates(self._px, 6)
            step_event, terminate = fmu.completedIntegratorStep()
            assert not terminate
            z_new = self._indicator()
            if step_event or (z_old > 0.0) != (z_new > 0.0):
                fmu.enterEventMode()
                self._event_iteration()
                fmu.enterContinuousTimeMode()
                z_new = self._indicator()
            z_old = z_new
            if k % ME_RECORD_EVERY == 0:
                rows.append(record(fmu, self.vr, t))
        return t, np.array(rows)


def cs_run(fmu: FMU2Slave, vr: dict[str, int], t: float, t_end: float) -> tuple[float, np.ndarray]:
    """fmi2DoStep with CS_STEP from t to t_end; one row per communication point."""
    n = round((t_end - t) / CS_STEP)
    t0 = t
    rows: list[list[float]] = []
    for k in range(n):
        fmu.doStep(t, CS_STEP)
        t = t0 + (k + 1) * CS_STEP
        rows.append(record(fmu, vr, t))
    return t, np.array(rows)


def assert_identical(a: np.ndarray, b: np.ndarray) -> None:
    assert a.shape == b.shape and a.size > 0
    if not np.array_equal(a, b):  # bitwise is expected; 1e-12 is the documented limit
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)


# ------------------------------------------------------------------------------------------
# model exchange


def me_prepared(make_fmu: MakeFmu, vr: dict[str, int]) -> tuple[FMU2Model, Any, MERunner, float]:
    fmu, log = make_fmu("ME")
    setup_scene(fmu, vr)
    runner = MERunner(fmu, vr)
    runner.start()
    t, _ = runner.run(0.0, T1)
    return fmu, log, runner, t


def test_me_get_set_state_replays_identically(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    fmu, log, runner, t1 = me_prepared(make_fmu, vr)
    assert discrete_state(fmu, vr)[0] == 0
    state = fmu.getFMUstate()
    _, first = runner.run(t1, T2)
    assert first[-1, -2] >= 1, "the replay window must contain a contact event"
    end_first = discrete_state(fmu, vr)

    fmu.setFMUstate(state)
    assert discrete_state(fmu, vr) == (0, False, 0.0)
    _, second = runner.run(t1, T2)
    assert_identical(first, second)
    assert discrete_state(fmu, vr) == end_first

    # the same state can be restored any number of times
    fmu.setFMUstate(state)
    _, third = runner.run(t1, T2)
    assert_identical(first, third)
    fmu.freeFMUstate(state)
    assert not log.errors()


def test_me_serialized_state_replays_identically(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    fmu, log, runner, t1 = me_prepared(make_fmu, vr)
    state = fmu.getFMUstate()
    data = fmu.serializeFMUstate(state)
    fmu.freeFMUstate(state)
    assert isinstance(data, bytes) and len(data) > 0
    _, first = runner.run(t1, T2)

    restored = fmu.deSerializeFMUstate(data)
    fmu.setFMUstate(restored)
    fmu.freeFMUstate(restored)  # the instance does not depend on the state object any more
    _, second = runner.run(t1, T2)
    assert_identical(first, second)

    # a serialized state carries everything: a fresh instance continues identically
    other, other_log = make_fmu("ME")
    setup_scene(other, vr)
    moved = other.deSerializeFMUstate(data)
    other.setFMUstate(moved)
    other.freeFMUstate(moved)
    _, third = MERunner(other, vr).run(t1, T2)
    assert_identical(first, third)
    assert not log.errors() and not other_log.errors()


def test_me_state_restores_parameters_and_time(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    fmu, _, _, t1 = me_prepared(make_fmu, vr)
    fmu.enterEventMode()
    state = fmu.getFMUstate()
    fmu.setReal([vr["contact.cr"]], [0.5])
    xi_changed = fmu.getReal([vr["contact.xi"]])[0]
    fmu.setFMUstate(state)
    assert fmu.getReal([vr["contact.cr"], vr["contact.xi"]]) == [0.9, 0.75 * (1.0 - 0.9 * 0.9)]
    assert xi_changed != fmu.getReal([vr["contact.xi"]])[0]
    assert fmu.getReal([vr["time"]])[0] == t1
    fmu.freeFMUstate(state)


# ------------------------------------------------------------------------------------------
# co-simulation


def cs_prepared(
    make_fmu: MakeFmu, vr: dict[str, int], t_save: float
) -> tuple[FMU2Slave, Any, float]:
    fmu, log = make_fmu("CS")
    setup_scene(fmu, vr)
    t, _ = cs_run(fmu, vr, 0.0, t_save)
    return fmu, log, t


def test_cs_get_set_state_replays_identically(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    fmu, log, t1 = cs_prepared(make_fmu, vr, T1)
    saved = discrete_state(fmu, vr)
    assert saved == (0, False, 0.0)
    state = fmu.getFMUstate()
    _, first = cs_run(fmu, vr, t1, T2)
    assert discrete_state(fmu, vr)[0] >= 1, "the replay window must contain a contact event"

    fmu.setFMUstate(state)
    assert discrete_state(fmu, vr) == saved
    assert fmu.getReal([vr["time"]])[0] == t1
    _, second = cs_run(fmu, vr, t1, T2)
    assert_identical(first, second)
    fmu.freeFMUstate(state)
    assert not log.errors()


def test_cs_serialized_state_replays_identically(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    fmu, log, t1 = cs_prepared(make_fmu, vr, T1)
    state = fmu.getFMUstate()
    data = fmu.serializeFMUstate(state)
    fmu.freeFMUstate(state)
    _, first = cs_run(fmu, vr, t1, T2)

    restored = fmu.deSerializeFMUstate(data)
    fmu.setFMUstate(restored)
    fmu.freeFMUstate(restored)
    _, second = cs_run(fmu, vr, t1, T2)
    assert_identical(first, second)

    other, other_log = make_fmu("CS")
    setup_scene(other, vr)
    moved = other.deSerializeFMUstate(data)
    other.setFMUstate(moved)
    other.freeFMUstate(moved)
    _, third = cs_run(other, vr, t1, T2)
    assert_identical(first, third)
    assert not log.errors() and not other_log.errors()


def test_cs_state_saved_in_contact_restores_discrete_state(
    make_fmu: MakeFmu, vr: dict[str, int]
) -> None:
    """Saved during the first contact (count 1, active), restored after the second one."""
    fmu, log, t_save = cs_prepared(make_fmu, vr, 0.075)
    saved = discrete_state(fmu, vr)
    assert saved[0] == 1 and saved[1] and saved[2] > 0.0
    state = fmu.getFMUstate()
    _, first = cs_run(fmu, vr, t_save, T2)
    after = discrete_state(fmu, vr)
    assert after[0] >= 2 and after[2] != saved[2]

    fmu.setFMUstate(state)
    assert discrete_state(fmu, vr) == saved
    _, second = cs_run(fmu, vr, t_save, T2)
    assert_identical(first, second)
    assert discrete_state(fmu, vr) == after
    fmu.freeFMUstate(state)
    assert not log.errors()


def test_get_state_does_not_change_the_trajectory_much(
    make_fmu: MakeFmu, vr: dict[str, int]
) -> None:
    """Taking a state restarts the CS integrator at that point: the result stays within the
    integration tolerance of an uninterrupted run."""
    plain, _ = make_fmu("CS")
    setup_scene(plain, vr)
    _, reference = cs_run(plain, vr, 0.0, 0.07)
    probed, _, t1 = cs_prepared(make_fmu, vr, T1)
    state = probed.getFMUstate()
    _, rest = cs_run(probed, vr, t1, 0.07)
    probed.freeFMUstate(state)
    n = rest.shape[0]
    np.testing.assert_allclose(rest[:, 1:7], reference[-n:, 1:7], rtol=0, atol=1e-6)


# ------------------------------------------------------------------------------------------
# fmi2Reset


@pytest.mark.parametrize("kind", ["ME", "CS"])
def test_reset_returns_to_start_values(
    make_fmu: MakeFmu, vr: dict[str, int], model_description: ModelDescription, kind: str
) -> None:
    fmu, log = make_fmu(kind)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal(
        [vr["contact.cr"], vr["body1.m"], vr["body1.x"], vr["F_ext[1]"]], [0.5, 3.0, 0.005, 2.0]
    )
    fmu.setInteger([vr["contact.law"]], [3])
    fmu.setBoolean([vr["flexure.enabled"]], [False])
    fmu.exitInitializationMode()
    if kind == "CS":
        cs_run(fmu, vr, 0.0, 0.1)
    else:
        runner = MERunner(fmu, vr)
        runner.start()
        runner.run(0.0, 0.01)
    assert fmu.getInteger([vr["diagnostics.rhs_evaluations"]])[0] > 0

    fmu.reset()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    for v in model_description.modelVariables:
        if v.start is not None:
            assert get_value(fmu, v) == xml_start(v), v.name
    assert fmu.getReal([vr["time"]])[0] == 0.0
    counters = [vr[n] for n in vr if n.startswith("diagnostics.")]
    assert fmu.getInteger(counters) == [0] * len(counters)
    fmu.exitInitializationMode()
    assert discrete_state(fmu, vr) == (0, False, 0.0)
    assert fmu.getReal([vr["contact.xi"]])[0] == 0.75 * (1.0 - 0.9 * 0.9)
    assert not log.errors()


def test_reset_then_rerun_matches_a_fresh_instance(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    used, _ = make_fmu("CS")
    setup_scene(used, vr)
    cs_run(used, vr, 0.0, 0.08)
    used.reset()
    setup_scene(used, vr)
    _, again = cs_run(used, vr, 0.0, 0.13)

    fresh, _ = make_fmu("CS")
    setup_scene(fresh, vr)
    _, reference = cs_run(fresh, vr, 0.0, 0.13)
    assert_identical(reference, again)
    assert reference[-1, -2] >= 2


@pytest.mark.parametrize("tolerance", [None, 1e-4])
def test_reset_after_a_bdf_run_matches_a_fresh_instance(
    make_fmu: MakeFmu, vr: dict[str, int], tolerance: float | None
) -> None:
    """fmi2Reset keeps the integration's memory: what a run with BDF (CVODE) through contacts,
    at the same tolerance or another, leaves there does not reach the next run (bit for bit)."""
    used, _ = make_fmu("CS")
    used.setupExperiment(tolerance=tolerance, startTime=0.0)
    used.enterInitializationMode()
    used.setInteger([vr["solver.method"]], [METHODS["BDF"]])
    used.setReal([vr["body1.x"], vr["body1.y"]], [0.01, 0.01])
    used.exitInitializationMode()
    cs_run(used, vr, 0.0, 0.13)
    used.reset()
    setup_scene(used, vr)
    _, again = cs_run(used, vr, 0.0, 0.13)

    fresh, _ = make_fmu("CS")
    setup_scene(fresh, vr)
    _, reference = cs_run(fresh, vr, 0.0, 0.13)
    assert np.array_equal(reference, again)
    assert reference[-1, -2] >= 2


def test_state_of_other_interface_is_rejected(make_fmu: MakeFmu, vr: dict[str, int]) -> None:
    """A co-simulation state cannot be restored into a model-exchange instance (and back): as
    serialized bytes (the way states move between instances) it is refused by
    fmi2DeSerializeFMUstate already; the FMUstate pointer of another instance is refused before
    a byte of it is read."""
    from fmpy.fmi1 import FMICallException

    cs, _ = make_fmu("CS")
    setup_scene(cs, vr)
    state = cs.getFMUstate()
    data = cs.serializeFMUstate(state)
    me, log = make_fmu("ME")
    setup_scene(me, vr)
    with pytest.raises(FMICallException):
        me.deSerializeFMUstate(data)
    assert any("co-simulation instance" in m for m in log.errors())
    with pytest.raises(FMICallException):
        me.setFMUstate(state)
    assert any("not made by this instance" in m for m in log.errors())
    cs.freeFMUstate(state)
