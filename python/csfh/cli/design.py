"""`csfh design SCENE [STUDY.toml]`: which hinge geometry passes a shock and stays precise. The
study's design variables are sampled (Sobol or Latin hypercube, seeded) and searched
(differential evolution) with every design a batch of shock runs; the feasible designs (margins
against the allowables), their Pareto front, the best designs as scene files, and the Sobol
indices of the objectives."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from .common import SCENE_HELP, CliError, add_command, add_quiet


def register(sub: Any) -> None:
    p = add_command(
        sub,
        "design",
        help="design for survival: the hinge geometry that passes a shock, Pareto front",
        description="Explore and search the design variables of a study (a TOML file of "
        "variables with ranges, the shock condition and directions, margins against the "
        "allowables as constraints, objectives: peak stress, contacts, settling time, "
        "parasitic motion under a nominal load; built-in for the mems and csfh scenes): "
        "quasi-random samples, a differential-evolution search with each population one batch "
        "of shock runs, the feasible Pareto front, Sobol indices with confidence intervals. "
        "Write design.md, design.json, figures, and the best designs as scene files that "
        "`csfh shock SCENE --condition C --direction D` reproduces. The runs are kept in the "
        "output directory (an interrupted study resumes).",
    )
    p.add_argument("scene", help=SCENE_HELP)
    p.add_argument(
        "study",
        nargs="?",
        help="the study file (default: the scene's built-in study)",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="the study's [quick] values: fewer samples, directions and generations",
    )
    p.add_argument(
        "--out",
        help="output directory, where finished runs are kept (default: results/design/SCENE)",
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
    add_quiet(p)
    p.set_defaults(func=cmd_design)


def _workers(text: str | None) -> int | None:
    if text is None:
        return None
    try:
        value = int(text)
    except ValueError:
        raise CliError(f"--workers = {text!r} is not an integer") from None
    if value < 1:
        raise CliError(f"--workers = {value} must be >= 1")
    return value


def cmd_design(args: argparse.Namespace) -> int:
    from ..studies.design.run import run_design
    from ..studies.execution import Execution

    how = Execution(
        Path(args.out) if args.out else None, _workers(args.workers), args.dask, args.quiet
    )
    outcome = run_design(args.scene, how, args.study, quick=args.quick)
    result, info = outcome.result, outcome.run_info
    if not args.quiet:
        for e in result["best_entries"]:
            print(
                f"  design {e['rank']}: {e['scene']} flexure margin "
                f"{e['margins']['flexure_margin']:+.3f}, contact margin "
                f"{e['margins']['contact_margin']:+.3f} -> "
                f"{'feasible' if e['feasible'] else 'INFEASIBLE'}"
            )
    feasible = sum(d["feasible"] for d in result["designs"])
    print(
        f"design: {len(result['designs'])} designs, {feasible} feasible, "
        f"{len(result['front'])} on the Pareto front, {info['tasks']} runs "
        f"({info['computed']} computed, {info['reused']} reused, {info['executor']}) -> "
        f"{outcome.path}"
    )
    return 0
