"""Growth under switching: whether a family of maps, each stable alone,
grows when the map changes from one period to the next.

A family whose parameters may vary however fast is stable only if every
product of its maps shrinks: its joint spectral radius is below one. The
spectral radius of any periodic product, to the power one over its
length, is a lower bound of it; one above one is a proof that some
variation makes the family grow (a certificate of instability), so no
Lyapunov function of any form proves it stable. Periodic switching
between two maps, held ``p`` periods at one and ``q`` at the other, is
searched here; finding no growth proves nothing either way.
"""

from typing import Sequence, Tuple

import numpy as np

__all__ = ["DWELLS", "periodic_growth", "spectral_radius"]

#: The dwell times searched (periods at each map): every one up to 12,
#: then about 15 % apart up to 256 (a slow mode needs long dwells).
DWELLS = tuple(
    sorted(
        set(range(1, 13))
        | set(np.geomspace(12, 256, 22).round().astype(int).tolist())
    )
)


def spectral_radius(A: np.ndarray) -> float:
    return float(np.max(np.abs(np.linalg.eigvals(A))))


def periodic_growth(
    A: np.ndarray, B: np.ndarray, dwells: Sequence[int] = DWELLS
) -> Tuple[float, Tuple[int, int]]:
    """(g, (p, q)): the largest growth per period rho(B^q A^p)^(1/(p+q))
    over p, q in ``dwells``: a lower bound of the pair's joint spectral
    radius (g > 1: holding ``A`` p periods and ``B`` q periods, over and
    over, makes the state grow by g per period)."""
    dwells = sorted(int(d) for d in dwells)
    if not dwells or dwells[0] < 1:
        raise ValueError(f"dwells {dwells} must be integers >= 1")
    powers_a, powers_b = _powers(A, dwells), _powers(B, dwells)
    best = (-1.0, (0, 0))
    for p, Ap in powers_a.items():
        for q, Bq in powers_b.items():
            rho = spectral_radius(Bq @ Ap)
            growth = rho ** (1.0 / (p + q)) if rho > 0 else 0.0
            if growth > best[0]:
                best = (growth, (p, q))
    return best


def _powers(A: np.ndarray, dwells: Sequence[int]) -> dict:
    """{d: A^d} for the sorted ``dwells``, each from the one before."""
    out, power, at = {}, np.eye(A.shape[0]), 0
    for d in dwells:
        power = np.linalg.matrix_power(A, d - at) @ power
        at = d
        out[d] = power
    return out
