"""Exploration and search over a study's design variables: seeded quasi-random samples
(scipy.stats.qmc: scrambled Sobol points or a Latin hypercube), the Pareto front of the feasible
designs, and scipy's differential evolution whose every population is one batch of shock runs.

The search minimises the study's search objective, divided by its value at the centre of the
ranges, plus a penalty for infeasible designs: PENALTY times the sum of the margins' shortfalls
(so that every feasible design ranks before every infeasible one whose shortfall exceeds its
objective's spread)."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .spec import DesignStudy

PENALTY = 100.0
"""The weight of a margin's shortfall in the search's objective."""

Evaluate = Callable[[np.ndarray, str], list[dict[str, Any]]]
"""Evaluates the designs (rows) under a progress label: one measures dict per design."""


def bounds(study: DesignStudy) -> tuple[np.ndarray, np.ndarray]:
    lo = np.array([r[0] for r in study.variables.values()])
    hi = np.array([r[1] for r in study.variables.values()])
    return lo, hi


def sample(study: DesignStudy, n: int) -> np.ndarray:
    """n designs over the ranges: scrambled Sobol points (the first n of the sequence) or a
    Latin hypercube, seeded by the study's seed."""
    from scipy.stats import qmc

    d = len(study.variables)
    engine: Any
    if study.method == "sobol":
        engine = qmc.Sobol(d, scramble=True, seed=study.seed)
    else:
        engine = qmc.LatinHypercube(d, seed=study.seed)
    with warnings.catch_warnings():  # Sobol's balance warning for n not a power of 2
        warnings.simplefilter("ignore", UserWarning)
        unit = engine.random(n)
    lo, hi = bounds(study)
    return np.asarray(qmc.scale(unit, lo, hi))


def objective_matrix(designs: Sequence[dict[str, Any]], names: Sequence[str]) -> np.ndarray:
    return np.array([[float(d["objectives"][k]) for k in names] for d in designs])


def pareto(values: np.ndarray) -> np.ndarray:
    """Indices of the rows that no other row dominates (<= in every column, < in one),
    minimisation; of equal rows the first."""
    keep = []
    for i, v in enumerate(values):
        dominated = np.all(values <= v, axis=1) & np.any(values < v, axis=1)
        equal_before = np.all(values[:i] == v, axis=1)
        if not dominated.any() and not equal_before.any():
            keep.append(i)
    return np.array(keep, dtype=int)


def feasible_front(designs: Sequence[dict[str, Any]], names: Sequence[str]) -> list[int]:
    """Indices (into designs) of the Pareto front of the feasible designs."""
    ok = [i for i, d in enumerate(designs) if d["feasible"]]
    if not ok:
        return []
    front = pareto(objective_matrix([designs[i] for i in ok], names))
    return [ok[i] for i in front]


def penalised(study: DesignStudy, design: dict[str, Any], scale: float) -> float:
    """The search's objective of one design (module docstring)."""
    value = float(design["objectives"][study.search_objective]) / scale
    return value + PENALTY * float(design["violation"])


def differential_evolution(
    study: DesignStudy, evaluate: Evaluate, scale: float
) -> tuple[dict[str, Any], list[dict[str, Any]], int]:
    """scipy's differential evolution (seeded, deferred updating: each generation is evaluated
    as one population, one batch of runs; no polishing); the best design's measures, every
    design it evaluated, and the generations run."""
    from scipy.optimize import differential_evolution as de

    lo, hi = bounds(study)
    seen: list[dict[str, Any]] = []
    generation = [0]

    def population(x: np.ndarray) -> np.ndarray:  # x: (variables, members)
        designs = evaluate(x.T, f"design search, generation {generation[0]}")
        generation[0] += 1
        seen.extend(designs)
        return np.array([penalised(study, d, scale) for d in designs])

    with warnings.catch_warnings():  # vectorized implies deferred updating: said, not warned
        warnings.simplefilter("ignore", UserWarning)
        result = de(
            population,
            list(zip(lo, hi, strict=True)),
            seed=study.seed,
            popsize=study.population,
            maxiter=study.generations,
            vectorized=True,
            updating="deferred",
            polish=False,
            init="sobol",
            tol=0.0,
        )
    best = evaluate(np.atleast_2d(result.x), "design search, best")[0]
    return best, seen, generation[0]
