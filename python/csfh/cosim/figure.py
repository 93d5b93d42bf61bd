"""The figure of a co-simulation run: voltage, actuator force and moment, the position of G1
against the clearance, the rotation and the contact force."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..plotting import save, subplots
from ..trajectory import Trajectory


def plot(tr: Trajectory, path: Path, title: str, delta: float) -> Path:
    """Voltage, actuator force and moment, position of G1 (x, y and the eccentricity |e| against
    the clearance delta: contact where |e| reaches delta), rotation, and the contact force."""
    t = tr.t
    fig, axes = subplots(5, 1, figsize=(8.5, 11.5), sharex=True)
    ax = axes[0]
    ax.plot(t, tr["V"], color="tab:purple", lw=1.2, label="drive voltage V")
    ax.set_ylabel("V [V]")
    ax = axes[1]
    ax.plot(t, tr["F_x"], color="tab:olive", lw=1.2, label="actuator force $F_x$")
    ax.plot(t, tr["F_y"], color="tab:brown", lw=1.2, label="actuator force $F_y$")
    ax.set_ylabel("force on body 1 [N]")
    twin = ax.twinx()
    twin.plot(t, tr["M"], color="tab:gray", lw=1.0, ls="--", label="actuator moment M about G1")
    twin.set_ylabel("M [N m]")
    for a, cols in ((ax, ("F_x", "F_y")), (twin, ("M",))):  # both axes include 0
        lo = min(0.0, *(float(np.min(tr[c])) for c in cols))
        hi = max(0.0, *(float(np.max(tr[c])) for c in cols))
        pad = 0.08 * (hi - lo) or 1.0
        a.set_ylim(lo - (pad if lo < 0 else 0.0), hi + pad)
    ax = axes[2]
    ecc = np.hypot(tr["x"], tr["y"])
    ax.plot(t, tr["x"] * 1e3, color="tab:blue", lw=1.0, label="x of G1")
    ax.plot(t, tr["y"] * 1e3, color="tab:orange", lw=1.0, label="y of G1")
    ax.plot(t, ecc * 1e3, color="k", lw=1.0, label="eccentricity |e|")
    ax.axhline(
        delta * 1e3, color="tab:red", ls=":", lw=1.2, label=f"clearance δ = {delta * 1e3:g} mm"
    )
    ax.set_ylabel("position [mm]")
    ax = axes[3]
    ax.plot(t, np.degrees(tr["theta"]), color="tab:green", lw=1.0, label=r"rotation $\theta$")
    ax.set_ylabel(r"$\theta$ [deg]")
    ax = axes[4]
    F_N = np.where(tr["F_N"] > 0, tr["F_N"], np.nan)
    ax.plot(t, F_N, color="tab:red", lw=0.9, label="contact normal force $F_N$")
    top = float(np.nanmax(F_N)) if np.any(np.isfinite(F_N)) else 10.0
    ax.set_yscale("log")
    ax.set_ylim(1.0, top * 3)
    ax.set_ylabel("$F_N$ [N] (log)")
    ax.set_xlabel("t [s]")
    for a in axes:
        a.grid(alpha=0.3)
    axes[0].set_title(title, fontsize=10)
    handles, labels = [], []
    for a in (*axes[:2], twin, *axes[2:]):
        h, lab = a.get_legend_handles_labels()
        handles += h
        labels += lab
    fig.legend(handles, labels, loc="lower center", ncol=3, frameon=False, fontsize=9)
    fig.tight_layout(rect=(0, 0.075, 1, 1))
    return save(fig, path, dpi=120)
