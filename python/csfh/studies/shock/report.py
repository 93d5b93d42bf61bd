"""The shock study's report: shock.md (the pulse and where it comes from, the peak stresses and
margins with pass or fail per model and direction, the Monte Carlo's probabilities of exceeding
the allowables), shock.json, and the figures: stresses over time in each model's worst direction,
peak stresses against the shock direction (polar), and the Monte Carlo's histograms."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ...output import write_json, write_text
from ...plotting import model_style, save, subplots
from .conditions import G_STANDARD
from .study import ShockSpec

MPA = 1e-6


def plot_time(
    path: Path,
    spec: ShockSpec,
    series: dict[tuple[str, str], dict[str, np.ndarray]],
    result: dict[str, Any],
) -> Path:
    """The frame's acceleration, the flexure stress and the contact pressure over time: each
    model in the direction where its flexure stress is largest (middle) and where its contact
    pressure is largest (bottom); the peaks over the communication steps marked, the allowables
    dashed where they are on scale."""
    fig, axes = subplots(3, 1, figsize=(8.5, 8.0), sharex=True, height_ratios=[1, 2, 2])
    allow = result["allowables"]
    panels = (
        (
            axes[1],
            "stress",
            "worst_flexure_stress_direction",
            "flexure.stress_allowable",
            "flexure stress [MPa]",
        ),
        (
            axes[2],
            "pressure",
            "worst_contact_pressure_direction",
            "contact.pressure_allowable",
            "contact pressure p0 [MPa]",
        ),
    )
    for ax, key, which, allow_key, label in panels:
        top = 0.0
        for model in spec.models:
            d = result["models"][model][which]
            s = series[(model, key)]
            color = model_style(model)["color"]
            t = s["t"] * 1e3
            ax.plot(t, s[key] * MPA, color=color, lw=0.9, label=f"{model} ({d:g}°)")
            i = int(np.argmax(s[f"{key}_peak"]))
            ax.plot(t[i], s[f"{key}_peak"][i] * MPA, "v", color=color, ms=5)
            top = max(top, float(s[f"{key}_peak"][i]) * MPA)
            if key == "stress":
                a = np.hypot(s["a_frame_x"], s["a_frame_y"]) / G_STANDARD
                axes[0].plot(t, a, color=color, lw=1.0)
        a = allow[allow_key] * MPA
        if a < 2 * top:
            ax.axhline(a, color="k", ls="--", lw=1, label="allowable")
            note = ""
        else:
            note = f" (allowable {a:g} MPa, off scale)"
        ax.set_ylabel(label)
        ax.set_title(
            f"each model in its direction of the largest {label.split(' [')[0]}{note}", fontsize=8.5
        )
        ax.legend(fontsize=7, loc="upper right", ncols=2)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("|a_frame| [g]")
    axes[0].set_title(
        f"Shock {spec.pulse.describe()} on scene {spec.scene.name} (the frame's acceleration)\n"
        "▼ the peak over a communication step, located on the integrator's interpolant",
        fontsize=9,
    )
    axes[0].grid(alpha=0.3)
    axes[2].set_xlabel("time [ms]")
    fig.tight_layout()
    return save(fig, path, dpi=110)


def plot_polar(path: Path, spec: ShockSpec, result: dict[str, Any]) -> Path:
    """Peak flexure stress and peak contact pressure against the direction of the frame's
    acceleration, one line per model; the allowable dashed where it is on scale."""
    fig, axes = subplots(1, 2, figsize=(11.0, 5.4), subplot_kw={"projection": "polar"})
    allow = result["allowables"]
    for ax, key, allow_key, title in (
        (axes[0], "flexure_stress", "flexure.stress_allowable", "peak flexure stress [MPa]"),
        (axes[1], "contact_pressure", "contact.pressure_allowable", "peak contact pressure [MPa]"),
    ):
        top = 0.0
        for model, r in result["models"].items():
            rows = r["directions"]
            theta = np.radians([row["direction"] for row in rows])
            v = np.array([row[key] for row in rows]) * MPA
            top = max(top, float(v.max()))
            if len(rows) > 1:  # close the curve
                theta, v = np.append(theta, theta[0]), np.append(v, v[0])
            ax.plot(theta, v, "o-", ms=3, lw=1.2, **model_style(model))
        a = allow[allow_key] * MPA
        if a < 1.5 * top:
            circle = np.linspace(0, 2 * math.pi, 361)
            ax.plot(circle, np.full_like(circle, a), "k--", lw=1, label="allowable")
        else:
            ax.set_xlabel(f"allowable {a:g} MPa: off scale", fontsize=8)
        ax.set_title(title, fontsize=10, pad=14)
        ax.set_rlim(0, None)
    axes[1].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.05, 1.0))
    fig.suptitle(
        f"Shock {spec.pulse.describe()} on scene {spec.scene.name}: peak stresses against the "
        "direction of the frame's acceleration\n(degrees from the global X axis, counter-clockwise;"
        " 90° = the frame accelerates upward, as when a falling device hits the floor)",
        fontsize=9.5,
    )
    fig.tight_layout()
    return save(fig, path, dpi=110)


def plot_montecarlo(
    path: Path, spec: ShockSpec, mc: dict[str, Any], allow: dict[str, float]
) -> Path:
    models = list(mc["models"])
    fig, axes = subplots(len(models), 2, figsize=(9.0, 2.3 * len(models) + 1.0), squeeze=False)
    for i, model in enumerate(models):
        r = mc["models"][model]
        color = model_style(model)["color"]
        for j, (key, allow_key, label) in enumerate(
            (
                ("flexure_stress", "flexure.stress_allowable", "peak flexure stress [MPa]"),
                ("contact_pressure", "contact.pressure_allowable", "peak contact pressure [MPa]"),
            )
        ):
            ax = axes[i][j]
            v = np.array(r["values"][key]) * MPA
            ax.hist(v, bins=40, color=color, alpha=0.75)
            ax.axvline(r["nominal"][key] * MPA, color="k", ls="--", lw=1)
            a = allow[allow_key] * MPA
            if a <= 1.2 * v.max():
                ax.axvline(a, color="r", lw=1.2)
            p = r["probability"]["flexure" if j == 0 else "contact"]
            ax.text(
                0.98,
                0.95,
                f"P(> allowable) = {p['p']:.3g}\n[{p['low']:.3g}, {p['high']:.3g}]",
                transform=ax.transAxes,
                ha="right",
                va="top",
                fontsize=7,
                bbox={"fc": "white", "ec": "none", "alpha": 0.85},
            )
            if i == len(models) - 1:
                ax.set_xlabel(label)
            if j == 0:
                ax.set_ylabel(f"{model} ({r['direction']:g}°)\nruns")
            ax.ticklabel_format(axis="x", useOffset=False)
    fig.suptitle(
        f"Monte Carlo over tolerances, shock {spec.pulse.describe()} on {spec.scene.name}\n"
        f"dashed the nominal, red the allowable (where on scale); {mc['interval']} "
        f"{mc['confidence'] * 100:g} % intervals",
        fontsize=9,
    )
    fig.tight_layout()
    return save(fig, path, dpi=110)


def _verdict(r: dict[str, Any]) -> str:
    n, bad = len(r["directions"]), len(r["failed_directions"])
    return "pass" if r["passed"] else f"fail in {bad} of {n} direction{'s' if n > 1 else ''}"


def _margin(m: float) -> str:
    """A margin to three decimals, or two significant digits where that would read 0."""
    return f"{m:+.1e}" if 0 < abs(m) < 5e-4 else f"{m:+.3f}"


def _mpa(v: float) -> str:
    return f"{v * MPA:.4g}"


def write_markdown(
    path: Path,
    spec: ShockSpec,
    result: dict[str, Any],
    run_info: dict[str, Any],
    figures: list[Path],
    mc: dict[str, Any] | None = None,
) -> Path:
    allow = result["allowables"]
    p = spec.pulse
    lines = [
        f"# Shock — scene `{spec.scene.name}`",
        "",
        "Generated by `csfh shock`; every number is also in `shock.json`.",
        "",
        f"* Pulse: **{p.describe()}**, half-sine a(t) = A sin(π (t − t0)/T) of the frame's "
        f"acceleration from t0 = {spec.start:g} s; A = {p.peak:.6g} m/s² (g = {G_STANDARD} m/s²), "
        f"velocity change 2AT/π = {p.velocity_change:.4g} m/s. Source: {p.source}.",
        f"* Directions of the frame's acceleration: {len(spec.directions)} "
        f"({', '.join(f'{d:g}' for d in spec.directions)} degrees from the global X axis, "
        "counter-clockwise; 90 = upward, as when a falling device hits the floor).",
        f"* Start: the scene's configuration q0 = {list(spec.scene.q0)} at rest relative to the "
        "frame (the scene's start, not necessarily its static equilibrium: a body that is not "
        f"held there moves under gravity as well); horizon {spec.stop_time:g} s.",
        f"* Models: {', '.join(spec.models)}; co-simulation, the integrator inside the FMU "
        "(solver.method auto: RK45, BDF where the motion is stiff), rtol "
        f"{spec.rtol:g}, communication step {spec.step:g} s; the pulse is evaluated in the "
        "right-hand side and the integrator stops at its start and end (docs/model.md §14.8); "
        "the peaks are located on the integrator's interpolant inside every step "
        "(flexure.track_stress_peak).",
        f"* Allowables: flexure {_mpa(allow['flexure.stress_allowable'])} MPa, contact "
        f"{_mpa(allow['contact.pressure_allowable'])} MPa; margin = 1 − peak/allowable; a "
        "direction passes when both margins are ≥ 0.",
        f"* {run_info['tasks']} runs ({run_info['computed']} computed, {run_info['reused']} "
        f"reused, {run_info['executor']}) in {run_info['wall_time']:.3g} s.",
        "",
        f"**Verdict: {'PASS' if result['passed'] else 'FAIL'}** — "
        + "; ".join(f"{m}: " + _verdict(r) for m, r in result["models"].items()),
        "",
        "| model | worst direction | peak flexure stress [MPa] (direction) | min flexure margin "
        "| peak contact pressure [MPa] (direction) | min contact margin | verdict |",
        "|---|---|---|---|---|---|---|",
    ]
    for m, r in result["models"].items():
        lines.append(
            f"| {m} | {r['worst_direction']:g}° | {_mpa(r['max_flexure_stress'])} "
            f"({r['worst_flexure_stress_direction']:g}°) | {_margin(r['min_flexure_margin'])} | "
            f"{_mpa(r['max_contact_pressure'])} ({r['worst_contact_pressure_direction']:g}°) | "
            f"{_margin(r['min_contact_margin'])} | {'pass' if r['passed'] else '**FAIL**'} |"
        )
    lines.append("")
    for fig in figures:
        lines += [f"![{fig.stem}]({fig.name})", ""]
    if mc is not None:
        lines += _montecarlo_markdown(mc, run_info)
    lines += ["## Per direction", ""]
    for m, r in result["models"].items():
        lines += [
            f"### {m}",
            "",
            "| direction | flexure stress [MPa] | margin | contact pressure [MPa] | margin | "
            "contacts | first contact [ms] | verdict |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for row in r["directions"]:
            first = row["first_contact"]
            lines.append(
                f"| {row['direction']:g}° | {_mpa(row['flexure_stress'])} | "
                f"{_margin(row['flexure_margin'])} | {_mpa(row['contact_pressure'])} | "
                f"{_margin(row['contact_margin'])} | {row['contacts']} | "
                f"{'—' if first is None else f'{first * 1e3:.4g}'} | "
                f"{'pass' if row['passed'] else '**FAIL**'} |"
            )
        lines.append("")
    return write_text(path, "\n".join(lines) + "\n")


def _montecarlo_markdown(mc: dict[str, Any], run_info: dict[str, Any]) -> list[str]:
    tol = run_info["tolerance"]
    lines = [
        "## Monte Carlo over tolerances",
        "",
        f"* {tol['runs']} samples per model, seed {tol['seed']} (sample k draws from "
        f"numpy default_rng([seed, k])), tolerances from {tol['source']}; each model at its "
        "worst direction above.",
        f"* Probability of exceeding an allowable: exceeded runs / runs, with the two-sided "
        f"{mc['interval']} interval at {mc['confidence'] * 100:g} % confidence (exact: it covers "
        "the true probability at least that often, whatever it is; with no run exceeding it, "
        "its upper end is 1 − (α/2)^(1/n)).",
        "",
        "| parameter | nominal | distribution |",
        "|---|---|---|",
    ]
    for key, d in tol["distributions"].items():
        unit = tol["units"].get(key, "")
        lines.append(f"| {key} | {tol['nominal'][key]:.6g} {unit} | {d} |")
    lines += [
        "",
        "| model | direction | flexure stress: nominal / mean / 99 % [MPa] | P(flexure > "
        "allowable) | contact pressure: nominal / mean / 99 % [MPa] | P(contact > allowable) | "
        "P(either) |",
        "|---|---|---|---|---|---|---|",
    ]

    def prob(p: dict[str, Any]) -> str:
        return f"{p['exceeded']}/{p['runs']} = {p['p']:.3g} [{p['low']:.3g}, {p['high']:.3g}]"

    for m, r in mc["models"].items():
        fs, cp = r["flexure_stress"], r["contact_pressure"]
        lines.append(
            f"| {m} | {r['direction']:g}° | {_mpa(r['nominal']['flexure_stress'])} / "
            f"{_mpa(fs['mean'])} / {_mpa(fs['p99'])} | {prob(r['probability']['flexure'])} | "
            f"{_mpa(r['nominal']['contact_pressure'])} / {_mpa(cp['mean'])} / {_mpa(cp['p99'])} | "
            f"{prob(r['probability']['contact'])} | {prob(r['probability']['either'])} |"
        )
    lines.append("")
    return lines


def write_json_report(
    path: Path,
    spec: ShockSpec,
    result: dict[str, Any],
    run_info: dict[str, Any],
    mc: dict[str, Any] | None = None,
) -> Path:
    p = spec.pulse
    data = {
        "scene": spec.scene.name,
        "pulse": {
            "name": p.name,
            "peak_g": p.peak_g,
            "peak": p.peak,
            "duration": p.duration,
            "start": spec.start,
            "velocity_change": p.velocity_change,
            "source": p.source,
        },
        "directions": list(spec.directions),
        "models": list(spec.models),
        "q0": list(spec.scene.q0),
        "stop_time": spec.stop_time,
        "communication_step": spec.step,
        "rtol": spec.rtol,
        "run": run_info,
        "result": result,
        "montecarlo": mc,
    }
    return write_json(path, data)
