"""Study files: a base scenario, a grid over scenario fields by dotted name
or Monte Carlo samples of them, the run duration, the metrics to collect
and a pass/fail rule per metric. Loaded with ``yaml_load_typed`` and
expanded, before any run starts, into full scenarios (YAML text) that are
each validated; a bad study is one :class:`ConfigError` line naming the
study field by its full dotted path (``study.sample.fields.part.pose.xyz``).
"""

import copy
from dataclasses import dataclass, field
import hashlib
import itertools
import math
import operator
from pathlib import Path
import re
from typing import Dict, List

import numpy as np
from pydrake.common.yaml import yaml_dump_typed, yaml_load_typed

from deburr_drake.config import (
    ConfigError,
    Scenario,
    field_type,
    load_scenario,
    set_field,
)
from deburr_drake.config.scenario import _check_yaml
from deburr_drake.sweep.results import METRICS

__all__ = [
    "Distribution",
    "SampleConfig",
    "Study",
    "Rule",
    "RunSpec",
    "load_study",
    "expand_runs",
    "parse_rule",
    "METRICS",
    "scenario_from_text",
    "KEY_VERSION",
    "check_reach",
    "rules_of",
    "metrics_of",
]

#: Part of every run's key: raise it when a change of the code makes old
#: results wrong (the key is otherwise the resolved scenario and duration).
KEY_VERSION = 1

DISTRIBUTIONS = ("uniform", "normal", "log_uniform")


@dataclass
class Distribution:
    """How one field is sampled: ``uniform`` and ``log_uniform`` in [low,
    high] (an integer field: uniform integers low..high), ``normal`` with
    ``mean`` and ``std`` (clipped to [low, high] where given)."""

    distribution: str = "uniform"
    low: float = math.nan
    high: float = math.nan
    mean: float = math.nan
    std: float = math.nan


@dataclass
class SampleConfig:
    """Monte Carlo: ``count`` runs, each field drawn independently, from a
    generator seeded with ``seed`` (run k's values do not depend on
    ``--limit``)."""

    seed: int = 0
    count: int = 0
    fields: Dict[str, Distribution] = field(default_factory=dict)


@dataclass
class Study:
    """A sweep: the runs are the base scenario with either every
    combination of the ``grid`` values or ``sample.count`` samples."""

    name: str = "study"
    base: str = "paper"  # a scenario name or a YAML path (from the study)
    base_text: str = ""  # YAML overrides on the base, as --scenario-text
    duration: float = 10.0  # s, simulated, every run
    grid: Dict[str, list[float]] = field(default_factory=dict)
    sample: SampleConfig = field(default_factory=SampleConfig)
    # What the results table holds (every rule's metric is added).
    metrics: List[str] = field(
        default_factory=lambda: [
            "chamfer_depth_rms_error_mm",
            "chamfering_force_rms_error_N",
        ]
    )
    # "METRIC OP NUMBER", OP one of <= < >= > == !=; a null metric fails.
    rules: List[str] = field(default_factory=list)
    keep_logs: bool = True  # each run's logs.npz next to its metrics.json


_OPS = {
    "<=": operator.le,
    "<": operator.lt,
    ">=": operator.ge,
    ">": operator.gt,
    "==": operator.eq,
    "!=": operator.ne,
}


@dataclass(frozen=True)
class Rule:
    text: str
    metric: str
    op: str
    value: float

    def passes(self, metric_value) -> bool:
        """False for a missing or non-finite value (null in metrics.json)."""
        if metric_value is None or not math.isfinite(metric_value):
            return False
        return bool(_OPS[self.op](metric_value, self.value))


def parse_rule(text: str, where: str) -> Rule:
    m = re.fullmatch(
        r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*(<=|>=|==|!=|<|>)\s*"
        r"(\S+)\s*",
        text,
    )
    if m is None:
        raise ConfigError(
            f"{where} = {text!r} is invalid: allowed "
            "'METRIC OP NUMBER', OP one of <= < >= > == !="
        )
    metric, op, value = m.groups()
    if metric not in METRICS:
        raise ConfigError(
            f"{where}: metric {metric!r} is unknown: allowed "
            f"{', '.join(METRICS)}"
        )
    try:
        number = float(value)
    except ValueError:
        raise ConfigError(
            f"{where} = {text!r}: {value!r} is not a number"
        ) from None
    if not math.isfinite(number):
        raise ConfigError(f"{where} = {text!r}: the bound must be finite")
    return Rule(text.strip(), metric, op, number)


@dataclass
class RunSpec:
    """One run: its place in the study, the values it was given by field,
    the full scenario as YAML and its key (a hash of that text, the
    duration and :data:`KEY_VERSION`)."""

    index: int
    params: Dict[str, float]
    scenario_text: str
    duration: float

    @property
    def key(self) -> str:
        h = hashlib.sha256(
            f"v{KEY_VERSION}\n{self.duration!r}\n{self.scenario_text}".encode()
        )
        return h.hexdigest()[:16]


def scenario_from_text(text: str) -> Scenario:
    """The scenario a :class:`RunSpec` carries (what a worker rebuilds)."""
    return yaml_load_typed(
        schema=Scenario, data=text, defaults=Scenario()
    ).validate()


def _study_error(e: Exception, where: str) -> ConfigError:
    return ConfigError(f"{where}: {' '.join(str(e).split())}")


def load_study(path, text=None) -> Study:
    """Reads and checks a study file (syntax, unknown or duplicate keys and
    types, with file:line:column; then every value); one ConfigError.
    ``text``: YAML overrides of the study's fields (``--study-text``), e.g.
    another base scenario and duration for the same samples."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"study {path}: no such file")
    overrides = text
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as e:
        raise ConfigError(f"study {path}: cannot read: {e}") from None
    _check_yaml(text, str(path), Study, "study")
    try:
        study = yaml_load_typed(schema=Study, data=text, defaults=Study())
    except (RuntimeError, ValueError, TypeError, AssertionError) as e:
        raise _study_error(e, str(path)) from None
    if overrides:
        _check_yaml(overrides, "--study-text", Study, "study")
        try:
            study = yaml_load_typed(data=overrides, defaults=study)
        except (RuntimeError, ValueError, TypeError, AssertionError) as e:
            raise _study_error(e, "--study-text") from None
    study._dir = path.resolve().parent
    return study


def _base(study: Study) -> Scenario:
    base = study.base
    folder = getattr(study, "_dir", Path.cwd())
    if base.endswith((".yaml", ".yml")) and not Path(base).is_absolute():
        base = str(folder / base)
    try:
        return load_scenario(base, text=study.base_text or None)
    except ConfigError as e:
        raise ConfigError(f"study.base: {e}") from None


def _check_field(scenario: Scenario, name: str, where: str):
    """The field's declared type (float, int), or ConfigError."""
    try:
        kind = field_type(scenario, name)
    except ConfigError as e:
        raise ConfigError(f"{where}: {e}") from None
    if kind not in (float, int):
        shown = getattr(kind, "__name__", str(kind))
        raise ConfigError(
            f"{where}: the field is of type {shown}: allowed "
            "a number field (a list's element by index, "
            "e.g. part.pose.xyz[0])"
        )
    return kind


def _check_distribution(d: Distribution, kind, where: str):
    def bad(message):
        raise ConfigError(f"{where}: {message}")

    if d.distribution not in DISTRIBUTIONS:
        bad(
            f"distribution = {d.distribution!r} is invalid: allowed one of "
            f"{', '.join(DISTRIBUTIONS)}"
        )
    if kind is int and d.distribution != "uniform":
        bad(
            f"an integer field cannot take a {d.distribution} distribution: "
            "allowed uniform (integers low..high)"
        )
    lo, hi = d.low, d.high
    if d.distribution in ("uniform", "log_uniform"):
        if not (math.isfinite(lo) and math.isfinite(hi)):
            bad(f"{d.distribution} needs finite low and high")
        if not lo < hi:
            bad(f"empty range: low = {lo!r} must be < high = {hi!r}")
        if d.distribution == "log_uniform" and lo <= 0:
            bad(f"log_uniform needs low > 0, got {lo!r}")
        if kind is int and (lo != int(lo) or hi != int(hi)):
            bad("an integer field needs integer low and high")
    else:
        if not (math.isfinite(d.mean) and math.isfinite(d.std) and d.std > 0):
            bad("normal needs a finite mean and std > 0")
        if math.isfinite(lo) and math.isfinite(hi) and not lo < hi:
            bad(f"empty range: low = {lo!r} must be < high = {hi!r}")


def _draw(d: Distribution, kind, rng: np.random.Generator, n: int):
    if d.distribution == "uniform":
        if kind is int:
            return rng.integers(int(d.low), int(d.high), n, endpoint=True)
        return rng.uniform(d.low, d.high, n)
    if d.distribution == "log_uniform":
        return np.exp(rng.uniform(math.log(d.low), math.log(d.high), n))
    values = rng.normal(d.mean, d.std, n)
    lo = d.low if math.isfinite(d.low) else -np.inf
    hi = d.high if math.isfinite(d.high) else np.inf
    return np.clip(values, lo, hi)


def _points(study: Study, base: Scenario) -> List[Dict[str, float]]:
    """The values of every run by field, in order."""
    grid, sample = study.grid, study.sample
    if grid and sample.fields:
        raise ConfigError("study.grid: give either grid or sample, not both")
    if not grid and not sample.fields:
        raise ConfigError(
            "study: give grid (values by field) or sample "
            "(a distribution by field)"
        )
    if grid:
        kinds = {}
        for name, values in grid.items():
            where = f"study.grid.{name}"
            kinds[name] = _check_field(base, name, where)
            if not values:
                raise ConfigError(f"{where}: empty list of values")
            if kinds[name] is int and any(v != int(v) for v in values):
                raise ConfigError(
                    f"{where} = {values}: an integer field needs integer values"
                )
        return [
            {
                name: (int(v) if kinds[name] is int else float(v))
                for name, v in zip(grid, combo)
            }
            for combo in itertools.product(*grid.values())
        ]
    where = "study.sample"
    if not (isinstance(sample.count, int) and sample.count >= 1):
        raise ConfigError(
            f"{where}.count = {sample.count!r} is invalid: "
            "allowed an integer >= 1"
        )
    if sample.seed < 0:
        raise ConfigError(
            f"{where}.seed = {sample.seed!r} is invalid: "
            "allowed an integer >= 0"
        )
    rng = np.random.default_rng(sample.seed)
    columns = {}
    for name, d in sample.fields.items():  # in the file's order
        kind = _check_field(base, name, f"{where}.fields.{name}")
        _check_distribution(d, kind, f"{where}.fields.{name}")
        drawn = _draw(d, kind, rng, sample.count)
        columns[name] = [int(v) if kind is int else float(v) for v in drawn]
    return [
        {name: columns[name][k] for name in columns}
        for k in range(sample.count)
    ]


def _invalid(study: Study, run_index: int, params, e: ConfigError):
    section = "grid" if study.grid else "sample.fields"
    shown = ", ".join(f"{n} = {v:.6g}" for n, v in params.items())
    return ConfigError(
        f"study.{section}: run {run_index} ({shown}) gives an "
        f"invalid scenario: {e}"
    )


def expand_runs(study: Study) -> List[RunSpec]:
    """Every run of the study as a full, validated scenario. ConfigError
    names the study field that gave an invalid scenario, and the run.
    (Whether the arm reaches the part: :func:`check_reach`.)"""
    if not (
        isinstance(study.duration, (int, float))
        and math.isfinite(study.duration)
        and study.duration > 0
    ):
        raise ConfigError(
            f"study.duration = {study.duration!r} is invalid: "
            "allowed a finite number > 0 (simulated seconds)"
        )
    if not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.+-]*", study.name):
        raise ConfigError(
            f"study.name = {study.name!r} is invalid: allowed a plain file name"
        )
    for k, name in enumerate(study.metrics):
        if name not in METRICS:
            raise ConfigError(
                f"study.metrics[{k}]: metric {name!r} is "
                f"unknown: allowed {', '.join(METRICS)}"
            )
    rules_of(study)
    base = _base(study)
    base.simulation.duration = float(study.duration)
    runs = []
    for index, params in enumerate(_points(study, base)):
        scenario = copy.deepcopy(base)
        for name, value in params.items():
            set_field(scenario, name, value)
        try:
            scenario.validate()
        except ConfigError as e:
            raise _invalid(study, index, params, e) from None
        runs.append(
            RunSpec(
                index, params, yaml_dump_typed(scenario), float(study.duration)
            )
        )
    return runs


def check_reach(study: Study, runs: List[RunSpec]):
    """ConfigError for the first run whose part the arm cannot reach (the
    inverse kinematics along the edge: about 0.1 s a run, so only for the
    runs about to start)."""
    from deburr_drake.cell.reach import check_part_in_reach

    for run in runs:
        try:
            check_part_in_reach(scenario_from_text(run.scenario_text))
        except ConfigError as e:
            raise _invalid(study, run.index, run.params, e) from None


def rules_of(study: Study) -> List[Rule]:
    return [
        parse_rule(t, f"study.rules[{k}]") for k, t in enumerate(study.rules)
    ]


def metrics_of(study: Study) -> List[str]:
    """The metrics the table holds: the study's, then the rules' own."""
    names = list(study.metrics)
    for rule in rules_of(study):
        if rule.metric not in names:
            names.append(rule.metric)
    return names
