"""``certify``: the stability certificate of a scenario's sampled loop
over a box of parameters, each map taken at the steady state its own
parameters produce.

The box, the values the loop can be at, is the scenario's
``uncertainty`` section (a range of one value leaves its parameter out):

- the robust margin's parameters
  (:data:`deburr_drake.analysis.robust.UNCERTAIN_PARAMETERS`: contact
  stiffness, c0, the cutting coefficient, the model mass scale; the burr
  height only enters on a burr, and the operating point is off them);
- the fuzzy surface's slope on each fuzzy axis: the total local slope
  d u_f / d s_k at the operating s_k, by default from 0 to the projection
  bound ``controller.fuzzy.max_slope``, widened to take in the slope the
  rules have learned. The law bounds |slope| by it; the default leaves
  the negative half out (below -K_k the total gain on s_k is negative
  and the loop unstable: docs/certify.md). A slope is changed
  about the operating s_k (theta_ij += (slope - learned) (j Delta_k -
  s_k)), so u_f and the operating point stay where they are: only the
  map's gain moves.

The contact estimator's c-hat is not an axis of its own: in the frozen
loop it enters only through the desired force c0-hat + c1-hat delta*, and
the estimator converges (with the depth reference) to where that equals
the contact's normal force at the desired depth (the estimate's split
between c0-hat and c1-hat is free on that line and does not reach the
map). So every map is taken at its steady state (:func:`steady_context`):
the sensor's filter at the contact's force, c-hat scaled so the desired
force equals the normal force, the loop run ``SETTLE_PERIODS`` periods to
let the held terms settle, and c-hat matched again.

The maps: the one-period map at the operating point (nominal), at both
ends and at the midpoint of each parameter's range with the others nominal,
and at every corner of the parameters that move the map (by more than
``VERTEX_THRESHOLD`` of its norm, balanced), the others nominal. Their
effects do not add up (their cross terms), so the corners are true maps.
What the corners leave out is bounded in the common Lyapunov function's
norm and added to the decay rate: each parameter's curvature (its
midpoint map against the chord through its ends: the miss of a map
quadratic in it) and the half-range of a parameter without a corner axis;
the certificate holds only if the sum stays below 1.

The scenario fields (stiffness, c0, k_c, mass scale) are the diagram's
construction data: each combination has its frozen diagram, built once.
"""

from __future__ import annotations

import copy
import itertools
import time
from typing import Callable, Dict, List, Optional, Tuple

import numpy as np
from pydrake.systems.analysis import (
    ApplySimulatorConfig,
    InitializeParams,
    Simulator,
)
import scipy.linalg

from deburr_drake.analysis.along import at_numerics
from deburr_drake.analysis.certificate import (
    CHECK_MARGIN,
    OutOfTime,
    certify_family,
    certify_rate_bounded,
    check_deadline,
    p_norm,
    reduce_family,
    solve_deadline,
)
from deburr_drake.analysis.operating_point import (
    DEFAULT_TIME_AFTER_CONTACT,
    _next_analysis_time,
    find_operating_point,
)
from deburr_drake.analysis.robust import UNCERTAIN_PARAMETERS
from deburr_drake.analysis.sampled import FrozenMap
from deburr_drake.config import Scenario
from deburr_drake.control.layout import CHAMFER_STATE, CONTROLLER_DIAGNOSTICS
from deburr_drake.math.switching import DWELLS, periodic_growth
from deburr_drake.runs.simulation import set_monitor

#: A parameter whose half-range moves the map by more than this fraction
#: (Frobenius norm) of the nominal map gets a vertex axis.
VERTEX_THRESHOLD = 1e-2
#: Control periods each map's loop may run at its own parameters before
#: the map is taken. 0: the steady state is constructed, not run to (the
#: loop's slowest mode, 0.9986 per period on the paper arm, takes seconds:
#: a run of 40 periods leaves the desired force up to 0.8 N off the
#: normal force, a transient, not a steady state; docs/certify.md).
SETTLE_PERIODS = 0
#: Bisections of the decay rate when the first P leaves no room for what
#: the corners leave out (each one more solve).
ROOM_BISECTIONS = 6
#: Nodes of the grid along a scheduled slope (P affine between them). The
#: window each node's inequality covers is its two cells plus the rate's
#: step: on the paper arm pairs of x2 slope maps 0 and 1000 N s/m apart
#: have a common P and 0 and 2000 none, so cells of at most ~500 N s/m.
SCHEDULE_NODES = 9
#: Most pieces a time-varying parameter's range is cut into (doubled
#: while its curvature is the largest of what a cell's corners leave
#: out): a constant's cell is halved instead, but a parameter that varies
#: while the loop runs needs one P over its whole range, and only more
#: vertices along it shrink its chords' miss (a quarter per doubling).
MAX_PIECES = 8
#: The parameters that are constants of a run (a material's cutting
#: coefficient and contact threshold, the controller model's mass error)
#: and the cells of the first grid over each: a Lyapunov function per
#: cell proves every constant value of the box, not values that jump
#: between cells (the stiffness varies along the edge: it stays
#: time-varying). A fuzzy slope that is held at the operating point
#: (:func:`slope_held`) is a constant too, in one cell at first. k_c
#: starts in 4: over its whole range its curvature alone (0.0072 in P's
#: norm on paper) is more than the slowest mode leaves (0.0014).
CONSTANT_CELLS = {"k_c": 4, "mass_scale": 1, "c0": 1}
#: The affine slope model's largest miss of the true map (relative to
#: the slopes' change of it) with which it is used; finite-difference
#: round-off is about 1e-8.
SLOPE_MODEL_TOLERANCE = 1e-6
#: How many times a cell that is not certified may be halved along one
#: constant (down to 1/16 of its range), and how many cells are tried
#: at most: the search's cost is a program per cell tried.
MAX_HALVINGS = 4
MAX_CELLS = 80
#: A held slope may be halved more: near a slope of zero the loop's
#: lightly damped pair turns with it (docs/certify.md), and the halvings
#: towards that end are geometric (down to 1/512 of the range).
MAX_SLOPE_HALVINGS = 9
#: The box's parameters by short key (``certify``'s ``only``).
BOX_KEYS = {
    "part.material.hydroelastic_modulus": "stiffness",
    "process.contact_threshold_force": "c0",
    "process.cutting_coefficient": "k_c",
    "controller.model_mass_scale": "mass_scale",
}

__all__ = [
    "box_maps",
    "certify",
    "certificate_summary",
    "steady_context",
    "PROVES",
    "DOES_NOT_PROVE",
    "SETTLE_PERIODS",
    "BOX_KEYS",
    "CONSTANT_CELLS",
    "certified_limit",
]

PROVES = (
    "the sampled 2.5 ms loop linearised at its steady cutting state is "
    "exponentially stable for any variation, however fast, of the "
    "parameters within the box (a common quadratic Lyapunov function of "
    "every vertex map)"
)
DOES_NOT_PROVE = (
    "a constant parameter (k_c, c0, the mass scale, a held slope) "
    "jumping between the cells of its grid while the loop runs, a held "
    "slope once its s leaves the adaptation's dead zone, loss of contact, burr "
    "impacts, the depth^1.4 contact away from the operating point, the "
    "outer loop and the adaptation's own dynamics (frozen), parameter "
    "values outside the box's ranges (a fuzzy slope's included), the "
    "feed's range and other poses along the edge (not in the box)"
)


PROVES_SCHEDULED = (
    "the sampled 2.5 ms loop linearised at its steady cutting state is "
    "exponentially stable for any variation of the parameters within the "
    "box, however fast, with the slope on {axis} moving no faster than "
    "{step:.4g} N s/m per period (the adaptation law's bound, "
    "slope_rate_bound): a Lyapunov function x^T P(slope) x, P affine "
    "between {nodes} nodes of the slope's range"
)


C_HAT = (
    "not an axis: in the frozen loop c-hat enters only through the "
    "desired force c0-hat + c1-hat delta*, which the estimator drives to "
    "the contact's normal force at the desired depth; every map has c-hat "
    "scaled to that steady state of its own contact parameters"
)


def _fuzzy_point(op) -> List[Dict]:
    """[{axis, s0, slope, held}] per fuzzy axis: the operating s_k (m/s),
    the learned surface's local slope there (N s/m) and why the slope is
    a constant of the loop there (:func:`slope_held`, None if not)."""
    controller = op.diagram.GetSubsystemByName("controller")
    fuzzy = op.scenario.controller.fuzzy
    cc = controller.GetMyContextFromRoot(op.context)
    diagnostics = controller.GetOutputPort("diagnostics").Eval(cc)
    s = CONTROLLER_DIAGNOSTICS.get(diagnostics, "s")
    y0 = float(np.linalg.norm(CONTROLLER_DIAGNOSTICS.get(diagnostics, "x_pd")))
    theta = controller.theta(cc)
    out = []
    for k, (axis, rb) in enumerate(
        zip(op.scenario.controller.fuzzy.axes, controller.rule_bases)
    ):
        h = 1e-3 * rb._dk
        slope = (
            rb.evaluate(theta[k], y0, s[axis] + h)
            - rb.evaluate(theta[k], y0, s[axis] - h)
        ) / (2 * h)
        out.append(
            {
                "axis": int(axis),
                "s0": float(s[axis]),
                "slope": slope,
                "held": slope_held(rb, float(s[axis]), theta[k], fuzzy),
            }
        )
    return out


def slope_held(rb, s0: float, theta, fuzzy) -> Optional[str]:
    """Why the surface's slope on ``rb``'s axis is a constant of the loop
    near the operating point (None when it is not): the rules do not
    adapt, or the operating s_k is inside the adaptation's dead zone,
    where the law (35) is zero for every |s_k| below its half-width (not
    only to first order), and the slope bound pulls no weight."""
    if not fuzzy.adapt:
        return "the rules do not adapt"
    hw = rb.resolved_dead_zone_half_width
    if abs(s0) >= hw:
        return None
    max_slope = float(fuzzy.max_slope) if fuzzy.max_slope > 0 else np.inf
    pull = rb.slope_rate(theta, max_slope, float(fuzzy.max_slope_rate))
    if np.any(pull != 0.0):
        return None
    return (
        f"the operating s ({s0 * 1e3:.3g} mm/s) is inside the adaptation's "
        f"dead zone ({hw * 1e3:.3g} mm/s): its rules do not move while "
        f"|s| stays below {hw * 1e3:.3g} mm/s, and no slope is beyond the "
        "bound"
    )


def _pivoted_slope(k: int, added: float, s0: float) -> Callable:
    """Adds ``added`` (N s/m) to fuzzy axis k's slope about s0: theta_ij
    += added (j Delta_k - s0); B-splines of order >= 1 reproduce linear
    functions and sum to one, so u_f gains added (s_k - s0)."""

    def modify(diagram, context):
        controller = diagram.GetSubsystemByName("controller")
        cc = controller.GetMyMutableContextFromRoot(context)
        x = cc.get_continuous_state_vector().CopyToVector()
        rb = controller.rule_bases[k]
        j = np.arange(-rb._U, rb._U + 1)
        grid = np.tile(added * (j * rb._dk - s0), (2 * rb._U + 1, 1))
        start = 1 + k * rb.n_rules
        x[start : start + rb.n_rules] += grid.ravel()
        cc.SetContinuousState(x)

    return modify


def _match_estimates(diagram, context) -> float:
    """Scales c-hat so the desired force c0-hat + c1-hat delta* equals the
    measured normal force (the estimator's steady state); returns the
    force error it removed (N)."""
    observer = diagram.GetSubsystemByName("chamfer_observer")
    chamfer = observer.GetOutputPort("chamfer_state").Eval(
        observer.GetMyContextFromRoot(context)
    )
    f_n = float(CHAMFER_STATE.get(chamfer, "f_n"))
    estimator = diagram.GetSubsystemByName("contact_estimator")
    ec = estimator.GetMyMutableContextFromRoot(context)
    desired = float(estimator.GetOutputPort("desired_normal_force").Eval(ec)[0])
    c = ec.get_continuous_state_vector().CopyToVector()
    ec.SetContinuousState(c * (f_n / desired))
    return desired - f_n


def steady_context(frozen: FrozenMap, context, periods: int = SETTLE_PERIODS):
    """(context, moved, residual): ``context`` of ``frozen``'s diagram
    brought to its own steady state (module docstring): the sensor's
    filter at the raw force, c-hat scaled so the desired force is the
    normal force (``moved``: by how much it changed it, N), then, with
    ``periods``, that many periods run (ending just before an inner
    sample that is not an outer one) and c-hat matched again
    (``residual``: the desired-force error it removed, N; 0 without)."""
    diagram = frozen.diagram
    sensor = diagram.GetSubsystemByName("force_sensor")
    sc = sensor.GetMyMutableContextFromRoot(context)
    sc.SetDiscreteState(0, sensor.raw_force(sc))
    moved = _match_estimates(diagram, context)
    if periods <= 0:
        return context, moved, 0.0
    scenario = frozen.scenario
    config = copy.copy(frozen.config)
    config.start_time = context.get_time()
    simulator = Simulator(diagram, context)
    set_monitor(simulator, diagram, config.integration_scheme)
    ApplySimulatorConfig(config, simulator)
    simulator.Initialize(InitializeParams(suppress_initialization_events=True))
    simulator.AdvanceTo(
        _next_analysis_time(
            context.get_time() + periods * frozen.period,
            frozen.period,
            scenario.command.period,
        )
    )
    context = simulator.get_context().Clone()
    return context, moved, _match_estimates(diagram, context)


class _Maps:
    """The one-period maps at parameter values ({name: value}), each
    frozen diagram built once per combination of scenario fields."""

    def __init__(self, op, box, settle_periods):
        self.op, self.box, self.settle = op, box, settle_periods
        self._frozen = {}
        # Each map once per certify call: cells share their corners.
        self.taken: Dict[tuple, np.ndarray] = {}
        self.moved, self.residuals = [], []
        self.affine = True

    def frozen(self, fields) -> FrozenMap:
        key = tuple(sorted(fields.items()))
        if key not in self._frozen:
            self._frozen[key] = FrozenMap(
                self.op.scenario, plan=self.op.plan, **fields
            )
        return self._frozen[key]

    def __call__(self, values) -> np.ndarray:
        """The map at ``values``: the fuzzy slopes are gains of the held
        actuation (u_f gains slope x (s_k - s0) about the same steady
        state), and the one-period map is affine in them, so it is taken
        from the true maps at the slopes' low ends and at each one's high
        end alone (:meth:`check_slope_model` measures the rest)."""
        return self._affine(values) if self.affine else self.true(values)

    def true(self, values) -> np.ndarray:
        """The map taken at ``values`` (each once per certify call)."""
        key = tuple(sorted(values.items()))
        if key not in self.taken:
            check_deadline()
            self.taken[key] = self._take(values)
        return self.taken[key]

    def _slope_steps(self, values):
        """(base, [(slope, change)]): the true map at ``values`` with every
        slope at its low end, and each slope's change of it over its
        range."""
        slopes = [p for p in self.box if p["field"] is None]
        low = {**values, **{p["name"]: p["range"][0] for p in slopes}}
        base = self.true(low)
        return base, [
            (p, self.true({**low, p["name"]: p["range"][1]}) - base)
            for p in slopes
        ]

    def _affine(self, values) -> np.ndarray:
        base, steps = self._slope_steps(values)
        A = base
        for p, change in steps:
            lo, hi = p["range"]
            t = (values[p["name"]] - lo) / (hi - lo)
            if t != 0.0:
                A = A + t * change
        return A

    def check_slope_model(self) -> Dict:
        """The affine slope model against the true map at the box's
        nominal values (relative to the slopes' change of the map,
        balanced as the map: finite-difference round-off when it holds);
        a model that misses by more than ``SLOPE_MODEL_TOLERANCE`` is not
        used: every map is then a true one."""
        values = {p["name"]: p["nominal"] for p in self.box}
        _, steps = self._slope_steps(values)
        if not steps:
            return {"slopes": 0, "used": self.affine}
        A = self.true(values)
        balanced = _balancer(A)
        change = sum(np.linalg.norm(balanced(D)) for _, D in steps)
        miss = float(np.linalg.norm(balanced(self._affine(values) - A)))
        miss /= max(float(change), 1e-300)
        self.affine = miss <= SLOPE_MODEL_TOLERANCE
        return {
            "maps": "affine in the fuzzy slopes, from the true maps at their "
            "low ends and at each one's high end",
            "miss_at_nominal": miss,
            "used": self.affine,
        }

    def _take(self, values) -> np.ndarray:
        box = self.box
        frozen = self.frozen(
            {
                p["field"]: values[p["name"]]
                for p in box
                if p["field"] is not None
            }
        )
        modifies = [
            _pivoted_slope(
                p["fuzzy_index"], values[p["name"]] - p["nominal"], p["s0"]
            )
            for p in box
            if p["field"] is None
        ]

        def modify_all(diagram, context):
            for m in modifies:
                m(diagram, context)

        context = frozen.context_from(
            self.op.diagram, self.op.context, modify_all
        )
        context, moved, residual = steady_context(frozen, context, self.settle)
        self.moved.append(abs(moved))
        self.residuals.append(abs(residual))
        return frozen.at_context(context)


def _box(op) -> List[Dict]:
    """[{name, field, unit, nominal, range}] (a fuzzy slope: field None,
    with its axis' index and operating s0): the parameters of the
    scenario's ``uncertainty`` box and their ranges (a range of one
    value: out of the box, :func:`_select_box`)."""
    scenario = op.scenario
    box = []
    for p in UNCERTAIN_PARAMETERS:
        if p.field is None:
            continue  # the burr height: off the burrs it is not in the map
        nominal, low, high = p.values(scenario)
        box.append(
            {
                "key": BOX_KEYS[p.field],
                "name": p.name,
                "field": p.field,
                "unit": p.unit,
                "nominal": nominal,
                "range": [low, high],
            }
        )
    max_slope = float(scenario.controller.fuzzy.max_slope)
    if np.isfinite(max_slope) and max_slope > 0:
        for k, point in enumerate(_fuzzy_point(op)):
            fractions = scenario.uncertainty.slope_fractions(point["axis"])
            box.append(
                {**_slope_entry(point, fractions, max_slope), "fuzzy_index": k}
            )
    return box


def _slope_entry(point: Dict, fractions, max_slope: float) -> Dict:
    """The box's entry of one fuzzy axis' slope (``point`` from
    :func:`_fuzzy_point`): its range ``fractions`` of ``max_slope``,
    widened to take in the slope the rules have learned (the operating
    point is in the box; ``widened`` says so); fractions of one value:
    the learned slope alone (out of the box)."""
    low, high = (float(f) * max_slope for f in fractions)
    learned = float(point["slope"])
    widened = None
    if fractions[0] == fractions[1]:
        low = high = learned
    elif not low <= learned <= high:
        widened = (
            f"widened from [{low:.6g}, {high:.6g}] N s/m to take in the "
            f"learned slope {learned:.6g} N s/m"
        )
        low, high = min(low, learned), max(high, learned)
    entry = {
        "key": f"slope_x{point['axis'] + 1}",
        "name": f"fuzzy surface slope on x{point['axis'] + 1} "
        "(total, at the operating s)",
        "field": None,
        "unit": "N s/m",
        "nominal": learned,
        "range": [low, high],
        "s0": point["s0"],
        "held": point["held"],
    }
    if widened:
        entry["widened"] = widened
    return entry


def _labels(frozen: FrozenMap) -> List[str]:
    context = frozen.diagram.CreateDefaultContext()
    labels = []
    for e in frozen.entries:
        n = e.get(frozen.diagram, context).size
        labels += [f"{e.label}[{i}]" for i in range(n)]
    return labels


def _nodes(p: Dict) -> List[float]:
    """The values of parameter ``p`` at which it gets vertices: its
    range's ends, and the ends of its pieces when it is cut into some
    (:func:`_more_pieces`)."""
    return list(p.get("nodes") or p["range"])


def box_maps(maps: _Maps, box, say=lambda m: None) -> Dict:
    """{A0, ends, mids, curvatures, labels, period}: the one-period maps
    of :func:`_parameter_maps`, the states' labels and the period."""
    frozen = maps.frozen({})
    return {
        **_parameter_maps(maps, box, say),
        "labels": _labels(frozen),
        "period": frozen.period,
    }


def _parameter_maps(maps, box, say=lambda m: None) -> Dict:
    """{A0, ends [(A_lo, A_hi)], mids, curvatures}: the one-period maps
    (``maps``) at the nominal values, at both ends and at the midpoint of
    every parameter of ``box``; ``curvatures``: per parameter, each
    piece's midpoint map less the chord through its ends (one piece: the
    whole range)."""
    nominal = {p["name"]: p["nominal"] for p in box}
    A0 = maps(nominal)
    ends, mids, curvatures = [], [], []
    for p in box:
        lo, hi = p["range"]
        ends.append(tuple(maps({**nominal, p["name"]: v}) for v in (lo, hi)))
        # The midpoint's map measures the curvature; it is the nominal
        # one when the range is centred on the nominal value.
        centred = abs(0.5 * (lo + hi) - p["nominal"]) <= 1e-12 * abs(hi - lo)
        mids.append(
            A0 if centred else maps({**nominal, p["name"]: 0.5 * (lo + hi)})
        )
        nodes = _nodes(p)
        if len(nodes) == 2:
            curvatures.append([mids[-1] - 0.5 * (ends[-1][0] + ends[-1][1])])
        else:
            at = [maps({**nominal, p["name"]: v}) for v in nodes]
            curvatures.append(
                [
                    maps({**nominal, p["name"]: 0.5 * (a + b)}) - 0.5 * (A + B)
                    for a, b, A, B in zip(nodes, nodes[1:], at, at[1:])
                ]
            )
        say(f"maps at the ends of {p['name']}")
    return {"A0": A0, "ends": ends, "mids": mids, "curvatures": curvatures}


def _balancer(A0: np.ndarray) -> Callable:
    """M -> D^-1 M D, D the diagonal balancing of ``A0`` (one scale for
    the states' units, as the certificate's program takes them)."""
    _, (scale, _) = scipy.linalg.matrix_balance(
        A0, permute=False, separate=True
    )
    return lambda M: M * (1.0 / scale)[:, None] * scale[None, :]


def _values(box, signs) -> Dict[str, float]:
    """{name: value}: each parameter at its low end (sign -1), high end
    (+1) or nominal (0)."""
    return {
        p["name"]: p["nominal"] if si == 0 else p["range"][0 if si < 0 else 1]
        for p, si in zip(box, signs)
    }


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


def _corners(maps: _Maps, box, axes):
    """(maps, points): the true maps at every corner of ``axes`` (at every
    node of a parameter cut into pieces), the other parameters nominal.
    The parameters' effects do not add up (their cross terms), so corners
    of a model built from the ends would not do."""
    corners, points = [], []
    if not axes:
        return corners, points
    nominal = {p["name"]: p["nominal"] for p in box}
    for values in itertools.product(*[_nodes(box[k]) for k in axes]):
        point = {**nominal}
        point.update({box[k]["name"]: v for k, v in zip(axes, values)})
        corners.append(maps(point))
        points.append(point)
    return corners, points


def _model_error(cert, box, maps, axes) -> Dict:
    """What the corners leave out, in P's norm: the curvature of each
    parameter's map (its midpoint map against the chord through its ends,
    the worst piece's when it is cut into pieces) and the half-range of
    those without a corner axis; the status inconclusive when the decay
    rate plus it is not below 1."""
    left_out = []
    for j, (p, (lo, hi)) in enumerate(zip(box, maps["ends"])):
        entry = {"parameter": p["name"]}
        pieces = maps["curvatures"][j]
        # The parameter is in one piece at a time: the worst piece's chord.
        bound = max(p_norm(cert.reduced.transform(E), cert.P) for E in pieces)
        if len(pieces) > 1:
            entry["pieces"] = len(pieces)
        if j not in axes:
            half = p_norm(cert.reduced.transform(0.5 * (hi - lo)), cert.P)
            entry["half_range_p_norm"] = half
            bound += half
        left_out.append({**entry, "p_norm": bound})
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


def _axes_for_room(cert, error: Dict) -> List[int]:
    """The parameters without a corner axis to give one when ``cert``'s P
    leaves no room (inconclusive) for what the corners leave out: by
    their half-ranges in P's norm, largest first, until the rest fits in
    what the decay rate leaves (all of them if it never does). A corner
    is the true map, so it takes the half-range out where a narrower cell
    of the constants would not (their corners are already axes)."""
    if error.get("status") != "inconclusive":
        return []
    halves = sorted(
        (
            (e["half_range_p_norm"], j)
            for j, e in enumerate(error["model_error"])
            if "half_range_p_norm" in e
        ),
        reverse=True,
    )
    left = error["decay_rate_with_model_error"] - cert.decay_rate
    added = []
    for half, j in halves:
        if cert.decay_rate + left < 1.0:
            break
        added.append(j)
        left -= half
    return added


def _rate_step(op, p, period: float) -> Dict:
    """{per_s, per_period, ...}: the adaptation law's bound on how fast
    slope ``p`` moves (:meth:`RuleBase.slope_rate_bound` at the operating
    s_k), 0 when the rules do not adapt."""
    fuzzy = op.scenario.controller.fuzzy
    controller = op.diagram.GetSubsystemByName("controller")
    rb = controller.rule_bases[p["fuzzy_index"]]
    per_s = (
        rb.slope_rate_bound(fuzzy.adaptation_gain, p["s0"])
        if fuzzy.adapt
        else 0.0
    )
    return {
        "per_s": per_s,
        "per_period": per_s * period,
        "period_s": period,
        "adaptation_gain": float(fuzzy.adaptation_gain),
        "upsilon": int(rb._U),
        "deltak": float(rb._dk),
        "s0": float(p["s0"]),
        "order": int(rb._m),
        "derivation": (
            "d/dt of the slope at s0 = r s (sum_i nu0_i nu0_i') (sum_j "
            "N_j'(s0) N_j(s)); |s| <= min(upsilon deltak, |s0| + (m + 1) "
            "deltak) where (35) acts and the rules overlap s0's, the first "
            "sum <= 1, the second <= max_j |N_j'(s0)|; the slope bound's "
            "pull is zero inside the box, a fuzzy weight < 1 only slows it"
        ),
    }


def _slopes_by_move(box, maps) -> List[int]:
    """The indices in ``box`` of the moving fuzzy slopes (not held as
    constants), the one whose ends move the map most (balanced by the
    nominal map's scaling) first."""
    balanced = _balancer(maps["A0"])
    return sorted(
        (
            j
            for j, p in enumerate(box)
            if p["field"] is None and not p.get("constant")
        ),
        key=lambda j: (
            -np.linalg.norm(balanced(maps["ends"][j][1] - maps["ends"][j][0]))
        ),
    )


def _slope_ends(box, maps, solver):
    """(index in ``box``, certificate) of the first slope (the held ones,
    then the moving ones in :func:`_slopes_by_move`'s order) whose two
    ends, with the nominal map, have no common P (the whole family then
    has none: the program on it need not run); (None, None) if every
    slope's do."""
    held = [
        j for j, p in enumerate(box) if p["field"] is None and p.get("constant")
    ]
    for j in held + _slopes_by_move(box, maps):
        cert = certify_family(
            [maps["A0"], *maps["ends"][j]],
            maps["labels"],
            solver=solver,
            bisections=0,
        )
        if cert.status != "certified":
            return j, cert
    return None, None


def _schedule_left_out(box, maps, axes, k) -> List:
    """[(name, [E...])]: what the other parameters' corners leave out when
    slope ``k`` is scheduled (each one's curvature, and the half-range of
    those without a corner axis), for :func:`certify_rate_bounded` to bound
    in P(slope)."""
    left_out = []
    for j, (q, (a, b)) in enumerate(zip(box, maps["ends"])):
        if j != k:
            # One piece at a time: the worst one's chord counts.
            Es = [tuple(maps["curvatures"][j])]
            if j not in axes:
                Es.append(0.5 * (b - a))
            left_out.append((q["name"], Es))
    return left_out


class _SlopeMaps:
    """The maps along a fuzzy slope, per corner of the other parameters:
    the quadratic in the slope through the true maps at its range's ends
    and centre. The slope is a gain of the law (u_f gains slope x (s_k -
    s0)), and the one-period map is affine in a gain of the held
    actuation: the centre's miss of the chord through the ends is
    finite-difference round-off (``record``), and the quadratic carries
    it, so the chord between grid nodes leaves out what the certificate
    bounds as it does for true maps (its ``chord_miss``)."""

    def __init__(self, lows, centres, highs, lo, hi):
        self.lows, self.centres, self.highs = lows, centres, highs
        self.lo, self.hi = lo, hi

    def __call__(self, value) -> List[np.ndarray]:
        t = (value - self.lo) / (self.hi - self.lo)
        return [
            a + t * (b - a) + 4.0 * t * (1.0 - t) * (c - 0.5 * (a + b))
            for a, c, b in zip(self.lows, self.centres, self.highs)
        ]

    def record(self) -> Dict:
        """The centre's largest miss of the chord, relative to the change
        of the map over the range (balanced as the nominal map)."""
        balanced = _balancer(self.centres[0])
        miss = max(
            np.linalg.norm(balanced(c - 0.5 * (a + b)))
            / max(np.linalg.norm(balanced(b - a)), 1e-300)
            for a, c, b in zip(self.lows, self.centres, self.highs)
        )
        return {
            "maps": "the quadratic in the slope through the true maps at "
            "its range's ends and centre, per corner",
            "centre_miss_of_chord": float(miss),
        }


def _scheduled(op, box, maps_at, maps, axes, k, solver, say) -> Dict:
    """The certificate with slope ``k`` of ``box`` scheduled: a grid of
    ``SCHEDULE_NODES`` nodes and P(slope) affine between them, moving at
    most the adaptation law's step per period (:func:`_rate_step`); at
    every node and cell midpoint, the maps at the other corner axes'
    corners (they may move arbitrarily fast), each from its three true
    maps along the slope (:class:`_SlopeMaps`); the others' half-ranges
    and curvatures bounded in P(slope) and added
    (:func:`certify_rate_bounded`)."""
    p = box[k]
    rate = _rate_step(op, p, maps["period"])
    lo, hi = p["range"]
    nodes = np.linspace(lo, hi, SCHEDULE_NODES)
    others = [j for j in axes if j != k]
    corners = list(itertools.product((-1.0, 1.0), repeat=len(others)))

    def at(value):
        out = []
        for corner in corners or [()]:
            sign = [0.0] * len(box)
            for si, j in zip(corner, others):
                sign[j] = si
            values = _values(box, sign)
            values[p["name"]] = value
            out.append(maps_at(values))
        return out

    say(
        f"P({p['key']}) on {SCHEDULE_NODES} nodes, "
        f"{max(len(corners), 1)} corners each"
    )
    along = _SlopeMaps(at(lo), at(0.5 * (lo + hi)), at(hi), lo, hi)
    node_maps = [along(v) for v in nodes]
    mid_maps = [along(0.5 * (a + b)) for a, b in zip(nodes[:-1], nodes[1:])]
    left_out = _schedule_left_out(box, maps, axes, k)
    cert = certify_rate_bounded(
        node_maps,
        nodes,
        rate["per_period"],
        maps["labels"],
        mids=mid_maps,
        left_out=left_out,
        solver=solver,
    )
    return {
        "scheduled": p["key"],
        "slope_rate_bound": rate,
        "schedule_nodes": nodes.tolist(),
        "schedule": cert.to_dict(),
        "scheduled_maps": 3 * len(node_maps[0]),
        "slope_model": along.record(),
    }


#: what certificate.json says of each parameter of the box
_BOX_FIELDS = (
    "key",
    "name",
    "field",
    "unit",
    "nominal",
    "range",
    "s0",
    "held",
    "widened",
    "constant",
    "nodes",
)


def _select_box(
    box: List[Dict], only: Optional[List[str]]
) -> Tuple[List[Dict], List[Dict]]:
    """(in, out): the box's parameters named in ``only`` (all with None)
    whose ranges hold more than one value, and the others (at their
    nominal values); an unknown name is refused before any map is
    taken."""
    if only is not None:
        unknown = set(only) - {p["key"] for p in box}
        if unknown:
            raise ValueError(
                f"unknown box parameters {sorted(unknown)}: allowed "
                f"{[p['key'] for p in box]}"
            )
    chosen = [
        p
        for p in box
        if (only is None or p["key"] in only) and p["range"][1] > p["range"][0]
    ]
    return chosen, [p for p in box if p not in chosen]


def _does_not_prove(left_out: List[Dict]) -> str:
    """``DOES_NOT_PROVE``, and the fuzzy slopes left out of the box
    although their rules move at the operating point."""
    moving = [
        p["key"] for p in left_out if p["field"] is None and not p["held"]
    ]
    if not moving:
        return DOES_NOT_PROVE
    return (
        f"{DOES_NOT_PROVE}; {' and '.join(moving)}, which the adaptation "
        "moves at the operating point, left out of the box (held at the "
        "learned value)"
    )


def _common_quadratic(family, box, maps, axes, options, final):
    """(certificate, what the corners leave out) of one common quadratic
    Lyapunov function of ``family`` (``final``: the cell will not be
    halved, so its breaking map is searched for when there is none, and
    its decay rate bisected for room; else one step of it)."""
    solver, _, bisections, seeds = options

    def room(cert):
        return "status" not in _model_error(cert, box, maps, axes)

    # The first P sits on its LMI's boundary at gamma = 1 - 1e-5: the
    # decay rate is bisected until it leaves room for what the corners
    # leave out (asked for bisections: all of them, for the best rate).
    # A cell that will be halved gets one step (halfway to the largest
    # spectral radius): halving quarters the curvature, and on paper a
    # solve near the least rate takes ~100 s.
    # Cells' families laid out alike (the same corner axes) bind at much
    # the same maps: each program starts with those the last one held.
    layout = (len(family), tuple(axes))
    cert = certify_family(
        family,
        maps["labels"],
        solver=solver,
        bisections=max(bisections, ROOM_BISECTIONS if final else 1),
        enough=None if bisections else room,
        name_breaking=final,
        seed=seeds.get(layout, ()),
    )
    if cert.held:
        seeds[layout] = cert.held
    error = _model_error(cert, box, maps, axes) if cert.P is not None else {}
    return cert, error


def _with_schedule(result: Dict, scheduled: Optional[Dict]) -> str:
    """``result`` updated with a slope schedule's certificate (the common
    quadratic one's status kept apart); returns what it proves."""
    if scheduled is None:
        return PROVES
    result["common_quadratic_status"] = result["status"]
    result.update(scheduled)
    result["status"] = scheduled["schedule"]["status"]
    if result["status"] != "certified":
        return PROVES
    check = scheduled["schedule"]["check"]
    result["decay_rate_per_period"] = check["decay_rate"]
    result["decay_rate_with_model_error"] = check["decay_rate_with_model_error"]
    result["P_condition"] = check["P_condition"]
    return PROVES_SCHEDULED.format(
        axis=scheduled["scheduled"].split("_")[1],
        step=scheduled["slope_rate_bound"]["per_period"],
        nodes=len(scheduled["schedule_nodes"]),
    )


def _map_names(box: List[Dict], points) -> List[str]:
    """The family's maps by name: nominal, each parameter's ends, then
    the corners."""
    return (
        ["nominal"]
        + [f"{p['name']} = {v:g}" for p in box for v in p["range"]]
        + [
            "corner: " + ", ".join(f"{k} = {v:g}" for k, v in q.items())
            for q in points
        ]
    )


def _schedule_worth_trying(cert, error: Dict, box: List[Dict]) -> bool:
    """A slope schedule, when the common quadratic form did not certify
    and the box has a slope (a map unstable by itself refuses the box
    whatever V is tried)."""
    return (
        error.get("status", cert.status) != "certified"
        and max(cert.spectral_radii) < 1.0
        and any(p["field"] is None and not p.get("constant") for p in box)
    )


def _cells(box: List[Dict], cells: Dict[str, int]) -> List[List[Dict]]:
    """The boxes of the cells of the grid over the constant parameters of
    ``box`` (``cells`` by key: how many cells along each), each a copy of
    ``box`` with the constants' ranges narrowed to the cell and their
    nominal values at its centre; one cell (``box``) without constants."""
    constants = [j for j, p in enumerate(box) if cells.get(p["key"], 0) > 0]
    edges = [
        np.linspace(*box[j]["range"], cells[box[j]["key"]] + 1)
        for j in constants
    ]
    out = []
    for index in itertools.product(*[range(len(e) - 1) for e in edges]):
        cell = [dict(p) for p in box]
        for j, e, i in zip(constants, edges, index):
            lo, hi = float(e[i]), float(e[i + 1])
            cell[j].update(range=[lo, hi], nominal=0.5 * (lo + hi))
            cell[j]["constant"] = True
        out.append(cell)
    return out


def _halves(cell: List[Dict], j: int) -> List[List[Dict]]:
    """The two halves of ``cell`` along its constant ``j``."""
    lo, hi = cell[j]["range"]
    out = []
    for a, b in ((lo, 0.5 * (lo + hi)), (0.5 * (lo + hi), hi)):
        half = [dict(p) for p in cell]
        half[j].update(
            range=[a, b],
            nominal=0.5 * (a + b),
            halvings=cell[j].get("halvings", 0) + 1,
        )
        out.append(half)
    return out


def _open_constants(cell: List[Dict]) -> List[int]:
    """The constants of ``cell`` that may still be halved."""
    return [
        j
        for j, p in enumerate(cell)
        if p.get("constant")
        and p.get("halvings", 0)
        < (MAX_SLOPE_HALVINGS if p["field"] is None else MAX_HALVINGS)
    ]


def _split_axis(cell: List[Dict], result: Dict) -> Optional[int]:
    """The constant to halve a cell that is not certified along: a held
    slope whose ends have no common P; for a P that leaves no room
    (inconclusive), the constant whose curvature is the most of what the
    corners leave out; else the constant whose range in the cell moves
    the map most; None when the cell has a map unstable
    by itself (no narrower cell takes it out), a moving slope whose ends
    at the cell's centre have no common P (a schedule's job, tried on the
    first grid's cells, not a narrower cell's) or no constant to
    halve."""
    candidates = _open_constants(cell)
    ends = result.get("_ends_failed")
    if not candidates or not result["_stable"]:
        return None
    if ends is not None and not cell[ends].get("constant"):
        return None
    if ends in candidates:
        return ends
    if result["status"] == "inconclusive" and result.get("model_error"):
        # A P that leaves no room for what the corners leave out: the
        # constant whose curvature is the most of it.
        left_out = [e["p_norm"] for e in result["model_error"]]
        return max(candidates, key=lambda j: left_out[j])
    return max(candidates, key=lambda j: result["_moves"][j])


def search_cells(
    grid: List[List[Dict]],
    try_cell: Callable[[List[Dict], bool], Dict],
    max_cells: int = MAX_CELLS,
    results: Optional[List[Dict]] = None,
) -> List[Dict]:
    """Every cell's result: the cells of ``grid`` tried in order
    (``try_cell(cell, splittable)``); one that is not certified is
    halved (:func:`_split_axis`) and its halves tried in its place. The
    search stops at a cell that is not certified and cannot be halved
    (or after ``max_cells`` tries): the certificate holds only if it
    ends with every cell tried certified or halved. ``results``: the
    list each result is appended to as it comes (what an interrupted
    search has finished)."""
    pending = list(grid)
    results = [] if results is None else results
    while pending:
        cell = pending.pop(0)
        splittable = (
            bool(_open_constants(cell)) and len(results) + 1 < max_cells
        )
        result = try_cell(cell, splittable)
        results.append(result)
        if result["status"] == "certified":
            continue
        j = _split_axis(cell, result) if splittable else None
        if j is None:
            break
        result["halved"] = cell[j]["key"]
        pending[:0] = _halves(cell, j)
    return results


def _stable(family) -> bool:
    """Every map's own spectral radius below 1 (else the family's program
    names the unstable one at once)."""
    return all(
        np.max(np.abs(np.linalg.eigvals(A))) < 1.0 - CHECK_MARGIN
        for A in family
    )


def _family(maps_at, box, maps, axes, say):
    """(maps, names): the nominal map, each parameter's ends and the true
    maps at the corners of ``axes``."""
    corners, points = _corners(maps_at, box, axes)
    say(f"maps at the {len(corners)} corners")
    family = [maps["A0"]] + [m for pair in maps["ends"] for m in pair]
    return family + corners, _map_names(box, points)


def _more_pieces(box, error: Dict, axes) -> Optional[int]:
    """The time-varying parameter to cut into twice as many pieces, when
    a P leaves no room (inconclusive) for what the corners leave out and
    that parameter's curvature is either the most of it or all that
    keeps the rest from fitting; None for a constant (a narrower cell
    shrinks its curvature), a slope (its map is affine), a parameter
    without a corner axis (:func:`_axes_for_room`'s) or one already in
    ``MAX_PIECES``."""
    if error.get("status") != "inconclusive":
        return None
    left_out = [e["p_norm"] for e in error["model_error"]]
    rest = error["decay_rate_with_model_error"] - 1.0
    for j in np.argsort(left_out)[::-1]:
        p = box[j]
        if (
            p.get("constant")
            or p["field"] is None
            or j not in axes
            or len(_nodes(p)) - 1 >= MAX_PIECES
        ):
            continue
        if left_out[j] == max(left_out) or rest < left_out[j]:
            return int(j)
    return None


def _common_with_room(maps_at, box, maps, at, options, splittable, say):
    """(certificate, what the corners leave out, axes, maps, names) of
    one common quadratic P of the family ``at`` (axes, maps, names); when
    its P leaves no room for what the corners leave out, once more with
    the corners of the parameters whose half-ranges leave none
    (:func:`_axes_for_room`), then with a time-varying parameter whose
    curvature is the most of it cut into twice the pieces
    (:func:`_more_pieces`) until it fits or neither helps (``box`` and
    ``maps`` then hold the pieces)."""
    axes, family, names = at
    solves = 0

    def solve(family):
        nonlocal solves
        say(f"common Lyapunov function of {len(family)} maps ({options[0]})")
        cert, error = _common_quadratic(
            family, box, maps, axes, options, not splittable
        )
        solves += cert.solves
        return cert, error

    cert, error = solve(family)
    added = _axes_for_room(cert, error)
    if added:
        say(
            "corner axes for "
            + ", ".join(box[j]["key"] for j in added)
            + ": their half-ranges leave no room"
        )
        axes = sorted(axes + added)
        family, names = _family(maps_at, box, maps, axes, say)
        cert, error = solve(family)
    while (j := _more_pieces(box, error, axes)) is not None:
        pieces = 2 * (len(_nodes(box[j])) - 1)
        box[j]["nodes"] = np.linspace(*box[j]["range"], pieces + 1).tolist()
        say(f"{box[j]['key']} in {pieces} pieces: its curvature leaves no room")
        maps.update(_parameter_maps(maps_at, box))
        family, names = _family(maps_at, box, maps, axes, say)
        cert, error = solve(family)
    cert.solves = solves
    return cert, error, axes, family, names


def _cell_axes(box, maps, threshold) -> List[int]:
    """A cell's corner axes: the parameters whose half-range moves the
    map by more than ``threshold``, and the constants."""
    # A constant's cell gets a corner axis whatever its size: its P must
    # serve the cell's corners, and a half-range bounded in P's norm
    # instead costs more than the room the slowest mode leaves.
    constants = {j for j, p in enumerate(box) if p.get("constant")}
    moving = _corner_axes(maps["A0"], maps["ends"], threshold)
    return sorted(set(moving) | constants)


def _search_fields(result, maps, ends_stable):
    """What :func:`search_cells` reads of a cell's result: how far each
    parameter's range moves the map (halving's order), which slope's
    ends failed, whether every map is stable."""
    balanced = _balancer(maps["A0"])
    result["_moves"] = [
        np.linalg.norm(balanced(hi - lo)) for lo, hi in maps["ends"]
    ]
    result["_ends_failed"], result["_stable"] = ends_stable


def _certify_cell(op, box, maps_at, options, say, splittable=False) -> Dict:
    """The certificate of one cell's box (every parameter time-varying
    within it): the common quadratic P, then, if it fails and the cell
    will not be halved (``splittable`` False) and is one of the first
    grid's, P(slope) of a slope that is not held."""
    solver, threshold, bisections, _ = options
    timings = {}
    t1 = time.perf_counter()
    maps = box_maps(maps_at, box, say)
    axes = _cell_axes(box, maps, threshold)
    family, names = _family(maps_at, box, maps, axes, say)
    timings["maps_s"] = time.perf_counter() - t1
    t2 = time.perf_counter()
    stable = _stable(family)
    k, cert = _slope_ends(box, maps, solver) if stable else (None, None)
    ends_failed = k
    if cert is None:
        cert, error, axes, family, names = _common_with_room(
            maps_at,
            box,
            maps,
            (axes, family, names),
            options,
            splittable,
            say,
        )
        stable = _stable(family)
    else:
        # A subset with no common P: the family has none either.
        say(f"no common Lyapunov function of the ends of {box[k]['key']}")
        lo, hi = box[k]["range"]
        names = ["nominal"] + [f"{box[k]['name']} = {v:g}" for v in (lo, hi)]
        error = {"common_quadratic_family": f"the ends of {box[k]['key']}"}
    timings["program_s"] = time.perf_counter() - t2
    scheduled = None
    # A held slope's ends with no common P, at the other parameters'
    # nominal values, have none for any P of a moving slope either; and a
    # halved cell's schedule is a program over nodes x corners that can
    # run for tens of minutes (docs/certify.md): only the first grid's.
    held_failed = k is not None and box[k].get("constant")
    halved = any(p.get("halvings", 0) for p in box)
    # A moving slope's ends with no common P are not taken out by a
    # narrower cell of the constants (search_cells does not halve it).
    moving_failed = k is not None and not held_failed
    if (
        (moving_failed or not (splittable or held_failed))
        and not halved
        and _schedule_worth_trying(cert, error, box)
    ):
        t3 = time.perf_counter()
        # Else the moving slope that moves the map most.
        if k is None:
            k = _slopes_by_move(box, maps)[0]
        scheduled = _scheduled(op, box, maps_at, maps, axes, k, solver, say)
        timings["scheduled_s"] = time.perf_counter() - t3
    result = cert.to_dict()
    result["vertex_parameters"] = [box[j]["name"] for j in axes]
    result.update(error)
    if result["breaking_map"] is not None:
        result["breaking_vertex"] = names[result["breaking_map"]]
    result["proves"] = _with_schedule(result, scheduled)
    result["vertices"] = len(family) + (scheduled or {}).get(
        "scheduled_maps", 0
    )
    result["timings_s"] = timings
    result["box"] = [{k: p[k] for k in _BOX_FIELDS if k in p} for p in box]
    result["_maps"] = {"family": family, "names": names}
    _search_fields(result, maps, (ends_failed, stable))
    result["sampling_period_s"] = maps["period"]
    result["labels"] = maps["labels"]
    return result


def _cell_record(cell: Dict) -> Dict:
    """What certificate.json says of one cell."""
    keys = (
        "status",
        "halved",
        "decay_rate_per_period",
        "decay_rate_with_model_error",
        "P_condition",
        "breaking_vertex",
        "breaking_reason",
        "scheduled",
        "vertices",
        "found_by",
        "solves",
    )
    return {
        "constants": {
            p["key"]: p["range"] for p in cell["box"] if p.get("constant")
        },
        # The time-varying parameters cut into pieces (_more_pieces).
        "pieces": {
            p["key"]: len(p["nodes"]) - 1 for p in cell["box"] if p.get("nodes")
        },
        **{k: cell.get(k) for k in keys},
    }


def _switch_pairs(cell: List[Dict]):
    """(values, values): every two corners of the time-varying parameters
    of ``cell`` (one or several of them switched at once), the constants
    at each corner of the cell."""
    varying = [j for j, p in enumerate(cell) if not p.get("constant")]
    constants = [j for j, p in enumerate(cell) if p.get("constant")]
    corners = list(itertools.product((-1.0, 1.0), repeat=len(varying)))
    for fixed in itertools.product((-1.0, 1.0), repeat=len(constants)):
        for a, b in itertools.combinations(corners, 2):
            ends = []
            for corner in (a, b):
                sign = [0.0] * len(cell)
                for k, si in zip(constants + varying, fixed + corner):
                    sign[k] = si
                ends.append(_values(cell, sign))
            yield ends


def switching_growth(maps_at, cell: List[Dict], labels) -> Optional[Dict]:
    """The largest growth per period found with the time-varying
    parameters of ``cell`` switched periodically between two of their
    corners (:func:`deburr_drake.math.switching.periodic_growth`; the
    pairs of :func:`_switch_pairs`); the search stops at a growth above
    1, which no Lyapunov function of any form can certify. None:
    nothing varies."""
    best, pairs = None, 0
    for low, high in _switch_pairs(cell):
        pair = [maps_at(low), maps_at(high)]
        growth, dwell = periodic_growth(*reduce_family(pair, labels).maps)
        pairs += 1
        if best is None or growth > best["growth_per_period"]:
            best = {
                "growth_per_period": growth,
                "switched": {
                    k: [v, high[k]] for k, v in low.items() if v != high[k]
                },
                "dwell_periods": list(dwell),
                "others": {k: v for k, v in low.items() if v == high[k]},
            }
        if growth > 1.0 + CHECK_MARGIN:
            break
    return best and {**best, "pairs": pairs, "dwells": list(DWELLS)}


def _search(grid, trier) -> Tuple[List[Dict], str]:
    """(results, stop reason): :func:`search_cells`, or what it finished
    when interrupted (SIGINT; SIGTERM as the CLI turns it into one),
    with "interrupted", or when its time ran out
    (:func:`~deburr_drake.analysis.certificate.solve_deadline`), with
    "time_limit"; interrupted before a cell was finished, the
    interruption goes on."""
    results: List[Dict] = []
    try:
        search_cells(grid, trier, results=results)
    except KeyboardInterrupt:
        if not results:
            raise
        return results, "interrupted"
    except OutOfTime:
        return results, "time_limit"
    return results, "search_ended"


def _add_switching(
    result: Dict, results: List[Dict], maps_at, say, rate_bounded=None
) -> None:
    """``result`` (not certified) with ``switching``: the growth found
    under switching in the cell that decides (none when a map there is
    unstable by itself: that decides already); an inconclusive cell in
    which the loop grows is not certified, unless what grows is a switch
    of a slope claimed only at a bounded rate (``rate_bounded``, by name;
    None: the slope the cell's schedule claimed)."""
    cell = results[-1]
    if result["status"] == "certified" or not cell.get("_stable"):
        return
    say("switching: periodic variations of the time-varying parameters")
    start = time.perf_counter()
    record = switching_growth(maps_at, cell["_cell"], cell["labels"])
    if record is None:
        return
    record["text"] = _switching_text(record)
    record["time_s"] = time.perf_counter() - start
    say(record["text"])
    result["switching"] = record
    # A slope claimed only at its rate bound is not refuted by a switch
    # of it, which breaks that bound: that claim stays open.
    if rate_bounded is None:
        rate_bounded = [
            p["name"]
            for p in cell["_cell"]
            if p["key"] == cell.get("scheduled")
        ]
    refutes = not set(rate_bounded) & set(record["switched"])
    if record["growth_per_period"] > 1.0 + CHECK_MARGIN and refutes:
        result["status"] = "not_certified"
        result["breaking_reason"] = record["text"]


def _switching_text(record: Dict) -> str:
    """What the switching search found, in one line."""
    g, (p, q) = record["growth_per_period"], record["dwell_periods"]
    switched = record["switched"]
    at = [
        ", ".join(f"{name} = {ends[i]:.6g}" for name, ends in switched.items())
        for i in (0, 1)
    ]
    held = f"held {p} periods at {at[0]} and {q} at {at[1]}, over and over"
    if g > 1.0 + CHECK_MARGIN:
        return (
            f"the loop grows under a variation within the box: {held}, "
            f"grows by {g:.6f} per period; no Lyapunov function of any form "
            "proves it stable for variations however fast"
        )
    return (
        f"no growth found under periodic switching ({record['pairs']} pairs "
        f"of corners, dwells up to {max(record['dwells'])} periods): the "
        f"largest, {g:.6f} per period ({held}), is a lower bound of the "
        "joint spectral radius; the quadratic function fails, not (as far as "
        "this search sees) the loop"
    )


def _worst_cell(results: List[Dict]) -> Dict:
    """The cell that decides: the last tried when it is not certified (the
    search stops there), else the certified one with the largest decay
    rate with what its corners leave out."""
    if results[-1]["status"] != "certified":
        return results[-1]
    return max(
        _leaves(results),
        key=lambda r: (
            r.get("decay_rate_with_model_error") or r["decay_rate_per_period"]
        ),
    )


def _leaves(results: List[Dict]) -> List[Dict]:
    """The cells that were not halved: the certificate's own."""
    return [r for r in results if "halved" not in r]


def _proves_cells(proves: str, box: List[Dict], results: List[Dict]) -> str:
    """What a certificate over cells of constants proves."""
    constants = [p for p in results[0]["_cell"] if p.get("constant")]
    if not constants:
        return proves
    proves = proves.replace(
        "of the parameters within the box", "of the other parameters"
    )
    held = "".join(
        f" ({p['key']} is held: {p['held']})" for p in box if p.get("held")
    )
    return (
        f"for every constant value of the "
        f"{', '.join(p['name'] for p in constants)} within the box (a "
        f"Lyapunov function for each of the {len(_leaves(results))} cells "
        "of a grid over them, each also covering their variation within "
        f"its cell){held}: {proves}"
    )


def _first_grid(box: List[Dict], cells: Optional[Dict[str, int]]) -> Dict:
    """The first grid's cells by key: ``cells``, or ``CONSTANT_CELLS``
    with one cell along each held slope ({}: no constants)."""
    if cells is not None:
        return cells
    held = {p["key"]: 1 for p in box if p.get("held")}
    return {**held, **CONSTANT_CELLS}


def _constants_text(cell: List[Dict]) -> str:
    return (
        ", ".join(
            f"{p['key']} {p['range'][0]:.4g}-{p['range'][1]:.4g}"
            for p in cell
            if p.get("constant")
        )
        or "the box"
    )


def _tried_text(results: List[Dict]) -> str:
    halved = len(results) - len(_leaves(results))
    certified = sum(r["status"] == "certified" for r in results)
    return f"{len(results)} tried: {certified} certified, {halved} halved"


def _cell_trier(op, maps_at, options, say) -> Callable:
    """:func:`search_cells`'s ``try_cell``: each cell certified
    (:func:`_certify_cell`), its outcome said."""
    tried = itertools.count(1)

    def try_cell(cell, splittable):
        say(f"cell {next(tried)}: {_constants_text(cell)}")
        result = _certify_cell(op, cell, maps_at, options, say, splittable)
        result["_cell"] = cell
        why = result.get("breaking_reason")
        say(f"{result['status']}" + (f": {why}" if why else ""))
        return result

    return try_cell


def certify(
    scenario: Scenario,
    *,
    numerics: str = "shipped",
    after_contact: float = DEFAULT_TIME_AFTER_CONTACT,
    solver: str = "Clarabel",
    vertex_threshold: float = VERTEX_THRESHOLD,
    bisections: int = 0,
    settle_periods: int = SETTLE_PERIODS,
    only: Optional[List[str]] = None,
    cells: Optional[Dict[str, int]] = None,
    progress: Optional[Callable[[str], None]] = None,
    max_time: Optional[float] = None,
) -> Dict:
    """certificate.json's dict (SI units) of ``scenario``'s sampled loop
    over the box (module docstring) at the operating point
    ``after_contact`` s after the first contact, at ``numerics``
    ("shipped" or "refined", analysis.along.at_numerics). ``bisections``
    of the decay rate after the first solve (0: the first P's checked
    rate); each map at its steady state after ``settle_periods`` periods
    (:func:`steady_context`); ``only``: the parameters by key (``BOX_KEYS``,
    ``slope_x1``...; []: the nominal map), the others nominal; ``cells``:
    the first grid's cells by key (``CONSTANT_CELLS`` and one along each
    held slope by default; {}: every parameter time-varying), a
    certificate per cell, a cell not certified halved
    (:func:`search_cells`) until one cannot be. ``max_time``: seconds
    (wall) after which no program or map starts, a running solve stops
    at its solver's time limit, and the cells finished decide
    (:func:`_ended`, :func:`_out_of_time`)."""
    say = progress or (lambda message: None)
    t0 = time.perf_counter()
    deadline = None if max_time is None else time.monotonic() + max_time
    run_scenario = at_numerics(scenario, numerics)
    say(f"operating point: {after_contact:g} s of cutting ({numerics})")
    op = find_operating_point(run_scenario, after_contact=after_contact)
    timings = {"operating_point_s": time.perf_counter() - t0}
    box, left_out = _select_box(_box(op), only)
    maps_at = _Maps(op, box, settle_periods)
    slope_model = maps_at.check_slope_model()
    grid = _cells(box, _first_grid(box, cells))
    # The last: the maps whose inequalities bound the last program of
    # each family layout, where the next one of that layout starts.
    options = (solver, vertex_threshold, bisections, {})
    with solve_deadline(deadline):
        results, stopped = _search(grid, _cell_trier(op, maps_at, options, say))
    if not results:
        return _out_of_time(op, box, grid[0], maps_at, max_time, say)
    result = dict(_worst_cell(results))
    for r in results:
        for k, v in r["timings_s"].items():
            timings[k] = timings.get(k, 0.0) + v
    _ended(result, results, stopped, max_time, maps_at, say)
    maps = result.pop("_maps")
    result.update(
        {
            "scenario": op.scenario.name,
            "numerics": numerics,
            "operating_point": op.summary(),
            "box": [{k: p[k] for k in _BOX_FIELDS if k in p} for p in box],
            "constant_cells": [_cell_record(r) for r in results],
            "cells_tried": _tried_text(results),
            "slope_model": slope_model,
            "contact_estimates": C_HAT,
            "steady_state": {
                "settle_periods": settle_periods,
                "largest_desired_force_change_N": max(maps_at.moved),
                "largest_desired_force_residual_N": max(maps_at.residuals),
            },
            "vertices": len(maps_at.taken),
            "proves": _proves_cells(result["proves"], box, results),
            "does_not_prove": _does_not_prove(left_out),
            "timings_s": {**timings, "total": time.perf_counter() - t0},
            "_maps": {
                "family": maps["family"],
                "names": maps["names"],
                "labels": result.pop("labels"),
            },
        }
    )
    return result


def _ended(result, results, stopped, max_time, maps_at, say) -> None:
    """``result`` (the deciding cell's) with how the search ended: a
    search that did not end is inconclusive; unless interrupted, the
    switching search runs on the deciding cell (:func:`_add_switching`)."""
    if stopped != "search_ended":
        result["status"] = "inconclusive"
        why = (
            "interrupted"
            if stopped == "interrupted"
            else f"the time limit ({max_time:g} s) ran out"
        )
        result["breaking_reason"] = (
            f"{why}: the search did not end ({_tried_text(results)})"
        )
    if stopped != "interrupted":
        _add_switching(result, results, maps_at, say)
    result["stop_reason"] = stopped


def _out_of_time(op, box, cell, maps_at, max_time, say) -> Dict:
    """certificate.json's dict when the time limit ran out before a cell
    was finished: inconclusive, with what the switching search finds on
    the first cell (a growth there proves that no Lyapunov function
    certifies the box for variations however fast; a moving slope's
    rate-bounded schedule stays open)."""
    timed = (
        f"the time limit ({max_time:g} s) ran out before a cell was finished"
    )
    say(timed)
    result = {
        "scenario": op.scenario.name,
        "status": "inconclusive",
        "stop_reason": "time_limit",
        "breaking_reason": timed,
        "operating_point": op.summary(),
        "box": [{k: p[k] for k in _BOX_FIELDS if k in p} for p in box],
    }
    # The cell's schedule was not reached or not finished: every moving
    # slope may still be claimed at its rate bound.
    moving = [
        p["name"] for p in cell if p["field"] is None and not p.get("constant")
    ]
    first = {"_cell": cell, "_stable": True}
    first["labels"] = _labels(maps_at.frozen({}))
    _add_switching(result, [first], maps_at, say, rate_bounded=moving)
    if "switching" in result:
        result["breaking_reason"] = f"{timed}; {result['switching']['text']}"
    return result


def _cell_text(cell: Dict) -> str:
    rate = cell.get("decay_rate_with_model_error")
    where = ", ".join(
        f"{k} {lo:.4g}-{hi:.4g}" for k, (lo, hi) in cell["constants"].items()
    )
    return where + (f": {rate:.6f}" if rate is not None else "")


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
    if result.get("found_by"):
        lines.append(
            f"  P found by {result['found_by']}, searched in "
            f"{result['search_dimension']} of {result['certified_dimension']} "
            "coordinates, checked in all"
        )
    if result.get("scheduled"):
        schedule, rate = result["schedule"], result["slope_rate_bound"]
        lines.append(
            f"  no common quadratic P ({result['common_quadratic_status']}"
            f"): P({result['scheduled']}) on "
            f"{len(result['schedule_nodes'])} nodes, the slope moving at "
            f"most {rate['per_period']:.4g} N s/m per period: "
            f"{schedule['status']} {schedule['reason']}"
        )
    cells = result.get("constant_cells", [])
    if len(cells) > 1 or (cells and cells[0]["constants"]):
        # The halved cells are in certificate.json; the leaves decide.
        lines.append(
            "  a certificate per cell of the constants: "
            f"{result['cells_tried']}; "
            + ", ".join(
                f"{c['status']} ({_cell_text(c)})"
                for c in cells
                if not c.get("halved")
            )
        )
    # With a slope scheduled, the common P's break is what led to it.
    broken = "the common P " if result.get("scheduled") else ""
    if result.get("breaking_vertex"):
        lines.append(f"  {broken}breaks at: {result['breaking_vertex']}")
    if result.get("breaking_reason"):
        lines.append(f"  why: {result['breaking_reason']}")
    switching = result.get("switching")
    if switching and switching["text"] != result.get("breaking_reason"):
        lines.append(f"  switching: {switching['text']}")
    for m in result["separated_modes"]:
        lines.append(
            f"  separated: a mode at {m['eigenvalue'][0]:.6f} in {m['state']}"
        )
    # Not certified, it is the claim that was tried, not a proof.
    proves = "proves" if result["status"] == "certified" else "would prove"
    lines.append(f"  {proves}: {result['proves']}")
    lines.append(f"  does not prove: {result['does_not_prove']}")
    lines.append(f"  wall time {result['timings_s']['total']:.1f} s")
    return "\n".join(lines)


def certified_limit(
    scenario: Scenario,
    overrides: Callable[[float], Dict[str, float]],
    lo: float,
    hi: float,
    *,
    harder_above: bool = True,
    rel_tol: float = 0.02,
    progress: Optional[Callable[[str], None]] = None,
    **certify_options,
) -> Dict:
    """The boundary of the certified values of one parameter, by
    bisection between ``lo`` and ``hi`` to ``rel_tol``: the scenario with
    ``overrides(value)`` (dotted fields) certified (:func:`certify` with
    ``certify_options``) at each trial. ``harder_above``: larger values
    are the harder ones (a gain; False for a cutoff, whose lowest
    certified value is sought); a trial without an operating point (the
    run lost contact) is refused. {certified, refused, trials}: the last
    certified and first refused values (None when an end decides it),
    and every trial's value, status, decay rate and wall time."""
    from deburr_drake.config import ConfigError, set_field

    say = progress or (lambda message: None)
    trials = []

    def certified(value):
        varied = copy.deepcopy(scenario)
        for path, v in overrides(value).items():
            set_field(varied, path, v)
        varied.validate()
        try:
            result = certify(varied, **certify_options)
        except ConfigError as e:
            # No operating point: the run lost contact (or never made it).
            result = {
                "status": "no_operating_point",
                "decay_rate_per_period": None,
                "breaking_reason": str(e),
                "timings_s": {"total": None},
            }
        trials.append(
            {
                "value": value,
                "status": result["status"],
                "decay_rate": result["decay_rate_per_period"],
                "breaking_vertex": result.get("breaking_vertex"),
                "breaking_reason": result.get("breaking_reason"),
                "wall_s": result["timings_s"]["total"],
            }
        )
        say(f"{value:g}: {result['status']}")
        return result["status"] == "certified"

    easy, hard = (lo, hi) if harder_above else (hi, lo)
    if not certified(easy):
        return {"certified": None, "refused": easy, "trials": trials}
    if certified(hard):
        return {"certified": hard, "refused": None, "trials": trials}
    while abs(hard - easy) > rel_tol * max(abs(hard), abs(easy)):
        mid = 0.5 * (easy + hard)
        if certified(mid):
            easy = mid
        else:
            hard = mid
    return {"certified": easy, "refused": hard, "trials": trials}
