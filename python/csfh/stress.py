"""Stiff and extreme cases (PHYSICS.md section 8): each case runs with every applicable model and
integrator, and each run gets a verdict with its reason.

Verdicts:

* ``pass``: the run completed (no NaN), gained no energy where the physics cannot, and met the
  case's own accuracy check;
* ``limit``: a documented limit, with the reason (e.g. the paper's RK4 scheme with h0 = 2e-4 s
  cannot resolve a contact that lasts less than ten steps; the Moreau step must be much smaller
  than delta / v_T); the run may have stopped with a clear, specific error;
* ``fail``: anything else — a bug to fix.

Integrators: model exchange with fmpy's CVode (``ME``, rtol 1e-10), co-simulation with CVODE in
the FMU (``CS``, rtol 1e-10, method auto), the paper's RK4 + bisection (``RK4``, h0 = 2e-4 s,
1e-4 m) and the Moreau stepper (h = 1e-5 s).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .fmu_runner import SimulationError, simulate_cs, simulate_me
from .moreau import moreau
from .progress import Progress
from .results import Trajectory, write_json
from .rk4 import rk4_event
from .scene import Scene, scene_from_dict

M1, I1, G = 10.0, 0.1617, 9.81
DELTA = 0.02
RK4_H0, RK4_TOL = 2e-4, 1e-4
MOREAU_H = 1e-5
RTOL = 1e-10
ENERGY_RTOL = 1e4 * RTOL  # allowed numerical energy gain of ME/CS, relative to the energy scale
XI = {  # PHYSICS.md 4.4
    "LN_spheres": lambda cr: 0.75 * (1 - cr * cr),
    "LN_cylinders": lambda cr: 0.75 * (1 - cr * cr),
    "LN_ESDU": lambda cr: 0.75 * (1 - cr * cr),
    "HuntCrossley": lambda cr: 1.5 * (1 - cr),
    "Flores": lambda cr: 8 * (1 - cr) / (5 * cr),
}


@dataclass
class Run:
    case: str
    model: str
    integrator: str
    verdict: str
    reason: str
    wall_time: float = math.nan
    details: dict[str, Any] = field(default_factory=dict)


@dataclass
class Case:
    name: str
    group: str
    description: str
    scene: Scene
    runs: list[tuple[str, str]]  # (model, integrator)
    check: Callable[[Trajectory, str, str], tuple[bool, str, dict[str, Any]]]
    energy_gain_allowed: float = 0.0  # J, beyond the integrator tolerance
    quick: bool = False
    t_contact: float | None = None  # shortest expected contact duration, s (RK4 resolution)
    t_contact_by_model: dict[str, float] = field(default_factory=dict)


# ------------------------------------------------------------------------------------------
# independent oracles


def hertz_max_indentation(K: float, v: float, n: float = 1.5, m: float = M1) -> float:
    """Undamped Hertz impact: rho_max = ((n + 1) m v^2 / (2 K))^(1/(n+1)) (PHYSICS.md 7.2)."""
    return ((n + 1) * m * v * v / (2 * K)) ** (1 / (n + 1))


def hertz_contact_time(K: float, v: float) -> float:
    """t_c = 2.943276 rho_max / v for n = 1.5 (PHYSICS.md 7.2)."""
    return 2.943276 * hertz_max_indentation(K, v) / v


def effective_restitution(law: str, cr: float, n: float = 1.5) -> float:
    """e_eff of F = K rho^n (1 + xi rhodot/rhodot0), clamped >= 0, from the parameter-free
    scaled impact X'' = -X^n max(0, 1 + xi X'), X(0) = 0, X'(0) = 1 (PHYSICS.md 7.3), integrated
    here with scipy (independent of the FMU)."""
    from scipy.integrate import solve_ivp

    xi = XI[law](cr)

    def rhs(_: float, y: np.ndarray) -> list[float]:
        x = max(y[0], 0.0)
        return [y[1], -(x**n) * max(0.0, 1.0 + xi * y[1])]

    def back(_: float, y: np.ndarray) -> float:
        return y[0]

    back.terminal = True  # type: ignore[attr-defined]
    back.direction = -1  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs,
        (0, 1e3),
        [0.0, 1.0],
        method="Radau",
        rtol=1e-12,
        atol=1e-14,
        events=back,
        first_step=1e-6,
    )
    return float(-sol.y_events[0][0][1]) if sol.y_events[0].size else 0.0


# ------------------------------------------------------------------------------------------
# running one case


def _run_one(case: Case, model: str, integ: str) -> tuple[Trajectory | None, str | None, float]:
    t0 = time.perf_counter()
    try:
        if model == "Moreau":
            tr = moreau(case.scene, h=MOREAU_H)
        elif integ == "ME":
            tr = simulate_me(case.scene, model, rtol=RTOL)
        elif integ == "CS":
            tr = simulate_cs(case.scene, model, rtol=RTOL, communication_step=1e-3)
        else:
            tr = rk4_event(case.scene, model, h0=RK4_H0, tol=RK4_TOL)
    except (SimulationError, FloatingPointError, ValueError) as exc:
        return None, str(exc), time.perf_counter() - t0
    return tr, None, time.perf_counter() - t0


def _energy_allowance(tr: Trajectory, integ: str, E0: float) -> float:
    """Numerical energy gain an integrator may show without anything being wrong: for CVODE
    what its relative tolerance and its absolute tolerances (rtol times the state nominals,
    0.01 m and 1 m/s) allow, given the largest contact force and speed of the run; Moreau and
    RK4 round-off."""
    if integ in ("ME", "CS"):
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


# ------------------------------------------------------------------------------------------
# the cases


COMPLIANT_INTEGRATORS = ("ME", "CS", "RK4")


def _runs(models: tuple[str, ...]) -> list[tuple[str, str]]:
    out = []
    for m in models:
        if m == "Moreau":
            out.append(("Moreau", "Moreau"))
        else:
            out += [(m, i) for i in COMPLIANT_INTEGRATORS]
    return out


def _impact_scene(name: str, v: float, stop: float, params: dict[str, Any]) -> Scene:
    """Body 1 a micrometre above the bore, moving straight down at v; no gravity, no flexure,
    no friction: the bare normal impact."""
    return scene_from_dict(
        {
            "name": name,
            "stop_time": stop,
            "initial": {"q": [0.0, -(DELTA - 1e-6), 0.0], "u": [0.0, -v, 0.0]},
            "parts": {"flexure": False, "friction": False},
            "parameters": {"g": 0.0, **params},
            "integrator": {"output_interval": stop / 400},
        },
        f"stress:{name}",
    )


def _first(tr: Trajectory, key: str) -> float:
    vals = tr.contact_records.get(key, np.zeros(0))
    return float(vals[0]) if len(vals) else math.nan


def _hertz_check(K: float, v: float) -> Callable[..., tuple[bool, str, dict[str, Any]]]:
    rho = hertz_max_indentation(K, v)
    tc = hertz_contact_time(K, v)

    def check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
        rebound = _first(tr, "release_speed")
        if model == "Moreau":
            ok = abs(rebound - v) <= 1e-9 * v
            return ok, f"rebound {rebound:.6g} m/s vs {v:g} (c_r = 1)", {"rebound": rebound}
        if len(tr.contacts) < 1 or not math.isfinite(_first(tr, "t_release")):
            return False, "the contact did not end", {}
        dur = _first(tr, "t_release") - _first(tr, "t_onset")
        got = _first(tr, "max_indentation")  # not observable through CS: NaN, not checked
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


def _restitution_check(cr: float, v: float) -> Callable[..., tuple[bool, str, dict[str, Any]]]:
    def check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
        rebound = _first(tr, "release_speed")
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


def _no_extra_check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
    return True, "completed, no NaN, no energy gain", {}


PAPER_CONTACT_TIMES = {"LN_spheres": 4.6e-4, "LN_cylinders": 1.56e-3, "LN_ESDU": 2.0e-3}
"""Contact durations of the first impact of the paper's scenes (PHYSICS.md 7.3, 4.6), s."""


def build_cases(quick: bool = False) -> list[Case]:
    cases: list[Case] = []
    K_sph = 4.7353e10
    # --- contact stiffness K (LN K spheres, Table 2 exponent), v = 0.767 m/s
    for K in (1e9, 1e10, K_sph, 1e12, 1e13, 1e14):
        v = 0.767
        tc = hertz_contact_time(K, v)
        sc = _impact_scene(
            f"K={K:.0e}",
            v,
            1.5 * tc + 3e-6 / v,
            {"contact.K_from_materials": False, "contact.K_spheres_given": K, "contact.cr": 1.0},
        )
        c = Case(
            f"stiffness K = {K:.3g} N/m^1.5",
            "stiffness",
            "undamped (c_r = 1) normal impact at 0.767 m/s: Hertz rho_max, t_c, rebound",
            sc,
            _runs(("LN_spheres",)) + ([("Moreau", "Moreau")] if K == K_sph else []),
            _hertz_check(K, v),
            quick=K in (1e9, 1e14),
        )
        c.t_contact = tc
        cases.append(c)
    # --- impact speed 1e-3 ... 10 m/s, all three paper laws
    for v in (1e-3, 1e-2, 1e-1, 1.0, 10.0):
        tc = hertz_contact_time(K_sph, v)
        sc = _impact_scene(
            f"v={v:g}",
            v,
            4e-3 + 1.5 * tc + 3e-6 / v,
            {
                "contact.K_from_materials": False,
                "contact.K_spheres_given": K_sph,
                "contact.cr": 1.0,
            },
        )
        c = Case(
            f"impact speed {v:g} m/s",
            "speed",
            "undamped normal impact, K = 4.7353e10: Hertz rho_max, t_c, rebound (LN K "
            "spheres); completes, no energy gain (other laws)",
            sc,
            _runs(("LN_spheres", "Moreau")),
            _hertz_check(K_sph, v),
            quick=v == 10.0,
        )
        c.t_contact = tc
        cases.append(c)
        c2 = Case(
            f"impact speed {v:g} m/s, cylinders and ESDU",
            "speed",
            "undamped normal impact, LN K cylinders and LN-ESDU: completes, no energy gain",
            _impact_scene(f"v={v:g}", v, 4e-3 + 30 * tc, {"contact.cr": 1.0}),
            _runs(("LN_cylinders", "LN_ESDU")),
            _no_extra_check,
        )
        c2.t_contact = 3 * tc
        cases.append(c2)
    # --- restitution coefficient
    for cr in (0.01, 0.1, 0.5, 0.9, 1.0):
        v = 0.767
        tc = hertz_contact_time(K_sph, v)
        # a slow exit (low e_eff) takes about rho_max / (e v) to leave the contact
        e_min = min(
            effective_restitution(law, cr) for law in ("LN_spheres", "HuntCrossley", "Flores")
        )
        stop = 3 * tc + 3 * hertz_max_indentation(K_sph, v) / (max(e_min, 1e-3) * v)
        sc = _impact_scene(
            f"cr={cr:g}",
            v,
            stop,
            {"contact.K_from_materials": False, "contact.K_spheres_given": K_sph, "contact.cr": cr},
        )
        c = Case(
            f"restitution c_r = {cr:g}",
            "restitution",
            "normal impact at 0.767 m/s: the measured e_eff against the law's own "
            "scaled-impact prediction (LN cannot produce low restitution: e_eff >> c_r is "
            "its physics, not an error)",
            sc,
            _runs(("LN_spheres", "HuntCrossley", "Flores", "Moreau")),
            _restitution_check(cr, v),
            quick=cr in (0.01, 1.0),
        )
        c.t_contact = tc
        cases.append(c)
    # --- clearance
    for delta in (2e-2, 1e-3, 1e-4, 1e-5):
        sc = scene_from_dict(
            {
                "name": f"delta={delta:g}",
                "stop_time": 0.3,
                "initial": {"q": [0.0, 0.0, 0.0], "u": [0.05, 0.0, 0.0]},
                "parts": {"flexure": False, "friction": True},
                "parameters": {"contact.R1": 0.2 - delta},
                "integrator": {"output_interval": 1e-4},
            },
            f"stress:delta={delta:g}",
        )
        cases.append(
            Case(
                f"clearance delta = {delta:g} m",
                "clearance",
                "falls from the centre with 0.05 m/s sideways, friction on, 0.3 s: penetration "
                "bounded (compliant: the Hertz scale at the impact speed; Moreau: 5 % of delta)",
                sc,
                _runs(("LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau")),
                _clearance_check(delta),
                quick=delta == 1e-4,
            )
        )
    # --- grazing impact
    sc = scene_from_dict(
        {
            "name": "grazing",
            "stop_time": 0.2,
            "initial": {"q": [0.0, -(DELTA - 1e-7), 0.0], "u": [0.3, 0.0, 0.0]},
            "parts": {"flexure": False, "friction": False},
            "integrator": {"output_interval": 1e-4},
        },
        "stress:grazing",
    )
    cases.append(
        Case(
            "grazing impact",
            "grazing",
            "slides along the bore from a 0.1 micrometre gap at 0.3 m/s: onset speed "
            "~0 (floored at v_min), the contact force bounded by the centripetal and "
            "gravity load",
            sc,
            _runs(("LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau")),
            _grazing_check,
            quick=True,
        )
    )
    # --- resting contact, 10 s (the Zeno case)
    sc = scene_from_dict(
        {
            "name": "resting",
            "stop_time": 10.0,
            "initial": {"q": [0.0, 0.01, 0.0]},
            "parts": {"flexure": False, "friction": False},
            "integrator": {"output_interval": 1e-3},
        },
        "stress:resting",
    )
    cases.append(
        Case(
            "resting contact, 10 s",
            "resting",
            "central drop, c_r = 0.9: bounces accumulate (rigid t_inf = 1.486 s), then "
            "rest: bounded time and events, final static indentation (m g / K)^(2/3)",
            sc,
            _runs(("LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau")),
            _resting_check,
            quick=False,
        )
    )
    # --- high friction
    sc = scene_from_dict(
        {
            "name": "friction1",
            "stop_time": 0.5,
            "initial": {"q": [0.01, 0.01, 0.0]},
            "parts": {"flexure": False, "friction": True},
            "parameters": {"friction.fd": 1.0, "friction.fa": 1.0},
        },
        "stress:friction",
    )
    cases.append(
        Case(
            "high friction f = 1",
            "friction",
            "asymmetric impact with f_d = f_a = 1: |F_T| <= f_d F_N, no energy gain",
            sc,
            _runs(("LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau")),
            _friction_bound_check(1.0),
            quick=True,
        )
    )
    # --- stick-slip f_a != f_d (PHYSICS.md 7.6)
    sc = scene_from_dict(
        {
            "name": "stickslip",
            "stop_time": 0.5,
            "initial": {"q": [0.01, 0.01, 0.0]},
            "parts": {"flexure": False, "friction": True},
        },
        "stress:stickslip",
    )
    cases.append(
        Case(
            "stick-slip f_a = 0.11, f_d = 0.055",
            "friction",
            "first asymmetric impact in the band f_d < |Lambda_T|/Lambda_N < f_a: "
            "omega after it (PHYSICS.md 7.6: LN K spheres 0.7467, K cylinders 0.7561, "
            "Moreau paper rule 1.3567, memory rule 0.7376)",
            sc,
            _runs(("LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau")),
            _stickslip_check,
            quick=True,
        )
    )
    # --- eccentric mass centre
    sc = scene_from_dict(
        {
            "name": "eccentric",
            "stop_time": 0.5,
            # O1 = G1 + s1 at [0.01, 0.01], as in the asymmetric scene (G1 at [0.01, 0.01] put
            # O1 5 mm deep in the bore, which the FMU now refuses)
            "initial": {"q": [0.0, 0.005, 0.0]},
            "parts": {"flexure": False, "friction": True},
            "parameters": {"body1.s1[1]": 0.01, "body1.s1[2]": 0.005},
        },
        "stress:eccentric",
    )
    cases.append(
        Case(
            "eccentric mass centre",
            "eccentric",
            "s1 = [0.01, 0.005] m (G_NT != 0), asymmetric impact with friction: no energy gain",
            sc,
            _runs(("LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau")),
            _no_extra_check,
            quick=True,
        )
    )
    for c in cases:
        if c.group in ("clearance", "grazing", "resting", "friction", "eccentric"):
            c.t_contact_by_model = dict(PAPER_CONTACT_TIMES)
    return [c for c in cases if c.quick] if quick else cases


def _clearance_check(delta: float) -> Callable[..., tuple[bool, str, dict[str, Any]]]:
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
                    f"needs h << delta/|v_T| = {delta / 0.05:.2g} s (PHYSICS.md 8)"
                )
            return ok, why, {"penetration": pen}
        bound = 3 * hertz_max_indentation(4.7353e10 if model == "LN_spheres" else 2.27e9, v)
        if model == "LN_ESDU":
            bound *= 2
        ok = pen <= bound
        return ok, f"max indentation {pen:.3g} m, bound {bound:.3g} m", {"penetration": pen}

    return check


def _grazing_check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
    load = M1 * (0.3**2 / DELTA + G)  # centripetal + gravity at the bottom, N
    if model == "Moreau":
        pen = float(np.max(tr.table["indentation"]))
        ok = pen <= 1e-6
        return ok, f"penetration {pen:.3g} m (bound 1e-6 m)", {"penetration": pen}
    peak = float(np.max(tr.table["F_N"]))
    onset = _first(tr, "onset_speed")
    ok = float(np.min(tr.table["F_N"])) >= 0 and peak <= 3 * load
    return (
        ok,
        (
            f"onset rate {onset:.2g} m/s (floor 1e-3), peak F_N {peak:.4g} N, bound "
            f"3 m (v^2/delta + g) = {3 * load:.4g} N"
        ),
        {"peak_F_N": peak, "onset": onset},
    )


def _resting_check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
    vy_end = float(abs(tr.table["vy"][-1]))
    if model == "Moreau":
        lam = float(tr.table["Lambda_N"][-1]) / max(1, round(1e-3 / MOREAU_H))
        expected = M1 * G * MOREAU_H
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


def _friction_bound_check(fd: float) -> Callable[..., tuple[bool, str, dict[str, Any]]]:
    def check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
        F_N, F_T = tr.table["F_N"], tr.table["F_T"]
        ratio = float(np.max(np.abs(F_T) - fd * F_N - 1e-9 * np.abs(F_N)))
        ok = ratio <= 1e-6
        return ok, f"max(|F_T| - f_d F_N) = {ratio:.2g} N", {}

    return check


def _stickslip_check(tr: Trajectory, model: str, integ: str) -> tuple[bool, str, dict[str, Any]]:
    expected = {"LN_spheres": 0.7467, "LN_cylinders": 0.7561, "Moreau": 1.3567}.get(model)
    if expected is None:
        return True, "no reference number (completed, no energy gain)", {}
    if model == "Moreau":
        omega = float(tr.impacts["omega_after"][0])
        tol = 2e-3
    else:
        t_off = _first(tr, "t_release")
        i = int(np.searchsorted(tr.t, t_off))
        omega = float(tr.table["omega"][min(i, len(tr.t) - 1)])
        tol = 2e-3 if integ != "RK4" else 0.05
    ok = abs(omega - expected) <= tol * expected
    return ok, f"omega after the first contact {omega:.4f} rad/s (PHYSICS.md 7.6: {expected})", {}


# ------------------------------------------------------------------------------------------
# the suite and its report


def run_suite(
    out: Path | None = None, *, quick: bool = False, quiet: bool = True, only: str | None = None
) -> list[Run]:
    cases = build_cases(quick)
    if only:
        cases = [c for c in cases if only in c.name or only == c.group]
    total = sum(len(c.runs) for c in cases)
    progress = Progress("stress", quiet=quiet)
    runs: list[Run] = []
    for case in cases:
        for model, integ in case.runs:
            runs.append(evaluate(case, model, integ))
            progress.update(len(runs) / total)
    progress.close()
    if out is not None:
        write_report(cases, runs, out)
    return runs


def write_report(cases: list[Case], runs: list[Run], out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    write_json(
        out / "stress.json",
        {
            "runs": [r.__dict__ for r in runs],
            "cases": [
                {"name": c.name, "group": c.group, "description": c.description} for c in cases
            ],
        },
    )
    counts = {v: sum(r.verdict == v for r in runs) for v in ("pass", "limit", "fail")}
    lines = [
        "# Stiff and extreme cases",
        "",
        f"{len(runs)} runs: {counts['pass']} pass, {counts['limit']} documented limits, "
        f"{counts['fail']} fail.",
        "",
        __doc__.split("\n\n", 1)[1].strip(),
        "",
        "## Cases",
        "",
    ]
    for c in cases:
        lines.append(f"* **{c.name}**: {c.description}")
    lines += [
        "",
        "## Results",
        "",
        "| case | model | integrator | verdict | reason | wall [s] |",
        "|---|---|---|---|---|---|",
    ]
    for r in runs:
        verdict = {"pass": "pass", "limit": "**limit**", "fail": "**FAIL**"}[r.verdict]
        lines.append(
            f"| {r.case} | {r.model} | {r.integrator} | {verdict} | "
            f"{r.reason.replace('|', '/')} | {r.wall_time:.3g} |"
        )
    (out / "stress.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
