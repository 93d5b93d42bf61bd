"""The tolerance study as one call (`run_tolerance`): the study file and the options, the samples,
the tasks run into the output directory's result store, the statistics, and the report
(tolerance.md, tolerance.json, histograms) written as one output set."""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from ...batch.executors import RunReport
from ...errors import ParameterError
from ...model.limits import MAX_RUNS, check_count
from ...model.scene import check_run_horizon
from ...output import output_set
from ..execution import (
    Execution,
    check_models,
    counts,
    execute,
    interface_text,
    open_store,
    run_time_sum,
)
from . import study as tolerance
from .report import plot_histograms, write_json_report, write_markdown


@dataclass
class ToleranceOutcome:
    """What a tolerance study computed and wrote: the study, its statistics, the task counts,
    the report's path."""

    study: tolerance.ToleranceStudy
    result: dict[str, Any]
    report: RunReport
    path: Path


def tolerance_study(
    source: str | Path, runs: int | None, seed: int | None, models: Sequence[str] | None
) -> tolerance.ToleranceStudy:
    """The study of a tolerance file (or a built-in scene), with the options' overrides."""
    if runs is not None:
        check_count("--runs", runs, MAX_RUNS, tolerance.RUNS_WHAT)
    study = tolerance.load_study(source)
    if seed is not None and seed < 0:
        raise ParameterError(f"--seed {seed} must be >= 0")
    return replace(
        study,
        runs=runs or study.runs,
        seed=study.seed if seed is None else seed,
        models=check_models(models, study.models),
    )


def run_tolerance(
    source: str | Path,
    how: Execution,
    *,
    runs: int | None = None,
    seed: int | None = None,
    models: Sequence[str] | None = None,
    stop_time: float | None = None,
    interface: str = "me",
    notes: str | None = None,
) -> ToleranceOutcome:
    """Sample the tolerances of `source` (a tolerance file, or a built-in scene with the
    default tolerances), run every model for each sample and write the report into `how.out`,
    where the finished runs are kept. `runs`, `seed`, `models` override the file's
    [montecarlo] table; `notes`: markdown appended to the report."""
    study = tolerance_study(source, runs, seed, models)
    horizon = stop_time or study.scene.stop_time
    check_run_horizon(study.scene, horizon, "--stop-time" if stop_time is not None else "stop_time")
    samples = [tolerance.sample(study, k) for k in range(study.runs)]
    tolerance.check_samples(study, samples)
    out = how.directory("tolerance", study.scene.name)
    tasks = tolerance.tolerance_tasks(
        study, samples, horizon, study.scene.integrator.output_interval, interface
    )
    wall = time.perf_counter()
    store = open_store(out)
    report = execute(tasks, store, how, f"tolerance {study.scene.name}")
    result = tolerance.analyse(study, samples, tasks, store)
    result["stop_time"] = horizon
    run_info = {
        "scene": study.scene.name,
        "source": study.source,
        "runs": study.runs,
        "seed": study.seed,
        "models": list(study.models),
        "stop_time": horizon,
        "interface": interface,
        "interface_text": interface_text(interface, study.scene.integrator.rtol),
        **counts(report),
        "wall_time": time.perf_counter() - wall,
        "run_time_sum": run_time_sum(tasks, store),
    }
    with output_set(out, "tolerance"):  # the report replaces the previous one as a whole
        fig = plot_histograms(out / "tolerance_histograms.png", study, result)
        write_json_report(out / "tolerance.json", study, result, run_info)
        path = write_markdown(
            out / "tolerance.md", study, result, {**run_info, "notes": notes}, fig
        )
    return ToleranceOutcome(study, result, report, path)
