"""CuttingProcess: the plant-side truth of the chamfering force (eq. (3)),
the contact threshold c0 of eq. (4), the burrs, and the surface finish the
pass leaves. The controller never reads it."""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np
from pydrake.common import RandomDistribution
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import Diagram, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import (
    Demultiplexer,
    Gain,
    LinearTransformDensity,
    Multiplexer,
    Saturation,
)

from deburr_drake.config import BurrConfig, ConfigError, ProcessConfig
from deburr_drake.control.kinematics import ToolPoint
from deburr_drake.control.layout import VectorLayout
from deburr_drake.math.damping import held_damper_mean
from deburr_drake.math.geometry import Contour, removal_scale
from deburr_drake.math.metrics import arc_distance

__all__ = [
    "CuttingProcess",
    "PROCESS_STATE",
    "cutting_force",
    "force_law_terms",
    "force_law_terms_size",
    "HeldMean",
    "generalized_cutting_force",
    "make_cutting_force_law",
    "burr_profile",
    "FinishBins",
    "material_overlap",
]

PROCESS_STATE = VectorLayout(
    "process_state",
    [
        ("delta", 1),  # m, true chamfer depth at the tool
        ("engagement", 1),  # 0..1, smooth contact onset
        ("g", 1),  # N s/m, g of (3)
        ("f_t", 1),  # N, true ||f_t||
        ("f_threshold", 1),  # N, the c0 part of the normal force
        ("v_t", 1),  # m/s, tangential speed
        ("burr_area", 1),  # m^2, burr cross-section at the tool
        ("arc_position", 1),  # m, of the tool on the edge
    ],
)


def _smoothstep(x):
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


def burr_profile(
    arc, burrs: Sequence[BurrConfig], edge_length: float, closed: bool
):
    """Burr height (m) at arc positions ``arc`` (m): raised-cosine bumps
    h (1 + cos(2 pi (s - c) / L)) / 2 for |s - c| < L / 2, the centre c a
    fraction of the edge length; on a closed edge the distance wraps."""
    arc = np.asarray(arc, float)
    height = np.zeros_like(arc)
    for burr in burrs:
        d = arc_distance(
            arc, burr.center_fraction * edge_length, edge_length, closed
        )
        inside = np.abs(d) < burr.length / 2
        bump = burr.height * 0.5 * (1 + np.cos(2 * np.pi * d / burr.length))
        height = np.maximum(height, np.where(inside, bump, 0.0))
    return height


class FinishBins:
    """Bins of at most ``bin_length`` along an edge of ``length``."""

    def __init__(self, length: float, bin_length: float):
        if not math.isfinite(length):
            raise ConfigError(
                "the surface-finish record needs a finite edge "
                f"length, got {length}"
            )
        self.count = max(1, math.ceil(length / bin_length - 1e-9))
        self.width = length / self.count
        self.centers = (np.arange(self.count) + 0.5) * self.width

    def index(self, s: float) -> int:
        return min(max(int(s // self.width), 0), self.count - 1)

    def near(self, s: float, radius: float, closed: bool) -> np.ndarray:
        """Indices of a superset of the bins whose centres lie within
        ``radius`` of arc position ``s`` (wrapping when ``closed``)."""
        first = math.floor((s - radius) / self.width) - 1
        last = math.ceil((s + radius) / self.width) + 1
        if last - first + 1 >= self.count:
            return np.arange(self.count)
        window = np.arange(first, last + 1)
        if closed:
            return window % self.count
        return window[(window >= 0) & (window < self.count)]


def cutting_force(
    config: ProcessConfig,
    contour: Contour,
    x_p,
    xdot_p,
    *,
    cut_height: float,
    burr_area: float = 0.0,
    overlap: float = 1.0,
    cutter_radius: float | None = None,
):
    """(force on the tool (3, N, world), PROCESS_STATE vector).

    ||f_t|| = g |v_t| + h |v_n| + P'_th (3), g = k_c s (chamfer area + burr
    area), chamfer area = delta * cut_height times the contour's
    ``chamfer_scale`` (1 on a planar edge), s the material removed per
    metre of the cutter centre's travel on the edge's curvature against a
    straight edge (math.geometry.removal_scale, with ``cutter_radius``;
    None: 1, the straight-edge law), v_t the speed along the edge
    (R5: motion along the wall's vertical cuts no chamfer), directed against
    that motion; the direction is sat(v_along / v_s), v_s =
    ``smoothing_speed``, so the force is continuous. Plus the contact
    threshold c0 along -n1. Both ramp in smoothly over the first
    ``threshold_depth`` of depth; ``overlap`` (material_overlap) scales
    both where the cutter runs off an open edge's end."""
    n1, tangent, delta, arc = contour.frame(x_p)
    removal = (
        1.0
        if cutter_radius is None
        else removal_scale(contour.curvature(x_p), delta, cutter_radius)
    )
    chamfer = contour.chamfer_scale(arc, delta, cut_height)
    return _force(
        config,
        n1,
        tangent,
        delta,
        arc,
        np.asarray(xdot_p, float),
        cut_height,
        burr_area,
        overlap,
        removal,
        chamfer,
    )


def _sat(x):
    return min(max(x, -1.0), 1.0)


def material_overlap(
    contour: Contour, arc: float, delta: float, cutter_radius: float
) -> float:
    """Fraction (0..1) of the cutter's contact chord that lies on material:
    1 on a closed edge; on an open edge of length L the chord of half-width
    sqrt(2 r delta) about the tool's arc position, clipped to [0, L]. Off
    the edge's ends it is 0: no cutting force, no threshold force."""
    if contour.closed:
        return 1.0
    c = max(math.sqrt(2.0 * cutter_radius * max(delta, 0.0)), 1e-6)
    covered = min(arc + c, contour.length) - max(arc - c, 0.0)
    return min(max(covered / (2.0 * c), 0.0), 1.0)


def _engagement(
    config: ProcessConfig,
    delta,
    cut_height,
    burr_area,
    overlap=1.0,
    removal=1.0,
    chamfer=1.0,
):
    """(engagement 0..1, g of (3) in N s/m). ``chamfer``: the chamfer
    area over delta * cut_height (the contour's ``chamfer_scale``)."""
    on = _smoothstep(delta / config.threshold_depth) * overlap
    area = max(delta, 0.0) * cut_height
    if chamfer != 1.0:  # a planar edge's force is not rounded differently
        area *= chamfer
    g = config.cutting_coefficient * removal * (area + burr_area)
    return on, g


def _force(
    config: ProcessConfig,
    n1,
    tangent,
    delta,
    arc,
    xdot_p,
    cut_height,
    burr_area,
    overlap=1.0,
    removal=1.0,
    chamfer=1.0,
):
    v_n = float(n1 @ xdot_p)
    v_along = float(tangent @ xdot_p)
    on, g = _engagement(
        config, delta, cut_height, burr_area, overlap, removal, chamfer
    )
    along = on * (
        g * v_along
        + (config.threshold_power_force + config.plunge_coefficient * abs(v_n))
        * _sat(v_along / config.smoothing_speed)
    )
    f_c0 = on * config.contact_threshold_force
    force = -along * tangent - f_c0 * n1
    return force, PROCESS_STATE.pack(
        delta=delta,
        engagement=on,
        g=g,
        f_t=abs(along),
        f_threshold=f_c0,
        v_t=abs(v_along),
        burr_area=burr_area,
        arc_position=arc,
    )


class HeldMean(NamedTuple):
    """What ``process.sample_mean`` needs beside the sample's place on the
    edge: the arm's response along a = J^T n2 to everything but the
    cutting force. y = M^-1 a (nv); ``rest`` = a^T M^-1 tau_rest (m/s^2),
    tau_rest every generalized force but the cutting law's and the
    actuation (gravity, Coriolis, contact, friction, damping) at the
    sample; ``actuation_matrix`` B (nv x nu, the plant's); ``period`` the
    interval the law is held over (s)."""

    y: np.ndarray
    rest: float
    actuation_matrix: np.ndarray
    period: float


def force_law_terms_size(nv: int, nu: int) -> int:
    """Length of :func:`force_law_terms`' vector."""
    return nv * nv + 4 * nv + 9 + nu + 1


def force_law_terms(
    config: ProcessConfig,
    n1,
    tangent,
    delta,
    J,
    xdot_p,
    *,
    cut_height: float,
    burr_area: float = 0.0,
    overlap: float = 1.0,
    removal: float = 1.0,
    chamfer: float = 1.0,
    v=None,
    inertia=None,
    nu: int | None = None,
    held: HeldMean | None = None,
) -> np.ndarray:
    """The terms of :func:`make_cutting_force_law` that make it give
    :func:`cutting_force` (J: the tool point's translational Jacobian, 3 x
    nv; xdot_p: the tool point's velocity, m/s). With u = a.v (v the joint
    velocities: the speed along the edge) and s = sat(u / v_s):

        tau = A [u, s] + b + S (v - v0) + a (k . u_act + k0) (joint space),
        f = B [u, s] + f0 (world),
        a = J^T tangent,  A = [-on g a, -on (P'_th + h |v_n|) a],
        b = -on c0 J^T n1,  B, f0 the same with J = I,

    u_act the plant's actuation (nu; ``nu`` defaults to nv). Returns [a,
    A by column, b - S v0, B by column, f0, S by column, k, k0] (nv^2 +
    4 nv + 9 + nu + 1, :func:`force_law_terms_size`). The place on the
    edge (tangent, n1, g, the engagement) and the plunge speed v_n are the
    sample's; u and s follow the velocities. ``removal``: the edge's
    curvature factor on g, ``chamfer`` its cross-section's factor on the
    chamfer area (:func:`cutting_force`).

    ``held`` (``process.sample_mean``, needs ``v``): A = 0, S = 0, and
    the force along the edge is instead held over the sample at its exact
    mean (deburr_drake.math.damping.held_damper_mean): F(u) = c u + F_0
    about the sample's u0 (c = on g, F_0 = on (P'_th + h |v_n|) sign(u0);
    inside the direction's ramp c = on (g + (P'_th + h |v_n|) / v_s),
    F_0 = 0), with beta = a . y, the rest a . M^-1 tau_rest plus the
    sample's threshold force along a, and the actuation's part k . u_act
    = -k1 y^T B u_act (k0 = -the mean's constant): with the rest and the
    actuation held over the sample, the speed along the edge at its end is
    exactly the damper's, however large g is. The world force f (what the
    force sensor adds back) stays eq. (3) at the velocities.

    Otherwise S (nv x nv) is zero without the sample's joint velocities
    ``v`` (v0). With them it is c a a^T - D, c = -dF/du >= 0 the law's
    damping along the edge at v0 (g, plus P'_th / v_s inside the
    direction's ramp) and D = diag(c |a_i| sqrt(m_i) sum_j |a_j| /
    sqrt(m_j)), m = ``inertia`` (the diagonal of the mass matrix; ones if
    not given: Gershgorin's bound), a diagonal that dominates c a a^T
    (Cauchy-Schwarz, for any positive m; with m = diag(M) it spreads D as
    the arm's inertia is spread, and when a lies along one joint D = c a
    a^T, exact implicit Euler): the term vanishes at the sample's
    velocities (so the force there is exactly eq. (3)) and makes d tau /
    dv = -D, diagonal (``process.implicit_damping``)."""
    J = np.asarray(J, float)
    _, terms = _sample(
        config,
        n1,
        tangent,
        delta,
        0.0,
        J,
        np.asarray(xdot_p, float),
        cut_height,
        burr_area,
        overlap,
        removal,
        chamfer,
        None if v is None else np.asarray(v, float),
        None if inertia is None else np.asarray(inertia, float),
        J.shape[1] if nu is None else nu,
        held,
    )
    return terms


#: PROCESS_STATE's blocks in order (all scalars): _sample fills it by
#: position.
_STATE_BLOCKS = (
    "delta",
    "engagement",
    "g",
    "f_t",
    "f_threshold",
    "v_t",
    "burr_area",
    "arc_position",
)
assert PROCESS_STATE.blocks == _STATE_BLOCKS


def _edge_damper(config: ProcessConfig, on, g, power, u):
    """(c, F_0): eq. (3)'s force along the edge about the speed u (m/s)
    as a damper with an offset, F = c u + F_0 (c = -dF/du >= 0, the law's
    damping there): inside the direction's ramp (|u| < v_s) c = on (g + P
    / v_s) and F_0 = 0, else c = on g and F_0 = on P sign(u), P the
    threshold power force plus the plunge term."""
    if abs(u) < config.smoothing_speed:
        return on * (g + power / config.smoothing_speed), 0.0
    return on * g, math.copysign(on * power, u)


def _sample(
    config: ProcessConfig,
    n1,
    tangent,
    delta,
    arc,
    J,
    xdot_p,
    cut_height,
    burr_area,
    overlap,
    removal,
    chamfer,
    v,
    inertia,
    nu,
    held=None,
):
    """(PROCESS_STATE vector, :func:`force_law_terms`) at one sample: one
    pass over the engagement, speeds and directions (float arrays in)."""
    on, g = _engagement(
        config, delta, cut_height, burr_area, overlap, removal, chamfer
    )
    v_n = float(n1 @ xdot_p)
    v_along = float(tangent @ xdot_p)
    power = config.threshold_power_force + config.plunge_coefficient * abs(v_n)
    threshold = on * config.contact_threshold_force
    along = on * (g * v_along + power * _sat(v_along / config.smoothing_speed))
    state = np.array(
        [delta, on, g, abs(along), threshold, abs(v_along), burr_area, arc]
    )
    a = tangent @ J
    nv = a.size
    terms = np.zeros(force_law_terms_size(nv, nu))
    terms[:nv] = a
    b = terms[3 * nv : 4 * nv]
    np.multiply(n1 @ J, -threshold, out=b)
    k = 4 * nv
    terms[k : k + 3] = (-on * g) * tangent
    terms[k + 3 : k + 6] = (-on * power) * tangent
    terms[k + 6 : k + 9] = (-threshold) * n1
    if held is not None:
        # The law holds the exact mean of F over the sample (A, S zero).
        u = float(a @ v)
        c, offset = _edge_damper(config, on, g, power, u)
        y = held.y
        k0, k1 = held_damper_mean(
            c, offset, u, float(a @ y), held.rest + float(y @ b), held.period
        )
        terms[-nu - 1 : -1] = (-k1 * y) @ held.actuation_matrix
        terms[-1] = -k0
        return state, terms
    np.multiply(a, -on * g, out=terms[nv : 2 * nv])
    np.multiply(a, -on * power, out=terms[2 * nv : 3 * nv])
    if v is not None:
        # S is symmetric: its column-major and row-major layouts agree.
        S = terms[k + 9 : k + 9 + nv * nv].reshape(nv, nv)
        c, _ = _edge_damper(config, on, g, power, float(a @ v))
        abs_a = np.abs(a)
        root_m = np.ones(nv) if inertia is None else np.sqrt(inertia)
        np.multiply.outer(c * a, a, out=S)
        S.flat[:: nv + 1] -= (
            (c * float((abs_a / root_m).sum())) * abs_a * root_m
        )
        b -= S @ v
    return state, terms


def _split_terms(terms, nv: int, nu: int):
    """(a, A, b, B, f0, S, k, k0) of :func:`force_law_terms`, as flat
    arrays."""
    terms = np.asarray(terms, float)
    if terms.size != force_law_terms_size(nv, nu):
        raise ValueError(
            f"force_law_terms: {terms.size} values for nv = "
            f"{nv}, nu = {nu}: expected "
            f"{force_law_terms_size(nv, nu)}"
        )
    return np.split(terms, np.cumsum([nv, 2 * nv, nv, 6, 3, nv * nv, nu]))


def generalized_cutting_force(terms, v, smoothing_speed: float, actuation=None):
    """(tau, f) of :func:`make_cutting_force_law` in numpy (for tests);
    ``actuation`` (nu) defaults to nv zeros."""
    v = np.asarray(v, float)
    nv = v.size
    actuation = (
        np.zeros(nv) if actuation is None else np.asarray(actuation, float)
    )
    a, A, b, B, f0, S, k, k0 = _split_terms(terms, nv, actuation.size)
    u = float(a @ v)
    w = np.array([u, _sat(u / smoothing_speed)])
    held = float(k @ actuation + k0[0])
    return (
        A.reshape(2, nv).T @ w + b + S.reshape(nv, nv).T @ v + held * a,
        B.reshape(2, 3).T @ w + f0,
    )


def make_cutting_force_law(
    nq: int, nv: int, smoothing_speed: float, nu: int | None = None
) -> Diagram:
    """``cutting_force``: the law of :func:`force_law_terms`, from
    ``plant_state`` (nq + nv; the velocities are read), ``actuation`` (nu,
    default nv: what drives the plant's actuation input; only
    ``process.sample_mean``'s terms read it) and the process's held
    ``force_law_terms`` (:func:`force_law_terms_size`), outputs
    ``generalized_force`` (nv, for the plant's applied generalized force)
    and ``applied_force`` (3, N, world: the same force, the true force
    applied on the tool, for the force sensor: a force applied through the
    joints does not pass the sensor's weld).

    The integrator evaluates whatever feeds the plant's applied forces
    about eight times a step to linearize it, so the law is built from
    Drake's C++ primitives rather than a Python LeafSystem or a (much
    slower to evaluate) SymbolicVectorSystem; scripts/bench_floor.py times
    it with the plant alone. LinearTransformDensity is the primitive that
    computes A w + b with A and b on input ports (no random input is
    involved)."""
    nu = nv if nu is None else nu
    builder = DiagramBuilder()

    def add(name, system):
        return builder.AddNamedSystem(name, system)

    def affine(name, n_in, n_out):
        return add(
            name,
            LinearTransformDensity(RandomDistribution.kGaussian, n_in, n_out),
        )

    state = add("state", Demultiplexer([nq, nv]))
    terms = add("terms", Demultiplexer([nv, 2 * nv, nv, 6, 3, nv * nv, nu, 1]))
    speed = affine("speed_along_edge", nv, 1)
    scale = add("per_smoothing_speed", Gain(1.0 / smoothing_speed, 1))
    sign = add("direction", Saturation([-1.0], [1.0]))
    mux = add("speed_and_direction", Multiplexer([1, 1]))
    joint_force = affine("generalized_force", 2, nv)
    applied_force = affine("applied_force", 2, 3)
    # S (v - v0): the diagonal-making term (force_law_terms).
    stabilized = affine("stabilized_generalized_force", nv, nv)
    # k . u_act + k0: minus the held mean force along the edge, applied
    # along a (force_law_terms' held).
    mean = affine("held_mean_force", nu, 1)
    along_edge = affine("held_generalized_force", 1, nv)
    connect = builder.Connect
    connect(state.get_output_port(1), speed.GetInputPort("w_in"))
    connect(terms.get_output_port(0), speed.GetInputPort("A"))
    connect(speed.GetOutputPort("w_out"), scale.get_input_port())
    connect(scale.get_output_port(), sign.get_input_port())
    connect(speed.GetOutputPort("w_out"), mux.get_input_port(0))
    connect(sign.get_output_port(), mux.get_input_port(1))
    for k, law in ((1, joint_force), (3, applied_force)):
        connect(mux.get_output_port(), law.GetInputPort("w_in"))
        connect(terms.get_output_port(k), law.GetInputPort("A"))
        connect(terms.get_output_port(k + 1), law.GetInputPort("b"))
    connect(state.get_output_port(1), stabilized.GetInputPort("w_in"))
    connect(terms.get_output_port(5), stabilized.GetInputPort("A"))
    connect(joint_force.GetOutputPort("w_out"), stabilized.GetInputPort("b"))
    connect(terms.get_output_port(6), mean.GetInputPort("A"))
    connect(terms.get_output_port(7), mean.GetInputPort("b"))
    connect(mean.GetOutputPort("w_out"), along_edge.GetInputPort("w_in"))
    connect(terms.get_output_port(0), along_edge.GetInputPort("A"))
    connect(stabilized.GetOutputPort("w_out"), along_edge.GetInputPort("b"))
    builder.ExportInput(state.get_input_port(), "plant_state")
    builder.ExportInput(mean.GetInputPort("w_in"), "actuation")
    builder.ExportInput(terms.get_input_port(), "force_law_terms")
    builder.ExportOutput(along_edge.GetOutputPort("w_out"), "generalized_force")
    builder.ExportOutput(applied_force.GetOutputPort("w_out"), "applied_force")
    diagram = builder.Build()
    diagram.set_name("cutting_force")
    return diagram


class CuttingProcess(LeafSystem):
    """The tool's place on the edge for the chamfering and threshold
    forces; burrs and the surface finish along the edge.

    .. pydrake_system::

        name: CuttingProcess
        input_ports:
        - plant_state
        - generalized_acceleration (optional)
        - applied_generalized_force (optional)
        - actuation (optional)
        - spindle (optional)
        output_ports:
        - force_law_terms
        - process_state
        - burr_height
        - finish_depth

    - ``plant_state`` (nq + nv): the true robot state.
    - ``spindle`` (1; only with ``spindle_input=True``): 1 the spindle
      turns (cutting as above), 0 it is off (touch probing): no chamfering
      or threshold force, nothing cut or recorded; a burr pushes the tool
      back along -n1 with ``burr_contact_stiffness`` times the depth the
      tool reaches into it.
    - ``generalized_acceleration``, ``applied_generalized_force`` (nv)
      and ``actuation`` (nu; only with ``process.sample_mean``): the
      plant's accelerations, the cutting law's output and what drives the
      plant's actuation, read at each sample (before the sample's
      updates): with the mass matrix they give a^T M^-1 of every other
      force on the arm, for the held mean (:class:`HeldMean`).
    - ``force_law_terms`` (:func:`force_law_terms_size`): the chamfering
      and threshold forces' dependence on the joint velocities (and, with
      ``process.sample_mean``, on the actuation) at the last sample
      (:func:`force_law_terms`), for :func:`make_cutting_force_law`, whose
      outputs go to the plant's ``applied_generalized_force`` input and to
      the force sensor.
    - ``process_state`` (PROCESS_STATE layout): eq. (3) at the last
      sample (for logs; the controller never reads it).
    - ``burr_height`` (bins, m): burr left on the edge.
    - ``finish_depth`` (bins, m): the deepest chamfer cut so far in each bin
      of at most ``finish_bin_length`` of arc (the paper's Fig. 8).
    - Discrete state, updated at initialization and every
      ``sample_period``: the bin under the tool records its depth, the burr
      is removed from the bins the cutter has swept, then the process state
      and the force law's terms are sampled (depth, directions, the burr at
      the cutter's front: arc position + r, the tool runs toward +arc).
      Between samples the force follows the velocities through that law
      and holds the place on the edge and the plunge speed: in 2.5 ms the
      tool moves about 6 um along it. ``tool_point`` (optional) computes the
      tool's kinematics; it may be shared with the observer (same frame,
      same kinematics).
    """

    def __init__(
        self,
        plant: MultibodyPlant,
        tool_frame_name: str,
        contour: Contour,
        config: ProcessConfig,
        *,
        cut_height: float,
        cutter_radius: float,
        tool_point: ToolPoint | None = None,
        spindle_input: bool = False,
    ):
        super().__init__()
        config.validate()
        self.set_name("cutting_process")
        self._tool_point = tool_point or ToolPoint(
            plant, plant.GetFrameByName(tool_frame_name)
        )
        self._nq = plant.num_positions()
        self._nv = plant.num_velocities()
        self._actuation_matrix = plant.MakeActuationMatrix()
        self._nu = self._actuation_matrix.shape[1]
        self._contour = contour
        self._config = config
        self._cut_height = cut_height
        self._cutter_radius = cutter_radius
        self._bins = FinishBins(contour.length, config.finish_bin_length)
        self._thickness = np.array(
            [self._burr_thickness(s) for s in self._bins.centers]
        )
        self._burr_index = self.DeclareDiscreteState(self.initial_burr_height())
        self._finish_index = self.DeclareDiscreteState(self._bins.count)
        self._terms_index = self.DeclareDiscreteState(
            force_law_terms_size(self._nv, self._nu)
        )
        self._state_port = self.DeclareVectorInputPort(
            "plant_state", plant.num_multibody_states()
        )
        self._held_ports = None
        if config.sample_mean:
            self._held_ports = (
                self.DeclareVectorInputPort(
                    "generalized_acceleration", self._nv
                ),
                self.DeclareVectorInputPort(
                    "applied_generalized_force", self._nv
                ),
                self.DeclareVectorInputPort("actuation", self._nu),
            )
        self._spindle_port = (
            self.DeclareVectorInputPort("spindle", 1) if spindle_input else None
        )
        self._state_index = self.DeclareDiscreteState(PROCESS_STATE.size)
        self.DeclareStateOutputPort("force_law_terms", self._terms_index)
        self.DeclareStateOutputPort("process_state", self._state_index)
        self.DeclareStateOutputPort("burr_height", self._burr_index)
        self.DeclareStateOutputPort("finish_depth", self._finish_index)
        self.DeclareInitializationDiscreteUpdateEvent(self._initialize)
        self.DeclarePeriodicDiscreteUpdateEvent(
            config.sample_period, 0.0, self._update
        )

    @property
    def bins(self) -> FinishBins:
        return self._bins

    def force_law(self) -> Diagram:
        """The ``cutting_force`` law for this process's plant and config."""
        return make_cutting_force_law(
            self._nq, self._nv, self._config.smoothing_speed, self._nu
        )

    def initial_burr_height(self) -> np.ndarray:
        """Burr height (m) per bin before the pass."""
        return burr_profile(
            self._bins.centers,
            self._config.burrs,
            self._contour.length,
            self._contour.closed,
        )

    def _leading_edge(self, s):
        """Arc position of the cutter's front (the traversal direction is
        +arc): the burr is cut there."""
        lead = s + self._cutter_radius
        return lead % self._contour.length if self._contour.closed else lead

    def _burr_thickness(self, s):
        # The thickness of the burr whose span covers s (they do not
        # overlap in the shipped scenarios; the thickest wins otherwise).
        thickness = 0.0
        L, closed = self._contour.length, self._contour.closed
        for burr in self._config.burrs:
            d = arc_distance(s, burr.center_fraction * L, L, closed)
            if abs(d) < burr.length / 2:
                thickness = max(thickness, burr.thickness)
        return thickness

    def _spindle_off(self, context) -> bool:
        return (
            self._spindle_port is not None
            and self._spindle_port.Eval(context)[0] < 0.5
        )

    def _update_probing(self, context, discrete_state):
        """The spindle is off: only a burr the tool reaches into acts, as
        a spring along -n1 (what a touch probe on a burr feels)."""
        burr = discrete_state.get_value(self._burr_index)
        x_p, xdot_p, J = self._tool_point.evaluate(
            self._state_port.Eval(context)
        )
        n1, tangent, delta, arc = self._contour.frame(x_p)
        k = self._bins.index(arc)
        push = (
            self._config.burr_contact_stiffness * max(0.0, delta + burr[k])
            if burr[k] > 0.0
            else 0.0
        )
        nv = self._nv
        # no chamfering force: no implicit-damping term (S = 0), no mean
        terms = np.zeros(force_law_terms_size(nv, self._nu))
        terms[:nv] = J.T @ tangent
        terms[3 * nv : 4 * nv] = -push * (J.T @ n1)
        terms[4 * nv + 6 : 4 * nv + 9] = -push * n1
        discrete_state.set_value(self._terms_index, terms)
        discrete_state.set_value(
            self._state_index,
            PROCESS_STATE.pack(
                delta=delta,
                engagement=0.0,
                g=0.0,
                f_t=0.0,
                f_threshold=push,
                v_t=abs(float(tangent @ xdot_p)),
                burr_area=0.0,
                arc_position=arc,
            ),
        )

    def _held_mean(self, context, state, a) -> HeldMean:
        """a^T M^-1 of every generalized force but the cutting law's and
        the actuation, from the plant's accelerations at the sample: a^T
        vdot - y^T (tau_law + B u_act), y = M^-1 a."""
        accelerations, law, actuation = (
            port.Eval(context) for port in self._held_ports
        )
        y = np.linalg.solve(self._tool_point.mass_matrix(state), a)
        rest = float(a @ accelerations) - float(
            y @ (law + self._actuation_matrix @ actuation)
        )
        return HeldMean(
            y, rest, self._actuation_matrix, self._config.sample_period
        )

    def _initialize(self, context, discrete_state):
        # Before initialization the actuation is not yet held (the
        # controller's is NaN), so the plant's accelerations are not
        # defined: eq. (3) at the velocities until the sample at t = 0.
        self._update(context, discrete_state, held_mean=False)

    def _update(self, context, discrete_state, held_mean=True):
        if self._spindle_off(context):
            self._update_probing(context, discrete_state)
            return
        burr = discrete_state.get_mutable_value(self._burr_index)
        state = self._state_port.Eval(context)
        x_p, xdot_p, J = self._tool_point.evaluate(state)
        n1, tangent, delta, arc = self._contour.frame(x_p)
        # math.geometry.removal_scale on the edge's curvature.
        removal = removal_scale(
            self._contour.curvature(x_p), delta, self._cutter_radius
        )
        overlap = material_overlap(
            self._contour, arc, delta, self._cutter_radius
        )
        # the faces' wedge cut (1 on a planar edge: not multiplied in)
        chamfer = self._contour.chamfer_scale(arc, delta, self._cut_height)
        if delta > 0.0 and overlap > 0.0:
            finish = discrete_state.get_mutable_value(self._finish_index)
            k = self._bins.index(arc)
            if delta > finish[k]:
                finish[k] = delta
            # The cutter (diameter 2 r) has swept the burr behind its front.
            r, w = self._cutter_radius, self._bins.width
            closed = self._contour.closed
            near = self._bins.near(arc, r, closed)
            d = arc_distance(
                self._bins.centers[near], arc, self._contour.length, closed
            )
            burr[near[(d >= -r) & (d < r - w)]] = 0.0
        k = self._bins.index(self._leading_edge(arc))
        area = burr[k] * self._thickness[k]
        v = inertia = held = None
        if self._config.implicit_damping:
            v = state[self._nq :]
            inertia = np.diag(self._tool_point.mass_matrix(state))
        elif self._held_ports is not None and held_mean:
            v = state[self._nq :]
            held = self._held_mean(context, state, tangent @ J)
        process_state, terms = _sample(
            self._config,
            n1,
            tangent,
            delta,
            arc,
            J,
            xdot_p,
            self._cut_height,
            area,
            overlap,
            removal,
            chamfer,
            v,
            inertia,
            self._nu,
            held,
        )
        discrete_state.set_value(self._state_index, process_state)
        discrete_state.set_value(self._terms_index, terms)
