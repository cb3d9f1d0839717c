"""The reduced normal-axis model's pieces: the contact fit and its bound,
the piecewise-quadratic compensator, the sampled map."""

import numpy as np
import pytest

from deburr_drake.math.region import (
    IN,
    ONSET,
    OUT,
    NormalAxisModel,
    fit_contact_law,
    piecewise_quadratic,
)


def _power_law(depths):
    return 1.0e4 * 1e-3 * (np.asarray(depths) / 1e-3) ** 1.4


def test_a_polynomial_law_is_fitted_exactly():
    d = np.linspace(0.0, 1e-3, 21)
    f = 3.0e3 * d + 2.0e6 * d**2
    fit = fit_contact_law(d, f, degree=2, anchor=5e-4, anchor_force=2.0)
    np.testing.assert_allclose(fit.coefficients, [3.0e3, 2.0e6], rtol=1e-8)
    assert fit.max_residual < 1e-9


def test_a_fit_of_depth_to_the_1_4_passes_its_anchor_and_bounds_it():
    d = np.linspace(0.0, 1e-3, 81)
    f = _power_law(d)
    anchor = 5e-4
    fit = fit_contact_law(
        d, f, degree=2, anchor=anchor, anchor_force=float(_power_law(anchor))
    )
    assert fit(0.0) == 0.0
    assert fit(anchor) == pytest.approx(_power_law(anchor), rel=1e-12)
    r = f - np.array([fit(x) for x in d])
    assert np.all(np.abs(r) <= fit.max_residual + 1e-12)
    assert np.all(np.abs(r) <= fit.sector * np.abs(d - anchor) + 1e-12)
    # A quadratic cannot be depth^1.4: the bound is not zero, and small.
    assert 0.05 < fit.max_residual < 0.05 * float(_power_law(1e-3))
    # The derivative is the polynomial's.
    h = 1e-9
    assert fit.derivative(3e-4) == pytest.approx(
        (fit(3e-4 + h) - fit(3e-4 - h)) / (2 * h), rel=1e-6
    )
    # The residual between the measured depths is interpolated, 0 out of
    # contact.
    assert fit.residual(-1e-4) == 0.0
    assert fit.residual(d[10]) == pytest.approx(r[10])


def test_a_fit_needs_its_anchor_within_the_depths():
    d = np.linspace(0.0, 1e-3, 5)
    with pytest.raises(ValueError, match="anchor"):
        fit_contact_law(d, d, degree=2, anchor=2e-3, anchor_force=1.0)


def _three_pieces(s):
    if s < -1.0:
        return -2.0
    if s < 1.0:
        return 1.0 + s - s * s
    return 3.0 * s - 2.0


def test_piecewise_quadratic_is_exact_and_finds_cells():
    pq = piecewise_quadratic(_three_pieces, [-1.0, 1.0])
    assert pq.n_cells == 3
    for s in (-5.0, -1.5, -0.3, 0.0, 0.9, 1.2, 7.0):
        assert pq(s) == pytest.approx(_three_pieces(s), abs=1e-9)
    assert pq.cell(-3.0) == 0 and pq.cell(0.0) == 1 and pq.cell(3.0) == 2


def test_piecewise_quadratic_refuses_a_function_that_is_not_quadratic():
    with pytest.raises(ValueError, match="not a quadratic"):
        piecewise_quadratic(np.sin, [-1.0, 1.0])


def _model():
    d = np.linspace(0.0, 1e-3, 41)
    anchor = 5e-4
    fit = fit_contact_law(
        d,
        _power_law(d),
        degree=2,
        anchor=anchor,
        anchor_force=float(_power_law(anchor)),
    )
    compensator = piecewise_quadratic(_three_pieces, [-1.0, 1.0])
    return NormalAxisModel(
        mass=9.0,
        sliding_gain=400.0,
        sliding_lambda=100.0,
        depth_gain=4e-4,
        sensor_alpha=0.145,
        period=0.0025,
        desired_force=2.0 + float(_power_law(anchor)),
        disturbance=-_three_pieces(0.0),
        threshold_force=2.0,
        threshold_depth=2e-5,
        damping=3.0,
        friction_slope=1500.0,
        friction=lambda v: 1.0 * np.tanh(v / 1e-3),
        contact=fit,
        compensator=compensator,
    )


def test_the_equilibrium_is_a_fixed_point_of_the_map():
    model = _model()
    x = model.equilibrium()
    assert model.sliding(x) == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(model.step(x, w=0.0), x, rtol=0, atol=1e-12)


def test_the_contact_regions_and_their_forces():
    model = _model()
    assert model.contact_region(-1e-6) == OUT
    assert model.contact_region(1e-5) == ONSET
    assert model.contact_region(1e-4) == IN
    # c0's onset reaches c0 at the onset's end, continuously.
    f_onset, _ = model.normal_force(2e-5, 0.0, ONSET)
    f_in, _ = model.normal_force(2e-5, 0.0, IN)
    assert f_onset == pytest.approx(f_in)
    assert model.normal_force(-1e-4, 0.3, OUT) == (0.0, 0.0)


def test_the_map_loses_contact_and_comes_back():
    """A reference 1 mm out of the part: the tool leaves it, the depth law
    brings it back (the sampled map stays bounded)."""
    model = _model()
    x0 = model.equilibrium() + np.array([0, 0, 0, -1e-3])
    path = model.simulate(x0, 2000)
    assert path[:, 0].min() < 0
    assert abs(path[-1, 0] - model.equilibrium()[0]) < 5e-6


def test_the_symbolic_map_is_the_float_map():
    from pydrake.symbolic import Variable

    model = _model()
    names = [Variable(n) for n in ("d", "v", "y", "r")]
    w, phi = Variable("w"), Variable("phi")
    x = np.array([3e-4, 1e-3, 4.0, 2e-4])
    cell, contact = model.region_of(x)
    symbolic = model.step_in_region(np.array(names), w, cell, contact, phi)
    values = dict(zip(names + [w, phi], list(x) + [0.1, 2.0]))
    numeric = model.step_in_region(x, 0.1, cell, contact, 2.0)
    got = [e.Evaluate(values) for e in symbolic]
    np.testing.assert_allclose(got, numeric, rtol=1e-12, atol=1e-15)


def test_the_taylor_step_follows_the_period_s_exact_integration():
    """Over one period with the force held, the third-order step against
    scipy's integration of M delta'' = U - F(delta) - c delta' - phi
    (the contact in one region), from a state 0.2 mm and 10 mm/s off:
    the neglected fourth-order term is a few nm."""
    from scipy.integrate import solve_ivp

    model = _model()
    x = model.equilibrium() + np.array([2e-4, 1e-2, 0.5, 1e-4])
    cell, contact = model.region_of(x)
    phi = model.friction(x[1])
    s = model.sliding(x)
    u = (
        model.sliding_gain * s
        + x[2]
        + model.compensator.piece(cell, s)
        + model.disturbance
    )

    def rhs(_, z):
        force, _ = model.normal_force(z[0], 0.0, contact)
        return [z[1], (u - force - model.damping * x[1] - phi) / model.mass]

    exact = solve_ivp(rhs, (0, model.period), x[:2], rtol=1e-12, atol=1e-15).y[
        :, -1
    ]
    step = model.step_in_region(x, 0.0, cell, contact, phi)
    # The period moves the depth by 21 um and the rate by 3.1 mm/s here.
    assert abs(step[0] - exact[0]) < 5e-9
    assert abs(step[1] - exact[1]) < 1e-5
