"""The C++ force laws that feed the plant: the cutting force from the
process's sampled terms, joint friction as DoorHinge elements, and the tool
kinematics memo they rely on."""

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import MultibodyForces
import pytest

from deburr_drake.cell.arm import ARM_URL
from deburr_drake.cell.edge import make_contour
from deburr_drake.cell.friction import add_joint_friction
from deburr_drake.cell.models import (
    POINT_MASS_URL,
    make_kinematic_model,
    make_parser,
)
from deburr_drake.cell.process import (
    HeldMean,
    cutting_force,
    force_law_terms,
    generalized_cutting_force,
    make_cutting_force_law,
)
from deburr_drake.config import (
    ConfigError,
    ProcessConfig,
    RobotConfig,
    load_scenario,
)
from deburr_drake.control.kinematics import ToolPoint
from deburr_drake.math.damping import held_damper_mean

CONFIG = ProcessConfig(plunge_coefficient=50.0)


@pytest.fixture(scope="module")
def arm():
    return make_kinematic_model(ARM_URL)


def _arm_state(arm, seed):
    rng = np.random.default_rng(seed)
    q = np.array([0.1, 0.6, -1.2, 0.5, 0.2]) + 0.05 * rng.normal(size=5)
    return np.concatenate([q, 0.01 * rng.normal(size=5)])


def test_tool_point_matches_drake_and_reuses_only_nearby_states(arm):
    frame = arm.GetFrameByName("tool_tip")
    tool = ToolPoint(arm, frame)
    context = arm.CreateDefaultContext()

    def assert_matches_drake(state, position_tolerance):
        x_p, xdot_p = tool(state)
        arm.SetPositionsAndVelocities(context, state)
        np.testing.assert_allclose(
            x_p,
            frame.CalcPoseInWorld(context).translation(),
            atol=position_tolerance,
        )
        np.testing.assert_allclose(
            tool.rotation(state),
            frame.CalcPoseInWorld(context).rotation().matrix(),
            atol=1e-9,
        )
        np.testing.assert_allclose(
            xdot_p,
            frame.CalcSpatialVelocityInWorld(context).translational(),
            atol=1e-15,
        )

    x = _arm_state(arm, 0)
    assert_matches_drake(x, 1e-15)
    assert tool.full_evaluations == 1
    # An integrator's perturbation (4e-11 rad): first order, no kinematics.
    nearby = x.copy()
    nearby[:5] += 4e-11
    nearby[5:] += 1.5e-8
    assert_matches_drake(nearby, 1e-16)
    assert tool.full_evaluations == 1
    # One step later (1e-5 rad): evaluated again.
    far = x.copy()
    far[:5] += 1e-5
    tool(far)
    assert tool.full_evaluations == 2
    with pytest.raises(ValueError, match="reuse_tolerance"):
        ToolPoint(arm, frame, reuse_tolerance=-1.0)


def test_tool_point_mass_matrix_and_gravity_are_the_plants(arm):
    """At the anchor's q, whatever was asked before (the context keeps
    the anchor's q and its kinematics between requests)."""
    tool = ToolPoint(arm, arm.GetFrameByName("tool_tip"))
    context = arm.CreateDefaultContext()
    for seed in (4, 5, 4):
        x = _arm_state(arm, seed)
        tool.evaluate(x)
        M = tool.mass_matrix(x)
        _, _, tau_g = tool.control_terms(x)
        arm.SetPositions(context, x[:5])
        np.testing.assert_allclose(M, arm.CalcMassMatrix(context), rtol=1e-12)
        np.testing.assert_allclose(
            tau_g, arm.CalcGravityGeneralizedForces(context), rtol=1e-12
        )
        assert not M.flags.writeable


@pytest.mark.parametrize("speed", [2.4e-3, -1.1e-3, 1e-4, 0.0])
def test_cutting_force_law_is_eq3_through_the_jacobian(arm, speed):
    """The C++ law, its numpy twin and J^T of the world-frame eq. (3) agree
    at the sample's state, including in the direction's ramp."""
    scenario = load_scenario("paper")
    contour = make_contour(scenario)
    frame = arm.GetFrameByName("tool_tip")
    tool = ToolPoint(arm, frame)
    x = _arm_state(arm, 1)
    x_p, _, J = tool.evaluate(x)
    n1, tangent, delta, _ = contour.frame(x_p)
    # Put the tool 0.5 mm deep with the wanted speed along the edge and a
    # little plunge.
    x_p = x_p + (5e-4 - delta) * n1
    xdot = speed * tangent + 1e-4 * n1
    v = np.linalg.lstsq(J, xdot, rcond=None)[0]
    state = np.concatenate([x[:5], v])
    terms = force_law_terms(
        CONFIG, n1, tangent, 5e-4, J, J @ v, cut_height=0.002, burr_area=1e-6
    )
    tau, f = generalized_cutting_force(terms, v, CONFIG.smoothing_speed)
    f_ref, _ = cutting_force(
        CONFIG, contour, x_p, J @ v, cut_height=0.002, burr_area=1e-6
    )
    np.testing.assert_allclose(f, f_ref, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(tau, J.T @ f_ref, rtol=1e-9, atol=1e-12)
    law = make_cutting_force_law(5, 5, CONFIG.smoothing_speed)
    context = law.CreateDefaultContext()
    law.GetInputPort("plant_state").FixValue(context, state)
    law.GetInputPort("force_law_terms").FixValue(context, terms)
    law.GetInputPort("actuation").FixValue(context, np.zeros(5))
    np.testing.assert_allclose(
        law.GetOutputPort("generalized_force").Eval(context),
        tau,
        rtol=1e-12,
        atol=1e-12,
    )
    np.testing.assert_allclose(
        law.GetOutputPort("applied_force").Eval(context),
        f,
        rtol=1e-12,
        atol=1e-12,
    )


def test_cutting_force_law_follows_the_velocity_between_samples(arm):
    """Held place on the edge, live speed: doubling the speed along the
    edge doubles the g part of the force, which opposes the motion."""
    frame = arm.GetFrameByName("tool_tip")
    _, _, J = ToolPoint(arm, frame).evaluate(_arm_state(arm, 2))
    tangent, n1 = np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])
    v = np.linalg.lstsq(J, 2e-3 * tangent, rcond=None)[0]
    terms = force_law_terms(
        CONFIG, n1, tangent, 5e-4, J, J @ v, cut_height=0.002
    )
    _, f1 = generalized_cutting_force(terms, v, CONFIG.smoothing_speed)
    _, f2 = generalized_cutting_force(terms, 2 * v, CONFIG.smoothing_speed)
    g = CONFIG.cutting_coefficient * 5e-4 * 0.002
    assert f2 @ tangent - f1 @ tangent == pytest.approx(-g * 2e-3, rel=1e-9)
    assert f1 @ tangent < 0


@pytest.mark.parametrize("inertia", [None, [1.0, 4.0, 0.5, 2.0, 1.0]])
def test_implicit_damping_term_makes_the_law_diagonal_and_vanishes_at_v0(
    arm, inertia
):
    """With the sample's joint velocities the law gains S (v - v0): at v0
    the torque is still J^T of eq. (3); d tau / dv is diagonal (-D, what
    cenic treats implicitly), and D - c a a^T is positive semidefinite
    (D dominates the true damping), inside the direction's ramp too."""
    frame = arm.GetFrameByName("tool_tip")
    x = _arm_state(arm, 3)
    _, _, J = ToolPoint(arm, frame).evaluate(x)
    tangent, n1 = np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])
    for speed in (2.4e-3, 1e-4):  # outside and inside the ramp
        v0 = np.linalg.lstsq(J, speed * tangent + 1e-4 * n1, rcond=None)[0]
        plain = force_law_terms(
            CONFIG, n1, tangent, 5e-4, J, J @ v0, cut_height=0.002
        )
        terms = force_law_terms(
            CONFIG,
            n1,
            tangent,
            5e-4,
            J,
            J @ v0,
            cut_height=0.002,
            v=v0,
            inertia=inertia,
        )
        tau0, f0 = generalized_cutting_force(terms, v0, CONFIG.smoothing_speed)
        ref_tau, ref_f = generalized_cutting_force(
            plain, v0, CONFIG.smoothing_speed
        )
        np.testing.assert_allclose(tau0, ref_tau, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(f0, ref_f, rtol=1e-12)
        eps = 1e-9
        jac = np.column_stack(
            [
                (
                    generalized_cutting_force(
                        terms, v0 + eps * e, CONFIG.smoothing_speed
                    )[0]
                    - tau0
                )
                / eps
                for e in np.eye(5)
            ]
        )
        off = jac - np.diag(np.diag(jac))
        assert np.max(np.abs(off)) < 1e-6 * np.max(np.abs(jac))
        true_jac = np.column_stack(
            [
                (
                    generalized_cutting_force(
                        plain, v0 + eps * e, CONFIG.smoothing_speed
                    )[0]
                    - ref_tau
                )
                / eps
                for e in np.eye(5)
            ]
        )
        # -jac (= D) minus the true damping -true_jac is PSD.
        gap = -jac + true_jac
        assert np.min(np.linalg.eigvalsh(0.5 * (gap + gap.T))) > -1e-6 * np.max(
            np.abs(jac)
        )


def test_joint_friction_is_smooth_coulomb_in_the_plant():
    plant = MultibodyPlant(0.0)
    make_parser(plant).AddModels(url=ARM_URL)
    config = RobotConfig(
        model="arm5",
        joint_coulomb_friction=[1.0, 1.0, 0.5, 0.0, 0.1],
        friction_smoothing_speed=1e-3,
    )
    elements = add_joint_friction(plant, config)
    plant.Finalize()
    assert len(elements) == 4  # none for the zero entry
    context = plant.CreateDefaultContext()
    v = np.array([5e-4, -2e-3, 1e-2, 3e-3, -0.1])
    plant.SetVelocities(context, v)
    forces = MultibodyForces(plant)
    plant.CalcForceElementsContribution(context, forces)
    damping = np.array(
        [
            j.default_damping_vector()[0]
            for j in (
                plant.GetJointByName(n)
                for n in (
                    "waist",
                    "shoulder",
                    "elbow",
                    "wrist_pitch",
                    "wrist_roll",
                )
            )
        ]
    )
    expected = -np.array([1.0, 1.0, 0.5, 0.0, 0.1]) * np.tanh(v / 1e-3)
    np.testing.assert_allclose(
        forces.generalized_forces() + damping * v,
        expected,
        rtol=1e-9,
        atol=1e-12,
    )


def test_joint_friction_rejects_bad_lists_and_prismatic_joints():
    plant = MultibodyPlant(0.0)
    make_parser(plant).AddModels(url=ARM_URL)
    with pytest.raises(ConfigError, match="one per joint"):
        add_joint_friction(
            plant, RobotConfig(model="arm5", joint_coulomb_friction=[1.0])
        )
    gantry = MultibodyPlant(0.0)
    make_parser(gantry).AddModels(url=POINT_MASS_URL)
    with pytest.raises(ConfigError, match="revolute"):
        add_joint_friction(
            gantry, RobotConfig(joint_coulomb_friction=[1.0, 1.0, 1.0])
        )
    assert add_joint_friction(gantry, RobotConfig()) == []


@pytest.mark.parametrize("speed", [2.4e-3, -1e-4])
def test_held_mean_law_is_the_damper_s_mean_and_reads_the_actuation(arm, speed):
    """process.sample_mean's terms: the joint torque no longer follows v;
    it is -a (k0 + k1 y^T B u_act) + the threshold's J^T f0, k0, k1 the
    damper's exact mean (math.damping) with c = g outside the direction's
    ramp and g + P / v_s inside it; the world force for the sensor stays
    eq. (3) at the velocities; the C++ law and numpy agree."""
    frame = arm.GetFrameByName("tool_tip")
    x = _arm_state(arm, 4)
    _, _, J = ToolPoint(arm, frame).evaluate(x)
    tangent, n1 = np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])
    v0 = np.linalg.lstsq(J, speed * tangent + 1e-4 * n1, rcond=None)[0]
    context = arm.CreateDefaultContext()
    arm.SetPositions(context, x[:5])
    M = arm.CalcMassMatrix(context)
    a = J.T @ tangent
    y = np.linalg.solve(M, a)
    B = np.diag([1.0, 2.0, 1.0, 0.5, 1.0])[:, :4]  # nu = 4, any B
    held = HeldMean(y, 0.7, B, 0.0025)
    terms = force_law_terms(
        CONFIG,
        n1,
        tangent,
        5e-4,
        J,
        J @ v0,
        cut_height=0.002,
        v=v0,
        nu=4,
        held=held,
    )
    plain = force_law_terms(
        CONFIG, n1, tangent, 5e-4, J, J @ v0, cut_height=0.002, nu=4
    )
    u_act = np.array([3.0, -1.0, 0.5, 2.0])
    tau, f = generalized_cutting_force(terms, v0, CONFIG.smoothing_speed, u_act)
    tau_v, f_v = generalized_cutting_force(
        terms, 3 * v0, CONFIG.smoothing_speed, u_act
    )
    np.testing.assert_allclose(tau_v, tau, rtol=1e-12)  # not v's
    _, f_plain = generalized_cutting_force(
        plain, v0, CONFIG.smoothing_speed, u_act
    )
    np.testing.assert_allclose(f, f_plain, rtol=1e-12)
    g = CONFIG.cutting_coefficient * 5e-4 * 0.002
    power = CONFIG.threshold_power_force + CONFIG.plunge_coefficient * 1e-4
    u = a @ v0
    if abs(u) < CONFIG.smoothing_speed:
        c, offset = g + power / CONFIG.smoothing_speed, 0.0
    else:
        c, offset = g, np.sign(u) * power
    threshold = -CONFIG.contact_threshold_force * (J.T @ n1)
    k0, k1 = held_damper_mean(c, offset, u, a @ y, 0.7 + y @ threshold, 0.0025)
    mean = k0 + k1 * (y @ B @ u_act)
    np.testing.assert_allclose(tau, -mean * a + threshold, rtol=1e-9)
    law = make_cutting_force_law(5, 5, CONFIG.smoothing_speed, nu=4)
    context = law.CreateDefaultContext()
    law.GetInputPort("plant_state").FixValue(
        context, np.concatenate([x[:5], v0])
    )
    law.GetInputPort("force_law_terms").FixValue(context, terms)
    law.GetInputPort("actuation").FixValue(context, u_act)
    np.testing.assert_allclose(
        law.GetOutputPort("generalized_force").Eval(context),
        tau,
        rtol=1e-12,
        atol=1e-12,
    )
    np.testing.assert_allclose(
        law.GetOutputPort("applied_force").Eval(context),
        f,
        rtol=1e-12,
        atol=1e-12,
    )


def test_sample_mean_and_implicit_damping_exclude_each_other():
    with pytest.raises(
        ConfigError,
        match=r"^process\.implicit_damping = "
        r"True is invalid: allowed false while "
        r"process\.sample_mean is true",
    ):
        ProcessConfig(implicit_damping=True).validate()
    ProcessConfig(implicit_damping=True, sample_mean=False).validate()
    with pytest.raises(ConfigError, match=r"^process\.sample_mean = 'yes'"):
        ProcessConfig(sample_mean="yes").validate()
