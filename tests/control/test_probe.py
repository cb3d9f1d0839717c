"""Touch probing: the layout of the touches, the detection-bias model
against the sensor's filter, the sequence's state machine (a touch
compensated by the modelled bias, a burr touch dropped, the hand-over to
the command generator) and the gate."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from deburr_drake.config import ProbeConfig
from deburr_drake.control.layout import CHAMFER_STATE
from deburr_drake.control.probe import (
    PHASES,
    PROBE_STATE,
    ProbeGate,
    ProbingSequence,
    detection_depth,
    measured_stiffness,
    probe_arcs,
    sensor_timing,
)
from deburr_drake.math.geometry import CircularContour, StraightContour


def test_touches_spread_on_closed_and_open_edges():
    circle = CircularContour([0, 0, 0], 0.027)
    arcs = probe_arcs(circle, ProbeConfig(points=4))
    np.testing.assert_allclose(arcs, np.arange(4) * circle.length / 4)
    line = StraightContour([0, 0, 0], [1, 0, 0], [0, -1, 0], length=0.06)
    np.testing.assert_allclose(
        probe_arcs(line, ProbeConfig(points=3)), [0.01, 0.03, 0.05]
    )
    np.testing.assert_allclose(
        probe_arcs(line, ProbeConfig(points=3, spacing=0.01, first_arc=0.02)),
        [0.02, 0.03, 0.04],
    )


@pytest.mark.parametrize("speed,stiffness", [(0.002, 5e3), (0.004, 1e4)])
def test_detection_depth_matches_the_sensor_filter(speed, stiffness):
    # The sensor's filter y += a (raw - y) sampled every T, read by the
    # probe one sample late, on a linear contact at constant speed; the
    # contact's phase against the samples uniform. The mean depth at
    # detection is the model's within 2 um.
    T, fc, threshold = 0.0025, 10.0, 1.0
    a = 1 - math.exp(-2 * math.pi * fc * T)
    depths = []
    for phase in np.linspace(0, T, 20, endpoint=False):
        y = 0.0
        for k in range(1, 2000):
            t = k * T - phase  # time since contact
            if y >= threshold:  # read before the filter's update at t
                depths.append(speed * t)
                break
            y += a * (stiffness * speed * max(t, 0.0) - y)
    model = detection_depth(speed, threshold, stiffness, sensor_timing(T, fc))
    assert np.mean(depths) == pytest.approx(model, abs=1e-6)


def _chamfer(x_p, xdot_p=(0, 0, 0)):
    return CHAMFER_STATE.pack(
        x_p=np.asarray(x_p, float),
        xdot_p=np.asarray(xdot_p, float),
        n1=np.zeros(3),
        n2=np.zeros(3),
        delta=0.0,
        delta_dot=0.0,
        f_n=0.0,
        f_t=0.0,
        arc_position=0.0,
        n1_rate=np.zeros(3),
    )


class _Run:
    """Steps a ProbingSequence's discrete updates with fixed inputs."""

    def __init__(self, probe, x0):
        self.probe = probe
        self.context = probe.CreateDefaultContext()
        self.x_p = np.asarray(x0, float)
        self.force = np.zeros(3)
        probe.GetInputPort("command_in").FixValue(self.context, np.zeros(3))
        self.fix()

    def fix(self, speed=(0, 0, 0)):
        self.probe.GetInputPort("chamfer_state").FixValue(
            self.context, _chamfer(self.x_p, speed)
        )
        self.probe.GetInputPort("measured_force").FixValue(
            self.context, self.force
        )

    def state(self):
        return self.context.get_discrete_state(0).get_value()

    def phase(self):
        return PHASES[int(round(float(PROBE_STATE.get(self.state(), "phase"))))]

    def step(self, T=0.0025):
        self.context.SetDiscreteState(
            self.probe.EvalUniquePeriodicDiscreteUpdate(self.context)
        )
        self.context.SetTime(self.context.get_time() + T)

    def command(self):
        return self.probe.GetOutputPort("command").Eval(self.context)


@pytest.mark.parametrize("left", [0.0, 2e-5])
def test_sequence_touches_compensates_the_bias_and_drops_a_burr(left):
    # ``left``: how far past the modelled detection depth contact really
    # comes, the calibrated ``detection_bias``.
    believed = CircularContour([0.4, 0.0, 0.048], 0.027)
    real_center = np.array([0.4004, -0.0003])
    # The force steps at contact: the configured stiffness, no second
    # threshold.
    cfg = ProbeConfig(
        points=6,
        settle_time=0.01,
        travel_speed=0.05,
        detection_bias=left,
        stiffness_threshold=0.0,
    )
    timing = sensor_timing(0.0025, 10.0)
    x0 = believed.point_at(0.0) - cfg.standoff * believed.n1(
        believed.point_at(0.0)
    )
    probe = ProbingSequence(
        believed, cfg, sample_period=0.0025, timing=timing, initial_position=x0
    )
    run = _Run(probe, x0)
    burr = 3  # this touch lands on a 0.8 mm burr
    expected = {}
    for _ in range(40000):
        if run.phase() == "done":
            break
        # The tool follows the command exactly; contact when the tool is
        # the modelled bias past the real edge (or the burr).
        run.x_p = run.command().copy()
        i = int(round(float(PROBE_STATE.get(run.state(), "index"))))
        d = np.linalg.norm(run.x_p[:2] - real_center) - believed.radius
        if i == burr:
            d += 0.0008
        n = believed.n1(believed.point_at(probe.arcs[min(i, 5)]))
        v = cfg.approach_speed
        bias = (
            detection_depth(
                v, cfg.force_threshold, cfg.contact_stiffness, timing
            )
            + left
        )
        touching = run.phase() == "approach" and d >= bias
        run.force = -2.0 * cfg.force_threshold * n if touching else np.zeros(3)
        if touching:
            expected[i] = run.x_p - bias * n
        run.fix(speed=v * n if run.phase() == "approach" else (0, 0, 0))
        run.step()
    assert run.phase() == "done"
    x = run.state()
    assert PROBE_STATE.get(x, "touches") == 6
    assert PROBE_STATE.get(x, "kept") == 5
    touches = run.context.get_discrete_state(1).get_value().reshape(6, 4)
    assert list(np.flatnonzero(touches[:, 3] == 2.0)) == [burr]
    # The compensated touches lie on the real edge within the command's
    # 2.5 ms quantisation (v T = 5 um).
    for i in range(6):
        if i != burr:
            r = np.linalg.norm(touches[i, :2] - real_center)
            assert r == pytest.approx(believed.radius, abs=6e-6)
    reg = PROBE_STATE.get(x, "registration")
    np.testing.assert_allclose(reg[:2], real_center - [0.4, 0.0], atol=6e-6)
    assert reg[3] == pytest.approx(0.0, abs=6e-6)  # the drawing's radius
    # Done: the spindle on, the generator's command passed through, the
    # tool brought to the corrected start.
    assert probe.GetOutputPort("spindle").Eval(run.context)[0] == 1.0
    start = np.r_[real_center, 0.048] + [believed.radius, 0, 0]
    np.testing.assert_allclose(PROBE_STATE.get(x, "command"), start, atol=1e-5)
    probe.GetInputPort("command_in").FixValue(run.context, [1.0, 2.0, 3.0])
    np.testing.assert_allclose(run.command(), [1.0, 2.0, 3.0])


def test_feed_holds_at_the_entry_until_the_cut_reaches_its_depth():
    """After probing, ``hold`` stays 1 (the generator does not feed) until
    the depth on the registered part reaches CUT_ESTABLISHED of the
    desired depth, or ``entry_dwell`` passes; ``probing`` is 0 and the
    spindle on meanwhile."""
    from deburr_drake.control.probe import CUT_ESTABLISHED

    believed = CircularContour([0.4, 0.0, 0.048], 0.027)
    x0 = believed.point_at(0.0)

    def done_run(cfg):
        probe = ProbingSequence(
            believed,
            cfg,
            sample_period=0.0025,
            timing=sensor_timing(0.0025, 10.0),
            initial_position=x0,
            desired_depth=5e-4,
        )
        run = _Run(probe, x0)
        x = run.state().copy()
        x[PROBE_STATE.slice("phase")] = PHASES.index("done")
        x[PROBE_STATE.slice("done_time")] = 0.0
        run.context.SetDiscreteState(0, x)
        return probe, run

    def at_depth(probe, run, delta):
        chamfer = _chamfer(x0)
        chamfer[CHAMFER_STATE.slice("delta")] = delta
        probe.GetInputPort("chamfer_state").FixValue(run.context, chamfer)

    def port(probe, run, name):
        return probe.GetOutputPort(name).Eval(run.context)[0]

    probe, run = done_run(ProbeConfig(points=3, entry_dwell=3.0))
    at_depth(probe, run, 0.5 * CUT_ESTABLISHED * 5e-4)  # on the way down
    for _ in range(400):  # 1 s
        run.step()
    assert port(probe, run, "hold") == 1.0
    assert port(probe, run, "probing") == 0.0
    assert port(probe, run, "spindle") == 1.0
    at_depth(probe, run, 1.01 * CUT_ESTABLISHED * 5e-4)
    run.step()
    assert port(probe, run, "hold") == 0.0
    assert PROBE_STATE.get(run.state(), "cut_time") == pytest.approx(1.0)
    # A cut that never gets there: the feed starts after entry_dwell.
    probe, run = done_run(ProbeConfig(points=3, entry_dwell=0.5))
    at_depth(probe, run, 0.0)
    for _ in range(199):
        run.step()
    assert port(probe, run, "hold") == 1.0
    for _ in range(2):
        run.step()
    assert port(probe, run, "hold") == 0.0


def test_gate_hides_contact_while_probing():
    gate = ProbeGate()
    context = gate.CreateDefaultContext()
    chamfer = _chamfer([0.4, 0, 0])
    chamfer[CHAMFER_STATE.slice("f_n")] = 3.0
    chamfer[CHAMFER_STATE.slice("delta")] = 1e-4
    gate.GetInputPort("chamfer_state").FixValue(context, chamfer)
    gate.GetInputPort("desired_normal_force").FixValue(context, [7.0])
    gate.GetInputPort("probing").FixValue(context, [1.0])
    out = gate.GetOutputPort("chamfer_state").Eval(context)
    assert CHAMFER_STATE.get(out, "f_n") == 0.0
    assert CHAMFER_STATE.get(out, "delta") == 0.0
    np.testing.assert_allclose(CHAMFER_STATE.get(out, "x_p"), [0.4, 0, 0])
    assert gate.GetOutputPort("desired_normal_force").Eval(context)[0] == 0
    gate.GetInputPort("probing").FixValue(context, [0.0])
    np.testing.assert_allclose(
        gate.GetOutputPort("chamfer_state").Eval(context), chamfer
    )
    assert gate.GetOutputPort("desired_normal_force").Eval(context)[0] == 7


def _square(**kw):
    from deburr_drake.math.profile import ProfileContour

    return ProfileContour(
        [[-0.025, -0.025], [0.025, -0.025], [0.025, 0.025], [-0.025, 0.025]],
        0.01,
        material="inside",
        offset=0.003,
        **kw,
    )


def test_profile_layout_fixes_the_turn_and_a_bad_one_is_refused():
    from deburr_drake.config import ConfigError
    from deburr_drake.control.probe import check_probe_layout
    from deburr_drake.math.registration import rigid_fit_amplification

    square = _square()
    # Evenly from the middle of a side, 8 touches fall on the middles of
    # the sides and fillets, which see no turn: the layout is shifted.
    arcs = probe_arcs(square, ProbeConfig(points=8))
    np.testing.assert_allclose(np.diff(arcs) % square.length, square.length / 8)
    assert 0.0 < arcs[0] < square.length / 8
    points = [square.point_at(s) for s in arcs]
    assert rigid_fit_amplification(square, points) < 1.0
    check_probe_layout(square, ProbeConfig(points=8))
    # Given a spacing it is kept as given; all on one side it is refused.
    config = ProbeConfig(points=4, spacing=0.005, first_arc=0.0)
    np.testing.assert_allclose(
        probe_arcs(square, config), [0.0, 0.005, 0.010, 0.015]
    )
    with pytest.raises(
        ConfigError,
        match=r"^localisation\.probe\.spacing "
        r"= 0\.005 is invalid: .*do not fix",
    ):
        check_probe_layout(square, config)


def test_travel_between_touches_stays_off_a_boss():
    # A straight move from a touch on one side of a boss to one on the
    # next cuts its corner through the material; the travel follows the
    # edge at the standoff. The tool follows the command; contact when it
    # is the modelled bias past the edge.
    boss = _square(center=[0.4, 0.0, 0.048])
    cfg = ProbeConfig(
        points=8,
        settle_time=0.01,
        travel_speed=0.05,
        detection_bias=0.0,
        stiffness_threshold=0.0,
    )
    timing = sensor_timing(0.0025, 10.0)
    x0 = boss.point_at(0.0) - cfg.standoff * boss.n1(boss.point_at(0.0))
    probe = ProbingSequence(
        boss, cfg, sample_period=0.0025, timing=timing, initial_position=x0
    )
    run = _Run(probe, x0)
    bias = detection_depth(
        cfg.approach_speed, cfg.force_threshold, cfg.contact_stiffness, timing
    )
    clearance = np.inf
    for _ in range(40000):
        if run.phase() == "done":
            break
        run.x_p = run.command().copy()
        depth = float(boss.depth(run.x_p))
        if run.phase() in ("travel", "return"):
            clearance = min(clearance, -depth)
        touching = run.phase() == "approach" and depth >= bias
        n = boss.n1(run.x_p)
        run.force = -2.0 * cfg.force_threshold * n if touching else np.zeros(3)
        run.fix(
            speed=cfg.approach_speed * n
            if run.phase() == "approach"
            else (0, 0, 0)
        )
        run.step()
    assert run.phase() == "done"
    x = run.state()
    assert PROBE_STATE.get(x, "touches") == 8
    assert PROBE_STATE.get(x, "kept") == 8
    # At the standoff all the way round (the retract ends the bias short
    # of it).
    assert clearance > cfg.standoff - 2 * bias
    np.testing.assert_allclose(
        PROBE_STATE.get(x, "registration"), 0.0, atol=2e-5
    )


@pytest.mark.parametrize("scale", [0.5, 1.0, 1.5])
def test_the_touches_measure_the_stiffness_they_touch(scale):
    # A bore 0.2 mm larger than drawn whose contact is the ring's
    # F = c delta^p exp(-b delta) (3.72 N at 0.5 mm on the paper cell's
    # modulus) times ``scale`` (the modulus x0.5, x1, x1.5: the softer
    # part touched deeper, where the law is less steep), read through the
    # sensor's filter one sample late; the tool follows the command. The
    # configured contact_stiffness is the paper cell's: the measured one
    # finds the radius within 10 um on every modulus.
    believed = CircularContour([0.4, 0.0, 0.048], 0.027)
    real = 0.027 + 2e-4
    cfg = ProbeConfig(
        points=6, settle_time=0.01, travel_speed=0.05, detection_bias=0.0
    )
    T, fc = 0.0025, 10.0
    p, b = cfg.contact_exponent, cfg.contact_exponent_slope
    timing = sensor_timing(T, fc)
    a = 1 - math.exp(-2 * math.pi * fc * T)

    def law(d):
        return d**p * math.exp(-b * d)

    c = scale * 3.72 / law(5e-4)
    x0 = believed.point_at(0.0) - cfg.standoff * believed.n1(
        believed.point_at(0.0)
    )
    probe = ProbingSequence(
        believed, cfg, sample_period=T, timing=timing, initial_position=x0
    )
    run = _Run(probe, x0)
    filtered = 0.0
    for _ in range(40000):
        if run.phase() == "done":
            break
        run.x_p = run.command().copy()
        d = np.linalg.norm(run.x_p[:2] - [0.4, 0.0]) - real
        n = (run.x_p[:2] - [0.4, 0.0]) / np.linalg.norm(run.x_p[:2] - [0.4, 0])
        run.force = -filtered * np.r_[n, 0.0]
        filtered += a * (c * law(max(d, 0.0)) - filtered)
        approach = run.phase() == "approach"
        run.fix(speed=cfg.approach_speed * np.r_[n, 0.0] if approach else 0)
        run.step()
    assert run.phase() == "done"
    x = run.state()
    assert PROBE_STATE.get(x, "kept") == 6
    # F / delta at 1 N.
    F = cfg.force_threshold
    k = F / brentq(lambda d: c * law(d) - F, 1e-7, 2e-3, xtol=1e-12)
    assert PROBE_STATE.get(x, "stiffness") == pytest.approx(k, rel=0.05)
    reg = PROBE_STATE.get(x, "registration")
    assert reg[3] == pytest.approx(2e-4, abs=1e-5)
    np.testing.assert_allclose(reg[:2], 0.0, atol=5e-6)


@pytest.mark.parametrize("exponent,slope", [(1.0, 0.0), (1.38, 0.0)])
def test_measured_stiffness_of_a_power_law_is_the_closed_form(exponent, slope):
    # F = c delta^n from 1 N at 0.3 mm to 3 N: the way between them.
    d1 = 3e-4
    d3 = d1 * 3.0 ** (1 / exponent)
    k = measured_stiffness(d3 - d1, 1.0, 3.0, exponent, slope)
    assert k == pytest.approx(1.0 / d1, rel=1e-9)


@pytest.mark.parametrize("d1", [1.5e-4, 3e-4, 4e-4])
def test_measured_stiffness_follows_the_exponent_falling_with_depth(d1):
    # The ring's law: the depth at 1 N found from the way to 3 N, the
    # touch shallow (stiff part) or deep (soft part).
    n, b = 1.54, 412.0

    def law(d):
        return d**n * math.exp(-b * d)

    d3 = brentq(lambda d: law(d) - 3.0 * law(d1), d1, 3e-3, xtol=1e-14)
    k = measured_stiffness(d3 - d1, 1.0, 3.0, n, b)
    assert k == pytest.approx(1.0 / d1, rel=1e-6)


def test_a_touch_that_finds_nothing_ends_the_run(run_untouched):
    """No contact anywhere: the first touch's guarded move ends at its
    search distance and the simulation stops, naming the touch."""
    from deburr_drake.runs.simulation import _stop_of

    believed = CircularContour([0.4, 0.0, 0.048], 0.027)
    cfg = ProbeConfig(points=4, settle_time=0.01, travel_speed=0.05)
    timing = sensor_timing(0.0025, 10.0)
    x0 = believed.point_at(0.0) - cfg.standoff * believed.n1(
        believed.point_at(0.0)
    )
    probe = ProbingSequence(
        believed, cfg, sample_period=0.0025, timing=timing, initial_position=x0
    )
    status, context = run_untouched(probe, _chamfer(x0))
    assert status.reason() == status.ReturnReason.kReachedTerminationCondition
    # the search: search_distance at approach_speed after the settle
    search = cfg.search_distance / cfg.approach_speed
    assert search < context.get_time() < search + 0.1
    reason, detail = _stop_of(status, None)
    assert reason == "probe_missed:0"
    assert detail.startswith("no contact within search_distance 0.004 m")
