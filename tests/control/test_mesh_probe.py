"""Touch probing of a mesh part: the sequence's state machine against an
emulated part (the tool at the command, the ball's linear contact with a
box moved by a known pose): the touches, their compensation, the
registration, the way to the start on the registered part and the
hand-over; the gate holding n1 and the arc position while probing."""

import math

import numpy as np
import pytest
import trimesh

from deburr_drake.config import ProbeConfig
from deburr_drake.control.layout import CHAMFER_STATE
from deburr_drake.control.mesh_probe import (
    MESH_PHASES,
    MESH_PROBE_STATE,
    MeshProbePlan,
    MeshProbingSequence,
    register_part,
    registered_contours,
)
from deburr_drake.control.probe import ProbeGate, sensor_timing
from deburr_drake.math.geometry import StraightContour
from deburr_drake.math.mesh_registration import MeshSurface, closest_on_mesh
from deburr_drake.math.rigid import rotvec_matrix, rpy_matrix
from deburr_drake.math.touch_plan import plan_touches, reachable_faces

T = 0.0025  # s, the sensor's sample period
K = 5.0e3  # N/m, the emulated contact's stiffness (linear)
R = 0.003  # m, the probe's ball


def _box(R_move=np.eye(3), p_move=np.zeros(3)):
    box = trimesh.creation.box(extents=[0.06, 0.04, 0.02])
    vertices = box.vertices @ R_move.T + p_move
    return MeshSurface(vertices, box.faces)


def _plan(surface):
    reachable = reachable_faces(
        surface, probe_radius=R, clearance=0.004, rise=0.05
    )
    touches = plan_touches(surface, count=8, reachable=reachable)
    return MeshProbePlan(
        surface,
        None,
        touches,
        safe_height=0.02,
        radius=R,
        allowance=np.full(8, 0.001),
    )


def _chamfer(x_p):
    return CHAMFER_STATE.pack(
        x_p=np.asarray(x_p, float),
        xdot_p=np.zeros(3),
        n1=np.zeros(3),
        n2=np.zeros(3),
        delta=0.0,
        delta_dot=0.0,
        f_n=0.0,
        f_t=0.0,
        arc_position=0.0,
        n1_rate=np.zeros(3),
    )


def _force(real: MeshSurface, x_p):
    """The real box's push on the ball at x_p (linear, along the nearest
    face's normal)."""
    q, j = closest_on_mesh(real, np.asarray(x_p)[None, :])
    m = real.normals[j[0]]
    depth = R - float(m @ (x_p - q[0]))
    return K * max(depth, 0.0) * m


#: The edge: the believed box's top front edge, the cutter's radius in.
_EDGE = StraightContour(
    [-0.03, -0.02 + R, 0.009], [1, 0, 0], [0, -1, 0], length=0.06
)


def _probe(real: MeshSurface, find_speed: float, false_find: float = 0.0):
    """The sequence on the believed box against ``real``, each touch a
    guarded move alone (find_speed 0) or a find touch and the measuring
    touch, stepped until done: (probe, context, the ``touching`` output
    on the entry's samples, the phases in the order they came). With
    ``false_find`` (N) the reading pushes back by that much on each find
    touch's first sample, as an arm still ringing at the tare does."""
    plan = _plan(_box())
    config = ProbeConfig(
        enabled=True,
        contact_exponent=1.0,
        contact_exponent_slope=0.0,
        contact_stiffness=K,
        detection_bias=0.0,
        # The emulated probe detects at the sample after the crossing:
        # slow, so that sample's way (1.25 um) stays under the tolerances.
        approach_speed=0.0005,
        find_speed=find_speed,
    )
    x0 = _EDGE.point_at(0.0) - config.standoff * _EDGE.n1(_EDGE.point_at(0.0))
    probe = MeshProbingSequence(
        _EDGE,
        plan,
        config,
        sample_period=T,
        timing=sensor_timing(T, 1e6),
        initial_position=x0,
    )
    context = probe.CreateDefaultContext()
    probe.GetInputPort("command_in").FixValue(context, np.zeros(3))
    assert probe.GetOutputPort("touching").Eval(context)[0] == 1.0
    assert probe.GetOutputPort("registration").size() == 7
    entered_touching, phases = [], []
    for _ in range(40000):
        x_p = probe.GetOutputPort("command").Eval(context).copy()
        probe.GetInputPort("chamfer_state").FixValue(context, _chamfer(x_p))
        state = context.get_discrete_state(0).get_value()
        phase = MESH_PHASES[int(MESH_PROBE_STATE.get(state, "phase"))]
        force = _force(real, x_p)
        if false_find and phase == "find" and phases[-1] != "find":
            i = int(MESH_PROBE_STATE.get(state, "index"))
            force = force + false_find * plan.touches.normals[i]
        probe.GetInputPort("measured_force").FixValue(context, force)
        if not phases or phases[-1] != phase:
            phases.append(phase)
        if phase == "enter":
            entered_touching.append(
                probe.GetOutputPort("touching").Eval(context)[0]
            )
        if phase == "done":
            break
        context.SetDiscreteState(
            probe.EvalUniquePeriodicDiscreteUpdate(context)
        )
        context.SetTime(context.get_time() + T)
    assert phase == "done"
    return probe, context, entered_touching, phases


def _off_real(probe, context, real: MeshSurface) -> float:
    """m: the compensated touches' largest distance from the real box."""
    touches = probe.GetOutputPort("touch_points").Eval(context)
    points = touches.reshape(-1, 4)[:, :3]
    q, _ = closest_on_mesh(real, points)
    return float(np.max(np.linalg.norm(points - q, axis=1)))


@pytest.mark.parametrize("find_speed", [0.0, ProbeConfig.find_speed])
def test_a_moved_box_is_registered_and_entered_on(find_speed):
    # The real box: 0.6 mm, -0.4 mm, 0.3 mm off and turned 0.5 deg about
    # every axis.
    R_move = rpy_matrix(np.radians([0.5, 0.5, 0.5]))
    p_move = np.array([0.0006, -0.0004, 0.0003])
    real = _box(R_move, p_move)
    probe, context, entered_touching, phases = _probe(real, find_speed)
    assert entered_touching and not any(entered_touching)
    # The entry starts from rest: after the last descent, the settle.
    assert phases[-4:] == ["down", "settle", "enter", "done"]
    if find_speed > 0:
        assert phases[3:8] == [
            "settle",
            "find",
            "back_off",
            "steady",
            "approach",
        ]
    state = context.get_discrete_state(0).get_value()
    assert MESH_PROBE_STATE.get(state, "touches") == 8
    assert MESH_PROBE_STATE.get(state, "kept") == 8
    reg = MESH_PROBE_STATE.get(state, "registration")
    # The registration: the real box's pose, within what the sampled
    # detection leaves (a few microns along the normals).
    np.testing.assert_allclose(rotvec_matrix(reg[:3]), R_move, atol=2e-4)
    np.testing.assert_allclose(reg[3:6], p_move, atol=1e-5)
    assert _off_real(probe, context, real) < 1e-5
    # The tool ends at the start of the edge on the registered part.
    registered = probe.GetOutputPort("command")
    probe.GetInputPort("command_in").FixValue(context, [1.0, 2.0, 3.0])
    np.testing.assert_allclose(registered.Eval(context), [1.0, 2.0, 3.0])
    start = _EDGE.point_at(0.0)
    moved = R_move @ start + p_move
    end = MESH_PROBE_STATE.get(state, "segment_end")
    assert np.linalg.norm(end - moved) < 3e-5
    assert math.isfinite(MESH_PROBE_STATE.get(state, "done_time"))


def test_a_find_touch_set_off_early_still_touches_the_face():
    # Every find touch set off at its first sample, 1 mm and more short of
    # the real box (moved 1 mm away from the planned touches' faces): the
    # measuring touch searches on to the find's end and touches the face.
    p_move = np.array([0.001, 0.001, -0.001])
    real = _box(np.eye(3), p_move)
    probe, context, _, phases = _probe(
        real, ProbeConfig.find_speed, false_find=1.5
    )
    state = context.get_discrete_state(0).get_value()
    assert MESH_PROBE_STATE.get(state, "touches") == 8
    np.testing.assert_allclose(
        MESH_PROBE_STATE.get(state, "registration")[3:6], p_move, atol=1e-5
    )
    assert _off_real(probe, context, real) < 1e-5


def test_a_face_turned_off_its_planned_normal_is_touched_where_it_is():
    # The real box turned 4 deg about z: its side faces' normals lie 4 deg
    # off the planned ones, as a hole's wall's facets do where the ball
    # meets them off the planned point. The ball's radius taken off along
    # the planned normal would put those touches r (1 - cos 4 deg) = 7 um
    # off the face; taken off along the force the ball felt, on it.
    real = _box(rpy_matrix(np.radians([0.0, 0.0, 4.0])))
    probe, context, _, _ = _probe(real, ProbeConfig.find_speed)
    assert _off_real(probe, context, real) < 2.5e-6


def test_a_find_touch_that_finds_nothing_ends_the_run(run_untouched):
    """No part at all: the first touch's find touch ends at its search
    (search_distance and twice the allowance) and the simulation stops,
    naming the touch, as a single guarded move's miss does."""
    from deburr_drake.runs.simulation import _stop_of

    plan = _plan(_box())
    contour = StraightContour(
        [-0.03, -0.02 + R, 0.009], [1, 0, 0], [0, -1, 0], length=0.06
    )
    config = ProbeConfig(enabled=True)
    x0 = plan.standoff_point(0, config.standoff)
    probe = MeshProbingSequence(
        contour,
        plan,
        config,
        sample_period=T,
        timing=sensor_timing(T, 10.0),
        initial_position=x0,
    )
    status, context = run_untouched(probe, _chamfer(x0))
    assert status.reason() == status.ReturnReason.kReachedTerminationCondition
    state = context.get_discrete_state(0).get_value()
    assert MESH_PHASES[int(MESH_PROBE_STATE.get(state, "phase"))] == "find"
    search = config.search_distance + 2.0 * plan.allowance[0]
    searched = MESH_PROBE_STATE.get(
        state, "segment_end"
    ) - MESH_PROBE_STATE.get(state, "segment_start")
    assert np.linalg.norm(searched) == pytest.approx(search, rel=1e-12)
    reason, detail = _stop_of(status, None)
    assert reason == "probe_missed:0"
    assert detail.startswith(f"no contact within {search:.3g} m")
    assert "the find touch of touch 0 of 8" in detail


def test_the_gate_holds_n1_and_the_arc_while_probing():
    gate = ProbeGate(held=(np.array([0.0, 1.0, 0.0]), 0.0))
    context = gate.CreateDefaultContext()
    chamfer = _chamfer([0.4, 0, 0])
    chamfer[CHAMFER_STATE.slice("n1")] = [1.0, 0.0, 0.0]
    chamfer[CHAMFER_STATE.slice("arc_position")] = 0.02
    gate.GetInputPort("chamfer_state").FixValue(context, chamfer)
    gate.GetInputPort("desired_normal_force").FixValue(context, [7.0])
    gate.GetInputPort("probing").FixValue(context, [1.0])
    out = gate.GetOutputPort("chamfer_state").Eval(context)
    np.testing.assert_array_equal(CHAMFER_STATE.get(out, "n1"), [0, 1, 0])
    assert CHAMFER_STATE.get(out, "arc_position") == 0.0
    gate.GetInputPort("probing").FixValue(context, [0.0])
    np.testing.assert_array_equal(
        gate.GetOutputPort("chamfer_state").Eval(context), chamfer
    )


def test_every_edge_of_a_job_moves_with_the_part_registered_once():
    R_move = rpy_matrix(np.radians([0.3, -0.4, 0.5]))
    p_move = np.array([0.0005, 0.0002, -0.0003])
    plan = _plan(_box())
    # Touches exactly on the real box at the planned faces.
    on_real = plan.touches.points @ R_move.T + p_move
    registration, fit = register_part(
        plan, on_real, ProbeConfig(enabled=True, fit_radius=False)
    )
    assert fit.kept.all()
    edges = [
        StraightContour([-0.03, -0.02, 0.01], [1, 0, 0], [0, 1, 0], 0.06),
        StraightContour([0.03, -0.02, 0.01], [0, 1, 0], [-1, 0, 0], 0.04),
    ]
    for edge, moved in zip(edges, registered_contours(edges, registration)):
        for s in (0.0, 0.01, 0.03):
            np.testing.assert_allclose(
                moved.point_at(s),
                R_move @ edge.point_at(s) + p_move,
                atol=1e-9,
            )
