"""Error against run time: a work-precision study of every integrator on a scene.

For each event-driven model (LN_spheres, LN_cylinders, LN_ESDU) the integrators are

* ``ME``: model exchange of the FMU with fmpy's CVode (BDF), relative tolerance 1e-3 ... 1e-10;
* ``CS``: co-simulation with the integrator inside the FMU (its default method, auto: the
  explicit Runge-Kutta 5(4) RK45 while the motion is not stiff, BDF where it is), the same
  tolerances;
* ``CS-Adams``: co-simulation with CVODE's Adams-Moulton inside the FMU (solver.method Adams,
  the former default), the same tolerances;
* ``RK4``: the paper's scheme, explicit RK4 with step bisection to the event tolerance, at the
  paper's (h0 = 2e-4 s, 1e-4 m) and at tighter settings;

and the Moreau model runs the Moreau stepper at h = 1e-3 ... 1e-6 s.

The reference of a model is the same model at a much tighter setting (ME at rtol 1e-12 for the
compliant models, Moreau at a tiny h), and the report shows that halving that setting changes
every metric by less than 1 % of the smallest error plotted.

Metrics, over the first three contacts (k = 1, 2, 3, matched by order):

* contact time: max_k |t_k - t_k,ref| (onset times, s);
* peak F_N: max_k |F_k - F_k,ref| / F_k,ref;
* max indentation: max_k |rho_k - rho_k,ref| / rho_k,ref;
* rebound normal velocity: max_k |v_k - v_k,ref| / |v_k,ref| (the separation speed dg/dt at the
  end of contact k);
* trajectory: max |q - q_ref| over the horizon before the first contact whose onset differs from
  the reference by more than 1 % of the preceding flight time (t_k,ref - t_k-1,ref), with
  |q| = max(|x|, |y|, R1 |theta|) in metres (theta as the arc it moves at the contact radius).

Moreau is compared with its own h -> 0 reference on contact time, rebound velocity and trajectory
(it has no indentation, and its "force" is an impulse divided by h, which has no limit), and
with the LN_spheres reference on the same three metrics to show the model difference.
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np

from ...model import model_info
from ...model.scene import Scene
from ...progress import Progress
from ...runners.registry import run
from ...trajectory import Trajectory
from .metrics import (
    COMPLIANT,
    METRICS,
    RIGID_METRICS,
    Point,
    Study,
    contact_errors,
    horizon,
    mark_unresolved,
    trajectory_error,
)

DEFAULT_SETTINGS: dict[str, list[Any]] = {
    "ME": [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
    "CS": [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
    "CS-Adams": [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
    "RK4": [(2e-4, 1e-4), (1e-4, 1e-5), (5e-5, 1e-6), (2.5e-5, 1e-7), (1.25e-5, 1e-8)],
    "Moreau": [1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6],
}
QUICK_SETTINGS: dict[str, list[Any]] = {
    "ME": [1e-4, 1e-6, 1e-8],
    "CS": [1e-4, 1e-6, 1e-8],
    "CS-Adams": [1e-4, 1e-6, 1e-8],
    "RK4": [(2e-4, 1e-4), (5e-5, 1e-6)],
    "Moreau": [1e-4, 1e-5, 1e-6],
}
REF_RTOL = 1e-13
REF_MOREAU_H = 1e-9
CS_COMMUNICATION_STEP = 1e-2  # s: the co-simulation runs are observed at these points
CS_METHODS: dict[str, str | None] = {"CS": None, "CS-Adams": "Adams"}
"""The co-simulation integrators: their solver.method (None: the FMU's default, auto)."""
INTEGRATORS = ("ME", *CS_METHODS, "RK4")  # of the compliant models


# ------------------------------------------------------------------------------------------
# running


def _median_run(fn: Callable[[], Trajectory], repeats: int) -> tuple[Trajectory, float]:
    walls: list[float] = []
    tr = None
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        tr = fn()
        walls.append(time.perf_counter() - t0)
    assert tr is not None
    return tr, statistics.median(walls)


def _grid(scene: Scene, stop_time: float) -> np.ndarray:
    dt = scene.integrator.output_interval
    return np.arange(1, math.floor(stop_time / dt * (1 + 1e-12)) + 1) * dt


def _compliant(
    study: Study,
    sc: Scene,
    model: str,
    settings: dict[str, list[Any]],
    ctx: _Context,
    step: Callable[[], None],
) -> Trajectory:
    """A compliant model: its reference (and the check at half the tolerance) and every
    integrator at every setting; returns the reference."""
    ref = run(sc, model, "me", rtol=ctx.ref_rtol, output_times=ctx.grid)
    half = run(sc, model, "me", rtol=ctx.ref_rtol / 2, output_times=ctx.grid)
    study.references[model] = f"ME CVode rtol {ctx.ref_rtol:g} (check: {ctx.ref_rtol / 2:g})"
    study.reference_checks[model] = _reference_change(half, ref, ctx.t_end, ctx.radius)
    for integ in INTEGRATORS:
        for setting in settings.get(integ, []):
            study.points.append(
                _measure(
                    sc,
                    model,
                    integ,
                    setting,
                    ref,
                    ctx.grid,
                    ctx.t_end,
                    ctx.radius,
                    ctx.repeats,
                    ctx.ref_rtol,
                )
            )
            step()
    return ref


def _moreau(
    study: Study,
    sc: Scene,
    settings: dict[str, list[Any]],
    ctx: _Context,
    compliant_ref: Trajectory | None,
    step: Callable[[], None],
) -> None:
    """Moreau against its own h -> 0 reference, and against LN_spheres' where it ran."""
    h_ref = ctx.ref_moreau_h
    dt = sc.integrator.output_interval
    ref = run(sc, "Moreau", "core", h=h_ref, output_interval=dt)
    half = run(sc, "Moreau", "core", h=h_ref / 2, output_interval=dt)
    study.references["Moreau"] = f"Moreau h = {h_ref:g} s (check: {h_ref / 2:g})"
    change = _reference_change(half, ref, ctx.t_end, ctx.radius)
    study.reference_checks["Moreau"] = {m: change[m] for m in RIGID_METRICS}
    for h in settings.get("Moreau", []):
        tr, wall = _median_run(partial(run, sc, "Moreau", "core", h=h), ctx.repeats)
        for against, vs in ((ref, "self"), (compliant_ref, "LN_spheres")):
            if against is not None:
                study.points.append(
                    _point(
                        "Moreau",
                        "Moreau",
                        h,
                        f"h = {h:g} s",
                        tr,
                        wall,
                        against,
                        ctx.t_end,
                        ctx.radius,
                        RIGID_METRICS,
                        vs=vs,
                    )
                )
        step()


@dataclass(frozen=True)
class _Context:
    """What every measurement of a study shares."""

    t_end: float
    grid: np.ndarray
    radius: float
    repeats: int
    ref_rtol: float
    ref_moreau_h: float


def _reference_settings(
    settings: dict[str, list[Any]], ref_rtol: float | None, ref_moreau_h: float | None
) -> tuple[float, float]:
    """The references' settings: a thousand times tighter than the tightest setting (rtol at
    most REF_RTOL, the Moreau step at least REF_MOREAU_H) unless given."""
    if ref_rtol is None:
        tightest = [s for i in ("ME", *CS_METHODS) for s in settings.get(i, [])] + [1e-10]
        ref_rtol = max(REF_RTOL, 1e-3 * min(tightest))
    if ref_moreau_h is None:
        ref_moreau_h = max(REF_MOREAU_H, 1e-3 * min(settings.get("Moreau", [1e-6])))
    return ref_rtol, ref_moreau_h


def run_study(
    scene: Scene,
    *,
    stop_time: float | None = None,
    settings: dict[str, list[Any]] | None = None,
    models: tuple[str, ...] | None = None,
    repeats: int = 3,
    ref_rtol: float | None = None,
    ref_moreau_h: float | None = None,
    quiet: bool = True,
) -> Study:
    """Run every integrator at every setting on every model and measure the errors. The
    references default to a thousand times tighter than the tightest setting (rtol at most
    1e-13, the Moreau step at least 1e-9 s)."""
    settings = settings or DEFAULT_SETTINGS
    ref_rtol, ref_moreau_h = _reference_settings(settings, ref_rtol, ref_moreau_h)
    t_end = min(scene.stop_time, stop_time) if stop_time else default_horizon(scene)
    sc = replace(scene, stop_time=t_end)
    models = models or (*COMPLIANT, "Moreau")
    radius = float(sc.parameter_values().get("contact.R1", 0.18))
    ctx = _Context(t_end, _grid(sc, t_end), radius, repeats, ref_rtol, ref_moreau_h)
    study = Study(scene=scene.name, stop_time=t_end)
    total = sum(len(settings.get(i, [])) for i in INTEGRATORS) * sum(
        m in COMPLIANT for m in models
    ) + len(settings.get("Moreau", [])) * ("Moreau" in models)
    progress = Progress(f"accuracy {scene.name}", quiet=quiet, total=total)
    done = 0

    def step() -> None:
        nonlocal done
        done += 1
        progress.update(done)

    refs = {m: _compliant(study, sc, m, settings, ctx, step) for m in models if m in COMPLIANT}
    if "Moreau" in models:
        _moreau(study, sc, settings, ctx, refs.get("LN_spheres"), step)
    progress.close()
    mark_unresolved(study)
    return study


def default_horizon(scene: Scene) -> float:
    """Long enough for the first three contacts (the end of the third, plus 20 %), at most the
    scene's stop time: the metrics look no further, and the Moreau reference costs 1/h steps."""
    probe = run(scene, "LN_spheres", "me", rtol=1e-8)
    ends = probe.contact_records["t_release"]
    ends = ends[np.isfinite(ends)]
    if len(ends) >= 3:
        return float(min(scene.stop_time, 1.2 * ends[2]))
    return scene.stop_time


def _reference_change(
    half: Trajectory, ref: Trajectory, t_end: float, radius: float
) -> dict[str, float]:
    errors = contact_errors(half, ref)
    errors["trajectory"] = trajectory_error(half, ref, horizon(half, ref, t_end), radius)
    return errors


def _measure(
    sc: Scene,
    model: str,
    integ: str,
    setting: Any,
    ref: Trajectory,
    grid: np.ndarray,
    t_end: float,
    radius: float,
    repeats: int,
    ref_rtol: float,
) -> Point:
    if integ == "ME":
        tr, wall = _median_run(
            lambda: run(sc, model, "me", rtol=setting, output_times=grid), repeats
        )
        return _point(model, "ME", setting, f"rtol = {setting:g}", tr, wall, ref, t_end, radius)
    if integ in CS_METHODS:
        method = CS_METHODS[integ]
        numbers = model_info.enumeration("SolverMethod")
        parameters = None if method is None else {"solver.method": numbers[method]}
        tr, _ = _median_run(
            lambda: run(
                sc,
                model,
                "cs",
                rtol=setting,
                communication_step=CS_COMMUNICATION_STEP,
                parameters=parameters,
            ),
            repeats,
        )
        wall = tr.stats["do_step_time"]  # time inside fmi2DoStep: the integration itself
        return _point(
            model,
            integ,
            setting,
            f"rtol = {setting:g}",
            tr,
            wall,
            ref,
            t_end,
            radius,
            ("contact_time", "rebound_velocity", "trajectory"),
        )
    h0, tol = setting
    tr, wall = _median_run(lambda: run(sc, model, "rk4", h0=h0, tol=tol), repeats)
    # the scheme has no dense output: the reference is evaluated at its own record times
    ref_here = run(sc, model, "me", rtol=ref_rtol, output_times=tr.t)
    ref_here.contact_records = ref.contact_records
    return _point(
        model, "RK4", h0, f"h0 = {h0:g} s, tol = {tol:g} m", tr, wall, ref_here, t_end, radius
    )


def _point(
    model: str,
    integ: str,
    setting: float,
    label: str,
    tr: Trajectory,
    wall: float,
    ref: Trajectory,
    t_end: float,
    radius: float,
    metrics: tuple[str, ...] = METRICS,
    vs: str = "self",
) -> Point:
    errors = contact_errors(tr, ref)
    errors["trajectory"] = trajectory_error(tr, ref, horizon(tr, ref, t_end), radius)
    errors = {m: (errors[m] if m in metrics else math.nan) for m in METRICS}
    return Point(
        model=model,
        integrator=integ,
        setting=float(setting),
        label=label,
        wall_time=wall,
        rhs_evaluations=int(tr.stats.get("rhs_evaluations", 0)),
        steps=int(tr.stats.get("steps", 0)),
        errors=errors,
        vs=vs,
    )
