"""The sweep as one call (`run_sweep`): the spec from the options, the tasks run into the output
directory's result store, the analysis, and the report (sweep.md, sweep.json, heat maps) written
as one output set."""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...batch.executors import RunReport
from ...errors import ParameterError
from ...model import model_info
from ...model.scene import Scene, check_run_horizon
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
from . import analysis, parameters, spec
from .figures import plot_departure, plot_examples, plot_levels
from .report import write_json_report, write_markdown

QUICK_STOP_TIME = 0.2
"""s: the horizon of `--quick` (unless a stop time is given)."""
MIN_INTERVALS = 10
"""The shortest horizon, in output intervals."""


@dataclass
class SweepOutcome:
    """What a sweep computed and wrote: the analysis, the task counts, the report's path."""

    result: dict[str, Any]
    report: RunReport
    path: Path


def sweep_parameters(params: Sequence[str] | None, quick: bool) -> tuple[str, ...]:
    """The parameters of a sweep: the given ones ("all": every one), else the quick or the full
    set; ParameterError naming an unknown one."""
    if not params:
        if quick:
            return parameters.QUICK_PARAMETERS
        return tuple(p.key for p in parameters.PARAMETERS)
    keys = [k for p in params for k in (parameters.ALL_PARAMETERS if p == "all" else [p])]
    for k in keys:
        if k not in parameters.ALL_PARAMETERS:
            raise ParameterError(
                f"unknown parameter {k!r} (known: {', '.join(parameters.ALL_PARAMETERS)}, all)"
            )
    return tuple(dict.fromkeys(keys))


def sweep_spec(
    scene: Scene,
    models: Sequence[str] | None,
    params: Sequence[str] | None,
    quick: bool,
    stop_time: float | None,
    interface: str,
) -> spec.SweepSpec:
    """The sweep's spec, every option checked before anything runs."""
    models_ = check_models(models, model_info.PAPER_MODELS)
    keys = sweep_parameters(params, quick)
    horizon = stop_time or (QUICK_STOP_TIME if quick else scene.stop_time)
    check_run_horizon(scene, horizon, "--stop-time" if stop_time is not None else "stop_time")
    dt = scene.integrator.output_interval
    if horizon / dt < MIN_INTERVALS:
        raise ParameterError(
            f"horizon {horizon:g} s is shorter than {MIN_INTERVALS} output intervals ({dt:g} s)"
        )
    return spec.SweepSpec(
        scene=scene,
        models=models_,
        parameters=keys,
        stop_time=horizon,
        output_interval=dt,
        interface=interface,
    )


def _run_info(
    sweep: spec.SweepSpec,
    tasks: list[Any],
    store: Any,
    report: RunReport,
    wall: float,
    notes: str | None,
) -> dict[str, Any]:
    scene = sweep.scene
    n_moreau = sum(t.model == "Moreau" for t in tasks)
    return {
        "scene": scene.name,
        "description": scene.description,
        "preset": scene.preset,
        "q0": list(scene.q0),
        "stop_time": sweep.stop_time,
        "output_interval": sweep.output_interval,
        "interface": sweep.interface,
        "interface_text": interface_text(sweep.interface, scene.integrator.rtol),
        "moreau_h": scene.integrator.moreau_h,
        "stick_rule": scene.stick_rule,
        "moreau_batch": f"{n_moreau} runs in batches of the C core",
        **counts(report),
        "wall_time": time.perf_counter() - wall,
        "run_time_sum": run_time_sum(tasks, store),
        "notes": notes,
    }


def run_sweep(
    scene: Scene,
    how: Execution,
    *,
    models: Sequence[str] | None = None,
    params: Sequence[str] | None = None,
    quick: bool = False,
    stop_time: float | None = None,
    interface: str = "me",
    notes: str | None = None,
) -> SweepOutcome:
    """Run the sweep of `scene` (every model, every parameter in both directions; `quick`: R1,
    m1, h over 0.2 s) and write its report into `how.out`, where the finished runs are kept (a
    repeated sweep reuses them). `notes`: markdown appended to the report."""
    sweep = sweep_spec(scene, models, params, quick, stop_time, interface)
    out = how.directory("sweep", scene.name)
    tasks = spec.sweep_tasks(sweep)
    wall = time.perf_counter()
    store = open_store(out)
    report = execute(tasks, store, how, f"sweep {scene.name}")
    result = analysis.analyse(sweep, tasks, store, analysis.MeasureSettings())
    run_info = _run_info(sweep, tasks, store, report, wall, notes)
    with output_set(out, "sweep"):  # the report replaces the previous one as a whole
        figures = [
            plot_levels(out / "sweep_levels.png", result),
            plot_departure(out / "sweep_departure.png", result),
        ]
        example = plot_examples(out / "sweep_examples.png", sweep, tasks, store, result)
        if example is not None:
            figures.append(example)
        write_json_report(
            out / "sweep.json", result, {k: v for k, v in run_info.items() if k != "notes"}
        )
        path = write_markdown(out / "sweep.md", result, run_info, figures)
    return SweepOutcome(result, report, path)
