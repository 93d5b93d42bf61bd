"""Global sensitivity: Sobol first-order and total indices (SALib's Saltelli sampling and Sobol
analysis, without second-order indices: N (D + 2) evaluations) with bootstrap confidence
intervals, of each objective to a set of inputs over their ranges.

Two sets: the study's design variables over their ranges, and the paper's Table 4-5 parameters
of the event-driven models (csfh.studies.sweep.parameters) about the scene's own design, each
scaled by a factor in [1 - PAPER_SPREAD, 1 + PAPER_SPREAD] (R1 moves by that fraction of the
clearance instead, so that it stays inside the bore). Both at one direction of the shock, the
scene's worst (`analyse` is given the evaluation)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ...errors import InstallError
from ...model.instance import nominal_values
from ...model.scene import Scene
from ..sweep.parameters import ALL_PARAMETERS, PARAMETERS

CONFIDENCE = 0.95
RESAMPLES = 200
"""Bootstrap resamples of the confidence intervals."""
PAPER_SPREAD = 0.1
"""The relative range of the paper's parameters about their nominal values."""


def problem(names: Sequence[str], ranges: Sequence[tuple[float, float]]) -> dict[str, Any]:
    return {
        "num_vars": len(names),
        "names": list(names),
        "bounds": [[float(lo), float(hi)] for lo, hi in ranges],
    }


def _salib() -> Any:
    """SALib, or InstallError saying how to install it (the extra "design")."""
    try:
        import SALib
    except ImportError:
        raise InstallError(
            "the Sobol indices of csfh design need SALib: pip install 'csfh[design]' (or set "
            "[sensitivity] samples = 0 in the study)"
        ) from None
    return SALib


def saltelli(prob: dict[str, Any], n: int, seed: int) -> np.ndarray:
    """SALib's Sobol-sequence (Saltelli) sample of N (D + 2) points."""
    _salib()
    from SALib.sample import sobol as sobol_sample

    return np.asarray(sobol_sample.sample(prob, n, calc_second_order=False, seed=seed))


def indices(prob: dict[str, Any], y: np.ndarray, seed: int) -> dict[str, Any]:
    """S1 and ST with their confidence half-widths for one output (all zero for an output that
    does not vary)."""
    from SALib.analyze import sobol

    d = prob["num_vars"]
    if not np.ptp(y) > 0:
        zero = [0.0] * d
        return {"S1": zero, "S1_conf": zero, "ST": zero, "ST_conf": zero, "constant": True}
    r = sobol.analyze(
        prob,
        np.asarray(y, dtype=float),
        calc_second_order=False,
        num_resamples=RESAMPLES,
        conf_level=CONFIDENCE,
        seed=seed,
    )
    out: dict[str, Any] = {k: [float(v) for v in r[k]] for k in ("S1", "S1_conf", "ST", "ST_conf")}
    out["constant"] = False
    return out


def sobol_indices(
    names: Sequence[str],
    ranges: Sequence[tuple[float, float]],
    model: Callable[[np.ndarray], dict[str, np.ndarray]],
    n: int,
    seed: int,
) -> dict[str, Any]:
    """The indices of every output of `model` (inputs as rows -> output name: values)."""
    prob = problem(names, ranges)
    x = saltelli(prob, n, seed)
    outputs = model(x)
    return {
        "inputs": list(names),
        "ranges": [list(r) for r in prob["bounds"]],
        "base_samples": n,
        "evaluations": len(x),
        "confidence": CONFIDENCE,
        "indices": {k: indices(prob, np.asarray(v), seed) for k, v in outputs.items()},
    }


def paper_inputs(scene: Scene) -> tuple[list[str], list[tuple[float, float]], Callable]:
    """The paper's Table 4 parameters as factors on their nominal values (module docstring),
    and the map from a row of factors to the parameter overrides."""
    rows = [p for p in PARAMETERS if p.table4 is not None]
    names = [v for p in rows for v in p.variables]
    nominal = nominal_values(scene, [*names, "contact.R1", "contact.R2"])
    clearance = nominal["contact.R2"] - nominal["contact.R1"]
    ranges = [(1.0 - PAPER_SPREAD, 1.0 + PAPER_SPREAD)] * len(rows)

    def overrides(factors: np.ndarray) -> dict[str, float]:
        out = {}
        for p, f in zip(rows, factors, strict=True):
            for v in p.variables:
                if v == "contact.R1":
                    out[v] = nominal[v] + (f - 1.0) * clearance
                else:
                    out[v] = nominal[v] * f
        return out

    return [p.key for p in rows], ranges, overrides


def table4_agreement(s: dict[str, Any]) -> dict[str, float | None]:
    """Per output, Spearman's rank correlation between the paper parameters' total indices and
    their mean level in the paper's Table 4 (the arrows the sweep measures; None: an output or
    a ranking that does not vary)."""
    from scipy.stats import spearmanr

    levels = [float(np.mean(ALL_PARAMETERS[k].table4 or (0,))) for k in s["inputs"]]
    out: dict[str, float | None] = {}
    for name, r in s["indices"].items():
        if r["constant"] or not np.ptp(r["ST"]) > 0:
            out[name] = None
            continue
        rho = float(spearmanr(r["ST"], levels).statistic)
        out[name] = None if math.isnan(rho) else rho
    return out
