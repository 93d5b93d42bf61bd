"""The paper's four-model comparison (section 6): run the scene's models and write tables, a
summary and the figures; and read such an output directory back (`csfh plot DIR`).

Files in the output directory: MODEL.csv (the output table of each model), MODEL.steps.csv (the
per-step records of the event-driven models, for the figures against the step number),
summary.json (the scene, each model's summary and contact onsets, the clearance) and the figures
of csfh.studies.paper_figures. They are one output set (csfh.output): a comparison replaces the
previous one's files as a whole."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ResultsError
from ..model.instance import clearance
from ..model.scene import Scene, load_scene
from ..output import check_set, output_set, read_table, write_json, write_table
from ..runners.simulate import simulate
from ..trajectory import UNITS, Trajectory
from .paper_figures import write_figures

SUMMARY = "summary.json"
OUTPUT_SET = "compare"
"""The name of a comparison's output set (csfh.output): its files replace the previous
comparison's in the same directory as a whole; `csfh plot` checks that they still belong
together."""


@dataclass
class Comparison:
    """What :func:`compare` ran and wrote: the scene, one :class:`Trajectory` per model, and
    the files (CSV, per-step records, summary.json, figures)."""

    scene: Scene
    runs: list[Trajectory]
    files: list[Path]


def compare(
    scene: Scene | str | Path,
    out: Path,
    *,
    models: tuple[str, ...] | None = None,
    interface: str = "me",
    quiet: bool = True,
) -> Comparison:
    """Run every model of the comparison on `scene` (a Scene, a built-in scene's name or a scene
    file) and write, into `out`: MODEL.csv (t, x, y, theta, vx, vy, omega, F_N, F_T,
    indentation, v_T, gap, energy), MODEL.steps.csv, summary.json and the figures (paper
    Figs. 6-12)."""
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    out = Path(out)
    models = models or scene.models
    runs = [simulate(scene, m, interface=interface, quiet=quiet) for m in models]
    delta = clearance(scene)
    summary = {
        "scene": scene.name,
        "description": scene.description,
        "preset": scene.preset,
        "stop_time": scene.stop_time,
        "q0": list(scene.q0),
        "clearance": delta,
        "models": {tr.model: tr.summary() for tr in runs},
        "contacts": {tr.model: [float(t) for t in tr.contacts] for tr in runs},
        "notes": {
            "Moreau F_N, F_T": "largest per-step impulse / h in each output interval (scales "
            "as 1/h); impulses are in the CSV as Lambda_N, Lambda_T",
            "steps": "integrator steps (CVODE internal steps; Moreau steps)",
            "rhs_evaluations": "model right-hand-side evaluations, including CVODE's "
            "difference-quotient Jacobian; Moreau: one force evaluation "
            "per step",
        },
    }
    files: list[Path] = []
    with output_set(out, OUTPUT_SET):  # replaces the previous comparison's files as a whole
        for tr in runs:
            files.append(tr.write_csv(out / f"{tr.model}.csv"))
            if tr.steps:
                files.append(write_table(out / f"{tr.model}.steps.csv", tr.steps, UNITS))
        files.append(write_json(out / SUMMARY, summary))
        files += write_figures(runs, out, title(scene.name, scene.description), delta)
    return Comparison(scene=scene, runs=runs, files=files)


def title(scene: str, description: str) -> str:
    """The title of the comparison's figures."""
    return f"scene {scene}: {description}"


def read_comparison(out: Path) -> tuple[dict[str, Any], list[Trajectory]]:
    """The summary and the runs of an output directory of `compare`: each model's table, its
    per-step records where they were written, and its contact onsets. Raises ResultsError
    naming the file that is missing or unreadable."""
    out = Path(out)
    path = out / SUMMARY
    check_set(out, OUTPUT_SET, [SUMMARY], "csfh compare")  # and completes an interrupted commit
    if not path.is_file():
        raise ResultsError(
            f"{out}: no {SUMMARY} here; csfh plot reads the output directory of csfh compare"
        )
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
        models = list(summary["models"])
        scene = str(summary["scene"])
        float(summary["clearance"])
    except OSError as exc:
        raise ResultsError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    except (ValueError, KeyError, TypeError) as exc:
        raise ResultsError(f"{path}: not a summary written by csfh compare ({exc})") from None
    names = [*(f"{m}.csv" for m in models), *(f"{m}.steps.csv" for m in models)]
    check_set(out, OUTPUT_SET, names, "csfh compare")
    runs = []
    for model in models:
        table = out / f"{model}.csv"
        if not table.is_file():
            raise ResultsError(f"{table}: missing (listed in {path})")
        tr = Trajectory.read_csv(table, model=model, scene=scene)
        tr.contacts = np.asarray(summary.get("contacts", {}).get(model, []), dtype=float)
        steps = out / f"{model}.steps.csv"
        if steps.is_file():
            tr.steps, _ = read_table(steps)
        runs.append(tr)
    return summary, runs


def replot(out: Path) -> list[Path]:
    """Draw the figures of a comparison again from its output directory (they replace the
    comparison's figures; its tables stay)."""
    with output_set(out, OUTPUT_SET, merge=True):
        summary, runs = read_comparison(out)
        name = title(summary["scene"], summary.get("description", ""))
        return write_figures(runs, Path(out), name, float(summary["clearance"]))
