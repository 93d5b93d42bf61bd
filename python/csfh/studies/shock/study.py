"""Shock survivability: a half-sine pulse of the frame's acceleration in one direction or a sweep
of directions, every event-driven model, the peak flexure stress and contact pressure against
their allowables; and a Monte Carlo over tolerances that gives the probability of exceeding them.

Every run is a co-simulation of the FMU with the pulse inside the model (shock.peak,
shock.duration, shock.start, shock.angle: a(t) is evaluated in the right-hand side at the
integrator's time, and the integrator stops and restarts at the pulse's ends, docs/model.md
§14.8) and flexure.track_stress_peak on, so that the peaks are located on the integrator's
interpolant inside every communication step. The runs go through the task system (csfh.batch):
batched in the FMU's own binary (csfh.runners.cs_batch), kept in the output directory (an
interrupted command resumes), serial, on local processes or on Dask with identical results.

The start: the scene's configuration q0 at rest relative to the frame (u = 0), before the pulse
starts at `start` (default 0); the device is thereby assumed to sit still when the shock comes
(a scene's own start velocity, e.g. mems' "after a shock", is not used)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ...batch.store import ResultStore
from ...batch.tasks import Task
from ...errors import ParameterError
from ...model import model_info
from ...model.instance import nominal_values
from ...model.scene import Scene
from .conditions import Pulse

ALLOWABLES = ("flexure.stress_allowable", "contact.pressure_allowable")
CONFIDENCE = 0.95


@dataclass(frozen=True)
class ShockSpec:
    """What a shock study runs: `scene` (already at rest), the pulse, its start, the directions
    of the frame's acceleration (degrees, counter-clockwise from the global X axis: 90 = the
    frame accelerates upward, as when a falling device hits the floor), the models, the horizon
    and the communication step."""

    scene: Scene
    pulse: Pulse
    directions: tuple[float, ...]
    models: tuple[str, ...]
    start: float
    stop_time: float
    step: float

    @property
    def rtol(self) -> float:
        return self.scene.integrator.rtol


def at_rest(scene: Scene) -> Scene:
    """The scene with body 1 at rest relative to the frame at its start configuration."""
    return replace(scene, u0=(0.0, 0.0, 0.0))


def directions(n: int) -> tuple[float, ...]:
    """n directions evenly over 360 degrees, from 0."""
    return tuple(360.0 * k / n for k in range(n))


def pulse_parameters(spec: ShockSpec, direction: float) -> dict[str, Any]:
    """The FMU parameters of the pulse in one direction (degrees)."""
    return {
        "shock.peak": spec.pulse.peak,
        "shock.duration": spec.pulse.duration,
        "shock.start": spec.start,
        "shock.angle": math.radians(direction),
        "flexure.track_stress_peak": True,
    }


def allowables(scene: Scene) -> dict[str, float]:
    """The scene's allowable flexure stress and contact pressure, Pa."""
    return nominal_values(scene, list(ALLOWABLES))


def direction_tasks(spec: ShockSpec) -> list[Task]:
    """One task per model and direction (signals off: the reductions are what is kept)."""
    tasks = []
    for model in spec.models:
        for d in spec.directions:
            tasks.append(
                Task(
                    scene=spec.scene,
                    model=model,
                    parameters=tuple(sorted(pulse_parameters(spec, d).items())),
                    stop_time=spec.stop_time,
                    output_interval=spec.step,
                    interface="cs",
                    signals=False,
                    meta=(("direction", d),),
                )
            )
    return tasks


def margin(peak: float, allowable: float) -> float:
    """1 - peak / allowable (docs/model.md Eq. (14.7))."""
    return 1.0 - peak / allowable


def direction_row(task: Task, summary: dict[str, Any], allow: dict[str, float]) -> dict[str, Any]:
    """One direction of shock.json, from its run's summary: the peak flexure stress and contact
    pressure, their margins against the allowables and the pass (both margins >= 0), the
    contacts, the first contact, the peak normal force and the steps."""
    stress, pressure = summary["peak_flexure_stress"], summary["peak_contact_pressure"]
    m_f = margin(stress, allow["flexure.stress_allowable"])
    m_c = margin(pressure, allow["contact.pressure_allowable"])
    return {
        "direction": dict(task.meta)["direction"],
        "flexure_stress": stress,
        "contact_pressure": pressure,
        "flexure_margin": m_f,
        "contact_margin": m_c,
        "passed": bool(m_f >= 0.0 and m_c >= 0.0),
        "contacts": summary["contacts"],
        "first_contact": summary["first_contact"],
        "peak_F_N": summary["peak_F_N"],
        "steps": summary["steps"],
    }


def analyse_directions(
    spec: ShockSpec, tasks: Sequence[Task], store: ResultStore
) -> dict[str, Any]:
    """Per model: for each direction the peak flexure stress and contact pressure, their margins
    and pass (both margins >= 0); the worst direction (smallest margin of either) and the
    verdict over all directions."""
    allow = allowables(spec.scene)
    out: dict[str, Any] = {"allowables": allow, "models": {}}
    for model in spec.models:
        rows = [direction_row(t, store.summary(t.key), allow) for t in tasks if t.model == model]
        rows.sort(key=lambda r: r["direction"])
        worst = min(rows, key=lambda r: min(r["flexure_margin"], r["contact_margin"]))
        out["models"][model] = {
            "directions": rows,
            "worst_direction": worst["direction"],
            "worst_flexure_stress_direction": max(rows, key=lambda r: r["flexure_stress"])[
                "direction"
            ],
            "worst_contact_pressure_direction": max(rows, key=lambda r: r["contact_pressure"])[
                "direction"
            ],
            "max_flexure_stress": max(r["flexure_stress"] for r in rows),
            "max_contact_pressure": max(r["contact_pressure"] for r in rows),
            "min_flexure_margin": min(r["flexure_margin"] for r in rows),
            "min_contact_margin": min(r["contact_margin"] for r in rows),
            "passed": all(r["passed"] for r in rows),
            "failed_directions": [r["direction"] for r in rows if not r["passed"]],
        }
    out["passed"] = all(m["passed"] for m in out["models"].values())
    return out


def time_series(
    spec: ShockSpec, model: str, direction: float, step: float
) -> dict[str, np.ndarray]:
    """One run on a communication grid of `step`, for the figures: time, the frame's
    acceleration, the flexure stress and contact pressure at the points and their peaks over
    each step (the same peaks as the study's run: they do not depend on the grid)."""
    from ...runners.cs_batch import cs_batch

    b = cs_batch(
        spec.scene,
        model,
        [pulse_parameters(spec, direction)],
        stop_time=spec.stop_time,
        communication_step=step,
        record=True,
    )
    tr = b.trajectory(0)
    return {
        name: np.asarray(tr[name])
        for name in (
            "t",
            "a_frame_x",
            "a_frame_y",
            "stress",
            "stress_peak",
            "pressure",
            "pressure_peak",
            "F_N_peak",
        )
    }


# ------------------------------------------------------------------------------------------
# Monte Carlo over tolerances


def clopper_pearson(k: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """The Clopper-Pearson ("exact") two-sided interval of a binomial proportion, k successes in
    n trials (docs/model.md Eq. (14.11)): it covers the true probability with at least
    `confidence` whatever it is (it is conservative); [0, 1 - (alpha/2)^(1/n)] for k = 0."""
    from scipy.stats import beta

    if n < 1 or not 0 <= k <= n:
        raise ValueError(f"k = {k}, n = {n}: need 0 <= k <= n, n >= 1")
    alpha = 1.0 - confidence
    lo = 0.0 if k == 0 else float(beta.ppf(alpha / 2, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(1 - alpha / 2, k + 1, n - k))
    return lo, hi


def montecarlo_tasks(
    spec: ShockSpec,
    samples: Sequence[dict[str, float]],
    nominal: dict[str, float],
    worst: dict[str, float],
) -> list[Task]:
    """Per model, the nominal run and one run per sample, all at that model's direction
    `worst[model]` (degrees). The nominal run sets the tolerance parameters to their nominal
    values, so that every run of a model sets the same variables (one batch)."""
    tasks = []
    for model in spec.models:
        d = worst[model]
        base = pulse_parameters(spec, d)
        for k, values in [(-1, nominal), *enumerate(samples)]:
            tasks.append(
                Task(
                    scene=spec.scene,
                    model=model,
                    parameters=tuple(sorted({**base, **values}.items())),
                    stop_time=spec.stop_time,
                    output_interval=spec.step,
                    interface="cs",
                    signals=False,
                    meta=(("run", k), ("direction", d)),
                )
            )
    return tasks


def analyse_montecarlo(
    spec: ShockSpec,
    samples: Sequence[dict[str, float]],
    tasks: Sequence[Task],
    store: ResultStore,
    confidence: float = CONFIDENCE,
) -> dict[str, Any]:
    """Per model: the peak stresses of every sample, and the probability of exceeding each
    allowable (and either) with its Clopper-Pearson interval. A toleranced allowable is the
    sample's own value."""
    allow = allowables(spec.scene)
    out: dict[str, Any] = {"confidence": confidence, "interval": "Clopper-Pearson", "models": {}}
    for model in spec.models:
        runs = sorted(
            (t for t in tasks if t.model == model and dict(t.meta)["run"] >= 0),
            key=lambda t: dict(t.meta)["run"],
        )
        nominal = next(t for t in tasks if t.model == model and dict(t.meta)["run"] == -1)
        stress = np.array([store.summary(t.key)["peak_flexure_stress"] for t in runs])
        pressure = np.array([store.summary(t.key)["peak_contact_pressure"] for t in runs])
        a_f = np.array([s.get(ALLOWABLES[0], allow[ALLOWABLES[0]]) for s in samples])
        a_c = np.array([s.get(ALLOWABLES[1], allow[ALLOWABLES[1]]) for s in samples])
        exceed = {
            "flexure": stress > a_f,
            "contact": pressure > a_c,
        }
        exceed["either"] = exceed["flexure"] | exceed["contact"]
        n = len(runs)
        probabilities = {}
        for what, flags in exceed.items():
            k = int(np.sum(flags))
            lo, hi = clopper_pearson(k, n, confidence)
            probabilities[what] = {"exceeded": k, "runs": n, "p": k / n, "low": lo, "high": hi}
        ns = store.summary(nominal.key)
        out["models"][model] = {
            "direction": dict(nominal.meta)["direction"],
            "nominal": {
                "flexure_stress": ns["peak_flexure_stress"],
                "contact_pressure": ns["peak_contact_pressure"],
            },
            "flexure_stress": _stats(stress),
            "contact_pressure": _stats(pressure),
            "probability": probabilities,
            "values": {
                "flexure_stress": [float(v) for v in stress],
                "contact_pressure": [float(v) for v in pressure],
            },
        }
    return out


def _stats(v: np.ndarray) -> dict[str, float]:
    q = np.percentile(v, [5, 50, 95, 99]) if len(v) else [math.nan] * 4
    return {
        "mean": float(np.mean(v)),
        "std": float(np.std(v, ddof=1)) if len(v) > 1 else 0.0,
        "min": float(np.min(v)),
        "max": float(np.max(v)),
        "p05": float(q[0]),
        "median": float(q[1]),
        "p95": float(q[2]),
        "p99": float(q[3]),
    }


def check_models(models: Sequence[str]) -> tuple[str, ...]:
    """The event-driven models of a shock study (Moreau has no stress peaks: refused)."""
    for m in models:
        if m not in model_info.LAWS:
            raise ParameterError(
                f"model {m!r} is not an event-driven model (shock: {', '.join(model_info.LAWS)})"
            )
    return tuple(dict.fromkeys(models))
