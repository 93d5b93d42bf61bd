"""The result of one simulation: an output table, optional per-step records, contact onsets and
statistics, with CSV/JSON writers."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

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

    def __getitem__(self, column: str) -> np.ndarray:
        """A column of the output table, e.g. ``run["F_N"]`` (units in ``UNITS``)."""
        return self.table[column]

    @property
    def t(self) -> np.ndarray:
        """The times of the output table, s."""
        return self.table["t"]

    def summary(self) -> dict[str, Any]:
        """First contact time, number of contacts, largest F_N, indentation and abs(F_T) (over
        the output table and the per-step records), and the integrator, its steps,
        right-hand-side evaluations and wall time."""
        F_N = self.table["F_N"]
        F_T = self.table["F_T"]
        ind = self.table["indentation"]
        out: dict[str, Any] = {
            "first_contact_time": float(self.contacts[0]) if len(self.contacts) else None,
            "contacts": len(self.contacts),
            "max_F_N": float(np.max(F_N)) if len(F_N) else 0.0,
            "max_indentation": float(np.max(ind)) if len(ind) else 0.0,
            "max_abs_F_T": float(np.max(np.abs(F_T))) if len(F_T) else 0.0,
        }
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
        return out

    def write_csv(self, path: Path) -> None:
        """Write the output table as CSV, one column per quantity, units in the header
        (``t [s],x [m],...``)."""
        names = [c for c in (*COLUMNS, *EXTRA_COLUMNS) if c in self.table]
        names += [c for c in self.table if c not in names]
        header = ",".join(f"{n} [{UNITS.get(n, '-')}]" for n in names)
        data = np.column_stack([self.table[n] for n in names])
        np.savetxt(path, data, delimiter=",", header=header, comments="", fmt="%.10g")


def write_json(path: Path, data: Any) -> None:
    path.write_text(json.dumps(data, indent=2, sort_keys=False) + "\n", encoding="utf-8")
