"""Figures 8-12 of Hsu & Fu, Section IV, drawn from a run's logs (logs.npz).

Pure matplotlib (explicit Agg canvas, no pyplot state, no pydrake).  Inputs are
SI (m, N, s); plots show depths in mm, forces in N, time in s.

* Fig. 8  surface finish: initial burr profile and achieved chamfer depth
  along the edge, desired depth (0.5 mm in the paper) dashed.
* Fig. 9  depth tracking error delta_d - delta and normal force error e_f
  (e_f = ||f_nd hat|| - ||f_n||, f_nd hat the identified desired normal force).
* Fig. 10 chamfering force error ||f_t|| - f_d (f_d = 10 N in the paper).
* Figs. 11/12 per fuzzy axis k: final theta_k as 3-D bars over the rule
  grid (i, j) (R8: (2U+1)**2 rules, i indexes y0 = ||x||, j indexes
  y_k = s_k) and the control surface u_fk(y0, s_k) of eq. (30).

Missing keys skip the figure that needs them (with a warning); present but
malformed arrays (wrong ndim or length) raise ValueError naming the key.

Use: ``make_figures(dict(np.load("out/paper/logs.npz")), out_dir)`` after a
run of the command line, or ``make_figures(report.log_arrays(log, values),
out_dir)`` straight from a RunLog; ``compare_figures({"m = 0": logs0,
"m = 2": logs2}, out_dir)`` overlays runs. Both return the PNG paths.
"""

from __future__ import annotations

import pathlib
from typing import Mapping
import warnings

import matplotlib
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
import numpy as np

from deburr_drake.math.fuzzy import RuleBase

__all__ = ["make_figures", "compare_figures", "FIGURE_NAMES", "COMPARE_NAMES"]

DPI = 120
MM = 1e3  # m -> mm

FIGURE_NAMES = {
    "fig08": "fig08_surface_finish.png",
    "fig09": "fig09_depth_force_error.png",
    "fig10": "fig10_chamfering_force_error.png",
    "fig11_12": "fig11_12_fuzzy_axis{k}.png",
}
COMPARE_NAMES = {
    "fig08": "compare_fig08_surface_finish.png",
    "fig09": "compare_fig09_depth_force_error.png",
    "fig10": "compare_fig10_chamfering_force_error.png",
}

_SURFACE_POINTS = 61  # per input axis of the control surface


class _Missing(Exception):
    """A key needed by one figure is absent: skip that figure."""


# ---------------------------------------------------------------------------
# Key access and validation


def _require(logs, key):
    if key not in logs:
        raise _Missing(key)
    return np.asarray(logs[key])


def _vec(logs, key, length=None, like=None):
    """1-D float array logs[key]; length must match `like` when given."""
    a = _require(logs, key)
    if a.ndim != 1:
        raise ValueError(f"{key} must be 1-D, got shape {a.shape}")
    if length is not None and a.shape[0] != length:
        raise ValueError(
            f"{key} has shape {a.shape}, expected ({length},) to match {like}"
        )
    try:
        return a.astype(float)
    except (TypeError, ValueError):
        raise ValueError(
            f"{key} must be numeric, got dtype {a.dtype}"
        ) from None


def _scalar(logs, key):
    a = _require(logs, key)
    if a.size != 1:
        raise ValueError(f"{key} must be a scalar, got shape {a.shape}")
    return a.reshape(()).item()


def _opt_scalar(logs, key):
    try:
        return float(_scalar(logs, key))
    except _Missing:
        return None


def _series(logs, t_key, keys):
    """(t, [arrays]) with every array the length of logs[t_key]."""
    t = _vec(logs, t_key)
    return t, [_vec(logs, k, len(t), t_key) for k in keys]


def _title(base, label):
    return f"{base} — {label}" if label else base


def _save(fig, path):
    FigureCanvasAgg(
        fig
    )  # Agg canvas explicitly; global backend / pyplot untouched
    fig.savefig(path, dpi=DPI)
    return pathlib.Path(path)


def _mark_contact(ax, logs):
    tc = _opt_scalar(logs, "meta.contact_start")
    if tc is not None and np.isfinite(tc):
        ax.axvline(tc, color="0.5", lw=0.8, ls=":", label="contact")


# ---------------------------------------------------------------------------
# Data extraction (shared by make_figures and compare_figures)


def _fig08_data(logs):
    arc = _vec(logs, "finish.arc")
    n = len(arc)
    depth = _vec(logs, "finish.depth", n, "finish.arc")
    burr0 = _vec(logs, "finish.burr_initial", n, "finish.arc")
    try:
        burr1 = _vec(logs, "finish.burr_remaining", n, "finish.arc")
    except _Missing:
        burr1 = None
    return arc, depth, burr0, burr1, _opt_scalar(logs, "meta.desired_depth")


def _fig09_data(logs):
    """(t, delta_d - delta, (t_ctrl, e_f)); t = controller.t within chamfer.t's
    range.

    delta (chamfer.t) is linearly interpolated onto controller.t, restricted to
    the overlap of the two time ranges (no extrapolation).
    """
    tc, (delta_d, e_f) = _series(
        logs, "controller.t", ["controller.delta_d", "controller.e_f"]
    )
    tp, (delta,) = _series(logs, "chamfer.t", ["chamfer.delta"])
    if len(tp) == 0 or len(tc) == 0:
        return tc[:0], tc[:0], (tc, e_f)
    keep = (tc >= tp.min()) & (tc <= tp.max())
    order = np.argsort(tp, kind="stable")
    delta_c = np.interp(tc[keep], tp[order], delta[order])
    return tc[keep], delta_d[keep] - delta_c, (tc, e_f)


def _fig10_data(logs):
    t, (f_t,) = _series(logs, "chamfer.t", ["chamfer.f_t"])
    f_d = float(_scalar(logs, "meta.desired_force"))
    return t, np.abs(f_t) - f_d, f_d


# ---------------------------------------------------------------------------
# Single-run figures


def _plot_fig08(logs, out_dir, label):
    arc, depth, burr0, burr1, d_des = _fig08_data(logs)
    fig = Figure(figsize=(8, 5.5))
    ax0, ax1 = fig.subplots(2, 1, sharex=True)
    ax0.plot(arc * MM, burr0 * MM, color="C3", label="initial burr")
    if burr1 is not None:
        ax0.plot(arc * MM, burr1 * MM, color="C0", lw=1, label="remaining burr")
    ax0.set_ylabel("burr height (mm)")
    ax0.legend(loc="upper right", fontsize=8)
    ax0.grid(alpha=0.3)
    ax1.plot(arc * MM, depth * MM, color="C2", label="chamfer depth δ")
    if d_des is not None:
        ax1.axhline(
            d_des * MM,
            color="k",
            ls="--",
            lw=1,
            label=f"desired δ_d = {d_des * MM:g} mm",
        )
    ax1.set_ylabel("chamfer depth (mm)")
    ax1.set_xlabel("arc position along the edge (mm)")
    ax1.legend(loc="upper right", fontsize=8)
    ax1.grid(alpha=0.3)
    fig.suptitle(_title("Fig. 8  Surface finish along the edge", label))
    fig.tight_layout()
    return _save(fig, out_dir / FIGURE_NAMES["fig08"])


def _plot_fig09_axes(fig):
    ax0, ax1 = fig.subplots(2, 1, sharex=True)
    ax0.set_ylabel("δ_d − δ (mm)")
    ax1.set_ylabel("e_f = ‖f̂_nd‖ − ‖f_n‖ (N)")
    ax1.set_xlabel("time (s)")
    for ax in (ax0, ax1):
        ax.axhline(0.0, color="k", lw=0.6)
        ax.grid(alpha=0.3)
    return ax0, ax1


def _plot_fig09(logs, out_dir, label):
    t, dz, (tc, e_f) = _fig09_data(logs)
    fig = Figure(figsize=(8, 5.5))
    ax0, ax1 = _plot_fig09_axes(fig)
    ax0.plot(t, dz * MM, color="C0", lw=0.8)
    ax1.plot(tc, e_f, color="C1", lw=0.8)
    for ax in (ax0, ax1):
        _mark_contact(ax, logs)
    fig.suptitle(
        _title("Fig. 9  Depth and normal-force tracking errors", label)
    )
    fig.tight_layout()
    return _save(fig, out_dir / FIGURE_NAMES["fig09"])


def _plot_fig10_axes(fig, f_d):
    ax = fig.subplots()
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_ylabel(f"‖f_t‖ − f_d (N),  f_d = {f_d:g} N")
    ax.set_xlabel("time (s)")
    ax.grid(alpha=0.3)
    return ax


def _plot_fig10(logs, out_dir, label):
    t, err, f_d = _fig10_data(logs)
    fig = Figure(figsize=(8, 3.5))
    ax = _plot_fig10_axes(fig, f_d)
    ax.plot(t, err, color="C3", lw=0.8)
    _mark_contact(ax, logs)
    fig.suptitle(_title("Fig. 10  Chamfering force error", label))
    fig.tight_layout()
    return _save(fig, out_dir / FIGURE_NAMES["fig10"])


def _fuzzy_setup(logs):
    """(theta (A, R), rule bases [A], task axes [A], m, U) from theta.final and
    meta.*."""
    theta = _require(logs, "theta.final")
    m = _scalar(logs, "meta.fuzzy_order")
    U = _scalar(logs, "meta.upsilon")
    delta0 = float(_scalar(logs, "meta.delta0"))
    deltak = np.atleast_1d(_require(logs, "meta.deltak")).astype(float)
    if deltak.ndim != 1:
        raise ValueError(
            f"meta.deltak must be 1-D (A,), got shape {deltak.shape}"
        )
    try:
        m, U = int(m), int(U)
    except (TypeError, ValueError):
        raise ValueError(
            f"meta.fuzzy_order / meta.upsilon must be ints, got {m!r}, {U!r}"
        ) from None
    R = (2 * U + 1) ** 2
    if theta.ndim != 2 or theta.shape[1] != R:
        raise ValueError(
            f"theta.final must have shape (A, (2U+1)**2) = (A, {R}), "
            f"got {theta.shape}"
        )
    A = theta.shape[0]
    if len(deltak) != A:
        raise ValueError(
            f"meta.deltak has shape {deltak.shape}, expected ({A},) "
            "to match theta.final"
        )
    if "meta.fuzzy_axes" in logs:
        axes = np.atleast_1d(np.asarray(logs["meta.fuzzy_axes"]))
        if axes.shape != (A,):
            raise ValueError(
                f"meta.fuzzy_axes has shape {axes.shape}, expected ({A},) "
                "to match theta.final"
            )
        axes = [int(a) for a in axes]
    else:
        axes = list(range(A))
    # Only plotting: dead-zone width is irrelevant, pass it so small U never
    # fails R4's default.
    bases = [
        RuleBase(m, U, delta0, float(dk), dead_zone_half_width=0.0)
        for dk in deltak
    ]
    return theta.astype(float), bases, axes, m, U


def _control_surface(rb, theta_k, n=_SURFACE_POINTS):
    """u_f(y0, s_k) of eq. (30) on y0 in [0, U*delta0], s_k in [-U*deltak,
    U*deltak]."""
    y0 = np.linspace(0.0, rb.omega0_half_width, n)
    sk = np.linspace(-rb.omegak_half_width, rb.omegak_half_width, n)
    u = np.empty((n, n))
    for a, y in enumerate(y0):
        for b, s in enumerate(sk):
            u[a, b] = rb.evaluate(theta_k, y, s)
    Y0, SK = np.meshgrid(y0, sk, indexing="ij")
    return Y0, SK, u


def _plot_fuzzy_axis(theta_k, rb, k, task_axis, m, U, out_dir, label):
    grid = rb.theta_grid(theta_k)  # grid[i+U, j+U], i: y0, j: s_k
    idx = np.arange(-U, U + 1)
    I, J = np.meshgrid(idx, idx, indexing="ij")
    x, y, dz = I.ravel() - 0.4, J.ravel() - 0.4, grid.ravel()
    span = float(np.ptp(dz)) or 1.0
    cmap = matplotlib.colormaps["viridis"]
    colors = cmap((dz - dz.min()) / span)

    fig = Figure(figsize=(13, 5.8))
    ax0 = fig.add_subplot(1, 2, 1, projection="3d")
    ax0.bar3d(x, y, np.zeros_like(dz), 0.8, 0.8, dz, color=colors, shade=True)
    lo, hi = min(0.0, float(dz.min())), max(0.0, float(dz.max()))
    pad = 0.05 * ((hi - lo) or 1.0)
    ax0.set_zlim(
        lo - pad, hi + pad
    )  # bar3d does not autoscale to negative heights
    ax0.set_xlabel("rule i  (y0 = i·Δ0)")
    ax0.set_ylabel(f"rule j  (s_{task_axis} = j·Δs)")
    ax0.set_zlabel("θ_ij (N)")
    ax0.set_title("Bar diagram of the final parameters θ")

    Y0, SK, u = _control_surface(rb, theta_k)
    ax1 = fig.add_subplot(1, 2, 2, projection="3d")
    ax1.plot_surface(
        Y0 * MM,
        SK * MM,
        u,
        cmap="viridis",
        rstride=1,
        cstride=1,
        linewidth=0,
        antialiased=False,
    )
    ax1.set_xlabel("y0 = ‖x‖ (mm)")
    ax1.set_ylabel(f"s_{task_axis} (mm/s)")
    ax1.set_zlabel("u_f (N)")
    ax1.set_title(f"Control surface u_f(y0, s_{task_axis}), eq. (30)")
    for ax in (ax0, ax1):
        ax.set_box_aspect(None, zoom=0.88)  # keep axis labels inside the canvas
    fig.suptitle(
        _title(
            f"Figs. 11/12  Fuzzy axis {k} (task axis {task_axis}): "
            f"order m = {m}, Υ = {U}, Δ0 = {rb.delta0 * MM:g} mm, "
            f"Δs = {rb.deltak * MM:g} mm/s",
            label,
        )
    )
    fig.subplots_adjust(left=0.0, right=0.97, top=0.9, bottom=0.02, wspace=0.05)
    return _save(fig, out_dir / FIGURE_NAMES["fig11_12"].format(k=k))


def _plot_fig11_12(logs, out_dir, label):
    theta, bases, axes, m, U = _fuzzy_setup(logs)
    return [
        _plot_fuzzy_axis(theta[k], bases[k], k, axes[k], m, U, out_dir, label)
        for k in range(len(bases))
    ]


def _run(name, fn, *args):
    """fn(*args) as a list of paths; [] with a warning if a key is missing."""
    try:
        out = fn(*args)
    except _Missing as e:
        warnings.warn(
            f"figures: skipping {name}, missing key {e.args[0]!r}", stacklevel=3
        )
        return []
    return out if isinstance(out, list) else [out]


_PLOTS = {
    "fig08": _plot_fig08,
    "fig09": _plot_fig09,
    "fig10": _plot_fig10,
    "fig11_12": _plot_fig11_12,
}


def make_figures(
    logs: Mapping[str, np.ndarray],
    out_dir,
    *,
    label: str = "",
    names=tuple(FIGURE_NAMES),
) -> list[pathlib.Path]:
    """Write Figs. 8-12 of one run as PNGs into out_dir; return the written
    paths.

    logs: dict (or NpzFile) of the run's arrays, SI units.  label goes into
    titles, e.g. "paper (m = 2)".  names: the figures to draw (keys of
    FIGURE_NAMES, in this order), all by default.  Figures whose keys are
    missing are skipped with a warning; malformed arrays raise ValueError
    naming the key.
    """
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for name in names:
        paths += _run(name, _PLOTS[name], logs, out_dir, label)
    return paths


# ---------------------------------------------------------------------------
# Overlays of several runs


def _collect(runs, name, fn):
    data = {}
    for run, logs in runs.items():
        try:
            data[run] = fn(logs)
        except _Missing as e:
            warnings.warn(
                f"figures: {name} without run {run!r}, "
                f"missing key {e.args[0]!r}",
                stacklevel=3,
            )
    return data


def compare_figures(
    runs: Mapping[str, Mapping[str, np.ndarray]], out_dir
) -> list[pathlib.Path]:
    """Overlay Figs. 8 (chamfer depth), 9 and 10 of several runs, legend by run
    name.

    runs: {name: logs}, e.g. {"m = 0": logs0, "m = 2": logs2}.  A run lacking
    the keys of one figure is left out of it; a figure no run can feed is
    skipped.
    """
    if not isinstance(runs, Mapping) or len(runs) == 0:
        raise ValueError("runs must be a non-empty dict {name: logs}")
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    title = " vs ".join(str(k) for k in runs)
    paths = []

    d8 = _collect(runs, "compare fig08", _fig08_data)
    if d8:
        fig = Figure(figsize=(8, 4))
        ax = fig.subplots()
        d_des = None
        for c, (run, (arc, depth, _, _, dd)) in enumerate(d8.items()):
            ax.plot(arc * MM, depth * MM, color=f"C{c}", lw=1, label=str(run))
            d_des = dd if dd is not None else d_des
        if d_des is not None:
            ax.axhline(
                d_des * MM,
                color="k",
                ls="--",
                lw=1,
                label=f"desired {d_des * MM:g} mm",
            )
        ax.set_xlabel("arc position along the edge (mm)")
        ax.set_ylabel("chamfer depth (mm)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.suptitle(_title("Fig. 8  Chamfer depth along the edge", title))
        fig.tight_layout()
        paths.append(_save(fig, out_dir / COMPARE_NAMES["fig08"]))

    d9 = _collect(runs, "compare fig09", _fig09_data)
    if d9:
        fig = Figure(figsize=(8, 5.5))
        ax0, ax1 = _plot_fig09_axes(fig)
        for c, (run, (t, dz, (tc, e_f))) in enumerate(d9.items()):
            ax0.plot(
                t, dz * MM, color=f"C{c}", lw=0.8, alpha=0.75, label=str(run)
            )
            ax1.plot(tc, e_f, color=f"C{c}", lw=0.8, alpha=0.75, label=str(run))
        ax0.legend(fontsize=8)
        ax1.legend(fontsize=8)
        fig.suptitle(
            _title("Fig. 9  Depth and normal-force tracking errors", title)
        )
        fig.tight_layout()
        paths.append(_save(fig, out_dir / COMPARE_NAMES["fig09"]))

    d10 = _collect(runs, "compare fig10", _fig10_data)
    if d10:
        fig = Figure(figsize=(8, 3.5))
        f_ds = {f_d for _, _, f_d in d10.values()}
        ax = _plot_fig10_axes(fig, next(iter(f_ds)))
        if len(f_ds) > 1:
            ax.set_ylabel("‖f_t‖ − f_d (N), f_d per run")
        for c, (run, (t, err, _)) in enumerate(d10.items()):
            ax.plot(t, err, color=f"C{c}", lw=0.8, alpha=0.75, label=str(run))
        ax.legend(fontsize=8)
        fig.suptitle(_title("Fig. 10  Chamfering force error", title))
        fig.tight_layout()
        paths.append(_save(fig, out_dir / COMPARE_NAMES["fig10"]))
    return paths
