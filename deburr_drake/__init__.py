"""deburr_drake: Drake reproduction of Hsu & Fu, adaptive fuzzy hybrid
position/force control of a deburring robot (IEEE T-RA, 2000).

The public Python API, importable from the package itself (docs/python-api.md;
``examples/`` and ``examples/tutorial.ipynb`` use it)::

    import deburr_drake as dd

    scenario = dd.load_scenario("paper", text="task: {desired_depth: 0.0006}")
    dd.set_field(scenario, "controller.fuzzy.order", 0)   # by dotted name
    plan = dd.plan_cell(scenario)          # resolved once: gains, edges, start
    diagram = dd.make_deburring_diagram(plan)
    log = dd.simulate(diagram, plan.scenario, duration=3.0)  # a RunLog
    log["chamfer"]["f_n"]                                 # named arrays
    values = dd.pass_metrics(log, only_cut=True)          # metrics by name
    dd.make_figures(dd.log_arrays(log, values), "out/figs")

- scenarios: :func:`load_scenario` (name or YAML file, plus YAML overrides),
  :func:`set_field` / :func:`get_field` (a field by dotted name),
  :class:`Scenario`, :class:`ConfigError`, :func:`scenario_names`;
- the cell: :func:`plan_cell` (a :class:`CellPlan`: the scenario resolved
  once), :func:`make_deburring_diagram`, :data:`LOGGED` (logger name ->
  system and port), :func:`make_contour`;
- running: :func:`simulate`, :func:`run` (build and simulate),
  :func:`run_pass` (build, simulate and the metrics, from a plan),
  :class:`RunLog`, :func:`make_simulator`;
- results: :func:`pass_metrics`, :func:`log_arrays`, :func:`write_run`,
  :func:`make_figures`, :func:`compare_figures`, :func:`write_graphs`,
  :func:`write_recording` (HTML replay), :func:`contact_truth`;
- the paper's loops inside your own Diagram: :func:`add_deburring_controller`
  and the systems :class:`HybridController`, :class:`CommandGenerator`,
  :class:`FirstOrderHold`, :class:`ContactParameterEstimator`,
  :class:`ChamferObserver`, :class:`ForceSensor`, :class:`CuttingProcess`;
  edge geometry :class:`CircularContour`, :class:`StraightContour`,
  :class:`ProfileContour`; signal
  layouts :data:`CHAMFER_STATE`, :data:`CONTROLLER_DIAGNOSTICS`,
  :data:`COMMAND_STATE`.

Names load on first use, so ``import deburr_drake`` (and the pure-numpy
modules of ``deburr_drake.math``: ``fuzzy``, ``geometry``, ``metrics``)
import no Drake.

The package is layered (pyproject.toml's import-linter contracts hold it):
``math`` at the ground, ``config`` on it, ``control`` (the paper's systems),
``cell`` (the simulated cell), ``runs`` (simulating and reporting), the
capabilities ``analysis``, ``sweep``, and ``cli`` on top. A module imports
only from its own layer or below.
"""

import importlib

#: Each module's public names, in the order of the docstring above.
_MODULES = {
    "config": (
        "load_scenario",
        "Scenario",
        "ConfigError",
        "scenario_names",
        "set_field",
        "get_field",
    ),
    "cell.plan": ("plan_cell", "CellPlan"),
    "cell.diagram": ("make_deburring_diagram", "LOGGED"),
    "cell.edge": ("make_contour",),
    "runs.simulation": ("simulate", "RunLog", "make_simulator"),
    "runs.passes": ("run", "run_pass"),
    "cell.truth": ("contact_truth",),
    "runs.pass_metrics": ("pass_metrics",),
    "runs.report": ("log_arrays", "write_run"),
    "runs.figures": ("make_figures", "compare_figures"),
    "runs.graphs": ("write_graphs",),
    "runs.replay": ("write_recording",),
    "control.loop": ("add_deburring_controller", "DeburringController"),
    "control.controller": ("HybridController",),
    "control.command": ("CommandGenerator", "FirstOrderHold"),
    "control.estimator": ("ContactParameterEstimator",),
    "control.observer": ("ChamferObserver",),
    "cell.sensor": ("ForceSensor",),
    "cell.process": ("CuttingProcess",),
    "math.geometry": ("CircularContour", "StraightContour"),
    "math.profile": ("ProfileContour",),
    "control.layout": (
        "CHAMFER_STATE",
        "CONTROLLER_DIAGNOSTICS",
        "COMMAND_STATE",
    ),
}
#: Public name -> the module that defines it.
_EXPORTS = {
    name: module for module, names in _MODULES.items() for name in names
}

__all__ = list(_EXPORTS)


def __getattr__(name):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'deburr_drake' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"deburr_drake.{module}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
