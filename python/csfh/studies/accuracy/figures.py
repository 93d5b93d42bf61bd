"""Work-precision figures of the accuracy study: error against wall time and against RHS
evaluations, log-log, one line per integrator (and reference) per model."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from ...plotting import save, subplots
from .metrics import METRIC_LABELS, METRICS, Point, Study, plotted

STYLE = {
    ("ME", "self"): {"color": "tab:blue", "marker": "o", "label": "ME, fmpy CVode (BDF)"},
    ("CS", "self"): {
        "color": "tab:green",
        "marker": "s",
        "label": "CS, RK45 in the FMU (auto)",
    },
    ("CS-Adams", "self"): {
        "color": "tab:olive",
        "marker": "P",
        "label": "CS, CVODE Adams in the FMU",
    },
    ("RK4", "self"): {"color": "tab:orange", "marker": "^", "label": "RK4 + bisection (paper)"},
    ("Moreau", "self"): {"color": "tab:red", "marker": "D", "label": "Moreau vs Moreau(h->0)"},
    ("Moreau", "LN_spheres"): {
        "color": "tab:purple",
        "marker": "v",
        "ls": "--",
        "label": "Moreau vs LN_spheres",
    },
}


def _lines(axes: Any, pts: list[Point], metrics: list[str]) -> None:
    """One line per integrator (and reference) in every metric's panels: error against wall
    time (top) and against RHS evaluations (bottom)."""
    for integ, vs in dict.fromkeys((p.integrator, p.vs) for p in pts):
        line = sorted(
            (p for p in pts if (p.integrator, p.vs) == (integ, vs)),
            key=lambda p: p.rhs_evaluations,
        )
        style = STYLE.get((integ, vs), {"label": f"{integ} vs {vs}"})
        for col, metric in enumerate(metrics):
            good = [p for p in line if plotted(p, metric)]
            for row, cost in enumerate(("wall_time", "rhs_evaluations") if good else ()):
                axes[row][col].loglog(
                    [getattr(p, cost) for p in good],
                    [p.errors[metric] for p in good],
                    ms=4,
                    lw=1.2,
                    **style,
                )


def _legend(fig: Any, axes: Any) -> None:
    """One legend for the figure, each label once."""
    handles, labels = [], []
    for ax in axes.flat:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), frameon=False)


def work_precision(study: Study, out: Path) -> list[Path]:
    files = []
    for model in dict.fromkeys(p.model for p in study.points):
        pts = [p for p in study.points if p.model == model]
        metrics = [m for m in METRICS if any(math.isfinite(p.errors[m]) for p in pts)]
        fig, axes = subplots(2, len(metrics), figsize=(3.6 * len(metrics), 7.2), squeeze=False)
        _lines(axes, pts, metrics)
        for col, metric in enumerate(metrics):
            axes[0][col].set_title(METRIC_LABELS[metric], fontsize=9)
            axes[0][col].set_xlabel("wall time [s] (median)")
            axes[1][col].set_xlabel("RHS evaluations")
            for row in range(2):
                axes[row][col].grid(alpha=0.3, which="both")
        axes[0][0].set_ylabel("error")
        axes[1][0].set_ylabel("error")
        fig.suptitle(
            f"work-precision, model {model}, scene {study.scene} "
            f"(first 3 contacts, {study.stop_time:g} s)",
            fontsize=11,
        )
        _legend(fig, axes)
        fig.tight_layout(rect=(0, 0.06, 1, 0.96))
        files.append(save(fig, out / f"wp_{model}.png", dpi=110))
    return files
