"""Tests of deburr_drake.cell.touches: a mesh part's touches planned on
the believed part (the hole's faces found, each touch's allowance, the
safe height above the part), too few touches refused naming the field,
and the guards' process state while touching."""

import numpy as np
import pytest

from deburr_drake.cell.process import PROCESS_STATE
from deburr_drake.cell.touches import TouchGate, plan_mesh_probe, touch_law
from deburr_drake.config import ConfigError, load_scenario
from deburr_drake.math.registration import MAX_AMPLIFICATION

PROBED = "localisation: {probe: {enabled: true}}"


@pytest.fixture(scope="module")
def cross_hole():
    return load_scenario("examples/cross_hole_6dof.yaml", text=PROBED)


def test_touches_pin_the_pose_and_the_hole_from_above(cross_hole):
    start = np.array([0.947, 0.0, 0.498])
    plan = plan_mesh_probe(cross_hole, start)
    p = cross_hole.localisation.probe
    assert plan.count == p.points
    assert plan.touches.amplification <= MAX_AMPLIFICATION
    # The hole's wall (radius 8 mm about the vertical through the rim's
    # centre) holds some of the touches: the size is told.
    assert plan.sized is not None and plan.sized[plan.touches.faces].any()
    # Allowance: the 1 mm offset along a face's normal at least, the turn
    # about the part's origin more.
    assert np.all(plan.allowance >= p.pose_offset_allowance - 1e-12)
    top = plan.surface.vertices[:, 2].max()
    assert plan.safe_height > top + plan.radius + p.standoff
    route = plan.route(p.standoff)
    assert route.shape == (2 * plan.count, 3)
    # The first touch is the nearest to the start.
    d = np.linalg.norm(plan.touches.points - start, axis=1)
    assert np.argmin(d) == 0


def test_too_few_touches_are_refused_naming_the_field(cross_hole):
    cross_hole.localisation.probe.points = 6
    try:
        with pytest.raises(ConfigError) as refused:
            plan_mesh_probe(cross_hole, np.zeros(3))
    finally:
        cross_hole.localisation.probe.points = 8
    assert str(refused.value).startswith("localisation.probe.points = 6")


def test_the_touch_law_has_the_configured_stiffness_at_the_threshold(
    cross_hole,
):
    c, n, b = touch_law(cross_hole)
    p = cross_hole.localisation.probe
    depth = p.force_threshold / p.contact_stiffness
    force = c * depth**n * np.exp(-b * depth)
    assert force == pytest.approx(p.force_threshold, rel=1e-12)


def test_the_guards_see_no_depth_while_touching():
    gate = TouchGate()
    context = gate.CreateDefaultContext()
    state = np.arange(PROCESS_STATE.size, dtype=float) + 1.0
    gate.GetInputPort("process_state").FixValue(context, state)
    gate.GetInputPort("touching").FixValue(context, [1.0])
    out = gate.GetOutputPort("process_state").Eval(context)
    assert PROCESS_STATE.get(out, "delta") == 0.0
    assert PROCESS_STATE.get(out, "g") == PROCESS_STATE.get(state, "g")
    gate.GetInputPort("touching").FixValue(context, [0.0])
    np.testing.assert_array_equal(
        gate.GetOutputPort("process_state").Eval(context), state
    )
