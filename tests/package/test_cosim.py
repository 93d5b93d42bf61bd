"""The coupled system: the csfh FMU and the comb-drive actuator FMU in the fmpy master loop and in
libcosim (libcosimpy), the [cosim] scene section and `csfh cosim`."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from csfh_command import run_csfh
from oracles import K_COMB, G

from csfh.cosim.run import cosimulate
from csfh.model.scene import SceneError, load_scene, scene_from_dict


def scene_dict(**cosim: Any) -> dict[str, Any]:
    """A small coupled scene: flexure off, body 1 at the centre, a constant voltage."""
    table: dict[str, Any] = {
        "step": 1e-4,
        "voltage": {"V0": 237.6, "V1": 237.6, "t0": 0.0, "t1": 1.0},  # k V^2 = 50 N
        "actuator": {"direction": math.radians(30.0)},
    }
    table.update(cosim)
    return {
        "name": "coupled",
        "stop_time": 0.05,
        "initial": {"q": [0.0, 0.0, 0.0]},
        "parts": {"flexure": False, "friction": True},
        "cosim": table,
    }


def test_libcosimpy_agrees_with_the_fmpy_master_loop(libcosim: None) -> None:
    """The example (0.5 s, 5000 communication steps, 4 contacts) in both engines, Jacobi.

    Both call the same FMU binaries with the same inputs at the same communication points; the
    only difference is that libcosim counts time in integer nanoseconds, so CVODE's stop times
    differ in the last bits. Such round-off perturbations grow at each impact but stay far below
    the integration tolerance: we require 1e-9 m and 1e-8 rad (the FMU's absolute tolerance on
    x, y is 1e-8 m), the same contacts at the same communication points, and the same forces."""
    scene = load_scene("combdrive")
    a = cosimulate(scene, engine="fmpy", stop_time=0.5)
    b = cosimulate(scene, engine="libcosimpy", stop_time=0.5)
    assert a.t.shape == b.t.shape == (5001,)
    np.testing.assert_allclose(b.t, a.t, rtol=0, atol=1e-12)
    assert len(a.contacts) >= 3
    np.testing.assert_array_equal(b.contacts, a.contacts)
    for col, tol in (("x", 1e-9), ("y", 1e-9), ("theta", 1e-8), ("vy", 1e-6)):
        np.testing.assert_allclose(b[col], a[col], rtol=0, atol=tol, err_msg=col)
    np.testing.assert_array_equal(b["V"], a["V"])
    np.testing.assert_array_equal(b["F_act"], a["F_act"])
    np.testing.assert_allclose(b["M"], a["M"], rtol=0, atol=1e-9)
    assert a.stats["steps"] == b.stats["steps"]  # CVODE took the same path


def test_gauss_seidel_removes_the_one_step_delay() -> None:
    """Jacobi applies the force of V(t_k-1) over [t_k, t_k+1], Gauss-Seidel that of V(t_k):
    the force columns are shifted by exactly one step, and the trajectories (up to the first
    contact, during the ramp) differ by O(h): halving h halves the difference."""
    scene = load_scene("combdrive")
    dy = []
    for h in (1e-4, 5e-5):
        jacobi = cosimulate(scene, ordering="jacobi", step=h, stop_time=0.2)
        gs = cosimulate(scene, ordering="gauss-seidel", step=h, stop_time=0.2)
        np.testing.assert_array_equal(jacobi["F_act"][1:], gs["F_act"][:-1])
        np.testing.assert_allclose(gs["F_act"], K_COMB * gs["V"] ** 2, rtol=1e-14)
        dy.append(float(np.max(np.abs(jacobi["y"] - gs["y"]))))
    assert 0 < dy[0] < 1e-4  # 0.5 % of the clearance
    assert 1.6 < dy[0] / dy[1] < 2.4, dy


@pytest.mark.parametrize("engine", ["fmpy", "libcosimpy"])
def test_the_actuator_force_drives_the_hinge(engine: str) -> None:
    if engine == "libcosimpy":
        pytest.importorskip("libcosimpy")
    """A constant 50 N at 30 deg, no flexure, no contact within 0.05 s: the coupled motion is the
    analytic parabola of G1 under the comb force and gravity (so F_x, F_y reach F_ext[1],
    F_ext[2] with the right signs and are held from t = 0)."""
    scene = scene_from_dict(scene_dict(engine=engine))
    tr = cosimulate(scene)
    F = K_COMB * 237.6**2
    t = tr.t
    ax, ay = F * math.cos(math.radians(30)) / 10.0, F * math.sin(math.radians(30)) / 10.0 - G
    assert len(tr.contacts) == 0
    np.testing.assert_allclose(tr["F_act"], F, rtol=1e-14)
    np.testing.assert_allclose(tr["x"], 0.5 * ax * t**2, rtol=0, atol=1e-7)
    np.testing.assert_allclose(tr["y"], 0.5 * ay * t**2, rtol=0, atol=1e-7)
    np.testing.assert_allclose(tr["theta"], 0.0, atol=1e-12)


def test_cli_cosim_writes_csv_and_figure(tmp_path: Path) -> None:
    out = tmp_path / "out"
    proc = run_csfh("cosim", "combdrive", "--out", str(out), "--quiet", "--stop-time", "0.25")
    assert proc.returncode == 0, proc.stderr
    assert "combdrive / cosim-fmpy-jacobi:" in proc.stdout and "contacts" in proc.stdout
    csv = out / "cosim_fmpy.csv"
    manifest = (out / ".csfh" / "cosim.fmpy.json").read_text()  # one output set (csfh.output)
    assert '"cosim_fmpy.csv"' in manifest and '"cosim_fmpy.png"' in manifest
    header = csv.read_text().splitlines()[0].split(",")
    assert header[:3] == ["t [s]", "x [m]", "y [m]"]
    assert {"V [V]", "F_act [N]", "F_x [N]", "F_y [N]", "M [N m]", "F_N [N]"} <= set(header)
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert data.shape == (2501, len(header))
    assert (out / "cosim_fmpy.png").stat().st_size > 20_000


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"engine": "simulink"}, "cosim.engine = 'simulink' is not one of fmpy, libcosimpy"),
        ({"step": -1e-4}, "cosim.step = -0.0001 must be > 0"),
        ({"ordering": "random"}, "cosim.ordering = 'random' is not one of"),
        ({"voltage": {"V0": 0, "V1": 1, "t0": 0.5, "t1": 0.5}}, "cosim.voltage.t1 = 0.5 must be"),
        ({"voltage": {"V0": 0, "V1": "high", "t0": 0, "t1": 1}}, "cosim.voltage.V1 = 'high'"),
        ({"voltage": {"V0": 0, "t0": 0, "t1": 1}}, "[cosim.voltage]: key 'V1' is missing"),
        ({"actuator": {"gap": -1e-6}}, "cosim.actuator: gap = -1e-06 is out of range (0, inf)"),
        ({"actuator": {"fingers": 2.5}}, "cosim.actuator.fingers = 2.5 must be an integer"),
        ({"actuator": {"V": 3.0}}, "[cosim.actuator]: unknown key 'V'"),
        ({"speed": 1}, "[cosim]: unknown key 'speed'"),
        ({"engine": "libcosimpy", "step": 1.5e-10}, "not a whole number of nanoseconds"),
        ({"engine": "libcosimpy", "tolerance": 1e-9}, "without a tolerance"),
        ({"engine": "libcosimpy", "ordering": "gauss-seidel"}, "fixed-step algorithm is Jacobi"),
    ],
)
def test_bad_cosim_section_is_a_one_line_error(change: dict[str, Any], message: str) -> None:
    data = scene_dict(**change)
    with pytest.raises(SceneError) as info:
        scene_from_dict(data, "bad.toml")
    text = str(info.value)
    assert "\n" not in text and text.startswith("bad.toml: ") and message in text, text


def test_driven_inputs_and_enumerations_are_refused(tmp_path: Path, libcosim: None) -> None:
    data = scene_dict()
    data["inputs"] = {"F_ext[2]": 3.0}
    with pytest.raises(SceneError, match=r"inputs.F_ext\[2\] is driven by the actuator"):
        scene_from_dict(data)
    # libcosimpy ignores Enumeration variables: the engine sets their Integer twins
    # (contact.law_number), so both engines run the chosen law
    data = scene_dict(engine="libcosimpy")
    data["parameters"] = {"contact.law": "LN_cylinders"}
    a = cosimulate(scene_from_dict(data), stop_time=0.3)
    b = cosimulate(scene_from_dict(data), engine="fmpy", stop_time=0.3)
    spheres = cosimulate(scene_from_dict(scene_dict()), engine="fmpy", stop_time=0.3)
    np.testing.assert_allclose(a["y"], b["y"], rtol=0, atol=1e-9)
    assert np.max(np.abs(a["F_N"] - spheres["F_N"])) > 1.0  # another law indeed
    scene = tmp_path / "plain.toml"
    scene.write_text('name = "plain"\n')
    proc = run_csfh("cosim", str(scene))
    assert proc.returncode == 2
    assert proc.stderr.strip().endswith("the scene has no [cosim] section"), proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
