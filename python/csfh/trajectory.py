"""The result of one simulation: an output table, optional per-step records, contact onsets and
statistics, its CSV table, and its output signals on a grid."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .errors import ResultsError
from .output import read_table, write_table

COLUMNS = ("t", "x", "y", "theta", "vx", "vy", "omega", "F_N", "F_T", "indentation", "v_T")
"""Columns of every output table (SI units: s, m, m, rad, m/s, m/s, rad/s, N, N, m, m/s)."""
EXTRA_COLUMNS = ("gap", "energy")
CONTACT_FIELDS = (
    "t_onset",
    "onset_speed",
    "t_release",
    "release_speed",
    "peak_F_N",
    "max_indentation",
)
"""Per-contact record every integrator reports (s, m/s, s, m/s, N, m): the indentation rate at the
onset, the separation speed dg/dt at the release, the largest normal force and indentation."""
SIGNALS = ("x", "y", "theta", "F_N", "F_T")
"""Output signals kept on a grid (m, m, rad, N, N): x, y, theta are the values at the grid
points; F_N and F_T the value of largest magnitude in each output interval (t_k-1, t_k] (over
every integrator step the run recorded), so that an impact peak does not depend on where the
grid happens to cut it."""
IMPULSIVE_MODELS = frozenset({"Moreau"})
"""Models whose F_N and F_T are not a contact law's forces but each step's impulse over the step,
Lambda / h (docs/model.md §6): they scale as 1/h (about 1e6 N at h = 1e-5 s where the laws give
1e4 N), so they are labelled wherever they are printed or plotted (`force_label`)."""


def force_label(model: str, name: str = "F_N") -> str:
    """The force `name` of `model` as printed beside the laws' forces: Moreau's is marked as an
    impulse over the step."""
    return f"{name} (impulse/h)" if model in IMPULSIVE_MODELS else name


UNITS = {
    "t": "s",
    "x": "m",
    "y": "m",
    "theta": "rad",
    "vx": "m/s",
    "vy": "m/s",
    "omega": "rad/s",
    "F_N": "N",
    "F_T": "N",
    "indentation": "m",
    "v_T": "m/s",
    "gap": "m",
    "energy": "J",
    "F_N_peak": "N",
    "F_T_peak": "N",
    "indentation_peak": "m",
    "stress": "Pa",
    "stress_peak": "Pa",
    "pressure": "Pa",
    "pressure_peak": "Pa",
    "a_frame_x": "m/s2",
    "a_frame_y": "m/s2",
    "Lambda_N": "N s",
    "Lambda_T": "N s",
    "mode": "-",
}


@dataclass
class Trajectory:
    """One model run. `table` holds the output grid (plus the event instants of the event-driven
    models, as left limits); `steps` per-integrator-step records (bounded; may be empty);
    `contacts` the contact onset times and `releases` the contact end times (event-driven models);
    `impacts` the Moreau onset steps."""

    model: str
    scene: str
    table: dict[str, np.ndarray]
    contacts: np.ndarray
    stats: dict[str, Any] = field(default_factory=dict)
    steps: dict[str, np.ndarray] = field(default_factory=dict)
    impacts: dict[str, np.ndarray] = field(default_factory=dict)
    releases: np.ndarray = field(default_factory=lambda: np.zeros(0))
    contact_records: dict[str, np.ndarray] = field(default_factory=dict)

    def force_label(self, name: str = "F_N") -> str:
        """The force `name` as printed beside other models' forces (`force_label`): Moreau's
        says that it is an impulse over the step."""
        return force_label(self.model, name)

    def __getitem__(self, column: str) -> np.ndarray:
        """A column of the output table, e.g. ``run["F_N"]`` (units in ``UNITS``)."""
        return self.table[column]

    @property
    def t(self) -> np.ndarray:
        """The times of the output table, s."""
        return self.table["t"]

    def summary(self) -> dict[str, Any]:
        """First contact time, number of contacts, largest F_N, indentation and abs(F_T) (over
        the output table, its peak columns where the run has them (co-simulation: the peaks over
        each communication step) and the per-step records), the largest flexure stress and
        contact pressure where the table has them, and the integrator, its steps,
        right-hand-side evaluations and wall time, when the last contact ended (None: none
        ended) and whether one is still on at the end. The number of contacts is the FMU's count
        where the run reports it (co-simulation: a step can hold several onsets)."""
        F_N = self.table["F_N"]
        F_T = self.table["F_T"]
        ind = self.table["indentation"]
        out: dict[str, Any] = {
            "first_contact_time": float(self.contacts[0]) if len(self.contacts) else None,
            "contacts": int(self.stats.get("contact_count", len(self.contacts))),
            "max_F_N": float(np.max(F_N)) if len(F_N) else 0.0,
            "max_indentation": float(np.max(ind)) if len(ind) else 0.0,
            "max_abs_F_T": float(np.max(np.abs(F_T))) if len(F_T) else 0.0,
        }
        for key, column in (
            ("max_F_N", "F_N_peak"),
            ("max_indentation", "indentation_peak"),
            ("max_abs_F_T", "F_T_peak"),
        ):
            if column in self.table and len(self.table[column]):
                out[key] = max(out[key], float(np.max(self.table[column])))
        for key, column in (
            ("max_flexure_stress", "stress_peak"),
            ("max_contact_pressure", "pressure_peak"),
        ):
            if column in self.table and len(self.table[column]):
                out[key] = float(np.max(self.table[column]))
        if self.steps:
            out["max_F_N"] = max(out["max_F_N"], float(np.max(self.steps["F_N"], initial=0.0)))
            out["max_indentation"] = max(
                out["max_indentation"], float(np.max(self.steps["indentation"], initial=0.0))
            )
            out["max_abs_F_T"] = max(
                out["max_abs_F_T"], float(np.max(np.abs(self.steps["F_T"]), initial=0.0))
            )
        for key in ("integrator", "steps", "rhs_evaluations", "wall_time"):
            out[key] = self.stats.get(key)
        ended = len(self.releases) > 0 and out["contacts"] > 0
        out["last_release_time"] = float(self.releases[-1]) if ended else None
        out["contact_at_end"] = int(len(self.contacts) > len(self.releases))
        return out

    def write_csv(self, path: Path) -> Path:
        """Write the output table as CSV, one column per quantity, units in the header
        (``t [s],x [m],...``; the standard columns first), and return its path."""
        names = [c for c in (*COLUMNS, *EXTRA_COLUMNS) if c in self.table]
        names += [c for c in self.table if c not in names]
        return write_table(path, {n: self.table[n] for n in names}, UNITS)

    @classmethod
    def read_csv(cls, path: Path, model: str | None = None, scene: str = "") -> Trajectory:
        """A Trajectory with the table that `write_csv` wrote (model: default the file's stem).
        Only the table is in the file: per-step records and contact lists are not."""
        table, _ = read_table(path)
        if "t" not in table:
            raise ResultsError(f"{path}: no time column 't'")
        return cls(
            model=Path(path).stem if model is None else model,
            scene=scene,
            table=table,
            contacts=np.zeros(0),
        )


def interval_peaks(g: np.ndarray, at_grid: np.ndarray, t: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Per grid point k, the sample of largest magnitude among the grid value and every sample
    (t, f) with g[k-1] < t <= g[k]."""
    k = np.searchsorted(g, t, side="left")
    inside = (k >= 1) & (k < len(g))
    hi, lo = at_grid.copy(), at_grid.copy()
    np.maximum.at(hi, k[inside], f[inside])
    np.minimum.at(lo, k[inside], f[inside])
    return np.where(np.abs(lo) > np.abs(hi), lo, hi)


def signals_on_grid(tr: Trajectory, g: np.ndarray) -> dict[str, np.ndarray]:
    """The run's SIGNALS on the grid g (see SIGNALS)."""
    sig = {name: np.interp(g, tr.t, tr[name]) for name in SIGNALS}
    for name in ("F_N", "F_T"):
        t_all = np.concatenate([tr.t, tr.steps["t"]]) if tr.steps else tr.t
        f_all = np.concatenate([tr[name], tr.steps[name]]) if tr.steps else tr[name]
        sig[name] = interval_peaks(g, sig[name], t_all, f_all)
    return sig
