"""The Moreau midpoint time stepper (docs/model.md §6), run in the C core through ctypes.

Why C: one step is ~100 floating-point operations; in C through the same core library as the FMU
a step costs well under a microsecond (see benchmarks/), the smooth forces are by construction the
FMU's, and the loop needs no Python per step. numba would also be fast but would duplicate the
physics in a second language."""

from __future__ import annotations

import ctypes
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..model._csfh_variables import MOREAU_V_STICK
from ..model.core import N_STATES, library
from ..model.instance import core_model
from ..model.scene import MAX_MOREAU_STEPS, MAX_OUTPUT_SAMPLES, Scene, load_scene
from ..trajectory import Trajectory

STICK_RULES = {"paper": 1, "memory": 2}
MODES = {0: "free", 1: "open", 2: "stick", 3: "slip", 4: "fallback"}
_RECORD = (
    "t",
    "x",
    "y",
    "theta",
    "vx",
    "vy",
    "omega",
    "F_N",
    "F_T",
    "Lambda_N",
    "Lambda_T",
    "gap",
    "indentation",
    "v_T",
    "energy",
    "mode",
)
_IMPACT = (
    "t",
    "gamma_N_before",
    "gamma_T_before",
    "gamma_N_after",
    "gamma_T_after",
    "Lambda_N",
    "Lambda_T",
    "mode",
    "restitution",
    "omega_after",
)
_STATS = (
    "steps",
    "active_steps",
    "stick_steps",
    "slip_steps",
    "fallback_steps",
    "onsets",
    "records",
    "impacts",
    "impacts_dropped",
)


def step_counts(t_end: float, h: float, dt_out: float) -> tuple[int, int, int]:
    """(steps, steps per output row, rows to allocate) of a Moreau run, within the limits of a
    scene (csfh.model.scene: at least one step, at most MAX_MOREAU_STEPS steps and
    MAX_OUTPUT_SAMPLES rows); ValueError naming the values otherwise."""
    for name, value in (("stop_time", t_end), ("h", h), ("output_interval", dt_out)):
        if not (value > 0 and math.isfinite(value)):
            raise ValueError(f"Moreau: {name} = {value!r} must be a finite number > 0")
    if not t_end / h <= MAX_MOREAU_STEPS:
        raise ValueError(
            f"Moreau: h = {h:g} s gives {t_end / h:.3g} steps over {t_end:g} s; at most "
            f"{MAX_MOREAU_STEPS:g}"
        )
    n_steps = round(t_end / h)
    if n_steps < 1:
        raise ValueError(f"Moreau: h = {h:g} s is longer than the run ({t_end:g} s)")
    record_every = max(1, round(dt_out / h))
    max_records = n_steps // record_every + 2
    if max_records > MAX_OUTPUT_SAMPLES + 2:
        raise ValueError(
            f"Moreau: output_interval = {dt_out:g} s gives {max_records - 2} rows; at most "
            f"{MAX_OUTPUT_SAMPLES:g}"
        )
    return n_steps, record_every, max_records


def moreau(
    scene: Scene | str | Path,
    *,
    h: float | None = None,
    stick_rule: str | None = None,
    output_interval: float | None = None,
    stop_time: float | None = None,
    v_eps: float | None = None,
    g_tol: float | None = None,
    parameters: dict[str, Any] | None = None,
    max_impacts: int = 100_000,
) -> Trajectory:
    """Run the Moreau stepper on a scene. The output table has one row per output interval
    (decimated: memory stays bounded); F_N and F_T there are the largest per-step Lambda/h of the
    interval (the impulsive "force", which scales as 1/h); Lambda_N and Lambda_T the impulse sums.
    Every contact onset is listed in `impacts`. `scene`: a Scene, a built-in scene's name or the
    path of a scene file."""
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    h = scene.integrator.moreau_h if h is None else h
    rule = scene.stick_rule if stick_rule is None else stick_rule
    if rule not in STICK_RULES:
        raise ValueError(f"stick_rule = {rule!r} is not one of {', '.join(STICK_RULES)}")
    if not (h > 0 and math.isfinite(h)):
        raise ValueError(f"h = {h!r} must be a positive step")
    t_end = scene.stop_time if stop_time is None else stop_time
    dt_out = scene.integrator.output_interval if output_interval is None else output_interval
    n_steps, record_every, max_records = step_counts(t_end, h, dt_out)
    lib = library()
    ncols, icols = lib.csfh_api_moreau_record_columns(), lib.csfh_api_moreau_impact_columns()
    assert ncols == len(_RECORD) and icols == len(_IMPACT), "core library and harness disagree"
    records = np.zeros((max_records, ncols))
    impacts = np.zeros((max_impacts, icols))
    x_end = np.zeros(N_STATES)
    stats = (ctypes.c_longlong * len(_STATS))()
    model = core_model(scene, parameters)
    x0 = np.array(scene.x0, dtype=float)
    dp = ctypes.POINTER(ctypes.c_double)
    wall = time.perf_counter()
    status = lib.csfh_api_moreau_run(
        model.handle,
        h,
        STICK_RULES[rule],
        scene.integrator.v_eps if v_eps is None else v_eps,
        MOREAU_V_STICK,
        scene.integrator.g_tol if g_tol is None else g_tol,
        0.0,
        x0.ctypes.data_as(dp),
        n_steps,
        record_every,
        records.ctypes.data_as(dp),
        max_records,
        impacts.ctypes.data_as(dp),
        max_impacts,
        x_end.ctypes.data_as(dp),
        stats,
    )
    wall = time.perf_counter() - wall
    st = dict(zip(_STATS, (int(v) for v in stats), strict=True))
    if status != 0:
        raise FloatingPointError(
            f"Moreau: non-finite state after {st['steps']} steps "
            f"(t = {st['steps'] * h:.6g} s); reduce h"
        )
    tr = trajectory_from_buffers(scene.name, h, rule, records, impacts, st)
    tr.stats.update({"wall_time": wall, "evaluations": model.counters()})
    return tr


def trajectory_from_buffers(
    scene_name: str,
    h: float,
    rule: str,
    records: np.ndarray,
    impacts: np.ndarray,
    stats: dict[str, int],
) -> Trajectory:
    """A Trajectory from the C stepper's record and impact buffers (single or batched run)."""
    rec = records[: stats["records"]]
    imp = impacts[: stats["impacts"]]
    table = {name: rec[:, i].copy() for i, name in enumerate(_RECORD)}
    impacts_d = {name: imp[:, i].copy() for i, name in enumerate(_IMPACT)}
    records_d = {  # rigid impacts: onset and release in one step, the impulse/h as "force"
        "t_onset": impacts_d["t"],
        "onset_speed": -impacts_d["gamma_N_before"],
        "t_release": impacts_d["t"] + h,
        "release_speed": impacts_d["gamma_N_after"],
        "peak_F_N": impacts_d["Lambda_N"] / h,
        "max_indentation": np.full(len(imp), np.nan),
    }
    tr = Trajectory(
        model="Moreau",
        scene=scene_name,
        table=table,
        contacts=imp[:, 0].copy(),
        impacts=impacts_d,
        contact_records=records_d,
    )
    tr.stats = {
        **stats,
        "integrator": f"Moreau midpoint h={h:g} s, stick rule {rule}",
        "rhs_evaluations": stats["steps"],
        "h": h,
        "stick_rule": rule,
    }
    return tr
