"""The sweep's figures: heat maps of our levels beside the paper's arrows and of the departure
times, and examples of what a low, medium and high rating look like."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ...batch.store import ResultStore
from ...batch.tasks import Task, grid
from ...plotting import save, subplots
from .analysis import index_tasks, load_signals
from .parameters import (
    ALL_PARAMETERS,
    ARROWS,
    LEVEL_NAMES,
    OUTPUT_LABELS,
    OUTPUTS,
    PAPER_KEYS,
    paper_levels,
)
from .spec import SweepSpec


def plot_levels(path: Path, result: dict[str, Any]) -> Path:
    """Heat map of our levels per group, the paper's arrows written in each cell."""
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Rectangle

    groups = list(result["groups"])
    keys = list(result["parameters"])
    cmap = ListedColormap(["#f0f0f0", "#c6dbef", "#6baed6", "#08519c"])
    norm = BoundaryNorm([-0.5, 0.5, 1.5, 2.5, 3.5], cmap.N)
    fig, axes = subplots(
        1, len(groups), figsize=(4.3 * len(groups) + 2.6, 0.5 * len(keys) + 1.9), squeeze=False
    )
    im = None
    for g_index, (ax, group) in enumerate(zip(axes[0], groups, strict=True)):
        data = np.array([[result["groups"][group][k][o] for o in OUTPUTS] for k in keys])
        im = ax.imshow(data, cmap=cmap, norm=norm, aspect="auto")
        for i, k in enumerate(keys):
            paper = paper_levels(group, k)
            for j in range(len(OUTPUTS)):
                ours = int(data[i, j])
                color = "white" if ours >= 3 else "black"
                ax.text(
                    j,
                    i - 0.13,
                    ARROWS[ours],
                    ha="center",
                    va="center",
                    fontsize=9,
                    color=color,
                    fontweight="bold",
                )
                ptxt = "n/a" if paper is None else ARROWS[paper[j]]
                ax.text(
                    j, i + 0.24, f"({ptxt})", ha="center", va="center", fontsize=6.5, color=color
                )
                if paper is not None and max(1, ours) != paper[j]:
                    ax.add_patch(
                        Rectangle(
                            (j - 0.46, i - 0.46),
                            0.92,
                            0.92,
                            fill=False,
                            edgecolor="#d62728",
                            lw=1.5,
                        )
                    )
        ax.set_xticks(range(len(OUTPUTS)), [OUTPUT_LABELS[o] for o in OUTPUTS])
        ax.set_yticks(range(len(keys)))
        if g_index == 0:
            ax.set_yticklabels(
                [
                    f"{ALL_PARAMETERS[k].symbol}  {ALL_PARAMETERS[k].step_text}".split(" (paper")[0]
                    for k in keys
                ]
            )
            for label, k in zip(ax.get_yticklabels(), keys, strict=True):
                if k not in PAPER_KEYS:
                    label.set_fontstyle("italic")
        else:
            ax.set_yticklabels([])
        ax.set_title(
            {"event-driven": "event-driven models (Table 4)", "Moreau": "Moreau (Table 5)"}.get(
                group, group
            ),
            fontsize=10,
        )
        ax.set_xticks(np.arange(-0.5, len(OUTPUTS)), minor=True)
        ax.set_yticks(np.arange(-0.5, len(keys)), minor=True)
        ax.grid(which="minor", color="white", lw=1.5)
        ax.tick_params(which="minor", length=0)
    fig.suptitle(
        "Influence of each parameter: ours (colour, bold arrows) and the paper's "
        "(in brackets); red frame: we disagree",
        fontsize=10,
    )
    cbar = fig.colorbar(im, ax=axes[0].tolist(), ticks=[0, 1, 2, 3], shrink=0.7, pad=0.02)
    cbar.ax.set_yticklabels(["none ·", "low ↑", "medium ↑↑", "high ↑↑↑"])
    return save(fig, path, dpi=120, bbox_inches="tight")


def plot_departure(path: Path, result: dict[str, Any]) -> Path:
    """Departure time per model, parameter and output (earlier of the two directions)."""
    from matplotlib import colormaps

    models = result["models"]
    keys = list(result["parameters"])
    T = result["horizon"]
    cmap = colormaps["magma"].with_extremes(bad="#e8e8e8")
    ncol = min(4, len(models))
    nrow = math.ceil(len(models) / ncol)
    fig, axes = subplots(
        nrow, ncol, figsize=(3.3 * ncol + 1.4, (0.36 * len(keys) + 1.6) * nrow), squeeze=False
    )
    im = None
    for idx, model in enumerate(models):
        ax = axes[idx // ncol][idx % ncol]
        data = np.full((len(keys), len(OUTPUTS)), np.nan)
        for i, k in enumerate(keys):
            for j, o in enumerate(OUTPUTS):
                v = result["runs"][model][k]["combined"][o]["t_dep"]
                data[i, j] = np.nan if v is None else v
        im = ax.imshow(np.ma.masked_invalid(data), cmap=cmap, vmin=0, vmax=T, aspect="auto")
        ax.set_xticks(range(len(OUTPUTS)), [OUTPUT_LABELS[o] for o in OUTPUTS])
        ax.set_yticks(range(len(keys)), [ALL_PARAMETERS[k].symbol for k in keys])
        if idx % ncol:
            ax.set_yticklabels([])
        ax.set_title(model, fontsize=10)
        ax.axhline(-0.5, color="k", lw=0.5)
    for idx in range(len(models), nrow * ncol):
        axes[idx // ncol][idx % ncol].axis("off")
    cbar = fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.85, pad=0.02)
    cbar.set_label("departure time t_dep [s] (grey: no departure)")
    cbar.ax.axhline(result["t_early"], color="c", lw=2)
    fig.suptitle(
        f"When the perturbed run leaves the nominal one's tube (T = {T:g} s; "
        f"cyan: T/4, the high/medium limit)",
        fontsize=10,
    )
    return save(fig, path, dpi=120, bbox_inches="tight")


def plot_examples(
    path: Path, spec: SweepSpec, tasks: Sequence[Task], store: ResultStore, result: dict[str, Any]
) -> Path | None:
    """What the levels look like: for one event-driven model, the nominal and perturbed y(t)
    and F_N(t) of a parameter rated low, one rated medium and one rated high for y."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Rectangle

    model = next((m for m in ("LN_cylinders", *spec.models) if m in spec.models), None)
    if model is None:
        return None
    by_meta = index_tasks(tasks)
    picks = []
    for level in (1, 2, 3):
        for key in spec.parameters:
            c = result["runs"][model][key]["combined"]["y"]
            if c["level"] == level:
                picks.append((level, key))
                break
    if not picks:
        return None
    t = grid(spec.stop_time, spec.output_interval)
    signals = load_signals([by_meta[(model, None, 0)]], store)
    nominal = next(iter(signals.values()))
    fig, axes = subplots(
        len(picks), 2, figsize=(11, 2.3 * len(picks) + 0.8), squeeze=False, sharex=True
    )
    for row, (level, key) in enumerate(picks):
        entry = result["runs"][model][key]
        direction = "+" if entry["+"]["outputs"]["y"]["level"] == level else "-"
        task = by_meta[(model, key, 1 if direction == "+" else -1)]
        sig = load_signals([task], store)[task.key]
        for col, (out, unit, factor) in enumerate((("y", "mm", 1e3), ("F_N", "kN", 1e-3))):
            ax = axes[row][col]
            ax.plot(t, nominal[out] * factor, color="0.35", lw=0.9, label="nominal")
            ax.plot(t, sig[out] * factor, color="tab:red", lw=0.8, alpha=0.85, label="perturbed")
            ax.axvspan(0, result["t_early"], color="tab:blue", alpha=0.07, lw=0)
            m = entry[direction]["outputs"][out]
            if m["t_dep"] is not None:
                ax.axvline(m["t_dep"], color="k", ls="--", lw=0.9)
            p = ALL_PARAMETERS[key]
            dep = "none" if m["t_dep"] is None else f"{m['t_dep']:.3f} s"
            ax.set_title(
                f"{p.symbol} {direction}{p.step_text.lstrip('± ').split(' (')[0]}: "
                f"{OUTPUT_LABELS[out]} {LEVEL_NAMES[m['level']]}, t_dep {dep}, "
                f"NRMS {m['nrms']:.2f}",
                fontsize=8.5,
            )
            ax.set_ylabel(f"{OUTPUT_LABELS[out]} [{unit}]")
            if row == len(picks) - 1:
                ax.set_xlabel("t [s]")
    handles, labels = axes[0][0].get_legend_handles_labels()
    handles.append(Line2D([], [], color="k", ls="--", lw=0.9))
    labels.append("departure t_dep")
    handles.append(Rectangle((0, 0), 1, 1, color="tab:blue", alpha=0.15))
    labels.append("early stage (t ≤ T/4)")
    fig.legend(handles, labels, loc="lower center", ncol=4, frameon=False)
    fig.suptitle(f"{model}: a parameter rated low, medium and high for y", fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 0.97))
    return save(fig, path, dpi=110)
