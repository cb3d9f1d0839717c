"""Runtime guards (issue 10): each trips by requesting termination through
Drake's event status, naming the guard and its values; the drives clamp the
commanded torque at the effort limits."""

import json

import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource
import pytest

from deburr_drake import cli
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.cell.guards import GuardLimits, SafetyGuards
from deburr_drake.config import ConfigError, load_scenario
from deburr_drake.control.layout import CHAMFER_STATE

LIMITS = GuardLimits(
    joint_names=["a", "b"],
    effort_limits=np.array([10.0, np.inf]),
    joint_torque_fraction=1.0,
    tool_force=50.0,
    depth=0.002,
    workspace_low=np.array([-0.1, -0.1, 0.0]),
    workspace_high=np.array([0.1, 0.1, 0.1]),
    contact_lost_time=0.1,
    contact_force=1.0,
    nan=True,
    check_period=0.0025,
    torque_period=0.0,
)


def _chamfer(**values):
    base = dict(
        x_p=[0.0, 0.0, 0.05],
        xdot_p=[0.0] * 3,
        n1=[1.0, 0, 0],
        n2=[0, 1.0, 0],
        delta=0.0005,
        delta_dot=0.0,
        f_n=5.0,
        f_t=10.0,
        arc_position=0.0,
        n1_rate=[0.0] * 3,
    )
    base.update(values)
    return CHAMFER_STATE.pack(**base)


def _run(
    tau=(1.0, 1e6),
    force=(0.0, 0.0, 10.0),
    chamfer=None,
    contact=None,
    extra=(0.0,),
):
    builder = DiagramBuilder()
    signals = {
        "actuation": np.array(tau, float),
        "tool_force": np.array(force, float),
        "chamfer": _chamfer() if chamfer is None else chamfer,
        "estimates": np.array(extra, float),
    }
    guards = builder.AddNamedSystem(
        "guards", SafetyGuards(LIMITS, {k: len(v) for k, v in signals.items()})
    )
    for name, value in signals.items():
        source = builder.AddSystem(ConstantVectorSource(value))
        builder.Connect(source.get_output_port(), guards.GetInputPort(name))
    simulator = Simulator(builder.Build())
    if contact is not None:
        guards.GetMyMutableContextFromRoot(
            simulator.get_mutable_context()
        ).SetDiscreteState(contact)
    simulator.Initialize()
    status = simulator.AdvanceTo(0.5)
    return status


def test_nothing_trips_within_the_limits():
    status = _run()
    assert status.reason() == status.ReturnReason.kReachedBoundaryTime


@pytest.mark.parametrize(
    "kwargs, name, values",
    [
        (dict(tau=(-12.0, 0.0)), "joint_torque", "a |tau| = 12 > 1 x effort"),
        (dict(force=(0.0, 60.0, 0.0)), "tool_force", "|f| = 60 N > 50 N"),
        (dict(chamfer=_chamfer(delta=0.003)), "depth", "delta = 3 mm measured"),
        (
            dict(chamfer=_chamfer(x_p=[0.0, 0.2, 0.05])),
            "workspace",
            "outside the box",
        ),
        (dict(extra=(np.nan,)), "nan", "signal estimates has non-finite"),
        (
            dict(chamfer=_chamfer(f_n=0.0), contact=[1.0, 0.0]),
            "contact_lost",
            "||f_n|| = 0 N <= 1 N for",
        ),
    ],
)
def test_each_guard_requests_termination_with_its_values(kwargs, name, values):
    status = _run(**kwargs)
    assert status.reason() == status.ReturnReason.kReachedTerminationCondition
    assert status.system().get_name() == "guards"
    assert status.message().startswith(f"{name}: ")
    assert values in status.message()
    if name == "contact_lost":
        assert status.return_time() == pytest.approx(0.1025, abs=0.003)
    else:
        assert status.return_time() == 0.0


def test_no_contact_yet_is_not_contact_lost():
    status = _run(chamfer=_chamfer(f_n=0.0))
    assert status.reason() == status.ReturnReason.kReachedBoundaryTime


def test_guards_are_validated():
    with pytest.raises(ConfigError, match=r"guards\.contact_lost_time"):
        load_scenario("paper", text="guards: {contact_lost_time: 0.0}")


def test_the_drives_clamp_the_commanded_torque_at_the_effort_limits(
    paper_cell,
):
    _, diagram = paper_cell()
    saturation = diagram.GetSubsystemByName("drive_saturation")
    context = saturation.CreateDefaultContext()
    saturation.get_input_port().FixValue(context, np.full(5, 1e4))
    np.testing.assert_allclose(
        saturation.get_output_port().Eval(context),
        [150.0, 150.0, 80.0, 20.0, 10.0],
    )
    names = [
        diagram.GetSystems()[i].get_name()
        for i in range(len(diagram.GetSystems()))
    ]
    assert "guards" in names
    off = load_scenario(
        "paper", text="guards: {enabled: false, saturate_effort: false}"
    )
    names = [
        s.get_name() for s in make_deburring_diagram(scenario=off).GetSystems()
    ]
    assert "guards" not in names and "drive_saturation" not in names


def test_a_runaway_gain_stops_on_the_torque_guard(tmp_path, capsys):
    """The issue's runaway: 16,566 N m through an 80 N m elbow and exit 0.
    Now the first commanded torque above the limit stops the run (exit 3)
    and the plant never takes more than the limit (run past the pre-flight,
    which refuses these gains: tests/analysis/test_preflight.py)."""
    out = tmp_path / "run"
    code = cli.main(
        [
            "simulate",
            "--out",
            str(out),
            "--no-preflight",
            "--scenario-text",
            "controller: {sliding_gain: [20000.0, 20000.0, 1500.0]}",
        ]
    )
    assert code == 3
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["stop_reason"] == "guard:joint_torque"
    assert metrics["stop_time_s"] <= 0.0051  # the first sample after it
    assert "effort limit" in metrics["stop_detail"]
    # One sample of commanded torque was logged before the trip.
    with np.load(out / "logs.npz") as logs:
        assert len(logs["actuation.t"]) <= 3


@pytest.mark.slow
def test_the_paper_cell_runs_without_a_trip(paper_log):
    # The session's 5 s of the paper cell (tests/conftest.py): no guard
    # trips within it, so none in its first 0.5 s either.
    assert paper_log.stop_reason == "duration"
    assert paper_log["chamfer"]["t"][-1] == pytest.approx(5.0)
