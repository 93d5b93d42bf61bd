"""The modes of a state-space model dx/dt = A x + B u, y = C x + D u: eigenvalues, natural
frequencies and damping ratios of its oscillatory modes, and the frequency response of one
input to one output."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

OSCILLATORY = 1e-6
"""An eigenvalue is one of an oscillatory pair when its imaginary part exceeds this fraction of
the largest |eigenvalue| and sqrt(NOISE max|A_ij|): the double zero of a rigid motion (a free
rotation or a body in flight without flexure) splits under an error eps of A into +-sqrt(eps),
and the Jacobians' error is ~1e-10 of their largest entries."""
NOISE = 1e-9


@dataclass(frozen=True)
class Mode:
    """One oscillatory pair lambda = -zeta w_n +- i w_n sqrt(1 - zeta^2): natural frequency
    w_n / 2 pi in Hz (|lambda|), damped frequency Im(lambda) / 2 pi, damping ratio zeta."""

    frequency_hz: float
    damped_frequency_hz: float
    damping_ratio: float


def eigenvalues(A: np.ndarray) -> np.ndarray:
    """The eigenvalues of A, by ascending modulus, then imaginary part."""
    lam = np.linalg.eigvals(A)
    return lam[np.lexsort((lam.imag, np.abs(lam)))]


def oscillatory_modes(lam: np.ndarray, A: np.ndarray) -> list[Mode]:
    """One mode per complex pair of A's eigenvalues `lam` (its eigenvalue of positive imaginary
    part), by ascending natural frequency."""
    largest = float(np.max(np.abs(lam))) if lam.size else 0.0
    floor = math.sqrt(NOISE * float(np.max(np.abs(A)))) if A.size else 0.0
    modes = [
        Mode(
            frequency_hz=abs(z) / (2 * math.pi),
            damped_frequency_hz=z.imag / (2 * math.pi),
            damping_ratio=-z.real / abs(z),
        )
        for z in lam
        if z.imag > max(OSCILLATORY * largest, floor)
    ]
    return sorted(modes, key=lambda m: m.frequency_hz)


def frequency_grid(modes: list[Mode], points: int = 600) -> np.ndarray:
    """Hz, log-spaced from a decade below the lowest mode to a decade above the highest (0.1 to
    1000 Hz without modes)."""
    if modes:
        lo, hi = modes[0].frequency_hz / 10, modes[-1].frequency_hz * 10
    else:
        lo, hi = 0.1, 1000.0
    grid = np.geomspace(lo, hi, points)
    # each natural frequency on the grid, so that the resonance peaks are drawn
    return np.unique(np.concatenate([grid, [m.frequency_hz for m in modes]]))


def frequency_response(
    A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, f_hz: np.ndarray
) -> np.ndarray:
    """G(i 2 pi f) = C (i 2 pi f I - A)^-1 B + D for one input column and one output row
    (B: n x 1, C: 1 x n, D: 1 x 1), complex, one value per frequency."""
    n = A.shape[0]
    eye = np.eye(n)
    out = np.empty(len(f_hz), dtype=complex)
    for k, f in enumerate(f_hz):
        s = 2j * math.pi * f
        out[k] = (C @ np.linalg.solve(s * eye - A, B))[0, 0] + D[0, 0]
    return out
