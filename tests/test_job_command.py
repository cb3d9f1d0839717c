"""``deburr-drake job``: the plan printed and written as job_plan.json,
and a scenario without a job refused in one line."""

import json
from pathlib import Path

from deburr_drake.cli import main

BLOCK = Path(__file__).resolve().parents[1] / "models" / "parts" / "block.stl"
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "block_job.yaml"


def test_the_job_plan_is_printed_and_written(tmp_path, capsys):
    scenario = tmp_path / "job.yaml"
    scenario.write_text(
        f"base: {EXAMPLE}\n"
        "job: {edges: [{near: [-0.03, 0.015, 0.0]}, "
        "{near: [0.011, 0.028, 0.0]}], order: listed}\n"
    )
    argv = ["job", "--scenario", str(scenario), "--out", str(tmp_path)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "2 edges cut, in order" in out
    record = json.loads((tmp_path / "job_plan.json").read_text())
    assert [e["move_before"] is None for e in record["edges"]] == [True, False]
    assert record["moves"]["count"] == 1
    assert record["moves"]["min_clearance_m"] > 0.0
    assert record["edges"][0]["length_m"] > 0.03


def test_a_scenario_without_a_job_is_refused(capsys):
    assert main(["job", "--scenario", "paper"]) == 2
    err = capsys.readouterr().err
    assert "no job" in err and len(err.strip().splitlines()) == 1
