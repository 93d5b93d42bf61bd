"""A design's evaluation: its parameter overrides, its shock runs (one task per direction, the
same tasks `csfh shock` runs on the design's scene file), and its measures.

Per direction, as shock.json gives them: the peak flexure stress and contact pressure with
their margins (docs/model.md Eq. (14.7)), the contacts, and the settling time, the end of the
last contact (after it body 1 swings on the flexure without impacts; the horizon when a contact
is still on at the end, 0 without contact). Over the directions, every objective is the worst
(largest) value and every margin the smallest. The parasitic motion is the static displacement
of the centre G1 under the study's nominal moment (the flexure's elastic force, gravity and the
scene's inputs in equilibrium, docs/model.md §2.4; contact is not part of it), from the C core in
this process: it is deterministic wherever the shock runs are computed."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ...batch.store import ResultStore
from ...batch.tasks import Task
from ...errors import ParameterError, SimulationError
from ...model.instance import core_model, nominal_values
from ...model.scene import Scene
from ..execution import Execution, counts, execute
from ..shock import STEP_FACTOR
from ..shock import study as shock
from .spec import CLEARANCE, DesignStudy, StudyError


def shock_spec(study: DesignStudy, scene: Scene) -> shock.ShockSpec:
    """The shock study `csfh shock SCENE --condition C --direction D` runs, over the study's
    directions with its one law (the scene at rest, the default horizon and step)."""
    scene = shock.at_rest(scene)
    return shock.ShockSpec(
        scene=scene,
        pulse=study.pulse,
        directions=study.directions,
        models=(study.law,),
        start=0.0,
        stop_time=scene.stop_time,
        step=STEP_FACTOR * scene.integrator.output_interval,
    )


def parameters_of(study: DesignStudy, r2: float, x: Sequence[float]) -> dict[str, float]:
    """The FMU parameter overrides of design x (the clearance sets R1 = R2 - clearance)."""
    out = {}
    for name, value in zip(study.names, x, strict=True):
        if name == CLEARANCE:
            out["contact.R1"] = r2 - float(value)
        else:
            out[name] = float(value)
    return out


NEWTON_STEPS = 30
"""The most Newton steps of a static equilibrium (it converges in a few: the elastic force is
smooth and nearly linear in the small displacements of a nominal load)."""


def equilibrium(
    forces: Callable[[np.ndarray], np.ndarray], q: np.ndarray, scale: np.ndarray
) -> np.ndarray:
    """The q where forces(q) = 0, by Newton's method from q with a central-difference Jacobian
    (steps 1e-7 scale), until a step is below 1e-13 scale in every coordinate."""
    q = np.array(q, dtype=float)
    h = 1e-7 * scale
    for _ in range(NEWTON_STEPS):
        jac = np.empty((3, 3))
        for j in range(3):
            e = np.zeros(3)
            e[j] = h[j]
            jac[:, j] = (forces(q + e) - forces(q - e)) / (2 * h[j])
        dq = np.linalg.solve(jac, -forces(q))
        q += dq
        if np.all(np.abs(dq) <= 1e-13 * scale):
            return q
    raise SimulationError(f"no static equilibrium found from q = {q.tolist()}")


def parasitic(scene: Scene, values: dict[str, Any], moment: float) -> dict[str, float]:
    """The static displacement of G1 caused by the moment `moment` about it: the equilibria
    Q(q) + [0, 0, M] = 0 with M = moment and M = 0 (the C core's smooth forces: the flexure's
    elastic force, gravity and the scene's inputs), the distance between their centres and the
    rotation."""
    model = core_model(scene, values)
    length = model.get("contact.R2")
    scale = np.array([length, length, 1.0])
    q0 = np.array(scene.q0, dtype=float)

    def loaded(m: float) -> Callable[[np.ndarray], np.ndarray]:
        load = np.array([0.0, 0.0, m])
        return lambda q: np.asarray(model.smooth_forces(q)) + load

    ends = [equilibrium(loaded(m), q0, scale) for m in (0.0, moment)]
    d = ends[1] - ends[0]
    return {"parasitic": float(math.hypot(d[0], d[1])), "rotation": float(d[2])}


@dataclass
class Evaluator:
    """Evaluates designs of a study on a scene through the batch engine into `store`."""

    study: DesignStudy
    scene: Scene
    store: ResultStore
    how: Execution
    spec: shock.ShockSpec = field(init=False)
    r2: float = field(init=False)
    allowables: dict[str, float] = field(init=False)
    runs: dict[str, int] = field(default_factory=lambda: {"tasks": 0, "computed": 0, "reused": 0})
    executor: str = ""
    _parasitic: dict[tuple[tuple[str, float], ...], dict[str, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.spec = shock_spec(self.study, self.scene)
        self.r2 = nominal_values(self.spec.scene, ["contact.R2"])["contact.R2"]
        self.allowables = shock.allowables(self.spec.scene)
        self.check_ranges()

    def check_ranges(self) -> None:
        """Each variable at both ends of its range (the others at the scene's values) set up in
        the C core with the scene's start, so that a range the model refuses (R1 >= R2, a start
        deeper in the bore than contact.max_initial_indentation, ...) is one line before
        anything runs."""
        for name, rng in self.study.variables.items():
            one = replace(self.study, variables={name: rng})
            for value in rng:
                why = self._refused(parameters_of(one, self.r2, [value]))
                if why:
                    raise StudyError(
                        f"{self.study.source}: variables.{name!r} = {value!r} is refused by "
                        f"the model: {why}"
                    )

    def _refused(self, values: dict[str, float]) -> str:
        try:
            model = core_model(self.spec.scene, values)
        except ParameterError as exc:
            return str(exc)
        depth = -model.get("contact.gap")
        limit = model.get("contact.max_initial_indentation")
        if depth > limit:
            return (
                f"the start initial.q = {list(self.spec.scene.q0)} is {depth:.6g} m deep in "
                f"the bore (> contact.max_initial_indentation = {limit:g} m)"
            )
        return ""

    def tasks(self, sets: Sequence[dict[str, float]], directions: Sequence[float]) -> list[Task]:
        """One task per parameter set (a design's overrides) and direction."""
        out = []
        for i, values in enumerate(sets):
            for d in directions:
                params = {**shock.pulse_parameters(self.spec, d), **values}
                out.append(
                    Task(
                        scene=self.spec.scene,
                        model=self.study.law,
                        parameters=tuple(sorted(params.items())),
                        stop_time=self.spec.stop_time,
                        output_interval=self.spec.step,
                        interface="cs",
                        signals=False,
                        meta=(("design", i), ("direction", d)),
                    )
                )
        return out

    def evaluate(
        self, designs: np.ndarray, label: str, directions: Sequence[float] | None = None
    ) -> list[dict[str, Any]]:
        """The measures of every design (rows of `designs`, in the variables' order)."""
        designs = np.atleast_2d(np.asarray(designs, dtype=float))
        sets = [parameters_of(self.study, self.r2, x) for x in designs]
        named = [dict(zip(self.study.names, map(float, x), strict=True)) for x in designs]
        return self.evaluate_sets(sets, named, label, directions)

    def evaluate_sets(
        self,
        sets: Sequence[dict[str, float]],
        variables: Sequence[dict[str, float]],
        label: str,
        directions: Sequence[float] | None = None,
    ) -> list[dict[str, Any]]:
        """The measures of parameter sets (overrides of the scene), each named by `variables`."""
        dirs = tuple(self.spec.directions if directions is None else directions)
        tasks = self.tasks(sets, dirs)
        report = counts(execute(tasks, self.store, self.how, label))
        for key in self.runs:
            self.runs[key] += report[key]
        if report["computed"] or not self.executor:  # the executor of the computed runs
            self.executor = report["executor"]
        n = len(dirs)
        return [
            self.measures(values, named, tasks[i * n : (i + 1) * n])
            for i, (values, named) in enumerate(zip(sets, variables, strict=True))
        ]

    def row(self, task: Task) -> dict[str, Any]:
        """One direction of a design, with the fields of shock.json's per-direction rows."""
        s = self.store.summary(task.key)
        if s["contact_at_end"]:
            settling = self.spec.stop_time
        else:
            settling = 0.0 if s["last_release"] is None else float(s["last_release"])
        return {**shock.direction_row(task, s, self.allowables), "settling_time": settling}

    def static(self, values: dict[str, float]) -> dict[str, float]:
        key = tuple(sorted(values.items()))
        if key not in self._parasitic:
            self._parasitic[key] = parasitic(
                self.spec.scene, values, self.study.parasitic_moment or 0.0
            )
        return self._parasitic[key]

    def measures(
        self, values: dict[str, float], variables: dict[str, float], tasks: Sequence[Task]
    ) -> dict[str, Any]:
        """A design's rows, worst direction, objectives, margins and feasibility."""
        rows = [self.row(t) for t in tasks]
        worst = min(rows, key=lambda r: min(r["flexure_margin"], r["contact_margin"]))
        static = self.static(values)
        margins = {
            "flexure_margin": min(r["flexure_margin"] for r in rows),
            "contact_margin": min(r["contact_margin"] for r in rows),
        }
        need = self.study.constraints
        return {
            "variables": dict(variables),
            "parameters": dict(values),
            "worst_direction": worst["direction"],
            "objectives": {
                "flexure_stress": max(r["flexure_stress"] for r in rows),
                "contact_pressure": max(r["contact_pressure"] for r in rows),
                "contacts": max(r["contacts"] for r in rows),
                "settling_time": max(r["settling_time"] for r in rows),
                "parasitic": static["parasitic"],
            },
            "rotation": static["rotation"],
            "margins": margins,
            "violation": sum(max(0.0, need[k] - margins[k]) for k in need),
            "feasible": all(margins[k] >= need[k] for k in need),
            "directions": rows,
        }
