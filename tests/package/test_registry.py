"""The runners' registry (csfh.runners.registry): every model and interface finds its runner, the
unknown ones are refused by name, and both entry points that run models, csfh.simulate and the
batch tasks, go through it (a runner replaced in the registry is the one they call)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from csfh.batch.tasks import Task, batch_group, run_alone, run_chunk, task_key
from csfh.errors import ParameterError
from csfh.model import model_info
from csfh.model.scene import load_scene
from csfh.runners import registry
from csfh.runners.registry import RUNNERS, TrajectoryRuns, runner_for
from csfh.runners.simulate import simulate
from csfh.trajectory import Trajectory


@pytest.mark.parametrize("law", model_info.LAWS)
@pytest.mark.parametrize("interface", ["me", "cs", "rk4"])
def test_every_law_runs_by_every_interface(law: str, interface: str) -> None:
    runner = runner_for(law, interface)
    assert runner.interface == interface and law in runner.models


@pytest.mark.parametrize("interface", ["me", "cs", "rk4", "core"])
def test_moreau_runs_in_the_core_whatever_the_interface(interface: str) -> None:
    assert runner_for("Moreau", interface) is RUNNERS["core"]


def test_the_laws_do_not_run_in_the_moreau_stepper() -> None:
    with pytest.raises(ParameterError, match="'LN_spheres' does not run by interface 'core'"):
        runner_for("LN_spheres", "core")


@pytest.mark.parametrize(
    ("model", "interface", "message"),
    [
        ("Hertz", "me", "unknown model 'Hertz'"),
        ("LN_spheres", "fmi4", "unknown interface 'fmi4'"),
    ],
)
def test_unknown_models_and_interfaces_are_named(model: str, interface: str, message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        runner_for(model, interface)
    with pytest.raises(ParameterError, match=message):
        simulate("central", model, interface=interface)


def test_every_runner_declares_what_the_protocol_needs() -> None:
    for key, runner in RUNNERS.items():
        assert runner.interface == key
        assert runner.models and set(runner.models) <= set(model_info.MODELS)
        for attribute in ("batches", "same_parameters", "exclusive"):
            assert isinstance(getattr(runner, attribute), bool), (key, attribute)
        assert callable(runner.run) and callable(runner.run_many)
    # every model has a runner, and Moreau exactly one
    assert {m for r in RUNNERS.values() for m in r.models} == set(model_info.MODELS)
    assert [r.interface for r in RUNNERS.values() if "Moreau" in r.models] == ["core"]


class FakeRunner:
    """A runner that records its calls and returns a fixed trajectory."""

    interface = "me"
    models = model_info.LAWS
    batches = False
    same_parameters = False
    exclusive = False

    def __init__(self) -> None:
        self.calls: list[tuple[str, str, dict[str, Any]]] = []

    def trajectory(self, model: str) -> Trajectory:
        t = np.linspace(0.0, 0.01, 11)
        table = {c: np.zeros_like(t) for c in ("x", "y", "theta", "F_N", "F_T", "indentation")}
        tr = Trajectory(model=model, scene="fake", table={"t": t, **table}, contacts=np.zeros(0))
        tr.stats = {"steps": 7, "wall_time": 0.5}
        return tr

    def run(self, scene: Any, model: str, **options: Any) -> Trajectory:
        self.calls.append(("run", model, options))
        return self.trajectory(model)

    def run_many(self, scene: Any, model: str, parameter_sets: Any, **options: Any) -> Any:
        self.calls.append(("run_many", model, {"sets": list(parameter_sets), **options}))
        return TrajectoryRuns([self.trajectory(model) for _ in parameter_sets])


@pytest.fixture
def fake(monkeypatch: pytest.MonkeyPatch) -> FakeRunner:
    runner = FakeRunner()
    monkeypatch.setitem(registry.RUNNERS, "me", runner)
    return runner


def test_simulate_goes_through_the_registry(fake: FakeRunner) -> None:
    tr = simulate("central", "LN_cylinders", stop_time=0.01)
    assert tr.scene == "fake" and tr.stats["steps"] == 7
    [(kind, model, options)] = fake.calls
    assert (kind, model, options["stop_time"]) == ("run", "LN_cylinders", 0.01)


def test_the_batch_tasks_go_through_the_registry(fake: FakeRunner) -> None:
    scene = load_scene("central")
    task = Task(scene=scene, model="LN_spheres", stop_time=0.01, output_interval=1e-3)
    [(key, summary, signals, wall)] = run_chunk([task])
    assert key == task.key and summary["steps"] == 7 and wall == 0.5
    assert signals is not None and set(signals) == {"x", "y", "theta", "F_N", "F_T"}
    kind, model, options = fake.calls[-1]
    assert (kind, model, options["sets"], options["stop_time"]) == (
        "run_many",
        "LN_spheres",
        [{}],
        0.01,
    )
    assert run_alone(task)[1] == summary
    assert fake.calls[-1][0] == "run"


def test_batch_groups_follow_the_runners() -> None:
    scene = load_scene("central")

    def task(model: str, interface: str, **parameters: float) -> Task:
        return Task(
            scene=scene,
            model=model,
            interface=interface,
            parameters=tuple(sorted(parameters.items())),
        )

    assert batch_group(task("LN_spheres", "me")) is None
    assert batch_group(task("LN_spheres", "rk4")) is None
    # the batch master sets the same variables in every run: a group per parameter set's names
    cs = batch_group(task("LN_spheres", "cs", **{"contact.cr": 0.5}))
    assert cs == batch_group(task("LN_spheres", "cs", **{"contact.cr": 0.7}))
    assert cs != batch_group(task("LN_spheres", "cs", **{"friction.fd": 0.1}))
    # Moreau batches any overrides together, whatever interface the task names
    moreau = batch_group(task("Moreau", "me", **{"contact.cr": 0.5}))
    assert moreau is not None and moreau == batch_group(task("Moreau", "cs", **{"body1.m": 9.0}))
    # the key names the runner that computes the task (Moreau: the core)
    assert task_key(task("Moreau", "me")) == task_key(task("Moreau", "cs"))
    assert task_key(task("LN_spheres", "me")) != task_key(task("LN_spheres", "cs"))
