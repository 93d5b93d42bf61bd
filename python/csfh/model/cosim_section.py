"""The [cosim] section of a scene: co-simulation of the hinge with the comb-drive actuator
(`csfh cosim`, `csfh.cosim.run.cosimulate`; the coupling is described in
`csfh.cosim.coupling`). Validated when the scene is loaded, with one-line errors naming the
key (SceneError).

Scene section (all keys optional except the voltage ramp):

    [cosim]
    engine = "fmpy"              # or "libcosimpy"
    step = 1e-4                  # s, communication step (libcosimpy: a whole number of ns;
                                 # default: the harness's output interval)
    ordering = "jacobi"          # fmpy engine: "jacobi" (as libcosim) or "gauss-seidel"
    tolerance = 1e-6             # relative tolerance inside the csfh FMU (fmpy engine;
                                 # libcosim sets none, so the FMU's default DEFAULT_TOLERANCE
                                 # applies)
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

import sys
from dataclasses import dataclass, field
from typing import Any

from ..errors import SceneError
from ._csfh_variables import DEFAULT_TOLERANCE, OUTPUT_INTERVAL
from .actuator import actuator_parameters, check_actuator
from .values import number as _number

ENGINES = ("fmpy", "libcosimpy")
ORDERINGS = ("jacobi", "gauss-seidel")
# DEFAULT_TOLERANCE: the csfh FMU's relative tolerance when fmi2SetupExperiment gives none

MIN_TOLERANCE = 10 * sys.float_info.epsilon
"""The smallest relative tolerance the csfh FMU accepts (FMU_TOLERANCE_MIN of
fmu_src/fmu/fmu_instance.h, docs/guide/fmu.md#tolerance)."""

CONNECTIONS = (("F_x", "F_ext[1]"), ("F_y", "F_ext[2]"), ("M", "M_ext"))
"""(actuator output, csfh input)."""

_TOP_KEYS = {"engine", "step", "ordering", "tolerance", "moment", "actuator", "voltage"}
_RAMP_KEYS = {"V0", "V1", "t0", "t1"}


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
    step: float = OUTPUT_INTERVAL
    ordering: str = "jacobi"
    tolerance: float | None = None  # None: the FMU's default (DEFAULT_TOLERANCE)
    moment: bool = True
    actuator: dict[str, float | int] = field(default_factory=dict)
    voltage: VoltageRamp = field(default_factory=VoltageRamp)

    @property
    def step_ns(self) -> int:
        return round(self.step * 1e9)


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
    step = _number("cosim.step", table.get("step", OUTPUT_INTERVAL), positive=True)
    ordering = table.get("ordering", "jacobi")
    if ordering not in ORDERINGS:
        raise SceneError(f"cosim.ordering = {ordering!r} is not one of {', '.join(ORDERINGS)}")
    tolerance = table.get("tolerance")
    if tolerance is not None:
        tolerance = _number("cosim.tolerance", tolerance, positive=True)
        if not MIN_TOLERANCE <= tolerance < 1:
            raise SceneError(
                f"cosim.tolerance = {tolerance!r} must be in [{MIN_TOLERANCE:.3g}, 1) (the csfh "
                "FMU refuses a relative tolerance below 10 machine epsilons)"
            )
    moment = table.get("moment", True)
    if not isinstance(moment, bool):
        raise SceneError(f"cosim.moment = {moment!r} must be true or false")
    voltage = _voltage(table)
    actuator = check_actuator(
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
        voltage=voltage,
    )
    check_engine(settings)
    return settings


def _voltage(table: dict[str, Any]) -> VoltageRamp:
    """[cosim.voltage]: every key given, t1 > t0 >= 0."""
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
    return VoltageRamp(**v)


def check_engine(s: CosimSettings) -> None:
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
