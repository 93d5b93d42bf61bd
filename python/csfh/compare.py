"""The paper's four-model comparison (section 6): run the scene's models and write tables, a
summary and the figures."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from . import plots
from .results import Trajectory, write_json
from .scene import Scene
from .simulate import simulate


@dataclass
class Comparison:
    """What :func:`compare` ran and wrote: the scene, one :class:`Trajectory` per model, and
    the files (CSV, summary.json, figures)."""

    scene: Scene
    runs: list[Trajectory]
    files: list[Path]


def compare(
    scene: Scene,
    out: Path,
    *,
    models: tuple[str, ...] | None = None,
    interface: str = "me",
    quiet: bool = True,
) -> Comparison:
    """Run every model of the comparison and write, into `out`:
    <model>.csv (t, x, y, theta, vx, vy, omega, F_N, F_T, indentation, v_T, gap, energy),
    summary.json, and the figures (paper Figs. 6-12)."""
    out.mkdir(parents=True, exist_ok=True)
    models = models or scene.models
    runs = [simulate(scene, m, interface=interface, quiet=quiet) for m in models]
    files: list[Path] = []
    for tr in runs:
        path = out / f"{tr.model}.csv"
        tr.write_csv(path)
        files.append(path)
    summary = {
        "scene": scene.name,
        "description": scene.description,
        "preset": scene.preset,
        "stop_time": scene.stop_time,
        "q0": list(scene.q0),
        "models": {tr.model: tr.summary() for tr in runs},
        "notes": {
            "Moreau F_N, F_T": "largest per-step impulse / h in each output interval (scales "
            "as 1/h); impulses are in the CSV as Lambda_N, Lambda_T",
            "steps": "integrator steps (CVODE internal steps; Moreau steps)",
            "rhs_evaluations": "model right-hand-side evaluations, including CVODE's "
            "difference-quotient Jacobian; Moreau: one force evaluation "
            "per step",
        },
    }
    path = out / "summary.json"
    write_json(path, summary)
    files.append(path)
    delta = _clearance(scene)
    title = f"scene {scene.name}: {scene.description}"
    files.append(plots.time_histories(runs, out / "time_histories.png", title))
    files.append(plots.central_impact(runs, out / "y_and_normal_force.png", title))
    files.append(plots.first_contact(runs, out / "first_contact.png", title))
    files.append(plots.friction_steps(runs, out / "friction_vs_step.png", title))
    files.append(plots.trajectory(runs, out / "trajectory.png", title, delta))
    return Comparison(scene=scene, runs=runs, files=files)


def _clearance(scene: Scene) -> float:
    values = scene.parameter_values()
    r1 = float(values.get("contact.R1", 0.18))
    r2 = float(values.get("contact.R2", 0.20))
    return r2 - r1
