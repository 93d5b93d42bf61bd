"""The runners behind one protocol, as interchangeable as FMPy's solvers: each runs models of
the hinge on a scene, one at a time (`Runner.run` -> Trajectory) or many parameter sets at once
(`Runner.run_many` -> Runs), and the registry finds the runner of a model and an interface.

| interface | models | one run | many runs |
|---|---|---|---|
| ``me`` | the FMU's laws | the FMU by model exchange, CVODE (`model_exchange`) | one by one |
| ``cs`` | the FMU's laws | the FMU by co-simulation (`co_simulation`) | `cs_batch` |
| ``rk4`` | the FMU's laws | the paper's RK4 + bisection in the C core (`rk4`) | one by one |
| ``core`` | Moreau | the Moreau stepper in the C core (`moreau`) | `moreau_batch` |

A model that only one runner takes (Moreau) runs there whatever interface is asked for: a
command's --interface chooses how the FMU runs, and the Moreau stepper has no FMU."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

import numpy as np

from ..errors import ParameterError
from ..model import model_info
from ..model.scene import Scene
from ..progress import Progress
from ..trajectory import Trajectory, signals_on_grid

RUN_MANY_STEP_RECORDS = 1_000_000
"""The integrator steps a model-exchange run of `run_many` records: every step of any run
within the limits, so that its summary and signals see every peak."""


class Runs(Protocol):
    """The results of many runs of one scene and model (one per parameter set)."""

    def __len__(self) -> int: ...

    def summary(self, i: int) -> dict[str, Any]:
        """Run i as `Trajectory.summary` reports it (its keys that the run has)."""
        ...

    def signals(self, i: int, grid: np.ndarray) -> dict[str, np.ndarray]:
        """Run i's output signals on `grid` (csfh.trajectory.SIGNALS)."""
        ...

    def run_time(self, i: int) -> float:
        """Wall time of run i, s (a batch's share of its call)."""
        ...


class Runner(Protocol):
    """Runs models on scenes. `interface` is its key in the registry, `models` the models it
    runs, `batches` whether `run_many` computes a batch in one call, `same_parameters` whether
    the parameter sets of a batch must name the same parameters, `exclusive` whether one run at a
    time may use it in a process (fmpy's instances share one logger)."""

    interface: str
    models: tuple[str, ...]
    batches: bool
    same_parameters: bool
    exclusive: bool

    def run(
        self, scene: Scene, model: str, *, progress: Progress | None = None, **options: Any
    ) -> Trajectory:
        """One run; `options` as the runner's function takes them (every runner takes
        stop_time, output_interval and parameters)."""
        ...

    def run_many(
        self,
        scene: Scene,
        model: str,
        parameter_sets: Sequence[dict[str, Any] | None],
        *,
        stop_time: float,
        output_interval: float,
        record: bool,
    ) -> Runs:
        """One run per parameter set (FMU parameter overrides), up to `stop_time`, outputs every
        `output_interval` (kept for `Runs.signals` only with `record`); SimulationError if one
        fails."""
        ...


@dataclass
class TrajectoryRuns:
    """Runs made one by one, as Runs."""

    runs: list[Trajectory]

    def __len__(self) -> int:
        return len(self.runs)

    def summary(self, i: int) -> dict[str, Any]:
        return self.runs[i].summary()

    def signals(self, i: int, grid: np.ndarray) -> dict[str, np.ndarray]:
        return signals_on_grid(self.runs[i], grid)

    def run_time(self, i: int) -> float:
        return float(self.runs[i].stats.get("wall_time", 0.0))


class _OneByOne:
    """A runner without batches: `run_many` is one `run` per parameter set."""

    batches: bool = False
    same_parameters: bool = False
    run_many_options: ClassVar[dict[str, Any]] = {}

    def run(
        self, scene: Scene, model: str, *, progress: Progress | None = None, **options: Any
    ) -> Trajectory:
        raise NotImplementedError

    def run_many(
        self,
        scene: Scene,
        model: str,
        parameter_sets: Sequence[dict[str, Any] | None],
        *,
        stop_time: float,
        output_interval: float,
        record: bool,
    ) -> Runs:
        options: dict[str, Any] = {"stop_time": stop_time, "output_interval": output_interval}
        return TrajectoryRuns(
            [
                self.run(scene, model, parameters=p, **options, **self.run_many_options)
                for p in parameter_sets
            ]
        )


class ModelExchange(_OneByOne):
    interface: str = "me"
    models: tuple[str, ...] = model_info.LAWS
    exclusive: bool = True
    run_many_options: ClassVar[dict[str, Any]] = {"max_step_records": RUN_MANY_STEP_RECORDS}

    def run(
        self, scene: Scene, model: str, *, progress: Progress | None = None, **options: Any
    ) -> Trajectory:
        from .model_exchange import simulate_me

        return simulate_me(scene, model, progress=progress, **options)


class Rk4(_OneByOne):
    interface: str = "rk4"
    models: tuple[str, ...] = model_info.LAWS
    exclusive: bool = False

    def run(
        self, scene: Scene, model: str, *, progress: Progress | None = None, **options: Any
    ) -> Trajectory:
        from .rk4 import rk4_event

        return rk4_event(scene, model, **options)


class CoSimulation:
    interface: str = "cs"
    models: tuple[str, ...] = model_info.LAWS
    batches: bool = True
    same_parameters: bool = True
    exclusive: bool = True

    def run(
        self,
        scene: Scene,
        model: str,
        *,
        progress: Progress | None = None,
        output_interval: float | None = None,
        **options: Any,
    ) -> Trajectory:
        """`output_interval` is the communication step (also taken as communication_step)."""
        from .co_simulation import simulate_cs

        if output_interval is not None:
            if options.get("communication_step") is not None:
                raise ParameterError("give output_interval or communication_step, not both")
            options["communication_step"] = output_interval
        return simulate_cs(scene, model, progress=progress, **options)

    def run_many(
        self,
        scene: Scene,
        model: str,
        parameter_sets: Sequence[dict[str, Any] | None],
        *,
        stop_time: float,
        output_interval: float,
        record: bool,
    ) -> Runs:
        from .cs_batch import cs_batch

        return cs_batch(
            scene,
            model,
            parameter_sets,
            stop_time=stop_time,
            communication_step=output_interval,
            record=record,
        )


class Moreau:
    interface: str = "core"
    models: tuple[str, ...] = ("Moreau",)
    batches: bool = True
    same_parameters: bool = False
    exclusive: bool = False

    def run(
        self, scene: Scene, model: str, *, progress: Progress | None = None, **options: Any
    ) -> Trajectory:
        from .moreau import moreau

        return moreau(scene, **options)

    def run_many(
        self,
        scene: Scene,
        model: str,
        parameter_sets: Sequence[dict[str, Any] | None],
        *,
        stop_time: float,
        output_interval: float,
        record: bool,
    ) -> Runs:
        from .moreau_batch import moreau_batch

        batch = moreau_batch(
            scene, parameter_sets, stop_time=stop_time, output_interval=output_interval
        )
        batch.check(parameter_sets)
        return batch


RUNNERS: dict[str, Runner] = {
    r.interface: r for r in (ModelExchange(), CoSimulation(), Rk4(), Moreau())
}
"""Every runner by its interface."""


def runner_for(model: str, interface: str = "me") -> Runner:
    """The runner of `model` by `interface` (module docstring); ParameterError naming the model
    or the interface that no runner has."""
    if model not in model_info.MODELS:
        raise ParameterError(f"unknown model {model!r} (known: {', '.join(model_info.MODELS)})")
    runner = RUNNERS.get(interface)
    if runner is None:
        raise ParameterError(f"unknown interface {interface!r} (known: {', '.join(RUNNERS)})")
    if model in runner.models:
        return runner
    own = [r for r in RUNNERS.values() if model in r.models]
    if len(own) == 1:
        return own[0]
    raise ParameterError(f"model {model!r} does not run by interface {interface!r}")


def run(scene: Scene, model: str, interface: str = "me", **options: Any) -> Trajectory:
    """One run of `model` on `scene` by its runner (`runner_for`), `options` as it takes them."""
    return runner_for(model, interface).run(scene, model, **options)
