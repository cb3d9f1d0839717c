"""Tests of deburr_drake.math.fuzzy: eqs. (24)-(35) of Hsu & Fu, corrections R1,
R4, R8."""

import math

import numpy as np
import pytest

from deburr_drake.math.fuzzy import (
    RuleBase,
    active_indices,
    bspline_membership,
    bspline_membership_derivative,
    dead_zone,
    default_dead_zone_half_width,
)

ORDERS = [0, 1, 2, 3]


def cox_de_boor(y, m, delta):
    """Independent construction: normalized B-spline B_{0,m} on knots
    x_l = (l - (m+1)/2) * delta, l = 0..m+1, by the Cox-de Boor recursion."""
    knots = [(l - 0.5 * (m + 1)) * delta for l in range(m + 2)]

    def b(l, p, x):
        if p == 0:
            return 1.0 if knots[l] <= x < knots[l + 1] else 0.0
        left = (x - knots[l]) / (knots[l + p] - knots[l]) * b(l, p - 1, x)
        right = (
            (knots[l + p + 1] - x)
            / (knots[l + p + 1] - knots[l + 1])
            * b(l + 1, p - 1, x)
        )
        return left + right

    return b(0, m, y)


# ---------------------------------------------------------------------------
# B-spline membership (24), R1


@pytest.mark.parametrize("m", ORDERS)
def test_partition_of_unity_inside_omega(m):
    rng = np.random.default_rng(m)
    delta, U = 0.37, 5
    # away from the edges of Omega by the half-support
    y = rng.uniform(-(U - (m + 1) / 2) * delta, (U - (m + 1) / 2) * delta, 500)
    total = sum(
        bspline_membership(y - i * delta, m, delta) for i in range(-U, U + 1)
    )
    np.testing.assert_allclose(total, 1.0, atol=1e-12)


@pytest.mark.parametrize("m", ORDERS)
def test_support_symmetry_positivity(m):
    delta = 0.6
    h = 0.5 * (m + 1) * delta
    rng = np.random.default_rng(10 + m)
    outside = np.concatenate(
        [
            rng.uniform(h, 5 * h, 200),
            rng.uniform(-5 * h, -h - 1e-12, 200),
            [h, np.inf, -np.inf],
        ]
    )
    np.testing.assert_array_equal(bspline_membership(outside, m, delta), 0.0)
    inside = rng.uniform(-h, h, 500)
    inside = inside[np.abs(inside) < h]
    assert np.all(bspline_membership(inside, m, delta) > 0.0)
    if m >= 1:
        np.testing.assert_array_equal(bspline_membership(-h, m, delta), 0.0)
        np.testing.assert_allclose(
            bspline_membership(inside, m, delta),
            bspline_membership(-inside, m, delta),
            atol=1e-14,
        )
    else:
        # half-open indicator of [-delta/2, delta/2)
        assert bspline_membership(-h, 0, delta) == 1.0
        assert bspline_membership(h, 0, delta) == 0.0


def test_r1_peak_values_not_scaled_by_delta():
    delta = 0.2  # != 1: without the 1/delta**m factor N_1(0) would be 0.2
    assert bspline_membership(0.0, 1, delta) == pytest.approx(1.0, abs=1e-15)
    assert bspline_membership(0.0, 2, delta) == pytest.approx(0.75, abs=1e-15)
    assert bspline_membership(0.0, 3, delta) == pytest.approx(
        2.0 / 3.0, abs=1e-15
    )
    assert bspline_membership(0.0, 0, delta) == 1.0
    assert bspline_membership(0.5 * delta, 1, delta) == pytest.approx(
        0.5, abs=1e-15
    )


@pytest.mark.parametrize("m", ORDERS)
def test_equals_cox_de_boor(m):
    delta = 0.45
    rng = np.random.default_rng(20 + m)
    y = rng.uniform(-(m + 2) / 2 * delta, (m + 2) / 2 * delta, 300)
    expected = np.array([cox_de_boor(v, m, delta) for v in y])
    np.testing.assert_allclose(
        bspline_membership(y, m, delta), expected, atol=1e-12
    )


def test_vectorized_shape_and_nan():
    y = np.linspace(-1, 1, 12).reshape(3, 4)
    assert bspline_membership(y, 2, 0.5).shape == (3, 4)
    assert bspline_membership_derivative(y, 3, 0.5).shape == (3, 4)
    assert math.isnan(bspline_membership(np.nan, 2, 0.5))


@pytest.mark.parametrize("m", [1, 2, 3])
def test_derivative_matches_finite_difference(m):
    delta, eps = 0.3, 1e-6
    rng = np.random.default_rng(30 + m)
    y = rng.uniform(-(m + 1) / 2 * delta, (m + 1) / 2 * delta, 300)
    # stay away from knots (where m = 1 has a kink)
    t = y / delta + (m + 1) / 2
    y = y[np.abs(t - np.round(t)) > 1e-3]
    fd = (
        bspline_membership(y + eps, m, delta)
        - bspline_membership(y - eps, m, delta)
    ) / (2 * eps)
    np.testing.assert_allclose(
        bspline_membership_derivative(y, m, delta), fd, atol=1e-6
    )
    np.testing.assert_array_equal(
        bspline_membership_derivative(y, 0, delta), 0.0
    )


@pytest.mark.parametrize("m", ORDERS)
def test_continuity_at_knots(m):
    """C^(m-1): value jumps vanish for m >= 1, derivative jumps vanish for m >=
    2, m = 1 has derivative jumps 1/delta (outer knots) and 2/delta (centre)."""
    delta, eps = 0.7, 1e-9
    knots = (np.arange(m + 2) - (m + 1) / 2) * delta
    val_jump = bspline_membership(knots + eps, m, delta) - bspline_membership(
        knots - eps, m, delta
    )
    der_jump = bspline_membership_derivative(
        knots + eps, m, delta
    ) - bspline_membership_derivative(knots - eps, m, delta)
    if m == 0:
        np.testing.assert_allclose(val_jump, [1.0, -1.0], atol=1e-12)
        return
    np.testing.assert_allclose(val_jump, 0.0, atol=1e-8)
    if m >= 2:
        np.testing.assert_allclose(der_jump, 0.0, atol=1e-7)
    else:
        np.testing.assert_allclose(
            der_jump, [1 / delta, -2 / delta, 1 / delta], rtol=1e-6
        )


@pytest.mark.parametrize("m", ORDERS)
def test_active_indices_match_positive_memberships(m):
    delta = 0.25
    rng = np.random.default_rng(40 + m)
    for y in rng.uniform(-2.0, 2.0, 200):
        idx = active_indices(y, m, delta)
        assert len(idx) == m + 1 and np.all(np.diff(idx) == 1)
        cand = np.arange(-20, 21)
        pos = cand[bspline_membership(y - cand * delta, m, delta) > 0]
        np.testing.assert_array_equal(idx, pos)


def test_active_indices_m0_half_open():
    delta = 0.25
    y = 0.125  # = delta/2: belongs to rule 1 ([delta/2, 3delta/2)), not rule 0
    np.testing.assert_array_equal(active_indices(y, 0, delta), [1])
    assert bspline_membership(y - 1 * delta, 0, delta) == 1.0
    assert bspline_membership(y - 0 * delta, 0, delta) == 0.0


# ---------------------------------------------------------------------------
# Rule base (30), R8


def dense_u(rb, theta, y0, yk):
    """Dense double sum of eq. (30) over all (2U+1)^2 rules."""
    u = 0.0
    U = rb.upsilon
    for i in range(-U, U + 1):
        for j in range(-U, U + 1):
            nu = bspline_membership(
                y0 - i * rb.delta0, rb.m, rb.delta0
            ) * bspline_membership(yk - j * rb.deltak, rb.m, rb.deltak)
            u += nu * theta[(i + U) * (2 * U + 1) + (j + U)]
    return float(u)


@pytest.mark.parametrize("m", ORDERS)
def test_sparse_evaluate_equals_dense_sum(m):
    rb = RuleBase(m=m, upsilon=3, delta0=0.2, deltak=0.05)
    rng = np.random.default_rng(50 + m)
    theta = rng.normal(size=rb.n_rules)
    # include points near and beyond the edges of Omega (fewer active rules
    # there)
    y0s = rng.uniform(
        -1.3 * rb.omega0_half_width, 1.3 * rb.omega0_half_width, 60
    )
    yks = rng.uniform(
        -1.3 * rb.omegak_half_width, 1.3 * rb.omegak_half_width, 60
    )
    for y0, yk in zip(y0s, yks):
        assert rb.evaluate(theta, y0, yk) == pytest.approx(
            dense_u(rb, theta, y0, yk), abs=1e-12
        )


@pytest.mark.parametrize("m", ORDERS)
def test_active_rule_count(m):
    rb = RuleBase(m=m, upsilon=5, delta0=0.2, deltak=0.1)
    rng = np.random.default_rng(60 + m)
    inner0 = rb.omega0_half_width - (m + 1) / 2 * rb.delta0
    innerk = rb.omegak_half_width - (m + 1) / 2 * rb.deltak
    for y0, yk in zip(
        rng.uniform(-inner0, inner0, 100), rng.uniform(-innerk, innerk, 100)
    ):
        idx, nu = rb.active_rules(y0, yk)
        assert len(idx) == (m + 1) ** 2 == len(nu)
        assert len(set(idx.tolist())) == len(idx)
        assert nu.sum() == pytest.approx(1.0, abs=1e-12)
    # far outside: no rule
    idx, nu = rb.active_rules(0.0, 10 * rb.omegak_half_width)
    assert len(idx) == 0 and len(nu) == 0
    assert (
        rb.evaluate(np.ones(rb.n_rules), 0.0, 10 * rb.omegak_half_width) == 0.0
    )


def test_layout_and_n_rules():
    rb = RuleBase(m=2, upsilon=5, delta0=0.2, deltak=0.2)
    assert rb.n_rules == 121  # paper: 242 = 2 axes * 11^2 (R8)
    assert rb.omega0_half_width == pytest.approx(1.0)
    assert rb.omegak_half_width == pytest.approx(1.0)
    assert rb.flat_index(-5, -5) == 0 and rb.flat_index(5, 5) == 120
    assert rb.flat_index(1, -2) == 6 * 11 + 3
    theta = np.arange(121.0)
    grid = rb.theta_grid(theta)
    assert grid.shape == (11, 11) and grid[6, 3] == theta[rb.flat_index(1, -2)]
    # rule at (i, j) = (1, -2) alone: y0 = 1*delta0, yk = -2*deltak
    idx, nu = rb.active_rules(0.2, -0.4)
    assert idx[np.argmax(nu)] == rb.flat_index(1, -2)


@pytest.mark.parametrize("m", ORDERS)
def test_proposition2_sign(m):
    U = 5
    rb = RuleBase(m=m, upsilon=U, delta0=0.2, deltak=0.1)
    rng = np.random.default_rng(70 + m)
    grid = np.zeros((2 * U + 1, 2 * U + 1))
    jj = np.arange(-U, U + 1)
    mag = rng.uniform(0.1, 3.0, grid.shape)
    grid[:, jj < 0] = -mag[:, jj < 0]
    grid[:, jj > 0] = mag[:, jj > 0]
    grid[:, U] = 100.0 * rng.normal(
        size=2 * U + 1
    )  # j = 0: arbitrary, inactive outside the dead zone
    theta = grid.ravel()
    h = (m + 1) / 2 * rb.deltak
    n_checked = 0
    for y0 in rng.uniform(-rb.omega0_half_width, rb.omega0_half_width, 300):
        yk = rng.choice([-1, 1]) * rng.uniform(h, rb.omegak_half_width)
        if abs(yk) <= h:
            continue
        u = rb.evaluate(theta, y0, yk)
        assert np.sign(u) == np.sign(yk), (y0, yk, u)
        n_checked += 1
    assert n_checked > 250


# ---------------------------------------------------------------------------
# Dead zone (31), R4, and adaptation (35)


def test_dead_zone_default_r4():
    assert default_dead_zone_half_width(2, 0.2) == pytest.approx(0.3)
    assert default_dead_zone_half_width(0, 0.2) == pytest.approx(0.1)
    assert RuleBase(
        m=3, upsilon=5, delta0=0.2, deltak=0.1
    ).resolved_dead_zone_half_width == pytest.approx(0.2)
    rb = RuleBase(
        m=1, upsilon=5, delta0=0.2, deltak=0.1, dead_zone_half_width=0.05
    )
    assert rb.resolved_dead_zone_half_width == 0.05
    assert dead_zone(0.29, 0.3) == 0.0
    assert dead_zone(0.3, 0.3) == 0.0
    assert dead_zone(-0.31, 0.3) == -0.31
    np.testing.assert_array_equal(
        dead_zone(np.array([-0.5, 0.1, 0.5]), 0.3), [-0.5, 0.0, 0.5]
    )


def test_adaptation_rate():
    rb = RuleBase(m=2, upsilon=5, delta0=0.2, deltak=0.1)
    r = 3.5
    hw = rb.resolved_dead_zone_half_width
    # inside the dead zone: zero on the active rules
    idx, dth = rb.adaptation_rate(0.1, 0.9 * hw, r)
    assert len(idx) == 9
    np.testing.assert_array_equal(dth, 0.0)
    # outside Omega_k but still with active (edge) rules: zero
    yk = rb.omegak_half_width + 0.5 * rb.deltak
    assert not rb.in_domain(yk)
    idx, dth = rb.adaptation_rate(0.1, yk, r)
    assert len(idx) > 0
    np.testing.assert_array_equal(dth, 0.0)
    # far outside: nothing
    idx, dth = rb.adaptation_rate(0.1, 5.0, r)
    assert len(idx) == 0 and len(dth) == 0
    # active: r * nu * yk
    rng = np.random.default_rng(80)
    theta = rng.normal(size=rb.n_rules)
    for y0, yk in [(0.13, -0.37), (-0.71, 0.44), (0.0, 0.5), (0.9, -0.31)]:
        assert rb.in_domain(yk) and abs(yk) > hw
        idx, dth = rb.adaptation_rate(y0, yk, r)
        idx2, nu = rb.active_rules(y0, yk)
        np.testing.assert_array_equal(idx, idx2)
        np.testing.assert_allclose(dth, r * nu * yk, rtol=1e-14)
        u, idx3, dth3 = rb.evaluate_and_rate(theta, y0, yk, r)
        np.testing.assert_array_equal(idx3, idx)
        np.testing.assert_allclose(dth3, dth, rtol=1e-14)
        assert u == pytest.approx(rb.evaluate(theta, y0, yk), abs=1e-14)


def test_in_domain_edges():
    rb = RuleBase(m=2, upsilon=5, delta0=0.2, deltak=0.1)
    assert rb.in_domain(0.5) and rb.in_domain(-0.5) and rb.in_domain(0.0)
    assert not rb.in_domain(0.5000001) and not rb.in_domain(-0.51)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(m=4), "m"),
        (dict(m=-1), "m"),
        (dict(m=1.0), "m"),
        (dict(upsilon=0), "upsilon"),
        (dict(upsilon=2.5), "upsilon"),
        (dict(delta0=0.0), "delta0"),
        (dict(delta0=np.inf), "delta0"),
        (dict(deltak=-0.1), "deltak"),
        (dict(deltak=np.nan), "deltak"),
        (dict(dead_zone_half_width=-0.01), "dead_zone_half_width"),
        (dict(dead_zone_half_width=0.51), "dead_zone_half_width"),
        (
            dict(m=3, upsilon=1),
            "dead_zone_half_width",
        ),  # default 2*deltak > U*deltak
    ],
)
def test_validation_names_field(kwargs, field):
    args = dict(m=2, upsilon=5, delta0=0.2, deltak=0.1)
    args.update(kwargs)
    with pytest.raises(ValueError, match=field):
        RuleBase(**args)


def test_function_argument_validation():
    with pytest.raises(ValueError, match="m"):
        bspline_membership(0.0, 4, 0.1)
    with pytest.raises(ValueError, match="delta"):
        bspline_membership(0.0, 2, 0.0)
    with pytest.raises(ValueError, match="delta"):
        active_indices(0.0, 2, -1.0)
    with pytest.raises(ValueError, match="yk"):
        RuleBase(m=2, upsilon=5, delta0=0.2, deltak=0.1).active_rules(
            0.0, np.nan
        )


# ---------------------------------------------------------------------------
# T-generic (AutoDiffXd)


@pytest.mark.parametrize("m", [1, 2, 3])
def test_autodiff_membership_derivative(m):
    ad = pytest.importorskip("pydrake.autodiffutils")
    delta = 0.3
    rng = np.random.default_rng(90 + m)
    y = rng.uniform(-(m + 1) / 2 * delta * 1.1, (m + 1) / 2 * delta * 1.1, 50)
    y_ad = np.array(
        [ad.AutoDiffXd(v, np.array([1.0])) for v in y], dtype=object
    )
    out = bspline_membership(y_ad, m, delta)
    vals = np.array([o.value() for o in out])
    ders = np.array(
        [o.derivatives()[0] if o.derivatives().size else 0.0 for o in out]
    )
    np.testing.assert_allclose(
        vals, bspline_membership(y, m, delta), atol=1e-14
    )
    np.testing.assert_allclose(
        ders, bspline_membership_derivative(y, m, delta), atol=1e-12
    )
    # scalar AutoDiff in, AutoDiff out
    s = bspline_membership(ad.AutoDiffXd(0.1, np.array([1.0])), m, delta)
    assert s.derivatives()[0] == pytest.approx(
        float(bspline_membership_derivative(0.1, m, delta))
    )
    # dead zone is T-generic
    z = dead_zone(ad.AutoDiffXd(0.1, np.array([1.0])), 0.3)
    assert z.value() == 0.0


@pytest.mark.parametrize("m", [1, 2, 3])
def test_autodiff_rule_base_gradient(m):
    ad = pytest.importorskip("pydrake.autodiffutils")
    rb = RuleBase(m=m, upsilon=4, delta0=0.25, deltak=0.1)
    rng = np.random.default_rng(100 + m)
    theta = rng.normal(size=rb.n_rules)
    eps = 1e-6
    for y0, yk in [(0.13, -0.27), (-0.61, 0.33), (0.9, 0.057)]:  # off the knots
        a0 = ad.AutoDiffXd(y0, np.array([1.0, 0.0]))
        ak = ad.AutoDiffXd(yk, np.array([0.0, 1.0]))
        u, idx, dth = rb.evaluate_and_rate(theta, a0, ak, 2.0)
        assert u.value() == pytest.approx(rb.evaluate(theta, y0, yk), abs=1e-14)
        g = u.derivatives()
        g0 = (
            rb.evaluate(theta, y0 + eps, yk) - rb.evaluate(theta, y0 - eps, yk)
        ) / (2 * eps)
        gk = (
            rb.evaluate(theta, y0, yk + eps) - rb.evaluate(theta, y0, yk - eps)
        ) / (2 * eps)
        np.testing.assert_allclose(g, [g0, gk], atol=1e-5)
        _, dth_f = rb.adaptation_rate(y0, yk, 2.0)
        np.testing.assert_allclose([d.value() for d in dth], dth_f, atol=1e-14)


@pytest.mark.parametrize("m", [1, 2, 3])
def test_slope_rate_bounds_the_surface_slope(m):
    """Following slope_rate alone (Euler at 2.5 ms), a steep learned
    surface settles with |d u / d yk| <= max_slope everywhere (checked on a
    fine grid of yk), its mean weight kept; a surface within the bound is
    left alone."""
    rb = RuleBase(m=m, upsilon=5, delta0=0.2, deltak=0.004)
    n = 11
    theta = np.zeros((n, n))
    theta[7] = [0, 0, 0, 0, -17.6, 12.2, 31.4, 18.5, 21.3, 19.6, 10.7]
    theta = theta.ravel()
    bound = 2400.0  # N s/m
    assert np.all(rb.slope_rate(theta * 0.2, bound, 80.0) == 0.0)
    assert np.all(rb.slope_rate(theta, math.inf, 80.0) == 0.0)
    x = theta.copy()
    for _ in range(2000):
        x = x + 0.0025 * rb.slope_rate(x, bound, 80.0)
    assert x.sum() == pytest.approx(theta.sum())
    yk = np.linspace(-0.018, 0.018, 2001)
    u = np.array([rb.evaluate(x, 0.4, y) for y in yk])
    slope = np.abs(np.diff(u) / np.diff(yk))
    assert slope.max() <= bound * 1.01
    u0 = np.array([rb.evaluate(theta, 0.4, y) for y in yk])
    assert np.abs(np.diff(u0) / np.diff(yk)).max() > 1.5 * bound


@pytest.mark.parametrize("m", [1, 2, 3])
def test_the_slope_rate_bound_holds_for_the_adaptation_law(m):
    rb = RuleBase(m=m, upsilon=5, delta0=0.02, deltak=0.001)
    r, yk0 = 2000.0, 0.0004
    general = rb.slope_rate_bound(r)
    at_point = rb.slope_rate_bound(r, yk0)
    assert at_point <= general == pytest.approx(r * 5)
    h = 1e-3 * rb.deltak

    def slope(theta, y):
        return (
            rb.evaluate(theta, 0.03, y + h) - rb.evaluate(theta, 0.03, y - h)
        ) / (2 * h)

    rng = np.random.default_rng(0)
    worst = 0.0
    for _ in range(400):
        y0 = 0.03 if rng.uniform() < 0.5 else rng.uniform(0.0, 0.1)
        yk = rng.uniform(-1.0, 1.0) * rb.omegak_half_width
        idx, rate = rb.adaptation_rate(y0, yk, r)
        dtheta = np.zeros(rb.n_rules)
        dtheta[idx] = rate
        # The slope at yk0 is linear in theta: its rate is the slope of
        # the rates' surface (at the y0 the slope is read at).
        worst = max(worst, abs(slope(dtheta, yk0)))
    assert worst <= at_point * (1 + 1e-6)
    assert worst >= 0.04 * at_point  # not vacuous (m = 3: within 20x)
