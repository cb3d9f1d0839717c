"""The envelope of the paper's cell over profile edges: fillet radius x
side (a pocket's inner edge, a boss's outer edge) x desired chamfering
force, on a 60 mm square profile, each run a partial pass through one
corner and along both sides of it.

A cell's run starts ``LEAD`` of path before the first fillet (or in the
middle of the right side if that side is shorter), so that the contact
transient (``pass_metrics.TRANSIENT``) is over on the line before the
corner, and stops ``TAIL`` of path past the fillet's end: the corner and a
piece of line on each side, which is what differs between cells (the rest
of the square repeats it four times). No burrs: the envelope is over the
edge's curvature.

Bounds (the pass criteria for a profile): the pass reached its end
(``pass_complete``, no guard, no NaN), the chamfer depth left on the edge
within 0.05 mm RMS and 0.1 mm at most of delta* (the bins the cutter
passed after the transient), the chamfering force within 1.5 N RMS of the
desired one. Reported too: the feed on the line before the fillet and in
it against the feed law's steady values there, (f_d - P'_th) / (k_c s
delta* h) with s = removal_scale of the line (1) and of the fillet: the
law slows in a pocket's corners (s > 1) and speeds up round a boss's
(s < 1)."""

from __future__ import annotations

import copy
from dataclasses import asdict, dataclass
import math
from typing import Dict, Iterable, List, Optional

import numpy as np

from deburr_drake.control.command import edge_steady_feed
from deburr_drake.runs.pass_metrics import TRANSIENT, pass_metrics

__all__ = [
    "FilletCell",
    "GRID_FILLETS",
    "GRID_SIDES",
    "GRID_FORCES",
    "HALF_SIDE",
    "LEAD",
    "TAIL",
    "LIMITS",
    "grid",
    "fillet_scenario",
    "first_fillet",
    "fillet_metrics",
    "run_fillet_cell",
    "law_feeds",
]

#: m: cutter radius + 1 mm to 30 mm (the 60 mm square's circle) on the
#: paper's 3 mm cutter.
GRID_FILLETS = (0.004, 0.008, 0.015, 0.030)
GRID_SIDES = ("inner", "outer")
GRID_FORCES = (5.0, 10.0, 15.0)
#: m, half the side of the square profile.
HALF_SIDE = 0.030
#: m of path on the line before the fillet from the start (after the
#: transient's path at the fastest feed, 2 s x 4.3 mm/s at 15 N).
LEAD = 0.012
#: m of path past the fillet's end before the run stops.
TAIL = 0.006
#: The pass bounds (m, N).
LIMITS = {
    "chamfer_depth_rms_error_mm": 0.05,
    "chamfer_depth_max_error_mm": 0.1,
    "chamfering_force_rms_error_N": 1.5,
}


@dataclass
class FilletCell:
    """One cell: fillet radius (m), side, desired chamfering force (N)."""

    fillet: float
    side: str
    force: float

    @property
    def label(self) -> str:
        kind = "pocket" if self.side == "inner" else "boss"
        return f"{kind} R {self.fillet * 1e3:g} mm, f_d {self.force:g} N"


def grid(
    fillets: Iterable[float] = GRID_FILLETS,
    sides: Iterable[str] = GRID_SIDES,
    forces: Iterable[float] = GRID_FORCES,
) -> List[FilletCell]:
    return [FilletCell(r, s, f) for s in sides for r in fillets for f in forces]


def first_fillet(contour):
    """(start, end) arc positions (m) of the first fillet the pass meets:
    the one the start lies in, or the next one."""
    L = contour.length
    best = None
    for _, _, _, u, length in contour.arcs():
        a = float(contour.parameter_to_arc(u))
        if a > L - length + 1e-9:  # the start lies inside it
            a -= L
        if best is None or a < best[0]:
            best = (a, a + length)
    return best


def fillet_scenario(base, cell: FilletCell, *, max_duration: float = 90.0):
    """``base`` (a Scenario) on the cell's square profile, no burrs, the
    cell's desired force, from ``LEAD`` before the first fillet to
    ``TAIL`` past it."""
    from deburr_drake.cell.edge import make_contour

    sc = copy.deepcopy(base)
    h, r = HALF_SIDE, cell.fillet
    sc.part.edge.kind = "profile"
    sc.part.edge.vertices = [[-h, -h], [h, -h], [h, h], [-h, h]]
    sc.part.edge.fillet_radius = r
    sc.part.edge.side = cell.side
    sc.part.edge.direction = 1
    # the right side's path runs at x = h -+ cutter radius up to y = h - r
    x = (
        h - sc.tool.cutter_radius
        if cell.side == "inner"
        else h + sc.tool.cutter_radius
    )
    sc.part.edge.start_angle = math.atan2(max(0.0, h - r - LEAD), x)
    sc.task.desired_chamfering_force = cell.force
    sc.process.burrs = []
    contour = make_contour(sc)
    _, end = first_fillet(contour)
    sc.simulation.stop_after_passes = (end + TAIL) / contour.length
    sc.simulation.duration = max_duration
    sc.name = f"{base.name}_{cell.side}_R{r * 1e3:g}mm_{cell.force:g}N"
    return sc.validate()


def law_feeds(scenario, curvature: float):
    """(line, fillet) steady feeds (m/s) of the feed law
    (control.command.edge_steady_feed), the fillet's of ``curvature``
    (1/m)."""
    return (
        edge_steady_feed(scenario),
        edge_steady_feed(scenario, curvature=curvature),
    )


def fillet_metrics(log, scenario) -> Dict[str, float]:
    """The cell's numbers (pass metrics over the bins the cutter passed,
    feeds on the line before the fillet and in it, the law's values
    there) and ``passed``."""
    from deburr_drake.cell.edge import make_contour

    values = pass_metrics(log, only_cut=True)
    contour = make_contour(scenario)
    start, end = first_fillet(contour)
    proc = log["process"]
    t, arc, v = proc["t"], proc["arc_position"], proc["v_t"]
    L = contour.length
    s = (
        np.where(arc > L - 1e-3 + min(start, 0.0), arc - L, arc)
        if start < 0
        else arc
    )
    contact = values.get("contact_time_s", math.nan)
    after = t >= (contact if np.isfinite(contact) else 0.0) + TRANSIENT
    on_line = after & (s < start)
    in_fillet = after & (s >= start) & (s <= end)
    kappa = contour.curvature(contour.point_at(0.5 * (start + end) % L))
    law_line, law_fillet = law_feeds(scenario, kappa)
    out = {k: float(values[k]) for k in LIMITS}
    out.update(
        {
            "edge_coverage": float(values["edge_coverage"]),
            "completed_pass": float(log.completed_pass),
            "stop_reason": log.stop_reason,
            "fillet_curvature_1_m": float(kappa),
            "feed_line_mm_s": float(np.mean(v[on_line]) * 1e3)
            if np.any(on_line)
            else math.nan,
            "feed_fillet_mm_s": float(np.mean(v[in_fillet]) * 1e3)
            if np.any(in_fillet)
            else math.nan,
            "law_line_mm_s": law_line * 1e3,
            "law_fillet_mm_s": law_fillet * 1e3,
        }
    )
    ok = log.completed_pass and all(
        np.isfinite(out[k]) and out[k] <= limit for k, limit in LIMITS.items()
    )
    out["passed"] = float(ok)
    return out


def run_fillet_cell(
    cell: FilletCell, base_name: str = "paper", base_text: Optional[str] = None
) -> Dict[str, object]:
    """Simulates one cell (in this process) and returns its numbers and
    the run's simulated and wall time."""
    from deburr_drake.cell.diagram import make_deburring_diagram
    from deburr_drake.config import load_scenario
    from deburr_drake.runs.simulation import simulate

    sc = fillet_scenario(load_scenario(base_name, text=base_text), cell)
    log = simulate(make_deburring_diagram(scenario=sc), sc)
    return {
        "cell": asdict(cell),
        "sim_time_s": log.sim_time,
        "wall_time_s": log.wall_time,
        **fillet_metrics(log, sc),
    }
