"""The two presets of docs/model.md §9.

`paper` (the FMU's start values) replicates the paper's figures; `consistent` is dimensionally and
geometrically sound physics. Every item is an ordinary parameter, so a scene can override any of
them."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Preset:
    name: str
    description: str
    parameters: dict[str, float | int | bool | str] = field(default_factory=dict)
    stick_rule: str = "paper"  # Moreau: which coefficient decides sticking (docs/model.md §6.4)


PRESETS: dict[str, Preset] = {
    "paper": Preset(
        name="paper",
        description="E1 = E2 = 210 GPa (Table 2), Eq. (14) external radius, n = 1.5 for both "
        "laws, LN_ESDU reading I3, Moreau stick decided by f_a",
        parameters={},
        stick_rule="paper",
    ),
    "consistent": Preset(
        name="consistent",
        description="E1 = E2 = 100 GPa (Table 1), internal radius R1 R2/(R2 - R1), linear "
        "cylinder law (n = 1), LN_ESDU reading I2, Moreau memory stick rule",
        parameters={
            "contact.E1": 100e9,
            "contact.E2": 100e9,
            "contact.Reff_internal": True,
            "contact.n_cylinders": 1.0,
            "contact.esdu_reading": "I2",
        },
        stick_rule="memory",
    ),
}
