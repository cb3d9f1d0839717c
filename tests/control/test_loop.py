"""add_deburring_controller: the paper's loops in a builder of one's own;
and the package's public names."""

import subprocess
import sys

import numpy as np
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

import deburr_drake as dd
from deburr_drake.cell.models import POINT_MASS_URL, make_kinematic_model
from deburr_drake.control.loop import (
    DeburringController,
    add_deburring_controller,
)

LOOP_SYSTEMS = (
    "chamfer_observer",
    "command_generator",
    "first_order_hold",
    "contact_estimator",
    "controller",
)


def test_the_loops_close_around_two_signals():
    scenario = dd.load_scenario("point_mass")
    model = make_kinematic_model(POINT_MASS_URL)
    contour = dd.make_contour(scenario)
    start = contour.point_at(0.0)
    builder = DiagramBuilder()
    state = builder.AddSystem(
        ConstantVectorSource(
            np.concatenate([start, np.zeros(model.num_velocities())])
        )
    )
    force = builder.AddSystem(ConstantVectorSource(np.zeros(3)))
    loops = add_deburring_controller(
        builder,
        scenario=scenario,
        plant=model,
        contour=contour,
        plant_state=state.get_output_port(),
        measured_force=force.get_output_port(),
    )
    assert isinstance(loops, DeburringController)
    assert loops.actuation.size() == model.num_actuators()
    diagram = builder.Build()
    for name in LOOP_SYSTEMS:
        diagram.GetSubsystemByName(name)
    # Every input of the loops is connected: the diagram has none left.
    assert diagram.num_input_ports() == 0
    context = diagram.CreateDefaultContext()
    diagram.ExecuteInitializationEvents(context)
    controller = diagram.GetSubsystemByName("controller")
    u = controller.GetOutputPort("actuation").Eval(
        controller.GetMyContextFromRoot(context)
    )
    assert np.all(np.isfinite(u))
    # No contact force measured: the controller pushes the tool into the
    # material (n1 at the start), against the small depth error.
    n1 = contour.n1(start)
    assert u @ n1 > 0.0


def test_the_cell_uses_the_same_loops():
    scenario = dd.load_scenario("point_mass")
    diagram = dd.make_deburring_diagram(scenario=scenario)
    for name in LOOP_SYSTEMS:
        diagram.GetSubsystemByName(name)
    assert isinstance(
        diagram.GetSubsystemByName("controller"), dd.HybridController
    )


def test_every_public_name_resolves():
    for name in dd.__all__:
        assert getattr(dd, name) is not None, name
    assert dd.run.__doc__ and dd.add_deburring_controller.__doc__


def test_importing_the_package_imports_no_drake():
    code = (
        "import sys, deburr_drake, deburr_drake.math.fuzzy, "
        "deburr_drake.math.geometry, deburr_drake.math.metrics; "
        "print('pydrake' in sys.modules)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == "False"
