"""HybridController: hand-derived outputs and derivatives through the public
API, ports, states and scalar conversion."""

import copy

import numpy as np
import pytest

from deburr_drake.cell.models import POINT_MASS_URL, make_kinematic_model
from deburr_drake.config import ConfigError, ControllerConfig
from deburr_drake.control.controller import HybridController, make_rule_bases
from deburr_drake.control.layout import CONTROLLER_DIAGNOSTICS
from deburr_drake.control.observer import chamfer_quantities
from deburr_drake.math.geometry import CircularContour

CONTOUR = CircularContour([0.0, 0.0, 0.048], 0.027)
G = 9.81


@pytest.fixture(scope="module")
def model():
    return make_kinematic_model(POINT_MASS_URL)


def _inputs(x_p, v, force, x_c, v_c, f_nd):
    chamfer = chamfer_quantities(
        CONTOUR, x_p, v, force, min_tangential_speed=1e-5
    )
    return dict(
        plant_state=np.concatenate([x_p, v]),
        chamfer_state=chamfer,
        measured_force=force,
        commanded_position=x_c,
        commanded_velocity=v_c,
        desired_normal_force=[f_nd],
    )


def _context(controller, inputs, delta_d, theta=None):
    context = controller.CreateDefaultContext()
    for name, value in inputs.items():
        controller.GetInputPort(name).FixValue(context, value)
    x = context.get_continuous_state_vector().CopyToVector()
    x[0] = delta_d
    if theta is not None:
        x[1:] = theta.ravel()
    context.SetContinuousState(x)
    return context


def _scenario_point():
    p = CONTOUR.point_at(0.01)
    n1, t = CONTOUR.n1(p), CONTOUR.tangent(p)
    x_p = p + 4e-4 * n1
    v = 2e-3 * t + 1e-4 * n1
    force = -5.0 * n1 - 9.0 * t
    x_c = p + 3e-5 * t
    v_c = 2.4e-3 * t
    return x_p, v, force, x_c, v_c, n1


def test_structure(model):
    config = ControllerConfig()
    controller = HybridController(model, "tool_tip", config)
    assert controller.get_name() == "controller"
    n_rules = (2 * config.fuzzy.upsilon + 1) ** 2
    assert controller.num_continuous_states() == 1 + 2 * n_rules  # 243
    ports = [
        controller.get_input_port(i).get_name()
        for i in range(controller.num_input_ports())
    ]
    assert ports == [
        "plant_state",
        "chamfer_state",
        "measured_force",
        "commanded_position",
        "commanded_velocity",
        "desired_normal_force",
    ]
    assert controller.GetOutputPort("actuation").size() == 3
    assert (
        controller.GetOutputPort("diagnostics").size()
        == CONTROLLER_DIAGNOSTICS.size
    )
    assert controller.ToAutoDiffXdMaybe() is not None


def test_control_law_by_hand(model):
    """(7), (9), s, (36) with theta = 0 inside Omega, J = I, gravity
    compensation from the model with masses scaled 1.2."""
    config = ControllerConfig(control_period=0.0)  # the law itself
    controller = HybridController(model, "tool_tip", config)
    x_p, v, force, x_c, v_c, n1 = _scenario_point()
    f_nd, delta_d = 6.0, 3e-4
    context = _context(
        controller, _inputs(x_p, v, force, x_c, v_c, f_nd), delta_d
    )
    f_n = 5.0
    e_f = f_nd - f_n
    dd = config.depth_gain * e_f
    x_pd = x_c + delta_d * n1
    e = x_pd - x_p
    # x_pd moves at xdot* + dd n1 + delta_d n1' (n1 turns along the arc)
    n1_rate = (
        v
        @ CONTOUR.tangent(x_p)
        / np.linalg.norm((x_p - CONTOUR.center)[:2])
        * CONTOUR.tangent(x_p)
    )
    s = (v_c + dd * n1 + delta_d * n1_rate - v) + np.array(
        config.sliding_lambda
    ) * e
    assert np.all(np.abs(s[:2]) < 5 * 0.2 * 0.005)  # inside Omega_k
    f_tau = np.array(config.sliding_gain) * s - force
    m_z = 1.2 * (0.3 + 1.0)  # flange + tool, as the controller models them
    expected = f_tau + np.array([0.0, 0.0, m_z * G])
    actuation = controller.GetOutputPort("actuation").Eval(context)
    np.testing.assert_allclose(actuation, expected, rtol=1e-9, atol=1e-9)
    d = CONTROLLER_DIAGNOSTICS.split(
        controller.GetOutputPort("diagnostics").Eval(context)
    )
    np.testing.assert_allclose(d["s"], s, rtol=1e-12)
    np.testing.assert_allclose(d["x_pd"], x_pd, rtol=1e-12)
    assert d["e_f"] == pytest.approx(e_f)
    np.testing.assert_array_equal(d["zeta"], [1, 1, 0])
    derivatives = controller.EvalTimeDerivatives(context).CopyToVector()
    assert derivatives[0] == pytest.approx(dd)


def test_integral_on_a_pd_axis(model):
    """integral_lambda on x3: one more state, int s_3 dt, whose rate is
    s_3, and f_tau_3 + K_3 lambda_I int s_3; theta and the other axes as
    without it."""
    plain = ControllerConfig(control_period=0.0)
    config = ControllerConfig(
        control_period=0.0, integral_lambda=[0.0, 0.0, 2.0]
    )
    base = HybridController(model, "tool_tip", plain)
    controller = HybridController(model, "tool_tip", config)
    n = base.num_continuous_states()
    assert controller.num_continuous_states() == n + 1
    x_p, v, force, x_c, v_c, _ = _scenario_point()
    inputs = _inputs(x_p, v, force, x_c, v_c, 6.0)
    context = _context(controller, inputs, 3e-4)
    x = context.get_continuous_state_vector().CopyToVector()
    x[n] = 1e-4  # m, int s_3 dt
    context.SetContinuousState(x)
    base_context = _context(base, inputs, 3e-4)
    expected = base.GetOutputPort("actuation").Eval(base_context).copy()
    expected[2] += config.sliding_gain[2] * 2.0 * 1e-4
    np.testing.assert_allclose(
        controller.GetOutputPort("actuation").Eval(context),
        expected,
        rtol=1e-12,
    )
    s = CONTROLLER_DIAGNOSTICS.split(
        controller.GetOutputPort("diagnostics").Eval(context)
    )["s"]
    rates = controller.EvalTimeDerivatives(context).CopyToVector()
    assert rates[n] == pytest.approx(s[2])
    np.testing.assert_allclose(
        rates[:n],
        base.EvalTimeDerivatives(base_context).CopyToVector(),
        rtol=1e-12,
    )
    np.testing.assert_array_equal(
        controller.theta(context), base.theta(base_context)
    )
    # fuzzy_weight 0 (touch probing) freezes theta, not the integral
    weighted = HybridController(
        model, "tool_tip", config, fuzzy_weight_input=True
    )
    ctx = _context(weighted, {**inputs, "fuzzy_weight": [0.0]}, 3e-4)
    frozen = weighted.EvalTimeDerivatives(ctx).CopyToVector()
    np.testing.assert_array_equal(frozen[1:n], 0.0)
    assert frozen[n] == pytest.approx(s[2])


def test_fuzzy_term_and_adaptation(model):
    """u_f = theta^T nu (30) on the fuzzy axes; theta' = r nu s_Delta (35)
    on the active rules only, zero inside the dead zone (R4)."""
    config = ControllerConfig(control_period=0.0)  # the law itself
    controller = HybridController(model, "tool_tip", config)
    rb = make_rule_bases(config)
    rng = np.random.default_rng(0)
    theta = rng.normal(size=(2, rb[0].n_rules))
    x_p, v, force, x_c, v_c, _ = _scenario_point()
    inputs = _inputs(x_p, v, force, x_c, v_c, 6.0)
    base = _context(controller, inputs, 3e-4)
    ctx = _context(controller, inputs, 3e-4, theta)
    s = CONTROLLER_DIAGNOSTICS.get(
        controller.GetOutputPort("diagnostics").Eval(ctx), "s"
    )
    y0 = np.linalg.norm(x_p)
    du = controller.GetOutputPort("actuation").Eval(
        ctx
    ) - controller.GetOutputPort("actuation").Eval(base)
    for k in range(2):
        assert du[k] == pytest.approx(
            rb[k].evaluate(theta[k], y0, s[k]), rel=1e-9
        )
    rate = controller.EvalTimeDerivatives(ctx).CopyToVector()[1:]
    rate = rate.reshape(2, -1)
    r = config.fuzzy.adaptation_gain
    for k in range(2):
        idx, nu = rb[k].active_rules(y0, s[k])
        hw = rb[k].resolved_dead_zone_half_width
        expected = np.zeros(rb[k].n_rules)
        if abs(s[k]) > hw:
            expected[idx] = r * nu * s[k]
        np.testing.assert_allclose(rate[k], expected, rtol=1e-9, atol=1e-15)
        assert np.count_nonzero(rate[k]) <= (config.fuzzy.order + 1) ** 2


def test_fuzzy_weight_scales_output_and_adaptation(model):
    """The ``fuzzy_weight`` input w (the ramp after touch probing) scales
    u_f and the rates (35) alike: the gradient of w theta . nu is w nu;
    w = 0 freezes theta."""
    config = ControllerConfig(control_period=0.0)
    plain = HybridController(model, "tool_tip", config)
    weighted = HybridController(
        model, "tool_tip", config, fuzzy_weight_input=True
    )
    rng = np.random.default_rng(1)
    theta = rng.normal(size=(2, make_rule_bases(config)[0].n_rules))
    x_p, v, force, x_c, v_c, _ = _scenario_point()
    v = v + 4e-3 * CONTOUR.tangent(x_p)  # s outside the dead zone
    inputs = _inputs(x_p, v, force, x_c, v_c, 6.0)
    full = plain.EvalTimeDerivatives(
        _context(plain, inputs, 3e-4, theta)
    ).CopyToVector()
    u_full = CONTROLLER_DIAGNOSTICS.get(
        plain.GetOutputPort("diagnostics").Eval(
            _context(plain, inputs, 3e-4, theta)
        ),
        "u_fuzzy",
    )
    assert np.count_nonzero(full[1:]) > 0
    for w in (1.0, 0.3, 0.0):
        ctx = _context(weighted, {**inputs, "fuzzy_weight": [w]}, 3e-4, theta)
        rate = weighted.EvalTimeDerivatives(ctx).CopyToVector()
        np.testing.assert_allclose(
            rate[1:], w * full[1:], rtol=1e-12, atol=1e-15
        )
        assert rate[0] == pytest.approx(full[0])
        u = CONTROLLER_DIAGNOSTICS.get(
            weighted.GetOutputPort("diagnostics").Eval(ctx), "u_fuzzy"
        )
        np.testing.assert_allclose(
            u[:2], w * u_full[:2], rtol=1e-12, atol=1e-15
        )


def test_robust_term_outside_omega(model):
    """zeta_k = 0 outside Omega_k: H_bar = h_bar sat(s / phi) (R10)."""
    config = ControllerConfig(control_period=0.0)  # the law itself
    controller = HybridController(model, "tool_tip", config)
    x_p, v, force, x_c, v_c, _ = _scenario_point()
    v = v + np.array([0.0, -0.05, 0.0])  # s_y far outside Omega
    ctx = _context(controller, _inputs(x_p, v, force, x_c, v_c, 6.0), 3e-4)
    d = CONTROLLER_DIAGNOSTICS.split(
        controller.GetOutputPort("diagnostics").Eval(ctx)
    )
    assert d["zeta"][1] == 0.0
    assert d["u_fuzzy"][1] == pytest.approx(config.robust_gain[1])
    rate = controller.EvalTimeDerivatives(ctx).CopyToVector()[1:]
    np.testing.assert_array_equal(rate.reshape(2, -1)[1], 0.0)


def test_autodiff_matches_finite_difference(model):
    """The AutoDiffXd controller's d(actuation)/d(delta_d) equals a finite
    difference of the float controller."""
    from pydrake.autodiffutils import AutoDiffXd, ExtractGradient

    config = ControllerConfig(control_period=0.0)  # the law itself
    controller = HybridController(model, "tool_tip", config)
    x_p, v, force, x_c, v_c, _ = _scenario_point()
    inputs = _inputs(x_p, v, force, x_c, v_c, 6.0)
    ad = controller.ToAutoDiffXd()
    ctx_ad = ad.CreateDefaultContext()
    for name, value in inputs.items():
        ad.GetInputPort(name).FixValue(
            ctx_ad,
            np.array([AutoDiffXd(float(x)) for x in np.asarray(value, float)]),
        )
    x_ad = [AutoDiffXd(0.0) for _ in range(controller.num_continuous_states())]
    x_ad[0] = AutoDiffXd(3e-4, np.array([1.0]))
    ctx_ad.SetContinuousState(np.array(x_ad))
    u_ad = ad.GetOutputPort("actuation").Eval(ctx_ad)
    grad = ExtractGradient(u_ad)[:, 0]
    h = 1e-7
    u1 = controller.GetOutputPort("actuation").Eval(
        _context(controller, inputs, 3e-4 + h)
    )
    u0 = controller.GetOutputPort("actuation").Eval(
        _context(controller, inputs, 3e-4 - h)
    )
    np.testing.assert_allclose(grad, (u1 - u0) / (2 * h), rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize(
    "path, value, match",
    [
        (("fuzzy", "order"), 4, "fuzzy.order"),
        (("fuzzy", "upsilon"), 0, "fuzzy.upsilon"),
        (
            ("fuzzy", "dead_zone_half_widths"),
            [0.01, 0.01],
            "fuzzy.dead_zone_half_widths",
        ),
        (("depth_gain",), -1.0, "controller.depth_gain"),
        (("sliding_gain",), [1.0, 1.0], "controller.sliding_gain"),
        # a fuzzy axis learns its steady force: no integral there
        (
            ("integral_lambda",),
            [1.0, 0.0, 0.0],
            r"controller.integral_lambda\[0\]",
        ),
        # slower than the sliding surface
        (
            ("integral_lambda",),
            [0.0, 0.0, 200.0],
            r"controller.integral_lambda\[2\]",
        ),
        (
            ("integral_lambda",),
            [0.0, 0.0, -1.0],
            r"controller.integral_lambda\[2\]",
        ),
    ],
)
def test_invalid_config_names_the_field(model, path, value, match):
    config = copy.deepcopy(ControllerConfig())
    target = config
    for name in path[:-1]:
        target = getattr(target, name)
    setattr(target, path[-1], value)
    with pytest.raises(ConfigError, match=match):
        HybridController(model, "tool_tip", config)


def test_sampled_law_holds_its_terms_between_samples(model):
    """control_period > 0: the law is evaluated at initialization and at
    each sample; outputs and rates hold the sample's values while the
    inputs move."""
    x_p, v, force, x_c, v_c, n1 = _scenario_point()
    inputs = _inputs(x_p, v, force, x_c, v_c, 6.0)
    continuous = HybridController(
        model, "tool_tip", ControllerConfig(control_period=0.0)
    )
    sampled = HybridController(
        model, "tool_tip", ControllerConfig(control_period=0.0025)
    )
    cc = _context(continuous, inputs, 4e-4)
    sc = _context(sampled, inputs, 4e-4)
    sc.SetDiscreteState(sampled.EvalUniquePeriodicDiscreteUpdate(sc))
    for port in ("actuation", "diagnostics"):
        np.testing.assert_allclose(
            sampled.GetOutputPort(port).Eval(sc),
            continuous.GetOutputPort(port).Eval(cc),
            rtol=1e-12,
            atol=1e-12,
        )
    np.testing.assert_allclose(
        sampled.EvalTimeDerivatives(sc).CopyToVector(),
        continuous.EvalTimeDerivatives(cc).CopyToVector(),
        rtol=1e-12,
        atol=1e-12,
    )
    held = sampled.GetOutputPort("actuation").Eval(sc).copy()
    sampled.GetInputPort("commanded_position").FixValue(sc, x_c + 1e-3 * n1)
    np.testing.assert_array_equal(
        sampled.GetOutputPort("actuation").Eval(sc), held
    )


def test_shared_tool_point_gives_the_same_law_on_the_arm():
    """On the arm (tilted tool, gravity on every joint) the law with a
    ToolPoint's kinematics and gravity forces equals the law computing its
    own; its AutoDiffXd copy computes its own."""
    from deburr_drake.cell.arm import ARM_URL
    from deburr_drake.control.kinematics import ToolPoint

    arm = make_kinematic_model(ARM_URL)
    tool_point = ToolPoint(arm, arm.GetFrameByName("tool_tip"))
    config = ControllerConfig(control_period=0.0)
    rotation = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    own = HybridController(arm, "tool_tip", config, rotation)
    shared = HybridController(
        arm, "tool_tip", config, rotation, tool_point=tool_point
    )
    state = np.array([0.1, 0.6, -1.2, 0.5, 0.2, 0.01, -0.02, 0.03, 0.0, 0.1])
    x_p, v = tool_point(state)
    _, _, force, x_c, v_c, _ = _scenario_point()
    inputs = _inputs(
        x_p, v, force, x_c + x_p - CONTOUR.point_at(0.01), v_c, 6.0
    )
    inputs["plant_state"] = state
    theta = np.random.default_rng(0).normal(size=2 * 121)
    outputs = []
    for controller in (own, shared):
        context = _context(controller, inputs, 3e-4, theta)
        outputs.append(
            [
                controller.GetOutputPort(name).Eval(context)
                for name in ("actuation", "diagnostics")
            ]
            + [controller.EvalTimeDerivatives(context).CopyToVector()]
        )
    assert np.linalg.norm(outputs[0][0]) > 1.0
    for a, b in zip(*outputs):
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)
    assert tool_point.full_evaluations == 1
    assert shared.ToAutoDiffXd() is not None
    with pytest.raises(ValueError, match="tool_point"):
        HybridController(
            make_kinematic_model(ARM_URL),
            "tool_tip",
            config,
            tool_point=tool_point,
        )


def test_slope_rate_autodiff_matches_float():
    from pydrake.autodiffutils import InitializeAutoDiff

    from deburr_drake.math.fuzzy import RuleBase

    rb = RuleBase(m=2, upsilon=5, delta0=0.2, deltak=0.004)
    rng = np.random.default_rng(3)
    theta = 30.0 * rng.normal(size=121)
    ad = InitializeAutoDiff(theta).ravel()
    rate = rb.slope_rate(ad, 1000.0, 80.0)
    np.testing.assert_allclose(
        [r.value() if hasattr(r, "value") else r for r in rate],
        rb.slope_rate(theta, 1000.0, 80.0),
    )


def test_desired_rotation_turns_with_a_3d_edge(tilted_circle):
    """Along a contour whose tool axis turns, the controller holds
    R_d(s) = axis_turn(s) R_start at the chamfer state's arc position: its
    actuation is that of a controller holding that rotation fixed, and
    R_d(s) carries the start's tool axis onto a(s). A planar contour
    changes nothing."""
    from deburr_drake.cell.arm import ARM_URL
    from deburr_drake.control.kinematics import ToolPoint
    from deburr_drake.control.layout import CHAMFER_STATE

    arm = make_kinematic_model(ARM_URL)
    tool_point = ToolPoint(arm, arm.GetFrameByName("tool_tip"))
    config = ControllerConfig(
        control_period=0.0,
        orientation_lambda=[20.0] * 3,
        orientation_gain=[20.0] * 3,
    )
    edge = tilted_circle([0.4, 0.0, 0.05], 0.01, np.radians(30.0), 0.4)
    state = np.array([0.1, 0.6, -1.2, 0.5, 0.2, 0.01, -0.02, 0.03, 0.0, 0.1])
    R_start = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    x_p, v = tool_point(state)
    _, _, force, x_c, v_c, _ = _scenario_point()
    inputs = _inputs(
        x_p, v, force, x_c + x_p - CONTOUR.point_at(0.01), v_c, 6.0
    )
    inputs["plant_state"] = state

    def actuation(controller, s):
        chamfer = inputs["chamfer_state"].copy()
        chamfer[CHAMFER_STATE.slice("arc_position")] = s
        context = _context(controller, dict(inputs, chamfer_state=chamfer), 0)
        return (
            controller.GetOutputPort("actuation").Eval(context),
            controller.desired_rotation(context),
        )

    turning = HybridController(arm, "tool_tip", config, R_start, contour=edge)
    for s in (0.0, 0.25 * edge.length, 0.6 * edge.length):
        R_d = edge.axis_turn(s) @ R_start
        held = HybridController(arm, "tool_tip", config, R_d)
        tau, rotation = actuation(turning, s)
        np.testing.assert_allclose(rotation, R_d, atol=1e-12)
        np.testing.assert_allclose(
            R_d @ R_start.T @ edge.tool_axis_at(0.0),
            edge.tool_axis_at(s),
            atol=1e-12,
        )
        np.testing.assert_allclose(tau, actuation(held, s)[0], atol=1e-12)
    # The axis turns by 2 x 0.4 rad half-way round: so does R_d.
    fixed = HybridController(arm, "tool_tip", config, R_start)
    half = 0.5 * edge.length
    angle = np.arccos(
        (np.trace(actuation(turning, half)[1] @ R_start.T) - 1) / 2
    )
    assert angle == pytest.approx(0.8, abs=1e-9)
    assert (
        np.linalg.norm(actuation(turning, half)[0] - actuation(fixed, half)[0])
        > 0.1
    )
    assert turning.ToAutoDiffXd() is not None
    planar = HybridController(arm, "tool_tip", config, R_start, contour=CONTOUR)
    np.testing.assert_array_equal(
        actuation(planar, half)[0], actuation(fixed, half)[0]
    )
    np.testing.assert_array_equal(actuation(planar, half)[1], R_start)


def test_the_law_works_on_the_task_axes(model, tilted_circle):
    """Along a contour with task axes Q (x3 the tilted tool axis), the
    controller is the world-axes controller seen in Q: fed every vector
    rotated by Q^T, the world controller logs the same e, s, f_tau,
    u_fuzzy and adapts theta alike (the gains differ per axis: K3 is the
    tool axis's, the fuzzy terms are across it, the integral along it);
    the actuation is Q f_tau (the point mass: J_v = I)."""
    from deburr_drake.control.layout import CHAMFER_STATE

    tilt = np.radians(30.0)
    c, s_ = np.cos(tilt), np.sin(tilt)
    Q = np.array([[1.0, 0.0, 0.0], [0.0, c, -s_], [0.0, s_, c]])

    class Framed(tilted_circle):
        def task_frame(self, s):
            return Q

    edge = Framed([0.0, 0.0, 0.048], 0.027, 0.0)
    config = ControllerConfig(
        control_period=0.0,
        sliding_gain=[400.0, 400.0, 4000.0],
        integral_lambda=[0.0, 0.0, 2.0],
        gravity_compensation=False,
    )
    framed = HybridController(model, "tool_tip", config, contour=edge)
    world = HybridController(model, "tool_tip", config)
    x_p, v, force, x_c, v_c, _ = _scenario_point()
    inputs = _inputs(x_p, v, force, x_c, v_c, 6.0)
    rotated = {
        "plant_state": np.concatenate([Q.T @ x_p, Q.T @ v]),
        "measured_force": Q.T @ force,
        "commanded_position": Q.T @ x_c,
        "commanded_velocity": Q.T @ v_c,
        "desired_normal_force": inputs["desired_normal_force"],
    }
    chamfer = inputs["chamfer_state"].copy()
    for name in ("x_p", "xdot_p", "n1", "n2", "n1_rate"):
        chamfer[CHAMFER_STATE.slice(name)] = (
            Q.T @ chamfer[CHAMFER_STATE.slice(name)]
        )
    rotated["chamfer_state"] = chamfer
    theta = np.random.default_rng(3).uniform(
        -5.0, 5.0, (2, make_rule_bases(config)[0].n_rules)
    )
    # delta_d, theta, then the integral: int s_3 dt (m) on the world
    # controller's x3, the same as a world force (N) on the framed one's.
    K_I = config.sliding_gain[2] * config.integral_lambda[2]
    contexts = []
    for controller, values, integral in (
        (framed, inputs, K_I * 2e-5 * Q[:, 2]),
        (world, rotated, [2e-5]),
    ):
        context = _context(controller, values, 4e-4)
        context.SetContinuousState(
            np.concatenate([[4e-4], theta.ravel(), integral])
        )
        contexts.append(context)

    def out(controller, context, port):
        return controller.GetOutputPort(port).Eval(context)

    d_f, d_w = (
        out(ctl, ctx, "diagnostics")
        for ctl, ctx in zip((framed, world), contexts)
    )
    for name in ("e", "s", "f_tau", "u_fuzzy", "zeta", "delta_d", "e_f"):
        np.testing.assert_allclose(
            CONTROLLER_DIAGNOSTICS.get(d_f, name),
            CONTROLLER_DIAGNOSTICS.get(d_w, name),
            rtol=1e-9,
            atol=1e-12,
        )
    np.testing.assert_allclose(
        CONTROLLER_DIAGNOSTICS.get(d_f, "x_pd"),
        Q @ CONTROLLER_DIAGNOSTICS.get(d_w, "x_pd"),
        atol=1e-12,
    )
    rates = [
        ctl.EvalTimeDerivatives(ctx).CopyToVector()
        for ctl, ctx in zip((framed, world), contexts)
    ]
    np.testing.assert_allclose(
        rates[0][:-3], rates[1][:-1], rtol=1e-9, atol=1e-12
    )
    np.testing.assert_allclose(
        rates[0][-3:], K_I * rates[1][-1] * Q[:, 2], rtol=1e-9, atol=1e-12
    )
    f_tau = CONTROLLER_DIAGNOSTICS.get(d_w, "f_tau")
    np.testing.assert_allclose(
        out(framed, contexts[0], "actuation"), Q @ f_tau, atol=1e-9
    )
    assert np.linalg.norm(Q @ f_tau - f_tau) > 1.0


def test_the_integral_holds_a_world_force_along_a_turning_axis(
    model, tilted_circle
):
    """Along a 3-D edge the integral is a world force (3 states, N): its
    rate is K_3 lambda_I s_3 along the tool axis, and where the task axes
    have turned it acts on every task axis as the same world force (what
    it learned along the old tool axis now partly across the new one)."""
    tilt = np.radians(15.0)
    c, s_ = np.cos(tilt), np.sin(tilt)
    turned = np.array([[1.0, 0.0, 0.0], [0.0, c, -s_], [0.0, s_, c]])
    frames = {"Q": np.eye(3)}

    class Framed(tilted_circle):
        def task_frame(self, s):
            return frames["Q"]

    edge = Framed([0.0, 0.0, 0.048], 0.027, 0.0)
    config = ControllerConfig(
        control_period=0.0,
        sliding_gain=[400.0, 400.0, 4000.0],
        integral_lambda=[0.0, 0.0, 2.0],
        gravity_compensation=False,
    )
    controller = HybridController(model, "tool_tip", config, contour=edge)
    base = HybridController(
        model,
        "tool_tip",
        ControllerConfig(
            control_period=0.0,
            sliding_gain=[400.0, 400.0, 4000.0],
            gravity_compensation=False,
        ),
        contour=edge,
    )
    n = base.num_continuous_states()
    assert controller.num_continuous_states() == n + 3
    x_p, v, force, x_c, v_c, _ = _scenario_point()
    inputs = _inputs(x_p, v, force, x_c, v_c, 6.0)
    learned = np.array([0.0, 0.0, -60.0])  # N, world
    for Q in (np.eye(3), turned):
        frames["Q"] = Q
        context = _context(controller, inputs, 3e-4)
        x = context.get_continuous_state_vector().CopyToVector()
        x[n:] = learned
        context.SetContinuousState(x)
        base_context = _context(base, inputs, 3e-4)

        def f_tau(ctl, ctx):
            return CONTROLLER_DIAGNOSTICS.get(
                ctl.GetOutputPort("diagnostics").Eval(ctx), "f_tau"
            )

        np.testing.assert_allclose(
            f_tau(controller, context),
            f_tau(base, base_context) + Q.T @ learned,
            rtol=1e-12,
            atol=1e-9,
        )
        s3 = CONTROLLER_DIAGNOSTICS.get(
            controller.GetOutputPort("diagnostics").Eval(context), "s"
        )[2]
        np.testing.assert_allclose(
            controller.EvalTimeDerivatives(context).CopyToVector()[n:],
            4000.0 * 2.0 * s3 * Q[:, 2],
            rtol=1e-12,
        )
    # Turned 15 deg, -60 N along the old axis is -60 sin 15 deg across.
    assert (turned.T @ learned)[1] == pytest.approx(-60.0 * np.sin(tilt))


def test_gains_are_parameters(model):
    """K (with the integral's K lambda_I) set in a Context gives, bit for
    bit, the controller built with that K."""
    config = ControllerConfig(
        control_period=0.0, integral_lambda=[0.0, 0.0, 2.0]
    )
    doubled = copy.deepcopy(config)
    doubled.sliding_gain = [2.0 * k for k in config.sliding_gain]
    controller = HybridController(model, "tool_tip", config)
    built = HybridController(model, "tool_tip", doubled)
    x_p, v, force, x_c, v_c, _ = _scenario_point()
    inputs = _inputs(x_p, v, force, x_c, v_c, 6.0)
    context = _context(controller, inputs, 3e-4)
    x = context.get_continuous_state_vector().CopyToVector()
    x[-1] = 1e-4  # m, int s_3 dt
    context.SetContinuousState(x)
    built_context = _context(built, inputs, 3e-4)
    built_context.SetContinuousState(x)
    before = controller.GetOutputPort("actuation").Eval(context).copy()
    controller.set_gains(context, sliding_gain=doubled.sliding_gain)
    K, _ = controller.gains(context)
    np.testing.assert_array_equal(K, doubled.sliding_gain)
    after = controller.GetOutputPort("actuation").Eval(context)
    assert not np.allclose(after, before)
    np.testing.assert_array_equal(
        after, built.GetOutputPort("actuation").Eval(built_context)
    )
    np.testing.assert_array_equal(
        controller.EvalTimeDerivatives(context).CopyToVector(),
        built.EvalTimeDerivatives(built_context).CopyToVector(),
    )
