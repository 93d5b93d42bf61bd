"""The stress cases (docs/model.md §8): contact stiffness, impact speed, restitution,
clearance, a grazing impact, resting contact, high friction, stick-slip and an eccentric mass
centre, each with its scene, the runs (model, integrator) it applies to, and its check."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ...model.scene import Scene, scene_from_dict
from . import checks
from .checks import Check
from .oracles import DELTA, effective_restitution, hertz_contact_time, hertz_max_indentation


@dataclass
class Case:
    name: str
    group: str
    description: str
    scene: Scene
    runs: list[tuple[str, str]]  # (model, integrator)
    check: Check
    energy_gain_allowed: float = 0.0  # J, beyond the integrator tolerance
    quick: bool = False
    t_contact: float | None = None  # shortest expected contact duration, s (RK4 resolution)
    t_contact_by_model: dict[str, float] = field(default_factory=dict)


COMPLIANT_INTEGRATORS = ("ME", "CS", "CS-RK45", "RK4")


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


PAPER_CONTACT_TIMES = {"LN_spheres": 4.6e-4, "LN_cylinders": 1.56e-3, "LN_ESDU": 2.0e-3}
"""Contact durations of the first impact of the paper's scenes (docs/model.md §7.3, 4.6), s."""


def build_cases(quick: bool = False) -> list[Case]:
    cases: list[Case] = []
    K_sph = 4.7353e10
    # --- contact stiffness K (LN_spheres, Table 2 exponent), v = 0.767 m/s
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
            checks.hertz_check(K, v),
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
            "undamped normal impact, K = 4.7353e10: Hertz rho_max, t_c, rebound (LN_spheres); "
            "completes, no energy gain (other laws)",
            sc,
            _runs(("LN_spheres", "Moreau")),
            checks.hertz_check(K_sph, v),
            quick=v == 10.0,
        )
        c.t_contact = tc
        cases.append(c)
        c2 = Case(
            f"impact speed {v:g} m/s, cylinders and ESDU",
            "speed",
            "undamped normal impact, LN_cylinders and LN_ESDU: completes, no energy gain",
            _impact_scene(f"v={v:g}", v, 4e-3 + 30 * tc, {"contact.cr": 1.0}),
            _runs(("LN_cylinders", "LN_ESDU")),
            checks.no_extra_check,
        )
        c2.t_contact = 3 * tc
        cases.append(c2)
    # --- restitution coefficient
    for cr in (0.01, 0.1, 0.5, 0.9, 1.0):
        v = 0.767
        tc = hertz_contact_time(K_sph, v)
        # a slow exit (low e_eff) takes about rho_max / (e v) to leave the contact
        e_min = min(  # an estimate for the horizon: a loose tolerance does
            effective_restitution(law, cr, rtol=1e-6)
            for law in ("LN_spheres", "HuntCrossley", "Flores")
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
            checks.restitution_check(cr, v),
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
                checks.clearance_check(delta),
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
            checks.grazing_check,
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
            checks.resting_check,
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
            checks.friction_bound_check(1.0),
            quick=True,
        )
    )
    # --- stick-slip f_a != f_d (docs/model.md §7.6)
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
            "omega after it (docs/model.md §7.6: LN_spheres 0.7467, LN_cylinders 0.7561, "
            "Moreau paper rule 1.3567, memory rule 0.7376)",
            sc,
            _runs(("LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau")),
            checks.stickslip_check,
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
            checks.no_extra_check,
            quick=True,
        )
    )
    for c in cases:
        if c.group in ("clearance", "grazing", "resting", "friction", "eccentric"):
            c.t_contact_by_model = dict(PAPER_CONTACT_TIMES)
    return [c for c in cases if c.quick] if quick else cases


def select_cases(quick: bool = False, only: str | None = None) -> list[Case]:
    """The cases to run: all, or the reduced suite (`quick`, as in CI), and of those the ones
    whose name contains `only` or whose group is `only`."""
    cases = build_cases(quick)
    if only:
        cases = [c for c in cases if only in c.name or only == c.group]
    return cases
