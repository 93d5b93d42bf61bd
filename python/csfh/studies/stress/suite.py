"""Stiff and extreme cases (docs/model.md §8): each case runs with every applicable model and
integrator, and each run gets a verdict with its reason.

Verdicts:

* ``pass``: the run completed (no NaN), gained no energy where the physics cannot, and met the
  case's own accuracy check;
* ``limit``: a documented limit, with the reason (e.g. the paper's RK4 scheme with h0 = 2e-4 s
  cannot resolve a contact that lasts less than ten steps; the Moreau step must be much smaller
  than delta / v_T); the run may have stopped with a clear, specific error;
* ``fail``: anything else — a bug to fix.

Integrators: model exchange with fmpy's CVode (``ME``, rtol 1e-10), co-simulation with the
integrator in the FMU (``CS``, rtol 1e-10, method auto: RK45, BDF where the motion is stiff; and
``CS-RK45``, the explicit Runge-Kutta 5(4) alone, however stiff), the paper's RK4 + bisection
(``RK4``, h0 = 2e-4 s, 1e-4 m) and the Moreau stepper (h = 1e-5 s).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...errors import SimulationError
from ...model import model_info
from ...progress import Progress
from ...runners.fmu import simulate_cs, simulate_me
from ...runners.moreau import moreau
from ...runners.rk4 import rk4_event
from ...trajectory import Trajectory
from .cases import Case
from .oracles import M1, MOREAU_STEP, RK4_H0, RK4_TOL, RTOL

ENERGY_RTOL = 1e4 * RTOL  # allowed numerical energy gain of ME/CS, relative to the energy scale
CS_METHODS: dict[str, str | None] = {"CS": None, "CS-RK45": "RK45"}
"""The co-simulation integrators: their solver.method (None: the FMU's default, auto)."""


@dataclass
class Run:
    case: str
    model: str
    integrator: str
    verdict: str
    reason: str
    wall_time: float = math.nan
    details: dict[str, Any] = field(default_factory=dict)


def _run_one(case: Case, model: str, integ: str) -> tuple[Trajectory | None, str | None, float]:
    t0 = time.perf_counter()
    try:
        if model == "Moreau":
            tr = moreau(case.scene, h=MOREAU_STEP)
        elif integ == "ME":
            tr = simulate_me(case.scene, model, rtol=RTOL)
        elif integ in CS_METHODS:
            method = CS_METHODS[integ]
            parameters = (
                None
                if method is None
                else {"solver.method": model_info.enumeration("SolverMethod")[method]}
            )
            tr = simulate_cs(
                case.scene, model, rtol=RTOL, communication_step=1e-3, parameters=parameters
            )
        else:
            tr = rk4_event(case.scene, model, h0=RK4_H0, tol=RK4_TOL)
    except (SimulationError, FloatingPointError, ValueError) as exc:
        return None, str(exc), time.perf_counter() - t0
    return tr, None, time.perf_counter() - t0


def _energy_allowance(tr: Trajectory, integ: str, E0: float) -> float:
    """Numerical energy gain an integrator may show without anything being wrong: for the
    adaptive integrators (ME, CS) what their relative tolerance and their absolute tolerances
    (rtol times the state nominals, 0.01 m and 1 m/s) allow, given the largest contact force and
    speed of the run; Moreau and RK4 round-off."""
    if integ == "ME" or integ in CS_METHODS:
        peak_F = float(np.max(np.abs(tr.table["F_N"]), initial=0.0))
        v_max = float(np.max(np.hypot(tr.table["vx"], tr.table["vy"]), initial=0.0))
        return ENERGY_RTOL * E0 + 10 * (peak_F * 0.01 * RTOL + M1 * v_max * RTOL)
    return 1e-9 * E0


def _energy_gain(tr: Trajectory) -> float:
    E = tr.table["energy"]
    return float(np.max(E - E[0])) if len(E) else 0.0


def _has_nan(tr: Trajectory) -> bool:
    return any(not np.all(np.isfinite(v)) for k, v in tr.table.items() if k != "mode")


def evaluate(case: Case, model: str, integ: str) -> Run:
    tr, error, wall = _run_one(case, model, integ)
    t_c = case.t_contact_by_model.get(model, case.t_contact)
    rk4_limit = integ == "RK4" and t_c is not None and t_c < 10 * RK4_H0
    limit_reason = (
        (
            f"the paper's RK4 with h0 = {RK4_H0:g} s cannot resolve a contact of "
            f"{t_c:.2g} s (fewer than ten steps)"
        )
        if rk4_limit
        else ""
    )
    if tr is None:
        verdict = "limit" if rk4_limit else "fail"
        return Run(
            case.name,
            model,
            integ,
            verdict,
            f"stopped: {error}" + (f"; {limit_reason}" if rk4_limit else ""),
            wall,
        )
    if _has_nan(tr):
        return Run(
            case.name,
            model,
            integ,
            "limit" if rk4_limit else "fail",
            "NaN in the output" + (f"; {limit_reason}" if rk4_limit else ""),
            wall,
        )
    E0 = abs(float(tr.table["energy"][0])) + 1e-12
    gain = _energy_gain(tr)
    tol_E = _energy_allowance(tr, integ, E0) + case.energy_gain_allowed
    details: dict[str, Any] = {
        "energy_gain_J": gain,
        "contacts": len(tr.contacts),
        "steps": tr.stats.get("steps"),
        "rhs_evaluations": tr.stats.get("rhs_evaluations"),
    }
    ok, why, more = case.check(tr, model, integ)
    details.update(more)
    if gain > tol_E:
        reason = f"energy gained: {gain:.3g} J (allowed {tol_E:.2g} J)"
        truncation = integ == "RK4" and gain <= 1e-3 * E0
        if truncation and not rk4_limit:
            limit_reason = (
                "explicit RK4 does not conserve energy: a gain of "
                f"{gain / E0:.1e} of the energy is its truncation error at "
                f"h0 = {RK4_H0:g} s"
            )
        return Run(
            case.name,
            model,
            integ,
            "limit" if rk4_limit or truncation else "fail",
            reason + (f"; {limit_reason}" if rk4_limit or truncation else ""),
            wall,
            details,
        )
    if not ok:
        verdict = "limit" if rk4_limit or why.startswith("limit:") else "fail"
        why = why.removeprefix("limit: ")
        return Run(
            case.name,
            model,
            integ,
            verdict,
            why + (f"; {limit_reason}" if rk4_limit else ""),
            wall,
            details,
        )
    return Run(case.name, model, integ, "pass", why, wall, details)


def run_suite(cases: Sequence[Case], *, quiet: bool = True) -> list[Run]:
    """Every run of every case, each with its verdict."""
    total = sum(len(c.runs) for c in cases)
    progress = Progress("stress", quiet=quiet, total=total)
    runs: list[Run] = []
    for case in cases:
        for model, integ in case.runs:
            runs.append(evaluate(case, model, integ))
            progress.update(len(runs))
    progress.close()
    return runs
