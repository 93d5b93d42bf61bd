"""The stress suite (csfh.studies.stress): its scaled impact oracle against docs/model.md §7.3,
and the reduced suite without a failure."""

from __future__ import annotations

import json
from pathlib import Path

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
