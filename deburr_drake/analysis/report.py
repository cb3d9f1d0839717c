"""``analyze``: the whole analysis of one scenario at its operating point,
as a plain dict (what ``analysis.json`` holds), its one-screen summary and
its figures (pole map, Bode/Nyquist)."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Callable, Dict, Optional

import numpy as np

from deburr_drake.analysis.frequency import (normal_force_loop,
                                             plot_bode_nyquist)
from deburr_drake.analysis.linearization import (eq8_time_constant,
                                                 linearize_closed_loop)
from deburr_drake.analysis.operating_point import (
    DEFAULT_TIME_AFTER_CONTACT, find_operating_point)
from deburr_drake.analysis.sampled import sampled_loop
from deburr_drake.config import Scenario

__all__ = ["analyze", "summary_text", "write_analysis", "plot_poles",
           "SUMMARY_KEYS"]

#: Keys analysis.json always holds.
SUMMARY_KEYS = ("eigenvalues", "depth_time_constant_s",
                "depth_time_constant_eq8_s", "sampled_spectral_radius",
                "gain_margin_dB", "phase_margin_deg", "operating_point")


def _finite(x):
    """JSON-safe: non-finite numbers become None."""
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


def analyze(scenario: Scenario, *, at: float = None,
            after_contact: float = DEFAULT_TIME_AFTER_CONTACT,
            overrides: Optional[Dict[str, float]] = None,
            progress: Optional[Callable[[str], None]] = None) -> Dict:
    """Operating point, continuous linearization (modes, eq. (8) check),
    sampled one-period map (rho), normal-force loop margins. Returns the
    dict of analysis.json (SI units) with the live objects under
    ``"_objects"`` (for figures; not written). ``overrides`` (scenario
    fields by dotted name) apply at the operating point: the scenario as
    given reaches steady cutting, then the loop is analysed with them
    (as the limits of :mod:`deburr_drake.analysis.validation` are)."""
    overrides = dict(overrides or {})
    from deburr_drake.cell.truth import contact_truth
    say = progress or (lambda message: None)
    timings = {}
    t0 = time.perf_counter()
    say("operating point: simulating to steady cutting")
    op = find_operating_point(scenario, at=at, after_contact=after_contact)
    timings["operating_point_s"] = time.perf_counter() - t0
    truth = contact_truth(scenario)
    t1 = time.perf_counter()
    say("continuous-time linearization")
    lin = linearize_closed_loop(op, stiffness=truth.local_stiffness,
                                **overrides)
    timings["linearization_s"] = time.perf_counter() - t1
    from deburr_drake.analysis.operating_point import frozen_scenario
    analysed = frozen_scenario(scenario, **overrides)
    tau_eq8 = eq8_time_constant(analysed.controller.depth_gain,
                                truth.local_stiffness, truth.c2)
    t2 = time.perf_counter()
    say("one-period map of the sampled loop")
    sampled = sampled_loop(op, **overrides)
    loop = normal_force_loop(sampled)
    tangential = normal_force_loop(sampled, direction=sampled.n2)
    timings["sampled_map_s"] = time.perf_counter() - t2
    t3 = time.perf_counter()
    say("map over one outer-loop period (feed law live)")
    frame = sampled_loop(op, outer_loop=True, **overrides)
    timings["outer_period_map_s"] = time.perf_counter() - t3
    z_eigs = sampled.eigenvalues
    z_eigs = z_eigs[np.argsort(-np.abs(z_eigs))]
    worst = z_eigs[0]
    result = {
        "scenario": scenario.name,
        "overrides_at_operating_point": overrides,
        "operating_point": op.summary(),
        "contact_truth": {"local_stiffness": truth.local_stiffness,
                          "secant_stiffness": truth.secant_stiffness,
                          "c0": truth.c0, "c2": truth.c2},
        "eigenvalues": [[float(e.real), float(e.imag)]
                        for e in lin.eigenvalues],
        "modes": [{"group": m.group, "re": m.eigenvalue.real,
                   "im": m.eigenvalue.imag,
                   "natural_frequency_rad_s": m.natural_frequency,
                   "damping_ratio": m.damping_ratio,
                   "time_constant_s": m.time_constant} for m in lin.modes],
        "depth_time_constant_s": lin.depth_time_constant,
        "depth_time_constant_eq8_s": tau_eq8,
        "depth_time_constant_error_rel": abs(
            lin.depth_time_constant - tau_eq8) / tau_eq8,
        "sampled_period_s": sampled.period,
        "sampled_spectral_radius": sampled.spectral_radius,
        "sampled_dominant_eigenvalue": [float(worst.real),
                                        float(worst.imag)],
        "sampled_dominant_frequency_hz": float(
            abs(np.angle(worst)) / (2 * np.pi * sampled.period)),
        "sampled_eigenvalues": [[float(e.real), float(e.imag)]
                                for e in z_eigs],
        "outer_period_s": frame.period,
        "outer_period_spectral_radius": frame.spectral_radius,
        "gain_margin_dB": loop.gain_margin_dB,
        "phase_margin_deg": loop.phase_margin_deg,
        "phase_crossover_hz": loop.phase_crossover_hz,
        "gain_crossover_hz": loop.gain_crossover_hz,
        "tangential_gain_margin_dB": tangential.gain_margin_dB,
        "tangential_phase_margin_deg": tangential.phase_margin_deg,
        "timings_s": timings,
        "frozen": ["outer loop (command generator, first-order hold)",
                   "adaptation (estimator c-hat, fuzzy theta)",
                   "burr (operating point off the burrs)",
                   "sensor noise"],
    }
    result["_objects"] = {"op": op, "linearization": lin,
                          "sampled": sampled, "loop": loop}
    return result


def summary_text(result: Dict) -> str:
    """One screen: the operating point, the modes by group, eq. (8),
    rho, the margins."""
    op = result["operating_point"]
    lines = [
        f"deburr-drake analyze: scenario '{result['scenario']}'",
        f"operating point t = {op['time']:.4f} s (contact at "
        f"{op['contact_time']:.3f} s): depth {op['depth'] * 1e3:.4f} mm, "
        f"feed {op['feed'] * 1e3:.3f} mm/s, |f_n| {op['normal_force']:.2f} N,"
        f" |f_t| {op['chamfering_force']:.2f} N",
        "frozen: outer loop, adaptation, burr, noise"
        + (f"; analysed with {result['overrides_at_operating_point']}"
           if result.get("overrides_at_operating_point") else ""),
        "",
        "continuous-time modes (controller continuous, sensor low-pass "
        "continuous):",
        f"  {'group':12s} {'Re (1/s)':>10s} {'Im (rad/s)':>11s} "
        f"{'wn (rad/s)':>11s} {'zeta':>7s} {'tau (s)':>9s}",
    ]
    for m in result["modes"]:
        if m["im"] < 0:
            continue
        lines.append(
            f"  {m['group']:12s} {m['re']:10.3f} {m['im']:11.3f} "
            f"{m['natural_frequency_rad_s']:11.3f} {m['damping_ratio']:7.3f} "
            f"{m['time_constant_s']:9.4f}")
    lines += [
        "",
        f"slowest depth mode tau = {result['depth_time_constant_s']:.4f} s;"
        f" eq. (8) (1 + k c2) / (k c1), c1 = "
        f"{result['contact_truth']['local_stiffness'] / 1e3:.2f} N/mm local: "
        f"{result['depth_time_constant_eq8_s']:.4f} s "
        f"({100 * result['depth_time_constant_error_rel']:.1f} % apart)",
        f"sampled loop ({result['sampled_period_s'] * 1e3:g} ms): "
        f"spectral radius rho = {result['sampled_spectral_radius']:.5f} "
        f"({'stable' if result['sampled_spectral_radius'] < 1 else 'UNSTABLE'}"
        f"), dominant eigenvalue at "
        f"{result['sampled_dominant_frequency_hz']:.1f} Hz",
        f"with the feed law live ({result['outer_period_s'] * 1e3:g} ms "
        f"map, shift along the edge left out; experimental, see README): "
        f"rho = "
        f"{result['outer_period_spectral_radius']:.5f}",
        f"normal-force loop: gain margin {result['gain_margin_dB']:.1f} dB "
        f"(at {result['phase_crossover_hz']:.2f} Hz), phase margin "
        f"{result['phase_margin_deg']:.1f} deg (at "
        f"{result['gain_crossover_hz']:.2f} Hz)",
    ]
    if "lyapunov" in result:
        ly = result["lyapunov"]
        lines.append(
            "Lyapunov: dV/dt > 0 in "
            f"{100 * ly['fraction_dV_positive_outside_dead_zone']:.0f} % of "
            f"{ly['samples_outside_dead_zone']} samples outside the dead "
            f"zone (V1: "
            f"{100 * ly['fraction_dV1_positive_outside_dead_zone']:.0f} %)")
    if "boundaries" in result:
        lines += ["", f"  {'parameter':52s} {'predicted':>11s} "
                      f"{'simulated':>11s}"]
        def fmt(x):
            return "none" if x is None else f"{x:.4g}"
        for b in result["boundaries"]:
            lines.append(f"  {b['parameter'][:52]:52s} "
                         f"{fmt(b['predicted']):>11s} "
                         f"{fmt(b['simulated']):>11s}")
    return "\n".join(lines)


def plot_poles(result: Dict, path, *, title: str = ""):
    """Continuous eigenvalues (s-plane, by group) and the sampled map's
    (z-plane with the unit circle)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.5))
    groups = {}
    for m in result["modes"]:
        groups.setdefault(m["group"], []).append((m["re"], m["im"]))
    for g, pts in sorted(groups.items()):
        pts = np.array(pts)
        a.plot(pts[:, 0], pts[:, 1], "x", label=g)
    a.axvline(0, color="k", lw=0.5)
    a.set_xscale("symlog", linthresh=10)
    a.set(xlabel="Re (1/s)", ylabel="Im (rad/s)",
          title="continuous linearization")
    a.legend(fontsize=8)
    z = np.array(result["sampled_eigenvalues"])
    th = np.linspace(0, 2 * np.pi, 400)
    b.plot(np.cos(th), np.sin(th), "k", lw=0.5)
    b.plot(z[:, 0], z[:, 1], "o", mfc="none")
    b.set(aspect="equal", xlabel="Re z", ylabel="Im z",
          title=f"one-period map, rho = "
                f"{result['sampled_spectral_radius']:.4f}")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_analysis(result: Dict, out) -> Dict[str, Path]:
    """analysis.json and the figures in ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = {}
    data = {k: v for k, v in result.items() if not k.startswith("_")}
    files["json"] = out / "analysis.json"
    files["json"].write_text(json.dumps(_finite(data), indent=2))
    objects = result.get("_objects", {})
    files["poles"] = plot_poles(result, out / "poles.png",
                                title=result["scenario"])
    if "loop" in objects:
        files["bode_nyquist"] = plot_bode_nyquist(
            objects["loop"], out / "bode_nyquist.png",
            title=result["scenario"])
    if "map" in objects:
        from deburr_drake.analysis.maps import plot_map
        files["map"] = plot_map(objects["map"], out / "stability_map.png",
                                boundaries=result.get("boundaries"))
    return files
