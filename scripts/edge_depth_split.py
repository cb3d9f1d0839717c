"""Where a mesh edge's chamfer-depth error comes from, split from one run's
logs.npz (after the transient, as the metrics judge it) and its scenario:

- metric: the finish bins' RMS (each bin keeps the deepest cut) against
  the RMS of the tool's depth sample by sample;
- the depth at the tool, delta - delta* = (delta_d - delta*) + n1 . (x_c* -
  z) - n1 . e: the depth reference the force loop moved, the command's
  own offset from the path along n1 (the hold's chord and lag) and the
  position loop's tracking error along n1 (e on the task axes, turned to
  the world by the contour's task frame);
- the finish bins judged, split into the first 5 mm after the transient
  (the entry) and the rest;
- the tool axis's turn and the lag it leaves in the orientation loop;
- the same error against the normal-force error: its share that
  (f_n - f_nd) / c1 explains (c1 fitted) and the rest;
- with ``--cross-hole``: the reference path itself against the true
  cylinder-cylinder intersection of models/parts/cross_hole.stl (the rim
  of an 8 mm hole through a tube of 30 mm outer radius): the edge point,
  the tool axis, n1 and the depth a tool on the fitted path would cut on
  the true part.

    python scripts/edge_depth_split.py OUT SCENARIO [--cross-hole]
"""

import argparse
import json
from pathlib import Path

import numpy as np

from deburr_drake.cell.edge import make_contour
from deburr_drake.config.scenario import load_scenario
from deburr_drake.math import metrics
from deburr_drake.runs.pass_metrics import TRANSIENT


def rms_mm(x):
    return float(np.sqrt(np.mean(np.square(x)))) * 1e3


def depth_split(logs, contour) -> dict:
    t = logs["chamfer.t"]
    late = t > float(logs["meta.contact_start"]) + TRANSIENT
    d_star = float(logs["meta.desired_depth"])
    n1, x_p = logs["chamfer.n1"][late], logs["chamfer.x_p"][late]
    delta = logs["chamfer.delta"][late]
    arc = logs["chamfer.arc_position"][late]
    z = x_p - delta[:, None] * n1
    frames = np.array([contour.task_frame(s) for s in arc])
    e = np.einsum("kij,kj->ki", frames, logs["controller.e"][late])
    f_n = logs["chamfer.f_n"][late]
    f_nd = logs["desired_normal_force.value"][late, 0]
    error = delta - d_star
    fit = np.polyfit(f_n - f_nd, error, 1)
    explained = np.polyval(fit, f_n - f_nd)
    return {
        "depth_rms_mm": rms_mm(error),
        "depth_mean_mm": float(np.mean(error)) * 1e3,
        "reference_delta_d_rms_mm": rms_mm(
            logs["controller.delta_d"][late] - d_star
        ),
        "command_along_n1_rms_mm": rms_mm(
            np.einsum("ij,ij->i", logs["reference.value"][late] - z, n1)
        ),
        "tracking_along_n1_rms_mm": rms_mm(-np.einsum("ij,ij->i", e, n1)),
        "normal_force_error_rms_N": rms_mm(f_n - f_nd) / 1e3,
        "depth_per_force_mm_N": float(fit[0]) * 1e3,
        "force_explained_rms_mm": rms_mm(explained),
        "force_unexplained_rms_mm": rms_mm(error - explained),
    }


def orientation_lag(logs, contour, scenario, step=1e-5) -> dict:
    """The turn rate of the tool axis a(s) at the tool's feed and the lag
    it leaves in an orientation loop with no feed-forward of the turn
    (s_o = lambda_o e_o - omega: e_o = omega / lambda_o), about the
    tangent (where it tilts the cutter's side across n1), and that tilt
    times the engagement (um): how far the cutter's side at the edge
    moves from where the tip puts it. The process measures the depth at
    the tip, so this is outside the metric."""
    t = logs["chamfer.t"]
    late = t > float(logs["meta.contact_start"]) + TRANSIENT
    arc = logs["chamfer.arc_position"][late]
    feed = np.einsum(
        "ij,ij->i", logs["chamfer.xdot_p"][late], logs["chamfer.n2"][late]
    )
    a = np.array([contour.tool_axis_at(s) for s in arc])
    ahead = np.array(
        [contour.tool_axis_at(min(s + step, contour.length)) for s in arc]
    )
    omega = np.cross(a, (ahead - a) / step) * feed[:, None]
    lam = float(scenario.controller.orientation_lambda[0])
    tilt = np.einsum("ij,ij->i", omega, logs["chamfer.n2"][late]) / lam
    return {
        "axis_turn_rate_max_rad_s": float(
            np.max(np.linalg.norm(omega, axis=1))
        ),
        "orientation_lag_rms_mrad": rms_mm(tilt),
        "lag_at_edge_rms_um": rms_mm(tilt * scenario.tool.engagement) * 1e3,
    }


def finish_regions(logs, contour, cutter_radius, entry=5e-3) -> dict:
    """The finish bins' RMS error (mm) over the bins the metric judges (the
    transient's bins left out as ``finish_metrics`` does), split into the
    first ``entry`` (m) of arc after them and the rest."""
    arc, depth = logs["finish.arc"], logs["finish.depth"]
    error = depth - float(logs["meta.desired_depth"])
    t, s = logs["process.t"], logs["process.arc_position"]
    contact = float(logs["meta.contact_start"])
    L, closed = contour.length, contour.closed
    transient = (t >= contact) & (t <= contact + TRANSIENT)
    span = s[transient]
    if closed:
        span = np.unwrap(span / L * 2 * np.pi) * L / (2 * np.pi)
    first, last = span[0], span.max()
    skipped = metrics.arc_span_mask(arc, first - cutter_radius, last, L, closed)
    near = ~skipped & metrics.arc_span_mask(arc, last, last + entry, L, closed)
    judged = ~skipped
    return {
        "finish_judged_rms_mm": rms_mm(error[judged]),
        "finish_entry_rms_mm": rms_mm(error[near]),
        "finish_after_entry_rms_mm": rms_mm(error[judged & ~near]),
    }


def cross_hole_reference(scenario, contour, samples=2000) -> dict:
    """The fitted path against the true rim (part frame: tube about z, outer
    radius 30 mm; hole about x, radius 8 mm, at z = 40 mm)."""
    part, _, _ = scenario.part.edge.mesh_edge(scenario.part.pose)
    R, rho, h = 0.030, 0.008, 0.040
    r, e = scenario.tool.cutter_radius, scenario.tool.engagement
    phi = np.linspace(0.0, 2 * np.pi, 100_000, endpoint=False)
    y, zz = rho * np.cos(phi), h + rho * np.sin(phi)
    x = np.sqrt(R * R - y * y)
    rim = np.column_stack([x, y, zz]) @ part.rotation.T + part.translation
    axis = (np.column_stack([x, y, 0 * x]) / R) @ part.rotation.T
    tangent = np.gradient(rim, axis=0)
    n1 = np.cross(tangent, axis)
    n1 /= np.linalg.norm(n1, axis=1)[:, None]
    hole = np.column_stack([0 * x, y, zz - h]) @ part.rotation.T
    n1 *= np.sign(np.einsum("ij,ij->i", n1, hole))[:, None]
    path = rim - r * n1 - e * axis
    off, axis_error, n1_error, point_error = [], [], [], []
    for s in np.linspace(0.0, contour.length, samples, endpoint=False):
        z = contour.point_at(s)
        k = int(np.argmin(np.linalg.norm(path - z, axis=1)))
        off.append(n1[k] @ (z - path[k]))
        a = contour.tool_axis_at(s)
        axis_error.append(np.arccos(np.clip(a @ axis[k], -1.0, 1.0)))
        n1_error.append(np.arccos(np.clip(contour.n1(z) @ n1[k], -1.0, 1.0)))
        point_error.append(
            np.min(np.linalg.norm(rim - contour.edge_point(s), axis=1))
        )
    return {
        "edge_point_rms_um": rms_mm(point_error) * 1e3,
        "tool_axis_rms_mrad": rms_mm(axis_error),
        "tool_axis_max_mrad": float(np.max(axis_error)) * 1e3,
        "n1_rms_mrad": rms_mm(n1_error),
        "path_depth_offset_rms_um": rms_mm(off) * 1e3,
        "path_depth_offset_max_um": float(np.max(np.abs(off))) * 1e6,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="a simulate --out folder")
    parser.add_argument("scenario", help="the scenario the run was of")
    parser.add_argument("--cross-hole", action="store_true")
    args = parser.parse_args()
    scenario = load_scenario(args.scenario)
    contour = make_contour(scenario)
    with np.load(args.out / "logs.npz") as logs:
        logs = dict(logs)
    split = depth_split(logs, contour)
    split.update(finish_regions(logs, contour, scenario.tool.cutter_radius))
    split.update(orientation_lag(logs, contour, scenario))
    metrics = json.loads((args.out / "metrics.json").read_text())
    split["finish_rms_mm"] = metrics["chamfer_depth_rms_error_mm"]
    if args.cross_hole:
        split.update(cross_hole_reference(scenario, contour))
    for name, value in split.items():
        print(f"{name:28s} {value:10.5f}")


if __name__ == "__main__":
    main()
