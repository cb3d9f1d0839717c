"""The part's convex pieces for planning: cached beside the part, made
again when the file changes, and on the job's block leaving the bore, the
slot and the holes open while covering the material."""

from pathlib import Path
import shutil

import numpy as np
import pytest
from scipy.spatial import ConvexHull
import trimesh

from deburr_drake.math.convex_pieces import (
    cache_path,
    convex_pieces,
    placed_pieces,
)
from deburr_drake.math.mesh_part import load_part

PARTS = Path(__file__).resolve().parents[2] / "models" / "parts"
BLOCK = PARTS / "block.stl"


def _inside(pieces, points):
    inside = np.zeros(len(points), bool)
    for piece in pieces:
        eq = ConvexHull(piece).equations
        inside |= np.all(points @ eq[:, :3].T + eq[:, 3] <= 1e-9, axis=1)
    return inside


def test_the_blocks_pieces_are_shipped_and_read_from_the_cache():
    assert cache_path(BLOCK).is_file()
    # write=False and the cache current: read, never decomposed
    pieces = convex_pieces(BLOCK, write=False)
    assert 8 <= len(pieces) <= 64
    assert all(p.shape[1] == 3 and len(p) >= 4 for p in pieces)


def test_the_blocks_pieces_cover_it_and_leave_its_openings_open():
    pieces = convex_pieces(BLOCK, write=False)
    mesh = trimesh.load_mesh(str(BLOCK))
    # the material: the pieces' volume is the block's, and points in it
    volume = sum(ConvexHull(p).volume for p in pieces)
    assert volume == pytest.approx(mesh.volume, rel=0.02)
    solid = np.array(
        [[-60, -40, -15], [30, -40, -15], [0, 0, -15], [-60, 30, -5]]
        + [[40, 0, -20], [-40, 0, -15], [5, 22, -15], [0, 44, -25]]
    )
    assert _inside(pieces, solid).all()
    # the air where the cutter goes in: the bore's and the slot's middles
    # and the 15 degree hole's axis, 2 to 25 mm under the top face
    air = np.array(
        [[-40, 15, -z] for z in (2, 10, 25)]
        + [[x, 22, -z] for x in (-10, 5, 20) for z in (2, 8)]
        + [[-40, -28 + z * np.tan(np.radians(15)), -z] for z in (2, 10)]
    )
    assert not _inside(pieces, air).any()
    # nothing above the top face
    assert max(p[:, 2].max() for p in pieces) < 0.05


def test_pieces_are_placed_as_the_part():
    part = load_part(BLOCK, units="mm", xyz=[1, 2, 3], rpy=[0, 0, np.pi / 2])
    pieces = convex_pieces(BLOCK, write=False)
    placed = placed_pieces(pieces, part, "mm")
    np.testing.assert_allclose(
        placed[0], (pieces[0] * 1e-3) @ part.rotation.T + [1, 2, 3]
    )


def test_a_changed_file_is_decomposed_again(tmp_path):
    path = tmp_path / "box.stl"
    trimesh.creation.box(extents=[10, 20, 30]).export(path)
    first = convex_pieces(path)
    assert cache_path(path).is_file()
    np.testing.assert_allclose(np.ptp(np.vstack(first), axis=0), [10, 20, 30])
    trimesh.creation.box(extents=[10, 20, 40]).export(path)
    again = convex_pieces(path)
    np.testing.assert_allclose(np.ptp(np.vstack(again), axis=0), [10, 20, 40])
    shutil.copy(path, tmp_path / "copy.stl")
    with pytest.raises(ValueError, match="no such file"):
        convex_pieces(tmp_path / "missing.stl")
