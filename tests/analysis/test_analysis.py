"""deburr_drake.analysis: the methods on hand-derived systems, then the
cell (point-mass testbed) against eq. (8) and the sampled-loop limit, the
summary keys and the command line's errors."""

import dataclasses
import json

import numpy as np
from pydrake.examples import PendulumPlant
from pydrake.systems.analysis import SimulatorConfig
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import (
    Linearize,
    LinearSystem,
    MatrixGain,
    ZeroOrderHold,
)
import pytest
import scipy.linalg

from deburr_drake import analysis
from deburr_drake.cli import main
from deburr_drake.config import ConfigError, load_scenario

# --- the methods on hand-derived systems ---------------------------------


def _mass_under_sampled_pd(m, kp, kd, T):
    """A mass (x, v) under u = -kp x - kd v through a zero-order hold."""
    builder = DiagramBuilder()
    plant = builder.AddNamedSystem(
        "mass",
        LinearSystem(
            A=[[0, 1], [0, 0]],
            B=[[0], [1 / m]],
            C=np.eye(2),
            D=np.zeros((2, 1)),
        ),
    )
    hold = builder.AddNamedSystem("hold", ZeroOrderHold(T, 2))
    gain = builder.AddNamedSystem("pd", MatrixGain(np.array([[-kp, -kd]])))
    builder.Connect(plant.get_output_port(), hold.get_input_port())
    builder.Connect(hold.get_output_port(), gain.get_input_port())
    builder.Connect(gain.get_output_port(), plant.get_input_port())
    return builder.Build()


def _zoh_closed_form_rho(m, kp, kd, T):
    """x_{k+1} = (Ad - Bd K) x_k, Ad = [[1, T], [0, 1]],
    Bd = [T^2 / (2 m), T / m]: the exact ZOH discretization."""
    Ad = np.array([[1.0, T], [0.0, 1.0]])
    Bd = np.array([[T * T / (2 * m)], [T / m]])
    return max(abs(np.linalg.eigvals(Ad - Bd @ np.array([[kp, kd]]))))


@pytest.mark.parametrize("kd", [10.0, 250.0])
def test_period_map_of_a_mass_under_sampled_pd_matches_the_zoh_closed_form(kd):
    m, kp, T = 1.0, 100.0, 0.01
    diagram = _mass_under_sampled_pd(m, kp, kd, T)
    context = diagram.CreateDefaultContext()
    context.SetTime(3 * T)  # just before a sample, as AdvanceTo leaves it
    diagram.GetSubsystemByName("mass").GetMyMutableContextFromRoot(
        context
    ).SetContinuousState([0.01, -0.02])
    entries = [
        analysis.StateEntry("mass", "continuous", step=1e-6),
        analysis.StateEntry("hold", "discrete", 0, step=1e-6),
    ]
    # RK3 integrates a constant-input double integrator exactly.
    config = SimulatorConfig(
        integration_scheme="runge_kutta3",
        max_step_size=T / 4,
        use_error_control=False,
    )
    Phi = analysis.period_map(
        diagram, context, entries, period=T, config=config
    )
    expected = _zoh_closed_form_rho(m, kp, kd, T)
    assert analysis.spectral_radius(Phi) == pytest.approx(expected, rel=1e-6)
    # kd T / m = 2.5 > 2: the sampled loop is unstable though the
    # continuous one (any kp, kd > 0) is not.
    assert (expected > 1.0) == (kd == 250.0)
    # The held value is overwritten by the sample: its columns are zero.
    np.testing.assert_allclose(Phi[:, 2:], 0.0, atol=1e-9)
    # The loop is linear: one-sided differences give the same map.
    one_sided = [dataclasses.replace(e, central=False) for e in entries]
    np.testing.assert_allclose(
        analysis.period_map(
            diagram, context, one_sided, period=T, config=config
        ),
        Phi,
        rtol=1e-6,
        atol=1e-6,
    )


def test_numerical_linearization_matches_drake_linearize_on_a_pendulum():
    builder = DiagramBuilder()
    pendulum = builder.AddNamedSystem("pendulum", PendulumPlant())
    pd = builder.AddNamedSystem("pd", MatrixGain(np.array([[-20.0, -3.0]])))
    builder.Connect(pendulum.get_state_output_port(), pd.get_input_port())
    builder.Connect(pd.get_output_port(), pendulum.get_input_port())
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    x0 = np.array([0.7, -0.3])
    context.SetContinuousState(x0)
    slices = analysis.continuous_state_slices(diagram, context)
    assert slices == {"pendulum": slice(0, 2)}

    def f(x):
        context.SetContinuousState(x)
        return diagram.EvalTimeDerivatives(context).CopyToVector()

    A = analysis.numerical_jacobian(f, x0, 1e-6)
    context.SetContinuousState(x0)
    drake_A = Linearize(diagram, context, equilibrium_check_tolerance=1e6).A()
    np.testing.assert_allclose(A, drake_A, rtol=1e-6, atol=1e-6)
    # Hand-derived: theta'' = (-m g l sin(theta) - b theta' + u) / (m l^2).
    params = pendulum.get_parameters(pendulum.GetMyContextFromRoot(context))
    ml2 = params.mass() * params.length() ** 2
    expected = np.array(
        [
            [0.0, 1.0],
            [
                (
                    -params.mass()
                    * params.gravity()
                    * params.length()
                    * np.cos(0.7)
                    - 20.0
                )
                / ml2,
                (-params.damping() - 3.0) / ml2,
            ],
        ]
    )
    np.testing.assert_allclose(A, expected, rtol=1e-6, atol=1e-8)


def test_margins_of_a_discrete_integrator_loop():
    # Phi_ol = 1, b = -g, c = 1: L(z) = g / (z - 1), closed-loop pole 1 - g.
    g, T = 0.5, 0.01
    r = analysis.loop_from_map(np.array([[1.0 - g]]), [-g], [1.0], T)
    # Phase -180 at the Nyquist frequency, |L| = g / 2 there.
    assert r.gain_margin_dB == pytest.approx(20 * np.log10(2 / g), abs=0.05)
    assert r.phase_crossover_hz == pytest.approx(0.5 / T, rel=1e-3)
    # |e^{j th} - 1| = g: th = 2 asin(g / 2), PM = 90 - th / 2 (degrees).
    theta = 2 * np.arcsin(g / 2)
    assert r.phase_margin_deg == pytest.approx(
        90 - np.degrees(theta) / 2, abs=0.05
    )
    assert r.gain_crossover_hz == pytest.approx(
        theta / (2 * np.pi * T), rel=1e-3
    )


def test_eq8_time_constant():
    assert analysis.eq8_time_constant(4e-4, 1e4, 20.0) == pytest.approx(
        (1 + 4e-4 * 20) / (4e-4 * 1e4)
    )


# --- the cell ------------------------------------------------------------


@pytest.fixture(scope="module")
def point_mass_op():
    return analysis.find_operating_point(
        load_scenario("point_mass"), after_contact=1.5
    )


@pytest.mark.slow
def test_point_mass_depth_mode_matches_eq8(point_mass_op):
    from deburr_drake.cell.truth import contact_truth

    sc = point_mass_op.scenario
    truth = contact_truth(sc)
    lin = analysis.linearize_closed_loop(
        point_mass_op, stiffness=truth.local_stiffness
    )
    tau8 = analysis.eq8_time_constant(
        sc.controller.depth_gain, truth.local_stiffness, truth.c2
    )
    assert lin.depth_time_constant == pytest.approx(tau8, rel=0.10)
    assert all(m.eigenvalue.real < 0 for m in lin.modes)
    assert {"depth/force", "tangential"} <= set(lin.groups())


@pytest.fixture(scope="module")
def paper_op():
    return analysis.find_operating_point(
        load_scenario("paper"), after_contact=1.0
    )


@pytest.mark.slow
def test_paper_arm_depth_mode_matches_eq8_and_the_loop_is_stable(paper_op):
    from deburr_drake.cell.truth import contact_truth

    op = paper_op
    sc = op.scenario
    truth = contact_truth(sc)
    lin = analysis.linearize_closed_loop(op, stiffness=truth.local_stiffness)
    tau8 = analysis.eq8_time_constant(
        sc.controller.depth_gain, truth.local_stiffness, truth.c2
    )
    assert lin.depth_time_constant == pytest.approx(tau8, rel=0.10)
    assert "joint" in lin.groups()
    assert analysis.sampled_loop(op).spectral_radius < 1.0


def test_frozen_scenario_freezes_the_adaptation_and_the_noise():
    sc = load_scenario("point_mass")
    frozen = analysis.frozen_scenario(
        sc, continuous=True, **{"sensor.cutoff_frequency": 7.0}
    )
    assert not frozen.estimator.adapt and not frozen.controller.fuzzy.adapt
    assert frozen.sensor.noise_std == 0.0
    assert frozen.controller.control_period == 0.0
    assert frozen.sensor.cutoff_frequency == 7.0
    assert not frozen.simulation.error_control
    assert frozen.simulation.max_step == sc.controller.control_period
    assert sc.estimator.adapt and sc.sensor.cutoff_frequency != 7.0


@pytest.mark.slow
def test_point_mass_sampled_loop_goes_unstable_with_a_fast_sensor(
    point_mass_op,
):
    stable = analysis.sampled_loop(point_mass_op)
    fast = analysis.sampled_loop(
        point_mass_op, **{"sensor.cutoff_frequency": 60.0}
    )
    assert stable.spectral_radius < 1.0 < fast.spectral_radius
    # The slow real eigenvalue is the continuous depth mode, sampled.
    worst = fast.eigenvalues[np.argmax(np.abs(fast.eigenvalues))]
    assert worst.real < -1.0  # a Nyquist-frequency (200 Hz) oscillation


def test_operating_point_without_contact_is_a_config_error():
    sc = load_scenario(
        "point_mass",
        text=(
            "estimator: {initial_estimates: [0.1, 100.0, 1.0], adapt: false}"
        ),
    )
    with pytest.raises(ConfigError, match="never reached contact"):
        analysis.find_operating_point(sc, max_time_to_contact=0.2)


@pytest.mark.slow
def test_analyze_writes_the_summary_keys(tmp_path, capsys):
    code = main(
        [
            "analyze",
            "--scenario",
            "point_mass",
            "--after-contact",
            "1.0",
            "--until",
            "3.5",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0
    data = json.loads((tmp_path / "analysis.json").read_text())
    for key in analysis.SUMMARY_KEYS:
        assert key in data, key
    assert data["verdict"] == "stable"
    assert all(len(e) == 2 for e in data["eigenvalues"])
    assert 0.5 < data["sampled_spectral_radius"] < 1.0
    for key in ("time", "depth", "feed", "normal_force", "chamfering_force"):
        assert key in data["operating_point"]
    along = data["rho_along_run"]
    assert [p["kind"] for p in along][:2] == ["transient", "cutting"]
    assert all(0 < p["rho"] < 1 and 0 <= p["t"] <= 3.5 for p in along)
    # 1 s after contact the point mass is still in its transient: the
    # operating point moves on to where the run is steady
    assert data["operating_point"]["time"] > 1.5
    assert "operating point" in [p["kind"] for p in along]
    robust = data["robust"]
    assert (
        robust["rho_worst"] >= max(m["rho"] for m in robust["maps"]) - 1e-12
        and robust["rho_worst"] >= robust["rho_nominal"]
    )
    # off the burrs: nominal, both ends of 4 parameters, 1 or 2 corners
    assert len(robust["maps"]) in (10, 11)
    assert robust["rho_worst_oscillatory"] == max(
        m["rho_oscillatory"] for m in robust["maps"]
    )
    assert "outer_period_spectral_radius" not in data
    for name in ("poles.png", "bode_nyquist.png", "rho_along_run.png"):
        assert (tmp_path / name).stat().st_size > 0
    out = capsys.readouterr().out
    summary = out[out.index("verdict:") :]
    assert summary.startswith("verdict: STABLE")
    assert "spectral radius" in summary


@pytest.mark.slow
def test_analyze_does_not_linearize_an_oscillating_run(tmp_path, capsys):
    # The 1.8 kg point mass with a sliding gain K = 3000 N s/m above
    # M / T = 720 N s/m of the 2.5 ms loop: a 200 Hz limit cycle from the
    # first contact on.
    code = main(
        [
            "analyze",
            "--scenario",
            "point_mass",
            "--scenario-text",
            "controller: {sliding_gain: [3000.0, 3000.0, 1500.0]}",
            "--after-contact",
            "1.0",
            "--until",
            "2.5",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0
    data = json.loads((tmp_path / "analysis.json").read_text())
    assert data["verdict"] == "unstable"
    assert data["eigenvalues"] is None and data["robust"] is None
    assert data["oscillation"]["frequency_hz"] > 150.0
    assert "oscillat" in data["verdict_reason"]
    # the drives' 200 N limit of the shipped point mass (its guard's
    # joint_torque) would have stopped this run
    guard = data["guard_that_would_stop"]
    assert guard["guard"] == "joint_torque" and guard["time"] < 2.5
    assert guard["guard"] in data["verdict_reason"]
    assert all(
        p["rho"] is None
        for p in data["rho_along_run"]
        if p["kind"] != "transient"
    )
    assert not (tmp_path / "poles.png").exists()
    out = capsys.readouterr().out
    assert out[out.index("verdict:") :].startswith("verdict: UNSTABLE")


@pytest.mark.parametrize(
    "option",
    [
        ["--at", "-3"],
        ["--until", "0"],
        ["--at", "5", "--until", "4"],
        ["--spacing", "nan"],
    ],
)
def test_bad_times_are_refused_before_anything_runs(tmp_path, option, capsys):
    out = tmp_path / "analysis"
    assert (
        main(
            ["analyze", "--scenario", "point_mass", *option, "--out", str(out)]
        )
        == 2
    )
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and option[-2] in err
    assert not out.exists()


def test_rho_of_map_of_a_rotation_and_a_decay():
    T = 0.0025
    a, r = 2 * np.pi * 50 * T, 0.9
    Phi = np.diag([0.5, 0.0, 0.0])
    Phi[1:, 1:] = r * np.array(
        [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
    )
    out = analysis.rho_of_map(Phi, T)
    assert out["rho"] == pytest.approx(r)
    assert out["frequency_hz"] == pytest.approx(50.0)
    assert out["decay_rate"] == pytest.approx(-np.log(r) / T)


def test_field_units_come_from_the_config_comments():
    sc = load_scenario("paper")
    assert analysis.field_unit(sc, "sensor.cutoff_frequency") == "Hz"
    assert analysis.field_unit(sc, "controller.sliding_gain[0]") == "N s/m"
    assert analysis.field_unit(sc, "controller.depth_gain") == "m/(N s)"
    assert analysis.field_unit(sc, "part.material.hydroelastic_modulus") == "Pa"
    assert analysis.field_unit(sc, "controller.model_mass_scale") == ""


@pytest.mark.parametrize(
    "spec, message",
    [
        ("controller.no_such_gain=1:2:3", "unknown"),
        ("sensor.cutoff_frequency=5:5:4", "empty range"),
        ("sensor.cutoff_frequency=5:80:0", "empty range"),
        ("sensor.cutoff_frequency=5-80", "expected FIELD=LO:HI:N"),
    ],
)
def test_bad_map_is_one_error_line(spec, message, capsys):
    assert main(["analyze", "--scenario", "point_mass", "--map", spec]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err


def test_set_field_by_dotted_name():
    sc = load_scenario("point_mass")
    analysis.set_field(sc, "controller.sliding_gain[1]", 123.0)
    analysis.set_field(sc, "sensor.cutoff_frequency", 7)
    assert sc.controller.sliding_gain[1] == 123.0
    assert sc.sensor.cutoff_frequency == 7.0
    with pytest.raises(ConfigError):
        analysis.set_field(sc, "sensor.cutoff", 1.0)


def test_fuzzy_slope_adds_slope_times_s_to_the_surface():
    from deburr_drake.cell.diagram import make_deburring_diagram

    sc = load_scenario("point_mass")
    diagram = make_deburring_diagram(scenario=sc)
    context = diagram.CreateDefaultContext()
    controller = diagram.GetSubsystemByName("controller")
    cc = controller.GetMyContextFromRoot(context)
    before = controller.theta(cc).copy()
    analysis.add_fuzzy_slope(diagram, context, 750.0)
    theta = controller.theta(cc)
    for k, rb in enumerate(controller.rule_bases):
        for s in (
            -0.7 * rb.omegak_half_width,
            0.013 * rb.omegak_half_width,
            0.4 * rb.omegak_half_width,
        ):
            u_before = rb.evaluate(before[k], 0.03, s)
            u_after = rb.evaluate(theta[k], 0.03, s)
            assert u_after - u_before == pytest.approx(750.0 * s, rel=1e-9)


def test_stability_map_grid_and_figure(tmp_path):
    sc = load_scenario("point_mass")
    axes = analysis.parse_map(
        sc,
        [
            "sensor.cutoff_frequency=10:40:4",
            "controller.sliding_gain[0]=100:400:3",
        ],
    )
    assert [a.field for a in axes] == [
        "sensor.cutoff_frequency",
        "controller.sliding_gain[0]",
    ]
    np.testing.assert_allclose(axes[0].values, [10, 20, 30, 40])

    class _Op:  # only the scenario's name is read without a simulation
        scenario = sc

    seen = []

    def rho_of(**overrides):
        seen.append(overrides)
        return overrides["sensor.cutoff_frequency"] / 25.0

    m = analysis.stability_map(_Op(), axes, rho_of=rho_of)
    assert m.rho.shape == (4, 3) and len(seen) == 12
    np.testing.assert_allclose(m.rho[:, 0], [0.4, 0.8, 1.2, 1.6])
    assert m.units == {
        "sensor.cutoff_frequency": "Hz",
        "controller.sliding_gain[0]": "N s/m",
    }
    from deburr_drake.analysis.maps import rho_colour_norm

    norm = rho_colour_norm(m.rho)
    assert norm(1.0) == pytest.approx(0.5)  # the middle of the scale
    assert norm(1.05) > 0.5 > norm(0.95)  # 1.05 is on the red side
    path = analysis.plot_map(m, tmp_path / "map.png")
    assert path.stat().st_size > 0


def test_settings_at_the_operating_point_are_checked():
    sc = load_scenario("paper")
    assert analysis.parse_settings(sc, ["controller.sliding_gain[1]=4500"]) == {
        "controller.sliding_gain[1]": 4500.0
    }
    for bad in (
        ["controller.sliding_gain[7]=1"],
        ["sensor.cutoff=3"],
        ["sensor.cutoff_frequency"],
        ["sensor.cutoff_frequency=x"],
        ["sensor.cutoff_frequency=300"],
    ):
        with pytest.raises(ConfigError):
            analysis.parse_settings(sc, bad)


def test_lyapunov_v1_starts_at_the_estimate_error():
    from deburr_drake.cell.truth import contact_truth

    sc = load_scenario("point_mass")
    trace = analysis.lyapunov_trace(sc, duration=0.2, sample_period=0.05)
    truth = contact_truth(sc)
    c_error = np.array(sc.estimator.initial_estimates) - [
        truth.c0,
        truth.secant_stiffness,
        truth.c2,
    ]
    gains = np.array(sc.estimator.gains)
    expected = np.sum(c_error[gains > 0] ** 2 / (2 * gains[gains > 0]))
    # At t = 0 the tool is nearly at rest on its command: s^T M s / 2 is
    # micro-joules against the estimate error's 0.3 J.
    assert expected <= trace.V1[0] <= expected + 1e-5
    assert np.all(np.isfinite(trace.V)) and np.all(trace.V >= trace.V1 - 1e-12)
    assert len(trace.t) == 5


@pytest.mark.slow
def test_held_columns_match_the_one_sided_ones_and_a_missing_port_is_caught(
    paper_op, monkeypatch
):
    from deburr_drake.analysis import sampled

    frozen = analysis.FrozenMap(paper_op.scenario, plan=paper_op.plan)
    context = frozen.context_from(paper_op.diagram, paper_op.context)
    runs = []
    run = sampled._OnePeriod.__call__
    monkeypatch.setattr(
        sampled._OnePeriod,
        "__call__",
        lambda self, z: runs.append(1) or run(self, z),
    )

    def period_map(held_through):
        return analysis.period_map(
            frozen.diagram,
            context,
            frozen.entries,
            period=frozen.period,
            config=frozen.config,
            held_through=held_through,
        )

    every_column = period_map(())
    runs.clear()
    held = frozen.at_context(context)
    # 14 central columns, the unperturbed period, a basis of the 13
    # ports' values and the check, against 66 held columns.
    assert len(runs) <= 2 * 14 + 1 + 13 + 1
    # In the coordinates the certificate balances the map to.
    _, (scale, _) = scipy.linalg.matrix_balance(
        every_column, permute=False, separate=True
    )
    balance = (1.0 / scale)[:, None] * scale[None, :]
    assert np.linalg.norm((held - every_column) * balance, 2) < 1e-7 * (
        np.linalg.norm(every_column * balance, 2)
    )
    assert analysis.spectral_radius(held) == pytest.approx(
        analysis.spectral_radius(every_column), abs=1e-10
    )
    # Without the sensor's port, the law's force reaches the sensor
    # unseen: the check catches it and every column is simulated.
    np.testing.assert_array_equal(
        period_map(frozen.held_through[:2]), every_column
    )


@pytest.mark.slow
def test_fast_map_matches_the_full_map(paper_op):
    fields = ["sensor.cutoff_frequency", "controller.sliding_gain[0]"]
    rho_of = analysis.fast_rho(paper_op, fields)
    assert analysis.fast_rho(paper_op, ["part.edge.inner_radius"]) is None
    # At the scenario's own parameters the split is exact; elsewhere the
    # integration is linearized along the base trajectory (first order in
    # the change of held actuation: 5 % here, 1 s after contact; 2e-5 at
    # the steadier 3 s operating point).
    base = {fields[0]: 10.0, fields[1]: 400.0}
    assert rho_of(**base) == pytest.approx(
        analysis.sampled_loop(paper_op, **base).spectral_radius, abs=1e-4
    )
    far = {fields[0]: 60.0, fields[1]: 5000.0}
    full = analysis.sampled_loop(paper_op, **far).spectral_radius
    assert full > 1.0 and rho_of(**far) == pytest.approx(full, rel=0.1)


def test_the_verdicts_numerics_refine_the_step_and_follow_eq3():
    from deburr_drake.analysis.along import at_numerics

    paper = load_scenario("paper")
    refined = at_numerics(paper)
    assert refined.simulation.max_step == pytest.approx(
        paper.simulation.max_step / 4
    )
    assert not refined.process.sample_mean and paper.process.sample_mean
    assert at_numerics(paper, "shipped") is paper
    with pytest.raises(ConfigError, match="--numerics"):
        at_numerics(paper, "finer")


@pytest.mark.slow
def test_analyze_states_the_numerics_of_its_verdict(tmp_path, capsys):
    code = main(
        [
            "analyze",
            "--scenario",
            "point_mass",
            "--after-contact",
            "0.5",
            "--until",
            "1.0",
            "--no-robust",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0
    data = json.loads((tmp_path / "analysis.json").read_text())
    numerics = data["numerics"]
    shipped = load_scenario("point_mass")
    assert numerics["name"] == "refined"
    assert numerics["shipped_max_step_s"] == shipped.simulation.max_step
    assert numerics["max_step_s"] == pytest.approx(
        shipped.simulation.max_step / 4
    )
    assert numerics["sample_mean"] is False
    # the maps integrate their period as the run does, at most one step
    # per period (the analysis's fixed steps replace error control)
    assert numerics["maps_sample_mean"] is False
    assert 0 < numerics["maps_max_step_s"] <= 0.0025 + 1e-12
    assert numerics["run_wall_time_s"] > 0
    out = capsys.readouterr().out
    assert "numerics (refined): the run at 2.5 ms steps, eq. (3)" in out


def test_the_verdict_tables_truth_runs_at_the_verdicts_numerics():
    from deburr_drake.analysis.along import at_numerics
    from deburr_drake.analysis.validation import truth_scenario

    paper = load_scenario("paper")
    truth = truth_scenario(paper)
    verdict = at_numerics(paper)
    assert truth.simulation.max_step == verdict.simulation.max_step
    assert truth.simulation.max_step < paper.simulation.max_step
    assert truth.process.sample_mean is False
    assert truth.guards.enabled is False
    shipped = truth_scenario(paper, "shipped")
    assert shipped.simulation.max_step == paper.simulation.max_step
    assert shipped.guards.enabled is False and paper.guards.enabled
