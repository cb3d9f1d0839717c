"""Tests of deburr_drake.cell.tube_mesh (pure numpy; pydrake only to read the
file back)."""

import collections

import numpy as np
import pytest

from deburr_drake.cell.tube_mesh import (
    band_width_limit,
    edge_band_mesh_path,
    make_framed_swept_volume_mesh,
    make_ring_volume_mesh,
    mesh_obj_path,
    polygonal_ring_volume,
    ring_mesh_path,
    sag_spacing,
    tet_volumes,
    write_vtk,
)

CASES = [
    (0.030, 0.035, 0.044, 0.050, 720, 2, 2),
    (0.030, 0.035, 0.044, 0.050, 12, 3, 4),
    (1.0, 2.0, -0.5, 0.5, 5, 5, 3),
]


def _faces(tets):
    count = collections.Counter()
    for t in tets:
        for f in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)):
            count[tuple(sorted(t[list(f)]))] += 1
    return count


def _on_boundary(v, args):
    ri, ro, zb, zt, n = args[:5]
    r = np.hypot(v[:, 0], v[:, 1])
    return (
        np.isclose(r, ri)
        | np.isclose(r, ro)
        | np.isclose(v[:, 2], zb)
        | np.isclose(v[:, 2], zt)
    )


@pytest.mark.parametrize("args", CASES)
def test_positive_volumes_and_total_volume(args):
    v, t = make_ring_volume_mesh(*args)
    assert t.shape == (6 * args[4] * args[5] * args[6], 4)
    vol = tet_volumes(v, t)
    assert vol.min() > 0
    np.testing.assert_allclose(
        vol.sum(), polygonal_ring_volume(*args[:5]), rtol=1e-12
    )


@pytest.mark.parametrize("args", CASES[1:])
def test_conforming_closed_surface(args):
    v, t = make_ring_volume_mesh(*args)
    faces = _faces(t)
    assert max(faces.values()) <= 2
    boundary = [f for f, c in faces.items() if c == 1]
    # Edge-manifold: every boundary edge is shared by exactly two boundary
    # triangles.
    edges = collections.Counter()
    for a, b, c in boundary:
        for e in ((a, b), (b, c), (a, c)):
            edges[tuple(sorted(e))] += 1
    assert set(edges.values()) == {2}
    # A ring's surface is a torus: V - E + F = 0.
    nv = len({i for f in boundary for i in f})
    assert nv - len(edges) + len(boundary) == 0
    # Boundary faces lie on the ring's boundary; interior faces don't all lie on
    # it.
    on = _on_boundary(v, args)
    assert all(on[list(f)].all() for f in boundary)


@pytest.mark.parametrize("args", CASES)
def test_interior_vertices_touch_every_tet(args):
    v, t = make_ring_volume_mesh(*args)
    on = _on_boundary(v, args)
    assert (~on).sum() == args[4] * (args[5] - 1) * (args[6] - 1)
    # Every tet has an interior vertex, so Drake's pressure field is positive in
    # it.
    assert (~on[t]).any(axis=1).all()


def test_deterministic_bytes(tmp_path):
    v, t = make_ring_volume_mesh(*CASES[1])
    write_vtk(tmp_path / "a.vtk", v, t)
    v2, t2 = make_ring_volume_mesh(*CASES[1])
    write_vtk(tmp_path / "b.vtk", v2, t2)
    a = (tmp_path / "a.vtk").read_bytes()
    assert a == (tmp_path / "b.vtk").read_bytes()
    assert b"CELL_TYPES 864\n10\n" in a and b"-0.000000000000e+00" not in a
    p = ring_mesh_path(*CASES[1], cache_dir=tmp_path / "cache")
    assert p.read_bytes() == a
    assert ring_mesh_path(*CASES[1], cache_dir=tmp_path / "cache") == p
    assert ring_mesh_path(*CASES[0], cache_dir=tmp_path / "cache") != p
    assert [
        x.name for x in (tmp_path / "cache").iterdir() if x.suffix != ".vtk"
    ] == []


def test_default_cache_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    p = ring_mesh_path(*CASES[2])
    assert p.parent == tmp_path / "deburr_drake" / "meshes" and p.exists()


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(inner_radius=0.0), "inner_radius"),
        (dict(outer_radius=0.02), "outer_radius"),
        (dict(z_top=0.0), "z_top"),
        (dict(z_bottom=float("nan")), "z_bottom"),
        (dict(n_theta=2), "n_theta"),
        (dict(n_radial=1), "n_radial"),
        (dict(n_z=1.5), "n_z"),
    ],
)
def test_bad_arguments(kwargs, name):
    args = dict(
        inner_radius=0.03,
        outer_radius=0.035,
        z_bottom=0.044,
        z_top=0.05,
        n_theta=8,
    )
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        make_ring_volume_mesh(**args)


def test_drake_reads_mesh_without_refinement(tmp_path):
    geometry = pytest.importorskip("pydrake.geometry")
    p = ring_mesh_path(*CASES[0], cache_dir=tmp_path)
    # Drake's refiner parses the VTK and splits "problematic" simplices
    # (all-boundary tets, boundary-to-boundary interior edges); our mesh must
    # need none.
    text = geometry.RefineVolumeMeshIntoVtkFileContents(geometry.MeshSource(p))
    assert "POINTS 6480 " in text and "CELLS 17280 " in text


def test_surface_obj_closed_outward(tmp_path):
    from deburr_drake.cell.tube_mesh import (
        make_ring_surface_mesh,
        ring_surface_path,
    )

    args = CASES[1][:5]
    v, q = make_ring_surface_mesh(*args)
    tris = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    p = v[tris]
    # Divergence theorem: sum of signed tet volumes from the origin = enclosed
    # volume (> 0: outward).
    vol = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0
    np.testing.assert_allclose(vol, polygonal_ring_volume(*args), rtol=1e-12)
    path = ring_surface_path(*args, cache_dir=tmp_path)
    text = path.read_text()
    assert (
        path.suffix == ".obj"
        and text.count("\nv ") == len(v)
        and text.count("\nf ") == len(q)
    )
    assert (
        ring_surface_path(*args, cache_dir=tmp_path).read_bytes()
        == path.read_bytes()
    )


# ------------------------------------------------------------ profile walls
from deburr_drake.cell.tube_mesh import (  # noqa: E402
    make_swept_surface_mesh,
    make_swept_volume_mesh,
    profile_mesh_paths,
)
from deburr_drake.math.profile import ProfileContour  # noqa: E402

L_SHAPE = [
    [-0.03, -0.03],
    [0.03, -0.03],
    [0.03, 0.0],
    [0.0, 0.0],
    [0.0, 0.03],
    [-0.03, 0.03],
]


def _shoelace(p):
    return 0.5 * abs(
        np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])
    )


@pytest.mark.parametrize(
    "vertices, fillet, material",
    [
        (
            [[-0.03, -0.03], [0.03, -0.03], [0.03, 0.03], [-0.03, 0.03]],
            0.03,
            "outside",
        ),
        (
            [[-0.03, -0.02], [0.03, -0.02], [0.03, 0.02], [-0.03, 0.02]],
            0.008,
            "outside",
        ),
        (
            [
                [-0.025, -0.025],
                [0.025, -0.025],
                [0.025, 0.025],
                [-0.025, 0.025],
            ],
            0.004,
            "inside",
        ),  # the wall thinner inside the small fillets
        (L_SHAPE, 0.004, "outside"),
        (L_SHAPE, 0.004, "inside"),
    ],
)
def test_profile_wall_mesh_fills_the_band(vertices, fillet, material):
    edge = ProfileContour(vertices, fillet, material=material)
    points, normals, depths = edge.material_band(
        0.005, segments_per_turn=120, max_step=0.005
    )
    assert depths.max() == pytest.approx(0.005)
    assert depths.min() > 0
    v, t = make_swept_volume_mesh(points, normals, depths, 0.044, 0.050)
    vol = tet_volumes(v, t)
    assert vol.min() > 0
    far = points + depths[:, None] * normals
    area = abs(_shoelace(far) - _shoelace(points))
    np.testing.assert_allclose(vol.sum(), area * 0.006, rtol=1e-9)
    faces = _faces(t)
    assert max(faces.values()) == 2  # no face shared by three tets
    # every tet touches an interior vertex (the middle of the wall)
    interior = np.zeros(len(v), bool)
    interior.reshape(len(points), 3, 3)[:, 1, 1] = True
    assert interior[t].any(axis=1).all()
    sv, quads = make_swept_surface_mesh(points, normals, depths, 0.0, 0.044)
    assert quads.shape == (4 * len(points), 4)


def test_square_pocket_of_fillet_R_is_the_ring():
    R = 0.03
    edge = ProfileContour([[-R, -R], [R, -R], [R, R], [-R, R]], R)
    points, normals, depths = edge.material_band(
        0.005, segments_per_turn=120, max_step=0.005
    )
    assert len(points) == 120
    v, t = make_swept_volume_mesh(points, normals, depths, 0.044, 0.050)
    np.testing.assert_allclose(
        tet_volumes(v, t).sum(),
        polygonal_ring_volume(0.030, 0.035, 0.044, 0.050, 120),
        rtol=1e-12,
    )


def test_profile_mesh_is_cached(tmp_path):
    edge = ProfileContour(
        [[-0.03, -0.02], [0.03, -0.02], [0.03, 0.02], [-0.03, 0.02]], 0.008
    )
    band = edge.material_band(0.005, segments_per_turn=120, max_step=0.005)
    first = profile_mesh_paths(
        *band, 0.044, 0.05, visual_z_bottom=0.0, cache_dir=tmp_path
    )
    again = profile_mesh_paths(
        *band, 0.044, 0.05, visual_z_bottom=0.0, cache_dir=tmp_path
    )
    assert first == again and all(p.is_file() for p in first)
    assert first[0].read_text().startswith("# vtk DataFile")


# -- the framed band along a 3-D edge -----------------------------------------


def _circle_stations(n, radius=0.030, z=0.050, rotation=np.eye(3), inner=True):
    """Stations of a horizontal circle (the bore's top inner edge when
    ``inner``: n1 radially out; a boss's outer edge otherwise), axis +z,
    turned by ``rotation`` about the origin."""
    theta = 2 * np.pi * np.arange(n) / n
    radial = np.stack([np.cos(theta), np.sin(theta), 0 * theta], axis=1)
    points = radius * radial + [0.0, 0.0, z]
    n1 = radial if inner else -radial
    axis = np.tile([0.0, 0.0, 1.0], (n, 1))
    return points @ rotation.T, n1 @ rotation.T, axis @ rotation.T


def test_framed_band_of_a_horizontal_circle_is_the_ring():
    points, n1, axis = _circle_stations(120)
    v, t = make_framed_swept_volume_mesh(
        points, n1, axis, 0.005, 0.006, closed=True
    )
    rv, rt = make_ring_volume_mesh(0.030, 0.035, 0.044, 0.050, 120)
    np.testing.assert_allclose(v, rv, atol=1e-15)
    np.testing.assert_array_equal(t, rt)


def test_planar_sweep_is_the_framed_band_with_a_vertical_axis():
    edge = ProfileContour(L_SHAPE, 0.004, material="inside")
    points, normals, depths = edge.material_band(
        0.005, segments_per_turn=120, max_step=0.005
    )
    v, t = make_swept_volume_mesh(points, normals, depths, 0.044, 0.050)
    n = len(points)
    fv, ft = make_framed_swept_volume_mesh(
        np.column_stack([points, np.full(n, 0.050)]),
        np.column_stack([normals, np.zeros(n)]),
        np.tile([0.0, 0.0, 1.0], (n, 1)),
        depths,
        0.006,
        closed=True,
    )
    np.testing.assert_allclose(fv, v, atol=1e-15)
    np.testing.assert_array_equal(ft, t)


def _rx(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def test_inclined_circle_band_is_the_ring_turned():
    R = _rx(np.radians(30.0))
    v, t = make_framed_swept_volume_mesh(
        *_circle_stations(120, rotation=R), 0.005, 0.006, closed=True
    )
    rv, rt = make_ring_volume_mesh(0.030, 0.035, 0.044, 0.050, 120)
    np.testing.assert_allclose(v, rv @ R.T, atol=1e-15)
    np.testing.assert_array_equal(t, rt)


def test_twisted_open_band_has_positive_tets_and_its_volume():
    # A straight 40 mm edge whose frame turns 90 degrees about it: every
    # cross-section is W x H, so the volume is W H L.
    n, L, W, H = 81, 0.040, 0.005, 0.006
    x = np.linspace(0.0, L, n)
    beta = np.linspace(0.0, np.pi / 2, n)
    points = np.column_stack([x, 0 * x, 0 * x])
    n1 = np.column_stack([0 * x, np.cos(beta), np.sin(beta)])
    axis = np.column_stack([0 * x, -np.sin(beta), np.cos(beta)])
    v, t = make_framed_swept_volume_mesh(points, n1, axis, W, H, closed=False)
    assert t.shape == (6 * 4 * (n - 1), 4)
    vol = tet_volumes(v, t)
    assert vol.min() > 0
    np.testing.assert_allclose(vol.sum(), W * H * L, rtol=1e-3)
    faces = _faces(t)
    assert max(faces.values()) == 2


def test_band_turning_with_the_edge_on_a_saddle():
    # The rim of a hole of radius r drilled along y into a tube of radius
    # R about z: points on the cylinder x^2 + y^2 = R^2, axis its outward
    # normal, n1 away from the hole's axis (into the material) and
    # perpendicular to the axis.
    r, R, n = 0.008, 0.030, 160
    theta = 2 * np.pi * np.arange(n) / n
    x, z = r * np.cos(theta), r * np.sin(theta)
    y = np.sqrt(R**2 - x**2)
    points = np.column_stack([x, y, z])
    axis = np.column_stack([x, y, 0 * x]) / R
    radial = np.column_stack([x, 0 * x, z]) / r
    n1 = radial - np.einsum("ij,ij->i", radial, axis)[:, None] * axis
    n1 /= np.linalg.norm(n1, axis=1)[:, None]
    v, t = make_framed_swept_volume_mesh(
        points, n1, axis, 0.005, 0.006, closed=True
    )
    assert tet_volumes(v, t).min() > 0
    assert max(_faces(t).values()) == 2


def test_band_wider_than_the_inner_radius_is_refused():
    points, n1, axis = _circle_stations(120, radius=0.004, inner=False)
    limit = band_width_limit(points, n1, axis, 0.006, closed=True)
    assert 0.0039 < limit < 0.0041
    v, t = make_framed_swept_volume_mesh(
        points, n1, axis, 0.5 * limit, 0.006, closed=True
    )
    assert tet_volumes(v, t).min() > 0
    with pytest.raises(ValueError, match=r"folds at s = .* narrower"):
        make_framed_swept_volume_mesh(
            points, n1, axis, 0.005, 0.006, closed=True
        )
    assert band_width_limit(*_circle_stations(120), 0.006, closed=True) == (
        np.inf
    )


def test_band_whose_frame_turns_over_is_refused():
    points, n1, axis = _circle_stations(120)
    n1[60:] *= -1
    with pytest.raises(ValueError, match=r"turns over at s = 0.09"):
        make_framed_swept_volume_mesh(
            points, n1, axis, 0.005, 0.006, closed=True
        )


@pytest.mark.parametrize(
    "change, match",
    [
        (dict(width=0.0), "width"),
        (dict(height=-1.0), "height"),
        (dict(n1=np.ones((120, 3))), "unit"),
        (dict(axis=None), "axis"),
        (dict(points=np.zeros((2, 3))), "at least 3"),
    ],
)
def test_band_bad_arguments(change, match):
    points, n1, axis = _circle_stations(120)
    args = dict(points=points, n1=n1, axis=axis, width=0.005, height=0.006)
    if "axis" in change and change["axis"] is None:
        change = dict(axis=n1)  # not perpendicular to n1
    args.update(change)
    with pytest.raises(ValueError, match=match):
        make_framed_swept_volume_mesh(**args, closed=True)


def test_edge_band_and_obj_are_cached(tmp_path):
    stations = _circle_stations(60)
    first = edge_band_mesh_path(
        *stations, 0.005, 0.006, closed=True, cache_dir=tmp_path
    )
    again = edge_band_mesh_path(
        *stations, 0.005, 0.006, closed=True, cache_dir=tmp_path
    )
    assert first == again and first.read_text().startswith("# vtk DataFile")
    obj = mesh_obj_path(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0.0]], [[0, 1, 2]], cache_dir=tmp_path
    )
    assert obj.read_text().splitlines()[-1] == "f 1 2 3"


def test_sag_spacing_of_a_circle_and_a_line():
    points, _, _ = _circle_stations(2000, radius=0.008)
    sag = 0.030 * (1 - np.cos(np.pi / 120))  # the paper's ring's
    np.testing.assert_allclose(
        sag_spacing(points, closed=True, sag=sag),
        np.sqrt(8 * 0.008 * sag),
        rtol=1e-5,
    )
    line = np.outer(np.linspace(0, 0.05, 20), [1.0, 2.0, 0.5])
    assert sag_spacing(line, closed=False, sag=sag) == np.inf
