"""The report of :func:`~deburr_drake.analysis.analyze_run.analyze`'s
result: its one-screen summary (the verdict first), ``analysis.json`` and
its figures (pole map, rho along the run, Bode/Nyquist)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Dict, Optional

import numpy as np

from deburr_drake.analysis.along import plot_rho_along_run
from deburr_drake.analysis.frequency import plot_bode_nyquist

__all__ = [
    "summary_text",
    "write_analysis",
    "plot_poles",
]


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


def summary_text(result: Dict) -> str:
    """One screen: the verdict first, then the operating point, the modes
    by group, eq. (8), rho at the operating point and along the run, the
    robust margin, the margins."""
    lines = [
        f"verdict: {result['verdict'].upper()}: {result['verdict_reason']}",
        f"deburr-drake analyze: scenario '{result['scenario']}', run "
        f"to {result['run']['end_time']:.2f} s "
        f"({result['run']['stop_reason']}, guards off)",
        _numerics_line(result["numerics"]),
    ]
    if result.get("eigenvalues") is None:
        return "\n".join(lines + _unsettled_lines(result))
    lines += _operating_point_lines(result)
    lines += _rho_lines(result)
    lines += _robust_lines(result.get("robust"))
    lines.append(
        f"normal-force loop: gain margin {result['gain_margin_dB']:.1f} dB "
        f"(at {result['phase_crossover_hz']:.2f} Hz), phase margin "
        f"{result['phase_margin_deg']:.1f} deg (at "
        f"{result['gain_crossover_hz']:.2f} Hz)"
    )
    if "lyapunov" in result:
        ly = result["lyapunov"]
        lines.append(
            "Lyapunov: dV/dt > 0 in "
            f"{100 * ly['fraction_dV_positive_outside_dead_zone']:.0f} % of "
            f"{ly['samples_outside_dead_zone']} samples outside the dead "
            f"zone (V1: "
            f"{100 * ly['fraction_dV1_positive_outside_dead_zone']:.0f} %)"
        )
    if "boundaries" in result:
        lines += _boundary_lines(result["boundaries"])
    return "\n".join(lines)


def _numerics_line(n: Dict) -> str:
    """Which step and treatment the verdict's run and its maps used, and
    what the run cost."""

    def treatment(step, sample_mean):
        held = "held mean" if sample_mean else "eq. (3)"
        return f"{step * 1e3:.4g} ms steps, {held} between samples"

    line = (
        f"numerics ({n['name']}): the run at "
        f"{treatment(n['max_step_s'], n['sample_mean'])}"
        + (" (error control)" if n["error_control"] else "")
        + f" (shipped {n['shipped_max_step_s'] * 1e3:.4g} ms)"
    )
    if n.get("maps_max_step_s") is not None:
        line += "; the maps at " + treatment(
            n["maps_max_step_s"], n["maps_sample_mean"]
        )
    return line + f"; {n['run_wall_time_s']:.1f} s of wall time"


def _unsettled_lines(result: Dict) -> list:
    lines = []
    g = result.get("guard_that_would_stop")
    if g:
        lines.append(
            f"guard that would have stopped the run: "
            f"{g['guard']} at t = {g['time']:.3f} s "
            f"({g['detail']})"
        )
    lines.append(
        "no linearization: the run is not in steady cutting "
        "at the analysed time (a limit cycle is not an "
        "operating point)"
    )
    return lines


def _operating_point_lines(result: Dict) -> list:
    """The operating point, what is frozen there and the continuous
    modes (one of each complex pair)."""
    op = result["operating_point"]
    lines = [
        f"operating point t = {op['time']:.4f} s (contact at "
        f"{op['contact_time']:.3f} s): depth {op['depth'] * 1e3:.4f} mm, "
        f"feed {op['feed'] * 1e3:.3f} mm/s, |f_n| {op['normal_force']:.2f} N,"
        f" |f_t| {op['chamfering_force']:.2f} N",
        "frozen: outer loop, adaptation, noise"
        + (
            f"; analysed with {result['overrides_at_operating_point']} (a "
            "what-if: the verdict is the run's as given)"
            if result.get("overrides_at_operating_point")
            else ""
        ),
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
            f"{m['time_constant_s']:9.4f}"
        )
    return lines


def _rho_lines(result: Dict) -> list:
    """eq. (8) against the depth mode, rho at the operating point and the
    smallest margins along the run."""
    rho = result["sampled_spectral_radius"]
    lines = [
        "",
        f"slowest depth mode tau = {result['depth_time_constant_s']:.4f} s;"
        f" eq. (8) (1 + k c2) / (k c1), c1 = "
        f"{result['contact_truth']['local_stiffness'] / 1e3:.2f} N/mm local: "
        f"{result['depth_time_constant_eq8_s']:.4f} s "
        f"({100 * result['depth_time_constant_error_rel']:.1f} % apart)",
        f"sampled loop ({result['sampled_period_s'] * 1e3:g} ms) at the "
        f"operating point: spectral radius rho = {rho:.5f} "
        f"({'stable' if rho < 1 else 'UNSTABLE'}), dominant eigenvalue at "
        f"{result['sampled_dominant_frequency_hz']:.1f} Hz",
    ]
    along = result.get("rho_along_run") or []
    steady = [p for p in along if p["rho"] is not None]
    sm = result.get("smallest_margin")
    if sm:
        lines.append(
            f"along the run: {len(steady)} steady points of {len(along)}; "
            f"smallest margin 1 - rho = {sm['margin']:.5f} (rho "
            f"{sm['rho']:.5f}, {sm['frequency_hz']:.1f} Hz, decay "
            f"{sm['decay_rate_per_s']:.3g} 1/s) at t = {sm['t']:.2f} s, arc "
            f"{sm['arc_position'] * 1e3:.1f} mm ({sm['kind']})"
        )
    so = result.get("smallest_oscillatory_margin")
    if so:
        lines.append(
            f"  the loop's oscillatory modes (above 1 Hz): largest |z| "
            f"{so['rho_oscillatory']:.5f} at t = {so['t']:.2f} s "
            f"({so['kind']})"
        )
    return lines


def _robust_lines(rb: Optional[Dict]) -> list:
    """The worst rho and the worst |z| of the oscillatory modes over the
    robust margin's maps, with where they are."""
    if not rb:
        return []
    lines = []
    for key, label in (
        ("", "rho"),
        ("_oscillatory", "|z| of the modes above 1 Hz"),
    ):
        at = ", ".join(f"{k} {v:.4g}" for k, v in rb["at" + key].items())
        lines.append(
            f"robust: worst {label} {rb['rho_worst' + key]:.5f} "
            f"(nominal {rb['rho_nominal' + key]:.5f}) over "
            f"{len(rb['maps'])} maps at t = {rb['point']['t']:.2f} s, "
            f"at {at}"
        )
    return lines


def _boundary_lines(boundaries) -> list:
    """--validate's table: predicted against simulated boundaries."""

    def fmt(x):
        return "none" if x is None else f"{x:.4g}"

    lines = [
        "",
        f"  {'parameter':52s} {'predicted':>11s} {'simulated':>11s}",
    ]
    for b in boundaries:
        lines.append(
            f"  {b['parameter'][:52]:52s} "
            f"{fmt(b['predicted']):>11s} "
            f"{fmt(b['simulated']):>11s}"
        )
    return lines


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
    a.set(
        xlabel="Re (1/s)", ylabel="Im (rad/s)", title="continuous linearization"
    )
    a.legend(fontsize=8)
    z = np.array(result["sampled_eigenvalues"])
    th = np.linspace(0, 2 * np.pi, 400)
    b.plot(np.cos(th), np.sin(th), "k", lw=0.5)
    b.plot(z[:, 0], z[:, 1], "o", mfc="none")
    b.set(
        aspect="equal",
        xlabel="Re z",
        ylabel="Im z",
        title=f"one-period map, rho = {result['sampled_spectral_radius']:.4f}",
    )
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
    if result.get("eigenvalues") is not None:
        files["poles"] = plot_poles(
            result, out / "poles.png", title=result["scenario"]
        )
    if result.get("rho_along_run"):
        files["rho_along_run"] = plot_rho_along_run(
            result["rho_along_run"],
            out / "rho_along_run.png",
            title=result["scenario"],
        )
    if "loop" in objects:
        files["bode_nyquist"] = plot_bode_nyquist(
            objects["loop"], out / "bode_nyquist.png", title=result["scenario"]
        )
    if "map" in objects:
        from deburr_drake.analysis.maps import plot_map

        files["map"] = plot_map(
            objects["map"],
            out / "stability_map.png",
            boundaries=result.get("boundaries"),
            units=objects["map"].units,
        )
    return files
