"""Continuous-time linearization of the closed loop at an operating point,
and the eigenvalues grouped by what they move (paper eqs. (7)-(8): the
depth mode, whose time constant (8) predicts).

The linearized system is the cell in the controller's continuous mode
(``control_period: 0``, :func:`frozen_scenario` with ``continuous=True``)
with the sampled force sensor replaced by its continuous equivalent, the
first-order low-pass y' = 2 pi f_c (raw - y) of the same cutoff, and the
cutting process's force-law terms (the tool's place on the edge) frozen at
the operating point's sample (the cutting force still follows the joint
velocities through its law). Its state is

    z = [q, v (plant), delta_d (controller), y (sensor, 3, N)],

and A = dz'/dz is taken by central differences of Drake's
``EvalTimeDerivatives`` of the whole diagram (plant with hydroelastic
contact, cutting-force law, observer, controller) and of the sensor's
``raw_force``. Why not ``FirstOrderTaylorApproximation``: it needs every
system of the diagram in AutoDiffXd, and the observer, sensor, cutting
process, estimator and command generator are float-only LeafSystems; the
tests check this differencing against Drake's ``Linearize`` on a diagram
that converts.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Dict, List

import numpy as np
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.systems.framework import Context, Diagram

from deburr_drake.analysis.operating_point import (
    OperatingPoint,
    frozen_scenario,
    transfer_state,
)
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.control.layout import CHAMFER_STATE

__all__ = [
    "numerical_jacobian",
    "continuous_state_slices",
    "ContinuousLinearization",
    "linearize_closed_loop",
    "Mode",
    "classify_modes",
    "eq8_time_constant",
]


def numerical_jacobian(
    f: Callable[[np.ndarray], np.ndarray], z0, steps
) -> np.ndarray:
    """df/dz at z0 by central differences, one step per coordinate."""
    z0 = np.asarray(z0, float)
    steps = np.broadcast_to(np.asarray(steps, float), z0.shape)
    columns = []
    for i in range(z0.size):
        dz = np.zeros_like(z0)
        dz[i] = steps[i]
        columns.append(
            (np.asarray(f(z0 + dz)) - np.asarray(f(z0 - dz))) / (2 * steps[i])
        )
    return np.array(columns).T


def continuous_state_slices(
    diagram: Diagram, context: Context
) -> Dict[str, slice]:
    """Subsystem name -> its slice of the diagram's continuous state
    vector (found by marking each subsystem's state)."""
    out = {}
    probe = context.Clone()
    for system in diagram.GetSystems():
        sub = system.GetMyMutableContextFromRoot(probe)
        n = sub.num_continuous_states()
        if n == 0:
            continue
        saved = sub.get_continuous_state_vector().CopyToVector()
        sub.SetContinuousState(np.full(n, np.nan))
        changed = np.flatnonzero(
            np.isnan(probe.get_continuous_state_vector().CopyToVector())
        )
        sub.SetContinuousState(saved)
        out[system.get_name()] = slice(int(changed[0]), int(changed[-1]) + 1)
    return out


@dataclass
class Mode:
    """One eigenvalue with what it moves."""

    eigenvalue: complex
    group: str  # depth/force, tangential, vertical, joint
    weights: Dict[str, float] = field(default_factory=dict)

    @property
    def natural_frequency(self) -> float:
        """rad/s."""
        return float(abs(self.eigenvalue))

    @property
    def damping_ratio(self) -> float:
        w = abs(self.eigenvalue)
        return float(-self.eigenvalue.real / w) if w > 0 else float("nan")

    @property
    def time_constant(self) -> float:
        """s, -1 / Re(lambda) (inf for Re >= 0)."""
        re = self.eigenvalue.real
        return float(-1.0 / re) if re < 0 else float("inf")


@dataclass
class ContinuousLinearization:
    """A = dz'/dz at the operating point; ``labels`` name z's entries."""

    A: np.ndarray
    labels: List[str]
    slices: Dict[str, slice]  # block of z: plant_q, plant_v, delta_d, force
    modes: List[Mode]
    depth_time_constant: float  # s, of the slowest depth/force mode
    eigenvalues: np.ndarray = None

    def groups(self) -> Dict[str, List[Mode]]:
        out: Dict[str, List[Mode]] = {}
        for m in self.modes:
            out.setdefault(m.group, []).append(m)
        return out


def eq8_time_constant(
    depth_gain: float, stiffness: float, damping: float
) -> float:
    """Eq. (8): tau = (1 + k_delta c2) / (k_delta c1) (s)."""
    return (1.0 + depth_gain * damping) / (depth_gain * stiffness)


def classify_modes(
    eigenvalues,
    vectors,
    *,
    slices,
    J_v,
    J_w,
    n1,
    n2,
    stiffness: float,
    reach: float = 0.05,
) -> List[Mode]:
    """Groups each mode by the largest of its displacements, in metres:
    the tool point along n1 (with delta_d and the measured normal force
    divided by the contact ``stiffness``: the depth/force loop), along n2
    (tangential), along n1 x n2 (vertical), and the tool's rotation times a
    ``reach`` (joint modes the tool point does not see)."""
    n3 = np.cross(n1, n2)
    modes = []
    for lam, w in zip(eigenvalues, vectors.T):
        dq = w[slices["plant_q"]]
        dx = J_v @ dq
        dy = w[slices["force"]]
        weights = {
            "depth/force": abs(n1 @ dx)
            + abs(w[slices["delta_d"]][0])
            + abs(n1 @ dy) / stiffness,
            "tangential": abs(n2 @ dx) + abs(n2 @ dy) / stiffness,
            "vertical": abs(n3 @ dx) + abs(n3 @ dy) / stiffness,
            "joint": reach * float(np.linalg.norm(J_w @ dq)),
        }
        total = sum(weights.values()) or 1.0
        weights = {k: float(v / total) for k, v in weights.items()}
        modes.append(Mode(complex(lam), max(weights, key=weights.get), weights))
    return sorted(modes, key=lambda m: (m.group, -m.eigenvalue.real))


def _continuous_cell(op: OperatingPoint, overrides):
    """(scenario, diagram, context): ``op``'s cell made continuous
    (frozen_scenario) with ``overrides``, at ``op``'s state."""
    scenario = frozen_scenario(op.scenario, continuous=True, **overrides)
    diagram = make_deburring_diagram(scenario=scenario)
    context = diagram.CreateDefaultContext()
    transfer_state(op.diagram, op.context, diagram, context)
    # The process's held law again, at this state, without the sampled
    # law's implicit-damping term (frozen_scenario).
    process = diagram.GetSubsystemByName("cutting_process")
    process_context = process.GetMyMutableContextFromRoot(context)
    process_context.SetDiscreteState(
        process.EvalUniquePeriodicDiscreteUpdate(process_context)
    )
    return scenario, diagram, context


def _modes(diagram, context, scenario, A, slices, stiffness):
    """(eigenvalues, modes) of A, the modes grouped by the tool's motion
    along the edge's directions at the state in ``context``."""
    plant = diagram.GetSubsystemByName("plant")
    plant_context = plant.GetMyContextFromRoot(context)
    frame = plant.GetFrameByName(scenario.robot.tool_frame)
    J = plant.CalcJacobianSpatialVelocity(
        plant_context,
        JacobianWrtVariable.kV,
        frame,
        np.zeros(3),
        plant.world_frame(),
        plant.world_frame(),
    )
    # q' = v for the cell's joints (revolute or prismatic).
    observer = diagram.GetSubsystemByName("chamfer_observer")
    chamfer = observer.GetOutputPort("chamfer_state").Eval(
        observer.GetMyContextFromRoot(context)
    )
    eigenvalues, vectors = np.linalg.eig(A)
    modes = classify_modes(
        eigenvalues,
        vectors,
        slices=slices,
        J_v=J[3:],
        J_w=J[:3],
        n1=CHAMFER_STATE.get(chamfer, "n1"),
        n2=CHAMFER_STATE.get(chamfer, "n2"),
        stiffness=stiffness,
    )
    return eigenvalues, modes


def linearize_closed_loop(
    op: OperatingPoint, *, stiffness: float | None = None, **overrides
) -> ContinuousLinearization:
    """The continuous-time linearization of ``op``'s closed loop (see the
    module docstring), with scenario ``overrides`` by dotted name.
    ``stiffness`` (N/m, for grouping modes) defaults to 1e4."""
    scenario, diagram, context = _continuous_cell(op, overrides)
    plant = diagram.GetSubsystemByName("plant")
    sensor = diagram.GetSubsystemByName("force_sensor")
    sensor_context = sensor.GetMyMutableContextFromRoot(context)
    xc_slices = continuous_state_slices(diagram, context)
    nq, nv = plant.num_positions(), plant.num_velocities()
    plant_slice = xc_slices["plant"]
    delta_index = xc_slices["controller"].start
    omega_c = 2 * np.pi * scenario.sensor.cutoff_frequency
    xc0 = context.get_continuous_state_vector().CopyToVector()
    z0 = np.concatenate(
        [
            xc0[plant_slice],
            [xc0[delta_index]],
            sensor_context.get_discrete_state(0).get_value(),
        ]
    )
    n = nq + nv
    slices = {
        "plant_q": slice(0, nq),
        "plant_v": slice(nq, n),
        "delta_d": slice(n, n + 1),
        "force": slice(n + 1, n + 4),
    }

    def f(z):
        xc = xc0.copy()
        xc[plant_slice] = z[:n]
        xc[delta_index] = z[n]
        context.SetContinuousState(xc)
        sensor_context.SetDiscreteState(0, z[n + 1 :])
        xdot = diagram.EvalTimeDerivatives(context).CopyToVector()
        raw = sensor.raw_force(sensor_context)
        return np.concatenate(
            [
                xdot[plant_slice],
                [xdot[delta_index]],
                omega_c * (raw - z[n + 1 :]),
            ]
        )

    steps = np.concatenate(
        [np.full(nq, 1e-7), np.full(nv, 1e-6), [1e-8], np.full(3, 1e-4)]
    )
    A = numerical_jacobian(f, z0, steps)
    f(z0)  # leave the context at the operating point

    eigenvalues, modes = _modes(
        diagram, context, scenario, A, slices, stiffness or 1e4
    )
    depth = [
        m for m in modes if m.group == "depth/force" and m.eigenvalue.real < 0
    ]
    tau = max((m.time_constant for m in depth), default=float("nan"))
    labels = (
        [f"q[{i}]" for i in range(nq)]
        + [f"v[{i}]" for i in range(nv)]
        + ["delta_d", "y[0]", "y[1]", "y[2]"]
    )
    return ContinuousLinearization(
        A=A,
        labels=labels,
        slices=slices,
        modes=modes,
        depth_time_constant=tau,
        eigenvalues=eigenvalues,
    )
