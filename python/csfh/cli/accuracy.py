"""`csfh accuracy` and `csfh stress`."""

from __future__ import annotations

import argparse
from pathlib import Path


def _cmd_accuracy(args: argparse.Namespace) -> int:
    from ..model.scene import load_scene
    from ..studies.accuracy.report import write_report
    from ..studies.accuracy.study import DEFAULT_SETTINGS, QUICK_SETTINGS, run_study

    scene = load_scene(args.scene)
    out = Path(args.out) if args.out else Path("results") / scene.name / "accuracy"
    if args.stop_time is not None and not args.stop_time > 0:
        raise ValueError(f"--stop-time = {args.stop_time} must be > 0")
    if args.repeats < 1:
        raise ValueError(f"--repeats = {args.repeats} must be >= 1")
    settings = QUICK_SETTINGS if args.quick else DEFAULT_SETTINGS
    study = run_study(
        scene,
        stop_time=args.stop_time,
        settings=settings,
        repeats=args.repeats,
        quiet=args.quiet,
    )
    write_report(study, out)
    print(f"wrote {out / 'report.md'}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("accuracy", help="error against run time of every integrator (report.md)")
    p.add_argument("scene", help="built-in scene or a .toml file")
    p.add_argument("--out", help="output directory (default results/SCENE/accuracy)")
    p.add_argument(
        "--stop-time", type=float, help="horizon, s (default: through the third contact + 20 %%)"
    )
    p.add_argument("--repeats", type=int, default=3, help="timing repeats (median), default 3")
    p.add_argument("--quick", action="store_true", help="fewer settings (a smoke run)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_accuracy)
    register_stress(sub)


def _cmd_stress(args: argparse.Namespace) -> int:
    from ..studies.stress.cases import select_cases
    from ..studies.stress.report import write_report
    from ..studies.stress.suite import run_suite

    out = Path(args.out) if args.out else Path("results") / "stress"
    cases = select_cases(quick=args.quick, only=args.only)
    if not cases:
        raise ValueError(f"--only = {args.only!r} matches no case")
    runs = run_suite(cases, quiet=args.quiet)
    write_report(cases, runs, out)
    counts = {v: sum(r.verdict == v for r in runs) for v in ("pass", "limit", "fail")}
    print(
        f"{len(runs)} runs: {counts['pass']} pass, {counts['limit']} documented limits, "
        f"{counts['fail']} fail -> {out / 'stress.md'}"
    )
    return 1 if counts["fail"] else 0


def register_stress(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("stress", help="stiff and extreme cases with verdicts (stress.md)")
    p.add_argument("--out", help="output directory (default results/stress)")
    p.add_argument("--quick", action="store_true", help="the reduced suite (as in CI)")
    p.add_argument("--only", help="run only the cases whose name contains this (or a group)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_stress)
