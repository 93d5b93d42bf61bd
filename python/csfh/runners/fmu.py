"""Running the FMU: model exchange with fmpy's CVode, and co-simulation through fmi2DoStep.

The model-exchange driver is fmpy's FMU2Model with fmpy's bundled CVODE (BDF, dense direct solver,
root finding on the event indicator), stepped one internal step at a time so that every step can be
counted and recorded (the paper's "vs step" figures), outputs are interpolated onto the requested
output grid with CVODE's dense output, and fmpy's limit of 500 internal steps per output interval
does not apply. Contact onsets are recorded at the located event instants."""

from __future__ import annotations

import atexit
import ctypes
import math
import os
import shutil
import tempfile
import time
from ctypes import byref, c_int, c_long, c_void_p, cast
from functools import cache
from typing import Any

import fmpy
import numpy as np
from fmpy import extract
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.model_description import ModelDescription

from ..errors import SimulationError
from ..model import model_info
from ..model._csfh_variables import MAX_ME_STEPS
from ..model.fmus import FmuLog
from ..model.scene import MAX_OUTPUT_SAMPLES, Scene
from ..paths import fmu_path
from ..progress import Progress
from ..trajectory import CONTACT_FIELDS, Trajectory
from . import cs_steps
from .direct_calls import DirectCalls

STATE_NAMES = model_info.STATE_NAMES
OUTPUT_NAMES = {  # table column -> FMU variable
    "x": "body1.x",
    "y": "body1.y",
    "theta": "body1.theta",
    "vx": "body1.vx",
    "vy": "body1.vy",
    "omega": "body1.omega",
    "F_N": "contact.F_N",
    "F_T": "contact.F_T",
    "indentation": "contact.indentation",
    "v_T": "contact.v_T",
    "gap": "contact.gap",
    "energy": "energy.total",
}


CS_OUTPUT_NAMES = {  # co-simulation only: the peaks over each communication step, stresses
    "F_N_peak": "contact.F_N_peak",
    "F_T_peak": "contact.F_T_peak",
    "indentation_peak": "contact.indentation_peak",
    "stress": "flexure.stress_max",
    "stress_peak": "flexure.stress_max_peak",
    "pressure": "contact.pressure_max",
    "pressure_peak": "contact.pressure_max_peak",
    "a_frame_x": "a_frame[1]",
    "a_frame_y": "a_frame[2]",
}
"""Extra columns of a co-simulation table: the peaks over the communication step that ends at
each row (located on CVODE's interpolant; at t = 0 the values there), the flexure stress and its
peak (tracked inside the step only with flexure.track_stress_peak), the Hertz pressure and its
peak, and the frame's acceleration (a_base plus the shock pulse)."""
model_info.require(OUTPUT_NAMES.values(), "runners.fmu.OUTPUT_NAMES")
model_info.require(CS_OUTPUT_NAMES.values(), "runners.fmu.CS_OUTPUT_NAMES")


@cache
def unzipped_fmu() -> str:
    """The directory of the unzipped csfh.fmu (once per process, removed at exit)."""
    directory = tempfile.mkdtemp(prefix="csfh-fmu-")
    atexit.register(shutil.rmtree, directory, True)
    return extract(str(fmu_path()), unzipdir=directory)


def _vr(name: str) -> int:
    return model_info.variables()[name].valueReference


def start_values(
    scene: Scene, law: str | None, extra: dict[str, Any] | None = None
) -> list[tuple[str, str, float | int | bool]]:
    """Every value a run sets in initialization mode, in the order it sets them: (name, FMI type
    as set: Real | Integer | Boolean, value). The parameters of the scene and law, the overrides,
    the start state, the inputs. The single runs and the batch master (csfh.runners.cs_batch)
    both take their values from here."""
    values: dict[str, Any] = dict(scene.parameter_values(law))
    if extra:
        values.update({k: model_info.coerce(k, v) for k, v in extra.items()})
    values.update(dict(zip(STATE_NAMES, scene.x0, strict=True)))
    values.update(scene.inputs)
    variables = model_info.variables()
    out: list[tuple[str, str, float | int | bool]] = []
    for name, value in values.items():
        kind = variables[name].type
        if kind == "Real":
            out.append((name, "Real", float(value)))
        elif kind == "Boolean":
            out.append((name, "Boolean", bool(value)))
        else:
            out.append((name, "Integer", int(value)))
    return out


def _apply_start_values(
    fmu: FMU2Model | FMU2Slave, scene: Scene, law: str | None, extra: dict[str, Any] | None = None
) -> None:
    for name, kind, value in start_values(scene, law, extra):
        if kind == "Real":
            fmu.setReal([_vr(name)], [value])
        elif kind == "Boolean":
            fmu.setBoolean([_vr(name)], [value])
        else:
            fmu.setInteger([_vr(name)], [value])


@cache
def _resident_binary(unzip_dir: str, model_identifier: str) -> ctypes.CDLL:
    """The FMU's binary, loaded once per process and kept loaded. fmpy loads the binary for each
    instance and unloads it at fmi2FreeInstance; with this reference held, its unload only drops
    a count, so the next run does not map, relocate and bind the library again, and starts with
    its pages mapped (benchmarks/bench_event_vs_rk4.py). The FMU keeps no state outside its
    instances, so instances of consecutive runs share nothing through it."""
    name = model_identifier + fmpy.sharedLibraryExtension
    return ctypes.CDLL(os.path.join(unzip_dir, "binaries", fmpy.platform, name))


def _instantiate(cls: type, md: ModelDescription, kind: str) -> FMU2Model | FMU2Slave:
    """An instance whose log keeps the FMU's error messages (`_fmu_error` reports them), instead
    of fmpy's default logger printing them on standard output."""
    interface = md.modelExchange if kind == "ME" else md.coSimulation
    _resident_binary(unzipped_fmu(), interface.modelIdentifier)
    fmu = cls(
        guid=md.guid,
        unzipDirectory=unzipped_fmu(),
        modelIdentifier=interface.modelIdentifier,
        instanceName="csfh",
    )
    log = FmuLog()
    fmu.instantiate(callbacks=log.callbacks)
    fmu._csfh_log = log  # the callbacks live as long as the instance
    return fmu


def _fmu_error(
    fmu: FMU2Model | FMU2Slave, law: str, t: float, exc: BaseException
) -> SimulationError:
    """One line for a failed FMI call: the model, the time, the call and the FMU's own reason."""
    log: FmuLog | None = getattr(fmu, "_csfh_log", None)
    reason = log.reason(str(exc)) if log is not None else str(exc)
    call = getattr(exc, "function", None) or type(exc).__name__
    return SimulationError(f"{law}: {call} failed at t = {t:.9g} s: {reason}")


def check_rows(t_end: float, step: float, what: str) -> int:
    """The number of output rows of a run on a grid of `step` up to `t_end`, within the limit of
    a scene (csfh.model.scene.MAX_OUTPUT_SAMPLES); ValueError naming the values otherwise."""
    for name, value in (("stop_time", t_end), (what, step)):
        if not (value > 0 and math.isfinite(value)):
            raise ValueError(f"{name} = {value!r} must be a finite number > 0")
    if not t_end / step <= MAX_OUTPUT_SAMPLES:
        raise ValueError(
            f"{what} = {step:g} s gives {t_end / step:.3g} output rows over {t_end:g} s; at most "
            f"{MAX_OUTPUT_SAMPLES:g}"
        )
    return math.ceil(t_end / step - 1e-9)


class _Table:
    """Growing column storage for output rows."""

    def __init__(self, names: tuple[str, ...]) -> None:
        self.names = names
        self.rows: list[list[float]] = []
        self._blocks: list[np.ndarray] = []  # earlier rows, as arrays

    def add(self, row: list[float]) -> None:
        self.rows.append(row)

    def add_block(self, block: np.ndarray) -> None:
        """Rows as a 2-D array (after those added before)."""
        if self.rows:
            self._blocks.append(self._rows_array())
            self.rows = []
        self._blocks.append(np.asarray(block, dtype=float).reshape(-1, len(self.names)))

    def _rows_array(self) -> np.ndarray:
        return np.array(self.rows, dtype=float).reshape(-1, len(self.names))

    def arrays(self) -> dict[str, np.ndarray]:
        data = np.concatenate([*self._blocks, self._rows_array()])
        return {n: data[:, i].copy() for i, n in enumerate(self.names)}


_TABLE_COLUMNS = ("t", *OUTPUT_NAMES)


def _one_step_solver(fmu: FMU2Model, rtol: float, t0: float):
    """fmpy's CVodeSolver, plus one-step mode, dense output and statistics from the same CVODE."""
    from fmpy.sundials import CVodeSolver
    from fmpy.sundials.cvode import sundials_cvode
    from fmpy.sundials.nvector_serial import NV_DATA_S, N_VNew_Serial
    from fmpy.sundials.sundials_types import sunrealtype

    class _NoInput:
        def apply(self, t: float, **_: Any) -> None:
            return None

    class _Solver(CVodeSolver):
        """fmpy's solver, whose right-hand side and root function return -1 (CVODE then stops
        with a failure flag) instead of raising inside the ctypes callback, where the exception
        would be printed and lost; the first exception is kept in `callback_error`."""

        callback_error: BaseException | None = None

        def f(self, t: float, y: Any, ydot: Any, user_data: Any) -> int:
            try:
                return int(super().f(t, y, ydot, user_data))
            except Exception as exc:  # reported by the caller
                self.callback_error = self.callback_error or exc
                return -1

        def g(self, t: float, y: Any, gout: Any, user_data: Any) -> int:
            try:
                return int(super().g(t, y, gout, user_data))
            except Exception as exc:  # reported by the caller
                self.callback_error = self.callback_error or exc
                return -1

    solver = _Solver(
        nx=6,
        nz=1,
        get_x=fmu.getContinuousStates,
        set_x=fmu.setContinuousStates,
        get_dx=fmu.getDerivatives,
        get_z=fmu.getEventIndicators,
        get_nominals=fmu.getNominalsOfContinuousStates,
        set_time=fmu.setTime,
        input=_NoInput(),
        startTime=t0,
        relativeTolerance=rtol,
        maxNumSteps=100000,
    )
    # only fmpy's handler, which keeps CVODE's message for the error we raise: SUNDIALS's default
    # handler would also print it on standard error
    clear, push = (
        sundials_cvode.SUNContext_ClearErrHandlers,
        sundials_cvode.SUNContext_PushErrHandler,
    )
    clear.argtypes, clear.restype = [c_void_p], c_int
    push.argtypes, push.restype = [c_void_p, c_void_p, c_void_p], c_int
    if clear(solver.sunctx) != 0 or push(solver.sunctx, cast(solver.ehfun_, c_void_p), None) != 0:
        raise SimulationError("CVODE: cannot install the error handler")
    api = {}
    for name, args in {
        "CVodeSetStopTime": [c_void_p, sunrealtype],
        "CVodeGetDky": [c_void_p, sunrealtype, c_int, c_void_p],
        "CVodeGetNumSteps": [c_void_p, c_void_p],
        "CVodeGetNumRhsEvals": [c_void_p, c_void_p],
    }.items():
        fn = getattr(sundials_cvode, name)
        fn.argtypes = args
        fn.restype = c_int
        api[name] = fn
    dky = N_VNew_Serial(6, solver.sunctx)
    return solver, api, dky, NV_DATA_S(dky), sunrealtype


def _contact_arrays(records: list[list[float]]) -> dict[str, np.ndarray]:
    data = np.array(records, dtype=float).reshape(-1, len(CONTACT_FIELDS))
    return {name: data[:, i].copy() for i, name in enumerate(CONTACT_FIELDS)}


def _evaluations(fmu: FMU2Model | FMU2Slave) -> dict[str, int]:
    """The FMU's evaluation counters: how often each part of the physics ran."""
    parts = ("rhs", "flexure", "contact", "friction")
    values = fmu.getInteger([_vr(f"diagnostics.{p}_evaluations") for p in parts])
    return dict(zip(parts, (int(v) for v in values), strict=True))


def _event_iteration(fmu: FMU2Model) -> float:
    """The event iteration; returns the next time event the FMU reports (inf: none)."""
    more = True
    next_event = math.inf
    while more:
        more, terminate, _, _, defined, next_time = fmu.newDiscreteStates()
        if terminate:
            raise SimulationError("the FMU requested termination")
        next_event = float(next_time) if defined else math.inf
    return next_event


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
    """Model exchange of the FMU with contact law `law`, CVode (BDF) via fmpy, events located by
    root finding on the gap. Returns the output table (the grid k * output_interval, or the given
    increasing `output_times`, plus the event instants), per-step records (the first
    `max_step_records` steps), per-contact records (peaks located on CVODE's interpolant) and
    statistics. More than `max_steps` CVODE steps (the budget: minutes of Python) raise
    SimulationError, so that no input makes the run hang."""
    if law not in model_info.LAWS:
        raise ValueError(f"law {law!r} is not an event-driven law ({', '.join(model_info.LAWS)})")
    from fmpy.sundials.cvode import CV_ROOT_RETURN, CVode

    CV_ONE_STEP = 2  # cvode.h (fmpy's binding leaves it commented out)
    CV_TSTOP_RETURN = 1  # cvode.h

    rtol = scene.integrator.rtol if rtol is None else rtol
    dt_out = scene.integrator.output_interval if output_interval is None else output_interval
    t_end = scene.stop_time if stop_time is None else stop_time
    md = model_info.model_description()
    out_vrs = [_vr(n) for n in OUTPUT_NAMES.values()]
    count_vr = _vr("contact.count")
    active_vr = _vr("contact.active")
    onset_vr = _vr("contact.onset_speed")
    rate_vr = _vr("contact.indentation_rate")
    ind_vr = _vr("contact.indentation")
    rhs_vr = _vr("diagnostics.rhs_evaluations")

    wall = time.perf_counter()
    fmu = _instantiate(FMU2Model, md, "ME")
    t = 0.0
    try:
        fmu.setupExperiment(tolerance=rtol, startTime=0.0, stopTime=t_end)
        fmu.enterInitializationMode()
        _apply_start_values(fmu, scene, law, parameters)
        fmu.exitInitializationMode()
        t_event = _event_iteration(fmu)  # time events: the ends of a shock pulse
        fmu.enterContinuousTimeMode()

        table = _Table(_TABLE_COLUMNS)
        steps = _Table(_TABLE_COLUMNS)
        contacts: list[float] = []
        releases: list[float] = []
        n_contacts = fmu.getInteger([count_vr])[0]
        if n_contacts:
            contacts.append(0.0)
        table.add([0.0, *fmu.getReal(out_vrs)])

        solver, api, dky, dky_data, realtype = _one_step_solver(fmu, rtol, 0.0)
        peak_vrs = [_vr("contact.F_N"), ind_vr]
        i_F, i_ind = list(OUTPUT_NAMES).index("F_N"), list(OUTPUT_NAMES).index("indentation")
        in_contact = bool(fmu.getBoolean([active_vr])[0])
        records: list[list[float]] = []
        if in_contact:
            records.append([0.0, fmu.getReal([onset_vr])[0], math.nan, math.nan, 0.0, 0.0])
        prev_peak_values = tuple(fmu.getReal(peak_vrs))

        def interpolated(tq: float, vrs: list[int]) -> list[float]:
            """Outputs at tq inside the last step, from CVODE's interpolant."""
            api["CVodeGetDky"](solver.cvode_mem, tq, 0, dky)
            fmu.setTime(tq)
            fmu.setContinuousStates(dky_data, 6)
            return fmu.getReal(vrs)

        def refine_peaks(rec: list[float], ta: float, tb: float, at_a: tuple[float, float]) -> None:
            """Largest F_N and indentation over the step [ta, tb] on CVODE's interpolant: the
            step is cut into eight parts; the values at their ends count, and in every part where
            the time derivative (a centred difference of the interpolant, one-sided at the step
            ends) changes sign from + to - (or to 0), its root is found by bisection and the value
            there counts (a contact step can hold more than one hump, e.g. in stick-slip)."""
            if not tb - ta > 1e-13 * max(1.0, abs(tb)):
                return
            eps = 1e-7 * (tb - ta)

            def slope(tq: float, j: int) -> float:
                step = max(eps, 8 * math.ulp(tq))
                lo, hi = max(ta, tq - step), min(tb, tq + step)
                if not hi > lo:
                    return 0.0
                return (interpolated(hi, peak_vrs)[j] - interpolated(lo, peak_vrs)[j]) / (hi - lo)

            ts = [ta + (tb - ta) * k / 8 for k in range(9)]
            samples = [interpolated(tk, peak_vrs) for tk in ts]
            for col, j in ((4, 0), (5, 1)):
                peak = max(at_a[j], *(v[j] for v in samples))
                slopes = [slope(tk, j) for tk in ts]
                for k in range(8):
                    # a zero difference (the hump right at a sample) ends the part before it
                    if not (slopes[k] > 0 and slopes[k + 1] <= 0):
                        continue
                    lo, hi = ts[k], ts[k + 1]
                    while hi - lo > 1e-14 * max(1.0, abs(hi)):
                        mid = 0.5 * (lo + hi)
                        if mid <= lo or mid >= hi:
                            break
                        lo, hi = (mid, hi) if slope(mid, j) > 0 else (lo, mid)
                    peak = max(peak, interpolated(0.5 * (lo + hi), peak_vrs)[j])
                rec[col] = max(rec[col], peak)

        api["CVodeSetStopTime"](solver.cvode_mem, min(t_end, t_event))
        t = 0.0
        if output_times is None:
            check_rows(t_end, dt_out, "output_interval")
            grid = np.arange(1, math.floor(t_end / dt_out * (1 + 1e-12)) + 1) * dt_out
        else:
            grid = np.asarray(output_times, dtype=float)
            grid = grid[(grid > 0) & (grid <= t_end * (1 + 1e-12))]
        i_out = 0
        n_steps_total = 0
        n_calls = 0
        n_events = 0
        tret = realtype(0.0)
        nst = c_long(0)
        while t < t_end * (1 - 1e-15):
            flag = CVode(solver.cvode_mem, t_end, solver.x, byref(tret), CV_ONE_STEP)
            if solver.callback_error is not None:
                raise _fmu_error(fmu, law, t, solver.callback_error)
            if flag < 0:
                info = solver.error_info or ("?", "?", "?", "no message")
                raise SimulationError(
                    f"{law}: CVode failed at t = {t:.9g} s (flag {flag}): {info[3]}"
                )
            t_new = tret.value
            n_calls += 1  # one CVODE step per call (CV_ONE_STEP)
            if n_calls > max_steps:
                raise SimulationError(
                    f"{law}: more than {max_steps} CVODE steps (the step budget) by t = "
                    f"{t_new:.9g} s of {t_end:g} s"
                )
            # outputs on the regular grid inside the step, from CVODE's interpolant
            while i_out < len(grid) and grid[i_out] <= t_new * (1 + 1e-14):
                table.add([float(grid[i_out]), *interpolated(float(grid[i_out]), out_vrs)])
                i_out += 1
            if in_contact and records:
                refine_peaks(records[-1], t, t_new, prev_peak_values)
            fmu.setTime(t_new)
            fmu.setContinuousStates(solver.px, 6)
            api["CVodeGetNumSteps"](solver.cvode_mem, byref(nst))
            row = [t_new, *fmu.getReal(out_vrs)]
            prev_peak_values = (row[1 + i_F], row[1 + i_ind])
            if len(steps.rows) < max_step_records:
                steps.add(row)
            t = t_new
            if flag == CV_ROOT_RETURN:
                n_events += 1
                table.add(row)  # the event instant itself (left limit)
                fmu.enterEventMode()
                t_event = _event_iteration(fmu)
                fmu.enterContinuousTimeMode()
                count = fmu.getInteger([count_vr])[0]
                if count > n_contacts:
                    contacts.append(t)
                    n_contacts = count
                    in_contact = True
                    records.append([t, fmu.getReal([onset_vr])[0], math.nan, math.nan, 0.0, 0.0])
                    prev_peak_values = tuple(fmu.getReal([_vr("contact.F_N"), ind_vr]))
                elif not fmu.getBoolean([active_vr])[0]:
                    releases.append(t)
                    in_contact = False
                    if records:
                        records[-1][2] = t
                        records[-1][3] = -fmu.getReal([rate_vr])[0]
                n_steps_total += nst.value  # CVodeReInit restarts the count
                solver.reset(t)
                api["CVodeSetStopTime"](solver.cvode_mem, min(t_end, t_event))
            elif flag == CV_TSTOP_RETURN and t < t_end * (1 - 1e-15):
                # a time event (the start or end of a shock pulse, where the right-hand side has
                # a kink): CVODE stopped exactly there; restart it
                fmu.enterEventMode()
                t_event = _event_iteration(fmu)
                fmu.enterContinuousTimeMode()
                n_steps_total += nst.value
                solver.reset(t)
                api["CVodeSetStopTime"](solver.cvode_mem, min(t_end, t_event))
            if progress is not None:
                progress.update(t / t_end)
        api["CVodeGetNumSteps"](solver.cvode_mem, byref(nst))
        n_steps_total += nst.value
        rhs = fmu.getInteger([rhs_vr])[0]
        evaluations = _evaluations(fmu)
        fmu.terminate()
    except FMICallException as exc:
        raise _fmu_error(fmu, law, t, exc) from None
    finally:
        fmu.freeInstance()
    tr = Trajectory(
        model=law,
        scene=scene.name,
        table=table.arrays(),
        contacts=np.array(contacts),
        steps=steps.arrays(),
        releases=np.array(releases),
        contact_records=_contact_arrays(records),
    )
    tr.stats = {
        "integrator": f"CVode BDF (fmpy, model exchange) rtol={rtol:g}",
        "steps": int(n_steps_total),
        "rhs_evaluations": int(rhs),
        "events": n_events,
        "evaluations": evaluations,
        "wall_time": time.perf_counter() - wall,
    }
    return tr


CS_STEPS_CHUNK = (256, 4096)
"""The communication steps per C call of simulate_cs's loop: about 1 % of the run (for the
progress shown between calls), at least the first number and at most the second."""


def chunk_size(n: int) -> int:
    """Steps per C call for a run of n communication steps (CS_STEPS_CHUNK)."""
    lo, hi = CS_STEPS_CHUNK
    return max(1, min(hi, max(lo, math.ceil(n / 100))))


def _contact_bookkeeping(
    records: list[list[float]],
    count: int,
    active: bool,
    counts: np.ndarray,
    actives: np.ndarray,
    events: np.ndarray,
) -> tuple[int, bool]:
    """simulate_cs's contact records over a chunk of communication points (counts, active flags
    and the event variables onset time and speed, release time and speed, one row per point),
    after the state (count, active) of the point before; returns the state after. The FMU
    reports the located event times of the last onset and release; contacts that begin and end
    inside one communication step show only their last values."""
    if not len(counts):
        return count, active
    previous_counts = np.concatenate([[count], counts[:-1]])
    previous_actives = np.concatenate([[active], actives[:-1]])
    onset = counts > previous_counts
    # only where a contact begins or ends does anything happen
    for i in np.flatnonzero(onset | (previous_actives & ~actives)):
        t_on, v_on, t_off, v_off = (float(x) for x in events[i])
        if onset[i]:
            records.append([t_on, v_on, math.nan, math.nan, math.nan, math.nan])
        if records and not actives[i]:
            records[-1][2:4] = [t_off, v_off]
    return int(counts[-1]), bool(actives[-1])


def cs_method_name(scene: Scene, parameters: dict[str, Any] | None = None) -> str:
    """The co-simulation method a run uses (solver.method: from the overrides, the scene, or the
    FMU's start value)."""
    values = {**scene.parameter_values(), **(parameters or {})}
    start = model_info.variables()["solver.method"].start
    value = model_info.coerce("solver.method", values.get("solver.method", start))
    names = {v: k for k, v in model_info.enumeration("SolverMethod").items()}
    return names.get(int(value), str(value))


def simulate_cs(
    scene: Scene,
    law: str,
    *,
    rtol: float | None = None,
    communication_step: float | None = None,
    stop_time: float | None = None,
    parameters: dict[str, Any] | None = None,
    progress: Progress | None = None,
    step_loop: str | None = None,
) -> Trajectory:
    """Co-simulation of the FMU (its own integrator, solver.method): one output row per
    communication step.

    The communication loop (fmi2DoStep, then reading the outputs and the contact events) runs in
    C, a chunk of steps per call (`csfh.runners.cs_steps`, in libcsfh_batch.so), or, with
    step_loop="python" or without that library, in Python with one ctypes call per FMI call;
    the results are the same, bitwise. stats["do_step_time"] is the wall time of the loop's FMI
    calls: in C the time inside the chunk calls, which includes reading the outputs; in Python
    the time of the fmi2DoStep calls alone."""
    if step_loop not in (None, "c", "python"):
        raise ValueError(f"step_loop = {step_loop!r}: 'c', 'python' or None")
    if law not in model_info.LAWS:
        raise ValueError(f"law {law!r} is not an event-driven law ({', '.join(model_info.LAWS)})")
    rtol = scene.integrator.rtol if rtol is None else rtol
    h = scene.integrator.output_interval if communication_step is None else communication_step
    t_end = scene.stop_time if stop_time is None else stop_time
    md = model_info.model_description()
    out_vrs = [_vr(n) for n in (*OUTPUT_NAMES.values(), *CS_OUTPUT_NAMES.values())]
    count_vr = _vr("contact.count")
    active_vr = _vr("contact.active")
    wall = time.perf_counter()
    fmu = _instantiate(FMU2Slave, md, "CS")
    t = 0.0
    try:
        fmu.setupExperiment(tolerance=rtol, startTime=0.0, stopTime=t_end)
        fmu.enterInitializationMode()
        _apply_start_values(fmu, scene, law, parameters)
        fmu.exitInitializationMode()
        table = _Table((*_TABLE_COLUMNS, *CS_OUTPUT_NAMES))
        table.add([0.0, *fmu.getReal(out_vrs)])
        n = check_rows(t_end, h, "communication_step")
        event_vrs = [
            _vr(n)
            for n in (
                "contact.onset_time",
                "contact.onset_speed",
                "contact.release_time",
                "contact.release_speed",
            )
        ]
        count, active = fmu.getInteger([count_vr])[0], bool(fmu.getBoolean([active_vr])[0])
        records: list[list[float]] = []
        if count:
            records.append(
                [0.0, fmu.getReal([event_vrs[1]])[0], math.nan, math.nan, math.nan, math.nan]
            )
        t = 0.0
        do_step_time = 0.0
        use_c = (step_loop or ("c" if cs_steps.available() else "python")) == "c"
        if use_c:
            # the loop in C, a chunk of steps per call (csfh.runners.cs_steps): Python's cost per
            # communication point (~1.5 us of ctypes calls and cold caches) would be more than
            # the FMU's own work on a fine grid; the contact bookkeeping over the returned arrays
            loop = cs_steps.CSteps(fmu, h, t_end, [*out_vrs, *event_vrs], [count_vr], [active_vr])
            n_out = len(out_vrs)
            size = chunk_size(n)
            rows: list[np.ndarray] = []
            for k in range(0, n, size):
                try:
                    chunk = loop.run(k, min(k + size, n), t)
                except FMICallException as exc:
                    t = exc.t
                    raise
                do_step_time += chunk.seconds
                t = float(chunk.times[-1])
                rows.append(np.column_stack([chunk.times, chunk.reals[:, :n_out]]))
                count, active = _contact_bookkeeping(
                    records,
                    count,
                    active,
                    chunk.integers[:, 0],
                    chunk.booleans[:, 0] != 0,
                    chunk.reals[:, n_out:],
                )
                if progress is not None:
                    progress.update(t / t_end)
            table.add_block(np.concatenate(rows))
        else:
            # the loop calls the FMU directly (fmpy's wrappers would cost more than the FMU's
            # own work on a fine communication grid)
            direct = DirectCalls(fmu)
            read_reals = direct.real_reader([*out_vrs, *event_vrs])
            read_count = direct.integer_reader([count_vr])
            read_active = direct.boolean_reader([active_vr])
            n_out = len(out_vrs)
            for k in range(n):
                t_next = min((k + 1) * h, t_end)
                t0 = time.perf_counter()
                direct.do_step(t, t_next - t)
                do_step_time += time.perf_counter() - t0
                t = t_next
                values = read_reals()
                table.add([t, *values[:n_out]])
                # the FMU reports the located event times of the last onset and release;
                # contacts that begin and end inside one communication step show only their
                # last values
                new_count, new_active = read_count()[0], bool(read_active()[0])
                t_on, v_on, t_off, v_off = values[n_out:]
                if new_count > count:
                    records.append([t_on, v_on, math.nan, math.nan, math.nan, math.nan])
                if records and not new_active and (new_count > count or active):
                    records[-1][2:4] = [t_off, v_off]
                count, active = new_count, new_active
                if progress is not None:
                    progress.update(t / t_end)
        steps, rhs = fmu.getInteger(
            [_vr("diagnostics.integrator_steps"), _vr("diagnostics.rhs_evaluations")]
        )
        evaluations = _evaluations(fmu)
        final_count = count
        fmu.terminate()
    except FMICallException as exc:
        raise _fmu_error(fmu, law, t, exc) from None
    finally:
        fmu.freeInstance()
    cr = _contact_arrays(records)
    tr = Trajectory(
        model=law,
        scene=scene.name,
        table=table.arrays(),
        contacts=cr["t_onset"],
        releases=cr["t_release"][np.isfinite(cr["t_release"])],
        contact_records=cr,
    )
    tr.stats = {
        "integrator": f"{cs_method_name(scene, parameters)} inside the FMU "
        f"(co-simulation) rtol={rtol:g}, communication step {h:g} s",
        "steps": int(steps),
        "rhs_evaluations": int(rhs),
        "evaluations": evaluations,
        "contact_count": int(final_count),
        "wall_time": time.perf_counter() - wall,
        "do_step_time": do_step_time,
    }
    return tr
