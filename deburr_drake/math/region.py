"""A reduced polynomial model of the normal-force axis, for a region of
attraction (pure numpy, no Drake).

The sampled inner loop along n1 (into the material), one control period T
per step, with the actuation held over the period:

- state x = [delta, delta', y, delta_d]: the tool's depth (m) and its rate
  (m/s) along n1, the sensor's filtered normal force (N) and the depth
  reference of the depth law (7) (m);
- the normal force F(delta), in three contact regions: zero out of contact
  (delta < 0); the contact threshold's onset (0 <= delta < delta_c: c0
  times the smoothstep 3 u^2 - 2 u^3 of u = delta / delta_c, the process's
  own ramp) plus the hydroelastic force; in contact (delta >= delta_c)
  c0 plus the hydroelastic force. The hydroelastic force is a polynomial
  p(delta) (:class:`ContactFit`, p(0) = 0, exact at the operating depth)
  plus a residual w that the fit bounds: |w| <= max_residual, and in
  contact also in a sector, |w| <= sector |delta - delta*|;
- s = k_delta (f_d - y) - delta' + lambda (delta_d - delta), the sliding
  variable along n1 (10) with delta_d' = k_delta (f_d - y) (7);
- U = K s + y + u(s) + d, the law's force along n1 (36): the measured force
  cancelled, u the fuzzy compensator along n1 with the rule weights frozen
  (:class:`PiecewiseQuadratic`: a quadratic per fuzzy cell, the robust
  term's constant outside the rules' domain) and d the constant force that
  makes the operating point an equilibrium (the part of gravity, friction
  and the model's error along n1 that the learned rules balance);
- the joints' damping along n1: viscous, c delta', and the change of
  the joints' smoothed Coulomb friction from the operating point's,
  phi(delta') (``friction``): monotone with slope in [0, friction_slope],
  a sector the S-procedure carries;
- over the period, M delta'' = U - F(delta) - c delta' - phi (M the task
  inertia along n1),
  integrated by its Taylor expansion to third order in T with F's
  derivative along the motion (:meth:`NormalAxisModel.step`), the sensor's
  exact first-order filter y+ = y + alpha (F(delta) - y), and
  delta_d+ = delta_d + T k_delta (f_d - y).

Every step is written with + and * only, so the same code gives floats and
the polynomial (pydrake.symbolic) map of each region (one fuzzy cell, in or
out of contact) that :mod:`deburr_drake.analysis.region` certifies."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

__all__ = [
    "ContactFit",
    "fit_contact_law",
    "PiecewiseQuadratic",
    "piecewise_quadratic",
    "NormalAxisModel",
    "STATE_NAMES",
    "OUT",
    "ONSET",
    "IN",
]

#: The reduced state, in order.
STATE_NAMES = ("depth", "depth_rate", "filtered_force", "depth_reference")
#: The contact regions: out of contact, c0's onset, in contact.
OUT, ONSET, IN = 0, 1, 2


@dataclass(frozen=True)
class ContactFit:
    """p(delta) = sum_i c_i delta^i (i = 1..degree; N, delta in m), fitted
    to a measured contact law F on [0, max_depth], exact at ``anchor``
    (the operating depth). ``sector`` (N/m) and ``max_residual`` (N) bound
    the residual F - p at the measured depths:
    |F - p| <= sector |delta - anchor| and |F - p| <= max_residual."""

    coefficients: np.ndarray
    anchor: float
    max_depth: float
    sector: float
    max_residual: float
    depths: np.ndarray
    residuals: np.ndarray

    def __call__(self, depth):
        """p(depth), with + and * only (floats or polynomials)."""
        out = 0.0 * depth
        for c in self.coefficients[::-1]:
            out = (out + c) * depth
        return out

    def derivative(self, depth):
        """p'(depth) (N/m), with + and * only."""
        out = 0.0 * depth
        for i in range(len(self.coefficients), 0, -1):
            out = out * depth + i * self.coefficients[i - 1]
        return out

    def residual(self, depth):
        """F - p at ``depth`` (float), interpolated between the measured
        depths; zero outside contact (there F = p = 0 by the model)."""
        if depth <= 0.0:
            return 0.0
        return float(np.interp(depth, self.depths, self.residuals))


def fit_contact_law(
    depths, forces, *, degree: int, anchor: float, anchor_force: float
) -> ContactFit:
    """The least-squares polynomial of ``degree`` through the origin that
    passes through (``anchor``, ``anchor_force``), fitted to the measured
    law (``depths`` >= 0 in m, ``forces`` in N), with its residual's
    sector and largest value over the measured depths."""
    d = np.asarray(depths, float)
    f = np.asarray(forces, float)
    if degree < 1 or d.ndim != 1 or d.shape != f.shape or len(d) <= degree:
        raise ValueError(
            "fit_contact_law: need degree >= 1 and more depths than degree"
        )
    if np.any(d < 0) or not 0 < anchor <= d.max():
        raise ValueError(
            "fit_contact_law: depths must be >= 0 and the anchor in "
            "(0, max depth]"
        )
    powers = np.arange(1, degree + 1)
    A = d[:, None] ** powers
    a = anchor**powers
    # Least squares with the one equality a . c = anchor_force (KKT).
    kkt = np.block([[2 * A.T @ A, a[:, None]], [a[None, :], np.zeros((1, 1))]])
    rhs = np.concatenate([2 * A.T @ f, [anchor_force]])
    c = np.linalg.solve(kkt, rhs)[:degree]
    r = f - A @ c
    away = np.abs(d - anchor) > 1e-12 * max(1.0, d.max())
    sector = float(np.max(np.abs(r[away]) / np.abs(d[away] - anchor)))
    order = np.argsort(d)
    return ContactFit(
        coefficients=c,
        anchor=float(anchor),
        max_depth=float(d.max()),
        sector=sector,
        max_residual=float(np.max(np.abs(r))),
        depths=d[order],
        residuals=r[order],
    )


@dataclass(frozen=True)
class PiecewiseQuadratic:
    """u(s) = c0 + c1 s + c2 s^2 on each cell [edges[i], edges[i+1]]
    (edges[0] = -inf, edges[-1] = inf)."""

    edges: np.ndarray
    coefficients: np.ndarray  # (cells, 3)

    @property
    def n_cells(self) -> int:
        return len(self.coefficients)

    def cell(self, s: float) -> int:
        """The cell holding ``s`` (float)."""
        i = int(np.searchsorted(self.edges, s, side="right")) - 1
        return min(max(i, 0), self.n_cells - 1)

    def piece(self, i: int, s):
        """Cell ``i``'s quadratic at ``s``, with + and * only."""
        c0, c1, c2 = self.coefficients[i]
        return c0 + (c1 + c2 * s) * s

    def __call__(self, s: float) -> float:
        return float(self.piece(self.cell(s), s))


def piecewise_quadratic(
    fn: Callable[[float], float],
    breakpoints: Sequence[float],
    *,
    tolerance: float = 1e-9,
) -> PiecewiseQuadratic:
    """The exact piecewise-quadratic form of ``fn`` (a scalar function
    quadratic between ``breakpoints``): each cell's quadratic through three
    of its points, checked at two more (ValueError when ``fn`` is not a
    quadratic there, relative to ``tolerance``)."""
    b = np.unique(np.asarray(breakpoints, float))
    edges = np.concatenate([[-np.inf], b, [np.inf]])
    width = max(float(np.ptp(b)), 1.0) if len(b) > 1 else 1.0
    coefficients = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        lo_f = lo if np.isfinite(lo) else hi - width
        hi_f = hi if np.isfinite(hi) else lo_f + width
        span = hi_f - lo_f
        fit_at = lo_f + span * np.array([0.1, 0.5, 0.9])
        check_at = lo_f + span * np.array([0.27, 0.73])
        c2, c1, c0 = np.polyfit(fit_at, [fn(s) for s in fit_at], 2)
        got = np.array([fn(s) for s in check_at])
        want = c0 + c1 * check_at + c2 * check_at**2
        scale = max(1.0, float(np.max(np.abs(got))))
        if np.max(np.abs(got - want)) > tolerance * scale:
            raise ValueError(
                f"piecewise_quadratic: not a quadratic on [{lo}, {hi}]"
            )
        coefficients.append([c0, c1, c2])
    return PiecewiseQuadratic(edges=edges, coefficients=np.array(coefficients))


@dataclass(frozen=True)
class NormalAxisModel:
    """The reduced sampled loop along n1 (module docstring), SI units."""

    mass: float  # kg, task inertia along n1
    sliding_gain: float  # N s/m, K along n1
    sliding_lambda: float  # 1/s, lambda along n1
    depth_gain: float  # m/(N s), k_delta of (7)
    sensor_alpha: float  # 1 - exp(-2 pi f_c T_s)
    period: float  # s, T
    desired_force: float  # N, ||f_nd hat||
    disturbance: float  # N, d
    threshold_force: float  # N, c0 of (4)
    threshold_depth: float  # m, delta_c: c0's onset
    damping: float  # N s/m, c: the joints' viscous damping along n1
    friction_slope: float  # N s/m, phi's largest slope
    friction: Callable[[float], float]  # N, phi(delta')
    contact: ContactFit
    compensator: PiecewiseQuadratic

    def sliding(self, x):
        """s along n1 (m/s), with + and * only."""
        depth, rate, y, ref = x
        return (
            self.depth_gain * (self.desired_force - y)
            - rate
            + self.sliding_lambda * (ref - depth)
        )

    def normal_force(self, depth, w, contact: int):
        """(F, dF/d delta) of the contact region ``contact`` (:data:`OUT`,
        :data:`ONSET`, :data:`IN`) with the fit's residual ``w``, with +
        and * only."""
        if contact == OUT:
            return 0.0 * depth, 0.0 * depth
        p = self.contact(depth) + w
        dp = self.contact.derivative(depth)
        if contact == IN:
            return p + self.threshold_force, dp
        u = depth * (1.0 / self.threshold_depth)
        ramp = self.threshold_force * (3.0 - 2.0 * u) * u * u
        dramp = self.threshold_force / self.threshold_depth * 6.0 * u * (1 - u)
        return p + ramp, dp + dramp

    def contact_region(self, depth: float) -> int:
        """:data:`OUT`, :data:`ONSET` or :data:`IN` of a float depth."""
        if depth < 0.0:
            return OUT
        return ONSET if depth < self.threshold_depth else IN

    def step_in_region(self, x, w, cell: int, contact: int, phi=0.0):
        """x one period later, with the compensator's ``cell``, the
        contact region ``contact`` (the residual ``w`` is ignored out of
        contact) and the friction's change ``phi`` (N), held over the
        period, with + and * only."""
        depth, rate, y, ref = x
        T, M = self.period, self.mass
        s = self.sliding(x)
        u = (
            self.sliding_gain * s
            + y
            + self.compensator.piece(cell, s)
            + self.disturbance
        )
        force, stiffness = self.normal_force(depth, w, contact)
        force_rate = stiffness * rate
        accel = (u - force - self.damping * rate - phi) * (1.0 / M)
        jerk = force_rate * (-1.0 / M)
        return np.array(
            [
                depth + T * rate + T**2 / 2 * accel + T**3 / 6 * jerk,
                rate + T * accel + T**2 / 2 * jerk,
                y + self.sensor_alpha * (force - y),
                ref + T * self.depth_gain * (self.desired_force - y),
            ],
            dtype=object if _symbolic(x) else float,
        )

    def region_of(self, x) -> tuple[int, int]:
        """(cell, contact region) of a float state."""
        return (
            self.compensator.cell(float(self.sliding(x))),
            self.contact_region(float(x[0])),
        )

    def step(self, x, w=None):
        """One period from a float state, the region read from it; ``w``
        the contact's residual (default: the measured one)."""
        x = np.asarray(x, float)
        cell, contact = self.region_of(x)
        if w is None:
            w = self.contact.residual(x[0])
        return self.step_in_region(
            x, w, cell, contact, self.friction(float(x[1]))
        )

    def equilibrium(self) -> np.ndarray:
        """The operating point [delta*, 0, f_d, delta_d*]: delta* the
        contact fit's anchor (where c0 + p = f_d), delta_d* = delta* +
        s* / lambda with s* solving K s + u(s) + d = 0 (the disturbance
        is chosen so that it does)."""
        s_star = self._equilibrium_sliding()
        depth = self.contact.anchor
        return np.array(
            [
                depth,
                0.0,
                self.desired_force,
                depth + s_star / self.sliding_lambda,
            ]
        )

    def _equilibrium_sliding(self) -> float:
        # K s + u(s) + d is monotone near the operating point (K dominates
        # the rules' slope there); bisection on a bracket of +-1 m/s.
        def g(s):
            return (
                self.sliding_gain * s + self.compensator(s) + self.disturbance
            )

        lo, hi = -1.0, 1.0
        if g(lo) > 0 or g(hi) < 0:
            raise ValueError("NormalAxisModel: no equilibrium s in [-1, 1] m/s")
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if g(mid) > 0:
                hi = mid
            else:
                lo = mid
        return 0.5 * (lo + hi)

    def simulate(self, x0, steps: int) -> np.ndarray:
        """(steps + 1, 4) states from ``x0``, the measured residual."""
        out = np.empty((steps + 1, 4))
        out[0] = x0
        for k in range(steps):
            out[k + 1] = self.step(out[k])
        return out


def _symbolic(x) -> bool:
    return any(
        not isinstance(v, (float, int, np.floating, np.integer)) for v in x
    )
