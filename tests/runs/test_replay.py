"""The HTML replay: written from a short run and rendered by a real
headless browser (Debian's chromium) whose screenshot shows the scene."""

import shutil
import subprocess

import numpy as np
import pytest

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.runs.replay import write_recording
from deburr_drake.runs.simulation import simulate

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.fixture(scope="module")
def replay(tmp_path_factory):
    from pydrake.geometry import Meshcat

    scenario = load_scenario("paper")
    meshcat = Meshcat()
    diagram = make_deburring_diagram(scenario=scenario, meshcat=meshcat)
    meshcat.StartRecording(frames_per_second=10.0)
    simulate(diagram, scenario, duration=0.5)
    path = write_recording(
        meshcat, tmp_path_factory.mktemp("replay") / "replay.html"
    )
    return path


def test_replay_is_self_contained(replay):
    html = replay.read_text()
    assert len(html) > 500_000  # three.js and the scene inlined
    assert "<script" in html
    # Nothing is fetched when the file is opened.
    assert 'src="http' not in html and "src='http" not in html


@pytest.mark.skipif(
    CHROMIUM is None,
    reason="no chromium found (Debian: "
    "apt-get install chromium); .ci/run installs it",
)
def test_replay_renders_in_headless_chromium(replay, tmp_path):
    shot = tmp_path / "shot.png"
    subprocess.run(
        [
            CHROMIUM,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            f"--user-data-dir={tmp_path / 'profile'}",
            "--window-size=800,600",
            "--virtual-time-budget=8000",
            f"--screenshot={shot}",
            replay.as_uri(),
        ],
        check=True,
        timeout=180,
        capture_output=True,
    )
    import matplotlib.image

    image = matplotlib.image.imread(str(shot))[..., :3]
    assert image.std() > 0.01
    # The background is grey; the arm (orange), the part and the edge
    # (green/red) are saturated colours: the scene was drawn.
    saturation = image.max(axis=2) - image.min(axis=2)
    assert np.count_nonzero(saturation > 0.3) > 200
