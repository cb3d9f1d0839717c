"""A region of attraction of the normal-force axis with the nonlinear
contact, by sums of squares on a reduced polynomial model.

- :func:`normal_axis_model`: the reduced model of
  :mod:`deburr_drake.math.region` at an operating point, every number read
  from the run's plan and Context (the task inertia along n1, K, lambda,
  k_delta, the sensor's filter, the desired normal force, the frozen fuzzy
  surface along n1) and the contact law measured on the cell's own part
  (:func:`deburr_drake.cell.truth.contact_normal_force`).
- :func:`diagram_response`: the full Diagram's response to a change of the
  depth reference (the frozen scenario: adaptation off, noise off), read
  as the reduced state, to validate the model against.
- :func:`sublevel_certificate`: the largest rho, by bisection, such that a
  quadratic V decreases by eps |x|^2 under every region's polynomial map
  on {V <= rho} intersected with the region (the S-procedure per region,
  ``NewSosPolynomial`` multipliers, a free solver of Drake's wheel), then
  checked on sample points of the sublevel set (:func:`check_sublevel`).
- :func:`normal_axis_region`: the three together at an operating point.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import time
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.solvers import (
    ClarabelSolver,
    CsdpSolver,
    MathematicalProgram,
    ScsSolver,
)
from pydrake.symbolic import (
    Expression,
    MonomialBasis,
    Polynomial,
    Variable,
    Variables,
)

from deburr_drake.analysis.operating_point import (
    OperatingPoint,
    frozen_scenario,
    transfer_state,
)
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.cell.truth import contact_normal_force
from deburr_drake.control.laws import TaskTerms
from deburr_drake.control.layout import CHAMFER_STATE, CONTROLLER_DIAGNOSTICS
from deburr_drake.math.region import (
    IN,
    ONSET,
    OUT,
    STATE_NAMES,
    NormalAxisModel,
    fit_contact_law,
    piecewise_quadratic,
)
from deburr_drake.runs.simulation import make_simulator

__all__ = [
    "SOLVERS",
    "Region",
    "SublevelResult",
    "normal_axis_model",
    "reduced_state",
    "diagram_response",
    "sublevel_certificate",
    "check_sublevel",
    "normal_axis_pieces",
    "normal_axis_region",
    "vertex_maps",
    "common_lyapunov",
    "improve_quadratic",
    "STATE_SCALES",
    "CONTACT_NAMES",
]

#: The free semidefinite solvers of Drake's wheel.
SOLVERS = {"Clarabel": ClarabelSolver, "SCS": ScsSolver, "CSDP": CsdpSolver}

#: The reduced state's scales (m, m/s, N, m): the program works on x / scale.
STATE_SCALES = np.array([1e-4, 1e-2, 1.0, 1e-4])


def _eval(system, context, port):
    return system.GetOutputPort(port).Eval(system.GetMyContextFromRoot(context))


def reduced_state(diagram, context) -> np.ndarray:
    """[delta, delta', y, delta_d] of the full Diagram's Context: the
    chamfer state's depth and rate, its (filtered) normal force and the
    controller's depth reference."""
    observer = diagram.GetSubsystemByName("chamfer_observer")
    chamfer = _eval(observer, context, "chamfer_state")
    controller = diagram.GetSubsystemByName("controller")
    ref = controller.depth_reference(controller.GetMyContextFromRoot(context))
    return np.array(
        [
            float(CHAMFER_STATE.get(chamfer, "delta")),
            float(CHAMFER_STATE.get(chamfer, "delta_dot")),
            float(CHAMFER_STATE.get(chamfer, "f_n")),
            float(ref),
        ]
    )


def _joint_terms(diagram, context, n1, robot):
    """(M_n, c, phi, phi's largest slope) along n1 at the tool point:
    M_n = 1 / (n1^T J M^-1 J^T n1) (kg), the inertia a force along n1
    meets, the other directions free; the joint velocities of a tool
    velocity v along n1, v Jbar with Jbar = M^-1 J^T n1 M_n (the
    dynamically consistent inverse); the joints' viscous damping along
    n1, c = Jbar^T D Jbar (N s/m); and the change of their friction
    F_c tanh(qdot / v_s) from the operating point's, along n1."""
    plant = diagram.GetSubsystemByName("plant")
    pc = plant.GetMyContextFromRoot(context)
    frame = plant.GetFrameByName(robot.tool_frame)
    J = plant.CalcJacobianTranslationalVelocity(
        pc,
        JacobianWrtVariable.kV,
        frame,
        np.zeros(3),
        plant.world_frame(),
        plant.world_frame(),
    )
    M = plant.CalcMassMatrix(pc)
    Minv_Jt_n = np.linalg.solve(M, J.T @ n1)
    mass = float(1.0 / (n1 @ J @ Minv_Jt_n))
    jbar = Minv_Jt_n * mass
    damping = np.zeros(plant.num_velocities())
    for i in plant.GetJointIndices():
        joint = plant.get_joint(i)
        if joint.num_velocities() == 1:
            damping[joint.velocity_start()] = joint.default_damping()
    qdot = plant.GetVelocities(pc)
    coulomb = np.asarray(robot.joint_coulomb_friction or [], float)
    v_s = robot.friction_smoothing_speed
    if len(coulomb) == 0:
        coulomb = np.zeros(len(qdot))
    if len(coulomb) != len(qdot):
        coulomb = np.zeros(len(qdot))

    def friction(v):
        return float(
            jbar
            @ (
                coulomb
                * (np.tanh((qdot + v * jbar) / v_s) - np.tanh(qdot / v_s))
            )
        )

    slope = float(jbar @ (coulomb / v_s * jbar))
    return mass, float(jbar @ (damping * jbar)), friction, slope


def _compensator_along(controller, cc, s_op, n1, x_p):
    """u(s_n) = n1 . u_f(s_op + (s_n - n1 . s_op) n1): the law's own
    compensator (rule weights frozen) along n1, and its breakpoints."""
    law = controller.law
    theta = controller.theta(cc)
    n_state = cc.num_continuous_states()
    s_n_op = float(n1 @ s_op)

    def u_along(s_n):
        s = s_op + (s_n - s_n_op) * n1
        terms = TaskTerms(
            x_p=x_p,
            n1=n1,
            f=np.zeros(3),
            e=np.zeros(3),
            edot=np.zeros(3),
            s=s,
            theta=theta,
            fuzzy_weight=None,
            K=np.zeros(3),
        )
        u, _ = law.compensator(terms, np.zeros(n_state))
        return float(n1 @ u)

    config = controller.config
    breaks = []
    for k, (axis, rb) in enumerate(
        zip(config.fuzzy.axes, controller.rule_bases)
    ):
        if abs(n1[axis]) < 1e-9:
            continue
        dk, U = rb.omegak_half_width / rb.upsilon, rb.upsilon
        knots = (np.arange(-U - 1, U + 1) + 0.5 + 0.5 * (rb.m % 2)) * dk
        knots = np.concatenate(
            [
                knots[np.abs(knots) <= U * dk],
                [-U * dk, U * dk],
                [
                    -config.robust_boundary_layer[k],
                    config.robust_boundary_layer[k],
                ],
            ]
        )
        breaks += list(s_n_op + (knots - s_op[axis]) / n1[axis])
    return u_along, breaks


def _contact_fit(
    scenario, depth_op, force_op, force_d, *, degree, top, n_depths
):
    """(fit, calibration): the hydroelastic law measured on the cell's
    part (at the middle of the edge), scaled to the force ``force_op``
    (N, without c0) the run reads at its own depth ``depth_op`` and place
    (the tool's height and tilt there differ from the measurement's),
    fitted on [0, ``top``] and anchored where it gives ``force_d`` (the
    depth the depth law settles at)."""
    depths = np.linspace(0.0, top, n_depths)
    measured = contact_normal_force(scenario, depths)
    calibration = force_op / float(np.interp(depth_op, depths, measured))
    forces = calibration * measured
    anchor = float(np.interp(force_d, forces, depths))
    fit = fit_contact_law(
        depths, forces, degree=degree, anchor=anchor, anchor_force=force_d
    )
    return fit, calibration


def normal_axis_model(
    op: OperatingPoint,
    *,
    degree: int = 2,
    max_depth: Optional[float] = None,
    n_depths: int = 41,
) -> tuple[NormalAxisModel, Dict[str, float]]:
    """The reduced model at ``op`` (:mod:`deburr_drake.math.region`), the
    contact law fitted by a polynomial of ``degree`` on [0, ``max_depth``]
    (default twice the operating depth) from ``n_depths`` measured depths,
    and what it was read from."""
    scenario, diagram, context = op.scenario, op.diagram, op.context
    observer = diagram.GetSubsystemByName("chamfer_observer")
    chamfer = _eval(observer, context, "chamfer_state")
    controller = diagram.GetSubsystemByName("controller")
    cc = controller.GetMyContextFromRoot(context)
    n1 = np.asarray(CHAMFER_STATE.get(chamfer, "n1"), float)
    x_p = np.asarray(CHAMFER_STATE.get(chamfer, "x_p"), float)
    diagnostics = controller.GetOutputPort("diagnostics").Eval(cc)
    s_op = np.asarray(CONTROLLER_DIAGNOSTICS.get(diagnostics, "s"), float)
    f_d = float(controller.GetInputPort("desired_normal_force").Eval(cc)[0])
    K, _ = controller.gains(cc)
    c = scenario.controller
    depth_op = float(CHAMFER_STATE.get(chamfer, "delta"))
    c0 = scenario.process.contact_threshold_force
    fit, calibration = _contact_fit(
        scenario,
        depth_op,
        float(CHAMFER_STATE.get(chamfer, "f_n")) - c0,
        f_d - c0,
        degree=degree,
        top=max_depth or 2.0 * depth_op,
        n_depths=n_depths,
    )
    u_along, breaks = _compensator_along(controller, cc, s_op, n1, x_p)
    compensator = piecewise_quadratic(u_along, breaks, tolerance=1e-7)
    K_n = float(n1 @ (np.asarray(K) * n1))
    s_n = float(n1 @ s_op)
    alpha = 1.0 - np.exp(
        -2
        * np.pi
        * scenario.sensor.cutoff_frequency
        * scenario.sensor.sample_period
    )
    mass, damping, friction, slope = _joint_terms(
        diagram, context, n1, scenario.robot
    )
    model = NormalAxisModel(
        mass=mass,
        damping=damping,
        friction=friction,
        friction_slope=slope,
        sliding_gain=K_n,
        sliding_lambda=float(n1 @ (np.asarray(c.sliding_lambda) * n1)),
        depth_gain=c.depth_gain,
        sensor_alpha=float(alpha),
        period=c.control_period,
        desired_force=f_d,
        disturbance=-(K_n * s_n + compensator(s_n)),
        threshold_force=c0,
        threshold_depth=scenario.process.threshold_depth,
        contact=fit,
        compensator=compensator,
    )
    info = {
        "time_s": op.time,
        "n1": n1.tolist(),
        "task_inertia_kg": model.mass,
        "sliding_gain_n_s_per_m": K_n,
        "sliding_variable_m_per_s": s_n,
        "desired_normal_force_n": f_d,
        "operating_depth_m": depth_op,
        "anchor_depth_m": fit.anchor,
        "contact_calibration": calibration,
        "joint_damping_n_s_per_m": damping,
        "friction_slope_n_s_per_m": slope,
        "compensator_cells": compensator.n_cells,
    }
    return model, info


def diagram_response(
    op: OperatingPoint,
    *,
    reference_step: float,
    duration: float,
    max_step: Optional[float] = None,
) -> np.ndarray:
    """(steps + 1, 4) reduced states of the full Diagram (the frozen
    scenario: adaptation and noise off) from ``op``'s state with the depth
    reference moved by ``reference_step`` (m), one row per control
    period; ``max_step`` (s) refines the integration step."""
    overrides = {} if max_step is None else {"simulation.max_step": max_step}
    scenario = frozen_scenario(op.scenario, **overrides)
    diagram = make_deburring_diagram(op.variant(scenario))
    context = diagram.CreateDefaultContext()
    transfer_state(op.diagram, op.context, diagram, context)
    controller = diagram.GetSubsystemByName("controller")
    cc = controller.GetMyMutableContextFromRoot(context)
    x = cc.get_mutable_continuous_state_vector()
    x.SetAtIndex(0, x.GetAtIndex(0) + reference_step)
    simulator = make_simulator(diagram, scenario)
    simulator.reset_context(context)
    simulator.Initialize()
    period = op.scenario.controller.control_period
    steps = int(round(duration / period))
    t0 = context.get_time()
    out = [reduced_state(diagram, simulator.get_context())]
    for k in range(1, steps + 1):
        simulator.AdvanceTo(t0 + k * period)
        out.append(reduced_state(diagram, simulator.get_context()))
    return np.array(out)


@dataclass
class Region:
    """One piece of a piecewise-polynomial map: ``next_state`` (the map,
    polynomials in ``x`` and the region's ``extras``) where every
    ``linear`` constraint a . x + b >= 0 holds (rows (a, b)), and the
    ``bounds`` (polynomials >= 0: the extras' sectors and limits) hold."""

    name: str
    next_state: List[Expression]
    linear: List[tuple] = field(default_factory=list)
    bounds: List[Expression] = field(default_factory=list)
    extras: List = field(default_factory=list)

    def meets(self, P_inv: np.ndarray, rho: float) -> bool:
        """False when a linear constraint misses the ellipsoid
        x^T P x <= rho altogether (the region is then empty there)."""
        for a, b in self.linear:
            a = np.asarray(a, float)
            if b + np.sqrt(max(rho * a @ P_inv @ a, 0.0)) < 0:
                return False
        return True


@dataclass
class SublevelResult:
    """The largest rho found, the status per region at it, the program's
    size and times; ``status`` is ``proven`` (the program and the
    sample check agree), ``inconclusive`` (the check failed) or
    ``failed`` (no rho > 0 was proven)."""

    rho: float
    status: str
    solver: str
    bisections: List[Dict] = field(default_factory=list)
    regions_checked: int = 0
    gram_sizes: List[int] = field(default_factory=list)
    solve_time_s: float = 0.0
    check: Dict = field(default_factory=dict)
    # The multipliers of (rho - V) at the last rho proven, by region.
    multipliers: Dict = field(default_factory=dict)


def _add_decrease(
    prog, x, P, region, rho, eps, multiplier_degree, rho_multiplier=None
):
    """Adds to ``prog`` the S-procedure of V(f(x)) - V(x) <= -eps |x|^2
    on {V <= rho} and ``region``, V = x^T P x (``P`` numbers or
    ``prog``'s decision variables): -(V(f) - V + eps |x|^2) - lam0
    (rho - V) - sum lam_i g_i is SOS with SOS multipliers lam
    (``rho_multiplier``: lam0 given, which keeps a free P linear).
    Returns (lam0, the Gram matrix's size)."""
    indeterminates = Variables(list(x) + list(region.extras))
    xv = np.array(x)
    fv = np.array(region.next_state)
    V = Polynomial(xv @ P @ xv, indeterminates)
    Vf = Polynomial(fv @ P @ fv, indeterminates)
    decrease = -(Vf - V + Polynomial(eps * (xv @ xv), indeterminates))
    degree = max(Polynomial(fv @ fv, indeterminates).TotalDegree(), 2)
    constraints = [
        Polynomial(float(b) + np.asarray(a, float) @ xv, indeterminates)
        for a, b in region.linear
    ]
    constraints += [Polynomial(g, indeterminates) for g in region.bounds]
    level = Polynomial(rho, indeterminates) - V
    if rho_multiplier is None:
        d = min(max(0, (degree - 2) // 2), multiplier_degree // 2)
        rho_multiplier, _ = prog.NewSosPolynomial(
            MonomialBasis(indeterminates, d)
        )
    decrease -= rho_multiplier * level
    for g in constraints:
        d = max(0, (degree - g.TotalDegree()) // 2)
        d = min(d, multiplier_degree // 2)
        lam, _ = prog.NewSosPolynomial(MonomialBasis(indeterminates, d))
        decrease -= lam * g
    gram = prog.AddSosConstraint(decrease)[0]
    return rho_multiplier, gram.shape[0]


def _region_feasible(x, P, eps, rho, region, solver, multiplier_degree):
    """Whether the S-procedure proves V(f(x)) - V(x) <= -eps |x|^2 on
    {V <= rho} and ``region``; (ok, solver status, lam0's value, Gram
    size, time)."""
    prog = MathematicalProgram()
    prog.AddIndeterminates(list(x) + list(region.extras))
    lam0, size = _add_decrease(prog, x, P, region, rho, eps, multiplier_degree)
    start = time.perf_counter()
    result = SOLVERS[solver]().Solve(prog)
    elapsed = time.perf_counter() - start
    status = result.get_solution_result().name
    ok = result.is_success()
    value = result.GetSolution(lam0) if ok else None
    return ok, status, value, size, elapsed


def improve_quadratic(
    x,
    P: np.ndarray,
    rho: float,
    regions: Sequence[Region],
    multipliers: Dict[str, Polynomial],
    *,
    eps: float,
    shape: np.ndarray,
    solver: str = "Clarabel",
    multiplier_degree: int = 4,
):
    """A new P, the multipliers of (rho - V) held at ``multipliers`` (by
    region name; these regions only) so the program is linear in P: the
    S-procedure of every region with P free, P >= eps I, and P / rho <=
    t ``shape`` with t minimised (the set {V <= rho} holds the largest
    {x^T shape x <= 1 / t}). None when the program fails. The new P is
    only a proposal: :func:`sublevel_certificate` proves it again."""
    n = len(x)
    prog = MathematicalProgram()
    extras = {v.get_id(): v for r in regions for v in r.extras}
    prog.AddIndeterminates(list(x) + list(extras.values()))
    Pv = prog.NewSymmetricContinuousVariables(n, "P")
    t = prog.NewContinuousVariables(1, "t")[0]
    prog.AddPositiveSemidefiniteConstraint(Pv - eps * np.eye(n))
    prog.AddPositiveSemidefiniteConstraint(t * shape - Pv * (1.0 / rho))
    for region in regions:
        if region.name in multipliers:
            _add_decrease(
                prog,
                x,
                Pv,
                region,
                rho,
                eps,
                multiplier_degree,
                rho_multiplier=multipliers[region.name],
            )
    prog.AddLinearCost(t)
    result = SOLVERS[solver]().Solve(prog)
    if not result.is_success():
        return None
    value = np.reshape(result.GetSolution(Pv), (n, n))
    return 0.5 * (value + value.T)


def sublevel_certificate(
    x,
    P: np.ndarray,
    regions: Sequence[Region],
    *,
    eps: float,
    rho_max: float,
    solver: str = "Clarabel",
    bisections: int = 12,
    multiplier_degree: int = 4,
    check: Optional[Callable[[float], Dict]] = None,
) -> SublevelResult:
    """The largest rho in (0, rho_max] (bisection, ``bisections`` steps)
    for which every region that meets {x^T P x <= rho} is proven by the
    S-procedure (:func:`_region_feasible`); then ``check(rho)`` (a dict
    with ``ok``), which makes the result ``inconclusive`` when it fails."""
    P_inv = np.linalg.inv(P)
    out = SublevelResult(rho=0.0, status="failed", solver=solver)

    def proven(rho):
        entry = {"rho": rho, "regions": 0, "failed_region": None}
        multipliers = {}
        for region in regions:
            if not region.meets(P_inv, rho):
                continue
            ok, status, lam0, size, elapsed = _region_feasible(
                x, P, eps, rho, region, solver, multiplier_degree
            )
            multipliers[region.name] = lam0
            entry["regions"] += 1
            out.gram_sizes.append(size)
            out.solve_time_s += elapsed
            if not ok:
                entry["failed_region"] = region.name
                entry["solver_status"] = status
                break
        entry["proven"] = entry["failed_region"] is None
        out.bisections.append(entry)
        if entry["proven"]:
            out.multipliers = multipliers
        return entry["proven"], entry["regions"]

    ok, n = proven(rho_max)
    if ok:
        lo, hi = rho_max, rho_max
        out.regions_checked = n
    else:
        lo, hi = 0.0, rho_max
        for _ in range(bisections):
            mid = 0.5 * (lo + hi)
            ok, n = proven(mid)
            if ok:
                lo, out.regions_checked = mid, n
            else:
                hi = mid
    out.rho = lo
    if lo <= 0.0:
        return out
    out.check = check(lo) if check is not None else {"ok": True}
    out.status = "proven" if out.check["ok"] else "inconclusive"
    return out


def check_sublevel(
    step: Callable,
    P: np.ndarray,
    rho: float,
    eps: float,
    *,
    samples: int = 2000,
    seed: int = 0,
    boundary_fraction: float = 0.5,
) -> Dict:
    """Samples {x^T P x <= rho} (uniform inside, and on its boundary) and
    checks V(x+) - V(x) <= -eps |x|^2 at each for every x+ that
    ``step(x)`` returns (a list: one per value of the model's uncertain
    terms). ``ok`` False, with the worst point, on any failure."""
    rng = np.random.default_rng(seed)
    n = P.shape[0]
    L = np.linalg.cholesky(np.linalg.inv(P))
    directions = rng.normal(size=(samples, n))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    radii = rng.uniform(size=samples) ** (1.0 / n)
    radii[: int(boundary_fraction * samples)] = 1.0
    worst, worst_x, failures = -np.inf, None, 0
    for d, r in zip(directions, radii):
        x = np.sqrt(rho) * r * (L @ d)
        V = x @ P @ x
        for x_next in step(x):
            margin = x_next @ P @ x_next - V + eps * (x @ x)
            if margin > worst:
                worst, worst_x = margin, x
            if margin > 1e-9 * max(V, 1e-12):
                failures += 1
    return {
        "ok": failures == 0,
        "samples": samples,
        "failures": failures,
        "worst_margin": float(worst),
        "worst_point": None if worst_x is None else worst_x.tolist(),
    }


def normal_axis_pieces(model: NormalAxisModel, x_vars):
    """(regions, x*, rho cap) of ``model`` in the scaled deviation
    xi = (x - x*) / :data:`STATE_SCALES` (``x_vars`` its four symbolic
    variables): one :class:`Region` per fuzzy cell and contact region (out
    of contact, c0's onset, in contact up to the fit's largest depth),
    each with the friction's sector phi (c_f v - phi) >= 0 and, in
    contact, the fit's residual bounds. The cap keeps {V <= rho} within
    the fit's depths: rho <= ((max_depth - delta*) / scale)^2 / (P^-1)_00
    is applied by the caller, who knows P."""
    x_star = model.equilibrium()
    scale = STATE_SCALES
    xi = np.array(x_vars, dtype=object)
    x_phys = x_star + scale * xi
    w, phi = Variable("w"), Variable("phi")
    fit = model.contact
    s_star = float(model.sliding(x_star))
    a_s = np.array(
        [
            float(model.sliding(x_star + scale * e)) - s_star
            for e in np.eye(len(scale))
        ]
    )
    e0 = np.eye(len(scale))[0]
    d_star, d_c, d_max = x_star[0], model.threshold_depth, fit.max_depth
    sc0 = scale[0]
    contact_rows = {
        OUT: [(-e0, -d_star / sc0)],
        ONSET: [(e0, d_star / sc0), (-e0, (d_c - d_star) / sc0)],
        IN: [(e0, (d_star - d_c) / sc0), (-e0, (d_max - d_star) / sc0)],
    }
    friction = phi * (model.friction_slope * scale[1] * xi[1] - phi)
    residual = fit.max_residual**2 - w * w
    sector = fit.sector**2 * (sc0 * xi[0]) ** 2 - w * w
    bounds = {OUT: [friction], ONSET: [friction, residual]}
    bounds[IN] = [friction, residual, sector]
    regions = []
    edges = model.compensator.edges
    for cell in range(model.compensator.n_cells):
        lo, hi = edges[cell], edges[cell + 1]
        rows = []
        if np.isfinite(lo):
            rows.append((a_s / 1e-2, (s_star - lo) / 1e-2))
        if np.isfinite(hi):
            rows.append((-a_s / 1e-2, (hi - s_star) / 1e-2))
        for contact in (IN, ONSET, OUT):
            nxt = model.step_in_region(
                x_phys, w if contact != OUT else 0.0, cell, contact, phi
            )
            regions.append(
                Region(
                    name=f"cell {cell} [{lo:.4g}, {hi:.4g}] m/s, "
                    + CONTACT_NAMES[contact],
                    next_state=[
                        ((nxt[i] - x_star[i]) / scale[i]).Expand()
                        for i in range(len(scale))
                    ],
                    linear=rows + contact_rows[contact],
                    bounds=bounds[contact],
                    extras=[phi] if contact == OUT else [phi, w],
                )
            )
    # The operating point's own region first: it is the one that matters.
    home = model.region_of(x_star)
    regions.sort(
        key=lambda r: (
            0
            if r.name.startswith(f"cell {home[0]} ")
            and r.name.endswith(CONTACT_NAMES[home[1]])
            else 1
        )
    )
    return regions, x_star


#: The contact regions' names.
CONTACT_NAMES = {OUT: "out of contact", ONSET: "c0 onset", IN: "in contact"}


def _scaled_step(model: NormalAxisModel, x_star):
    """xi -> the list of xi+ over the uncertain terms' extremes: the fit's
    residual at -bound, 0, +bound (in contact), the friction's change at
    0, c_f v and its true value."""
    scale = STATE_SCALES
    fit = model.contact

    def step(xi):
        x = x_star + scale * xi
        cell, contact = model.region_of(x)
        v = float(x[1])
        if contact == IN:
            bound = min(fit.sector * abs(x[0] - fit.anchor), fit.max_residual)
        elif contact == ONSET:
            bound = fit.max_residual
        else:
            bound = 0.0
        out = []
        for w in (-bound, 0.0, bound):
            for phi in (0.0, model.friction_slope * v, model.friction(v)):
                nxt = model.step_in_region(x, w, cell, contact, phi)
                out.append((nxt - x_star) / scale)
        return out

    return step


def vertex_maps(model: NormalAxisModel, x_star, *, h=1e-4):
    """The scaled map's Jacobians at x* (central differences) at the
    vertices of its uncertain terms' sectors: the friction's slope 0 and
    c_f, the fit's residual slope -sector, 0 and +sector."""
    scale = STATE_SCALES
    n = len(scale)
    cell, contact = model.region_of(x_star)
    maps = []
    for slope in (0.0, model.friction_slope):
        for sign in (-1.0, 0.0, 1.0):

            def f(xi):
                x = x_star + scale * xi
                w = sign * model.contact.sector * (x[0] - x_star[0])
                nxt = model.step_in_region(x, w, cell, contact, slope * x[1])
                return (nxt - x_star) / scale

            maps.append(
                np.column_stack(
                    [(f(h * e) - f(-h * e)) / (2 * h) for e in np.eye(n)]
                )
            )
    return maps


def common_lyapunov(maps, *, solver: str = "Clarabel") -> np.ndarray:
    """P with P >= I and A^T P A - P <= -I at every map, its largest
    eigenvalue minimised (a small semidefinite program); ValueError when
    there is none."""
    n = maps[0].shape[0]
    prog = MathematicalProgram()
    P = prog.NewSymmetricContinuousVariables(n, "P")
    kappa = prog.NewContinuousVariables(1, "kappa")[0]
    prog.AddPositiveSemidefiniteConstraint(P - np.eye(n))
    prog.AddPositiveSemidefiniteConstraint(kappa * np.eye(n) - P)
    for A in maps:
        prog.AddPositiveSemidefiniteConstraint(P - A.T @ P @ A - np.eye(n))
    prog.AddLinearCost(kappa)
    result = SOLVERS[solver]().Solve(prog)
    if not result.is_success():
        raise ValueError(
            "common_lyapunov: no common quadratic V for the linearised "
            f"maps ({result.get_solution_result().name})"
        )
    value = result.GetSolution(P)
    return 0.5 * (value + value.T)


def normal_axis_region(
    op: OperatingPoint,
    *,
    eps: float = 0.01,
    bisections: int = 8,
    solver: str = "Clarabel",
    degree: int = 2,
    check_samples: int = 2000,
    validation_steps: Sequence[float] = (),
    validation_duration: float = 1.0,
    validation_max_step: Optional[float] = None,
    iterations: int = 3,
) -> Dict:
    """The region of attraction of the normal-force axis at ``op``: the
    reduced model, a common quadratic V of its linearised sector vertices,
    the largest proven sublevel set (:func:`_iterate`), what it means in
    physical units, and (``validation_steps``, m) the full Diagram against
    the reduced model after each depth-reference step. A plain dict
    (JSON-ready)."""
    start = time.perf_counter()
    model, info = normal_axis_model(op, degree=degree)
    x = [Variable(name) for name in STATE_NAMES]
    regions, x_star = normal_axis_pieces(model, x)
    P = common_lyapunov(vertex_maps(model, x_star), solver=solver)
    P, result, history, solve_time = _iterate(
        x,
        P,
        regions,
        depth_room=(model.contact.max_depth - x_star[0]) / STATE_SCALES[0],
        eps=eps,
        solver=solver,
        bisections=bisections,
        iterations=iterations,
    )
    if result.rho > 0.0:
        result.check = check_sublevel(
            _scaled_step(model, x_star),
            P,
            result.rho,
            eps,
            samples=check_samples,
        )
        result.status = "proven" if result.check["ok"] else "inconclusive"
    out = _summary(model, info, x_star, P, result)
    out.update(
        eps=eps,
        regions=len(regions),
        # The radius of the largest ball (scaled units) in each proven
        # set of the V-s iteration, the first for the linearised V.
        ball_radius_history=history,
        solve_time_all_iterations_s=solve_time,
    )
    out["validation"] = [
        _validate(
            op,
            model,
            d,
            validation_duration,
            out["single_state_error"]["depth_reference"],
            validation_max_step,
        )
        for d in validation_steps
    ]
    out["time_s"] = time.perf_counter() - start
    return out


def _iterate(x, P, regions, *, depth_room, eps, solver, bisections, iterations):
    """The V-s iteration: the largest rho for P, then a P that holds a
    larger ball in {V <= rho} with the multipliers of (rho - V) held
    (:func:`improve_quadratic`), and again; a P is kept only when its own
    rho, proven anew, holds a larger ball. rho is capped so that
    {V <= rho} stays within the fit's depths (``depth_room``, scaled).
    Returns (P, its SublevelResult, the balls' radii, all solves' time)."""

    def proven_set(P):
        return sublevel_certificate(
            x,
            P,
            regions,
            eps=eps,
            rho_max=depth_room**2 / np.linalg.inv(P)[0, 0],
            solver=solver,
            bisections=bisections,
        )

    result = proven_set(P)
    history, solve_time = [_ball(P, result.rho)], result.solve_time_s
    for _ in range(iterations):
        if result.rho <= 0.0:
            break
        proposal = improve_quadratic(
            x,
            P,
            result.rho,
            regions,
            result.multipliers,
            eps=eps,
            shape=np.eye(len(x)),
            solver=solver,
        )
        if proposal is None:
            break
        again = proven_set(proposal)
        solve_time += again.solve_time_s
        history.append(_ball(proposal, again.rho))
        if history[-1] <= max(history[:-1]):
            break
        P, result = proposal, again
    return P, result, history, solve_time


def _summary(model, info, x_star, P, result) -> Dict:
    """The proven set in physical units: its half-widths along each state
    (the others free) and the largest error of one state alone (the others
    at x*), with the program's record and the model's numbers."""
    rho, scale = result.rho, STATE_SCALES
    extent = np.sqrt(rho * np.diag(np.linalg.inv(P))) * scale
    alone = np.sqrt(rho / np.diag(P)) * scale
    return {
        "status": result.status,
        "rho": rho,
        "solver": result.solver,
        "bisections": result.bisections,
        "regions_meeting_the_set": result.regions_checked,
        "largest_gram": max(result.gram_sizes, default=0),
        "solve_time_s": result.solve_time_s,
        "check": result.check,
        "P_scaled": P.tolist(),
        "state_scales": dict(zip(STATE_NAMES, scale.tolist())),
        "equilibrium": dict(zip(STATE_NAMES, x_star.tolist())),
        "extent": dict(zip(STATE_NAMES, extent.tolist())),
        "single_state_error": dict(zip(STATE_NAMES, alone.tolist())),
        "contact_loss_inside": bool(x_star[0] - extent[0] < 0.0),
        "model": {
            **info,
            "contact_fit_coefficients": model.contact.coefficients.tolist(),
            "contact_fit_sector_n_per_m": model.contact.sector,
            "contact_fit_max_residual_n": model.contact.max_residual,
            "contact_fit_max_depth_m": model.contact.max_depth,
            "sensor_alpha": model.sensor_alpha,
            "disturbance_n": model.disturbance,
        },
    }


def _ball(P, rho) -> float:
    """The radius of the largest ball in {x^T P x <= rho}."""
    return float(np.sqrt(rho / np.linalg.eigvalsh(P)[-1]))


def _validate(
    op, model, reference_step, duration, proven_step, max_step
) -> Dict:
    """The full Diagram against the reduced model after a depth-reference
    step: the largest depth and force differences, the least depth, and
    whether each is back within 5 % of the step (or 5 um) of its start at
    the end."""
    full = diagram_response(
        op, reference_step=reference_step, duration=duration, max_step=max_step
    )
    reduced = model.simulate(full[0], len(full) - 1)
    settled = max(0.05 * abs(reference_step), 5e-6)
    base = diagram_response(
        op, reference_step=0.0, duration=duration, max_step=max_step
    )
    return {
        "reference_step_m": reference_step,
        "inside_proven_region": bool(abs(reference_step) <= proven_step),
        "duration_s": duration,
        "depth_difference_max_m": float(
            np.max(np.abs(full[:, 0] - reduced[:, 0]))
        ),
        "force_difference_max_n": float(
            np.max(np.abs(full[:, 2] - reduced[:, 2]))
        ),
        "least_depth_full_m": float(full[:, 0].min()),
        "least_depth_reduced_m": float(reduced[:, 0].min()),
        "contact_lost_full": bool(full[:, 0].min() < 0.0),
        "contact_lost_reduced": bool(reduced[:, 0].min() < 0.0),
        "recovered_full": bool(abs(full[-1, 0] - base[-1, 0]) < settled),
        "recovered_reduced": bool(
            abs(reduced[-1, 0] - model.equilibrium()[0]) < settled
        ),
    }
