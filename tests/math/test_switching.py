"""Growth under switching (deburr_drake.math.switching): known answers."""

import numpy as np
import pytest

from deburr_drake.math.switching import (
    DWELLS,
    periodic_growth,
    spectral_radius,
)


def test_the_shear_pair_grows_by_the_golden_ratio():
    # alpha [[1, 1], [0, 1]] and alpha [[1, 0], [1, 1]]: each of radius
    # alpha, their joint spectral radius alpha (1 + sqrt 5) / 2, reached
    # by alternating them.
    alpha = 0.7
    A = alpha * np.array([[1.0, 1.0], [0.0, 1.0]])
    B = alpha * np.array([[1.0, 0.0], [1.0, 1.0]])
    assert spectral_radius(A) == pytest.approx(alpha)
    growth, (p, q) = periodic_growth(A, B)
    assert growth == pytest.approx(alpha * (1 + 5**0.5) / 2, rel=1e-9)
    assert growth > 1.0 and (p, q) == (1, 1)


def test_a_pair_with_a_common_lyapunov_function_does_not_grow():
    # Both contract the Euclidean norm by 0.95 at most: every product
    # shrinks, and the growth found is at most 0.95.
    rng = np.random.default_rng(3)
    maps = []
    for _ in range(2):
        Q, _ = np.linalg.qr(rng.standard_normal((6, 6)))
        maps.append(0.95 * Q @ np.diag(rng.uniform(0.5, 1.0, 6)))
    growth, _ = periodic_growth(*maps)
    assert 0.0 < growth <= 0.95 + 1e-12


def test_a_slow_pair_needs_long_dwells():
    # Two lightly damped oscillators whose axes are turned: growth comes
    # from holding each for about a quarter of its period (8 periods
    # here), not from alternating every period.
    def oscillator(turn, r=0.999, w=2 * np.pi / 32, k=1.1):
        R = np.array([[np.cos(w), -np.sin(w)], [np.sin(w), np.cos(w)]])
        S = np.diag([k, 1 / k])
        T = np.array(
            [[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]]
        )
        return r * T @ S @ R @ np.linalg.inv(S) @ T.T

    A, B = oscillator(0.0), oscillator(np.pi / 2)
    assert spectral_radius(A) == pytest.approx(0.999)
    growth, (p, q) = periodic_growth(A, B)
    assert growth > 1.02
    # Alternating every period does not grow.
    assert periodic_growth(A, B, dwells=[1])[0] < 1.0
    assert (p, q) == (8, 8)


def test_dwells_are_checked():
    A = np.eye(2)
    with pytest.raises(ValueError, match="dwells"):
        periodic_growth(A, A, dwells=[0, 1])
    assert DWELLS[0] == 1 and DWELLS[-1] == 256
