"""The stress cases (docs/model.md §8): contact stiffness, impact speed, restitution,
clearance, a grazing impact, resting contact, high friction, stick-slip and an eccentric mass
centre, each with its scene, the runs (model, integrator) it applies to, and its check. The cases
are data, cases.toml beside this module (its header describes the keys); this module reads
them."""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from typing import Any

from ...model.scene import Scene, scene_from_dict
from . import checks
from .checks import Check

CASES_FILE = "cases.toml"
COMPLIANT_INTEGRATORS = ("ME", "CS", "CS-RK45", "RK4")
CHECKS: dict[str, Callable[..., Check]] = {
    "hertz": checks.hertz_check,
    "restitution": checks.restitution_check,
    "clearance": checks.clearance_check,
    "friction_bound": checks.friction_bound_check,
    "no_extra": lambda: checks.no_extra_check,
    "grazing": lambda: checks.grazing_check,
    "resting": lambda: checks.resting_check,
    "stickslip": lambda: checks.stickslip_check,
}
"""Each check of the cases by its `kind`: a factory taking the check's arguments."""
_KEYS = {
    "name",
    "group",
    "description",
    "quick",
    "models",
    "check",
    "scene",
    "t_contact",
    "t_contact_by_model",
    "energy_gain_allowed",
}


@dataclass
class Case:
    name: str
    group: str
    description: str
    scene: Scene
    runs: list[tuple[str, str]]  # (model, integrator)
    check: Check
    energy_gain_allowed: float = 0.0  # J, beyond the integrator tolerance
    quick: bool = False
    t_contact: float | None = None  # shortest expected contact duration, s (RK4 resolution)
    t_contact_by_model: dict[str, float] = field(default_factory=dict)


def runs_of(models: list[str]) -> list[tuple[str, str]]:
    """The runs of a case: each compliant model with every integrator, Moreau with its own."""
    out: list[tuple[str, str]] = []
    for m in models:
        out += [("Moreau", "Moreau")] if m == "Moreau" else [(m, i) for i in COMPLIANT_INTEGRATORS]
    return out


def _case(entry: dict[str, Any], contact_times: dict[str, dict[str, float]]) -> Case:
    unknown = sorted(set(entry) - _KEYS)
    if unknown:
        raise ValueError(f"{CASES_FILE}: case {entry.get('name')!r}: unknown key {unknown[0]!r}")
    check = dict(entry["check"])
    scene = entry["scene"]
    return Case(
        name=entry["name"],
        group=entry["group"],
        description=entry["description"],
        scene=scene_from_dict(scene, f"stress:{scene['name']}"),
        runs=runs_of(entry["models"]),
        check=CHECKS[check.pop("kind")](**check),
        energy_gain_allowed=float(entry.get("energy_gain_allowed", 0.0)),
        quick=bool(entry["quick"]),
        t_contact=entry.get("t_contact"),
        t_contact_by_model=dict(contact_times.get(entry.get("t_contact_by_model", ""), {})),
    )


def build_cases(quick: bool = False) -> list[Case]:
    """Every case of cases.toml, in its order (`quick`: the reduced suite's)."""
    text = resources.files(__package__).joinpath(CASES_FILE).read_text("utf-8")
    data = tomllib.loads(text)
    cases = [_case(entry, data.get("contact_times", {})) for entry in data["case"]]
    return [c for c in cases if c.quick] if quick else cases


def select_cases(quick: bool = False, only: str | None = None) -> list[Case]:
    """The cases to run: all, or the reduced suite (`quick`, as in CI), and of those the ones
    whose name contains `only` or whose group is `only`."""
    cases = build_cases(quick)
    if only:
        cases = [c for c in cases if only in c.name or only == c.group]
    return cases
