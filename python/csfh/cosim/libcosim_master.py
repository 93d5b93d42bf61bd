"""The same coupling in libcosim, the Open Simulation Platform's engine, through libcosimpy
(fixed-step, Jacobi; step sizes in whole nanoseconds)."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..model.cosim_section import CONNECTIONS, CosimSettings, check_engine
from ..model.fmus import description
from ..model.scene import Scene
from ..paths import combdrive_fmu_path, fmu_path
from ..progress import Progress
from ..runners.fmu import OUTPUT_NAMES
from ..trajectory import Trajectory
from .coupling import (
    ACTUATOR_COLUMNS,
    CosimError,
    actuator_start_values,
    csfh_start_values,
    make_trajectory,
)


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


def _initial_values(
    ex: Any, slave: int, refs: dict[str, int], md: Any, values: dict[str, Any]
) -> None:
    """The start values of one instance as libcosim's initial values."""
    variables = {v.name: v for v in md.modelVariables}
    setters = {
        "Real": (ex.real_initial_value, float),
        "Boolean": (ex.boolean_initial_value, bool),
    }
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
        setter, kind = setters.get(var.type, (ex.integer_initial_value, int))
        if not setter(slave, refs[name], kind(value)):
            raise CosimError(f"libcosimpy: cannot set {name} = {value}: {_last_error()}")


def _libcosimpy() -> Any:
    """libcosimpy's modules (CosimError naming the missing package)."""
    try:
        import libcosimpy.CosimEnums as enums
        import libcosimpy.CosimExecution as execution
        import libcosimpy.CosimLogging as logging
        import libcosimpy.CosimManipulator as manipulator
        import libcosimpy.CosimObserver as observer
        import libcosimpy.CosimSlave as slave
    except ImportError as exc:
        raise CosimError(
            f"the libcosimpy engine is not installed ({exc}): pip install libcosimpy"
        ) from None
    return enums, execution, logging, manipulator, observer, slave


def _run_steps(
    ex: Any,
    override: Any,
    ia: int,
    av: dict[str, int],
    s: CosimSettings,
    n: int,
    voltage_in_fmu: bool,
    progress: Progress | None,
) -> None:
    for k in range(n):
        if not voltage_in_fmu:
            override.slave_real_values(ia, [av["V"]], [s.voltage(k * s.step)])
        if not ex.step():
            raise CosimError(f"libcosimpy: step {k} (t = {k * s.step:g} s) failed: {_last_error()}")
        if progress is not None and k % 200 == 0:
            progress.update((k + 1) / n)
    status = ex.status()
    if status.current_time != n * s.step_ns:
        raise CosimError(f"libcosimpy stopped at {status.current_time} ns, not {n * s.step_ns} ns")


def _table(
    series: Any, ic: int, ia: int, cv: dict[str, int], av: dict[str, int], s: CosimSettings, n: int
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The observed time series as the result table, and the contact counts."""
    count = n + 1
    table: dict[str, np.ndarray] = {"t": np.arange(count) * (s.step_ns * 1e-9)}
    for col, name in OUTPUT_NAMES.items():
        table[col] = _libcosim_samples(series, ic, cv[name], count, integer=False)
    table["V"] = np.array([s.voltage(k * s.step) for k in range(count)])
    for name, col in ACTUATOR_COLUMNS.items():
        table[col] = _libcosim_samples(series, ia, av[name], count, integer=False)
    return table, _libcosim_samples(series, ic, cv["contact.count"], count, integer=True)


def run_libcosimpy(
    scene: Scene,
    settings: CosimSettings,
    *,
    stop_time: float | None = None,
    progress: Progress | None = None,
    voltage_in_fmu: bool = False,
) -> Trajectory:
    """The same coupling in libcosim (fixed-step, Jacobi; step sizes in integer nanoseconds).
    `voltage_in_fmu`: the actuator evaluates the voltage ramp itself (csfh.cosim.coupling)
    instead of an override manipulator setting V before each step."""
    enums, execution, logging, manipulator, observer, slave = _libcosimpy()
    s = settings
    check_engine(s)
    t_end = scene.stop_time if stop_time is None else stop_time
    n = max(1, round(t_end / s.step))
    csfh_path, act_path = str(fmu_path()), str(combdrive_fmu_path())
    # libcosim's FMI library reports the (valid, FMI 2.0 2.2.7) missing start value of the
    # independent variable `time` as an error (fmi-library#21, libcosimpy#12): keep the console
    # quiet and report failures from the return codes and cosim_last_error_message
    logging.log_output_level(logging.CosimLogLevel.FATAL)
    wall = time.perf_counter()
    ex = execution.CosimExecution.from_step_size(s.step_ns)
    ic = ex.add_local_slave(slave.CosimLocalSlave(fmu_path=csfh_path, instance_name="csfh"))
    ia = ex.add_local_slave(slave.CosimLocalSlave(fmu_path=act_path, instance_name="combdrive"))
    if ic < 0 or ia < 0:
        raise CosimError(f"libcosimpy: cannot load the FMUs: {_last_error()}")
    cv = {v.name.decode(): v.reference for v in ex.slave_variables(ic)}
    av = {v.name.decode(): v.reference for v in ex.slave_variables(ia)}
    _initial_values(ex, ic, cv, description(csfh_path), csfh_start_values(scene))
    _initial_values(ex, ia, av, description(act_path), actuator_start_values(s, voltage_in_fmu))
    for out, inp in [(o, i) for o, i in CONNECTIONS if s.moment or o != "M"]:
        ex.connect_real_variables(ia, av[out], ic, cv[inp])
    if s.moment:
        ex.connect_real_variables(ic, cv["body1.theta"], ia, av["theta"])
    override = manipulator.CosimManipulator.create_override()
    if not voltage_in_fmu:
        ex.add_manipulator(override)
    series = observer.CosimObserver.create_time_series(buffer_size=n + 1)  # default: 10000
    ex.add_observer(series)
    real = enums.CosimVariableType.REAL
    for name in OUTPUT_NAMES.values():
        series.start_time_series(ic, cv[name], real)
    for name in ACTUATOR_COLUMNS:
        series.start_time_series(ia, av[name], real)
    series.start_time_series(ic, cv["contact.count"], enums.CosimVariableType.INTEGER)
    last = observer.CosimObserver.create_last_value()
    ex.add_observer(last)
    _run_steps(ex, override, ia, av, s, n, voltage_in_fmu, progress)
    steps = last.last_integer_values(ic, [cv["diagnostics.integrator_steps"]])[0]
    table, counts = _table(series, ic, ia, cv, av, s, n)
    stats = {
        "engine": "libcosimpy",
        "communication_steps": n,
        "steps": int(steps),
        "wall_time": time.perf_counter() - wall,
    }
    return make_trajectory(scene, s, table, counts, stats)
