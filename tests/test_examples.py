"""The user-facing Python: every example script runs from the command line
(short durations), the ```python blocks of the README and of every page
of the docs site run as written, and
the tutorial notebook executes top to bottom (nbclient) and is committed
without outputs."""

import json
import os
from pathlib import Path
import re
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
NOTEBOOK = EXAMPLES / "tutorial.ipynb"

pytestmark = pytest.mark.slow


def _run(args, cwd, timeout=300, env=None):
    """Runs python with ``args`` in ``cwd``; returns stdout, fails with
    stderr's tail."""
    result = subprocess.run(
        [sys.executable, *map(str, args)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, **(env or {})},
    )
    assert result.returncode == 0, result.stderr[-3000:]
    return result.stdout


def _numbers(line):
    return [float(x) for x in re.findall(r"-?\d+\.\d+", line)]


def test_parameter_study_prints_one_row_per_value(tmp_path):
    out = _run(
        [
            EXAMPLES / "parameter_study.py",
            "--duration",
            "2.6",
            "--values",
            "0.4,0.6",
        ],
        tmp_path,
    )
    rows = [
        line for line in out.splitlines() if re.match(r"\s+0\.[46] \|", line)
    ]
    assert len(rows) == 2, out
    depths = {
        row.split("|")[0].strip(): _numbers(row.split("|")[1])[0]
        for row in rows
    }
    # The measured depth follows the desired one (mm).
    assert depths["0.4"] == pytest.approx(0.4, abs=0.03)
    assert depths["0.6"] == pytest.approx(0.6, abs=0.03)


def test_own_plant_tracks_depth_and_force(tmp_path):
    out = _run([EXAMPLES / "own_plant.py", "--duration", "3"], tmp_path)
    lines = {
        line.split()[0]: _numbers(line)
        for line in out.splitlines()
        if line.startswith("  ")
    }
    assert lines["chamfer"][0] == pytest.approx(0.5, abs=0.05)  # mm
    assert lines["chamfering"][0] == pytest.approx(10.0, abs=1.0)  # N
    assert lines["commanded"][0] > 0.0  # mm/s: the tool moves on


def test_custom_logging_logs_and_plots(tmp_path):
    png = tmp_path / "plot.png"
    out = _run(
        [EXAMPLES / "custom_logging.py", "--duration", "1.5", "--out", png],
        tmp_path,
    )
    assert "'joints' (q and v of 5 joints)" in out
    assert png.stat().st_size > 10_000


def test_own_robot_runs_the_cell_on_a_model_file(tmp_path):
    out = _run([EXAMPLES / "own_robot.py", "--duration", "2.5"], tmp_path)
    assert "my_arm.sdf" in out
    assert "stop: duration at 2.50 s; 5 actuated joints" in out
    normal = [
        line for line in out.splitlines() if "normal_force_rms_error_N" in line
    ]
    assert _numbers(normal[0])[0] < 0.5


DOCS = ROOT / "docs"


def pages_with_python():
    """README.md and every page of the site (not docs/drafts/, not the
    generated scenario reference) that has ```python blocks."""
    pages = [ROOT / "README.md"] + sorted(
        p for p in DOCS.glob("*.md") if p.name != "scenario-reference.md"
    )
    return [p for p in pages if python_blocks(p)]


def python_blocks(page):
    """The ```python blocks of a Markdown page, in order."""
    return re.findall(r"^```python\n(.*?)^```", page.read_text(), re.S | re.M)


def test_the_pages_with_python_are_found():
    names = {p.name for p in pages_with_python()}
    assert {"README.md", "python-api.md", "own-robot.md"} <= names
    assert len(python_blocks(DOCS / "python-api.md")) >= 4


@pytest.mark.parametrize("page", pages_with_python(), ids=lambda p: p.name)
def test_page_python_runs(page, tmp_path):
    """A page's blocks run in order as one script (a later block uses what
    an earlier one made), in a fresh directory."""
    script = tmp_path / f"{page.stem}.py"
    script.write_text("\n".join(python_blocks(page)))
    _run([script], tmp_path)
    if page.name == "python-api.md":
        out = tmp_path / "out" / "api"
        for name in (
            "logs.npz",
            "metrics.json",
            "diagram.dot",
            "replay.html",
            "fig08_surface_finish.png",
        ):
            assert (out / name).exists(), name


def test_notebook_is_committed_without_outputs():
    notebook = json.loads(NOTEBOOK.read_text())
    code = [c for c in notebook["cells"] if c["cell_type"] == "code"]
    assert code
    for cell in code:
        assert cell["outputs"] == [] and cell["execution_count"] is None


def test_notebook_executes_top_to_bottom(tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    monkeypatch.setenv("DEBURR_TUTORIAL_DURATION", "3")
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    # The kernel must run in this interpreter's environment (the venv with
    # deburr_drake): jupyter_client starts the "python3" kernel with
    # sys.executable.
    notebook.cells.insert(
        0, nbformat.v4.new_code_cell("import sys; print(sys.prefix)")
    )
    nbclient.NotebookClient(
        notebook,
        timeout=600,
        kernel_name="python3",
        resources={"metadata": {"path": str(tmp_path)}},
    ).execute()
    assert notebook.cells[0].outputs[0]["text"].strip() == sys.prefix
    text = "".join(
        o.get("text", "")
        for c in notebook.cells
        if c.cell_type == "code"
        for o in c.outputs
    )
    assert "duration at 3.00 s" in text
    images = sum(
        "image/png" in o.get("data", {})
        for c in notebook.cells
        if c.cell_type == "code"
        for o in c.outputs
    )
    assert images >= 5  # Figs. 8-12, the depth plot and the overlays
    assert (tmp_path / "out" / "tutorial" / "replay.html").exists()
