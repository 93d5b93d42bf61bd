"""The shock study as one call (`run_shock`): the spec from the request, the runs over directions
(and the Monte Carlo at each model's worst direction) into the output directory's result store,
the verdicts, and the report (shock.md, shock.json, figures) written as one output set."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from ...batch.store import ResultStore
from ...errors import ParameterError
from ...model import model_info
from ...model.limits import MAX_DIRECTIONS, MAX_RUNS, check_communication_points, check_count
from ...model.scene import Scene, load_scene
from ...output import output_set
from ..execution import Execution, counts, execute, open_store
from ..tolerance import study as tolerance
from . import DEFAULT_DIRECTIONS, STEP_FACTOR, report, study
from .conditions import Pulse


@dataclass(frozen=True)
class ShockRequest:
    """What to shake: a scene, the pulse and its start (s), one direction (degrees) or a number
    of directions over 360 degrees, the models (None: every event-driven one), the horizon and
    the communication step (None: the scene's stop time, STEP_FACTOR output intervals), and a
    tolerance file for the Monte Carlo with its runs and seed (None: the file's)."""

    scene: Scene | str | Path
    pulse: Pulse
    start: float = 0.0
    direction: float | None = None
    directions: int | None = None
    models: tuple[str, ...] | None = None
    stop_time: float | None = None
    step: float | None = None
    tolerance: str | Path | None = None
    runs: int | None = None
    seed: int | None = None


@dataclass
class ShockOutcome:
    """What a shock study computed and wrote."""

    spec: study.ShockSpec
    result: dict[str, Any]
    montecarlo: dict[str, Any] | None
    run_info: dict[str, Any]
    path: Path

    @property
    def passed(self) -> bool:
        return bool(self.result["passed"])


def shock_spec(request: ShockRequest) -> study.ShockSpec:
    """The study's spec, every option checked before anything runs."""
    r = request
    if r.directions is not None:
        check_count("--directions", r.directions, MAX_DIRECTIONS, "directions of a shock sweep")
    if r.runs is not None:
        check_count("--runs", r.runs, MAX_RUNS, tolerance.RUNS_WHAT)
    scene = r.scene if isinstance(r.scene, Scene) else load_scene(r.scene)
    scene = study.at_rest(scene)
    models = study.check_models(r.models or model_info.LAWS)
    stop_time = r.stop_time or scene.stop_time
    if not r.start < stop_time:
        raise ParameterError(f"--start = {r.start:g} s is not before the horizon {stop_time:g} s")
    if r.direction is not None:
        directions: tuple[float, ...] = (r.direction % 360.0,)
    else:
        directions = study.directions(r.directions or DEFAULT_DIRECTIONS)
    spec = study.ShockSpec(
        scene=scene,
        pulse=r.pulse,
        directions=directions,
        models=models,
        start=r.start,
        stop_time=stop_time,
        step=r.step or STEP_FACTOR * scene.integrator.output_interval,
    )
    check_communication_points(spec.stop_time, spec.step, "--step")
    return spec


def _tolerance_study(spec: study.ShockSpec, r: ShockRequest) -> tolerance.ToleranceStudy | None:
    if r.tolerance is None:
        return None
    tol = tolerance.study_for_scene(spec.scene, r.tolerance)
    return replace(tol, runs=r.runs or tol.runs, seed=tol.seed if r.seed is None else r.seed)


def _montecarlo(
    spec: study.ShockSpec,
    tol: tolerance.ToleranceStudy,
    result: dict[str, Any],
    store: ResultStore,
    how: Execution,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The Monte Carlo at each model's worst direction: its analysis and its part of the run's
    information."""
    samples = [tolerance.sample(tol, k) for k in range(tol.runs)]
    tolerance.check_samples(tol, samples)
    worst = {m: result["models"][m]["worst_direction"] for m in spec.models}
    tasks = study.montecarlo_tasks(spec, samples, tol.nominal, worst)
    rep = execute(tasks, store, how, f"shock Monte Carlo {spec.scene.name}")
    mc = study.analyse_montecarlo(spec, samples, tasks, store)
    variables = model_info.variables()
    units = {k: variables[k].unit or "" for k in tol.tolerances}
    info = {
        "tolerance": {
            "source": tol.source,
            "runs": tol.runs,
            "seed": tol.seed,
            "distributions": {k: d.describe(units.get(k, "")) for k, d in tol.tolerances.items()},
            "nominal": tol.nominal,
            "units": units,
        },
        **counts(rep),
    }
    return mc, info


def _series(spec: study.ShockSpec, result: dict[str, Any]) -> dict[tuple[str, str], Any]:
    """The runs of the time figure: each model in its worst directions, on the finer grid."""
    step = min(spec.step, spec.scene.integrator.output_interval)
    return {
        (m, key): study.time_series(spec, m, result["models"][m][which], step)
        for m in spec.models
        for key, which in (
            ("stress", "worst_flexure_stress_direction"),
            ("pressure", "worst_contact_pressure_direction"),
        )
    }


def _write_report(
    out: Path,
    spec: study.ShockSpec,
    result: dict[str, Any],
    mc: dict[str, Any] | None,
    run_info: dict[str, Any],
) -> Path:
    """The report replaces the previous one as a whole (a run without a Monte Carlo leaves no
    stale Monte Carlo figure); the result store is not part of it."""
    series = _series(spec, result)
    with output_set(out, "shock"):
        figures = [
            report.plot_time(out / "shock_time.png", spec, series, result),
            report.plot_polar(out / "shock_polar.png", spec, result),
        ]
        if mc is not None:
            figures.append(
                report.plot_montecarlo(out / "shock_montecarlo.png", spec, mc, result["allowables"])
            )
        report.write_json_report(out / "shock.json", spec, result, run_info, mc)
        return report.write_markdown(out / "shock.md", spec, result, run_info, figures, mc)


def run_shock(request: ShockRequest, how: Execution) -> ShockOutcome:
    """Run the shock study of `request` and write its report into `how.out` (default
    results/shock/SCENE), where the finished runs are kept (an interrupted study resumes)."""
    spec = shock_spec(request)
    tol = _tolerance_study(spec, request)
    out = how.directory("shock", spec.scene.name)
    store = open_store(out)
    wall = time.perf_counter()
    tasks = study.direction_tasks(spec)
    total = counts(execute(tasks, store, how, f"shock {spec.scene.name}"))
    result = study.analyse_directions(spec, tasks, store)
    mc = None
    run_info: dict[str, Any] = {}
    if tol is not None:
        mc, info = _montecarlo(spec, tol, result, store, how)
        run_info["tolerance"] = info["tolerance"]
        for key in ("tasks", "computed", "reused"):
            total[key] += info[key]
        total["executor"] = info["executor"]  # the last part's
    run_info.update(total)
    run_info["wall_time"] = time.perf_counter() - wall
    path = _write_report(out, spec, result, mc, run_info)
    return ShockOutcome(spec, result, mc, run_info, path)
