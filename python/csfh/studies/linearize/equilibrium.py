"""The static equilibrium of body 1 under constant inputs: q with the accelerations zero at rest,
M^-1 Q(q, 0) = 0 (docs/model.md Eq. (0.3)), by Newton's method on the Jacobian of a
`JacobianSource`, with a backtracking line search and least-squares steps (a rigid motion, e.g.
the rotation without flexure and friction, leaves the Jacobian singular; the step then leaves
that coordinate alone).

The contact mode of an FMU instance is frozen between events (docs/model.md §10.3), so each
solve runs in one mode, the one the FMU sets at the start from the gap. An equilibrium is
consistent when its gap agrees with its mode (flight: gap > 0; contact: indentation > 0). When
it does not, the solve starts again in the other mode: from a point just inside the bore on the
way to the inconsistent flight solution (or, when there is no flight solution, along the
unbalanced force), or from the contact solution that left the bore. In contact the unknowns
are polar coordinates of the eccentricity (`BorePolar`), in flight q itself."""

from __future__ import annotations

import math
from collections.abc import Callable
from contextlib import AbstractContextManager
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...errors import SimulationError
from .jacobian import OUTPUTS, JacobianSource, Plant, fd_steps

MAX_ITERATIONS = 60
TOLERANCE = 1e-9
"""Convergence: the last Newton step below this fraction of each coordinate's length scale (in
contact the indentation for the radius, the clearance along the bore and for the rotation; in
flight 1e3 x the finite-difference steps: the clearance, or the deflection if smaller)."""
MAX_STEP = 1e3
"""A Newton step longer than this many length scales ends the solve unconverged: the stiffness
is round-off (a free flight under a constant force)."""
RESIDUAL = 1e-9
"""Convergence: the accelerations below this fraction of the largest change of an acceleration
over one length scale (the stiffness times the scale)."""
_GAP = OUTPUTS.index("contact.gap")
_INDENTATION = OUTPUTS.index("contact.indentation")

PlantAt = Callable[[np.ndarray], AbstractContextManager[Plant]]
"""Makes a plant started at rest at configuration q (its contact mode from the gap there)."""


@dataclass
class NewtonResult:
    q: np.ndarray
    converged: bool
    iterations: int
    residual: float  # max |acceleration| at q, m/s2 or rad/s2
    rank: int  # of the stiffness at q (< 3: a rigid motion)
    path: list[np.ndarray] = field(default_factory=list)


@dataclass(frozen=True)
class Equilibrium:
    q: np.ndarray
    mode: str  # "contact" or "flight"
    iterations: int
    residual: float
    rank: int
    gap: float
    indentation: float
    attempts: list[str]

    def summary(self) -> dict[str, object]:
        return {
            "converged": True,
            "mode": self.mode,
            "iterations": self.iterations,
            "residual": self.residual,
            "stiffness_rank": self.rank,
            "gap": self.gap,
            "indentation": self.indentation,
            "attempts": self.attempts,
        }


def _residual(plant: Plant, q: np.ndarray, u: np.ndarray) -> np.ndarray:
    return plant.evaluate(np.concatenate([q, np.zeros(3)]), u)[3:6]


class Cartesian:
    """q itself: the coordinates of a flight solve."""

    def to_q(self, p: np.ndarray) -> np.ndarray:
        return p

    def from_q(self, q: np.ndarray) -> np.ndarray:
        return q

    def tangent(self, p: np.ndarray) -> np.ndarray:
        return np.eye(3)

    def scales(self, q_scales: np.ndarray, p: np.ndarray) -> np.ndarray:
        return q_scales


class BorePolar:
    """p = [|e|, phi, theta] with e = r + A(theta) s1-bar = |e| [cos phi, sin phi] the
    eccentricity (docs/model.md Eq. (3.1)): the coordinates of a solve in contact, where a
    straight Newton step along the bore would push body 1 into it by step^2 / 2 delta, far deeper
    than the indentation, and the radius alone sets the stiff normal force."""

    def __init__(self, s1bar: np.ndarray, delta: float, R1: float) -> None:
        self.s1bar = np.asarray(s1bar, dtype=float)
        self.delta, self.R1 = delta, R1

    def _s1(self, theta: float) -> np.ndarray:
        c, s = math.cos(theta), math.sin(theta)
        return np.array(
            [c * self.s1bar[0] - s * self.s1bar[1], s * self.s1bar[0] + c * self.s1bar[1]]
        )

    def to_q(self, p: np.ndarray) -> np.ndarray:
        e = p[0] * np.array([math.cos(p[1]), math.sin(p[1])])
        return np.array([*(e - self._s1(p[2])), p[2]])

    def from_q(self, q: np.ndarray) -> np.ndarray:
        e = q[:2] + self._s1(q[2])
        return np.array([math.hypot(e[0], e[1]), math.atan2(e[1], e[0]), q[2]])

    def tangent(self, p: np.ndarray) -> np.ndarray:
        """dq/dp."""
        c, s = math.cos(p[1]), math.sin(p[1])
        s1 = self._s1(p[2])
        return np.array([[c, -p[0] * s, s1[1]], [s, p[0] * c, -s1[0]], [0.0, 0.0, 1.0]])

    def scales(self, q_scales: np.ndarray, p: np.ndarray) -> np.ndarray:
        """The indentation for the radius; the clearance along the bore and for the rotation,
        which leave the gap alone in these coordinates."""
        return np.array([q_scales[0], self.delta / p[0], self.delta / self.R1])


def newton(
    plant: Plant, source: JacobianSource, q: np.ndarray, u: np.ndarray, coords: Any
) -> NewtonResult:
    """Newton's method in the plant's contact mode from q, in coordinates `coords`. Converged:
    the last step below TOLERANCE of the length scales and the accelerations below RESIDUAL of
    what the stiffness makes of one length scale (a free fall, with no stiffness, never
    converges)."""
    p = coords.from_q(np.array(q, dtype=float))
    r = _residual(plant, coords.to_q(p), u)
    path = [coords.to_q(p)]
    it = 0
    for it in range(1, MAX_ITERATIONS + 1):
        x = np.concatenate([coords.to_q(p), np.zeros(3)])
        scale = coords.scales(1e3 * fd_steps(plant, x, u)[:3], p)
        K = source.jacobians(plant, x, u).A[3:, :3] @ coords.tangent(p) * scale
        r_tol = RESIDUAL * float(np.max(np.abs(K)))
        step, _, rank, _ = np.linalg.lstsq(K, -r, rcond=1e-12)
        small = bool(np.max(np.abs(r)) <= r_tol)
        if np.max(np.abs(step)) > MAX_STEP:  # a stiffness at round-off: nothing holds body 1
            break
        t, r_new = _line_search(plant, coords, p, step * scale, r, u)
        if r_new is None or (small and np.max(np.abs(step)) < TOLERANCE):
            # no descent left: converged when the residual is already at round-off
            q_end = coords.to_q(p)
            return NewtonResult(q_end, small, it, float(np.max(np.abs(r))), int(rank), path)
        p, r = p + t * step * scale, r_new
        path.append(coords.to_q(p))
    return NewtonResult(coords.to_q(p), False, it, float(np.max(np.abs(r))), 3, path)


def _line_search(
    plant: Plant, coords: Any, p: np.ndarray, dp: np.ndarray, r: np.ndarray, u: np.ndarray
) -> tuple[float, np.ndarray | None]:
    """The largest t = 2^-k (k < 40) with |r(p + t dp)| <= |r(p)|; None when there is none."""
    t = 1.0
    for _ in range(40):
        r_new = _residual(plant, coords.to_q(p + t * dp), u)
        if np.all(np.isfinite(r_new)) and np.linalg.norm(r_new) <= np.linalg.norm(r):
            return t, r_new
        t *= 0.5
    return t, None


def _contact_values(plant: Plant, q: np.ndarray, u: np.ndarray) -> tuple[float, float]:
    y = plant.evaluate(np.concatenate([q, np.zeros(3)]), u)
    return float(y[6 + _GAP]), float(y[6 + _INDENTATION])


def _entry_point(plant: Plant, path: list[np.ndarray], u: np.ndarray, depth: float) -> np.ndarray:
    """A configuration on the Newton path at a gap of about -depth: bisection between the last
    iterate outside the bore and the first inside."""
    gaps = [_contact_values(plant, q, u)[0] for q in path]
    k = next(i for i, g in enumerate(gaps) if g < 0.0)
    lo, hi = path[k - 1], path[k]
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        g = _contact_values(plant, mid, u)[0]
        if -2 * depth <= g <= -0.5 * depth:
            return mid
        lo, hi = (mid, hi) if g > -0.5 * depth else (lo, mid)
    return hi


def _solve_in_mode(
    plant_at: PlantAt, source: JacobianSource, q0: np.ndarray, u: np.ndarray
) -> tuple[NewtonResult, bool, float, float, np.ndarray | None]:
    """Newton in the mode the FMU starts in at q0: the result, whether in contact, the gap and
    indentation at the result, and (flight only) a start just inside the bore when the Newton
    path entered it."""
    with plant_at(q0) as plant:
        contact = plant.in_contact()
        s1bar = np.array([plant.value("body1.s1[1]"), plant.value("body1.s1[2]")])
        delta = plant.value("contact.R2") - plant.value("contact.R1")
        R1 = plant.value("contact.R1")
        coords: Any = BorePolar(s1bar, delta, R1) if contact else Cartesian()
        result = newton(plant, source, q0, u, coords)
        gap, indentation = _contact_values(plant, result.q, u)
        entry = None
        if not contact and not (result.converged and gap > 0.0):
            path = result.path + _drift(plant, result.q, u, delta)
            if any(_contact_values(plant, q, u)[0] < 0.0 for q in path):
                entry = _entry_point(plant, path, u, 1e-4 * delta)
    return result, contact, gap, indentation, entry


def _drift(plant: Plant, q: np.ndarray, u: np.ndarray, delta: float) -> list[np.ndarray]:
    """Configurations along the unbalanced translational acceleration at q, out to 4 delta: where
    a force that nothing holds in flight (Newton finds no flight equilibrium) takes body 1."""
    a = _residual(plant, q, u)
    direction = np.array([a[0], a[1], 0.0])
    norm = float(np.linalg.norm(direction))
    if not norm > 0.0:
        return []
    return [q + delta * 2.0**k / 64 * direction / norm for k in range(9)]


def _next_start(
    contact: bool, result: NewtonResult, gap: float, entry: np.ndarray | None, tried: set[bool]
) -> np.ndarray | None:
    """Where to start the solve in the other mode (None: nowhere left)."""
    if not contact and entry is not None and True not in tried:
        return entry
    if contact and result.converged and gap > 0.0 and False not in tried:
        return result.q
    return None


def _failure(attempts: list[str], result: NewtonResult) -> SimulationError:
    if not math.isfinite(result.residual):
        return SimulationError("equilibrium: Newton's method diverged (non-finite accelerations)")
    q = ", ".join(f"{v:.9g}" for v in result.q)
    return SimulationError(
        "equilibrium: Newton's method found no equilibrium consistent with the contact mode ("
        f"{'; '.join(attempts)}; last residual {result.residual:.3g} at q = [{q}])"
    )


def static_equilibrium(
    plant_at: PlantAt, source: JacobianSource, q0: np.ndarray, u: np.ndarray
) -> Equilibrium:
    """The equilibrium from the guess q0 (module docstring); SimulationError when Newton's method
    does not converge to a consistent equilibrium in either mode."""
    attempts: list[str] = []
    start: np.ndarray | None = np.asarray(q0, dtype=float)
    total = 0
    tried: set[bool] = set()
    while start is not None:
        result, contact, gap, indentation, entry = _solve_in_mode(plant_at, source, start, u)
        mode = "contact" if contact else "flight"
        total += result.iterations
        if contact in tried:  # the FMU started in a mode already solved (law none: no contact)
            break
        tried.add(contact)
        attempts.append(
            f"{mode}: {'converged' if result.converged else 'not converged'} in "
            f"{result.iterations} iterations, gap {gap:.6g} m"
        )
        if result.converged and (indentation > 0.0 if contact else gap > 0.0):
            return Equilibrium(
                result.q, mode, total, result.residual, result.rank, gap, indentation, attempts
            )
        start = _next_start(contact, result, gap, entry, tried)
    raise _failure(attempts, result)
