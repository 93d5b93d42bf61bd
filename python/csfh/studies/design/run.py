"""The design study as one call (`run_design`): the scene's own design and the centre of the
ranges, the quasi-random samples, the differential-evolution search, the feasible Pareto front,
the best designs written as scene files, the Sobol indices, and the report (design.md,
design.json, figures) written as one output set. Every run goes through the output directory's
result store, so an interrupted study keeps its finished designs and a repeated one resumes."""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...model.scene import Scene, load_scene
from ...output import output_set, write_text
from ..execution import Execution, open_store
from . import report, search, sensitivity
from .evaluate import Evaluator
from .scenefile import scene_toml
from .spec import DesignStudy, load_study

SCENES = "scenes"
"""The subdirectory of the written scene files."""


@dataclass
class DesignOutcome:
    """What a design study computed and wrote."""

    study: DesignStudy
    result: dict[str, Any]
    run_info: dict[str, Any]
    path: Path


def _unique(designs: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """The designs without repeats (by their variables), first occurrence kept."""
    seen, out = set(), []
    for d in designs:
        key = tuple(sorted(d["variables"].items()))
        if key not in seen:
            seen.add(key)
            out.append(d)
    return out


def _best(study: DesignStudy, designs: Sequence[dict[str, Any]], scale: float) -> list[int]:
    """The indices of the best designs: by the search's penalised objective (feasible first)."""
    order = sorted(range(len(designs)), key=lambda i: search.penalised(study, designs[i], scale))
    return order[: study.best]


def best_entry(
    study: DesignStudy, design: dict[str, Any], rank: int, scene_path: str
) -> dict[str, Any]:
    """A best design as design.json lists it: where its scene file is, how `csfh shock`
    reproduces it (condition or peak and duration, direction, law) and its worst direction's
    fields as shock.json has them, with its variables, objectives and margins."""
    row = next(r for r in design["directions"] if r["direction"] == design["worst_direction"])
    p = study.pulse
    return {
        "rank": rank,
        "scene": scene_path,
        "condition": p.name or None,
        "peak_g": p.peak_g,
        "duration": p.duration,
        "direction": design["worst_direction"],
        "law": study.law,
        **row,
        "feasible": design["feasible"],
        "variables": design["variables"],
        "parameters": design["parameters"],
        "objectives": design["objectives"],
        "margins": design["margins"],
    }


def _write_scenes(
    out: Path, scene: Scene, study: DesignStudy, best: list[dict[str, Any]]
) -> list[dict[str, Any]]:
    entries = []
    for k, design in enumerate(best, start=1):
        name = f"{scene.name}_design_{k}"
        rel = f"{SCENES}/{name}.toml"
        how = (
            f"--condition {study.pulse.name}"
            if study.pulse.name
            else (f"--peak {study.pulse.peak_g!r} --duration {study.pulse.duration!r}")
        )
        header = (
            f"Design {k} of the design study of scene {scene.name} ({study.source}), written\n"
            f"by csfh design. Reproduce its worst direction with\n"
            f"  csfh shock {rel} {how} --direction {design['worst_direction']:g}"
        )
        text = scene_toml(
            scene,
            name,
            f"{scene.name}: design {k} of csfh design ({study.pulse.describe()})",
            design["parameters"],
            header,
        )
        write_text(out / rel, text)
        entries.append(best_entry(study, design, k, rel))
    return entries


def _sensitivity(study: DesignStudy, ev: Evaluator, direction: float) -> dict[str, Any] | None:
    """Sobol indices of the objectives to the design variables and the paper's parameters, at
    one direction (None: no sensitivity samples)."""
    n = study.sensitivity_samples
    if n == 0:
        return None
    names = study.objectives

    def outputs(designs: list[dict[str, Any]]) -> dict[str, np.ndarray]:
        return {k: np.array([float(d["objectives"][k]) for d in designs]) for k in names}

    lo, hi = search.bounds(study)
    out = {
        "direction": direction,
        "design": sensitivity.sobol_indices(
            study.names,
            list(zip(lo, hi, strict=True)),
            lambda x: outputs(ev.evaluate(x, "design sensitivity", [direction])),
            n,
            study.seed,
        ),
    }
    if study.paper_parameters:
        keys, ranges, overrides = sensitivity.paper_inputs(ev.spec.scene)

        def paper(x: np.ndarray) -> dict[str, np.ndarray]:
            sets = [overrides(row) for row in x]
            named = [dict(zip(keys, map(float, row), strict=True)) for row in x]
            return outputs(ev.evaluate_sets(sets, named, "paper sensitivity", [direction]))

        indices = sensitivity.sobol_indices(keys, ranges, paper, n, study.seed)
        indices["table4_spearman"] = sensitivity.table4_agreement(indices)
        out["paper"] = indices
    return out


def explore(study: DesignStudy, ev: Evaluator) -> dict[str, Any]:
    """Every computation of the study (module docstring); the result design.json holds."""
    nominal = ev.evaluate_sets([{}], [{}], "design: the scene's own design")[0]
    lo, hi = search.bounds(study)
    centre = ev.evaluate(((lo + hi) / 2)[None, :], "design: the centre of the ranges")[0]
    scale = float(centre["objectives"][study.search_objective]) or 1.0
    samples = ev.evaluate(search.sample(study, study.samples), "design samples")
    best, seen, generations = search.differential_evolution(study, ev.evaluate, scale)
    designs = _unique([*samples, *seen, best])
    front = search.feasible_front(designs, study.objectives)
    return {
        "nominal": nominal,
        "centre": centre,
        "scale": scale,
        "samples": samples,
        "search": {"best": best, "generations": generations, "evaluated": len(seen)},
        "designs": designs,
        "front": front,
        "best": [designs[i] for i in _best(study, designs, scale)],
        "sensitivity": _sensitivity(study, ev, nominal["worst_direction"]),
    }


def run_design(
    scene: Scene | str | Path,
    how: Execution,
    study_file: str | Path | None = None,
    *,
    quick: bool = False,
) -> DesignOutcome:
    """Run the design study of `study_file` (None: the scene's built-in study; `quick`: its
    [quick] values) on `scene` and write its report into `how.out` (default
    results/design/SCENE), where the finished runs are kept."""
    scene = scene if isinstance(scene, Scene) else load_scene(scene)
    study = load_study(scene, study_file)
    if quick:
        study = study.quick_study()
    out = how.directory("design", scene.name)
    wall = time.perf_counter()
    ev = Evaluator(study, scene, open_store(out), how)
    result = explore(study, ev)
    run_info = {**ev.runs, "executor": ev.executor, "wall_time": time.perf_counter() - wall}
    with output_set(out, "design"):  # the report replaces the previous one as a whole
        result["best_entries"] = _write_scenes(out, scene, study, result["best"])
        path = report.write_report(out, scene, study, ev, result, run_info)
    return DesignOutcome(study, result, run_info, path)


def design(
    scene: Scene | str | Path,
    study: str | Path | None = None,
    *,
    out: str | Path | None = None,
    quick: bool = False,
    workers: int | None = None,
    dask: str | None = None,
    quiet: bool = True,
) -> DesignOutcome:
    """`csfh design SCENE [STUDY] --out OUT`: the design study of `study` (None: the scene's
    built-in one) on `scene`, its report written into `out` (default results/design/SCENE);
    `workers` local processes (None: all cores, 1: serial) or the Dask scheduler at `dask`."""
    how = Execution(Path(out) if out is not None else None, workers, dask, quiet)
    return run_design(scene, how, study, quick=quick)
