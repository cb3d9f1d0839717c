"""deburr_drake.runs.convergence: a scenario at its step and at the step
halved, the metrics' changes against the finest run, and the files."""

import json

import numpy as np
import pytest

from deburr_drake import cli
from deburr_drake.config import ConfigError, load_scenario
from deburr_drake.runs.convergence import (
    converge,
    refined,
    relative_change,
)


def test_refined_halves_the_step_and_follows_eq3_between_samples():
    scenario = load_scenario("paper")
    assert refined(scenario, 0).simulation.max_step == 0.0025
    assert refined(scenario, 0).process.sample_mean is True
    fine = refined(scenario, 2)
    assert fine.simulation.max_step == pytest.approx(0.0025 / 4)
    assert fine.process.sample_mean is False
    # the scenario given is not changed
    assert scenario.simulation.max_step == 0.0025
    assert scenario.process.sample_mean is True


def test_relative_change():
    assert relative_change(2.0, 2.0) == 0.0
    assert relative_change(0.0, 0.0) == 0.0
    assert relative_change(1.0, 0.9) == pytest.approx(0.1)
    assert np.isnan(relative_change(np.nan, 1.0))


def test_bad_options_are_refused():
    scenario = load_scenario("point_mass")
    with pytest.raises(ConfigError, match="--steps"):
        converge(scenario, duration=1.0, max_halvings=0)
    with pytest.raises(ConfigError, match="--tolerance"):
        converge(scenario, duration=1.0, tolerance=-1.0)


def test_converge_on_a_short_point_mass_window(tmp_path, capsys):
    out = tmp_path / "c"
    args = [
        "converge",
        "--scenario",
        "point_mass",
        "--duration",
        "3",
        "--steps",
        "2",
        "--out",
        str(out),
    ]
    assert cli.main(args) == 0
    data = json.loads((out / "convergence.json").read_text())
    runs = data["runs"]
    assert 2 <= len(runs) <= 3
    steps = [r["max_step"] for r in runs]
    assert steps == pytest.approx([steps[0] / 2**k for k in range(len(runs))])
    assert [r["sample_mean"] for r in runs][1:] == [False] * (len(runs) - 1)
    # The changes are against the finest run: the finest's are all 0.
    assert all(v in (0.0, None) for v in data["changes"][-1].values())
    # The point mass's loop is well inside its limits: the metrics agree.
    depth = [r["metrics"]["chamfer_depth_rms_error_mm"] for r in runs]
    assert depth[0] == pytest.approx(depth[-1], rel=0.2)
    last = [v for v in data["last_change"].values() if v is not None]
    assert data["converged"] == (max(last) <= 0.05)
    table = (out / "convergence.md").read_text()
    assert "| chamfer_depth_rms_error_mm |" in table
    assert "convergence.md" in capsys.readouterr().out
    # An existing study is kept without --force.
    assert cli.main(args) == 2
