"""HybridController: the inner-loop adaptive fuzzy hybrid position/force
controller, eqs. (7), (9)-(11), (30), (35)-(37) with R4, R8, R9, R10.

Use: ``HybridController(plant, "tool_tip", scenario.controller)`` is an
ordinary LeafSystem (float and AutoDiffXd); its input and output ports are
in the class docstring. :func:`deburr_drake.control.loop.add_deburring_controller`
adds it together with the systems that feed it."""

from __future__ import annotations

import math

import numpy as np
from pydrake.autodiffutils import AutoDiffXd
from pydrake.common.value import AbstractValue
from pydrake.multibody.tree import (
    BodyIndex,
    JacobianWrtVariable,
    MultibodyForces_,
)
from pydrake.systems.framework import BasicVector_, LeafSystem_, ValueProducer
from pydrake.systems.scalar_conversion import TemplateSystem

from deburr_drake.config import ControllerConfig
from deburr_drake.control.laws import impedance_force, robust_term
from deburr_drake.control.layout import CHAMFER_STATE, CONTROLLER_DIAGNOSTICS
from deburr_drake.math.fuzzy import RuleBase

__all__ = [
    "HybridController",
    "HybridController_",
    "make_rule_bases",
    "saturation",
]


#: What HybridController's law returns, in order.
_LAW_OUTPUTS = ("actuation", "derivatives", "diagnostics")


def _value(y):
    return y.value() if hasattr(y, "value") else float(y)


def _float_values(J):
    """J's values as floats (an AutoDiffXd array's values; a float array
    as is): what the pseudo-inverses are taken of."""
    return np.vectorize(_value)(J) if J.dtype == object else J


def saturation(x):
    """sat(x) = x for |x| <= 1, sign(x) otherwise (T-generic)."""
    v = _value(x)
    if v > 1.0:
        return 1.0 + 0.0 * x
    if v < -1.0:
        return -1.0 + 0.0 * x
    return x


def make_rule_bases(config: ControllerConfig):
    """One two-input RuleBase (y0 = ||x||, y_k = s_k) per fuzzy task axis."""
    f = config.fuzzy
    delta0, deltas = f.deltas()
    widths = f.dead_zone_half_widths or [None] * len(f.axes)
    return [
        RuleBase(
            m=f.order,
            upsilon=f.upsilon,
            delta0=delta0,
            deltak=dk,
            dead_zone_half_width=w,
        )
        for dk, w in zip(deltas, widths)
    ]


@TemplateSystem.define("HybridController_", T_list=[float, AutoDiffXd])
def HybridController_(T):

    class Impl(LeafSystem_[T]):
        """Adaptive fuzzy hybrid position/force control law in task space
        (the tool point's world x, y, z), mapped to joint torques by the
        controller's own model of the robot.

        With the chamfer state (x_p, xdot_p, n1, ||f_n||) and the measured
        force f:

        - delta_d' = k_delta (||f_nd hat|| - ||f_n||)            (7), (13)
        - x_pd = x_c* + delta_d n1,  xdot_pd = xdot_c* + delta_d' n1   (9)
          (the delta_d dn1/dt term, about 1e-5 of the feed, is left out)
        - e = x_pd - x_p,  s = edot + lambda e                    (10)
        - f_tau = K s - f + zeta u_f + (1 - zeta) H_bar          (36), (37)
          on the fuzzy axes (u_f of (30) with y0 = ||x_p||, y_k = s_k, R8;
          H_bar_k = h_bar_k sat(s_k / phi_k), R10); K s - f on the others
          (R9)
        - tau = J_v^T f_tau + J_w^T K_o s_o - tau_g(q): tool orientation by
          a PD on s_o = lambda_o e_o - omega (e_o the rotation vector of
          R_d R^T, R_d = ``desired_rotation``, identity by default); tau_g
          from the controller's model (masses scaled by
          ``model_mass_scale``: deliberately imperfect). With 5 joints J_w^T
          passes two of the three orientation axes, with 6 all three; with
          more than 6 (and a ``posture``) tau also gets (I - J^T J^T+)
          (k_n (q_posture - q) - d_n v), a posture PD in J's null space.
        - theta_k' = r nu_k(y0, s_k) s_Delta,k on the (m+1)^2 active rules
          (35), with the dead zone of R4.

        ``config.kind`` replaces the law f_tau and keeps the rest (ports,
        states, e, s, the Jacobian mapping, the orientation PD, the gravity
        compensation, the sampled hold):

        - ``robust`` (22): K s - f + H(||x_p||, s_k) on the fuzzy axes,
          H = (b1 + b2 ||x|| + b3 ||x||^2) sgn(s_k) + (b4 + b5 ||x||) s_k.
        - ``ideal`` (12): K s - f, plus in joint space the true model
          (``true_plant``: its own M, C, gravity, friction and damping)
          M vdot_r + C v - tau_g - tau_friction by Drake's inverse dynamics,
          J vdot_r + Jdot v = [-lambda_o omega; lambda edot] (xddot_d = 0
          between the hold's samples), least squares; its own gravity
          replaces the model's.
        - ``impedance`` (ref. [2]): x_pd = x_c* + delta* n1 (delta* =
          ``nominal_depth``, fixed), f_tau = n1 (k e_n + d edot_n) +
          (I - n1 n1^T) K s; no force feedback, no estimate.
        - ``position``: the same x_pd, f_tau = K_p s, no force feedback.

        theta is not adapted except by ``fuzzy``; delta_d is fixed at
        delta* by the constant-feed kinds (impedance, position).

        .. pydrake_system::

            name: HybridController
            input_ports:
            - plant_state
            - chamfer_state
            - tool_force
            - commanded_position
            - commanded_velocity
            - desired_normal_force
            - fuzzy_weight (optional)
            output_ports:
            - actuation
            - diagnostics

        - ``plant_state`` (nq + nv): joint positions and velocities.
        - ``chamfer_state`` (CHAMFER_STATE layout, from ChamferObserver).
        - ``tool_force`` (3, N): measured force on the tool, world.
        - ``commanded_position`` (3, m), ``commanded_velocity`` (3, m/s):
          x_c*(t) and its derivative from the first-order hold.
        - ``desired_normal_force`` (1, N): ||f_nd hat|| from the estimator.
        - ``fuzzy_weight`` (1; only with ``fuzzy_weight_input=True``): w
          scales the fuzzy compensator's u_f and its adaptation rates
          (35); theta is not adapted while w <= 0 (touch probing: the
          travel between touches is not the cutting the rules learn; after
          it w ramps in, so weights learned on an earlier part do not push
          the tool along before the cut is established).
        - ``actuation`` (nu, N or N m): actuator efforts.
        - ``diagnostics`` (CONTROLLER_DIAGNOSTICS layout).
        - Continuous state: delta_d (m), then theta_k ((2 Upsilon + 1)^2
          values, N) for each fuzzy axis, row-major in (i, j).
        - With ``control_period`` T > 0 the law runs as the paper's digital
          inner loop: at t = kT (and at initialization) it is evaluated once
          from the inputs and a discrete state holds the actuation, the
          diagnostics and the rates of delta_d and theta until the next
          sample, so the continuous states integrate the sampled rates
          exactly (theta((k+1)T) = theta(kT) + T theta'(kT)). With T = 0
          everything is continuous in time (for linearization).
        - ``tool_point`` (optional, float only): a ToolPoint of the tool
          frame on ``plant`` whose kinematics and gravity forces the law
          reuses (e.g. shared with the observer, which has evaluated them at
          the same state); the AutoDiffXd system computes its own.
        """

        def _construct(
            self,
            plant,
            tool_frame_name,
            config,
            desired_rotation=None,
            converter=None,
            *,
            tool_point=None,
            nominal_depth=None,
            true_plant=None,
            posture=None,
            fuzzy_weight_input=False,
        ):
            LeafSystem_[T].__init__(self, converter)
            self._fuzzy_weight_input = fuzzy_weight_input
            config.validate()
            if (
                config.kind in config.CONSTANT_FEED_KINDS
                and nominal_depth is None
            ):
                raise ValueError(
                    f"controller.kind = {config.kind!r} needs "
                    "nominal_depth (the desired depth, m)"
                )
            if config.kind == "ideal" and true_plant is None:
                raise ValueError(
                    "controller.kind = 'ideal' needs "
                    "true_plant (the plant's own model)"
                )
            self._nominal_depth = nominal_depth
            self._float_true_plant = true_plant
            if true_plant is not None:
                self._true_plant = (
                    true_plant if T is float else true_plant.ToAutoDiffXd()
                )
                self._true_context = self._true_plant.CreateDefaultContext()
                self._true_frame = self._true_plant.GetFrameByName(
                    tool_frame_name
                )
                self._true_forces = MultibodyForces_[T](self._true_plant)
            self.set_name("controller")
            if tool_point is not None and (
                tool_point.frame.name() != tool_frame_name
                or tool_point.frame.GetParentPlant() is not plant
            ):
                raise ValueError(
                    f"tool_point must be of {tool_frame_name!r} on the "
                    "controller's plant"
                )
            # Shared kinematics serve the float law; AutoDiffXd has its own.
            self._tool_point = tool_point if T is float else None
            self._float_plant = plant
            self._plant = plant if T is float else plant.ToAutoDiffXd()
            self._plant_context = self._plant.CreateDefaultContext()
            for i in range(1, self._plant.num_bodies()):
                body = self._plant.get_body(BodyIndex(i))
                body.SetMass(
                    self._plant_context,
                    config.model_mass_scale * body.default_mass(),
                )
            self._tool_frame_name = tool_frame_name
            self._frame = self._plant.GetFrameByName(tool_frame_name)
            self._world = self._plant.world_frame()
            self._config = config
            self._rule_bases = make_rule_bases(config)
            # fuzzy.max_slope 0 is "designed" (the diagram builder writes
            # the design, deburr_drake.cell.gains.resolve_slope_bound); a
            # controller built from a configuration nobody designed bounds
            # nothing.
            self._max_slope = (
                float(config.fuzzy.max_slope)
                if config.fuzzy.max_slope > 0
                else math.inf
            )
            self._axes = list(config.fuzzy.axes)
            self._n_rules = self._rule_bases[0].n_rules
            self._nq = plant.num_positions()
            self._B_T = plant.MakeActuationMatrix().T  # nu x nv
            self._lambda = np.asarray(config.sliding_lambda, float)
            self._K = np.asarray(config.sliding_gain, float)
            self._K_position = np.asarray(config.position.sliding_gain, float)
            self._desired_rotation = (
                np.eye(3)
                if desired_rotation is None
                else np.asarray(desired_rotation, float)
            )
            self._lambda_o = np.asarray(config.orientation_lambda, float)
            self._K_o = np.asarray(config.orientation_gain, float)
            self._orientation_control = bool(np.any(self._K_o > 0))
            # Redundant arms only: nothing else holds J's null space.
            self._posture = (
                None
                if posture is None or plant.num_velocities() <= 6
                else np.asarray(posture, float)
            )
            n_theta = len(self._axes) * self._n_rules
            self.DeclareContinuousState(1 + n_theta)
            nx = plant.num_multibody_states()
            self._ports = {
                name: self.DeclareVectorInputPort(name, size)
                for name, size in [
                    ("plant_state", nx),
                    ("chamfer_state", CHAMFER_STATE.size),
                    ("tool_force", 3),
                    ("commanded_position", 3),
                    ("commanded_velocity", 3),
                    ("desired_normal_force", 1),
                ]
                + ([("fuzzy_weight", 1)] if fuzzy_weight_input else [])
            }
            self._cache = self.DeclareCacheEntry(
                "control_terms",
                ValueProducer(
                    allocate=AbstractValue.Make(dict()).Clone,
                    calc=self._calc_terms,
                ),
                prerequisites_of_calc={self.all_sources_ticket()},
            )
            nu = plant.num_actuators()
            sizes = dict(
                zip(
                    _LAW_OUTPUTS, (nu, 1 + n_theta, CONTROLLER_DIAGNOSTICS.size)
                )
            )
            # name -> discrete state group holding it (sampled mode only)
            self._held = {}
            if config.control_period > 0:
                self._held = {
                    name: self.DeclareDiscreteState(BasicVector_[T](size))
                    for name, size in sizes.items()
                }
                self.DeclareInitializationDiscreteUpdateEvent(self._sample)
                self.DeclarePeriodicDiscreteUpdateEvent(
                    config.control_period, 0.0, self._sample
                )
                for name in ("actuation", "diagnostics"):
                    self.DeclareStateOutputPort(name, self._held[name])
            else:
                deps = {self._cache.ticket()}
                self.DeclareVectorOutputPort(
                    "actuation",
                    BasicVector_[T](nu),
                    self._calc_actuation,
                    prerequisites_of_calc=deps,
                )
                self.DeclareVectorOutputPort(
                    "diagnostics",
                    BasicVector_[T](sizes["diagnostics"]),
                    self._calc_diagnostics,
                    prerequisites_of_calc=deps,
                )

        def _construct_copy(self, other, converter=None):
            Impl._construct(
                self,
                other._float_plant,
                other._tool_frame_name,
                other._config,
                other._desired_rotation,
                converter=converter,
                nominal_depth=other._nominal_depth,
                true_plant=other._float_true_plant,
                posture=other._posture,
                fuzzy_weight_input=other._fuzzy_weight_input,
            )

        @property
        def rule_bases(self):
            return self._rule_bases

        @property
        def config(self):
            return self._config

        def theta(self, context):
            """(n_fuzzy_axes, (2 Upsilon + 1)^2) array of the rule weights."""
            x = context.get_continuous_state_vector().CopyToVector()
            return x[1:].reshape(len(self._axes), self._n_rules)

        def depth_reference(self, context):
            """delta_d (m)."""
            return context.get_continuous_state_vector()[0]

        def _calc_terms(self, context, value):
            value.set_value(dict(zip(_LAW_OUTPUTS, self._law(context))))

        def _law(self, context):
            """(actuation, derivatives, diagnostics) at ``context``."""
            c = self._config
            x = context.get_continuous_state_vector().CopyToVector()
            delta_d = x[0]
            theta = x[1:].reshape(len(self._axes), self._n_rules)
            p = {k: port.Eval(context) for k, port in self._ports.items()}
            chamfer = p["chamfer_state"]
            x_p = CHAMFER_STATE.get(chamfer, "x_p")
            xdot_p = CHAMFER_STATE.get(chamfer, "xdot_p")
            n1 = CHAMFER_STATE.get(chamfer, "n1")
            f_n = CHAMFER_STATE.get(chamfer, "f_n")
            f = p["tool_force"]

            e_f = p["desired_normal_force"][0] - f_n
            # [delta_d', theta'] with theta' zero off the active rules.
            derivatives = np.zeros_like(x)
            if c.kind in c.CONSTANT_FEED_KINDS:
                # The nominal path at the desired depth: no depth law.
                delta_d = self._nominal_depth + 0.0 * x[0]
                delta_d_dot = 0.0 * x[0]
            else:
                delta_d_dot = c.depth_gain * e_f
                derivatives[0] = delta_d_dot
            # d/dt (delta_d n1(x_p)): n1 turns with the edge's curvature;
            # without delta_d n1' the reference velocity runs delta/rho
            # slower than the reference on a circle (a steady edot).
            x_pd = p["commanded_position"] + delta_d * n1
            xdot_pd = (
                p["commanded_velocity"]
                + delta_d_dot * n1
                + delta_d * CHAMFER_STATE.get(chamfer, "n1_rate")
            )
            e = x_pd - x_p
            edot = xdot_pd - xdot_p
            s = edot + self._lambda * e

            u_fuzzy = np.zeros(3, dtype=x.dtype)
            zeta = np.zeros(3)
            if c.kind == "impedance":
                im = c.impedance
                f_tau = impedance_force(
                    e,
                    edot,
                    n1,
                    s,
                    stiffness=im.stiffness,
                    damping=im.damping,
                    gain=self._K,
                )
            elif c.kind == "position":
                f_tau = self._K_position * s
            else:
                f_tau = self._K * s - f
                y0 = np.sqrt(x_p @ x_p)
                if c.kind == "fuzzy":
                    self._fuzzy(theta, y0, s, u_fuzzy, zeta, derivatives)
                    if "fuzzy_weight" in p:
                        self._weigh_fuzzy(
                            _value(p["fuzzy_weight"][0]),
                            u_fuzzy,
                            zeta,
                            derivatives,
                        )
                elif c.kind == "robust":
                    for axis in self._axes:
                        u_fuzzy[axis] = robust_term(s[axis], y0, c.robust.gains)
                f_tau = f_tau + u_fuzzy

            state = p["plant_state"]
            J, R, tau_g = self._kinematics(state)
            tau = J[3:].T @ f_tau
            omega = J[:3] @ state[self._nq :]
            if self._orientation_control:
                E = self._desired_rotation @ R.T
                # Rotation vector of R_d R^T to first order (exact axis).
                e_o = 0.5 * np.array(
                    [E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]]
                )
                tau = tau + J[:3].T @ (
                    self._K_o * (self._lambda_o * e_o - omega)
                )
            if self._posture is not None:
                tau = tau + self._null_space_posture(state, J)
            if c.kind == "ideal":
                tau = tau + self._true_model_forces(
                    state,
                    J,
                    self._lambda * edot,
                    -self._lambda_o * omega
                    if self._orientation_control
                    else 0.0 * omega,
                )
            elif c.gravity_compensation:
                tau = tau - tau_g
            return (
                self._B_T @ tau,
                derivatives,
                CONTROLLER_DIAGNOSTICS.pack(
                    dtype=x.dtype,
                    x_pd=x_pd,
                    e=e,
                    s=s,
                    delta_d=delta_d,
                    e_f=e_f,
                    f_tau=f_tau,
                    u_fuzzy=u_fuzzy,
                    zeta=zeta,
                ),
            )

        def _fuzzy(self, theta, y0, s, u_fuzzy, zeta, derivatives):
            """(36), (37) on the fuzzy axes: fills u_fuzzy, zeta and the
            theta rates (35) in place."""
            c = self._config
            r = c.fuzzy.adaptation_gain
            n = self._n_rules
            for k, (axis, rb) in enumerate(zip(self._axes, self._rule_bases)):
                s_k = s[axis]
                if rb.in_domain(s_k):
                    u, idx, rate = rb.evaluate_and_rate(theta[k], y0, s_k, r)
                    zeta[axis] = 1.0
                    if c.fuzzy.adapt and len(idx):
                        derivatives[1 + k * n + idx] = rate
                else:
                    u = c.robust_gain[k] * saturation(
                        s_k / c.robust_boundary_layer[k]
                    )
                if c.fuzzy.adapt and self._max_slope < math.inf:
                    derivatives[1 + k * n : 1 + (k + 1) * n] += rb.slope_rate(
                        theta[k], self._max_slope, c.fuzzy.max_slope_rate
                    )
                u_fuzzy[axis] = u

        def _weigh_fuzzy(self, w, u_fuzzy, zeta, derivatives):
            """The ``fuzzy_weight`` input w: the fuzzy compensator's u_f
            scaled by w, and the rates (35) with it: the output the rules
            move is w theta . nu, so its gradient is w nu (at w < 1 the
            unscaled law would keep raising weights that the output uses
            only in part: on a batch's ramps after probing they grew part
            after part); theta frozen while w <= 0."""
            if w <= 0.0:
                derivatives[1:] = 0.0
            elif w < 1.0:
                derivatives[1:] = w * derivatives[1:]
            for axis in self._axes:
                if zeta[axis] == 1.0:
                    u_fuzzy[axis] = w * u_fuzzy[axis]

        def _null_space_posture(self, state, J):
            """(I - J^T J^T+) (k_n (q_posture - q) - d_n v): the posture PD
            that changes no force or moment at the tool frame (the
            projector from float values)."""
            c = self._config
            q, v = state[: self._nq], state[self._nq :]
            J_value = _float_values(J)
            projector = np.eye(J.shape[1]) - J_value.T @ np.linalg.pinv(
                J_value.T
            )
            return projector @ (
                c.null_space_stiffness * (self._posture - q)
                - c.null_space_damping * v
            )

        def _true_model_forces(self, state, J, a_r, alpha_r):
            """M vdot_r + C v - tau_g - tau_friction of the true plant (its
            force elements: joint friction; its joint damping), with vdot_r
            the least-squares solution of J vdot_r = [alpha_r; a_r] - Jdot v
            (the pseudo-inverse from float values)."""
            plant, ctx = self._true_plant, self._true_context
            plant.SetPositionsAndVelocities(ctx, state)
            bias = plant.CalcBiasSpatialAcceleration(
                ctx,
                JacobianWrtVariable.kV,
                self._true_frame,
                np.zeros(3),
                plant.world_frame(),
                plant.world_frame(),
            )
            target = np.concatenate(
                [alpha_r - bias.rotational(), a_r - bias.translational()]
            )
            J_value = _float_values(J)
            vdot_r = np.linalg.pinv(J_value) @ target
            plant.CalcForceElementsContribution(ctx, self._true_forces)
            return plant.CalcInverseDynamics(ctx, vdot_r, self._true_forces)

        def _kinematics(self, state):
            """(J, R, tau_g) of the controller's model at ``state``: the tool
            frame's spatial Jacobian (rows angular, translational) and
            orientation in world, and the gravity forces with the model's
            masses."""
            if self._tool_point is not None:
                J, R, tau_g = self._tool_point.control_terms(state)
                # Every mass scaled alike: tau_g scales with them.
                return J, R, self._config.model_mass_scale * tau_g
            plant, ctx = self._plant, self._plant_context
            plant.SetPositionsAndVelocities(ctx, state)
            J = plant.CalcJacobianSpatialVelocity(
                ctx,
                JacobianWrtVariable.kV,
                self._frame,
                np.zeros(3),
                self._world,
                self._world,
            )
            R = self._frame.CalcPoseInWorld(ctx).rotation().matrix()
            return J, R, plant.CalcGravityGeneralizedForces(ctx)

        def _sample(self, context, discrete_state):
            # Once per sample, at the sample's inputs: no cache needed.
            for name, value in zip(_LAW_OUTPUTS, self._law(context)):
                discrete_state.set_value(self._held[name], value)

        def DoCalcTimeDerivatives(self, context, derivatives):
            if self._held:
                rates = context.get_discrete_state(
                    self._held["derivatives"]
                ).get_value()
            else:
                rates = self._cache.Eval(context)["derivatives"]
            derivatives.get_mutable_vector().SetFromVector(rates)

        def _calc_actuation(self, context, output):
            output.SetFromVector(self._cache.Eval(context)["actuation"])

        def _calc_diagnostics(self, context, output):
            output.SetFromVector(self._cache.Eval(context)["diagnostics"])

    return Impl


HybridController = HybridController_[None]
