"""The damper's exact mean force over a held interval."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from deburr_drake.math.damping import held_damper_end_speed, held_damper_mean


def _integrated(c, offset, u0, beta, b, h):
    """(mean of F, u(h)) by a tight numerical integration."""
    sol = solve_ivp(
        lambda t, y: [b - beta * (c * y[0] + offset), c * y[0] + offset],
        (0.0, h),
        [u0, 0.0],
        rtol=1e-12,
        atol=1e-15,
        method="DOP853",
    )
    return sol.y[1, -1] / h, sol.y[0, -1]


@pytest.mark.parametrize("x", [1e-6, 5e-4, 2e-3, 0.3, 1.16, 7.5, 60.0])
def test_mean_matches_the_integrated_damper(x):
    # alpha h = x on the paper arm's numbers: m = 7 kg, h = 2.5 ms.
    beta, h, offset, u0, b = 1.0 / 7.0, 0.0025, 0.9, 2.4e-3, 1.7
    c = x / (beta * h)
    for p in (0.0, -0.8):
        k0, k1 = held_damper_mean(c, offset, u0, beta, b, h)
        mean, end = _integrated(c, offset, u0, beta, b + p, h)
        assert k0 + k1 * p == pytest.approx(mean, rel=1e-9, abs=1e-12)
        # one constant force at the mean gives the exact end speed
        assert u0 + h * (b + p - beta * (k0 + k1 * p)) == pytest.approx(
            end, rel=1e-9, abs=1e-15
        )
    assert held_damper_end_speed(c, offset, u0, beta, b, h) == pytest.approx(
        _integrated(c, offset, u0, beta, b, h)[1], rel=1e-9
    )


def test_limits():
    beta, h, offset, u0, b = 0.2, 0.0025, 0.5, 1e-3, 3.0
    # no damping: the force at u0, nothing from p
    assert held_damper_mean(0.0, offset, u0, beta, b, h) == (offset, 0.0)
    assert held_damper_mean(5000.0, offset, u0, 0.0, b, h) == (
        5000.0 * u0 + offset,
        0.0,
    )
    # stiff: the force that stops u within h and holds it at rest,
    # u0 / (beta h) + (b + p) / beta
    k0, k1 = held_damper_mean(1e9, offset, u0, beta, b, h)
    assert k0 == pytest.approx(u0 / (beta * h) + b / beta, rel=1e-5)
    assert k1 == pytest.approx(1.0 / beta, rel=1e-5)
    # the series and the closed form meet where they switch
    c_switch = 1e-3 / (beta * h)
    below = held_damper_mean(c_switch * (1 - 1e-9), offset, u0, beta, b, h)
    above = held_damper_mean(c_switch * (1 + 1e-9), offset, u0, beta, b, h)
    np.testing.assert_allclose(below, above, rtol=1e-8)


def test_explicit_euler_alternates_where_the_mean_decays():
    """At alpha h = 7.5 an explicit step with F(u0) multiplies u by
    1 - 7.5 (growing, alternating); the held mean by exp(-7.5)."""
    beta, h, c = 1.0, 0.0025, 3000.0
    u = 0.05
    for _ in range(4):
        k0, _ = held_damper_mean(c, 0.0, u, beta, 0.0, h)
        u_next = u - h * beta * k0
        assert u_next / u == pytest.approx(np.exp(-7.5), rel=1e-9)
        u = u_next


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="c = -1"):
        held_damper_mean(-1.0, 0.0, 0.0, 1.0, 0.0, 0.0025)
    with pytest.raises(ValueError, match="h = 0"):
        held_damper_mean(1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
