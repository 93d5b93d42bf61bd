"""`csfh tolerance` (csfh.studies.tolerance): Monte Carlo samples that are reproducible and do not
depend on the run count, a study whose first contacts agree with the flight integrated
independently for each sample, and a bad tolerance file refused in one line."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import oracles
import pytest

from csfh.cli.main import main
from csfh.studies.tolerance.study import load_study, sample


def test_monte_carlo_samples_are_reproducible_and_independent_of_the_run_count() -> None:
    study = load_study("tolerance_csfh")
    first = [sample(study, k) for k in range(5)]
    assert first == [sample(study, k) for k in range(5)]
    assert first[3] == sample(study, 3)  # run k does not depend on how many runs there are
    assert first[0] != first[1]
    r1 = np.array([sample(study, k)["contact.R1"] for k in range(400)])
    assert abs(np.mean(r1) - 0.18) < 4 * 2e-5 / math.sqrt(400)
    assert 0.8 * 2e-5 < np.std(r1) < 1.2 * 2e-5


def test_tolerance_study_is_reproducible(tmp_path: Path) -> None:
    args = [
        "tolerance",
        "tolerance_csfh",
        "--runs",
        "6",
        "--seed",
        "7",
        "--models",
        "LN_cylinders",
        "Moreau",
        "--stop-time",
        "0.1",
        "--quiet",
    ]
    assert main([*args, "--out", str(tmp_path / "a"), "--workers", "1"]) == 0
    assert main([*args, "--out", str(tmp_path / "b"), "--workers", "2"]) == 0
    ja = json.loads((tmp_path / "a" / "tolerance.json").read_text())
    jb = json.loads((tmp_path / "b" / "tolerance.json").read_text())
    ja.pop("run"), jb.pop("run")
    assert ja == jb
    assert len(ja["samples"]["contact.R1"]) == 6
    # each run's first contact against the flight on the flexure integrated here with that
    # run's sampled R1, R2, h, rho, beta (oracles.py: own compliance, DOP853 at rtol 1e-12).
    # The samples move it by ~1e-4 s; LN_cylinders (CVODE, rtol 1e-6) agrees to ~4e-8 s (the
    # position error ~ rtol x the 0.027 m path, over the 0.7 m/s approach): 4e-7 s; Moreau's
    # first contact step starts within h/2 of it (docs/model.md §6.1)
    samples = ja["samples"]
    fc = ja["models"]["LN_cylinders"]["values"]["first_contact"]
    fc_moreau = ja["models"]["Moreau"]["values"]["first_contact"]
    expected = []
    for k in range(6):
        flexure = oracles.Flexure(
            h=samples["flexure.h"][k],
            rho=samples["flexure.rho"][k],
            beta=samples["flexure.beta"][k],
        )
        delta = samples["contact.R2"][k] - samples["contact.R1"][k]
        expected.append(oracles.first_contact_of_flight(flexure, delta=delta)[0])
    assert np.ptp(expected) > 5e-5  # the tolerances move it far beyond the tolerance below
    np.testing.assert_allclose(fc, expected, rtol=0, atol=4e-7)
    h = load_study("tolerance_csfh").scene.integrator.moreau_h
    assert all(
        t_c - h / 2 - 1e-12 <= t < t_c + h / 2 for t, t_c in zip(fc_moreau, expected, strict=True)
    )
    for name in ("tolerance.md", "tolerance_histograms.png"):
        assert (tmp_path / "a" / name).stat().st_size > 0
    manifest = json.loads((tmp_path / "a" / ".csfh" / "tolerance.json").read_text())
    assert set(manifest["files"]) == {"tolerance.md", "tolerance.json", "tolerance_histograms.png"}


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ('"contact.R1" = {sigma = -1e-5}', "'contact.R1'"),
        ('"contact.R1" = {sigma = 1e-5, half_width = 1e-5}', "exactly one of"),
        ('"contact.R1" = {sgima = 1e-5}', "sgima"),
        ('"contact.R9" = {sigma = 1e-5}', "contact.R9"),
        ('"contact.law" = {sigma = 1}', "contact.law"),
        ('"contact.R1" = 2e-5', "must be a table"),
        ('"contact.R1" = {sigma = 0.05}', "invalid model"),
    ],
)
def test_bad_tolerance_file_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], table: str, message: str
) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(f'name = "bad"\n[initial]\nq = [0.01, 0.01, 0.0]\n[tolerance]\n{table}\n')
    assert main(["tolerance", str(path), "--runs", "30", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert message in err[0] and "bad.toml" in err[0]
