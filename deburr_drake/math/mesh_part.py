"""A part from a CAD file and the edges on it (pure numpy/scipy/trimesh).

``load_part`` reads an STL, OBJ or STEP file into a closed triangle mesh in
metres, placed by a pose (xyz in m, roll-pitch-yaw in rad: the part frame P
in the world W, R = Rz(yaw) Ry(pitch) Rx(roll) as Drake's RollPitchYaw).
``sharp_edges`` finds the part's edges: the mesh edges whose two faces'
normals differ by more than an angle, or for a STEP part the boundaries
between its CAD faces, chained in order into open chains and closed loops.
``choose_edge`` picks the chain nearest a point (or by index), and
``EdgeCurve`` smooths it into a C2 curve parametrised by arc length u that
carries the two faces' normals along it and gives the chamfer frame:

  * n2: the unit tangent, in the traversal direction;
  * left / right normal: the outward normals of the faces left and right of
    the traversal, seen from outside the part;
  * n1 = -(left + right) / |left + right|: into the edge between the two
    faces, the direction that removes material;
  * face angle: the angle between the two faces through the material (pi/2
    for a box's edge, 2 pi/3 where two faces meet at 120 degrees).

Everything is in SI units (m, rad) and in the world frame.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
import tempfile

import numpy as np
from scipy.interpolate import BSpline, CubicSpline
from scipy.spatial.transform import Rotation
import trimesh

from deburr_drake.math.units import UNITS

__all__ = [
    "UNITS",
    "MeshPart",
    "EdgeChain",
    "EdgeCurve",
    "ChamferFrame",
    "load_part",
    "sharp_edges",
    "choose_edge",
    "UP",
    "ToolRule",
    "EdgeSummary",
    "wall_axis",
    "hole_axis",
    "default_tool_rule",
    "side_plane_tilts",
    "rule_axes",
    "open_side",
    "surface_points",
    "spindle_hits",
    "CUTTER_RADIUS",
    "CUTTER_LENGTH",
    "HOLDER_RADIUS",
    "describe_edges",
    "shown_direction",
]


_MESH_TYPES = {".stl": "stl", ".obj": "obj"}
_STEP_TYPES = {".step", ".stp"}
_DEFAULT_SHARP_ANGLE = math.radians(30.0)
_TOOL_RULES = ("left", "right", "bisector", "axis")


@dataclasses.dataclass(frozen=True)
class MeshPart:
    """A closed, consistently wound triangle mesh in the world frame (m),
    outward normals. ``face_tags`` (STEP parts) holds the CAD face of each
    triangle, else None. ``rotation`` and ``translation`` are the pose the
    part was placed with (R_WP, p_WP)."""

    mesh: trimesh.Trimesh
    face_tags: np.ndarray | None
    rotation: np.ndarray
    translation: np.ndarray

    def to_world(self, p_P):
        """A point given in the part frame (m), in the world frame."""
        return self.rotation @ np.asarray(p_P, float) + self.translation


def _pose(xyz, rpy):
    xyz = np.asarray(xyz, float)
    rpy = np.asarray(rpy, float)
    if xyz.shape != (3,) or rpy.shape != (3,):
        raise ValueError("a pose is xyz (3 numbers, m) and rpy (3, rad)")
    if not (np.all(np.isfinite(xyz)) and np.all(np.isfinite(rpy))):
        raise ValueError("a pose's xyz and rpy must be finite")
    # scipy's extrinsic "xyz" is Rz(yaw) Ry(pitch) Rx(roll), Drake's RPY
    return Rotation.from_euler("xyz", rpy).as_matrix(), xyz


def _read_step(path, deflection):
    """Triangles and their CAD face indices of a STEP file through cascadio
    (OpenCASCADE). trimesh's own STEP loader calls cascadio without the
    face data, so cascadio is called here and its GLB read back."""
    try:
        import cascadio
    except ImportError as error:
        raise ValueError(
            f"{path}: reading STEP needs cascadio "
            "(pip install deburr_drake[cad])"
        ) from error
    with tempfile.TemporaryDirectory() as folder:
        glb = Path(folder) / "part.glb"
        try:
            cascadio.step_to_glb(
                str(path),
                str(glb),
                tol_linear=deflection,
                tol_angular=0.05,
                include_brep=True,
            )
            scene = trimesh.load(str(glb), file_type="glb")
        except Exception as error:
            raise ValueError(
                f"{path}: not a readable STEP file ({error})"
            ) from error
    vertices, faces, tags = [], [], []
    offset = 0
    geometries = getattr(scene, "geometry", {}) or {}
    for geometry in geometries.values():
        index = geometry.face_attributes.get("brep_index")
        if index is None:
            raise ValueError(f"{path}: cascadio gave no CAD faces")
        vertices.append(geometry.vertices)
        faces.append(geometry.faces + offset)
        # CAD face indices are per solid: keep solids apart
        tags.append(np.asarray(index, int) + 1_000_000 * len(tags))
        offset += len(geometry.vertices)
    if not faces:
        raise ValueError(f"{path}: no triangles in the STEP file")
    # GLB is in metres; each CAD face is meshed apart, so the vertices on
    # the faces' shared boundaries are merged here (faces keep their order)
    mesh = trimesh.Trimesh(np.vstack(vertices), np.vstack(faces), process=True)
    return mesh, np.concatenate(tags)


def _read_mesh(path, file_type):
    try:
        mesh = trimesh.load_mesh(str(path), file_type=file_type)
    except Exception as error:
        raise ValueError(
            f"{path}: not a readable {file_type.upper()} file ({error})"
        ) from error
    if isinstance(mesh, trimesh.Scene):
        mesh = mesh.to_geometry()
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ValueError(
            f"{path}: no triangles in it (not a {file_type.upper()} mesh?)"
        )
    return trimesh.Trimesh(mesh.vertices, mesh.faces, process=True)


def _check_closed(path, mesh):
    _, counts = np.unique(mesh.edges_sorted, axis=0, return_counts=True)
    open_edges = int(np.sum(counts == 1))
    shared = int(np.sum(counts > 2))
    if shared:
        raise ValueError(
            f"{path}: the mesh is not manifold ({shared} edges shared by "
            "more than two triangles)"
        )
    if open_edges:
        raise ValueError(
            f"{path}: the mesh is open, not watertight ({open_edges} edges "
            "on one triangle only): a part must be a closed solid"
        )
    if not mesh.is_winding_consistent:
        raise ValueError(f"{path}: the triangles are not consistently wound")


def load_part(
    path,
    *,
    units: str = "m",
    xyz=(0.0, 0.0, 0.0),
    rpy=(0.0, 0.0, 0.0),
    step_deflection: float = 0.01,
) -> MeshPart:
    """The part in ``path`` (STL, OBJ, or STEP with cascadio installed),
    its coordinates in ``units`` (m, mm, cm or in) scaled to metres, then
    rotated by ``rpy`` (rad) and moved by ``xyz`` (m). A STEP file keeps
    its own unit (``units`` does not apply); ``step_deflection``, the
    largest distance of its triangles from its CAD surfaces, is
    cascadio's linear tolerance (OpenCASCADE reads it in the file's
    unit), with 0.05 rad between neighbouring triangles at most.
    ValueError says what is wrong: a missing or unreadable file, unknown
    units, an open or non-manifold mesh."""
    if units not in UNITS:
        raise ValueError(f"unknown units {units!r}: one of {', '.join(UNITS)}")
    rotation, translation = _pose(xyz, rpy)
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    suffix = path.suffix.lower()
    tags = None
    if suffix in _MESH_TYPES:
        mesh = _read_mesh(path, _MESH_TYPES[suffix])
    elif suffix in _STEP_TYPES:
        # cascadio writes metres whatever the STEP file's own unit: the
        # STEP file carries its unit, so ``units`` does not apply
        mesh, tags = _read_step(path, step_deflection)
        units = "m"
    else:
        raise ValueError(
            f"{path}: unknown file type {suffix!r}: .stl, .obj, .step, .stp"
        )
    keep = mesh.nondegenerate_faces()
    if not np.all(keep):
        mesh.update_faces(keep)
        mesh.remove_unreferenced_vertices()
        if tags is not None:
            tags = tags[keep]
    _check_closed(path, mesh)
    if mesh.volume < 0.0:  # wound inwards: the normals turned outwards
        mesh.invert()
    vertices = (mesh.vertices * UNITS[units]) @ rotation.T + translation
    placed = trimesh.Trimesh(vertices, mesh.faces, process=False)
    return MeshPart(placed, tags, rotation, translation)


@dataclasses.dataclass(frozen=True)
class EdgeChain:
    """An edge of the part as a polyline of mesh vertices (m), in order.
    ``closed``: a loop (the last point joins the first; it is not
    repeated). Per segment (i to i + 1; a loop's last segment closes it):
    the outward unit normals of the faces left and right of the traversal,
    seen from outside the part."""

    points: np.ndarray
    left_normals: np.ndarray
    right_normals: np.ndarray
    closed: bool

    @property
    def segments(self):
        """Segment vectors (m), one per pair of normals."""
        end = np.roll(self.points, -1, axis=0) if self.closed else None
        if end is None:
            return np.diff(self.points, axis=0)
        return end - self.points

    @property
    def length(self):
        """m, along the polyline."""
        return float(np.linalg.norm(self.segments, axis=1).sum())

    def reversed(self) -> EdgeChain:
        """The same edge traversed the other way (left and right swap)."""
        if self.closed:
            points = np.roll(self.points[::-1], 1, axis=0)
        else:
            points = self.points[::-1]
        return EdgeChain(
            points.copy(),
            self.right_normals[::-1].copy(),
            self.left_normals[::-1].copy(),
            self.closed,
        )

    def distance(self, point):
        """m, from ``point`` to the polyline."""
        a = self.points
        b = np.roll(a, -1, axis=0) if self.closed else a[1:]
        a = a if self.closed else a[:-1]
        d = b - a
        t = np.einsum("ij,ij->i", np.asarray(point) - a, d)
        t = np.clip(t / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0, 1)
        nearest = a + t[:, None] * d
        return float(np.min(np.linalg.norm(nearest - point, axis=1)))


def _walks(edges, n_vertices):
    """Chains of the undirected ``edges`` (E x 2 vertex indices): lists of
    edge indices and vertex paths, broken where a vertex does not have
    exactly two edges; the rest are loops."""
    incident = [[] for _ in range(n_vertices)]
    for e, (a, b) in enumerate(edges):
        incident[a].append(e)
        incident[b].append(e)
    used = np.zeros(len(edges), bool)

    def walk(start, e):
        path = [start]
        while True:
            used[e] = True
            a, b = edges[e]
            v = b if a == path[-1] else a
            path.append(v)
            if len(incident[v]) != 2:
                return path, False
            nxt = [f for f in incident[v] if not used[f]]
            if not nxt:
                return path[:-1], True  # back at the start: a loop
            e = nxt[0]

    chains = []
    ends = [v for v in range(n_vertices) if len(incident[v]) not in (0, 2)]
    for v in ends:
        for e in incident[v]:
            if not used[e]:
                chains.append(walk(v, e))
    for e in range(len(edges)):
        if not used[e]:
            chains.append(walk(edges[e][0], e))
    return chains


def sharp_edges(part: MeshPart, *, min_angle: float = _DEFAULT_SHARP_ANGLE):
    """The part's edges as a list of ``EdgeChain``, longest first. A mesh
    edge belongs to one where its two faces' normals differ by more than
    ``min_angle`` (rad); on a STEP part, where the two faces lie on
    different CAD faces (``min_angle`` unused). A chain ends where more
    or fewer than two edge segments meet (a box's corner). Loops run
    counter-clockwise seen from outside (about the mean of their faces'
    normals), start at their lexicographically smallest vertex; open
    chains start at that of their two ends."""
    mesh = part.mesh
    adjacency = mesh.face_adjacency
    if part.face_tags is not None:
        tags = part.face_tags
        sharp = tags[adjacency[:, 0]] != tags[adjacency[:, 1]]
    else:
        sharp = mesh.face_adjacency_angles > min_angle
    faces = adjacency[sharp]
    edges = mesh.face_adjacency_edges[sharp]
    # which of the two faces has the edge as (a -> b) in its winding: the
    # face left of a -> b seen from outside
    tri = mesh.faces[faces[:, 0]]
    a, b = edges[:, 0], edges[:, 1]
    forward = np.zeros(len(edges), bool)
    for k in range(3):
        forward |= (tri[:, k] == a) & (tri[:, (k + 1) % 3] == b)
    left_of_ab = np.where(forward, faces[:, 0], faces[:, 1])
    right_of_ab = np.where(forward, faces[:, 1], faces[:, 0])
    lookup = {(int(p), int(q)): i for i, (p, q) in enumerate(edges)}
    normals = mesh.face_normals
    chains = []
    for path, closed in _walks(edges, len(mesh.vertices)):
        pairs = list(zip(path[:-1], path[1:]))
        if closed:
            pairs.append((path[-1], path[0]))
        left, right = [], []
        for p, q in pairs:
            i = lookup.get((p, q))
            if i is not None:
                left.append(left_of_ab[i])
                right.append(right_of_ab[i])
            else:
                i = lookup[(q, p)]
                left.append(right_of_ab[i])
                right.append(left_of_ab[i])
        chain = EdgeChain(
            mesh.vertices[path].copy(),
            normals[left].copy(),
            normals[right].copy(),
            closed,
        )
        chains.append(_canonical(chain))
    chains.sort(key=lambda c: -c.length)
    return chains


def _canonical(chain):
    def first(points):
        return int(np.lexsort(np.round(points, 12).T[::-1])[0])

    if not chain.closed:
        p = chain.points
        ends = np.array([p[0], p[-1]])
        return chain if first(ends) == 0 else chain.reversed()
    p = chain.points
    area = 0.5 * np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)
    outward = (chain.left_normals + chain.right_normals).sum(axis=0)
    if area @ outward < 0.0:
        chain = chain.reversed()
    k = first(chain.points)
    return EdgeChain(
        np.roll(chain.points, -k, axis=0),
        np.roll(chain.left_normals, -k, axis=0),
        np.roll(chain.right_normals, -k, axis=0),
        True,
    )


def choose_edge(chains, *, near=None, index=None) -> EdgeChain:
    """The chain nearest the point ``near`` (m, the chains' frame) or the
    one at ``index`` (``sharp_edges`` lists them longest first)."""
    if not chains:
        raise ValueError("the part has no edges")
    if (near is None) == (index is None):
        raise ValueError("choose an edge by near or by index (one of them)")
    if index is not None:
        if not 0 <= index < len(chains):
            raise ValueError(
                f"edge index {index}: the part has {len(chains)} edges "
                f"(0 to {len(chains) - 1})"
            )
        return chains[index]
    near = np.asarray(near, float)
    if near.shape != (3,) or not np.all(np.isfinite(near)):
        raise ValueError("near is a point: 3 finite numbers (m)")
    return min(chains, key=lambda c: c.distance(near))


@dataclasses.dataclass(frozen=True)
class ChamferFrame:
    """The edge at arc lengths u (arrays with u's shape first): the point
    (m), n1 into the edge, n2 along it, the two faces' outward normals,
    the angle between the faces through the material (rad) and whether
    the edge is convex (material inside the faces' wedge)."""

    point: np.ndarray
    n1: np.ndarray
    n2: np.ndarray
    left_normal: np.ndarray
    right_normal: np.ndarray
    face_angle: np.ndarray
    convex: np.ndarray


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _densify(points, closed):
    """Segments much longer than the chain's typical one (a straight run
    between fine curved parts, a box's edge) split into pieces of the
    typical length, so that the least-squares fit sees no long gap; the
    points and, per piece, the chain segment it came from."""
    ends = np.roll(points, -1, axis=0) if closed else points[1:]
    starts = points if closed else points[:-1]
    lengths = np.linalg.norm(ends - starts, axis=1)
    typical = float(np.median(lengths))
    pieces = np.where(
        lengths > 2.0 * typical, np.ceil(lengths / typical), 1
    ).astype(int)
    # a chain of one or two segments (a box's edge): a few points more
    pieces = np.maximum(pieces, math.ceil(16 / len(lengths)))
    out = []
    parent = []
    for i, (a, b, k) in enumerate(zip(starts, ends, pieces)):
        t = np.arange(k)[:, None] / k
        out.append(a + t * (b - a))
        parent += [i] * k
    if not closed:
        out.append(points[-1:])
    return np.vstack(out), np.array(parent)


def _least_squares_spline(x, y, period, spacing):
    """A cubic B-spline fitted to y(x) (rows) by least squares on uniform
    knots about ``spacing`` apart: periodic with ``period`` if given, else
    clamped at x[0] and x[-1]. On uniform knots it is C2, and it follows a
    curve sampled at vertices within (h^4 / 384) times its curvature cubed
    while averaging out the wiggles of a boolean's vertices."""
    length = period if period is not None else x[-1] - x[0]
    n = max(4, round(length / spacing))
    h = length / n
    if period is not None:
        knots = h * np.arange(-3, n + 4)
        basis = BSpline.design_matrix(x, knots, 3).toarray()
        # coefficients j and j + n are one: the spline repeats
        basis[:, :3] += basis[:, n : n + 3]
        basis = basis[:, :n]
    else:
        inner = x[0] + h * np.arange(1, n)
        knots = np.concatenate([[x[0]] * 4, inner, [x[-1]] * 4])
        basis = BSpline.design_matrix(x, knots, 3).toarray()
    coefficients = np.linalg.lstsq(basis, y, rcond=None)[0]
    if period is not None:
        coefficients = np.vstack([coefficients, coefficients[:3]])
        return BSpline(knots, coefficients, 3, extrapolate="periodic")
    return BSpline(knots, coefficients, 3)


class EdgeCurve:
    """An ``EdgeChain`` smoothed into a C2 curve c(u) with u the arc length
    (m, 0 <= u <= length; a loop's u is taken modulo its length).

    The chain's points are fitted by a cubic least-squares B-spline on
    knots ``knot_spacing`` (m) apart (at least twice the chain's median
    segment; periodic for a loop), resampled every ``spacing`` (m) of its
    arc length and interpolated by a cubic spline in arc length. The
    faces' normals, one per chain segment, are averaged over a Gaussian
    window of ``normal_window`` (m, standard deviation; at least the
    longest piece) so that the facets of a curved face do not show, made
    normal to the curve and interpolated the same way.
    """

    def __init__(
        self,
        chain: EdgeChain,
        *,
        knot_spacing: float = 1.0e-3,
        spacing: float = 5.0e-4,
        normal_window: float = 1.0e-3,
    ):
        self.closed = chain.closed
        self.chain = chain
        points, parent = _densify(chain.points, chain.closed)
        data = np.vstack([points, points[:1]]) if self.closed else points
        chord = np.linalg.norm(np.diff(data, axis=0), axis=1)
        x = np.concatenate([[0.0], np.cumsum(chord)])
        spacing_knots = max(
            knot_spacing,
            2.0 * float(np.median(np.linalg.norm(chain.segments, axis=1))),
        )
        if self.closed:
            fit = _least_squares_spline(x[:-1], points, x[-1], spacing_knots)
        else:
            fit = _least_squares_spline(x, points, None, spacing_knots)
        velocity = fit.derivative()
        # arc length s(x) of the fitted spline by Gauss-Legendre quadrature
        grid = np.linspace(0.0, x[-1], 16 * len(data) + 1)
        g, w = np.polynomial.legendre.leggauss(5)
        h = np.diff(grid)
        nodes = grid[:-1, None] + 0.5 * h[:, None] * (g[None, :] + 1.0)
        speed = np.linalg.norm(velocity(nodes.ravel()), axis=1)
        speed = speed.reshape(nodes.shape)
        s_grid = np.concatenate([[0.0], np.cumsum(0.5 * h * (speed @ w))])
        self.length = float(s_grid[-1])
        n = max(16, math.ceil(self.length / spacing))
        s_k = np.linspace(0.0, self.length, n + 1)
        p_k = fit(np.interp(s_k, s_grid, grid))
        bc = "periodic" if self.closed else "not-a-knot"
        if self.closed:
            p_k[-1] = p_k[0]
        self._point = CubicSpline(s_k, p_k, bc_type=bc)
        self._tangent = self._point.derivative()
        # the faces' normals at the chain's segment midpoints, averaged
        s_mid = np.interp(0.5 * (x[:-1] + x[1:]), grid, s_grid)
        d = s_k[:, None] - s_mid[None, :]
        if self.closed:
            d = (d + 0.5 * self.length) % self.length - 0.5 * self.length
        # no wider than the fit's pieces: no sample without a neighbour
        window = max(normal_window, float(chord.max()))
        kernel = chord[None, :] * np.exp(-0.5 * (d / window) ** 2)
        tangent = _unit(self._tangent(s_k))
        splines = []
        for normals in (chain.left_normals, chain.right_normals):
            n_k = kernel @ normals[parent]
            n_k -= np.einsum("ij,ij->i", n_k, tangent)[:, None] * tangent
            n_k = _unit(n_k)
            if self.closed:
                n_k[-1] = n_k[0]
            splines.append(CubicSpline(s_k, n_k, bc_type=bc))
        self._left, self._right = splines

    def _u(self, u):
        u = np.asarray(u, float)
        if self.closed:
            return np.mod(u, self.length)
        return np.clip(u, 0.0, self.length)

    def point(self, u):
        """m, c(u)."""
        return self._point(self._u(u))

    def tangent(self, u):
        """The unit tangent n2 at u, in the traversal direction."""
        return _unit(self._tangent(self._u(u)))

    def curvature_vector(self, u):
        """1/m, the curvature vector at u: towards the centre of
        curvature, its length the curvature."""
        u = self._u(u)
        t = self._tangent(u)
        a = self._point.derivative(2)(u)
        speed2 = np.sum(t * t, axis=-1, keepdims=True)
        return np.cross(np.cross(t, a), t) / speed2**2

    def curvature(self, u):
        """1/m, |c''| at u (c is parametrised by arc length)."""
        u = self._u(u)
        t = self._tangent(u)
        a = self._point.derivative(2)(u)
        speed = np.linalg.norm(t, axis=-1)
        return np.linalg.norm(np.cross(t, a), axis=-1) / speed**3

    def face_normals(self, u):
        """The outward unit normals of the faces left and right of the
        traversal at u, normal to the tangent."""
        u = self._u(u)
        t = _unit(self._tangent(u))
        out = []
        for spline in (self._left, self._right):
            n = spline(u)
            n = n - np.sum(n * t, axis=-1, keepdims=True) * t
            out.append(_unit(n))
        return tuple(out)

    def frame(self, u) -> ChamferFrame:
        """The chamfer frame at arc lengths u (m)."""
        u = self._u(u)
        n2 = self.tangent(u)
        left, right = self.face_normals(u)
        n1 = -_unit(left + right)
        between = np.arccos(np.clip(np.sum(left * right, axis=-1), -1, 1))
        convex = np.sum(n2 * np.cross(left, right), axis=-1) > 0.0
        angle = np.where(convex, math.pi - between, math.pi + between)
        return ChamferFrame(self.point(u), n1, n2, left, right, angle, convex)

    def tool_axis(self, u, *, rule="bisector", lead=0.0, tilt=0.0, axis=None):
        """The tool's axis at u: a unit vector out of the part (from the
        cutter's tip towards its holder). ``rule``: ``left`` or ``right``
        (along that face's normal), ``bisector`` (-n1, between the two
        normals) or ``axis`` (the constant unit direction ``axis``, world:
        a hole's). Then ``tilt`` (rad) turns it about n2 (right hand) and
        ``lead`` (rad) leans it towards n2 (the holder ahead of the tip)."""
        if rule not in _TOOL_RULES:
            raise ValueError(
                f"unknown tool axis rule {rule!r}: one of "
                f"{', '.join(_TOOL_RULES)}"
            )
        frame = self.frame(u)
        if rule == "axis":
            base = np.broadcast_to(
                np.asarray(axis, float) / np.linalg.norm(axis),
                frame.n2.shape,
            )
        else:
            base = {
                "left": frame.left_normal,
                "right": frame.right_normal,
                "bisector": -frame.n1,
            }[rule]
        t = frame.n2
        side = np.cross(t, base)
        axis = math.cos(tilt) * base + math.sin(tilt) * side
        return math.cos(lead) * axis + math.sin(lead) * t

    def project(self, point):
        """The arc length u (m) of the curve's point nearest ``point``."""
        point = np.asarray(point, float)
        u = np.linspace(0.0, self.length, max(64, int(self.length / 1e-4)))
        u0 = u[np.argmin(np.linalg.norm(self.point(u) - point, axis=1))]
        for _ in range(8):  # Newton on (c(u) - p) . c'(u) = 0
            r = self.point(u0) - point
            d1 = self._tangent(self._u(u0))
            d2 = self._point.derivative(2)(self._u(u0))
            step = (r @ d1) / (d1 @ d1 + r @ d2)
            u0 = float(self._u(u0 - step))
        return u0


#: The part's up (world): the default tool rule stands the tool on the
#: face whose outward normal is nearest it.
UP = np.array([0.0, 0.0, 1.0])
# -, the wall's normals' spread about the fitted axis (the square root of
# the least eigenvalue of their scatter) below which a face is a cylinder
# or cone about it: the facets of a 160-sided hole give 1e-3
_WALL_RESIDUAL = 0.05
# -, the scatter's middle eigenvalue above which the normals go round the
# axis (a full turn of a cylinder gives 0.5, a 45-degree cone's 0.25; an
# arc of a pipe's wall beside a small hole much less)
_WALL_SPREAD = 0.05
#: The tool as the open-side check sees it (m): the cutter (radius and
#: length along its axis from the edge) and beyond it the spindle's nose,
#: a cylinder of ``HOLDER_RADIUS`` round the axis; the part's surface must
#: keep out of the spindle's cylinder.
CUTTER_RADIUS = 0.003
CUTTER_LENGTH = 0.020
HOLDER_RADIUS = 0.020
# rad: a turn of the tool about the edge smaller than this is none (a
# box's edge sits at the end of its range, 0 give or take rounding; the
# side plane check allows 0.02 rad)
_TILT_NEEDED = 0.01
# stations per edge the open-side check looks at (at most one per segment)
_STATIONS = 48
# points sampled (seeded) on the part's surface, area-weighted, for it
_SURFACE_SAMPLES = 20000


def shown_direction(v) -> str:
    """A unit vector as text, 3 decimals, no "-0.000"."""
    return "[" + ", ".join(f"{round(float(x), 3) + 0.0:.3f}" for x in v) + "]"


@dataclasses.dataclass(frozen=True)
class ToolRule:
    """How the tool axis is set along an edge.

    ``kind`` ``face``: along the outward normal of the face ``side`` (left
    or right of the chain's direction) stands on, turned ``tilt`` (rad)
    about the chain's own tangent (right hand); ``axis``: the constant
    unit direction ``axis`` (world; a hole's axis, out of the part).
    ``reason`` says, in a few words, why this rule."""

    kind: str
    side: str = ""
    axis: tuple = ()
    reason: str = ""
    tilt: float = 0.0

    def describe(self) -> str:
        """One line: the rule and why."""
        if self.kind == "axis":
            a = shown_direction(self.axis)
            return f"the tool axis along {a} ({self.reason})"
        tilted = (
            f", tilted {math.degrees(self.tilt):.1f} deg about the edge"
            if self.tilt
            else ""
        )
        return f"the tool on the {self.side} face{tilted} ({self.reason})"


def _weights(chain):
    return np.linalg.norm(chain.segments, axis=1)


def wall_axis(chain: EdgeChain, side: str):
    """(axis, residual, spread): the unit axis of a cylinder or cone
    fitted to the outward normals of the face on ``side`` (left or right)
    of the loop ``chain``: the normals of such a face keep one angle to
    its axis, so they lie on a plane's circle on the unit sphere and the
    axis is the least eigenvector of their (length-weighted) scatter.
    ``residual``: the normals' spread off that circle (0 on an exact
    cylinder or cone); ``spread``: the scatter's middle eigenvalue (how
    far the normals go round). The axis' sign is not set."""
    normals = chain.left_normals if side == "left" else chain.right_normals
    w = _weights(chain)
    w = w / w.sum()
    mean = w @ normals
    d = normals - mean
    scatter = (w[:, None] * d).T @ d
    values, vectors = np.linalg.eigh(scatter)
    return (
        vectors[:, 0],
        math.sqrt(max(values[0], 0.0)),
        float(values[1]),
    )


def hole_axis(chain: EdgeChain):
    """(the unit axis out of the part, the wall's side) when ``chain`` is
    a loop round a cylindrical or conical wall (a hole, a bore, a boss),
    else None. The axis is fitted from the wall's normals (``wall_axis``)
    and points to the side the other face looks to (out of the hole)."""
    if not chain.closed:
        return None
    fits = []
    for side in ("left", "right"):
        axis, residual, spread = wall_axis(chain, side)
        if residual < _WALL_RESIDUAL and spread > _WALL_SPREAD:
            fits.append((residual, side, axis))
    if not fits:
        return None
    _, side, axis = min(fits, key=lambda fit: fit[0])
    w = _weights(chain)
    out = w @ (chain.left_normals + chain.right_normals)
    if axis @ out < 0.0:
        axis = -axis
    return axis, side


def side_plane_tilts(chain: EdgeChain, side: str):
    """rad, (lo, hi): the tilts about the chain's tangent (right hand) of a
    tool along the outward normal of the face on ``side`` for which the
    cutter's side plane (through the edge, holding the tool axis and the
    tangent) supports the part on every segment: its normal n1 within
    (pi - the faces' angle) / 2 of the faces' bisector, so it cuts into
    neither face. lo > hi: no constant tilt does (the faces' angle varies
    too much along the edge). On a convex edge at 90 degrees (a box's) the
    face's own normal is at the end of the range (0 in it); where the
    faces meet at an obtuse angle theta the least turn is theta - 90 deg,
    towards the other face."""
    t = chain.segments / np.linalg.norm(chain.segments, axis=1)[:, None]
    base = chain.left_normals if side == "left" else chain.right_normals
    into = -(chain.left_normals + chain.right_normals)
    into /= np.maximum(np.linalg.norm(into, axis=1), 1e-12)[:, None]
    n1 = np.cross(t, base)
    n1 /= np.maximum(np.linalg.norm(n1, axis=1), 1e-12)[:, None]
    n1 *= np.where(np.sum(n1 * into, 1) >= 0.0, 1.0, -1.0)[:, None]
    off = np.arctan2(
        np.sum(t * np.cross(into, n1), 1),
        np.clip(np.sum(into * n1, 1), -1.0, 1.0),
    )
    between = np.arccos(
        np.clip(np.sum(chain.left_normals * chain.right_normals, 1), -1, 1)
    )
    half = 0.5 * between  # (pi - (pi - between)) / 2 on a convex edge
    return float(np.max(-half - off)), float(np.min(half - off))


def default_tool_rule(chain: EdgeChain, up=UP) -> ToolRule:
    """The tool rule that needs no guess: on a loop round a cylindrical or
    conical wall (a hole, in a flat or curved face, drilled along its
    face's normal or not), the axis along the wall (``hole_axis``), the
    cutter's side on the wall; else the tool on the face whose outward
    normal is nearest ``up`` (world) on average along the edge (where
    both are as near, the left one). On a convex edge whose faces meet at
    more than 90 degrees that face's normal would lay the cutter's side
    plane into the other face, so the tool is turned about the edge
    towards the other face by the least angle that clears it
    (``side_plane_tilts``: the faces' angle less 90 degrees), the side
    along the other face, the axis as near the face's normal as the
    cutter allows."""
    hole = hole_axis(chain)
    if hole is not None:
        axis, side = hole
        return ToolRule(
            "axis",
            axis=tuple(float(x) for x in axis),
            reason=f"the default: a loop round a cylindrical wall ({side} "
            "of the chain), the tool along its axis",
        )
    w = _weights(chain)
    up = np.asarray(up, float) / np.linalg.norm(up)
    near_left = float(w @ (chain.left_normals @ up)) / w.sum()
    near_right = float(w @ (chain.right_normals @ up)) / w.sum()
    side = "left" if near_left >= near_right else "right"
    reason = (
        "the default: the face whose outward normal is nearest up "
        f"(cosines {near_left:.2f} left, {near_right:.2f} right)"
    )
    tilt = 0.0
    lo, hi = side_plane_tilts(chain, side)
    needed = lo > _TILT_NEEDED or hi < -_TILT_NEEDED
    if _convexity(chain) and lo <= hi and needed:
        tilt = lo if lo > 0.0 else hi
        between = np.arccos(
            np.clip(np.sum(chain.left_normals * chain.right_normals, 1), -1, 1)
        )
        angle = math.degrees(math.pi - float(np.min(between)))
        reason += (
            f"; the faces meet at up to {angle:.1f} deg, so the least turn "
            "that keeps the cutter's side out of the other face"
        )
    return ToolRule("face", side=side, reason=reason, tilt=tilt)


def rule_axes(chain: EdgeChain, rule: ToolRule):
    """The tool axis (unit, world) on each segment of ``chain`` by
    ``rule``, its tilt included."""
    if rule.kind == "axis":
        return np.tile(np.asarray(rule.axis, float), (len(chain.segments), 1))
    normals = chain.left_normals if rule.side == "left" else chain.right_normals
    if not rule.tilt:
        return normals.copy()
    t = chain.segments / np.linalg.norm(chain.segments, axis=1)[:, None]
    return math.cos(rule.tilt) * normals + math.sin(rule.tilt) * np.cross(
        t, normals
    )


@dataclasses.dataclass(frozen=True)
class EdgeSummary:
    """One edge chain of a part, as ``deburr-drake edges`` lists it.

    ``index`` (in ``sharp_edges``' order), ``closed`` (a loop),
    ``length`` (m), ``dihedral`` (rad, least and greatest angle between
    the two faces' outward normals), ``convex`` (True, False; None where
    it is both along the chain), ``point`` (m, world: the middle
    vertex), ``rule`` (``default_tool_rule``), ``reachable`` and, if not,
    ``blocked`` (why, one phrase)."""

    index: int
    closed: bool
    length: float
    dihedral: tuple
    convex: bool | None
    point: np.ndarray
    rule: ToolRule
    reachable: bool
    blocked: str = ""


def _convexity(chain):
    t = chain.segments / np.linalg.norm(chain.segments, axis=1)[:, None]
    sign = np.sum(t * np.cross(chain.left_normals, chain.right_normals), 1)
    if np.all(sign > 0.0):
        return True
    if np.all(sign < 0.0):
        return False
    return None


def surface_points(part: MeshPart, count=_SURFACE_SAMPLES):
    """m, world: the part's vertices and ``count`` points spread over its
    surface by area (seeded): what the spindle must keep clear of."""
    rng = np.random.default_rng(0)
    mesh = part.mesh
    area = mesh.area_faces / mesh.area_faces.sum()
    faces = rng.choice(len(area), size=count, p=area)
    r = rng.random((count, 2))
    flip = r.sum(axis=1) > 1.0
    r[flip] = 1.0 - r[flip]
    tri = mesh.triangles[faces]
    inside = (
        tri[:, 0]
        + r[:, :1] * (tri[:, 1] - tri[:, 0])
        + r[:, 1:] * (tri[:, 2] - tri[:, 0])
    )
    return np.vstack([mesh.vertices, inside])


def spindle_hits(
    surface,
    points,
    n1,
    axes,
    *,
    cutter_radius=CUTTER_RADIUS,
    cutter_length=CUTTER_LENGTH,
    holder_radius=HOLDER_RADIUS,
):
    """Per station (rows of ``points`` on the edge, ``n1`` into the
    material, the tool ``axes``, unit, world): whether any of the part's
    ``surface`` points (``surface_points``) lies in the spindle: farther
    than ``cutter_length`` from the edge along the axis and within
    ``holder_radius`` of the axis (the line through the cutter's centre,
    ``cutter_radius`` off the edge against n1). The cutter itself cuts
    the part; the spindle beyond it must stand in free space."""
    hits = np.zeros(len(points), bool)
    for k, (p, n, a) in enumerate(zip(points, n1, axes)):
        d = surface - (p - cutter_radius * n)
        along = d @ a
        near = along > cutter_length
        if not np.any(near):
            continue
        radial = d[near] - along[near, None] * a
        hits[k] = bool(
            np.any(np.einsum("ij,ij->i", radial, radial) < holder_radius**2)
        )
    return hits


def _rule_n1(chain, axes):
    """n1 along ``chain`` for tool ``axes`` (one per segment): normal to
    the axis and the tangent, into the material."""
    t = chain.segments / np.linalg.norm(chain.segments, axis=1)[:, None]
    side = np.cross(t, axes)
    side /= np.maximum(np.linalg.norm(side, axis=1), 1e-12)[:, None]
    into = -(chain.left_normals + chain.right_normals)
    return side * np.where(np.sum(side * into, 1) >= 0.0, 1.0, -1.0)[:, None]


def open_side(
    part: MeshPart, chain: EdgeChain, rule: ToolRule, up=UP, surface=None
):
    """'' when the tool can reach ``chain`` from the part's open side, else
    why not. The rule: (1) the part stands on its lowest points along
    ``up`` (a table, a fixture): an edge all on them is not reachable;
    (2) at up to 48 stations along the edge, with the tool axis of
    ``rule``, the spindle (``spindle_hits``: beyond the cutter's
    ``CUTTER_LENGTH``, within ``HOLDER_RADIUS`` of the axis) holds none
    of the part's surface."""
    up = np.asarray(up, float) / np.linalg.norm(up)
    base = float(np.min(part.mesh.vertices @ up))
    scale = float(part.mesh.scale)
    if np.max(chain.points @ up - base) < 1e-6 * scale + 1e-9:
        return "on the part's base (it stands on it)"
    axes = rule_axes(chain, rule)
    n = len(chain.segments)
    pick = np.unique(np.linspace(0, n - 1, min(n, _STATIONS)).astype(int))
    ends = np.roll(chain.points, -1, axis=0) if chain.closed else None
    if ends is None:
        ends = chain.points[1:]
    middle = 0.5 * (chain.points[: len(ends)] + ends)[pick]
    surface = surface_points(part) if surface is None else surface
    hits = spindle_hits(
        surface, middle, _rule_n1(chain, axes)[pick], axes[pick]
    )
    if not np.any(hits):
        return ""
    where = middle[int(np.flatnonzero(hits)[0])]
    return (
        f"the spindle along the tool axis meets the part at {np.mean(hits):.0%}"
        f" of the edge (first at [{where[0]:.4f}, {where[1]:.4f}, "
        f"{where[2]:.4f}] m, world)"
    )


def _middle(chain):
    """m: the chain's point half its length along it."""
    lengths = np.linalg.norm(chain.segments, axis=1)
    k = int(np.searchsorted(np.cumsum(lengths), 0.5 * lengths.sum()))
    k = min(k, len(lengths) - 1)
    before = float(np.sum(lengths[:k]))
    t = (0.5 * lengths.sum() - before) / max(lengths[k], 1e-300)
    return chain.points[k] + t * chain.segments[k]


def describe_edges(part: MeshPart, chains, up=UP):
    """An ``EdgeSummary`` of each chain of ``part`` (``sharp_edges``)."""
    out = []
    surface = surface_points(part)
    for index, chain in enumerate(chains):
        cos = np.sum(chain.left_normals * chain.right_normals, axis=1)
        dihedral = np.arccos(np.clip(cos, -1.0, 1.0))
        rule = default_tool_rule(chain, up)
        blocked = open_side(part, chain, rule, up, surface)
        out.append(
            EdgeSummary(
                index=index,
                closed=chain.closed,
                length=chain.length,
                dihedral=(float(dihedral.min()), float(dihedral.max())),
                convex=_convexity(chain),
                point=_middle(chain),
                rule=rule,
                reachable=not blocked,
                blocked=blocked,
            )
        )
    return out
