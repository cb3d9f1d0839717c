#!/usr/bin/env python3
"""The cost of the paper cell's physics alone, without any Python in the
loop: the same plant (arm, joint friction, compliant ring, cutter), the
same cutting-force law (its terms, the held mean of process.sample_mean
included, fixed at the start's values, reading the held actuation), cenic
in fixed steps of ``--step`` (the
2.5 ms control period by default: one step per sample), the weld's
reaction forces sampled every 2.5 ms (as the force sensor does) and a C++
joint PID through a 2.5 ms hold pressing the tool 0.5 mm into the edge.
What an 80 s pass costs at best on this host, whatever the controller is
written in. Prints seconds per simulated second and per 80 s pass.

    python scripts/bench_floor.py [--duration 6] [--step 0.0025]
        [--python-systems N]

--python-systems N adds N idle Python systems, each a periodic discrete
update at 2.5 ms that reads the plant's state: what the dispatch of the
cell's Python systems costs before they compute anything.
"""

import argparse
import time

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import (
    ApplySimulatorConfig,
    Simulator,
    SimulatorConfig,
)
from pydrake.systems.controllers import PidController
from pydrake.systems.framework import DiagramBuilder, LeafSystem
from pydrake.systems.primitives import (
    Adder,
    ConstantVectorSource,
    ZeroOrderHold,
)

from deburr_drake.cell.arm import solve_tool_pose
from deburr_drake.cell.diagram import TOOL_FRAME
from deburr_drake.cell.edge import make_contour
from deburr_drake.cell.plant import add_cell_plant
from deburr_drake.cell.process import (
    HeldMean,
    force_law_terms,
    make_cutting_force_law,
)
from deburr_drake.config import load_scenario
from deburr_drake.control.kinematics import ToolPoint
from deburr_drake.runs.simulation import set_monitor


class _IdleSampler(LeafSystem):
    """A Python system that does nothing but what every one of the cell's
    does each sample: a periodic discrete update that reads the plant's
    state port and writes one state (the price of the dispatch alone)."""

    def __init__(self, nx, period):
        super().__init__()
        self._state = self.DeclareVectorInputPort("plant_state", nx)
        self.DeclareDiscreteState(1)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)

    def _update(self, context, discrete_state):
        discrete_state.set_value(0, self._state.Eval(context)[:1])


def _add_cutting_force(builder, plant, context, scenario, contour, q0):
    """The cell's cutting-force law with its terms held constant at 0.5 mm
    depth at the contour's start, applied to the plant; returns the law."""
    nq, nv = plant.num_positions(), plant.num_velocities()
    T = scenario.controller.control_period
    p = contour.point_at(0.0)
    _, _, J = ToolPoint(plant, plant.GetFrameByName(TOOL_FRAME)).evaluate(
        np.concatenate([q0, np.zeros(nv)])
    )
    n1, tangent, delta, _ = contour.frame(p + 5e-4 * contour.n1(p))
    a = J.T @ tangent
    B = plant.MakeActuationMatrix()
    held = HeldMean(
        np.linalg.solve(plant.CalcMassMatrix(context), a), 0.0, B, T
    )
    terms = force_law_terms(
        scenario.process,
        n1,
        tangent,
        delta,
        J,
        np.zeros(3),
        cut_height=scenario.tool.engagement,
        v=np.zeros(nv),
        nu=B.shape[1],
        held=held,
    )
    law = builder.AddSystem(
        make_cutting_force_law(
            nq, nv, scenario.process.smoothing_speed, B.shape[1]
        )
    )
    source = builder.AddSystem(ConstantVectorSource(terms))
    builder.Connect(
        source.get_output_port(), law.GetInputPort("force_law_terms")
    )
    builder.Connect(
        plant.get_state_output_port(), law.GetInputPort("plant_state")
    )
    builder.Connect(
        law.GetOutputPort("generalized_force"),
        plant.get_applied_generalized_force_input_port(),
    )
    return law


def _add_joint_control(builder, plant, context, q0, T, law):
    """A joint PID holding q0 with gravity feedforward, through a zero-order
    hold of period T, into the plant and the force law's actuation."""
    nv = plant.num_velocities()
    pid = builder.AddSystem(
        PidController(
            kp=np.full(nv, 2000.0), ki=np.zeros(nv), kd=np.full(nv, 100.0)
        )
    )
    target = builder.AddSystem(
        ConstantVectorSource(np.concatenate([q0, np.zeros(nv)]))
    )
    builder.Connect(
        target.get_output_port(), pid.get_input_port_desired_state()
    )
    builder.Connect(
        plant.get_state_output_port(), pid.get_input_port_estimated_state()
    )
    # Gravity feedforward at q0 (the arm barely moves).
    gravity = builder.AddSystem(
        ConstantVectorSource(-plant.CalcGravityGeneralizedForces(context))
    )
    total = builder.AddSystem(Adder(2, nv))
    builder.Connect(pid.get_output_port_control(), total.get_input_port(0))
    builder.Connect(gravity.get_output_port(), total.get_input_port(1))
    hold = builder.AddSystem(ZeroOrderHold(T, nv))
    builder.Connect(total.get_output_port(), hold.get_input_port())
    builder.Connect(hold.get_output_port(), plant.get_actuation_input_port())
    builder.Connect(hold.get_output_port(), law.GetInputPort("actuation"))


def make_floor_simulator(step=None, sensor=True, python_systems=0):
    """(simulator, plant) of the floor, initialized; ``step`` (s) the fixed
    cenic step, the control period by default; ``python_systems`` idle
    Python samplers (:class:`_IdleSampler`) added beside the physics."""
    scenario = load_scenario("paper")
    T = scenario.controller.control_period
    builder = DiagramBuilder()
    plant, _ = add_cell_plant(builder, scenario)
    contour = make_contour(scenario)
    p = contour.point_at(0.0)
    # Aimed 1.5 mm deep: the joint PID settles near 0.5 mm, about 5 N.
    q0 = solve_tool_pose(plant, p + 1.5e-3 * contour.n1(p))
    plant.SetDefaultPositions(q0)
    context = plant.CreateDefaultContext()
    law = _add_cutting_force(builder, plant, context, scenario, contour, q0)
    _add_joint_control(builder, plant, context, q0, T, law)
    if sensor:
        reactions = plant.get_reaction_forces_output_port()
        sample = builder.AddSystem(
            ZeroOrderHold(
                T, AbstractValue.Make(reactions.Allocate().get_value())
            )
        )
        builder.Connect(reactions, sample.get_input_port())
    for i in range(python_systems):
        idle = builder.AddNamedSystem(
            f"idle_{i}", _IdleSampler(plant.num_multibody_states(), T)
        )
        builder.Connect(plant.get_state_output_port(), idle.get_input_port())
    diagram = builder.Build()

    step = T if step is None else step
    if not 0 < step <= T:
        raise ValueError(f"step must be in (0, {T}] s, got {step}")
    simulator = Simulator(diagram)
    ApplySimulatorConfig(
        SimulatorConfig(
            integration_scheme="cenic",
            max_step_size=step,
            use_error_control=False,
        ),
        simulator,
    )
    # the plant's cache fresh after each step, as in the cell's simulators
    set_monitor(simulator, diagram, "cenic")
    simulator.Initialize()
    return simulator, plant


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--duration", type=float, default=6.0, help="s")
    ap.add_argument(
        "--step",
        type=float,
        default=None,
        help="s, the fixed cenic step (default: the control period, 2.5 ms)",
    )
    ap.add_argument(
        "--sensor",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="sample the reaction forces",
    )
    ap.add_argument(
        "--python-systems",
        type=int,
        default=0,
        help="idle Python systems sampled every 2.5 ms beside "
        "the physics (the cost of their dispatch alone)",
    )
    args = ap.parse_args()
    try:
        simulator, plant = make_floor_simulator(
            args.step, args.sensor, args.python_systems
        )
    except ValueError as e:
        ap.error(str(e))
    step = simulator.get_integrator().get_maximum_step_size()
    simulator.AdvanceTo(1.0)
    steps = simulator.get_num_steps_taken()
    wall = time.perf_counter()
    simulator.AdvanceTo(1.0 + args.duration)
    wall = time.perf_counter() - wall
    steps = simulator.get_num_steps_taken() - steps
    results = plant.get_contact_results_output_port().Eval(
        plant.GetMyContextFromRoot(simulator.get_context())
    )
    contact = sum(
        np.linalg.norm(
            results.hydroelastic_contact_info(i).F_Ac_W().translational()
        )
        for i in range(results.num_hydroelastic_contacts())
    )
    print(f"contact force at the end: {contact:.2f} N")
    sensor = "with" if args.sensor else "without"
    extra = (
        f", {args.python_systems} idle Python systems"
        if args.python_systems
        else ""
    )
    print(
        f"physics only{extra}, {1e3 * step:g} ms steps, {sensor} the sampled "
        f"reaction forces: {steps / args.duration:.0f} steps per "
        f"simulated second, {1e3 * wall / steps:.3f} ms per step, "
        f"{wall / args.duration:.3f} s per simulated second; an 80 s "
        f"pass: {80 * wall / args.duration:.1f} s"
    )


if __name__ == "__main__":
    main()
