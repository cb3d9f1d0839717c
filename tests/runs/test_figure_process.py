"""Tests of deburr_drake.runs.figure_process: the figures drawn by a process
forked before the run give what drawing them in the caller gives (paths,
files, a failure said in one line, the warnings of a skipped figure)."""

import numpy as np
import pytest
from test_figures import EXPECTED, check_png, synthetic_logs

from deburr_drake.runs.figure_process import FigureProcess, draw_figures


def _logs_file(tmp_path, logs):
    path = tmp_path / "logs.npz"
    np.savez(path, **logs)
    return path


def test_the_process_draws_every_figure_as_the_caller_would(tmp_path):
    logs = _logs_file(tmp_path, synthetic_logs())
    with FigureProcess() as drawer:
        paths, failure = drawer.draw(logs, tmp_path / "forked", "test")
    here, failure_here = draw_figures(logs, tmp_path / "here", "test")
    assert failure is None and failure_here is None
    assert [p.name for p in paths] == [p.name for p in here]
    assert {p.name for p in paths} == EXPECTED
    for p in paths:
        assert p.parent == tmp_path / "forked"
        check_png(p)


def test_a_figure_failure_is_said_not_raised(tmp_path):
    logs = synthetic_logs()
    logs["chamfer.delta"] = logs["chamfer.delta"][:-1]  # malformed
    path = _logs_file(tmp_path, logs)
    with FigureProcess() as drawer:
        paths, failure = drawer.draw(path, tmp_path / "out", "test")
    assert paths == []
    assert failure == draw_figures(path, tmp_path / "here", "test")[1]
    assert failure.startswith("ValueError: chamfer.delta")


def test_a_missing_logs_file_is_said_not_raised(tmp_path):
    with FigureProcess() as drawer:
        paths, failure = drawer.draw(tmp_path / "none.npz", tmp_path, "x")
    assert paths == [] and failure.startswith("FileNotFoundError")


def test_a_skipped_figure_warns_in_the_caller(tmp_path):
    logs = synthetic_logs()
    del logs["theta.final"]
    path = _logs_file(tmp_path, logs)
    with FigureProcess() as drawer:
        with pytest.warns(UserWarning, match="theta.final"):
            paths, failure = drawer.draw(path, tmp_path / "out", "test")
    assert failure is None
    assert {p.name for p in paths} == EXPECTED - {
        "fig11_12_fuzzy_axis0.png",
        "fig11_12_fuzzy_axis1.png",
    }


def test_the_caller_draws_when_the_process_is_gone(tmp_path):
    path = _logs_file(tmp_path, synthetic_logs())
    drawer = FigureProcess()
    drawer._process.kill()
    drawer._process.join()
    paths, failure = drawer.draw(path, tmp_path / "out", "test")
    drawer.close()
    assert failure is None and {p.name for p in paths} == EXPECTED
