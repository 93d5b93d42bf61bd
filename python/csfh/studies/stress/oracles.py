"""The stress suite's test body and integrator settings, and the independent predictions its runs
are checked against (docs/model.md §7): Hertz's undamped impact and the effective
restitution of each damped law from the scaled impact ODE, integrated here with scipy."""

from __future__ import annotations

from functools import cache

import numpy as np

# the integrator settings of the suite: the paper's, which are the harness's defaults
from ...model._csfh_variables import MOREAU_STEP as MOREAU_STEP
from ...model._csfh_variables import RK4_H0 as RK4_H0
from ...model._csfh_variables import RK4_TOL as RK4_TOL

M1, I1, G = 10.0, 0.1617, 9.81
DELTA = 0.02
RTOL = 1e-10
XI = {  # docs/model.md §4.4
    "LN_spheres": lambda cr: 0.75 * (1 - cr * cr),
    "LN_cylinders": lambda cr: 0.75 * (1 - cr * cr),
    "LN_ESDU": lambda cr: 0.75 * (1 - cr * cr),
    "HuntCrossley": lambda cr: 1.5 * (1 - cr),
    "Flores": lambda cr: 8 * (1 - cr) / (5 * cr),
}


def hertz_max_indentation(K: float, v: float, n: float = 1.5, m: float = M1) -> float:
    """Undamped Hertz impact: rho_max = ((n + 1) m v^2 / (2 K))^(1/(n+1)) (docs/model.md §7.2)."""
    return ((n + 1) * m * v * v / (2 * K)) ** (1 / (n + 1))


def hertz_contact_time(K: float, v: float) -> float:
    """t_c = 2.943276 rho_max / v for n = 1.5 (docs/model.md §7.2)."""
    return 2.943276 * hertz_max_indentation(K, v) / v


@cache
def effective_restitution(law: str, cr: float, n: float = 1.5, rtol: float = 1e-12) -> float:
    """e_eff of F = K rho^n (1 + xi rhodot/rhodot0), clamped >= 0, from the parameter-free
    scaled impact X'' = -X^n max(0, 1 + xi X'), X(0) = 0, X'(0) = 1 (docs/model.md §7.3), integrated
    here with scipy (independent of the FMU) to the relative tolerance `rtol`."""
    from scipy.integrate import solve_ivp

    xi = XI[law](cr)

    def rhs(_: float, y: np.ndarray) -> list[float]:
        x = max(y[0], 0.0)
        return [y[1], -(x**n) * max(0.0, 1.0 + xi * y[1])]

    def back(_: float, y: np.ndarray) -> float:
        return y[0]

    back.terminal = True  # type: ignore[attr-defined]
    back.direction = -1  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs,
        (0, 1e3),
        [0.0, 1.0],
        method="Radau",
        rtol=rtol,
        atol=1e-2 * rtol,
        events=back,
        first_step=1e-6,
    )
    return float(-sol.y_events[0][0][1]) if sol.y_events[0].size else 0.0
