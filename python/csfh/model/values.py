"""Numbers read from a scene file: TOML integers have no size limit, so a key may hold one
beyond every double (10^400); it is refused like any other value that is not a finite number,
naming the key and the value, never by an OverflowError."""

from __future__ import annotations

import math
import sys
from decimal import Decimal
from typing import Any

from ..errors import SceneError


def shown(value: Any) -> str:
    """`value` for a message: repr, but an integer beyond the doubles in four digits (1.000e+400:
    its repr could be thousands of digits long)."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > sys.float_info.max:
        return f"{Decimal(value):.4g}"
    return repr(value)


def as_float(value: int | float) -> float:
    """float(value), or inf (with its sign) for an integer beyond the doubles."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


def number(where: str, value: Any, positive: bool = False, nonnegative: bool = False) -> float:
    """The finite number of key `where` (>0 or >= 0 if asked); SceneError naming the key and the
    value otherwise."""
    if (
        isinstance(value, bool)
        or not isinstance(value, int | float)
        or not math.isfinite(as_float(value))
    ):
        raise SceneError(f"{where} = {shown(value)} must be a finite number")
    if positive and not value > 0:
        raise SceneError(f"{where} = {value!r} must be > 0")
    if nonnegative and not value >= 0:
        raise SceneError(f"{where} = {value!r} must be >= 0")
    return float(value)
