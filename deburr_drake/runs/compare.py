"""``deburr-drake compare``: one scenario run with several controllers,
side by side: ``comparison.json``, ``comparison.md`` (one row per
controller: the metrics of ``metrics.json`` plus smoothness) and overlay
figures. Each controller's run also writes its own ``logs.npz`` and
``metrics.json`` in ``<out>/<controller>/``."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
import json
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

__all__ = [
    "CONTROLLERS",
    "HIGH_FREQUENCY",
    "configure",
    "run_controller",
    "compare",
    "write_comparison",
]

#: Controller names ``compare`` knows: (controller.kind, fuzzy order or None
#: for the scenario's).
CONTROLLERS = {
    "fuzzy": ("fuzzy", None),
    "fuzzy_m0": ("fuzzy", 0),
    "fuzzy_m2": ("fuzzy", 2),
    "robust": ("robust", None),
    "ideal": ("ideal", None),
    "impedance": ("impedance", None),
    "position": ("position", None),
}
DEFAULT_CONTROLLERS = (
    "fuzzy",
    "fuzzy_m0",
    "impedance",
    "robust",
    "ideal",
    "position",
)
#: Hz: the torque's power above it is the chattering measure.
HIGH_FREQUENCY = 50.0

#: The columns of comparison.md, in order: (key, header).
_TABLE = (
    ("stop_reason", "stop"),
    ("chamfering_force_rms_error_N", "f_t RMS err (N)"),
    ("normal_force_rms_error_N", "e_f RMS (N)"),
    ("normal_force_vs_truth_rms_error_N", "f_n - f_n(d*) RMS (N)"),
    ("chamfer_depth_rms_error_mm", "depth RMS err (mm)"),
    ("chamfer_depth_mean_error_mm", "depth mean err (mm)"),
    ("feed_mean_off_burrs_mm_s", "feed off burrs (mm/s)"),
    ("feed_mean_on_burrs_mm_s", "feed on burrs (mm/s)"),
    ("torque_total_variation", "torque TV (N m)"),
    ("torque_power_above_50Hz", "torque power >50 Hz (N^2 m^2)"),
    ("torque_rms_above_50Hz", "torque RMS >50 Hz (N m)"),
    ("fuzzy_cell_crossings", "s cell crossings"),
    ("control_surface_roughness_N", "u_f roughness (N)"),
    ("wall_time_s", "wall (s)"),
)


def configure(scenario, controller: str):
    """A copy of ``scenario`` running ``controller`` (a CONTROLLERS name);
    its name gets the controller appended."""
    import copy

    from deburr_drake.config import ConfigError

    if controller not in CONTROLLERS:
        raise ConfigError(
            f"--controllers: {controller!r} is unknown: "
            f"allowed {', '.join(CONTROLLERS)}"
        )
    kind, order = CONTROLLERS[controller]
    sc = copy.deepcopy(scenario)
    sc.controller.kind = kind
    if order is not None:
        sc.controller.fuzzy.order = order
    sc.name = f"{scenario.name}.{controller}"
    return sc.validate()


def smoothness(log, t0: float) -> Dict[str, float]:
    """Torque total variation is in pass_metrics; here the torque's power
    and RMS above HIGH_FREQUENCY Hz after ``t0`` s (the chattering of a
    sampled sign law shows there) and the m = 0 cell crossings of s."""
    from deburr_drake.math import metrics

    act = log["actuation"]
    mask = metrics.window(act["t"], t0)
    power = (
        metrics.high_frequency_power(
            act["t"][mask], act["value"][mask], HIGH_FREQUENCY
        )
        if np.count_nonzero(mask) >= 8
        else float("nan")
    )
    ctl = log["controller"]
    late = metrics.window(ctl["t"], t0)
    f = log.scenario.controller.fuzzy
    _, deltas = f.deltas()
    crossings = sum(
        metrics.cell_crossings(ctl["s"][late][:, axis], d)
        for axis, d in zip(f.axes, deltas)
    )
    return {
        "torque_power_above_50Hz": power,
        "torque_rms_above_50Hz": float(np.sqrt(power)),
        # How often s_k left its m = 0 cell (width Delta_k) on the
        # fuzzy axes: 0 means m = 0 and m = 2 cannot differ in
        # smoothness through the memberships.
        "fuzzy_cell_crossings": float(crossings),
    }


def run_controller(
    scenario, controller: str, duration: Optional[float], out_dir
) -> dict:
    """Runs ``controller`` on ``scenario`` for ``duration`` s (the
    scenario's if None) and writes ``out_dir``/logs.npz, metrics.json;
    returns the metrics.json content plus the smoothness metrics and the
    normal force against the plant's true force at delta*."""
    from deburr_drake.cell.plan import plan_cell
    from deburr_drake.math import metrics
    from deburr_drake.runs import report
    from deburr_drake.runs.pass_metrics import TRANSIENT
    from deburr_drake.runs.passes import run_pass, truth_force

    sc = configure(scenario, controller)
    plan = plan_cell(sc)
    done = run_pass(plan, duration=duration)
    log, values = done.log, done.metrics
    truth = truth_force(plan)[0]
    t0 = values.get("contact_time_s", np.nan) + TRANSIENT
    for key, value in smoothness(log, t0).items():
        values[key] = value
    ch = log["chamfer"]
    late = metrics.window(ch["t"], t0)
    if truth is not None and np.any(late):
        # The estimator's f_nd hat is not a common yardstick (impedance and
        # position do not use it): the plant's force at delta* is.
        values["normal_force_vs_truth_rms_error_N"] = metrics.rms(
            ch["f_n"][late] - truth
        )
    else:
        values.unavailable(
            "normal_force_vs_truth_rms_error_N",
            "no contact truth or no sample after the transient",
        )
    report.write_run(log, out_dir, values)
    row = report.run_summary(log, values)
    row["controller"] = controller
    row["kind"] = sc.controller.kind
    row["fuzzy_order"] = sc.controller.fuzzy.order
    return row


def _run(job):
    scenario, controller, duration, out_dir = job
    return run_controller(scenario, controller, duration, out_dir)


def compare(
    scenario,
    controllers: List[str],
    *,
    duration=None,
    out_dir,
    workers: int = 1,
) -> List[dict]:
    """Runs every controller (``workers`` processes at a time; 1: in this
    process, one after the other) and writes the comparison into
    ``out_dir``. Returns the rows."""
    for c in controllers:
        configure(scenario, c)  # unknown names fail before anything runs
    out = Path(out_dir)
    jobs = [(scenario, c, duration, out / c) for c in controllers]
    if workers <= 1:
        rows = [_run(job) for job in jobs]
    else:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            rows = list(pool.map(_run, jobs))
    write_comparison(rows, out, scenario=scenario.name, duration=duration)
    return rows


def _cell(value):
    """A table cell: text as it is, a number to 4 digits, n/a for null."""
    if isinstance(value, str):
        return value
    if value is None:
        return "n/a"
    return f"{value:.4g}"


def write_comparison(
    rows: List[dict], out_dir, *, scenario: str, duration
) -> Dict[str, Path]:
    """comparison.json (every row in full), comparison.md (the table) and
    the overlay figures (from each row's logs.npz)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "comparison.json", "w") as f:
        json.dump(
            {"scenario": scenario, "duration_s": duration, "rows": rows},
            f,
            indent=2,
            sort_keys=True,
            allow_nan=False,
        )
    lines = [
        f"# Controller comparison: scenario `{scenario}`"
        + (f", {duration:g} s" if duration else ", full run"),
        "",
        "| controller | " + " | ".join(h for _, h in _TABLE) + " |",
        "|---" * (len(_TABLE) + 1) + "|",
    ]
    for row in rows:
        lines.append(
            f"| {row['controller']} | "
            + " | ".join(_cell(row.get(k)) for k, _ in _TABLE)
            + " |"
        )
    lines += [
        "",
        "f_t: chamfering force against the desired one; e_f: "
        "the controller's normal-force error (against its own "
        "estimate f_nd hat; impedance and position ignore it); "
        "f_n - f_n(d*): the normal force against the plant's true "
        "force at the desired depth; depth: the chamfer on the real "
        "part. All after the contact transient. Torque power above "
        f"{HIGH_FREQUENCY:g} Hz: the chattering measure.",
    ]
    (out / "comparison.md").write_text("\n".join(lines) + "\n")
    files = {"json": out / "comparison.json", "md": out / "comparison.md"}
    try:
        files["figures"] = overlay_figures(rows, out)
    except Exception as e:  # too little to draw: the tables stand
        print(f"deburr-drake: no overlay figures: {type(e).__name__}: {e}")
    return files


def overlay_figures(rows: List[dict], out: Path) -> List[Path]:
    """Overlays of every controller: chamfering force error, normal force
    error, depth along the edge on the real part, torque norm, and the
    torque's spectrum."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    logs = {}
    for row in rows:
        with np.load(out / row["controller"] / "logs.npz") as z:
            logs[row["controller"]] = dict(z)
    fig, axes = plt.subplots(4, 1, figsize=(9, 11))
    spec_fig, spec_ax = plt.subplots(figsize=(8, 4))
    for name, z in logs.items():
        f_td = float(z["meta.desired_force"])
        axes[0].plot(
            z["process.t"], z["process.f_t"] - f_td, label=name, lw=0.8
        )
        axes[1].plot(z["controller.t"], z["controller.e_f"], label=name, lw=0.8)
        cut = z["finish.depth"] > 0
        axes[2].plot(
            z["finish.arc"][cut] * 1e3,
            z["finish.depth"][cut] * 1e3,
            ".",
            ms=2,
            label=name,
        )
        tau = z["actuation.value"]
        axes[3].plot(
            z["actuation.t"], np.linalg.norm(tau, axis=1), label=name, lw=0.6
        )
        if len(tau) >= 8:
            dt = float(np.median(np.diff(z["actuation.t"])))
            freq = np.fft.rfftfreq(len(tau), dt)
            amp = np.linalg.norm(
                np.abs(np.fft.rfft(tau - tau.mean(axis=0), axis=0)), axis=1
            ) / len(tau)
            spec_ax.semilogy(freq[1:], amp[1:], lw=0.7, label=name)
    for ax, label in zip(
        axes,
        (
            "chamfering force error (N)",
            "normal force error e_f (N)",
            "chamfer depth on the part (mm)",
            "||joint torque|| (N m)",
        ),
    ):
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7, ncol=3)
    axes[2].set_xlabel("arc position along the edge (mm)")
    axes[3].set_xlabel("t (s)")
    axes[0].set_xlabel("t (s)")
    axes[1].set_xlabel("t (s)")
    fig.tight_layout()
    spec_ax.axvline(HIGH_FREQUENCY, color="k", lw=0.5, ls="--")
    spec_ax.set_xlabel("frequency (Hz)")
    spec_ax.set_ylabel("joint torque amplitude (N m)")
    spec_ax.legend(fontsize=7)
    spec_ax.grid(True, alpha=0.3)
    spec_fig.tight_layout()
    paths = [out / "comparison_overlay.png", out / "torque_spectrum.png"]
    fig.savefig(paths[0], dpi=110)
    spec_fig.savefig(paths[1], dpi=110)
    plt.close(fig)
    plt.close(spec_fig)
    return paths
