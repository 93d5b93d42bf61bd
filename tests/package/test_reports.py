"""What the harness writes and reads back: the CSV tables and their reader, and the comparison's
figures (what they draw, how they name the models). (`csfh plot` re-plotting a saved run:
test_compare.py.)"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from csfh.model import model_info
from csfh.output import read_table, write_table
from csfh.studies import paper_figures
from csfh.trajectory import COLUMNS, UNITS, Trajectory


def synthetic_run(model: str, seed: int) -> Trajectory:
    """A made-up run: a damped bounce, with per-step records (no simulation involved)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 0.2, 401)
    y = -0.0199 * np.abs(np.sin(25 * t))  # down to the bore at t = (2k + 1) pi / 50
    table = {c: rng.normal(size=t.size) for c in COLUMNS}
    table.update(t=t, x=0.001 * np.sin(7 * t), y=y, theta=0.01 * t)
    table["F_N"] = np.where(y < -0.0195, 1e4, 0.0)
    table["indentation"] = np.where(y < -0.0195, 1e-5, 0.0)
    steps = {k: v[::10].copy() for k, v in table.items()}
    contacts = np.array([np.pi / 50, 3 * np.pi / 50]) - 0.008
    return Trajectory(model, "synthetic", table, contacts, steps=steps)


def test_a_table_reads_back_as_written(tmp_path: Path) -> None:
    rng = np.random.default_rng(1)
    columns = {
        "t": np.arange(5) * 0.1,
        "F_N": rng.lognormal(5, 3, 5),
        "gap": -rng.random(5) * 1e-7,
        "mode": np.array([0.0, 1, 2, 3, 4]),
    }
    path = write_table(tmp_path / "a.csv", columns, UNITS)
    assert path.read_text().splitlines()[0] == "t [s],F_N [N],gap [m],mode [-]"
    back, units = read_table(path)
    assert list(back) == list(columns) and units == {"t": "s", "F_N": "N", "gap": "m", "mode": "-"}
    for name, values in columns.items():
        np.testing.assert_allclose(back[name], values, rtol=1e-9, atol=0)  # 10 digits written


def test_a_trajectory_reads_back_from_its_csv(tmp_path: Path) -> None:
    run = synthetic_run("LN_ESDU", 2)
    back = Trajectory.read_csv(run.write_csv(tmp_path / "LN_ESDU.csv"))
    assert back.model == "LN_ESDU" and list(back.table)[:3] == ["t", "x", "y"]
    for name in run.table:
        np.testing.assert_allclose(back[name], run[name], rtol=1e-9, atol=1e-300)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "empty file"),
        ("t [s],x [m]\n0,1,2\n", "3 values per row, 2 columns named"),
        ("t [s],t [s]\n0,1\n", "column 't' appears twice"),
        ("t [s],x [m\n0,1\n", "is not 'name [unit]'"),
        ("t [s],x [m]\n0,abc\n", "not a table of numbers"),
    ],
)
def test_a_bad_table_is_refused_naming_the_file(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match=re.escape(message)) as info:
        read_table(path)
    assert str(path) in str(info.value)


@pytest.mark.parametrize("delta", [0.005, 0.02])
def test_the_central_impact_figure_marks_the_scenes_clearance(delta: float) -> None:
    """Fig. 6's dashed line is the bottom of the clearance circle, y = -delta (mm)."""
    fig = paper_figures.central_impact([synthetic_run("LN_spheres", 3)], "t", delta)
    flat = [
        line
        for line in fig.axes[0].get_lines()
        if len(set(np.asarray(line.get_ydata(), dtype=float))) == 1
    ]
    assert len(flat) == 1
    assert float(flat[0].get_ydata()[0]) == pytest.approx(-1e3 * delta, rel=1e-12)
    assert flat[0].get_linestyle() == "--"


def test_every_figure_names_the_models_as_the_command_line_does() -> None:
    runs = [synthetic_run(m, i) for i, m in enumerate(model_info.MODELS)]
    figures = [
        paper_figures.time_histories(runs, "t"),
        paper_figures.central_impact(runs, "t", 0.02),
        paper_figures.first_contact(runs, "t"),
        paper_figures.friction_steps(runs, "t"),
        paper_figures.trajectory(runs, "t", 0.02),
    ]
    for fig in figures:
        labels = {text.get_text() for legend in fig.legends for text in legend.get_texts()}
        assert set(model_info.MODELS) <= labels, labels
        assert not any("LNA" in label or "K spheres" in label for label in labels), labels
    colors = {
        line.get_label(): line.get_color()
        for line in figures[0].axes[0].get_lines()
        if line.get_label() in model_info.MODELS
    }
    assert len(set(colors.values())) == len(model_info.MODELS)  # one colour per model
