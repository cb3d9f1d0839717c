"""A stability certificate for a family of one-period maps A_i: a common
quadratic Lyapunov function V(x) = x^T P x with V(A_i x) <= gamma^2 V(x)
for every i, found by a semidefinite program in Drake's
``MathematicalProgram`` and checked in numpy after the solve.

Such a P proves the switched (and, by convexity, any time-varying convex
combination of the A_i) linear system x+ = A(k) x stable with decay rate
gamma per period, whatever the order in which the maps follow each other.

Before the program, the family is reduced by transformations that are
exact:

- coordinates every map overwrites (a zero row in every A_i: a held
  value set anew at each sample) are zero after one period, so the
  dynamics from then on live on the others;
- a diagonal similarity (``scipy.linalg.matrix_balance`` of the nominal
  map) puts the states' units on one scale;
- after one period the state lies in the span of the maps' images (a
  sampled loop's map has low rank: the modes faster than a period are
  gone within it), so the maps are restricted to that span (its
  orthonormal basis from the SVD of [A_1 ... A_N], singular values below
  ``IMAGE_TOLERANCE`` of the largest, round-off, left out and recorded);
- modes that no parameter moves (eigenvalues within ``neutral_tolerance``
  of 1 of the nominal map, spanning a subspace every map leaves
  invariant with the same eigenvalues there: a rigid-body shift, an
  integrator) are separated by an orthogonal similarity and named; the
  program certifies the maps on the quotient, the rest of the state.

The search for P runs on fewer coordinates still: the maps' common row
space (their stacked rows' SVD, singular values above
``SEARCH_TOLERANCE`` of the largest). A sampled loop's map reads the state
through a few quantities (the paper arm's family of 30 maps: 17 of the
32 image coordinates), and w = V^T x follows w+ = V^T A_i V w up to the
left-out singular values; the semidefinite program's cost grows with the
sixth power of the dimension. The P found there is lifted back, P = V
P_w V^T + mu (I - V V^T) (mu the best of a grid), and checked on the
maps of the full reduced family: the search coordinates are a way to
find P, never what is proved.

Candidates, the first that passes the check wins: the discrete Lyapunov
equation of the nominal map (one linear solve: enough when the other
maps stay near it in its norm), then the semidefinite program.

The solver's "solved" is not taken as a proof: the P it returns is
checked (P positive definite with a bounded condition number; the largest
P-norm of the maps below 1 by ``margin``); a P that fails is
``inconclusive``.
"""

from __future__ import annotations

import contextlib
import contextvars
from dataclasses import dataclass, field
import time
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np
from pydrake.solvers import (
    ClarabelSolver,
    CsdpSolver,
    MathematicalProgram,
    ScsSolver,
    SolverOptions,
)
import scipy.linalg

__all__ = [
    "SeparatedMode",
    "ReducedFamily",
    "LmiSolution",
    "Certificate",
    "reduce_family",
    "solve_common_lyapunov",
    "solve_deadline",
    "check_deadline",
    "OutOfTime",
    "check_lyapunov",
    "certify_family",
    "p_norm",
    "left_out_norm",
    "search_basis",
    "lift",
    "nominal_lyapunov",
    "RateBoundedCertificate",
    "certify_rate_bounded",
    "check_rate_bounded",
    "mixed_norm",
    "rate_vertices",
    "reach",
    "schedule_rate",
    "solve_rate_bounded",
    "CellsCertificate",
    "certify_cells",
]

#: A P whose condition number is above this is not accepted as a proof:
#: x^T P x would not bound the state in any useful sense, and the check's
#: own round-off grows with it.
MAX_CONDITION = 1e10
#: Singular values of [A_1 ... A_N] below this fraction of the largest are
#: round-off: their directions are left out of the maps' common image.
IMAGE_TOLERANCE = 1e-12
#: The largest P-norm of a map must stay below 1 - CHECK_MARGIN.
CHECK_MARGIN = 1e-6
#: Singular values of the stacked maps [A_1; ...; A_N] below this fraction
#: of the largest are left out of the coordinates P is searched in (the
#: paper arm's: 1e-3 above the gap, 2e-11 below it, the finite
#: differences' round-off); the check after the lift sees them.
SEARCH_TOLERANCE = 1e-8
#: How P's lift weighs the coordinates the search left out (relative to
#: P_w's smallest eigenvalue), tried from the largest (see :func:`lift`).
LIFT_WEIGHTS = np.logspace(2, -8, 21)

#: Constraint generation: how many of the most broken inequalities of a
#: group (a family; a node of a schedule) each round adds to the program.
ACTIVE_ADD = 3
#: How each candidate P is named in the certificate.
FOUND_BY_NOMINAL = "the discrete Lyapunov equation of the nominal map"
FOUND_BY_PROGRAM = "the semidefinite program"
#: The solution result of a program shown to have no solution; any other
#: failure is the solver's, not a proof.
INFEASIBLE = "kInfeasibleConstraints"

_SOLVERS = {
    "Clarabel": ClarabelSolver,
    "CSDP": CsdpSolver,
    "SCS": ScsSolver,
}


#: Each solver's own time limit (seconds), set to what is left before
#: the deadline of :func:`solve_deadline`; CSDP has none, so its solves
#: are only kept from starting after it.
_TIME_LIMIT_OPTIONS = {"Clarabel": "time_limit", "SCS": "time_limit_secs"}

#: The time.monotonic() by which every program must have ended (None: no
#: limit): a context value, so that the programs deep in a search need
#: not carry it.
_DEADLINE: contextvars.ContextVar[Optional[float]] = contextvars.ContextVar(
    "certificate_deadline", default=None
)


class OutOfTime(Exception):
    """A program or a map was about to start after the deadline of
    :func:`solve_deadline`."""


@contextlib.contextmanager
def solve_deadline(deadline: Optional[float]):
    """Within the block, every program is given what is left before
    ``deadline`` (time.monotonic(); None: no limit) as its solver's time
    limit, and one that would start after it raises :class:`OutOfTime`
    (:func:`check_deadline`)."""
    token = _DEADLINE.set(deadline)
    try:
        yield
    finally:
        _DEADLINE.reset(token)


def check_deadline() -> Optional[float]:
    """The seconds left before the deadline (None: no limit); raises
    :class:`OutOfTime` when none are."""
    deadline = _DEADLINE.get()
    if deadline is None:
        return None
    left = deadline - time.monotonic()
    if left <= 0.0:
        raise OutOfTime("the time limit ran out")
    return left


def _solve(prog: MathematicalProgram, solver: str):
    """``prog`` solved by ``solver``, stopped at the deadline: a solver
    stopped by its time limit gives neither a P nor a proof that none
    exists (its status is not kInfeasibleConstraints: inconclusive)."""
    left = check_deadline()
    options = SolverOptions()
    if left is not None and solver in _TIME_LIMIT_OPTIONS:
        options.SetOption(
            _SOLVERS[solver].id(), _TIME_LIMIT_OPTIONS[solver], left
        )
    return _SOLVERS[solver]().Solve(prog, None, options)


@dataclass
class SeparatedMode:
    """A mode no map moves: its eigenvalue and the state it lives in most
    (the largest component of its eigenvector, by label)."""

    eigenvalue: complex
    label: str

    def to_dict(self) -> Dict:
        return {
            "eigenvalue": [
                float(self.eigenvalue.real),
                float(self.eigenvalue.imag),
            ],
            "state": self.label,
        }


@dataclass
class ReducedFamily:
    """The maps on the coordinates the program certifies: ``maps`` (m x
    m), ``kept`` the labels of the original coordinates that survive the
    overwritten-state reduction, ``separated`` the neutral modes taken
    out, ``separation_error`` how far (relative) the other maps are from
    leaving the neutral subspace invariant."""

    maps: List[np.ndarray]
    kept: List[str]
    overwritten: List[str]
    separated: List[SeparatedMode] = field(default_factory=list)
    separation_error: float = 0.0
    image_rank: int = 0
    neglected_singular_value: float = 0.0  # relative to the largest
    # The reductions: kept coordinates, their scale, the basis (columns)
    # of the certified coordinates in the scaled ones.
    keep: np.ndarray = None
    scale: np.ndarray = None
    basis: np.ndarray = None

    def transform(self, M: np.ndarray) -> np.ndarray:
        """A matrix on the original state, in the certified coordinates
        (as the family's maps were taken there)."""
        M = np.asarray(M, float)[np.ix_(self.keep, self.keep)]
        M = M * (1.0 / self.scale)[:, None] * self.scale[None, :]
        return self.basis.T @ M @ self.basis


def _overwritten(maps: Sequence[np.ndarray]) -> np.ndarray:
    """Coordinates with a zero row in every map."""
    rows = np.zeros(maps[0].shape[0], dtype=bool)
    for A in maps:
        rows |= np.any(A != 0.0, axis=1)
    return ~rows


def reduce_family(
    maps: Sequence[np.ndarray],
    labels: Sequence[str],
    *,
    neutral_tolerance: float = 1e-6,
    invariance_tolerance: float = 1e-6,
) -> ReducedFamily:
    """The exact reductions of the module docstring; ``maps[0]`` is the
    nominal map. Neutral modes that are not shared (another map moves them
    or does not leave their subspace invariant within
    ``invariance_tolerance``, relative) stay in the program, which then
    cannot certify the family."""
    maps = [np.asarray(A, dtype=float) for A in maps]
    dropped = _overwritten(maps)
    keep = np.flatnonzero(~dropped)
    maps = [A[np.ix_(keep, keep)] for A in maps]
    kept = [labels[i] for i in keep]
    overwritten = [labels[i] for i in np.flatnonzero(dropped)]
    # One scale for every state's units: a diagonal similarity.
    _, (scale, _) = scipy.linalg.matrix_balance(
        maps[0], permute=False, separate=True
    )
    maps = [A * (1.0 / scale)[:, None] * scale[None, :] for A in maps]
    # The maps' common image: where the state is after one period.
    U, sigma, _ = np.linalg.svd(np.hstack(maps))
    rank = int(np.sum(sigma > IMAGE_TOLERANCE * sigma[0]))
    U = U[:, :rank]
    maps = [U.T @ A @ U for A in maps]
    reduced = ReducedFamily(
        maps,
        kept,
        overwritten,
        image_rank=rank,
        keep=keep,
        scale=scale,
        basis=U,
    )
    if rank < sigma.size:
        reduced.neglected_singular_value = float(sigma[rank] / sigma[0])
    # Neutral modes of the nominal map, first in an ordered real Schur form.
    T, Z, n_neutral = scipy.linalg.schur(
        maps[0],
        output="real",
        sort=lambda re, im: abs(complex(re, im) - 1.0) < neutral_tolerance,
    )
    if n_neutral == 0:
        return reduced
    V, W = Z[:, :n_neutral], Z[:, n_neutral:]
    neutral = np.linalg.eigvals(T[:n_neutral, :n_neutral])
    error = 0.0
    for A in maps:
        leak = np.linalg.norm(W.T @ A @ V) / max(np.linalg.norm(A), 1e-300)
        moved = np.max(np.abs(np.linalg.eigvals(V.T @ A @ V) - 1.0))
        error = max(error, leak)
        if leak > invariance_tolerance or moved > neutral_tolerance:
            reduced.separation_error = error
            return reduced
    # The modes' names: each eigenvector's largest component, back in the
    # unscaled coordinates.
    eigs, vecs = np.linalg.eig(maps[0])
    for lam in neutral:
        v = (U @ vecs[:, int(np.argmin(np.abs(eigs - lam)))]) * scale
        reduced.separated.append(
            SeparatedMode(complex(lam), kept[int(np.argmax(np.abs(v)))])
        )
    reduced.maps = [W.T @ A @ W for A in maps]
    reduced.basis = U @ W
    reduced.separation_error = error
    return reduced


@dataclass
class LmiSolution:
    """What the solver returned for one decay rate (P None if it did not
    succeed)."""

    P: Optional[np.ndarray]
    solver: str
    status: str
    success: bool
    # How many of the maps' inequalities the program held when it ended,
    # and in how many solves (constraint generation); which ones.
    inequalities: int = 0
    rounds: int = 1
    active: List[int] = field(default_factory=list)


def _symmetric_basis(n: int) -> List[np.ndarray]:
    basis = []
    for i in range(n):
        for j in range(i, n):
            E = np.zeros((n, n))
            E[i, j] = E[j, i] = 1.0
            basis.append(E)
    return basis


def _program(n: int, N: int):
    """(prog, Ps, flat, basis): N symmetric n x n P's with P_i >= I,
    P_i <= kappa I and kappa minimised (a well-conditioned P); ``flat``
    each P's entries on and above the diagonal, ``basis`` their matrices."""
    prog = MathematicalProgram()
    Ps = [prog.NewSymmetricContinuousVariables(n, f"P{i}") for i in range(N)]
    kappa = prog.NewContinuousVariables(1, "kappa")
    basis = _symmetric_basis(n)
    flat = [[P[a, b] for a in range(n) for b in range(a, n)] for P in Ps]
    eye = np.eye(n)
    for f in flat:
        prog.AddLinearMatrixInequalityConstraint([-eye] + basis, f)
        prog.AddLinearMatrixInequalityConstraint(
            [np.zeros((n, n)), eye] + [-E for E in basis],
            np.concatenate([kappa, f]),
        )
    prog.AddLinearCost(kappa[0])
    return prog, Ps, flat, basis


def _generate(solve, excess, groups, first):
    """(solution, active, rounds): constraint generation. ``solve(active)``
    solves the program on the inequalities ``active`` (keys) alone;
    ``excess(solution, key)`` is how far its solution breaks inequality
    ``key`` (> 0: broken); ``groups`` [[key, ...]] partition the keys,
    ``first`` the keys to start from. Each round adds the
    ``ACTIVE_ADD`` most broken of each group, until none is broken or
    the program is infeasible (a subset's infeasibility is the whole
    family's): the solution is the full program's, at the cost of the
    few inequalities that bind."""
    active, rounds = set(first), 0
    while True:
        solution = solve(sorted(active))
        rounds += 1
        if not solution[-1]:
            return solution, active, rounds
        added = []
        for group in groups:
            broken = [
                (excess(solution, k), k) for k in group if k not in active
            ]
            broken = sorted((b for b in broken if b[0] > 0.0), reverse=True)
            added += [k for _, k in broken[:ACTIVE_ADD]]
        if not added:
            return solution, active, rounds
        active.update(added)


def solve_common_lyapunov(
    maps: Sequence[np.ndarray],
    gamma: float,
    *,
    solver: str = "Clarabel",
    epsilon: float = 1e-9,
    first: Sequence[int] = (),
) -> LmiSolution:
    """P = P^T, P >= I, A_i^T P A_i - gamma^2 P <= -epsilon I for all i,
    P <= kappa I with kappa minimised (a well-conditioned P), by
    ``solver`` (Clarabel, CSDP or SCS, all shipped with the wheel), the
    inequalities generated as they bind (:func:`_generate`: from the
    nominal map, the one of largest radius and the maps ``first``, those
    that bound an earlier solve of a family laid out alike). The LMIs are
    written in P's basis (``AddLinearMatrixInequalityConstraint``) rather
    than as symbolic products, which grow as n^3 expressions."""
    n = maps[0].shape[0]
    eye = np.eye(n)

    def solve(active):
        prog, (P,), (variables,), basis = _program(n, 1)
        # gamma^2 P - A^T P A - epsilon I >= 0 at every active map.
        for i in active:
            A = maps[i]
            prog.AddLinearMatrixInequalityConstraint(
                [-epsilon * eye] + [gamma**2 * E - A.T @ E @ A for E in basis],
                variables,
            )
        result = _solve(prog, solver)
        success = result.is_success()
        return (result.GetSolution(P) if success else None, result, success)

    radii = [float(np.max(np.abs(np.linalg.eigvals(A)))) for A in maps]
    (P, result, success), active, rounds = _generate(
        solve,
        lambda solution, i: p_norm(maps[i], solution[0]) - gamma,
        [list(range(len(maps)))],
        {0, int(np.argmax(radii))} | {i for i in first if 0 <= i < len(maps)},
    )
    return LmiSolution(
        P=P,
        solver=solver,
        status=result.get_solution_result().name,
        success=success,
        inequalities=len(active),
        rounds=rounds,
        active=sorted(active),
    )


def p_norm(A: np.ndarray, P: np.ndarray) -> float:
    """The induced norm of A in ||x||_P = sqrt(x^T P x): the square root of
    the largest generalized eigenvalue of (A^T P A, P); inf when P is
    not positive definite in floating point (its Cholesky fails)."""
    try:
        mu = scipy.linalg.eigh(A.T @ P @ A, P, eigvals_only=True)
    except np.linalg.LinAlgError:
        return float("inf")  # P not positive definite in floating point
    return float(np.sqrt(max(mu[-1], 0.0)))


def check_lyapunov(
    maps: Sequence[np.ndarray],
    P: np.ndarray,
    *,
    margin: float = CHECK_MARGIN,
    max_condition: float = MAX_CONDITION,
) -> Dict:
    """The check after the solve, in numpy: P symmetric positive definite
    with condition number below ``max_condition``, and every map's P-norm
    (its decay rate under V) below 1 - ``margin``; also the largest
    eigenvalue of A_i^T P A_i - rate^2 P relative to P's largest, at the
    achieved rate (<= 0 up to round-off)."""
    P = 0.5 * (P + P.T)
    eig = np.linalg.eigvalsh(P)
    positive = bool(eig[0] > 0)
    condition = float(eig[-1] / eig[0]) if positive else float("inf")
    norms = [p_norm(A, P) for A in maps] if positive else [float("inf")]
    rate = max(norms)
    worst = int(np.argmax(norms))
    passed = positive and condition < max_condition and rate < 1.0 - margin
    return {
        "passed": bool(passed),
        "P_min_eigenvalue": float(eig[0]),
        "P_max_eigenvalue": float(eig[-1]),
        "P_condition": condition,
        "decay_rate": rate,
        "worst_map": worst,
        "margin": margin,
        "max_condition": max_condition,
    }


def search_basis(
    maps: Sequence[np.ndarray], tolerance: float = SEARCH_TOLERANCE
) -> np.ndarray:
    """V (columns orthonormal): the maps' common row space, singular
    values of the stacked maps above ``tolerance`` of the largest."""
    _, sigma, Vt = np.linalg.svd(np.vstack(maps))
    rank = max(int(np.sum(sigma > tolerance * sigma[0])), 1)
    return Vt[:rank].T


def lift(
    P_w: np.ndarray,
    V: np.ndarray,
    maps: Sequence[np.ndarray],
    margin: float = CHECK_MARGIN,
) -> np.ndarray:
    """P on the maps' coordinates from P_w on V's: V P_w V^T + mu (I - V
    V^T), mu (times P_w's smallest eigenvalue) the largest of
    ``LIFT_WEIGHTS`` whose largest P-norm of ``maps`` is within half the
    room below 1 - ``margin`` of the smallest (a smaller mu costs P's
    condition for nothing)."""
    n, r = V.shape
    P_w = 0.5 * (P_w + P_w.T)
    if r == n:
        return V @ P_w @ V.T
    inside = V @ P_w @ V.T
    outside = np.eye(n) - V @ V.T
    smallest = max(np.linalg.eigvalsh(P_w)[0], 1e-300)
    candidates = [inside + w * smallest * outside for w in LIFT_WEIGHTS]
    rates = [max(p_norm(A, P) for A in maps) for P in candidates]
    best = min(rates)
    good_enough = best + 0.5 * max(1.0 - margin - best, 0.0)
    return next(P for P, r in zip(candidates, rates) if r <= good_enough)


def nominal_lyapunov(maps: Sequence[np.ndarray]) -> Optional[np.ndarray]:
    """P of A_0^T P A_0 - P = -I (``maps[0]`` the nominal map), or None
    when A_0 is not stable."""
    A0 = maps[0]
    if np.max(np.abs(np.linalg.eigvals(A0))) >= 1.0:
        return None
    P = scipy.linalg.solve_discrete_lyapunov(A0.T, np.eye(A0.shape[0]))
    return P / np.linalg.eigvalsh(0.5 * (P + P.T))[0]


@dataclass
class Certificate:
    """The outcome: ``status`` certified, not_certified or inconclusive;
    ``decay_rate`` the checked one (the largest P-norm of the maps, per
    period) when certified; ``breaking`` the index of the map that breaks
    the program when not."""

    status: str
    decay_rate: Optional[float]
    P: Optional[np.ndarray]
    check: Optional[Dict]
    solver: str
    solver_status: str
    reduced: ReducedFamily
    breaking: Optional[int] = None
    breaking_reason: str = ""
    spectral_radii: List[float] = field(default_factory=list)
    solves: int = 0
    found_by: Optional[str] = None
    search_dimension: int = 0
    # The maps whose inequalities the programs held (constraint
    # generation), by index: a later family laid out alike starts there.
    held: List[int] = field(default_factory=list)

    def to_dict(self) -> Dict:
        r = self.reduced
        return {
            "status": self.status,
            "decay_rate_per_period": self.decay_rate,
            "P_condition": self.check["P_condition"] if self.check else None,
            "check": self.check,
            "solver": self.solver,
            "solver_status": self.solver_status,
            "solves": self.solves,
            "found_by": self.found_by,
            "certified_dimension": int(r.maps[0].shape[0]),
            "search_dimension": self.search_dimension,
            "image_rank": r.image_rank,
            "neglected_singular_value": r.neglected_singular_value,
            "overwritten_states": r.overwritten,
            "separated_modes": [m.to_dict() for m in r.separated],
            "separation_error": r.separation_error,
            "largest_spectral_radius": max(self.spectral_radii),
            "breaking_map": self.breaking,
            "breaking_reason": self.breaking_reason,
        }


def _feasible(maps, gamma, solver, margin, V=None, family=None, first=()):
    """(solution, check or None): the program at ``gamma`` on ``maps``
    (its inequalities generated from ``first`` on) and its check; with
    the search basis ``V``, ``maps`` are the ``family``'s in V's
    coordinates, and the solution's P is lifted to the family's and
    checked there."""
    solution = solve_common_lyapunov(maps, gamma, solver=solver, first=first)
    if not solution.success:
        return solution, None
    if V is None:
        return solution, check_lyapunov(maps, solution.P, margin=margin)
    solution.P = lift(solution.P, V, family, margin)
    return solution, check_lyapunov(family, solution.P, margin=margin)


def _breaking_map(search, family, V, radii, solver, margin, gamma) -> tuple:
    """The map that breaks the program: one whose own spectral radius is
    not below 1, else the first map, adding them in order of decreasing
    radius, with which no common P exists (found by bisection on the
    count); (index, reason, solves)."""
    order = np.argsort(radii)[::-1]
    if radii[order[0]] >= 1.0 - margin:
        return (
            int(order[0]),
            f"its own spectral radius is {radii[order[0]]:.6f}",
            0,
        )
    lo, hi, solves = 1, len(search), 0  # lo feasible (one stable map), hi not
    while hi - lo > 1:
        mid = (lo + hi) // 2
        solution, check = _feasible(
            [search[i] for i in order[:mid]],
            gamma,
            solver,
            margin,
            V,
            [family[i] for i in order[:mid]],
        )
        solves += 1
        if solution.success and check["passed"]:
            lo = mid
        else:
            hi = mid
    return (
        int(order[hi - 1]),
        f"each map alone is stable (largest radius "
        f"{radii[order[0]]:.6f}), but with this one added to the "
        f"{hi - 1} of larger radius no common P exists",
        solves,
    )


def _by_program(cert, search, family, V, radii, solver, margin, hi, name):
    """The program's P at decay rate ``hi`` (None when there is none, with
    ``cert`` then not_certified naming the breaking map when ``name``, or
    inconclusive when the solver's P fails the check); ``cert`` records
    the solve, and the inequalities it held (``held``, its start)."""
    solution, check = _feasible(
        search, hi, solver, margin, V, family, first=cert.held
    )
    cert.held = sorted(set(cert.held) | set(solution.active))
    cert.solves, cert.check = 1, check
    cert.solver_status = solution.status
    if not solution.success and solution.status != INFEASIBLE:
        # A solver that stops without a P has not shown that none exists.
        cert.status = "inconclusive"
        cert.breaking_reason = (
            f"the solver stopped with {solution.status}: neither a P nor "
            "a proof that none exists"
        )
        return None
    if not solution.success:
        cert.status = "not_certified"
        if not name:
            cert.breaking_reason = "no common P of the family"
            return None
        index, reason, solves = _breaking_map(
            search, family, V, radii, solver, margin, hi
        )
        cert.breaking, cert.breaking_reason = index, reason
        cert.solves += solves
        return None
    if not check["passed"]:
        cert.status = "inconclusive"
        cert.breaking = check["worst_map"]
        cert.breaking_reason = (
            f"the solver reported {solution.status} but its P fails "
            f"the check: decay rate {check['decay_rate']:.8f} (needs "
            f"< {1 - margin}), condition {check['P_condition']:.3g}"
        )
        return None
    cert.found_by = FOUND_BY_PROGRAM
    return solution.P


def certify_family(
    maps: Sequence[np.ndarray],
    labels: Sequence[str],
    *,
    solver: str = "Clarabel",
    margin: float = CHECK_MARGIN,
    bisections: int = 8,
    neutral_tolerance: float = 1e-6,
    enough: Optional[Callable[[Certificate], bool]] = None,
    name_breaking: bool = True,
    seed: Sequence[int] = (),
) -> Certificate:
    """The certificate of the family ``maps`` (``maps[0]`` nominal) over
    states ``labels``: reduced (:func:`reduce_family`); P searched in the
    maps' common row space (:func:`search_basis`), first from the nominal
    map's Lyapunov equation (:func:`nominal_lyapunov`), then, if its
    lifted P fails the check, by the program at gamma = 1 - 10 margin
    (the minimal-kappa P sits on the LMI's boundary, so the check at
    1 - margin keeps room for round-off). Once a P passes,
    gamma is bisected down towards the largest spectral radius (below it
    no P exists) for the best decay rate, or, with ``enough``, until
    ``enough(cert)`` (the checked P so far) says it is enough (each step is
    a solve). Infeasible: not_certified, with the breaking map; solved but
    failing the check: inconclusive. ``name_breaking`` False: an
    infeasible family's breaking map is not searched for (a bisection of
    solves; a caller that splits the family next has no use for it).
    ``seed``: maps (by index) whose inequalities every program starts
    with, as the bisection's solves start with those the solves before
    them held (``held``): the answer is the full program's whatever the
    start, which only saves the rounds of generating them."""
    reduced = reduce_family(maps, labels, neutral_tolerance=neutral_tolerance)
    family = reduced.maps
    radii = [float(np.max(np.abs(np.linalg.eigvals(A)))) for A in family]
    V = search_basis(family)
    search = [V.T @ A @ V for A in family]
    hi = 1.0 - 10 * margin
    cert = Certificate(
        status="certified",
        decay_rate=None,
        P=None,
        check=None,
        solver=solver,
        solver_status="not run",
        reduced=reduced,
        spectral_radii=radii,
        search_dimension=int(V.shape[1]),
        held=sorted(i for i in seed if 0 <= i < len(family)),
    )
    worst = int(np.argmax(radii))
    if radii[worst] >= 1.0 - margin:
        # A map unstable by itself refuses the family whatever P is tried:
        # no program is run.
        cert.status, cert.breaking = "not_certified", worst
        cert.breaking_reason = f"its own spectral radius is {radii[worst]:.6f}"
        return cert
    best = None
    # The cheap candidate: the nominal map's own Lyapunov function.
    P_w = nominal_lyapunov(search)
    if P_w is not None:
        P = lift(P_w, V, family, margin)
        check = check_lyapunov(family, P, margin=margin)
        if check["passed"]:
            best, cert.check, cert.found_by = P, check, FOUND_BY_NOMINAL
            hi = min(hi, check["decay_rate"])
    if best is None:
        best = _by_program(
            cert, search, family, V, radii, solver, margin, hi, name_breaking
        )
        if best is None:
            return cert
    cert.P, cert.decay_rate = best, cert.check["decay_rate"]
    bounds = (max(radii), hi)
    _bisect_rate(
        cert, (search, family, V), solver, margin, bounds, bisections, enough
    )
    return cert


def _bisect_rate(cert, maps, solver, margin, bounds, bisections, enough):
    """``cert`` with the decay rate bisected ``bisections`` times within
    ``bounds`` (lo, hi), or until ``enough(cert)``; ``maps``: (search,
    family, V) as :func:`_feasible` takes them."""
    (search, family, V), (lo, hi) = maps, bounds
    for _ in range(bisections):
        if enough is not None and enough(cert):
            break
        gamma = 0.5 * (lo + hi)
        trial, trial_check = _feasible(
            search, gamma, solver, margin, V, family, first=cert.held
        )
        cert.held = sorted(set(cert.held) | set(trial.active))
        cert.solves += 1
        if trial.success and trial_check["passed"]:
            hi, cert.P, cert.check = gamma, trial.P, trial_check
            cert.decay_rate = trial_check["decay_rate"]
            cert.solver_status = trial.status
            cert.found_by = FOUND_BY_PROGRAM
        else:
            lo = gamma


# -- A Lyapunov function per cell of parameters that are constant ----------


def left_out_norm(cert: Certificate, left_out: Sequence[np.ndarray]) -> float:
    """The sum of the P-norms of ``left_out`` (matrices on the maps'
    original coordinates, what the family's maps do not cover), in the
    certificate's coordinates and P: by the triangle inequality, added to
    the decay rate it bounds the P-norm of every map the family stands
    for."""
    return sum(p_norm(cert.reduced.transform(E), cert.P) for E in left_out)


@dataclass
class CellsCertificate:
    """The outcome of :func:`certify_cells`: ``status`` certified only if
    every cell is; ``cells`` per cell its status, decay rate, what its
    corners leave out and the sum; ``worst`` the cell that is not
    certified (the first), else the one with the largest sum."""

    status: str
    cells: List[Dict]
    worst: int
    certificates: List[Certificate]

    def to_dict(self) -> Dict:
        return {"status": self.status, "cells": self.cells, "worst": self.worst}


def certify_cells(
    cells: Sequence[Sequence[np.ndarray]],
    labels: Sequence[str],
    *,
    left_out: Optional[Sequence[Sequence[np.ndarray]]] = None,
    solver: str = "Clarabel",
    margin: float = CHECK_MARGIN,
    bisections: int = 6,
) -> CellsCertificate:
    """A quadratic Lyapunov function per cell, for a parameter that is
    constant while the system runs: x+ = A(c) x with c fixed somewhere in
    the box, unknown. ``cells`` per cell of a grid over c its family
    (:func:`certify_family`: its centre's map first, then the maps at the
    cell's corners), ``left_out`` per cell the matrices its corners do not
    cover (the curvature within the cell: its centre's map against the
    chord through its corners), bounded in the cell's P and added to its
    decay rate (the decay rate is bisected when the first P leaves no
    room). Each P proves its cell stable for any c in it, even moving
    within the cell; together they prove every constant c of the box
    stable, not a c that jumps from cell to cell. The cells are tried in
    order and the first that is not certified stops the search."""
    out = CellsCertificate("certified", [], 0, [])
    worst = -1.0

    for i, family in enumerate(cells):
        errors = list(left_out[i]) if left_out is not None else []

        def room(cert):
            return cert.decay_rate + left_out_norm(cert, errors) < 1 - margin

        # The first P sits on its LMI's boundary: the decay rate is
        # bisected until it leaves room for what the corners leave out.
        cert = certify_family(
            family,
            labels,
            solver=solver,
            margin=margin,
            bisections=bisections,
            enough=room,
        )
        total = None
        if cert.status == "certified":
            total = cert.decay_rate + left_out_norm(cert, errors)
        status = cert.status
        if total is not None and total >= 1.0 - margin:
            status = "inconclusive"
        out.certificates.append(cert)
        out.cells.append(
            {
                "status": status,
                "decay_rate": cert.decay_rate,
                "decay_rate_with_model_error": total,
                "P_condition": cert.check["P_condition"]
                if cert.check
                else None,
                "breaking_map": cert.breaking,
                "breaking_reason": cert.breaking_reason,
            }
        )
        if status != "certified":
            out.status, out.worst = status, i
            return out
        if total > worst:
            worst, out.worst = total, i
    return out


# -- A Lyapunov function that depends on a slowly moving parameter ---------


def _weights(thetas: np.ndarray, t: float) -> Dict[int, float]:
    """{node: weight}: t as the convex combination of its two grid nodes
    (the piecewise-affine interpolation's hat functions at t)."""
    j = int(
        np.clip(
            np.searchsorted(thetas, t, side="right") - 1, 0, len(thetas) - 2
        )
    )
    lam = float((t - thetas[j]) / (thetas[j + 1] - thetas[j]))
    lam = min(max(lam, 0.0), 1.0)
    return {j: 1.0 - lam, j + 1: lam}


def rate_vertices(thetas: Sequence[float], i: int, step: float) -> List[float]:
    """The values of theta' at which node i's inequality is imposed: the
    ends of [theta_{i-1} - step, theta_{i+1} + step] (within the grid)
    and every node inside. P(theta') is affine between nodes and
    A^T P A - gamma^2 P_i is affine in P, so these vertices cover every
    theta' of that interval."""
    thetas = np.asarray(thetas, float)
    lo = max(thetas[max(i - 1, 0)] - step, thetas[0])
    hi = min(thetas[min(i + 1, len(thetas) - 1)] + step, thetas[-1])
    inside = [float(t) for t in thetas if lo < t < hi]
    return sorted({lo, hi, *inside})


def reach(
    thetas: Sequence[float], c: int, step: float
) -> List[Tuple[int, int]]:
    """(sign, m): from a theta in cell c, theta' = theta + d with d in
    [0, step] (sign +1) or [-step, 0] (sign -1), and P(theta') - P(theta)
    = d times a convex combination of the slopes D_m of the cells m it
    crosses; these are the cells within ``step`` of cell c on that side
    (within the grid: the slope never leaves its range)."""
    thetas = np.asarray(thetas, float)
    if step <= 0.0:
        return [(1, c)]
    last = len(thetas) - 2
    lo = np.searchsorted(thetas, thetas[c] - step, side="right") - 1
    hi = np.searchsorted(thetas, thetas[c + 1] + step, side="left") - 1
    down = [(-1, m) for m in range(max(int(lo), 0), c + 1)]
    return down + [(1, m) for m in range(c, min(int(hi), last) + 1)]


def _polya_terms(A0, A1, c, sign, m, thetas, step):
    """The coefficients of F(a, b) = gamma^2 P(a, b) (a + b)^2 - A(a, b)^T
    Q A(a, b) on the cell [theta_c, theta_c+1] (a = 1 - l, b = l, A and P
    the chords, Q = P + (a + b) sign step D_m): [(Pterms, Aterms)] per
    monomial a^3, a^2 b, a b^2, b^3, each term (X, Y, {node: weight})
    standing for weight X^T P_node Y; the coefficient is gamma^2 times
    the first sum minus the second."""
    eye = np.eye(A0.shape[0])
    P = [((1, 0), {c: 1.0}), ((0, 1), {c + 1: 1.0})]
    slope = sign * step / (thetas[m + 1] - thetas[m])
    dD = {m + 1: slope, m: -slope} if slope else {}
    Q = P + ([((1, 0), dD), ((0, 1), dD)] if dD else [])
    coefficients = {(3 - k, k): ([], []) for k in range(4)}
    for (pa, pb), w in P:
        for (qa, qb), scale in (((2, 0), 1.0), ((1, 1), 2.0), ((0, 2), 1.0)):
            coefficients[(pa + qa, pb + qb)][0].append((scale * eye, eye, w))
    ends = [((1, 0), A0), ((0, 1), A1)]
    for (xa, xb), X in ends:
        for (qa, qb), w in Q:
            for (ya, yb), Y in ends:
                key = (xa + qa + ya, xb + qb + yb)
                coefficients[key][1].append((X, Y, w))
    return [coefficients[(3 - k, k)] for k in range(4)]


def _value(terms, Ps) -> np.ndarray:
    M = sum(
        X.T @ sum(w * Ps[j] for j, w in weights.items()) @ Y
        for X, Y, weights in terms
    )
    return 0.5 * (M + M.T)


def _in_basis(terms, basis) -> Dict[int, np.ndarray]:
    """{node: [n_basis, n, n]}: the terms' value for each basis matrix of
    each node's P."""
    out = {}
    for X, Y, weights in terms:
        T = np.einsum("ip,kij,jq->kpq", X, basis, Y)
        T = 0.5 * (T + T.transpose(0, 2, 1))
        for j, w in weights.items():
            out[j] = out.get(j, 0.0) + w * T
    return out


def _schedule_keys(maps, thetas, step) -> List[List[Tuple]]:
    """[[(cell, corner, sign, m, coefficient), ...] per cell]."""
    return [
        [
            (c, a, sign, m, e)
            for a in range(len(maps[c]))
            for sign, m in reach(thetas, c, step)
            for e in range(4)
        ]
        for c in range(len(thetas) - 1)
    ]


def schedule_rate(maps, thetas, step, Ps) -> Tuple[float, int]:
    """(rate, cell): the least gamma for which every coefficient of
    :func:`_polya_terms` is positive semidefinite with these P_i (its P
    part is positive definite, so per coefficient the square root of the
    largest generalized eigenvalue of (A part, P part)), and the cell it
    is at. By Polya's argument it bounds ||A(theta) x||_P(theta') /
    ||x||_P(theta) over every theta of the cells and theta' within
    ``step``."""
    maps = _per_node(maps)
    rate, worst = 0.0, 0
    quads = {
        key[:4] for group in _schedule_keys(maps, thetas, step) for key in group
    }
    for c, a, sign, m in sorted(quads):
        for Pt, At in _polya_terms(
            maps[c][a], maps[c + 1][a], c, sign, m, thetas, step
        ):
            r = _generalized_root(_value(At, Ps), _value(Pt, Ps))
            if r > rate:
                rate, worst = r, c
    return rate, worst


def _generalized_root(N: np.ndarray, M: np.ndarray) -> float:
    try:
        mu = scipy.linalg.eigh(N, M, eigvals_only=True)
    except np.linalg.LinAlgError:
        return float("inf")
    return float(np.sqrt(max(mu[-1], 0.0)))


def _interpolated(Ps: Sequence[np.ndarray], thetas, t) -> np.ndarray:
    return sum(w * Ps[j] for j, w in _weights(np.asarray(thetas), t).items())


def mixed_norm(A: np.ndarray, P_to: np.ndarray, P_from: np.ndarray) -> float:
    """sup ||A x||_{P_to} / ||x||_{P_from}: the square root of the largest
    generalized eigenvalue of (A^T P_to A, P_from); inf when P_from is not
    positive definite in floating point."""
    try:
        mu = scipy.linalg.eigh(A.T @ P_to @ A, P_from, eigvals_only=True)
    except np.linalg.LinAlgError:
        return float("inf")
    return float(np.sqrt(max(mu[-1], 0.0)))


def _per_node(maps) -> List[List[np.ndarray]]:
    """[[A, ...] per node]: a node's maps (one array: its only map)."""
    return [[m] if isinstance(m, np.ndarray) else list(m) for m in maps]


def _solved(prog, Ps, solver):
    """(the P_i's values or None, the result, success)."""
    result = _solve(prog, solver)
    success = result.is_success()
    values = [result.GetSolution(P) for P in Ps] if success else None
    return values, result, success


def _schedule_solution(solve, excess, groups, first):
    """(Ps or None, solver status, success, {inequalities, of, rounds}):
    a schedule program's answer from :func:`_generate`."""
    (Ps, result, success), active, rounds = _generate(
        solve, excess, groups, first
    )
    stats = {
        "inequalities": len(active),
        "of": sum(len(g) for g in groups),
        "rounds": rounds,
    }
    return Ps, result.get_solution_result().name, success, stats


def _solve_neighbourwise(maps, thetas, step, gamma, solver, epsilon):
    """P_i (one per grid node theta_i, P(theta) affine between nodes) with
    P_i >= I, P_i <= kappa I (kappa minimised) and A_i^T P(theta') A_i -
    gamma^2 P_i <= -epsilon I at every theta' of :func:`rate_vertices`,
    the inequalities generated as they bind (:func:`_generate`: from
    each node's map of largest radius); (Ps or None, solver status,
    success, {inequalities, of, rounds})."""
    maps = _per_node(maps)
    thetas = np.asarray(thetas, float)
    n, N = maps[0][0].shape[0], len(maps)
    eye = np.eye(n)
    vertices = [rate_vertices(thetas, i, step) for i in range(N)]
    groups = [
        [(i, a, t) for a in range(len(node)) for t in range(len(vertices[i]))]
        for i, node in enumerate(maps)
    ]

    def weights(i, t):
        w = dict(_weights(thetas, vertices[i][t]))
        w.setdefault(i, 0.0)
        return w

    def solve(active):
        prog, Ps, flat, basis = _program(n, N)
        for i, a, t in active:
            A, terms, variables = maps[i][a], [-epsilon * eye], []
            for j, w in weights(i, t).items():
                own = gamma**2 if j == i else 0.0
                terms += [own * E - w * (A.T @ E @ A) for E in basis]
                variables += flat[j]
            prog.AddLinearMatrixInequalityConstraint(terms, variables)
        return _solved(prog, Ps, solver)

    def excess(solution, key):
        i, a, t = key
        P_to = _interpolated(solution[0], thetas, vertices[i][t])
        return mixed_norm(maps[i][a], P_to, solution[0][i]) - gamma

    largest = [
        int(np.argmax([np.max(np.abs(np.linalg.eigvals(A))) for A in node]))
        for node in maps
    ]
    first = {
        (i, largest[i], t) for i in range(N) for t in range(len(vertices[i]))
    }
    return _schedule_solution(solve, excess, groups, first)


def solve_rate_bounded(
    maps: Sequence[np.ndarray],
    thetas: Sequence[float],
    step: float,
    gamma: float,
    *,
    solver: str = "Clarabel",
    epsilon: float = 1e-9,
    tied: bool = False,
) -> Tuple[Optional[List[np.ndarray]], str, bool, Dict]:
    """P(theta) by the neighbour-wise program (:func:`_solve_neighbourwise`,
    ``tied`` False: cheap, each node's maps decaying into every P within
    its neighbours' cells) or the tied one (:func:`_solve_tied`: theta'
    tied to theta, less conservative, its LMIs spanning up to four
    nodes' variables)."""
    program = _solve_tied if tied else _solve_neighbourwise
    return program(maps, thetas, step, gamma, solver, epsilon)


def _solve_tied(maps, thetas, step, gamma, solver, epsilon):
    """P_i (one per grid node theta_i, P(theta) affine between nodes) with
    P_i >= I, P_i <= kappa I (kappa minimised) and, on every cell and
    for every corner map and cell :func:`reach` can cross, each
    coefficient of :func:`_polya_terms` at ``gamma`` >= epsilon I; the
    inequalities generated as they bind (:func:`_generate`: from each
    cell's map of largest radius); (Ps or None, solver status, success,
    {inequalities, of, rounds}).

    Why the coefficients: with theta = (1 - l) theta_c + l theta_c+1 and
    theta' = theta + d, A(theta)^T P(theta') A(theta) <= gamma^2
    P(theta) is a cubic matrix polynomial in (a, b) = (1 - l, l) that
    keeps theta' tied to theta, so a node's map never has to decay into
    a neighbouring node's P; a homogeneous polynomial whose coefficients
    are all positive semidefinite is so on the whole simplex (Polya).
    Every term is linear in the P_i."""
    maps = _per_node(maps)
    thetas = np.asarray(thetas, float)
    n, N = maps[0][0].shape[0], len(maps)
    eye = np.eye(n)
    groups = _schedule_keys(maps, thetas, step)
    terms = {}

    def polya(key):
        if key[:4] not in terms:
            c, a, sign, m = key[:4]
            terms[key[:4]] = _polya_terms(
                maps[c][a], maps[c + 1][a], c, sign, m, thetas, step
            )
        return terms[key[:4]][key[4]]

    def solve(active):
        prog, Ps, flat, basis = _program(n, N)
        basis = np.array(basis)
        for key in active:
            Pt, At = polya(key)
            Pb, Ab = _in_basis(Pt, basis), _in_basis(At, basis)
            nodes = sorted(set(Pb) | set(Ab))
            mats = [-epsilon * eye]
            for j in nodes:
                mats += list(gamma**2 * Pb.get(j, 0.0) - Ab.get(j, 0.0))
            variables = [v for j in nodes for v in flat[j]]
            prog.AddLinearMatrixInequalityConstraint(mats, variables)
        return _solved(prog, Ps, solver)

    def excess(solution, key):
        Pt, At = polya(key)
        Ps = solution[0]
        return _generalized_root(_value(At, Ps), _value(Pt, Ps)) - gamma

    def radius(c, a):
        return max(
            np.max(np.abs(np.linalg.eigvals(maps[i][a]))) for i in (c, c + 1)
        )

    largest = [
        max(range(len(maps[c])), key=lambda a: radius(c, a))
        for c in range(N - 1)
    ]
    first = {key for g in groups for key in g if key[1] == largest[key[0]]}
    return _schedule_solution(solve, excess, groups, first)


def _node_rate(maps, thetas, step, Ps):
    """(rate, node): the largest mixed norm of a node's map from its P to
    P(theta') over :func:`rate_vertices`, and the node it is at."""
    rate, worst = 0.0, 0
    for i, A in ((i, A) for i, node in enumerate(maps) for A in node):
        for t in rate_vertices(thetas, i, step):
            r = mixed_norm(A, _interpolated(Ps, thetas, t), Ps[i])
            if r > rate:
                rate, worst = r, i
    return rate, worst


def _cell_pairs(thetas, step):
    """(c, j, k): P(theta') from node j, P(theta) from node k, for theta in
    cell c and theta' within ``step`` of it."""
    n = len(thetas)
    for c in range(n - 1):
        lo = np.searchsorted(thetas, thetas[c] - step, side="right") - 1
        hi = np.searchsorted(thetas, thetas[c + 1] + step, side="left")
        for j in range(max(lo, 0), min(hi, n - 1) + 1):
            for k in (c, c + 1):
                yield c, j, k


def check_rate_bounded(
    maps: Sequence[np.ndarray],
    thetas: Sequence[float],
    step: float,
    Ps: Sequence[np.ndarray],
    *,
    mids: Optional[Sequence[np.ndarray]] = None,
    left_out: Optional[Sequence] = None,
    margin: float = CHECK_MARGIN,
    max_condition: float = MAX_CONDITION,
    tied: bool = False,
) -> Dict:
    """The check in numpy of P(theta) (``Ps`` at the nodes, affine
    between): every P_i positive definite with condition below
    ``max_condition``; ``decay_rate`` a bound of the chord's maps between
    nodes decaying from P(theta) to P(theta') within ``step``: with
    ``tied``, the least gamma at which every coefficient of
    :func:`_polya_terms` holds (:func:`schedule_rate`), else the largest
    mixed norm of A_i from P_i to P(theta') over :func:`rate_vertices`
    (by convexity: A_lin^T Q A_lin <= (1 - l) A_i^T Q A_i + l A_{i+1}^T
    Q A_{i+1}); with ``mids`` (the maps at the cells'
    midpoints), ``chord_miss`` bounds what the chord leaves out: the
    largest mixed norm of (mid - chord) from any node's P of the cell to
    any P within ``step`` of it (a ratio of convex combinations is at most
    the largest ratio of their terms), added to the rate; ``left_out``
    [(name, [E, ...])]: what other parameters' corners leave out, each E
    bounded likewise over every cell, added too (an E that is a tuple:
    alternatives, of which one holds at a time, the worst added: a
    parameter's pieces)."""
    thetas = np.asarray(thetas, float)
    Ps = [0.5 * (P + P.T) for P in Ps]
    eigs = [np.linalg.eigvalsh(P) for P in Ps]
    positive = all(e[0] > 0 for e in eigs)
    condition = max(e[-1] / e[0] for e in eigs) if positive else float("inf")
    maps = _per_node(maps)
    rate_of = schedule_rate if tied else _node_rate
    rate, worst = rate_of(maps, thetas, step, Ps) if positive else (np.inf, 0)

    def bound(E, cells=None):
        return max(
            mixed_norm(E, Ps[j], Ps[k])
            for c, j, k in _cell_pairs(thetas, step)
            if cells is None or c in cells
        )

    miss = 0.0
    if mids is not None and positive:
        for c, cell in enumerate(_per_node(mids)):
            for mid, a, b in zip(cell, maps[c], maps[c + 1]):
                miss = max(miss, bound(mid - 0.5 * (a + b), {c}))
    errors = []
    if positive:
        errors = [
            {
                "parameter": name,
                "p_norm": sum(
                    max(map(bound, E)) if isinstance(E, tuple) else bound(E)
                    for E in Es
                ),
            }
            for name, Es in (left_out or [])
        ]
    total = rate + miss + sum(e["p_norm"] for e in errors)
    return {
        "passed": bool(
            positive and condition < max_condition and total < 1.0 - margin
        ),
        "P_condition": float(condition),
        "decay_rate": float(rate),
        "chord_miss": float(miss),
        "model_error": errors,
        "decay_rate_with_model_error": float(total),
        "worst": int(worst),
        "program": "tied" if tied else "neighbour-wise",
        "margin": margin,
        "max_condition": max_condition,
    }


@dataclass
class RateBoundedCertificate:
    """The outcome of :func:`certify_rate_bounded`: ``status``, the
    checked P_i at the grid's nodes (in the reduced coordinates) and the
    check."""

    status: str
    Ps: Optional[List[np.ndarray]]
    check: Optional[Dict]
    solver_status: str
    reduced: ReducedFamily
    search_dimension: int
    spectral_radii: List[float]
    reason: str = ""
    solves: int = 0
    # The last program's inequalities: held, of all, and its rounds.
    inequalities: Dict = field(default_factory=dict)
    # Whether the tied program (not the neighbour-wise one) gave P.
    tied: bool = False

    def to_dict(self) -> Dict:
        return {
            "status": self.status,
            "inequalities": self.inequalities,
            "program": "tied" if self.tied else "neighbour-wise",
            "check": self.check,
            "solver_status": self.solver_status,
            "search_dimension": self.search_dimension,
            "certified_dimension": int(self.reduced.maps[0].shape[0]),
            "largest_spectral_radius": max(self.spectral_radii),
            "reason": self.reason,
            "solves": self.solves,
        }


def _lifted_check(P_ws, V, family, thetas, step, mids, left_out, margin, tied):
    """(Ps, check): the search coordinates' P_i lifted with the one weight
    (of ``LIFT_WEIGHTS``) whose check leaves the most room, of those that
    pass it if any do."""
    n, r = V.shape
    inside = [V @ P @ V.T for P in P_ws]
    outside = np.eye(n) - V @ V.T
    smallest = max(min(np.linalg.eigvalsh(P)[0] for P in P_ws), 1e-300)
    best = None
    for w in LIFT_WEIGHTS if r < n else [0.0]:
        Ps = [P + w * smallest * outside for P in inside]
        check = check_rate_bounded(
            family,
            thetas,
            step,
            Ps,
            mids=mids,
            left_out=left_out,
            margin=margin,
            tied=tied,
        )
        # A weight that passes beats one that does not: the least rate
        # comes with the smallest weight, and P's condition with it.
        key = (not check["passed"], check["decay_rate_with_model_error"])
        if best is None or key < best[0]:
            best = (key, Ps, check)
    return best[1:]


def _reduced_schedule(maps, mids, labels, left_out):
    """(reduced, per-node maps, per-cell midpoint maps or None, left_out)
    in the coordinates :func:`reduce_family` gives the nodes' and the
    midpoints' maps together."""
    nodes = _per_node(maps)
    cells = _per_node(mids) if mids is not None else []
    reduced = reduce_family([A for node in nodes + cells for A in node], labels)
    it = iter(reduced.maps)
    family = [[next(it) for _ in node] for node in nodes]
    mid_maps = [[next(it) for _ in cell] for cell in cells] or None

    def transform(E):
        if isinstance(E, tuple):
            return tuple(map(reduced.transform, E))
        return reduced.transform(E)

    left_out = [(name, list(map(transform, Es))) for name, Es in left_out or []]
    return reduced, family, mid_maps, left_out


def _failed_check(status: str, check: Dict, margin: float) -> str:
    """Why a solved P(theta) is inconclusive: what its check found."""
    left = sum(e["p_norm"] for e in check["model_error"])
    return (
        f"the solver reported {status} but P(theta) fails the check: "
        f"decay rate {check['decay_rate']:.8f} plus the chord's miss "
        f"{check['chord_miss']:.3g} plus what the corners leave out "
        f"{left:.3g} (needs < {1 - margin}), condition "
        f"{check['P_condition']:.3g}"
    )


def certify_rate_bounded(
    maps: Sequence[np.ndarray],
    thetas: Sequence[float],
    step: float,
    labels: Sequence[str],
    *,
    mids: Optional[Sequence[np.ndarray]] = None,
    left_out: Optional[Sequence] = None,
    solver: str = "Clarabel",
    margin: float = CHECK_MARGIN,
    bisections: int = 6,
) -> RateBoundedCertificate:
    """A Lyapunov function V(x, theta) = x^T P(theta) x, P affine between
    the grid's nodes ``thetas``, for x+ = A(theta) x with theta moving by
    at most ``step`` per period: A(theta) the chord through ``maps`` (per
    node one map, or a list: the corners of other parameters, which may
    move arbitrarily fast, aligned across nodes), plus what the chord
    leaves out at the cells' midpoints (``mids``). Reduced together
    (:func:`reduce_family`), P_i searched in the common row space, lifted, the
    decay rate bisected until the chord's miss has room, then checked in
    numpy (:func:`check_rate_bounded`): a solved program whose P fails
    the check is inconclusive. ``left_out`` [(name, [E, ...])], in the maps'
    coordinates: what other parameters' corners leave out, bounded in
    P(theta) and added."""
    thetas = np.asarray(thetas, float)
    reduced, family, mid_maps, left_out = _reduced_schedule(
        maps, mids, labels, left_out
    )
    radii = [
        float(np.max(np.abs(np.linalg.eigvals(A))))
        for node in family
        for A in node
    ]
    V = search_basis([A for node in family for A in node])
    search = [[V.T @ A @ V for A in node] for node in family]
    out = RateBoundedCertificate(
        "not_certified", None, None, "not run", reduced, int(V.shape[1]), radii
    )
    if max(radii) >= 1.0 - margin:
        out.reason = f"a node's own spectral radius is {max(radii):.6f}"
        return out
    problem = (search, V, family, thetas, step, mid_maps, left_out)
    for tied in (False, True):
        # The neighbour-wise program is the cheaper, but it asks each
        # node's map to decay into its neighbours' P: its failure is not
        # the family's.
        out.tied = tied
        _bisect_schedule(out, problem, solver, margin, bisections)
        if out.status == "certified":
            break
    return out


def _bisect_schedule(out, problem, solver, margin, bisections):
    """Fills ``out`` from one program (``out.tied``) on ``problem``
    (search maps, their basis V, the family, the grid, the step, the
    midpoints' maps, what is left out): the first P(theta)
    sits on its LMI's boundary at gamma = 1 - 10 margin, leaving no room
    for the chord's miss, so the decay rate is bisected towards the
    nodes' largest radius until a P passes the check."""
    search, V, family, thetas, step, mid_maps, left_out = problem
    # What ``out`` holds is this program's alone: a P and check left by
    # the other program would be recorded under this one's name.
    out.Ps, out.check, out.reason = None, None, ""
    lo, gamma, best = max(out.spectral_radii), 1.0 - 10 * margin, None
    for attempt in range(bisections + 1):
        P_ws, status, success, out.inequalities = solve_rate_bounded(
            search, thetas, step, gamma, solver=solver, tied=out.tied
        )
        out.solves += 1
        if not success:
            if attempt == 0:
                program = "tied" if out.tied else "neighbour-wise"
                out.solver_status = status
                if status != INFEASIBLE:
                    out.status = "inconclusive"
                    out.reason = (
                        f"the solver stopped with {status} on the "
                        f"{program} program: neither a P(theta) nor a "
                        "proof that none exists"
                    )
                    return
                out.status = "not_certified"
                out.reason = (
                    f"no P(theta) affine between the {len(family)} nodes "
                    f"exists for a step of {step:g} per period ({status}, "
                    f"{program} program)"
                )
                return
            lo, gamma = gamma, 0.5 * (gamma + best[2])
            continue
        out.solver_status = status
        trial = _lifted_check(
            P_ws, V, family, thetas, step, mid_maps, left_out, margin, out.tied
        )
        if best is None or (
            trial[1]["decay_rate_with_model_error"]
            < best[1]["decay_rate_with_model_error"]
        ):
            best = (*trial, gamma)
        if best[1]["passed"]:
            break
        gamma = 0.5 * (lo + gamma)
    out.Ps, out.check = best[0], best[1]
    if out.check["passed"]:
        out.status, out.reason = "certified", ""
    else:
        out.status = "inconclusive"
        out.reason = _failed_check(status, out.check, margin)
