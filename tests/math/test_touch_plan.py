"""Tests of deburr_drake.math.touch_plan: touches planned on a mesh part's
reachable faces pin its pose (and a hole's size), and a part whose faces
cannot pin a degree of freedom is refused naming it."""

from pathlib import Path

import numpy as np
import pytest
import trimesh

from deburr_drake.math.mesh_part import load_part
from deburr_drake.math.mesh_registration import (
    MeshSurface,
    register_mesh,
)
from deburr_drake.math.registration import MAX_AMPLIFICATION
from deburr_drake.math.rigid import rpy_matrix
from deburr_drake.math.touch_plan import plan_touches, reachable_faces

PARTS = Path(__file__).resolve().parents[2] / "models" / "parts"
XYZ = [0.99, 0.0, 0.47]  # the cross-hole part's origin (conftest.py)
PROBE = dict(probe_radius=0.003, clearance=0.002, rise=0.05)


@pytest.fixture(scope="module")
def cross_hole(cross_hole_part):
    _, surface, hole = cross_hole_part
    return surface, hole, reachable_faces(surface, **PROBE)


def test_a_box_is_touched_from_above_and_the_sides():
    box = trimesh.creation.box(extents=[0.04, 0.04, 0.02])
    surface = MeshSurface(box.vertices, box.faces)
    ok = reachable_faces(surface, **PROBE)
    np.testing.assert_array_equal(ok, surface.normals[:, 2] > -0.5)


def test_a_hole_too_narrow_for_the_probe_is_not_reachable(cross_hole):
    surface, hole, ok = cross_hole
    assert ok[hole].sum() > 0.5 * hole.sum()  # from inside the 8 mm hole
    wide = reachable_faces(surface, **{**PROBE, "probe_radius": 0.0085})
    assert not wide[hole].any()
    # the bore (radius 20 mm about the tube's axis, along x) is closed
    # from above but through the hole, and its faces' centroids (faces
    # the tube's length) lie off the hole: none is reached
    c = surface.centroid
    bore = np.abs(np.hypot(c[:, 1], c[:, 2] - 0.47) - 0.020) < 2e-4
    assert bore.sum() > 100 and not ok[bore].any()


def test_plan_pins_the_pose_and_the_hole(cross_hole):
    surface, hole, ok = cross_hole
    plan = plan_touches(surface, count=12, reachable=ok, sized_faces=hole)
    assert len(plan.points) == 12 and ok[plan.faces].all()
    assert plan.amplification <= MAX_AMPLIFICATION
    np.testing.assert_allclose(
        plan.normals, surface.normals[plan.faces], atol=0
    )
    # the plan's touches on the part moved 1 mm and 1 deg about every
    # axis, its hole 0.05 mm larger: recovered
    R = rpy_matrix(np.radians([1.0, -1.0, 1.0]))
    t = np.array(XYZ) - R @ XYZ + [0.001, -0.001, 0.001]
    grown = 5e-5
    x = plan.points - grown * plan.normals * hole[plan.faces][:, None]
    fit = register_mesh(
        surface, x @ R.T + t, max_residual=5e-5, sized_faces=hole
    )
    np.testing.assert_allclose(fit.rotation, R, atol=1e-9)
    np.testing.assert_allclose(fit.translation, t, atol=1e-9)
    assert fit.size == pytest.approx(grown, abs=1e-9)


def test_a_plan_that_cannot_pin_a_degree_of_freedom_names_it():
    part = load_part(PARTS / "tube.stl", units="mm")
    surface = MeshSurface(part.mesh.vertices, part.mesh.faces)
    ok = reachable_faces(surface, **PROBE)
    with pytest.raises(ValueError) as e:
        plan_touches(surface, count=12, reachable=ok)
    message = str(e.value)
    assert "\n" not in message
    assert "do not pin rotation about z" in message  # the tube's axis
