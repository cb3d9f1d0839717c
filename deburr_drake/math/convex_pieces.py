"""A part's collision geometry for planning: convex pieces whose union is
the part (pure numpy/trimesh; the decomposition itself by V-HACD).

Drake's distance queries treat a mesh as its convex hull, which fills a
block's bore, holes and slot; a move planned against the hull could never
reach into them. ``convex_pieces`` splits the part's mesh into convex
pieces (V-HACD through trimesh, the vhacdx wheel) and keeps them in a
cache file beside the part, ``<file>.convex.npz``: the decomposition takes
seconds to a minute, is deterministic for a given file and settings, and
the cache records both (the file's SHA-256 and the settings), so a changed
file or setting is decomposed again and nothing is computed twice. The
pieces are in the file's own coordinates and unit; ``placed_pieces``
scales and places them as ``load_part`` places the part.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull, QhullError
import trimesh

from deburr_drake.math.mesh_part import MeshPart
from deburr_drake.math.units import UNITS

__all__ = ["MAX_PIECES", "cache_path", "convex_pieces", "placed_pieces"]

#: V-HACD's pieces at most: on the job's block 64 pieces keep its bore,
#: slot and holes open where the cutter goes in (docs/job.md).
MAX_PIECES = 64


def cache_path(path) -> Path:
    """``<file>.convex.npz`` beside the part's file."""
    path = Path(path)
    return path.with_name(path.name + ".convex.npz")


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _read_cache(cache: Path, digest: str, max_pieces: int):
    if not cache.is_file():
        return None
    with np.load(cache) as data:
        if str(data["sha256"]) != digest or int(data["max_pieces"]) != int(
            max_pieces
        ):
            return None
        counts = data["counts"]
        vertices = np.split(data["vertices"], np.cumsum(counts)[:-1])
    return [np.asarray(v, float) for v in vertices]


def _decompose(mesh: trimesh.Trimesh, max_pieces: int):
    try:
        import vhacdx  # noqa: F401 (trimesh's V-HACD engine)
    except ImportError as error:
        raise ValueError(
            "decomposing a part into convex pieces needs vhacdx "
            "(pip install deburr_drake[planning])"
        ) from error
    pieces = trimesh.decomposition.convex_decomposition(
        mesh, maxConvexHulls=max_pieces
    )
    # each piece by its vertices (Drake's Convex takes their hull); a flat
    # piece (V-HACD leaves some on a face) has no hull and holds nothing
    least = 1e-6 * mesh.volume
    return [
        np.asarray(p["vertices"], float)
        for p in pieces
        if _volume(p["vertices"]) > least
    ]


def _volume(points) -> float:
    try:
        return float(ConvexHull(points).volume)
    except QhullError:
        return 0.0


def convex_pieces(path, *, max_pieces: int = MAX_PIECES, write: bool = True):
    """The convex pieces of the closed mesh in ``path`` (STL or OBJ), as a
    list of vertex arrays (k x 3) in the file's coordinates: read from
    :func:`cache_path` when it was made from this file with this
    ``max_pieces``, else decomposed (and written there when ``write``).
    ValueError: no such file, or vhacdx missing where a decomposition is
    needed."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    digest = _sha256(path)
    cache = cache_path(path)
    cached = _read_cache(cache, digest, max_pieces)
    if cached is not None:
        return cached
    mesh = trimesh.load_mesh(str(path))
    pieces = _decompose(mesh, max_pieces)
    if write:
        np.savez_compressed(
            cache,
            sha256=digest,
            max_pieces=int(max_pieces),
            counts=np.array([len(p) for p in pieces]),
            vertices=np.vstack(pieces),
        )
    return pieces


def placed_pieces(pieces, part: MeshPart, units: str):
    """``pieces`` (the file's coordinates, in ``units``) placed in the world
    as ``part`` was (m)."""
    scale = UNITS[units]
    return [
        (np.asarray(p) * scale) @ part.rotation.T + part.translation
        for p in pieces
    ]
