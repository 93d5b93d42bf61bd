"""Co-simulation of the CSFH FMU with the comb-drive actuator FMU (`combdrive.fmu`), in two
engines: a master loop over fmpy's FMU2Slave, and libcosim (the Open Simulation Platform engine,
through libcosimpy).

The coupling (the same in both engines):

    V(t) (voltage ramp of the scene)  -> combdrive.V
    combdrive.F_x                     -> csfh.F_ext[1]
    combdrive.F_y                     -> csfh.F_ext[2]
    combdrive.M                       -> csfh.M_ext          (moment = true)
    csfh.body1.theta                  -> combdrive.theta     (moment = true)

Ordering. Both FMUs advance with a fixed communication step h; inputs are held constant over a
step (zero-order hold; the csfh FMU restarts CVODE when an input changes).

* Jacobi (default): every FMU steps from t_k to t_k+1 with the inputs it holds at t_k; outputs are
  exchanged after all have stepped. This is libcosim's fixed-step algorithm, so the two engines
  compute the same thing and agree to round-off (tests/python/test_cosim.py). The actuator is
  algebraic (direct feedthrough), so the hinge sees during [t_k, t_k+1] the force of V(t_k-1),
  theta(t_k-1): one communication step of delay.
* Gauss-Seidel (fmpy engine only): at t_k the actuator is evaluated first, with V(t_k) and the
  current theta(t_k), and its force acts on the hinge over the same step: no delay. There is no
  algebraic loop to solve: theta is a state of the hinge (no direct feedthrough).

The voltage is set by the master before each step (libcosim: an override manipulator), V(t_k).

Scene section (all keys optional except the voltage ramp):

    [cosim]
    engine = "fmpy"              # or "libcosimpy"
    step = 1e-4                  # s, communication step (libcosimpy: a whole number of ns)
    ordering = "jacobi"          # fmpy engine: "jacobi" (as libcosim) or "gauss-seidel"
    tolerance = 1e-6             # relative tolerance of CVODE inside the csfh FMU (fmpy engine;
                                 # libcosim sets none, so the FMU's default 1e-6 applies)
    moment = true                # connect M -> M_ext and body1.theta -> theta

    [cosim.actuator]             # comb-drive parameters by FMU name (combdrive.toml)
    fingers = 20000
    gap = 5e-6                   # m
    thickness = 0.025            # m
    permittivity = 8.8541878128e-12   # F/m
    direction = 1.5707963267948966    # rad, global frame (+Y)
    "arm[1]" = 0.0               # m, application point relative to G1, body frame
    "arm[2]" = 0.0

    [cosim.voltage]              # V0 until t0, linear to V1 at t1, V1 afterwards
    V0 = 0.0                     # V
    V1 = 500.0                   # V
    t0 = 0.0                     # s
    t1 = 0.5                     # s

The rest of the scene (initial state, parts, parameters, stop_time, preset) sets up the hinge as
for every other command; its contact law is the scene's (the FMU default LN_spheres unless
[parameters] sets contact.law; the libcosimpy engine sets its Integer twin contact.law_number).
libcosim (libcosimpy 0.0.6) ignores FMI 2.0 Enumeration
variables, so with that engine an enumeration can only keep its FMU start value.
"""

from __future__ import annotations

import atexit
import math
import shutil
import tempfile
import time
from collections.abc import Callable
from ctypes import byref
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from .fmu_runner import OUTPUT_NAMES, SimulationError
from .progress import Progress
from .results import Trajectory
from .scene import Scene, SceneError

ENGINES = ("fmpy", "libcosimpy")
ORDERINGS = ("jacobi", "gauss-seidel")
DEFAULT_TOLERANCE = 1e-6
"""The csfh FMU's relative tolerance when fmi2SetupExperiment gives none (FMU_DEFAULT_TOLERANCE)."""

CONNECTIONS = (("F_x", "F_ext[1]"), ("F_y", "F_ext[2]"), ("M", "M_ext"))
"""(actuator output, csfh input)."""
ACTUATOR_COLUMNS = {"F": "F_act", "F_x": "F_x", "F_y": "F_y", "M": "M"}
"""Actuator output -> column of the result table."""
COSIM_UNITS = {"V": "V", "F_act": "N", "F_x": "N", "F_y": "N", "M": "N m"}

_TOP_KEYS = {"engine", "step", "ordering", "tolerance", "moment", "actuator", "voltage"}
_RAMP_KEYS = {"V0", "V1", "t0", "t1"}


class CosimError(SimulationError):
    """The co-simulation failed; the message says which FMU or engine and why (the CLI reports it
    on one line, like every SimulationError)."""


# ------------------------------------------------------------------------------------------
# settings


@dataclass(frozen=True)
class VoltageRamp:
    """V0 until t0, linear to V1 at t1, V1 afterwards."""

    V0: float = 0.0
    V1: float = 0.0
    t0: float = 0.0
    t1: float = 0.0

    def __call__(self, t: float) -> float:
        if t <= self.t0:
            return self.V0
        if t >= self.t1:
            return self.V1
        return self.V0 + (self.V1 - self.V0) * (t - self.t0) / (self.t1 - self.t0)


@dataclass(frozen=True)
class CosimSettings:
    engine: str = "fmpy"
    step: float = 1e-4
    ordering: str = "jacobi"
    tolerance: float | None = None  # None: the FMU's default (1e-6)
    moment: bool = True
    actuator: dict[str, float | int] = field(default_factory=dict)
    voltage: VoltageRamp = field(default_factory=VoltageRamp)

    @property
    def step_ns(self) -> int:
        return round(self.step * 1e9)


def _number(where: str, value: Any, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise SceneError(f"{where} = {value!r} must be a finite number")
    if positive and not value > 0:
        raise SceneError(f"{where} = {value!r} must be > 0")
    return float(value)


def _keys(where: str, table: Any, allowed: set[str]) -> dict[str, Any]:
    if not isinstance(table, dict):
        raise SceneError(f"{where} must be a table")
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise SceneError(
            f"{where}: unknown key {unknown[0]!r} (allowed: {', '.join(sorted(allowed))})"
        )
    return table


def parse_cosim(table: dict[str, Any], inputs: dict[str, float] | None = None) -> CosimSettings:
    """Validate the [cosim] table of a scene (SceneError with a one-line message naming the key).
    `inputs`: the scene's constant [inputs], which must not drive the inputs the actuator
    drives."""
    _keys("[cosim]", table, _TOP_KEYS)
    engine = table.get("engine", "fmpy")
    if engine not in ENGINES:
        raise SceneError(f"cosim.engine = {engine!r} is not one of {', '.join(ENGINES)}")
    step = _number("cosim.step", table.get("step", 1e-4), positive=True)
    ordering = table.get("ordering", "jacobi")
    if ordering not in ORDERINGS:
        raise SceneError(f"cosim.ordering = {ordering!r} is not one of {', '.join(ORDERINGS)}")
    tolerance = table.get("tolerance")
    if tolerance is not None:
        tolerance = _number("cosim.tolerance", tolerance, positive=True)
        if tolerance >= 1:
            raise SceneError(f"cosim.tolerance = {tolerance} must be < 1")
    moment = table.get("moment", True)
    if not isinstance(moment, bool):
        raise SceneError(f"cosim.moment = {moment!r} must be true or false")
    if "voltage" not in table:
        raise SceneError("[cosim.voltage] is missing (keys V0, V1, t0, t1)")
    ramp = _keys("[cosim.voltage]", table["voltage"], _RAMP_KEYS)
    missing = sorted(_RAMP_KEYS - set(ramp))
    if missing:
        raise SceneError(f"[cosim.voltage]: key {missing[0]!r} is missing (V0, V1, t0, t1)")
    v = {k: _number(f"cosim.voltage.{k}", ramp[k]) for k in ("V0", "V1", "t0", "t1")}
    if v["t0"] < 0:
        raise SceneError(f"cosim.voltage.t0 = {v['t0']} must be >= 0")
    if not v["t1"] > v["t0"]:
        raise SceneError(f"cosim.voltage.t1 = {v['t1']} must be greater than t0 = {v['t0']}")
    actuator = _check_actuator(
        dict(_keys("[cosim.actuator]", table.get("actuator", {}), set(actuator_parameters())))
    )
    driven = {csfh_in for out, csfh_in in CONNECTIONS if moment or out != "M"}
    clash = sorted(driven & set(inputs or {}))
    if clash:
        raise SceneError(
            f"inputs.{clash[0]} is driven by the actuator in co-simulation: remove it from [inputs]"
        )
    settings = CosimSettings(
        engine=engine,
        step=step,
        ordering=ordering,
        tolerance=tolerance,
        moment=moment,
        actuator=actuator,
        voltage=VoltageRamp(**v),
    )
    _check_engine(settings)
    return settings


def _check_engine(s: CosimSettings) -> None:
    """What only one engine can do."""
    if s.engine != "libcosimpy":
        return
    if abs(s.step_ns - s.step * 1e9) > 1e-6 * s.step * 1e9 or s.step_ns < 1:
        raise SceneError(
            f"cosim.step = {s.step!r} s is not a whole number of nanoseconds (libcosimpy)"
        )
    if s.ordering != "jacobi":
        raise SceneError(
            f"cosim.ordering = {s.ordering!r}: libcosimpy's fixed-step algorithm is Jacobi"
        )
    if s.tolerance is not None and s.tolerance != DEFAULT_TOLERANCE:
        raise SceneError(
            f"cosim.tolerance = {s.tolerance!r}: libcosimpy calls fmi2SetupExperiment without a "
            f"tolerance, so the FMU uses its default {DEFAULT_TOLERANCE:g}; remove the key or use "
            'engine = "fmpy"'
        )


def cosim_settings(scene: Scene, **overrides: Any) -> CosimSettings:
    """The scene's [cosim] settings, with overrides (engine=..., step=..., ordering=...)."""
    if not scene.cosim:
        raise SceneError(f"{scene.source or scene.name}: the scene has no [cosim] section")
    table = dict(scene.cosim)
    table.update({k: v for k, v in overrides.items() if v is not None})
    try:
        return parse_cosim(table, scene.inputs)
    except SceneError as exc:
        raise SceneError(f"{scene.source or scene.name}: {exc}") from None


# ------------------------------------------------------------------------------------------
# FMUs through fmpy


@cache
def _unzipped(path: str) -> str:
    from fmpy import extract

    directory = tempfile.mkdtemp(prefix="csfh-cosim-")
    atexit.register(shutil.rmtree, directory, True)
    return extract(path, unzipdir=directory)


@cache
def _description(path: str) -> Any:
    from fmpy import read_model_description

    return read_model_description(path)


def _paths() -> tuple[str, str]:
    from ._paths import combdrive_fmu_path, fmu_path

    return str(fmu_path()), str(combdrive_fmu_path())


def actuator_parameters() -> dict[str, Any]:
    """The comb-drive FMU's parameters (name -> ModelVariable)."""
    md = _description(_paths()[1])
    return {v.name: v for v in md.modelVariables if v.causality == "parameter"}


class _Log:
    """FMI logger callbacks that keep the messages (for error reports)."""

    def __init__(self) -> None:
        from fmpy import calloc, free
        from fmpy.fmi2 import (
            fmi2CallbackAllocateMemoryTYPE,
            fmi2CallbackFreeMemoryTYPE,
            fmi2CallbackFunctions,
            fmi2CallbackLoggerTYPE,
        )
        from fmpy.logging import addLoggerProxy

        self.errors: list[str] = []
        self.callbacks = fmi2CallbackFunctions()
        self._logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.logger = self._logger
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(self.callbacks))

    def _log(self, env: object, instance: bytes, status: int, category: bytes, msg: bytes) -> None:
        if status >= 3:  # fmi2Error, fmi2Fatal
            self.errors.append(msg.decode(errors="replace"))


class _Slave:
    """One co-simulation FMU instance through fmpy, with typed set by name and error messages."""

    def __init__(self, path: str, name: str) -> None:
        from fmpy.fmi2 import FMU2Slave

        md = _description(path)
        self.name = name
        self.vars = {v.name: v for v in md.modelVariables}
        self.log = _Log()
        self.fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=_unzipped(path),
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate(callbacks=self.log.callbacks)

    def vr(self, name: str) -> int:
        return self.vars[name].valueReference

    def set(self, values: dict[str, Any]) -> None:
        for name, value in values.items():
            kind = self.vars[name].type
            if kind == "Real":
                self.fmu.setReal([self.vr(name)], [float(value)])
            elif kind == "Boolean":
                self.fmu.setBoolean([self.vr(name)], [bool(value)])
            else:
                self.fmu.setInteger([self.vr(name)], [int(value)])

    def error(self, exc: Exception) -> CosimError:
        detail = self.log.errors[-1] if self.log.errors else str(exc)
        return CosimError(f"{self.name}: {detail}")

    def free(self) -> None:
        try:
            self.fmu.freeInstance()
        except Exception:
            pass


def _check_actuator(values: dict[str, Any]) -> dict[str, float | int]:
    """Type-check the actuator parameters and let the comb-drive FMU validate them (ranges,
    finiteness): its own message becomes the scene error."""
    from fmpy.fmi1 import FMICallException

    params = actuator_parameters()
    out: dict[str, float | int] = {}
    for name, value in values.items():
        if params[name].type == "Integer":
            if isinstance(value, bool) or not isinstance(value, int):
                raise SceneError(f"cosim.actuator.{name} = {value!r} must be an integer")
            out[name] = value
        else:
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise SceneError(f"cosim.actuator.{name} = {value!r} must be a number")
            out[name] = float(value)
    slave = _Slave(_paths()[1], "combdrive")
    try:
        slave.fmu.setupExperiment(startTime=0.0)
        slave.fmu.enterInitializationMode()
        slave.set(out)
        slave.fmu.exitInitializationMode()
    except FMICallException as exc:
        detail = slave.log.errors[-1] if slave.log.errors else str(exc)
        detail = detail.split(": ", 1)[-1]  # drop the "fmi2SetReal: " prefix
        raise SceneError(f"cosim.actuator: {detail}") from None
    finally:
        slave.free()
    return out


def _csfh_start_values(scene: Scene) -> dict[str, Any]:
    """Parameters (preset, parts, overrides; the scene's contact law), initial state, inputs."""
    from .fmu_runner import STATE_NAMES

    values: dict[str, Any] = dict(scene.parameter_values(None))
    values.update(dict(zip(STATE_NAMES, scene.x0, strict=True)))
    values.update(scene.inputs)
    return values


# ------------------------------------------------------------------------------------------
# results


class _Rows:
    def __init__(self, names: tuple[str, ...]) -> None:
        self.names = names
        self.rows: list[list[float]] = []

    def arrays(self) -> dict[str, np.ndarray]:
        data = np.array(self.rows, dtype=float).reshape(-1, len(self.names))
        return {n: data[:, i].copy() for i, n in enumerate(self.names)}


COLUMNS = ("t", *OUTPUT_NAMES, "V", *ACTUATOR_COLUMNS.values())
"""Columns of a co-simulation table: the hinge's outputs at t, the voltage V(t) and the actuator
force acting on the hinge from t on (over the next communication step)."""


def _trajectory(
    scene: Scene,
    s: CosimSettings,
    table: dict[str, np.ndarray],
    counts: np.ndarray,
    stats: dict[str, Any],
) -> Trajectory:
    # onsets known to the communication step (the FMU locates them exactly inside the step)
    onsets = table["t"][1:][np.diff(counts) > 0] if len(counts) > 1 else np.zeros(0)
    model = f"cosim-{s.engine}" + ("" if s.engine == "libcosimpy" else f"-{s.ordering}")
    tr = Trajectory(model=model, scene=scene.name, table=table, contacts=onsets)
    tr.stats = {
        "integrator": f"CVODE inside the csfh FMU, rtol={s.tolerance or DEFAULT_TOLERANCE:g}"
        f"; {s.engine} master, {s.ordering}, communication step {s.step:g} s",
        **stats,
    }
    return tr


def write_csv(tr: Trajectory, path: Path) -> Path:
    """The co-simulation table as CSV, units in the header."""
    from .results import UNITS

    names = list(tr.table)
    units = {**UNITS, **COSIM_UNITS}
    header = ",".join(f"{n} [{units.get(n, '-')}]" for n in names)
    data = np.column_stack([tr.table[n] for n in names])
    np.savetxt(path, data, delimiter=",", header=header, comments="", fmt="%.10g")
    return path


# ------------------------------------------------------------------------------------------
# the fmpy master loop


def run_fmpy(
    scene: Scene,
    settings: CosimSettings,
    *,
    stop_time: float | None = None,
    progress: Progress | None = None,
) -> Trajectory:
    """Fixed-step master loop over fmpy's FMU2Slave (ordering from the settings)."""
    from fmpy.fmi1 import FMICallException

    s = settings
    t_end = scene.stop_time if stop_time is None else stop_time
    n = max(1, round(t_end / s.step))
    h = s.step
    csfh_path, act_path = _paths()
    wall = time.perf_counter()
    c = _Slave(csfh_path, "csfh")
    a = _Slave(act_path, "combdrive")
    current = c
    try:
        c.fmu.setupExperiment(tolerance=s.tolerance, startTime=0.0, stopTime=t_end)
        a.fmu.setupExperiment(startTime=0.0, stopTime=t_end)
        c.fmu.enterInitializationMode()
        a.fmu.enterInitializationMode()
        c.set(_csfh_start_values(scene))
        current = a
        a.set({**s.actuator, "V": s.voltage(0.0)})
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
        exchange_theta()
        applied = a.fmu.getReal(act_vrs)
        c.fmu.setReal(in_vrs, a.fmu.getReal(out_vrs))
        current = c
        c.fmu.exitInitializationMode()
        current = a
        a.fmu.exitInitializationMode()

        rows = _Rows(COLUMNS)
        counts: list[int] = []
        for k in range(n + 1):
            t = k * h
            V = s.voltage(t)
            current = a
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
        raise current.error(exc) from None
    finally:
        c.free()
        a.free()
    stats = {
        "engine": "fmpy",
        "communication_steps": n,
        "steps": int(steps),
        "wall_time": time.perf_counter() - wall,
    }
    return _trajectory(scene, s, rows.arrays(), np.array(counts), stats)


# ------------------------------------------------------------------------------------------
# libcosim (libcosimpy)


def _libcosim_samples(observer: Any, slave: int, vr: int, count: int, integer: bool) -> np.ndarray:
    """All `count` samples of one observed variable from step 0, via libcosimc's
    cosim_observer_slave_get_{real,integer}_samples (libcosimpy 0.0.6's wrapper drops the last
    sample: it trims by counting zero step numbers, and step 0 is one)."""
    from ctypes import POINTER, c_double, c_int, c_int64, c_size_t, c_uint32

    from libcosimpy._internal import libcosimc, wrap_function
    from libcosimpy.CosimObserver import CosimObserver

    ctype = c_int if integer else c_double
    fn = wrap_function(
        lib=libcosimc(),
        funcname=f"cosim_observer_slave_get_{'integer' if integer else 'real'}_samples",
        argtypes=[
            POINTER(CosimObserver),
            c_int,
            c_uint32,
            c_int64,
            c_size_t,
            POINTER(ctype),
            POINTER(c_int64),
            POINTER(c_int64),
        ],
        restype=c_int64,
    )
    values = (ctype * count)()
    steps = (c_int64 * count)()
    times = (c_int64 * count)()
    got = fn(observer.ptr(), slave, vr, 0, count, values, steps, times)
    if got != count or list(steps) != list(range(count)):
        raise CosimError(f"libcosimpy: expected {count} samples of variable {vr}, got {got}")
    return np.array(values[:], dtype=float)


def _last_error() -> str:
    from libcosimpy._internal import get_last_error_message

    try:
        return get_last_error_message() or "no message"
    except Exception:  # pragma: no cover - the message is best effort
        return "no message"


def run_libcosimpy(
    scene: Scene,
    settings: CosimSettings,
    *,
    stop_time: float | None = None,
    progress: Progress | None = None,
) -> Trajectory:
    """The same coupling in libcosim (fixed-step, Jacobi; step sizes in integer nanoseconds)."""
    try:
        from libcosimpy.CosimEnums import CosimVariableType
        from libcosimpy.CosimExecution import CosimExecution
        from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
        from libcosimpy.CosimManipulator import CosimManipulator
        from libcosimpy.CosimObserver import CosimObserver
        from libcosimpy.CosimSlave import CosimLocalSlave
    except ImportError as exc:
        raise CosimError(
            f"the libcosimpy engine is not installed ({exc}): pip install libcosimpy"
        ) from None

    s = settings
    _check_engine(s)
    t_end = scene.stop_time if stop_time is None else stop_time
    n = max(1, round(t_end / s.step))
    h_ns = s.step_ns
    csfh_path, act_path = _paths()
    # libcosim's FMI library reports the (valid, FMI 2.0 2.2.7) missing start value of the
    # independent variable `time` as an error (fmi-library#21, libcosimpy#12): keep the console
    # quiet and report failures from the return codes and cosim_last_error_message
    log_output_level(CosimLogLevel.FATAL)
    wall = time.perf_counter()
    ex = CosimExecution.from_step_size(h_ns)
    ic = ex.add_local_slave(CosimLocalSlave(fmu_path=csfh_path, instance_name="csfh"))
    ia = ex.add_local_slave(CosimLocalSlave(fmu_path=act_path, instance_name="combdrive"))
    if ic < 0 or ia < 0:
        raise CosimError(f"libcosimpy: cannot load the FMUs: {_last_error()}")
    cv = {v.name.decode(): v.reference for v in ex.slave_variables(ic)}
    av = {v.name.decode(): v.reference for v in ex.slave_variables(ia)}

    def initial(slave: int, refs: dict[str, int], md: Any, values: dict[str, Any]) -> None:
        variables = {v.name: v for v in md.modelVariables}
        for name, value in values.items():
            var = variables[name]
            if var.type == "Enumeration":
                # libcosimpy ignores FMI 2.0 Enumeration variables: set its Integer twin
                if f"{name}_number" in refs:
                    name, var = f"{name}_number", variables[f"{name}_number"]
                elif int(value) != int(var.start):
                    raise CosimError(
                        f"libcosimpy ignores FMI 2.0 Enumeration variables: {name} = {value} "
                        f"cannot be set (the FMU default is {var.start}); use the fmpy engine"
                    )
                else:
                    continue
            if var.type == "Real":
                ok = ex.real_initial_value(slave, refs[name], float(value))
            elif var.type == "Boolean":
                ok = ex.boolean_initial_value(slave, refs[name], bool(value))
            else:
                ok = ex.integer_initial_value(slave, refs[name], int(value))
            if not ok:
                raise CosimError(f"libcosimpy: cannot set {name} = {value}: {_last_error()}")

    initial(ic, cv, _description(csfh_path), _csfh_start_values(scene))
    initial(ia, av, _description(act_path), {**s.actuator, "V": s.voltage(0.0)})
    links = [(o, i) for o, i in CONNECTIONS if s.moment or o != "M"]
    for out, inp in links:
        ex.connect_real_variables(ia, av[out], ic, cv[inp])
    if s.moment:
        ex.connect_real_variables(ic, cv["body1.theta"], ia, av["theta"])
    override = CosimManipulator.create_override()
    ex.add_manipulator(override)
    series = CosimObserver.create_time_series(buffer_size=n + 1)  # default: 10000 samples
    ex.add_observer(series)
    real = CosimVariableType.REAL
    for name in OUTPUT_NAMES.values():
        series.start_time_series(ic, cv[name], real)
    for name in ACTUATOR_COLUMNS:
        series.start_time_series(ia, av[name], real)
    series.start_time_series(ic, cv["contact.count"], CosimVariableType.INTEGER)
    last = CosimObserver.create_last_value()
    ex.add_observer(last)

    for k in range(n):
        override.slave_real_values(ia, [av["V"]], [s.voltage(k * s.step)])
        if not ex.step():
            raise CosimError(f"libcosimpy: step {k} (t = {k * s.step:g} s) failed: {_last_error()}")
        if progress is not None and k % 200 == 0:
            progress.update((k + 1) / n)
    status = ex.status()
    if status.current_time != n * h_ns:
        raise CosimError(f"libcosimpy stopped at {status.current_time} ns, not {n * h_ns} ns")
    steps = last.last_integer_values(ic, [cv["diagnostics.integrator_steps"]])[0]

    count = n + 1
    table: dict[str, np.ndarray] = {"t": np.arange(count) * (h_ns * 1e-9)}
    for col, name in OUTPUT_NAMES.items():
        table[col] = _libcosim_samples(series, ic, cv[name], count, integer=False)
    table["V"] = np.array([s.voltage(k * s.step) for k in range(count)])
    for name, col in ACTUATOR_COLUMNS.items():
        table[col] = _libcosim_samples(series, ia, av[name], count, integer=False)
    counts = _libcosim_samples(series, ic, cv["contact.count"], count, integer=True)
    stats = {
        "engine": "libcosimpy",
        "communication_steps": n,
        "steps": int(steps),
        "wall_time": time.perf_counter() - wall,
    }
    return _trajectory(scene, s, table, counts, stats)


# ------------------------------------------------------------------------------------------
# entry point

RUNNERS: dict[str, Callable[..., Trajectory]] = {"fmpy": run_fmpy, "libcosimpy": run_libcosimpy}


def cosimulate(
    scene: Scene,
    *,
    engine: str | None = None,
    step: float | None = None,
    ordering: str | None = None,
    stop_time: float | None = None,
    quiet: bool = True,
) -> Trajectory:
    """Co-simulate the scene's hinge with its comb-drive actuator, as set up by the scene's
    ``[cosim]`` section (see this module's docstring for its keys), and return the
    :class:`Trajectory` of the hinge's outputs at the communication points, with the voltage
    ``V`` and the actuator's ``F_act``, ``F_x``, ``F_y``, ``M``.

    `engine` (``"fmpy"`` or ``"libcosimpy"``), `step` (s) and `ordering` (``"jacobi"`` or
    ``"gauss-seidel"``, fmpy only) override the scene's settings, `stop_time` its stop time.
    Raises :class:`SceneError` for bad settings and :class:`CosimError` when an FMU fails."""
    settings = cosim_settings(scene, engine=engine, step=step, ordering=ordering)
    progress = Progress(f"{scene.name}: cosim {settings.engine}", quiet=quiet)
    try:
        return RUNNERS[settings.engine](scene, settings, stop_time=stop_time, progress=progress)
    finally:
        progress.close()


# ------------------------------------------------------------------------------------------
# figure


def plot(tr: Trajectory, path: Path, title: str, delta: float) -> Path:
    """Voltage, actuator force and moment, position of G1 (x, y and the eccentricity |e| against
    the clearance delta: contact where |e| reaches delta), rotation, and the contact force."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = tr.t
    fig, axes = plt.subplots(5, 1, figsize=(8.5, 11.5), sharex=True)
    ax = axes[0]
    ax.plot(t, tr["V"], color="tab:purple", lw=1.2, label="drive voltage V")
    ax.set_ylabel("V [V]")
    ax = axes[1]
    ax.plot(t, tr["F_x"], color="tab:olive", lw=1.2, label="actuator force $F_x$")
    ax.plot(t, tr["F_y"], color="tab:brown", lw=1.2, label="actuator force $F_y$")
    ax.set_ylabel("force on body 1 [N]")
    twin = ax.twinx()
    twin.plot(t, tr["M"], color="tab:gray", lw=1.0, ls="--", label="actuator moment M about G1")
    twin.set_ylabel("M [N m]")
    for a, cols in ((ax, ("F_x", "F_y")), (twin, ("M",))):  # both axes include 0
        lo = min(0.0, *(float(np.min(tr[c])) for c in cols))
        hi = max(0.0, *(float(np.max(tr[c])) for c in cols))
        pad = 0.08 * (hi - lo) or 1.0
        a.set_ylim(lo - (pad if lo < 0 else 0.0), hi + pad)
    ax = axes[2]
    ecc = np.hypot(tr["x"], tr["y"])
    ax.plot(t, tr["x"] * 1e3, color="tab:blue", lw=1.0, label="x of G1")
    ax.plot(t, tr["y"] * 1e3, color="tab:orange", lw=1.0, label="y of G1")
    ax.plot(t, ecc * 1e3, color="k", lw=1.0, label="eccentricity |e|")
    ax.axhline(
        delta * 1e3, color="tab:red", ls=":", lw=1.2, label=f"clearance δ = {delta * 1e3:g} mm"
    )
    ax.set_ylabel("position [mm]")
    ax = axes[3]
    ax.plot(t, np.degrees(tr["theta"]), color="tab:green", lw=1.0, label=r"rotation $\theta$")
    ax.set_ylabel(r"$\theta$ [deg]")
    ax = axes[4]
    F_N = np.where(tr["F_N"] > 0, tr["F_N"], np.nan)
    ax.plot(t, F_N, color="tab:red", lw=0.9, label="contact normal force $F_N$")
    top = float(np.nanmax(F_N)) if np.any(np.isfinite(F_N)) else 10.0
    ax.set_yscale("log")
    ax.set_ylim(1.0, top * 3)
    ax.set_ylabel("$F_N$ [N] (log)")
    ax.set_xlabel("t [s]")
    for a in axes:
        a.grid(alpha=0.3)
    axes[0].set_title(title, fontsize=10)
    handles, labels = [], []
    for a in (*axes[:2], twin, *axes[2:]):
        h, lab = a.get_legend_handles_labels()
        handles += h
        labels += lab
    fig.legend(handles, labels, loc="lower center", ncol=3, frameon=False, fontsize=9)
    fig.tight_layout(rect=(0, 0.075, 1, 1))
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def clearance(scene: Scene) -> float:
    values = scene.parameter_values()
    return float(values.get("contact.R2", 0.20)) - float(values.get("contact.R1", 0.18))
