"""Half-sine shock pulses: by peak and duration, or a standard test condition by name.

The conditions shipped are the lettered mechanical-shock conditions A-G of JEDEC JESD22-B104
("Mechanical Shock") and of MIL-STD-883 Method 2002 ("Mechanical shock"), which are quoted with
the same peak acceleration and pulse duration for the same letter. The standards' own texts are
not reproduced or checked here (they are not freely redistributable); the numbers are the values
as they are commonly tabulated, and each entry says how far we could corroborate it:

* A (500 g, 1.0 ms), B (1500 g, 0.5 ms) and E (10 000 g, 0.2 ms) appear in this form in public
  component data sheets and qualification reports that cite these standards (e.g. "MIL-STD-883
  Method 2002, 500 g, 1.0 ms, half-sine"; "JESD22-B104, 1500 g, 0.5 ms half-sine"; "JESD22-B104C,
  MIL-STD-883 Method 2002.5 condition E, 10 000 g, 0.2 ms").
* C, D, F and G are the remaining rows of the same table as it is commonly reproduced; we found
  no public document to cross-check them against and call them "typical".

A standard also prescribes tolerances on the pulse shape, the number of pulses and the axes;
none of that is modelled: the pulse here is the ideal half-sine a(t) = A sin(pi t / T). Check the
values against the edition of the standard you qualify to, or give --peak and --duration."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...errors import ParameterError

G_STANDARD = 9.80665
"""m/s^2: the unit g of shock specifications (standard gravity)."""


@dataclass(frozen=True)
class Pulse:
    """A half-sine pulse of the frame's acceleration: peak in g, duration in s."""

    peak_g: float
    duration: float
    name: str = ""  # the condition's name, or "" for a pulse given by its numbers
    source: str = ""  # where the numbers come from

    @property
    def peak(self) -> float:
        """The peak acceleration, m/s^2."""
        return self.peak_g * G_STANDARD

    @property
    def velocity_change(self) -> float:
        """The pulse's velocity change, the integral of a(t): 2 A T / pi, m/s."""
        return 2.0 * self.peak * self.duration / math.pi

    def describe(self) -> str:
        what = f"{self.peak_g:g} g, {self.duration * 1e3:g} ms half-sine"
        return f"{self.name} ({what})" if self.name else what


_CORROBORATED = "corroborated by public data sheets that cite the standard"
_TYPICAL = "typical: the value commonly tabulated, not cross-checked here"
_TABLE = {  # letter: (peak in g, duration in s, how far the numbers are corroborated)
    "A": (500.0, 1.0e-3, _CORROBORATED),
    "B": (1500.0, 0.5e-3, _CORROBORATED),
    "C": (3000.0, 0.3e-3, _TYPICAL),
    "D": (5000.0, 0.3e-3, _TYPICAL),
    "E": (10000.0, 0.2e-3, _CORROBORATED),
    "F": (20000.0, 0.2e-3, _TYPICAL),
    "G": (30000.0, 0.12e-3, _TYPICAL),
}
_STANDARDS = {
    "JESD22-B104": "JEDEC JESD22-B104 (Mechanical Shock), condition",
    "MIL-STD-883-2002": "MIL-STD-883 Method 2002 (Mechanical shock), test condition",
}

CONDITIONS: dict[str, Pulse] = {
    f"{std}-{letter}": Pulse(peak_g, duration, f"{std}-{letter}", f"{title} {letter}; {how}")
    for std, title in _STANDARDS.items()
    for letter, (peak_g, duration, how) in _TABLE.items()
}
"""The standard conditions by name (JESD22-B104-A ... -G, MIL-STD-883-2002-A ... -G)."""

DEFAULT_CONDITION = "JESD22-B104-B"


def condition(name: str) -> Pulse:
    """A standard condition by name (case-insensitive); ParameterError naming the known ones."""
    for key, pulse in CONDITIONS.items():
        if key.lower() == name.strip().lower():
            return pulse
    raise ParameterError(f"unknown shock condition {name!r} (known: {', '.join(CONDITIONS)})")


def pulse(peak_g: float, duration: float) -> Pulse:
    """A pulse by its numbers; ParameterError naming the bad one."""
    if not (math.isfinite(peak_g) and peak_g > 0):
        raise ParameterError(f"shock peak = {peak_g!r} g must be a finite number > 0")
    if not (math.isfinite(duration) and duration > 0):
        raise ParameterError(f"shock duration = {duration!r} s must be a finite number > 0")
    return Pulse(peak_g, duration, "", "given on the command line")


def table_markdown() -> str:
    """The conditions shipped, as a markdown table (the user guide and the report)."""
    lines = ["| condition | peak | duration | velocity change | source |", "|---|---|---|---|---|"]
    for p in CONDITIONS.values():
        lines.append(
            f"| {p.name} | {p.peak_g:g} g | {p.duration * 1e3:g} ms | "
            f"{p.velocity_change:.3g} m/s | {p.source} |"
        )
    return "\n".join(lines)
