"""The believed contour moved onto the real one from points on the real
edge (circle: centre, optionally radius; straight: offset and heading;
profile: move and turn), early (burr) touches dropped, and the online
model's regressor."""

import math

import numpy as np
import pytest

from deburr_drake.math.geometry import CircularContour, StraightContour
from deburr_drake.math.profile import ProfileContour
from deburr_drake.math.registration import (
    moved_contour,
    pivot_of,
    registration_from_points,
    rigid_fit_amplification,
    size_amplification,
)


def test_circle_centre_registered_and_burr_point_dropped():
    believed = CircularContour([0.4, 0.0, 0.048], 0.027)
    real = CircularContour([0.4006, -0.0004, 0.048], 0.027)
    s = np.arange(8) * real.length / 8
    pts = np.array([real.point_at(x) for x in s])
    pts[1] -= 0.0008 * real.n1(pts[1])  # touched a burr 0.8 mm early
    fit = registration_from_points(believed, pts, max_residual=1e-4)
    np.testing.assert_allclose(fit.registration, [6e-4, -4e-4, 0, 0], atol=1e-9)
    assert list(np.flatnonzero(~fit.kept)) == [1]
    moved = moved_contour(believed, fit.registration)
    np.testing.assert_allclose(moved.center, real.center, atol=1e-9)


def test_circle_radius_fitted_when_asked():
    believed = CircularContour([0.0, 0.0, 0.0], 0.030)
    real = CircularContour([1e-4, 2e-4, 0.0], 0.0302)
    pts = np.array(
        [
            real.point_at(x)
            for x in np.linspace(0, real.length, 6, endpoint=False)
        ]
    )
    fit = registration_from_points(
        believed, pts, max_residual=1e-4, fit_radius=True
    )
    np.testing.assert_allclose(
        fit.registration, [1e-4, 2e-4, 0, 2e-4], atol=1e-9
    )


@pytest.mark.parametrize("dradius", [-3e-4, 2.5e-4])
def test_circle_radius_error_recovered_through_noise_and_a_burr(dradius):
    believed = CircularContour([0.4, 0.0, 0.048], 0.027)
    real = CircularContour([0.4005, -0.0006, 0.048], 0.027 + dradius)
    pts = _touches(real, 8, 0.003)
    pts[:, :2] += np.random.default_rng(5).normal(0.0, 3e-6, (8, 2))
    pts[1] -= 8e-4 * real.n1(pts[1])  # a burr, 0.8 mm early
    fit = registration_from_points(
        believed, pts, max_residual=5e-5, fit_radius=True
    )
    assert list(np.flatnonzero(~fit.kept)) == [1]
    assert fit.registration[3] == pytest.approx(dradius, abs=3e-6)
    np.testing.assert_allclose(fit.registration[:2], [5e-4, -6e-4], atol=5e-6)


def test_circle_radius_held_on_touches_within_a_half_circle():
    believed = CircularContour([0.0, 0.0, 0.0], 0.030)
    real = CircularContour([1e-4, 0.0, 0.0], 0.0302)
    pts = np.array(
        [real.point_at(s) for s in np.linspace(0.0, 0.4 * real.length, 5)]
    )
    fit = registration_from_points(
        believed, pts, max_residual=1e-3, fit_radius=True
    )
    assert fit.registration[3] == 0.0


@pytest.mark.parametrize("heading", [0.0, 0.7, -2.0])
def test_straight_edge_offset_and_heading(heading):
    t = np.array([math.cos(heading), math.sin(heading), 0.0])
    n = np.array([t[1], -t[0], 0.0])
    believed = StraightContour([0.3, 0.1, 0.05], t, n, length=0.06)
    real = moved_contour(believed, [3e-4, -5e-4, 0.01, 0.0])
    pts = np.array([real.point_at(x) for x in np.linspace(0.005, 0.055, 5)])
    fit = registration_from_points(believed, pts, max_residual=1e-4)
    moved = moved_contour(believed, fit.registration)
    assert fit.registration[2] == pytest.approx(0.01, abs=1e-12)
    for p in pts:
        assert moved.phi(p) == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(
        moved.material_normal, real.material_normal, atol=1e-12
    )


def test_zero_registration_is_the_same_contour():
    c = CircularContour([0.0, 0.0, 0.0], 0.03)
    assert moved_contour(c, np.zeros(4)) is c


def test_common_bias_kept_out_of_the_centre_and_no_point_dropped():
    # Every touch 0.15 mm past the edge (an uncompensated detection depth):
    # with the radius held, the centre is right and nothing is dropped.
    believed = CircularContour([0.4, 0.0, 0.048], 0.027)
    real = CircularContour([0.4003, 0.0002, 0.048], 0.027)
    pts = np.array(
        [
            real.point_at(x) + 1.5e-4 * real.n1(real.point_at(x))
            for x in np.linspace(0, real.length, 8, endpoint=False)
        ]
    )
    fit = registration_from_points(believed, pts, max_residual=1e-4)
    assert fit.kept.all()
    np.testing.assert_allclose(fit.registration[:2], [3e-4, 2e-4], atol=1e-9)


def test_burr_flank_touches_and_common_bias_leave_the_centre():
    """Two touches 0.15 and 0.12 mm early (a burr's flanks: within the
    old 0.1 mm rejection of the worst residual after a fit they pulled),
    every touch 0.14 mm past the edge (a detection bias), and a third
    touch on a burr 0.8 mm early: the centre within 1 um. The
    one-at-a-time rejection with the radius held is 20-60 um off on such
    touches."""
    believed = CircularContour([0.4, 0.0, 0.048], 0.049)
    real = CircularContour([0.3996, -0.0005, 0.048], 0.049)
    arcs = np.linspace(0, real.length, 8, endpoint=False)
    pts = []
    for k, s in enumerate(arcs):
        x = real.point_at(s)
        early = {1: 8e-4, 4: 1.5e-4, 6: 1.2e-4}.get(k, 0.0)
        pts.append(x + (1.4e-4 - early) * real.n1(x))
    fit = registration_from_points(believed, np.array(pts), max_residual=5e-5)
    assert list(np.flatnonzero(~fit.kept)) == [1, 4, 6]
    np.testing.assert_allclose(
        fit.registration, [-4e-4, -5e-4, 0, 0], atol=1e-6
    )


def test_straight_edge_flank_touches_dropped():
    believed = StraightContour(
        [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], length=0.06
    )
    real = moved_contour(believed, [2e-4, 5e-4, 0.008, 0.0])
    arcs = np.linspace(0.004, 0.056, 8)
    pts = []
    for k, s in enumerate(arcs):
        x = real.point_at(s)
        early = {2: 9e-5, 3: 7e-5, 6: 6e-4}.get(k, 0.0)
        pts.append(x - early * real.n1(x))
    fit = registration_from_points(believed, np.array(pts), max_residual=5e-5)
    assert list(np.flatnonzero(~fit.kept)) == [2, 3, 6]
    moved = moved_contour(believed, fit.registration)
    for s in (0.0, 0.03, 0.06):
        x = real.point_at(s)
        assert abs(moved.phi(x)) < 1e-7


def _online_fit(reference, real, arcs, c0=2.0, c1=1.0e4):
    """Fit the online model to exact forces c0 + c1 delta_real along
    ``arcs``, the depth on the reference varying (the force loop
    settling)."""
    from deburr_drake.math.registration import (
        contact_regressor,
        onset_regressor,
        registration_of,
        rls_update,
    )

    theta = np.array([3.0, 4000.0, 0.0, 0.0, 0.0])
    P = np.diag([4.0, 1e8, 100.0, 100.0, 1e4])
    # The contact onset at the entry, then the cut.
    x = reference.point_at(arcs[0])
    x = x + (reference.depth(x) - real.depth(x)) * reference.n1(x)
    theta, P = rls_update(
        theta,
        P,
        onset_regressor(reference, x),
        0.0,
        noise_var=1e-4,
        forgetting=1.0,
    )
    for k, s in enumerate(arcs):
        x = reference.point_at(s)
        depth = 5e-4 * (1 - np.exp(-k / 50)) + 1e-4 * np.sin(k / 7)
        x = x + (depth + reference.depth(x) - real.depth(x)) * reference.n1(x)
        f = c0 + c1 * real.depth(x)
        theta, P = rls_update(
            theta,
            P,
            contact_regressor(reference, x),
            f,
            noise_var=1e-4,
            forgetting=1.0,
        )
    return registration_of(reference, theta)


def test_online_model_recovers_a_circle_offset():
    reference = CircularContour([0.4, 0.0, 0.048], 0.027)
    real = moved_contour(reference, [4e-4, -3e-4, 0.0, 0.0])
    # 85 degrees of arc; the model is first order in |w| / R.
    reg = _online_fit(reference, real, np.linspace(0, 0.04, 400))
    np.testing.assert_allclose(reg, [4e-4, -3e-4, 0, 0], atol=1e-5)


def test_online_model_recovers_a_straight_edge_heading_and_offset():
    t = np.array([0.0, 1.0, 0.0])
    reference = StraightContour(
        [0.4, -0.03, 0.048], t, [1.0, 0.0, 0.0], length=0.06
    )
    real = moved_contour(reference, [3e-4, 0.0, 0.004, 0.0])
    reg = _online_fit(reference, real, np.linspace(0.0, 0.06, 400))
    moved = moved_contour(reference, reg)
    for s in (0.0, 0.03, 0.06):
        p = real.point_at(s)
        assert moved.phi(p) == pytest.approx(0.0, abs=5e-6)


# -- profiles (every contour kind) ---------------------------------------
def _pocket(**kw):
    # The pocket scenario's cutter path: 60 x 40 mm, 8 mm fillets, the
    # cutter (3 mm) inside.
    return ProfileContour(
        [[-0.03, -0.02], [0.03, -0.02], [0.03, 0.02], [-0.03, 0.02]],
        0.008,
        material="outside",
        offset=0.003,
        center=[0.4, 0.0, 0.048],
        **kw,
    )


def _boss(**kw):
    # The boss scenario's, off-centre vertices (the pivot is their
    # centroid, not ``center``): a 50 mm square, 10 mm fillets.
    return ProfileContour(
        [[-0.015, -0.02], [0.035, -0.02], [0.035, 0.03], [-0.015, 0.03]],
        0.010,
        material="inside",
        offset=0.003,
        center=[0.4, 0.0, 0.048],
        **kw,
    )


def _touches(real, n, first=0.0):
    return np.array(
        [real.point_at(first + k * real.length / n) for k in range(n)]
    )


# Even layouts that fix the move and turn (a square's mid-sides and
# mid-fillets see no turn: test_profile_touches_on_one_side_do_not_fix_it).
_FIRST = {"_pocket": 0.004, "_boss": 0.012}


@pytest.mark.parametrize("make", [_pocket, _boss])
def test_profile_moved_is_the_profile_built_moved(make):
    believed = make(start_angle=0.3)
    reg = [6e-4, -4e-4, 0.02, 0.0]
    moved = moved_contour(believed, reg)
    pivot = pivot_of(believed)
    np.testing.assert_allclose(
        pivot[:2], believed.center[:2] + believed.vertices.mean(axis=0)
    )
    R = np.array(
        [[math.cos(0.02), -math.sin(0.02)], [math.sin(0.02), math.cos(0.02)]]
    )
    center = believed.center
    center[:2] = pivot[:2] + R @ (center[:2] - pivot[:2]) + [6e-4, -4e-4]
    rebuilt = make(start_angle=0.32)
    rebuilt = ProfileContour(
        believed.vertices @ R.T,
        0.008 if make is _pocket else 0.010,
        material=rebuilt._material,
        offset=0.003,
        center=center,
        start_angle=0.32,
    )
    for s in np.linspace(0, believed.length, 37, endpoint=False):
        np.testing.assert_allclose(
            moved.point_at(s), rebuilt.point_at(s), atol=1e-12
        )
        # A material point moves rigidly with the part.
        q = believed.point_at(s) + 4e-4 * believed.n1(believed.point_at(s))
        q2 = q.copy()
        q2[:2] = pivot[:2] + R @ (q[:2] - pivot[:2]) + [6e-4, -4e-4]
        assert moved.phi(q2) == pytest.approx(believed.phi(q), abs=1e-12)
        assert moved.arc_position(q2) == pytest.approx(
            believed.arc_position(q), abs=1e-9
        )
        np.testing.assert_allclose(
            moved.n1(q2)[:2], R @ believed.n1(q)[:2], atol=1e-12
        )
    # There and back; the pivot moves with (dx, dy), so moves add.
    back = moved_contour(moved, [-6e-4, 4e-4, -0.02, 0.0])
    twice = moved_contour(
        moved_contour(believed, [1e-4, 0, 0.01, 0]), [5e-4, -4e-4, 0.01, 0]
    )
    for s in np.linspace(0, believed.length, 11, endpoint=False):
        np.testing.assert_allclose(
            back.point_at(s), believed.point_at(s), atol=1e-12
        )
        np.testing.assert_allclose(
            twice.point_at(s), moved.point_at(s), atol=1e-12
        )


def test_straight_edge_has_no_size_to_register():
    line = StraightContour([0, 0, 0], [1, 0, 0], [0, -1, 0], length=0.06)
    with pytest.raises(ValueError, match="dradius"):
        moved_contour(line, [1e-4, 0.0, 0.0, 1e-4])
    real = moved_contour(line, [0.0, 3e-4, 0.0, 0.0])
    pts = np.array([real.point_at(x) for x in np.linspace(0.005, 0.055, 5)])
    fit = registration_from_points(
        line, pts, max_residual=4e-5, fit_radius=True
    )
    np.testing.assert_allclose(fit.registration, [0, 3e-4, 0, 0], atol=1e-9)


@pytest.mark.parametrize("make", [_pocket, _boss])
def test_profile_grown_is_the_profile_built_larger(make):
    believed = make(start_angle=0.3)
    reg = [6e-4, -4e-4, 0.02, 2.5e-4]
    moved = moved_contour(believed, reg)
    built = moved_contour(believed.grown(2.5e-4), [*reg[:3], 0.0])
    for s in np.linspace(0.0, moved.length, 40, endpoint=False):
        np.testing.assert_allclose(
            moved.point_at(s), built.point_at(s), atol=1e-12
        )
    # Larger: the believed pocket's path inside the real one's (on its
    # free side), the believed boss's inside the real material.
    larger = moved_contour(believed, [0.0, 0.0, 0.0, 2.5e-4])
    for s in np.linspace(0.0, believed.length, 40, endpoint=False):
        assert larger.phi(believed.point_at(s)) == pytest.approx(
            -2.5e-4 if make is _boss else 2.5e-4, abs=1e-9
        )


@pytest.mark.parametrize("growth", [-3e-4, 2.5e-4])
@pytest.mark.parametrize("make", [_pocket, _boss])
def test_profile_size_registered_where_the_touches_tell_it(make, growth):
    believed = make()
    truth = [5e-4, -3e-4, 0.01, growth]
    real = moved_contour(believed, truth)
    pts = _touches(real, 8, _FIRST[make.__name__])
    rng = np.random.default_rng(3)
    pts[:, :2] += rng.normal(0.0, 2e-6, (8, 2))
    fit = registration_from_points(
        believed, pts, max_residual=4e-5, fit_radius=True
    )
    np.testing.assert_allclose(fit.registration[:2], truth[:2], atol=5e-6)
    assert fit.registration[3] == pytest.approx(growth, abs=3e-6)
    assert fit.level == 0.0
    # Held: the drawing's size, the growth left in the level.
    held = registration_from_points(believed, pts, max_residual=4e-5)
    assert held.registration[3] == 0.0
    assert abs(held.level) == pytest.approx(abs(growth), abs=1e-5)


def test_profile_size_held_when_the_touches_cannot_tell_it():
    # Touches on the bottom and the right side only: a growth moves them
    # as a move along (1, -1) would.
    believed = _pocket()
    real = moved_contour(believed, [2e-4, 1e-4, 0.0, 2e-4])
    bottom = [[x, -0.023, 0.048] for x in (0.38, 0.39, 0.40, 0.41)]
    right = [[0.433, y, 0.048] for y in (-0.005, 0.0, 0.005)]
    pts = np.array(
        [real.point_at(real.arc_position(np.array(p))) for p in bottom + right]
    )
    for p in pts:
        assert real.phi(p) == pytest.approx(0.0, abs=1e-9)
        assert real.curvature(p) == 0.0  # on the sides, not the fillets
    assert size_amplification(believed, pts) == math.inf
    fit = registration_from_points(
        believed, pts, max_residual=4e-5, fit_radius=True
    )
    assert fit.registration[3] == 0.0


@pytest.mark.parametrize("make", [_pocket, _boss])
@pytest.mark.parametrize(
    "reg", [[6e-4, -4e-4, 0.0], [-8e-4, 3e-4, 0.015], [2e-4, 9e-4, -0.02]]
)
def test_profile_fit_recovers_a_known_move(make, reg):
    believed = make()
    real = moved_contour(believed, [*reg, 0.0])
    pts = _touches(real, 8, first=_FIRST[make.__name__])
    fit = registration_from_points(believed, pts, max_residual=4e-5)
    np.testing.assert_allclose(fit.registration, [*reg, 0.0], atol=1e-10)
    assert fit.kept.all() and fit.rms < 1e-10


@pytest.mark.parametrize("make", [_pocket, _boss])
def test_profile_fit_with_noise_within_its_expected_spread(make):
    # 8 um RMS touch noise along n1 (the probe's qualification): over 40
    # draws the error of (dx, dy, L dyaw) stays within 4 sigma of what
    # the amplification predicts, and nothing is dropped wrongly often.
    believed = make()
    reg = np.array([5e-4, -7e-4, 0.012])
    real = moved_contour(believed, [*reg, 0.0])
    clean = _touches(real, 8, first=_FIRST[make.__name__])
    gain = rigid_fit_amplification(believed, clean)
    assert gain < 1.5  # spread around the whole edge: of order one
    L = float(
        np.sqrt(
            np.mean(np.sum((clean[:, :2] - pivot_of(real)[:2]) ** 2, axis=1))
        )
    )
    rng = np.random.default_rng(3)
    errors, dropped = [], 0
    for _ in range(40):
        pts = np.array(
            [p + 8e-6 * rng.standard_normal() * real.n1(p) for p in clean]
        )
        fit = registration_from_points(believed, pts, max_residual=4e-5)
        e = fit.registration[:3] - reg
        errors.append(np.abs([e[0], e[1], L * e[2]]))
        dropped += int((~fit.kept).sum())
    assert np.max(errors) < 4 * gain * 8e-6
    assert dropped <= 2


@pytest.mark.parametrize("make", [_pocket, _boss])
def test_profile_burr_touch_dropped_and_a_late_one_kept(make):
    believed = make()
    reg = [-6e-4, 5e-4, -0.01]
    real = moved_contour(believed, [*reg, 0.0])
    pts = _touches(real, 8, first=_FIRST[make.__name__])
    pts[2] -= 8e-4 * real.n1(pts[2])  # on a 0.8 mm burr: early
    pts[5] -= 9e-5 * real.n1(pts[5])  # on a burr's flank: 90 um early
    pts[6] += 3e-5 * real.n1(pts[6])  # 30 um late: within max_residual
    fit = registration_from_points(believed, pts, max_residual=4e-5)
    assert list(np.flatnonzero(~fit.kept)) == [2, 5]
    assert fit.residuals[2] > 7e-4 and fit.residuals[6] < 0
    # The late touch alone among the kept: the fit is off by a few um.
    np.testing.assert_allclose(fit.registration[:2], reg[:2], atol=2e-5)
    assert fit.registration[2] == pytest.approx(reg[2], abs=1e-3)


def test_profile_touches_on_one_side_do_not_fix_it():
    believed = _pocket()
    # All on the right side's straight piece (the start is its middle).
    pts = np.array([believed.point_at(s) for s in (-0.005, 0.0, 0.005, 0.008)])
    assert rigid_fit_amplification(believed, pts) == math.inf
    with pytest.raises(ValueError, match="do not fix"):
        registration_from_points(believed, pts, max_residual=4e-5)
    with pytest.raises(ValueError, match="do not fix"):
        registration_from_points(believed, pts[:2], max_residual=4e-5)
    # Two on one side and one on the next fix it.
    pts = np.array([believed.point_at(s) for s in (-0.008, 0.008, 0.03)])
    assert rigid_fit_amplification(believed, pts) < 10.0
    # A square's touches in the middle of every side and fillet see no
    # turn about its centre.
    square = ProfileContour(
        [[-0.025, -0.025], [0.025, -0.025], [0.025, 0.025], [-0.025, 0.025]],
        0.01,
        material="inside",
        offset=0.003,
    )
    assert rigid_fit_amplification(square, _touches(square, 8)) > 1e6


def test_straight_edge_touch_off_the_rest_dropped_either_side():
    # Of 8 touches, one 60 um late or early is dropped (late touches off
    # the rest happen too: docs/localisation.md), the fit exact.
    believed = StraightContour(
        [0.3, 0.1, 0.05], [1, 0, 0], [0, -1, 0], length=0.06
    )
    pts = np.array(
        [believed.point_at(s) for s in np.linspace(0.00375, 0.05625, 8)]
    )
    for sign in (1.0, -1.0):
        off = pts.copy()
        off[2] += sign * 6e-5 * believed.n1(off[2])
        fit = registration_from_points(believed, off, max_residual=4e-5)
        assert list(np.flatnonzero(~fit.kept)) == [2]
        np.testing.assert_allclose(fit.registration, 0.0, atol=1e-12)
        # Kept below the threshold.
        off = pts.copy()
        off[2] += sign * 3e-5 * believed.n1(off[2])
        assert registration_from_points(
            believed, off, max_residual=4e-5
        ).kept.all()


def _old_offset_terms(contour, x_p):
    """The circle's and straight edge's terms before the general form:
    (n1, 0) and (n1, s - s_pivot)."""
    n1 = contour.n1(x_p)
    if isinstance(contour, StraightContour):
        s = contour.arc_position(x_p) - contour.arc_position(pivot_of(contour))
        return np.array([n1[0], n1[1], s])
    return np.array([n1[0], n1[1], 0.0])


def test_general_regressor_is_the_old_one_on_circle_and_line():
    from deburr_drake.math.registration import contact_regressor

    circle = CircularContour([0.4, 0.0, 0.048], 0.027, start_angle=0.4)
    line = StraightContour(
        [0.4, -0.03, 0.048], [0.6, 0.8, 0.0], [0.8, -0.6, 0.0], length=0.06
    )
    for contour, sign in ((circle, 1.0), (line, -1.0)):
        for s in np.linspace(0.0, 0.06, 7):
            p = contour.point_at(s)
            x_p = p + 3e-4 * contour.n1(p) + [0, 0, 1e-3]
            new = contact_regressor(contour, x_p)
            old = np.concatenate(
                [[1.0, contour.depth(x_p)], -_old_offset_terms(contour, x_p)]
            )
            # psi is now the turn (counter-clockwise): minus the old
            # heading term on a straight edge.
            old[4] *= sign
            np.testing.assert_allclose(new, old, atol=1e-15)


@pytest.mark.parametrize("make", [_pocket, _boss])
def test_online_model_recovers_a_profile_move(make):
    reference = make()
    real = moved_contour(reference, [4e-4, -3e-4, 0.006, 0.0])
    # Around the whole edge: the move and the turn are all seen.
    reg = _online_fit(reference, real, np.linspace(0, reference.length, 800))
    np.testing.assert_allclose(reg[:2], [4e-4, -3e-4], atol=5e-6)
    assert reg[2] == pytest.approx(0.006, abs=2e-4)
    assert reg[3] == 0.0


@pytest.mark.parametrize("make", [_pocket, _boss])
def test_profile_common_detection_bias_is_not_taken_for_burrs(make):
    # Every touch 60 um early (a contact stiffer than modelled) and one on
    # a burr: only the burr is dropped, and the move is found (a common
    # bias moves no closed profile much).
    believed = make()
    reg = [3e-4, 6e-4, 0.008]
    real = moved_contour(believed, [*reg, 0.0])
    pts = np.array(
        [
            p - 6e-5 * real.n1(p)
            for p in _touches(real, 8, first=_FIRST[make.__name__])
        ]
    )
    pts[4] -= 7e-4 * real.n1(pts[4])
    fit = registration_from_points(believed, pts, max_residual=4e-5)
    assert list(np.flatnonzero(~fit.kept)) == [4]
    np.testing.assert_allclose(fit.registration[:2], reg[:2], atol=2e-5)
