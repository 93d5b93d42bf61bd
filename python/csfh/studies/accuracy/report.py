"""The accuracy study's report: report.md (definitions, reference checks, figures, the table, the
observed orders, and conclusions computed from the numbers), accuracy.json and the
work-precision figures."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from ...output import output_set, write_json, write_text
from .figures import work_precision
from .metrics import METRICS, RESOLUTION, Point, Study, grouped, observed_order, plotted


def introduction(study: Study) -> list[str]:
    """What was run and what each metric means."""
    return [
        f"Scene `{study.scene}`, horizon {study.stop_time:g} s. Each integrator runs each model "
        "at a range of settings; each run is compared with a reference of the same model.",
        "",
        "Metrics (first three contacts, matched by order):",
        "",
        "* **contact time**: largest |t_k - t_k,ref| of the contact onsets, s;",
        "* **peak F_N** and **max indentation**: largest relative error of the per-contact "
        "maxima (ME locates them on CVODE's interpolant; RK4 takes its accepted steps; the "
        "co-simulation runs read only communication points, so CS reports neither);",
        "* **rebound velocity**: largest relative error of the separation speed dg/dt at the "
        "end of each contact;",
        "* **trajectory**: max |q - q_ref| with |q| = max(|x|, |y|, R1 |theta|), over the "
        "horizon before the first contact whose onset differs from the reference by more than "
        "1 % of the preceding flight time (afterwards the runs are on different branches of a "
        "chaotic motion and the difference measures nothing about the integrator).",
        "",
        "Moreau is rigid: indentation does not exist and its 'force' is an impulse divided by h "
        "(no limit as h -> 0), so only contact time, rebound velocity and trajectory are measured "
        "for it — against its own h -> 0 reference (convergence) and against the LN_spheres "
        "reference (the difference between the rigid and the compliant model).",
        "",
        "Costs: the number of right-hand-side evaluations (machine-independent), and the "
        "median wall time of repeated runs on this machine. ME's wall time includes fmpy "
        "calling the FMU from Python at every right-hand side, as a user of model exchange "
        "through fmpy experiences it; for CS it is the time spent inside fmi2DoStep (observed "
        "every 10 ms), i.e. the C integration; RK4 and Moreau run in C. CS is the FMU's default "
        "method, auto (the explicit Runge-Kutta 5(4) RK45 while the motion is not stiff, BDF "
        "where it is); CS-Adams is CVODE's Adams-Moulton, the FMU's default before RK45.",
    ]


def _cheapest(points: list[Point], metric: str, target: float, cost: str) -> Point | None:
    ok = [p for p in points if math.isfinite(p.errors[metric]) and p.errors[metric] <= target]
    return min(ok, key=lambda p: getattr(p, cost)) if ok else None


def conclusions(study: Study, groups: dict[tuple[str, str, str], list[Point]]) -> list[str]:
    """What the numbers show, computed from them."""
    lines = ["## What the numbers show", ""]
    for model in dict.fromkeys(p.model for p in study.points):
        if model == "Moreau":
            continue
        rk4 = sorted(groups.get((model, "RK4", "self"), []), key=lambda p: -p.setting)
        if not rk4:
            continue
        paper = rk4[0]
        e = paper.errors["contact_time"]
        line = (
            f"* **{model}**: the paper's setting ({paper.label}) gets the contact times to "
            f"{e:.1e} s with {paper.rhs_evaluations} RHS evaluations."
        )
        for integ in ("CS", "CS-Adams", "ME"):
            best = _cheapest(
                groups.get((model, integ, "self"), []), "contact_time", e, "rhs_evaluations"
            )
            if best is not None:
                line += (
                    f" {integ} reaches that error at {best.label} with "
                    f"{best.rhs_evaluations} evaluations "
                    f"({paper.rhs_evaluations / max(best.rhs_evaluations, 1):.1f}x fewer) "
                    f"in {best.wall_time:.2g} s (RK4: {paper.wall_time:.2g} s)."
                )
        tight = rk4[-1]
        line += (
            f" At {tight.label} RK4 reaches {tight.errors['contact_time']:.1e} s for "
            f"{tight.rhs_evaluations} evaluations."
        )
        lines.append(line)
    orders = []
    for (m, i, v), ps in groups.items():
        o = observed_order(ps, "contact_time")
        if math.isfinite(o):
            orders.append(f"{m}/{i}{'' if v == 'self' else ' vs ' + v}: {o:.2f}")
    lines += [
        "",
        "Observed order in the contact time (slope against the setting): "
        + "; ".join(orders)
        + ".",
        "",
        "ME and CS (both methods) are close to first order in the tolerance, as a well-behaved "
        "adaptive integrator should be (the error follows the tolerance). Moreau is first "
        "order in h, and against the compliant reference its error is flat: the rigid and the "
        "compliant "
        "model differ by a fixed amount that no step size removes. The RK4 slopes are against "
        "h0 while the event tolerance shrinks ten times per halving of h0, so the contact-time "
        "error follows the event tolerance: "
        + "; ".join(
            f"{m}: {observed_order(ps, 'contact_time') * math.log(2) / math.log(10):.2f}"
            for (m, i, v), ps in groups.items()
            if i == "RK4" and math.isfinite(observed_order(ps, "contact_time"))
        )
        + " against the tolerance (the fourth order of RK4 shows only between events).",
        "",
    ]
    lines += [
        "Which method for which purpose:",
        "",
        "* contact forces, indentation and impact timing (wear, stress): an event-driven "
        "compliant model with an adaptive integrator (CS inside a system simulation, ME when "
        "the host tool integrates); the error falls steadily with the tolerance and the onsets "
        "are located by root finding, not by step bisection;",
        "* gross motion, many impacts, resting and rolling contact, parameter sweeps: Moreau, "
        "cheap and robust but first order in the impact times, and blind to the compliance;",
        "* the paper's RK4 + bisection: only as a baseline; its contact-time error is set by "
        "the event tolerance and its cost grows as the step shrinks through every contact.",
    ]
    return lines


def write_report(study: Study, out: Path) -> list[Path]:
    """report.md, accuracy.json and work-precision figures in `out` (one output set: they
    replace the previous report's files as a whole)."""
    with output_set(out, "accuracy"):
        return _write_report(study, out)


def _write_report(study: Study, out: Path) -> list[Path]:
    files = work_precision(study, out)
    data = {
        "scene": study.scene,
        "stop_time": study.stop_time,
        "references": study.references,
        "reference_checks": study.reference_checks,
        "points": [p.__dict__ for p in study.points],
        "orders": {
            f"{m}/{i}/{v}": {k: observed_order(ps, k) for k in METRICS}
            for (m, i, v), ps in grouped(study).items()
        },
    }
    write_json(out / "accuracy.json", data)
    files.append(out / "accuracy.json")
    write_text(out / "report.md", _markdown(study))
    files.append(out / "report.md")
    return files


def _fmt(x: float) -> str:
    return "-" if not math.isfinite(x) else f"{x:.2e}"


def _references(study: Study) -> list[str]:
    lines = [
        "",
        "## References",
        "",
        "Each reference and the change of every metric when its setting is halved, against "
        "the smallest error plotted for that model (the check passes below 1 %). Errors smaller "
        f"than {RESOLUTION:g} times that change measure the reference rather than the "
        "integrator: they are not plotted, not used for the orders, and shown as '< x' in the "
        "table.",
        "",
        "| model | reference | metric | change on halving | smallest error plotted | ratio |",
        "|---|---|---|---|---|---|",
    ]
    for model, change in study.reference_checks.items():
        pts = [p for p in study.points if p.model == model and p.vs == "self"]
        for metric, value in change.items():
            smallest = min((p.errors[metric] for p in pts if plotted(p, metric)), default=math.nan)
            ratio = value / smallest if smallest and math.isfinite(smallest) else math.nan
            verdict = "" if not math.isfinite(ratio) else (" ok" if ratio < 0.01 else " **no**")
            lines.append(
                f"| {model} | {study.references[model]} | {metric} | {_fmt(value)} | "
                f"{_fmt(smallest)} | {_fmt(ratio)}{verdict} |"
            )
    return lines


def _table(study: Study) -> list[str]:
    lines = ["", "## Figures", ""]
    for model in dict.fromkeys(p.model for p in study.points):
        lines.append(f"![{model}](wp_{model}.png)")
        lines.append("")
    lines += [
        "## Table",
        "",
        "Errors as defined above; cost as median wall time of the repeats and the number of "
        "right-hand-side evaluations (including CVODE's difference-quotient Jacobian; one per "
        "Moreau step).",
        "",
        "| model | integrator | setting | vs | wall [s] | RHS | steps | contact time [s] | "
        "peak F_N | max ind. | rebound | trajectory [m] |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for p in study.points:
        ref = study.reference_checks.get(p.model if p.vs == "self" else p.vs, {})
        cells = [
            f"< {RESOLUTION * ref[m]:.1e}" if m in p.unresolved else _fmt(p.errors[m])
            for m in METRICS
        ]
        lines.append(
            f"| {p.model} | {p.integrator} | {p.label} | {p.vs} | {p.wall_time:.3g} | "
            f"{p.rhs_evaluations} | {p.steps} | " + " | ".join(cells) + " |"
        )
    return lines


def _orders(groups: dict[Any, list[Point]]) -> list[str]:
    lines = [
        "",
        "## Observed order of convergence",
        "",
        "Least-squares slope of log(error) against log(setting): the setting is the relative "
        "tolerance for ME and CS (1 means the error is proportional to the tolerance), the "
        "nominal step h0 for RK4 (its event tolerance shrinks with it) and the step h for "
        "Moreau.",
        "",
        "| model | integrator | vs | " + " | ".join(METRICS) + " |",
        "|---|---|---|" + "---|" * len(METRICS),
    ]
    for (m, i, v), ps in groups.items():
        orders = [observed_order(ps, k) for k in METRICS]
        lines.append(
            f"| {m} | {i} | {v} | "
            + " | ".join("-" if not math.isfinite(o) else f"{o:.2f}" for o in orders)
            + " |"
        )
    return lines


def _markdown(study: Study) -> str:
    groups = grouped(study)
    lines = [f"# Error against run time: scene `{study.scene}`", ""]
    lines += introduction(study)
    lines += [*_references(study), *_table(study), *_orders(groups), ""]
    lines += conclusions(study, groups)
    return "\n".join(lines) + "\n"
