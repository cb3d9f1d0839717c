"""A region of attraction of the normal-force axis with the nonlinear
contact, by sums of squares on a reduced polynomial model.

- :func:`normal_axis_model`: the reduced model of
  :mod:`deburr_drake.math.region` at an operating point, every number read
  from the run's plan and Context (the task inertia along n1, K, lambda,
  k_delta, the sensor's filter, the desired normal force, the frozen fuzzy
  surface along n1) and the contact law measured on the cell's own part
  (:func:`deburr_drake.cell.truth.contact_normal_force`).
- :func:`diagram_response`: the full Diagram's response to a change of the
  depth reference (the frozen scenario: adaptation off, noise off), read
  as the reduced state, to validate the model against.
- :func:`sublevel_certificate`: the largest rho, by bisection, such that a
  quadratic V decreases by eps |x|^2 under every region's polynomial map
  on {V <= rho} intersected with the region (the S-procedure per region,
  ``NewSosPolynomial`` multipliers, a free solver of Drake's wheel), then
  checked on sample points of the sublevel set (:func:`check_sublevel`).
- :func:`normal_axis_region`: the three together at an operating point.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import time
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np
from pydrake.solvers import (
    ClarabelSolver,
    CsdpSolver,
    MathematicalProgram,
    ScsSolver,
)
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.symbolic import Expression, Polynomial, Variables

from deburr_drake.analysis.operating_point import OperatingPoint
from deburr_drake.analysis.sampled import frozen_cell
from deburr_drake.cell.truth import contact_normal_force
from deburr_drake.control.laws import TaskTerms
from deburr_drake.control.layout import CHAMFER_STATE
from deburr_drake.math.region import (
    STATE_NAMES,
    NormalAxisModel,
    fit_contact_law,
    piecewise_quadratic,
)
from deburr_drake.runs.simulation import make_simulator

__all__ = [
    "SOLVERS",
    "Region",
    "SublevelResult",
    "normal_axis_model",
    "reduced_state",
    "diagram_response",
    "sublevel_certificate",
    "check_sublevel",
    "normal_axis_pieces",
    "STATE_SCALES",
]

#: The free semidefinite solvers of Drake's wheel.
SOLVERS = {"Clarabel": ClarabelSolver, "SCS": ScsSolver, "CSDP": CsdpSolver}

#: The reduced state's scales (m, m/s, N, m): the program works on x / scale.
STATE_SCALES = np.array([1e-4, 1e-2, 1.0, 1e-4])


def _eval(system, context, port):
    return system.GetOutputPort(port).Eval(system.GetMyContextFromRoot(context))


def reduced_state(diagram, context) -> np.ndarray:
    """[delta, delta', y, delta_d] of the full Diagram's Context: the
    chamfer state's depth and rate, its (filtered) normal force and the
    controller's depth reference."""
    observer = diagram.GetSubsystemByName("chamfer_observer")
    chamfer = _eval(observer, context, "chamfer_state")
    controller = diagram.GetSubsystemByName("controller")
    ref = controller.depth_reference(controller.GetMyContextFromRoot(context))
    return np.array(
        [
            float(CHAMFER_STATE.get(chamfer, "delta")),
            float(CHAMFER_STATE.get(chamfer, "delta_dot")),
            float(CHAMFER_STATE.get(chamfer, "f_n")),
            float(ref),
        ]
    )


def _joint_terms(diagram, context, n1, robot):
    """(M_n, c, phi, phi's largest slope) along n1 at the tool point:
    M_n = 1 / (n1^T J M^-1 J^T n1) (kg), the inertia a force along n1
    meets, the other directions free; the joint velocities of a tool
    velocity v along n1, v Jbar with Jbar = M^-1 J^T n1 M_n (the
    dynamically consistent inverse); the joints' viscous damping along
    n1, c = Jbar^T D Jbar (N s/m); and the change of their friction
    F_c tanh(qdot / v_s) from the operating point's, along n1."""
    plant = diagram.GetSubsystemByName("plant")
    pc = plant.GetMyContextFromRoot(context)
    frame = plant.GetFrameByName(_tool_frame(diagram))
    J = plant.CalcJacobianTranslationalVelocity(
        pc,
        JacobianWrtVariable.kV,
        frame,
        np.zeros(3),
        plant.world_frame(),
        plant.world_frame(),
    )
    M = plant.CalcMassMatrix(pc)
    Minv_Jt_n = np.linalg.solve(M, J.T @ n1)
    mass = float(1.0 / (n1 @ J @ Minv_Jt_n))
    jbar = Minv_Jt_n * mass
    damping = np.zeros(plant.num_velocities())
    for i in plant.GetJointIndices():
        joint = plant.get_joint(i)
        if joint.num_velocities() == 1:
            damping[joint.velocity_start()] = joint.default_damping()
    qdot = plant.GetVelocities(pc)
    coulomb = np.asarray(robot.joint_coulomb_friction or [], float)
    v_s = robot.friction_smoothing_speed
    if len(coulomb) == 0:
        coulomb = np.zeros(len(qdot))
    if len(coulomb) != len(qdot):
        coulomb = np.zeros(len(qdot))

    def friction(v):
        return float(
            jbar
            @ (
                coulomb
                * (np.tanh((qdot + v * jbar) / v_s) - np.tanh(qdot / v_s))
            )
        )

    slope = float(jbar @ (coulomb / v_s * jbar))
    return mass, float(jbar @ (damping * jbar)), friction, slope


def _tool_frame(diagram) -> str:
    return diagram.GetSubsystemByName("controller")._arguments[
        "tool_frame_name"
    ]


def _compensator_along(controller, cc, s_op, n1, x_p):
    """u(s_n) = n1 . u_f(s_op + (s_n - n1 . s_op) n1): the law's own
    compensator (rule weights frozen) along n1, and its breakpoints."""
    law = controller.law
    theta = controller.theta(cc)
    n_state = cc.num_continuous_states()
    s_n_op = float(n1 @ s_op)

    def u_along(s_n):
        s = s_op + (s_n - s_n_op) * n1
        terms = TaskTerms(
            x_p=x_p,
            n1=n1,
            f=np.zeros(3),
            e=np.zeros(3),
            edot=np.zeros(3),
            s=s,
            theta=theta,
            fuzzy_weight=None,
            K=np.zeros(3),
        )
        u, _ = law.compensator(terms, np.zeros(n_state))
        return float(n1 @ u)

    config = controller.config
    breaks = []
    for k, (axis, rb) in enumerate(
        zip(config.fuzzy.axes, controller.rule_bases)
    ):
        if abs(n1[axis]) < 1e-9:
            continue
        dk, U = rb.omegak_half_width / rb.upsilon, rb.upsilon
        knots = (np.arange(-U - 1, U + 1) + 0.5 + 0.5 * (rb.m % 2)) * dk
        knots = np.concatenate(
            [
                knots[np.abs(knots) <= U * dk],
                [-U * dk, U * dk],
                [
                    -config.robust_boundary_layer[k],
                    config.robust_boundary_layer[k],
                ],
            ]
        )
        breaks += list(s_n_op + (knots - s_op[axis]) / n1[axis])
    return u_along, breaks


def normal_axis_model(
    op: OperatingPoint,
    *,
    degree: int = 2,
    max_depth: Optional[float] = None,
    n_depths: int = 41,
) -> tuple[NormalAxisModel, Dict[str, float]]:
    """The reduced model at ``op`` (:mod:`deburr_drake.math.region`), the
    contact law fitted by a polynomial of ``degree`` on [0, ``max_depth``]
    (default twice the operating depth) from ``n_depths`` measured depths,
    and what it was read from."""
    scenario, diagram, context = op.scenario, op.diagram, op.context
    observer = diagram.GetSubsystemByName("chamfer_observer")
    chamfer = _eval(observer, context, "chamfer_state")
    controller = diagram.GetSubsystemByName("controller")
    cc = controller.GetMyContextFromRoot(context)
    n1 = np.asarray(CHAMFER_STATE.get(chamfer, "n1"), float)
    x_p = np.asarray(CHAMFER_STATE.get(chamfer, "x_p"), float)
    diagnostics = controller.GetOutputPort("diagnostics").Eval(cc)
    from deburr_drake.control.layout import CONTROLLER_DIAGNOSTICS

    s_op = np.asarray(CONTROLLER_DIAGNOSTICS.get(diagnostics, "s"), float)
    f_d = float(controller.GetInputPort("desired_normal_force").Eval(cc)[0])
    K, _ = controller.gains(cc)
    c = scenario.controller
    # The contact law measured on the cell's part; the anchor where it
    # gives the desired force (the depth the depth law settles at).
    depth_op = float(CHAMFER_STATE.get(chamfer, "delta"))
    top = max_depth or 2.0 * depth_op
    depths = np.linspace(0.0, top, n_depths)
    c0 = scenario.process.contact_threshold_force
    # The law measured at the middle of the edge, scaled to the force the
    # run reads at its own depth and place (the tool's height and tilt
    # there differ from the measurement's).
    measured = contact_normal_force(scenario, depths)
    f_op = float(CHAMFER_STATE.get(chamfer, "f_n"))
    calibration = (f_op - c0) / float(np.interp(depth_op, depths, measured))
    forces = calibration * measured
    anchor = float(np.interp(f_d - c0, forces, depths))
    fit = fit_contact_law(
        depths, forces, degree=degree, anchor=anchor, anchor_force=f_d - c0
    )
    u_along, breaks = _compensator_along(controller, cc, s_op, n1, x_p)
    compensator = piecewise_quadratic(u_along, breaks, tolerance=1e-7)
    K_n = float(n1 @ (np.asarray(K) * n1))
    s_n = float(n1 @ s_op)
    alpha = 1.0 - np.exp(
        -2
        * np.pi
        * scenario.sensor.cutoff_frequency
        * scenario.sensor.sample_period
    )
    mass, damping, friction, slope = _joint_terms(
        diagram, context, n1, scenario.robot
    )
    model = NormalAxisModel(
        mass=mass,
        damping=damping,
        friction=friction,
        friction_slope=slope,
        sliding_gain=K_n,
        sliding_lambda=float(n1 @ (np.asarray(c.sliding_lambda) * n1)),
        depth_gain=c.depth_gain,
        sensor_alpha=float(alpha),
        period=c.control_period,
        desired_force=f_d,
        disturbance=-(K_n * s_n + compensator(s_n)),
        threshold_force=c0,
        threshold_depth=scenario.process.threshold_depth,
        contact=fit,
        compensator=compensator,
    )
    info = {
        "time_s": op.time,
        "n1": n1.tolist(),
        "task_inertia_kg": model.mass,
        "sliding_gain_n_s_per_m": K_n,
        "sliding_variable_m_per_s": s_n,
        "desired_normal_force_n": f_d,
        "operating_depth_m": depth_op,
        "anchor_depth_m": anchor,
        "contact_calibration": calibration,
        "joint_damping_n_s_per_m": damping,
        "friction_slope_n_s_per_m": slope,
        "compensator_cells": compensator.n_cells,
    }
    return model, info


def diagram_response(
    op: OperatingPoint,
    *,
    reference_step: float,
    duration: float,
) -> np.ndarray:
    """(steps + 1, 4) reduced states of the full Diagram (the frozen
    scenario: adaptation and noise off) from ``op``'s state with the depth
    reference moved by ``reference_step`` (m), one row per control
    period."""
    diagram, context, _ = frozen_cell(op, {})
    controller = diagram.GetSubsystemByName("controller")
    cc = controller.GetMyMutableContextFromRoot(context)
    x = cc.get_mutable_continuous_state_vector()
    x.SetAtIndex(0, x.GetAtIndex(0) + reference_step)
    simulator = make_simulator(diagram, op.scenario)
    simulator.reset_context(context)
    simulator.Initialize()
    period = op.scenario.controller.control_period
    steps = int(round(duration / period))
    t0 = context.get_time()
    out = [reduced_state(diagram, simulator.get_context())]
    for k in range(1, steps + 1):
        simulator.AdvanceTo(t0 + k * period)
        out.append(reduced_state(diagram, simulator.get_context()))
    return np.array(out)
