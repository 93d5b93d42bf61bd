"""A design study as data: a TOML file of design variables, the shock, constraints, objectives,
the search and the sensitivity analysis (the keys below); built-in files for the mems and csfh
scenes (studies/SCENE.toml), any other given by path. Every key is checked when the file is
read, with one line naming the key and its value.

    [variables]                  # a parameter by name, or the clearance, with its range (SI)
    "contact.R2 - contact.R1" = [10e-6, 30e-6]   # clearance: R1 = R2 - clearance, R2 held
    "flexure.h" = [3e-6, 8e-6]

    [shock]
    condition = "JESD22-B104-B"  # or peak_g = 1500.0 and duration = 0.5e-3
    directions = 8               # evenly over 360 degrees, or a list of degrees
    law = "LN_cylinders"         # the event-driven model of the runs

    [constraints]                # a design is feasible when every margin is >= its minimum
    flexure_margin = 0.0         # 1 - peak flexure stress / flexure.stress_allowable
    contact_margin = 0.0         # 1 - peak contact pressure / contact.pressure_allowable

    [objectives]                 # all minimised
    names = ["flexure_stress", "contacts", "settling_time", "parasitic"]
    search = "flexure_stress"    # the objective of the differential-evolution search
    parasitic_moment = 1e-9      # N m: the nominal load of the parasitic motion

    [sampling]                   # scrambled Sobol points or a Latin hypercube, seeded
    method = "sobol"
    samples = 256
    seed = 1

    [search]                     # scipy's differential evolution; populations as batches
    generations = 10
    population = 8               # population size = population x number of variables
    best = 3                     # the best designs written as scene files

    [sensitivity]                # Sobol indices (SALib), N base samples: N (D + 2) runs
    samples = 64                 # 0 or a power of 2
    paper_parameters = true      # also over the paper's Table 4 parameters (+-10 % of nominal)

    [report]                     # the feasible region's two variables (default: the first two)
    axes = ["contact.R2 - contact.R1", "flexure.h"]

    [quick]                      # what --quick replaces (a run of a minute or two)
    samples = 32
    directions = 4
    generations = 3
    population = 4
    sensitivity_samples = 8
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path
from typing import Any

from ...errors import SceneError
from ...model import model_info
from ...model.scene import Scene
from ..shock import conditions
from ..shock.conditions import Pulse

CLEARANCE = "contact.R2 - contact.R1"
"""The clearance as a design variable: R1 = R2 - clearance with R2 held."""
OBJECTIVES = ("flexure_stress", "contact_pressure", "contacts", "settling_time", "parasitic")
"""What a design is measured by (evaluate.objectives); every one is minimised."""
CONSTRAINTS = ("flexure_margin", "contact_margin")
METHODS = ("sobol", "lhs")
_TABLES = {
    "variables",
    "shock",
    "constraints",
    "objectives",
    "sampling",
    "search",
    "sensitivity",
    "quick",
    "report",
}
_QUICK = {"samples", "directions", "generations", "population", "sensitivity_samples"}


class StudyError(SceneError):
    """A design study that cannot be used; the message names the file and the key."""


@dataclass(frozen=True)
class DesignStudy:
    """A parsed study (the keys of the module docstring)."""

    variables: dict[str, tuple[float, float]]
    pulse: Pulse
    directions: tuple[float, ...]
    law: str
    constraints: dict[str, float]
    objectives: tuple[str, ...]
    search_objective: str
    parasitic_moment: float
    method: str = "sobol"
    samples: int = 256
    seed: int = 1
    generations: int = 10
    population: int = 8
    best: int = 3
    sensitivity_samples: int = 64
    paper_parameters: bool = True
    source: str = ""
    quick: tuple[tuple[str, int], ...] = ()
    axes: tuple[str, ...] = ()

    @property
    def region_axes(self) -> tuple[str, str]:
        """The two variables of the feasible region's figure."""
        names = self.axes or self.names
        return (names[0], names[1]) if len(names) > 1 else (names[0], names[0])

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self.variables)

    def quick_study(self) -> DesignStudy:
        """The study with its [quick] values."""
        q = dict(self.quick)
        return replace(
            self,
            directions=_directions(q["directions"]) if "directions" in q else self.directions,
            sensitivity_samples=q.get("sensitivity_samples", self.sensitivity_samples),
            samples=q.get("samples", self.samples),
            generations=q.get("generations", self.generations),
            population=q.get("population", self.population),
            quick=(),
        )


def _finite(value: Any) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float) and math.isfinite(value)


def _table(where: str, value: Any, allowed: set[str] | None = None) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise StudyError(f"{where} must be a table")
    if allowed is not None:
        unknown = sorted(set(value) - allowed)
        if unknown:
            raise StudyError(
                f"{where}: unknown key {unknown[0]!r} (allowed: {', '.join(sorted(allowed))})"
            )
    return value


def _int(where: str, value: Any, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise StudyError(f"{where} = {value!r} must be an integer >= {minimum}")
    return value


def _range(where: str, rng: Any, positive: bool) -> tuple[float, float]:
    if not (isinstance(rng, list) and len(rng) == 2 and all(_finite(v) for v in rng)):
        raise StudyError(f"{where} = {rng!r} must be a range [low, high] of two numbers")
    lo, hi = float(rng[0]), float(rng[1])
    if not lo < hi:
        raise StudyError(f"{where} = {rng!r}: low must be < high")
    if positive and lo <= 0:
        raise StudyError(f"{where} = {rng!r}: the range must be > 0")
    return lo, hi


def _power_of_two(where: str, value: Any) -> int:
    """0 or a power of 2 (the Sobol sequence of the Saltelli sample keeps its balance only for
    those)."""
    n = _int(where, value, 0)
    if n & (n - 1):
        raise StudyError(f"{where} = {n} must be 0 or a power of 2")
    return n


def _variables(table: Any) -> dict[str, tuple[float, float]]:
    table = _table("[variables]", table)
    if not table:
        raise StudyError("[variables] must name at least one design variable")
    real = {
        n
        for n, v in model_info.variables().items()
        if v.causality == "parameter" and v.type == "Real"
    }
    out = {}
    for key, rng in table.items():
        if key != CLEARANCE and key not in real:
            raise StudyError(f"variables.{key!r} is not a real FMU parameter nor {CLEARANCE!r}")
        out[key] = _range(f"variables.{key!r}", rng, key in (CLEARANCE, "contact.R1"))
    for other in ("contact.R1", "contact.R2"):
        if CLEARANCE in out and other in out:
            raise StudyError(f"variables: give either {CLEARANCE!r} or {other!r}, not both")
    return out


def _directions(value: Any) -> tuple[float, ...]:
    if isinstance(value, list):
        if not value or not all(_finite(v) for v in value):
            raise StudyError(f"shock.directions = {value!r} must be a list of degrees")
        return tuple(float(v) % 360.0 for v in value)
    n = _int("shock.directions", value, 1)
    return tuple(360.0 * k / n for k in range(n))


def _shock(table: Any) -> tuple[Pulse, tuple[float, ...], str]:
    t = _table("[shock]", table, {"condition", "peak_g", "duration", "directions", "law"})
    if "condition" in t and ("peak_g" in t or "duration" in t):
        raise StudyError("[shock]: give either condition or peak_g and duration, not both")
    if ("peak_g" in t) != ("duration" in t):
        raise StudyError("[shock]: peak_g and duration go together")
    try:
        if "peak_g" in t:
            for key in ("peak_g", "duration"):
                if not _finite(t[key]):
                    raise StudyError(f"shock.{key} = {t[key]!r} must be a number")
            pulse = conditions.pulse(float(t["peak_g"]), float(t["duration"]))
        else:
            name = t.get("condition", conditions.DEFAULT_CONDITION)
            if not isinstance(name, str):
                raise StudyError(f"shock.condition = {name!r} must be a condition's name")
            pulse = conditions.condition(name)
    except StudyError:
        raise
    except Exception as exc:  # the conditions' own one-line ParameterError
        raise StudyError(f"[shock]: {exc}") from None
    law = t.get("law", "LN_cylinders")
    if law not in model_info.LAWS:
        raise StudyError(
            f"shock.law = {law!r} is not an event-driven model ({', '.join(model_info.LAWS)})"
        )
    return pulse, _directions(t.get("directions", 8)), law


def _constraints(table: Any) -> dict[str, float]:
    t = _table("[constraints]", table, set(CONSTRAINTS))
    out = {}
    for key in CONSTRAINTS:
        value = t.get(key, 0.0)
        if not _finite(value) or value >= 1.0:
            raise StudyError(f"constraints.{key} = {value!r} must be a number < 1")
        out[key] = float(value)
    return out


def _objectives(table: Any) -> tuple[tuple[str, ...], str, float]:
    t = _table("[objectives]", table, {"names", "search", "parasitic_moment"})
    names = t.get("names", ["flexure_stress", "contacts", "settling_time", "parasitic"])
    if not isinstance(names, list) or not names:
        raise StudyError(f"objectives.names = {names!r} must be a non-empty list")
    for n in names:
        if n not in OBJECTIVES:
            raise StudyError(f"objectives.names: {n!r} is not one of {', '.join(OBJECTIVES)}")
    search = t.get("search", names[0])
    if not isinstance(search, str) or search not in names:
        raise StudyError(f"objectives.search = {search!r} is not in objectives.names")
    moment = t.get("parasitic_moment", 0.0)
    if not _finite(moment) or ("parasitic" in names and not moment > 0):
        raise StudyError(f"objectives.parasitic_moment = {moment!r} N m must be a number > 0")
    return tuple(dict.fromkeys(names)), search, float(moment)


def _options(data: dict[str, Any]) -> dict[str, Any]:
    sampling = _table("[sampling]", data.get("sampling", {}), {"method", "samples", "seed"})
    search = _table("[search]", data.get("search", {}), {"generations", "population", "best"})
    sens = _table("[sensitivity]", data.get("sensitivity", {}), {"samples", "paper_parameters"})
    method = sampling.get("method", "sobol")
    if method not in METHODS:
        raise StudyError(f"sampling.method = {method!r} is not one of {', '.join(METHODS)}")
    paper = sens.get("paper_parameters", True)
    if not isinstance(paper, bool):
        raise StudyError(f"sensitivity.paper_parameters = {paper!r} must be true or false")
    quick = _table("[quick]", data.get("quick", {}), _QUICK)
    return {
        "method": method,
        "samples": _int("sampling.samples", sampling.get("samples", 256), 2),
        "seed": _int("sampling.seed", sampling.get("seed", 1), 0),
        "generations": _int("search.generations", search.get("generations", 10), 0),
        "population": _int("search.population", search.get("population", 8), 1),
        "best": _int("search.best", search.get("best", 3), 1),
        "sensitivity_samples": _power_of_two("sensitivity.samples", sens.get("samples", 64)),
        "paper_parameters": paper,
        "quick": tuple(sorted((k, _quick(k, v)) for k, v in quick.items())),
    }


def _axes(table: Any, variables: dict[str, Any]) -> tuple[str, ...]:
    t = _table("[report]", table, {"axes"})
    axes = t.get("axes", [])
    if not isinstance(axes, list) or len(axes) not in (0, 2) or len(set(axes)) != len(axes):
        raise StudyError(f"report.axes = {axes!r} must be two different design variables")
    for a in axes:
        if a not in variables:
            raise StudyError(f"report.axes: {a!r} is not a design variable")
    return tuple(axes)


def _quick(key: str, value: Any) -> int:
    if key == "sensitivity_samples":
        return _power_of_two(f"quick.{key}", value)
    return _int(f"quick.{key}", value, 1)


def study_from_dict(data: dict[str, Any], source: str = "<dict>") -> DesignStudy:
    """Validate a parsed study; errors name the file and the key."""
    try:
        _table("study", data, _TABLES)
        pulse, directions, law = _shock(data.get("shock", {}))
        names, search, moment = _objectives(data.get("objectives", {}))
        variables = _variables(data.get("variables", {}))
        return DesignStudy(
            variables=variables,
            axes=_axes(data.get("report", {}), variables),
            pulse=pulse,
            directions=directions,
            law=law,
            constraints=_constraints(data.get("constraints", {})),
            objectives=names,
            search_objective=search,
            parasitic_moment=moment,
            source=source,
            **_options(data),
        )
    except StudyError as exc:
        raise StudyError(f"{source}: {exc}") from None


def _builtin(scene: Scene) -> tuple[str, str] | None:
    ref = resources.files(__package__).joinpath("studies", f"{scene.name}.toml")
    if not ref.is_file():
        return None
    return ref.read_text("utf-8"), f"the built-in study of scene {scene.name}"


def load_study(scene: Scene, study: str | Path | None = None) -> DesignStudy:
    """The study of a file, or (None) the built-in study of the scene."""
    if study is None:
        found = _builtin(scene)
        if found is None:
            raise StudyError(
                f"scene {scene.name!r} has no built-in design study: give a STUDY.toml file"
            )
        text, source = found
    else:
        path = Path(study)
        if not path.is_file():
            raise StudyError(f"{path}: no such study file")
        try:
            text = path.read_text("utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise StudyError(f"{path}: cannot be read ({exc})") from None
        source = str(path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{source}: not valid TOML: {exc}") from None
    return study_from_dict(data, source)
