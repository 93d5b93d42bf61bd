"""Figures equivalent to the paper's (Figs. 6-12), from Trajectory objects. Each function draws
one figure and returns it; `write_figures` writes all of them (`csfh compare`, `csfh plot`).
Legends name the models as the command line does (LN_spheres, LN_cylinders, LN_ESDU, Moreau)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..plotting import model_style, save, subplots
from ..trajectory import IMPULSIVE_MODELS, Trajectory

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

FIGURES = (
    "time_histories.png",
    "y_and_normal_force.png",
    "first_contact.png",
    "friction_vs_step.png",
    "trajectory.png",
)
"""The files `write_figures` writes, in its order."""


def write_figures(runs: Sequence[Trajectory], out: Path, title: str, delta: float) -> list[Path]:
    """The five figures of a comparison into `out` (names in FIGURES); `delta` is the radial
    clearance R2 - R1 in m."""
    figures = (
        time_histories(runs, title),
        central_impact(runs, title, delta),
        first_contact(runs, title),
        friction_steps(runs, title),
        trajectory(runs, title, delta),
    )
    return [save(fig, out / name, dpi=130) for fig, name in zip(figures, FIGURES, strict=True)]


def _style(tr: Trajectory) -> dict[str, Any]:
    return model_style(tr.model)


def _finish(fig: Figure, handles_from: Axes | None = None) -> Figure:
    """One legend for the whole figure, below the axes."""
    if handles_from is not None:
        handles, labels = handles_from.get_legend_handles_labels()
        ncol = min(len(labels), 3)
        rows = -(-len(labels) // ncol)
        height = fig.get_size_inches()[1]
        bottom = (0.3 + 0.25 * rows) / height
        fig.legend(
            handles, labels, loc="lower center", ncol=ncol, frameon=False, bbox_to_anchor=(0.5, 0.0)
        )
        fig.tight_layout(rect=(0, bottom, 1, 1))
    else:
        fig.tight_layout()
    return fig


def _force_axis(ax: Axes, runs: Sequence[Trajectory], column: str, ylabel: str) -> None:
    """Contact forces: log scale when the Moreau impulse 'forces' (~1/h) sit next to the
    compliant forces, so that both are readable; the label says that Moreau's are impulses over
    the step (csfh.trajectory.force_label)."""
    impulsive = any(tr.model in IMPULSIVE_MODELS for tr in runs)
    has_moreau = impulsive and any(np.any(np.abs(tr[column]) > 0) for tr in runs)
    for tr in runs:
        y = np.abs(tr[column]) if has_moreau else tr[column]
        ax.plot(tr.t, y, lw=0.9, **_style(tr))
    if has_moreau:
        ax.set_yscale("log")
        # five decades below the largest force, whatever the scale (mN at MEMS scale)
        top = max(float(np.max(np.abs(tr[column]), initial=0.0)) for tr in runs)
        ax.set_ylim(top * 1e-5, top * 3)
        ylabel = ylabel.replace("[N]", "| [N] (log)").replace("$F", "|$F")
    ax.set_ylabel(f"{ylabel}\nMoreau: impulse / h" if impulsive else ylabel)


def time_histories(runs: Sequence[Trajectory], title: str) -> Figure:
    """Figs. 8 and 11: x, y, theta, F_N, F_T against time."""
    fig, axes = subplots(5, 1, figsize=(8, 11), sharex=True)
    for tr in runs:
        st = _style(tr)
        axes[0].plot(tr.t, tr["x"] * 1e3, lw=1, **st)
        axes[1].plot(tr.t, tr["y"] * 1e3, lw=1, **st)
        axes[2].plot(tr.t, np.degrees(tr["theta"]), lw=1, **st)
    axes[0].set_ylabel("x of G1 [mm]")
    axes[1].set_ylabel("y of G1 [mm]")
    axes[2].set_ylabel(r"$\theta$ [deg]")
    _force_axis(axes[3], runs, "F_N", "$F_N$ [N]")
    _force_axis(axes[4], runs, "F_T", "$F_T$ [N]")
    axes[-1].set_xlabel("t [s]")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].set_title(title, fontsize=10)
    return _finish(fig, axes[0])


def central_impact(runs: Sequence[Trajectory], title: str, delta: float) -> Figure:
    """Fig. 6: y(t), with the bottom of the clearance circle y = -delta dashed, and F_N(t)."""
    fig, axes = subplots(2, 1, figsize=(8, 6.5), sharex=True)
    for tr in runs:
        axes[0].plot(tr.t, tr["y"] * 1e3, lw=1, **_style(tr))
    axes[0].axhline(
        -delta * 1e3, color="0.4", ls="--", lw=0.8, label=f"y = -δ = {-delta * 1e3:g} mm"
    )
    axes[0].set_ylabel("y of G1 [mm]")
    _force_axis(axes[1], runs, "F_N", "$F_N$ [N]")
    axes[1].set_xlabel("t [s]")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].set_title(title, fontsize=10)
    return _finish(fig, axes[0])


def _first_contact_steps(tr: Trajectory) -> dict[str, np.ndarray] | None:
    """Per-step records of the first contact (from its onset to the first release)."""
    if not tr.steps or len(tr.contacts) == 0:
        return None
    s = tr.steps
    t0 = tr.contacts[0]
    inside = np.nonzero((s["t"] >= t0 - 1e-15) & (s["indentation"] > 0))[0]
    if len(inside) == 0:
        return None
    start = inside[0]
    end = start
    while end + 1 < len(s["t"]) and s["indentation"][end + 1] > 0:
        end += 1
    sl = slice(max(start - 1, 0), end + 2)
    return {k: v[sl] for k, v in s.items()}


def first_contact(runs: Sequence[Trajectory], title: str) -> Figure:
    """Fig. 7: indentation against step number, and the hysteresis F_N against indentation of
    the first contact (compliant models; the Moreau contact is rigid and impulsive)."""
    fig, axes = subplots(2, 1, figsize=(8, 7.5))
    drawn = False
    for tr in runs:
        seg = _first_contact_steps(tr)
        if seg is None:
            continue
        drawn = True
        st = _style(tr)
        steps = np.arange(len(seg["t"]))
        axes[0].plot(steps, seg["indentation"] * 1e6, "o-", ms=2.5, lw=1, **st)
        axes[1].plot(seg["indentation"] * 1e6, seg["F_N"] * 1e-3, "o-", ms=2.5, lw=1, **st)
    axes[0].set_xlabel("integrator step since the contact onset")
    axes[0].set_ylabel(r"indentation [$\mu$m]")
    axes[1].set_xlabel(r"indentation [$\mu$m]")
    axes[1].set_ylabel("$F_N$ [kN]")
    for ax in axes:
        ax.grid(alpha=0.3)
    if not drawn:
        axes[0].text(0.5, 0.5, "no compliant contact", ha="center", transform=axes[0].transAxes)
    axes[0].set_title(title, fontsize=10)
    return _finish(fig, axes[0] if drawn else None)


def friction_steps(runs: Sequence[Trajectory], title: str) -> Figure:
    """Fig. 9: v_T and F_T against the step number (event-driven models; during contacts the
    integrator takes many small steps, so most steps are spent there)."""
    fig, axes = subplots(2, 1, figsize=(8, 6.5), sharex=False)
    drawn = None
    for tr in runs:
        if not tr.steps:
            continue
        st = _style(tr)
        n = np.arange(len(tr.steps["t"]))
        axes[0].plot(n, tr.steps["v_T"], lw=0.8, **st)
        axes[1].plot(n, tr.steps["F_T"], lw=0.8, **st)
        drawn = axes[0]
    axes[0].set_ylabel("$v_T$ [m/s]")
    axes[1].set_ylabel("$F_T$ [N]")
    for ax in axes:
        ax.set_xlabel("integrator step")
        ax.grid(alpha=0.3)
    axes[0].set_title(title, fontsize=10)
    return _finish(fig, drawn)


def trajectory(runs: Sequence[Trajectory], title: str, delta: float) -> Figure:
    """Figs. 10 and 12: the path of G1 inside the clearance circle |e| = delta."""
    fig, ax = subplots(figsize=(7, 7))
    phi = np.linspace(0, 2 * np.pi, 400)
    ax.plot(
        delta * 1e3 * np.cos(phi),
        delta * 1e3 * np.sin(phi),
        color="0.3",
        lw=1.2,
        ls="--",
        label=f"clearance circle, $\\delta$ = {delta * 1e3:g} mm",
    )
    for tr in runs:
        ax.plot(tr["x"] * 1e3, tr["y"] * 1e3, lw=0.8, **_style(tr))
    first = runs[0]
    ax.plot(first["x"][0] * 1e3, first["y"][0] * 1e3, "k*", ms=10, label="start")
    ax.set_aspect("equal")
    ax.set_xlabel("x of G1 [mm]")
    ax.set_ylabel("y of G1 [mm]")
    ax.grid(alpha=0.3)
    ax.set_title(title, fontsize=10)
    return _finish(fig, ax)
