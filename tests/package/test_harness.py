"""The harness: scenes, the Moreau stepper against docs/model.md §7, the four-model
comparison, and the command line."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import oracles
import pytest

from csfh.model.core import CoreModel
from csfh.model.instance import core_model
from csfh.model.scene import SceneError, load_scene, scene_from_dict
from csfh.runners.fmu import simulate_me
from csfh.runners.moreau import moreau

G = 9.81
CR = 0.9
T_FIRST_CENTRAL = math.sqrt(2 * 0.03 / G)  # docs/model.md §7.1
V_IMPACT = math.sqrt(2 * G * 0.03)


# ------------------------------------------------------------------------------------------
# Moreau against docs/model.md §7.4-7.6


@pytest.fixture(scope="module")
def central_moreau():
    scene = load_scene("central")
    return moreau(scene, h=1e-5, output_interval=1e-5, stop_time=0.7)


def test_moreau_impact_steps_and_restitution(central_moreau) -> None:
    """7.4: impact times of the rigid bounce sequence, v+/v- = c_r exactly."""
    imp = central_moreau.impacts
    exact = [T_FIRST_CENTRAL]
    v = V_IMPACT
    for _ in range(5):
        v *= CR
        exact.append(exact[-1] + 2 * v / G)
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
    assert imp["Lambda_N"][0] == pytest.approx(10 * (1 + CR) * V_IMPACT, rel=1e-3)
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
# the compliant models through the FMU


def test_all_models_reach_the_first_central_contact_together() -> None:
    """7.1: every model meets the bore at t = sqrt(2 * 0.03 / g) (Moreau: within one step)."""
    scene = load_scene("central")
    for law in ("LN_spheres", "LN_cylinders", "LN_ESDU"):
        tr = simulate_me(scene, law, stop_time=0.1)
        assert abs(tr.contacts[0] - T_FIRST_CENTRAL) < 1e-6, law
    tr = moreau(scene, stop_time=0.1)
    h = scene.integrator.moreau_h
    assert abs(tr.contacts[0] - T_FIRST_CENTRAL) <= h


@pytest.mark.parametrize(
    ("law", "duration", "e_eff", "max_indentation", "second_contact"),
    [
        ("LN_spheres", 4.6251e-4, 0.9128, 1.1524e-4, 0.221437),
        ("LN_cylinders", 1.5621e-3, 0.9118, 3.8984e-4, 0.222383),
        ("Flores", None, 0.8934, None, 0.218412),
        ("HuntCrossley", None, 0.9086, None, 0.220783),
    ],
)
def test_first_rebound_matches_physics_7_3(
    law: str,
    duration: float | None,
    e_eff: float,
    max_indentation: float | None,
    second_contact: float,
) -> None:
    """7.3 (with gravity, Table 2 stiffness): contact duration, effective restitution, maximum
    indentation and the time of the second contact, each within 1e-3 (relative)."""
    scene = load_scene("central")
    tr = simulate_me(
        scene, law, rtol=1e-10, stop_time=0.25, parameters={"contact.K_from_materials": False}
    )
    t_on, t_off = tr.contacts[0], tr.releases[0]
    tab = tr.table
    v_on = tab["vy"][np.nonzero(tab["t"] == t_on)[0][0]]
    v_off = tab["vy"][np.nonzero(tab["t"] == t_off)[0][0]]
    assert -v_off / v_on == pytest.approx(e_eff, rel=1e-3)
    assert tr.contacts[1] == pytest.approx(second_contact, rel=1e-3)
    if duration is not None:
        assert t_off - t_on == pytest.approx(duration, rel=1e-3)
    if max_indentation is not None:
        assert np.max(tr.steps["indentation"]) == pytest.approx(max_indentation, rel=1e-3)


@pytest.mark.parametrize("interface", ["me", "cs"])
def test_switched_off_parts_are_never_evaluated(interface: str) -> None:
    """A scene runs only what it needs: flexure/friction off means never evaluated (counters of
    the FMU and of the core library); on means evaluated."""
    from csfh.runners.simulate import simulate

    off = load_scene("central").with_parameters()  # no flexure, no friction
    for model in ("LN_spheres", "Moreau"):
        ev = simulate(off, model, interface=interface, stop_time=0.2).stats["evaluations"]
        assert ev["flexure"] == 0 and ev["friction"] == 0, (model, ev)
        assert ev["contact"] > 0
    on = load_scene("csfh")
    for model in ("LN_spheres", "Moreau"):
        ev = simulate(on, model, interface=interface, stop_time=0.2).stats["evaluations"]
        assert ev["flexure"] > 0 and ev["friction"] > 0, (model, ev)


def test_me_driver_agrees_with_fmpy_simulate_fmu() -> None:
    """Our one-step model-exchange driver and fmpy.simulate_fmu give the same trajectory."""
    from csfh.runners.fmu import simulate_fmpy

    scene = load_scene("asymmetric")
    ours = simulate_me(scene, "LN_spheres", rtol=1e-9, stop_time=0.2)
    theirs = simulate_fmpy(
        scene.__class__(**{**scene.__dict__, "stop_time": 0.2}),
        "LN_spheres",
        rtol=1e-9,
        output_interval=1e-4,
    )
    for col, name in (("x", "body1.x"), ("y", "body1.y"), ("theta", "body1.theta")):
        t_grid = np.arange(0, 0.2, 1e-3)
        a = np.interp(t_grid, ours.t, ours[col])
        b = np.interp(t_grid, theirs["time"], theirs[name])
        np.testing.assert_allclose(a, b, atol=2e-6)


# ------------------------------------------------------------------------------------------
# scenes and the command line


def test_builtin_scenes() -> None:
    central, asym, full = (load_scene(n) for n in ("central", "asymmetric", "csfh"))
    assert central.q0 == (0.0, 0.01, 0.0) and not central.flexure and not central.friction
    assert asym.q0 == (0.01, 0.01, 0.0) and not asym.flexure and asym.friction
    assert full.q0 == (0.01, 0.01, 0.0) and full.flexure and full.friction


def test_the_scene_example_in_the_documentation_is_a_valid_scene() -> None:
    """The example scene in csfh.model.scene's docstring parses and loads as documented."""
    import textwrap
    import tomllib

    import csfh.model.scene as scene_module

    doc = str(scene_module.__doc__)
    example = textwrap.dedent(doc[doc.index("    name = ") :])
    data = tomllib.loads(example)
    scene = scene_from_dict(data, "docstring")
    assert scene.models == ("LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau")
    assert scene.integrator.stick_rule == "paper" and scene.parameters == {"contact.cr": 0.9}
    assert scene.q0 == (0.01, 0.01, 0.0) and scene.inputs == {"F_ext[1]": 0.0}


def test_the_scene_example_of_the_user_guide_is_a_valid_scene() -> None:
    import tomllib

    text = (Path(__file__).resolve().parents[2] / "docs/guide/harness.md").read_text()
    example = text.split("```toml\n", 1)[1].split("```", 1)[0]
    scene = scene_from_dict(tomllib.loads(example), "guide")
    assert scene.name == "my_drop" and scene.models == (
        "LN_spheres",
        "LN_cylinders",
        "LN_ESDU",
        "Moreau",
    )


@pytest.mark.parametrize("entry", ["simulate", "moreau"])
def test_public_runners_take_a_scene_name_or_file(entry: str, tmp_path: Path) -> None:
    """csfh.simulate / csfh.moreau accept what csfh.load_scene accepts (as the CLI does)."""
    import csfh

    by_object = csfh.simulate(load_scene("central"), "LN_ESDU", stop_time=0.1)
    if entry == "simulate":
        by_name = csfh.simulate("central", "LN_ESDU", stop_time=0.1)
    else:
        by_object = csfh.moreau(load_scene("central"), stop_time=0.1)
        by_name = csfh.moreau("central", stop_time=0.1)
    path = tmp_path / "mine.toml"
    path.write_text('name = "mine"\nstop_time = 0.1\n[initial]\nq = [0.0, 0.01, 0.0]\n')
    by_file = csfh.simulate(path, "LN_ESDU") if entry == "simulate" else csfh.moreau(str(path))
    assert by_name.scene == "central" and by_file.scene == "mine"
    np.testing.assert_array_equal(by_name["y"], by_object["y"])
    assert by_file.t[-1] == pytest.approx(0.1)


def test_consistent_preset_values() -> None:
    scene = scene_from_dict({"name": "c", "preset": "consistent"})
    model = core_model(scene)
    assert model.get("contact.E1") == 100e9
    assert model.get("contact.n_cylinders") == 1.0
    assert model.get("contact.K_spheres") == pytest.approx(9.8289e10, rel=1e-4)  # 4.1
    assert scene.stick_rule == "memory"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('name = "x"\nstop_time = -1', "stop_time = -1 must be > 0"),
        ('name = "x"\nbogus = 1', "unknown key 'bogus'"),
        ('name = "x"\n[parameters]\n"contact.nope" = 1', "unknown parameter 'contact.nope'"),
        ('name = "x"\n[parameters]\n"contact.cr" = 1.5', "contact.cr = 1.5 is out of range"),
        ('name = "x"\n[parameters]\n"contact.R1" = 0.3', "contact.R1 = 0.3"),
        ('name = "x"\n[parameters]\n"contact.law" = "Bogus"', 'contact.law = "Bogus"'),
        ('name = "x"\n[initial]\nq = [0, 1]', "initial.q must be a list of 3 numbers"),
        ('name = "x"\npreset = "weird"', "preset = 'weird'"),
        ('name = "x"\n[integrator]\nstick_rule = "loose"', "stick_rule = 'loose'"),
        ("name = ", "not valid TOML"),
    ],
)
def test_bad_scene_file_one_line_error(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(SceneError, match=r"bad\.toml") as info:
        load_scene(path)
    assert message in str(info.value)
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "csfh",
            "run",
            str(path),
            "--law",
            "Moreau",
            "--out",
            str(tmp_path / "o"),
        ],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], proc.stderr


def test_cli_unknown_scene_and_law(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "csfh", "run", "nowhere", "--law", "Moreau"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert proc.returncode == 2 and "unknown scene 'nowhere'" in proc.stderr
    proc = subprocess.run(
        [sys.executable, "-m", "csfh", "run", "central", "--law", "Bogus"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert proc.returncode == 2 and "Bogus" in proc.stderr


def test_user_scene_file_runs(tmp_path: Path) -> None:
    path = tmp_path / "mine.toml"
    path.write_text(
        'name = "mine"\nstop_time = 0.1\n[initial]\nq = [0.005, 0.0, 0.0]\n'
        '[parts]\nflexure = false\n[parameters]\n"contact.cr" = 0.5\n'
    )
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "csfh",
            "run",
            str(path),
            "--law",
            "Flores",
            "--out",
            str(tmp_path / "out"),
            "--quiet",
        ],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr
    data = np.genfromtxt(tmp_path / "out" / "Flores.csv", delimiter=",", names=True)
    assert data["t_s"][-1] == pytest.approx(0.1)


def test_compare_writes_everything(tmp_path: Path) -> None:
    scene = scene_from_dict(
        {
            "name": "short",
            "stop_time": 0.15,
            "initial": {"q": [0.01, 0.01, 0.0]},
            "parts": {"flexure": True, "friction": True},
        }
    )
    from csfh.studies.compare import compare

    result = compare(scene, tmp_path)
    names = {p.name for p in result.files}
    for model in ("LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau"):
        assert f"{model}.csv" in names
        header = (tmp_path / f"{model}.csv").read_text().splitlines()[0]
        for col in (
            "t [s]",
            "x [m]",
            "theta [rad]",
            "F_N [N]",
            "F_T [N]",
            "indentation [m]",
            "v_T [m/s]",
        ):
            assert col in header
    for png in (
        "time_histories.png",
        "y_and_normal_force.png",
        "first_contact.png",
        "friction_vs_step.png",
        "trajectory.png",
    ):
        assert (tmp_path / png).stat().st_size > 10_000
    summary = json.loads((tmp_path / "summary.json").read_text())
    for model, s in summary["models"].items():
        for key in (
            "first_contact_time",
            "contacts",
            "max_F_N",
            "max_indentation",
            "max_abs_F_T",
            "steps",
            "rhs_evaluations",
            "wall_time",
        ):
            assert key in s, (model, key)
    # the first contact against the flight on the flexure integrated here (oracles.py: the
    # test's own compliance, co-rotated law, DOP853 at rtol 1e-12): 0.0717153 s, 2.9 ms before
    # the free fall's 0.074632 s (docs/model.md §7.1), so the flexure's stiffness shows (E +5 %
    # moves it by 1.3e-4 s)
    t_c, x_c = oracles.first_contact_of_flight(oracles.Flexure(), q0=(0.01, 0.01, 0.0))
    # event-driven models (CVODE, scene rtol 1e-6): the position error ~ rtol x the path
    # travelled, over the approach speed; ten times that
    path = math.hypot(x_c[0] - 0.01, x_c[1] - 0.01)
    tol = 10 * scene.integrator.rtol * path / math.hypot(x_c[3], x_c[4])
    assert tol < 1e-6
    for model in ("LN_spheres", "LN_cylinders", "LN_ESDU"):
        t = summary["models"][model]["first_contact_time"]
        assert abs(t - t_c) < tol, (model, t, t_c, tol)
    # Moreau: the first step whose midpoint gap is <= 0 (docs/model.md §6.1) starts within h/2 of
    # the contact (Verlet's flight error is ~h^2 g, far below h here): one point of the h grid
    h = scene.integrator.moreau_h
    t = summary["models"]["Moreau"]["first_contact_time"]
    assert t_c - h / 2 - 1e-12 <= t < t_c + h / 2, (t, t_c)
