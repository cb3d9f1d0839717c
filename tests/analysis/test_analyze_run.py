"""analyze's own checks before it simulates, and what it says for a
scenario that never reaches steady cutting: the verdict, the oscillation
and the guard that would have stopped the run."""

import json
import math
import time

import pytest

from deburr_drake import analysis
from deburr_drake.cli import main
from deburr_drake.config import ConfigError


@pytest.mark.parametrize(
    "args",
    [
        ["--at", "-3"],
        ["--at", "nan"],
        ["--after-contact", "-1"],
        ["--lyapunov", "0"],
        ["--until", "0"],
        ["--at", "3", "--until", "2"],
    ],
)
def test_bad_options_are_refused_before_anything_runs(tmp_path, capsys, args):
    out = tmp_path / "analysis"
    start = time.perf_counter()
    assert main(["analyze", *args, "--out", str(out)]) == 2
    assert time.perf_counter() - start < 5.0  # nothing simulated
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and args[0] in err[0]
    assert not out.exists()


def _reached_the_run(scenario, **kwargs):
    raise ConfigError("the checks passed")


@pytest.mark.parametrize("held", ["analysis.json", "poles.png"])
def test_an_existing_analysis_is_kept_without_force(
    tmp_path, capsys, monkeypatch, held
):
    # As simulate: an --out that holds an analysis is refused before
    # anything runs; --force, or a folder holding other files, passes.
    monkeypatch.setattr(analysis, "analyze", _reached_the_run)
    (tmp_path / held).write_text("kept")
    (tmp_path / "notes.txt").write_text("not the analysis's")
    args = ["analyze", "--scenario", "point_mass", "--out", str(tmp_path)]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and held in err[0] and "--force" in err[0]
    assert (tmp_path / held).read_text() == "kept"
    assert main([*args, "--force"]) == 2
    assert "the checks passed" in capsys.readouterr().err
    (tmp_path / held).unlink()
    assert main(args) == 2
    assert "the checks passed" in capsys.readouterr().err


@pytest.mark.slow
def test_a_run_that_never_reaches_steady_cutting_says_what_stopped_it(
    tmp_path, capsys
):
    out = tmp_path / "analysis"
    code = main(
        [
            "analyze",
            "--scenario",
            "paper",
            "--scenario-text",
            "controller: {sliding_gain: [20000.0, 400.0, 1500.0]}",
            "--until",
            "2",
            "--no-robust",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    lines = capsys.readouterr().out.splitlines()
    # the summary's first line is the verdict
    first = next(
        i for i, line in enumerate(lines) if line.startswith("verdict:")
    )
    assert lines[first].startswith("verdict: UNSTABLE")
    assert lines[first - 1] == ""
    assert lines[first + 1].startswith("deburr-drake analyze:")
    result = json.loads((out / "analysis.json").read_text())
    assert result["verdict"] == "unstable"
    assert "eigenvalues" not in result or result["eigenvalues"] is None
    guard = result["guard_that_would_stop"]
    assert guard["guard"] == "joint_torque" and guard["time"] < 2.0
    assert guard["value"] > guard["limit"]
    assert "joint_torque" in result["verdict_reason"]


def test_a_diverging_run_is_unstable_with_its_divergence_time():
    """analyze's run (guards off) ends at the numerical sanity check: the
    verdict is unstable and analysis.json has when it diverged."""
    from deburr_drake.config import load_scenario

    scenario = load_scenario(
        "paper", text="{estimator: {gains: [2000.0, 2.0e9, 0.0]}}"
    )
    result = analysis.analyze(scenario, robust=False)
    assert result["verdict"] == "unstable"
    assert result["run"]["stop_reason"] == "diverged"
    assert result["run"]["divergence_time"] == pytest.approx(
        result["run"]["end_time"]
    )
    # Within the first tenths of a second: at the refined numerics the
    # verdict runs at (a quarter step) the runaway takes about 0.15 s.
    assert result["run"]["divergence_time"] < 0.5
    assert "diverged at t = " in result["verdict_reason"]


def test_a_frozen_mode_the_rest_of_the_run_refutes_does_not_decide():
    # rho 1.00046 at 2.5 ms grows x 280 over 30 s: a run steady for those
    # 30 s refutes it; 1 s before the end it would grow x 1.2, unseen.
    from types import SimpleNamespace

    from deburr_drake.analysis.along import RhoPoint
    from deburr_drake.analysis.analyze_run import _steady_verdict
    from deburr_drake.analysis.settled import SettleTolerances

    rate = -math.log(1.00046) / 0.0025

    def point(t, rho):
        return RhoPoint(
            t=t,
            arc_position=0.01,
            kind="burr 1",
            rho=rho,
            frequency_hz=0.0,
            decay_rate=-math.log(rho) / 0.0025,
        )

    run = SimpleNamespace(
        end_time=40.0, stop_reason="duration", op=SimpleNamespace(time=5.0)
    )
    tol = SettleTolerances()
    early = _steady_verdict(run, [point(9.5, 1.00046), point(20, 0.999)], tol)
    assert early["verdict"] == "stable"
    grown = math.exp(-rate * 30.5)  # the growth by the run's end
    assert f"growth x {grown:.3g} by the run's end" in early["verdict_reason"]
    assert round(grown) == 273
    late = _steady_verdict(run, [point(39.0, 1.00046), point(20, 0.999)], tol)
    assert late["verdict"] == "unstable"
    assert "t = 39.00 s" in late["verdict_reason"]
    assert _steady_verdict(run, [point(20, 0.999)], tol)["verdict"] == "stable"
