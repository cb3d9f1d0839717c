"""``analyze``: the verdict on the run the user will run and, when it
settles into steady cutting, the analysis at its operating point, along
the run and over the uncertain parameters, as a plain dict (what
``analysis.json`` holds; :mod:`deburr_drake.analysis.report` writes it,
its one-screen summary and its figures)."""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Callable, Dict, Optional

import numpy as np

from deburr_drake.analysis.along import (
    DEFAULT_SPACING,
    RhoPoint,
    analysis_run,
    guard_that_would_stop,
    rho_of_map,
)
from deburr_drake.analysis.frequency import normal_force_loop
from deburr_drake.analysis.linearization import (
    eq8_time_constant,
    linearize_closed_loop,
)
from deburr_drake.analysis.operating_point import (
    DEFAULT_TIME_AFTER_CONTACT,
    frozen_scenario,
)
from deburr_drake.analysis.robust import robust_margin
from deburr_drake.analysis.sampled import sampled_loop
from deburr_drake.analysis.settled import (
    SettleTolerances,
    describe_oscillation,
    scan_run,
    settle_check,
)
from deburr_drake.cell.truth import contact_truth
from deburr_drake.config import Scenario

__all__ = [
    "analyze",
    "SUMMARY_KEYS",
]

#: What the linear models at the operating point hold constant.
FROZEN = (
    "outer loop (command generator, first-order hold)",
    "adaptation (estimator c-hat, fuzzy theta)",
    "sensor noise",
)
#: Keys analysis.json always holds (null where the run gives no value:
#: no linearization of a run that is not steady).
SUMMARY_KEYS = (
    "verdict",
    "verdict_reason",
    "numerics",
    "rho_along_run",
    "robust",
    "eigenvalues",
    "depth_time_constant_s",
    "depth_time_constant_eq8_s",
    "sampled_spectral_radius",
    "gain_margin_dB",
    "phase_margin_deg",
    "operating_point",
)


def _oscillation_reason(osc: Dict, guard: Optional[Dict]) -> str:
    parts = []
    if osc.get("start_time") is not None:
        parts.append(f"from t = {osc['start_time']:.2f} s")
    if osc.get("frequency_hz") is not None:
        parts.append(f"{osc['frequency_hz']:.1f} Hz")
    if osc.get("amplitude_N") is not None:
        parts.append(f"|f_t| up to {osc['amplitude_N']:.1f} N (measured)")
    g = osc.get("growth")
    if g:
        parts.append(
            f"growing {g['from_N']:.2g} -> {g['to_N']:.3g} N RMS "
            f"from {g['t0']:.2f} to {g['t1']:.2f} s "
            f"(x {osc['growth_per_s']:.3g} per s)"
        )
    elif osc.get("rms_N") is not None:
        parts.append(f"sustained, {osc['rms_N']:.3g} N RMS (a limit cycle)")
    text = "the run oscillates" + (": " + ", ".join(parts) if parts else "")
    if guard:
        text += (
            f"; the guard {guard['guard']} would have stopped it at "
            f"t = {guard['time']:.3f} s ({guard['detail']})"
        )
    return text


def analyze(
    scenario: Scenario,
    *,
    at: float | None = None,
    after_contact: float = DEFAULT_TIME_AFTER_CONTACT,
    overrides: Optional[Dict[str, float]] = None,
    until: Optional[float] = None,
    spacing: float = DEFAULT_SPACING,
    robust: bool = True,
    numerics: str = "refined",
    progress: Optional[Callable[[str], None]] = None,
) -> Dict:
    """The verdict on the run the user will run and, only if it settles
    into steady cutting, the analysis at its operating point (modes and
    eq. (8), the one-period map's rho, the normal-force loop's margins),
    rho along the run and the robust margin: the dict of analysis.json (SI
    units), the live objects under ``"_objects"`` (for figures).

    ``verdict``: "unstable" when the run oscillates at ``at`` or later
    (:mod:`deburr_drake.analysis.settled`) or rho >= 1 at a steady point
    along it; "not settled" out of contact without oscillating; else
    "stable"; ``verdict_reason`` says why. ``overrides`` (dotted fields)
    apply at the operating point only (a what-if; the verdict is the
    run's). ``numerics`` ("refined" or "shipped",
    :func:`deburr_drake.analysis.along.at_numerics`) is how the run, its
    maps and the models are integrated; the result says which."""
    overrides = dict(overrides or {})
    say = progress or (lambda message: None)
    tol = SettleTolerances()
    # The run as the user will run it (guards off), at the verdict's
    # numerics, mapped along the way.
    say(
        f"the run: simulating the scenario (guards off) at the {numerics} "
        "numerics, with the one-period map at points along it"
    )
    run = analysis_run(
        scenario,
        at=at,
        after_contact=after_contact,
        until=until,
        spacing=spacing,
        numerics=numerics,
        progress=say,
    )
    # From here on the scenario as run: at the verdict's numerics.
    scenario = run.analysed
    timings = {
        "run_s": run.wall_time_s - run.map_time_s,
        "maps_along_run_s": run.map_time_s,
    }
    result = _run_header(scenario, run, overrides, tol)
    result["_objects"] = {"run": run}
    # Steady at the analysed time? The run's own signals say.
    check = _operating_point_check(run, at, after_contact, tol)
    result["settle_check"] = check.to_dict()
    guard = guard_that_would_stop(run, scenario)
    result["guard_that_would_stop"] = guard
    # The verdict the run gives by itself: not steady, or not staying so.
    result.update(_run_verdict(run, check, guard, tol))
    # A limit cycle is not an operating point: nothing to linearize.
    if not check.settled:
        return _not_settled(result, run, timings, say)
    # In steady cutting: the operating point's linear models, rho along
    # the run and the robust margin.
    keys, models = _steady_analysis(
        scenario,
        run,
        overrides,
        robust=robust,
        tol=tol,
        decided=result["verdict"] is not None,
        say=say,
        timings=timings,
    )
    result.update(keys, timings_s=timings)
    result["_objects"].update(models)
    return result


def _not_settled(result, run, timings, say) -> Dict:
    """``result`` of a run not steady at the analysed time: a limit cycle
    is not an operating point, so nothing is linearized."""
    result.update(_unsettled_keys(run), timings_s=timings)
    say(
        "not steady at the analysed time: no linearization (a limit "
        "cycle is not an operating point)"
    )
    return result


def _unsettled_keys(run) -> Dict:
    """What a run not steady at the analysed time gives: where it was
    analysed and the maps along it (those not steady without rho)."""
    return {
        "operating_point": run.op.summary() if run.op is not None else None,
        "rho_along_run": [p.to_dict() for p in run.points],
        "robust": None,
    }


def _steady_analysis(
    scenario, run, overrides, *, robust, tol, decided, say, timings
):
    """The keys of a run steady at its operating point (the verdict too
    unless ``decided``) and the live models (for figures)."""
    # The operating point: its linearization, one-period map and margins.
    truth = contact_truth(scenario)
    lin, tau_eq8, sampled, loop, tangential = _operating_point_models(
        scenario, run.op, truth, overrides, say, timings
    )
    keys = {
        **_continuous_result(run.op, truth, lin, tau_eq8),
        **_sampled_result(sampled, loop, tangential),
    }
    # rho along the run, the operating point's own map among its points.
    points = _points_with_operating_point(run, sampled, overrides)
    steady = [p for p in points if p.rho is not None]
    keys["rho_along_run"] = [p.to_dict() for p in points]
    keys["frozen"] = list(FROZEN)
    # The smallest margin along the run decides a steady run's verdict.
    weakest = max(steady, key=lambda p: p.rho) if steady else None
    keys.update(_smallest_margins(steady))
    if not decided:
        keys.update(_steady_verdict(run, steady, tol))
    # The robust margin at the weakest point.
    keys["robust"] = (
        _robust_at(scenario, run, weakest, say, timings)
        if robust and weakest is not None
        else None
    )
    return keys, {
        "op": run.op,
        "linearization": lin,
        "sampled": sampled,
        "loop": loop,
    }


def _run_header(scenario, run, overrides, tol) -> Dict:
    """The result's first keys: what was run, then SUMMARY_KEYS (None
    until found)."""
    result = {
        "scenario": scenario.name,
        "overrides_at_operating_point": overrides,
        "run": {
            "contact_time": run.contact_time,
            "end_time": run.end_time,
            "stop_reason": run.stop_reason,
            "stop_detail": run.stop_detail,
            "divergence_time": run.end_time
            if run.stop_reason == "diverged"
            else None,
            "guards": "off in the run; the first one that would have "
            "tripped is named",
        },
        "numerics": {
            **run.numerics,
            "run_wall_time_s": run.wall_time_s,
        },
        "settle_tolerances": dataclasses.asdict(tol),
    }
    for key in SUMMARY_KEYS:
        result.setdefault(key, None)
    return result


def _operating_point_check(run, at, after_contact, tol):
    """The settle check at the operating point, or, without one, at the
    run's end and failed with why there is none."""
    if run.op is not None:
        return settle_check(run.signals, run.op.time, tol)
    check = settle_check(run.signals, run.end_time, tol)
    check.settled = False
    start = at if at is not None else run.contact_time + after_contact
    check.reasons.append(
        run.op_note
        or (
            f"no steady operating point from {start:.3f} s to the end of "
            f"the run ({run.end_time:.3f} s, {run.stop_reason})"
        )
    )
    return check


def _run_verdict(run, check, guard, tol) -> Dict:
    """``verdict``, ``verdict_reason`` and ``oscillation`` from the run
    alone: unstable or not settled when it is not steady at the analysed
    time, unstable when it stops being steady later by a sustained (or
    final) oscillation; empty while the run is steady throughout (the
    maps along it decide)."""
    sig, op = run.signals, run.op
    if run.stop_reason == "diverged":
        osc = describe_oscillation(sig, run.contact_time + 0.5, tol)
        return {
            "oscillation": osc,
            "verdict": "unstable",
            "verdict_reason": (
                f"the run diverged at t = {run.end_time:.3f} s "
                f"({run.stop_detail}); " + _oscillation_reason(osc, guard)
            ),
        }
    final = settle_check(sig, run.end_time, tol)
    if check.settled:
        late = scan_run(sig, op.time, run.end_time, tol)
        if late is None:
            return {}
        osc = describe_oscillation(sig, late.start, tol)
        if osc["start_time"] is None or not (
            osc.get("sustained") or not final.settled
        ):
            return {}  # a passing transient (a burr's entry)
        return {
            "oscillation": osc,
            "verdict": "unstable",
            "verdict_reason": (
                f"steady at the analysed time {op.time:.3f} s but not over "
                f"[{late.start:.2f}, {late.end:.2f}] s: "
                + "; ".join(late.reasons[:2])
                + "; "
                + _oscillation_reason(osc, guard)
            ),
        }
    osc = describe_oscillation(sig, run.contact_time + 0.5, tol)
    transient = op is not None and final.settled
    if run.stop_reason in ("nan", "error"):
        verdict = "unstable"
        reason = (
            f"the run failed at {run.end_time:.3f} s "
            f"({run.stop_detail}); " + _oscillation_reason(osc, guard)
        )
    elif transient or (op is None and run.op_note):
        verdict = "not settled"
        reason = (
            f"not steady over [{check.start:.3f}, {check.end:.3f}] s: "
            + "; ".join(check.reasons[:3])
            + (
                f"; steady at the end of the run ({run.end_time:.2f} s):"
                " analyse a later time (--at)"
                if transient
                else ""
            )
        )
    else:
        verdict = "unstable"
        where = (
            f"not steady over [{check.start:.3f}, "
            f"{check.end:.3f}] s and at the end of the run: "
            if op is not None
            else "never steady from the analysed time to the end of "
            f"the run; over its last {tol.window:g} s: "
        )
        reason = (
            where
            + "; ".join(check.reasons[:2])
            + "; "
            + _oscillation_reason(osc, guard)
        )
    return {"verdict": verdict, "verdict_reason": reason, "oscillation": osc}


def _points_with_operating_point(run, sampled, overrides) -> list:
    """The run's points in time order, with the operating point's map
    among them unless ``overrides`` make it a point of another run."""
    points = list(run.points)
    if not overrides:
        op = run.op
        r = rho_of_map(sampled.Phi, sampled.period)
        points.append(
            RhoPoint(
                t=op.time,
                arc_position=op.signals["arc_position"],
                kind="operating point",
                rho=r["rho"],
                frequency_hz=r["frequency_hz"],
                decay_rate=r["decay_rate"],
                rho_oscillatory=r["rho_oscillatory"],
                burr_area=op.signals["burr_area"],
                context=op.context,
            )
        )
    points.sort(key=lambda p: p.t)
    return points


def _operating_point_models(scenario, op, truth, overrides, say, timings):
    """At ``op`` (``overrides`` applied): the continuous linearization,
    eq. (8)'s depth time constant, the sampled loop's one-period map and
    its normal and tangential force loops; their times into ``timings``."""
    t1 = time.perf_counter()
    say("continuous-time linearization")
    lin = linearize_closed_loop(
        op, stiffness=truth.local_stiffness, **overrides
    )
    timings["linearization_s"] = time.perf_counter() - t1
    analysed = frozen_scenario(scenario, **overrides)
    tau_eq8 = eq8_time_constant(
        analysed.controller.depth_gain, truth.local_stiffness, truth.c2
    )
    t2 = time.perf_counter()
    say("one-period map of the sampled loop at the operating point")
    sampled = sampled_loop(op, **overrides)
    loop = normal_force_loop(sampled)
    tangential = normal_force_loop(sampled, direction=sampled.n2)
    timings["sampled_map_s"] = time.perf_counter() - t2
    return lin, tau_eq8, sampled, loop, tangential


def _continuous_result(op, truth, lin, tau_eq8) -> Dict:
    """The operating point, the contact truth, the continuous modes and
    the depth time constant against eq. (8)'s."""
    return {
        "operating_point": op.summary(),
        "contact_truth": {
            "local_stiffness": truth.local_stiffness,
            "secant_stiffness": truth.secant_stiffness,
            "c0": truth.c0,
            "c2": truth.c2,
        },
        "eigenvalues": [
            [float(e.real), float(e.imag)] for e in lin.eigenvalues
        ],
        "modes": [
            {
                "group": m.group,
                "re": m.eigenvalue.real,
                "im": m.eigenvalue.imag,
                "natural_frequency_rad_s": m.natural_frequency,
                "damping_ratio": m.damping_ratio,
                "time_constant_s": m.time_constant,
            }
            for m in lin.modes
        ],
        "depth_time_constant_s": lin.depth_time_constant,
        "depth_time_constant_eq8_s": tau_eq8,
        "depth_time_constant_error_rel": abs(lin.depth_time_constant - tau_eq8)
        / tau_eq8,
    }


def _sampled_result(sampled, loop, tangential) -> Dict:
    """The one-period map's eigenvalues and the normal and tangential
    force loops' margins."""
    z_eigs = sampled.eigenvalues
    z_eigs = z_eigs[np.argsort(-np.abs(z_eigs))]
    worst = z_eigs[0]
    return {
        "sampled_period_s": sampled.period,
        "sampled_spectral_radius": sampled.spectral_radius,
        "sampled_dominant_eigenvalue": [float(worst.real), float(worst.imag)],
        "sampled_dominant_frequency_hz": float(
            abs(np.angle(worst)) / (2 * np.pi * sampled.period)
        ),
        "sampled_eigenvalues": [[float(e.real), float(e.imag)] for e in z_eigs],
        "gain_margin_dB": loop.gain_margin_dB,
        "phase_margin_deg": loop.phase_margin_deg,
        "phase_crossover_hz": loop.phase_crossover_hz,
        "gain_crossover_hz": loop.gain_crossover_hz,
        "tangential_gain_margin_dB": tangential.gain_margin_dB,
        "tangential_phase_margin_deg": tangential.phase_margin_deg,
    }


def _smallest_margins(steady) -> Dict:
    """The steady point of largest rho and that of the largest |z| of the
    oscillatory modes (``smallest_margin`` None without steady points)."""
    if not steady:
        return {"smallest_margin": None}
    w = max(steady, key=lambda p: p.rho)
    o = max(steady, key=lambda p: p.rho_oscillatory)
    return {
        "smallest_margin": {
            "rho": w.rho,
            "margin": 1.0 - w.rho,
            "t": w.t,
            "arc_position": w.arc_position,
            "kind": w.kind,
            "frequency_hz": w.frequency_hz,
            "decay_rate_per_s": w.decay_rate,
        },
        "smallest_oscillatory_margin": {
            "rho_oscillatory": o.rho_oscillatory,
            "t": o.t,
            "arc_position": o.arc_position,
            "kind": o.kind,
        },
    }


def _refuted(point, run, tol) -> bool:
    """Whether the run after ``point`` refutes its map's rho >= 1: the
    frozen loop there would have grown more than ``tol.growth`` over the
    rest of the run, and the run, steady throughout, did not. A frozen map
    stands for the loop only while the loop stays near that point (a burr
    passes, the adaptation moves on); a mode slow enough to show only
    after the run ends stays unrefuted."""
    if point.decay_rate is None or point.rho < 1.0:
        return False
    growth = math.exp(-point.decay_rate * (run.end_time - point.t))
    return growth > tol.growth


def _steady_verdict(run, steady, tol) -> Dict:
    """The verdict of a run steady throughout: unstable if the sampled
    loop is (rho >= 1) at a steady point whose growth the run after it
    cannot refute (:func:`_refuted`), else stable."""
    op = run.op
    refuted = [p for p in steady if _refuted(p, run, tol)]
    standing = [p for p in steady if p not in refuted]
    w = max(standing, key=lambda p: p.rho) if standing else None
    if w is not None and w.rho >= 1.0:
        return {
            "verdict": "unstable",
            "verdict_reason": (
                f"the run is steady, but the sampled loop is unstable at "
                f"t = {w.t:.2f} s ({w.kind}, arc "
                f"{w.arc_position * 1e3:.1f} mm): rho = {w.rho:.5f}, "
                f"dominant eigenvalue at {w.frequency_hz:.1f} Hz"
            ),
        }
    reason = (
        f"steady cutting at {op.time:.3f} s (all signals within "
        f"their tolerances over the {tol.window:g} s before) and "
        f"to the end of the run ({run.end_time:.2f} s, "
        f"{run.stop_reason}); rho < 1 at all {len(standing)} steady "
        "points along it"
        + (
            f", largest {w.rho:.5f} at t = {w.t:.2f} s ({w.kind})"
            if w is not None
            else ""
        )
    )
    for p in refuted:
        grown = math.exp(-p.decay_rate * (run.end_time - p.t))
        reason += (
            f"; rho = {p.rho:.5f} at t = {p.t:.2f} s ({p.kind}) predicts "
            f"growth x {grown:.3g} by the run's end, which the run does "
            "not show: that map's loop did not last"
        )
    return {"verdict": "stable", "verdict_reason": reason}


def _robust_at(scenario, run, point, say, timings) -> Dict:
    """The robust margin over the uncertain parameters' ranges from the
    run's Context at ``point``; its time into ``timings``."""
    t0 = time.perf_counter()
    say("robust margin over the uncertain parameters' ranges")
    robust = robust_margin(
        scenario,
        run.diagram,
        point.context,
        on_burr=point.burr_area > 0,
        progress=say,
    )
    robust["point"] = {
        "t": point.t,
        "kind": point.kind,
        "arc_position": point.arc_position,
    }
    timings["robust_s"] = time.perf_counter() - t0
    return robust
