"""Baseline controllers: each law's output by hand on the
Cartesian point mass (J = I), the Appendix gains, the constant-feed command,
and a short closed-loop run of each baseline on the paper cell. The full
passes are ``scripts/paper_comparison.py``, not tests."""

import numpy as np
import pytest

# The controller tests' contour and tool point: the laws are checked at
# the same place.
from test_controller import CONTOUR
from test_controller import _scenario_point as _point

from deburr_drake.cell.models import POINT_MASS_URL, make_kinematic_model
from deburr_drake.config import (
    CommandConfig,
    ConfigError,
    ControllerConfig,
    TaskConfig,
)
from deburr_drake.control.command import CommandGenerator
from deburr_drake.control.controller import HybridController
from deburr_drake.control.laws import LAWS, appendix_gains, robust_term
from deburr_drake.control.layout import COMMAND_STATE, CONTROLLER_DIAGNOSTICS
from deburr_drake.control.observer import chamfer_quantities

G = 9.81
M_Z = 0.3 + 1.0  # flange + tool (kg): what the z joint carries
MASSES = np.array([0.5 + 0.5 + M_Z, 0.5 + M_Z, M_Z])  # x, y, z carriages


@pytest.fixture(scope="module")
def model():
    return make_kinematic_model(POINT_MASS_URL)


def _context(controller, delta_d=3e-4, f_nd=6.0):
    """The controller's context at the tool point of :func:`_point`, its
    inputs fixed, delta_d set (float or AutoDiffXd controller)."""
    x_p, v, force, x_c, v_c, _ = _point()
    chamfer = chamfer_quantities(
        CONTOUR, x_p, v, force, min_tangential_speed=1e-5
    )
    context = controller.CreateDefaultContext()
    for name, value in dict(
        plant_state=np.concatenate([x_p, v]),
        chamfer_state=chamfer,
        measured_force=force,
        commanded_position=x_c,
        commanded_velocity=v_c,
        desired_normal_force=[f_nd],
    ).items():
        controller.GetInputPort(name).FixValue(context, value)
    x = context.get_continuous_state_vector().CopyToVector()
    x[0] = delta_d
    context.SetContinuousState(x)
    return context


def _evaluate(controller, delta_d=3e-4, f_nd=6.0):
    x_p, v, force, x_c, v_c, n1 = _point()
    context = _context(controller, delta_d, f_nd)
    return (
        controller.GetOutputPort("actuation").Eval(context),
        CONTROLLER_DIAGNOSTICS.split(
            controller.GetOutputPort("diagnostics").Eval(context)
        ),
        controller.EvalTimeDerivatives(context).CopyToVector(),
    )


def _sliding(config, delta_d, dd):
    """e, edot, s of (9), (10) at _point() with depth delta_d, rate dd
    (x_pd = x* + delta_d n1(x_p) moves at xdot* + dd n1 + delta_d n1')."""
    x_p, v, _, x_c, v_c, n1 = _point()
    e = x_c + delta_d * n1 - x_p
    edot = v_c + dd * n1 + delta_d * CONTOUR.n1_rate(x_p, v) - v
    return e, edot, edot + np.array(config.sliding_lambda) * e


def test_robust_law_by_hand(model):
    """(22): K s - f + (b1 + b2 ||x|| + b3 ||x||^2) sgn(s_k)
    + (b4 + b5 ||x||) s_k on x1, x2; gravity from the 1.2-scaled model."""
    gains = [5.0, 2.0, 1.0, 30.0, 4.0]
    config = ControllerConfig(control_period=0.0, kind="robust")
    config.robust.gains = gains
    actuation, d, rates = _evaluate(HybridController(model, "tool_tip", config))
    x_p, _, force, *_ = _point()
    dd = config.depth_gain * (6.0 - 5.0)  # ||f_n|| = 5 N
    _, _, s = _sliding(config, 3e-4, dd)
    r = np.linalg.norm(x_p)
    H = np.array(
        [
            (5 + 2 * r + r * r) * np.sign(s[k]) + (30 + 4 * r) * s[k]
            for k in (0, 1)
        ]
        + [0.0]
    )
    expected = (
        np.array(config.sliding_gain) * s
        - force
        + H
        + [0.0, 0.0, 1.2 * M_Z * G]
    )
    np.testing.assert_allclose(actuation, expected, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(d["u_fuzzy"], H, rtol=1e-9, atol=1e-12)
    assert rates[0] == pytest.approx(dd)  # the depth law (7) is kept
    assert not np.any(rates[1:])  # no adaptation
    assert robust_term(-1e-9, 0.0, gains) == pytest.approx(-5.0 - 30e-9)


def test_ideal_law_by_hand(model):
    """(12) with the true model: K s - f + M lambda edot + true gravity
    (xddot_d = 0, J = I, no Coriolis, no friction on the point mass)."""
    config = ControllerConfig(control_period=0.0, kind="ideal")
    truth = make_kinematic_model(POINT_MASS_URL)
    actuation, _, rates = _evaluate(
        HybridController(model, "tool_tip", config, true_plant=truth)
    )
    _, _, force, *_ = _point()
    dd = config.depth_gain * 1.0
    _, edot, s = _sliding(config, 3e-4, dd)
    lam = np.array(config.sliding_lambda)
    expected = (
        np.array(config.sliding_gain) * s
        - force
        + MASSES * lam * edot
        + [0.0, 0.0, M_Z * G]
    )
    np.testing.assert_allclose(actuation, expected, rtol=1e-9, atol=1e-9)
    assert rates[0] == pytest.approx(dd)


def test_impedance_law_by_hand(model):
    """Impedance along n1 about the nominal path at the desired depth,
    K s across it, no -f, delta_d fixed (no depth law, no estimate)."""
    config = ControllerConfig(control_period=0.0, kind="impedance")
    actuation, d, rates = _evaluate(
        HybridController(model, "tool_tip", config, nominal_depth=5e-4),
        f_nd=50.0,
    )
    *_, n1 = _point()
    e, edot, s = _sliding(config, 5e-4, 0.0)
    k, b = config.impedance.stiffness, config.impedance.damping
    ks = np.array(config.sliding_gain) * s
    f = n1 * (k * (n1 @ e) + b * (n1 @ edot)) + ks - n1 * (n1 @ ks)
    np.testing.assert_allclose(
        actuation, f + [0.0, 0.0, 1.2 * M_Z * G], rtol=1e-9, atol=1e-9
    )
    assert float(d["delta_d"]) == 5e-4
    assert not np.any(rates)


def test_position_law_by_hand(model):
    config = ControllerConfig(control_period=0.0, kind="position")
    actuation, _, rates = _evaluate(
        HybridController(model, "tool_tip", config, nominal_depth=5e-4)
    )
    _, _, s = _sliding(config, 5e-4, 0.0)
    expected = np.array(config.position.sliding_gain) * s + [
        0.0,
        0.0,
        1.2 * M_Z * G,
    ]
    np.testing.assert_allclose(actuation, expected, rtol=1e-9, atol=1e-9)
    assert not np.any(rates)


def test_kinds_need_their_inputs(model):
    with pytest.raises(ValueError, match="nominal_depth"):
        HybridController(model, "tool_tip", ControllerConfig(kind="impedance"))
    with pytest.raises(ValueError, match="true_plant"):
        HybridController(model, "tool_tip", ControllerConfig(kind="ideal"))
    with pytest.raises(ConfigError, match="controller.kind"):
        ControllerConfig(kind="pid").validate()
    with pytest.raises(ConfigError, match=r"controller.robust.gains\[2\]"):
        HybridController(model, "tool_tip", _bad_robust("robust"))
    # The fuzzy law does not read robust.gains.
    HybridController(model, "tool_tip", _bad_robust("fuzzy"))


def _bad_robust(kind):
    config = ControllerConfig(kind=kind)
    config.robust.gains = [1.0, 0.0, -1.0, 0.0, 0.0]
    return config


@pytest.mark.parametrize("kind", ControllerConfig.KINDS)
def test_the_kind_chooses_the_law_once(model, kind):
    """One law object per controller, of the kind's class, also in the
    AutoDiffXd copy; the constant-feed laws are the config's."""
    config = ControllerConfig(control_period=0.0, kind=kind)
    controller = HybridController(
        model, "tool_tip", config, nominal_depth=5e-4, true_plant=model
    )
    assert type(controller.law) is LAWS[kind]
    assert type(controller.ToAutoDiffXd().law) is LAWS[kind]
    assert controller.law.constant_feed == (
        kind in ControllerConfig.CONSTANT_FEED_KINDS
    )


def test_appendix_gains_by_hand():
    b = appendix_gains(
        m_bar=2.0,
        h0=1.0,
        h1=0.5,
        h2=3.0,
        h3=0.25,
        d0=0.1,
        d1=0.2,
        d2=0.3,
        lambda_bar=10.0,
    )
    b1 = (
        2 * 0.3
        + 3
        + 0.2 * 1
        + 0.2 * 0.25
        + 0.04 * 0.5
        + 100 * 2 * 0.1
        + 10 * 0.1 * 1
        + 10 * 0.1 * 0.25
        + 100 * 0.01 * 0.5
        + 2 * 10 * 0.1 * 0.2 * 0.5
    )
    b2 = 10 * (1 + 0.25 + 2 + 2 * 0.5 * 0.2 + 2 * 10 * 0.1 * 0.5)
    np.testing.assert_allclose(
        b, [b1, b2, 100 * 0.5, 0.25 + 20 + 10 * 0.1 * 0.5 + 0.2 * 0.5, 5.0]
    )


def test_constant_feed_is_a_timed_path():
    """x_c advances v T per period whatever the tool does."""
    x0 = CONTOUR.point_at(0.0)
    generator = CommandGenerator(
        CommandConfig(), TaskConfig(), CONTOUR, x0, constant_feed=0.0024
    )
    context = generator.CreateDefaultContext()
    chamfer = chamfer_quantities(
        CONTOUR,
        x0 + [0.0, 0.0, 0.0],
        np.zeros(3),
        np.array([0.0, 0.0, 50.0]),
        min_tangential_speed=1e-5,
    )
    generator.GetInputPort("chamfer_state").FixValue(context, chamfer)
    for _ in range(4):
        context.SetDiscreteState(
            generator.EvalUniquePeriodicDiscreteUpdate(context)
            .get_vector(0)
            .CopyToVector()
        )
    xd = context.get_discrete_state_vector().CopyToVector()
    s0 = generator.start_arc_position
    assert COMMAND_STATE.get(xd, "arc_position") == pytest.approx(
        s0 + 4 * 0.0024 * 0.025
    )
    assert COMMAND_STATE.get(xd, "feed") == 0.0024


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["robust", "ideal", "impedance", "position"])
def test_short_closed_loop_run(kind, paper_cell):
    """2 s of the paper cell: in contact from 0.5 s on, no NaN, no guard."""
    from deburr_drake.math import metrics
    from deburr_drake.runs.simulation import simulate

    scenario, diagram = paper_cell(kind)
    log = simulate(diagram, scenario, duration=2.0)
    assert log.stop_reason == "duration"
    ch = log["chamfer"]
    assert np.all(ch["f_n"][ch["t"] > 0.5] > 1.0)
    assert 2e-4 < ch["delta"][-1] < 8e-4
    assert not metrics.any_nan(
        *[v for b in log.signals.values() for v in b.values()]
    )


def test_high_frequency_power_by_hand():
    from deburr_drake.math.metrics import high_frequency_power

    t = np.arange(4000) * 0.0025
    x = np.c_[
        3 * np.sin(2 * np.pi * 100 * t) + 5 * np.sin(2 * np.pi * 10 * t),
        np.sin(2 * np.pi * 60 * t),
    ]
    assert high_frequency_power(t, x, 50.0) == pytest.approx(4.5 + 0.5)


@pytest.mark.slow
def test_compare_writes_both_files(tmp_path):
    import json

    from deburr_drake.cli import main

    out = tmp_path / "cmp"
    assert (
        main(
            [
                "compare",
                "--controllers",
                "fuzzy,position",
                "--duration",
                "0.5",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    data = json.loads((out / "comparison.json").read_text())
    assert [r["controller"] for r in data["rows"]] == ["fuzzy", "position"]
    assert all(r["stop_reason"] == "duration" for r in data["rows"])
    assert "torque_power_above_50Hz" in data["rows"][0]
    table = (out / "comparison.md").read_text()
    assert "| fuzzy |" in table and "| position |" in table
    assert (out / "position" / "metrics.json").exists()
    assert (
        main(
            [
                "compare",
                "--controllers",
                "fuzzy,pid",
                "--duration",
                "0.5",
                "--out",
                str(tmp_path / "bad"),
            ]
        )
        == 2
    )
    assert not (tmp_path / "bad").exists()


def test_cell_crossings_by_hand():
    from deburr_drake.math.metrics import cell_crossings

    # cells of width 1: [-0.5, 0.5) is 0, [0.5, 1.5) is 1
    assert cell_crossings([0.0, 0.49, 0.5, 0.2, -0.5, -0.51], 1.0) == 3
    assert cell_crossings(np.zeros((5, 2)), 1.0) == 0


@pytest.mark.parametrize("kind", ["robust", "ideal", "impedance", "position"])
def test_scalar_conversion(model, kind):
    """Every kind converts to AutoDiffXd (for linearization) and gives the
    float law's actuation."""
    config = ControllerConfig(control_period=0.0, kind=kind)
    controller = HybridController(
        model, "tool_tip", config, nominal_depth=5e-4, true_plant=model
    )
    expected, _, _ = _evaluate(controller)
    ad = controller.ToAutoDiffXd()
    context = _context(ad)
    actuation = [a.value() for a in ad.GetOutputPort("actuation").Eval(context)]
    np.testing.assert_allclose(actuation, expected, rtol=1e-9, atol=1e-9)
