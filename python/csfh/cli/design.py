"""`csfh design SCENE [STUDY.toml]`: which hinge geometry passes a shock and stays precise. The
study's design variables are sampled (Sobol or Latin hypercube, seeded) and searched
(differential evolution) with every design a batch of shock runs; the feasible designs (margins
against the allowables), their Pareto front, the best designs as scene files, and the Sobol
indices of the objectives."""

from __future__ import annotations

import argparse
from typing import Any

from .common import SCENE_HELP, add_command, add_execution_options, add_quiet, execution


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
    add_execution_options(p, "design")
    add_quiet(p)
    p.set_defaults(func=cmd_design)


def cmd_design(args: argparse.Namespace) -> int:
    from ..studies.design.run import run_design

    outcome = run_design(args.scene, execution(args), args.study, quick=args.quick)
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
