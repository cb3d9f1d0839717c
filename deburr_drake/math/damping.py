"""A damper's exact mean force over a held interval (pure numpy).

Along one direction a of the joint velocities v (u = a . v) the cutting
force of eq. (3) is a damper with an offset, F(u) = c u + F_0, applied
through the joints as -a F. With everything else that acts on the arm
held over an interval h (the controller's 2.5 ms sample), the speed
obeys the scalar equation

    du/dt = b - beta F(u),   beta = a^T M^-1 a,  b = a^T M^-1 tau_other,

whose solution relaxes to its rest speed with the rate alpha = beta c:

    u(t) = u_inf + (u0 - u_inf) exp(-alpha t),  u_inf = (b/beta - F_0)/c.

Applied as one constant force over the interval, the mean of F over that
solution moves u from u0 to exactly u(h), whatever alpha h is: an explicit
step with that force is the exact discretization of the damper, not the
explicit Euler step that alternates and grows once alpha h > 2.
:func:`held_damper_mean` gives that mean as k0 + k1 p, linear in a part p
of b known only later (the controller's torque of the same sample).
"""

from __future__ import annotations

import math
from typing import Tuple

__all__ = ["held_damper_mean", "held_damper_end_speed"]

# Below this alpha h the closed forms lose digits to cancellation; their
# series (three terms: error below x^3 / 120 relative) are used instead.
_SERIES_BELOW = 1.0e-3


def _fractions(x: float) -> Tuple[float, float]:
    """(phi, 1 - phi), phi = (1 - exp(-x)) / x: the mean of exp(-x s)
    over s in [0, 1]."""
    if x < _SERIES_BELOW:
        rest = x / 2.0 - x * x / 6.0 + x**3 / 24.0
        return 1.0 - rest, rest
    decayed = -math.expm1(-x)
    return decayed / x, (x - decayed) / x


def held_damper_mean(
    c: float, offset: float, u0: float, beta: float, b: float, h: float
) -> Tuple[float, float]:
    """(k0, k1): the mean over [0, h] of F(u) = c u + ``offset`` along the
    solution of du/dt = b + p - beta F(u) from u(0) = ``u0`` is k0 + k1 p.

    c >= 0 (N s/m), beta >= 0 (1/kg: a^T M^-1 a), h > 0 (s); b and p in
    m/s^2. With c = 0 or beta = 0 the force is F(u0) and does not depend
    on p. As alpha h = beta c h grows the mean tends to u0 / (beta h) +
    (b + p) / beta, the force that stops u within h and holds it at
    rest; as it vanishes, to F(u0) +
    c h (b + p - beta F(u0)) / 2, the trapezoidal mean."""
    if c < 0.0 or beta < 0.0 or h <= 0.0:
        raise ValueError(
            f"held_damper_mean: c = {c}, beta = {beta} and "
            f"h = {h} must be c >= 0, beta >= 0, h > 0"
        )
    x = beta * c * h
    if x == 0.0:
        return c * u0 + offset, 0.0
    phi, rest = _fractions(x)
    k1 = rest / x * c * h  # (1 - phi) / beta without dividing by beta
    return c * phi * u0 + phi * offset + k1 * b, k1


def held_damper_end_speed(
    c: float, offset: float, u0: float, beta: float, b: float, h: float
) -> float:
    """u(h) of the equation of :func:`held_damper_mean` (p = 0), in closed
    form: what a constant force at that mean gives after h."""
    x = beta * c * h
    if x == 0.0:
        return u0 + h * (b - beta * (c * u0 + offset))
    u_inf = (b / beta - offset) / c
    return u_inf + (u0 - u_inf) * math.exp(-x)
