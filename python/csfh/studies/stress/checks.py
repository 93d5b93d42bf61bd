"""The accuracy checks of the stress cases: each takes a run (trajectory, model, integrator) and
says whether it meets the case's own expectation, why, and the numbers."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ...trajectory import Trajectory
from .oracles import (
    DELTA,
    M1,
    MOREAU_STEP,
    G,
    effective_restitution,
    hertz_contact_time,
    hertz_max_indentation,
)

Check = Callable[[Trajectory, str, str], tuple[bool, str, dict[str, Any]]]
"""(trajectory, model, integrator) -> (passed, reason, numbers). A reason that starts with
"limit: " marks a documented limit rather than a failure."""


def first(tr: Trajectory, key: str) -> float:
    vals = tr.contact_records.get(key, np.zeros(0))
    return float(vals[0]) if len(vals) else math.nan


def hertz_check(K: float, v: float) -> Check:
    rho = hertz_max_indentation(K, v)
    tc = hertz_contact_time(K, v)

    def check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
        rebound = first(tr, "release_speed")
        if model == "Moreau":
            ok = abs(rebound - v) <= 1e-9 * v
            return ok, f"rebound {rebound:.6g} m/s vs {v:g} (c_r = 1)", {"rebound": rebound}
        if len(tr.contacts) < 1 or not math.isfinite(first(tr, "t_release")):
            return False, "the contact did not end", {}
        dur = first(tr, "t_release") - first(tr, "t_onset")
        got = first(tr, "max_indentation")  # not observable through CS: NaN, not checked
        errs = {
            "max_indentation": abs(got / rho - 1),
            "contact_time": abs(dur / tc - 1),
            "rebound": abs(rebound / v - 1),
        }
        errs = {k: e for k, e in errs.items() if math.isfinite(e)}
        tol = 1e-3 if integ != "RK4" else 0.05
        ok = len(errs) >= 2 and all(e <= tol for e in errs.values())
        return (
            ok,
            (
                f"rho_max {got:.4g} m (Hertz {rho:.4g}), t_c {dur:.4g} s (Hertz {tc:.4g}), "
                f"rebound {rebound:.5g} m/s; worst relative error "
                f"{max(errs.values(), default=math.nan):.1e} (tolerance {tol:g})"
            ),
            errs,
        )

    return check


def restitution_check(cr: float, v: float) -> Check:
    def check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
        rebound = first(tr, "release_speed")
        e = rebound / v
        expected = cr if model == "Moreau" else effective_restitution(model, cr)
        tol = 1e-9 if model == "Moreau" else (1e-3 if integ != "RK4" else 0.05)
        ok = abs(e - expected) <= tol * max(expected, 1e-3)
        return (
            ok,
            (
                f"e_eff {e:.5f}, expected {expected:.5f} "
                f"({'c_r' if model == 'Moreau' else 'scaled impact ODE'})"
            ),
            {"e_eff": e},
        )

    return check


def no_extra_check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
    return True, "completed, no NaN, no energy gain", {}


def clearance_check(delta: float) -> Check:
    def check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
        pen = float(np.max(tr.table["indentation"]))
        v = math.hypot(0.05, math.sqrt(2 * G * delta))
        if model == "Moreau":
            bound = 0.05 * delta
            ok = pen <= bound
            why = f"penetration {pen:.3g} m, bound 5 % of delta = {bound:.3g} m"
            if not ok:
                why = (
                    f"limit: penetration {pen:.3g} m > {bound:.3g} m: the midpoint scheme "
                    f"needs h << delta/|v_T| = {delta / 0.05:.2g} s (docs/model.md §8)"
                )
            return ok, why, {"penetration": pen}
        bound = 3 * hertz_max_indentation(4.7353e10 if model == "LN_spheres" else 2.27e9, v)
        if model == "LN_ESDU":
            bound *= 2
        ok = pen <= bound
        return ok, f"max indentation {pen:.3g} m, bound {bound:.3g} m", {"penetration": pen}

    return check


def grazing_check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
    load = M1 * (0.3**2 / DELTA + G)  # centripetal + gravity at the bottom, N
    if model == "Moreau":
        pen = float(np.max(tr.table["indentation"]))
        ok = pen <= 1e-6
        return ok, f"penetration {pen:.3g} m (bound 1e-6 m)", {"penetration": pen}
    peak = float(np.max(tr.table["F_N"]))
    onset = first(tr, "onset_speed")
    ok = float(np.min(tr.table["F_N"])) >= 0 and peak <= 3 * load
    return (
        ok,
        (
            f"onset rate {onset:.2g} m/s (floor 1e-3), peak F_N {peak:.4g} N, bound "
            f"3 m (v^2/delta + g) = {3 * load:.4g} N"
        ),
        {"peak_F_N": peak, "onset": onset},
    )


def resting_check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
    vy_end = float(abs(tr.table["vy"][-1]))
    if model == "Moreau":
        lam = float(tr.table["Lambda_N"][-1]) / max(1, round(1e-3 / MOREAU_STEP))
        expected = M1 * G * MOREAU_STEP
        ok = abs(lam / expected - 1) < 1e-6 and vy_end < 1e-6
        return (
            ok,
            (
                f"final impulse per step {lam:.6g} N s (m g h = {expected:.6g}), "
                f"|vy| {vy_end:.2g} m/s, {len(tr.contacts)} onsets"
            ),
            {},
        )
    K = {"LN_spheres": 4.7353e10, "LN_cylinders": 2.2656e9}.get(model)
    ind = float(tr.table["indentation"][-1])
    if K is None:  # ESDU: the static indentation solves F_el(rho) = m g; check equilibrium
        ok = vy_end < 1e-4 and abs(float(tr.table["F_N"][-1]) / (M1 * G) - 1) < 1e-3
        return (
            ok,
            (
                f"at rest: F_N {tr.table['F_N'][-1]:.5g} N = m g {M1 * G:.5g} N, |vy| "
                f"{vy_end:.2g} m/s, {len(tr.contacts)} contacts"
            ),
            {},
        )
    static = (M1 * G / K) ** (2 / 3)
    ok = vy_end < 1e-4 and abs(ind / static - 1) < 1e-2
    return (
        ok,
        (
            f"at rest: indentation {ind:.4g} m (static {static:.4g}), |vy| {vy_end:.2g} "
            f"m/s, {len(tr.contacts)} contacts"
        ),
        {"indentation": ind},
    )


def friction_bound_check(fd: float) -> Check:
    def check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
        F_N, F_T = tr.table["F_N"], tr.table["F_T"]
        ratio = float(np.max(np.abs(F_T) - fd * F_N - 1e-9 * np.abs(F_N)))
        ok = ratio <= 1e-6
        return ok, f"max(|F_T| - f_d F_N) = {ratio:.2g} N", {}

    return check


def stickslip_check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
    expected = {"LN_spheres": 0.7467, "LN_cylinders": 0.7561, "Moreau": 1.3567}.get(model)
    if expected is None:
        return True, "no reference number (completed, no energy gain)", {}
    if model == "Moreau":
        omega = float(tr.impacts["omega_after"][0])
        tol = 2e-3
    else:
        t_off = first(tr, "t_release")
        i = int(np.searchsorted(tr.t, t_off))
        omega = float(tr.table["omega"][min(i, len(tr.t) - 1)])
        tol = 2e-3 if integ != "RK4" else 0.05
    ok = abs(omega - expected) <= tol * expected
    text = f"omega after the first contact {omega:.4f} rad/s (docs/model.md §7.6: {expected})"
    return ok, text, {}
