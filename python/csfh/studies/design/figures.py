"""The design study's figures: the feasible region over two design variables, the Pareto front
of the feasible designs, the Sobol indices with their confidence intervals, and the best
designs' margins."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ...plotting import save, subplots
from .spec import CLEARANCE, DesignStudy

LABELS = {
    "flexure_stress": ("peak flexure stress", "MPa", 1e-6),
    "contact_pressure": ("peak contact pressure", "MPa", 1e-6),
    "contacts": ("contacts", "", 1.0),
    "settling_time": ("settling time (end of the last contact)", "ms", 1e3),
    "parasitic": ("parasitic motion of G1", "µm", 1e6),
}


def variable_label(name: str) -> str:
    """A variable's name on an axis."""
    return "clearance R2 − R1" if name == CLEARANCE else name


def _scaled(name: str, values: np.ndarray) -> tuple[np.ndarray, str]:
    """Lengths in µm (below 1 mm) or mm, other values as they are."""
    label = variable_label(name)
    if name == CLEARANCE or (name.endswith((".h", ".b", ".rho", ".R1", ".R2", ".L"))):
        big = float(np.max(np.abs(values)))
        if big < 1e-3:
            return values * 1e6, f"{label} [µm]"
        return values * 1e3, f"{label} [mm]"
    return values, label


def plot_region(path: Path, study: DesignStudy, result: dict[str, Any]) -> Path:
    """Every evaluated design over the first two variables: feasible, infeasible, the feasible
    Pareto front and the best designs."""
    designs = result["designs"]
    names = study.region_axes
    xy = np.array([[d["variables"][n] for n in names] for d in designs])
    x, xl = _scaled(names[0], xy[:, 0])
    y, yl = _scaled(names[1], xy[:, 1])
    ok = np.array([d["feasible"] for d in designs])
    fig, ax = subplots(figsize=(7.5, 5.6))
    ax.scatter(x[ok], y[ok], s=10, c="tab:blue", alpha=0.6, label="feasible")
    ax.scatter(x[~ok], y[~ok], s=14, c="tab:red", marker="x", alpha=0.7, label="infeasible")
    front = result["front"]
    ax.scatter(x[front], y[front], s=40, facecolors="none", edgecolors="k", label="Pareto front")
    index = {id(d): i for i, d in enumerate(designs)}
    best = [index[id(d)] for d in result["best"] if id(d) in index]
    ax.scatter(x[best], y[best], s=150, marker="*", c="gold", edgecolors="k", label="best")
    ax.set_xlabel(xl)
    ax.set_ylabel(yl)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(
        f"Designs of {study.source}: feasible = both margins above their minimums\n"
        f"({len(designs)} designs, the other variables anywhere in their ranges)",
        fontsize=9,
    )
    fig.tight_layout()
    return save(fig, path, dpi=110)


def plot_pareto(path: Path, study: DesignStudy, result: dict[str, Any]) -> Path:
    """The first objective against each other one: feasible designs, their Pareto front."""
    names = study.objectives
    first, others = names[0], names[1:] or names[:1]
    fig, axes = subplots(1, len(others), figsize=(4.2 * len(others), 4.2), squeeze=False)
    designs = result["designs"]
    ok = [d for d in designs if d["feasible"]]
    front = [designs[i] for i in result["front"]]
    lx, ux, sx = LABELS[first]
    for ax, other in zip(axes[0], others, strict=True):
        ly, uy, sy = LABELS[other]
        for group, style in (
            (ok, {"s": 8, "c": "0.6", "label": "feasible"}),
            (front, {"s": 28, "c": "tab:blue", "edgecolors": "k", "label": "Pareto front"}),
            (result["best"], {"s": 140, "marker": "*", "c": "gold", "edgecolors": "k"}),
        ):
            if group:
                ax.scatter(
                    [d["objectives"][first] * sx for d in group],
                    [d["objectives"][other] * sy for d in group],
                    **style,
                )
        ax.set_xlabel(f"{lx} [{ux}]")
        ax.set_ylabel(f"{ly}" + (f" [{uy}]" if uy else ""))
        ax.grid(alpha=0.3)
    if ok:
        axes[0][0].legend(fontsize=7)
    fig.suptitle(
        f"Feasible designs and their Pareto front over {', '.join(names)} (all minimised; "
        "★ the best by the search objective)\nthe front is over every objective at once: in "
        "a projection onto two of them it need not be the lower-left edge",
        fontsize=9,
    )
    fig.tight_layout()
    return save(fig, path, dpi=110)


def plot_sensitivity(path: Path, study: DesignStudy, sens: dict[str, Any]) -> Path:
    """S1 and ST with their confidence intervals, per objective (columns) and input set
    (rows)."""
    sets = [k for k in ("design", "paper") if k in sens]
    names = study.objectives
    fig, axes = subplots(
        len(sets), len(names), figsize=(3.4 * len(names), 3.2 * len(sets)), squeeze=False
    )
    for i, key in enumerate(sets):
        s = sens[key]
        inputs = [variable_label(n) for n in s["inputs"]]
        pos = np.arange(len(inputs))
        for j, obj in enumerate(names):
            ax = axes[i][j]
            r = s["indices"][obj]
            ax.barh(pos - 0.2, r["S1"], 0.4, xerr=r["S1_conf"], label="S1", color="tab:blue")
            ax.barh(pos + 0.2, r["ST"], 0.4, xerr=r["ST_conf"], label="ST", color="tab:orange")
            ax.set_yticks(pos, inputs if j == 0 else [""] * len(inputs), fontsize=7)
            ax.invert_yaxis()
            ax.axvline(0, color="k", lw=0.6)
            ax.grid(alpha=0.3, axis="x")
            title = LABELS[obj][0] + (" (constant)" if r["constant"] else "")
            ax.set_title(title, fontsize=8)
        axes[i][0].set_ylabel(
            "design variables" if key == "design" else "paper's Table 4 parameters (±10 %)",
            fontsize=8,
        )
    axes[0][-1].legend(fontsize=7)
    fig.suptitle(
        f"Sobol first-order (S1) and total (ST) indices, {sens['design']['confidence'] * 100:g} "
        f"% bootstrap intervals; at the direction {sens['direction']:g}°",
        fontsize=9,
    )
    fig.tight_layout()
    return save(fig, path, dpi=110)


def plot_best(path: Path, study: DesignStudy, entries: list[dict[str, Any]]) -> Path:
    """The best designs' margins against their minimums."""
    fig, ax = subplots(figsize=(7.0, 3.6))
    pos = np.arange(len(entries))
    f = [e["margins"]["flexure_margin"] for e in entries]
    c = [e["margins"]["contact_margin"] for e in entries]
    ax.bar(pos - 0.2, f, 0.4, label="flexure margin", color="tab:blue")
    ax.bar(pos + 0.2, c, 0.4, label="contact margin", color="tab:green")
    ax.axhline(study.constraints["flexure_margin"], color="tab:blue", ls="--", lw=1)
    ax.axhline(study.constraints["contact_margin"], color="tab:green", ls=":", lw=1.2)
    ax.set_xticks(pos, [f"design {e['rank']}" for e in entries])
    ax.set_ylabel("smallest margin over the directions")
    ax.set_ylim(min(0.0, *f, *c) - 0.05, 1.0)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title(
        "Best designs: margins 1 − peak/allowable (dashed: the required minimums)", fontsize=9
    )
    fig.tight_layout()
    return save(fig, path, dpi=110)
