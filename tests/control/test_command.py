"""CommandGenerator (feedrate law, R5, R6) and FirstOrderHold (eq. 5, R2)."""

import numpy as np
from pydrake.systems.analysis import (
    ApplySimulatorConfig,
    Simulator,
    SimulatorConfig,
)
from pydrake.systems.framework import DiagramBuilder, LeafSystem
import pytest

from deburr_drake.config import CommandConfig, ConfigError, TaskConfig
from deburr_drake.control.command import (
    CommandGenerator,
    FirstOrderHold,
    edge_steady_feed,
    feedrate_law,
)
from deburr_drake.control.layout import COMMAND_STATE
from deburr_drake.control.observer import chamfer_quantities
from deburr_drake.math.geometry import CircularContour
from deburr_drake.math.registration import moved_contour

CONTOUR = CircularContour([0.0, 0.0, 0.048], 0.027)


def _chamfer(x_p, xdot_p, f_t):
    """Chamfer state whose measured force has ||f_t|| = f_t."""
    n2 = CONTOUR.n2(x_p, xdot_p, 1e-5)
    return chamfer_quantities(
        CONTOUR, x_p, xdot_p, -f_t * n2, min_tangential_speed=1e-5
    )


def _step(system, chamfer):
    context = system.CreateDefaultContext()
    system.GetInputPort("chamfer_state").FixValue(context, chamfer)
    xd = system.EvalUniquePeriodicDiscreteUpdate(context).get_vector(0)
    return COMMAND_STATE.split(xd.CopyToVector())


def test_feedrate_law_of_the_configuration():
    config, task = CommandConfig(), TaskConfig(desired_chamfering_force=10.0)
    law = feedrate_law(config, task)
    assert (
        law.desired_force,
        law.threshold_force,
        law.force_offset,
        law.default_feed,
        law.max_feed,
    ) == (
        10.0,
        config.threshold_power_force,
        config.force_offset,
        config.default_feed,
        config.max_feed,
    )
    # auto: the paper's law on a planar edge, integrating where it turns.
    assert not law.integrating
    assert feedrate_law(config, task, varying_frame=True).integrating
    for kind, planar, turning in (
        ("paper", False, False),
        ("integrating", True, True),
    ):
        c = CommandConfig(feed_law=kind)
        assert feedrate_law(c, task).integrating == planar
        assert feedrate_law(c, task, varying_frame=True).integrating == turning


def test_edge_steady_feed_by_hand():
    from deburr_drake.config import load_scenario

    sc = load_scenario("paper", text="process: {threshold_power_force: 3.0}")
    # g = 3e9 N s/m^3 x 0.5 mm x 2 mm = 3000 N s/m on a line; the cut
    # carries the process's 3 N: v = (10 - 3) N / g.
    assert sc.process.cutting_coefficient == 3.0e9
    assert edge_steady_feed(sc) == pytest.approx(7.0 / 3000.0)
    # A 1 mm x 2 mm burr: g = 9000 N s/m. A path radius of 5 mm round a
    # pocket (3 mm cutter): removal scale (1 + 3.25 / 5) / (1 + 0.5 / 5).
    assert edge_steady_feed(sc, burr_area=2e-6) == pytest.approx(7.0 / 9000.0)
    assert edge_steady_feed(sc, curvature=200.0) == pytest.approx(7.0 / 4500.0)


def test_command_generator_clamps_the_feed():
    # A chamfer that vanishes under a tool at 15 mm/s: ||f_t|| - P' = 0.6,
    # the law asks 15 * 8 / 0.6 = 200 mm/s; the command takes max_feed.
    config, task = CommandConfig(), TaskConfig()
    x0 = CONTOUR.point_at(0.01)
    generator = CommandGenerator(config, task, CONTOUR, x0)
    x_p = x0 + 0.00001 * CONTOUR.n1(x0)
    out = _step(generator, _chamfer(x_p, 0.015 * CONTOUR.tangent(x0), 2.6))
    assert out["feed"] == pytest.approx(config.max_feed, rel=1e-12)


@pytest.mark.parametrize(
    "f_t, speed, expected",
    [
        (12.0, 0.003, 0.003 * 8.0 / 10.0),  # force too high: slow down
        (6.0, 0.002, 0.002 * 8.0 / 4.0),  # force too low: speed up
        (1.0, 0.002, 0.001),  # below P' + v_eps: v0
    ],
)
def test_command_advances_on_contour(f_t, speed, expected):
    config, task = CommandConfig(), TaskConfig()
    x0 = CONTOUR.point_at(0.01)
    generator = CommandGenerator(config, task, CONTOUR, x0)
    # The tool sits 0.5 mm inside the material, moving along the contour.
    x_p = x0 + 0.0005 * CONTOUR.n1(x0)
    xdot_p = speed * CONTOUR.tangent(x0)
    out = _step(generator, _chamfer(x_p, xdot_p, f_t))
    assert out["feed"] == pytest.approx(expected, rel=1e-9)
    # R6: the command is on the zero-depth contour, v T of arc ahead of the
    # projection of x_p; the depth is not carried into the command.
    assert CONTOUR.depth(out["x_c"]) == pytest.approx(0.0, abs=1e-12)
    assert CONTOUR.arc_position(out["x_c"]) == pytest.approx(
        0.01 + expected * config.period, abs=1e-12
    )
    assert out["arc_position"] == pytest.approx(
        0.01 + expected * config.period, abs=1e-12
    )


def _step_from(generator, previous, chamfer):
    context = generator.CreateDefaultContext()
    context.SetDiscreteState(previous)
    generator.GetInputPort("chamfer_state").FixValue(context, chamfer)
    xd = generator.EvalUniquePeriodicDiscreteUpdate(context).get_vector(0)
    return COMMAND_STATE.split(xd.CopyToVector())


def test_integrating_feed_law():
    """feed_law integrating: cutting, v scales the last commanded feed
    (not the tool's speed) and x_c starts from x_p (R6); below the
    cutting threshold the default feed advances x_c from the last
    command, so a tool that does not follow meets a growing error."""
    config = CommandConfig(feed_law="integrating")
    task = TaskConfig()
    x0 = CONTOUR.point_at(0.01)
    generator = CommandGenerator(config, task, CONTOUR, x0)
    x_p = x0 + 0.0005 * CONTOUR.n1(x0)
    # The tool lags: 1 mm/s against a 2 mm/s command, f_t 6 N.
    previous = COMMAND_STATE.pack(
        x_c=CONTOUR.point_at(0.0101), feed=0.002, arc_position=0.0101
    )
    out = _step_from(
        generator, previous, _chamfer(x_p, 0.001 * CONTOUR.tangent(x0), 6.0)
    )
    v = 0.002 * 8.0 / 4.0
    assert out["feed"] == pytest.approx(v, rel=1e-9)
    assert CONTOUR.arc_position(out["x_c"]) == pytest.approx(
        0.01 + v * config.period, abs=1e-12
    )
    # Not cutting (f_t 1 N), the tool standing: the command moves on
    # from where it was, v0 T further.
    out = _step_from(generator, previous, _chamfer(x_p, np.zeros(3), 1.0))
    assert out["feed"] == pytest.approx(config.default_feed, rel=1e-12)
    s = 0.0101 + config.default_feed * config.period
    assert CONTOUR.arc_position(out["x_c"]) == pytest.approx(s, abs=1e-12)
    assert out["arc_position"] == pytest.approx(s, abs=1e-12)
    with pytest.raises(ConfigError, match="command.feed_law"):
        CommandConfig(feed_law="fast").validate()


def test_auto_feed_law_planar_paper_3d_integrating():
    """feed_law auto (the default): a planar contour keeps the paper's
    law (v scales the tool's speed), a contour whose tool frame turns
    gets the integrating one (v scales the last commanded feed)."""
    import copy

    turning = copy.copy(CONTOUR)
    turning.varying_frame = True
    x0 = CONTOUR.point_at(0.01)
    x_p = x0 + 0.0005 * CONTOUR.n1(x0)
    previous = COMMAND_STATE.pack(
        x_c=CONTOUR.point_at(0.0101), feed=0.002, arc_position=0.0101
    )
    chamfer = _chamfer(x_p, 0.001 * CONTOUR.tangent(x0), 6.0)
    feeds = []
    for contour in (CONTOUR, turning):
        generator = CommandGenerator(CommandConfig(), TaskConfig(), contour, x0)
        feeds.append(_step_from(generator, previous, chamfer)["feed"])
    assert CommandConfig().feed_law == "auto"
    assert feeds[0] == pytest.approx(0.001 * 8.0 / 4.0, rel=1e-9)
    assert feeds[1] == pytest.approx(0.002 * 8.0 / 4.0, rel=1e-9)


def test_command_counts_arc_past_one_revolution():
    config, task = CommandConfig(), TaskConfig()
    L = CONTOUR.length
    generator = CommandGenerator(config, task, CONTOUR, CONTOUR.point_at(0))
    context = generator.CreateDefaultContext()
    context.SetDiscreteState(
        COMMAND_STATE.pack(
            x_c=CONTOUR.point_at(L - 1e-5), feed=0.001, arc_position=L - 1e-5
        )
    )
    x_p = CONTOUR.point_at(L - 1e-5)
    generator.GetInputPort("chamfer_state").FixValue(
        context, _chamfer(x_p, np.zeros(3), 0.0)
    )
    xd = generator.EvalUniquePeriodicDiscreteUpdate(context).get_vector(0)
    s = COMMAND_STATE.get(xd.CopyToVector(), "arc_position")
    assert s == pytest.approx(L - 1e-5 + 0.001 * config.period, abs=1e-12)
    assert s > L


def test_probe_hold_keeps_the_command_at_the_registered_start():
    """The probe's hold (registered, hold 1: probing, then the entry's
    dwell): x_c stays at the pass's start on the registered contour
    while the entry's cut pushes the tool back along the edge; released,
    the feed law takes over from the tool."""
    config, task = CommandConfig(), TaskConfig()
    generator = CommandGenerator(
        config, task, CONTOUR, CONTOUR.point_at(0.0), registered=True
    )
    s0 = generator.start_arc_position
    registration = np.array([0.0004, -0.0002, 0.01, 0.0003])
    moved = moved_contour(CONTOUR, registration)
    # The tool 5 mm behind the start, 0.4 mm deep, moving back.
    p = moved.point_at(s0 - 0.005)
    x_p = p + 0.0004 * moved.n1(p)
    back = -0.005 * moved.tangent(p)
    chamfer = chamfer_quantities(
        moved, x_p, back, 30.0 * moved.tangent(p), min_tangential_speed=1e-5
    )
    context = generator.CreateDefaultContext()
    generator.GetInputPort("chamfer_state").FixValue(context, chamfer)
    generator.GetInputPort("registration").FixValue(context, registration)
    outputs = []
    for hold in (1.0, 0.0):
        generator.GetInputPort("hold").FixValue(context, [hold])
        xd = generator.EvalUniquePeriodicDiscreteUpdate(context).get_vector(0)
        outputs.append(COMMAND_STATE.split(xd.CopyToVector()))
    held, released = outputs
    np.testing.assert_allclose(held["x_c"], moved.point_at(s0), atol=1e-12)
    assert held["arc_position"] == pytest.approx(s0, abs=1e-12)
    assert np.linalg.norm(held["x_c"] - moved.project(x_p)) > 0.0049
    s_p = moved.unwrapped_arc_position(x_p, s0)
    assert released["arc_position"] == pytest.approx(
        s_p + released["feed"] * config.period, abs=1e-12
    )


def test_command_rejects_unreachable_force():
    with pytest.raises(ConfigError, match="desired_chamfering_force"):
        CommandGenerator(
            CommandConfig(threshold_power_force=12.0),
            TaskConfig(),
            CONTOUR,
            CONTOUR.point_at(0),
        )


class _Samples(LeafSystem):
    """Emits samples[k] from t = kT on, updated at kT like the command
    generator (so the hold sees both updates at the same instants)."""

    def __init__(self, samples, period):
        super().__init__()
        self._samples = list(samples)
        self._k = self.DeclareDiscreteState(2)  # [value, k]
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)
        self.DeclareVectorOutputPort(
            "value",
            1,
            lambda c, o: o.SetAtIndex(
                0, c.get_discrete_state(self._k).get_value()[0]
            ),
            prerequisites_of_calc={self.xd_ticket()},
        )

    def _update(self, context, state):
        k = int(context.get_discrete_state(self._k).get_value()[1])
        value = self._samples[min(k, len(self._samples) - 1)]
        state.set_value(self._k, [value, k + 1])


def _run_hold(variant, samples, period=0.025, integrator="runge_kutta3"):
    """x*(kT) and x*(kT + T/2) of a FirstOrderHold fed x_c(kT) = samples[k]
    in a simulated diagram."""
    builder = DiagramBuilder()
    source = builder.AddSystem(_Samples(samples, period))
    hold = builder.AddSystem(
        FirstOrderHold(period, [samples[0]], variant=variant)
    )
    builder.Connect(source.get_output_port(), hold.GetInputPort("sampled"))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    ApplySimulatorConfig(
        SimulatorConfig(integration_scheme=integrator), simulator
    )
    context = hold.GetMyContextFromRoot(simulator.get_context())
    at_knots, midpoints = [], []
    for k in range(len(samples)):
        simulator.AdvanceTo(k * period)
        at_knots.append(hold.GetOutputPort("position").Eval(context)[0])
        simulator.AdvanceTo((k + 0.5) * period)
        midpoints.append(hold.GetOutputPort("position").Eval(context)[0])
        velocity = hold.GetOutputPort("velocity").Eval(context)[0]
        assert velocity == pytest.approx(
            (midpoints[-1] - at_knots[-1]) / (period / 2), abs=1e-9
        )
    return np.array(at_knots), np.array(midpoints)


def test_first_order_hold_r2_settles_one_period_behind():
    # x_c(kT) steps from 0 to 1 at k = 1; the update at t = 0 emits
    # samples[0].
    samples = [0.0, 1.0] + [1.0] * 7
    knots, mids = _run_hold("delayed_ramp", samples)
    # x*((k+1)T) = x_c(kT): the step is reached one period later and held.
    np.testing.assert_allclose(knots, [0, 0, 1, 1, 1, 1, 1, 1, 1], atol=1e-9)
    np.testing.assert_allclose(mids[1], 0.5, atol=1e-9)
    np.testing.assert_allclose(mids[2:], 1.0, atol=1e-9)


def test_first_order_hold_paper_eq5_does_not_settle():
    samples = [0.0] + [1.0] * 8
    knots, _ = _run_hold("paper_eq5", samples)
    # (5) as printed: 0, 1, 2, 2, 1, 0, ... for a unit step (R2).
    np.testing.assert_allclose(knots[1:8], [0, 1, 2, 2, 1, 0, 0], atol=1e-9)


def test_first_order_hold_tracks_a_ramp_exactly():
    v, T = 0.0024, 0.025
    samples = [v * T * k for k in range(10)]
    knots, mids = _run_hold("delayed_ramp", samples)
    np.testing.assert_allclose(knots[1:], np.array(samples[:-1]), atol=1e-12)
    np.testing.assert_allclose(mids[1:] - knots[1:], v * T / 2, rtol=1e-6)


def test_first_order_hold_validation():
    with pytest.raises(ConfigError, match="period"):
        FirstOrderHold(0.0, [0.0])
    with pytest.raises(ConfigError, match="variant"):
        FirstOrderHold(0.025, [0.0], variant="zoh")
