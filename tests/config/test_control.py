"""ControllerConfig.validate(): the chosen law's fields and the shared ones,
not the other laws' sections."""

import pytest

from deburr_drake.config import ConfigError, ControllerConfig


def _set(config, path, value):
    *owners, name = path.split(".")
    target = config
    for owner in owners:
        target = getattr(target, owner)
    setattr(target, name, value)


# (the kind that reads the field, the field, a bad value, the error's
# dotted path)
BAD = [
    (
        "fuzzy",
        "fuzzy.adaptation_gain",
        -1.0,
        "controller.fuzzy.adaptation_gain",
    ),
    ("fuzzy", "robust_gain", [2.0], "controller.robust_gain"),
    (
        "robust",
        "robust.gains",
        [5.0, 0.0, -1.0, 0.0, 0.0],
        "controller.robust.gains[2]",
    ),
    ("impedance", "impedance.stiffness", 0.0, "controller.impedance.stiffness"),
    (
        "position",
        "position.sliding_gain",
        [1.0, -1.0, 1.0],
        "controller.position.sliding_gain[1]",
    ),
]


@pytest.mark.parametrize("reader, path, value, name", BAD)
def test_only_the_chosen_law_is_validated(reader, path, value, name):
    for kind in ControllerConfig.KINDS:
        config = ControllerConfig(kind=kind)
        _set(config, path, value)
        if kind != reader:
            config.validate()  # another law's section: not read
            continue
        with pytest.raises(ConfigError) as error:
            config.validate()
        message = str(error.value)
        assert "\n" not in message
        assert message.startswith(f"{name} = ")


@pytest.mark.parametrize("kind", ControllerConfig.KINDS)
def test_shared_fields_are_validated_whatever_the_kind(kind):
    """The shell's fields and the fuzzy axes' rule base (every law's
    state holds the rule weights) fail for every kind."""
    for path, value, name in [
        ("sliding_lambda", [1.0, 1.0], "controller.sliding_lambda"),
        ("fuzzy.axes", [0, 0], "controller.fuzzy.axes"),
        ("fuzzy.upsilon", 0, "controller.fuzzy.upsilon"),
    ]:
        config = ControllerConfig(kind=kind)
        _set(config, path, value)
        with pytest.raises(ConfigError, match=name):
            config.validate()


def test_depth_gain_belongs_to_the_force_laws():
    for kind in ControllerConfig.KINDS:
        config = ControllerConfig(kind=kind, depth_gain=-1.0)
        if kind in ControllerConfig.CONSTANT_FEED_KINDS:
            config.validate()
        else:
            with pytest.raises(ConfigError, match="controller.depth_gain"):
                config.validate()
