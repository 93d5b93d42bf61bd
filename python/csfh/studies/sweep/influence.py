"""The influence measure of the sweep: when and how much a perturbed signal departs from the
nominal one (see csfh.studies.sweep.analysis for the definitions)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.ndimage import maximum_filter1d, minimum_filter1d


@dataclass(frozen=True)
class MeasureSettings:
    tau: float = 0.05  # departure threshold for x, y, theta: fraction of the nominal range
    tau_force: float = 0.10  # ... for F_N, F_T (impact peaks scale as a power of the speed)
    window: float = 2e-3  # s, time tolerance of the tube
    early_fraction: float = 0.25  # high: departure within this fraction of the horizon
    nrms_medium: float = 0.25  # medium: late departure with at least this NRMS
    none_rel: float = 1e-9  # none: max |b - a| <= none_rel * S


def _sliding(a: np.ndarray, w: int, fn: Any) -> np.ndarray:
    """Running minimum or maximum over +-w samples (the edges repeat the end values)."""
    if w <= 0:
        return a
    return fn(a, size=2 * w + 1, mode="nearest")


def influence(
    t: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    settings: MeasureSettings | None = None,
    force: bool = False,
) -> dict[str, Any]:
    """Compare a perturbed signal b with the nominal a on the uniform grid t (see the module
    docstring; `force` selects the force threshold). Returns t_dep (s, None if no departure),
    nrms, max_dev (max |b - a| / S), peak_change, scale S and level (0-3)."""
    s = settings or MeasureSettings()
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    horizon = float(t[-1] - t[0])
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    scale = float(np.max(a) - np.min(a))
    diff = np.abs(b - a)
    max_diff = float(np.max(diff)) if len(diff) else 0.0
    w = max(0, round(s.window / dt))
    tol = (s.tau_force if force else s.tau) * scale
    lo_a, hi_a = _sliding(a, w, minimum_filter1d), _sliding(a, w, maximum_filter1d)
    lo_b, hi_b = _sliding(b, w, minimum_filter1d), _sliding(b, w, maximum_filter1d)
    out = (b < lo_a - tol) | (b > hi_a + tol) | (a < lo_b - tol) | (a > hi_b + tol)
    t_dep = float(t[int(np.argmax(out))]) if np.any(out) else None
    nrms = _nrms(a, b)
    return {
        "t_dep": t_dep,
        "nrms": nrms,
        "max_dev": _ratio(max_diff, scale, 0.0 if max_diff == 0 else math.inf),
        "peak_change": _peak_change(a, b),
        "scale": scale,
        "level": _level(s, max_diff, scale, t_dep, t[0], horizon, nrms),
    }


def _ratio(x: float, y: float, otherwise: float) -> float:
    return x / y if y > 0 else otherwise


def _nrms(a: np.ndarray, b: np.ndarray) -> float:
    """RMS(b - a) / sqrt(var a + var b): 0 for identical signals, 1 for a zero spread."""
    rms = float(np.sqrt(np.mean((b - a) ** 2))) if len(a) else 0.0
    den = float(np.sqrt(np.var(a) + np.var(b))) if len(a) else 0.0
    return _ratio(rms, den, 0.0 if rms == 0 else 1.0)


def _peak_change(a: np.ndarray, b: np.ndarray) -> float:
    pa, pb = float(np.max(np.abs(a))), float(np.max(np.abs(b)))
    return (pb - pa) / pa if pa > 0 else (0.0 if pb == 0 else math.inf)


def _level(
    s: MeasureSettings,
    max_diff: float,
    scale: float,
    t_dep: float | None,
    t0: float,
    horizon: float,
    nrms: float,
) -> int:
    """The level of the module docstring: 0 none, 1 low, 2 medium, 3 high."""
    if max_diff == 0.0 or (scale > 0 and max_diff <= s.none_rel * scale):
        return 0
    if t_dep is not None and t_dep - t0 <= s.early_fraction * horizon:
        return 3
    if t_dep is not None and nrms >= s.nrms_medium:
        return 2
    return 1
