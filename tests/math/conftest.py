"""Fixtures of the math tests: the shipped cross-hole part."""

import math
from pathlib import Path

import pytest

from deburr_drake.math.mesh_part import load_part
from deburr_drake.math.mesh_registration import MeshSurface, cylinder_faces

PARTS = Path(__file__).resolve().parents[2] / "models" / "parts"
# The cross-hole part as examples/cross_hole_6dof.yaml places it: the
# hole's axis (+x in the file) up, the tube's axis along -x.
CROSS_HOLE_XYZ = [0.99, 0.0, 0.47]
CROSS_HOLE_RPY = [0.0, -math.pi / 2, 0.0]


@pytest.fixture(scope="module")
def cross_hole_part():
    """(part, MeshSurface, the hole's faces) of the cross-hole part."""
    part = load_part(
        PARTS / "cross_hole.stl",
        units="mm",
        xyz=CROSS_HOLE_XYZ,
        rpy=CROSS_HOLE_RPY,
    )
    surface = MeshSurface(part.mesh.vertices, part.mesh.faces)
    hole = cylinder_faces(
        surface,
        point=part.to_world([0.0, 0.0, 0.040]),
        axis=part.rotation @ [1.0, 0.0, 0.0],
        radius=0.008,
        tolerance=2e-4,
    )
    return part, surface, hole
