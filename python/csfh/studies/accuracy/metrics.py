"""The metrics of the accuracy study (see csfh.studies.accuracy.study): per-contact errors, the
comparable horizon, the trajectory error, which errors the reference resolves, and the observed
order of convergence; the study's data (Point, Study)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...trajectory import Trajectory

COMPLIANT = ("LN_spheres", "LN_cylinders", "LN_ESDU")
METRICS = ("contact_time", "peak_F_N", "max_indentation", "rebound_velocity", "trajectory")
METRIC_LABELS = {
    "contact_time": "contact time error [s]",
    "peak_F_N": "peak $F_N$ relative error",
    "max_indentation": "max indentation relative error",
    "rebound_velocity": "rebound velocity relative error",
    "trajectory": "trajectory error max|q - q_ref| [m]",
}
RIGID_METRICS = ("contact_time", "rebound_velocity", "trajectory")


@dataclass
class Point:
    """One integrator at one setting on one model."""

    model: str
    integrator: str
    setting: float
    label: str
    wall_time: float
    rhs_evaluations: int
    steps: int
    errors: dict[str, float]
    vs: str = "self"  # which reference: "self" or a compliant model name (Moreau)
    unresolved: list[str] = field(default_factory=list)  # metrics below the reference's accuracy


@dataclass
class Study:
    scene: str
    stop_time: float
    points: list[Point] = field(default_factory=list)
    reference_checks: dict[str, dict[str, float]] = field(default_factory=dict)
    references: dict[str, str] = field(default_factory=dict)


# ------------------------------------------------------------------------------------------
# metrics


def _onsets(tr: Trajectory, n: int = 3) -> dict[str, np.ndarray]:
    cr = tr.contact_records
    return {k: v[:n] for k, v in cr.items()}


def contact_errors(tr: Trajectory, ref: Trajectory, n: int = 3) -> dict[str, float]:
    """Errors of the first n contacts, matched by order."""
    a, b = _onsets(tr, n), _onsets(ref, n)
    k = min(len(a["t_onset"]), len(b["t_onset"]))
    if k == 0:
        return {m: math.nan for m in METRICS[:4]}

    def rel(name: str) -> float:
        x, y = a[name][:k], b[name][:k]
        ok = np.isfinite(x) & np.isfinite(y) & (np.abs(y) > 0)
        return float(np.max(np.abs(x[ok] - y[ok]) / np.abs(y[ok]))) if ok.any() else math.nan

    return {
        "contact_time": float(np.max(np.abs(a["t_onset"][:k] - b["t_onset"][:k]))),
        "peak_F_N": rel("peak_F_N"),
        "max_indentation": rel("max_indentation"),
        "rebound_velocity": rel("release_speed"),
    }


def horizon(tr: Trajectory, ref: Trajectory, stop_time: float) -> float:
    """End of the comparable horizon: the reference onset of the first contact whose timing
    differs by more than 1 % of the preceding flight time (or the stop time)."""
    t, t_ref = tr.contact_records["t_onset"], ref.contact_records["t_onset"]
    previous = 0.0
    for k in range(len(t_ref)):
        if k >= len(t) or abs(t[k] - t_ref[k]) > 0.01 * (t_ref[k] - previous):
            return float(t_ref[k])
        previous = float(t_ref[k])
    return stop_time


def trajectory_error(tr: Trajectory, ref: Trajectory, t_max: float, radius: float) -> float:
    """max over common output times t < t_max of max(|dx|, |dy|, radius |dtheta|)."""
    ta, tb = tr.t, ref.t
    idx = np.searchsorted(tb, ta)
    idx = np.clip(idx, 0, len(tb) - 1)
    match = (np.abs(tb[idx] - ta) <= 1e-12 * np.maximum(1.0, np.abs(ta))) & (ta < t_max)
    # the event rows of a table are left limits at the event instants: skip repeated times
    if not match.any():
        return math.nan
    ia, ib = np.nonzero(match)[0], idx[match]
    d = np.maximum.reduce(
        [
            np.abs(tr["x"][ia] - ref["x"][ib]),
            np.abs(tr["y"][ia] - ref["y"][ib]),
            radius * np.abs(tr["theta"][ia] - ref["theta"][ib]),
        ]
    )
    return float(np.max(d))


RESOLUTION = 100.0
"""An error is plotted only if it is at least this many times the change of its reference on
halving the reference's setting: below that it measures the reference, not the integrator."""


def mark_unresolved(study: Study) -> None:
    """List, per point, the metrics whose error its reference does not resolve."""
    for p in study.points:
        change = study.reference_checks.get(p.model if p.vs == "self" else p.vs, {})
        p.unresolved = [
            m for m, c in change.items() if math.isfinite(c) and p.errors[m] < RESOLUTION * c
        ]


def plotted(p: Point, metric: str) -> bool:
    """The error is finite, positive and resolved by the reference."""
    e = p.errors[metric]
    return math.isfinite(e) and e > 0 and metric not in p.unresolved


def observed_order(points: list[Point], metric: str) -> float:
    """Slope of log(error) against log(setting) (rtol, h0 or h), least squares over the points
    with a finite, positive error."""
    xs = [math.log(p.setting) for p in points if plotted(p, metric)]
    ys = [math.log(p.errors[metric]) for p in points if plotted(p, metric)]
    if len(xs) < 2:
        return math.nan
    return float(np.polyfit(xs, ys, 1)[0])


def grouped(study: Study) -> dict[tuple[str, str, str], list[Point]]:
    """The points by (model, integrator, reference)."""
    groups: dict[tuple[str, str, str], list[Point]] = {}
    for p in study.points:
        groups.setdefault((p.model, p.integrator, p.vs), []).append(p)
    return groups
