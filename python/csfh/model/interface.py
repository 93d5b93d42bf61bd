"""An FMU's interface as data: its variables (names, value references, types, causality and
variability, start values, units, ranges, descriptions, which are states) and enumerations.

Each FMU's interface is a generated module, python/csfh/model/_<prefix>_variables.py, written by
modelDescription/generate.py from the same variables file as the FMU's modelDescription.xml and
C table: the package knows the interface without a built binary, and cannot drift from it.
Field names are modelDescription.xml's attribute names (valueReference, declaredType, ...), as
fmpy's ModelVariable has them."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

from ..errors import ParameterError


def format_value(x: float) -> str:
    """The shortest "%g" text that reads back as the same double (the FMU's messages write values
    so: csfh_format_value)."""
    text = f"{x:g}"
    for precision in range(6, 18):
        text = f"{x:.{precision}g}"
        if float(text) == x:
            break
    return text


@dataclass(frozen=True)
class Range:
    """The values a variable takes: low..high, each end open or closed (as the FMU checks them;
    FMI's min and max are the extreme values inside)."""

    low: float
    high: float
    low_open: bool = False
    high_open: bool = False

    def __contains__(self, x: float) -> bool:
        above = x > self.low if self.low_open else x >= self.low
        below = x < self.high if self.high_open else x <= self.high
        return above and below

    def __str__(self) -> str:
        left, right = "(" if self.low_open else "[", ")" if self.high_open else "]"
        return f"{left}{format_value(self.low)}, {format_value(self.high)}{right}"


@dataclass(frozen=True)
class Item:
    name: str
    value: int
    description: str = ""


@dataclass(frozen=True)
class Enumeration:
    name: str
    description: str
    items: tuple[Item, ...]

    def values(self) -> dict[str, int]:
        """Item name -> value."""
        return {item.name: item.value for item in self.items}


@dataclass(frozen=True)
class Variable:
    """One variable. `type` is FMI 2.0's (Real, Integer, Boolean, Enumeration); `range` the
    declared one (None: any finite value; an Enumeration takes its items, a Boolean 0 and 1);
    `state`: a continuous state; `derivative_of`: the state it is the derivative of."""

    name: str
    valueReference: int
    type: str
    causality: str
    variability: str
    initial: str | None = None
    start: float | int | bool | None = None
    declaredType: str | None = None
    quantity: str | None = None
    unit: str | None = None
    displayUnit: str | None = None
    nominal: float | None = None
    range: Range | None = None
    description: str = ""
    state: bool = False
    derivative_of: str | None = None


@dataclass(frozen=True)
class Interface:
    """The variables and enumerations of one FMU, in the order of its modelDescription.xml."""

    model_name: str
    variables: tuple[Variable, ...]
    enumerations: tuple[Enumeration, ...] = ()

    @cached_property
    def by_name(self) -> dict[str, Variable]:
        return {v.name: v for v in self.variables}

    def select(self, causality: str) -> tuple[Variable, ...]:
        """The variables of one causality (parameter, input, output, ...)."""
        return tuple(v for v in self.variables if v.causality == causality)

    @property
    def states(self) -> tuple[Variable, ...]:
        """The continuous states, in the order of the FMU's state vector."""
        return tuple(v for v in self.variables if v.state)

    def enumeration(self, name: str) -> Enumeration:
        for e in self.enumerations:
            if e.name == name:
                return e
        raise KeyError(name)

    def check(self, name: str, value: float) -> None:
        """ParameterError naming the variable and the value, in the FMU's words, when the FMU
        would refuse `value` for variable `name` (fmu_src/fmu/csfh_vartable.c)."""
        v = self.by_name[name]
        if not math.isfinite(value):
            raise ParameterError(f"{name} = {value:g} is not finite")
        if v.type == "Enumeration":
            items = self.enumeration(str(v.declaredType)).items
            if value not in {item.value for item in items}:
                raise ParameterError(
                    f"{name} = {value:.0f} is not a valid enumeration value "
                    f"({items[0].value}..{items[-1].value})"
                )
        elif v.type == "Boolean":
            if value not in (0, 1):
                raise ParameterError(f"{name} = {int(value)} is not a Boolean (0 or 1)")
        elif v.range is not None and value not in v.range:
            raise ParameterError(f"{name} = {format_value(value)} is out of range {v.range}")
