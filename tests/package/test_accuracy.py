"""Error against run time (csfh.studies.accuracy): the convergence of each integrator, where the
contact peaks and onsets are found, and the quick accuracy report. (The stress suite:
test_stress.py.)"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
from oracles import G, rigid_impact_times

from csfh.model.scene import load_scene
from csfh.runners.fmu import simulate_me
from csfh.runners.moreau import moreau
from csfh.runners.rk4 import rk4_event
from csfh.studies.accuracy.metrics import contact_errors, observed_order
from csfh.studies.accuracy.report import write_report
from csfh.studies.accuracy.study import QUICK_SETTINGS, _grid, default_horizon, run_study


def test_moreau_is_first_order_in_the_impact_times() -> None:
    scene = load_scene("central")
    exact = rigid_impact_times(4)
    hs = [1e-4, 3e-5, 1e-5, 3e-6, 1e-6]
    errors = []
    for h in hs:
        tr = moreau(scene, h=h, stop_time=0.5, output_interval=1e-3)
        errors.append(float(np.max(np.abs(tr.impacts["t"][:4] - exact))))
    slope = np.polyfit(np.log(hs), np.log(errors), 1)[0]
    assert 0.8 < slope < 1.3, (slope, errors)
    # each bounce is late by at most a few steps (docs/model.md §6.3), over four bounces
    assert all(e <= 5 * h for e, h in zip(errors, hs, strict=True)), errors


def test_cvode_error_falls_with_the_tolerance() -> None:
    scene = replace(load_scene("asymmetric"), stop_time=0.25)
    ref = simulate_me(scene, "LN_cylinders", rtol=1e-12)
    errors = [
        contact_errors(simulate_me(scene, "LN_cylinders", rtol=r), ref)["contact_time"]
        for r in (1e-4, 1e-6, 1e-8)
    ]
    assert errors[0] > errors[1] > errors[2], errors
    assert errors[0] / errors[2] > 100, errors


def test_contact_peaks_are_found_on_the_interpolant() -> None:
    """Peak F_N and max indentation of the first three contacts come from CVODE's interpolant
    inside each step, not from the step ends: at rtol 1e-13 and 5e-14 (different steps) they
    agree to 1e-8 relative on the csfh scene, while a step is 4e-6 s long, so a peak missed by
    a step end would differ by ~1e-6 (the LN_ESDU third contact has its hump exactly on a
    sample, where the centred difference is zero; LN_spheres differed by 4e-8)."""
    for name in ("csfh",):
        scene = load_scene(name)
        t_end = default_horizon(scene)
        scene = replace(scene, stop_time=t_end)
        grid = _grid(scene, t_end)
        for law in ("LN_spheres", "LN_ESDU"):
            a = simulate_me(scene, law, rtol=1e-13, output_times=grid)
            b = simulate_me(scene, law, rtol=5e-14, output_times=grid)
            errors = contact_errors(b, a)
            assert errors["peak_F_N"] < 1e-8, (name, law, errors)
            assert errors["max_indentation"] < 1e-8, (name, law, errors)


def test_rk4_bisection_locates_the_onset_within_the_event_tolerance() -> None:
    """The paper's scheme: the penetration at the accepted onset is at most the tolerance, so
    the onset time is within tol / v of the exact one (docs/model.md §7.1)."""
    scene = load_scene("central")
    t_exact, v = math.sqrt(2 * 0.03 / G), math.sqrt(2 * G * 0.03)
    for h0, tol in ((2e-4, 1e-4), (5e-5, 1e-6), (1.25e-5, 1e-8)):
        tr = rk4_event(scene, "LN_spheres", h0=h0, tol=tol, stop_time=0.1)
        assert 0 <= tr.contacts[0] - t_exact <= tol / v * 1.01, (h0, tol, tr.contacts[0])
        assert tr.stats["rejected_steps"] >= 1


def test_accuracy_report_quick(tmp_path: Path) -> None:
    scene = load_scene("central")
    settings = {k: v[:2] for k, v in QUICK_SETTINGS.items()}
    study = run_study(scene, stop_time=0.25, settings=settings, repeats=1)
    write_report(study, tmp_path)
    for name in ("report.md", "accuracy.json", "wp_LN_spheres.png", "wp_Moreau.png"):
        assert (tmp_path / name).exists(), name
    data = json.loads((tmp_path / "accuracy.json").read_text())
    assert data["reference_checks"]["LN_spheres"]["contact_time"] < 1e-9
    me = [p for p in study.points if p.model == "LN_spheres" and p.integrator == "ME"]
    assert me[0].errors["contact_time"] > me[1].errors["contact_time"]
    assert observed_order(me, "contact_time") > 0.5
    text = (tmp_path / "report.md").read_text()
    assert "Observed order of convergence" in text and "What the numbers show" in text
    # one output set (csfh.output): the manifest lists every file of the report
    manifest = json.loads((tmp_path / ".csfh" / "accuracy.json").read_text())
    assert set(manifest["files"]) == {p.name for p in tmp_path.iterdir() if p.is_file()}
