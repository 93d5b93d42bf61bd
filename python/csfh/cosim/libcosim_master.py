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
    check_engine(s)
    t_end = scene.stop_time if stop_time is None else stop_time
    n = max(1, round(t_end / s.step))
    h_ns = s.step_ns
    csfh_path, act_path = str(fmu_path()), str(combdrive_fmu_path())
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

    initial(ic, cv, description(csfh_path), csfh_start_values(scene))
    initial(ia, av, description(act_path), actuator_start_values(s, voltage_in_fmu))
    links = [(o, i) for o, i in CONNECTIONS if s.moment or o != "M"]
    for out, inp in links:
        ex.connect_real_variables(ia, av[out], ic, cv[inp])
    if s.moment:
        ex.connect_real_variables(ic, cv["body1.theta"], ia, av["theta"])
    override = CosimManipulator.create_override()
    if not voltage_in_fmu:
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
        if not voltage_in_fmu:
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
    return make_trajectory(scene, s, table, counts, stats)
