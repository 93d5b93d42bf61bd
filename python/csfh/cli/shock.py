"""`csfh shock SCENE`: a half-sine shock pulse (by peak and duration, or a standard condition by
name) in one direction or a sweep of directions, every event-driven model; the peak flexure
stress and contact pressure against their allowables, pass or fail per direction; with
--tolerance, a Monte Carlo over tolerances that gives the probability of exceeding them."""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import Any

from .common import SCENE_HELP, CliError, add_command, add_quiet

DEFAULT_DIRECTIONS = 24
STEP_FACTOR = 10  # the default communication step, in output intervals


def register(sub: Any) -> None:
    p = add_command(
        sub,
        "shock",
        help="shock survivability: peak stresses under a half-sine pulse, Monte Carlo",
        description="Shake the frame (body 2) with a half-sine acceleration pulse, by peak and "
        "duration or a standard condition by name (JESD22-B104-A..G, MIL-STD-883-2002-A..G; "
        "--list-conditions), in one direction or a sweep of directions over 360 degrees, with "
        "every event-driven model; write shock.md (peak flexure stress and contact pressure, "
        "margins, pass or fail per direction), shock.json and figures. With --tolerance FILE, "
        "sample the file's tolerances and give the probability of exceeding each allowable, "
        "with its Clopper-Pearson interval. Body 1 starts at the scene's configuration at rest. "
        "The runs are batched in the FMU's own binary and kept in the output directory (an "
        "interrupted command resumes).",
    )
    p.add_argument("scene", nargs="?", help=SCENE_HELP)
    p.add_argument(
        "--condition",
        metavar="NAME",
        help="standard condition, e.g. JESD22-B104-B (default: JESD22-B104-B, 1500 g, 0.5 ms, "
        "unless --peak and --duration are given)",
    )
    p.add_argument(
        "--peak",
        metavar="G",
        help="peak acceleration in g (9.80665 m/s2), with --duration (default: the condition's)",
    )
    p.add_argument(
        "--duration",
        metavar="T",
        help="pulse duration in s, with --peak (default: the condition's)",
    )
    p.add_argument("--start", metavar="T", default="0", help="time at which the pulse starts, s")
    p.add_argument(
        "--direction",
        metavar="DEG",
        help="one direction of the frame's acceleration, degrees counter-clockwise from the "
        "global X axis (90: upward) (default: a sweep, see --directions)",
    )
    p.add_argument(
        "--directions",
        metavar="N",
        help="number of directions evenly over 360 degrees, from 0 (default: "
        f"{DEFAULT_DIRECTIONS})",
    )
    p.add_argument(
        "--models",
        nargs="+",
        metavar="MODEL",
        help="event-driven models (default: all, LN_spheres LN_cylinders LN_ESDU HuntCrossley "
        "Flores)",
    )
    p.add_argument("--stop-time", metavar="T", help="horizon in s (default: the scene's stop_time)")
    p.add_argument(
        "--step",
        metavar="H",
        help="communication step of the runs in s: the peaks inside each step are located on "
        "the integrator's interpolant whatever it is (default: 10 x the scene's "
        "output_interval; the figure of stresses over time is drawn on the output_interval)",
    )
    p.add_argument(
        "--tolerance",
        metavar="FILE",
        help="Monte Carlo over the [tolerance] table of FILE (a tolerance file or a built-in "
        "one such as tolerance_csfh, tolerance_mems) at each model's worst direction (default: "
        "no Monte Carlo)",
    )
    p.add_argument(
        "--runs",
        metavar="N",
        help="Monte Carlo samples per model (default: the file's [montecarlo] runs, else 200)",
    )
    p.add_argument("--seed", metavar="S", help="random seed >= 0 (default: the file's, else 1)")
    p.add_argument(
        "--out",
        help="output directory, where finished runs are kept (default: results/shock/SCENE)",
    )
    p.add_argument(
        "--workers",
        metavar="N",
        help="local processes (default: all cores; 1 = serial in this process)",
    )
    p.add_argument(
        "--dask",
        metavar="ADDRESS",
        help="run on an existing Dask distributed scheduler, e.g. tcp://host:8786 (default: "
        "local processes, see --workers)",
    )
    p.add_argument(
        "--list-conditions", action="store_true", help="print the standard conditions and exit"
    )
    add_quiet(p)
    p.set_defaults(func=cmd_shock)


def _number(option: str, text: str | None, *, positive: bool = False) -> float | None:
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        raise CliError(f"{option} = {text!r} is not a number") from None
    if not math.isfinite(value) or (positive and not value > 0):
        raise CliError(
            f"{option} = {text!r} must be a finite number" + (" > 0" if positive else "")
        )
    return value


def _count(option: str, text: str | None, minimum: int) -> int | None:
    if text is None:
        return None
    try:
        value = int(text)
    except ValueError:
        raise CliError(f"{option} = {text!r} is not an integer") from None
    if value < minimum:
        raise CliError(f"{option} = {value} must be >= {minimum}")
    return value


def cmd_shock(args: argparse.Namespace) -> int:
    from ..studies.shock import conditions

    if args.list_conditions:
        for c in conditions.CONDITIONS.values():
            print(f"{c.name:<20} {c.peak_g:>7g} g {c.duration * 1e3:>5g} ms   {c.source}")
        return 0
    if args.scene is None:
        raise CliError("shock needs a SCENE (a built-in scene or a .toml file)")
    # every number first, so that a typo costs no run
    peak = _number("--peak", args.peak, positive=True)
    duration = _number("--duration", args.duration)
    if duration is not None and not duration > 0:
        raise CliError(f"--duration = {args.duration!r} s must be > 0")
    start = _number("--start", args.start)
    assert start is not None
    if start < 0:
        raise CliError(f"--start = {args.start!r} s must be >= 0")
    direction = _number("--direction", args.direction)
    n_dirs = _count("--directions", args.directions, 1)
    stop = _number("--stop-time", args.stop_time, positive=True)
    step = _number("--step", args.step, positive=True)
    runs = _count("--runs", args.runs, 1)
    seed = _count("--seed", args.seed, 0)
    workers = _count("--workers", args.workers, 1)
    if args.condition is not None and (peak is not None or duration is not None):
        raise CliError("give either --condition or --peak and --duration, not both")
    if (peak is None) != (duration is None):
        raise CliError("--peak and --duration go together")
    if direction is not None and n_dirs is not None:
        raise CliError("give either --direction or --directions, not both")
    if args.tolerance is None and (runs is not None or seed is not None):
        raise CliError("--runs and --seed need --tolerance FILE")
    try:
        if peak is not None and duration is not None:
            pulse = conditions.pulse(peak, duration)
        else:
            pulse = conditions.condition(args.condition or conditions.DEFAULT_CONDITION)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    return _run(args, pulse, start, direction, n_dirs, stop, step, runs, seed, workers)


def _run(
    args: argparse.Namespace,
    pulse: Any,
    start: float,
    direction: float | None,
    n_dirs: int | None,
    stop: float | None,
    step: float | None,
    runs: int | None,
    seed: int | None,
    workers: int | None,
) -> int:
    from dataclasses import replace

    from ..batch.executors import run_tasks
    from ..batch.store import ResultStore
    from ..model import model_info
    from ..model._csfh_variables import MAX_COMMUNICATION_POINTS
    from ..model.scene import load_scene
    from ..output import output_set
    from ..studies.shock import report, study
    from ..studies.tolerance import study as tolerance

    scene = study.at_rest(load_scene(args.scene))
    try:
        models = study.check_models(args.models or model_info.LAWS)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    stop_time = stop or scene.stop_time
    if not start < stop_time:
        raise CliError(f"--start = {start:g} s is not before the horizon {stop_time:g} s")
    spec = study.ShockSpec(
        scene=scene,
        pulse=pulse,
        directions=(direction % 360.0,)
        if direction is not None
        else study.directions(n_dirs or DEFAULT_DIRECTIONS),
        models=models,
        start=start,
        stop_time=stop_time,
        step=step or STEP_FACTOR * scene.integrator.output_interval,
    )
    if spec.stop_time / spec.step > MAX_COMMUNICATION_POINTS:
        raise CliError(
            f"{spec.stop_time:g} s in steps of {spec.step:g} s are more than "
            f"{MAX_COMMUNICATION_POINTS:g} communication points: give a larger --step"
        )
    tol = None
    if args.tolerance is not None:
        tol = tolerance.study_for_scene(scene, args.tolerance)
        tol = replace(tol, runs=runs or tol.runs, seed=tol.seed if seed is None else seed)
    out = Path(args.out) if args.out else Path("results") / "shock" / spec.scene.name
    store = ResultStore(out)
    wall = time.perf_counter()

    def execute(tasks: list[Any], label: str) -> Any:
        try:
            return run_tasks(
                tasks,
                store,
                workers=workers,
                dask_address=args.dask,
                label=label,
                quiet=args.quiet,
            )
        except KeyboardInterrupt:
            print(
                f"csfh: {len(store)} finished runs are kept in {out}; run the same command "
                "again to resume",
                file=sys.stderr,
            )
            raise
        except RuntimeError as exc:
            raise CliError(str(exc)) from None

    tasks = study.direction_tasks(spec)
    rep = execute(tasks, f"shock {spec.scene.name}")
    result = study.analyse_directions(spec, tasks, store)
    counts = {"tasks": rep.total, "computed": rep.computed, "reused": rep.reused}
    executor = rep.executor
    mc = None
    run_info: dict[str, Any] = {}
    if tol is not None:
        samples = [tolerance.sample(tol, k) for k in range(tol.runs)]
        tolerance.check_samples(tol, samples)
        worst = {m: result["models"][m]["worst_direction"] for m in spec.models}
        mc_tasks = study.montecarlo_tasks(spec, samples, tol.nominal, worst)
        mc_rep = execute(mc_tasks, f"shock Monte Carlo {spec.scene.name}")
        mc = study.analyse_montecarlo(spec, samples, mc_tasks, store)
        variables = model_info.variables()
        units = {k: variables[k].unit or "" for k in tol.tolerances}
        for key in counts:
            counts[key] += getattr(mc_rep, key if key != "tasks" else "total")
        executor = mc_rep.executor
        run_info["tolerance"] = {
            "source": tol.source,
            "runs": tol.runs,
            "seed": tol.seed,
            "distributions": {k: d.describe(units.get(k, "")) for k, d in tol.tolerances.items()},
            "nominal": tol.nominal,
            "units": units,
        }
    series = {
        (m, key): study.time_series(
            spec, m, result["models"][m][which], min(spec.step, scene.integrator.output_interval)
        )
        for m in spec.models
        for key, which in (
            ("stress", "worst_flexure_stress_direction"),
            ("pressure", "worst_contact_pressure_direction"),
        )
    }
    run_info.update(counts)
    run_info["executor"] = executor
    run_info["wall_time"] = time.perf_counter() - wall
    # the report replaces the previous one as a whole (a run without --tolerance leaves no stale
    # Monte Carlo figure); the result store is not part of it
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
        report.write_markdown(out / "shock.md", spec, result, run_info, figures, mc)
    if not args.quiet:
        for m, r in result["models"].items():
            print(
                f"  {m:<13} worst {r['worst_direction']:g}°: flexure margin "
                f"{r['min_flexure_margin']:+.3f}, contact margin {r['min_contact_margin']:+.3f}"
                f" -> {'pass' if r['passed'] else 'FAIL'}"
            )
        if mc is not None:
            for m, r in mc["models"].items():
                p = r["probability"]["either"]
                print(
                    f"  {m:<13} P(exceeding an allowable) = {p['p']:.3g} "
                    f"[{p['low']:.3g}, {p['high']:.3g}] ({p['runs']} samples)"
                )
    print(
        f"shock: {'PASS' if result['passed'] else 'FAIL'}, {counts['tasks']} runs "
        f"({counts['computed']} computed, {counts['reused']} reused, {executor}) -> "
        f"{out / 'shock.md'}"
    )
    return 0 if result["passed"] else 1
