"""The tool's path along a 3-D edge against closed forms: the paper's bore
(a CircularContour), a circle in an inclined plane, the 120-degree wedge."""

import math
from pathlib import Path
import re

import numpy as np
import pytest
import trimesh

from deburr_drake.math.edge_contour import (
    EdgeContour,
    chamfer_area_ratio,
    spindle_clash,
)
from deburr_drake.math.geometry import CircularContour
from deburr_drake.math.mesh_part import (
    EdgeCurve,
    choose_edge,
    default_tool_rule,
    load_part,
    sharp_edges,
)

PARTS = Path(__file__).resolve().parents[2] / "models" / "parts"
R, TOP, r, e = 0.030, 0.050, 0.003, 0.002  # the paper's bore and cutter
INCLINE = math.radians(30.0)
HOLE = 0.010


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@pytest.fixture(scope="module")
def bore():
    """The tube's top inner edge (its loop starts at (-R, 0, TOP) and runs
    counter-clockwise seen from +z; its right face is the top face)."""
    part = load_part(PARTS / "tube.stl", units="mm")
    return EdgeCurve(choose_edge(sharp_edges(part), near=[R, 0.0, TOP]))


@pytest.fixture(scope="module")
def inclined(tmp_path_factory):
    """A hole of radius 10 mm through a round plate whose top face is
    tilted 30 degrees about x: the rim is a circle about the origin."""
    plate = trimesh.creation.annulus(
        r_min=10.0, r_max=40.0, height=20.0, sections=200
    )
    plate.apply_translation([0.0, 0.0, -10.0])
    plate.apply_transform(
        trimesh.transformations.rotation_matrix(INCLINE, [1, 0, 0])
    )
    path = tmp_path_factory.mktemp("parts") / "plate.stl"
    plate.export(path)
    part = load_part(path, units="mm")
    return EdgeCurve(choose_edge(sharp_edges(part), near=[HOLE, 0.0, 0.0]))


@pytest.fixture(scope="module")
def wedge():
    part = load_part(PARTS / "wedge.stl", units="mm")
    return EdgeCurve(choose_edge(sharp_edges(part), near=[0.04, 0.03, 0.02]))


def _bore_contour(curve, **kwargs):
    return EdgeContour(
        curve, cutter_radius=r, engagement=e, rule="right", **kwargs
    )


def _near_path(circle, rng, n=200):
    """Points near the circle's path: off it by up to 0.5 mm in depth and
    0.3 mm along the axis."""
    s = rng.uniform(0.0, circle.length, n)
    out = []
    for si in s:
        p = circle.point_at(si)
        p = p + rng.uniform(-5e-4, 5e-4) * circle.n1(p)
        out.append(p + [0.0, 0.0, rng.uniform(-3e-4, 3e-4)])
    return out


@pytest.mark.parametrize("direction", [1, -1])
def test_the_bore_is_the_papers_circle(bore, direction):
    contour = _bore_contour(bore, direction=direction)
    circle = CircularContour(
        [0.0, 0.0, TOP - e], R - r, start_angle=math.pi, direction=direction
    )
    assert contour.closed and contour.varying_frame
    assert contour.length == pytest.approx(circle.length, rel=1e-6)
    assert contour.height == pytest.approx(TOP - e, abs=1e-9)
    for s in np.linspace(0.0, circle.length, 37):
        np.testing.assert_allclose(
            contour.point_at(s), circle.point_at(s), atol=2e-6
        )
        np.testing.assert_allclose(
            contour.tool_axis_at(s), [0, 0, 1], atol=1e-5
        )
        np.testing.assert_allclose(contour.axis_turn(s), np.eye(3), atol=1e-5)
    for p in _near_path(circle, np.random.default_rng(3)):
        n1, t, depth, s = contour.frame(p)
        n1c, tc, depthc, sc = circle.frame(p)
        np.testing.assert_allclose(n1, n1c, atol=1e-5)
        np.testing.assert_allclose(t, tc, atol=1e-5)
        assert depth == pytest.approx(depthc, abs=2e-6)
        gap = (s - sc + 0.5 * circle.length) % circle.length
        assert gap - 0.5 * circle.length == pytest.approx(0.0, abs=2e-6)
        assert contour.phi(p) == pytest.approx(circle.phi(p), abs=2e-6)
        assert contour.depth(p) == pytest.approx(depth, abs=1e-12)
        np.testing.assert_allclose(contour.n1(p), n1, atol=1e-15)
        np.testing.assert_allclose(
            contour.project(p), circle.project(p), 0, 2e-6
        )
        assert contour.curvature(p) == pytest.approx(1 / (R - r), rel=1e-3)
        v = np.array([0.01, -0.02, 0.003])
        np.testing.assert_allclose(
            contour.n1_rate(p, v), circle.n1_rate(p, v), atol=1e-3 * 1.0
        )


def test_the_bore_edge_points_and_stations(bore):
    contour = _bore_contour(bore)
    for s in np.linspace(0.0, contour.length, 13):
        angle = math.pi + s / (R - r)
        np.testing.assert_allclose(
            contour.edge_point(s),
            [R * math.cos(angle), R * math.sin(angle), TOP],
            atol=2e-6,
        )
    st = contour.stations(1e-3)
    n = len(st.arc)
    assert n == round(2 * math.pi * R / 1e-3)
    assert st.arc[0] == 0.0 and np.all(np.diff(st.arc) > 0)
    np.testing.assert_allclose(
        st.arc, np.arange(n) * contour.length / n, atol=2e-6
    )
    radial = _unit(st.points * [1, 1, 0])
    np.testing.assert_allclose(np.hypot(*st.points[:, :2].T), R, atol=1e-6)
    np.testing.assert_allclose(st.n1, radial, atol=1e-5)
    np.testing.assert_allclose(st.axis, np.tile([0, 0, 1.0], (n, 1)), 0, 1e-5)
    np.testing.assert_allclose(st.face_angle, math.pi / 2, atol=1e-6)


def test_the_start_and_a_far_jump(bore):
    quarter = _bore_contour(bore, start_fraction=0.25)
    np.testing.assert_allclose(
        quarter.point_at(0.0), [0.0, -(R - r), TOP - e], atol=2e-6
    )
    near = _bore_contour(bore, start_near=[0.0, R, TOP], direction=-1)
    np.testing.assert_allclose(
        near.point_at(0.0), [0.0, R - r, TOP - e], atol=2e-6
    )
    np.testing.assert_allclose(
        near.point_at(0.5 * math.pi * (R - r)),
        [R - r, 0.0, TOP - e],
        atol=2e-6,
    )
    # after a point near the start, a point across the bore: the warm
    # start must not keep it on the near side
    contour = _bore_contour(bore)
    contour.frame(np.array([-(R - r), 0.001, TOP - e]))
    s = contour.arc_position(np.array([R - r, 0.001, TOP - e]))
    assert s == pytest.approx(0.5 * contour.length + 0.001, abs=1e-5)


@pytest.mark.parametrize("tilt", [0.0, 0.2])
def test_a_circle_in_an_inclined_plane(inclined, tilt):
    """The tool along the top face's normal N, tilted about the tangent:
    a = cos N + sin rho_hat, n1 = cos rho_hat - sin N, so the path is the
    circle of radius R - r cos - e sin about (r sin - e cos) N."""
    contour = EdgeContour(
        inclined, cutter_radius=r, engagement=e, rule="right", tilt=tilt
    )
    normal = np.array([0.0, -math.sin(INCLINE), math.cos(INCLINE)])
    c, s_ = math.cos(tilt), math.sin(tilt)
    radius = HOLE - r * c - e * s_
    center = (r * s_ - e * c) * normal
    assert contour.length == pytest.approx(2 * math.pi * radius, rel=1e-6)
    st = contour.stations(5e-4)
    rho = _unit(st.points)
    np.testing.assert_allclose(st.axis, c * normal + s_ * rho, atol=2e-5)
    np.testing.assert_allclose(st.n1, c * rho - s_ * normal, atol=2e-5)
    a0 = contour.tool_axis_at(0.0)
    for s in np.linspace(0.0, contour.length, 25):
        z = contour.point_at(s)
        assert (z - center) @ normal == pytest.approx(0.0, abs=1e-8)
        assert np.linalg.norm(z - center) == pytest.approx(radius, abs=1e-7)
        turn = contour.axis_turn(s)
        np.testing.assert_allclose(turn @ turn.T, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(turn @ a0, contour.tool_axis_at(s), 0, 1e-12)
        # the least rotation: about a normal of both axes
        axis = np.cross(a0, contour.tool_axis_at(s))
        np.testing.assert_allclose(turn @ axis, axis, atol=1e-12)
        p = z + 3e-4 * contour.n1(z)
        assert contour.depth(p) == pytest.approx(3e-4, abs=1e-9)
        L = contour.length
        gap = (contour.arc_position(p) - s + 0.5 * L) % L - 0.5 * L
        assert gap == pytest.approx(0.0, abs=1e-7)


def test_the_wedge_needs_the_tilt_the_refusal_names(wedge):
    with pytest.raises(ValueError) as refused:
        EdgeContour(wedge, cutter_radius=r, engagement=e, rule="left")
    message = str(refused.value)
    assert "\n" not in message
    assert "cuts 30.0 deg into a face at arc position" in message
    assert "the faces meet at 120.0 deg" in message
    tilt = float(re.search(r"a tilt of (\S+) rad \((\S+) deg\)", message)[1])
    assert abs(tilt) == pytest.approx(math.pi / 6, abs=1e-3)
    contour = EdgeContour(
        wedge, cutter_radius=r, engagement=e, rule="left", tilt=tilt
    )
    assert not contour.closed
    assert contour.length == pytest.approx(0.06, rel=1e-6)
    # the side plane now lies in the sloped face (n1 its inward normal)
    # and the axis is 30 degrees off the top face's normal
    slope = np.array([math.sin(math.pi / 3), 0.0, math.cos(math.pi / 3)])
    st = contour.stations(1e-3)
    np.testing.assert_allclose(st.n1 @ slope, -1.0, atol=1e-5)
    np.testing.assert_allclose(st.axis[:, 2], math.cos(math.pi / 6), 0, 1e-3)
    np.testing.assert_allclose(st.face_angle, 2 * math.pi / 3, atol=1e-6)
    # an open edge: s runs from one end to the other, beyond them clamped
    np.testing.assert_allclose(
        contour.edge_point(0.0), [0.04, 0, 0.02], 0, 1e-9
    )
    np.testing.assert_allclose(
        contour.point_at(-1.0), contour.point_at(0.0), atol=0
    )
    back = EdgeContour(
        wedge,
        cutter_radius=r,
        engagement=e,
        rule="left",
        tilt=tilt,
        direction=-1,
    )
    np.testing.assert_allclose(
        back.edge_point(0.0), [0.04, 0.06, 0.02], 0, 1e-9
    )
    np.testing.assert_allclose(
        back.tangent(back.point_at(0.01)), [0, -1, 0], 0, 1e-9
    )


def test_refusals_are_one_line(wedge, bore):
    with pytest.raises(ValueError, match="bisector rule leaves n1 undefined"):
        EdgeContour(bore, cutter_radius=r, engagement=e, rule="bisector")
    with pytest.raises(ValueError, match="unknown tool rule"):
        EdgeContour(bore, cutter_radius=r, engagement=e, rule="top")
    with pytest.raises(ValueError, match="the pass is empty"):
        EdgeContour(
            wedge,
            cutter_radius=r,
            engagement=e,
            rule="left",
            tilt=-0.53,
            start_fraction=1.0,
        )
    # the tool along the bore wall's normal (horizontal) cuts with its
    # side in the top face's plane: tilted, it gouges the top face
    with pytest.raises(ValueError, match=r"a tilt of 0\.0000 rad"):
        EdgeContour(bore, cutter_radius=r, engagement=e, rule="left", tilt=0.5)


def test_autodiff_inputs(bore):
    ad = pytest.importorskip("pydrake.autodiffutils")
    contour = _bore_contour(bore)
    p0 = np.array([0.010, 0.025, TOP - e + 1e-4])
    p = ad.InitializeAutoDiff(p0).reshape(-1)
    d = contour.depth(p)
    assert d.value() == pytest.approx(contour.depth(p0), abs=1e-15)
    np.testing.assert_allclose(d.derivatives(), contour.n1(p0), atol=1e-15)
    np.testing.assert_allclose(
        ad.ExtractValue(contour.n1(p)).reshape(-1), contour.n1(p0)
    )
    np.testing.assert_allclose(
        ad.ExtractValue(contour.grad_phi(p)).reshape(-1), -contour.n1(p0)
    )
    v = np.array([ad.AutoDiffXd(x) for x in (0.01, 0.0, 0.0)])
    np.testing.assert_allclose(
        ad.ExtractValue(contour.n2(p, v, 1e-6)).reshape(-1),
        contour.n2(p0, ad.ExtractValue(v).reshape(-1), 1e-6),
    )
    assert contour.depth_rate(p, v).value() == pytest.approx(
        contour.n1(p0)[0] * 0.01
    )


@pytest.fixture(scope="module")
def cross_hole():
    """The rim of a radial hole in a tube: the tool axis (the tube's outer
    face normal) turns towards and away from n1 along it."""
    part = load_part(PARTS / "cross_hole.stl", units="mm")
    return EdgeCurve(choose_edge(sharp_edges(part), near=[0.03, 0.0, 0.048]))


def test_the_cross_section_through_a_tool_pressed_in(cross_hole):
    """A tool point delta along n1 and eps along a from z(s) lies in the
    cross-section at s (normal to n2): its arc position is s and its depth
    delta, though the path's own tangent leans off n2 where the axis
    tilts (the nearest point of the path would be off by tens of um)."""
    contour = EdgeContour(
        cross_hole, cutter_radius=r, engagement=e, rule="right"
    )
    L = contour.length
    lean = []
    for s in np.linspace(0.0, L, 40, endpoint=False):
        z = contour.point_at(s)
        n1, t = contour.n1(z), contour.tangent(z)
        a = contour.tool_axis_at(s)
        step = 1e-6
        dz = (contour.point_at(s + step) - contour.point_at(s - step)) / (
            2 * step
        )
        lean.append(abs(n1 @ dz) / np.linalg.norm(dz))
        for delta, eps in [(5e-4, 0.0), (3e-4, -2e-5), (-2e-4, 1e-4)]:
            p = z + delta * n1 + eps * a
            gap = (contour.arc_position(p) - s + 0.5 * L) % L - 0.5 * L
            assert gap == pytest.approx(0.0, abs=1e-8)
            assert contour.depth(p) == pytest.approx(delta, abs=1e-8)
        # n1' ds*/dt: a tool moving along n2 at 1 m/s
        p = z + 5e-4 * n1
        rate = contour.n1_rate(p, t)
        ahead, behind = p + 1e-5 * t, p - 1e-5 * t
        slope = (contour.n1(ahead) - contour.n1(behind)) / 2e-5
        np.testing.assert_allclose(
            rate, slope, atol=1e-3 * np.linalg.norm(slope)
        )
    assert max(lean) > 0.02  # the case the cross-section is needed for


def test_the_task_frame_turns_with_the_tool(cross_hole):
    """x3 of the task frame is the tool axis; the frame is fixed in the
    desired tool rotation (it turns by axis_turn); world z maps onto the
    start's axis by the least rotation."""
    contour = EdgeContour(
        cross_hole, cutter_radius=r, engagement=e, rule="right"
    )
    T0 = contour.task_frame(0.0)
    a0 = contour.tool_axis_at(0.0)
    np.testing.assert_allclose(T0[:, 2], a0, atol=1e-12)
    np.testing.assert_allclose(
        T0 @ np.cross([0.0, 0.0, 1.0], a0),
        np.cross([0.0, 0.0, 1.0], a0),
        atol=1e-12,
    )
    for s in np.linspace(0.0, contour.length, 13):
        T = contour.task_frame(s)
        np.testing.assert_allclose(T.T @ T, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(T[:, 2], contour.tool_axis_at(s), atol=1e-12)
        np.testing.assert_allclose(T, contour.axis_turn(s) @ T0, atol=1e-12)


def test_a_planar_contours_task_frame_is_the_world():
    circle = CircularContour((0.0, 0.0, 0.05), 0.027)
    np.testing.assert_array_equal(circle.task_frame(0.01), np.eye(3))


def test_the_chamfer_area_of_a_planar_edge_is_delta_times_height():
    """A face along n1 (normal a) and one along -a (normal -n1): the
    rectangle delta x height, exactly; nothing cut, nothing to scale."""
    faces = ((0.0, 1.0), (-1.0, 0.0))
    for delta in (1e-5, 3e-4, 2.5e-3):
        assert chamfer_area_ratio(faces, delta, e) == 1.0
    assert chamfer_area_ratio(faces, 0.0, e) == 1.0
    circle = CircularContour([0.0, 0.0, TOP - e], R - r)
    assert circle.chamfer_scale(0.0, 3e-4, e) == 1.0


def test_the_wedges_chamfer_with_the_tool_along_its_sloped_face(wedge):
    """120 deg between the faces, the side plane in the sloped face: the
    top face rises 30 deg off n1 from the edge, so the section is the
    rectangle delta x e plus the triangle delta^2 tan(30 deg) / 2."""
    contour = EdgeContour(
        wedge, cutter_radius=r, engagement=e, rule="left", tilt=-math.pi / 6
    )
    for delta in (1e-4, 5e-4, 1.5e-3):
        area = delta * e + 0.5 * delta**2 * math.tan(math.pi / 6)
        for s in np.linspace(0.0, contour.length, 7):
            assert contour.chamfer_scale(s, delta, e) == pytest.approx(
                area / (delta * e), rel=1e-6
            )


@pytest.mark.parametrize("delta", [2e-4, 5e-4, 1.5e-3])
def test_the_chamfer_under_a_tilted_tool(inclined, delta):
    """A 90-degree rim, the tool tilted theta from the top face's normal
    towards the material: the top face rises as y = x tan(theta), the
    wall falls as y = -x cot(theta) until the tip's y = -e (at x = e
    tan(theta)), so the section is delta^2 (tan + cot) / 2 before that
    and delta^2 tan / 2 + e delta - e^2 tan / 2 beyond it."""
    theta = 0.2
    contour = EdgeContour(
        inclined, cutter_radius=r, engagement=e, rule="right", tilt=theta
    )
    tan = math.tan(theta)
    if delta < e * tan:
        area = 0.5 * delta**2 * (tan + 1.0 / tan)
    else:
        area = 0.5 * delta**2 * tan + e * delta - 0.5 * e**2 * tan
    for s in np.linspace(0.0, contour.length, 9):
        assert contour.chamfer_scale(s, delta, e) == pytest.approx(
            area / (delta * e), rel=2e-4
        )
    upright = EdgeContour(inclined, cutter_radius=r, engagement=e, rule="right")
    for s in np.linspace(0.0, upright.length, 9):
        assert upright.chamfer_scale(s, delta, e) == pytest.approx(1, abs=1e-4)


def test_the_chamfer_area_by_a_polygon():
    """Against the wedge clipped by the strip and the tip as a polygon
    (shoelace), for random convex wedges the side plane supports."""
    rng = np.random.default_rng(7)
    for _ in range(200):
        # the faces' rays at angles from -a (the lower) and from n1
        lo = rng.uniform(-0.5 * math.pi, 0.4)
        hi = rng.uniform(max(lo + 0.3, -0.3), 0.5 * math.pi)
        rays = [(math.cos(lo), math.sin(lo)), (math.cos(hi), math.sin(hi))]
        # outward normals: the lower ray's turned clockwise, the upper's
        # counter-clockwise (the wedge between the rays is the material)
        faces = ((rays[0][1], -rays[0][0]), (-rays[1][1], rays[1][0]))
        delta = rng.uniform(1e-4, 3e-3)
        box = [(0.0, -e), (delta, -e), (delta, 1.0), (0.0, 1.0)]
        for n_x, n_y in faces:
            out = []
            for k, p in enumerate(box):
                q = box[(k + 1) % len(box)]
                dp, dq = p[0] * n_x + p[1] * n_y, q[0] * n_x + q[1] * n_y
                if dp <= 0.0:
                    out.append(p)
                if dp * dq < 0.0:
                    w = dp / (dp - dq)
                    out.append(
                        (p[0] + w * (q[0] - p[0]), p[1] + w * (q[1] - p[1]))
                    )
            box = out
        area = 0.5 * abs(
            sum(
                box[k][0] * box[k - 1][1] - box[k - 1][0] * box[k][1]
                for k in range(len(box))
            )
        )
        assert chamfer_area_ratio(faces, delta, e) * delta * e == (
            pytest.approx(area, rel=1e-9, abs=1e-15)
        )


def test_a_hole_off_its_faces_normal_cuts_along_its_own_axis():
    """angled_hole.stl: a 16 mm hole 30 deg off a flat plate's normal.
    With the tool on the top face every constant tilt gouges the wall
    somewhere; along the hole's axis (the default rule) the cutter's
    side plane is the wall's tangent plane all round, no tilt given: the
    tool path is the rim moved r into the hole and e down the axis."""
    part = load_part(PARTS / "angled_hole.stl", units="mm")
    chain = choose_edge(sharp_edges(part), near=[0.008, 0.0, 0.0])
    curve = EdgeCurve(chain)
    with pytest.raises(ValueError, match="cuts .* into a face"):
        EdgeContour(curve, cutter_radius=r, engagement=e, rule="left")
    rule = default_tool_rule(chain)
    path = EdgeContour(
        curve, cutter_radius=r, engagement=e, rule="axis", axis=rule.axis
    )
    hole = np.array([0.0, -math.sin(INCLINE), math.cos(INCLINE)])
    for s in np.linspace(0.0, path.length, 16, endpoint=False):
        np.testing.assert_allclose(path.tool_axis_at(s), hole, atol=1e-3)
        # the tool's centre line is r - r = 0 from the hole's wall...
        z = path.point_at(s)
        radial = z - (z @ hole) * hole  # off the hole's axis (origin)
        assert np.linalg.norm(radial) == pytest.approx(0.008 - r, abs=3e-5)
        # ...e below the rim along the axis
        assert z @ hole == pytest.approx(
            path.edge_point(s) @ hole - e, abs=3e-5
        )
    assert "axis along [0.000, -0.500, 0.866]" in path.describe_rule()


def test_the_axis_rule_takes_an_axis(bore):
    with pytest.raises(ValueError, match="takes an axis"):
        EdgeContour(bore, cutter_radius=r, engagement=e, rule="axis")
    with pytest.raises(ValueError, match="takes an axis"):
        EdgeContour(
            bore, cutter_radius=r, engagement=e, rule="left", axis=[0, 0, 1]
        )


def test_the_spindle_clash_of_a_tool_lying_across_the_bore(bore):
    """The tube's bore with the tool on the wall (left for this chain):
    the tool lies across the bore and its spindle in the far wall; on the
    top face (right) it stands clear."""
    part = load_part(PARTS / "tube.stl", units="mm")
    across = EdgeContour(bore, cutter_radius=r, engagement=e, rule="left")
    assert "spindle stands in the part at 100%" in spindle_clash(
        part, across, r, 0.02
    )
    assert spindle_clash(part, _bore_contour(bore), r, 0.02) == ""


@pytest.mark.parametrize("hole", [0.0030, 0.0033])
def test_a_hole_no_larger_than_the_cutter_is_refused(hole, tmp_path):
    """A hole's rim bends towards the free side with the hole's radius:
    the 3 mm cutter fits a 3.3 mm hole (its path a 0.3 mm circle) and not
    a 3 mm one, where its centre would stand on the hole's axis."""
    ring = trimesh.creation.annulus(
        r_min=hole * 1e3, r_max=20.0, height=10.0, sections=160
    )
    ring.export(tmp_path / "ring.stl")
    part = load_part(tmp_path / "ring.stl", units="mm")
    rim = choose_edge(sharp_edges(part), near=[hole, 0.0, 0.005])
    rule = default_tool_rule(rim)
    path = dict(cutter_radius=r, engagement=e, rule="axis", axis=rule.axis)
    if hole > r:
        contour = EdgeContour(EdgeCurve(rim), **path)
        assert contour.length == pytest.approx(
            2 * math.pi * (hole - r), rel=0.05
        )
    else:
        with pytest.raises(ValueError, match="bends tighter than the cutter"):
            EdgeContour(EdgeCurve(rim), **path)
