"""Touch probing closed loop on the paper cell and a boss: the arm's
guarded moves, contact on the simulated sensor, the bias compensated, the
part found."""

import numpy as np
import pytest

from deburr_drake.config import load_scenario
from deburr_drake.runs.probe_study import probe_once


def test_probing_finds_a_misplaced_part_in_the_paper_cell():
    # Four touches (0, 90, 180, 270 degrees: off the burrs), the part
    # 0.64 mm from where the controller believes it.
    scenario = load_scenario(
        "paper_localised",
        text=(
            "localisation: {probe: {points: 4}}\n"
            "part_error: {offset: [0.0005, -0.0004, 0.0]}"
        ),
    )
    result = probe_once(scenario)
    assert np.isfinite(result.probing_time)
    assert (result.touches, result.kept) == (4, 4)
    # The compensated touches lie on one circle of the drawing's radius
    # within 15 um, and its centre is the real part's within 15 um.
    assert result.fit_rms < 15e-6
    assert np.linalg.norm(result.centre_error) < 15e-6


def test_probing_finds_a_misplaced_and_turned_boss():
    # A profile: four touches on the boss (the layout shifted so that
    # they see the turn), the part 0.86 mm and 10 mrad from where the
    # controller believes it; the travels go round its corners.
    from deburr_drake.runs.pass_metrics import registration_error

    scenario = load_scenario(
        "boss",
        text=(
            "localisation: {probe: {enabled: true, points: 4}}\n"
            "part_error: {offset: [-0.0005, 0.0007, 0.0], yaw: 0.01}"
        ),
    )
    assert registration_error(scenario, np.zeros(4)) > 8e-4
    result = probe_once(scenario)
    assert np.isfinite(result.probing_time)
    assert (result.touches, result.kept) == (4, 4)
    # The corrected edge within 60 um of the real one all the way round
    # (the touches' scatter, docs/localisation.md).
    assert registration_error(scenario, result.registration) < 6e-5
    assert result.registration[2] == pytest.approx(-0.01, abs=3e-3)
