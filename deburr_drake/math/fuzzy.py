"""Central B-spline fuzzy rule base of Hsu & Fu, Section III.C, eqs. (24)-(35).

Pure numpy (no pydrake).  Conventions and corrections (R1-R10 in
docs/cell-and-paper.md):

* R1: the central cardinal B-spline of eq. (24) carries the factor 1/Delta**m,
  so shifted copies N_m(y - i*Delta) sum to one (partition of unity) and the
  peak of N_1 is 1.  Order m = 0 is the half-open indicator of [-Delta/2,
  Delta/2).
* R4: the dead zone of eq. (31) has a half-width parameter whose default is the
  half-support (m+1)/2 * Delta_k used in the proof of Proposition 2 (not
  Delta_k).
* R8: one two-input controller u_fk(y0, yk) has (2*Upsilon+1)**2 rules.

Piecewise form used everywhere: with t = y/Delta + (m+1)/2, segment k = floor(t)
in 0..m and u = t - k in [0, 1), N_m(y) is the k-th uniform B-spline piece at u;
N_m = 0 for t outside [0, m+1).  The m+1 rules active at y (eq. 25) are
i = first + p, p = 0..m, first = floor(y/Delta - (m+1)/2) + 1, and their weights
are the pieces m-p evaluated at the fractional part f of y/Delta - (m+1)/2.

T-generic (CONTRACTS.md): for m >= 1, `bspline_membership`, `dead_zone` and the
RuleBase weights accept pydrake AutoDiffXd scalars / object arrays; the piece is
selected by the plain value and evaluated with + - * on y, so derivatives flow.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

__all__ = [
    "bspline_membership",
    "bspline_membership_derivative",
    "active_indices",
    "default_dead_zone_half_width",
    "dead_zone",
    "RuleBase",
]


def _value(y):
    """Plain float value of a float or AutoDiffXd scalar (never float() on
    AutoDiff)."""
    return y.value() if hasattr(y, "value") else float(y)


def _check_m(m, name="m"):
    if (
        isinstance(m, bool)
        or not isinstance(m, (int, np.integer))
        or not 0 <= m <= 3
    ):
        raise ValueError(f"{name} must be an int in 0..3, got {m!r}")
    return int(m)


def _check_positive(x, name):
    try:
        xf = float(x)
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be a finite float > 0, got {x!r}"
        ) from None
    if not (math.isfinite(xf) and xf > 0.0):
        raise ValueError(f"{name} must be a finite float > 0, got {x!r}")
    return xf


def _is_object(y):
    return (isinstance(y, np.ndarray) and y.dtype == object) or hasattr(
        y, "value"
    )


# ---------------------------------------------------------------------------
# Uniform B-spline pieces (unit spacing), segment k of [0, m+1), local u in
# [0,1). Written with + - * only so they accept AutoDiffXd.


def _piece(m, k, u):
    if m == 0:
        return 0.0 * u + 1.0
    if m == 1:
        return u if k == 0 else 1.0 - u
    if m == 2:
        if k == 0:
            return 0.5 * u * u
        if k == 1:
            return 0.5 + u - u * u
        a = 1.0 - u
        return 0.5 * a * a
    # m == 3
    if k == 0:
        return u * u * u / 6.0
    if k == 1:
        return (((-3.0 * u + 3.0) * u + 3.0) * u + 1.0) / 6.0
    if k == 2:
        return ((3.0 * u - 6.0) * u * u + 4.0) / 6.0
    a = 1.0 - u
    return a * a * a / 6.0


def _dpiece(m, k, u):
    """d(piece)/du, float arrays."""
    if m == 0:
        return 0.0 * u
    if m == 1:
        return 0.0 * u + (1.0 if k == 0 else -1.0)
    if m == 2:
        return (u, 1.0 - 2.0 * u, u - 1.0)[k]
    if k == 0:
        return 0.5 * u * u
    if k == 1:
        return (-9.0 * u * u + 6.0 * u + 3.0) / 6.0
    if k == 2:
        return (9.0 * u * u - 12.0 * u) / 6.0
    a = 1.0 - u
    return -0.5 * a * a


def _active_weights(m, f):
    """Weights of the m+1 active rules (p = 0..m) at fractional position f in
    [0,1).

    Equals _piece(m, m - p, f); sums to one.  T-generic in f.
    """
    if m == 0:
        return (0.0 * f + 1.0,)
    if m == 1:
        return (1.0 - f, f)
    if m == 2:
        a = 1.0 - f
        return (0.5 * a * a, 0.5 + f - f * f, 0.5 * f * f)
    a = 1.0 - f
    f2 = f * f
    return (
        a * a * a / 6.0,
        ((3.0 * f - 6.0) * f2 + 4.0) / 6.0,
        (((-3.0 * f + 3.0) * f + 3.0) * f + 1.0) / 6.0,
        f2 * f / 6.0,
    )


def _membership_float(y, m, delta, deriv=False):
    y = np.asarray(y, dtype=float)
    t = y / delta + 0.5 * (m + 1)
    k = np.floor(t)
    with np.errstate(
        invalid="ignore"
    ):  # inf - inf at y = +-inf: outside, gives 0
        u = t - k
    out = np.zeros_like(t)
    for seg in range(m + 1):
        mask = k == seg
        if mask.any():
            uu = u[mask]
            out[mask] = (
                _dpiece(m, seg, uu) / delta if deriv else _piece(m, seg, uu)
            )
    if not deriv:
        out[np.isnan(t)] = (
            np.nan
        )  # propagate NaN instead of silently returning 0
    return out[()] if out.ndim == 0 else out


def _membership_scalar_generic(y, m, delta):
    t = y / delta + 0.5 * (m + 1)
    k = math.floor(_value(t))
    if k < 0 or k > m:
        return 0.0 * y
    return _piece(m, k, t - float(k))


def bspline_membership(y, m, delta):
    """Central cardinal B-spline N_m(y) of eq. (24) with the 1/delta**m factor
    (R1).

    Support [-(m+1)/2*delta, (m+1)/2*delta]; sum_i N_m(y - i*delta) = 1; peak of
    N_1 is 1.  m = 0: indicator of [-delta/2, delta/2).  Float arrays are
    evaluated vectorized (NaN propagates); AutoDiffXd scalars / object arrays (m
    >= 1) are evaluated element by element with arithmetic on y so derivatives
    flow.
    """
    m = _check_m(m)
    delta = _check_positive(delta, "delta")
    if _is_object(y):
        if isinstance(y, np.ndarray):
            out = np.empty(y.shape, dtype=object)
            for ix, yi in np.ndenumerate(y):
                out[ix] = _membership_scalar_generic(yi, m, delta)
            return out
        return _membership_scalar_generic(y, m, delta)
    return _membership_float(y, m, delta)


def bspline_membership_derivative(y, m, delta):
    """dN_m/dy for float arrays (zeros for m = 0; right-sided at the knots for m
    = 1)."""
    m = _check_m(m)
    delta = _check_positive(delta, "delta")
    return _membership_float(y, m, delta, deriv=True)


def active_indices(y, m, delta):
    """Index set I_c(y) of eq. (25) as m+1 consecutive ints (plain value of y).

    first = floor(y/delta - (m+1)/2) + 1; consistent with the half-open m = 0
    convention.  At knots (m >= 1) one of the returned indices has weight 0.
    """
    m = _check_m(m)
    delta = _check_positive(delta, "delta")
    yv = _value(y)
    if not math.isfinite(yv):
        raise ValueError(f"y must be finite, got {yv!r}")
    first = math.floor(yv / delta - 0.5 * (m + 1)) + 1
    return np.arange(first, first + m + 1)


def default_dead_zone_half_width(m, delta):
    """Default dead-zone half-width (m+1)/2 * delta (R4: half-support, Prop.
    2)."""
    m = _check_m(m)
    delta = _check_positive(delta, "delta")
    return 0.5 * (m + 1) * delta


def dead_zone(y, half_width):
    """y_Delta of eq. (31) with half-width as a parameter (R4): y if |y| >
    half_width else 0.

    T-generic: returns y or 0*y for AutoDiffXd; float arrays are handled
    elementwise.
    """
    if isinstance(y, np.ndarray):
        if y.dtype == object:
            out = np.empty(y.shape, dtype=object)
            for ix, yi in np.ndenumerate(y):
                out[ix] = yi if abs(_value(yi)) > half_width else 0.0 * yi
            return out
        return np.where(np.abs(y) > half_width, y, 0.0)
    return y if abs(_value(y)) > half_width else 0.0 * y


# ---------------------------------------------------------------------------

_EMPTY_IDX = np.zeros(0, dtype=np.intp)


@dataclass(frozen=True)
class RuleBase:
    """One two-input fuzzy controller u_fk(y0, yk) of eq. (30).

    Rules (i, j), i, j in {-upsilon..upsilon}; i indexes y0 (spacing delta0), j
    indexes yk (spacing deltak); nu_ij = N_m(y0 - i*delta0) * N_m(yk -
    j*deltak). theta is flat of length n_rules = (2U+1)**2 (R8) with
    flat_index(i, j) = (i+U)*(2U+1) + (j+U).

    Only the (m+1)**2 rules active at (y0, yk) (eq. 25) are ever touched.
    Inputs outside Omega_0 x Omega_k are valid: rules whose index falls outside
    -U..U are simply absent, so near/over the edges fewer (or no) rules are
    active, the weights no longer sum to one and u decays to 0 (the controller
    then switches to H_bar via zeta_k, eq. 37).  Adaptation (eq. 35) happens
    only for yk in Omega_k and |yk| > dead-zone half-width (default
    (m+1)/2*deltak, R4).
    """

    m: int
    upsilon: int
    delta0: float
    deltak: float
    dead_zone_half_width: float | None = None

    def __post_init__(self):
        _check_m(self.m, "m")
        U = self.upsilon
        if isinstance(U, bool) or not isinstance(U, (int, np.integer)) or U < 1:
            raise ValueError(f"upsilon must be an int >= 1, got {U!r}")
        d0 = _check_positive(self.delta0, "delta0")
        dk = _check_positive(self.deltak, "deltak")
        hw_max = U * dk
        if self.dead_zone_half_width is None:
            hw = 0.5 * (self.m + 1) * dk
            if hw > hw_max:
                raise ValueError(
                    f"dead_zone_half_width default (m+1)/2*deltak = {hw} "
                    f"must lie in [0, upsilon*deltak] = [0, {hw_max}]; "
                    "pass it explicitly or raise upsilon"
                )
        else:
            try:
                hw = float(self.dead_zone_half_width)
            except (TypeError, ValueError):
                hw = float("nan")
            if not (math.isfinite(hw) and 0.0 <= hw <= hw_max):
                raise ValueError(
                    "dead_zone_half_width must lie in [0, upsilon*deltak] = "
                    f"[0, {hw_max}], "
                    f"got {self.dead_zone_half_width!r}"
                )
        m = int(self.m)
        n = 2 * int(U) + 1
        p = np.arange(m + 1)
        # Precomputed caches (not dataclass fields).
        object.__setattr__(self, "_m", m)
        object.__setattr__(self, "_U", int(U))
        object.__setattr__(self, "_n", n)
        object.__setattr__(self, "_d0", d0)
        object.__setattr__(self, "_dk", dk)
        object.__setattr__(self, "_hw", hw)
        object.__setattr__(self, "_half", 0.5 * (m + 1))
        object.__setattr__(
            self, "_offsets", (p[:, None] * n + p[None, :]).ravel()
        )

    # -- layout ------------------------------------------------------------
    @property
    def n_rules(self) -> int:
        """(2*upsilon+1)**2 (R8)."""
        return self._n * self._n

    @property
    def omega0_half_width(self) -> float:
        return self._U * self._d0

    @property
    def omegak_half_width(self) -> float:
        return self._U * self._dk

    @property
    def resolved_dead_zone_half_width(self) -> float:
        """dead_zone_half_width, or its default (m+1)/2*deltak when None
        (R4)."""
        return self._hw

    def flat_index(self, i, j):
        """(i+U)*(2U+1) + (j+U); i indexes y0, j indexes yk."""
        return (np.asarray(i) + self._U) * self._n + (np.asarray(j) + self._U)

    def theta_grid(self, theta):
        """(2U+1, 2U+1) view of flat theta; grid[i+U, j+U] = theta_ij."""
        return np.asarray(theta).reshape(self._n, self._n)

    # -- evaluation ----------------------------------------------------------
    def _axis(self, y, delta, name):
        """(lo, weights) of the in-range active rules of one axis, or (None,
        ())."""
        yv = y.value() if hasattr(y, "value") else float(y)
        if not math.isfinite(yv):
            raise ValueError(f"{name} must be finite, got {yv!r}")
        s = yv / delta - self._half
        fl = math.floor(s)
        first = fl + 1
        f = (y / delta - self._half) - fl  # arithmetic on y: derivatives flow
        w = _active_weights(self._m, f)
        U = self._U
        last = first + self._m
        if first >= -U and last <= U:
            return first, w
        lo = max(first, -U)
        hi = min(last, U)
        if lo > hi:
            return None, ()
        return lo, w[lo - first : hi - first + 1]

    def active_rules(self, y0, yk):
        """(idx, nu): flat indices of the active rules inside -U..U and their
        weights.

        nu_ij = N_m(y0 - i*delta0) * N_m(yk - j*deltak); T-generic in nu.
        """
        # Plain numbers (numpy scalars included) as Python floats: the
        # scalar arithmetic below is then several times faster.
        plain = not (hasattr(y0, "value") or hasattr(yk, "value"))
        if plain:
            y0, yk = float(y0), float(yk)
        lo0, w0 = self._axis(y0, self._d0, "y0")
        lok, wk = self._axis(yk, self._dk, "yk")
        if lo0 is None or lok is None:
            return _EMPTY_IDX, np.zeros(0)
        base = (lo0 + self._U) * self._n + (lok + self._U)
        n0, nk = len(w0), len(wk)
        if n0 == nk == self._m + 1:
            idx = self._offsets + base
        else:
            idx = (
                np.arange(n0)[:, None] * self._n + np.arange(nk)[None, :]
            ).ravel() + base
        if plain:
            nu = np.array([a * b for a in w0 for b in wk])
        else:
            nu = np.multiply.outer(np.array(w0), np.array(wk)).ravel()
        return idx, nu

    def evaluate(self, theta, y0, yk):
        """u_fk = sum over active rules of nu_ij * theta_ij (eq. 30)."""
        idx, nu = self.active_rules(y0, yk)
        if len(idx) == 0:
            return 0.0 * yk
        return np.dot(np.asarray(theta)[idx], nu)

    def in_domain(self, yk) -> bool:
        """zeta_k of eq. (37): yk in Omega_k = [-U*deltak, U*deltak] (plain
        value)."""
        yv = yk.value() if hasattr(yk, "value") else float(yk)
        return abs(yv) <= self._U * self._dk

    def _rate(self, nu, yk, r):
        yv = yk.value() if hasattr(yk, "value") else float(yk)
        if abs(yv) <= self._U * self._dk and abs(yv) > self._hw:
            return (r * yk) * nu
        return np.zeros(len(nu)) if nu.dtype != object else (0.0 * yk) * nu

    def adaptation_rate(self, y0, yk, r):
        """(idx, dtheta) of eq. (35): dtheta = r*nu*dead_zone(yk) on the active
        rules.

        idx are the active rules (as active_rules); dtheta is zero when yk is in
        the dead zone or outside Omega_k.  Rules not in idx have zero rate.
        """
        idx, nu = self.active_rules(y0, yk)
        return idx, self._rate(nu, yk, r)

    def slope_rate(self, theta, max_slope: float, rate: float):
        """dtheta (n_rules) that pulls the learned surface's slope in yk
        back within ``max_slope``: adjacent weights along yk differ by at
        most c = max_slope * deltak (then |d u / d yk| <= max_slope, a
        B-spline's derivative being a convex combination of those
        differences over deltak); a difference d beyond it moves both
        weights towards each other at ``rate`` (1/s) times the excess
        (d - c sgn d). Zero while every slope is within the bound (and for
        ``max_slope`` inf). T-generic (the excess is chosen on values)."""
        theta = np.asarray(theta)
        out = np.zeros(
            theta.shape, dtype=object if theta.dtype == object else float
        )
        if not math.isfinite(max_slope):
            return out
        c = max_slope * self._dk
        grid = theta.reshape(self._n, self._n)
        d = grid[:, 1:] - grid[:, :-1]
        values = d if d.dtype != object else np.vectorize(_value)(d)
        over = np.abs(values) > c
        if not over.any():
            return out
        pull = np.zeros(d.shape, dtype=d.dtype)
        pull[over] = rate * (d[over] - c * np.sign(values[over]))
        rates = out.reshape(self._n, self._n)
        rates[:, :-1] += pull
        rates[:, 1:] -= pull
        return out

    def slope_rate_bound(self, r: float, yk0: float | None = None) -> float:
        """The largest |d/dt| (N s/m per s) that the adaptation (35) with
        gain ``r`` can give the surface's slope d u / d yk at ``yk0``
        (anywhere when None). The slope there is sum_ij nu0_i N_j'(yk0)
        theta_ij and (35) moves theta_ij at r yk nu0_i N_j(yk) on the
        active rules, so its rate is r yk (sum_i nu0_i nu0_i') (sum_j
        N_j'(yk0) N_j(yk)): |yk| <= upsilon deltak where (35) acts, the
        first sum <= 1 and the second <= max_j |N_j'(yk0)| (the N_j(yk)
        sum to at most 1), itself <= 1 / deltak for m >= 1 (N_m' is a
        difference of two order m - 1 B-splines, each in [0, 1], over
        deltak). At ``yk0`` only the yk whose rules overlap yk0's count:
        |yk| <= |yk0| + (m + 1) deltak too. m = 0: the surface is flat
        between knots, rate 0. The
        slope bound's pull is zero while every slope is within it, and a
        fuzzy weight below 1 only scales the rate down."""
        if self._m == 0:
            return 0.0
        reach = self._U * self._dk
        if yk0 is None:
            steepest = 1.0 / self._dk
        else:
            reach = min(reach, abs(yk0) + (self._m + 1) * self._dk)
            j = np.arange(-self._U, self._U + 1)
            steepest = float(
                np.max(
                    np.abs(
                        bspline_membership_derivative(
                            yk0 - j * self._dk, self._m, self._dk
                        )
                    )
                )
            )
        return float(r * reach * steepest)

    def evaluate_and_rate(self, theta, y0, yk, r):
        """(u, idx, dtheta) = evaluate(...) and adaptation_rate(...),
        memberships once."""
        idx, nu = self.active_rules(y0, yk)
        if len(idx) == 0:
            return 0.0 * yk, idx, nu
        u = np.dot(np.asarray(theta)[idx], nu)
        return u, idx, self._rate(nu, yk, r)
