"""The pre-flight (deburr_drake.analysis.preflight): the one-period map at
the start pose proves designed gains and refuses, in one line naming the
gain, written gains the sampled loop cannot hold."""

import copy
import json

import pytest

from deburr_drake.analysis.preflight import (
    GAIN_MARGIN,
    NEUTRAL_TOLERANCE,
    GainMaps,
    preflight,
    start_operating_point,
)
from deburr_drake.analysis.sampled import sampled_loop, spectral_radius
from deburr_drake.cli import main
from deburr_drake.config import ConfigError, load_scenario


@pytest.mark.slow
def test_written_gains_pass_unchanged():
    scenario = load_scenario("paper")
    before = copy.deepcopy(scenario)
    found = preflight(scenario)
    assert found.design is None and 0.9 < found.rho < 1.0
    assert scenario == before


@pytest.mark.slow
def test_designed_gains_are_proven_with_the_gain_margin():
    scenario = load_scenario("paper_6dof", text="controller: {design: auto}")
    before = copy.deepcopy(scenario)
    lines = []
    found = preflight(scenario, say=lines.append)
    assert scenario == before
    designed = found.scenario.controller
    assert found.design is not None and designed.design == "written"
    assert found.rho < 1.0 and found.rho_at_margin < 1.0
    assert designed.sliding_gain == found.design.sliding_gain
    assert any(
        "predicted rho" in line and f"x {GAIN_MARGIN:g}" in line
        for line in lines
    )


@pytest.mark.slow
def test_the_split_map_matches_the_full_one_and_is_affine_in_the_gain():
    op = start_operating_point(load_scenario("paper"))
    maps = GainMaps(op)
    full = spectral_radius(maps.full_map())
    assert maps.rho() == pytest.approx(full, abs=1e-4)
    assert maps.rho_full == pytest.approx(full, abs=NEUTRAL_TOLERANCE)
    maps.add_path("K0", lambda c: {"controller.sliding_gain[0]": 400.0 * c})
    # rho at 15 x K1 from the affine sample map against the whole map taken
    # there, from the same state.
    direct = sampled_loop(
        op, **{"controller.sliding_gain[0]": 6000.0}
    ).spectral_radius
    assert direct > 1.0
    assert maps.rho(K0=15.0) == pytest.approx(direct, rel=0.02)


@pytest.mark.slow
def test_an_unstable_gain_is_refused_in_one_line_naming_it(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(
        [
            "simulate",
            "--scenario",
            "paper",
            "--scenario-text",
            "controller: {sliding_gain: [20000.0, 400.0, 1500.0]}",
            "--out",
            str(out),
        ]
    )
    assert code == 2
    err = [
        line
        for line in capsys.readouterr().err.splitlines()
        if line.startswith("deburr-drake: error:")
    ]
    assert len(err) == 1
    message = err[0]
    assert "controller.sliding_gain[0] = 20000 is predicted unstable" in message
    assert (
        "rho = " in message
        and "largest stable controller.sliding_gain[0] is" in message
    )
    stable = float(
        message.split("largest stable controller.sliding_gain[0] is ")[
            1
        ].split()[0]
    )
    assert 400.0 < stable < 20000.0
    assert not out.exists()
    # The largest stable value is stable, and a little more is not.
    at = load_scenario(
        "paper",
        text=f"controller: {{sliding_gain: [{stable:g}, 400.0, 1500.0]}}",
    )
    preflight(at)
    above = load_scenario(
        "paper",
        text=f"controller: {{sliding_gain: [{1.2 * stable:g}, 400.0, 1500.0]}}",
    )
    with pytest.raises(ConfigError):
        preflight(above)


@pytest.mark.slow
def test_no_preflight_runs_anyway_and_the_outputs_hold_the_gains(tmp_path):
    out = tmp_path / "out"
    assert (
        main(
            [
                "simulate",
                "--scenario",
                "paper_6dof",
                "--scenario-text",
                "controller: {design: auto}",
                "--duration",
                "0.05",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    found = json.loads((out / "preflight.json").read_text())
    assert found["design"] == "auto" and found["predicted_rho"] < 1.0
    rerun = load_scenario(str(out / "scenario.yaml"))
    assert rerun.controller.design == "written"
    assert (
        rerun.controller.sliding_gain
        == found["gains"]["controller.sliding_gain"]
    )
    code = main(
        [
            "simulate",
            "--scenario",
            "paper",
            "--scenario-text",
            "controller: {sliding_gain: [20000.0, 400.0, 1500.0]}",
            "--duration",
            "0.01",
            "--no-preflight",
            "--out",
            str(tmp_path / "anyway"),
        ]
    )
    assert code == 3  # the joint-torque guard
    assert not (tmp_path / "anyway" / "preflight.json").exists()


def test_a_mode_within_the_maps_resolution_of_the_unit_circle_is_neutral():
    from deburr_drake.analysis.preflight import (
        NEUTRAL_TOLERANCE,
        predicted_unstable,
    )

    assert not predicted_unstable(0.9985)
    assert not predicted_unstable(1.0 + 0.5 * NEUTRAL_TOLERANCE)
    assert predicted_unstable(1.0 + 2.0 * NEUTRAL_TOLERANCE)
    assert predicted_unstable(1.02)
    assert predicted_unstable(float("nan"))
