"""The paper's parametric analysis (section 7, Tables 4 and 5), made quantitative.

Each parameter of the tables is moved by the paper's step in both directions, one at a time, and
each of the four models is run on the scene (the `csfh` scene by default). For every output
x, y, theta, F_N, F_T the perturbed run is compared with the nominal run of the same model:

* departure time t_dep: the first time at which one signal leaves the *tube* around the other,
  i.e. differs from every value the other takes within +-w (w = 2 ms) by more than tau times the
  peak-to-peak range S of the nominal signal over the horizon (tau = 5 %). The time tolerance makes
  an impact that comes a little earlier or later (less than w) count as the same impact.
* normalised RMS difference NRMS = RMS(b - a) / sqrt(var a + var b) over the horizon: 0 for
  identical signals, about 1 for unrelated signals of the same spread.
* peak change: relative change of max |signal| over the horizon (forces: the largest impact).

Mapped to the paper's arrows (definitions of section 7 turned into thresholds):

* high (3): the runs depart early, t_dep <= t_early = T/4 ("differences appear already in the
  early stages ... completely different dynamics");
* medium (2): they depart later and the difference accumulates, NRMS >= 0.25 ("the differences
  gradually amplify as the simulation proceeds");
* low (1): no departure within the horizon, or a late one with NRMS < 0.25 ("limited changes");
* none (0): the outputs are identical to 1e-9 S (the parameter does not enter the model).

A parameter's level for a model is the larger over its two directions; the event-driven group
(Table 4) takes the median over LN_spheres, LN_cylinders and LN_ESDU.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, replace
from typing import Any

import numpy as np

from ...batch.store import ResultStore
from ...batch.tasks import Task, grid
from .influence import MeasureSettings, influence
from .parameters import ALL_PARAMETERS, EVENT_DRIVEN, FORCES, OUTPUTS, PARAMETERS, paper_levels
from .spec import SweepSpec, rest_shift


def _median_level(levels: Sequence[int]) -> int:
    return sorted(levels)[len(levels) // 2]


def load_signals(tasks: Sequence[Task], store: ResultStore) -> dict[str, dict[str, np.ndarray]]:
    """Output signals of every task; runs with a rest shift are read at O1 (the paper's G1)."""
    out = {}
    for task in tasks:
        sig = dict(store.signals(task.key))
        shift = dict(task.meta).get("shift")
        if shift is not None:
            dx, dy = shift
            c, s_ = np.cos(sig["theta"]), np.sin(sig["theta"])
            sig["x"] = sig["x"] + dx * c - dy * s_
            sig["y"] = sig["y"] + dx * s_ + dy * c
        out[task.key] = sig
    return out


def index_tasks(tasks: Sequence[Task]) -> dict[tuple[str, str | None, int], Task]:
    """The tasks by (model, parameter key or None for the nominal run, direction)."""
    by_meta: dict[tuple[str, str | None, int], Task] = {}
    for task in tasks:
        meta = dict(task.meta)
        by_meta[(task.model, meta["param"], meta["direction"])] = task
    return by_meta


def measure(
    spec: SweepSpec,
    tasks: Sequence[Task],
    signals: dict[str, dict[str, np.ndarray]],
    settings: MeasureSettings,
) -> dict[str, dict[str, dict[str, Any]]]:
    """Influence of every parameter on every output of every model: per direction and combined
    (level: the larger of the two directions; t_dep: the earlier; NRMS: the larger)."""
    t = grid(spec.stop_time, spec.output_interval)
    by_meta = index_tasks(tasks)
    runs: dict[str, dict[str, dict[str, Any]]] = {}
    for model in spec.models:
        nominal = signals[by_meta[(model, None, 0)].key]
        runs[model] = {}
        for key in spec.parameters:
            entry: dict[str, Any] = {}
            for direction, label in ((+1, "+"), (-1, "-")):
                sig = signals[by_meta[(model, key, direction)].key]
                entry[label] = {
                    out: influence(t, nominal[out], sig[out], settings, force=out in FORCES)
                    for out in OUTPUTS
                }
            combined = {}
            for out in OUTPUTS:
                pair = [entry[d][out] for d in ("+", "-")]
                deps = [m["t_dep"] for m in pair if m["t_dep"] is not None]
                combined[out] = {
                    "level": max(m["level"] for m in pair),
                    "t_dep": min(deps) if deps else None,
                    "nrms": max(m["nrms"] for m in pair),
                }
            entry["combined"] = combined
            runs[model][key] = entry
    return runs


def group_levels(spec: SweepSpec, runs: dict[str, Any]) -> dict[str, dict[str, dict[str, int]]]:
    levels = {
        m: {k: {o: runs[m][k]["combined"][o]["level"] for o in OUTPUTS} for k in spec.parameters}
        for m in spec.models
    }
    groups: dict[str, dict[str, dict[str, int]]] = {}
    ed = [m for m in EVENT_DRIVEN if m in spec.models]
    if ed:
        groups["event-driven"] = {
            key: {out: _median_level([levels[m][key][out] for m in ed]) for out in OUTPUTS}
            for key in spec.parameters
        }
    if "Moreau" in spec.models:
        groups["Moreau"] = {key: dict(levels["Moreau"][key]) for key in spec.parameters}
    return groups


SENSITIVITY = (
    ("tau", (0.02, 0.05, 0.10)),
    ("tau_force", (0.05, 0.10, 0.20)),
    ("window", (1e-3, 2e-3, 5e-3)),
    ("early_fraction", (0.15, 0.25, 0.35)),
    ("nrms_medium", (0.15, 0.25, 0.4)),
)


def _runs(
    spec: SweepSpec, by_meta: dict[Any, Task], store: ResultStore, measures: dict[str, Any]
) -> dict[str, Any]:
    """Per model and parameter: the combined measures and each direction's run and measures."""
    runs: dict[str, Any] = {}
    for model in spec.models:
        runs[model] = {}
        for key in spec.parameters:
            m = measures[model][key]
            runs[model][key] = {"combined": m["combined"]}
            for d, direction in (("+", 1), ("-", -1)):
                task = by_meta[(model, key, direction)]
                runs[model][key][d] = {
                    "parameters": dict(task.parameters),
                    "q0": list(task.scene.q0),
                    "summary": store.summary(task.key),
                    "outputs": m[d],
                }
    return runs


def _comparison(spec: SweepSpec, groups: dict[str, Any]) -> dict[str, Any]:
    """Each group's levels against the paper's (and against its own reading, where a row has
    one)."""
    comparison = {g: compare_with_paper(g, groups[g]) for g in groups}
    if any(ALL_PARAMETERS[k].paper_row for k in spec.parameters):
        for g in groups:
            comparison[f"{g}, paper's reading"] = compare_with_paper(g, groups[g], "paper")
    return comparison


def _sensitivity(
    spec: SweepSpec, tasks: Sequence[Task], signals: Any, settings: MeasureSettings
) -> list[dict[str, Any]]:
    """How the agreement with the paper moves with each threshold (SENSITIVITY)."""
    rows = []
    for name, values in SENSITIVITY:
        for value in values:
            alt = replace(settings, **{name: value})
            alt_groups = group_levels(spec, measure(spec, tasks, signals, alt))
            row = {"setting": name, "value": value}
            for g in alt_groups:
                c = compare_with_paper(g, alt_groups[g])
                row[g] = {k: c[k] for k in ("agree", "higher", "lower", "within_one", "total")}
            rows.append(row)
    return rows


def _parameter(spec: SweepSpec, key: str) -> dict[str, Any]:
    p = ALL_PARAMETERS[key]
    return {
        "symbol": p.symbol,
        "variables": list(p.variables),
        "delta": p.delta,
        "step": p.step_text,
        "note": p.note,
        "rest_shift_m": [list(rest_shift(spec.scene, p, d)) for d in (+1, -1)]
        if p.rest_shift
        else None,
    }


def analyse(
    spec: SweepSpec, tasks: Sequence[Task], store: ResultStore, settings: MeasureSettings
) -> dict[str, Any]:
    """Every number of the sweep (JSON-ready): per model, parameter, direction and output, the
    group levels beside the paper's, and how the agreement moves with each threshold."""
    by_meta = index_tasks(tasks)
    signals = load_signals(tasks, store)
    measures = measure(spec, tasks, signals, settings)
    runs = _runs(spec, by_meta, store, measures)
    groups = group_levels(spec, measures)
    comparison = _comparison(spec, groups)
    sensitivity = _sensitivity(spec, tasks, signals, settings)
    return {
        "settings": asdict(settings),
        "horizon": spec.stop_time,
        "t_early": settings.early_fraction * spec.stop_time,
        "models": list(spec.models),
        "parameters": {key: _parameter(spec, key) for key in spec.parameters},
        "nominal": {m: store.summary(by_meta[(m, None, 0)].key) for m in spec.models},
        "runs": runs,
        "levels": {
            m: {
                k: {o: runs[m][k]["combined"][o]["level"] for o in OUTPUTS} for k in spec.parameters
            }
            for m in spec.models
        },
        "groups": groups,
        "paper": {
            "table4": {p.key: list(p.table4) for p in PARAMETERS if p.table4},
            "table5": {p.key: list(p.table5) for p in PARAMETERS if p.table5},
        },
        "comparison": comparison,
        "sensitivity": sensitivity,
    }


def compare_with_paper(
    group: str, ours: dict[str, dict[str, int]], reading: str = "ours"
) -> dict[str, Any]:
    """Cell by cell: agree, ours higher, ours lower (our 'none' counts as low: the paper has
    no lower level); cells the paper does not rate are left out. reading="ours" compares the
    paper's rows with our parameters; reading="paper" replaces each row by its alternative
    reading (e.g. beta by beta_r0) where that was run."""
    rows: dict[str, str] = {}  # paper row -> our row
    for key in ours:
        p = ALL_PARAMETERS[key]
        if p.paper_row is None:
            rows.setdefault(key, key)
        elif reading == "paper":
            rows[p.paper_row] = key
    cells: list[dict[str, Any]] = []
    for row, key in rows.items():
        paper = paper_levels(group, row)
        if paper is None:
            continue
        for out, p_level in zip(OUTPUTS, paper, strict=True):
            o = max(1, ours[key][out])
            cells.append(
                {
                    "param": key,
                    "output": out,
                    "ours": ours[key][out],
                    "paper": p_level,
                    "verdict": "agree" if o == p_level else ("higher" if o > p_level else "lower"),
                }
            )
    n = len(cells)
    count = {v: sum(c["verdict"] == v for c in cells) for v in ("agree", "higher", "lower")}
    within_one = sum(abs(max(1, c["ours"]) - c["paper"]) <= 1 for c in cells)
    return {"cells": cells, "total": n, **count, "within_one": within_one}
