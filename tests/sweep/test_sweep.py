"""deburr_drake.sweep: study files (typed, one error line naming the study
field before any run), the runs' keys and sampling, the results' numbers
(Wilson interval, the parameter that separates failures), and sweeps of
very short point-mass runs on a local Dask cluster and against a real
``distributed`` scheduler started here: resumable, a tripped guard recorded
as a row."""

import json
import math
from pathlib import Path
import textwrap

import numpy as np
import pytest

from deburr_drake import cli, sweep
from deburr_drake.cell.robot import LIMITS_NOTE
from deburr_drake.config import ConfigError
from deburr_drake.runs.pass_metrics import TRANSIENT
from deburr_drake.sweep.results import LOCALISATION_METRICS

# Two runs of 0.4 s of the point mass: one as given, one whose tool-force
# guard trips at contact.
TINY = """\
name: tiny
base: point_mass
duration: 0.4
grid:
  guards.tool_force: [0.0, 0.5]
metrics: [contact_time_s, chamfering_force_rms_error_N]
rules:
  - guard_tripped == 0
  - nan_detected == 0
"""

MC = """\
name: mc
base: paper
base_text: "simulation: {{duration: 5.0}}"
duration: 1.0
sample:
  seed: 3
  count: 6
  fields:
    part.edge.inner_radius: {{distribution: uniform, low: 0.02, high: 0.06}}
    sensor.noise_std: {{distribution: log_uniform, low: 0.05, high: 0.3}}
    sensor.noise_seed: {{distribution: uniform, low: 1, high: 9}}
    process.burrs[0].height:
      {{distribution: normal, mean: 0.001, std: 0.001, low: 0.0, high: 0.002}}
{extra}rules: ["chamfer_depth_rms_error_mm <= 0.05"]
"""


def write(tmp_path, text, name="study.yaml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def test_monte_carlo_runs_are_full_validated_scenarios_and_reproducible(
    tmp_path,
):
    study = sweep.load_study(write(tmp_path, MC.format(extra="")))
    runs = sweep.expand_runs(study)
    assert len(runs) == 6
    again = sweep.expand_runs(sweep.load_study(tmp_path / "study.yaml"))
    assert [r.key for r in runs] == [r.key for r in again]
    assert len({r.key for r in runs}) == 6
    for run in runs:
        sc = sweep.scenario_from_text(run.scenario_text)
        assert sc.simulation.duration == 1.0  # the study's, not base_text's
        assert 0.02 <= sc.part.edge.inner_radius <= 0.06
        assert sc.part.edge.inner_radius == run.params["part.edge.inner_radius"]
        assert 0.05 <= sc.sensor.noise_std <= 0.3
        assert isinstance(sc.sensor.noise_seed, int)
        assert 1 <= sc.sensor.noise_seed <= 9
        assert 0.0 <= sc.process.burrs[0].height <= 0.002
        assert sc.process.burrs[1].height == 0.001  # the base's
        assert sc.robot.model == "arm5"
    sweep.check_reach(study, runs[:1])


def test_grid_is_every_combination(tmp_path):
    study = sweep.load_study(
        write(
            tmp_path,
            """\
        base: point_mass
        grid:
          part.edge.inner_radius: [0.02, 0.03, 0.045]
          task.desired_depth: [0.0004, 0.0006]
        """,
        )
    )
    runs = sweep.expand_runs(study)
    assert [tuple(r.params.values()) for r in runs] == [
        (r, d) for r in (0.02, 0.03, 0.045) for d in (0.0004, 0.0006)
    ]


BAD = {
    "unknown scenario field": (
        "tube.inner_radiu: {distribution: uniform, low: 0.02, high: 0.06}",
        "study.sample.fields.tube.inner_radiu",
    ),
    "empty range": (
        "part.edge.inner_radius: {distribution: uniform, low: 0.06, high: "
        "0.02}",
        "study.sample.fields.part.edge.inner_radius: empty range",
    ),
    "normal on an integer field": (
        "sensor.noise_seed: {distribution: normal, mean: 3, std: 1}",
        "study.sample.fields.sensor.noise_seed: an integer field cannot "
        "take a normal distribution",
    ),
    "a list field without an index": (
        "part.pose.xyz: {distribution: uniform, low: 0, high: 1}",
        "study.sample.fields.part.pose.xyz: the field is of type",
    ),
    "a string field": (
        "robot.model: {distribution: uniform, low: 0, high: 1}",
        "study.sample.fields.robot.model: the field is of type str",
    ),
    "unknown distribution": (
        "part.edge.inner_radius: {distribution: beta, low: 0.02, high: 0.06}",
        "study.sample.fields.part.edge.inner_radius: distribution = 'beta'",
    ),
    "log-uniform from zero": (
        "sensor.noise_std: {distribution: log_uniform, low: 0, high: 1}",
        "study.sample.fields.sensor.noise_std: log_uniform needs low > 0",
    ),
    "unknown key of a distribution": (
        "part.edge.inner_radius: {distribution: uniform, lo: 0.02}",
        "study.sample.fields.part.edge.inner_radius.lo is unknown",
    ),
    "a value the scenario rejects": (
        "part.edge.inner_radius: {distribution: uniform, low: 0.001, high: "
        "0.002}",
        "study.sample.fields: run 0 (part.edge.inner_radius = ",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_study_is_one_line_naming_the_field_before_any_run(
    tmp_path, capsys, case
):
    extra, expected = BAD[case]
    lines = [
        line
        for line in MC.format(extra="").splitlines()
        if not line.strip().startswith(extra.split(":")[0] + ":")
    ]
    text = "\n".join(lines).replace("  fields:", f"  fields:\n    {extra}")
    path = write(tmp_path, text)
    out = tmp_path / "out"
    code = cli.main(["sweep", str(path), "--out", str(out)])
    captured = capsys.readouterr()
    assert code == 2, captured
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and expected in lines[0], lines
    assert not out.exists()


@pytest.mark.parametrize(
    "text, expected",
    [
        ("name: x\nsampel: {count: 3}\n", "study.sampel is unknown"),
        (
            "duration: 0\ngrid: {task.desired_depth: [0.0004]}\n",
            "study.duration = 0",
        ),
        (
            "grid:\n  part.edge.inner_radius: []\n",
            "study.grid.part.edge.inner_radius: empty list",
        ),
        (
            "grid:\n  part.edge.inner_radius: [a]\n",
            "study.grid.part.edge.inner_radius[0] = 'a' is invalid",
        ),
        (
            "grid: {part.edge.inner_radius: [0.03]}\nrules: ['depth < 1']\n",
            "study.rules[0]: metric 'depth' is unknown",
        ),
        (
            "grid: {part.edge.inner_radius: [0.03]}\nrules: ['edge_coverage "
            "~ 1']\n",
            "study.rules[0] = 'edge_coverage ~ 1' is invalid",
        ),
        (
            "grid: {part.edge.inner_radius: [0.03]}\n"
            "base_text: 'part: {edge: {radius: 1}}'\n",
            "study.base: --scenario-text:1:15: part.edge.radius is unknown",
        ),
        ("name: x\n", "study: give grid"),
    ],
)
def test_bad_study_files(tmp_path, text, expected):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as e:
        sweep.expand_runs(sweep.load_study(path))
    message = str(e.value)
    assert expected in message and "\n" not in message, message


def test_wilson_interval_and_association():
    lo, hi = sweep.wilson_interval(200, 200)
    assert (lo, hi) == pytest.approx((0.9812, 1.0), abs=1e-4)
    lo, hi = sweep.wilson_interval(5, 10)
    assert (lo, hi) == pytest.approx((0.2366, 0.7634), abs=1e-4)
    assert all(math.isnan(v) for v in sweep.wilson_interval(0, 0))
    # Monotone in the parameter: 1; independent of it: about 0.
    x = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]
    assert sweep.association(x, [1, 2, 3, 4, 5, 6]) == pytest.approx(1.0)
    assert sweep.association(x, [0, 0, 0, 1, 1, 1]) == pytest.approx(
        0.878, abs=1e-3
    )
    assert math.isnan(sweep.association(x, [0] * 6))
    # Bad at both ends (a symmetric error): by the distance from the
    # median.
    y = [-0.3, -0.2, -0.1, 0.1, 0.2, 0.3]
    assert sweep.association(y, [3, 2, 1, 1, 2, 3]) == pytest.approx(1.0)


def test_badness_is_the_most_failed_rules_metric_null_worst():
    rules = [
        sweep.parse_rule("guard_tripped == 0", "a"),
        sweep.parse_rule("chamfer_depth_rms_error_mm <= 0.05", "b"),
    ]
    rows = [
        {
            "pass: guard_tripped == 0": g,
            "pass_all": False,
            "pass: chamfer_depth_rms_error_mm <= 0.05": False,
            "chamfer_depth_rms_error_mm": d,
        }
        for g, d in ((True, 0.1), (True, 0.3), (False, None))
    ]
    np.testing.assert_allclose(sweep.badness(rows, rules), [0.1, 0.3, 1.3])


def test_rules_fail_on_null():
    rule = sweep.parse_rule("chamfer_depth_rms_error_mm <= 0.05", "r")
    assert rule.passes(0.05) and not rule.passes(0.0501)
    assert not rule.passes(None) and not rule.passes(float("nan"))


def _check_outputs(out: Path, n: int):
    rows = (out / "results.csv").read_text().strip().splitlines()
    assert len(rows) == n + 1
    summary = json.loads((out / "summary.json").read_text())
    assert summary["runs_finished"] == n
    assert (out / "metrics.png").stat().st_size > 0
    assert (out / "failures.png").stat().st_size > 0
    return rows, summary


@pytest.mark.slow
def test_local_sweep_records_a_guard_and_a_rerun_does_no_work(tmp_path, capsys):
    path = write(tmp_path, TINY)
    out = tmp_path / "out"
    assert (
        cli.main(["sweep", str(path), "--workers", "2", "--out", str(out)]) == 0
    )
    rows, summary = _check_outputs(out, 2)
    assert "guard_tripped == 0" in rows[0]
    assert summary["stop_reasons"] == {"duration": 1, "guard:tool_force": 1}
    rule = summary["rules"][0]
    assert (rule["rule"], rule["passed"], rule["runs"]) == (
        "guard_tripped == 0",
        1,
        2,
    )
    assert summary["metric_window"].startswith(f"from {TRANSIENT:g} s")
    runs = sweep.expand_runs(sweep.load_study(path))
    results = [sweep.read_result(out, r.key) for r in runs]
    assert results[1]["stop_reason"] == "guard:tool_force"
    # Every metric is there (the force at delta* only when a metric asks;
    # the localisation's only with localisation).
    assert set(sweep.METRICS) - {"true_force_at_desired_depth_N"} - set(
        LOCALISATION_METRICS
    ) <= set(results[0])
    # ... and every metric the run reports is a column (METRICS is the
    # sweep's list: a metric added to the report must be added there).
    reported = json.loads(
        (out / "runs" / runs[0].key / "metrics.json").read_text()
    )
    assert set(reported) - {
        "scenario",
        "stop_reason",
        "stop_time_s",
        "stop_detail",
        "unavailable",
    } <= set(sweep.METRICS)
    assert (out / "runs" / runs[0].key / "logs.npz").exists()
    capsys.readouterr()
    assert cli.main(["sweep", str(path), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "all 2 run(s) already have results" in printed
    assert "0 run(s) now, 2 already done" in printed
    assert cli.main(["sweep", str(path), "--out", str(out), "--no-run"]) == 0
    assert "2/2 run(s) finished" in capsys.readouterr().out


@pytest.mark.slow
def test_sweep_against_a_distributed_scheduler(tmp_path, capsys):
    from distributed import LocalCluster

    path = write(tmp_path, TINY.replace("[0.0, 0.5]", "[0.0]"))
    out = tmp_path / "out"
    with LocalCluster(
        n_workers=1,
        threads_per_worker=1,
        processes=True,
        dashboard_address=":0",
    ) as cluster:
        code = cli.main(
            [
                "sweep",
                str(path),
                "--scheduler",
                cluster.scheduler_address,
                "--out",
                str(out),
            ]
        )
    assert code == 0
    assert f"scheduler {cluster.scheduler_address}" in capsys.readouterr().out
    _check_outputs(out, 1)


def test_a_run_that_raises_is_recorded_with_its_reason(tmp_path):
    result = sweep.run_scenario(
        "part: {edge: {inner_radius: -1}}", str(tmp_path / "run"), "k"
    )
    assert result["stop_reason"] == "error"
    assert "part.edge.inner_radius" in result["stop_detail"]
    assert result["run_failed"] == 1.0
    assert (
        json.loads((tmp_path / "run" / "result.json").read_text())[
            "stop_reason"
        ]
        == "error"
    )


def test_binned_success_shows_where_runs_fail():
    from deburr_drake.sweep.results import binned_success

    x = [0.1, 0.9, 0.2, 0.8, 0.3, 0.7]
    bins = binned_success(x, [True, False, True, False, True, True], bins=2)
    assert [(b["low"], b["high"], b["passed"], b["runs"]) for b in bins] == [
        (0.1, 0.3, 3, 3),
        (0.7, 0.9, 1, 3),
    ]


def test_a_crashed_or_failed_run_fails_every_rule_and_is_a_row():
    from deburr_drake.sweep.results import table_rows
    from deburr_drake.sweep.runner import failed_result

    runs = [
        sweep.RunSpec(0, {"part.edge.inner_radius": 0.03}, "a", 1.0),
        sweep.RunSpec(1, {"part.edge.inner_radius": 0.04}, "b", 1.0),
        sweep.RunSpec(2, {"part.edge.inner_radius": 0.05}, "c", 1.0),
    ]
    rule = sweep.parse_rule("guard_tripped == 0", "r")
    results = {
        runs[0].key: failed_result(runs[0].key, "crash", "died"),
        runs[1].key: {
            "stop_reason": "duration",
            "guard_tripped": 0.0,
            "run_failed": 0.0,
        },
    }
    rows = table_rows(runs, results, ["guard_tripped"], [rule])
    assert [(r["index"], r["stop_reason"], r["pass_all"]) for r in rows] == [
        (0, "crash", False),
        (1, "duration", True),
    ]


@pytest.mark.slow
def test_a_run_the_preflight_refuses_is_one_line_naming_it(tmp_path, capsys):
    path = write(
        tmp_path,
        """\
        name: unstable
        base: paper
        duration: 0.05
        grid:
          controller.sliding_gain[0]: [400.0, 20000.0]
        rules: ["guard_tripped == 0"]
        """,
    )
    out = tmp_path / "out"
    assert cli.main(["sweep", str(path), "--out", str(out)]) == 2
    # The joint-limits note is said once per process, by whichever test
    # finalizes a continuous plant first.
    lines = [
        line
        for line in capsys.readouterr().err.strip().splitlines()
        if line != f"deburr-drake: {LIMITS_NOTE}"
    ]
    assert len(lines) == 1, lines
    assert lines[0].startswith(
        "deburr-drake: error: study.grid: run 1 "
        "(controller.sliding_gain[0] = 20000): "
        "controller.sliding_gain[0] = 20000 is predicted unstable"
    )
    assert not (out / "runs").exists()


def test_a_study_can_tabulate_every_localisation_metric():
    from deburr_drake.runs.pass_metrics import METRICS as PASS_METRICS
    from deburr_drake.sweep.results import METRICS

    localisation = {
        name
        for name, doc in PASS_METRICS.items()
        if doc.family == "localisation_metrics"
    }
    assert localisation <= set(METRICS)
    assert set(METRICS) - set(PASS_METRICS) == {"guard_tripped", "run_failed"}
