"""Independent oracles for the tests: the physics of docs/model.md computed here, in Python, by a
different route than the C core (numerical quadrature instead of the closed forms, global
coordinates instead of the tip frame, scipy's integrators instead of CVODE). Nothing here calls
the package or the FMU; the tests compare the FMU and the harness with these numbers.

* Flexure (docs/model.md §1-2): the tip compliance of the circular arc by Gauss-Legendre
  quadrature of the Castigliano integrals (2.3) written in global coordinates (moment arm from
  the arc points, axial and shear force from the section's tangent and normal), the stiffness
  K0 = C^-1, and the co-rotated elastic force (2.7)-(2.9).
* The flight of body 1 on the flexure under gravity to the first contact (gap = 0), by scipy's
  DOP853 with event location.
* Contact stiffnesses (4.2)-(4.4), the damping factors (4.6), the ESDU law (4.7) in its explicit
  direction rho(F), its tangent stiffness (4.8) and F*.
* The central impact with gravity of each compliant law (4.1), integrated by scipy.
* The central scene's free fall to the first contact (7.1) and its rigid bounce sequence (7.4).
* The comb drive's force constant n eps0 t / g of the combdrive scene (F = k V^2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

G = 9.81  # m/s^2, along -Y (docs/model.md §0)
# docs/model.md §7.1: the central scene's free fall of 0.03 m, from q0 = [0, 0.01, 0] to the bore
T_FIRST_CENTRAL = math.sqrt(2 * 0.03 / G)
V_FIRST_CENTRAL = math.sqrt(2 * G * 0.03)


EPS0 = 8.8541878128e-12  # F/m, the vacuum permittivity
K_COMB = 20000 * EPS0 * 0.025 / 5e-6  # N/V^2: n eps0 t / g of the combdrive scene's actuator


def rigid_impact_times(n: int, cr: float = 0.9) -> np.ndarray:
    """docs/model.md §7.4: the first n impact times of the central scene's rigid bounce sequence
    (restitution cr)."""
    t = [T_FIRST_CENTRAL]
    v = V_FIRST_CENTRAL
    for _ in range(n - 1):
        v *= cr
        t.append(t[-1] + 2 * v / G)
    return np.array(t)


@dataclass(frozen=True)
class Flexure:
    """Table 1 of the paper (docs/model.md §1.1): arc centre O_F, radius rho, opening beta from the
    root at polar angle phi_root; section b x h; beam material E, nu; shear factor kappa."""

    rho: float = 0.144
    beta: float = 5 * math.pi / 3
    OF: tuple[float, float] = (0.22, 0.1)
    phi_root: float = 0.0
    h: float = 0.005
    b: float = 0.025
    E: float = 100e9
    nu: float = 0.3
    kappa: float = 1.2
    shear: bool = True  # False: bending + axial only (to size the shear term in the tests)
    axial: bool = True

    def tip(self) -> np.ndarray:
        """C1, the tip of the arc at q = 0: the attachment s-bar relative to G1 (1.2)."""
        phi = self.phi_root + self.beta
        return np.array(self.OF) + self.rho * np.array([math.cos(phi), math.sin(phi)])

    def compliance(self, points: int = 64) -> np.ndarray:
        """Tip compliance in global components at q = 0, for the wrench [F_x, F_y, M] at C1:
        C_ij = int (m_i m_j / EI + N_i N_j / EA + kappa V_i V_j / GA) rho dphi (2.3-2.4), with
        m = M + (C1 - P) x F, N = F . tau, V = F . nu at the section point P(phi) of the arc,
        by Gauss-Legendre quadrature (the integrands are trigonometric polynomials of low
        degree: 64 points integrate them to round-off)."""
        A = self.b * self.h
        EI = self.E * self.b * self.h**3 / 12.0
        EA = self.E * A
        GA = self.E / (2.0 * (1.0 + self.nu)) * A
        x, w = np.polynomial.legendre.leggauss(points)
        phi = self.phi_root + 0.5 * self.beta * (x + 1.0)
        w = 0.5 * self.beta * w
        c1 = self.tip()
        px = self.OF[0] + self.rho * np.cos(phi)
        py = self.OF[1] + self.rho * np.sin(phi)
        dx, dy = c1[0] - px, c1[1] - py
        m = np.array([-dy, dx, np.ones_like(phi)])  # dm/dF_x, dm/dF_y, dm/dM
        tau = np.array([-np.sin(phi), np.cos(phi), np.zeros_like(phi)])  # axial: N = F . tau
        nrm = np.array([np.cos(phi), np.sin(phi), np.zeros_like(phi)])  # shear: V = F . nu
        C = np.zeros((3, 3))
        for i in range(3):
            for j in range(3):
                f = m[i] * m[j] / EI
                if self.axial:
                    f = f + tau[i] * tau[j] / EA
                if self.shear:
                    f = f + self.kappa * nrm[i] * nrm[j] / GA
                C[i, j] = self.rho * float(np.sum(w * f))
        return C

    def stiffness(self) -> np.ndarray:
        """K0 = C^-1 in global components at q = 0 (2.8)."""
        return np.linalg.inv(self.compliance())

    def force(self, q: np.ndarray, K0: np.ndarray | None = None) -> np.ndarray:
        """The co-rotated elastic force Q_e(q) = -T_e(s) K(theta) dp (2.7)-(2.9)."""
        K0 = self.stiffness() if K0 is None else K0
        sbar = self.tip()
        c, s_ = math.cos(q[2]), math.sin(q[2])
        A = np.array([[c, -s_], [s_, c]])
        s = A @ sbar
        dp = np.array([q[0] + s[0] - sbar[0], q[1] + s[1] - sbar[1], q[2]])
        B = np.eye(3)
        B[:2, :2] = A
        K = B @ K0 @ B.T
        Te = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-s[1], s[0], 1.0]])
        return -Te @ (K @ dp)

    def linear_stiffness(self, K0: np.ndarray | None = None) -> np.ndarray:
        """K_G = T_e(s-bar) K0 T_e(s-bar)^T, the stiffness of body 1 at q = 0 (2.4)."""
        K0 = self.stiffness() if K0 is None else K0
        sbar = self.tip()
        Te = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-sbar[1], sbar[0], 1.0]])
        return Te @ K0 @ Te.T


MASS = np.array([10.0, 10.0, 0.1617])  # m1, m1, I1 (Table 1)


def natural_frequencies(flexure: Flexure, mass: np.ndarray = MASS) -> np.ndarray:
    """Natural frequencies [Hz] of body 1 on the flexure: det(K_G - w^2 M) = 0 (docs/model.md
    7.7), ascending."""
    KG = flexure.linear_stiffness()
    Mi = np.diag(1.0 / np.sqrt(mass))
    w2 = np.linalg.eigvalsh(Mi @ KG @ Mi)
    return np.sqrt(np.sort(w2)) / (2 * math.pi)


def first_contact_of_flight(
    flexure: Flexure | None,
    q0: tuple[float, float, float] = (0.01, 0.01, 0.0),
    delta: float = 0.02,
    mass: np.ndarray = MASS,
    g: float = G,
    rtol: float = 1e-12,
) -> tuple[float, np.ndarray]:
    """Time and state [x, y, theta, vx, vy, omega] of the first contact (the gap (3.1) of
    docs/model.md §3 with s1-bar = 0: delta - |r| = 0) of body 1 released at rest from q0, under
    gravity and the flexure (None: free fall); DOP853 with event location at rtol (position
    error ~ rtol x 0.01 m, time error ~ that / the approach speed ~ 1e-14 s at 1e-12)."""
    K0 = flexure.stiffness() if flexure is not None else None

    def rhs(_t: float, x: np.ndarray) -> np.ndarray:
        Q = np.array([0.0, -mass[0] * g, 0.0])
        if flexure is not None:
            Q = Q + flexure.force(x[:3], K0)
        return np.concatenate([x[3:], Q / mass])

    def gap(_t: float, x: np.ndarray) -> float:
        return delta - math.hypot(x[0], x[1])

    gap.terminal = True  # type: ignore[attr-defined]
    gap.direction = -1  # type: ignore[attr-defined]
    sol = solve_ivp(
        rhs,
        (0.0, 1.0),
        np.array([*q0, 0.0, 0.0, 0.0]),
        method="DOP853",
        rtol=rtol,
        atol=rtol * 1e-2,
        events=gap,
    )
    if not sol.t_events[0].size:
        raise AssertionError("no contact within 1 s")
    return float(sol.t_events[0][0]), np.asarray(sol.y_events[0][0])


# ------------------------------------------------------------------------------------------
# contact laws (docs/model.md §4)


def sigma(E: float, nu: float) -> float:
    """(1 - nu^2)/E (4.2)."""
    return (1.0 - nu * nu) / E


def k_spheres(
    E1: float = 210e9,
    E2: float = 210e9,
    nu1: float = 0.3,
    nu2: float = 0.3,
    R1: float = 0.18,
    R2: float = 0.20,
    internal: bool = False,
) -> float:
    """Hertz sphere stiffness 4 sqrt(R_eff) / (3 (sigma1 + sigma2)), N/m^1.5 (4.3)."""
    reff = R1 * R2 / (R2 - R1) if internal else R1 * R2 / (R1 + R2)
    return 4.0 * math.sqrt(reff) / (3.0 * (sigma(E1, nu1) + sigma(E2, nu2)))


def k_cylinders(
    E1: float = 210e9, E2: float = 210e9, nu1: float = 0.3, nu2: float = 0.3, L: float = 0.025
) -> float:
    """(pi/4) E* L, N/m (4.4)."""
    return math.pi / 4.0 / (sigma(E1, nu1) + sigma(E2, nu2)) * L


def xi(law: str, cr: float) -> float:
    """Damping factor of the law (4.6)."""
    if law == "HuntCrossley":
        return 1.5 * (1.0 - cr)
    if law == "Flores":
        return 8.0 * (1.0 - cr) / (5.0 * cr)
    return 0.75 * (1.0 - cr * cr)


@dataclass(frozen=True)
class Esdu:
    """ESDU-78035 (paper Eq. 18, docs/model.md §4.5) with sigma_k = (1 - nu_k^2)/(pi E_k)."""

    E1: float = 210e9
    E2: float = 210e9
    nu1: float = 0.3
    nu2: float = 0.3
    L: float = 0.025
    dR: float = 0.02

    @property
    def a(self) -> float:
        return (sigma(self.E1, self.nu1) + sigma(self.E2, self.nu2)) / math.pi / self.L

    @property
    def F_star(self) -> float:
        """F* = 4 L dR / (sigma1 + sigma2): dr/dF = 0 there, the law's validity limit."""
        return 4.0 * self.dR / self.a

    def indentation(self, F: float) -> float:
        """rho(F) = a F [ln(F*/F) + 1] (4.7): explicit in this direction."""
        return self.a * F * (math.log(self.F_star / F) + 1.0)

    def tangent_stiffness(self, F: float) -> float:
        """dF/drho = 1 / (a ln(F*/F)) (4.8)."""
        return 1.0 / (self.a * math.log(self.F_star / F))

    def force(self, rho: float) -> float:
        """F(rho): the inverse of (4.7), by Brent's method on u = ln(F/F*) <= 0, where rho is
        monotone (independent of the core's Newton iteration on (4.9))."""
        if rho <= 0.0:
            return 0.0
        u = brentq(
            lambda u: self.a * self.F_star * math.exp(u) * (1.0 - u) - rho,  # (4.7), F = F* e^u
            -700.0,
            0.0,
            xtol=1e-15,
            rtol=4 * np.finfo(float).eps,
        )
        return self.F_star * math.exp(u)


def central_impact(
    elastic, xi_: float, v_in: float, m: float = 10.0, g: float = G, rtol: float = 1e-11
) -> dict[str, float]:
    """The central impact of (4.1) with gravity: m rho'' = m g - F_el(rho) max(0, 1 + xi
    rho'/v_in), rho(0) = 0, rho'(0) = v_in, to the release rho = 0; by scipy's Radau (the end of
    contact is stiff for the stiff laws). Returns the duration, the largest indentation and
    force, and the exit speed."""

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        rho, rate = y
        F = elastic(rho) * max(0.0, 1.0 + xi_ * rate / v_in) if rho > 0.0 else 0.0
        return np.array([rate, g - F / m])

    def release(_t: float, y: np.ndarray) -> float:
        return y[0]

    release.terminal = True  # type: ignore[attr-defined]
    release.direction = -1  # type: ignore[attr-defined]
    # a rough duration scale: the undamped Hertz time of (7.2) with the stiffness at 1e-4 m
    k = elastic(1e-4) / 1e-4**1.5
    t_c = 2.943276 * ((2.5 * m * v_in**2 / (2.0 * k)) ** 0.4) / v_in
    sol = solve_ivp(
        rhs,
        (0.0, 20.0 * t_c),
        np.array([0.0, v_in]),
        method="DOP853",
        rtol=rtol,
        atol=1e-16,
        events=release,
        dense_output=True,
        max_step=t_c / 200.0,
    )
    if not sol.t_events[0].size:
        raise AssertionError("the contact does not end")
    t_end = float(sol.t_events[0][0])
    ts = np.linspace(0.0, t_end, 20001)
    rho = sol.sol(ts)[0]
    i = int(np.argmax(rho))
    # refine the maximum: rho' = 0 there
    lo, hi = ts[max(i - 1, 0)], ts[min(i + 1, len(ts) - 1)]
    t_max = brentq(lambda t: sol.sol(t)[1], lo, hi, xtol=1e-18) if lo < hi else ts[i]
    rho_max = float(sol.sol(t_max)[0])
    return {
        "duration": t_end,
        "rho_max": rho_max,
        "exit_speed": float(-sol.y_events[0][0][1]),
    }
