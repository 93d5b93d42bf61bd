"""Model exchange of the csfh FMU with CVODE (BDF, `cvode.CvodeStepper`) on fmpy's FMU2Model.

CVODE is stepped one internal step at a time, so that every step can be counted and recorded
(the paper's "vs step" figures); outputs are interpolated onto the requested output grid with
CVODE's dense output, and fmpy's limit of 500 internal steps per output interval does not
apply. Contact onsets and releases are recorded at the located event instants.

Peaks: the largest normal force and indentation of each contact are searched here, on CVODE's
interpolant (`_MeRun.refine_peaks`), while a co-simulation run gets them from the FMU, whose C
search (fmu_src/models/csfh/csfh_peaks.c) runs on its own integrator's dense output. One algorithm
cannot serve both: in model exchange the integrator and its interpolant are the importer's, and
the FMU only evaluates the states it is given, so the search must run where the interpolant is;
the FMU's search works on its stepper's internal data and is not reachable from outside (the
FMU exports the FMI functions only), and calling it back into Python for every evaluation of the
interpolant would cost what the search here costs."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from ..errors import SimulationError
from ..model import model_info
from ..model._csfh_variables import MAX_ME_STEPS
from ..model.fmus import FmuLog
from ..model.limits import check_rows
from ..model.scene import Scene
from ..progress import Progress
from ..trajectory import Trajectory
from .cvode import CV_TSTOP_RETURN, CvodeStepper
from .fmu import (
    EVALUATION_PARTS,
    OUTPUT_NAMES,
    TABLE_COLUMNS,
    Table,
    check_law,
    contact_arrays,
    fmu_error,
    resident_binary,
    start_values,
    unzipped_fmu,
    vr,
)

N_STATES = len(model_info.STATE_NAMES)
OUT_VRS = [vr(n) for n in OUTPUT_NAMES.values()]
PEAK_VRS = [vr("contact.F_N"), vr("contact.indentation")]
_I_F, _I_IND = list(OUTPUT_NAMES).index("F_N"), list(OUTPUT_NAMES).index("indentation")


def _instantiate() -> tuple[Any, FmuLog]:
    """A model-exchange instance whose log keeps the FMU's error messages, instead of fmpy's
    default logger printing them on standard output."""
    from fmpy.fmi2 import FMU2Model

    md = model_info.model_description()
    resident_binary(unzipped_fmu(), md.modelExchange.modelIdentifier)
    fmu = FMU2Model(
        guid=md.guid,
        unzipDirectory=unzipped_fmu(),
        modelIdentifier=md.modelExchange.modelIdentifier,
        instanceName="csfh",
    )
    log = FmuLog()
    fmu.instantiate(callbacks=log.callbacks)
    return fmu, log


def _event_iteration(fmu: Any) -> float:
    """The event iteration; returns the next time event the FMU reports (inf: none)."""
    more = True
    next_event = math.inf
    while more:
        more, terminate, _, _, defined, next_time = fmu.newDiscreteStates()
        if terminate:
            raise SimulationError("the FMU requested termination")
        next_event = float(next_time) if defined else math.inf
    return next_event


def output_grid(t_end: float, dt_out: float, output_times: np.ndarray | None) -> np.ndarray:
    """The output times after t = 0: k * dt_out up to t_end, or the given increasing times."""
    if output_times is None:
        check_rows(t_end, dt_out, "output_interval")
        return np.arange(1, math.floor(t_end / dt_out * (1 + 1e-12)) + 1) * dt_out
    grid = np.asarray(output_times, dtype=float)
    return grid[(grid > 0) & (grid <= t_end * (1 + 1e-12))]


class _MeRun:
    """One model-exchange run after initialization: the CVODE loop, its tables and records."""

    def __init__(
        self,
        fmu: Any,
        law: str,
        rtol: float,
        t_end: float,
        grid: np.ndarray,
        max_step_records: int,
        max_steps: int,
    ) -> None:
        self.fmu, self.law, self.t_end, self.grid = fmu, law, t_end, grid
        self.max_step_records, self.max_steps = max_step_records, max_steps
        self.t = 0.0
        self.row: list[float] = []  # the outputs at the end of the last step
        self.t_event = _event_iteration(fmu)  # time events: the ends of a shock pulse
        fmu.enterContinuousTimeMode()
        self.table, self.steps = Table(TABLE_COLUMNS), Table(TABLE_COLUMNS)
        self.contacts: list[float] = []
        self.releases: list[float] = []
        self.n_contacts = fmu.getInteger([vr("contact.count")])[0]
        if self.n_contacts:
            self.contacts.append(0.0)
        self.table.add([0.0, *fmu.getReal(OUT_VRS)])
        self.solver = CvodeStepper(fmu, N_STATES, 1, rtol, 0.0)
        self.in_contact = bool(fmu.getBoolean([vr("contact.active")])[0])
        self.records: list[list[float]] = []
        if self.in_contact:
            self.records.append([0.0, self._onset_speed(), math.nan, math.nan, 0.0, 0.0])
        self.prev_peak = tuple(fmu.getReal(PEAK_VRS))
        self.i_out = self.n_steps = self.n_calls = self.n_events = 0
        self.solver.set_stop_time(min(t_end, self.t_event))

    def _onset_speed(self) -> float:
        return float(self.fmu.getReal([vr("contact.onset_speed")])[0])

    def interpolated(self, tq: float, vrs: list[int]) -> list[float]:
        """Outputs at tq inside the last step, from CVODE's interpolant."""
        self.fmu.setTime(tq)
        self.fmu.setContinuousStates(self.solver.dense(tq), N_STATES)
        return list(self.fmu.getReal(vrs))

    def refine_peaks(self, rec: list[float], ta: float, tb: float) -> None:
        """Largest F_N and indentation over the step [ta, tb] on CVODE's interpolant: the step is
        cut into eight parts; the values at their ends count, and in every part where the time
        derivative (a centred difference of the interpolant, one-sided at the step ends) changes
        sign from + to - (or to 0), its root is found by bisection and the value there counts (a
        contact step can hold more than one hump, e.g. in stick-slip)."""
        if not tb - ta > 1e-13 * max(1.0, abs(tb)):
            return
        eps = 1e-7 * (tb - ta)

        def slope(tq: float, j: int) -> float:
            step = max(eps, 8 * math.ulp(tq))
            lo, hi = max(ta, tq - step), min(tb, tq + step)
            if not hi > lo:
                return 0.0
            return (self.interpolated(hi, PEAK_VRS)[j] - self.interpolated(lo, PEAK_VRS)[j]) / (
                hi - lo
            )

        ts = [ta + (tb - ta) * k / 8 for k in range(9)]
        samples = [self.interpolated(tk, PEAK_VRS) for tk in ts]
        for col, j in ((4, 0), (5, 1)):
            peak = max(self.prev_peak[j], *(v[j] for v in samples))
            slopes = [slope(tk, j) for tk in ts]
            for k in range(8):
                # a zero difference (the hump right at a sample) ends the part before it
                if slopes[k] > 0 and slopes[k + 1] <= 0:
                    root = _bisect(lambda tq, j=j: slope(tq, j), ts[k], ts[k + 1])
                    peak = max(peak, self.interpolated(root, PEAK_VRS)[j])
            rec[col] = max(rec[col], peak)

    def _restart(self) -> None:
        """The event iteration at the current time, then CVODE again from there."""
        self.fmu.enterEventMode()
        self.t_event = _event_iteration(self.fmu)
        self.fmu.enterContinuousTimeMode()

    def _contact_event(self) -> None:
        """A root of the gap: the event instant in the table, a contact begins or ends."""
        self.n_events += 1
        self.table.add(self.row)  # the event instant itself (left limit)
        self._restart()
        count = self.fmu.getInteger([vr("contact.count")])[0]
        if count > self.n_contacts:
            self.contacts.append(self.t)
            self.n_contacts = count
            self.in_contact = True
            self.records.append([self.t, self._onset_speed(), math.nan, math.nan, 0.0, 0.0])
            self.prev_peak = tuple(self.fmu.getReal(PEAK_VRS))
        elif not self.fmu.getBoolean([vr("contact.active")])[0]:
            self.releases.append(self.t)
            self.in_contact = False
            if self.records:
                self.records[-1][2] = self.t
                self.records[-1][3] = -self.fmu.getReal([vr("contact.indentation_rate")])[0]

    def _step(self) -> None:
        """One CVODE step: the grid outputs inside it, the peaks, the step's record, events."""
        from fmpy.sundials.cvode import CV_ROOT_RETURN

        flag, t_new = self.solver.step(self.t_end)
        if self.solver.callback_error is not None:
            raise self.solver.callback_error
        if flag < 0:
            raise SimulationError(
                f"{self.law}: CVode failed at t = {self.t:.9g} s (flag {flag}): "
                f"{self.solver.message()}"
            )
        self.n_calls += 1  # one CVODE step per call (one-step mode)
        if self.n_calls > self.max_steps:
            raise SimulationError(
                f"{self.law}: more than {self.max_steps} CVODE steps (the step budget) by t = "
                f"{t_new:.9g} s of {self.t_end:g} s"
            )
        # outputs on the regular grid inside the step, from CVODE's interpolant
        while self.i_out < len(self.grid) and self.grid[self.i_out] <= t_new * (1 + 1e-14):
            tq = float(self.grid[self.i_out])
            self.table.add([tq, *self.interpolated(tq, OUT_VRS)])
            self.i_out += 1
        if self.in_contact and self.records:
            self.refine_peaks(self.records[-1], self.t, t_new)
        self.fmu.setTime(t_new)
        self.fmu.setContinuousStates(self.solver.px, N_STATES)
        n_steps = self.solver.steps()
        self.row = [t_new, *self.fmu.getReal(OUT_VRS)]
        self.prev_peak = (self.row[1 + _I_F], self.row[1 + _I_IND])
        if len(self.steps.rows) < self.max_step_records:
            self.steps.add(self.row)
        self.t = t_new
        time_event = flag == CV_TSTOP_RETURN and self.t < self.t_end * (1 - 1e-15)
        if flag == CV_ROOT_RETURN:
            self._contact_event()
        elif time_event:
            # a time event (the start or end of a shock pulse, where the right-hand side has a
            # kink): CVODE stopped exactly there; restart it
            self._restart()
        if flag == CV_ROOT_RETURN or time_event:
            self.n_steps += n_steps  # CVodeReInit restarts the count
            self.solver.reset(self.t)
            self.solver.set_stop_time(min(self.t_end, self.t_event))

    def integrate(self, progress: Progress | None) -> None:
        while self.t < self.t_end * (1 - 1e-15):
            self._step()
            if progress is not None:
                progress.update(self.t / self.t_end)
        self.n_steps += self.solver.steps()

    def statistics(self) -> dict[str, Any]:
        counters = self.fmu.getInteger(
            [vr(f"diagnostics.{p}_evaluations") for p in EVALUATION_PARTS]
        )
        return {
            "steps": int(self.n_steps),
            "rhs_evaluations": int(counters[0]),
            "events": self.n_events,
            "evaluations": dict(zip(EVALUATION_PARTS, (int(v) for v in counters), strict=True)),
        }

    def trajectory(self, scene: str) -> Trajectory:
        return Trajectory(
            model=self.law,
            scene=scene,
            table=self.table.arrays(),
            contacts=np.array(self.contacts),
            steps=self.steps.arrays(),
            releases=np.array(self.releases),
            contact_records=contact_arrays(self.records),
        )


def _bisect(slope: Any, lo: float, hi: float) -> float:
    """Where `slope` turns from + to - in [lo, hi], to round-off."""
    while hi - lo > 1e-14 * max(1.0, abs(hi)):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        lo, hi = (mid, hi) if slope(mid) > 0 else (lo, mid)
    return 0.5 * (lo + hi)


def _initialize(
    fmu: Any,
    scene: Scene,
    law: str,
    rtol: float,
    t_end: float,
    parameters: dict[str, Any] | None,
) -> None:
    """Set-up and initialization mode with every start value of the run (fmu.start_values)."""
    fmu.setupExperiment(tolerance=rtol, startTime=0.0, stopTime=t_end)
    fmu.enterInitializationMode()
    for name, kind, value in start_values(scene, law, parameters):
        getattr(fmu, f"set{kind}")([vr(name)], [value])
    fmu.exitInitializationMode()


def simulate_me(
    scene: Scene,
    law: str,
    *,
    rtol: float | None = None,
    output_interval: float | None = None,
    stop_time: float | None = None,
    max_step_records: int = 200_000,
    parameters: dict[str, Any] | None = None,
    output_times: np.ndarray | None = None,
    progress: Progress | None = None,
    max_steps: int = MAX_ME_STEPS,
) -> Trajectory:
    """Model exchange of the FMU with contact law `law`, CVode (BDF), events located by root
    finding on the gap. Returns the output table (the grid k * output_interval, or the given
    increasing `output_times`, plus the event instants), per-step records (the first
    `max_step_records` steps), per-contact records (peaks located on CVODE's interpolant) and
    statistics. More than `max_steps` CVODE steps (the budget: minutes of Python) raise
    SimulationError, so that no input makes the run hang."""
    from fmpy.fmi1 import FMICallException

    check_law(law)
    rtol = scene.integrator.rtol if rtol is None else rtol
    dt_out = scene.integrator.output_interval if output_interval is None else output_interval
    t_end = scene.stop_time if stop_time is None else stop_time
    grid = output_grid(t_end, dt_out, output_times)
    wall = time.perf_counter()
    fmu, log = _instantiate()
    run: _MeRun | None = None
    try:
        _initialize(fmu, scene, law, rtol, t_end, parameters)
        run = _MeRun(fmu, law, rtol, t_end, grid, max_step_records, max_steps)
        run.integrate(progress)
        stats = run.statistics()
        fmu.terminate()
    except FMICallException as exc:
        t = run.t if run is not None else 0.0
        raise fmu_error(law, t, exc.function or type(exc).__name__, log.reason(str(exc))) from None
    finally:
        if run is not None:
            run.solver.close()
        fmu.freeInstance()
    tr = run.trajectory(scene.name)
    tr.stats = {
        "integrator": f"CVode BDF (fmpy, model exchange) rtol={rtol:g}",
        **stats,
        "wall_time": time.perf_counter() - wall,
    }
    return tr


@contextmanager
def instance_at(
    scene: Scene,
    law: str,
    time: float = 0.0,
    *,
    parameters: dict[str, Any] | None = None,
    rtol: float | None = None,
) -> Iterator[Any]:
    """A model-exchange instance (fmpy's FMU2Model) in continuous-time mode at `time`: after
    the event iteration at the scene's start, and for `time` > 0 after a run to `time` as
    `simulate_me` computes it, so that its states, its contact mode and the onset rate the
    contact damping uses (docs/model.md §10.4) are those of that run. A failed FMI call inside
    the block is a SimulationError naming the call."""
    from fmpy.fmi1 import FMICallException

    if law != "none":  # the flexure alone is a model too
        check_law(law)
    rtol = scene.integrator.rtol if rtol is None else rtol
    fmu, log = _instantiate()
    run: _MeRun | None = None
    try:
        _initialize(fmu, scene, law, rtol, max(time, scene.stop_time), parameters)
        if time > 0.0:
            run = _MeRun(fmu, law, rtol, time, np.empty(0), 0, MAX_ME_STEPS)
            run.integrate(None)
        else:
            _event_iteration(fmu)
            fmu.enterContinuousTimeMode()
        yield fmu
    except FMICallException as exc:
        t = run.t if run is not None else 0.0
        raise fmu_error(law, t, exc.function or type(exc).__name__, log.reason(str(exc))) from None
    finally:
        if run is not None:
            run.solver.close()
        fmu.freeInstance()
