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


def test_a_circle_shows_the_translations_across_its_axis_only():
    for contour, axis in ((CIRCLE, [0, 0, 1]), (TILTED, TILT @ [0, 0, 1])):
        model = edge_model(contour, 1.0 / MAX_AMPLIFICATION)
        assert model.basis.shape == (6, 2)
        np.testing.assert_allclose(model.shown, np.sqrt(0.5), rtol=1e-3)
        # pure translations, across the axis
        np.testing.assert_allclose(model.basis[3:], 0.0, atol=1e-12)
        np.testing.assert_allclose(axis @ model.basis[:3], 0.0, atol=1e-12)
        assert model.names()[0].startswith("translation")


def test_a_straight_edge_shows_its_heading_only():
    line = StraightContour(
        [0.3, -0.02, 0.05], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], length=0.04
    )
    model = edge_model(line, 1.0 / MAX_AMPLIFICATION)
    assert model.basis.shape == (6, 1)
    np.testing.assert_allclose(np.abs(model.basis[:, 0]), [0, 0, 0, 0, 0, 1])
    # the heading of a line from -L/2 to L/2 about its middle:
    # (s - s_pivot) / L has RMS 1
    np.testing.assert_allclose(model.shown, [1.0], rtol=1e-2)
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


def test_least_squares_on_the_force_recovers_the_shown_part_of_a_move():
    """The force c0 + c1 (delta_0 - d) along the tilted rim, the real
    rim moved by MOVE: the fit returns MOVE's part across the axis, and
    nothing of its turn or its move along the axis (the pivot is the
    rim's centre: a turn about it moves no point of the rim along n1)."""
    model = edge_model(TILTED, 1.0 / MAX_AMPLIFICATION)
    R, t = move_of(MOVE, model.pivot)
    real = PosedContour(TILTED, R, t)
    c0, c1 = 2.0, 9000.0
    theta = np.array([3.0, 4000.0, 0.0, 0.0])
    P = np.diag([9.0, 4000.0**2, 4.0, 4.0])
    for k, s in enumerate(np.linspace(0.0, 2 * TILTED.length, 400)):
        # the depth settles in, as the force loop brings it (a constant
        # depth cannot tell c1 from c0)
        depth = 5e-4 * (1.0 - np.exp(-k / 60.0))
        x = TILTED.point_at(s) + depth * TILTED.n1(TILTED.point_at(s))
        f_n = c0 + c1 * float(real.depth(x))
        phi = edge_contact_regressor(model, TILTED, x)
        theta, P = rls_update(theta, P, phi, f_n, noise_var=1e-6, forgetting=1)
    found = edge_registration_of(model, theta)
    axis = TILT @ [0.0, 0.0, 1.0]
    across = MOVE[:3] - (MOVE[:3] @ axis) * axis
    # to within the second-order terms of a 0.15 deg turn of an 8 mm rim
    np.testing.assert_allclose(found[:3], across, atol=2e-7)
    np.testing.assert_allclose(found[3:], 0.0, atol=1e-12)
    assert theta[1] == pytest.approx(c1, rel=1e-3)
