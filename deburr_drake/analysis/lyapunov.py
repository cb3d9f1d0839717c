"""Lyapunov monitors along a run: Proposition 1's

    V1 = sum_i c~_i^2 / (2 r_i) + s^T M_x s / 2

(c~ = c-hat - c, c from the contact truth: c0, the secant stiffness
(F(delta*) - c0) / delta* and the Hunt-Crossley c2, since the
hydroelastic force is not linear in the depth; parameters with r_i = 0 are
not adapted and drop out; M_x = (J M^-1 J^T)^-1 the plant's task-space
inertia at the tool point) and Theorem 2's V of (38),
V = V1 + sum_k |theta_k - theta*_k|^2 / (2 r), with theta* estimated as
the run's final rule weights (the optimal weights are unknown; the final
ones are what the adaptation converged to)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict

import numpy as np
from pydrake.common import RandomGenerator
from pydrake.multibody.tree import JacobianWrtVariable

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import Scenario
from deburr_drake.control.layout import CONTROLLER_DIAGNOSTICS
from deburr_drake.runs.simulation import make_simulator

__all__ = ["LyapunovTrace", "lyapunov_trace", "plot_lyapunov"]


@dataclass
class LyapunovTrace:
    t: np.ndarray  # s
    V1: np.ndarray  # J
    V: np.ndarray  # J, (38) with theta* = final theta
    outside_dead_zone: np.ndarray  # bool per sample
    summary: Dict[str, float]


def _task_inertia(plant, plant_context, frame):
    """The task-space inertia (kg, 3 x 3) of ``frame``'s origin:
    (J M^-1 J^T)^-1."""
    M = plant.CalcMassMatrix(plant_context)
    J = plant.CalcJacobianTranslationalVelocity(
        plant_context,
        JacobianWrtVariable.kV,
        frame,
        np.zeros(3),
        plant.world_frame(),
        plant.world_frame(),
    )
    return np.linalg.inv(J @ np.linalg.solve(M, J.T))


def _summary(t, V1, V, outside, settle) -> Dict[str, float]:
    """The fractions of samples after ``settle`` where V and V1 grow."""
    late = t[1:] > settle
    mask = late & outside[1:]
    dV = np.diff(V)
    dV1 = np.diff(V1)
    return {
        "samples_outside_dead_zone": int(np.sum(mask)),
        "fraction_dV_positive_outside_dead_zone": float(np.mean(dV[mask] > 0))
        if np.any(mask)
        else float("nan"),
        "fraction_dV1_positive_outside_dead_zone": float(np.mean(dV1[mask] > 0))
        if np.any(mask)
        else float("nan"),
        "fraction_dV_positive_all": float(np.mean(dV[late] > 0))
        if np.any(late)
        else float("nan"),
    }


def lyapunov_trace(
    scenario: Scenario,
    *,
    duration: float = 5.0,
    sample_period: float = 0.01,
    settle: float = 0.5,
) -> LyapunovTrace:
    """Simulates ``scenario`` (as given, adaptation on) for ``duration``
    and evaluates V1 and V every ``sample_period``. The summary holds the
    fraction of samples after ``settle`` s where dV/dt > 0 while some
    fuzzy |s_k| is outside its dead zone (where (35) adapts and the proofs
    make V decrease)."""
    from deburr_drake.cell.truth import contact_truth

    truth = contact_truth(scenario)
    c_true = np.array([truth.c0, truth.secant_stiffness, truth.c2])
    r_c = np.asarray(scenario.estimator.gains, float)
    r_f = scenario.controller.fuzzy.adaptation_gain
    diagram = make_deburring_diagram(scenario=scenario)
    simulator = make_simulator(diagram, scenario)
    context = simulator.get_mutable_context()
    diagram.SetRandomContext(
        context, RandomGenerator(scenario.sensor.noise_seed)
    )
    plant = diagram.GetSubsystemByName("plant")
    estimator = diagram.GetSubsystemByName("contact_estimator")
    controller = diagram.GetSubsystemByName("controller")
    frame = plant.GetFrameByName(scenario.robot.tool_frame)
    pc = plant.GetMyContextFromRoot(context)
    ec = estimator.GetMyContextFromRoot(context)
    cc = controller.GetMyContextFromRoot(context)
    widths = np.array(
        [rb.resolved_dead_zone_half_width for rb in controller.rule_bases]
    )
    axes = list(scenario.controller.fuzzy.axes)
    simulator.Initialize()
    rows, thetas = [], []
    n = int(round(duration / sample_period))
    for k in range(n + 1):
        if k:
            simulator.AdvanceTo(k * sample_period)
        c_hat = ec.get_continuous_state_vector().CopyToVector()
        s = CONTROLLER_DIAGNOSTICS.get(
            controller.GetOutputPort("diagnostics").Eval(cc), "s"
        )
        M_x = _task_inertia(plant, pc, frame)
        adapted = r_c > 0
        V1 = float(
            np.sum((c_hat - c_true)[adapted] ** 2 / (2 * r_c[adapted]))
            + 0.5 * s @ M_x @ s
        )
        outside = bool(np.any(np.abs(s[axes]) > widths))
        rows.append((context.get_time(), V1, outside))
        thetas.append(controller.theta(cc).copy())
    t, V1, outside = (np.array(x) for x in zip(*rows))
    theta_star = thetas[-1]
    V = V1 + np.array(
        [np.sum((th - theta_star) ** 2) / (2 * r_f) for th in thetas]
    )
    summary = _summary(t, V1, V, outside, settle)
    return LyapunovTrace(t, V1, V, outside, summary)


def plot_lyapunov(trace: LyapunovTrace, path, *, title: str = ""):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4))
    ax.semilogy(trace.t, trace.V1, label="V1 (Prop. 1)")
    ax.semilogy(trace.t, trace.V, label="V (38), theta* = final theta")
    ax.set(
        xlabel="t (s)",
        ylabel="V (J)",
        title=f"{title} Lyapunov functions along the run",
    )
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
