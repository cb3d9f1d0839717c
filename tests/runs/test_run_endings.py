"""Every ending of a run writes what the run has (issue 10): logs.npz and a
strict-JSON metrics.json with completed_pass, stop_reason and stop_time_s,
and a documented exit code."""

import json
import os
from pathlib import Path
import signal
import subprocess
import sys

import numpy as np
import pytest

from deburr_drake import cli
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.runs import report
from deburr_drake.runs.pass_metrics import pass_metrics
from deburr_drake.runs.simulation import simulate

ROOT = Path(__file__).resolve().parents[2]


def _strict_json(path):
    def reject(constant):
        raise ValueError(f"non-strict JSON constant {constant}")

    return json.loads(Path(path).read_text(), parse_constant=reject)


def test_a_run_shorter_than_the_transient_writes_logs_and_metrics(
    tmp_path, capsys
):
    out = tmp_path / "d"
    code = cli.main(["simulate", "--duration", "1", "--out", str(out)])
    assert code == 0
    metrics = _strict_json(out / "metrics.json")
    assert metrics["stop_reason"] == "duration"
    assert metrics["completed_pass"] is False
    assert metrics["stop_time_s"] == pytest.approx(1.0)
    # Metrics after the 2 s transient cannot be computed: null, with why.
    assert metrics["chamfering_force_rms_error_N"] is None
    assert "transient" in metrics["unavailable"]["chamfering_force_rms_error_N"]
    assert metrics["contact_time_s"] < 0.5
    # The feed law never reached command.max_feed (20 mm/s).
    assert metrics["feed_at_max_fraction"] == 0.0
    with np.load(out / "logs.npz") as logs:
        assert logs["chamfer.t"][-1] == pytest.approx(1.0)
    # A second run into the same directory is refused (nothing run) ...
    capsys.readouterr()
    assert cli.main(["simulate", "--duration", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--force" in err[0]


def test_a_clamped_feed_is_counted_in_the_metrics(tmp_path):
    """command.max_feed below the feeds the law asks for: the metrics say
    for how much of the run the feed was held at the clamp."""
    out = tmp_path / "d"
    assert (
        cli.main(
            [
                "simulate",
                "--duration",
                "1",
                "--out",
                str(out),
                "--scenario-text",
                "command: {max_feed: 0.0015}",
            ]
        )
        == 0
    )
    metrics = _strict_json(out / "metrics.json")
    with np.load(out / "logs.npz") as logs:
        feed = logs["command.feed"]
    assert feed.max() == pytest.approx(0.0015)
    assert metrics["feed_at_max_fraction"] == pytest.approx(
        np.mean(feed >= 0.0015 * (1 - 1e-9))
    )
    assert metrics["feed_at_max_fraction"] > 0.3


def _run_and_signal(tmp_path, number):
    """Starts a paper run, sends ``number`` once it has simulated a few
    seconds, and returns (exit code, metrics)."""
    out = tmp_path / "run"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "deburr_drake.cli",
            "simulate",
            "--out",
            str(out),
            "--progress-interval",
            "0.5",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        env=env,
        cwd=tmp_path,
    )
    try:
        for line in proc.stdout:
            if "t =   2.00 s simulated" in line:
                proc.send_signal(number)
                break
        proc.stdout.read()
        code = proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    return code, _strict_json(out / "metrics.json"), out


@pytest.mark.parametrize(
    "number, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)]
)
def test_a_signal_stops_the_run_and_its_results_are_written(
    tmp_path, number, code
):
    exit_code, metrics, out = _run_and_signal(tmp_path, number)
    assert exit_code == code
    assert metrics["stop_reason"] == "interrupted"
    assert metrics["stop_detail"] == signal.Signals(number).name
    assert 2.0 <= metrics["stop_time_s"] < 10.0
    with np.load(out / "logs.npz") as logs:
        assert logs["chamfer.t"][-1] == pytest.approx(
            metrics["stop_time_s"], abs=0.003
        )


@pytest.fixture(scope="module")
def point_mass():
    scenario = load_scenario("point_mass")
    return scenario, make_deburring_diagram(scenario=scenario)


@pytest.mark.parametrize(
    "message, reason",
    [
        ("Detected NaN in the actuation input port", "nan"),
        ("something else broke", "error"),
    ],
)
def test_an_exception_during_the_run_keeps_the_logs(
    point_mass, message, reason
):
    scenario, diagram = point_mass
    calls = []

    def should_stop():
        calls.append(1)
        if len(calls) > 40:
            raise RuntimeError(message)

    log = simulate(diagram, scenario, duration=1.0, should_stop=should_stop)
    assert log.stop_reason == reason
    assert message in log.stop_detail
    assert log.stop_time == pytest.approx(0.1, abs=0.01)
    assert len(log["chamfer"]["t"]) > 10
    values = pass_metrics(log)
    summary = report.run_summary(log, values)
    json.dumps(summary, allow_nan=False)
    assert summary["stop_reason"] == reason
    assert summary["nan_detected"] == (1.0 if reason == "nan" else 0.0)


#: The estimator gains that run away within a few periods (c-hat to
#: 1e25 in 0.1 s), guards off: no user limit stops the run.
RUNAWAY = "{estimator: {gains: [2000.0, 2.0e9, 0.0]}, guards: {enabled: false}}"


def test_a_diverging_run_ends_diverged_with_its_results(tmp_path):
    """The numerical sanity check is not a guard: with guards off the
    runaway ends ``diverged`` (exit 5) at its first absurd command, its
    logs and metrics written, and never ``pass_complete``."""
    out = tmp_path / "d"
    code = cli.main(
        [
            "simulate",
            "--no-preflight",
            "--duration",
            "2",
            "--out",
            str(out),
            "--scenario-text",
            RUNAWAY,
        ]
    )
    assert code == 5
    metrics = _strict_json(out / "metrics.json")
    assert metrics["stop_reason"] == "diverged"
    assert metrics["completed_pass"] is False
    assert metrics["stop_time_s"] < 0.1
    assert "effort limit" in metrics["stop_detail"]
    with np.load(out / "logs.npz") as logs:
        assert logs["chamfer.t"][-1] == pytest.approx(
            metrics["stop_time_s"], abs=0.003
        )


def test_a_pass_is_complete_only_when_the_tool_cut_the_edge(monkeypatch):
    """Without the sanity check the runaway tool, thrown across the part,
    jumps the command's arc progress past a full edge length within a
    second while cutting almost nothing: the run goes on (here to its
    duration), not ``pass_complete``."""
    from deburr_drake.runs import simulation

    monkeypatch.setattr(simulation.NumericalSanity, "SPEED_FACTOR", np.inf)
    monkeypatch.setattr(simulation.NumericalSanity, "TORQUE_FACTOR", np.inf)
    scenario = load_scenario("paper", text=RUNAWAY)
    diagram = make_deburring_diagram(scenario=scenario)
    log = simulate(diagram, scenario, duration=1.5)
    end = simulation.PassProgress(diagram, 1.0).end
    assert np.max(log["command"]["arc_position"]) > end
    assert log.stop_reason == "duration"
    assert np.mean(log["finish"]["depth"] > 0) < 0.05


def test_the_sanity_check_names_what_diverged(paper_cell):
    from deburr_drake.runs.simulation import NumericalSanity, make_simulator

    scenario, diagram = paper_cell()
    simulator = make_simulator(diagram, scenario)
    simulator.Initialize()
    context = simulator.get_mutable_context()
    sanity = NumericalSanity(diagram, scenario)
    assert sanity.check(context) is None
    plant = diagram.GetSubsystemByName("plant")
    plant_context = plant.GetMyMutableContextFromRoot(context)
    v = plant.GetVelocities(plant_context)
    limits = plant.GetVelocityUpperLimits()
    v[1] = 9.0 * limits[1]  # within 10 x its limit: fast, not diverged
    plant.SetVelocities(plant_context, v)
    assert sanity.check(context) is None
    v[1] = 11.0 * limits[1]
    plant.SetVelocities(plant_context, v)
    assert "velocity limit" in sanity.check(context)
    assert plant.GetVelocityNames()[1] in sanity.check(context)
    v[1] = 0.0
    plant.SetVelocities(plant_context, v)
    x = context.get_mutable_continuous_state_vector()
    x.SetAtIndex(x.size() - 1, np.nan)
    assert "non-finite" in sanity.check(context)
