"""`csfh sweep` (the paper's Tables 4 and 5, quantitative) and `csfh tolerance` (Monte Carlo over
manufacturing tolerances). Both run their tasks serially, on local processes (default: all
cores) or on a Dask cluster (--dask ADDRESS), with identical results, and keep every finished
run in the output directory: an interrupted command picks up where it stopped."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from .common import (
    CliError,
    add_command,
    add_execution_options,
    add_quiet,
    execution,
    positive_float,
    positive_int,
)


def _batch_options(p: argparse.ArgumentParser, command: str) -> None:
    """How the runs of a sweep or tolerance study are made: where, on what, through which
    interface."""
    add_execution_options(p, command)
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
    _batch_options(p, "sweep")
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
    _batch_options(p, "tolerance")
    p.set_defaults(func=cmd_tolerance)


def _notes(args: argparse.Namespace) -> str | None:
    """The text of --notes FILE (read before anything runs)."""
    if not args.notes:
        return None
    path = Path(args.notes)
    if not path.is_file():
        raise CliError(f"--notes {path}: no such file")
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise CliError(f"--notes {path}: not UTF-8 text") from None
    except OSError as exc:
        raise CliError(f"--notes {path}: cannot be read ({exc.strerror or exc})") from None


def _counts(report: Any) -> str:
    return (
        f"{report.total} runs ({report.computed} computed, {report.reused} reused, "
        f"{report.executor})"
    )


def cmd_sweep(args: argparse.Namespace) -> int:
    from ..model.scene import load_scene
    from ..studies.sweep.run import run_sweep

    scene = load_scene(args.scene)
    outcome = run_sweep(
        scene,
        execution(args),
        models=args.models,
        params=args.params,
        quick=args.quick,
        stop_time=args.stop_time,
        interface=args.interface,
        notes=_notes(args),
    )
    if not args.quiet:
        for group, c in outcome.result["comparison"].items():
            print(
                f"  {group:<13} agrees with the paper in {c['agree']}/{c['total']} cells "
                f"({c['within_one']} within one level; ours higher {c['higher']}, lower "
                f"{c['lower']})"
            )
    print(f"sweep: {_counts(outcome.report)} -> {outcome.path}")
    return 0


def cmd_tolerance(args: argparse.Namespace) -> int:
    from ..studies.tolerance.run import run_tolerance
    from ..trajectory import force_label

    notes = _notes(args)
    outcome = run_tolerance(
        args.study,
        execution(args),
        runs=args.runs,
        seed=args.seed,
        models=args.models,
        stop_time=args.stop_time,
        interface=args.interface,
        notes=notes,
    )
    if not args.quiet:
        for model, r in outcome.result["models"].items():
            st = r["stats"]
            fc = st["first_contact"]
            print(
                f"  {model:<13} first contact {1e3 * fc['mean']:.3f} ± {1e3 * fc['std']:.3f} ms,"
                f" peak {force_label(model)} {st['peak_F_N']['mean']:.4g} ± "
                f"{st['peak_F_N']['std']:.3g} N"
                if fc["n"]
                else f"  {model:<13} no contact"
            )
    print(f"tolerance: {_counts(outcome.report)} -> {outcome.path}")
    return 0
