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

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.ndimage import maximum_filter1d, minimum_filter1d

from ...batch.tasks import SIGNALS, ResultStore, Task, grid
from ...model.scene import Scene
from ...trajectory import write_json

OUTPUTS = SIGNALS
FORCES = ("F_N", "F_T")
OUTPUT_LABELS = {"x": "x", "y": "y", "theta": "θ", "F_N": "F_N", "F_T": "F_T"}
EVENT_DRIVEN = ("LN_spheres", "LN_cylinders", "LN_ESDU")
LEVEL_NAMES = {0: "none", 1: "low", 2: "medium", 3: "high"}
ARROWS = {0: "·", 1: "↑", 2: "↑↑", 3: "↑↑↑"}


@dataclass(frozen=True)
class SweepParameter:
    key: str
    symbol: str  # as the paper prints it
    variables: tuple[str, ...]  # FMU parameters moved together
    delta: float  # SI step
    step_text: str  # the paper's step, with its unit
    table4: tuple[int, int, int, int, int] | None  # arrows for x, y, theta, F_N, F_T
    table5: tuple[int, int, int, int, int] | None
    note: str = ""
    rest_shift: bool = False  # also move the flexure's rest position as the paper's Eq. (4)
    paper_row: str | None = None  # an alternative reading of this row of the paper's tables


# The paper's Tables 4 (event-driven) and 5 (Moreau), as printed at the end of the paper text.
PARAMETERS: tuple[SweepParameter, ...] = (
    SweepParameter(
        "R1",
        "R1",
        ("contact.R1",),
        1e-3,
        "± 1 mm",
        (3, 3, 3, 2, 1),
        (3, 3, 3, 2, 2),
        "clearance δ = R2 − R1 = 20 ∓ 1 mm",
    ),
    SweepParameter("m1", "m1", ("body1.m",), 0.1, "± 0.1 kg", (1, 1, 1, 1, 1), (2, 2, 2, 2, 2)),
    SweepParameter(
        "I1", "I1", ("body1.I",), 1e-3, "± 0.001 kg m²", (1, 1, 1, 1, 1), (1, 1, 1, 1, 1)
    ),
    SweepParameter(
        "E12",
        "E1,2",
        ("contact.E1", "contact.E2"),
        10e9,
        "± 10 GPa",
        (1, 1, 1, 1, 1),
        None,
        "both surfaces; enters the compliant laws only (Moreau is rigid)",
    ),
    SweepParameter("cr", "c_r", ("contact.cr",), 0.01, "± 0.01", (1, 1, 1, 1, 1), (2, 2, 2, 2, 2)),
    SweepParameter(
        "fd", "f_d", ("friction.fd",), 0.005, "± 0.005", (1, 1, 1, 1, 1), (2, 2, 1, 1, 1)
    ),
    SweepParameter(
        "fa",
        "f_a",
        ("friction.fa",),
        0.01,
        "± 0.01",
        None,
        (1, 1, 1, 1, 1),
        "stiction: Moreau only (the Ambrósio law has none)",
    ),
    SweepParameter(
        "rho",
        "ρ",
        ("flexure.rho",),
        1e-3,
        "± 1 mm",
        (2, 2, 1, 2, 2),
        (2, 2, 1, 2, 2),
        "arc centre O_F fixed: C1 moves with ρ, the rest position of G1 stays at O2",
    ),
    SweepParameter(
        "b",
        "b",
        ("flexure.b",),
        1e-3,
        "± 1 mm (paper: '(-)')",
        (1, 1, 1, 1, 1),
        (1, 1, 1, 1, 1),
        "beam width only; contact.L stays 25 mm (see bL)",
    ),
    SweepParameter("h", "h", ("flexure.h",), 1e-3, "± 1 mm", (2, 2, 2, 2, 2), (3, 3, 3, 2, 2)),
    SweepParameter(
        "beta",
        "β",
        ("flexure.beta",),
        math.radians(1.0),
        "± 1°",
        (3, 3, 2, 3, 2),
        (3, 3, 2, 2, 2),
        "arc centre O_F fixed: C1 moves with β, the rest position of G1 stays at O2",
    ),
    SweepParameter("Eh", "E_h", ("flexure.E",), 10e9, "± 10 GPa", (3, 3, 3, 2, 2), (3, 3, 3, 3, 3)),
)
# Not in the paper's tables: the alternatives our choices leave open (see sweep.md).
EXTRA_PARAMETERS: tuple[SweepParameter, ...] = (
    SweepParameter(
        "bL",
        "b (+L)",
        ("flexure.b", "contact.L"),
        1e-3,
        "± 1 mm",
        None,
        None,
        "not in the paper: beam width and contact length together (K_cylinders ∝ L)",
    ),
    SweepParameter(
        "rho_r0",
        "ρ (Eq. 4)",
        ("flexure.rho",),
        1e-3,
        "± 1 mm",
        None,
        None,
        "the paper's reading: root C2 and attachment s̄ fixed, so the rest position "
        "r0 of Eq. (4) moves by the change of the chord C2→C1",
        rest_shift=True,
        paper_row="rho",
    ),
    SweepParameter(
        "beta_r0",
        "β (Eq. 4)",
        ("flexure.beta",),
        math.radians(1.0),
        "± 1°",
        None,
        None,
        "the paper's reading: root C2 and attachment s̄ fixed, so the rest "
        "position r0 of Eq. (4) moves by the change of the chord C2→C1",
        rest_shift=True,
        paper_row="beta",
    ),
)
ALL_PARAMETERS = {p.key: p for p in (*PARAMETERS, *EXTRA_PARAMETERS)}
PAPER_KEYS = tuple(p.key for p in PARAMETERS)
QUICK_PARAMETERS = ("R1", "m1", "h")


@dataclass(frozen=True)
class MeasureSettings:
    tau: float = 0.05  # departure threshold for x, y, theta: fraction of the nominal range
    tau_force: float = 0.10  # ... for F_N, F_T (impact peaks scale as a power of the speed)
    window: float = 2e-3  # s, time tolerance of the tube
    early_fraction: float = 0.25  # high: departure within this fraction of the horizon
    nrms_medium: float = 0.25  # medium: late departure with at least this NRMS
    none_rel: float = 1e-9  # none: max |b - a| <= none_rel * S


def _sliding(a: np.ndarray, w: int, fn: Any) -> np.ndarray:
    """Running minimum or maximum over +-w samples (the edges repeat the end values)."""
    if w <= 0:
        return a
    return fn(a, size=2 * w + 1, mode="nearest")


def influence(
    t: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    settings: MeasureSettings | None = None,
    force: bool = False,
) -> dict[str, Any]:
    """Compare a perturbed signal b with the nominal a on the uniform grid t (see the module
    docstring; `force` selects the force threshold). Returns t_dep (s, None if no departure),
    nrms, max_dev (max |b - a| / S), peak_change, scale S and level (0-3)."""
    s = settings or MeasureSettings()
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    horizon = float(t[-1] - t[0])
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    scale = float(np.max(a) - np.min(a))
    diff = np.abs(b - a)
    max_diff = float(np.max(diff)) if len(diff) else 0.0
    w = max(0, round(s.window / dt))
    tol = (s.tau_force if force else s.tau) * scale
    lo_a, hi_a = _sliding(a, w, minimum_filter1d), _sliding(a, w, maximum_filter1d)
    lo_b, hi_b = _sliding(b, w, minimum_filter1d), _sliding(b, w, maximum_filter1d)
    out = (b < lo_a - tol) | (b > hi_a + tol) | (a < lo_b - tol) | (a > hi_b + tol)
    t_dep = float(t[int(np.argmax(out))]) if np.any(out) else None
    rms = float(np.sqrt(np.mean((b - a) ** 2))) if len(a) else 0.0
    den = float(np.sqrt(np.var(a) + np.var(b))) if len(a) else 0.0
    nrms = rms / den if den > 0 else (0.0 if rms == 0 else 1.0)
    pa, pb = float(np.max(np.abs(a))), float(np.max(np.abs(b)))
    peak_change = (pb - pa) / pa if pa > 0 else (0.0 if pb == 0 else math.inf)
    if max_diff == 0.0 or (scale > 0 and max_diff <= s.none_rel * scale):
        level = 0
    elif t_dep is not None and t_dep - t[0] <= s.early_fraction * horizon:
        level = 3
    elif t_dep is not None and nrms >= s.nrms_medium:
        level = 2
    else:
        level = 1
    return {
        "t_dep": t_dep,
        "nrms": nrms,
        "max_dev": max_diff / scale if scale > 0 else (0.0 if max_diff == 0 else math.inf),
        "peak_change": peak_change,
        "scale": scale,
        "level": level,
    }


# ------------------------------------------------------------------------------------------
# tasks


@dataclass(frozen=True)
class SweepSpec:
    scene: Scene
    models: tuple[str, ...]
    parameters: tuple[str, ...]
    stop_time: float
    output_interval: float
    interface: str = "me"


def nominal_values(scene: Scene, names: Sequence[str]) -> dict[str, float]:
    """The scene's value of each FMU parameter (its override, the preset's, or the start)."""
    from ...runners.moreau import core_model

    model = core_model(scene)
    return {n: model.get(n) for n in names}


def rest_shift(scene: Scene, p: SweepParameter, direction: int) -> tuple[float, float]:
    """How far the paper's Eq. (4) moves the rest position of G1 when the step changes rho or
    beta with the root C2 and the attachment s-bar fixed: r0 = f + h - s-bar, h the chord from
    the root to the tip, h = rho [e(phi_root + beta) - e(phi_root)] in our layout (the paper's
    Eq. (2) rotated by +90 deg, PHYSICS.md 1.2)."""
    nom = nominal_values(scene, ["flexure.rho", "flexure.beta", "flexure.phi_root"])

    def chord(rho: float, beta: float) -> np.ndarray:
        phi = nom["flexure.phi_root"]
        return rho * np.array(
            [math.cos(phi + beta) - math.cos(phi), math.sin(phi + beta) - math.sin(phi)]
        )

    rho, beta = nom["flexure.rho"], nom["flexure.beta"]
    new = {"flexure.rho": rho, "flexure.beta": beta}
    for v in p.variables:
        new[v] += direction * p.delta
    d = chord(new["flexure.rho"], new["flexure.beta"]) - chord(rho, beta)
    return float(d[0]), float(d[1])


def perturbed(scene: Scene, p: SweepParameter, direction: int) -> tuple[Scene, dict[str, float]]:
    """The scene and the parameter overrides of one step. With `rest_shift` the paper's moving
    rest position is emulated exactly in translation: the flexure keeps its rest at the origin,
    so the start is moved by -dr0 and the conjugate circle of body 1 by +dr0 relative to G1
    (body1.s1), and the outputs x, y are read at O1 (the paper's G1). The rotation of that
    offset with theta (|dr0| theta, < 0.5 mm here) is the emulation's only approximation."""
    from dataclasses import replace

    nominal = nominal_values(scene, p.variables)
    values = {v: nominal[v] + direction * p.delta for v in p.variables}
    if not p.rest_shift:
        return scene, values
    dx, dy = rest_shift(scene, p, direction)
    s1 = nominal_values(scene, ["body1.s1[1]", "body1.s1[2]"])
    values["body1.s1[1]"] = s1["body1.s1[1]"] + dx
    values["body1.s1[2]"] = s1["body1.s1[2]"] + dy
    q0 = (scene.q0[0] - dx, scene.q0[1] - dy, scene.q0[2])
    return replace(scene, q0=q0), values


def sweep_tasks(spec: SweepSpec) -> list[Task]:
    """Nominal + two perturbed runs per parameter, for every model. Deterministic order."""
    tasks: list[Task] = []
    for model in spec.models:
        common = {
            "model": model,
            "stop_time": spec.stop_time,
            "output_interval": spec.output_interval,
            "interface": spec.interface,
        }
        tasks.append(Task(scene=spec.scene, **common, meta=(("param", None), ("direction", 0))))
        for key in spec.parameters:
            p = ALL_PARAMETERS[key]
            for direction in (+1, -1):
                scene, values = perturbed(spec.scene, p, direction)
                meta: tuple[tuple[str, Any], ...] = (("param", key), ("direction", direction))
                if p.rest_shift:
                    meta += (("shift", rest_shift(spec.scene, p, direction)),)
                tasks.append(
                    Task(scene=scene, parameters=tuple(sorted(values.items())), **common, meta=meta)
                )
    return tasks


# ------------------------------------------------------------------------------------------
# analysis


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


def _index(tasks: Sequence[Task]) -> dict[tuple[str, str | None, int], Task]:
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
    by_meta = _index(tasks)
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


def analyse(
    spec: SweepSpec, tasks: Sequence[Task], store: ResultStore, settings: MeasureSettings
) -> dict[str, Any]:
    """Every number of the sweep (JSON-ready): per model, parameter, direction and output, the
    group levels beside the paper's, and how the agreement moves with each threshold."""
    from dataclasses import replace

    by_meta = _index(tasks)
    signals = load_signals(tasks, store)
    measures = measure(spec, tasks, signals, settings)
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
    groups = group_levels(spec, measures)
    comparison = {g: compare_with_paper(g, groups[g]) for g in groups}
    if any(ALL_PARAMETERS[k].paper_row for k in spec.parameters):
        for g in groups:
            comparison[f"{g}, paper's reading"] = compare_with_paper(g, groups[g], "paper")
    sensitivity = []
    for name, values in SENSITIVITY:
        for value in values:
            alt = replace(settings, **{name: value})
            alt_groups = group_levels(spec, measure(spec, tasks, signals, alt))
            row = {"setting": name, "value": value}
            for g in alt_groups:
                c = compare_with_paper(g, alt_groups[g])
                row[g] = {k: c[k] for k in ("agree", "higher", "lower", "within_one", "total")}
            sensitivity.append(row)
    return {
        "settings": asdict(settings),
        "horizon": spec.stop_time,
        "t_early": settings.early_fraction * spec.stop_time,
        "models": list(spec.models),
        "parameters": {
            key: {
                "symbol": ALL_PARAMETERS[key].symbol,
                "variables": list(ALL_PARAMETERS[key].variables),
                "delta": ALL_PARAMETERS[key].delta,
                "step": ALL_PARAMETERS[key].step_text,
                "note": ALL_PARAMETERS[key].note,
                "rest_shift_m": [
                    list(rest_shift(spec.scene, ALL_PARAMETERS[key], d)) for d in (+1, -1)
                ]
                if ALL_PARAMETERS[key].rest_shift
                else None,
            }
            for key in spec.parameters
        },
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


def paper_levels(group: str, key: str) -> tuple[int, ...] | None:
    """The paper's arrows for a row (an alternative reading takes its paper row's)."""
    p = ALL_PARAMETERS[key]
    if p.paper_row is not None:
        p = ALL_PARAMETERS[p.paper_row]
    return p.table4 if group == "event-driven" else p.table5


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
    cells = []
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


# ------------------------------------------------------------------------------------------
# report


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


def write_markdown(
    path: Path, result: dict[str, Any], run_info: dict[str, Any], figures: Sequence[Path]
) -> Path:
    s = result["settings"]
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
    lines += [
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
    lines += [
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
    lines += [
        "",
        "Moreau's F_N and F_T are impulses divided by h (the largest per step in each output "
        "interval): they scale as 1/h and are compared only with Moreau's own nominal run.",
        "",
    ]
    path.write_text("\n".join(lines), encoding="utf-8")
    return path


def plot_levels(path: Path, result: dict[str, Any]) -> Path:
    """Heat map of our levels per group, the paper's arrows written in each cell."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import BoundaryNorm, ListedColormap

    groups = list(result["groups"])
    keys = list(result["parameters"])
    cmap = ListedColormap(["#f0f0f0", "#c6dbef", "#6baed6", "#08519c"])
    norm = BoundaryNorm([-0.5, 0.5, 1.5, 2.5, 3.5], cmap.N)
    fig, axes = plt.subplots(
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
                        plt.Rectangle(
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
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path


def plot_departure(path: Path, result: dict[str, Any]) -> Path:
    """Departure time per model, parameter and output (earlier of the two directions)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    models = result["models"]
    keys = list(result["parameters"])
    T = result["horizon"]
    cmap = plt.get_cmap("magma").with_extremes(bad="#e8e8e8")
    ncol = min(4, len(models))
    nrow = math.ceil(len(models) / ncol)
    fig, axes = plt.subplots(
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
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path


def plot_examples(
    path: Path, spec: SweepSpec, tasks: Sequence[Task], store: ResultStore, result: dict[str, Any]
) -> Path | None:
    """What the levels look like: for one event-driven model, the nominal and perturbed y(t)
    and F_N(t) of a parameter rated low, one rated medium and one rated high for y."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    model = next((m for m in ("LN_cylinders", *spec.models) if m in spec.models), None)
    if model is None:
        return None
    by_meta = _index(tasks)
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
    fig, axes = plt.subplots(
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
    handles.append(plt.Line2D([], [], color="k", ls="--", lw=0.9))
    labels.append("departure t_dep")
    handles.append(plt.Rectangle((0, 0), 1, 1, color="tab:blue", alpha=0.15))
    labels.append("early stage (t ≤ T/4)")
    fig.legend(handles, labels, loc="lower center", ncol=4, frameon=False)
    fig.suptitle(f"{model}: a parameter rated low, medium and high for y", fontsize=10)
    fig.tight_layout(rect=(0, 0.05, 1, 0.97))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_json_report(path: Path, result: dict[str, Any], run_info: dict[str, Any]) -> Path:
    write_json(path, {"run": run_info, **result})
    return path
