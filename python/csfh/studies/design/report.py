"""The design study's report: design.json (the study, every design's measures, the feasible
Pareto front, the best designs as `csfh shock` reproduces them, the Sobol indices; nothing that
depends on where or when the runs were computed, so that every executor writes the same file),
design.md with the figures, and the run's bookkeeping in design.md only."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ...model.scene import Scene
from ...output import write_json, write_text
from ..sweep.parameters import ALL_PARAMETERS
from . import figures
from .evaluate import Evaluator
from .spec import DesignStudy

MPA = 1e-6


def _compact(d: dict[str, Any]) -> dict[str, Any]:
    """A design without its per-direction rows and parameter overrides (the best designs have
    them)."""
    return {k: v for k, v in d.items() if k not in ("directions", "parameters")}


def json_data(
    scene: Scene, study: DesignStudy, ev: Evaluator, result: dict[str, Any]
) -> dict[str, Any]:
    p = study.pulse
    return {
        "scene": scene.name,
        "study": {
            "source": study.source,
            "variables": {k: list(v) for k, v in study.variables.items()},
            "pulse": {"name": p.name, "peak_g": p.peak_g, "duration": p.duration},
            "directions": list(study.directions),
            "law": study.law,
            "constraints": study.constraints,
            "objectives": list(study.objectives),
            "search_objective": study.search_objective,
            "parasitic_moment": study.parasitic_moment,
            "sampling": {"method": study.method, "samples": study.samples, "seed": study.seed},
            "search": {"generations": study.generations, "population": study.population},
            "sensitivity_samples": study.sensitivity_samples,
        },
        "allowables": ev.allowables,
        "stop_time": ev.spec.stop_time,
        "communication_step": ev.spec.step,
        "runs": ev.runs["tasks"],
        "nominal": result["nominal"],
        "centre": _compact(result["centre"]),
        "search": {
            "generations": result["search"]["generations"],
            "evaluated": result["search"]["evaluated"],
            "best": _compact(result["search"]["best"]),
        },
        "designs": [_compact(d) for d in result["designs"]],
        "front": result["front"],
        "best": result["best_entries"],
        "sensitivity": result["sensitivity"],
    }


def _fmt(key: str, v: float) -> str:
    return f"{v * figures.LABELS[key][2]:.4g}"


def _objective_header(study: DesignStudy) -> str:
    return " | ".join(
        f"{figures.LABELS[k][0]}" + (f" [{figures.LABELS[k][1]}]" if figures.LABELS[k][1] else "")
        for k in study.objectives
    )


def _best_lines(study: DesignStudy, entries: list[dict[str, Any]]) -> list[str]:
    names = study.names
    lines = [
        "| design | scene file | "
        + " | ".join(names)
        + " | "
        + _objective_header(study)
        + " | flexure margin | contact margin | worst direction | feasible |",
        "|---" * (len(names) + len(study.objectives) + 6) + "|",
    ]
    for e in entries:
        lines.append(
            f"| {e['rank']} | [{e['scene']}]({e['scene']}) | "
            + " | ".join(f"{e['variables'][n]:.5g}" for n in names)
            + " | "
            + " | ".join(_fmt(k, e["objectives"][k]) for k in study.objectives)
            + f" | {e['margins']['flexure_margin']:+.3f} | {e['margins']['contact_margin']:+.3f}"
            f" | {e['direction']:g}° | {'yes' if e['feasible'] else '**no**'} |"
        )
    return lines


def _sensitivity_lines(study: DesignStudy, sens: dict[str, Any]) -> list[str]:
    lines: list[str] = []
    for key, title in (("design", "the design variables"), ("paper", "the paper's parameters")):
        if key not in sens:
            continue
        s = sens[key]
        lines += [
            f"### Over {title} ({s['evaluations']} evaluations, N = {s['base_samples']})",
            "",
            "| input | " + " | ".join(f"{k}: S1 / ST" for k in study.objectives) + " |",
            "|---" * (len(study.objectives) + 1) + "|",
        ]
        for i, name in enumerate(s["inputs"]):
            cells = []
            for k in study.objectives:
                r = s["indices"][k]
                cells.append(
                    f"{r['S1'][i]:.2f} ± {r['S1_conf'][i]:.2f} / {r['ST'][i]:.2f} ± "
                    f"{r['ST_conf'][i]:.2f}"
                )
            lines.append(f"| {name} | " + " | ".join(cells) + " |")
        lines.append("")
    if "paper" in sens:
        lines += _ranking_lines(study, sens["paper"])
    return lines


def _ranking_lines(study: DesignStudy, s: dict[str, Any]) -> list[str]:
    """The paper parameters ranked by their total index of the first objective, beside the
    levels the sweep (the paper's Table 4) gives them."""
    first = study.objectives[0]
    st = s["indices"][first]["ST"]
    order = sorted(range(len(st)), key=lambda i: -st[i])
    lines = [
        f"Ranking by the total index of {figures.LABELS[first][0]}, beside the paper's Table 4 "
        "arrows (x, y, θ, F_N, F_T; `csfh sweep` measures them):",
        "",
        "| rank | parameter | ST | Table 4 (x, y, θ, F_N, F_T) |",
        "|---|---|---|---|",
    ]
    arrows = {0: "·", 1: "↑", 2: "↑↑", 3: "↑↑↑"}
    for rank, i in enumerate(order, start=1):
        key = s["inputs"][i]
        levels = ALL_PARAMETERS[key].table4 or ()
        lines.append(f"| {rank} | {key} | {st[i]:.3f} | {' '.join(arrows[v] for v in levels)} |")
    rho = s["table4_spearman"]
    text = ", ".join(
        f"{k} {'—' if v is None else f'{v:+.2f}'}" for k, v in rho.items() if k in study.objectives
    )
    lines += [
        "",
        "Spearman's rank correlation between the total indices and the mean Table 4 level of "
        f"each parameter (+1: the same order): {text}. The table ranks the parameters by how "
        "soon they change the trajectory; the indices, by how much they move each objective.",
    ]
    return [*lines, ""]


def _markdown(
    scene: Scene,
    study: DesignStudy,
    result: dict[str, Any],
    run_info: dict[str, Any],
    figs: list[Path],
) -> str:
    p = study.pulse
    feasible = sum(d["feasible"] for d in result["designs"])
    lines = [
        f"# Design — scene `{scene.name}`",
        "",
        f"Generated by `csfh design` from {study.source}; every number is also in "
        "`design.json`, and every best design's numbers are reproduced by `csfh shock` on its "
        "scene file (the command is in the file's header).",
        "",
        f"* Shock: **{p.describe()}** in {len(study.directions)} directions "
        f"({', '.join(f'{d:g}' for d in study.directions)}°), law {study.law}, the scene at "
        "rest (as `csfh shock`).",
        "* Variables: "
        + "; ".join(f"{k} in [{lo:.4g}, {hi:.4g}]" for k, (lo, hi) in study.variables.items())
        + ".",
        "* Constraints: "
        + ", ".join(f"{k} ≥ {v:g}" for k, v in study.constraints.items())
        + " (margin = 1 − peak/allowable, the smallest over the directions).",
        f"* Objectives (minimised, the worst over the directions): {', '.join(study.objectives)}"
        f"; the search minimises {study.search_objective}. Parasitic motion: the static "
        f"displacement of G1 under a moment of {study.parasitic_moment:g} N m.",
        f"* {study.samples} {study.method} samples (seed {study.seed}), differential evolution "
        f"over {result['search']['generations']} populations ({result['search']['evaluated']} "
        f"designs): {len(result['designs'])} designs, {feasible} feasible, "
        f"{len(result['front'])} on the feasible Pareto front.",
        f"* {run_info['tasks']} runs ({run_info['computed']} computed, {run_info['reused']} "
        f"reused, {run_info['executor']}) in {run_info['wall_time']:.3g} s.",
        "",
        "## Best designs",
        "",
        *_best_lines(study, result["best_entries"]),
        "",
    ]
    lines += [f"![{f.stem}]({f.name})\n" for f in figs]
    if result["sensitivity"] is not None:
        lines += ["## Sensitivity (Sobol indices)", ""]
        lines += _sensitivity_lines(study, result["sensitivity"])
    return "\n".join(lines) + "\n"


def write_report(
    out: Path,
    scene: Scene,
    study: DesignStudy,
    ev: Evaluator,
    result: dict[str, Any],
    run_info: dict[str, Any],
) -> Path:
    figs = [
        figures.plot_region(out / "design_region.png", study, result),
        figures.plot_pareto(out / "design_pareto.png", study, result),
        figures.plot_best(out / "design_best.png", study, result["best_entries"]),
    ]
    if result["sensitivity"] is not None:
        figs.append(
            figures.plot_sensitivity(out / "design_sensitivity.png", study, result["sensitivity"])
        )
    write_json(out / "design.json", json_data(scene, study, ev, result))
    return write_text(out / "design.md", _markdown(scene, study, result, run_info, figs))
