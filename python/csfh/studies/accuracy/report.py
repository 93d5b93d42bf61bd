"""The prose of the accuracy report: definitions, and conclusions computed from the numbers."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .study import Point, Study


def introduction(study: Study) -> list[str]:
    return [
        f"Scene `{study.scene}`, horizon {study.stop_time:g} s. Each integrator runs each model "
        "at a range of settings; each run is compared with a reference of the same model.",
        "",
        "Metrics (first three contacts, matched by order):",
        "",
        "* **contact time**: largest |t_k - t_k,ref| of the contact onsets, s;",
        "* **peak F_N** and **max indentation**: largest relative error of the per-contact "
        "maxima (ME locates them on CVODE's interpolant; RK4 takes its accepted steps; the "
        "co-simulation interface shows only communication points, so CS reports neither);",
        "* **rebound velocity**: largest relative error of the separation speed dg/dt at the "
        "end of each contact;",
        "* **trajectory**: max |q - q_ref| with |q| = max(|x|, |y|, R1 |theta|), over the "
        "horizon before the first contact whose onset differs from the reference by more than "
        "1 % of the preceding flight time (afterwards the runs are on different branches of a "
        "chaotic motion and the difference measures nothing about the integrator).",
        "",
        "Moreau is rigid: indentation does not exist and its 'force' is an impulse divided by h "
        "(no limit as h -> 0), so only contact time, rebound velocity and trajectory are measured "
        "for it — against its own h -> 0 reference (convergence) and against the LN K spheres "
        "reference (the difference between the rigid and the compliant model).",
        "",
        "Costs: the number of right-hand-side evaluations (machine-independent), and the "
        "median wall time of repeated runs on this machine. ME's wall time includes fmpy "
        "calling the FMU from Python at every right-hand side, as a user of model exchange "
        "through fmpy experiences it; for CS it is the time spent inside fmi2DoStep (observed "
        "every 10 ms), i.e. the C integration; RK4 and Moreau run in C.",
    ]


def _cheapest(points: list[Point], metric: str, target: float, cost: str) -> Point | None:
    ok = [p for p in points if math.isfinite(p.errors[metric]) and p.errors[metric] <= target]
    return min(ok, key=lambda p: getattr(p, cost)) if ok else None


def conclusions(study: Study, groups: dict[tuple[str, str, str], list[Point]]) -> list[str]:
    from .study import observed_order

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
        for integ in ("CS", "ME"):
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
        "ME and CS are close to first order in the tolerance, as a well-behaved adaptive "
        "integrator should be (the error follows the tolerance). Moreau is first order in h, "
        "and against the compliant reference its error is flat: the rigid and the compliant "
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
        "compliant model with CVODE (CS inside a system simulation, ME when the host tool "
        "integrates); the error falls steadily with the tolerance and the onsets are located by "
        "root finding, not by step bisection;",
        "* gross motion, many impacts, resting and rolling contact, parameter sweeps: Moreau, "
        "cheap and robust but first order in the impact times, and blind to the compliance;",
        "* the paper's RK4 + bisection: only as a baseline; its contact-time error is set by "
        "the event tolerance and its cost grows as the step shrinks through every contact.",
    ]
    return lines
