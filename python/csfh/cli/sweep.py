"""`csfh sweep` (the paper's Tables 4 and 5, quantitative) and `csfh tolerance` (Monte Carlo over
manufacturing tolerances). Both run their tasks serially, on local processes (default: all
cores) or on a Dask cluster (--dask ADDRESS), with identical results, and keep every finished
run in the output directory: an interrupted command picks up where it stopped."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from .common import CliError, add_command, add_quiet, positive_float, positive_int


def _execution_options(p: argparse.ArgumentParser, command: str) -> None:
    p.add_argument(
        "--out",
        help="output directory, where finished runs are kept and reused (default: "
        f"results/{command}/SCENE)",
    )
    p.add_argument(
        "--workers",
        type=positive_int,
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
        "--interface",
        choices=("me", "cs"),
        default="me",
        help="FMU interface of the event-driven models: me = model exchange with fmpy's "
        "CVode, events located exactly, one run at a time; cs = co-simulation, the integrator "
        "inside the FMU, the runs batched (tens of times faster)",
    )
    p.add_argument(
        "--stop-time",
        type=positive_float,
        metavar="T",
        help="horizon in s (default: the scene's stop_time)",
    )
    p.add_argument(
        "--notes",
        metavar="FILE",
        help="markdown appended to the report, e.g. a hand-written discussion (default: none)",
    )
    add_quiet(p)


def register(sub: Any) -> None:
    p = add_command(
        sub,
        "sweep",
        help="parametric analysis of the paper's Tables 4 and 5, quantitative",
        description="Move each parameter of the paper's Tables 4 and 5 by its step in both "
        "directions, run every model, measure when and how much each output departs from the "
        "nominal run, and write sweep.md, sweep.json and heat maps.",
    )
    p.add_argument(
        "scene", nargs="?", default="csfh", help="built-in scene or .toml file (default: csfh)"
    )
    p.add_argument(
        "--models",
        nargs="+",
        metavar="MODEL",
        help="models (default: LN_spheres LN_cylinders LN_ESDU Moreau)",
    )
    p.add_argument(
        "--params",
        nargs="+",
        metavar="P",
        help="parameters: R1 m1 I1 E12 cr fd fa rho b h beta Eh (default: all 12), "
        "bL (b with the contact length), or 'all'",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="reduced sweep: R1, m1, h over 0.2 s (unless --params/--stop-time)",
    )
    _execution_options(p, "sweep")
    p.set_defaults(func=cmd_sweep)

    p = add_command(
        sub,
        "tolerance",
        help="Monte Carlo over manufacturing tolerances",
        description="Sample the [tolerance] table of a tolerance file, run every model for each "
        "sample, and write histograms of the first-contact time, peak F_N and peak F_T.",
    )
    p.add_argument(
        "study",
        metavar="SCENE_OR_FILE",
        help="tolerance file (.toml with [tolerance]), tolerance_csfh, or a built-in "
        "scene (then with the tolerances of tolerance_csfh)",
    )
    p.add_argument(
        "--runs",
        type=positive_int,
        metavar="N",
        help="runs per model (default: the file's [montecarlo] runs, else 200)",
    )
    p.add_argument(
        "--seed",
        type=int,
        metavar="S",
        help="random seed >= 0 (default: the file's [montecarlo] seed, else 1)",
    )
    p.add_argument(
        "--models",
        nargs="+",
        metavar="MODEL",
        help="models (default: the file's [montecarlo] models, else LN_spheres LN_cylinders "
        "LN_ESDU Moreau)",
    )
    _execution_options(p, "tolerance")
    p.set_defaults(func=cmd_tolerance)


def _check_models(models: list[str] | None, default: tuple[str, ...]) -> tuple[str, ...]:
    from ..model import model_info

    if not models:
        return default
    for m in models:
        if m not in model_info.MODELS:
            raise CliError(f"unknown model {m!r} (known: {', '.join(model_info.MODELS)})")
    return tuple(dict.fromkeys(models))


def _interface_text(interface: str, rtol: float) -> str:
    if interface == "cs":
        return (
            f"co-simulation (the integrator inside the FMU; the runs batched in the FMU's own "
            f"binary by the batch master), rtol {rtol:g}"
        )
    return f"model exchange with fmpy's CVode (BDF, events by root finding), rtol {rtol:g}"


def _run(tasks: list[Any], out: Path, args: argparse.Namespace, label: str) -> Any:
    from ..batch.executors import run_tasks
    from ..batch.store import ResultStore

    store = ResultStore(out)
    for problem in store.problems[:10]:
        print(f"csfh: warning: {problem}", file=sys.stderr)
    if len(store.problems) > 10:
        print(
            f"csfh: warning: {len(store.problems) - 10} more records skipped "
            f"(all of them are in {out / 'tasks.rejected.jsonl'})",
            file=sys.stderr,
        )
    try:
        report = run_tasks(
            tasks,
            store,
            workers=args.workers,
            dask_address=args.dask,
            label=label,
            quiet=args.quiet,
        )
    except KeyboardInterrupt:
        print(
            f"csfh: {len(store)} finished runs are kept in {out}; run the same command again "
            "to resume",
            file=sys.stderr,
        )
        raise
    except RuntimeError as exc:
        raise CliError(str(exc)) from None
    return store, report


def _check_horizon(scene: Any, stop_time: float, option: bool) -> None:
    """The scene's limits (csfh.model.scene) on a horizon that --stop-time may have changed."""
    from ..errors import SceneError
    from ..model.scene import check_horizon

    try:
        check_horizon(
            stop_time,
            scene.integrator.output_interval,
            scene.integrator.moreau_h,
            stop_key="--stop-time" if option else "stop_time",
        )
    except SceneError as exc:
        raise SceneError(f"{scene.source or scene.name}: {exc}") from None


def _run_time_sum(tasks: list[Any], store: Any) -> float:
    """Wall time of the runs themselves, summed over the tasks (whenever they were computed)."""
    keys = {t.key for t in tasks}
    return float(sum(store.records[k].get("wall_time", 0.0) for k in keys))


def _notes(args: argparse.Namespace) -> str | None:
    if not args.notes:
        return None
    path = Path(args.notes)
    if not path.is_file():
        raise CliError(f"--notes {path}: no such file")
    return path.read_text(encoding="utf-8")


def cmd_sweep(args: argparse.Namespace) -> int:
    from ..model import model_info
    from ..model.scene import load_scene
    from ..output import output_set
    from ..studies.sweep import analysis, parameters, spec
    from ..studies.sweep.figures import plot_departure, plot_examples, plot_levels
    from ..studies.sweep.report import write_json_report, write_markdown

    scene = load_scene(args.scene)
    models = _check_models(args.models, model_info.PAPER_MODELS)
    if args.params:
        keys = [k for p in args.params for k in (parameters.ALL_PARAMETERS if p == "all" else [p])]
        for k in keys:
            if k not in parameters.ALL_PARAMETERS:
                raise CliError(
                    f"unknown parameter {k!r} (known: {', '.join(parameters.ALL_PARAMETERS)}, all)"
                )
        params = tuple(dict.fromkeys(keys))
    else:
        params = (
            parameters.QUICK_PARAMETERS
            if args.quick
            else tuple(p.key for p in parameters.PARAMETERS)
        )
    stop_time = args.stop_time or (0.2 if args.quick else scene.stop_time)
    _check_horizon(scene, stop_time, args.stop_time is not None)
    dt = scene.integrator.output_interval
    if stop_time / dt < 10:
        raise CliError(f"horizon {stop_time:g} s is shorter than 10 output intervals ({dt:g} s)")
    sweep_spec = spec.SweepSpec(
        scene=scene,
        models=models,
        parameters=params,
        stop_time=stop_time,
        output_interval=dt,
        interface=args.interface,
    )
    notes = _notes(args)
    out = Path(args.out) if args.out else Path("results") / "sweep" / scene.name
    tasks = spec.sweep_tasks(sweep_spec)
    wall = time.perf_counter()
    store, report = _run(tasks, out, args, f"sweep {scene.name}")
    settings = analysis.MeasureSettings()
    result = analysis.analyse(sweep_spec, tasks, store, settings)
    n_moreau = sum(t.model == "Moreau" for t in tasks)
    run_info = {
        "scene": scene.name,
        "description": scene.description,
        "preset": scene.preset,
        "q0": list(scene.q0),
        "stop_time": stop_time,
        "output_interval": dt,
        "interface": args.interface,
        "interface_text": _interface_text(args.interface, scene.integrator.rtol),
        "moreau_h": scene.integrator.moreau_h,
        "stick_rule": scene.stick_rule,
        "moreau_batch": f"{n_moreau} runs in batches of the C core",
        "tasks": report.total,
        "computed": report.computed,
        "reused": report.reused,
        "executor": report.executor,
        "wall_time": time.perf_counter() - wall,
        "run_time_sum": _run_time_sum(tasks, store),
        "notes": notes,
    }
    with output_set(out, "sweep"):  # the report replaces the previous one as a whole
        figures = [
            plot_levels(out / "sweep_levels.png", result),
            plot_departure(out / "sweep_departure.png", result),
        ]
        example = plot_examples(out / "sweep_examples.png", sweep_spec, tasks, store, result)
        if example is not None:
            figures.append(example)
        write_json_report(
            out / "sweep.json", result, {k: v for k, v in run_info.items() if k != "notes"}
        )
        write_markdown(out / "sweep.md", result, run_info, figures)
    if not args.quiet:
        for group, c in result["comparison"].items():
            print(
                f"  {group:<13} agrees with the paper in {c['agree']}/{c['total']} cells "
                f"({c['within_one']} within one level; ours higher {c['higher']}, lower "
                f"{c['lower']})"
            )
    print(
        f"sweep: {report.total} runs ({report.computed} computed, {report.reused} reused, "
        f"{report.executor}) -> {out / 'sweep.md'}"
    )
    return 0


def cmd_tolerance(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from ..output import output_set
    from ..studies.tolerance import study as tolerance
    from ..studies.tolerance.report import plot_histograms, write_json_report, write_markdown

    study = tolerance.load_study(args.study)
    if args.seed is not None and args.seed < 0:
        raise CliError(f"--seed {args.seed} must be >= 0")
    study = replace(
        study,
        runs=args.runs or study.runs,
        seed=study.seed if args.seed is None else args.seed,
        models=_check_models(args.models, study.models),
    )
    stop_time = args.stop_time or study.scene.stop_time
    _check_horizon(study.scene, stop_time, args.stop_time is not None)
    samples = [tolerance.sample(study, k) for k in range(study.runs)]
    tolerance.check_samples(study, samples)
    notes = _notes(args)
    out = Path(args.out) if args.out else Path("results") / "tolerance" / study.scene.name
    tasks = tolerance.tolerance_tasks(
        study, samples, stop_time, study.scene.integrator.output_interval, args.interface
    )
    wall = time.perf_counter()
    store, report = _run(tasks, out, args, f"tolerance {study.scene.name}")
    result = tolerance.analyse(study, samples, tasks, store)
    result["stop_time"] = stop_time
    run_info = {
        "scene": study.scene.name,
        "source": study.source,
        "runs": study.runs,
        "seed": study.seed,
        "models": list(study.models),
        "stop_time": stop_time,
        "interface": args.interface,
        "interface_text": _interface_text(args.interface, study.scene.integrator.rtol),
        "tasks": report.total,
        "computed": report.computed,
        "reused": report.reused,
        "executor": report.executor,
        "wall_time": time.perf_counter() - wall,
        "run_time_sum": _run_time_sum(tasks, store),
    }
    with output_set(out, "tolerance"):  # the report replaces the previous one as a whole
        fig = plot_histograms(out / "tolerance_histograms.png", study, result)
        write_json_report(out / "tolerance.json", study, result, run_info)
        write_markdown(out / "tolerance.md", study, result, {**run_info, "notes": notes}, fig)
    if not args.quiet:
        for model, r in result["models"].items():
            st = r["stats"]
            fc = st["first_contact"]
            print(
                f"  {model:<13} first contact {1e3 * fc['mean']:.3f} ± {1e3 * fc['std']:.3f} ms,"
                f" peak F_N {st['peak_F_N']['mean']:.4g} ± {st['peak_F_N']['std']:.3g} N"
                if fc["n"]
                else f"  {model:<13} no contact"
            )
    print(
        f"tolerance: {report.total} runs ({report.computed} computed, {report.reused} reused, "
        f"{report.executor}) -> {out / 'tolerance.md'}"
    )
    return 0
