"""The four-model comparison (csfh.studies.compare): what `csfh compare` writes, its first
contacts against the flight integrated independently, and `csfh plot` drawing a saved comparison
again."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import oracles
import pytest

from csfh.cli.main import main
from csfh.model.scene import scene_from_dict
from csfh.studies import paper_figures
from csfh.studies.compare import compare, read_comparison


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


def test_plot_redraws_a_saved_comparison(tmp_path: Path) -> None:
    """`csfh plot DIR` draws the figures of `csfh compare` again from its files alone."""
    out = tmp_path / "run"
    result = compare("central", out, models=("LN_cylinders", "Moreau"))
    figures = {p.name: p for p in result.files if p.suffix == ".png"}
    assert sorted(figures) == sorted(paper_figures.FIGURES)
    for path in figures.values():
        path.unlink()
    summary, runs = read_comparison(out)
    assert summary["clearance"] == pytest.approx(0.02, rel=1e-12)  # R2 - R1 of the central scene
    for original, back in zip(result.runs, runs, strict=True):
        assert back.model == original.model
        np.testing.assert_allclose(back["y"], original["y"], rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(back.contacts, original.contacts, rtol=1e-15)
        assert bool(back.steps) == bool(original.steps)
        if original.steps:
            np.testing.assert_allclose(back.steps["F_N"], original.steps["F_N"], rtol=1e-9)
    assert main(["plot", str(out)]) == 0
    for name in paper_figures.FIGURES:
        assert (out / name).stat().st_size > 10_000, name


def test_plot_of_a_directory_without_a_comparison_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plot", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("csfh: error: ") and "summary.json" in err and "\n" not in err
    (tmp_path / "summary.json").write_text(json.dumps({"scene": "x", "models": {"Spring": {}}}))
    assert main(["plot", str(tmp_path)]) == 2
    assert "not a summary written by csfh compare" in capsys.readouterr().err
    (tmp_path / "summary.json").write_text(
        json.dumps({"scene": "x", "clearance": 0.02, "models": {"Spring": {}}})
    )
    assert main(["plot", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "Spring.csv: missing" in err
