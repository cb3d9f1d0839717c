"""The job's sequencer: its phases from a cut's entry to its end, the move
along the planned joint path, the next cut, done; its outputs per phase;
the planned path's reference; the actuation switch."""

import numpy as np
import pytest

from deburr_drake.control.layout import CHAMFER_STATE, COMMAND_STATE
from deburr_drake.control.sequencer import (
    JOB_PHASES,
    JOB_STATE,
    ActuationSwitch,
    CutPlan,
    JobProbe,
    JobSequencer,
    MovePlan,
)

T = 0.025
DEPTH = 5e-4


def _move():
    times = np.array([0.0, 0.5, 1.5, 2.0])
    path = np.array([[0.0, 0.0], [0.0, 0.1], [1.0, 0.1], [1.0, 0.0]])
    return MovePlan(times, path, retract_end=0.5, approach_start=1.5)


def _chamfer(delta):
    """A chamfer state at depth ``delta``, every other block zero."""
    chamfer = np.zeros(CHAMFER_STATE.size)
    chamfer[CHAMFER_STATE.slice("delta")] = delta
    return chamfer


class _Run:
    """Steps the sequencer's discrete updates with fixed inputs."""

    def __init__(self, sequencer):
        self.sequencer = sequencer
        self.context = sequencer.CreateDefaultContext()
        self.set(arc=0.0, delta=DEPTH)

    def set(self, *, arc, delta):
        command = COMMAND_STATE.pack(
            x_c=np.zeros(3), feed=0.0, arc_position=arc
        )
        self.sequencer.GetInputPort("command_state").FixValue(
            self.context, command
        )
        self.sequencer.GetInputPort("chamfer_state").FixValue(
            self.context, _chamfer(delta)
        )

    def step(self):
        self.context.SetDiscreteState(
            self.sequencer.EvalUniquePeriodicDiscreteUpdate(self.context)
        )
        self.context.SetTime(self.context.get_time() + T)

    def out(self, name):
        return self.sequencer.GetOutputPort(name).Eval(self.context)

    def phase(self):
        return self.sequencer.phase(self.context), self.sequencer.cut(
            self.context
        )


def _sequencer(dwell=1.0):
    return JobSequencer(
        [CutPlan(end_arc=0.1, move=_move()), CutPlan(end_arc=10.05, move=None)],
        period=T,
        desired_depth=DEPTH,
        entry_dwell=dwell,
        num_positions=2,
    )


def _probing_sequencer(moves):
    """A two-cut job that probes first; ``moves`` records the calls of
    its path mover (a shift of the path by the registration's first
    number)."""

    def move(path, registration):
        moves.append(np.asarray(registration).copy())
        return path + registration[0]

    return JobSequencer(
        [CutPlan(end_arc=0.1, move=_move()), CutPlan(end_arc=10.05, move=None)],
        period=T,
        desired_depth=DEPTH,
        entry_dwell=1.0,
        num_positions=2,
        probe=JobProbe(registration=7, move=move),
    )


def test_a_probing_job_probes_then_cuts_on_the_moved_paths():
    moves = []
    sequencer = _probing_sequencer(moves)
    inputs = [
        sequencer.get_input_port(i).get_name()
        for i in range(sequencer.num_input_ports())
    ]
    assert inputs == [
        "command_state",
        "chamfer_state",
        "probing",
        "registration",
    ]
    run = _Run(sequencer)
    registration = np.array([0.25, 0, 0, 0, 0, 0, 0])
    sequencer.GetInputPort("registration").FixValue(run.context, registration)
    sequencer.GetInputPort("probing").FixValue(run.context, [1.0])
    # Probing: the force loop drives the arm, nothing is cut, the feed is
    # held, no spindle turns; the planned path until the registration.
    assert run.phase() == ("probe", 0)
    assert run.out("force_loop")[0] == 1 and run.out("cutting")[0] == 0
    assert run.out("off_part")[0] == 1 and run.out("hold")[0] == 1
    assert run.out("fuzzy_weight")[0] == 0
    np.testing.assert_array_equal(run.out("spindles"), [0, 0])
    np.testing.assert_array_equal(run.out("joint_reference"), np.zeros(4))
    for _ in range(3):
        run.step()
    assert run.phase() == ("probe", 0) and moves == []
    # Done probing: every move's path moved once, the first cut begins,
    # held until its entry is established (as the later cuts are).
    sequencer.GetInputPort("probing").FixValue(run.context, [0.0])
    run.set(arc=0.0, delta=0.0)
    run.step()
    assert run.phase() == ("cut", 0) and len(moves) == 1
    np.testing.assert_array_equal(moves[0], registration)
    assert run.out("hold")[0] == 1 and run.out("cutting")[0] == 1
    np.testing.assert_array_equal(run.out("spindles"), [1, 0])
    run.set(arc=0.0, delta=DEPTH)
    run.step()
    assert run.out("hold")[0] == 0
    # The move follows the moved path.
    run.set(arc=0.1, delta=DEPTH)
    run.step()
    assert run.phase() == ("retract", 0)
    run.step()
    reference = run.out("joint_reference")
    start = JOB_STATE.get(
        run.context.get_discrete_state(0).value(), "move_start"
    )
    into = run.context.get_time() - float(start)
    assert into > 0
    expected = _move().reference(into, _move().path + 0.25)
    np.testing.assert_allclose(reference, expected)
    assert reference[0] == pytest.approx(0.25)
    assert len(moves) == 1


def test_ports_and_state():
    sequencer = _sequencer()
    assert sequencer.get_name() == "job_sequencer"
    sizes = {
        sequencer.get_output_port(i).get_name(): sequencer.get_output_port(
            i
        ).size()
        for i in range(sequencer.num_output_ports())
    }
    assert sizes == {
        "job_state": JOB_STATE.size,
        "cutting": 1,
        "force_loop": 1,
        "off_part": 1,
        "hold": 1,
        "fuzzy_weight": 1,
        "joint_reference": 4,
        "spindles": 2,
    }


def test_the_phases_of_a_two_cut_job():
    run = _Run(_sequencer())
    # The first cut starts in contact: established, feeding, adapting.
    assert run.phase() == ("cut", 0)
    assert run.out("cutting")[0] == 1 and run.out("hold")[0] == 0
    assert run.out("fuzzy_weight")[0] == 1
    np.testing.assert_array_equal(run.out("spindles"), [1, 0])
    run.step()
    assert run.phase() == ("cut", 0)
    # Its command reaches the end: the retract begins.
    run.set(arc=0.1, delta=DEPTH)
    run.step()
    assert run.phase() == ("retract", 0)
    assert run.out("cutting")[0] == 0 and run.out("off_part")[0] == 1
    assert run.out("hold")[0] == 1 and run.out("fuzzy_weight")[0] == 0
    np.testing.assert_array_equal(run.out("spindles"), [1, 0])
    seen = [run.phase()]
    while run.phase()[0] != "cut":
        run.step()
        if run.phase() != seen[-1]:
            seen.append(run.phase())
        assert run.context.get_time() < 3.0
    assert seen == [("retract", 0), ("move", 0), ("approach", 0), ("cut", 1)]
    # The move took its planned time.
    start = float(
        JOB_STATE.get(run.context.get_discrete_state(0).value(), "phase_start")
    )
    assert start == pytest.approx(0.05 + 2.0, abs=T)
    # The next cut's entry: held until the depth is reached.
    run.set(arc=10.0, delta=0.0)
    run.step()
    assert run.out("cutting")[0] == 1 and run.out("hold")[0] == 1
    assert run.out("fuzzy_weight")[0] == 0
    np.testing.assert_array_equal(run.out("spindles"), [0, 1])
    run.set(arc=10.0, delta=0.95 * DEPTH)
    run.step()
    assert run.out("hold")[0] == 0 and run.out("fuzzy_weight")[0] == 1
    # The last cut's end: done.
    run.set(arc=10.05, delta=DEPTH)
    run.step()
    assert run.phase() == ("done", 1)
    assert run.out("cutting")[0] == 0


def test_the_entry_waits_no_longer_than_the_dwell():
    run = _Run(_sequencer(dwell=0.1))
    run.set(arc=0.1, delta=0.0)
    while run.phase()[0] != "cut" or run.phase()[1] != 1:
        run.step()
    for _ in range(3):
        run.step()
        assert run.out("hold")[0] == 1
    for _ in range(3):
        run.step()
    assert run.out("hold")[0] == 0


def test_the_reference_follows_the_planned_path():
    run = _Run(_sequencer())
    # In a cut: the next move's start, at rest.
    np.testing.assert_allclose(run.out("joint_reference"), [0, 0, 0, 0])
    run.set(arc=0.1, delta=DEPTH)
    run.step()  # the retract begins at t = 0
    for _ in range(40):  # 1.025 s into the move (t = 41 T)
        run.step()
    assert JOB_PHASES.index(run.phase()[0]) == JOB_PHASES.index("move")
    np.testing.assert_allclose(
        run.out("joint_reference"), [0.525, 0.1, 1.0, 0.0], atol=1e-9
    )


def test_move_plan_reference():
    move = _move()
    np.testing.assert_allclose(move.reference(0.25), [0, 0.05, 0, 0.2])
    np.testing.assert_allclose(move.reference(-1.0), [0, 0, 0, 0])
    np.testing.assert_allclose(move.reference(5.0), [1, 0, 0, 0])
    assert move.duration == 2.0


def test_a_job_needs_its_moves():
    with pytest.raises(ValueError, match="cut 0: no move"):
        JobSequencer(
            [CutPlan(0.1, None), CutPlan(10.1, None)],
            period=T,
            desired_depth=DEPTH,
            entry_dwell=1.0,
            num_positions=2,
        )


def test_the_switch_passes_the_loop_in_use():
    switch = ActuationSwitch(2)
    context = switch.CreateDefaultContext()
    switch.GetInputPort("force_loop").FixValue(context, [1.0, 2.0])
    switch.GetInputPort("position_loop").FixValue(context, [3.0, 4.0])
    for cutting, expected in ((1.0, [1, 2]), (0.0, [3, 4])):
        switch.GetInputPort("cutting").FixValue(context, [cutting])
        np.testing.assert_array_equal(
            switch.GetOutputPort("actuation").Eval(context), expected
        )
