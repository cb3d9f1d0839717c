"""CommandGenerator (feedrate law, R5, R6) and FirstOrderHold (eq. 5, R2)."""

import numpy as np
import pytest

from deburr_drake.command import CommandGenerator, FirstOrderHold, feedrate
from deburr_drake.config import CommandConfig, ConfigError, TaskConfig
from deburr_drake.geometry import CircularContour
from deburr_drake.layout import CHAMFER_STATE, COMMAND_STATE
from deburr_drake.observer import chamfer_quantities

CONTOUR = CircularContour([0.0, 0.0, 0.048], 0.027)


def _chamfer(x_p, xdot_p, f_t):
    """Chamfer state whose measured force has ||f_t|| = f_t."""
    n2 = CONTOUR.n2(x_p, xdot_p, 1e-5)
    return chamfer_quantities(CONTOUR, x_p, xdot_p, -f_t * n2,
                              min_tangential_speed=1e-5)


def _step(system, chamfer):
    context = system.CreateDefaultContext()
    system.GetInputPort("chamfer_state").FixValue(context, chamfer)
    xd = system.EvalUniquePeriodicDiscreteUpdate(context).get_vector(0)
    return COMMAND_STATE.split(xd.CopyToVector())


def test_feedrate_law_branches():
    kw = dict(desired_force=10.0, threshold_force=2.0, force_offset=0.5,
              default_feed=0.001)
    # ||f_t|| - P' = 4 > v_eps: v = |v_t| * 8 / 4.
    assert feedrate(0.002, 6.0, **kw) == pytest.approx(0.004)
    assert feedrate(-0.002, 6.0, **kw) == pytest.approx(0.004)
    # ||f_t|| - P' = 0.4 <= v_eps: the default feed v0.
    assert feedrate(0.002, 2.4, **kw) == pytest.approx(0.001)
    assert feedrate(0.0, 0.0, **kw) == pytest.approx(0.001)


@pytest.mark.parametrize("f_t, speed, expected", [
    (12.0, 0.003, 0.003 * 8.0 / 10.0),   # force too high: slow down
    (6.0, 0.002, 0.002 * 8.0 / 4.0),     # force too low: speed up
    (1.0, 0.002, 0.001),                 # below P' + v_eps: v0
])
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
        0.01 + expected * config.period, abs=1e-12)
    assert out["arc_position"] == pytest.approx(
        0.01 + expected * config.period, abs=1e-12)


def test_command_counts_arc_past_one_revolution():
    config, task = CommandConfig(), TaskConfig()
    L = CONTOUR.length
    generator = CommandGenerator(config, task, CONTOUR, CONTOUR.point_at(0))
    context = generator.CreateDefaultContext()
    context.SetDiscreteState(COMMAND_STATE.pack(
        x_c=CONTOUR.point_at(L - 1e-5), feed=0.001, arc_position=L - 1e-5))
    x_p = CONTOUR.point_at(L - 1e-5)
    generator.GetInputPort("chamfer_state").FixValue(
        context, _chamfer(x_p, np.zeros(3), 0.0))
    xd = generator.EvalUniquePeriodicDiscreteUpdate(context).get_vector(0)
    s = COMMAND_STATE.get(xd.CopyToVector(), "arc_position")
    assert s == pytest.approx(L - 1e-5 + 0.001 * config.period, abs=1e-12)
    assert s > L


def test_command_rejects_unreachable_force():
    with pytest.raises(ConfigError, match="desired_chamfering_force"):
        CommandGenerator(CommandConfig(threshold_power_force=12.0),
                         TaskConfig(), CONTOUR, CONTOUR.point_at(0))


def _run_hold(variant, samples, period=0.025):
    """Feed a FirstOrderHold the sequence x_c(kT) and return x*(kT) and
    x*(kT + T/2), emulating the simultaneous discrete updates."""
    hold = FirstOrderHold(period, [samples[0]], variant=variant)
    context = hold.CreateDefaultContext()
    at_knots, midpoints = [], []
    port = hold.GetInputPort("sampled")
    previous = samples[0]
    for k, value in enumerate(samples):
        t = k * period
        context.SetTime(t)
        port.FixValue(context, [previous])  # the input before kT's update
        xd = hold.EvalUniquePeriodicDiscreteUpdate(context)
        context.SetDiscreteState(xd.get_vector(0).CopyToVector())
        port.FixValue(context, [value])     # x_c(kT) after the update
        at_knots.append(hold.GetOutputPort("position").Eval(context)[0])
        context.SetTime(t + period / 2)
        midpoints.append(hold.GetOutputPort("position").Eval(context)[0])
        velocity = hold.GetOutputPort("velocity").Eval(context)[0]
        assert velocity == pytest.approx(
            (midpoints[-1] - at_knots[-1]) / (period / 2))
        previous = value
    return np.array(at_knots), np.array(midpoints)


def test_first_order_hold_r2_settles_one_period_behind():
    samples = [0.0] + [1.0] * 8
    knots, mids = _run_hold("delayed_ramp", samples)
    # x*((k+1)T) = x_c(kT): a unit step is reached one period later and held.
    np.testing.assert_allclose(knots, [0, 0, 1, 1, 1, 1, 1, 1, 1], atol=1e-12)
    np.testing.assert_allclose(mids[1], 0.5, atol=1e-12)
    np.testing.assert_allclose(mids[2:], 1.0, atol=1e-12)


def test_first_order_hold_paper_eq5_does_not_settle():
    samples = [0.0] + [1.0] * 8
    knots, _ = _run_hold("paper_eq5", samples)
    # (5) as printed: 0, 1, 2, 2, 1, 0, ... for a unit step (R2).
    np.testing.assert_allclose(knots[1:8], [0, 1, 2, 2, 1, 0, 0], atol=1e-12)


def test_first_order_hold_tracks_a_ramp_exactly():
    v, T = 0.0024, 0.025
    samples = [v * T * k for k in range(10)]
    knots, mids = _run_hold("delayed_ramp", samples)
    np.testing.assert_allclose(knots[1:], np.array(samples[:-1]), atol=1e-15)
    np.testing.assert_allclose(mids[1:] - knots[1:], v * T / 2, rtol=1e-9)


def test_first_order_hold_validation():
    with pytest.raises(ConfigError, match="period"):
        FirstOrderHold(0.0, [0.0])
    with pytest.raises(ConfigError, match="variant"):
        FirstOrderHold(0.025, [0.0], variant="zoh")
