"""The job section: read from a scenario file, its part file relative to
it, and every bad field refused in one line naming its dotted path."""

from pathlib import Path
import shutil

import pytest

from deburr_drake.config import ConfigError, load_scenario

BLOCK = Path(__file__).resolve().parents[2] / "models" / "parts" / "block.stl"

JOB = """\
name: block_job
base: paper_6dof
job:
  file: parts/block.stl
  units: mm
  pose: {xyz: [0.95, 0.0, 0.50], rpy: [0.0, 0.0, 0.0]}
  edges: [{near: [-0.03, 0.015, 0.0]}, {index: 3}]
  order: listed
"""


@pytest.fixture
def job_file(tmp_path):
    (tmp_path / "parts").mkdir()
    shutil.copy(BLOCK, tmp_path / "parts" / "block.stl")
    path = tmp_path / "job.yaml"
    path.write_text(JOB)
    return path


def test_a_job_reads_with_its_part_beside_the_scenario(job_file):
    job = load_scenario(str(job_file)).job
    assert Path(job.file) == (job_file.parent / "parts/block.stl").resolve()
    assert job.units == "mm" and job.order == "listed"
    assert [e.near for e in job.edges] == [[-0.03, 0.015, 0.0], []]
    assert [e.index for e in job.edges] == [-1, 3]
    assert job.approach > 0 and job.retract > 0 and job.clearance >= 0


def test_no_job_by_default():
    assert load_scenario("paper").job.file == ""


@pytest.mark.parametrize(
    "text, field",
    [
        ("job: {edges: [{near: [1, 2]}]}", "job.edges[0].near"),
        ("job: {edges: [{}]}", "job.edges[0] "),
        ("job: {edges: [{near: [0, 0, 0], index: 2}]}", "job.edges[0] "),
        ("job: {order: random}", "job.order"),
        ("job: {clearance: -1}", "job.clearance"),
        ("job: {approach: 0}", "job.approach"),
        ("job: {units: ft}", "job.units"),
        ("job: {file: not_there.stl}", "job.file"),
        ("job: {pose: {xyz: [1, 2]}}", "job.pose.xyz"),
        ("job: {start: [0, 0]}", "job.start"),
    ],
)
def test_a_bad_job_field_is_named(job_file, text, field):
    with pytest.raises(ConfigError) as error:
        load_scenario(str(job_file), text=text)
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(field), message
