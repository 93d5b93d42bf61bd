"""Co-simulation of the CSFH FMU with the comb-drive actuator FMU (`combdrive.fmu`): the coupled
system and its result table. Two engines run it: a master loop over fmpy's FMU2Slave
(`fmpy_master`) and libcosim, the Open Simulation Platform engine, through libcosimpy
(`libcosim_master`); `run.cosimulate` chooses. The scene's [cosim] section is described in
`csfh.model.cosim_section`.

The coupling (the same in both engines):

    V(t) (voltage ramp of the scene)  -> combdrive.V
    combdrive.F_x                     -> csfh.F_ext[1]
    combdrive.F_y                     -> csfh.F_ext[2]
    combdrive.M                       -> csfh.M_ext          (moment = true)
    csfh.body1.theta                  -> combdrive.theta     (moment = true)

Ordering. Both FMUs advance with a fixed communication step h; inputs are held constant over a
step (zero-order hold; the csfh FMU restarts its integrator when an input changes).

* Jacobi (default): every FMU steps from t_k to t_k+1 with the inputs it holds at t_k; outputs are
  exchanged after all have stepped. This is libcosim's fixed-step algorithm, so the two engines
  compute the same thing and agree to round-off (tests/package/test_cosim.py). The actuator is
  algebraic (direct feedthrough), so the hinge sees during [t_k, t_k+1] the force of V(t_k-1),
  theta(t_k-1): one communication step of delay.
* Gauss-Seidel (fmpy engine only): at t_k the actuator is evaluated first, with V(t_k) and the
  current theta(t_k), and its force acts on the hinge over the same step: no delay. There is no
  algebraic loop to solve: theta is a state of the hinge (no direct feedthrough).

The voltage is set by the master before each step (libcosim: an override manipulator), V(t_k).
With ``voltage_in_fmu`` the master instead sets the scene's ramp as the actuator's parameters
ramp.V0, ramp.V1, ramp.t0, ramp.t1 and leaves its input V at 0: the actuator then evaluates
V(t) itself at its own time, so after the step to t_k+1 its force is that of V(t_k+1) (one step
earlier than with the master's V(t_k)). This is how the SSP export carries the voltage
(csfh.cosim.ssp), and both masters run it that way to compare with the SSP importers.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SimulationError
from ..model.cosim_section import DEFAULT_TOLERANCE, CosimSettings
from ..model.scene import Scene
from ..output import write_table
from ..runners.fmu import OUTPUT_NAMES, STATE_NAMES
from ..trajectory import UNITS, Trajectory

ACTUATOR_COLUMNS = {"F": "F_act", "F_x": "F_x", "F_y": "F_y", "M": "M"}
"""Actuator output -> column of the result table."""
COSIM_UNITS = {"V": "V", "F_act": "N", "F_x": "N", "F_y": "N", "M": "N m"}


class CosimError(SimulationError):
    """The co-simulation failed; the message says which FMU or engine and why (the CLI reports it
    on one line, like every SimulationError)."""


def csfh_start_values(scene: Scene) -> dict[str, Any]:
    """Parameters (preset, parts, overrides; the scene's contact law), initial state, inputs."""
    values: dict[str, Any] = dict(scene.parameter_values(None))
    values.update(dict(zip(STATE_NAMES, scene.x0, strict=True)))
    values.update(scene.inputs)
    return values


RAMP_PARAMETERS = {"V0": "ramp.V0", "V1": "ramp.V1", "t0": "ramp.t0", "t1": "ramp.t1"}
"""Voltage ramp key of the scene -> the actuator FMU's parameter."""


def actuator_start_values(s: CosimSettings, voltage_in_fmu: bool) -> dict[str, Any]:
    """The actuator's parameters of the scene, and the voltage: the input V = V(0) (set again
    by the master before each step), or with `voltage_in_fmu` the ramp as the FMU's ramp.*
    parameters (the input V stays at its start value 0)."""
    values: dict[str, Any] = dict(s.actuator)
    if voltage_in_fmu:
        ramp = s.voltage
        values.update({RAMP_PARAMETERS[k]: float(getattr(ramp, k)) for k in RAMP_PARAMETERS})
    else:
        values["V"] = s.voltage(0.0)
    return values


# ------------------------------------------------------------------------------------------
# results


class Rows:
    """Growing table of output rows."""

    def __init__(self, names: tuple[str, ...]) -> None:
        self.names = names
        self.rows: list[list[float]] = []

    def arrays(self) -> dict[str, np.ndarray]:
        data = np.array(self.rows, dtype=float).reshape(-1, len(self.names))
        return {n: data[:, i].copy() for i, n in enumerate(self.names)}


COLUMNS = ("t", *OUTPUT_NAMES, "V", *ACTUATOR_COLUMNS.values())
"""Columns of a co-simulation table: the hinge's outputs at t, the voltage V(t) and the actuator
force acting on the hinge from t on (over the next communication step)."""


def make_trajectory(
    scene: Scene,
    s: CosimSettings,
    table: dict[str, np.ndarray],
    counts: np.ndarray,
    stats: dict[str, Any],
) -> Trajectory:
    """The Trajectory of a co-simulation run (model name cosim-ENGINE[-ORDERING])."""
    # onsets known to the communication step (the FMU locates them exactly inside the step)
    onsets = table["t"][1:][np.diff(counts) > 0] if len(counts) > 1 else np.zeros(0)
    model = f"cosim-{s.engine}" + ("" if s.engine == "libcosimpy" else f"-{s.ordering}")
    tr = Trajectory(model=model, scene=scene.name, table=table, contacts=onsets)
    tr.stats = {
        "integrator": "the csfh FMU's own integrator (solver.method), "
        f"rtol={s.tolerance or DEFAULT_TOLERANCE:g}; {s.engine} master, {s.ordering}, "
        f"communication step {s.step:g} s",
        **stats,
    }
    return tr


def write_csv(tr: Trajectory, path: Path) -> Path:
    """The co-simulation table as CSV, units in the header."""
    return write_table(path, tr.table, {**UNITS, **COSIM_UNITS})
