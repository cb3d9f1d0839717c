"""The ``uncertainty:`` section: the values of the parameters a user does
not know exactly, the box over which ``analyze``'s robust margin searches
for the worst spectral radius and ``certify`` proves the sampled loop
stable.

Each range is ``[low, high]`` relative to the scenario's own value, so one
box applies to any scenario: factors of it (the mass scale's are offsets
added to it, the fuzzy slope's fractions of ``controller.fuzzy.max_slope``).
A range must hold the scenario's own value (factor 1, offset 0): the
operating point is in the box. A range of one value (``[1, 1]``, offsets
``[0, 0]``) leaves that parameter out of the box, at the scenario's value.
"""

from dataclasses import dataclass, field
import math
from typing import Dict, List

from deburr_drake.config.checks import _require

__all__ = ["UncertaintyConfig"]

#: The ranges that are factors of a positive scenario field.
_FACTORS = (
    "hydroelastic_modulus",
    "contact_threshold_force",
    "cutting_coefficient",
)


# A Dict's values are list[float], not typing.List: Drake's YAML reader
# cannot build the latter inside a Dict.


def _pair(*values: float):
    return field(default_factory=lambda: list(values))


@dataclass
class UncertaintyConfig:
    """The box over which ``analyze``'s robust margin searches for the
    worst spectral radius and ``certify`` proves the loop stable. Each
    range is [low, high] relative to the scenario's own value (factors
    of it; the mass scale's offsets added to it, the fuzzy slope's
    fractions of ``controller.fuzzy.max_slope``) and holds that value; a
    range of one value leaves its parameter out of the box, at the
    scenario's value. The defaults are the Monte Carlo robustness study's:
    the contact stiffness and c0 +-50 %, the cutting coefficient +-30 %,
    the burr height 0-2 times the scenario's, the model mass scale
    +-0.2, and the fuzzy surface's slope over the projection's positive
    half."""

    # -, x part.material.hydroelastic_modulus: the contact stiffness (it
    # also varies along the edge, so certify keeps it time-varying)
    hydroelastic_modulus: List[float] = _pair(0.5, 1.5)
    # -, x process.contact_threshold_force (c0)
    contact_threshold_force: List[float] = _pair(0.5, 1.5)
    # -, x process.cutting_coefficient (k_c)
    cutting_coefficient: List[float] = _pair(0.7, 1.3)
    # -, x the scenario's burr heights (the robust margin on a burr only)
    burr_height: List[float] = _pair(0.0, 2.0)
    # -, added to controller.model_mass_scale
    model_mass_scale: List[float] = _pair(-0.2, 0.2)
    # -, x controller.fuzzy.max_slope: the fuzzy surface's total slope
    # d u_f / d s_k on each axis (certify only); a range that leaves out
    # the slope the rules have learned is widened to take it in, and the
    # certificate says so
    fuzzy_slope: List[float] = _pair(0.0, 1.0)
    # -, x controller.fuzzy.max_slope: fuzzy_slope for one axis of
    # controller.fuzzy.axes by name (x1, x2, x3), e.g. {x2: [0.05, 1.0]};
    # the axes not named take fuzzy_slope
    fuzzy_slope_per_axis: Dict[str, list[float]] = field(default_factory=dict)

    def validate(self):
        o = "uncertainty"
        for name in (*_FACTORS, "burr_height"):
            low = _range(o, name, getattr(self, name), inside=1.0)
            _require(
                low > 0 or name == "burr_height",
                f"{o}.{name}[0]",
                low,
                "a factor > 0 (the parameter itself must stay positive)",
            )
        _range(o, "model_mass_scale", self.model_mass_scale, inside=0.0)
        _slope_fractions(o, "fuzzy_slope", self.fuzzy_slope)
        for axis, fractions in self.fuzzy_slope_per_axis.items():
            _slope_fractions(o, f"fuzzy_slope_per_axis.{axis}", fractions)

    def check_axes(self, axes: List[int]):
        """Each axis named in ``fuzzy_slope_per_axis`` is a fuzzy one."""
        names = [f"x{a + 1}" for a in axes]
        for axis in self.fuzzy_slope_per_axis:
            _require(
                axis in names,
                f"uncertainty.fuzzy_slope_per_axis.{axis}",
                self.fuzzy_slope_per_axis[axis],
                f"an axis of controller.fuzzy.axes: {', '.join(names)}",
            )

    def slope_fractions(self, axis: int) -> List[float]:
        """The fuzzy slope's range on task ``axis`` (0, 1, 2), as
        fractions of controller.fuzzy.max_slope."""
        return self.fuzzy_slope_per_axis.get(f"x{axis + 1}", self.fuzzy_slope)

    def check_mass_scale(self, model_mass_scale: float):
        """The model's masses stay positive over the range."""
        low = self.model_mass_scale[0]
        _require(
            model_mass_scale + low > 0,
            "uncertainty.model_mass_scale[0]",
            low,
            f"an offset > -{model_mass_scale:g} (controller.model_mass_scale: "
            "the model's masses stay positive)",
        )


def _slope_fractions(owner: str, name: str, value) -> None:
    """A fuzzy slope's range: fractions in [-1, 1] of max_slope."""
    low = _range(owner, name, value, inside=None)
    _require(
        -1.0 <= low and value[1] <= 1.0,
        f"{owner}.{name}",
        value,
        "fractions in [-1, 1] of controller.fuzzy.max_slope (the "
        "projection bounds the slope's size by it)",
    )


def _range(owner: str, name: str, value, inside) -> float:
    """``value``'s low end once it is checked as a range [low, high] of
    finite numbers holding ``inside`` (None: any)."""
    _require(
        isinstance(value, list)
        and len(value) == 2
        and all(
            isinstance(v, (int, float)) and math.isfinite(v) for v in value
        ),
        f"{owner}.{name}",
        value,
        "a range [low, high] of two finite numbers",
    )
    low, high = value
    _require(low <= high, f"{owner}.{name}", value, "low <= high")
    if inside is not None:
        _require(
            low <= inside <= high,
            f"{owner}.{name}",
            value,
            f"a range holding {inside:g}, the scenario's own value",
        )
    return low
