"""The run-length limits, in one place: how long a run may be, how many output rows, Moreau steps
and communication points it may have, how many runs a study may make. The numbers are the
[harness] table of modelDescription/variables.toml (generated into `_csfh_variables`); every
check of a run's length or a study's size, whether its numbers come from a scene file, a
command-line option or a runner's argument, is one of the functions here, so that no input
exhausts the memory or runs for hours by accident."""

from __future__ import annotations

import math

from ..errors import ParameterError, SceneError
from ._csfh_variables import (
    MAX_COMMUNICATION_POINTS,
    MAX_DIRECTIONS,
    MAX_MOREAU_STEPS,
    MAX_OUTPUT_SAMPLES,
    MAX_RUNS,
    MAX_STOP_TIME,
)

__all__ = [
    "MAX_COMMUNICATION_POINTS",
    "MAX_DIRECTIONS",
    "MAX_MOREAU_STEPS",
    "MAX_OUTPUT_SAMPLES",
    "MAX_RUNS",
    "MAX_STOP_TIME",
    "check_communication_points",
    "check_count",
    "check_horizon",
    "check_rows",
    "moreau_step_counts",
]


def check_horizon(
    stop_time: float,
    output_interval: float,
    moreau_h: float | None = None,
    *,
    stop_key: str = "stop_time",
    interval_key: str = "integrator.output_interval",
) -> None:
    """The limits of a scene's run: SceneError naming the key and value. `stop_key` and
    `interval_key` name where the stop time and the output interval come from (keys of the
    scene, or command-line options)."""
    T, dt = stop_time, output_interval
    if not T <= MAX_STOP_TIME:
        raise SceneError(
            f"{stop_key} = {T:g} s is longer than {MAX_STOP_TIME:g} s, the longest run (every "
            "transient of the hinge decays within seconds)"
        )
    if dt > T:
        raise SceneError(f"{interval_key} = {dt:g} s is longer than {stop_key} = {T:g} s")
    if T / dt > MAX_OUTPUT_SAMPLES:
        raise SceneError(
            f"{interval_key} = {dt:g} s gives {T / dt:.3g} output samples over {stop_key} = "
            f"{T:g} s; at most {MAX_OUTPUT_SAMPLES:g} (a larger {interval_key.split('.')[-1]} or "
            "a shorter stop time)"
        )
    if moreau_h is None:
        return
    h = moreau_h
    if h > T:
        raise SceneError(
            f"integrator.moreau_h = {h:g} s is longer than {stop_key} = {T:g} s (not one step)"
        )
    if T / h > MAX_MOREAU_STEPS:
        raise SceneError(
            f"integrator.moreau_h = {h:g} s gives {T / h:.3g} Moreau steps over {stop_key} = "
            f"{T:g} s; at most {MAX_MOREAU_STEPS:g} (a larger moreau_h or a shorter stop time)"
        )


def _positive(prefix: str, **values: float) -> None:
    for name, value in values.items():
        if not (value > 0 and math.isfinite(value)):
            raise ParameterError(f"{prefix}{name} = {value!r} must be a finite number > 0")


def check_rows(t_end: float, step: float, what: str) -> int:
    """The number of output rows of a run on a grid of `step` up to `t_end`, at most
    MAX_OUTPUT_SAMPLES; ParameterError naming the values otherwise."""
    _positive("", **{"stop_time": t_end, what: step})
    if not t_end / step <= MAX_OUTPUT_SAMPLES:
        raise ParameterError(
            f"{what} = {step:g} s gives {t_end / step:.3g} output rows over {t_end:g} s; at most "
            f"{MAX_OUTPUT_SAMPLES:g}"
        )
    return math.ceil(t_end / step - 1e-9)


def moreau_step_counts(t_end: float, h: float, dt_out: float) -> tuple[int, int, int]:
    """(steps, steps per output row, rows to allocate) of a Moreau run: at least one step, at
    most MAX_MOREAU_STEPS steps and MAX_OUTPUT_SAMPLES rows; ParameterError naming the values
    otherwise."""
    _positive("Moreau: ", stop_time=t_end, h=h, output_interval=dt_out)
    if not t_end / h <= MAX_MOREAU_STEPS:
        raise ParameterError(
            f"Moreau: h = {h:g} s gives {t_end / h:.3g} steps over {t_end:g} s; at most "
            f"{MAX_MOREAU_STEPS:g}"
        )
    n_steps = round(t_end / h)
    if n_steps < 1:
        raise ParameterError(f"Moreau: h = {h:g} s is longer than the run ({t_end:g} s)")
    record_every = max(1, round(dt_out / h))
    max_records = n_steps // record_every + 2
    if max_records > MAX_OUTPUT_SAMPLES + 2:
        raise ParameterError(
            f"Moreau: output_interval = {dt_out:g} s gives {max_records - 2} rows; at most "
            f"{MAX_OUTPUT_SAMPLES:g}"
        )
    return n_steps, record_every, max_records


def check_communication_points(stop_time: float, step: float, step_key: str = "step") -> None:
    """At most MAX_COMMUNICATION_POINTS communication steps over the horizon; ParameterError
    naming the step's key otherwise."""
    if stop_time / step > MAX_COMMUNICATION_POINTS:
        raise ParameterError(
            f"{stop_time:g} s in steps of {step:g} s are more than "
            f"{MAX_COMMUNICATION_POINTS:g} communication points: give a larger {step_key}"
        )


def check_count(key: str, value: int, maximum: int, what: str) -> int:
    """A count of runs (`what`: of what, for the message) of at most `maximum`, so that a typo
    does not start days of runs or fill the memory with their tasks; ParameterError naming the
    key (an option or a file's key) and the value otherwise."""
    if value > maximum:
        raise ParameterError(f"{key} = {value} is more than {maximum:g}, the most {what}")
    return value
