"""The ``uncertainty:`` section: the box of the robust margin and the
certificate, read from the scenario, every bad range refused by its
dotted name before anything runs."""

from types import SimpleNamespace

import pytest

from deburr_drake.analysis import box_certificate
from deburr_drake.analysis.robust import UNCERTAIN_PARAMETERS
from deburr_drake.config import ConfigError, load_scenario


@pytest.mark.parametrize(
    "text, message",
    [
        (
            "{cutting_coefficient: [1.1, 1.3]}",
            "uncertainty.cutting_coefficient = [1.1, 1.3] is invalid: "
            "allowed a range holding 1",
        ),
        (
            "{contact_threshold_force: [1.5, 0.5]}",
            "uncertainty.contact_threshold_force = [1.5, 0.5] is invalid: "
            "allowed low <= high",
        ),
        (
            "{hydroelastic_modulus: [0.0, 1.5]}",
            "uncertainty.hydroelastic_modulus[0] = 0.0 is invalid",
        ),
        (
            "{model_mass_scale: [0.1, 0.2]}",
            "uncertainty.model_mass_scale = [0.1, 0.2] is invalid: "
            "allowed a range holding 0",
        ),
        (
            "{model_mass_scale: [-1.2, 0.2]}",
            "uncertainty.model_mass_scale[0] = -1.2 is invalid: allowed an "
            "offset > -1.2",
        ),
        (
            "{fuzzy_slope: [-1.5, 1.0]}",
            "uncertainty.fuzzy_slope = [-1.5, 1.0] is invalid: allowed "
            "fractions in [-1, 1]",
        ),
        (
            "{fuzzy_slope_per_axis: {x2: [0.5, 1.5]}}",
            "uncertainty.fuzzy_slope_per_axis.x2 = [0.5, 1.5] is invalid: "
            "allowed fractions in [-1, 1]",
        ),
        (
            "{fuzzy_slope_per_axis: {x3: [0.0, 1.0]}}",
            "uncertainty.fuzzy_slope_per_axis.x3 = [0.0, 1.0] is invalid: "
            "allowed an axis of controller.fuzzy.axes: x1, x2",
        ),
        (
            "{burr_height: [0.5]}",
            "uncertainty.burr_height = [0.5] is invalid: allowed a range "
            "[low, high] of two finite numbers",
        ),
        (
            "{burr_height: [0.0, .inf]}",
            "uncertainty.burr_height = [0.0, inf] is invalid",
        ),
    ],
)
def test_a_bad_range_is_one_line_naming_the_field(text, message):
    with pytest.raises(ConfigError) as error:
        load_scenario("paper", text=f"uncertainty: {text}")
    assert str(error.value).startswith(message)
    assert "\n" not in str(error.value)


def test_the_ranges_are_the_scenarios_relative_to_its_own_values():
    scenario = load_scenario(
        "paper",
        text="uncertainty: {cutting_coefficient: [0.9, 1.0], "
        "model_mass_scale: [0.0, 0.0]}",
    )
    by_range = {p.range: p for p in UNCERTAIN_PARAMETERS}
    k_c = scenario.process.cutting_coefficient
    assert by_range["cutting_coefficient"].values(scenario) == (
        k_c,
        pytest.approx(0.9 * k_c),
        k_c,
    )
    assert not by_range["model_mass_scale"].varied(scenario)
    stiffness = by_range["hydroelastic_modulus"]
    modulus = scenario.part.material.hydroelastic_modulus
    assert stiffness.values(scenario)[1:] == (0.5 * modulus, 1.5 * modulus)


def _op(text, slopes):
    """A stand-in operating point: the scenario (its slope bound as the
    cell designs it for the paper arm), its fuzzy axes' points."""
    text += "\ncontroller: {fuzzy: {max_slope: 3818.59}}"
    return SimpleNamespace(scenario=load_scenario("paper", text=text)), [
        {"axis": k, "s0": 1e-4, "slope": slope, "held": None}
        for k, slope in enumerate(slopes)
    ]


def test_the_certificates_box_is_the_scenarios(monkeypatch):
    op, points = _op(
        "uncertainty: {contact_threshold_force: [1.0, 1.0], "
        "fuzzy_slope: [0.25, 0.5]}",
        [-7.8, 0.3 * 3818.59],
    )
    monkeypatch.setattr(box_certificate, "_fuzzy_point", lambda op: points)
    box, left_out = box_certificate._select_box(box_certificate._box(op), None)
    box = {p["key"]: p for p in box}
    # c0 holds one value: out of the box, at the scenario's value.
    assert [p["key"] for p in left_out] == ["c0"]
    assert set(box) == {
        "stiffness",
        "k_c",
        "mass_scale",
        "slope_x1",
        "slope_x2",
    }
    max_slope = op.scenario.controller.fuzzy.max_slope
    # A range that leaves out the learned slope takes it in, and says so.
    assert box["slope_x1"]["range"] == [-7.8, pytest.approx(0.5 * max_slope)]
    assert box["slope_x1"]["nominal"] == -7.8
    assert "learned slope -7.8" in box["slope_x1"]["widened"]
    assert box["slope_x2"]["range"] == pytest.approx(
        [0.25 * max_slope, 0.5 * max_slope]
    )
    assert "widened" not in box["slope_x2"]


def test_a_slope_range_of_one_value_leaves_the_slope_at_the_learned_one(
    monkeypatch,
):
    op, points = _op("uncertainty: {fuzzy_slope: [0.5, 0.5]}", [100.0, 200.0])
    points[1]["held"] = "inside the dead zone"
    monkeypatch.setattr(box_certificate, "_fuzzy_point", lambda op: points)
    box, left_out = box_certificate._select_box(box_certificate._box(op), None)
    assert [p["key"] for p in box] == ["stiffness", "c0", "k_c", "mass_scale"]
    assert [p["range"] for p in left_out] == [[100.0, 100.0], [200.0, 200.0]]
    # The certificate names the slope left out while its rules move.
    text = box_certificate._does_not_prove(left_out)
    assert text.startswith(box_certificate.DOES_NOT_PROVE)
    assert "slope_x1, which the adaptation moves" in text
    assert "slope_x2" not in text
    assert box_certificate._does_not_prove(left_out[1:]) == (
        box_certificate.DOES_NOT_PROVE
    )


def test_a_slope_range_per_axis_overrides_the_others(monkeypatch):
    op, points = _op(
        "uncertainty: {fuzzy_slope: [0.0, 1.0], "
        "fuzzy_slope_per_axis: {x2: [0.05, 1.0]}}",
        [100.0, 200.0],
    )
    monkeypatch.setattr(box_certificate, "_fuzzy_point", lambda op: points)
    box, _ = box_certificate._select_box(box_certificate._box(op), None)
    box = {p["key"]: p for p in box}
    max_slope = op.scenario.controller.fuzzy.max_slope
    assert box["slope_x1"]["range"] == [0.0, pytest.approx(max_slope)]
    assert box["slope_x2"]["range"] == pytest.approx(
        [0.05 * max_slope, max_slope]
    )
