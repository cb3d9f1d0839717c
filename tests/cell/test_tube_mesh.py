"""Tests of deburr_drake.cell.tube_mesh (pure numpy; pydrake only to read the
file back)."""

import collections

import numpy as np
import pytest

from deburr_drake.cell.tube_mesh import (
    make_ring_volume_mesh,
    polygonal_ring_volume,
    ring_mesh_path,
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
from deburr_drake.math.geometry import ProfileContour  # noqa: E402

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
