"""The generated scenario reference (deburr_drake/config/reference.py):
every field of Scenario, each with a unit and a meaning by the comment
convention, its defaults and the range validate() allows."""

import dataclasses
import importlib.util
import sys
import typing

import pytest

from deburr_drake.config import Scenario, load_scenario, reference
from deburr_drake.config.reference import (
    convention_problems,
    is_unit,
    scenario_fields,
    scenario_reference_markdown,
    split_unit,
)


@pytest.fixture(scope="module")
def fields():
    return scenario_fields()


def _leaf_paths(cls, prefix=""):
    """Every leaf field of ``cls`` by dotted name, found independently of
    the generator: dataclasses.fields and the type hints."""
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        hint = hints[f.name]
        args = typing.get_args(hint)
        if dataclasses.is_dataclass(hint):
            yield from _leaf_paths(hint, f"{prefix}{f.name}.")
        elif args and dataclasses.is_dataclass(args[0]):
            yield from _leaf_paths(args[0], f"{prefix}{f.name}[].")
        else:
            yield f"{prefix}{f.name}"


def test_every_field_of_scenario_is_in_the_reference(fields):
    expected = list(_leaf_paths(Scenario))
    assert len(expected) > 100
    assert [d.path for d in fields] == expected
    page = scenario_reference_markdown()
    missing = [p for p in expected if f"| `{p}` (" not in page]
    assert missing == []


def test_every_field_has_a_unit_and_a_meaning(fields):
    # The convention: `name: type = default  # UNIT, meaning`.
    assert convention_problems(fields) == []


def test_a_field_without_unit_or_meaning_is_named(tmp_path, monkeypatch):
    source = tmp_path / "bad_config.py"
    source.write_text(
        "from dataclasses import dataclass\n\n\n"
        "@dataclass\n"
        "class BadConfig:\n"
        "    gain: float = 2.0  # N s/m, the gain\n"
        "    plain: float = 1.0\n"
        "    # the cutoff, with its unit missing\n"
        "    cutoff: float = 3.0\n"
        "    depth: float = 0.1  # m\n\n"
        "    def validate(self):\n"
        "        return self\n"
    )
    spec = importlib.util.spec_from_file_location("bad_config", source)
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, "bad_config", module)
    spec.loader.exec_module(module)
    docs = list(
        reference._walk(
            module.BadConfig,
            "bad.",
            module.BadConfig(),
            module.BadConfig(),
            module.BadConfig(),
            lambda obj: obj,
        )
    )
    problems = convention_problems(docs)
    assert len(problems) == 3
    assert problems[0].startswith(
        f"bad.plain ({source}:7) has no a unit and no a meaning"
    )
    assert problems[1].startswith(f"bad.cutoff ({source}:9) has no a unit")
    assert "no a meaning" not in problems[1]
    assert problems[2].startswith(f"bad.depth ({source}:10) has no a meaning")


@pytest.mark.parametrize(
    "text",
    [
        "m",
        "N s/m",
        "m/(N s)",
        "1/s",
        "N m s/rad",
        "N or N m",
        "m/s or rad/s",
        "N s/m^3",
        "Pa",
        "Hz",
        "-",
        "[N, N/m, N s/m]",
        "N s/m per s",
        "kg",
    ],
)
def test_units_by_the_convention(text):
    assert is_unit(text)


@pytest.mark.parametrize(
    "text",
    [
        "",
        "meters",
        "Around the circumference",
        "x sensor.noise_std",
        "N,",
        "[N, N/m",
        "0..3",
        "m of arc",
    ],
)
def test_not_units(text):
    assert not is_unit(text)


def test_split_unit():
    assert split_unit("m/s, the feed; more") == ("m/s", "the feed; more")
    assert split_unit("[N, N/m, N s/m], c0, c1, c2") == (
        "[N, N/m, N s/m]",
        "c0, c1, c2",
    )
    assert split_unit("s. With cenic") == ("s", "With cenic")
    assert split_unit("Hz") == ("Hz", "")
    assert split_unit("the feed") == ("", "the feed")


def test_defaults_types_and_ranges(fields):
    by = {d.path: d for d in fields}
    paper = load_scenario("paper")
    scale = by["controller.fuzzy.position_scale"]
    assert (scale.type, scale.unit) == ("float", "m")
    assert scale.default == Scenario().controller.fuzzy.position_scale
    assert scale.paper == paper.controller.fuzzy.position_scale == 1.0
    assert by["controller.fuzzy.order"].allowed == "an integer in 0..3"
    # Every check validate() makes on the field, cross-field ones too.
    depth = by["task.desired_depth"].allowed
    assert "a finite number > 0" in depth
    assert "< part.edge.wall_thickness" in depth
    assert by["controller.kind"].allowed == (
        "one of fuzzy, robust, ideal, impedance, position"
    )
    assert by["guards.enabled"].allowed == "true or false"
    assert "a list of 3 numbers" in by["controller.sliding_gain"].allowed
    # A list of dataclasses: its element's fields, the paper's values.
    height = by["process.burrs[].height"]
    assert height.paper == [b.height for b in paper.process.burrs]
    assert by["faults.dropouts[].mode"].allowed.startswith("one of")
    # Every numeric field has a range from validate().
    unchecked = [
        d.path
        for d in fields
        if d.type in ("float", "int", "List[float]") and not d.allowed
    ]
    assert unchecked == []


def test_write_scenario_reference(tmp_path):
    path = tmp_path / "scenario-reference.md"
    text = reference.write_scenario_reference(path)
    assert path.read_text() == text
    assert text.startswith("# Scenario reference")
    assert "## `controller`" in text
