"""A robust margin: the worst spectral radius of the sampled (2.5 ms) map
over ranges of the parameters a user does not know exactly, at a steady
point of the run.

The ranges are the scenario's ``uncertainty`` section
(:class:`deburr_drake.config.UncertaintyConfig`), relative to its own
values; the defaults are the Monte Carlo study's
(``studies/robustness.yaml``): the contact stiffness (the part's
hydroelastic modulus) and c0 +-50 %, the cutting coefficient +-30 %, the
burr height 0-2 times the scenario's (0-2 mm for the paper's 1 mm burrs),
and the controller's model mass scale +-0.2 around its value (the paper's
1.2: the model 20 % heavy, here 0-40 %). A range of one value leaves its
parameter out.

The search: each parameter alone at both ends of its range (the others at
the scenario's values), then the corner where every parameter sits at the
end that gave the larger rho. rho_worst is the largest rho of all these
maps, ``at`` its parameter values. (A vertex search: exact when rho is
monotone in each parameter over the box; otherwise a lower bound of the
box's worst, which the report says.) The burr height enters only at a
point on a burr: there the process's remaining burr under the tool is
scaled; off the burrs it does not change the map and is left out.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Dict, List, Optional, Tuple

from deburr_drake.analysis.sampled import FrozenMap
from deburr_drake.config import Scenario, get_field

__all__ = ["UncertainParameter", "UNCERTAIN_PARAMETERS", "robust_margin"]


@dataclass
class UncertainParameter:
    """``field`` by dotted name (None: ``burr_scale``), its range the
    scenario's ``uncertainty.<range>``: (low, high) factors of the
    scenario's value (``additive``: offsets added to it)."""

    name: str
    field: Optional[str]
    range: str
    unit: str
    additive: bool = False

    def values(self, scenario: Scenario) -> Tuple[float, float, float]:
        """(nominal, low, high) in the field's unit."""
        low, high = getattr(scenario.uncertainty, self.range)
        if self.field is None:
            return 1.0, low, high
        v = float(get_field(scenario, self.field))
        if self.additive:
            return v, v + low, v + high
        return v, v * low, v * high

    def varied(self, scenario: Scenario) -> bool:
        """Whether the scenario's range of it holds more than one value."""
        low, high = getattr(scenario.uncertainty, self.range)
        return high > low


#: The parameters and their ranges' fields in ``uncertainty``.
UNCERTAIN_PARAMETERS = (
    UncertainParameter(
        "contact stiffness (hydroelastic modulus)",
        "part.material.hydroelastic_modulus",
        "hydroelastic_modulus",
        "Pa",
    ),
    UncertainParameter(
        "c0 (contact threshold force)",
        "process.contact_threshold_force",
        "contact_threshold_force",
        "N",
    ),
    UncertainParameter(
        "cutting coefficient k_c",
        "process.cutting_coefficient",
        "cutting_coefficient",
        "N s/m^3",
    ),
    UncertainParameter(
        "burr height (x the scenario's)", None, "burr_height", "-"
    ),
    UncertainParameter(
        "model mass scale",
        "controller.model_mass_scale",
        "model_mass_scale",
        "-",
        additive=True,
    ),
)


def _scale_burr(factor: float) -> Callable:
    def modify(diagram, context):
        process = diagram.GetSubsystemByName("cutting_process")
        pc = process.GetMyMutableContextFromRoot(context)
        index = process._burr_index
        pc.SetDiscreteState(
            index, factor * pc.get_discrete_state(index).get_value()
        )

    return modify


def _parameter_table(scenario: Scenario, active) -> List[Dict]:
    """[{name, field, unit, range}] of the parameters varied."""
    return [
        {
            "name": p.name,
            "field": p.field,
            "unit": p.unit,
            "range": list(p.values(scenario)[1:]),
        }
        for p in active
    ]


def robust_margin(
    scenario: Scenario,
    diagram,
    context,
    *,
    on_burr: bool,
    parameters=UNCERTAIN_PARAMETERS,
    progress: Optional[Callable[[str], None]] = None,
) -> Dict:
    """{rho_nominal, rho_worst, at {name: value}, the same for the
    oscillatory modes (``_oscillatory``: the modes above 1 Hz, see
    :func:`deburr_drake.analysis.rho_of_map`, with its own corner when it
    differs), maps [{values, rho, rho_oscillatory}],
    parameters [{name, field, unit, range}], method} at the state
    ``context`` of ``diagram`` (a run of ``scenario``)."""
    say = progress or (lambda m: None)
    active = [
        p
        for p in parameters
        if (p.field is not None or on_burr) and p.varied(scenario)
    ]
    nominal = {p.name: p.values(scenario)[0] for p in active}
    maps: List[Dict] = []

    def rho_at(values: Dict[str, float]) -> float:
        overrides = {
            p.field: values[p.name]
            for p in active
            if p.field is not None and values[p.name] != nominal[p.name]
        }
        burr = [values[p.name] for p in active if p.field is None]
        modify = _scale_burr(burr[0]) if burr and burr[0] != 1.0 else None
        from deburr_drake.analysis.along import rho_of_map

        frozen = FrozenMap(scenario, **overrides)
        r = rho_of_map(frozen.at(diagram, context, modify), frozen.period)
        rho = r["rho"]
        maps.append(
            {
                "values": dict(values),
                "rho": rho,
                "rho_oscillatory": r["rho_oscillatory"],
            }
        )
        burr_text = f" burr x{burr[0]}" if modify else ""
        say(f"robust: {overrides or ''}{burr_text} rho = {rho:.5f}")
        return rho

    rho0 = rho_at(nominal)
    worst_end, worst_fast_end = {}, {}
    for p in active:
        _, lo, hi = p.values(scenario)
        ends = {}
        for v in (lo, hi):
            values = dict(nominal)
            values[p.name] = v
            rho_at(values)
            ends[v] = (maps[-1]["rho"], maps[-1]["rho_oscillatory"])
        worst_end[p.name] = max(ends, key=lambda v: ends[v][0])
        worst_fast_end[p.name] = max(ends, key=lambda v: ends[v][1])
    rho_at(worst_end)
    if worst_fast_end != worst_end:
        rho_at(worst_fast_end)
    worst = max(maps, key=lambda m: m["rho"])
    fast = max(maps, key=lambda m: m["rho_oscillatory"])
    return {
        "rho_nominal": rho0,
        "rho_worst": worst["rho"],
        "at": worst["values"],
        "rho_nominal_oscillatory": maps[0]["rho_oscillatory"],
        "rho_worst_oscillatory": fast["rho_oscillatory"],
        "at_oscillatory": fast["values"],
        "maps": maps,
        "parameters": _parameter_table(scenario, active),
        "left_out": [p.name for p in parameters if p not in active],
        "method": "each parameter alone at both ends, then the corner of "
        "the worse ends (vertex search)",
    }
