"""Tests of deburr_drake.math.profile: closed profiles with filleted,
offset corners."""

import math

import numpy as np
import pytest

from deburr_drake.math.geometry import CircularContour
from deburr_drake.math.profile import (
    ProfileContour,
    polyline_self_intersection,
)

C = np.array([0.5, -0.2, 0.3])

RECT = [[-0.03, -0.02], [0.03, -0.02], [0.03, 0.02], [-0.03, 0.02]]
L_SHAPE = [
    [-0.03, -0.03],
    [0.03, -0.03],
    [0.03, 0.0],
    [0.0, 0.0],
    [0.0, 0.03],
    [-0.03, 0.03],
]
DUMBBELL = [
    [-0.04, -0.015],
    [-0.01, -0.015],
    [-0.01, -0.002],
    [0.01, -0.002],
    [0.01, -0.015],
    [0.04, -0.015],
    [0.04, 0.015],
    [0.01, 0.015],
    [0.01, 0.002],
    [-0.01, 0.002],
    [-0.01, 0.015],
    [-0.04, 0.015],
]
Z = 0.048


def prof(vertices=RECT, fillet=0.008, **kw):
    kw.setdefault("center", [0.4, 0.1, Z])
    return ProfileContour(vertices, fillet, **kw)


def test_square_of_side_2R_with_fillets_R_is_the_circle():
    R, r = 0.03, 0.003
    sq = ProfileContour(
        [[-R, -R], [R, -R], [R, R], [-R, R]],
        R,
        offset=r,
        center=C,
        start_angle=0.4,
        direction=-1,
    )
    ci = CircularContour(C, R - r, start_angle=0.4, direction=-1)
    assert sq.length == pytest.approx(ci.length, rel=1e-12)
    v = np.array([0.002, -0.001, 0.0])
    for s in np.linspace(0.0, ci.length, 17):
        np.testing.assert_allclose(sq.point_at(s), ci.point_at(s), atol=1e-12)
        p = ci.point_at(s) + 4e-4 * ci.n1(ci.point_at(s))
        for a, b in zip(sq.frame(p), ci.frame(p)):
            np.testing.assert_allclose(a, b, atol=1e-12)
        np.testing.assert_allclose(
            sq.n1_rate(p, v), ci.n1_rate(p, v), atol=1e-12
        )
        assert sq.curvature(p) == pytest.approx(ci.curvature(p))


def test_rounded_rectangle_pocket_lines_and_fillets():
    c = prof(offset=0.003)
    # path: lines shifted 3 mm inward, fillets of 8 - 3 = 5 mm
    assert c.length == pytest.approx(
        2 * (0.06 + 0.04) - 8 * 0.008 + 2 * math.pi * 0.005
    )
    p = np.array([0.4 + 0.01, 0.1 - 0.02 + 0.003 - 0.0004, 1.0])  # bottom side
    assert c.depth(p) == pytest.approx(4e-4, abs=1e-12)
    np.testing.assert_allclose(c.n1(p), [0, -1, 0], atol=1e-12)
    np.testing.assert_allclose(c.tangent(p), [1, 0, 0], atol=1e-12)
    assert c.curvature(p) == 0.0
    np.testing.assert_allclose(c.n1_rate(p, [0.01, 0.0, 0.0]), 0.0)
    # corner at (0.03, -0.02): fillet centre (0.022, -0.012), path radius 5 mm
    cc = np.array([0.4 + 0.022, 0.1 - 0.012])
    q = np.array([*(cc + 0.0053 * np.array([1, -1]) / math.sqrt(2)), Z])
    assert c.depth(q) == pytest.approx(3e-4, abs=1e-12)
    np.testing.assert_allclose(
        c.n1(q), [1 / math.sqrt(2), -1 / math.sqrt(2), 0], atol=1e-12
    )
    assert c.curvature(q) == pytest.approx(1 / 0.005)
    assert c.depth(np.array([0.4, 0.1, Z])) < 0  # the pocket's middle: free


def test_boss_material_inside_convex_fillets():
    c = prof(material="inside", offset=0.003, start_angle=0.0)
    assert c.length == pytest.approx(
        2 * (0.06 + 0.04) - 8 * 0.008 + 2 * math.pi * 0.011
    )
    assert c.depth(np.array([0.4, 0.1, Z])) > 0  # the boss's middle
    p0 = c.point_at(0.0)
    np.testing.assert_allclose(p0, [0.4 + 0.033, 0.1, Z], atol=1e-12)
    np.testing.assert_allclose(c.n1(p0), [-1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(c.tangent(p0), [0, 1, 0], atol=1e-12)
    corner = c.point_at(0.012 + 0.5 * math.pi / 2 * 0.011)
    assert c.curvature(corner) == pytest.approx(-1 / 0.011)


@pytest.mark.parametrize(
    "make",
    [
        lambda: prof(offset=0.003),
        lambda: prof(material="inside", offset=0.003, direction=-1),
        lambda: prof(L_SHAPE, 0.005, offset=0.003, start_angle=-2.0),
        lambda: prof(
            L_SHAPE, 0.004, material="inside", offset=0.003, start_angle=2.0
        ),
    ],
)
def test_profile_derivatives_and_round_trip(make):
    c = make()
    h = 1e-7
    v = np.array([0.003, -0.002, 0.0])
    for s in np.linspace(0.0, c.length, 41, endpoint=False):
        x = c.point_at(s)
        assert c.arc_position(x) == pytest.approx(s, abs=1e-9) or abs(
            c.arc_position(x) - s
        ) == pytest.approx(c.length, abs=1e-9)
        assert c.depth(x) == pytest.approx(0.0, abs=1e-12)
        p = x + 3e-4 * c.n1(x) + np.array([0, 0, 0.01])
        assert c.depth(p) == pytest.approx(3e-4, abs=1e-10)
        g = np.array(
            [(c.phi(p + h * e) - c.phi(p - h * e)) / (2 * h) for e in np.eye(3)]
        )
        np.testing.assert_allclose(c.grad_phi(p), g, atol=1e-6)
        assert abs(c.n1(p) @ c.tangent(p)) < 1e-12
        # the tangent runs the traversal direction
        ahead = c.arc_position(c.project(p) + 1e-6 * c.tangent(p))
        assert (ahead - c.arc_position(p)) % c.length < 1e-5
        # n1_rate = d n1 / dt along v, away from the line/arc joints
        n_a, n_b = c.n1(p - h * v), c.n1(p + h * v)
        if c.curvature(p - h * v) == c.curvature(p + h * v):
            np.testing.assert_allclose(
                c.n1_rate(p, v), (n_b - n_a) / (2 * h), atol=1e-5
            )
        frame = c.frame(p)
        np.testing.assert_allclose(frame[0], c.n1(p), atol=1e-12)
        np.testing.assert_allclose(frame[1], c.tangent(p), atol=1e-12)
        assert frame[2] == pytest.approx(c.depth(p), abs=1e-15)
        assert frame[3] == pytest.approx(c.arc_position(p), abs=1e-12)


def test_dumbbell_pocket_with_a_channel_wide_enough():
    c = prof(
        [[x, 3.0 * y] for x, y in DUMBBELL],
        0.0035,
        offset=0.003,
        start_angle=0.5,
    )
    assert c.depth(np.array([0.4, 0.1, Z])) < 0


def test_l_shaped_pocket_inner_corner_is_convex_for_the_cutter():
    c = prof(L_SHAPE, 0.005, offset=0.003, start_angle=-0.5)
    kappas = sorted(k for _, _, k, _, _ in c.arcs())
    # five pocket corners 1 / (5 - 3 mm), the re-entrant one -1 / (5 + 3 mm)
    np.testing.assert_allclose(kappas, [-1 / 0.008] + [1 / 0.002] * 5)


@pytest.mark.parametrize(
    "vertices, fillet, kw, message",
    [
        (RECT, 0.002, {"offset": 0.003}, "larger than the cutter radius"),
        (
            [[0, 0], [0.05, 0.05], [0.05, 0], [0, 0.05]],
            0.002,
            {},
            "counter-clockwise|intersects itself",
        ),
        (
            [[0, 0], [0.05, 0], [0.05, 0.05], [0.0, 0.05], [0.06, 0.02]],
            0.002,
            {},
            "intersects itself",
        ),
        ([[0, 0], [0.05, 0], [0.05, 0], [0, 0.05]], 0.002, {}, "coincide"),
        (RECT[::-1], 0.002, {}, "counter-clockwise"),
        ([[0, 0], [0.01, 0]], 0.002, {}, "at least 3"),
        (RECT, 0.025, {}, "do not fit"),
        # two pockets joined by a channel 4 mm wide: the 3 mm cutter's path
        # overlaps itself there
        (DUMBBELL, 0.0035, {"offset": 0.003}, "overlaps itself"),
        (
            [[0.01, 0.01], [0.03, 0.01], [0.03, 0.03]],
            0.001,
            {},
            "meets no point",
        ),
    ],
)
def test_bad_profiles_are_refused_with_a_reason(vertices, fillet, kw, message):
    with pytest.raises(ValueError, match=message):
        prof(vertices, fillet, **kw)


def test_polyline_self_intersection():
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    assert polyline_self_intersection(square) is None
    bow = np.array([[0, 0], [1, 1], [1, 0], [0, 1]], float)
    assert polyline_self_intersection(bow) is not None


# An L-shaped pocket whose origin is its inner (reflex) corner, vertex 3.
L_POCKET = L_SHAPE


def test_an_l_pocket_with_its_origin_on_a_vertex_starts_at_the_vertex():
    center = [0.4, 0.0, Z]
    with pytest.raises(ValueError, match="start_vertex or start_fraction"):
        ProfileContour(L_POCKET, 0.006, offset=0.003, center=center)
    path = ProfileContour(
        L_POCKET, 0.006, offset=0.003, center=center, start_vertex=3
    )
    # The middle of the reflex corner's fillet: the arc of radius 6 + 3 mm
    # about the fillet's centre (6, 6) mm, on the diagonal to the vertex.
    d = 0.009 - 0.006 * math.sqrt(2)
    np.testing.assert_allclose(
        path.point_at(0.0),
        [0.4 - d / math.sqrt(2), -d / math.sqrt(2), Z],
        atol=1e-12,
    )
    # The same point whatever the direction; the offset path keeps it.
    back = ProfileContour(
        L_POCKET,
        0.006,
        offset=0.003,
        center=center,
        start_vertex=3,
        direction=-1,
    )
    np.testing.assert_allclose(back.point_at(0.0), path.point_at(0.0))
    np.testing.assert_allclose(
        path.with_offset(0.0).point_at(0.0)[:2],
        np.array(center[:2]) + 0.006 * (1 - 1 / math.sqrt(2)) * np.ones(2),
        atol=1e-12,
    )


def test_start_fraction_counts_from_vertex_0_counter_clockwise():
    at_0 = prof(start_vertex=0)
    for f in (0.0, 0.3, 0.75):
        path = prof(start_fraction=f)
        np.testing.assert_allclose(
            path.point_at(0.0), at_0.point_at(f * at_0.length), atol=1e-12
        )
    # Vertex 2 of the rectangle is half the (symmetric) path from vertex 0.
    np.testing.assert_allclose(
        prof(start_fraction=0.5).point_at(0.0),
        prof(start_vertex=2).point_at(0.0),
        atol=1e-12,
    )
    for bad, match in (
        (dict(start_vertex=4), "start_vertex must be a vertex index"),
        (dict(start_fraction=1.0), r"start_fraction must be in \[0, 1\)"),
        (dict(start_vertex=0, start_fraction=0.1), "not both"),
    ):
        with pytest.raises(ValueError, match=match):
            prof(**bad)
