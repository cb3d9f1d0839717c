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

The same cross-section and split sweep along a planar profile
(:func:`make_swept_volume_mesh`) and along a 3-D edge with a moving frame
(:func:`make_framed_swept_volume_mesh`: the cross-section in the plane of
n1, into the material, and the tool axis); the ring is the framed band of a
horizontal circle. Every tet is oriented from its place in the sweep, so a
band that folds where the edge turns is refused rather than turned inside
out.
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
    "make_framed_swept_volume_mesh",
    "band_width_limit",
    "sag_spacing",
    "edge_band_mesh_path",
    "mesh_obj_path",
    "tet_volumes",
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


def _sweep_tets(vertices, n_stations, n_radial, n_z, closed=True):
    """Tets (6 (n_stations - 1 + closed) n_radial n_z, 4) of a sweep of a
    (n_radial x n_z)-cell cross-section through n_stations stations, the
    vertex of station i, cell-corner (j, k) at (i*(n_radial+1) + j)*(n_z+1)
    + k; closed sweeps join the last station to the first.

    Each tet is oriented by its shape in the sweep's parameter space
    (station, j, k) and the handedness of the stations' frames, not by its
    own volume: a folded sweep then shows as negative volumes instead of
    being hidden by flipped tets. Raises ValueError naming the first
    station whose frame has the other handedness."""
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
    n_prisms = n_stations if closed else n_stations - 1
    i = np.arange(n_prisms)[:, None, None]
    bottom = i * stride + local[None]  # (n_prisms, T, 3)
    top = ((i + 1) % n_stations) * stride + local[None]
    prisms = np.concatenate([bottom, top], axis=2).reshape(-1, 6)
    tets = _split_prisms(prisms, rank)

    # Parameter-space coordinates (station, j, k) of each tet's vertices;
    # a closed sweep's last prism reaches station n_stations, not 0.
    first = np.repeat(np.arange(n_prisms), 3 * len(tris))[:, None]
    station = tets // stride
    station = np.where(station == first, first, first + 1)
    within = tets % stride
    ref = np.stack([station, within // (n_z + 1), within % (n_z + 1)], -1)
    e = ref[:, 1:] - ref[:, :1]
    ref_sign = np.sign(
        np.einsum("ij,ij->i", np.cross(e[:, 0], e[:, 1]), e[:, 2])
    )
    handed = _station_handedness(vertices, n_stations, n_radial, n_z, closed)
    flip = ref_sign * handed[first[:, 0]] < 0
    tets[flip] = tets[flip][:, [0, 2, 1, 3]]
    return tets


def _station_handedness(vertices, n_stations, n_radial, n_z, closed):
    """+1 or -1: the sign of t . (w x h) at every station, t along the sweep,
    w and h the cross-section's j and k directions. Raises ValueError at the
    first station whose sign differs from the first's."""
    grid = np.asarray(vertices, float).reshape(
        n_stations, n_radial + 1, n_z + 1, 3
    )
    origin = grid[:, 0, 0]
    w = grid[:, -1, 0] - origin
    h = grid[:, 0, -1] - origin
    if closed:
        t = np.roll(origin, -1, axis=0) - np.roll(origin, 1, axis=0)
    else:
        t = np.gradient(origin, axis=0)
    sign = np.sign(np.einsum("ij,ij->i", t, np.cross(w, h)))
    bad = np.flatnonzero(sign != sign[0])
    if sign[0] == 0 or len(bad):
        raise _TurnedOver(0 if sign[0] == 0 else int(bad[0]))
    return sign


class _TurnedOver(ValueError):
    """A swept cross-section whose frame has the other handedness than the
    first station's (``station`` its index)."""

    def __init__(self, station):
        super().__init__(
            f"the swept cross-section turns over at station {station}: its "
            "frame is not the first station's (n1 x axis against the "
            "traversal)"
        )
        self.station = station


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


def _unit_rows(name, a, n):
    a = np.asarray(a, float)
    if a.shape != (n, 3) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be a finite array of shape ({n}, 3)")
    if not np.allclose(np.linalg.norm(a, axis=1), 1.0, atol=1e-6):
        raise ValueError(f"{name} must hold unit vectors")
    return a


def _band_arrays(points, n1, axis, width, height, closed, s):
    """The stations as checked arrays: (points, n1, axis, width (n,), s)."""
    points = np.asarray(points, float)
    n = len(points)
    if points.shape != (n, 3) or not np.all(np.isfinite(points)):
        raise ValueError("points must be a finite array of shape (N, 3)")
    if n < (3 if closed else 2):
        raise ValueError(
            f"a {'closed' if closed else 'open'} band needs at least "
            f"{3 if closed else 2} stations, got {n}"
        )
    n1 = _unit_rows("n1", n1, n)
    axis = _unit_rows("axis", axis, n)
    if np.abs(np.einsum("ij,ij->i", n1, axis)).max() > 1e-6:
        raise ValueError("n1 must be perpendicular to axis at every station")
    width = np.broadcast_to(np.asarray(width, float), (n,))
    if not np.all(np.isfinite(width) & (width > 0)):
        raise ValueError("width must be finite and > 0 (m)")
    _check_positive_finite("height", height)
    if s is None:
        step = np.linalg.norm(np.diff(points, axis=0), axis=1)
        s = np.concatenate([[0.0], np.cumsum(step)])
    return points, n1, axis, width, np.asarray(s, float)


def _prism_pairs(n, closed):
    lo = np.arange(n if closed else n - 1)
    return lo, (lo + 1) % n


def band_width_limit(points, n1, axis, height, *, closed):
    """The widest band (m) the stations can carry with ``height`` (m): the
    width at which a far corner of some cross-section stops advancing along
    the edge (where the edge turns towards the material, at about its
    radius of curvature there); inf where it never does. Raises ValueError
    if the height alone already folds the band."""
    points, n1, axis, _, s = _band_arrays(
        points, n1, axis, 1.0, height, closed, None
    )
    lo, hi = _prism_pairs(len(points), closed)
    t = points[hi] - points[lo]
    limit = np.inf
    for h in (0.0, height):
        near = np.einsum("ij,ij->i", t - h * (axis[hi] - axis[lo]), t)
        if np.any(near <= 0):
            at = s[lo[np.argmax(near <= 0)]]
            raise ValueError(
                f"the band folds at s = {at:.4g} m: the edge turns along "
                f"the tool axis faster than a height of {height:.4g} m allows"
            )
        turn = np.einsum("ij,ij->i", n1[hi] - n1[lo], t)
        inner = turn < 0
        if np.any(inner):
            limit = min(limit, float(np.min(near[inner] / -turn[inner])))
    return limit


def sag_spacing(points, *, closed, sag):
    """The station spacing (m) at which a chord of the curve through
    ``points`` (N, 3, m, dense) strays at most ``sag`` (m) from it where it
    is most curved: sqrt(8 rho sag), rho the least radius of the circles
    through three consecutive points; inf on a straight curve."""
    _check_positive_finite("sag", sag)
    p = np.asarray(points, float)
    if closed:
        a, b, c = np.roll(p, 1, axis=0), p, np.roll(p, -1, axis=0)
    else:
        a, b, c = p[:-2], p[1:-1], p[2:]
    # circumradius |ab| |bc| |ca| / (2 |ab x bc|)
    twice_area = np.linalg.norm(np.cross(b - a, c - b), axis=1)
    sides = (
        np.linalg.norm(b - a, axis=1)
        * np.linalg.norm(c - b, axis=1)
        * np.linalg.norm(a - c, axis=1)
    )
    curved = twice_area > 1e-12 * sides ** (2.0 / 3.0)
    if not np.any(curved):
        return math.inf
    rho = float(np.min(sides[curved] / (2.0 * twice_area[curved])))
    return math.sqrt(8.0 * rho * sag)


def make_framed_swept_volume_mesh(
    points, n1, axis, width, height, *, closed, n_radial=2, n_z=2, s=None
):
    """Tetrahedral band along a 3-D edge with a moving frame: at station i
    (``points`` (N, 3), m, on the edge) the cross-section is the rectangle
    [0, width] along ``n1`` (N, 3, unit, into the material) by [0, height]
    below the edge along -``axis`` (N, 3, unit, the tool axis, n1 . axis =
    0), swept through the stations in order (``closed``: the last joined to
    the first). ``width`` (m) is a number or one per station. The ring's
    cross-section and tet split (:func:`make_ring_volume_mesh`), so a
    horizontal circle with axis +z and n1 radial gives the ring's mesh.

    Returns (vertices (N (n_radial+1) (n_z+1), 3), tets (M, 4)) with vertex
    (i*(n_radial+1) + j)*(n_z+1) + k at points[i] + j/n_radial width n1 -
    (1 - k/n_z) height axis. Raises ValueError, naming the arc length
    (``s`` (N,), m; default the chord length from the first station), where
    the frame turns over or the band folds (the edge turning towards the
    material with a radius smaller than the width: see
    :func:`band_width_limit`)."""
    _check_int("n_radial", n_radial, 2)
    _check_int("n_z", n_z, 2)
    points, n1, axis, width, s = _band_arrays(
        points, n1, axis, width, height, closed, s
    )
    n = len(points)
    frac = np.arange(n_radial + 1) / n_radial
    below = (1.0 - np.arange(n_z + 1) / n_z) * height
    vertices = (
        points[:, None, None, :]
        + (frac[None, :, None] * width[:, None, None])[..., None]
        * n1[:, None, None, :]
        - below[None, None, :, None] * axis[:, None, None, :]
    ).reshape(-1, 3)
    try:
        tets = _sweep_tets(vertices, n, n_radial, n_z, closed)
    except _TurnedOver as error:
        raise ValueError(
            f"the band's frame turns over at s = {s[error.station]:.4g} m: "
            "n1 x axis points against the traversal there, not as at the "
            "start"
        ) from None
    _check_band_advances(vertices, n, n_radial, n_z, closed, s, width, height)
    volumes = tet_volumes(vertices, tets)
    if np.any(volumes <= 0):
        first = int(np.argmax(volumes <= 0)) // (6 * n_radial * n_z)
        raise ValueError(
            f"the band's tetrahedra invert at s = {s[first]:.4g} m: the "
            "frame turns too much between two stations (place them closer)"
        )
    return vertices, tets


def _check_band_advances(vertices, n, n_radial, n_z, closed, s, width, height):
    """Every corner of the cross-section moves forward along the edge from
    one station to the next: otherwise the band folds over itself."""
    grid = vertices.reshape(n, n_radial + 1, n_z + 1, 3)
    corners = grid[:, [0, 0, -1, -1], [0, -1, 0, -1]]  # (n, 4, 3)
    lo, hi = _prism_pairs(n, closed)
    t = grid[hi, 0, -1] - grid[lo, 0, -1]
    advance = np.einsum("ijk,ik->ij", corners[hi] - corners[lo], t)
    bad = np.flatnonzero(np.any(advance <= 0, axis=1))
    if len(bad):
        i = lo[bad[0]]
        raise ValueError(
            f"the band folds at s = {s[i]:.4g} m: the edge turns towards "
            f"the material with a radius below the band's width "
            f"({width[i]:.4g} m) or height ({height:.4g} m) there; "
            "make the band narrower (band_width_limit)"
        )


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


def edge_band_mesh_path(
    points,
    n1,
    axis,
    width,
    height,
    *,
    closed,
    n_radial=2,
    n_z=2,
    cache_dir=None,
):
    """Path of the cached .vtk of :func:`make_framed_swept_volume_mesh`
    for these stations, cached like :func:`ring_mesh_path` by a SHA-256 of
    the arrays and arguments."""
    arrays = [
        np.ascontiguousarray(a, dtype=float)
        for a in (points, n1, axis, np.broadcast_to(width, (len(points),)))
    ]
    digest = hashlib.sha256(
        b"".join(a.tobytes() for a in arrays)
        + repr((float(height), bool(closed), int(n_radial), int(n_z))).encode()
    ).hexdigest()[:16]
    return _cached(
        cache_dir,
        f"edge_{len(arrays[0])}x{int(n_radial)}x{int(n_z)}_{digest}.vtk",
        lambda: _vtk_text(
            *make_framed_swept_volume_mesh(
                *arrays[:3],
                arrays[3],
                height,
                closed=closed,
                n_radial=n_radial,
                n_z=n_z,
            )
        ),
    )


def mesh_obj_path(vertices, faces, *, name="part", cache_dir=None):
    """Path of a cached Wavefront OBJ of a triangle (or polygon) mesh
    (vertices (N, 3), m; faces (M, k) 0-based), named by a SHA-256 of the
    arrays and written like :func:`ring_mesh_path`."""
    vertices = np.ascontiguousarray(vertices, dtype=float)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise ValueError(
            f"vertices must have shape (N, 3), got {vertices.shape}"
        )
    if faces.ndim != 2 or faces.size == 0:
        raise ValueError("faces must be a non-empty (M, k) array")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise ValueError(
            f"faces must index vertices in [0, {len(vertices) - 1}]"
        )
    digest = hashlib.sha256(vertices.tobytes() + faces.tobytes()).hexdigest()
    return _cached(
        cache_dir,
        f"{name}_{digest[:16]}.obj",
        lambda: _obj_text(vertices, faces),
    )
