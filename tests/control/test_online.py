"""OnlineRegistration converges on a known offset of the part from the
contact force along the cut (open loop: the tool runs on the real edge, the
force is the contact law of the real depth)."""

import numpy as np
import pytest

from deburr_drake.config import EstimatorConfig, OnlineRegistrationConfig
from deburr_drake.control.layout import CHAMFER_STATE
from deburr_drake.control.online import ONLINE_STATE, OnlineRegistration
from deburr_drake.math.geometry import CircularContour
from deburr_drake.math.registration import moved_contour


def _system(believed, *, active=1.0):
    """(config, system, context): registration while cutting on
    ``believed``, no probe, ``active`` fixed."""
    config = OnlineRegistrationConfig(enabled=True)
    system = OnlineRegistration(
        believed,
        config,
        EstimatorConfig(initial_estimates=[3.0, 4000.0, 20.0]),
        latency=0.018,
    )
    context = system.CreateDefaultContext()
    size = system.GetInputPort("base_registration").size()
    system.GetInputPort("base_registration").FixValue(context, np.zeros(size))
    system.GetInputPort("active").FixValue(context, [active])
    return config, system, context


def _step(system, context, real, *, s, v, depth, f_n, T):
    """One sample: the tool ``depth`` into ``real`` at arc position
    ``s``, moving at ``v`` along it, the force ``f_n``; then the update
    and the clock by ``T``."""
    p = real.point_at(s)
    n1 = real.n1(p)
    system.GetInputPort("chamfer_state").FixValue(
        context,
        CHAMFER_STATE.pack(
            x_p=p + depth * n1,
            xdot_p=v * real.tangent(p),
            n1=n1,
            n2=n1,
            delta=depth,
            delta_dot=0.0,
            f_n=f_n,
            f_t=0.0,
            arc_position=s,
            n1_rate=np.zeros(3),
        ),
    )
    context.SetDiscreteState(system.EvalUniquePeriodicDiscreteUpdate(context))
    context.SetTime(context.get_time() + T)


def _run(offset, *, active=1.0, seconds=40.0, c0=2.0, c1=9000.0, seed=0):
    believed = CircularContour([0.4, 0.0, 0.048], 0.027)
    real = moved_contour(believed, [*offset, 0.0, 0.0])
    config, system, context = _system(believed, active=active)
    rng = np.random.default_rng(seed)
    T, v = config.sample_period, 0.0024
    for k in range(int(seconds / T)):
        t = k * T
        # The force loop settles the real depth towards 0.5 mm.
        depth = 5e-4 * (1 - np.exp(-t / 1.5))
        f_n = c0 + c1 * depth + 0.1 * rng.standard_normal()
        _step(system, context, real, s=v * t, v=v, depth=depth, f_n=f_n, T=T)
    return system.GetOutputPort("registration").Eval(
        context
    ), context.get_discrete_state(0).get_value()


def test_online_estimate_converges_on_a_known_offset():
    reg, state = _run([6e-4, -4e-4])
    np.testing.assert_allclose(reg[:2], [6e-4, -4e-4], atol=2e-5)
    theta = ONLINE_STATE.get(state, "theta")
    assert theta[1] == pytest.approx(9000.0, rel=0.1)  # c1 with it


def test_no_offset_no_correction_and_nothing_learned_while_inactive():
    reg, _ = _run([0.0, 0.0])
    np.testing.assert_allclose(reg[:2], 0.0, atol=1e-5)
    reg, state = _run([6e-4, -4e-4], active=0.0, seconds=2.0)
    np.testing.assert_allclose(reg, 0.0)
    assert ONLINE_STATE.get(state, "onset") == 0.0


def test_profile_offset_found_with_stiffer_fillets_left_out():
    # A pocket whose fillets are 1.5 times as stiff as its sides (as in
    # the simulated cell: the cutter in a concave corner): the model
    # learns on the sides only and finds the move and the turn.
    from deburr_drake.math.profile import ProfileContour

    believed = ProfileContour(
        [[-0.03, -0.02], [0.03, -0.02], [0.03, 0.02], [-0.03, 0.02]],
        0.008,
        offset=0.003,
        center=[0.4, 0.0, 0.048],
    )
    move = [5e-4, -3e-4, 0.004, 0.0]
    real = moved_contour(believed, move)
    config, system, context = _system(believed)
    rng = np.random.default_rng(0)
    T, v, c0, c1 = config.sample_period, 0.002, 2.0, 9000.0
    n = int(real.length / v / T)  # one lap
    worst = 0.0
    for k in range(n):
        t = k * T
        if k > 0.2 * n and k % 100 == 0:
            # After the first side and fillet, never off by more than
            # 50 um (learning in the fillets too: 0.65 mm off over the
            # first 40 % of the lap, the stiffer corners taken for a
            # move towards them).
            reg = system.GetOutputPort("registration").Eval(context)
            worst = max(worst, np.max(np.abs(reg[:2] - move[:2])))
        depth = 5e-4 * (1 - np.exp(-t / 1.5))
        stiff = 1.5 if real.curvature(real.point_at(v * t)) != 0.0 else 1.0
        f_n = c0 + stiff * c1 * depth + 0.1 * rng.standard_normal()
        _step(system, context, real, s=v * t, v=v, depth=depth, f_n=f_n, T=T)
    reg = system.GetOutputPort("registration").Eval(context)
    assert worst < 5e-5
    np.testing.assert_allclose(reg[:2], move[:2], atol=5e-6)
    assert reg[2] == pytest.approx(move[2], abs=5e-4)
    assert reg[3] == 0.0


def _tilted_run(base, move, seconds):
    """(registration, system, context): the edge ``base`` in a plane
    tilted 30 deg about x (a 3-D edge: its frame turns), the real part
    moved by ``move`` (v, omega) about the edge's pivot, the force the
    contact law of the real depth."""
    from deburr_drake.math.edge_registration import edge_pivot, move_of
    from deburr_drake.math.registration import PosedContour
    from deburr_drake.math.rigid import rpy_matrix

    tilt = rpy_matrix([np.radians(30.0), 0.0, 0.0])
    centre = np.array([0.95, 0.0, 0.5])
    believed = PosedContour(base, tilt, centre - tilt @ centre)
    real = PosedContour(believed, *move_of(move, edge_pivot(believed)[0]))
    config, system, context = _system(believed)
    assert system.GetOutputPort("registration").size() == 7
    rng = np.random.default_rng(0)
    T, v, c0, c1 = config.sample_period, 0.002, 2.0, 9000.0
    for k in range(int(seconds / T)):
        t = k * T
        depth = 5e-4 * (1 - np.exp(-t / 1.5))
        f_n = c0 + c1 * depth + 0.1 * rng.standard_normal()
        _step(system, context, real, s=v * t, v=v, depth=depth, f_n=f_n, T=T)
    theta = system.layout.get(context.get_discrete_state(0).value(), "theta")
    assert theta[1] == pytest.approx(c1, rel=0.1)
    return system.GetOutputPort("registration").Eval(context)


def test_a_3d_rim_leaves_the_move_across_its_axis_alone():
    """A rim in a tilted plane, the real part moved by 0.15 mm and turned
    by 0.2 deg: the force's first harmonic is also what a tilt raising
    the rim on one side makes, so the model estimates it as that and
    moves nothing."""
    move = np.array([1.2e-4, -0.8e-4, 0.6e-4, 0.0021, -0.0017, 0.0026])
    reg = _tilted_run(CircularContour([0.95, 0.0, 0.5], 0.008), move, 20.0)
    np.testing.assert_array_equal(reg, 0.0)


def test_a_3d_profile_registers_its_turn_about_the_axis():
    """A rounded rectangle (40 x 20 mm) in a tilted plane, the real part
    turned by 0.15 deg about its axis and moved: the correction is the
    turn about the axis, which its straight sides show and neither a
    lean nor a tilt makes; the move across is left to them."""
    from deburr_drake.math.profile import ProfileContour
    from deburr_drake.math.rigid import rpy_matrix

    profile = ProfileContour(
        [[-0.02, -0.01], [0.02, -0.01], [0.02, 0.01], [-0.02, 0.01]],
        0.004,
        center=(0.95, 0.0, 0.5),
    )
    axis = rpy_matrix([np.radians(30.0), 0.0, 0.0]) @ [0.0, 0.0, 1.0]
    turn = np.radians(0.15)
    move = np.concatenate([[1.2e-4, -0.8e-4, 0.6e-4], turn * axis])
    reg = _tilted_run(profile, move, 70.0)
    np.testing.assert_allclose(reg[:3], turn * axis, rtol=0.05, atol=1e-5)
    assert reg[6] == 0.0
