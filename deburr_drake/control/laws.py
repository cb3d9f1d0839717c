"""The baseline control laws' task-space terms as pure functions (no Drake):
the robust term H of (22) with the Appendix's gains, impedance along n1 and
the ideal law's reference acceleration. ``HybridController`` evaluates them
in place of the fuzzy compensator; everything else is shared."""

from __future__ import annotations

__all__ = ["robust_term", "appendix_gains", "impedance_force", "sign"]


def _value(y):
    return y.value() if hasattr(y, "value") else float(y)


def sign(x):
    """sgn(x) in {-1, 0, 1} (T-generic: a constant of x's type)."""
    v = _value(x)
    return (1.0 if v > 0 else -1.0 if v < 0 else 0.0) + 0.0 * x


def robust_term(s_k, x_norm, gains):
    """H(||x||, s_k) of (22) on one task axis:
    (b1 + b2 ||x|| + b3 ||x||^2) sgn(s_k) + (b4 + b5 ||x||) s_k (N)."""
    b1, b2, b3, b4, b5 = gains
    return (b1 + b2 * x_norm + b3 * x_norm**2) * sign(s_k) + (
        b4 + b5 * x_norm
    ) * s_k


def appendix_gains(*, m_bar, h0, h1, h2, h3, d0, d1, d2, lambda_bar):
    """b1..b5 of the Appendix from the bounds P1 (m_bar, kg), P2 (h0 N s/m,
    h1 N s^2/m^2), A1 (h2 N, h3 N s/m), A2 (d0 m, d1 m/s, d2 m/s^2) and
    D1 (lambda_bar 1/s).

    On the paper cell (m_bar = 36 kg task inertia, lambda_bar = 100 1/s,
    d0 = ||x_d|| = 0.43 m, d1 = 5 mm/s, d2 = 0.04 m/s^2, h2 = 5 N,
    h0 = h1 = h3 = 1) this gives b1 = 1.6e5 N (the term lambda^2 m d0
    alone is 1.55e5 N) and b4 = 3.6e3 N s/m, above the sampled loop's
    M / T = 2800 N s/m: the literal bounds are the "overestimated" gains of
    the paper's Section III.B. ``RobustConfig`` therefore defaults to
    b1 = 5 N (h2 + m_bar d2, rounded up) and b2..b5 = 0."""
    lb = lambda_bar
    b1 = (
        m_bar * d2
        + h2
        + d1 * h0
        + d1 * h3
        + d1**2 * h1
        + lb**2 * m_bar * d0
        + lb * d0 * h0
        + lb * d0 * h3
        + lb**2 * d0**2 * h1
        + 2 * lb * d0 * d1 * h1
    )
    b2 = lb * (h0 + h3 + m_bar + 2 * h1 * d1 + 2 * lb * d0 * h1)
    b3 = lb**2 * h1
    b4 = h3 + m_bar * lb + lb * d0 * h1 + d1 * h1
    b5 = lb * h1
    return [b1, b2, b3, b4, b5]


def impedance_force(e, edot, n1, s, *, stiffness, damping, gain):
    """Impedance along n1 and a PD elsewhere (N):
    f = n1 (k n1.e + d n1.edot) + (I - n1 n1^T) (K * s).
    ``e``, ``edot``: nominal-path error and its rate; ``gain``: K per task
    axis; no force feedback."""
    e_n = n1 @ e
    edot_n = n1 @ edot
    ks = gain * s
    return n1 * (stiffness * e_n + damping * edot_n) + ks - n1 * (n1 @ ks)
