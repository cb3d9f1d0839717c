"""The tall-burr envelope: its bounds and per-run numbers on hand-made
logs and the cenic behaviour behind the surge. A tall long burr
(2 mm x 20 mm at 10 N) on the paper cell, 17 simulated seconds, is
scripts/tall_burr.py (docs/benchmarks.md)."""

import numpy as np
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import PrismaticJoint, SpatialInertia
from pydrake.systems.analysis import (
    ApplySimulatorConfig,
    Simulator,
    SimulatorConfig,
)
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import MatrixGain
import pytest

from deburr_drake.config import load_scenario
from deburr_drake.runs import envelope


@pytest.fixture(scope="module")
def paper():
    return load_scenario("paper")


def test_bounds_follow_the_feed_law(paper):
    cell = envelope.BurrCell(height=0.002, length=0.02, force=10.0)
    b = envelope.burr_bounds(paper, cell)
    # v_off = (10 - 2) N / (3.3e9 * 0.5 mm * 2 mm) = 2.424 mm/s.
    v_off = 8.0 / 3300.0
    assert envelope.off_burr_feed(paper) == pytest.approx(v_off)
    assert b["max_chamfering_force_N"] == pytest.approx(
        20.0 + 3.3e9 * 0.002 * 0.002 * v_off
    )
    assert b["max_tool_speed_m_s"] == pytest.approx(1.5 * v_off)
    # At 5 N the law settles below v0, at 3 N / 3300 N s/m = 0.91 mm/s:
    # v0 is its branch below the cutting threshold, not a floor.
    paper_5 = load_scenario("paper", text="task: {desired_chamfering_force: 5}")
    assert paper_5.command.default_feed == 1e-3
    assert envelope.off_burr_feed(paper_5) == pytest.approx(3.0 / 3300.0)
    # Below v_eps the law runs at v0: 2.5 N on the 1 mm/s default.
    low = envelope.BurrCell(height=0.001, length=0.008, force=2.5)
    paper_low = load_scenario(
        "paper", text="task: {desired_chamfering_force: 2.5}"
    )
    assert envelope.burr_bounds(paper_low, low)[
        "max_tool_speed_m_s"
    ] == pytest.approx(1.5e-3)


def _signals(f_t, v_t, delta, burr_area, g):
    """A log whose first sample (t = 0) is the start of contact, with a
    start-up speed of 9 mm/s and force of 30 N that the bounds ignore, and
    the given samples from t = TRANSIENT on."""
    n = len(f_t)
    t = np.concatenate([[0.0], envelope.TRANSIENT + np.arange(n) * 0.0025])

    def first(value, rest):
        return np.concatenate([[value], np.asarray(rest, float)])

    return {
        "process": {
            "t": t,
            "f_t": first(30.0, f_t),
            "v_t": first(9e-3, v_t),
            "delta": first(1e-4, delta),
            "burr_area": first(0.0, burr_area),
            "g": first(600, g),
        },
        "chamfer": {"t": t, "f_n": np.full(n + 1, 5.0)},
    }


def test_burr_metrics_on_a_hand_made_log(paper):
    cell = envelope.BurrCell(height=0.001, length=0.008, force=10.0)
    on = np.array([0, 0, 1, 1, 0], float) * 2e-6
    sig = _signals(
        f_t=[10, 11, 12, 9, 10],
        v_t=[2.4e-3, 2.4e-3, 1e-3, 1.2e-3, 2.4e-3],
        delta=[5e-4, 5e-4, 5.3e-4, 4.9e-4, 5e-4],
        burr_area=on,
        g=[3300, 3300, 8000, 8000, 3300],
    )
    m = envelope.burr_metrics(sig, paper, cell)
    assert m["max_chamfering_force_N"] == 12.0
    assert m["max_tool_speed_m_s"] == pytest.approx(2.4e-3)
    assert m["depth_rms_error_on_burr_m"] == pytest.approx(
        np.sqrt((0.03e-3**2 + 0.01e-3**2) / 2)
    )
    assert m["feed_on_burr_m_s"] == pytest.approx(1.1e-3)
    assert m["feed_law_on_burr_m_s"] == pytest.approx(8.0 / 8000)
    assert m["passed"] == 1.0 and m["nan"] == 0.0

    surge = _signals(
        f_t=[10, 900, 12, 9, 10],
        v_t=[2.4e-3, 50e-3, 1e-3, 1.2e-3, 2.4e-3],
        delta=[5e-4] * 5,
        burr_area=on,
        g=[3300] * 5,
    )
    assert envelope.burr_metrics(surge, paper, cell)["passed"] == 0.0
    never = _signals(
        f_t=[10] * 5,
        v_t=[2.4e-3] * 5,
        delta=[5e-4] * 5,
        burr_area=np.zeros(5),
        g=[3300] * 5,
    )
    assert envelope.burr_metrics(never, paper, cell)["passed"] == 0.0


def test_burr_scenario_places_the_burr_ahead(paper):
    cell = envelope.BurrCell(height=0.002, length=0.02, force=10.0)
    sc = envelope.burr_scenario(paper, cell, lead_time=1.0)
    (burr,) = sc.process.burrs
    from deburr_drake.cell.edge import make_contour

    L = make_contour(sc).length
    start = burr.center_fraction * L - burr.length / 2
    # The cutter's front (arc + r) reaches it after 2 s + 1 s at 2.42 mm/s.
    assert start == pytest.approx(3.0 * 8.0 / 3300 + 0.003)
    assert sc.simulation.stop_after_passes * L == pytest.approx(
        start + 0.02 + 1e-3
    )


def _point_on_three_joints(builder, mass):
    """A continuous plant: a point of ``mass`` on three prismatic joints
    along x, y, z (massless links), each with an actuator, no gravity."""
    plant, _ = AddMultibodyPlant(MultibodyPlantConfig(time_step=0.0), builder)
    parent = plant.world_body()
    for i, axis in enumerate(np.eye(3)):
        body = plant.AddRigidBody(
            f"body{i}",
            SpatialInertia.SolidSphereWithMass(mass if i == 2 else 1e-6, 0.01),
        )
        joint = plant.AddJoint(
            PrismaticJoint(
                f"joint{i}", parent.body_frame(), body.body_frame(), axis
            )
        )
        plant.AddJointActuator(f"actuator{i}", joint)
        parent = body
    plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, 0.0])
    plant.Finalize()
    return plant


def _fixed_cenic(diagram, h):
    simulator = Simulator(diagram)
    ApplySimulatorConfig(
        SimulatorConfig(
            integration_scheme="cenic", max_step_size=h, use_error_control=False
        ),
        simulator,
    )
    return simulator


def _rank_one_damper_velocities(direction, *, g=3000.0, mass=1.0, h=0.0025):
    """A point mass on three prismatic joints under the force -g a a^T v,
    a the unit ``direction``, from an initial speed along a: its speed
    along a after each of 5 fixed cenic steps of ``h`` (later steps reach
    the solver's tolerance when the speed decays)."""
    builder = DiagramBuilder()
    plant = _point_on_three_joints(builder, mass)
    a = np.asarray(direction, float) / np.linalg.norm(direction)
    damper = builder.AddSystem(
        MatrixGain(np.hstack([np.zeros((3, 3)), -g * np.outer(a, a)]))
    )
    builder.Connect(plant.get_state_output_port(), damper.get_input_port())
    builder.Connect(
        damper.get_output_port(),
        plant.get_applied_generalized_force_input_port(),
    )
    simulator = _fixed_cenic(builder.Build(), h)
    context = plant.GetMyMutableContextFromRoot(simulator.get_mutable_context())
    plant.get_actuation_input_port().FixValue(context, np.zeros(3))
    plant.SetVelocities(context, 1e-3 * a)
    speeds = []
    for k in range(1, 6):
        simulator.AdvanceTo(k * h)
        speeds.append(plant.GetVelocities(context) @ a)
    return np.array(speeds)


def test_cenic_treats_only_the_diagonal_of_an_applied_damping_implicitly():
    """What the surge turned on (README, numerical choices): cenic
    linearizes the applied generalized forces keeping only the diagonal of
    d tau / dv. A damper g a a^T along a joint axis decays as implicit
    Euler, 1 / (1 + h g / m) per step; along (1, 1, 1) the off-diagonal
    part is explicit and the step's factor is (1 - 2 h g / 3 m) / (1 +
    h g / 3 m) = -1.14 at h g / m = 7.5: it grows, alternating sign. Half
    the step (3.75) gives -0.57."""
    along_axis = _rank_one_damper_velocities([1, 0, 0])
    np.testing.assert_allclose(
        along_axis[1:] / along_axis[:-1], 1 / 8.5, rtol=1e-3
    )
    diagonal = _rank_one_damper_velocities([1, 1, 1])
    np.testing.assert_allclose(
        diagonal[1:] / diagonal[:-1], -4.0 / 3.5, rtol=1e-3
    )
    half = _rank_one_damper_velocities([1, 1, 1], h=0.00125)
    np.testing.assert_allclose(half[1:] / half[:-1], -1.5 / 2.25, rtol=1e-3)


def _cutting_law_velocities(treatment, h=0.0025, push=0.0):
    """Speed along a = (1, 1, 1)/sqrt(3) of a 1 kg point on three
    prismatic joints under the cutting law (g = 3000 N s/m, h g / m =
    7.5, no threshold forces) and a constant actuation ``push`` (N) along
    a, after each of 4 fixed cenic steps of h, the law's terms sampled at
    each step's start as the process does: ``treatment`` "plain" (eq. (3)
    between samples), "implicit" (process.implicit_damping) or "held"
    (process.sample_mean: nothing but the push acts, so the rest is 0)."""
    from deburr_drake.cell.process import (
        HeldMean,
        force_law_terms,
        make_cutting_force_law,
    )
    from deburr_drake.config import ProcessConfig

    builder = DiagramBuilder()
    plant = _point_on_three_joints(builder, 1.0)
    config = ProcessConfig(
        cutting_coefficient=3.0e9,
        threshold_power_force=0.0,
        contact_threshold_force=0.0,
    )
    law = builder.AddSystem(
        make_cutting_force_law(3, 3, config.smoothing_speed)
    )
    builder.Connect(
        plant.get_state_output_port(), law.GetInputPort("plant_state")
    )
    builder.Connect(
        law.GetOutputPort("generalized_force"),
        plant.get_applied_generalized_force_input_port(),
    )
    terms_port = builder.ExportInput(law.GetInputPort("force_law_terms"))
    pushes = [
        builder.ExportInput(law.GetInputPort("actuation")),
        builder.ExportInput(plant.get_actuation_input_port()),
    ]
    diagram = builder.Build()
    simulator = _fixed_cenic(diagram, h)
    root = simulator.get_mutable_context()
    context = plant.GetMyMutableContextFromRoot(root)
    a = np.ones(3) / np.sqrt(3.0)
    n1 = np.array([1.0, -1.0, 0.0]) / np.sqrt(2.0)
    for port in pushes:  # the law reads what drives the plant
        diagram.get_input_port(port).FixValue(root, push * a)
    plant.SetVelocities(context, 0.05 * a)
    speeds = []
    for k in range(1, 5):
        v = plant.GetVelocities(context)
        held = None
        if treatment == "held":
            M = plant.CalcMassMatrix(context)
            held = HeldMean(
                np.linalg.solve(M, a), 0.0, plant.MakeActuationMatrix(), h
            )
        diagram.get_input_port(terms_port).FixValue(
            root,
            force_law_terms(
                config,
                n1,
                a,
                5e-4,
                np.eye(3),
                v,
                cut_height=0.002,
                v=v if treatment != "plain" else None,
                held=held,
            ),
        )
        simulator.AdvanceTo(k * h)
        speeds.append(plant.GetVelocities(context) @ a)
    return np.array(speeds)


def test_cutting_laws_implicit_damping_holds_any_g_at_one_cenic_step():
    """The cutting law along (1, 1, 1) at h g / m = 7.5: eq. (3) as is
    alternates and grows in cenic, -1.14 per step (as the rank-one damper
    above); with process.implicit_damping's term it decays as implicit
    Euler, 1 / (1 + h g / m) (here D = g I exactly)."""
    plain = _cutting_law_velocities("plain")
    np.testing.assert_allclose(plain[1:] / plain[:-1], -4.0 / 3.5, rtol=1e-3)
    held = _cutting_law_velocities("implicit")
    np.testing.assert_allclose(held[1:] / held[:-1], 1 / 8.5, rtol=1e-3)


def test_cutting_laws_held_mean_is_the_exact_damper_at_one_cenic_step():
    """process.sample_mean at h g / m = 7.5 along (1, 1, 1): in cenic, one
    step per sample, the speed follows the damper's closed form exactly,
    exp(-7.5) per step with nothing else acting; with a 6 N push on the
    actuators (the held mean takes the sample's actuation) it settles at
    push / g = 2 mm/s, as the continuous damper does."""
    from deburr_drake.math.damping import held_damper_end_speed

    free = _cutting_law_velocities("held")
    # (after two steps the speed, 1.5e-8 m/s, is at the solver's
    # tolerance)
    np.testing.assert_allclose(
        free[:2] / [0.05, free[0]], np.exp(-7.5), rtol=1e-4
    )
    pushed = _cutting_law_velocities("held", push=6.0)
    u, expected = 0.05, []
    for _ in range(4):
        u = held_damper_end_speed(3000.0, 0.0, u, 1.0, 6.0, 0.0025)
        expected.append(u)
    np.testing.assert_allclose(pushed, expected, rtol=1e-6, atol=1e-9)
    assert pushed[-1] == pytest.approx(6.0 / 3000.0, rel=1e-3)
