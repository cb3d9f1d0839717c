"""A part from a mesh file, its edges and the chamfer frame along one,
against meshes whose edges are known in closed form."""

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
import trimesh

from deburr_drake.math.mesh_part import (
    EdgeCurve,
    choose_edge,
    default_tool_rule,
    describe_edges,
    hole_axis,
    load_part,
    rule_axes,
    sharp_edges,
    side_plane_tilts,
    wall_axis,
)

PARTS = Path(__file__).resolve().parents[2] / "models" / "parts"
INCLINE = math.radians(30.0)


def _write(mesh, path):
    mesh.export(path)
    return path


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@pytest.fixture(scope="module")
def tube_rim():
    """The paper's tube (mm file): its bore's top edge, r = 30 mm at
    z = 50 mm."""
    part = load_part(PARTS / "tube.stl", units="mm")
    chain = choose_edge(sharp_edges(part), near=[0.03, 0.0, 0.05])
    return chain, EdgeCurve(chain)


@pytest.fixture(scope="module")
def inclined_rim(tmp_path_factory):
    """A 20 mm hole (r = 10 mm) through a round plate whose top face is
    tilted 30 degrees about x: its top rim is a circle in that plane."""
    plate = trimesh.creation.annulus(
        r_min=10.0, r_max=40.0, height=20.0, sections=200
    )
    plate.apply_translation([0.0, 0.0, -10.0])  # top face at z = 0
    plate.apply_transform(
        trimesh.transformations.rotation_matrix(INCLINE, [1, 0, 0])
    )
    path = _write(plate, tmp_path_factory.mktemp("parts") / "plate.stl")
    part = load_part(path, units="mm")
    chain = choose_edge(sharp_edges(part), near=[0.01, 0.0, 0.0])
    return EdgeCurve(chain)


def test_a_box_has_twelve_straight_edges(tmp_path):
    box = trimesh.creation.box(extents=[0.1, 0.2, 0.3])
    chains = sharp_edges(load_part(_write(box, tmp_path / "box.stl")))
    assert len(chains) == 12
    assert all(not c.closed and len(c.points) == 2 for c in chains)
    lengths = [c.length for c in chains]
    np.testing.assert_allclose(lengths, [0.3] * 4 + [0.2] * 4 + [0.1] * 4)
    curve = EdgeCurve(chains[0])
    frame = curve.frame(np.linspace(0.0, curve.length, 7))
    np.testing.assert_allclose(frame.face_angle, math.pi / 2, atol=1e-9)
    assert frame.convex.all()
    # n1 points into the box: from the edge towards its centre's side
    toward_center = -frame.point
    assert np.all(np.sum(frame.n1 * toward_center, axis=1) > 0.0)


def test_the_tube_rim_is_one_circle(tube_rim):
    chain, curve = tube_rim
    assert chain.closed and len(chain.points) == 256
    assert curve.closed
    assert curve.length == pytest.approx(2 * math.pi * 0.03, abs=1e-8)
    u = np.linspace(0.0, curve.length, 2001)
    p = curve.point(u)
    # the smoothed curve on the true circle (the mesh's vertices are on it)
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 1]), 0.03, atol=1e-8)
    np.testing.assert_allclose(p[:, 2], 0.05, atol=1e-12)
    # arc length: the polar angle advances by u / r, counter-clockwise
    angle = np.unwrap(np.arctan2(p[:, 1], p[:, 0]))
    np.testing.assert_allclose(angle - angle[0], u / 0.03, atol=1e-6)
    np.testing.assert_allclose(curve.curvature(u), 1 / 0.03, rtol=1e-3)


def test_the_tube_rim_frame(tube_rim):
    _, curve = tube_rim
    u = np.linspace(0.0, curve.length, 301)
    f = curve.frame(u)
    radial = _unit(f.point * [1.0, 1.0, 0.0])
    up = np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(f.left_normal, -radial, atol=1e-5)  # bore
    np.testing.assert_allclose(f.right_normal, up + 0 * radial, atol=1e-5)
    np.testing.assert_allclose(f.n1, _unit(radial - up), atol=1e-5)
    np.testing.assert_allclose(f.n2, np.cross(up, radial), atol=1e-5)
    np.testing.assert_allclose(f.face_angle, math.pi / 2, atol=1e-9)
    # the tool held vertical: along the top face's normal
    np.testing.assert_allclose(
        curve.tool_axis(u, rule="right"), up + 0 * radial, atol=1e-5
    )


def test_the_frame_on_a_circle_in_an_inclined_plane(inclined_rim):
    curve = inclined_rim
    assert curve.length == pytest.approx(2 * math.pi * 0.01, rel=1e-7)
    normal = np.array([0.0, -math.sin(INCLINE), math.cos(INCLINE)])
    u = np.linspace(0.0, curve.length, 401)
    f = curve.frame(u)
    np.testing.assert_allclose(f.point @ normal, 0.0, atol=1e-9)
    radial = _unit(f.point)
    np.testing.assert_allclose(np.linalg.norm(f.point, axis=1), 0.01, 1e-6)
    # counter-clockwise seen from outside (from the plane's normal side)
    np.testing.assert_allclose(f.n2, np.cross(normal, radial), atol=1e-5)
    np.testing.assert_allclose(f.left_normal, -radial, atol=1e-5)
    np.testing.assert_allclose(
        f.right_normal, normal + 0 * u[:, None], atol=1e-5
    )
    np.testing.assert_allclose(f.n1, _unit(radial - normal), atol=1e-5)
    np.testing.assert_allclose(f.face_angle, math.pi / 2, atol=1e-6)
    # the bisector, then leaned by 0.2 rad towards n2 and tilted about it
    axis = curve.tool_axis(u, rule="bisector", lead=0.2)
    np.testing.assert_allclose(np.sum(axis * f.n2, axis=1), math.sin(0.2))
    axis = curve.tool_axis(u, rule="right", tilt=0.3)
    np.testing.assert_allclose(axis @ normal, math.cos(0.3), atol=1e-5)
    np.testing.assert_allclose(np.sum(axis * f.n2, axis=1), 0.0, atol=1e-9)


def test_an_open_edge_where_faces_meet_at_120_degrees():
    part = load_part(PARTS / "wedge.stl", units="mm")
    chain = choose_edge(sharp_edges(part), near=[0.04, 0.03, 0.02])
    assert not chain.closed
    curve = EdgeCurve(chain)
    assert curve.length == pytest.approx(0.06)
    u = np.linspace(0.0, curve.length, 11)
    f = curve.frame(u)
    np.testing.assert_allclose(f.point[0], [0.04, 0.0, 0.02], atol=1e-12)
    np.testing.assert_allclose(f.face_angle, 2 * math.pi / 3, atol=1e-6)
    assert f.convex.all()
    slope = [math.sin(math.radians(60)), 0.0, math.cos(math.radians(60))]
    n1 = -_unit(np.array([0.0, 0.0, 1.0]) + slope)
    np.testing.assert_allclose(f.n1, n1 + 0 * u[:, None], atol=1e-6)
    reversed_curve = EdgeCurve(chain.reversed())
    np.testing.assert_allclose(
        reversed_curve.tangent(0.0), -f.n2[-1], atol=1e-9
    )
    np.testing.assert_allclose(
        reversed_curve.frame(0.0).left_normal, f.right_normal[-1], atol=1e-9
    )


def test_the_cross_drilled_holes_saddle():
    part = load_part(PARTS / "cross_hole.stl", units="mm")
    chains = sharp_edges(part)
    chain = choose_edge(chains, near=[0.03, 0.0, 0.048])
    assert chain.closed
    curve = EdgeCurve(chain)
    u = np.linspace(0.0, curve.length, 2001)
    f = curve.frame(u)
    p = f.point
    # on the tube's outer face and on the hole's wall
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 1]), 0.03, atol=1e-5)
    np.testing.assert_allclose(np.hypot(p[:, 1], p[:, 2] - 0.04), 0.008, 1e-3)
    outer = _unit(p * [1.0, 1.0, 0.0])
    wall = -_unit(p * [0.0, 1.0, 1.0] - [0.0, 0.0, 0.04])
    angle = math.pi - np.arccos(np.sum(outer * wall, axis=1))
    # within half a facet of the 256-sided tube (0.7 degrees)
    np.testing.assert_allclose(f.face_angle, angle, atol=math.radians(0.8))
    assert math.radians(74) < f.face_angle.min() < math.radians(76)
    assert f.convex.all()


def test_choose_by_index_and_project(tube_rim):
    part = load_part(PARTS / "tube.stl", units="mm")
    chains = sharp_edges(part)
    assert choose_edge(chains, index=3) is chains[3]
    with pytest.raises(ValueError, match="edge index 4: the part has 4"):
        choose_edge(chains, index=4)
    _, curve = tube_rim
    assert curve.project(curve.point(0.05)) == pytest.approx(0.05, abs=1e-9)


def test_units_and_pose(tmp_path, tube_rim):
    _, curve_mm = tube_rim
    metres = trimesh.load_mesh(PARTS / "tube.stl")
    metres.apply_scale(1e-3)
    path = _write(metres, tmp_path / "tube_m.stl")
    chain = choose_edge(sharp_edges(load_part(path)), near=[0.03, 0, 0.05])
    u = np.linspace(0.0, curve_mm.length, 50)
    # the same edge to the STL's float32 rounding
    np.testing.assert_allclose(
        EdgeCurve(chain).point(u), curve_mm.point(u), atol=1e-8
    )
    inches = metres.copy()
    inches.apply_scale(1 / 0.0254)
    path = _write(inches, tmp_path / "tube_in.stl")
    part = load_part(path, units="in")
    np.testing.assert_allclose(part.mesh.bounds, metres.bounds, atol=1e-12)
    # placed by a pose: the same edge, moved and turned
    xyz, rpy = [0.4, -0.1, 0.05], [0.3, -0.2, 1.0]
    part = load_part(PARTS / "tube.stl", units="mm", xyz=xyz, rpy=rpy)
    near = part.to_world([0.03, 0.0, 0.05])
    curve = EdgeCurve(choose_edge(sharp_edges(part), near=near))
    rotation = Rotation.from_euler("xyz", rpy).as_matrix()
    assert curve.length == pytest.approx(curve_mm.length, rel=1e-9)
    start = curve.project(rotation @ curve_mm.point(0.0) + xyz)
    f = curve.frame(start + u)
    g = curve_mm.frame(u)
    np.testing.assert_allclose(f.point, g.point @ rotation.T + xyz, atol=1e-8)
    np.testing.assert_allclose(f.n1, g.n1 @ rotation.T, atol=1e-5)
    np.testing.assert_allclose(f.n2, g.n2 @ rotation.T, atol=1e-5)


def test_bad_files_and_fields(tmp_path):
    with pytest.raises(ValueError, match="no such file"):
        load_part(tmp_path / "missing.stl")
    text = tmp_path / "notes.stl"
    text.write_text("not a mesh at all")
    with pytest.raises(ValueError, match="no triangles"):
        load_part(text)
    with pytest.raises(ValueError, match="unknown file type '.txt'"):
        load_part(text.rename(tmp_path / "notes.txt"))
    with pytest.raises(ValueError, match="unknown units 'ft'"):
        load_part(PARTS / "tube.stl", units="ft")
    box = trimesh.creation.box()
    box.update_faces(np.arange(len(box.faces)) != 0)
    with pytest.raises(ValueError, match="open, not watertight"):
        load_part(_write(box, tmp_path / "open.stl"))
    # two tetrahedra sharing one edge: four triangles on it
    vertices = np.array(
        [[0, 0, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]],
        float,
    )
    faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    faces += [[0, 4, 1], [0, 1, 5], [0, 5, 4], [1, 4, 5]]
    pair = trimesh.Trimesh(vertices, faces, process=False)
    with pytest.raises(ValueError, match="not manifold"):
        load_part(_write(pair, tmp_path / "pair.obj"))
    with pytest.raises(ValueError, match="unknown tool axis rule"):
        EdgeCurve(sharp_edges(load_part(PARTS / "wedge.stl"))[0]).tool_axis(
            0.0, rule="normal"
        )


@pytest.mark.skipif(
    importlib.util.find_spec("cascadio") is not None,
    reason="cascadio is installed: STEP files are read",
)
def test_step_without_cascadio_says_so(tmp_path):
    step = tmp_path / "part.step"
    step.write_text("ISO-10303-21;\nEND-ISO-10303-21;\n")
    with pytest.raises(ValueError, match="reading STEP needs cascadio"):
        load_part(step)


def test_the_job_blocks_top_side_edges():
    """models/parts/block.stl: on its top face (z = 0) a through bore, two
    holes drilled 15 and 30 degrees off the top's normal, a slot, the outer
    rim and a chamfer's 120-degree edge, each an edge of its own."""
    chains = sharp_edges(load_part(PARTS / "block.stl", units="mm"))
    top = [c for c in chains if np.allclose(c.points[:, 2], 0.0, atol=1e-9)]
    assert len(top) == 6

    def dihedral(chain):
        cos = np.sum(chain.left_normals * chain.right_normals, axis=1)
        d = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
        return d.min(), d.max()

    def at(x, y):
        return choose_edge(top, near=[x * 1e-3, y * 1e-3, 0.0])

    bore, hole15, hole30 = at(-30, 15), at(-34, -28), at(7, -25)
    slot, rim, chamfer = at(5, 28), at(-70, 0), at(0, 32)
    assert len({id(c) for c in (bore, hole15, hole30, slot, rim, chamfer)}) == 6
    for loop in (bore, hole15, hole30, slot):
        assert loop.closed
    assert bore.length == pytest.approx(2 * math.pi * 0.010, rel=1e-3)
    np.testing.assert_allclose(dihedral(bore), [90.0, 90.0], atol=1e-6)
    # a hole drilled off the normal: its wall meets the top at 90 -/+ tilt
    np.testing.assert_allclose(dihedral(hole15), [75.0, 105.0], atol=0.1)
    np.testing.assert_allclose(dihedral(hole30), [60.0, 120.0], atol=0.1)
    assert slot.length == pytest.approx(2 * 0.036 + 2 * math.pi * 0.006, 1e-3)
    assert not rim.closed and not chamfer.closed
    assert chamfer.length == pytest.approx(0.140)
    f = EdgeCurve(chamfer).frame(np.array([0.07]))
    np.testing.assert_allclose(f.face_angle, 2 * math.pi / 3, atol=1e-6)
    assert f.convex.all()


def test_a_corner_where_a_third_edge_meets_ends_the_chains(tmp_path):
    """A hexagonal prism: with sharp_angle 50 deg its vertical edges
    (side faces 60 deg apart) are edges too, so three edges meet at each
    corner and every side is an edge of its own (18); with 70 deg they are
    not, the sides' faces turn smoothly, and the rims stay two loops."""
    prism = trimesh.creation.cylinder(radius=0.02, height=0.01, sections=6)
    part = load_part(_write(prism, tmp_path / "hex.stl"))
    chains = sharp_edges(part, min_angle=math.radians(50.0))
    assert len(chains) == 18
    for chain in chains:
        assert not chain.closed and len(chain.points) == 2
        # one face pair per chain
        assert np.ptp(chain.left_normals, axis=0).max() < 1e-9
        assert np.ptp(chain.right_normals, axis=0).max() < 1e-9
    rims = sharp_edges(part, min_angle=math.radians(70.0))
    assert [(c.closed, len(c.points)) for c in rims] == [(True, 6)] * 2


def test_the_default_rule_on_a_hole_drilled_off_its_faces_normal():
    """angled_hole.stl: a 16 mm hole 30 deg off the normal of a flat
    plate. The top rim is a loop round the hole's cylindrical wall: the
    tool axis is the hole's axis, fitted from the wall's normals, out of
    the part; an outer edge of the plate stands the tool on the top."""
    part = load_part(PARTS / "angled_hole.stl", units="mm")
    chains = sharp_edges(part)
    rim = choose_edge(chains, near=[0.008, 0.0, 0.0])
    rule = default_tool_rule(rim)
    assert rule.kind == "axis"
    hole = [0.0, -math.sin(INCLINE), math.cos(INCLINE)]
    np.testing.assert_allclose(rule.axis, hole, atol=1e-3)
    _, residual, spread = wall_axis(rim, hole_axis(rim)[1])
    assert residual < 0.01 and spread > 0.4
    top = choose_edge(chains, near=[0.04, 0.0, 0.0])
    rule = default_tool_rule(top)
    assert rule.kind == "face"
    normals = top.left_normals if rule.side == "left" else top.right_normals
    np.testing.assert_allclose(normals[0], [0, 0, 1], atol=1e-9)


def test_the_default_rule_on_a_pipes_radial_hole():
    """pipe_hole.stl: the radial hole's outer rim (a saddle on the pipe's
    curved face) gets the hole's axis, +z; the pipe's own face round the
    rim is no cylinder about it (its normals do not go round)."""
    part = load_part(PARTS / "pipe_hole.stl", units="mm")
    rim = choose_edge(sharp_edges(part), near=[0.008, 0.0, 0.06])
    axis, side = hole_axis(rim)
    np.testing.assert_allclose(axis, [0, 0, 1], atol=1e-3)
    other = "right" if side == "left" else "left"
    assert wall_axis(rim, other)[2] < 0.05


@pytest.mark.parametrize("angle", [90.0, 120.0, 128.0, 135.0])
def test_an_obtuse_edge_turns_the_tool_by_the_least_clear_angle(
    angle, roof_stl, tmp_path
):
    """The tool stands on the top; where the faces meet at more than 90
    degrees the top's normal would lay the cutter's side plane into the
    sloped face, so the default turns it about the edge by the faces'
    angle less 90 degrees, leaning over the top: the side plane along the
    sloped face. The path with that tilt is accepted, with 3 degrees
    less it gouges."""
    from deburr_drake.math.edge_contour import EdgeContour

    part = load_part(roof_stl(angle, tmp_path / "roof.stl"), units="mm")
    edge = choose_edge(sharp_edges(part), near=[0.04, 0.03, 0.02])
    rule = default_tool_rule(edge)
    assert rule.kind == "face"
    top = edge.left_normals if rule.side == "left" else edge.right_normals
    np.testing.assert_allclose(top, [[0.0, 0.0, 1.0]] * len(top), atol=1e-9)
    assert abs(rule.tilt) == pytest.approx(math.radians(angle - 90.0), abs=1e-6)
    # leaning over the top (-x), away from the sloped face
    tilt = math.radians(angle - 90.0)
    np.testing.assert_allclose(
        rule_axes(edge, rule)[0],
        [-math.sin(tilt), 0.0, math.cos(tilt)],
        atol=1e-6,
    )
    lo, hi = side_plane_tilts(edge, rule.side)
    assert hi - lo == pytest.approx(math.radians(180.0 - angle), abs=1e-6)
    path = dict(cutter_radius=0.003, engagement=0.002, rule=rule.side)
    EdgeContour(EdgeCurve(edge), tilt=rule.tilt, **path)
    if angle > 90.0:
        less = rule.tilt - math.copysign(math.radians(3.0), rule.tilt)
        with pytest.raises(ValueError, match="cuts .* into a face"):
            EdgeContour(EdgeCurve(edge), tilt=less, **path)


def test_the_listing_of_a_block(tmp_path):
    """A 40 x 30 x 20 mm block on its base: twelve convex 90-degree
    edges, a point half way along each; the four on its base are not
    reachable, the eight others are."""
    box = trimesh.creation.box(extents=[0.04, 0.03, 0.02])
    part = load_part(_write(box, tmp_path / "block.stl"), xyz=[0.5, 0, 0.1])
    chains = sharp_edges(part)
    listing = describe_edges(part, chains)
    assert [s.index for s in listing] == list(range(12))
    assert (
        sorted(round(s.length, 6) for s in listing)
        == [0.02] * 4 + [0.03] * 4 + [0.04] * 4
    )
    for summary, chain in zip(listing, chains):
        assert not summary.closed and summary.convex is True
        np.testing.assert_allclose(summary.dihedral, [math.pi / 2] * 2)
        assert chain.distance(summary.point) < 1e-12
        np.testing.assert_allclose(
            summary.point, chain.points.mean(axis=0), atol=1e-12
        )
    base = [s for s in listing if s.point[2] < 0.1 - 0.0099]
    assert len(base) == 4
    assert all(not s.reachable and "base" in s.blocked for s in base)
    assert sum(s.reachable for s in listing) == 8


def test_the_spindle_across_a_pipe_is_not_the_open_side():
    """The radial hole's inner rim (at the pipe's bore): its axis points
    into the bore, so the spindle stands in the pipe's far wall; the
    outer rim's stands in free space."""
    part = load_part(PARTS / "pipe_hole.stl", units="mm")
    chains = sharp_edges(part)
    listing = describe_edges(part, chains)
    inner, outer = (
        listing[[c is chain for c in chains].index(True)]
        for chain in (
            choose_edge(chains, near=[0.008, 0, 0.05]),
            choose_edge(chains, near=[0.008, 0, 0.06]),
        )
    )
    assert outer.reachable and not outer.blocked
    assert not inner.reachable and "spindle" in inner.blocked
    np.testing.assert_allclose(inner.rule.axis, [0, 0, -1], atol=1e-3)


def _summary(part, chains, summaries, near):
    chain = choose_edge(chains, near=near)
    return chain, summaries[[c is chain for c in chains].index(True)]


def test_the_castings_inclined_face_its_hole_and_its_edges():
    """casting.stl: an inclined face sloping down 40 degrees from the
    top, a hole along its normal. The hole's rim gets that normal as its
    axis; the inclined face's edge with the vertical end (130 degrees) is
    cut with a 40-degree turn; its edge with the top (140 degrees) needs
    50, which lays the spindle on the top: not reachable, and why."""
    part = load_part(PARTS / "casting.stl", units="mm")
    chains = sharp_edges(part)
    summaries = describe_edges(part, chains)
    slope = math.radians(40.0)
    _, hole = _summary(part, chains, summaries, [-0.0419, 0.0, -0.0058])
    np.testing.assert_allclose(
        hole.rule.axis, [-math.sin(slope), 0.0, math.cos(slope)], atol=1e-6
    )
    assert hole.reachable
    _, lower = _summary(part, chains, summaries, [-0.055, 0.0, -0.0168])
    assert abs(lower.rule.tilt) == pytest.approx(math.radians(40.0), abs=1e-6)
    assert lower.reachable
    _, top = _summary(part, chains, summaries, [-0.035, 0.0, 0.0])
    assert abs(top.rule.tilt) == pytest.approx(math.radians(50.0), abs=1e-6)
    assert not top.reachable and "spindle" in top.blocked


def test_the_plates_holes_at_other_angles_and_sizes():
    """plate_holes.stl: holes of radius 4 mm 45 degrees off the normal,
    7 mm 20 degrees off it about the diagonal, 3 mm along it. Each rim
    gets its hole's axis; at 45 degrees the spindle lies on the top; the
    3 mm hole is no larger than the 3 mm cutter, and its path says so."""
    from deburr_drake.math.edge_contour import EdgeContour

    part = load_part(PARTS / "plate_holes.stl", units="mm")
    chains = sharp_edges(part)
    summaries = describe_edges(part, chains)
    _, steep = _summary(part, chains, summaries, [-0.0293, 0.015, 0.0])
    half = math.sqrt(0.5)
    np.testing.assert_allclose(steep.rule.axis, [half, 0.0, half], atol=1e-6)
    assert not steep.reachable and "spindle" in steep.blocked
    _, diagonal = _summary(part, chains, summaries, [0.0072, -0.0155, 0.0])
    tilt = math.radians(20.0)
    np.testing.assert_allclose(
        diagonal.rule.axis,
        [half * math.sin(tilt), -half * math.sin(tilt), math.cos(tilt)],
        atol=1e-6,
    )
    assert diagonal.reachable
    small, summary = _summary(part, chains, summaries, [-0.032, -0.022, 0.0])
    with pytest.raises(ValueError, match="bends tighter than the cutter"):
        EdgeContour(
            EdgeCurve(small),
            cutter_radius=0.003,
            engagement=0.002,
            rule="axis",
            axis=summary.rule.axis,
        )
