"""One pass of a planned cell: build, simulate, the metrics against the
contact truth, and (optionally) the files. What every command runs
(``simulate``, ``sweep``, ``batch``, ``compare``, ``converge``).

Use: ``result = run_pass(plan_cell(scenario))``; ``result.log`` is the
:class:`deburr_drake.runs.simulation.RunLog`, ``result.metrics`` the
:func:`deburr_drake.runs.pass_metrics.pass_metrics` of it. :func:`run`
builds and simulates a scenario in one call."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, Optional, Union

from pydrake.systems.framework import Diagram

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.cell.plan import CellPlan, plan_cell
from deburr_drake.config import Scenario
from deburr_drake.runs.pass_metrics import PassMetrics, pass_metrics
from deburr_drake.runs.simulation import RunLog, simulate

__all__ = ["PassResult", "run_pass", "run", "truth_force"]


@dataclass
class PassResult:
    """What :func:`run_pass` gives: the log, its metrics, the diagram
    run, the files written ({"logs": path, "metrics": path}, if any) and
    why the contact truth is missing ("" when it is there or was not
    asked for)."""

    log: RunLog
    metrics: PassMetrics
    diagram: Diagram
    files: Dict[str, str] = field(default_factory=dict)
    no_truth: str = ""


def truth_force(plan: CellPlan) -> tuple:
    """(||f_n|| at the desired depth from the plan's contact truth, "") or
    (None, why not): the metrics then leave out what needs it."""
    try:
        return plan.contact_truth().force_at_desired_depth, ""
    except Exception as e:
        return None, f"{type(e).__name__}: {e}"


def run_pass(
    plan: CellPlan,
    *,
    diagram: Optional[Diagram] = None,
    duration: Optional[float] = None,
    truth: Union[bool, float, None] = True,
    out=None,
    **simulate_kwargs,
) -> PassResult:
    """Builds ``plan``'s diagram (or runs ``diagram``, built from it),
    simulates it (:func:`deburr_drake.runs.simulation.simulate`, with
    ``duration`` and ``simulate_kwargs``), and computes the pass's
    metrics, over the bins cut when the pass did not complete.

    ``truth``: True, the plant's force at the desired depth from the
    plan's contact truth (computed once per plan); a number, that force
    (N); False or None, none (the metrics that need it are then null with
    their reason). ``out``: a directory to write logs.npz and
    metrics.json into (deburr_drake.runs.report.write_run)."""
    if diagram is None:
        diagram = make_deburring_diagram(plan)
    log = simulate(diagram, plan.scenario, duration=duration, **simulate_kwargs)
    no_truth = ""
    if truth is True:
        force, no_truth = truth_force(plan)
    else:
        force = truth or None
    values = pass_metrics(
        log,
        true_force_at_desired_depth=force,
        only_cut=not log.completed_pass,
    )
    result = PassResult(log, values, diagram, no_truth=no_truth)
    if out is not None:
        from deburr_drake.runs import report

        result.files = report.write_run(log, out, values)
    return result


def run(scenario: Scenario, duration: float, **kwargs) -> RunLog:
    """Plans the scenario's cell, builds and simulates it for
    ``duration`` s (:func:`run_pass`, without the contact truth); returns
    the log. ``kwargs`` go to :func:`simulate`."""
    return run_pass(
        plan_cell(scenario), duration=duration, truth=False, **kwargs
    ).log
