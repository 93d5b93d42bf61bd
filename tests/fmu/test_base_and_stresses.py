"""Base acceleration, stresses and contact pressure through fmpy (docs/model.md §14).

* a_base = 0 leaves the trajectory bitwise unchanged, and a_base acts exactly as the force
  -m1 a_base at G1 (bitwise, in co-simulation, model exchange and the Moreau stepper);
* the energy balance of the relative-frame energy under a varying a_base (Eq. (14.2));
* a slow ramp of a_base ends at the static equilibrium found independently (the minimum of the
  potential, with the flexure stiffness from a quadrature of Castigliano's integrals);
* contact.pressure_max is the Hertz formula at every sample; flexure.stress_max for a static load
  is the largest outer-fibre stress of the internal forces along the arc, from the equilibrium of
  the free part of the arc under the tip wrench that holds body 1, at many sections;
* the tracked stress peak against a fine grid;
* scale consistency (§14.6): the paper's scene with every quantity of dimension M^a L^b T^c
  scaled by s^(3a + b + c) reproduces x/s and theta at times x s;
* the MEMS scene (§14.7) runs and its masses follow from silicon's density and the geometry.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from fmi2_calls import STATES, TIGHT, MakeFmu, scene_start_values, set_values
from fmpy import simulate_fmu
from fmpy.model_description import ModelDescription
from scipy.optimize import minimize

from csfh import load_scene, moreau, scene_from_dict, simulate


def run_cs(
    make_fmu: MakeFmu,
    md: ModelDescription,
    values: dict[str, Any],
    stop: float,
    step: float,
    outputs: Iterable[str],
    inputs: Callable[[float], dict[str, float]] | None = None,
    tolerance: float = TIGHT,
) -> np.ndarray:
    """Rows [t, outputs...] at t = 0, step, 2 step, ...; `inputs(t)` gives the input values held
    over the step that starts at t."""
    types = {v.name: (v.valueReference, v.type) for v in md.modelVariables}
    reals = [types[n][0] for n in outputs if types[n][1] == "Real"]
    ints = [types[n][0] for n in outputs if types[n][1] != "Real"]
    fmu, _ = make_fmu("CS")
    fmu.setupExperiment(tolerance=tolerance, startTime=0.0)
    fmu.enterInitializationMode()
    set_values(fmu, md, values)
    fmu.exitInitializationMode()

    def row(t: float) -> list[float]:  # the Real outputs, then the Integer ones
        return [t, *fmu.getReal(reals), *(float(i) for i in fmu.getInteger(ints))]

    rows = [row(0.0)]
    n = round(stop / step)
    for k in range(n):
        t = k * step
        if inputs is not None:
            set_values(fmu, md, inputs(t))
        fmu.doStep(t, step)
        rows.append(row((k + 1) * step))
    return np.array(rows)


def defaults(md: ModelDescription) -> dict[str, float]:
    """The start values of the FMU's Real and Integer variables."""
    return {
        v.name: float(v.start)
        for v in md.modelVariables
        if v.start is not None and v.type in ("Real", "Integer")
    }


# ------------------------------------------------------------------------------------------
# base acceleration


def test_a_base_zero_is_bitwise_unchanged_and_a_base_is_the_force_minus_m1_a(
    make_fmu: MakeFmu, model_description: ModelDescription
) -> None:
    """a_base set to 0 (at start and at every step) gives the run without it, bitwise; a constant
    a_base gives the run with F_ext = -m1 a_base, bitwise: the d'Alembert force at G1 enters the
    sums exactly as the external force does (docs/model.md Eq. (14.1))."""
    md = model_description
    scene = load_scene("csfh")
    m1 = defaults(md)["body1.m"]
    outputs = [*STATES, "contact.F_N", "contact.F_N_peak", "flexure.stress_max"]
    base = scene_start_values(scene, "LN_spheres")
    plain = run_cs(make_fmu, md, base, 0.3, 1e-3, outputs, tolerance=1e-6)
    zeros = run_cs(
        make_fmu,
        md,
        {**base, "a_base[1]": 0.0, "a_base[2]": 0.0},
        0.3,
        1e-3,
        outputs,
        inputs=lambda t: {"a_base[1]": 0.0, "a_base[2]": 0.0},
        tolerance=1e-6,
    )
    assert np.array_equal(plain, zeros)
    a = (250.0, -40.0)
    with_base = run_cs(
        make_fmu, md, {**base, "a_base[1]": a[0], "a_base[2]": a[1]}, 0.3, 1e-3, outputs
    )
    with_force = run_cs(
        make_fmu, md, {**base, "F_ext[1]": -m1 * a[0], "F_ext[2]": -m1 * a[1]}, 0.3, 1e-3, outputs
    )
    assert np.array_equal(with_base, with_force)
    assert np.max(np.abs(with_base[:, 1] - plain[:, 1])) > 1e-3  # a_base moves body 1
    # model exchange and the Moreau stepper (scene inputs: the harness's path)
    sb = replace(scene, stop_time=0.2, inputs={"a_base[1]": a[0], "a_base[2]": a[1]})
    sf = replace(scene, stop_time=0.2, inputs={"F_ext[1]": -m1 * a[0], "F_ext[2]": -m1 * a[1]})
    for model in ("LN_spheres", "Moreau"):
        rb, rf = simulate(sb, model), simulate(sf, model)
        for col in ("x", "y", "theta", "F_N"):
            assert np.array_equal(rb[col], rf[col]), (model, col)
    # the scene loader accepts the base acceleration as an input
    data = {"name": "b", "inputs": {"a_base[2]": -9.81}}
    assert scene_from_dict(data).inputs == {"a_base[2]": -9.81}


def test_energy_balance_under_base_acceleration(
    make_fmu: MakeFmu, model_description: ModelDescription
) -> None:
    """energy.total is the energy of the motion relative to the frame. Without dissipation
    (c_r = 1, no friction, conservative flexure) its change over a communication step, where the
    inputs are held, is the work of the held forces: -m1 a_base . dr + F_ext . dr + M_ext dtheta
    (Eq. (14.2)). The base acceleration is a half-sine pulse in a changing direction; body 1
    impacts the bore during it."""
    md = model_description
    scene = load_scene("csfh")
    m1 = defaults(md)["body1.m"]
    values = scene_start_values(
        scene,
        "LN_spheres",
        {
            "contact.cr": 1.0,
            "friction.enabled": False,
            "flexure.conservative": True,
            "F_ext[1]": 3.0,
            "M_ext": -0.5,
        },
    )
    step, stop = 1e-3, 0.4

    def pulse(t: float) -> dict[str, float]:
        amp = 60.0 * math.sin(math.pi * t / 0.3) if t < 0.3 else 0.0
        return {"a_base[1]": amp * math.cos(7.0 * t), "a_base[2]": amp * math.sin(7.0 * t)}

    rows = run_cs(
        make_fmu,
        md,
        values,
        stop,
        step,
        ["body1.x", "body1.y", "body1.theta", "energy.total", "contact.count"],
        inputs=pulse,
    )
    assert rows[-1, 5] >= 2  # impacts happened under the pulse
    t, x, y, th, E = rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3], rows[:, 4]
    a = np.array([[pulse(tk)["a_base[1]"], pulse(tk)["a_base[2]"]] for tk in t[:-1]])
    base = np.r_[0.0, np.cumsum(-m1 * (a[:, 0] * np.diff(x) + a[:, 1] * np.diff(y)))]
    inputs = np.r_[0.0, np.cumsum(3.0 * np.diff(x) - 0.5 * np.diff(th))]
    scale = np.max(np.abs(base))
    assert scale > 10.0  # J: the pulse does work
    balance = (E - E[0]) - base - inputs
    assert np.max(np.abs(balance)) < 1e-6 * scale, np.max(np.abs(balance)) / scale
    # not trivially true: with the opposite sign of the d'Alembert force it fails
    assert np.max(np.abs((E - E[0]) + base - inputs)) > 0.1 * scale


# an independent flexure: compliance by quadrature of Castigliano's integrals in global
# coordinates (docs/model.md Eq. (2.4), bending + axial + shear), stiffness at C1, attachment
# point from Eq. (1.2)


def flexure_k0(p: dict[str, float], n: int = 20001) -> tuple[np.ndarray, np.ndarray]:
    rho, beta, phi0 = p["flexure.rho"], p["flexure.beta"], p["flexure.phi_root"]
    E, nu, h, b = p["flexure.E"], p["flexure.nu"], p["flexure.h"], p["flexure.b"]
    kappa = p["flexure.kappa"]
    EI, EA, GA = E * b * h**3 / 12, E * b * h, E / (2 * (1 + nu)) * b * h
    phi = np.linspace(phi0, phi0 + beta, n)
    tip = rho * np.array([math.cos(phi0 + beta), math.sin(phi0 + beta)])
    d = tip[:, None] - rho * np.array([np.cos(phi), np.sin(phi)])
    m_i = np.array([-d[1], d[0], np.ones(n)])  # moment at the section of unit Fx, Fy, M
    N_i = np.array([-np.sin(phi), np.cos(phi), np.zeros(n)])
    V_i = np.array([np.cos(phi), np.sin(phi), np.zeros(n)])
    w = np.full(n, beta / (n - 1) * rho)
    w[0] = w[-1] = w[0] / 2  # trapezoid on a fine grid (error 1e-9 relative)
    C = (m_i * w) @ m_i.T / EI + (N_i * w) @ N_i.T / EA + kappa * (V_i * w) @ V_i.T / GA
    sbar = np.array([p["flexure.OF[1]"], p["flexure.OF[2]"]]) + tip
    return np.linalg.inv(C), sbar


def rot(theta: float) -> np.ndarray:
    return np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])


def test_slow_ramp_of_a_base_reaches_the_static_equilibrium(
    make_fmu: MakeFmu, model_description: ModelDescription
) -> None:
    """Flexure only (no contact law, the conservative law, an exact potential). Body 1 starts
    at rest at its equilibrium under gravity; a_base then rises from 0 to [4, -3] m/s^2 along a
    smoothstep of degree 7 (C3) over 40 s and is held for 1 s (the flexure's lowest mode is
    1.07 Hz: the residual oscillation is of order f^(4)(0) / (2 pi f T)^4 = 840 / 269^4 = 2e-7
    of the deflection, the higher modes leave less). Both equilibria are
    the minima of the total potential V_e(q) + m1 (g e_y + a_base) . r, found here with an
    independent flexure stiffness."""
    md = model_description
    scene = load_scene("csfh")
    p = defaults(md)  # the csfh scene overrides no flexure parameter
    assert not any(k.startswith("flexure.") for k in scene.parameters)
    K0, sbar = flexure_k0(p)
    m1, g = p["body1.m"], p["g"]

    def equilibrium(a: np.ndarray) -> np.ndarray:
        def potential(q: np.ndarray) -> float:
            dp = np.r_[q[:2] + (rot(q[2]) - np.eye(2)) @ sbar, q[2]]
            return 0.5 * dp @ K0 @ dp + m1 * (g * q[1] + a @ q[:2])

        return minimize(potential, np.zeros(3), method="BFGS", options={"gtol": 1e-12}).x

    a_end, T = np.array([4.0, -3.0]), 40.0
    q_start, q_eq = equilibrium(np.zeros(2)), equilibrium(a_end)
    assert abs(q_eq[2]) > 0.01 and np.hypot(*q_eq[:2]) > 0.01  # a large, nonlinear deflection
    values = scene_start_values(
        scene,
        "LN_spheres",
        {
            "contact.law": 1,  # none
            "flexure.conservative": True,
            **dict(zip(STATES[:3], q_start, strict=True)),
        },
    )

    def ramp(t: float) -> dict[str, float]:
        u = min(t / T, 1.0)
        f = u**4 * (35 - 84 * u + 70 * u**2 - 20 * u**3)
        return {"a_base[1]": f * a_end[0], "a_base[2]": f * a_end[1]}

    rows = run_cs(make_fmu, md, values, T + 1.0, 5e-3, STATES, inputs=ramp, tolerance=1e-9)
    assert np.max(np.abs(rows[:, 1:4] - q_start)) > 0.5 * np.max(np.abs(q_eq - q_start))
    speed = np.max(np.abs(rows[:, 4:7]), axis=0)
    assert np.all(np.abs(rows[-1, 4:7]) < 1e-4 * speed), (rows[-1, 4:7], speed)  # at rest
    err = np.max(np.abs(rows[-1, 1:4] - q_eq) / np.abs(q_eq))
    assert err < 1e-5, (rows[-1, 1:4], q_eq)


# ------------------------------------------------------------------------------------------
# stresses and pressure


def hertz(F_N: np.ndarray, p: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """p0 and b of the Hertz line contact, from the paper's Eq. (17) and 1/R' = 1/R1 - 1/R2."""
    E_star = 1.0 / (
        (1 - p["contact.nu1"] ** 2) / p["contact.E1"]
        + (1 - p["contact.nu2"] ** 2) / p["contact.E2"]
    )
    R = 1.0 / (1.0 / p["contact.R1"] - 1.0 / p["contact.R2"])
    L = p["contact.L"]
    F = np.maximum(F_N, 0.0)
    return np.sqrt(F * E_star / (math.pi * L * R)), np.sqrt(4 * F * R / (math.pi * L * E_star))


@pytest.mark.parametrize("kind", ["CoSimulation", "ModelExchange"])
def test_pressure_max_is_the_hertz_formula_at_every_contact_sample(
    fmu_path: Any, model_description: ModelDescription, kind: str
) -> None:
    md = model_description
    scene = load_scene("csfh")
    values = scene_start_values(scene, "LN_spheres")
    names = [
        "contact.F_N",
        "contact.F_N_peak",
        "contact.pressure_max",
        "contact.pressure_max_peak",
        "contact.half_width",
        "contact.pressure_margin",
    ]
    r = simulate_fmu(
        str(fmu_path),
        fmi_type=kind,
        stop_time=1.0,
        output_interval=2e-5,
        output=names,
        start_values=values,
        relative_tolerance=1e-6,
    )
    p = {**defaults(md), **{k: v for k, v in values.items() if k.startswith("contact.E")}}
    F = r["contact.F_N"]
    touching = F > 0
    assert touching.sum() > 200, touching.sum()  # many contact samples
    p0, b = hertz(F, p)
    np.testing.assert_allclose(r["contact.pressure_max"], p0, rtol=1e-13, atol=0)
    np.testing.assert_allclose(r["contact.half_width"], b, rtol=1e-13, atol=0)
    assert np.all(r["contact.pressure_max"][~touching] == 0.0)
    p0_peak, _ = hertz(r["contact.F_N_peak"], p)
    np.testing.assert_allclose(r["contact.pressure_max_peak"], p0_peak, rtol=1e-13, atol=0)
    allowable = p["contact.pressure_allowable"]
    np.testing.assert_allclose(
        r["contact.pressure_margin"], 1 - p0_peak / allowable, rtol=0, atol=1e-15
    )
    if kind == "CoSimulation":  # the peak over the step exceeds the sample where it matters
        assert np.max(r["contact.pressure_max_peak"] - r["contact.pressure_max"]) > 1e6


def arc_stress_brute_force(
    p: dict[str, float], theta: float, co_rotated: bool, F: np.ndarray, M: float, n: int
) -> tuple[float, float]:
    """Largest |N|/(b h) + 6|m|/(b h^2) at n + 1 sections, N = F . tau and m = M + (C1 - P) x F
    from the equilibrium of the arc between the section and the tip, the arc carried by body 1's
    rotation (co-rotated law) or in its reference place (conservative law). Returns the stress
    and the arc angle of its section from the root."""
    rho, beta, phi0 = p["flexure.rho"], p["flexure.beta"], p["flexure.phi_root"]
    phi = phi0 + beta * np.arange(n + 1) / n
    A = rot(theta) if co_rotated else np.eye(2)
    tip = rho * np.array([math.cos(phi0 + beta), math.sin(phi0 + beta)])
    rel = A @ (tip[:, None] - rho * np.array([np.cos(phi), np.sin(phi)]))  # C1 - P
    tau = A @ np.array([-np.sin(phi), np.cos(phi)])
    N = F @ tau
    m = M + rel[0] * F[1] - rel[1] * F[0]
    b, h = p["flexure.b"], p["flexure.h"]
    sigma = np.abs(N) / (b * h) + 6 * np.abs(m) / (b * h * h)
    k = int(np.argmax(sigma))
    return float(sigma[k]), float(phi[k] - phi0)


@pytest.mark.parametrize("conservative", [False, True])
@pytest.mark.parametrize("q", [(0.004, -0.007, 0.03), (-0.012, 0.002, -0.08), (0.0, 0.0, 0.15)])
def test_flexure_stress_for_a_static_load(
    make_fmu: MakeFmu,
    model_description: ModelDescription,
    vr: dict[str, int],
    conservative: bool,
    q: tuple[float, float, float],
) -> None:
    """At a configuration q, the static load (F_ext, M_ext) that holds body 1 there is read from
    the FMU's own accelerations (M a = Q_e + Q_g + Q_ext, no contact law). The beam tip then
    carries the reaction of body 1's equilibrium; flexure.stress_max must equal the largest
    stress of the internal forces along the arc computed from it (independent of the stiffness
    and of the model's closed form), and flexure.stress_location its section."""
    md = model_description
    fmu, _ = make_fmu("ME")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    values = {"contact.law": 1, "flexure.conservative": conservative}
    values.update(dict(zip(STATES, [*q, 0.0, 0.0, 0.0], strict=True)))
    set_values(fmu, md, values)
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    m1, I1, g = fmu.getReal([vr["body1.m"], vr["body1.I"], vr["g"]])
    der = [vr["der(body1.vx)"], vr["der(body1.vy)"], vr["der(body1.omega)"]]
    acc = np.array(fmu.getReal(der))
    Q_e = np.array([m1, m1, I1]) * acc + np.array([0.0, m1 * g, 0.0])  # no input yet
    # the static load: F_ext, M_ext = -(Q_e + Q_g)
    set_values(fmu, md, {"F_ext[1]": -Q_e[0], "F_ext[2]": -Q_e[1] + m1 * g, "M_ext": -Q_e[2]})
    held = np.array(fmu.getReal(der))
    assert np.max(np.abs(held)) < 1e-12 * np.max(np.abs(acc))  # a static state
    sigma, location = fmu.getReal([vr["flexure.stress_max"], vr["flexure.stress_location"]])
    # the beam's force on body 1 is Q_e[:2] at C1; its moment about G1 is s x F + M_b
    sbar = np.array(fmu.getReal([vr["flexure.sbar[1]"], vr["flexure.sbar[2]"]]))
    s = rot(q[2]) @ sbar
    F_b = Q_e[:2]
    M_b = Q_e[2] - (s[0] * F_b[1] - s[1] * F_b[0])
    names = ["flexure.rho", "flexure.beta", "flexure.phi_root", "flexure.b", "flexure.h"]
    p = dict(zip(names, fmu.getReal([vr[n] for n in names]), strict=True))
    n = 200000
    ref, ref_location = arc_stress_brute_force(p, q[2], not conservative, -F_b, -M_b, n)
    assert sigma == pytest.approx(ref, rel=1e-8)
    assert location == pytest.approx(ref_location, abs=2 * p["flexure.beta"] / n)


def test_tracked_stress_peak_against_a_fine_grid(
    make_fmu: MakeFmu, model_description: ModelDescription
) -> None:
    """flexure.track_stress_peak: the peak over each 10 ms step equals the largest stress of the
    same trajectory sampled every 10 us (the co-simulation trajectory does not depend on the
    grid) to 1e-5; untracked, the output is the value at the communication point."""
    md = model_description
    scene = load_scene("csfh")
    names = ["flexure.stress_max", "flexure.stress_max_peak", "flexure.stress_margin"]
    values = scene_start_values(scene, "LN_spheres", {"flexure.track_stress_peak": True})
    coarse = run_cs(make_fmu, md, values, 0.5, 1e-2, names, tolerance=1e-9)
    fine = run_cs(make_fmu, md, values, 0.5, 1e-5, names[:1], tolerance=1e-9)
    allowable = defaults(md)["flexure.stress_allowable"]
    per_step = fine[1:, 1].reshape(50, 1000).max(axis=1)
    per_step = np.maximum(per_step, fine[:-1:1000, 1])  # the step's start is in it
    np.testing.assert_allclose(coarse[1:, 2], per_step, rtol=1e-5)
    assert np.max(coarse[1:, 2] / coarse[1:, 1]) > 1.05  # peaks between the points
    untracked = run_cs(
        make_fmu, md, {**values, "flexure.track_stress_peak": False}, 0.5, 1e-2, names, None, 1e-9
    )
    assert np.array_equal(untracked[:, 2], untracked[:, 1])
    assert np.array_equal(untracked[:, 1], coarse[:, 1])  # tracking does not move the run
    np.testing.assert_allclose(coarse[:, 3], 1 - coarse[:, 2] / allowable, rtol=0, atol=1e-15)


# ------------------------------------------------------------------------------------------
# scale consistency and the MEMS scene


def scale_exponents(md: ModelDescription) -> dict[str, int]:
    """Exponent of s for every Real parameter, input and state: a quantity of dimension
    M^a L^b T^c scales as s^(3a + b + c) (lengths x s, masses x s^3, times x s: density, elastic
    moduli, velocities and stresses unchanged, g / s, inertia x s^5)."""
    units = {u.name: u.baseUnit for u in md.unitDefinitions}
    out = {}
    for v in md.modelVariables:
        if v.type != "Real" or v.causality not in ("parameter", "input", "output"):
            continue
        if v.causality == "output" and v.name not in STATES:
            continue
        if v.unit == "N/m^n":
            continue  # stiffness given directly: s^(2 - n), unused with K_from_materials
        assert v.unit, f"{v.name} has no unit: state its scaling law"
        base = units[v.unit]
        out[v.name] = 0 if v.unit == "1" else 3 * base.kg + base.m + base.s
    return out


@pytest.mark.parametrize(
    "preset,law,consistent",
    [
        ("paper", "LN_spheres", True),
        ("consistent", "LN_cylinders", True),
        ("consistent", "LN_ESDU", True),
        # K (pi/4) E* L is N/m: with n = 1.5 (Table 2) the force scales as s^2.5, not s^2
        ("paper", "LN_cylinders", False),
    ],
)
def test_scale_consistency(
    make_fmu: MakeFmu,
    model_description: ModelDescription,
    preset: str,
    law: str,
    consistent: bool,
) -> None:
    """The paper's scene (flexure, friction, contacts) with lengths x s, masses x s^3, inertia
    x s^5, g / s (and every other quantity by its dimension, e.g. the gap hysteresis and the
    deepest start x s, the friction velocities and v_min unchanged) reproduces x/s, y/s and
    theta at times x s to 1e-6 relative over 0.5 s (5 contacts), and the same stresses;
    s = 1e-3 (MEMS) and 10. Both runs at rtol 1e-10."""
    md = model_description
    scene = replace(load_scene("csfh"), preset=preset)
    exps = scale_exponents(md)
    start = defaults(md)
    values = scene_start_values(scene, law)
    for name in exps:  # every Real quantity explicitly, so that its default is scaled too
        values.setdefault(name, start[name])
    names = ["body1.x", "body1.y", "body1.theta", "flexure.stress_max", "contact.count"]

    def run(s: float) -> np.ndarray:
        scaled = {k: (v * s ** exps[k] if k in exps else v) for k, v in values.items()}
        return run_cs(make_fmu, md, scaled, 0.5 * s, 1e-3 * s, names)

    ref = run(1.0)
    assert ref[-1, 5] >= 4
    for s in (1e-3, 10.0):
        got = run(s)
        err_x = np.max(np.abs(got[:, 1:3] / s - ref[:, 1:3])) / np.max(np.abs(ref[:, 1:3]))
        err_t = np.max(np.abs(got[:, 3] - ref[:, 3])) / np.max(np.abs(ref[:, 3]))
        if consistent:
            assert err_x < 1e-6 and err_t < 1e-6, (s, err_x, err_t)
            np.testing.assert_allclose(got[:, 4], ref[:, 4], rtol=1e-6)
            assert got[-1, 5] == ref[-1, 5]
        else:
            assert err_x > 1e-2, (s, err_x)


def test_mems_scene_runs(fmu_path: Any) -> None:
    """The built-in MEMS scene: silicon, the paper's geometry x 1e-3, masses from the density;
    it runs in co-simulation and with Moreau, body 1 reaches the bore several times, the
    stresses are finite and below the scene's allowables."""
    scene = load_scene("mems")
    p = scene.parameter_values()
    R1, L = p["contact.R1"], p["contact.L"]
    m1 = 2330.0 * math.pi * R1**2 * L
    assert p["body1.m"] == pytest.approx(m1, rel=1e-12)
    assert p["body1.I"] == pytest.approx(m1 * R1**2 / 2, rel=1e-12)
    assert p["contact.E1"] == p["flexure.E"] == 169e9
    assert p["flexure.rho"] == pytest.approx(0.144e-3) and p["contact.R2"] == pytest.approx(0.2e-3)
    run = simulate(scene, "LN_spheres", interface="cs")
    assert len(run.contacts) >= 3
    assert np.all(np.isfinite(run["x"])) and np.max(np.hypot(run["x"], run["y"])) < 25e-6
    mo = moreau(scene)
    assert len(mo.impacts["t"]) >= 3
    r = simulate_fmu(
        str(fmu_path),
        fmi_type="CoSimulation",
        stop_time=scene.stop_time,
        output_interval=1e-6,
        output=[
            "flexure.stress_max_peak",
            "contact.pressure_max_peak",
            "flexure.stress_margin",
            "contact.pressure_margin",
        ],
        start_values={**scene_start_values(scene, "LN_spheres"), "flexure.track_stress_peak": True},
        relative_tolerance=scene.integrator.rtol,
    )
    assert 1e7 < np.max(r["flexure.stress_max_peak"]) < p["flexure.stress_allowable"]
    assert 1e7 < np.max(r["contact.pressure_max_peak"]) < p["contact.pressure_allowable"]
    assert 0 < np.min(r["flexure.stress_margin"]) < 1
    assert 0 < np.min(r["contact.pressure_margin"]) < 1
