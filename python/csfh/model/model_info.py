"""What the FMU declares: variables, types, enumerations (read once from modelDescription.xml,
which is generated from the same table as the C code)."""

from __future__ import annotations

from functools import cache
from typing import TYPE_CHECKING

from ..paths import fmu_path

if TYPE_CHECKING:
    from fmpy.model_description import ModelDescription, ModelVariable

LAWS = ("LN_spheres", "LN_cylinders", "LN_ESDU", "HuntCrossley", "Flores")
"""Normal contact laws of the FMU's event-driven models (contact.law), besides `none`."""
MODELS = (*LAWS, "Moreau")
"""Everything `csfh run --law` accepts."""
PAPER_MODELS = ("LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau")
"""The paper's four-model comparison (section 6)."""


@cache
def model_description() -> ModelDescription:
    from fmpy import read_model_description  # here, not at import: `csfh --help` stays fast

    return read_model_description(str(fmu_path()))


@cache
def variables() -> dict[str, ModelVariable]:
    return {v.name: v for v in model_description().modelVariables}


@cache
def enumeration(type_name: str) -> dict[str, int]:
    for t in model_description().typeDefinitions:
        if t.name == type_name:
            return {item.name: int(item.value) for item in t.items}
    raise KeyError(type_name)


def parameter_names() -> list[str]:
    return [n for n, v in variables().items() if v.causality == "parameter"]


def coerce(name: str, value: object) -> float | int | bool:
    """Turn a user value into what the variable takes (enumeration items by name); raises
    ValueError naming the variable for a wrong type or an unknown item."""
    var = variables().get(name)
    if var is None:
        raise ValueError(f'unknown parameter "{name}"')
    if var.type == "Enumeration":
        items = enumeration(var.declaredType.name)
        if isinstance(value, str):
            if value not in items:
                raise ValueError(f'{name} = "{value}" is not one of {", ".join(items)}')
            return items[value]
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{name} = {value!r} must be one of {', '.join(items)}")
        return value
    if var.type == "Boolean":
        if not isinstance(value, bool):
            raise ValueError(f"{name} = {value!r} must be true or false")
        return value
    if var.type == "Integer":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{name} = {value!r} must be an integer")
        return value
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{name} = {value!r} must be a number")
    return float(value)
