"""Moreau's F_N and F_T are each step's impulse over h (docs/model.md §6), about 1/h: wherever
they are printed or plotted beside the contact laws' forces they say so."""

from __future__ import annotations

from pathlib import Path

import pytest
from csfh_command import run_csfh
from test_cli_errors import csfh_env

from csfh.model.scene import load_scene
from csfh.runners.simulate import simulate


@pytest.mark.parametrize(("law", "labelled"), [("Moreau", True), ("LN_spheres", False)])
def test_csfh_run_labels_moreaus_impulses(tmp_path: Path, law: str, labelled: bool) -> None:
    proc = run_csfh(
        "run",
        "central",
        "--law",
        law,
        "--out",
        str(tmp_path),
        "--quiet",
        cwd=tmp_path,
        env=csfh_env(),
    )
    assert proc.returncode == 0, proc.stderr
    assert ("max F_N (impulse/h) " in proc.stdout) == labelled, proc.stdout
    assert "max F_N " in proc.stdout or labelled, proc.stdout


def test_the_force_axes_of_a_comparison_label_moreaus_impulses() -> None:
    from csfh.studies.paper_figures import central_impact, time_histories

    scene = load_scene("central")
    scene = type(scene)(**{**scene.__dict__, "stop_time": 0.1})
    runs = [simulate(scene, m, quiet=True) for m in ("LN_spheres", "Moreau")]
    fig = time_histories(runs, "t")
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert any("F_N" in s and "impulse / h" in s for s in labels), labels
    assert any("F_T" in s and "impulse / h" in s for s in labels), labels
    fig = central_impact(runs[:1], "t", 0.02)
    assert not any("impulse" in ax.get_ylabel() for ax in fig.axes)


@pytest.mark.parametrize("name", ["contact.F_N", "contact.F_T"])
def test_the_instantaneous_forces_point_to_their_peaks(name: str) -> None:
    """In co-simulation contact.F_N is 0 at nearly every communication point (contacts are far
    shorter than a step): the variable's description says so and where the peak is."""
    from csfh.model.model_info import variables

    text = variables()[name].description
    assert "instantaneous" in text.lower() and f"{name}_peak" in text, text
