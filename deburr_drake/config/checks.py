"""The one error every bad input raises (:class:`ConfigError`: one line
naming the field by its dotted path and what is allowed) and the checks the
dataclasses' ``validate()`` share. Nothing is clamped."""

import math

__all__ = ["ConfigError"]


class ConfigError(ValueError):
    """A configuration value is invalid; the message names the field."""


def _require(ok: bool, name: str, value, allowed: str):
    if not ok:
        raise ConfigError(f"{name} = {value!r} is invalid: allowed {allowed}")


def _positive(owner: str, name: str, value: float):
    _require(
        isinstance(value, (int, float)) and math.isfinite(value) and value > 0,
        f"{owner}.{name}",
        value,
        "a finite number > 0",
    )


def _non_negative(owner: str, name: str, value: float):
    _require(
        isinstance(value, (int, float)) and math.isfinite(value) and value >= 0,
        f"{owner}.{name}",
        value,
        "a finite number >= 0",
    )


def _vector(owner: str, name: str, value, size: int, check):
    _require(
        len(value) == size,
        f"{owner}.{name}",
        value,
        f"a list of {size} numbers",
    )
    for i, v in enumerate(value):
        check(owner, f"{name}[{i}]", v)


def _finite(owner, name, value):
    _require(
        isinstance(value, (int, float)) and math.isfinite(value),
        f"{owner}.{name}",
        value,
        "a finite number",
    )
