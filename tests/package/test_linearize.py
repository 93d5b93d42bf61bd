"""csfh.linearize and `csfh linearize`: the flexure's modes against the analytic modes of
docs/model.md §7.7 (the tests' own compliance by quadrature, tests/oracles.py); an equilibrium
pressed into the bore against the ESDU law's own indentation and tangent stiffness (§4.5,
computed in oracles.py from the explicit rho(F)); the gravity equilibrium of the csfh scene
against the Hertz stiffness at its indentation; a time of a run against that run; the files and
their keys; bad input on one line; the directional derivatives against the finite differences."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import oracles
import pytest
from csfh_command import run_csfh

import csfh
from csfh.errors import ParameterError, SimulationError
from csfh.model.instance import nominal_values
from csfh.model.scene import load_scene, scene_from_dict
from csfh.studies.linearize.jacobian import (
    INPUTS,
    OUTPUTS,
    STATES,
    provides_directional_derivatives,
)

M1 = 10.0  # kg, body1.m of Table 1


def flexure_scene(**parameters: object) -> csfh.Scene:
    """Body 1 at q = 0 on the flexure, no gravity, out of contact."""
    return scene_from_dict(
        {
            "name": "flexure",
            "initial": {"q": [0.0, 0.0, 0.0]},
            "parameters": {"g": 0.0, **parameters},
            "parts": {"flexure": True, "friction": False},
        }
    )


@pytest.mark.parametrize("bending_only", [False, True])
def test_flexure_modes_match_the_analytic_modes(bending_only: bool) -> None:
    """At q = 0 without gravity: three undamped modes, det(K_G - w^2 M) = 0 with the tests' own
    compliance (with or without the shear and axial terms, which move them by up to 2.4e-4), to
    1e-6 relative; docs/model.md §7.7 prints 1.0705, 3.1190 and 6.2367 Hz."""
    lin = csfh.linearize(
        flexure_scene(**{"flexure.bending_only": bending_only}), "LN_cylinders", jacobian="fd"
    )
    flex = oracles.Flexure(shear=not bending_only, axial=not bending_only)
    expected = oracles.natural_frequencies(flex)
    assert not lin.in_contact
    np.testing.assert_allclose(lin.frequencies_hz, expected, rtol=1e-6)
    assert np.max(np.abs(lin.damping_ratios)) < 1e-9
    if not bending_only:
        np.testing.assert_allclose(lin.frequencies_hz, [1.0705, 3.1190, 6.2367], atol=5e-5)
    full = oracles.natural_frequencies(oracles.Flexure())
    assert (
        np.max(
            np.abs(
                oracles.natural_frequencies(oracles.Flexure(shear=False, axial=False)) / full - 1
            )
        )
        > 1e-4
    )


def pressed_scene(force: float) -> csfh.Scene:
    """Body 1 without flexure, gravity and friction, pushed down by F_ext[2] = -force; LN_ESDU
    in its consistent reading (I2: the elastic force is the ESDU force) and c_r = 1 (no
    damping)."""
    return scene_from_dict(
        {
            "name": "pressed",
            "initial": {"q": [0.0, 0.0, 0.0]},
            "parameters": {"g": 0.0, "contact.esdu_reading": "I2", "contact.cr": 1.0},
            "parts": {"flexure": False, "friction": False},
            "inputs": {"F_ext[2]": -force},
        }
    )


@pytest.mark.parametrize("force", [50.0, 1000.0])
def test_equilibrium_in_contact_shows_the_contact_stiffness(force: float) -> None:
    """The body rests at the bottom of the bore with the ESDU indentation rho(F) (4.7); its
    vertical mode is sqrt(K_t(F) / m) with the tangent stiffness (4.8), its horizontal one the
    pendulum of the normal force about O2, sqrt(F / (m |e|)); the rotation is free (no flexure,
    no friction)."""
    lin = csfh.linearize(pressed_scene(force), "LN_ESDU", at="equilibrium", jacobian="fd")
    esdu = oracles.Esdu()
    rho = esdu.indentation(force)
    assert lin.in_contact and lin.equilibrium is not None
    assert lin.equilibrium.mode == "contact"
    assert lin.equilibrium.indentation == pytest.approx(rho, rel=1e-9)
    assert lin.operating_point[1] == pytest.approx(-(0.02 + rho), rel=1e-12)
    f_contact = math.sqrt(esdu.tangent_stiffness(force) / M1) / (2 * math.pi)
    f_pendulum = math.sqrt(force / (M1 * (0.02 + rho))) / (2 * math.pi)
    np.testing.assert_allclose(lin.frequencies_hz, [f_pendulum, f_contact], rtol=1e-6)
    assert np.max(np.abs(lin.state_derivatives)) < 1e-8 * force / M1
    # the flight modes of the flexure are far below the contact's
    assert f_contact > 100 * oracles.natural_frequencies(oracles.Flexure())[-1]


def test_gravity_equilibrium_of_the_csfh_scene() -> None:
    """The csfh scene under gravity rests on the bore (§2.5: its flight equilibrium lies
    outside): the solve finds the flight solution inconsistent and converges in contact. The
    highest mode is the normal contact's, sqrt(1.5 K rho^0.5 / m) at the equilibrium's
    indentation (LN_spheres, n = 1.5, the paper preset's K of §4.1), to the flexure's share
    (~1e-4); it is damped by the LN law (4.1) with the onset rate at v_min."""
    lin = csfh.linearize("csfh", "LN_spheres", at="equilibrium", jacobian="fd")
    eq = lin.equilibrium
    assert eq is not None and eq.mode == "contact"
    assert [a.split(":")[0] for a in eq.attempts] == ["flight", "contact"]
    k = 1.5 * oracles.k_spheres() * math.sqrt(eq.indentation)
    f_normal = math.sqrt(k / M1) / (2 * math.pi)
    assert lin.frequencies_hz[-1] == pytest.approx(f_normal, rel=1e-3)
    assert lin.damping_ratios[-1] > 0.05
    assert lin.frequencies_hz[-1] > 50 * oracles.natural_frequencies(oracles.Flexure())[-1]


def test_a_time_of_a_run_is_that_runs_state() -> None:
    """--at T: the operating point is the model-exchange run's state at T."""
    scene = load_scene("csfh")
    lin = csfh.linearize(scene, "LN_cylinders", at=0.05, jacobian="fd")
    tr = csfh.simulate(scene, "LN_cylinders", stop_time=0.05)
    expected = [tr[c][-1] for c in ("x", "y", "theta", "vx", "vy", "omega")]
    np.testing.assert_allclose(lin.operating_point, expected, rtol=1e-9, atol=1e-15)
    assert lin.at == "t = 0.05 s" and lin.to_json()["time"] == 0.05


def test_a_time_inside_a_contact_keeps_the_runs_onset_rate() -> None:
    """Inside the central scene's first impact the linearization is in contact, and its damping
    is the LN law's (4.1) with the run's own onset rate (0.77 m/s, not the floor v_min = 1e-3
    m/s a fresh start at rest would take): d(dvy/dt)/dvy = -F_el(rho) xi / (rho'- m), with
    F_el = K rho^1.5 (4.3) at the indentation rho = -y - delta."""
    scene = load_scene("central")
    records = csfh.simulate(scene, "LN_spheres", stop_time=0.1).contact_records
    t_on, t_off = records["t_onset"][0], records["t_release"][0]
    v_on = records["onset_speed"][0]
    lin = csfh.linearize(scene, "LN_spheres", at=0.7 * t_on + 0.3 * t_off, jacobian="fd")
    assert lin.in_contact
    rho = -lin.operating_point[1] - 0.02
    cr = nominal_values(scene, ["contact.cr"])["contact.cr"]
    damping = oracles.k_spheres() * rho**1.5 * oracles.xi("LN_spheres", cr) / v_on
    assert lin.A[4, 4] == pytest.approx(-damping / M1, rel=1e-6)
    assert v_on > 100 * 1e-3


def test_no_equilibrium_is_refused() -> None:
    """Free fall without contact law and flexure: nothing holds body 1."""
    scene = scene_from_dict({"name": "falling", "parts": {"flexure": False, "friction": False}})
    with pytest.raises(SimulationError, match="equilibrium: Newton's method found no"):
        csfh.linearize(scene, "none", at="equilibrium", jacobian="fd")


def test_the_command_writes_the_model_and_its_modes(tmp_path: Path) -> None:
    out = tmp_path / "lin"
    proc = run_csfh("linearize", "central", "--at", "equilibrium", "--out", str(out), "--quiet")
    assert proc.returncode == 0, proc.stderr
    data = json.loads((out / "linearization.json").read_text())
    for key in ("A", "B", "C", "D", "states", "inputs", "outputs", "operating_point"):
        assert key in data
    assert data["states"] == list(STATES) and data["inputs"] == list(INPUTS)
    assert data["outputs"] == list(OUTPUTS)
    n, m, p = len(STATES), len(INPUTS), len(OUTPUTS)
    assert np.shape(data["A"]) == (n, n) and np.shape(data["B"]) == (n, m)
    assert np.shape(data["C"]) == (p, n) and np.shape(data["D"]) == (p, m)
    assert np.shape(data["eigenvalues"]) == (n, 2) and len(data["operating_point"]) == n
    f, zeta = data["frequencies_hz"], data["damping_ratios"]
    assert len(f) == len(zeta) == 2 and f == sorted(f)
    assert data["equilibrium"]["converged"] is True
    with np.load(out / "linearization.npz") as npz:
        np.testing.assert_array_equal(npz["A"], data["A"])
        np.testing.assert_array_equal(npz["D"], data["D"])
    assert "damping ratio" in (out / "linearization.md").read_text()
    assert (out / "bode.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # B maps F_ext[2] onto dvy/dt = 1/m
    assert data["B"][4][1] == pytest.approx(1 / M1, rel=1e-9)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--at", "soon"], "--at = 'soon' must be start, equilibrium or a time"),
        (["--at", "-1"], "--at = '-1' must be"),
        (["--input", "F_ext[3]"], "input 'F_ext[3]' is not one of"),
        (["--output", "energy"], "output 'energy' is not one of"),
        (["--model", "Moreau"], "model 'Moreau' cannot be linearized"),
        (["--jacobian", "magic"], "jacobian = 'magic' is not one of"),
    ],
)
def test_bad_options_exit_2_on_one_line(args: list[str], message: str, tmp_path: Path) -> None:
    proc = run_csfh("linearize", "central", "--out", str(tmp_path / "x"), *args)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], proc.stderr
    assert not (tmp_path / "x" / "linearization.json").exists()


def test_the_api_refuses_a_bad_point() -> None:
    with pytest.raises(ParameterError, match="at = 'later'"):
        csfh.linearize("central", at="later")


@pytest.mark.skipif(
    not provides_directional_derivatives(), reason="the FMU provides no directional derivatives"
)
@pytest.mark.parametrize(
    ("scene", "at"), [("csfh", "start"), ("csfh", "equilibrium"), ("csfh", 0.3)]
)
def test_directional_derivatives_match_the_finite_differences(scene: str, at: str | float) -> None:
    """The FMU's fmi2GetDirectionalDerivative against the 4th-order differences, row by row of
    [A B; C D] relative to the row's largest entry: 1e-6 (the differences' own error is ~1e-10
    at these steps, jacobian.py)."""
    fd = csfh.linearize(scene, "LN_spheres", at=at, jacobian="fd")
    dd = csfh.linearize(scene, "LN_spheres", at=at, jacobian="directional")
    assert dd.jacobian.startswith("directional") and fd.jacobian.startswith("finite")
    J_fd = np.block([[fd.A, fd.B], [fd.C, fd.D]])
    J_dd = np.block([[dd.A, dd.B], [dd.C, dd.D]])
    scale = np.max(np.abs(J_fd), axis=1, keepdims=True)
    assert np.all(np.abs(J_dd - J_fd) <= 1e-6 * scale + 1e-300), np.abs(J_dd - J_fd) / scale
    np.testing.assert_allclose(dd.frequencies_hz, fd.frequencies_hz, rtol=1e-6)
