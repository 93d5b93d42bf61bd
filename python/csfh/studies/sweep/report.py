"""The sweep's report: sweep.md (what was run, the influence measure, our tables beside the
paper's with every disagreement named, the sensitivity to each threshold, the per-model numbers)
and sweep.json."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ...output import write_json, write_text
from .parameters import (
    ALL_PARAMETERS,
    ARROWS,
    LEVEL_NAMES,
    OUTPUT_LABELS,
    OUTPUTS,
    PAPER_KEYS,
    paper_levels,
)


def _fmt_t(v: float | None) -> str:
    return "—" if v is None else f"{1e3 * v:.0f}"


GROUP_TITLES = {
    "event-driven": "Table 4 — event-driven models (median of LN_spheres, LN_cylinders, LN_ESDU)",
    "Moreau": "Table 5 — Moreau time stepping",
}


def _group_table(result: dict[str, Any], group: str) -> list[str]:
    lines = [
        f"### {GROUP_TITLES.get(group, group)}",
        "",
        "Each cell: ours (paper); ✗ marks a disagreement; · = no effect at all; n/a = the paper "
        "does not rate it. Rows in italics are not in the paper: the alternative readings, "
        "shown beside the paper's arrows of the row they stand for.",
        "",
        "| parameter | step | " + " | ".join(OUTPUT_LABELS[o] for o in OUTPUTS) + " |",
        "|" + "---|" * (len(OUTPUTS) + 2),
    ]
    for key, row in result["groups"][group].items():
        p = ALL_PARAMETERS[key]
        paper = paper_levels(group, key)
        cells = []
        for i, out in enumerate(OUTPUTS):
            ours = ARROWS[row[out]]
            if paper is None:
                cells.append(f"{ours} (n/a)")
            else:
                mark = "" if max(1, row[out]) == paper[i] else " ✗"
                cells.append(f"{ours} ({ARROWS[paper[i]]}){mark}")
        name = p.symbol if key in PAPER_KEYS else f"*{p.symbol}*"
        lines.append(f"| {name} | {p.step_text} | " + " | ".join(cells) + " |")
    c = result["comparison"][group]
    lines += [
        "",
        f"Agreement with the paper's {'Table 4' if group == 'event-driven' else 'Table 5'}: "
        f"**{c['agree']} of {c['total']}** rated cells equal, {c['within_one']} within one "
        f"level; ours higher in {c['higher']}, lower in {c['lower']}.",
    ]
    alt = result["comparison"].get(f"{group}, paper's reading")
    if alt is not None:
        lines.append(
            f"With the paper's reading of ρ and β (rows in italics instead of ρ, β): "
            f"**{alt['agree']} of {alt['total']}** equal, {alt['within_one']} within one level; "
            f"ours higher in {alt['higher']}, lower in {alt['lower']}."
        )
    return [*lines, ""]


def _disagreements(result: dict[str, Any], group: str) -> list[str]:
    cells = [c for c in result["comparison"][group]["cells"] if c["verdict"] != "agree"]
    if not cells:
        return ["No disagreement.", ""]
    by_param: dict[str, list[str]] = {}
    for c in cells:
        by_param.setdefault(c["param"], []).append(
            f"{OUTPUT_LABELS[c['output']]} {LEVEL_NAMES[c['ours']]} vs {LEVEL_NAMES[c['paper']]}"
        )
    return [
        f"* {ALL_PARAMETERS[k].symbol}: " + "; ".join(v) + " (ours vs paper)"
        for k, v in by_param.items()
    ] + [""]


def _per_model_table(result: dict[str, Any], model: str) -> list[str]:
    lines = [
        f"#### {model}",
        "",
        "Each cell: level (0-3) · departure time t_dep in ms (earlier of the two directions; "
        "— = no departure) · NRMS (larger of the two).",
        "",
        "| parameter | " + " | ".join(OUTPUT_LABELS[o] for o in OUTPUTS) + " |",
        "|" + "---|" * (len(OUTPUTS) + 1),
    ]
    for key, entry in result["runs"][model].items():
        cells = []
        for out in OUTPUTS:
            c = entry["combined"][out]
            cells.append(f"{c['level']} · {_fmt_t(c['t_dep'])} · {c['nrms']:.2f}")
        lines.append(f"| {ALL_PARAMETERS[key].symbol} | " + " | ".join(cells) + " |")
    return [*lines, ""]


def _sensitivity_table(result: dict[str, Any]) -> list[str]:
    groups = list(result["groups"])
    lines = [
        "## How much the verdict depends on the thresholds",
        "",
        "Cells equal to the paper's (of the rated cells), with one threshold changed at a time "
        "(the others at their defaults, marked ◀):",
        "",
        "| threshold | value | " + " | ".join(groups) + " |",
        "|---|---|" + "---|" * len(groups),
    ]
    defaults = result["settings"]
    for row in result["sensitivity"]:
        mark = " ◀" if row["value"] == defaults[row["setting"]] else ""
        cells = [
            f"{row[g]['agree']}/{row[g]['total']} (±1: {row[g]['within_one']})" for g in groups
        ]
        lines.append(f"| {row['setting']} | {row['value']:g}{mark} | " + " | ".join(cells) + " |")
    return [*lines, ""]


def _what_was_run(result: dict[str, Any], run_info: dict[str, Any]) -> list[str]:
    T = result["horizon"]
    lines = [
        f"# Parametric analysis of the paper's Tables 4 and 5 — scene `{run_info['scene']}`",
        "",
        "Generated by `csfh sweep`; every number is in `sweep.json`.",
        "",
        "## What was run",
        "",
        f"* Scene `{run_info['scene']}` ({run_info['description']}), preset "
        f"`{run_info['preset']}`, q0 = {run_info['q0']}, horizon T = {T:g} s, outputs on a "
        f"grid of {run_info['output_interval']:g} s.",
        f"* Models: {', '.join(result['models'])}. Event-driven models through the FMU: "
        f"{run_info['interface_text']}. Moreau: the C core, h = {run_info['moreau_h']:g} s, "
        f"stick rule `{run_info['stick_rule']}`, {run_info['moreau_batch']}.",
        f"* {run_info['tasks']} runs ({run_info['computed']} computed, {run_info['reused']} "
        f"reused from the output directory) on {run_info['executor']}, "
        f"{run_info['wall_time']:.1f} s for this command; the runs themselves took "
        f"{run_info['run_time_sum']:.1f} s summed over the tasks.",
        "* One parameter at a time, both directions, with the paper's steps:",
        "",
        "| parameter | FMU variables | step | note |",
        "|---|---|---|---|",
    ]
    for p in result["parameters"].values():
        note = p["note"]
        if p.get("rest_shift_m"):
            dx, dy = p["rest_shift_m"][0]
            note += f"; +step: Δr0 = [{1e3 * dx:+.2f}, {1e3 * dy:+.2f}] mm"
        lines.append(f"| {p['symbol']} | {', '.join(p['variables'])} | {p['step']} | {note} |")
    return lines


def _influence_measure(result: dict[str, Any]) -> list[str]:
    s = result["settings"]
    return [
        "",
        "## The influence measure",
        "",
        "For each output (x, y, θ of G1; F_N, F_T of the contact) the perturbed signal b(t) is "
        "compared with the nominal a(t) of the same model on the output grid:",
        "",
        "* **Departure time t_dep**: the first time at which one signal leaves the tube around "
        "the other, |b(t) − a(t′)| > τ·S for every t′ within ±w of t, with S the peak-to-peak "
        f"range of the nominal signal over the horizon, w = {1e3 * s['window']:g} ms, "
        f"τ = {s['tau']:g} for x, y, θ and τ = {s['tau_force']:g} for F_N, F_T (an impact peak "
        "grows as a power of the impact speed, about v^1.2 for n = 1.5, so forces amplify small "
        "differences of the motion). The time tolerance w lets an impact that comes less than "
        "w earlier or later count as the same impact: a force spike is never compared with the "
        "empty signal just beside it.",
        "* Signals: x, y, θ are sampled at the grid points; F_N, F_T are, per output interval, "
        "the value of largest magnitude (event-driven: over every integrator step; Moreau: the "
        "step with the largest impulse), so an impact peak does not depend on where the grid "
        "cuts it.",
        "* **NRMS** = RMS(b − a) / sqrt(var a + var b) over the horizon: 0 for identical "
        "signals, ≈ 1 for unrelated signals of the same spread.",
        "* **Peak change**: relative change of max |signal| over the horizon (in `sweep.json`).",
        "",
        "Levels — the paper's verbal definitions (section 7) turned into thresholds:",
        "",
        f'* **high ↑↑↑**: t_dep ≤ T/4 = {result["t_early"]:g} s — "the differences appear '
        "already in the early stages of the simulation generating completely different "
        'dynamics";',
        f'* **medium ↑↑**: departure after T/4 and NRMS ≥ {s["nrms_medium"]:g} — "the '
        'differences gradually amplify as the simulation proceeds";',
        f"* **low ↑**: no departure within T, or a late one with NRMS < {s['nrms_medium']:g} — "
        '"the changes in the dynamic response are limited";',
        f"* **none ·**: max |b − a| ≤ {s['none_rel']:g}·S: the parameter does not enter this "
        "model (counted as low against the paper, which has no lower level).",
        "",
        "A parameter's level is the larger of its two directions; Table 4's is the median of "
        'the three event-driven models (they are grouped in the paper "because the behavior '
        'is similar").',
        "",
        "## Our table beside the paper's",
        "",
    ]


def _nominal_runs(result: dict[str, Any]) -> list[str]:
    lines = [
        "## Nominal runs",
        "",
        "| model | first contact [s] | contacts | peak F_N [N] | peak abs F_T [N] | steps |",
        "|---|---|---|---|---|---|",
    ]
    for model, sm in result["nominal"].items():
        first = "—" if sm["first_contact"] is None else f"{sm['first_contact']:.6f}"
        lines.append(
            f"| {model} | {first} | {sm['contacts']} | {sm['peak_F_N']:.4g} | "
            f"{sm['peak_abs_F_T']:.4g} | {sm['steps']} |"
        )
    return [
        *lines,
        "",
        "Moreau's F_N and F_T are impulses divided by h (the largest per step in each output "
        "interval): they scale as 1/h and are compared only with Moreau's own nominal run.",
        "",
    ]


def write_markdown(
    path: Path, result: dict[str, Any], run_info: dict[str, Any], figures: Sequence[Path]
) -> Path:
    lines = [*_what_was_run(result, run_info), *_influence_measure(result)]
    for group in result["groups"]:
        lines += _group_table(result, group)
        lines += ["Disagreements:", "", *_disagreements(result, group)]
    for fig in figures:
        lines += [f"![{fig.stem}]({fig.name})", ""]
    lines += _sensitivity_table(result)
    notes = run_info.get("notes")
    if notes:
        lines += [notes.rstrip(), ""]
    lines += ["## Per model", ""]
    for model in result["models"]:
        lines += _per_model_table(result, model)
    lines += _nominal_runs(result)
    return write_text(path, "\n".join(lines))


def write_json_report(path: Path, result: dict[str, Any], run_info: dict[str, Any]) -> Path:
    return write_json(path, {"run": run_info, **result})
