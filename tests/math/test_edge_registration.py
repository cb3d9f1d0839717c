"""A 3-D edge's registration while cutting: the correction on a pose
registration, and what the force along n1 shows of a small rigid
move."""

import numpy as np
import pytest

from deburr_drake.math.edge_registration import (
    carried_pivot,
    corrected,
    edge_contact_regressor,
    edge_model,
    edge_offset_terms,
    edge_pivot,
    edge_registration_of,
    move_of,
    observable_directions,
)
from deburr_drake.math.geometry import CircularContour, StraightContour
from deburr_drake.math.profile import ProfileContour
from deburr_drake.math.registration import (
    MAX_AMPLIFICATION,
    PosedContour,
    rls_update,
)
from deburr_drake.math.rigid import rotvec_matrix, rpy_matrix

CIRCLE = CircularContour([0.95, 0.0, 0.5], 0.008)
# The same circle in a plane tilted 30 deg about x (an inclined hole's rim).
TILT = rpy_matrix([np.radians(30.0), 0.0, 0.0])
TILTED = PosedContour(
    CIRCLE, TILT, CIRCLE.center - TILT @ CIRCLE.center + [0.0, 0.001, 0.0]
)
# A rounded rectangle, 40 x 20 mm: straight sides and fillets.
PROFILE = ProfileContour(
    [[-0.02, -0.01], [0.02, -0.01], [0.02, 0.01], [-0.02, 0.01]],
    0.004,
    center=(0.4, 0.0, 0.05),
)
MOVE = np.array([1.2e-4, -0.8e-4, 0.6e-4, 0.0021, -0.0017, 0.0026])


def test_a_correction_moves_the_registered_edge_about_its_carried_pivot():
    pivot = np.array([0.9, 0.1, 0.4])
    base = np.array([0.01, -0.02, 0.015, 1e-3, -2e-3, 5e-4, 1e-4])
    correction = np.array([-3e-4, 1e-4, 2e-4, -0.004, 0.003, 0.008])
    x = np.random.default_rng(0).normal(size=(10, 3)) * 0.01 + pivot
    R_b, p_b = rotvec_matrix(base[:3]), base[3:6]
    c = R_b @ pivot + p_b
    np.testing.assert_allclose(carried_pivot(base, pivot), c)
    R_c, t_c = move_of(correction, c)
    # the correction turns about c and moves it by v
    np.testing.assert_allclose(R_c @ c + t_c, c + correction[:3])
    np.testing.assert_allclose(R_c, rotvec_matrix(correction[3:]))
    total = corrected(base, correction, pivot)
    expected = (R_c @ (R_b @ x.T + p_b[:, None]) + t_c[:, None]).T
    found = (rotvec_matrix(total[:3]) @ x.T).T + total[3:6]
    np.testing.assert_allclose(found, expected, atol=1e-15)
    assert total[6] == base[6]  # the size is the probe's
    # no correction: the registration as it was
    np.testing.assert_allclose(corrected(base, np.zeros(6), pivot), base)


def test_offset_terms_are_the_first_order_move_along_n1():
    """d = g . (v, L omega): the depth a point of the reference path has
    on the reference moved by a small move is -d, to second order."""
    pivot, L = edge_pivot(TILTED)
    for scale in (1e-2, 1e-3):
        move = MOVE * scale
        R, t = move_of(move, pivot)
        real = PosedContour(TILTED, R, t)
        s = np.linspace(0.0, TILTED.length, 16, endpoint=False)
        x = np.array([TILTED.point_at(v) for v in s])
        n1 = np.array([TILTED.n1(p) for p in x])
        g = edge_offset_terms(x, n1, pivot, L)
        d = g @ np.concatenate([move[:3], L * move[3:]])
        depth = np.array([real.depth(p) for p in x])
        # second order in the move: the error falls a hundredfold
        np.testing.assert_allclose(-depth, d, atol=3e-3 * scale**2)


def test_a_circle_shows_no_move_its_tilt_does_not_make():
    """Around a rim the move across the axis makes the first harmonic of
    the force; so does a tilt, which raises the rim on one side (the
    engaged height), and the tool's lean: the model leaves the move
    alone and estimates the two harmonics as nuisances."""
    for contour in (CIRCLE, TILTED):
        model = edge_model(contour, 1.0 / MAX_AMPLIFICATION)
        assert model.basis.shape == (6, 0)
        assert model.nuisance.shape == (256, 2)
        s = model.arcs
        x = np.array([contour.point_at(v) for v in s])
        n1 = np.array([contour.n1(p) for p in x])
        g = edge_offset_terms(x, n1, model.pivot, model.length)
        # the nuisances span the translations' first harmonic
        explained = np.column_stack([np.ones(len(s)), model.nuisance])
        fit, *_ = np.linalg.lstsq(explained, g[:, :3], rcond=None)
        np.testing.assert_allclose(explained @ fit, g[:, :3], atol=1e-12)


def test_a_straight_edge_leaves_its_heading_to_the_roll():
    """Along a straight edge the heading varies d linearly; a roll of the
    part about n1 tilts the top face along the edge and varies the
    engaged height linearly too: nothing is estimated."""
    line = StraightContour(
        [0.3, -0.02, 0.05], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], length=0.04
    )
    model = edge_model(line, 1.0 / MAX_AMPLIFICATION)
    assert model.basis.shape == (6, 0)
    assert model.nuisance.shape[1] == 1
    assert model.period == 0.0


def test_a_profile_shows_its_turn_about_the_axis_only():
    """On a profile n1 is constant along each side: a move across the
    axis shows there as the tool's lean does (n1 . (beta x a)), and is
    left alone; the turn about the axis varies d along each side, which
    neither a lean nor a tilt's rise does."""
    model = edge_model(PROFILE, 1.0 / MAX_AMPLIFICATION)
    assert model.basis.shape == (6, 1)
    np.testing.assert_allclose(
        np.abs(model.basis[:, 0]), [0, 0, 0, 0, 0, 1], atol=1e-12
    )
    assert model.shown[0] > 1.0 / MAX_AMPLIFICATION
    assert model.names() == ["rotation about z +1.00"]


def test_observable_directions_leave_out_what_does_not_vary():
    s = np.linspace(0.0, 2 * np.pi, 200, endpoint=False)
    g = np.column_stack(
        [np.cos(s), np.sin(s), np.ones_like(s), 0.05 * np.cos(3 * s)]
    )
    basis, shown = observable_directions(g, 0.1)
    np.testing.assert_allclose(shown, [np.sqrt(0.5)] * 2, rtol=1e-12)
    np.testing.assert_allclose(basis[2:], 0.0, atol=1e-12)
    basis, shown = observable_directions(g, 0.01)
    assert basis.shape == (4, 3)


def _fit_on(contour, real, force_of, seconds=400):
    """theta after RLS on the force ``force_of(x, s)`` along ``contour``
    (the reference), the depth settling in as the force loop brings it."""
    model = edge_model(contour, 1.0 / MAX_AMPLIFICATION)
    k, j = model.basis.shape[1], model.nuisance.shape[1]
    theta = np.concatenate([[3.0, 4000.0], np.zeros(k + j)])
    P = np.diag([9.0, 4000.0**2] + [4.0] * k + [9.0] * j)
    for i, s in enumerate(np.linspace(0.0, 2 * contour.length, seconds)):
        # a constant depth cannot tell c1 from c0
        depth = 5e-4 * (1.0 - np.exp(-i / 60.0))
        x = contour.point_at(s) + depth * contour.n1(contour.point_at(s))
        phi = edge_contact_regressor(model, contour, x)
        f_n = force_of(x, contour.arc_position(x))
        theta, P = rls_update(theta, P, phi, f_n, noise_var=1e-6, forgetting=1)
    return model, theta


def test_least_squares_on_the_force_recovers_the_shown_part_of_a_move():
    """The force c0 + c1 (delta_0 - d) along a profile, the real profile
    moved by MOVE: the fit returns MOVE's turn about the axis (what the
    force tells from a lean and a tilt), nothing else."""
    pivot, _ = edge_pivot(PROFILE)
    R, t = move_of(MOVE, pivot)
    real = PosedContour(PROFILE, R, t)
    c0, c1 = 2.0, 9000.0
    model, theta = _fit_on(
        PROFILE, real, lambda x, s: c0 + c1 * float(real.depth(x))
    )
    found = edge_registration_of(model, theta)
    np.testing.assert_allclose(found[:5], 0.0, atol=1e-12)
    # to within the second-order terms of a 0.15 deg turn
    assert found[5] == pytest.approx(MOVE[5], rel=0.02)
    assert theta[1] == pytest.approx(c1, rel=1e-2)


def test_a_tilted_part_rising_along_the_tool_makes_no_move():
    """The tilted rim's force scaled by its engaged height as a 0.2 deg
    tilt raises it on one side: no move comes of it (before, 0.04 mm
    across the axis in simulation)."""
    model = edge_model(TILTED, 1.0 / MAX_AMPLIFICATION)
    axis = TILT @ [0.0, 0.0, 1.0]
    omega = np.radians(0.2) * (TILT @ [1.0, 0.0, 0.0])
    engaged = 0.002

    def force(x, s):
        rise = axis @ np.cross(omega, x - model.pivot)
        return (2.0 + 9000.0 * float(TILTED.depth(x))) * (1 + rise / engaged)

    model, theta = _fit_on(TILTED, TILTED, force)
    np.testing.assert_array_equal(edge_registration_of(model, theta), 0.0)
