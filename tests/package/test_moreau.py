"""The Moreau stepper (csfh.runners.moreau) against docs/model.md §6-7: the rigid bounce
sequence, apex heights and impulse of the central drop, energy without dissipation, the first
asymmetric impact, rolling without slip, restitution only for closing contacts, the smooth forces
the FMU computes; and the batched stepper (csfh.runners.moreau_batch) against single runs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from oracles import V_FIRST_CENTRAL, G, rigid_impact_times

from csfh.model.core import CoreModel
from csfh.model.scene import load_scene, scene_from_dict
from csfh.runners.moreau import moreau
from csfh.runners.moreau_batch import moreau_batch

CR = 0.9


# ------------------------------------------------------------------------------------------
# the stepper against docs/model.md §7.4-7.6


@pytest.fixture(scope="module")
def central_moreau():
    scene = load_scene("central")
    return moreau(scene, h=1e-5, output_interval=1e-5, stop_time=0.7)


def test_moreau_impact_steps_and_restitution(central_moreau) -> None:
    """7.4: impact times of the rigid bounce sequence, v+/v- = c_r exactly."""
    imp = central_moreau.impacts
    exact = rigid_impact_times(6, CR)
    h = 1e-5
    for k, t_exact in enumerate(exact):
        # the impact step starts at most a few steps after the exact instant (6.3)
        assert -h <= imp["t"][k] - t_exact <= 6 * h, (k, imp["t"][k], t_exact)
        ratio = -imp["gamma_N_after"][k] / imp["gamma_N_before"][k]
        assert ratio == pytest.approx(CR, abs=1e-12), k
        assert imp["restitution"][k] == 1


def test_moreau_apex_heights_scale_by_cr_squared(central_moreau) -> None:
    """7.4: apex height above the contact level after each bounce is c_r^(2(k+1)) 0.03 m."""
    tab = central_moreau.table
    y, t = tab["y"], tab["t"]
    impacts = [*list(central_moreau.impacts["t"][:6]), t[-1]]
    for k in range(5):
        window = (t > impacts[k]) & (t < impacts[k + 1])
        apex = np.max(y[window]) + 0.02
        expected = CR ** (2 * (k + 1)) * 0.03
        assert apex == pytest.approx(expected, rel=3e-4), (k, apex, expected)


def test_moreau_peak_impulse(central_moreau) -> None:
    """7.4: Lambda_N = m1 (1 + c_r) v_imp at the first impact (14.577 N s), F = Lambda/h."""
    imp = central_moreau.impacts
    assert imp["Lambda_N"][0] == pytest.approx(10 * (1 + CR) * V_FIRST_CENTRAL, rel=1e-3)
    assert central_moreau.summary()["max_F_N"] == pytest.approx(imp["Lambda_N"][0] / 1e-5, rel=1e-9)


def test_moreau_energy_conserved_elastic() -> None:
    """7.5: c_r = 1, no friction, no flexure, off-centre start: energy to round-off."""
    scene = scene_from_dict(
        {
            "name": "elastic",
            "stop_time": 1.0,
            "initial": {"q": [0.0, 0.01, 0.0], "u": [0.3, 0.0, 0.5]},
            "parts": {"flexure": False, "friction": False},
            "parameters": {"contact.cr": 1.0},
        }
    )
    tr = moreau(scene, h=1e-5, output_interval=1e-4)
    E = tr["energy"]
    assert E[0] == pytest.approx(1.4512, abs=1e-4)
    assert tr.stats["onsets"] >= 10
    assert np.max(np.abs(E - E[0])) / E[0] < 1e-9


@pytest.mark.parametrize(
    ("rule", "mode", "Lambda_T", "omega", "v_T"),
    [("memory", "slip", -0.6626, 0.7376, 0.1670), ("paper", "stick", -1.2187, 1.3567, 0.0)],
)
def test_moreau_first_asymmetric_impact(
    rule: str, mode: str, Lambda_T: float, omega: float, v_T: float
) -> None:
    """7.6: the first asymmetric impact lands in the band f_d < |Lambda_T|/Lambda_N < f_a."""
    scene = load_scene("asymmetric")
    tr = moreau(scene, h=1e-5, stop_time=0.08, stick_rule=rule)
    imp = tr.impacts
    assert imp["t"][0] == pytest.approx(0.07464, abs=2e-5)
    assert imp["Lambda_N"][0] == pytest.approx(12.0479, rel=2e-4)
    assert {2: "stick", 3: "slip"}[int(imp["mode"][0])] == mode
    assert imp["Lambda_T"][0] == pytest.approx(Lambda_T, abs=2e-3)
    assert imp["omega_after"][0] == pytest.approx(omega, abs=2e-3)
    assert imp["gamma_T_after"][0] == pytest.approx(v_T, abs=2e-3)


@pytest.mark.parametrize("rule", ["memory", "paper"])
def test_moreau_rolls_without_slip_where_static_friction_holds(rule: str) -> None:
    """docs/model.md §6.4, the other half of the memory rule: a contact that is stuck stays stuck
    while |Lambda_T| <= f_a Lambda_N. Body 1 starts at rest, touching the bore at the angle phi0
    from the bottom (no flexure). Rolling without slip there needs the friction ratio
    |F_T|/F_N = tan(phi0) I/(I + m R1^2) (a cylinder rolling on a slope of angle phi0); phi0 is
    chosen here to make it 0.0825, between f_d = 0.055 and f_a = 0.11, and it only falls as the
    body speeds up (F_N gains the centripetal part). So every step sticks, under both rules, and
    body 1 rolls as the pendulum phi'' = -g sin(phi) / (delta (1 + I/(m R1^2))) with
    omega = -(delta/R1) phi' (the contact point at rest), integrated here. Moreau's error is
    O(h) = 1e-5 x phi' (phi' <= 4.4 rad/s); it is 3e-7 rad: 1e-5 rad and 1e-5 rad/s bound it
    with margin, while slipping with f_d, or the inertia m in place of I, changes the motion at
    the 1e-2 level."""
    m, inertia, R1, delta, fd, fa = 10.0, 0.1617, 0.18, 0.20 - 0.18, 0.055, 0.11
    ratio = 0.0825
    assert fd < ratio < fa
    phi0 = math.atan(ratio * (inertia + m * R1**2) / inertia)
    scene = scene_from_dict(
        {
            "name": "rolling",
            "initial": {"q": [delta * math.sin(phi0), -delta * math.cos(phi0), 0.0]},
            "parts": {"flexure": False, "friction": True},
        }
    )
    tr = moreau(scene, h=1e-5, stop_time=0.4, stick_rule=rule, output_interval=1e-3)
    assert tr.stats["active_steps"] == tr.stats["steps"] == 40000
    assert tr.stats["stick_steps"] == tr.stats["steps"]
    from scipy.integrate import solve_ivp

    k = 1 + inertia / (m * R1**2)
    sol = solve_ivp(
        lambda _t, y: [y[1], -G * math.sin(y[0]) / (delta * k)],
        (0.0, 0.4),
        [phi0, 0.0],
        rtol=1e-12,
        atol=1e-14,
        dense_output=True,
    )
    tab = tr.table
    phi_ref, rate_ref = sol.sol(tab["t"])
    assert np.min(phi_ref) < -0.9 * phi0  # most of a swing
    phi = np.arctan2(tab["x"], -tab["y"])
    np.testing.assert_allclose(phi, phi_ref, rtol=0, atol=1e-5)
    np.testing.assert_allclose(tab["omega"], -(delta / R1) * rate_ref, rtol=0, atol=1e-5)
    assert np.max(np.abs(tab["v_T"])) < 1e-9


def test_moreau_restitution_only_for_closing_contacts() -> None:
    """docs/model.md §6.3: sustained sliding along the bore (g = 0, no friction, no flexure, v = 0.3
    m/s along the wall from the bottom): each step approaches the wall by gamma_A,N ~ -h v^2 /
    delta (centripetal). With v_eps = 1e-3 m/s that approach gets no restitution, the impulse
    stops it, and the gap drifts by -h v^2 / (2 delta) per unit time = -2.25e-5 m/s (to the
    next order, h v / delta ~ 1e-4, and the speed's own 3e-4 change: 1 %); with v_eps = 0
    restitution applies to it and holds the gap twenty times closer (-1.2e-6 m in 1 s)."""
    h, v, delta = 1e-5, 0.3, 0.20 - 0.18
    scene = scene_from_dict(
        {
            "name": "sliding",
            "initial": {"q": [0.0, -delta, 0.0], "u": [v, 0.0, 0.0]},
            "parts": {"flexure": False, "friction": False},
            "parameters": {"g": 0.0},
        }
    )
    drift = {}
    for v_eps in (0.0, 1e-3):
        tr = moreau(scene, h=h, stop_time=1.0, v_eps=v_eps, output_interval=1e-2)
        assert tr.stats["active_steps"] == tr.stats["steps"]  # in contact all along
        t, gap = tr.table["t"], tr.table["gap"]
        drift[v_eps] = np.polyfit(t[10:], gap[10:], 1)[0]
    assert drift[1e-3] == pytest.approx(-h * v**2 / (2 * delta), rel=1e-2)
    assert abs(drift[0.0]) < 0.1 * abs(drift[1e-3])


def test_moreau_smooth_forces_are_the_fmus(make_fmu, vr) -> None:
    """The stepper's smooth forces (gravity, flexure, inputs) equal the FMU's derivatives."""
    rng = np.random.default_rng(1)
    fmu, _ = make_fmu("ME")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setInteger([vr["contact.law"]], [1])  # none: only the smooth forces act
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    core = CoreModel()
    core.set("contact.law", 1)
    core.prepare()
    M = np.array([10.0, 10.0, 0.1617])
    inputs = [vr["F_ext[1]"], vr["F_ext[2]"], vr["M_ext"]]
    for _ in range(50):
        x = np.concatenate(
            [rng.uniform(-0.05, 0.05, 2), rng.uniform(-0.5, 0.5, 1), rng.uniform(-1, 1, 3)]
        )
        u = rng.uniform(-20, 20, 3)
        fmu.setReal(inputs, list(u))
        fmu.setContinuousStates(
            x.ctypes.data_as(__import__("ctypes").POINTER(__import__("ctypes").c_double)), 6
        )
        xdot = np.array(
            fmu.getReal(
                [
                    vr[f"der({n})"]
                    for n in (
                        "body1.x",
                        "body1.y",
                        "body1.theta",
                        "body1.vx",
                        "body1.vy",
                        "body1.omega",
                    )
                ]
            )
        )
        core.set_inputs(u)
        acc = core.smooth_forces(x[:3]) / M
        np.testing.assert_allclose(acc, xdot[3:], rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(xdot[:3], x[3:])


# ------------------------------------------------------------------------------------------
# batched Moreau


def test_moreau_batch_is_bitwise_the_single_runs() -> None:
    scene = load_scene("csfh")
    sets = [None, {"contact.R1": 0.181}, {"flexure.h": 0.006, "body1.m": 9.9}]
    batch = moreau_batch(scene, sets, stop_time=0.3)
    assert batch.steps == 3 * 30000
    for i, p in enumerate(sets):
        single = moreau(scene, parameters=p, stop_time=0.3)
        tr = batch.trajectory(i)
        assert single.table.keys() == tr.table.keys()
        for k in single.table:
            assert np.array_equal(single.table[k], tr.table[k]), k
        assert np.array_equal(single.contacts, tr.contacts)
    # the variants differ from each other (the batch does not share state between them)
    assert not np.array_equal(batch.column(0, "x"), batch.column(1, "x"))
