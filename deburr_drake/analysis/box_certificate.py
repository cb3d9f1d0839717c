"""``certify``: the stability certificate of a scenario's sampled loop over
a box of parameters, from the run's Context at its operating point.

The box: the robust margin's parameters and ranges
(:data:`deburr_drake.analysis.robust.UNCERTAIN_PARAMETERS`: contact
stiffness, c0, the cutting coefficient, the model mass scale; the burr
height only enters on a burr, and the operating point is off them), the
contact estimator's c-hat (all three scaled together by 0.5-1.5, not below
their projection floor ``estimator.lower_bounds``) and the fuzzy surface's
slope added on every fuzzy axis, 0 to the projection bound
``controller.fuzzy.max_slope`` (:func:`deburr_drake.analysis.add_fuzzy_slope`).

The maps: the one-period map at the operating point (nominal), at both
ends and at the midpoint of each parameter's range with the others nominal,
and at every corner of the parameters that move the map (by more than
``VERTEX_THRESHOLD`` of its norm, balanced), the others nominal. Their
effects do not add up (the paper arm: a corner built by adding each
parameter's change to the nominal map has radius 1.0127 where the true map
there has 0.998644), so the corners are true maps. What the corners leave
out is bounded in the common Lyapunov function's norm and added to the
decay rate: each parameter's curvature (its midpoint map against the
chord through its ends: the miss of a map quadratic in it) and the
half-range of a parameter without a corner axis; the certificate holds
only if the sum stays below 1.

The c-hat and slope ends are changes of the operating point's Context on
the nominal diagram; the scenario fields (stiffness, c0, k_c, mass scale)
are the diagram's construction data, so each end has its frozen diagram
(one build each).
"""

from __future__ import annotations

import itertools
import time
from typing import Callable, Dict, List, Optional

import numpy as np
import scipy.linalg

from deburr_drake.analysis.along import at_numerics
from deburr_drake.analysis.certificate import certify_family, p_norm
from deburr_drake.analysis.operating_point import (
    DEFAULT_TIME_AFTER_CONTACT,
    find_operating_point,
)
from deburr_drake.analysis.robust import UNCERTAIN_PARAMETERS
from deburr_drake.analysis.sampled import FrozenMap
from deburr_drake.analysis.validation import add_fuzzy_slope
from deburr_drake.config import Scenario

#: A parameter whose half-range moves the map by more than this fraction
#: (Frobenius norm) of the nominal map gets a vertex axis.
VERTEX_THRESHOLD = 1e-2

__all__ = [
    "box_maps",
    "certify",
    "certificate_summary",
    "PROVES",
    "DOES_NOT_PROVE",
]

PROVES = (
    "the sampled 2.5 ms loop linearised at the operating point is "
    "exponentially stable for any variation, however fast, of the "
    "parameters within the box (a common quadratic Lyapunov function of "
    "every vertex map)"
)
DOES_NOT_PROVE = (
    "loss of contact, burr impacts, the depth^1.4 contact away from the "
    "operating point, the outer loop and the adaptation's own dynamics "
    "(frozen), and the feed's range (not in the box)"
)


def _scale_estimates(factor: float, floor) -> Callable:
    def modify(diagram, context):
        estimator = diagram.GetSubsystemByName("contact_estimator")
        ec = estimator.GetMyMutableContextFromRoot(context)
        c = ec.get_continuous_state_vector().CopyToVector()
        ec.SetContinuousState(np.maximum(factor * c, floor))

    return modify


def _slope(value: float) -> Callable:
    def modify(diagram, context):
        add_fuzzy_slope(diagram, context, value)

    return modify


def _box(scenario: Scenario) -> List[Dict]:
    """[{name, field, unit, nominal, low, high, overrides(v) or
    modify(v)}]: the parameters and their ranges."""
    box = []
    for p in UNCERTAIN_PARAMETERS:
        if p.field is None:
            continue  # the burr height: off the burrs it is not in the map
        nominal, low, high = p.values(scenario)
        box.append(
            {
                "name": p.name,
                "field": p.field,
                "unit": p.unit,
                "nominal": nominal,
                "range": [low, high],
            }
        )
    floor = np.asarray(scenario.estimator.lower_bounds, float)
    box.append(
        {
            "name": "contact estimates c-hat (x the operating point's)",
            "field": None,
            "unit": "-",
            "nominal": 1.0,
            "range": [0.5, 1.5],
            "modify": lambda v: _scale_estimates(v, floor),
        }
    )
    max_slope = float(scenario.controller.fuzzy.max_slope)
    if np.isfinite(max_slope) and max_slope > 0:
        box.append(
            {
                "name": "fuzzy surface slope added (theta_ij += s j Delta_k)",
                "field": None,
                "unit": "N s/m",
                "nominal": 0.0,
                "range": [0.0, max_slope],
                "modify": _slope,
            }
        )
    return box


def _labels(frozen: FrozenMap) -> List[str]:
    context = frozen.diagram.CreateDefaultContext()
    labels = []
    for e in frozen.entries:
        n = e.get(frozen.diagram, context).size
        labels += [f"{e.label}[{i}]" for i in range(n)]
    return labels


def box_maps(op, box, say=lambda m: None) -> Dict:
    """{A0, ends [(A_lo, A_hi)], mids, labels, period}: the one-period
    maps at ``op`` (nominal), at both ends and at the midpoint of every
    parameter of ``box``."""
    nominal = FrozenMap(op.scenario, plan=op.plan)
    A0 = nominal.at(op.diagram, op.context)

    def map_at(p, v):
        if "modify" in p:
            return nominal.at(op.diagram, op.context, p["modify"](v))
        frozen = FrozenMap(op.scenario, plan=op.plan, **{p["field"]: v})
        return frozen.at(op.diagram, op.context)

    ends, mids = [], []
    for p in box:
        lo, hi = p["range"]
        ends.append((map_at(p, lo), map_at(p, hi)))
        # The midpoint's map measures the curvature; it is the nominal
        # one when the range is centred on the nominal value.
        centred = abs(0.5 * (lo + hi) - p["nominal"]) <= 1e-12 * abs(hi - lo)
        mids.append(A0 if centred else map_at(p, 0.5 * (lo + hi)))
        say(f"maps at the ends of {p['name']}")
    return {
        "A0": A0,
        "ends": ends,
        "mids": mids,
        "labels": _labels(nominal),
        "period": nominal.period,
    }


def _balancer(A0: np.ndarray) -> Callable:
    """M -> D^-1 M D, D the diagonal balancing of ``A0`` (one scale for
    the states' units, as the certificate's program takes them)."""
    _, (scale, _) = scipy.linalg.matrix_balance(
        A0, permute=False, separate=True
    )
    return lambda M: M * (1.0 / scale)[:, None] * scale[None, :]


def _corner_map(op, box, values) -> np.ndarray:
    """The true one-period map with every parameter at ``values``."""
    modifies = [p["modify"](values[p["name"]]) for p in box if "modify" in p]

    def modify_all(diagram, context):
        for m in modifies:
            m(diagram, context)

    frozen = FrozenMap(
        op.scenario,
        plan=op.plan,
        **{
            p["field"]: values[p["name"]] for p in box if p["field"] is not None
        },
    )
    return frozen.at(op.diagram, op.context, modify_all)


def _values(box, signs) -> Dict[str, float]:
    """{name: value}: each parameter at its low end (sign -1), high end
    (+1) or nominal (0)."""
    return {
        p["name"]: p["nominal"] if si == 0 else p["range"][0 if si < 0 else 1]
        for p, si in zip(box, signs)
    }


def _value_text(box, signs) -> str:
    return ", ".join(
        f"{name} = {v:g}" for name, v in _values(box, signs).items()
    )


def _corner_axes(A0, ends, threshold) -> List[int]:
    """The parameters whose half-range moves the (balanced) map by more
    than ``threshold`` of its norm: each gets a corner axis; the others'
    half-differences are bounded in P's norm instead."""
    balanced = _balancer(A0)
    size = np.linalg.norm(balanced(A0))
    return [
        j
        for j, (lo, hi) in enumerate(ends)
        if np.linalg.norm(balanced(0.5 * (hi - lo))) > threshold * size
    ]


def _corners(op, box, axes):
    """(maps, signs): the true maps at every corner of ``axes``, the other
    parameters nominal. The parameters' effects do not add up (their cross
    terms), so corners of a model built from the ends would not do."""
    corners, signs = [], []
    for corner in itertools.product((-1.0, 1.0), repeat=len(axes)):
        sign = [0.0] * len(box)
        for si, k in zip(corner, axes):
            sign[k] = si
        corners.append(_corner_map(op, box, _values(box, sign)))
        signs.append(sign)
    return corners, signs


def _model_error(cert, box, maps, axes) -> Dict:
    """What the corners leave out, in P's norm: the curvature of each
    parameter's map (its midpoint map against the chord through its ends)
    and the half-range of those without a corner axis; the status
    inconclusive when the decay rate plus it is not below 1."""
    left_out = []
    for j, (p, (lo, hi), mid) in enumerate(
        zip(box, maps["ends"], maps["mids"])
    ):
        bound = p_norm(cert.reduced.transform(mid - 0.5 * (lo + hi)), cert.P)
        if j not in axes:
            bound += p_norm(cert.reduced.transform(0.5 * (hi - lo)), cert.P)
        left_out.append({"parameter": p["name"], "p_norm": bound})
    miss = sum(c["p_norm"] for c in left_out)
    out = {
        "model_error": left_out,
        "decay_rate_with_model_error": cert.decay_rate + miss,
    }
    if cert.status == "certified" and cert.decay_rate + miss >= 1.0:
        out["status"] = "inconclusive"
        out["breaking_reason"] = (
            f"decay rate {cert.decay_rate:.6f} plus what the corners "
            f"leave out {miss:.3g} is not below 1"
        )
    return out


def certify(
    scenario: Scenario,
    *,
    numerics: str = "shipped",
    after_contact: float = DEFAULT_TIME_AFTER_CONTACT,
    solver: str = "Clarabel",
    vertex_threshold: float = VERTEX_THRESHOLD,
    bisections: int = 0,
    progress: Optional[Callable[[str], None]] = None,
) -> Dict:
    """The certificate (the dict of certificate.json, SI units) of
    ``scenario``'s sampled loop over the box (module docstring) at the
    operating point ``after_contact`` s after the first contact, its run
    and maps at ``numerics`` ("shipped" or "refined",
    :func:`deburr_drake.analysis.along.at_numerics`). ``bisections`` of
    the decay rate after the first solve (each a solve as long as the
    first; 0: the decay rate is the checked one of the first P). The
    live maps are under ``"_maps"``."""
    say = progress or (lambda message: None)
    timings = {}
    t0 = time.perf_counter()
    run_scenario = at_numerics(scenario, numerics)
    say(f"operating point: {after_contact:g} s of cutting ({numerics})")
    op = find_operating_point(run_scenario, after_contact=after_contact)
    timings["operating_point_s"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    box = _box(op.scenario)
    maps = box_maps(op, box, say)
    A0, ends = maps["A0"], maps["ends"]
    axes = _corner_axes(A0, ends, vertex_threshold)
    corners, signs = _corners(op, box, axes)
    say(f"maps at the {len(corners)} corners")
    timings["maps_s"] = time.perf_counter() - t1
    family = [A0] + [m for pair in ends for m in pair] + corners
    names = (
        ["nominal"]
        + [f"{p['name']} = {v:g}" for p in box for v in p["range"]]
        + ["corner: " + _value_text(box, s) for s in signs]
    )
    # The program and its check.
    t2 = time.perf_counter()
    say(f"common Lyapunov function of {len(family)} maps ({solver})")
    cert = certify_family(
        family, maps["labels"], solver=solver, bisections=bisections
    )
    timings["program_s"] = time.perf_counter() - t2
    result = cert.to_dict()
    result["vertex_parameters"] = [box[j]["name"] for j in axes]
    if cert.P is not None:
        result.update(_model_error(cert, box, maps, axes))
    if result["breaking_map"] is not None:
        result["breaking_vertex"] = names[result["breaking_map"]]
    result.update(
        {
            "scenario": op.scenario.name,
            "numerics": numerics,
            "sampling_period_s": maps["period"],
            "operating_point": op.summary(),
            "box": [
                {k: p[k] for k in ("name", "field", "unit", "nominal", "range")}
                for p in box
            ],
            "vertices": len(family),
            "proves": PROVES,
            "does_not_prove": DOES_NOT_PROVE,
            "timings_s": {**timings, "total": time.perf_counter() - t0},
            "_maps": {
                "family": family,
                "names": names,
                "labels": maps["labels"],
            },
        }
    )
    return result


def certificate_summary(result: Dict) -> str:
    """The certificate in a few lines."""
    lines = [
        f"{result['scenario']}: {result['status']} "
        f"({result['vertices']} maps, {result['numerics']} numerics, "
        f"solver {result['solver']}: {result['solver_status']})"
    ]
    if result["decay_rate_per_period"] is not None:
        lines.append(
            f"  decay rate {result['decay_rate_per_period']:.6f} per "
            f"{result['sampling_period_s'] * 1e3:g} ms period "
            f"(with what the vertices leave out "
            f"{result.get('decay_rate_with_model_error', float('nan')):.6f}); "
            f"largest spectral radius {result['largest_spectral_radius']:.6f}; "
            f"P's condition {result['P_condition']:.3g}"
        )
    if result.get("breaking_vertex"):
        lines.append(f"  breaks at: {result['breaking_vertex']}")
    if result.get("breaking_reason"):
        lines.append(f"  why: {result['breaking_reason']}")
    for m in result["separated_modes"]:
        lines.append(
            f"  separated: a mode at {m['eigenvalue'][0]:.6f} in {m['state']}"
        )
    lines.append(f"  proves: {result['proves']}")
    lines.append(f"  does not prove: {result['does_not_prove']}")
    lines.append(f"  wall time {result['timings_s']['total']:.1f} s")
    return "\n".join(lines)
