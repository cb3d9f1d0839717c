"""Sweeps and Monte Carlo studies on Dask (``deburr-drake sweep``): a study
file (:mod:`.study`), its runs as tasks in worker processes (:mod:`.runner`)
and the results table, summary and figures (:mod:`.results`)."""

from deburr_drake.sweep.results import (
    association,
    badness,
    wilson_interval,
    write_results,
)
from deburr_drake.sweep.runner import (
    SweepOutcome,
    read_result,
    run_scenario,
    run_sweep,
)
from deburr_drake.sweep.study import (
    METRICS,
    Distribution,
    Rule,
    RunSpec,
    SampleConfig,
    Study,
    check_reach,
    expand_runs,
    load_study,
    metrics_of,
    parse_rule,
    rules_of,
    scenario_from_text,
)

__all__ = [
    "Study",
    "SampleConfig",
    "Distribution",
    "Rule",
    "RunSpec",
    "METRICS",
    "load_study",
    "expand_runs",
    "check_reach",
    "parse_rule",
    "rules_of",
    "metrics_of",
    "scenario_from_text",
    "run_scenario",
    "run_sweep",
    "read_result",
    "SweepOutcome",
    "write_results",
    "wilson_interval",
    "association",
    "badness",
]
