"""A batch of parts through one cell: ``deburr-drake batch``.

K parts in sequence, each with its own part error drawn from a
distribution (the offset uniform over a disc of radius ``max_offset``, the
yaw uniform within +-``max_yaw``): probe, cut, next. The cell learns across
parts: the contact estimates c hat (``estimator.initial_estimates`` of the
next part, which also start the online registration's contact parameters)
and the learned fuzzy weights theta (the controller's state at the start
of the next part) carry over from one part to the next (from the last part
that ended well: a part a guard stopped leaves nothing); ``fresh`` starts
every part cold. Per part: the pass's metrics, the cycle time, and the
depth error over the first 10 % of the edge (:func:`first_edge_error`).

Use::

    parts = run_batch(load_scenario("paper_localised"), count=10, seed=1,
                      max_offset=0.001)
    write_batch(parts, "out/batch")   # batch.csv, batch.json, batch.md, png
"""

from __future__ import annotations

import copy
import csv
from dataclasses import dataclass, field
import json
import math
from pathlib import Path
from typing import Callable, Dict, List, Optional

import numpy as np

from deburr_drake.cell.plan import plan_cell
from deburr_drake.config import ConfigError, Scenario
from deburr_drake.runs.pass_metrics import first_edge_error
from deburr_drake.runs.passes import run_pass
from deburr_drake.runs.simulation import RunLog

__all__ = [
    "BatchPart",
    "CarriedState",
    "draw_part_errors",
    "run_batch",
    "write_batch",
    "batch_table",
    "BATCH_COLUMNS",
    "CARRY",
]

#: The table's columns: (key, header).
BATCH_COLUMNS = (
    ("part", "part"),
    ("offset_x_mm", "offset x (mm)"),
    ("offset_y_mm", "offset y (mm)"),
    ("stop_reason", "stop"),
    ("chamfer_depth_rms_error_mm", "depth RMS (mm)"),
    ("first_10pct_depth_rms_error_mm", "first 10 % RMS (mm)"),
    ("probing_time_s", "probing (s)"),
    ("cycle_time_s", "cycle (s)"),
    ("c0_hat_N", "c0 hat (N)"),
    ("c1_hat_N_per_mm", "c1 hat (N/mm)"),
)


@dataclass
class CarriedState:
    """What one part leaves to the next: the contact estimates (c0 N, c1
    N/m, c2 N s/m) and the fuzzy rule weights (axes x rules)."""

    estimates: np.ndarray
    theta: np.ndarray

    @classmethod
    def of(cls, log: RunLog) -> Optional["CarriedState"]:
        est = log.signals.get("estimates")
        theta = log.signals.get("theta")
        if est is None or theta is None or not len(est["t"]):
            return None
        return cls(
            np.asarray(est["value"][-1], float),
            np.asarray(theta["final"], float),
        )

    def apply(self, scenario: Scenario) -> Scenario:
        """The next part's scenario starting from these estimates (each at
        least its lower bound)."""
        s = copy.deepcopy(scenario)
        bounds = s.estimator.lower_bounds
        s.estimator.initial_estimates = [
            max(float(v), float(b)) for v, b in zip(self.estimates, bounds)
        ]
        return s

    def set_theta(self, diagram, context):
        controller = diagram.GetSubsystemByName("controller")
        cc = controller.GetMyMutableContextFromRoot(context)
        x = cc.get_continuous_state_vector().CopyToVector()
        x[1 : 1 + self.theta.size] = self.theta.ravel()
        cc.SetContinuousState(x)


@dataclass
class BatchPart:
    part: int
    offset: List[float]  # m, part_error.offset (believed - real)
    yaw: float  # rad
    metrics: Dict[str, float] = field(default_factory=dict)
    stop_reason: str = ""
    #: The pass's PassMetrics (values with the reasons of the missing).
    values: Optional[object] = field(default=None, repr=False)

    def row(self) -> Dict[str, object]:
        m = self.metrics
        return {
            "part": self.part,
            "offset_x_mm": self.offset[0] * 1e3,
            "offset_y_mm": self.offset[1] * 1e3,
            "stop_reason": self.stop_reason,
            **{k: m.get(k, float("nan")) for k, _ in BATCH_COLUMNS[4:]},
        }


def draw_part_errors(
    count: int, *, seed: int, max_offset: float, max_yaw: float = 0.0
) -> List[tuple]:
    """``count`` (offset (3, m), yaw (rad)) drawn with ``seed``: the offset
    uniform over the horizontal disc of radius ``max_offset``, the yaw
    uniform in [-max_yaw, max_yaw]."""
    if not (isinstance(count, int) and count >= 1):
        raise ConfigError(
            f"count = {count!r} is invalid: allowed an integer >= 1"
        )
    for name, v in (("max_offset", max_offset), ("max_yaw", max_yaw)):
        if not (math.isfinite(v) and v >= 0):
            raise ConfigError(
                f"{name} = {v!r} is invalid: allowed a finite number >= 0"
            )
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        r = max_offset * math.sqrt(rng.uniform())
        a = rng.uniform(0.0, 2 * math.pi)
        yaw = rng.uniform(-max_yaw, max_yaw) if max_yaw > 0 else 0.0
        out.append(([r * math.cos(a), r * math.sin(a), 0.0], yaw))
    return out


#: What a batch carries from part to part (``carry``).
CARRY = ("all", "estimates", "weights")


def run_batch(
    scenario: Scenario,
    *,
    count: int,
    seed: int,
    max_offset: float,
    max_yaw: float = 0.0,
    fresh: bool = False,
    carry: str = "all",
    duration: Optional[float] = None,
    on_part: Optional[Callable[[BatchPart, RunLog], None]] = None,
) -> List[BatchPart]:
    """Runs ``count`` parts of ``scenario`` in sequence (see the module);
    ``duration`` (s) caps each part's run (the scenario's by default).
    ``carry``: ``all`` (c hat and theta), ``estimates`` (c hat only) or
    ``weights`` (theta only) pass from part to part (nothing with
    ``fresh``). ``on_part(part, log)`` is called after each part (progress,
    files)."""
    if carry not in CARRY:
        raise ConfigError(
            f"carry = {carry!r} is invalid: allowed one of {CARRY}"
        )
    scenario.validate()
    errors = draw_part_errors(
        count, seed=seed, max_offset=max_offset, max_yaw=max_yaw
    )
    carried: Optional[CarriedState] = None
    parts = []
    for k, (offset, yaw) in enumerate(errors, start=1):
        s = copy.deepcopy(scenario)
        s.name = f"{scenario.name}_part{k}"
        s.part_error.offset = list(offset)
        s.part_error.yaw = yaw
        use = carried is not None and not fresh
        if use and carry in ("all", "estimates"):
            s = carried.apply(s)
        s.validate()
        done = run_pass(
            plan_cell(s),
            duration=duration,
            initial_state=(
                carried.set_theta
                if use and carry in ("all", "weights")
                else None
            ),
        )
        log, values = done.log, done.metrics
        metrics = {k2: float(v) for k2, v in values.items()}
        metrics["first_10pct_depth_rms_error_mm"] = first_edge_error(log)
        est = log.signals.get("estimates")
        if est is not None and len(est["t"]):
            metrics["c0_hat_N"] = float(est["value"][-1][0])
            metrics["c1_hat_N_per_mm"] = float(est["value"][-1][1]) / 1e3
        part = BatchPart(
            part=k,
            offset=list(offset),
            yaw=yaw,
            metrics=metrics,
            stop_reason=log.stop_reason,
            values=values,
        )
        parts.append(part)
        if on_part is not None:
            on_part(part, log)
        # A part a guard stopped (or NaN) leaves nothing to learn from: the
        # next part starts from what the last good part left.
        if log.stop_reason in ("pass_complete", "duration"):
            carried = CarriedState.of(log) or carried
    return parts


def _fmt(v) -> str:
    if isinstance(v, str):
        return v
    if isinstance(v, (int, np.integer)):
        return str(v)
    return "n/a" if not np.isfinite(v) else f"{v:.4g}"


def batch_table(parts: List[BatchPart]) -> str:
    """The per-part table as Markdown."""
    lines = [
        "| " + " | ".join(h for _, h in BATCH_COLUMNS) + " |",
        "|" + "---|" * len(BATCH_COLUMNS),
    ]
    for p in parts:
        row = p.row()
        lines.append(
            "| " + " | ".join(_fmt(row[k]) for k, _ in BATCH_COLUMNS) + " |"
        )
    return "\n".join(lines)


def write_batch(parts: List[BatchPart], out, *, label: str = "") -> Dict:
    """batch.csv, batch.json (every metric of every part), batch.md (the
    table) and batch.png (depth RMS and the first 10 % of the edge's RMS
    per part) in ``out``; returns their paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = {
        "csv": out / "batch.csv",
        "json": out / "batch.json",
        "md": out / "batch.md",
        "png": out / "batch.png",
    }
    with open(paths["csv"], "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=[k for k, _ in BATCH_COLUMNS])
        w.writeheader()
        for p in parts:
            w.writerow(p.row())

    def clean(v):
        return v if not isinstance(v, float) or math.isfinite(v) else None

    paths["json"].write_text(
        json.dumps(
            [
                {
                    "part": p.part,
                    "offset_m": p.offset,
                    "yaw_rad": p.yaw,
                    "stop_reason": p.stop_reason,
                    "metrics": {k: clean(v) for k, v in p.metrics.items()},
                }
                for p in parts
            ],
            indent=1,
            allow_nan=False,
        )
    )
    paths["md"].write_text(batch_table(parts) + "\n")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    k = [p.part for p in parts]
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for key, name in (
        ("first_10pct_depth_rms_error_mm", "first 10 % of the edge"),
        ("chamfer_depth_rms_error_mm", "whole pass"),
    ):
        ax.plot(
            k, [p.metrics.get(key, np.nan) for p in parts], "o-", label=name
        )
    ax.axhline(0.05, color="k", lw=0.8, ls="--", label="0.05 mm rule")
    ax.set_xlabel("part")
    ax.set_ylabel("depth RMS error (mm)")
    ax.set_title(label or "batch")
    ax.legend()
    fig.tight_layout()
    fig.savefig(paths["png"], dpi=120)
    plt.close(fig)
    return paths
