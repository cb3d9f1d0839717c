"""analyze's own checks before it simulates, and what it says for a
scenario that never reaches steady cutting (deburr_drake.analysis.stopped)."""

import time

import pytest

from deburr_drake.cli import main


@pytest.mark.parametrize("args", [["--at", "-3"], ["--at", "nan"], ["--after-contact", "-1"],
                                  ["--lyapunov", "0"]])
def test_bad_options_are_refused_before_anything_runs(tmp_path, capsys, args):
    out = tmp_path / "analysis"
    start = time.perf_counter()
    assert main(["analyze", *args, "--out", str(out)]) == 2
    assert time.perf_counter() - start < 5.0  # nothing simulated
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and args[0] in err[0]
    assert not out.exists()


@pytest.mark.slow
def test_a_run_that_never_reaches_an_operating_point_says_what_stopped_it(tmp_path, capsys):
    out = tmp_path / "analysis"
    code = main(["analyze", "--scenario", "paper", "--scenario-text",
                 "controller: {sliding_gain: [20000.0, 400.0, 1500.0]}", "--out", str(out)])
    assert code == 2
    err = [line for line in capsys.readouterr().err.splitlines()
           if line.startswith("deburr-drake: error:")]
    assert len(err) == 1
    assert "never reaches steady cutting" in err[0]
    assert "guard:joint_torque" in err[0] and "at t = " in err[0]
    assert not out.exists()
