"""What the csfh FMU declares: variables, types, enumerations, ranges. They come from the
generated module of the interface (csfh.model._csfh_variables, written from the same
variables.toml as the FMU's modelDescription.xml and C table), so that scenes load and validate
without a built binary; the FMU's own model description (`model_description`) is read only to
run the FMU."""

from __future__ import annotations

import math
from collections.abc import Iterable
from functools import cache
from typing import TYPE_CHECKING

from ..errors import ParameterError
from ..paths import fmu_path
from ._csfh_variables import INTERFACE
from .interface import Variable
from .values import as_float, shown

if TYPE_CHECKING:
    from fmpy.model_description import ModelDescription

LAWS = tuple(item.name for item in INTERFACE.enumeration("ContactLaw").items if item.name != "none")
"""Normal contact laws of the FMU's event-driven models (contact.law), besides `none`."""
MODELS = (*LAWS, "Moreau")
"""Everything `csfh run --law` accepts."""
PAPER_MODELS = ("LN_spheres", "LN_cylinders", "LN_ESDU", "Moreau")
"""The paper's four-model comparison (section 6)."""
STATE_NAMES = tuple(v.name for v in INTERFACE.states)
"""The continuous states, in the order of the state vector [x, y, theta, vx, vy, omega]."""


@cache
def model_description() -> ModelDescription:
    """The built FMU's model description (fmpy), for running it."""
    from fmpy import read_model_description  # here, not at import: `csfh --help` stays fast

    return read_model_description(str(fmu_path()))


def variables() -> dict[str, Variable]:
    """Every variable by name."""
    return INTERFACE.by_name


def enumeration(type_name: str) -> dict[str, int]:
    """An enumeration's items: name -> value."""
    return INTERFACE.enumeration(type_name).values()


def parameter_names() -> list[str]:
    return [v.name for v in INTERFACE.select("parameter")]


def require(names: Iterable[str], what: str) -> None:
    """RuntimeError unless every name is a variable of the FMU (`what`: where the names come
    from, for the message)."""
    unknown = [n for n in names if n not in INTERFACE.by_name]
    if unknown:
        raise RuntimeError(f"{what}: {', '.join(unknown)} is not a variable of the csfh FMU")


def coerce(name: str, value: object) -> float | int | bool:
    """Turn a user value into what the variable takes (enumeration items by name); raises
    ParameterError naming the variable for a wrong type or an unknown item."""
    var = INTERFACE.by_name.get(name)
    if var is None:
        raise ParameterError(f'unknown parameter "{name}"')
    if var.type == "Enumeration":
        items = enumeration(str(var.declaredType))
        if isinstance(value, str):
            if value not in items:
                raise ParameterError(f'{name} = "{value}" is not one of {", ".join(items)}')
            return items[value]
        if isinstance(value, bool) or not isinstance(value, int):
            raise ParameterError(f"{name} = {value!r} must be one of {', '.join(items)}")
        return value
    if var.type == "Boolean":
        if not isinstance(value, bool):
            raise ParameterError(f"{name} = {value!r} must be true or false")
        return value
    if var.type == "Integer":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ParameterError(f"{name} = {value!r} must be an integer")
        return value
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ParameterError(f"{name} = {value!r} must be a number")
    if not math.isfinite(as_float(value)):
        raise ParameterError(f"{name} = {shown(value)} must be a finite number")
    return float(value)


def check(name: str, value: float | int | bool) -> None:
    """ParameterError, in the FMU's words, when the FMU would refuse `value` for `name` (its
    range, an enumeration's items, finiteness; an integer beyond the doubles is not finite)."""
    if not math.isfinite(as_float(value)):
        raise ParameterError(f"{name} = {shown(value)} is not finite")
    INTERFACE.check(name, float(value))
