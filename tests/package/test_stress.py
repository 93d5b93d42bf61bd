"""The stress suite (csfh.studies.stress): its scaled impact oracle against docs/model.md §7.3,
and the reduced suite without a failure."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from csfh.studies.stress.cases import select_cases
from csfh.studies.stress.oracles import effective_restitution
from csfh.studies.stress.report import write_report as write_stress_report
from csfh.studies.stress.suite import run_suite


def test_scaled_impact_oracle_matches_physics_7_3() -> None:
    assert effective_restitution("LN_spheres", 0.9) == pytest.approx(0.9132, abs=1e-4)
    assert effective_restitution("HuntCrossley", 0.9) == pytest.approx(0.9090, abs=1e-4)
    assert effective_restitution("Flores", 0.9) == pytest.approx(0.8939, abs=1e-4)
    assert effective_restitution("LN_spheres", 1.0) == pytest.approx(1.0, abs=1e-9)


def test_reduced_stress_suite_has_no_failure(tmp_path: Path) -> None:
    cases = select_cases(quick=True)
    runs = run_suite(cases)
    write_stress_report(cases, runs, tmp_path)
    failures = [(r.case, r.model, r.integrator, r.reason) for r in runs if r.verdict == "fail"]
    assert not failures, failures
    # every documented limit says why
    assert all(r.reason for r in runs if r.verdict == "limit")
    # the event-driven FMU integrators and Moreau never hit a limit in the reduced suite
    assert all(r.verdict == "pass" for r in runs if r.integrator != "RK4")
    assert (tmp_path / "stress.md").exists() and (tmp_path / "stress.json").exists()
    manifest = json.loads((tmp_path / ".csfh" / "stress.json").read_text())
    assert set(manifest["files"]) == {"stress.md", "stress.json"}


# ------------------------------------------------------------------------------------------
# the cases are data (csfh/studies/stress/cases.toml): the numbers it writes out in full are the
# oracles' (the derivations its comments give), so the data and the physics cannot drift apart


def _impact(case: Any) -> tuple[float, float]:
    """(K, v) of a bare normal impact case."""
    params = case.scene.parameters
    return float(params.get("contact.K_spheres_given", K_SPHERES)), -case.scene.u0[1]


K_SPHERES = 4.7353e10


def test_the_impact_cases_horizons_are_the_hertz_oracles() -> None:
    from csfh.studies.stress.oracles import hertz_contact_time, hertz_max_indentation

    checked = 0
    for case in select_cases():
        if case.group not in ("stiffness", "speed", "restitution"):
            continue
        K, v = _impact(case)
        tc = hertz_contact_time(K, v)
        if case.group == "stiffness":
            stop = 1.5 * tc + 3e-6 / v
            assert case.t_contact == tc
        elif case.group == "speed" and "cylinders" not in case.name:
            stop = 4e-3 + 1.5 * tc + 3e-6 / v
            assert case.t_contact == tc
        elif case.group == "speed":
            stop = 4e-3 + 30 * tc
            assert case.t_contact == 3 * tc
        else:
            e_min = min(
                effective_restitution(law, case.scene.parameters["contact.cr"], rtol=1e-6)
                for law in ("LN_spheres", "HuntCrossley", "Flores")
            )
            stop = 3 * tc + 3 * hertz_max_indentation(K, v) / (max(e_min, 1e-3) * v)
            assert case.t_contact == tc
        # the restitution horizon comes from an integration to rtol 1e-6 (scipy's Radau), whose
        # last digits may move with scipy's version
        assert case.scene.stop_time == pytest.approx(stop, rel=1e-12), case.name
        assert case.scene.integrator.output_interval == pytest.approx(stop / 400, rel=1e-12)
        checked += 1
    assert checked == 21


def test_every_case_has_a_check_runs_and_a_unique_name() -> None:
    from csfh.studies.stress.cases import COMPLIANT_INTEGRATORS

    cases = select_cases()
    assert len({c.name for c in cases}) == len(cases) == 30
    assert [c.name for c in select_cases(quick=True)] == [c.name for c in cases if c.quick]
    for case in cases:
        assert callable(case.check) and case.runs
        for model, integ in case.runs:
            assert integ in (*COMPLIANT_INTEGRATORS, "Moreau") and (integ == "Moreau") == (
                model == "Moreau"
            )


def test_a_case_with_an_unknown_key_is_refused() -> None:
    from csfh.studies.stress import cases as cases_module

    entry = {
        "name": "x",
        "group": "g",
        "description": "",
        "quick": False,
        "models": ["Moreau"],
        "check": {"kind": "no_extra"},
        "scene": {"name": "x"},
        "colour": "red",
    }
    with pytest.raises(ValueError, match="unknown key 'colour'"):
        cases_module._case(entry, {})
