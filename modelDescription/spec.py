"""Reading and checking a variables file (variables.toml, combdrive.toml): the one description of
an FMU's interface that every generated file is written from (generate.py)."""

from __future__ import annotations

import hashlib
import math
import os
import re
import time
import tomllib
import uuid
from pathlib import Path
from typing import Any

Spec = dict[str, Any]

STATES_DEFAULT = "states"
"""`depends` of a variable that names none: it depends on every state."""
NOT_IN_GUID = ("harness", "abi")
"""Tables about the Python harness and the libraries' ABIs, not about the FMU: outside the GUID,
which changes only with the FMU's interface."""
VERSION_FILE = Path(__file__).resolve().parents[1] / "python" / "csfh" / "_version.py"


class SpecError(Exception):
    pass


def parse_range(text: str) -> tuple[float, float, bool, bool]:
    """ "(lo, hi]" -> (lo, hi, lo_open, hi_open); "inf" and "-inf" for an unbounded end."""
    m = re.fullmatch(r"\s*([\[(])\s*([^,]+?)\s*,\s*([^,]+?)\s*([\])])\s*", text)
    if not m:
        raise SpecError(f"bad range {text!r}")
    lo = float(m.group(2)) if m.group(2) != "-inf" else -math.inf
    hi = float(m.group(3)) if m.group(3) != "inf" else math.inf
    return lo, hi, m.group(1) == "(", m.group(4) == ")"


# the dependenciesKind values of FMI 2.0 (FMI 3.0 has the same and "independent")
DEPENDENCY_KINDS = ("dependent", "constant", "fixed", "tunable", "discrete")


def c_ident(name: str) -> str:
    """body1.x -> BODY1_X, der(body1.x) -> DER_BODY1_X, F_ext[1] -> F_EXT_1."""
    return re.sub(r"[^0-9A-Za-z]+", "_", name).strip("_").upper()


def c_names(spec: Spec) -> tuple[str, str, str, str]:
    """(prefix, PREFIX, struct, include) of the model's C side ([model] c_* keys, csfh default)."""
    model = spec["model"]
    prefix = model.get("c_prefix", "csfh")
    return (
        prefix,
        prefix.upper(),
        model.get("c_struct", "csfh_model_t"),
        model.get("c_include", "csfh_model.h"),
    )


def states(spec: Spec) -> list[str]:
    return [v["name"] for v in spec["variables"] if v.get("state")]


def dependencies(spec: Spec, v: dict[str, Any]) -> list[str]:
    """The names `v` depends on (ModelStructure): its `depends`, else every state."""
    d = v.get("depends", STATES_DEFAULT)
    return states(spec) if d == STATES_DEFAULT else list(d)


def quantity_of(spec: Spec, v: dict[str, Any]) -> str | None:
    """A Real's physical quantity: its own, else its unit's ([[units]] quantity)."""
    if v["type"] != "Real":
        return None
    units = {u["name"]: u for u in spec.get("units", [])}
    return v.get("quantity", units.get(v.get("unit", ""), {}).get("quantity"))


def _check_variable(v: dict[str, Any], enums: dict[str, Any], units: dict[str, Any]) -> None:
    name = v["name"]
    if v["type"] == "Enumeration" and v.get("declaredType") not in enums:
        raise SpecError(f"{name}: unknown declaredType {v.get('declaredType')}")
    if "unit" in v and v["unit"] not in units:
        raise SpecError(f"{name}: unit {v['unit']} not declared")
    if "range" in v:
        parse_range(v["range"])
    for dep, kind in v.get("depends_kind", {}).items():
        if dep not in v.get("depends", []) or kind not in DEPENDENCY_KINDS:
            raise SpecError(
                f"{name}: depends_kind {dep} = {kind} (a name of depends, one of "
                f"{', '.join(DEPENDENCY_KINDS)})"
            )


def _check_variables(spec: Spec) -> None:
    variables = spec["variables"]
    enums = {e["name"]: e for e in spec.get("enumerations", [])}
    units = {u["name"]: u for u in spec.get("units", [])}
    seen_vr: dict[int, str] = {}
    seen_name: set[str] = set()
    for v in variables:
        name = v["name"]
        if name in seen_name:
            raise SpecError(f"duplicate variable name {name}")
        seen_name.add(name)
        # FMI 2.0 value references are unique per base type; we keep them unique overall
        if v["vr"] in seen_vr:
            raise SpecError(
                f"value reference {v['vr']} of {name} already used by {seen_vr[v['vr']]}"
            )
        seen_vr[v["vr"]] = name
        _check_variable(v, enums, units)
    for e in enums.values():
        values = [it["value"] for it in e["items"]]
        if values != list(range(1, len(values) + 1)):
            raise SpecError(f"enumeration {e['name']} must be numbered 1..N in order")
    by_name = {v["name"]: v for v in variables}
    for v in variables:
        if "derivative_of" in v and not by_name.get(v["derivative_of"], {}).get("state"):
            raise SpecError(f"{v['name']}: derivative_of must name a state")
        for d in v.get("depends", []):
            if d not in by_name:
                raise SpecError(f"{v['name']}: depends on unknown variable {d}")


def _check_event_indicators(spec: Spec) -> None:
    """FMI 3.0 declares each event indicator as a variable: [model] event_indicator_variables."""
    model = spec["model"]
    by_name = {v["name"]: v for v in spec["variables"]}
    indicators = list(model.get("event_indicator_variables", []))
    if len(indicators) != model["numberOfEventIndicators"]:
        raise SpecError(
            f"[model] event_indicator_variables names {len(indicators)} variables, "
            f"numberOfEventIndicators is {model['numberOfEventIndicators']}"
        )
    for name in indicators:
        if name not in by_name or by_name[name]["type"] != "Real":
            raise SpecError(f"event indicator {name!r} is not a Real variable")


def _check_tables(spec: Spec) -> None:
    """[default_experiment] with a tolerance is required (the FMU's default); [harness] and
    [abi] hold numbers under lower-case names (generated as constants)."""
    experiment = spec.get("default_experiment")
    if not isinstance(experiment, dict) or "tolerance" not in experiment:
        raise SpecError("[default_experiment] with a tolerance is required")
    for table in NOT_IN_GUID:
        for key, value in spec.get(table, {}).items():
            if not re.fullmatch(r"[a-z][a-z0-9_]*", key):
                raise SpecError(f"[{table}] {key}: a key must be a lower-case identifier")
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise SpecError(f"[{table}] {key} = {value!r} is not a number")
    for key, value in spec.get("abi", {}).items():
        if not isinstance(value, int):
            raise SpecError(f"[abi] {key} = {value!r} is not an integer")


def constants(spec: Spec) -> dict[str, int | float]:
    """The values both sides of a boundary must agree on, by the name of their constant (C adds
    the model's prefix): [default_experiment] as DEFAULT_START_TIME ..., [harness] keys in
    capitals, [abi] keys as NAME_ABI_VERSION."""
    experiment = spec["default_experiment"]
    out: dict[str, int | float] = {
        "DEFAULT_" + re.sub(r"(?<!^)(?=[A-Z])", "_", k).upper(): float(v)
        for k, v in experiment.items()
    }
    out |= {k.upper(): v for k, v in spec.get("harness", {}).items()}
    out |= {f"{k.upper()}_ABI_VERSION": v for k, v in spec.get("abi", {}).items()}
    return out


def load(path: Path) -> Spec:
    """The variables file, checked (SpecError naming what is wrong)."""
    with path.open("rb") as f:
        spec = tomllib.load(f)
    _check_variables(spec)
    _check_event_indicators(spec)
    _check_tables(spec)
    return spec


def build_epoch(given: int | None) -> int:
    """The generation time: given, else $SOURCE_DATE_EPOCH (reproducible builds), else now."""
    if given is not None:
        return given
    env = os.environ.get("SOURCE_DATE_EPOCH", "")
    if env:
        try:
            return int(env)
        except ValueError:
            raise SpecError(f"SOURCE_DATE_EPOCH = {env!r} is not an integer") from None
    return int(time.time())


def guid_of(spec: Spec) -> str:
    """A digest of the FMU's interface (the spec without the NOT_IN_GUID tables)."""
    interface = {k: v for k, v in spec.items() if k not in NOT_IN_GUID}
    digest = hashlib.sha256(repr(interface).encode()).hexdigest()
    return "{" + str(uuid.UUID(digest[:32])) + "}"


def package_version(path: Path = VERSION_FILE) -> str:
    """The version in python/csfh/_version.py (`__version__ = "X.Y.Z"`)."""
    m = re.search(r'^__version__ = "(\d+\.\d+\.\d+)"$', path.read_text(encoding="utf-8"), re.M)
    if m is None:
        raise SpecError(f'{path}: no line __version__ = "X.Y.Z"')
    return m.group(1)
