"""`csfh accuracy` (error against run time of every integrator) and `csfh stress` (stiff and
extreme cases with verdicts)."""

from __future__ import annotations

import argparse
from typing import Any

from .common import SCENE_HELP, add_command, add_quiet, out_dir, positive_float, positive_int


def _cmd_accuracy(args: argparse.Namespace) -> int:
    from ..model.scene import load_scene
    from ..studies.accuracy.run import run_accuracy

    scene = load_scene(args.scene)
    path = run_accuracy(
        scene,
        out_dir(args, scene.name, "accuracy"),
        stop_time=args.stop_time,
        quick=args.quick,
        repeats=args.repeats,
        quiet=args.quiet,
    )
    print(f"wrote {path}")
    return 0


def register(sub: Any) -> None:
    p = add_command(
        sub,
        "accuracy",
        help="error against run time of every integrator (report.md)",
        description="Run every integrator (model exchange, co-simulation with the FMU's auto "
        "method (RK45) and with CVODE Adams, at rtol 1e-3 ... 1e-10, the paper's RK4 + "
        "bisection, Moreau at h = 1e-3 ... 1e-6 s) on "
        "every model of a scene, measure the contact-time, peak, indentation, rebound and "
        "trajectory errors over the first three contacts against a tighter reference, and "
        "write report.md, accuracy.json and work-precision figures.",
    )
    p.add_argument("scene", help=SCENE_HELP)
    p.add_argument("--out", help="output directory (default: results/SCENE/accuracy)")
    p.add_argument(
        "--stop-time",
        type=positive_float,
        metavar="T",
        help="horizon in s (default: through the third contact + 20 %%)",
    )
    p.add_argument(
        "--repeats", type=positive_int, default=3, help="timing repeats (median of them)"
    )
    p.add_argument("--quick", action="store_true", help="fewer settings (a smoke run)")
    add_quiet(p)
    p.set_defaults(func=_cmd_accuracy)
    register_stress(sub)


def _list_cases(cases: list[Any]) -> None:
    width = max(len(c.group) for c in cases)
    for c in cases:
        by_model: dict[str, list[str]] = {}
        for model, integ in c.runs:
            by_model.setdefault(model, []).append(integ)
        which = ", ".join(
            m if integs == [m] else f"{m} {'/'.join(integs)}" for m, integs in by_model.items()
        )
        quick = "quick" if c.quick else "     "
        print(f"{c.group:<{width}}  {quick}  {c.name}: {which}")


def _cmd_stress(args: argparse.Namespace) -> int:
    from ..studies.stress.run import cases_of, run_stress

    if args.list:
        _list_cases(cases_of(quick=args.quick, only=args.only))
        return 0
    outcome = run_stress(
        out_dir(args, "stress"), quick=args.quick, only=args.only, quiet=args.quiet
    )
    counts = outcome.counts()
    print(
        f"{len(outcome.runs)} runs: {counts['pass']} pass, {counts['limit']} documented limits, "
        f"{counts['fail']} fail -> {outcome.path}"
    )
    return 1 if counts["fail"] else 0


def register_stress(sub: Any) -> None:
    p = add_command(
        sub,
        "stress",
        help="stiff and extreme cases with verdicts (stress.md)",
        description="Run the stiff and extreme cases (contact stiffness, impact speed, "
        "restitution, clearance, grazing, resting contact, friction, eccentric mass) with "
        "every applicable model and integrator, give each run a verdict (pass, documented "
        "limit, fail) and write stress.md and stress.json. Exit status 1 if any run fails. "
        "`--list` shows the cases (group, whether the quick suite has it, name, runs).",
    )
    p.add_argument("--out", help="output directory (default: results/stress)")
    p.add_argument("--quick", action="store_true", help="the reduced suite (as in CI)")
    p.add_argument(
        "--only",
        metavar="TEXT",
        help="only the cases whose name contains TEXT, or whose group is TEXT (see --list; "
        "default: all)",
    )
    p.add_argument(
        "--list", action="store_true", help="list the cases (after --quick, --only) and exit"
    )
    add_quiet(p)
    p.set_defaults(func=_cmd_stress)
