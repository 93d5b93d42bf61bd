"""What a sweep runs: the scene, models, parameters and horizon (SweepSpec), and its tasks, the
nominal run and a step in each direction per parameter and model."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ...batch.tasks import Task
from ...model.instance import nominal_values
from ...model.scene import Scene
from .parameters import ALL_PARAMETERS, SweepParameter


@dataclass(frozen=True)
class SweepSpec:
    scene: Scene
    models: tuple[str, ...]
    parameters: tuple[str, ...]
    stop_time: float
    output_interval: float
    interface: str = "me"


def rest_shift(scene: Scene, p: SweepParameter, direction: int) -> tuple[float, float]:
    """How far the paper's Eq. (4) moves the rest position of G1 when the step changes rho or
    beta with the root C2 and the attachment s-bar fixed: r0 = f + h - s-bar, h the chord from
    the root to the tip, h = rho [e(phi_root + beta) - e(phi_root)] in our layout (the paper's
    Eq. (2) rotated by +90 deg, docs/model.md §1.2)."""
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
        common: dict[str, Any] = {
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
