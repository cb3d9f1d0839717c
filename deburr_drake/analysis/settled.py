"""Has the run settled into steady cutting? Pure numpy over a run's logged
signals (no Drake): the test ``analyze`` applies before it linearizes
anything, so that it never linearizes a limit cycle.

Steady cutting over a window (``SettleTolerances.window`` seconds before
the analysed time):

- in contact throughout: depth > 0 and ||f_n|| above the contact force;
- no oscillation: the *fast part* of each signal (its deviation from a
  centred moving average over ``SettleTolerances.average`` seconds, 10
  outer-loop periods: everything faster than about 2 Hz) has an RMS within
  its tolerance, stated relative to the task so that it holds for any
  scenario: the depth within ``depth`` x delta*, the measured normal and
  chamfering forces within ``force`` x the desired chamfering force, the
  tool speed along n2 within ``speed`` x the default feed v0, the
  controller's s on its fuzzy axes within lambda_k x ``depth`` x delta*
  (s = edot + lambda e: an oscillation of the depth error of that size);
- no growing oscillation: the fast part's RMS over the window's four
  quarters does not rise from quarter to quarter to more than ``growth``
  times the first and above the tolerance, in two signals or more (a
  mode of the loop moves several of its signals; the feed's slow-down at a
  burr's entry moves the chamfering force alone, rising over a second).
  An oscillation whose latest quarter is still within the tolerance is
  not growth, however fast it rose: a mode that keeps growing crosses the
  tolerance in a later window, one that levels off below it is steady
  cutting. The test catches a growth that has crossed the tolerance before
  the whole window's RMS does.

A slow drift (the depth converging, the feed slowing on a burr) is not an
oscillation: the moving average follows it. A run that fails is described
by :func:`describe_oscillation` (its frequency, start, amplitude, growth)
and :func:`first_guard_trip` (the runtime guard that would have stopped
it).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np

__all__ = [
    "SettleTolerances",
    "RunSignals",
    "SettleCheck",
    "settle_check",
    "describe_oscillation",
    "first_guard_trip",
    "scan_run",
    "fast_part",
]


@dataclass
class SettleTolerances:
    """The stated tolerances of steady cutting (see the module
    docstring); relative ones multiply the task's own scales."""

    window: float = 1.0  # s, before the analysed time
    average: float = 0.25  # s, the moving average the fast part leaves out
    depth: float = 0.02  # x desired depth (RMS of the fast part)
    force: float = 0.05  # x desired chamfering force
    speed: float = 0.1  # x the default feed v0
    growth: float = 2.0  # last-quarter over first-quarter RMS
    contact_force: float = 0.5  # N, ||f_n|| above it is contact


@dataclass
class RunSignals:
    """The signals the test reads, one row per logged sample (SI)."""

    t: np.ndarray  # s
    depth: np.ndarray  # m
    normal_force: np.ndarray  # N, ||f_n|| measured
    chamfering_force: np.ndarray  # N, ||f_t|| measured
    speed: np.ndarray  # m/s, tool speed along n2
    s: np.ndarray  # m/s, (samples, axes): the controller's s on its
    # fuzzy axes
    arc_position: np.ndarray  # m
    # the task's scales
    desired_depth: float
    desired_force: float
    default_feed: float
    sliding_lambda: np.ndarray  # 1/s, per column of s

    @classmethod
    def from_log(cls, log, scenario) -> "RunSignals":
        """From a :class:`deburr_drake.runs.simulation.RunLog` (or the
        same nested dict of arrays) and its scenario."""
        ch, co = log["chamfer"], log["controller"]
        n = min(len(ch["t"]), len(co["t"]))
        axes = list(scenario.controller.fuzzy.axes) or [0, 1, 2]
        lam = np.asarray(scenario.controller.sliding_lambda, float)[axes]
        return cls(
            t=np.asarray(ch["t"][:n], float),
            depth=np.asarray(ch["delta"][:n], float),
            normal_force=np.asarray(ch["f_n"][:n], float),
            chamfering_force=np.asarray(ch["f_t"][:n], float),
            speed=np.sum(
                np.asarray(ch["n2"][:n]) * np.asarray(ch["xdot_p"][:n]), axis=1
            ),
            s=np.asarray(co["s"][:n], float)[:, axes],
            arc_position=np.asarray(ch["arc_position"][:n], float),
            desired_depth=scenario.task.desired_depth,
            desired_force=scenario.task.desired_chamfering_force,
            default_feed=scenario.command.default_feed,
            sliding_lambda=lam,
        )

    def tolerances(self, tol: SettleTolerances) -> Dict[str, float]:
        """Per signal, the RMS the fast part may have (SI)."""
        out = {
            "depth": tol.depth * self.desired_depth,
            "normal_force": tol.force * self.desired_force,
            "chamfering_force": tol.force * self.desired_force,
            "speed": tol.speed * self.default_feed,
        }
        for k, lam in enumerate(self.sliding_lambda):
            out[f"s[{k}]"] = lam * tol.depth * self.desired_depth
        return out

    def series(self) -> Dict[str, np.ndarray]:
        out = {
            "depth": self.depth,
            "normal_force": self.normal_force,
            "chamfering_force": self.chamfering_force,
            "speed": self.speed,
        }
        for k in range(self.s.shape[1]):
            out[f"s[{k}]"] = self.s[:, k]
        return out


#: Units of the signals in messages (value scale, unit).
_UNITS = {
    "depth": (1e3, "mm"),
    "normal_force": (1.0, "N"),
    "chamfering_force": (1.0, "N"),
    "speed": (1e3, "mm/s"),
}


def _fmt(name, value):
    scale, unit = _UNITS.get(name, (1e3, "mm/s"))
    return f"{value * scale:.3g} {unit}"


def fast_part(t, x, average: float) -> np.ndarray:
    """x minus its centred moving average over ``average`` seconds (the
    ends use the part of the average that exists)."""
    x = np.asarray(x, float)
    if len(t) < 2:
        return np.zeros_like(x)
    dt = float(np.median(np.diff(t)))
    n = 2 * int(round(average / dt / 2)) + 1  # odd: centred
    # No longer than x (np.convolve's "same" is as long as the longer).
    n = min(n, 2 * ((len(x) - 1) // 2) + 1)
    kernel = np.ones(n)
    total = np.convolve(x, kernel, mode="same")
    count = np.convolve(np.ones_like(x), kernel, mode="same")
    return x - total / count


@dataclass
class SettleCheck:
    """The outcome of :func:`settle_check` over [start, end]."""

    settled: bool
    start: float  # s
    end: float  # s
    reasons: List[str] = field(default_factory=list)
    fast_rms: Dict[str, float] = field(default_factory=dict)  # SI
    tolerance: Dict[str, float] = field(default_factory=dict)  # SI
    growth: Dict[str, float] = field(default_factory=dict)

    def to_dict(self):
        return {
            "settled": self.settled,
            "window": [self.start, self.end],
            "reasons": self.reasons,
            "fast_rms": self.fast_rms,
            "tolerance": self.tolerance,
            "growth": self.growth,
        }


def _rms(x):
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else 0.0


def settle_check(
    sig: RunSignals,
    end: float,
    tol: SettleTolerances = SettleTolerances(),
    *,
    window: Optional[float] = None,
) -> SettleCheck:
    """Steady cutting over [end - window, end] (module docstring)."""
    window = tol.window if window is None else window
    start = end - window
    # The fast part is taken over a margin around the window so that its
    # ends see a full average.
    margin = tol.average
    around = (sig.t >= start - margin) & (sig.t <= end + margin)
    inside = (sig.t[around] >= start) & (sig.t[around] <= end)
    check = SettleCheck(True, start, end, tolerance=sig.tolerances(tol))
    if inside.sum() < 8:
        check.settled = False
        check.reasons.append(
            f"the run has too few samples in [{start:.3f}, {end:.3f}] s"
        )
        return check
    t = sig.t[around]
    depth = sig.depth[around][inside]
    fn = sig.normal_force[around][inside]
    if not (np.all(np.isfinite(depth)) and np.all(np.isfinite(fn))):
        check.settled = False
        check.reasons.append("non-finite signals")
        return check
    lost = (depth <= 0) | (fn <= tol.contact_force)
    if lost.any():
        check.settled = False
        check.reasons.append(
            f"out of contact in {100 * lost.mean():.1f} % of the window "
            f"(depth <= 0 or ||f_n|| <= {tol.contact_force:g} N)"
        )
    growing = []
    for name, x in sig.series().items():
        r = fast_part(t, x[around], tol.average)[inside]
        rms = _rms(r)
        limit = check.tolerance[name]
        check.fast_rms[name] = rms
        quarters = [_rms(q) for q in np.array_split(r, 4)]
        g = (
            quarters[-1] / quarters[0]
            if quarters[0] > 0
            else (np.inf if quarters[-1] > 0 else 1.0)
        )
        check.growth[name] = float(g)
        rising = all(b > a for a, b in zip(quarters, quarters[1:]))
        if not rms <= limit:
            check.settled = False
            check.reasons.append(
                f"{name} oscillates: fast part RMS {_fmt(name, rms)} > "
                f"{_fmt(name, limit)}"
            )
        elif rising and g > tol.growth and quarters[-1] > limit:
            growing.append(
                f"{name} oscillation grows {g:.2f} x over "
                f"{0.75 * window:g} s (RMS {_fmt(name, quarters[-1])})"
            )
    if len(growing) >= 2:
        check.settled = False
        check.reasons += growing
    return check


def scan_run(
    sig: RunSignals,
    start: float,
    end: float,
    tol: SettleTolerances = SettleTolerances(),
    *,
    step: float = 0.5,
) -> Optional[SettleCheck]:
    """The first window of length ``tol.window`` ending in (start, end]
    (every ``step`` s) that is not steady, or None."""
    t = start + tol.window
    while t <= end + 1e-9:
        check = settle_check(sig, t, tol)
        if not check.settled:
            return check
        t += step
    return None


def describe_oscillation(
    sig: RunSignals,
    after: float,
    tol: SettleTolerances = SettleTolerances(),
    *,
    block: float = 0.1,
) -> Dict:
    """What the run shows after ``after`` (s, e.g. the first contact):
    the chamfering force's fast part in blocks of ``block`` s; the start
    is the first block whose RMS exceeds the force tolerance (None if
    none); the frequency is the largest peak of its spectrum from the
    start on; the amplitude is max |f_t| from the start (N, measured);
    the growth is the RMS ratio per second over the first second after
    the start (before saturation)."""
    keep = sig.t >= after
    t = sig.t[keep]
    f = sig.chamfering_force[keep]
    out = {
        "start_time": None,
        "frequency_hz": None,
        "amplitude_N": None,
        "growth_per_s": None,
        "rms_N": None,
        "sustained": False,
    }
    if len(t) < 8:
        return out
    r = fast_part(t, f, tol.average)
    limit = tol.force * sig.desired_force
    edges = np.arange(t[0], t[-1] + block, block)
    rms = []
    for a in edges[:-1]:
        m = (t >= a) & (t < a + block)
        rms.append(_rms(r[m]) if m.any() else 0.0)
    rms = np.array(rms)
    over = rms > limit
    hold = max(1, int(round(0.5 / block)))  # sustained for 0.5 s
    sustained = [
        k
        for k in range(len(rms))
        if over[k : k + hold].all() and k + hold <= len(rms)
    ]
    out["sustained"] = bool(sustained)
    if sustained:
        k0 = int(sustained[0])
    elif over.any():  # over the tolerance, but never for 0.5 s
        k0 = int(np.argmax(over))
    else:
        return out
    t0 = float(edges[k0])
    out["start_time"] = t0
    after0 = t >= t0
    if after0.sum() >= 8:
        x = r[after0] - np.mean(r[after0])
        dt = float(np.median(np.diff(t)))
        spectrum = np.abs(np.fft.rfft(x * np.hanning(len(x))))
        freqs = np.fft.rfftfreq(len(x), dt)
        spectrum[freqs < 1.0 / tol.average] = 0.0
        out["frequency_hz"] = float(freqs[int(np.argmax(spectrum))])
    out["amplitude_N"] = float(np.max(np.abs(f[after0])))
    out["rms_N"] = float(np.max(rms[k0:]))
    # growth: from the start block to the first block at 90 % of the
    # largest RMS (None when it is already there: a limit cycle)
    k1 = k0 + int(np.argmax(rms[k0:] >= 0.9 * out["rms_N"]))
    if k1 > k0 and rms[k0] > 0:
        span = (k1 - k0) * block
        out["growth_per_s"] = float((rms[k1] / rms[k0]) ** (1.0 / span))
        out["growth"] = {
            "from_N": float(rms[k0]),
            "to_N": float(rms[k1]),
            "t0": t0,
            "t1": float(edges[k1]),
        }
    return out


# Each guard's first trip in logged samples t: (time, guard, value, limit,
# detail), or None.
def _torque_trip(t, actuation, effort_limits, torque_fraction, names):
    tau = np.abs(np.asarray(actuation, float))
    lim = np.asarray(effort_limits, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(np.isfinite(lim), tau / lim, 0.0)
    bad = np.flatnonzero(np.any(ratio > torque_fraction, axis=1))
    if not bad.size:
        return None
    i = int(bad[0])
    j = int(np.argmax(ratio[i]))
    name = names[j] if names is not None else f"joint {j}"
    return (
        t[i],
        "joint_torque",
        float(tau[i, j]),
        float(torque_fraction * lim[j]),
        f"{name} |tau| = {tau[i, j]:.4g} N m > "
        f"{torque_fraction:g} x effort limit "
        f"{lim[j]:.4g} N m",
    )


def _tool_force_trip(t, tool_force, tool_force_limit):
    mag = np.linalg.norm(np.asarray(tool_force, float), axis=1)
    bad = np.flatnonzero(mag > tool_force_limit)
    if not bad.size:
        return None
    i = int(bad[0])
    return (
        t[i],
        "tool_force",
        float(mag[i]),
        float(tool_force_limit),
        f"|f| = {mag[i]:.4g} N > {tool_force_limit:.4g} N",
    )


def _depth_trip(t, depth, true_depth, depth_limit):
    d = np.asarray(depth, float)
    if true_depth is not None:
        d = np.maximum(d, np.asarray(true_depth, float))
    bad = np.flatnonzero(d > depth_limit)
    if not bad.size:
        return None
    i = int(bad[0])
    return (
        t[i],
        "depth",
        float(d[i]),
        float(depth_limit),
        f"delta = {d[i] * 1e3:.4g} mm > {depth_limit * 1e3:.4g} mm",
    )


def _workspace_trip(t, x_p, workspace_low, workspace_high):
    x = np.asarray(x_p, float)
    out = np.any((x < workspace_low) | (x > workspace_high), axis=1)
    bad = np.flatnonzero(out)
    if not bad.size:
        return None
    i = int(bad[0])
    return (
        t[i],
        "workspace",
        None,
        None,
        f"tool tip {np.round(x[i], 4).tolist()} m outside the workspace box",
    )


def _contact_lost_trip(t, normal_force, contact_force, contact_lost_time):
    fn = np.asarray(normal_force, float)
    on = fn > contact_force
    if not on.any():
        return None
    first = int(np.argmax(on))
    lost_since = None
    for i in range(first, len(t)):
        if on[i]:
            lost_since = None
        elif lost_since is None:
            lost_since = t[i]
        elif t[i] - lost_since > contact_lost_time:
            return (
                t[i],
                "contact_lost",
                float(fn[i]),
                float(contact_force),
                f"||f_n|| <= {contact_force:g} N for more"
                f" than {contact_lost_time:g} s (since "
                f"{lost_since:.3f} s)",
            )
    return None


def first_guard_trip(
    t,
    *,
    actuation=None,
    effort_limits=None,
    torque_fraction: float = 1.0,
    tool_force=None,
    tool_force_limit: float = np.inf,
    depth=None,
    true_depth=None,
    depth_limit: float = np.inf,
    x_p=None,
    workspace_low=None,
    workspace_high=None,
    normal_force=None,
    contact_force: float = 1.0,
    contact_lost_time: float = np.inf,
    names=None,
) -> Optional[Dict]:
    """The first logged sample at which a runtime guard
    (:mod:`deburr_drake.cell.guards`) would have tripped, from logs of a
    run without guards: {guard, time, value, limit, detail}, or None. The
    checks are the guards' own (their limits from
    :func:`deburr_drake.cell.guards.guard_limits`), at every logged
    sample rather than every ``check_period``."""
    t = np.asarray(t, float)
    trips = []
    if actuation is not None and effort_limits is not None:
        trips.append(
            _torque_trip(t, actuation, effort_limits, torque_fraction, names)
        )
    if tool_force is not None:
        trips.append(_tool_force_trip(t, tool_force, tool_force_limit))
    if depth is not None:
        trips.append(_depth_trip(t, depth, true_depth, depth_limit))
    if x_p is not None and workspace_low is not None:
        trips.append(_workspace_trip(t, x_p, workspace_low, workspace_high))
    if normal_force is not None and np.isfinite(contact_lost_time):
        trips.append(
            _contact_lost_trip(
                t, normal_force, contact_force, contact_lost_time
            )
        )
    trips = [trip for trip in trips if trip is not None]
    if not trips:
        return None
    time, guard, value, limit, detail = min(trips, key=lambda x: x[0])
    return {
        "guard": guard,
        "time": float(time),
        "value": value,
        "limit": limit,
        "detail": detail,
    }
