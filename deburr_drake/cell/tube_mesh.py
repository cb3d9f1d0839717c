"""Tetrahedral volume mesh of a ring (the tube's top layer) for Drake's
compliant hydroelastic model.

Pure numpy, no pydrake. Drake builds the pressure field of a compliant ``Mesh``
from its tetrahedra (docs/own-part.md): boundary vertices get pressure 0, so the
mesh needs vertices strictly inside the volume. This module makes a structured
annular grid that has them, writes it as legacy ASCII VTK, and caches the file
by the hash of its arguments.

The ring is the n_theta-gon annulus: vertices at angles 2*pi*i/n_theta on
circles of radius inner_radius .. outer_radius, so its faces are planar and its
volume is exactly ``0.5 * n_theta * sin(2*pi/n_theta) * (R_o**2 - R_i**2) *
(z_top - z_bottom)``.
"""

from __future__ import annotations

import hashlib
import math
import os
import pathlib
import tempfile

import numpy as np

__all__ = [
    "make_ring_volume_mesh",
    "write_vtk",
    "ring_mesh_path",
    "polygonal_ring_volume",
    "make_ring_surface_mesh",
    "write_obj",
    "ring_surface_path",
    "make_swept_volume_mesh",
    "make_swept_surface_mesh",
    "profile_mesh_paths",
]


def _check_positive_finite(name, value):
    if not (
        isinstance(value, (int, float, np.floating, np.integer))
        and math.isfinite(value)
        and value > 0
    ):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")


def _check_int(name, value, minimum):
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, np.integer))
        or value < minimum
    ):
        raise ValueError(
            f"{name} must be an integer >= {minimum}, got {value!r}"
        )


def _validate(
    inner_radius, outer_radius, z_bottom, z_top, n_theta, n_radial, n_z
):
    _check_positive_finite("inner_radius", inner_radius)
    _check_positive_finite("outer_radius", outer_radius)
    if not outer_radius > inner_radius:
        raise ValueError(
            f"outer_radius must be > inner_radius = {inner_radius!r}, "
            f"got {outer_radius!r}"
        )
    for name, value in (("z_bottom", z_bottom), ("z_top", z_top)):
        if not (
            isinstance(value, (int, float, np.floating, np.integer))
            and math.isfinite(value)
        ):
            raise ValueError(f"{name} must be a finite number, got {value!r}")
    if not z_top > z_bottom:
        raise ValueError(
            f"z_top must be > z_bottom = {z_bottom!r}, got {z_top!r}"
        )
    _check_int("n_theta", n_theta, 3)
    # n_radial >= 2 and n_z >= 2 give vertices strictly inside the volume.
    _check_int("n_radial", n_radial, 2)
    _check_int("n_z", n_z, 2)


def polygonal_ring_volume(inner_radius, outer_radius, z_bottom, z_top, n_theta):
    """Volume (m^3) of the n_theta-gon annulus the mesh fills."""
    return (
        0.5
        * n_theta
        * math.sin(2.0 * math.pi / n_theta)
        * (outer_radius**2 - inner_radius**2)
        * (z_top - z_bottom)
    )


def _cross_section_triangles(n_radial, n_z):
    """Triangles (T, 3, 2) of (j, k) grid indices covering the wall's cross
    section.

    "Union Jack" pattern: each cell's diagonal points at the nearest corner of
    the cross section, so no triangle has only boundary vertices and no interior
    edge joins two boundary vertices (the simplices Drake's pressure field
    cannot handle: they would be zero-pressure regions right at the edge the
    tool touches).
    """
    tris = []
    for j in range(n_radial):
        for k in range(n_z):
            a, b, c, d = (j, k), (j + 1, k), (j, k + 1), (j + 1, k + 1)
            if (2 * j + 1 < n_radial) == (2 * k + 1 < n_z):
                tris += [(a, b, d), (a, d, c)]  # diagonal a-d
            else:
                tris += [(a, b, c), (b, d, c)]  # diagonal b-c
    return np.array(tris, dtype=np.int64)


# Vertex permutations of a triangular prism (bottom 0,1,2; top 3,4,5 above them)
# that move vertex m to position 0: rotate the triangle, swap bottom and top.
_PRISM_PERM = np.array(
    [
        [0, 1, 2, 3, 4, 5],
        [1, 2, 0, 4, 5, 3],
        [2, 0, 1, 5, 3, 4],
        [3, 4, 5, 0, 1, 2],
        [4, 5, 3, 1, 2, 0],
        [5, 3, 4, 2, 0, 1],
    ],
    dtype=np.int64,
)


def _split_prisms(prisms, rank):
    """Split prisms (M, 6) into 3 tets each; quad-face diagonals start at the
    lowest-rank vertex.

    Diagonals chosen by one global vertex order match on every shared face (no
    cracks), and such a prism always splits into 3 tets (Dompierre et al.,
    1999). Every tet contains the prism's lowest-rank vertex.
    """
    m = np.argmin(rank[prisms], axis=1)
    P = np.take_along_axis(prisms, _PRISM_PERM[m], axis=1)
    p, q, r, p1, q1, r1 = P.T
    first = np.stack([p, p1, q1, r1], axis=1)
    rq = rank[np.stack([q, r, r1, q1], axis=1)]
    diag_q_r1 = np.isin(np.argmin(rq, axis=1), (0, 2))
    t2 = np.where(
        diag_q_r1[:, None],
        np.stack([p, q, r, r1], axis=1),
        np.stack([p, q, r, q1], axis=1),
    )
    t3 = np.where(
        diag_q_r1[:, None],
        np.stack([p, q, r1, q1], axis=1),
        np.stack([p, r, r1, q1], axis=1),
    )
    return np.stack([first, t2, t3], axis=1).reshape(-1, 4)


def make_ring_volume_mesh(
    inner_radius, outer_radius, z_bottom, z_top, n_theta, n_radial=2, n_z=2
):
    """Structured tetrahedral mesh of the ring inner_radius <= r <=
    outer_radius, z_bottom <= z <= z_top.

    Each hexahedral cell (one angular segment x one radial x one height step) is
    cut into two triangular prisms by a "Union Jack" diagonal of its cross
    section and each prism into 3 tets, with face diagonals chosen from one
    global vertex order (interior vertices first), so neighbouring cells match
    and every tet touches an interior vertex: Drake's pressure field (0 on the
    boundary) is positive in every tet.

    Args:
        inner_radius, outer_radius: radii (m),
            0 < inner_radius < outer_radius.
        z_bottom, z_top: heights (m), z_bottom < z_top.
        n_theta: segments around (>= 3); n_radial: cells through the wall
            (>= 2); n_z: cells in height (>= 2). n_radial, n_z >= 2
            guarantee interior vertices.

    Returns:
        (vertices, tets): float array (n_theta*(n_radial+1)*(n_z+1), 3) in m
        and int array (6*n_theta*n_radial*n_z, 4); every tet has positive
        signed volume det([v1-v0, v2-v0, v3-v0]) / 6 > 0. Vertex index =
        (i*(n_radial+1) + j)*(n_z+1) + k for angle index i (angle
        2*pi*i/n_theta), radial index j, height index k.
    """
    _validate(
        inner_radius, outer_radius, z_bottom, z_top, n_theta, n_radial, n_z
    )
    theta = 2.0 * np.pi * np.arange(n_theta) / n_theta
    radii = np.linspace(inner_radius, outer_radius, n_radial + 1)
    heights = np.linspace(z_bottom, z_top, n_z + 1)
    T, R, Z = np.meshgrid(theta, radii, heights, indexing="ij")
    vertices = np.stack([R * np.cos(T), R * np.sin(T), Z], axis=-1).reshape(
        -1, 3
    )
    return vertices, _sweep_tets(vertices, n_theta, n_radial, n_z)


def _sweep_tets(vertices, n_stations, n_radial, n_z):
    """Tets (6 n_stations n_radial n_z, 4) of a closed sweep of a
    (n_radial x n_z)-cell cross-section through n_stations stations, the
    vertex of station i, radial index j, height index k at
    (i*(n_radial+1) + j)*(n_z+1) + k; positively oriented."""
    # Global vertex order: interior vertices first, then by index.
    J, K = np.meshgrid(
        np.arange(n_radial + 1), np.arange(n_z + 1), indexing="ij"
    )
    boundary = ((J == 0) | (J == n_radial) | (K == 0) | (K == n_z)).ravel()
    boundary = np.tile(boundary, n_stations)
    order = np.lexsort((np.arange(len(vertices)), boundary))
    rank = np.empty(len(vertices), dtype=np.int64)
    rank[order] = np.arange(len(vertices))

    tris = _cross_section_triangles(n_radial, n_z)  # (T, 3, 2)
    local = tris[..., 0] * (n_z + 1) + tris[..., 1]  # (T, 3)
    stride = (n_radial + 1) * (n_z + 1)
    i = np.arange(n_stations)[:, None, None]
    bottom = i * stride + local[None]  # (n_stations, T, 3)
    top = ((i + 1) % n_stations) * stride + local[None]
    prisms = np.concatenate([bottom, top], axis=2).reshape(-1, 6)
    tets = _split_prisms(prisms, rank)

    p = vertices[tets]
    signed = np.einsum(
        "ij,ij->i",
        np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]),
        p[:, 3] - p[:, 0],
    )
    negative = signed < 0
    tets[negative] = tets[negative][:, [0, 2, 1, 3]]
    return tets


def make_swept_volume_mesh(
    points, normals, depths, z_bottom, z_top, n_radial=2, n_z=2
):
    """Tetrahedral mesh of the material along a closed planar profile: at
    each station (points (N, 2), m) the wall runs ``depths`` (N,) along
    ``normals`` (N, 2, unit, into the material), z_bottom <= z <= z_top;
    the ring's cross-section and tet split (:func:`make_ring_volume_mesh`)
    swept through the stations in order. Returns (vertices, tets) as
    make_ring_volume_mesh does, station i in place of angle index i."""
    points = np.asarray(points, float)
    normals = np.asarray(normals, float)
    depths = np.asarray(depths, float)
    n = len(points)
    if (
        points.shape != (n, 2)
        or normals.shape != (n, 2)
        or depths.shape != (n,)
        or n < 3
    ):
        raise ValueError(
            "points and normals must have shape (N, 2) and depths (N,), N >= 3"
        )
    if not np.all(depths > 0):
        raise ValueError("depths must be > 0")
    _validate(1.0, 2.0, z_bottom, z_top, 3, n_radial, n_z)
    frac = np.arange(n_radial + 1) / n_radial
    xy = (
        points[:, None, :]
        + (frac[None, :, None] * depths[:, None, None]) * normals[:, None, :]
    )
    heights = np.linspace(z_bottom, z_top, n_z + 1)
    XY = np.broadcast_to(xy[:, :, None, :], (n, n_radial + 1, n_z + 1, 2))
    Z = np.broadcast_to(
        heights[None, None, :, None], (n, n_radial + 1, n_z + 1, 1)
    )
    vertices = np.concatenate([XY, Z], axis=-1).reshape(-1, 3)
    tets = _sweep_tets(vertices, n, n_radial, n_z)
    if np.any(tet_volumes(vertices, tets) <= 0):
        raise ValueError("the swept mesh has flat or inverted tetrahedra")
    return vertices, tets


def tet_volumes(vertices, tets):
    """Signed volumes (m^3) of the tetrahedra."""
    p = np.asarray(vertices, dtype=float)[np.asarray(tets)]
    return (
        np.einsum(
            "ij,ij->i",
            np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]),
            p[:, 3] - p[:, 0],
        )
        / 6.0
    )


def _vtk_text(vertices, tets):
    vertices = np.asarray(vertices, dtype=float)
    tets = np.asarray(tets, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise ValueError(
            f"vertices must have shape (N, 3), got {vertices.shape}"
        )
    if tets.ndim != 2 or tets.shape[1] != 4:
        raise ValueError(f"tets must have shape (M, 4), got {tets.shape}")
    if tets.size and (tets.min() < 0 or tets.max() >= len(vertices)):
        raise ValueError(
            f"tets must index vertices in [0, {len(vertices) - 1}]"
        )
    lines = [
        "# vtk DataFile Version 3.0",
        "deburr_drake ring volume mesh",
        "ASCII",
        "DATASET UNSTRUCTURED_GRID",
        f"POINTS {len(vertices)} double",
    ]
    # Fixed format (and "+0.0" for "-0.0") so the bytes are the same on every
    # run.
    lines += ["%.12e %.12e %.12e" % tuple(v) for v in (vertices + 0.0)]
    lines.append(f"CELLS {len(tets)} {5 * len(tets)}")
    lines += ["4 %d %d %d %d" % tuple(t) for t in tets]
    lines.append(f"CELL_TYPES {len(tets)}")
    lines += ["10"] * len(tets)
    return "\n".join(lines) + "\n"


def write_vtk(path, vertices, tets):
    """Write a legacy ASCII VTK UNSTRUCTURED_GRID of tetrahedra (cell type 10),
    byte-deterministic."""
    pathlib.Path(path).write_bytes(_vtk_text(vertices, tets).encode("ascii"))


def _default_cache_dir():
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(
        os.path.expanduser("~"), ".cache"
    )
    return pathlib.Path(base) / "deburr_drake" / "meshes"


def _cached(directory, name, text):
    """Write text to directory/name atomically (temp file + os.replace) unless
    it holds exactly that text already; return the path. A cached file that
    differs (truncated, edited, a disk error) is rebuilt: regenerating the text
    costs about 12 ms for the default ring."""
    directory = (
        pathlib.Path(directory)
        if directory is not None
        else _default_cache_dir()
    )
    path = directory / name
    data = text().encode("ascii")
    try:
        if path.read_bytes() == data:
            return path
    except OSError:  # absent (or unreadable: rewritten below)
        pass
    directory.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(
        prefix=path.stem + ".", suffix=".tmp", dir=directory
    )
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def _key(kind, inner_radius, outer_radius, z_bottom, z_top, counts):
    key = (
        kind
        + ":"
        + ",".join(
            repr(float(x))
            for x in (inner_radius, outer_radius, z_bottom, z_top)
        )
        + ":"
        + ",".join(str(int(n)) for n in counts)
    )
    return hashlib.sha256(key.encode()).hexdigest()[:16]


def ring_mesh_path(
    inner_radius,
    outer_radius,
    z_bottom,
    z_top,
    n_theta,
    n_radial=2,
    n_z=2,
    cache_dir=None,
):
    """Path of the cached ring volume mesh (.vtk) for these arguments; generated
    only when absent.

    The file name carries a SHA-256 of the arguments (repr of floats, exact);
    the file is written to a temporary file in the cache dir and moved in place
    with os.replace, so concurrent processes never see a partial file. cache_dir
    defaults to $XDG_CACHE_HOME/deburr_drake/meshes (or
    ~/.cache/deburr_drake/meshes).
    """
    _validate(
        inner_radius, outer_radius, z_bottom, z_top, n_theta, n_radial, n_z
    )
    digest = _key(
        "ring-v2",
        inner_radius,
        outer_radius,
        z_bottom,
        z_top,
        (n_theta, n_radial, n_z),
    )
    name = f"ring_{int(n_theta)}x{int(n_radial)}x{int(n_z)}_{digest}.vtk"
    return _cached(
        cache_dir,
        name,
        lambda: _vtk_text(
            *make_ring_volume_mesh(
                inner_radius,
                outer_radius,
                z_bottom,
                z_top,
                n_theta,
                n_radial,
                n_z,
            )
        ),
    )


def make_ring_surface_mesh(
    inner_radius, outer_radius, z_bottom, z_top, n_theta
):
    """Boundary of the n_theta-gon annulus as quads: (vertices (4*n_theta, 3),
    quads (4*n_theta, 4)).

    Quads are counter-clockwise seen from outside (outward normals). For visuals
    (Meshcat renders .obj, not .vtk).
    """
    _validate(inner_radius, outer_radius, z_bottom, z_top, n_theta, 2, 2)
    theta = 2.0 * np.pi * np.arange(n_theta) / n_theta
    # Cross-section loop s = 0..3: inner-bottom, outer-bottom, outer-top,
    # inner-top.
    loop = np.array(
        [
            [inner_radius, z_bottom],
            [outer_radius, z_bottom],
            [outer_radius, z_top],
            [inner_radius, z_top],
        ]
    )
    c, s_ = np.cos(theta)[:, None], np.sin(theta)[:, None]
    vertices = np.stack(
        [
            loop[None, :, 0] * c,
            loop[None, :, 0] * s_,
            np.broadcast_to(loop[:, 1], (n_theta, 4)),
        ],
        axis=-1,
    ).reshape(-1, 3)
    i = np.arange(n_theta)[:, None]
    s = np.arange(4)[None, :]
    v = lambda ii, ss: (ii % n_theta) * 4 + ss % 4  # noqa: E731
    quads = np.stack(
        [v(i, s), v(i + 1, s), v(i + 1, s + 1), v(i, s + 1)], axis=-1
    ).reshape(-1, 4)
    return vertices, quads


def _obj_text(vertices, faces):
    lines = ["# deburr_drake ring surface"]
    lines += [
        "v %.12e %.12e %.12e" % tuple(p)
        for p in (np.asarray(vertices, dtype=float) + 0.0)
    ]
    lines += ["f " + " ".join(str(int(k) + 1) for k in f) for f in faces]
    return "\n".join(lines) + "\n"


def write_obj(path, vertices, faces):
    """Write a Wavefront OBJ (1-based faces), byte-deterministic."""
    pathlib.Path(path).write_bytes(_obj_text(vertices, faces).encode("ascii"))


def ring_surface_path(
    inner_radius, outer_radius, z_bottom, z_top, n_theta, cache_dir=None
):
    """Path of the cached ring surface (.obj), cached and written like
    ring_mesh_path."""
    _validate(inner_radius, outer_radius, z_bottom, z_top, n_theta, 2, 2)
    digest = _key(
        "ring-obj-v1", inner_radius, outer_radius, z_bottom, z_top, (n_theta,)
    )
    return _cached(
        cache_dir,
        f"ring_{int(n_theta)}_{digest}.obj",
        lambda: _obj_text(
            *make_ring_surface_mesh(
                inner_radius, outer_radius, z_bottom, z_top, n_theta
            )
        ),
    )


def make_swept_surface_mesh(points, normals, depths, z_bottom, z_top):
    """Boundary quads of :func:`make_swept_volume_mesh`'s wall (for
    visuals), outward normals: (vertices (4 N, 3), quads (4 N, 4))."""
    points = np.asarray(points, float)
    far = points + np.asarray(depths, float)[:, None] * np.asarray(
        normals, float
    )
    n = len(points)
    # Cross-section loop: near-bottom, far-bottom, far-top, near-top.
    loop_xy = np.stack([points, far, far, points], axis=1)  # (n, 4, 2)
    loop_z = np.broadcast_to(
        np.array([z_bottom, z_bottom, z_top, z_top]), (n, 4)
    )
    vertices = np.concatenate([loop_xy, loop_z[..., None]], axis=-1).reshape(
        -1, 3
    )
    i = np.arange(n)[:, None]
    s = np.arange(4)[None, :]
    v = lambda ii, ss: (ii % n) * 4 + ss % 4  # noqa: E731
    quads = np.stack(
        [v(i, s), v(i + 1, s), v(i + 1, s + 1), v(i, s + 1)], axis=-1
    ).reshape(-1, 4)
    # Outward: the quad's normal must point away from the wall's middle.
    p = vertices[quads]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 3] - p[:, 0])
    middle = np.repeat((points + 0.5 * (far - points)), 4, axis=0)
    mid_z = 0.5 * (z_bottom + z_top)
    out = p.mean(axis=1) - np.column_stack(
        [middle, np.full(len(middle), mid_z)]
    )
    flip = np.einsum("ij,ij->i", normal, out) < 0
    quads[flip] = quads[flip][:, ::-1]
    return vertices, quads


def profile_mesh_paths(
    points,
    normals,
    depths,
    z_bottom,
    z_top,
    n_radial=2,
    n_z=2,
    visual_z_bottom=None,
    cache_dir=None,
):
    """(volume .vtk path, surface .obj path of the compliant layer, surface
    .obj of the wall below it or None) of a profile's wall, cached like
    :func:`ring_mesh_path` by a SHA-256 of the stations."""
    arrays = [np.asarray(a, float) for a in (points, normals, depths)]
    digest = hashlib.sha256(
        b"".join(a.tobytes() for a in arrays)
        + repr(
            (
                float(z_bottom),
                float(z_top),
                int(n_radial),
                int(n_z),
                visual_z_bottom,
            )
        ).encode()
    ).hexdigest()[:16]
    n = len(arrays[0])
    volume = _cached(
        cache_dir,
        f"profile_{n}x{int(n_radial)}x{int(n_z)}_{digest}.vtk",
        lambda: _vtk_text(
            *make_swept_volume_mesh(*arrays, z_bottom, z_top, n_radial, n_z)
        ),
    )
    surface = _cached(
        cache_dir,
        f"profile_{n}_{digest}.obj",
        lambda: _obj_text(*make_swept_surface_mesh(*arrays, z_bottom, z_top)),
    )
    body = None
    if visual_z_bottom is not None and visual_z_bottom < z_bottom:
        body = _cached(
            cache_dir,
            f"profile_{n}_{digest}_body.obj",
            lambda: _obj_text(
                *make_swept_surface_mesh(*arrays, visual_z_bottom, z_bottom)
            ),
        )
    return volume, surface, body
