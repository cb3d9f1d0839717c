"""Fault injection: each fault's effect on the signal it touches."""

import numpy as np
import pytest

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.cell.edge import believed_contour_step
from deburr_drake.cell.faults import SensorFaults
from deburr_drake.config import ConfigError, load_scenario
from deburr_drake.control.layout import CHAMFER_STATE
from deburr_drake.runs.simulation import simulate


def _faults(text):
    return load_scenario("paper", text=f"faults: {text}").faults


def test_bias_and_dropouts_on_the_reading():
    faults = _faults(
        "{sensor_bias: [1.0, -2.0, 0.5], dropouts: ["
        "{start: 1.0, duration: 0.5, mode: hold}, "
        "{start: 2.0, duration: 0.5, mode: zero}]}"
    )
    system = SensorFaults(faults, 0.0025)
    context = system.CreateDefaultContext()
    port = system.get_input_port()
    assert port.get_name() == "measured_force"
    assert system.get_output_port().get_name() == "faulted_force"
    port.FixValue(context, [3.0, 4.0, 5.0])
    out = system.get_output_port()
    context.SetTime(0.9)
    np.testing.assert_allclose(out.Eval(context), [4.0, 2.0, 5.5])
    # The sample before the window stores the biased reading ...
    context.SetDiscreteState(
        system.EvalUniquePeriodicDiscreteUpdate(context).get_vector(0).value()
    )
    # ... which the hold window keeps whatever the sensor says.
    port.FixValue(context, [30.0, 40.0, 50.0])
    context.SetTime(1.2)
    np.testing.assert_allclose(out.Eval(context), [4.0, 2.0, 5.5])
    np.testing.assert_allclose(  # no update inside the window
        system.EvalUniquePeriodicDiscreteUpdate(context).get_vector(0).value(),
        [4.0, 2.0, 5.5],
    )
    context.SetTime(2.2)
    np.testing.assert_allclose(out.Eval(context), [0.0, 0.0, 0.0])
    context.SetTime(2.5)  # the window is half-open
    np.testing.assert_allclose(out.Eval(context), [31.0, 38.0, 50.5])


def test_noise_scale_multiplies_the_sensor_noise():
    scenario = load_scenario("paper", text="faults: {noise_scale: 3.0}")
    diagram = make_deburring_diagram(scenario=scenario)
    gain = diagram.GetSubsystemByName("sensor_noise_scale")
    context = gain.CreateDefaultContext()
    gain.get_input_port().FixValue(context, [1.0, -2.0, 0.5])
    np.testing.assert_allclose(
        gain.get_output_port().Eval(context), [3.0, -6.0, 1.5]
    )


def test_no_fault_adds_no_system(paper_cell):
    _, diagram = paper_cell()
    names = {s.get_name() for s in diagram.GetSystems()}
    assert not names & {"sensor_faults", "sensor_noise_scale"}


@pytest.mark.parametrize(
    "text, field",
    [
        (
            "{dropouts: [{start: 1.0, duration: 0.0}]}",
            "faults.dropouts[0].duration",
        ),
        (
            "{dropouts: [{start: 1.0, duration: 1.0, mode: last}]}",
            "faults.dropouts[0].mode",
        ),
        ("{noise_scale: -1.0}", "faults.noise_scale"),
        ("{sensor_bias: [1.0]}", "faults.sensor_bias"),
    ],
)
def test_bad_faults_name_the_field(text, field):
    with pytest.raises(
        ConfigError,
        match=field.replace(".", r"\.").replace("[", r"\[").replace("]", r"\]"),
    ):
        _faults(text)


@pytest.mark.slow
def test_bias_and_dropout_in_the_closed_loop():
    """A +2 N bias along n1 (world x at the start): the controller holds
    its measured force, the true one is 2 N higher. A zero dropout: the
    observer reads 0 N inside the window."""
    scenario = load_scenario(
        "paper",
        text="""
faults:
  sensor_bias: [2.0, 0.0, 0.0]
  dropouts: [{start: 3.0, duration: 0.2, mode: zero}]
""",
    )
    log = simulate(
        make_deburring_diagram(scenario=scenario),
        scenario,
        # to the dropout window's end: nothing after 3.2 s is read
        duration=3.25,
        progress_interval=3.25,
    )
    ch, sensed = log["chamfer"], log["tool_force"]["value"]
    true_f_n = -np.einsum("ij,ij->i", sensed, ch["n1"])
    settled = (ch["t"] > 2.0) & (ch["t"] < 2.99)
    assert np.mean(true_f_n[settled] - ch["f_n"][settled]) == pytest.approx(
        2.0, abs=0.05
    )
    window = (ch["t"] >= 3.0) & (ch["t"] < 3.2)
    assert np.all(ch["f_n"][window] == 0.0)
    assert np.all(true_f_n[window] > 1.0)  # the contact is still there


def test_part_step_moves_the_part_the_controller_sees():
    """faults.part_step: the real part moves by 0.3 mm along x (n1 at the
    start of the point-mass testbed's edge is +x) at 0.5 s. Before it the
    observer and the command generator see the part as it was; from 0.5 s
    on, the observer's depth at the same tool state is 0.3 mm larger (the
    part the controller believes in sits 0.3 mm nearer the tool than the
    real one), and the command moves onto the stepped contour."""
    scenario = load_scenario(
        "point_mass",
        text="""
faults: {part_step: {time: 0.5, offset: [0.0003, 0.0, 0.0]}}
""",
    )
    diagram = make_deburring_diagram(scenario=scenario)
    context = diagram.CreateDefaultContext()
    observer = diagram.GetSubsystemByName("chamfer_observer")
    generator = diagram.GetSubsystemByName("command_generator")

    def chamfer(t):
        context.SetTime(t)
        return CHAMFER_STATE.split(
            observer.GetOutputPort("chamfer_state").Eval(
                observer.GetMyContextFromRoot(context)
            )
        )

    before, after = chamfer(0.49), chamfer(0.5)
    np.testing.assert_allclose(before["n1"], [1.0, 0.0, 0.0], atol=1e-9)
    assert after["delta"] - before["delta"] == pytest.approx(3e-4, abs=1e-9)
    gc = generator.GetMyMutableContextFromRoot(context)
    for t in (0.475, 0.5):
        context.SetTime(t)
        x_c = (
            generator.EvalUniquePeriodicDiscreteUpdate(gc)
            .get_vector(0)
            .CopyToVector()[:3]
        )
        # The command lies on the zero-depth contour the observer uses.
        contour = (
            generator.contour if t < 0.5 else believed_contour_step(scenario)[1]
        )
        assert abs(contour.phi(x_c)) < 1e-9


@pytest.mark.parametrize(
    "text, field",
    [
        (
            "{part_step: {time: -1.0, offset: [0.001, 0.0, 0.0]}}",
            "faults.part_step.time",
        ),
        ("{part_step: {time: 1.0}}", "faults.part_step.offset"),
    ],
)
def test_bad_part_step_names_the_field(text, field):
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        _faults(text)
