"""The paper's controller around a plant of your own, without
make_deburring_diagram.

The user's side of the diagram, all written here:
- a MultibodyPlant built in code: a 2 kg tool body on three actuated
  prismatic joints along world x, y, z (frame "tool_tip" at its origin);
- a LeafSystem for the part: a stiff circular wall with a chamfering
  (cutting) force, f_n = c0 + k delta + b delta_dot into the wall and
  f_t = P'_th + g v_t against the motion along the edge; it applies the
  force to the plant and reports it as the "measured" tool force.

The library's side is one call, deburr_drake.add_deburring_controller: the
command generator, first-order hold, chamfer observer, contact estimator
and hybrid controller, configured by the point_mass scenario's sections.

    python examples/own_plant.py --duration 4
"""

import argparse
import os

import numpy as np
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import (
    FixedOffsetFrame,
    PrismaticJoint,
    SpatialInertia,
)
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder, LeafSystem
from pydrake.systems.primitives import LogVectorOutput

import deburr_drake as dd


def add_cartesian_tool(plant, mass=2.0):
    """A point-mass tool on x, y, z prismatic joints; returns its body."""
    tool = plant.AddRigidBody(
        "tool", SpatialInertia.SolidSphereWithMass(mass, 0.02)
    )
    parent = plant.world_frame()
    for axis, name in zip(np.eye(3), "xyz"):
        if name == "z":
            child = tool.body_frame()
        else:
            child = plant.AddRigidBody(
                f"{name}_carriage",
                SpatialInertia.SolidSphereWithMass(0.5, 0.02),
            ).body_frame()
        joint = plant.AddJoint(
            PrismaticJoint(f"{name}_slide", parent, child, axis)
        )
        plant.AddJointActuator(f"{name}_drive", joint)
        parent = child
    plant.AddFrame(
        FixedOffsetFrame("tool_tip", tool.body_frame(), RigidTransform())
    )
    return tool


class CuttingWall(LeafSystem):
    """The part as the user models it: a wall outside ``contour`` (the
    zero-depth path of the tool point). Input ``plant_state`` [q; v] of the
    Cartesian tool (q is the tool point, so forces are generalized forces);
    outputs ``generalized_force`` (3, N) and ``measured_force`` (3, N, world).
    """

    def __init__(
        self,
        contour,
        *,
        c0=2.0,
        stiffness=1.0e4,
        damping=50.0,
        threshold=2.0,
        cutting_damping=1500.0,
        smoothing_speed=5e-4,
    ):
        super().__init__()
        self._contour = contour
        self._c = (c0, stiffness, damping)
        self._cut = (threshold, cutting_damping, smoothing_speed)
        self._state = self.DeclareVectorInputPort("plant_state", 6)
        self.DeclareVectorOutputPort("generalized_force", 3, self._output)
        self.DeclareVectorOutputPort("measured_force", 3, self._output)

    def force(self, x, v):
        n1, tangent, delta, _ = self._contour.frame(x)
        if delta <= 0.0:
            return np.zeros(3)
        c0, k, b = self._c
        p_th, g, v_s = self._cut
        f_n = max(c0 + k * delta + b * (n1 @ v), 0.0)
        v_t = tangent @ v
        f_t = p_th * np.tanh(v_t / v_s) + g * v_t
        return -f_n * n1 - f_t * tangent

    def _output(self, context, output):
        state = self._state.Eval(context)
        output.SetFromVector(self.force(state[:3], state[3:]))


def build(scenario):
    builder = DiagramBuilder()
    # A discrete plant: the wall's forces enter once per 1 ms step.
    plant, _ = AddMultibodyPlant(MultibodyPlantConfig(time_step=1e-3), builder)
    add_cartesian_tool(plant)
    plant.Finalize()

    # The zero-depth path of the tool point: a 27 mm circle at z = 48 mm.
    contour = dd.CircularContour([0.0, 0.0, 0.048], 0.027)
    wall = builder.AddNamedSystem("wall", CuttingWall(contour))
    state = plant.get_state_output_port()
    builder.Connect(state, wall.GetInputPort("plant_state"))
    builder.Connect(
        wall.GetOutputPort("generalized_force"),
        plant.get_applied_generalized_force_input_port(),
    )

    loops = dd.add_deburring_controller(
        builder,
        scenario=scenario,
        plant=plant,
        contour=contour,
        plant_state=state,
        measured_force=wall.GetOutputPort("measured_force"),
    )
    builder.Connect(loops.actuation, plant.get_actuation_input_port())

    # Log two of the library's named outputs (dd.LOGGED) at 10 ms.
    loggers = {
        name: LogVectorOutput(
            builder.GetSubsystemByName(dd.LOGGED[name][0]).GetOutputPort(
                dd.LOGGED[name][1]
            ),
            builder,
            0.01,
        )
        for name in ("chamfer", "command")
    }
    diagram = builder.Build()
    # Start with the tool point on the contour's start (q is the position).
    plant.SetDefaultPositions(contour.point_at(0.0))
    return diagram, loggers


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--duration",
        type=float,
        default=float(os.environ.get("DEBURR_EXAMPLE_DURATION", 4.0)),
        help="simulated seconds (default 4)",
    )
    args = parser.parse_args(argv)
    scenario = dd.load_scenario("point_mass")
    diagram, loggers = build(scenario)
    simulator = Simulator(diagram)
    simulator.AdvanceTo(args.duration)
    context = simulator.get_context()
    chamfer = dd.CHAMFER_STATE.split(
        loggers["chamfer"].FindLog(context).data().T
    )
    command = dd.COMMAND_STATE.split(
        loggers["command"].FindLog(context).data().T
    )
    t = loggers["chamfer"].FindLog(context).sample_times()
    late = t >= 0.5 * args.duration
    print(f"own plant, {args.duration:g} s, means over the second half:")
    print(
        f"  chamfer depth     {np.mean(chamfer['delta'][late]) * 1e3:7.4f}"
        f" mm  (desired {scenario.task.desired_depth * 1e3:g} mm)"
    )
    print(f"  normal force      {np.mean(chamfer['f_n'][late]):7.3f} N")
    print(
        f"  chamfering force  {np.mean(chamfer['f_t'][late]):7.3f} N"
        f"  (desired {scenario.task.desired_chamfering_force:g} N)"
    )
    print(
        f"  commanded feed    {np.mean(command['feed'][late]) * 1e3:7.3f} mm/s"
    )


if __name__ == "__main__":
    main()
