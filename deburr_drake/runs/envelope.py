"""The stability envelope over burr size and desired force: one burr per
run on the paper cell, its pass/fail bounds and per-run numbers.

``scripts/envelope.py`` runs the grid in parallel processes and prints the
table. The numbers of one run come from :func:`burr_metrics`, a pure numpy
function of the logged arrays; the bounds from :func:`burr_bounds`.

Bounds (SI units), for desired chamfering force f_d, the threshold force
P'_th, the cutting coefficient k_c (times the edge's removal_scale at
delta*), the cut height h (the cutter's
engagement), the desired depth delta*, a burr of cross-section A_b
(height x thickness):

- the feed the outer loop's law gives off the burr, in steady cutting:
  v_off = (f_d - P'_th) / (k_c delta* h), at most max_feed, v0 where f_d -
  P'_th is within v_eps (math.feedrate.FeedrateLaw.steady_feed);
- the true chamfering force stays below 2 f_d + k_c A_b v_off: twice the
  desired force, plus what the burr would cut at the feed the tool had
  before the law saw the burr;
- the tool's speed along the edge stays below 1.5 v_off: the fastest steady
  feed of the pass plus half of it for transients (a surge runs far past
  it);
- the true chamfer depth, while the cutter's front is on the burr, stays
  within 0.05 mm RMS of delta*.

The force and speed bounds hold from the end of the contact transient
(``pass_metrics.TRANSIENT`` after first contact, as every pass metric), when the
cutter is still ``LEAD_TIME`` of feed short of the burr. Before it the
depth is still growing and the feed law runs fast on the shallow cut (at
15 N the tool reaches 7.2 mm/s at 0.5 s, depth 0.27 mm): a start-up
transient the same with or without a burr.
"""

from __future__ import annotations

import copy
from dataclasses import asdict, dataclass
import math
from typing import Callable, Dict, Iterable, List, Optional

import numpy as np

from deburr_drake.config import ConfigError
from deburr_drake.control.command import edge_steady_feed, feedrate_law
from deburr_drake.math import metrics
from deburr_drake.runs.pass_metrics import TRANSIENT

__all__ = [
    "BurrCell",
    "burr_bounds",
    "burr_metrics",
    "burr_scenario",
    "run_burr_cell",
    "GRID_HEIGHTS",
    "GRID_LENGTHS",
    "GRID_FORCES",
    "grid",
    "off_burr_feed",
    "DEPTH_RMS_LIMIT",
    "SPEED_FACTOR",
    "LEAD_TIME",
    "run_cells",
]

#: The envelope's grid: burr height (m), burr length (m of arc), desired
#: chamfering force (N).
GRID_HEIGHTS = (0.0005, 0.001, 0.0015, 0.002)
GRID_LENGTHS = (0.003, 0.008, 0.020, 0.040)
GRID_FORCES = (5.0, 10.0, 15.0)

#: m, RMS of the true depth error on the burr.
DEPTH_RMS_LIMIT = 5.0e-5
#: The tool's speed bound as a multiple of the steady feed off the burr.
SPEED_FACTOR = 1.5
#: s of steady cutting at the off-burr feed before the cutter reaches the
#: burr (after the contact transient).
LEAD_TIME = 3.0


@dataclass
class BurrCell:
    """One cell of the envelope: a burr (m) and a desired force (N)."""

    height: float
    length: float
    force: float
    thickness: float = 0.002  # m

    @property
    def label(self) -> str:
        return (
            f"h {self.height * 1e3:.1f} mm, L {self.length * 1e3:.0f} "
            f"mm, f_d {self.force:.0f} N"
        )


def grid(
    heights: Iterable[float] = GRID_HEIGHTS,
    lengths: Iterable[float] = GRID_LENGTHS,
    forces: Iterable[float] = GRID_FORCES,
) -> List[BurrCell]:
    return [
        BurrCell(h, length, f)
        for f in forces
        for h in heights
        for length in lengths
    ]


def _cutting_coefficient(scenario) -> float:
    """k_c times the edge's removal_scale at its start at delta* (N s/m^3):
    g per area of cross-section there (1.1 k_c on the paper's bore)."""
    from deburr_drake.cell.edge import make_contour
    from deburr_drake.math.geometry import removal_scale

    contour = make_contour(scenario)
    return scenario.process.cutting_coefficient * removal_scale(
        contour.curvature(contour.point_at(0.0)),
        scenario.task.desired_depth,
        scenario.tool.cutter_radius,
    )


def off_burr_feed(scenario) -> float:
    """v_off (m/s): the feed law's steady feed off the burrs at the edge's
    start (control.command.edge_steady_feed)."""
    from deburr_drake.cell.edge import make_contour

    contour = make_contour(scenario)
    return edge_steady_feed(
        scenario, curvature=contour.curvature(contour.point_at(0.0))
    )


def burr_bounds(scenario, cell: BurrCell) -> Dict[str, float]:
    """The pass bounds of a cell (N, m/s, m); see the module docstring."""
    v_off = off_burr_feed(scenario)
    k_c = _cutting_coefficient(scenario)
    return {
        "max_chamfering_force_N": 2 * cell.force
        + k_c * cell.height * cell.thickness * v_off,
        "max_tool_speed_m_s": SPEED_FACTOR * v_off,
        "depth_rms_error_on_burr_m": DEPTH_RMS_LIMIT,
    }


def burr_scenario(
    base,
    cell: BurrCell,
    *,
    lead_time: float = LEAD_TIME,
    max_duration: float = 40.0,
):
    """``base`` (a Scenario) with one burr of ``cell`` placed so that the
    cutter's front reaches it ``lead_time`` s of off-burr feed after the
    contact transient, the desired force of ``cell``, and a stop once the
    command is 1 mm past the burr (or at ``max_duration`` s)."""
    from deburr_drake.cell.edge import make_contour
    from deburr_drake.config import BurrConfig

    sc = copy.deepcopy(base)
    sc.task.desired_chamfering_force = cell.force
    length = make_contour(sc).length
    v_off = off_burr_feed(sc)
    start = (TRANSIENT + lead_time) * v_off + sc.tool.cutter_radius
    center = start + cell.length / 2
    if center + cell.length / 2 >= length:
        raise ConfigError(
            f"{cell.label}: the burr does not fit on the edge "
            f"({length * 1e3:.1f} mm)"
        )
    sc.process.burrs = [
        BurrConfig(
            center_fraction=center / length,
            length=cell.length,
            height=cell.height,
            thickness=cell.thickness,
        )
    ]
    sc.simulation.stop_after_passes = (center + cell.length / 2 + 1e-3) / length
    sc.simulation.duration = max_duration
    sc.name = (
        f"{base.name}_burr_{cell.height * 1e3:g}mm_"
        f"{cell.length * 1e3:g}mm_{cell.force:g}N"
    )
    return sc.validate()


def burr_metrics(
    signals: Dict[str, Dict[str, np.ndarray]], scenario, cell: BurrCell
) -> Dict[str, float]:
    """The envelope's numbers of one run from its logged ``process`` and
    ``chamfer`` signals (RunLog.signals), SI units:

    - ``max_chamfering_force_N``: the true ||f_t|| from TRANSIENT after
      first contact (||f_n|| > 1 N) on;
    - ``max_tool_speed_m_s``: the true speed along the edge, the same span;
    - ``depth_rms_error_on_burr_m``: true depth minus delta* while the
      cutter's front is on the burr (burr area at the front > 0);
    - ``feed_on_burr_m_s``: the mean speed along the edge there, and
      ``feed_law_on_burr_m_s``, the feed law's steady value there
      (FeedrateLaw.steady_feed on the true g of (3); ``scenario``'s f_d,
      which :func:`burr_scenario` sets to the cell's);
    - ``burr_reached``: 1.0 when the front reached the burr;
    - ``nan``: 1.0 when any logged signal holds a NaN;
    - ``passed``: 1.0 when every bound of :func:`burr_bounds` holds and the
      burr was reached without NaN.
    """
    proc, ch = signals["process"], signals["chamfer"]
    t_contact = metrics.first_time(ch["t"], ch["f_n"] > 1.0)
    after = metrics.window(proc["t"], t_contact + TRANSIENT)
    on = metrics.window(proc["t"], t_contact) & (proc["burr_area"] > 0.0)
    law = feedrate_law(scenario.command, scenario.task).steady_feed(proc["g"])
    nan = metrics.any_nan(
        *[v for blocks in signals.values() for v in blocks.values()]
    )
    out = {
        "max_chamfering_force_N": float(np.max(proc["f_t"][after]))
        if np.any(after)
        else math.nan,
        "max_tool_speed_m_s": float(np.max(proc["v_t"][after]))
        if np.any(after)
        else math.nan,
        "depth_rms_error_on_burr_m": metrics.rms(
            proc["delta"][on] - scenario.task.desired_depth
        ),
        "feed_on_burr_m_s": float(np.mean(proc["v_t"][on]))
        if np.any(on)
        else math.nan,
        "feed_law_on_burr_m_s": float(np.mean(law[on]))
        if np.any(on)
        else math.nan,
        "burr_reached": float(np.any(on)),
        "nan": float(nan),
    }
    bounds = burr_bounds(scenario, cell)
    ok = (
        (not nan)
        and bool(np.any(on))
        and all(
            np.isfinite(out[k]) and out[k] <= limit
            for k, limit in bounds.items()
        )
    )
    out["passed"] = float(ok)
    return out


def run_burr_cell(
    cell: BurrCell, base_name: str = "paper", base_text: Optional[str] = None
) -> Dict[str, object]:
    """Simulates one cell (in this process) and returns its numbers, the
    bounds and the run's simulated and wall time."""
    from deburr_drake.cell.diagram import make_deburring_diagram
    from deburr_drake.config import load_scenario
    from deburr_drake.runs.simulation import simulate

    base = load_scenario(base_name, text=base_text)
    sc = burr_scenario(base, cell)
    log = simulate(
        make_deburring_diagram(scenario=sc), sc, loggers=("process", "chamfer")
    )
    return {
        "cell": asdict(cell),
        "bounds": burr_bounds(sc, cell),
        "sim_time_s": log.sim_time,
        "wall_time_s": log.wall_time,
        **burr_metrics(log.signals, sc, cell),
    }


def run_cells(
    run: Callable,
    cells: list,
    *args,
    workers: int = 2,
    on_row: Optional[Callable] = None,
) -> List[dict]:
    """``run(cell, *args)`` for every cell in ``workers`` spawned
    processes; the rows in the cells' order, a crashed run as {"cell",
    "error", "passed": 0.0}; ``on_row(cell, row)`` as each is ready."""
    from concurrent.futures import ProcessPoolExecutor
    import multiprocessing

    rows = []
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(workers, mp_context=context) as pool:
        futures = [pool.submit(run, cell, *args) for cell in cells]
        for cell, future in zip(cells, futures):
            try:
                row = future.result()
            except Exception as e:  # a crashed run is a failed cell
                row = {"cell": vars(cell), "error": repr(e), "passed": 0.0}
            rows.append(row)
            if on_row is not None:
                on_row(cell, row)
    return rows
