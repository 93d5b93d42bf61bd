"""What every run of the csfh FMU shares, by model exchange (`model_exchange`), co-simulation
(`co_simulation`) or the batch master (`cs_batch`): the unzipped FMU and its binary, the values a
run sets, the output columns, the contact records read from the FMU's event outputs, and the
one-line error of a failed FMI call."""

from __future__ import annotations

import atexit
import ctypes
import math
import os
import shutil
import tempfile
from collections.abc import Sequence
from functools import cache
from typing import Any

import numpy as np

from ..errors import ParameterError, SimulationError
from ..model import model_info
from ..model.scene import Scene
from ..paths import fmu_path
from ..trajectory import CONTACT_FIELDS, Trajectory

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
each row (located on the integrator's interpolant; at t = 0 the values there), the flexure
stress and its peak (tracked inside the step only with flexure.track_stress_peak), the Hertz
pressure and its peak, and the frame's acceleration (a_base plus the shock pulse)."""
EVENT_NAMES = (
    "contact.onset_time",
    "contact.onset_speed",
    "contact.release_time",
    "contact.release_speed",
)
"""The FMU's outputs of the last contact onset and release (located event times and speeds)."""
EVALUATION_PARTS = ("rhs", "flexure", "contact", "friction")
"""The FMU's evaluation counters, diagnostics.PART_evaluations."""
TABLE_COLUMNS = ("t", *OUTPUT_NAMES)
model_info.require(OUTPUT_NAMES.values(), "runners.fmu.OUTPUT_NAMES")
model_info.require(CS_OUTPUT_NAMES.values(), "runners.fmu.CS_OUTPUT_NAMES")
model_info.require(EVENT_NAMES, "runners.fmu.EVENT_NAMES")


@cache
def unzipped_fmu() -> str:
    """The directory of the unzipped csfh.fmu (once per process, removed at exit)."""
    from fmpy import extract

    directory = tempfile.mkdtemp(prefix="csfh-fmu-")
    atexit.register(shutil.rmtree, directory, True)
    return str(extract(str(fmu_path()), unzipdir=directory))


def binary_path(unzip_dir: str, model_identifier: str) -> str:
    """The FMU's binary for this platform inside the unzipped FMU."""
    import fmpy

    name = model_identifier + fmpy.sharedLibraryExtension
    return os.path.join(unzip_dir, "binaries", fmpy.platform, name)


@cache
def resident_binary(unzip_dir: str, model_identifier: str) -> ctypes.CDLL:
    """The FMU's binary, loaded once per process through our own ctypes handle and kept loaded.
    fmpy loads the binary for each instance and unloads it at fmi2FreeInstance; with this
    reference held, its unload only drops a count, so the next run does not map, relocate and
    bind the library again (benchmarks/bench_event_vs_rk4.py). The FMU keeps no state outside
    its instances, so instances of consecutive runs share nothing through it."""
    return ctypes.CDLL(binary_path(unzip_dir, model_identifier))


def vr(name: str) -> int:
    """The value reference of an FMU variable."""
    return model_info.variables()[name].valueReference


def start_values(
    scene: Scene, law: str | None, extra: dict[str, Any] | None = None
) -> list[tuple[str, str, float | int | bool]]:
    """Every value a run sets in initialization mode, in the order it sets them: (name, FMI type
    as set: Real | Integer | Boolean, value). The parameters of the scene and law, the overrides,
    the start state, the inputs. Every run of the FMU (model exchange, co-simulation, the batch
    master) takes its values from here."""
    return start_values_of_runs(scene, law, [extra])[0]


def start_values_of_runs(
    scene: Scene, law: str | None, extras: Sequence[dict[str, Any] | None]
) -> list[list[tuple[str, str, float | int | bool]]]:
    """`start_values(scene, law, extra)` of each run's overrides `extra`, the scene's part
    worked out once for all of them."""
    base: dict[str, Any] = dict(scene.parameter_values(law))
    after = {**dict(zip(STATE_NAMES, scene.x0, strict=True)), **scene.inputs}
    variables = model_info.variables()
    as_set = {name: _as_set(variables[name].type) for name in (*base, *after)}
    runs = []
    for extra in extras:
        values = dict(base)
        if extra:
            values.update({k: model_info.coerce(k, v) for k, v in extra.items()})
        values.update(after)
        out: list[tuple[str, str, float | int | bool]] = []
        for name, value in values.items():
            kind, convert = as_set.get(name) or _as_set(variables[name].type)
            out.append((name, kind, convert(value)))
        runs.append(out)
    return runs


def _as_set(kind: str) -> tuple[str, Any]:
    """The FMI type a variable of type `kind` is set as, and the Python type of its value."""
    return {"Real": ("Real", float), "Boolean": ("Boolean", bool)}.get(kind, ("Integer", int))


def check_law(law: str) -> None:
    """ParameterError unless `law` is one of the FMU's event-driven contact laws."""
    if law not in model_info.LAWS:
        raise ParameterError(
            f"law {law!r} is not an event-driven law ({', '.join(model_info.LAWS)})"
        )


def fmu_error(law: str, t: float, call: str, reason: str) -> SimulationError:
    """One line for a failed FMI call: the model, the time, the call and the FMU's own reason."""
    return SimulationError(f"{law}: {call} failed at t = {t:.9g} s: {reason}")


class Table:
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


def contact_arrays(records: list[list[float]]) -> dict[str, np.ndarray]:
    """Contact records (rows of CONTACT_FIELDS) as columns."""
    data = np.array(records, dtype=float).reshape(-1, len(CONTACT_FIELDS))
    return {name: data[:, i].copy() for i, name in enumerate(CONTACT_FIELDS)}


def first_record(count: int, onset_speed: float) -> list[list[float]]:
    """The contact records at the start: one open record if the run starts in contact."""
    return [[0.0, onset_speed, math.nan, math.nan, math.nan, math.nan]] if count else []


def contact_bookkeeping(
    records: list[list[float]],
    count: int,
    active: bool,
    counts: np.ndarray,
    actives: np.ndarray,
    events: np.ndarray,
) -> tuple[int, bool]:
    """The contact records of a co-simulation over communication points (counts, active flags
    and the EVENT_NAMES values, one row per point), after the state (count, active) of the point
    before; returns the state after. The FMU reports the located event times of the last onset
    and release; contacts that begin and end inside one communication step show only their last
    values. The single run and the batch master's records both go through here."""
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


def cs_trajectory(
    law: str, scene: str, table: dict[str, np.ndarray], records: list[list[float]]
) -> Trajectory:
    """The Trajectory of a co-simulation run: its table, its contact records, and the onsets
    and releases they hold."""
    cr = contact_arrays(records)
    return Trajectory(
        model=law,
        scene=scene,
        table=table,
        contacts=cr["t_onset"],
        releases=cr["t_release"][np.isfinite(cr["t_release"])],
        contact_records=cr,
    )
