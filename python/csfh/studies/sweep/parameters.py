"""What the sweep moves and measures: the paper's Tables 4 and 5 (each parameter with its step and
the paper's arrows), the alternatives our choices leave open, the outputs and the levels."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...trajectory import SIGNALS

OUTPUTS = SIGNALS
FORCES = ("F_N", "F_T")
OUTPUT_LABELS = {"x": "x", "y": "y", "theta": "θ", "F_N": "F_N", "F_T": "F_T"}
EVENT_DRIVEN = ("LN_spheres", "LN_cylinders", "LN_ESDU")
LEVEL_NAMES = {0: "none", 1: "low", 2: "medium", 3: "high"}
ARROWS = {0: "·", 1: "↑", 2: "↑↑", 3: "↑↑↑"}


@dataclass(frozen=True)
class SweepParameter:
    key: str
    symbol: str  # as the paper prints it
    variables: tuple[str, ...]  # FMU parameters moved together
    delta: float  # SI step
    step_text: str  # the paper's step, with its unit
    table4: tuple[int, int, int, int, int] | None  # arrows for x, y, theta, F_N, F_T
    table5: tuple[int, int, int, int, int] | None
    note: str = ""
    rest_shift: bool = False  # also move the flexure's rest position as the paper's Eq. (4)
    paper_row: str | None = None  # an alternative reading of this row of the paper's tables


# The paper's Tables 4 (event-driven) and 5 (Moreau), as printed at the end of the paper text.
PARAMETERS: tuple[SweepParameter, ...] = (
    SweepParameter(
        "R1",
        "R1",
        ("contact.R1",),
        1e-3,
        "± 1 mm",
        (3, 3, 3, 2, 1),
        (3, 3, 3, 2, 2),
        "clearance δ = R2 − R1 = 20 ∓ 1 mm",
    ),
    SweepParameter("m1", "m1", ("body1.m",), 0.1, "± 0.1 kg", (1, 1, 1, 1, 1), (2, 2, 2, 2, 2)),
    SweepParameter(
        "I1", "I1", ("body1.I",), 1e-3, "± 0.001 kg m²", (1, 1, 1, 1, 1), (1, 1, 1, 1, 1)
    ),
    SweepParameter(
        "E12",
        "E1,2",
        ("contact.E1", "contact.E2"),
        10e9,
        "± 10 GPa",
        (1, 1, 1, 1, 1),
        None,
        "both surfaces; enters the compliant laws only (Moreau is rigid)",
    ),
    SweepParameter("cr", "c_r", ("contact.cr",), 0.01, "± 0.01", (1, 1, 1, 1, 1), (2, 2, 2, 2, 2)),
    SweepParameter(
        "fd", "f_d", ("friction.fd",), 0.005, "± 0.005", (1, 1, 1, 1, 1), (2, 2, 1, 1, 1)
    ),
    SweepParameter(
        "fa",
        "f_a",
        ("friction.fa",),
        0.01,
        "± 0.01",
        None,
        (1, 1, 1, 1, 1),
        "stiction: Moreau only (the Ambrósio law has none)",
    ),
    SweepParameter(
        "rho",
        "ρ",
        ("flexure.rho",),
        1e-3,
        "± 1 mm",
        (2, 2, 1, 2, 2),
        (2, 2, 1, 2, 2),
        "arc centre O_F fixed: C1 moves with ρ, the rest position of G1 stays at O2",
    ),
    SweepParameter(
        "b",
        "b",
        ("flexure.b",),
        1e-3,
        "± 1 mm (paper: '(-)')",
        (1, 1, 1, 1, 1),
        (1, 1, 1, 1, 1),
        "beam width only; contact.L stays 25 mm (see bL)",
    ),
    SweepParameter("h", "h", ("flexure.h",), 1e-3, "± 1 mm", (2, 2, 2, 2, 2), (3, 3, 3, 2, 2)),
    SweepParameter(
        "beta",
        "β",
        ("flexure.beta",),
        math.radians(1.0),
        "± 1°",
        (3, 3, 2, 3, 2),
        (3, 3, 2, 2, 2),
        "arc centre O_F fixed: C1 moves with β, the rest position of G1 stays at O2",
    ),
    SweepParameter("Eh", "E_h", ("flexure.E",), 10e9, "± 10 GPa", (3, 3, 3, 2, 2), (3, 3, 3, 3, 3)),
)
# Not in the paper's tables: the alternatives our choices leave open (see sweep.md).
EXTRA_PARAMETERS: tuple[SweepParameter, ...] = (
    SweepParameter(
        "bL",
        "b (+L)",
        ("flexure.b", "contact.L"),
        1e-3,
        "± 1 mm",
        None,
        None,
        "not in the paper: beam width and contact length together (K_cylinders ∝ L)",
    ),
    SweepParameter(
        "rho_r0",
        "ρ (Eq. 4)",
        ("flexure.rho",),
        1e-3,
        "± 1 mm",
        None,
        None,
        "the paper's reading: root C2 and attachment s̄ fixed, so the rest position "
        "r0 of Eq. (4) moves by the change of the chord C2→C1",
        rest_shift=True,
        paper_row="rho",
    ),
    SweepParameter(
        "beta_r0",
        "β (Eq. 4)",
        ("flexure.beta",),
        math.radians(1.0),
        "± 1°",
        None,
        None,
        "the paper's reading: root C2 and attachment s̄ fixed, so the rest "
        "position r0 of Eq. (4) moves by the change of the chord C2→C1",
        rest_shift=True,
        paper_row="beta",
    ),
)
ALL_PARAMETERS = {p.key: p for p in (*PARAMETERS, *EXTRA_PARAMETERS)}
PAPER_KEYS = tuple(p.key for p in PARAMETERS)
QUICK_PARAMETERS = ("R1", "m1", "h")


def paper_levels(group: str, key: str) -> tuple[int, ...] | None:
    """The paper's arrows for a row (an alternative reading takes its paper row's)."""
    p = ALL_PARAMETERS[key]
    if p.paper_row is not None:
        p = ALL_PARAMETERS[p.paper_row]
    return p.table4 if group == "event-driven" else p.table5
