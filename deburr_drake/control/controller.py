"""HybridController: the inner-loop adaptive fuzzy hybrid position/force
controller, eqs. (7), (9)-(11), (30), (35)-(37) with R4, R8, R9, R10, and
the shell that every baseline law of :mod:`deburr_drake.control.laws`
shares.

Use: ``HybridController(plant, "tool_tip", scenario.controller)`` is an
ordinary LeafSystem (float and AutoDiffXd); its input and output ports are
in the class docstring.
:func:`deburr_drake.control.loop.add_deburring_controller` adds it together
with the systems that feed it."""

from __future__ import annotations

import sys

import numpy as np
from pydrake.autodiffutils import AutoDiffXd
from pydrake.common.value import AbstractValue
from pydrake.multibody.tree import BodyIndex, JacobianWrtVariable
from pydrake.systems.framework import BasicVector_, LeafSystem_, ValueProducer
from pydrake.systems.scalar_conversion import TemplateSystem

from deburr_drake.config import ControllerConfig
from deburr_drake.control.laws import (
    LawSetting,
    TaskTerms,
    float_values,
    make_law,
    saturation,
)
from deburr_drake.control.layout import CHAMFER_STATE, CONTROLLER_DIAGNOSTICS
from deburr_drake.math.fuzzy import RuleBase

__all__ = [
    "HybridController",
    "HybridController_",
    "make_rule_bases",
    "saturation",
]


#: What HybridController evaluates once per sample, in order.
_TERMS = ("actuation", "derivatives", "diagnostics")


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


# scope: the module by name; pydrake otherwise finds it by inspecting the
# whole call stack, source lines included, at import.
@TemplateSystem.define(
    "HybridController_",
    T_list=[float, AutoDiffXd],
    scope=sys.modules[__name__],
)
def HybridController_(T):

    class Impl(LeafSystem_[T]):
        """Hybrid position/force control in task space (the tool point's
        world x, y, z), mapped to joint torques by the controller's own
        model of the robot. ``config.kind`` chooses the law
        (:data:`deburr_drake.control.laws.LAWS`) once, here; the law gives
        the depth reference, the task-space force f_tau and the
        joint-space model terms, the rest is shared.

        With the chamfer state (x_p, xdot_p, n1, n1', ||f_n||) and the
        measured force f:

        - delta_d' = k_delta (||f_nd hat|| - ||f_n||)            (7), (13)
          (the constant-feed laws: delta_d = delta*, ``nominal_depth``)
        - x_pd = x_c* + delta_d n1,
          xdot_pd = xdot_c* + delta_d' n1 + delta_d n1'           (9)
        - e = x_pd - x_p,  s = edot + lambda e                    (10)
        - f_tau from the law; the paper's (``fuzzy``):
          f_tau = K s - f + zeta u_f + (1 - zeta) H_bar          (36), (37)
          on the fuzzy axes (u_f of (30) with y0 = ||x_p||, y_k = s_k, R8;
          H_bar_k = h_bar_k sat(s_k / phi_k), R10); K s - f on the others
          (R9); theta_k' = r nu_k(y0, s_k) s_Delta,k on the (m+1)^2
          active rules (35), with the dead zone of R4.
        - tau = J_v^T f_tau + J_w^T K_o s_o + the law's model terms
          (-tau_g(q) of the controller's model, masses scaled by
          ``model_mass_scale``: deliberately imperfect; the ideal law: the
          true model's inverse dynamics). s_o = lambda_o e_o - omega, e_o
          the rotation vector of R_d R^T, R_d = ``desired_rotation``
          (identity by default; along a ``contour`` whose frame turns,
          ``contour.axis_turn(s) @ desired_rotation`` at the tool point's
          arc position s). With 5 joints J_w^T passes two of the
          three orientation axes, with 6 all three; with more than 6 (and
          a ``posture``) tau also gets (I - J^T J^T+) (k_n (q_posture - q)
          - d_n v), a posture PD in J's null space.

        .. pydrake_system::

            name: HybridController
            input_ports:
            - plant_state
            - chamfer_state
            - measured_force
            - commanded_position
            - commanded_velocity
            - desired_normal_force
            - fuzzy_weight (optional)
            - active (optional)
            output_ports:
            - actuation
            - diagnostics

        - ``plant_state`` (nq + nv): joint positions and velocities.
        - ``chamfer_state`` (CHAMFER_STATE layout, from ChamferObserver).
        - ``measured_force`` (3, N): the force sensor's reading of the
          force on the tool, world.
        - ``commanded_position`` (3, m), ``commanded_velocity`` (3, m/s):
          x_c*(t) and its derivative from the first-order hold.
        - ``desired_normal_force`` (1, N): ||f_nd hat|| from the estimator.
        - ``fuzzy_weight`` (1; only with ``fuzzy_weight_input=True``): w
          scales the fuzzy compensator's u_f and its adaptation rates
          (35); theta is not adapted while w <= 0 (touch probing: the
          travel between touches is not the cutting the rules learn; after
          it w ramps in, so weights learned on an earlier part do not push
          the tool along before the cut is established).
        - ``active`` (1; only with ``active_input=True``): while <= 0.5
          every state is held (delta_d, theta, the integral): a job's
          moves, where another loop drives the arm and the law's errors
          mean nothing.
        - ``actuation`` (nu, N or N m): actuator efforts.
        - ``diagnostics`` (CONTROLLER_DIAGNOSTICS layout).
        - Continuous state: delta_d (m), then theta_k ((2 Upsilon + 1)^2
          values, N) for each fuzzy axis, row-major in (i, j). Every law
          has them; only ``fuzzy`` adapts theta, and the constant-feed
          laws leave delta_d alone; then int s_k dt (m) on each axis k
          with ``integral_lambda`` > 0 (f_tau_k + K_k lambda_I,k int s_k,
          after the law's f_tau); when ``contour.varying_frame``, instead
          three states, the integral's force as a world vector (N).
        - With ``control_period`` T > 0 the law runs as the paper's digital
          inner loop: at t = kT (and at initialization) it is evaluated once
          from the inputs and a discrete state holds the actuation, the
          diagnostics and the rates of delta_d and theta until the next
          sample, so the continuous states integrate the sampled rates
          exactly (theta((k+1)T) = theta(kT) + T theta'(kT)). With T = 0
          everything is continuous in time (for linearization).
        - Numeric parameter: [K (3, N s/m), K_o (3, N m s/rad)], from
          ``sliding_gain`` and ``orientation_gain``; :meth:`set_gains`
          changes them in a Context (an orientation gain of zero in the
          configuration leaves the orientation uncontrolled whatever the
          parameter holds).
        - ``tool_point`` (optional, float only): a ToolPoint of the tool
          frame on ``plant`` whose kinematics and gravity forces the law
          reuses (e.g. shared with the observer, which has evaluated them at
          the same state); the AutoDiffXd system computes its own.
        - ``contour`` (optional): the contour the chamfer state is of.
          When ``contour.varying_frame`` (a 3-D edge) the desired
          rotation turns with the tool axis, R_d(s) =
          ``contour.axis_turn(s)`` R_start, s the chamfer state's
          ``arc_position`` (the tool point's: the observer has projected
          it already, where the command's arc position would need a port
          or a projection per sample; it trails the command's by about
          one feed step, a turn of the axis far below the orientation
          loop's lag). Otherwise R_d is ``desired_rotation`` throughout.
        - Task axes: the law's x1, x2, x3 (the fuzzy axes, K, lambda and
          the integral per axis) are the world's on a planar contour (the
          tool vertical). When ``contour.varying_frame`` they are
          ``contour.task_frame(s)`` (columns, world; x3 the tool axis,
          turning with R_d): e, edot, f and n1 are rotated onto them, f_tau
          back, so the stiff, integrating x3 stays along the tool however
          it is tilted, and the fuzzy terms act across it. ``diagnostics``
          e, s, f_tau, u_fuzzy and zeta are on the task axes, x_pd world.
        - ``nominal_depth`` (m): delta* of the constant-feed laws;
          ``true_plant``: the plant's own model, for the ideal law.
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
            contour=None,
            active_input=False,
        ):
            LeafSystem_[T].__init__(self, converter)
            config.validate()
            self.set_name("controller")
            self._config = config
            # What the scalar-converted copy is built from (the AutoDiffXd
            # system computes its own kinematics: no tool_point).
            self._arguments = dict(
                plant=plant,
                tool_frame_name=tool_frame_name,
                config=config,
                desired_rotation=desired_rotation,
                nominal_depth=nominal_depth,
                true_plant=true_plant,
                posture=posture,
                fuzzy_weight_input=fuzzy_weight_input,
                contour=contour,
                active_input=active_input,
            )
            # The controller's model of the robot.
            self._set_model(plant, tool_frame_name, tool_point)
            # The rule bases shape the state (theta) whatever the law.
            self._rule_bases = make_rule_bases(config)
            self._axes = list(config.fuzzy.axes)
            self._n_rules = self._rule_bases[0].n_rules
            # The law, chosen once.
            self._law = make_law(
                config,
                LawSetting(
                    T=T,
                    rule_bases=self._rule_bases,
                    nominal_depth=nominal_depth,
                    true_plant=true_plant,
                    tool_frame_name=tool_frame_name,
                ),
            )
            # The sliding variables, orientation and posture every law
            # shares.
            self._set_shared_gains(desired_rotation, posture, contour)
            # State [delta_d, theta, int s on the integral axes], the
            # inputs, the outputs.
            self._n_theta = len(self._axes) * self._n_rules
            n_states = 1 + self._n_theta + self._n_integral
            self.DeclareContinuousState(n_states)
            self._ports = self._declare_inputs(fuzzy_weight_input, active_input)
            self._declare_outputs(n_states)

        def _construct_copy(self, other, converter=None):
            Impl._construct(self, converter=converter, **other._arguments)

        def _set_model(self, plant, tool_frame_name, tool_point):
            """``plant`` (for T) with every mass scaled by
            ``model_mass_scale``, its tool frame, and a shared ToolPoint."""
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
            self._plant = plant if T is float else plant.ToAutoDiffXd()
            self._plant_context = self._plant.CreateDefaultContext()
            for i in range(1, self._plant.num_bodies()):
                body = self._plant.get_body(BodyIndex(i))
                body.SetMass(
                    self._plant_context,
                    self._config.model_mass_scale * body.default_mass(),
                )
            self._frame = self._plant.GetFrameByName(tool_frame_name)
            self._world = self._plant.world_frame()
            self._nq = plant.num_positions()
            self._B_T = plant.MakeActuationMatrix().T  # nu x nv

        def _set_shared_gains(self, desired_rotation, posture, contour):
            c = self._config
            self._lambda = np.asarray(c.sliding_lambda, float)
            self._integral_axes = [
                k for k, rate in enumerate(c.integral_lambda) if rate > 0
            ]
            self._integral_lambda = np.asarray(c.integral_lambda, float)[
                self._integral_axes
            ]
            self._desired_rotation = (
                np.eye(3)
                if desired_rotation is None
                else np.asarray(desired_rotation, float)
            )
            # Chosen once: a planar contour's R_d is a constant and its
            # task axes are the world's.
            varying = contour is not None and contour.varying_frame
            # Along a 3-D edge int s is held as a world vector (see
            # _with_integral); on the task axes otherwise.
            self._n_integral = (
                3
                if varying and self._integral_axes
                else len(self._integral_axes)
            )
            self._axis_turn = contour.axis_turn if varying else None
            self._task_frame = contour.task_frame if varying else None
            self._lambda_o = np.asarray(c.orientation_lambda, float)
            K_o = np.asarray(c.orientation_gain, float)
            # Chosen once: a gain of zero leaves the orientation free,
            # whatever the parameter is set to later.
            self._orientation_control = bool(np.any(K_o > 0))
            # K and K_o are numeric parameters: an analysis that varies
            # them changes a Context, not the Diagram.
            self._gains = self.DeclareNumericParameter(
                BasicVector_[T](
                    np.concatenate([np.asarray(c.sliding_gain, float), K_o])
                )
            )
            # Redundant arms only: nothing else holds J's null space.
            self._posture = (
                None
                if posture is None or self._plant.num_velocities() <= 6
                else np.asarray(posture, float)
            )

        def _declare_inputs(self, fuzzy_weight_input, active_input):
            """name -> input port, in the docstring's order."""
            nx = self._plant.num_multibody_states()
            return {
                name: self.DeclareVectorInputPort(name, size)
                for name, size in [
                    ("plant_state", nx),
                    ("chamfer_state", CHAMFER_STATE.size),
                    ("measured_force", 3),
                    ("commanded_position", 3),
                    ("commanded_velocity", 3),
                    ("desired_normal_force", 1),
                ]
                + ([("fuzzy_weight", 1)] if fuzzy_weight_input else [])
                + ([("active", 1)] if active_input else [])
            }

        def _declare_outputs(self, n_states):
            """The terms' cache, and the outputs: held between samples
            (``control_period`` > 0) or computed continuously."""
            self._cache = self.DeclareCacheEntry(
                "control_terms",
                ValueProducer(
                    allocate=AbstractValue.Make(dict()).Clone,
                    calc=self._calc_terms,
                ),
                prerequisites_of_calc={self.all_sources_ticket()},
            )
            nu = self._B_T.shape[0]
            sizes = dict(
                zip(_TERMS, (nu, n_states, CONTROLLER_DIAGNOSTICS.size))
            )
            period = self._config.control_period
            # name -> discrete state group holding it (sampled mode only)
            self._held = {}
            if period > 0:
                self._held = {
                    name: self.DeclareDiscreteState(BasicVector_[T](size))
                    for name, size in sizes.items()
                }
                self.DeclareInitializationDiscreteUpdateEvent(self._sample)
                self.DeclarePeriodicDiscreteUpdateEvent(
                    period, 0.0, self._sample
                )
                for name in ("actuation", "diagnostics"):
                    self.DeclareStateOutputPort(name, self._held[name])
                return
            deps = {self._cache.ticket()}
            for name, calc in (
                ("actuation", self._calc_actuation),
                ("diagnostics", self._calc_diagnostics),
            ):
                self.DeclareVectorOutputPort(
                    name,
                    BasicVector_[T](sizes[name]),
                    calc,
                    prerequisites_of_calc=deps,
                )

        def set_gains(
            self, context, *, sliding_gain=None, orientation_gain=None
        ):
            """K and/or K_o (3 each) in the controller's ``context``."""
            gains = context.get_mutable_numeric_parameter(self._gains)
            value = gains.CopyToVector()
            if sliding_gain is not None:
                value[:3] = sliding_gain
            if orientation_gain is not None:
                value[3:] = orientation_gain
            gains.SetFromVector(value)

        def gains(self, context):
            """(K, K_o) in the controller's ``context``."""
            value = context.get_numeric_parameter(self._gains).CopyToVector()
            return value[:3], value[3:]

        @property
        def rule_bases(self):
            return self._rule_bases

        @property
        def config(self):
            return self._config

        @property
        def law(self):
            """The law ``config.kind`` chose (a laws.ControlLaw)."""
            return self._law

        def theta(self, context):
            """(n_fuzzy_axes, (2 Upsilon + 1)^2) array of the rule weights."""
            x = context.get_continuous_state_vector().CopyToVector()
            return self._theta_of(x)

        def _theta_of(self, x):
            return x[1 : 1 + self._n_theta].reshape(
                len(self._axes), self._n_rules
            )

        def depth_reference(self, context):
            """delta_d (m)."""
            return context.get_continuous_state_vector()[0]

        def _calc_terms(self, context, value):
            value.set_value(dict(zip(_TERMS, self._evaluate(context))))

        def _evaluate(self, context):
            """(actuation, derivatives, diagnostics) at ``context``."""
            x = context.get_continuous_state_vector().CopyToVector()
            p = {k: port.Eval(context) for k, port in self._ports.items()}
            chamfer = p["chamfer_state"]
            x_p = CHAMFER_STATE.get(chamfer, "x_p")
            n1 = CHAMFER_STATE.get(chamfer, "n1")
            e_f = p["desired_normal_force"][0] - CHAMFER_STATE.get(
                chamfer, "f_n"
            )
            # [delta_d', theta'], zero where the law drives nothing.
            rates = np.zeros_like(x)
            # The depth reference: (7), or the constant-feed laws' delta*.
            delta_d, delta_d_dot = self._law.depth_reference(x[0], e_f, rates)
            # (9), (10). n1 turns with the edge's curvature: without the
            # delta_d n1' term x_pd's velocity would lag the reference by
            # delta / rho on a circle (a steady edot).
            x_pd = p["commanded_position"] + delta_d * n1
            xdot_pd = (
                p["commanded_velocity"]
                + delta_d_dot * n1
                + delta_d * CHAMFER_STATE.get(chamfer, "n1_rate")
            )
            e_world = x_pd - x_p
            edot_world = xdot_pd - CHAMFER_STATE.get(chamfer, "xdot_p")
            # The law works on the task axes (x3 along the tool axis).
            to_task = self._task_axes(chamfer)
            e, edot, n1_task, f = (
                (e_world, edot_world, n1, p["measured_force"])
                if to_task is None
                else (
                    to_task.T @ e_world,
                    to_task.T @ edot_world,
                    to_task.T @ n1,
                    to_task.T @ p["measured_force"],
                )
            )
            s = edot + self._lambda * e
            gains = context.get_numeric_parameter(self._gains).CopyToVector()
            K, K_o = gains[:3], gains[3:]
            # The law's task-space force.
            force = self._law.task_force(
                TaskTerms(
                    x_p=x_p,
                    n1=n1_task,
                    f=f,
                    e=e,
                    edot=edot,
                    s=s,
                    theta=self._theta_of(x),
                    fuzzy_weight=p.get("fuzzy_weight"),
                    K=K,
                ),
                rates,
            )
            force = self._with_integral(force, x, s, rates, to_task, K)
            rates *= self._activity(p)
            # Joint torques.
            tau = self._joint_torque(
                p["plant_state"],
                force.f_tau if to_task is None else to_task @ force.f_tau,
                edot_world,
                self._rotation_at(chamfer),
                K_o,
            )
            return (
                self._B_T @ tau,
                rates,
                CONTROLLER_DIAGNOSTICS.pack(
                    dtype=x.dtype,
                    x_pd=x_pd,
                    e=e,
                    s=s,
                    delta_d=delta_d,
                    e_f=e_f,
                    f_tau=force.f_tau,
                    u_fuzzy=force.u_fuzzy,
                    zeta=force.zeta,
                ),
            )

        @staticmethod
        def _activity(p):
            """0 off the part (the ``active`` input 0: a job's moves,
            every state held), else 1."""
            return 0.0 if "active" in p and p["active"][0] < 0.5 else 1.0

        def _with_integral(self, force, x, s, rates, to_task, K):
            """f_tau + K lambda_I int s on the integral axes, whose states
            integrate s.

            With turning task axes (``to_task``, columns world) the states
            are a world force, int R K lambda_I s dt over the integral
            axes' columns of R = ``to_task``, and it acts on every task
            axis: what the integral takes out is a force fixed
            in the world (the model's gravity error), so what it learned
            along the tool axis stays put when the axis turns, and the part
            now across the axis reaches the fuzzy axes at once instead of
            being learned again by their adaptation."""
            axes = self._integral_axes
            if not axes:
                return force
            K_integral = K[axes] * self._integral_lambda
            start = 1 + self._n_theta
            f_tau = force.f_tau.copy()
            if to_task is None:
                rates[start:] = s[axes]
                f_tau[axes] = f_tau[axes] + K_integral * x[start:]
                return force._replace(f_tau=f_tau)
            rates[start:] = to_task[:, axes] @ (K_integral * s[axes])
            f_world = x[start:]
            f_tau = f_tau + to_task.T @ f_world
            return force._replace(f_tau=f_tau)

        @staticmethod
        def _arc_value(chamfer):
            """The chamfer state's arc position as a float (the frames
            from it are constants of the AutoDiffXd law)."""
            s = CHAMFER_STATE.get(chamfer, "arc_position")
            return s.value() if isinstance(s, AutoDiffXd) else float(s)

        def _rotation_at(self, chamfer):
            """R_d where the chamfer state's tool point is."""
            if self._axis_turn is None:
                return self._desired_rotation
            return self._axis_turn(self._arc_value(chamfer)) @ (
                self._desired_rotation
            )

        def _task_axes(self, chamfer):
            """The task axes (columns, world) where the chamfer state's
            tool point is; None: the world's."""
            if self._task_frame is None:
                return None
            return self._task_frame(self._arc_value(chamfer))

        def desired_rotation(self, context):
            """R_d (3 x 3) at the ``chamfer_state`` input's arc
            position."""
            return self._rotation_at(self._ports["chamfer_state"].Eval(context))

        def _joint_torque(self, state, f_tau, edot, desired_rotation, K_o):
            """J_v^T f_tau, the orientation PD towards
            ``desired_rotation``, the null-space posture and the law's
            model terms (nv)."""
            J, R, tau_g = self._kinematics(state)
            tau = J[3:].T @ f_tau
            omega = J[:3] @ state[self._nq :]
            if self._orientation_control:
                E = desired_rotation @ R.T
                # Rotation vector of R_d R^T to first order (exact axis).
                e_o = 0.5 * np.array(
                    [E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]]
                )
                tau = tau + J[:3].T @ (K_o * (self._lambda_o * e_o - omega))
            if self._posture is not None:
                tau = tau + self._null_space_posture(state, J)
            return self._law.model_torque(tau, state, J, tau_g, edot, omega)

        def _null_space_posture(self, state, J):
            """(I - J^T J^T+) (k_n (q_posture - q) - d_n v): the posture PD
            that changes no force or moment at the tool frame (the
            projector from float values)."""
            c = self._config
            q, v = state[: self._nq], state[self._nq :]
            J_value = float_values(J)
            projector = np.eye(J.shape[1]) - J_value.T @ np.linalg.pinv(
                J_value.T
            )
            return projector @ (
                c.null_space_stiffness * (self._posture - q)
                - c.null_space_damping * v
            )

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
            for name, value in zip(_TERMS, self._evaluate(context)):
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
