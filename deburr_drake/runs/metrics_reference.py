"""The metrics reference page, generated at every docs build (docs/conf.py)
from the descriptions kept next to the code that computes the metrics:
:data:`deburr_drake.runs.pass_metrics.METRICS` and
:data:`deburr_drake.runs.report.SUMMARY_FIELDS`, and a job's
:data:`deburr_drake.runs.job_report.EDGE_FIELDS` and
:data:`~deburr_drake.runs.job_report.JOB_FIELDS`.

Use: ``write_metrics_reference("docs/metrics-reference.md")``."""

from __future__ import annotations

from pathlib import Path
from typing import Dict, List

from deburr_drake.runs.job_report import EDGE_FIELDS, JOB_FIELDS
from deburr_drake.runs.pass_metrics import (
    CONTACT_FORCE,
    METRICS,
    TRANSIENT,
    MetricDoc,
)
from deburr_drake.runs.report import SUMMARY_FIELDS

__all__ = ["metrics_reference_markdown", "write_metrics_reference"]

_FAMILIES = {
    "pass_metrics": "Contact",
    "finish_metrics": "Surface finish (Fig. 8)",
    "force_metrics": "Forces and depth tracking (Figs. 9-10)",
    "feed_metrics": "Feed",
    "estimate_metrics": "Contact estimate",
    "smoothness_metrics": "Smoothness",
    "status_metrics": "Status",
    "localisation_metrics": "Localisation (runs with localisation only)",
}


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("``", "`")


def _intro() -> List[str]:
    return [
        "# Metrics reference",
        "",
        "Generated from the descriptions next to the code that computes "
        "the metrics (`METRICS` in `deburr_drake/runs/pass_metrics.py`, "
        "`SUMMARY_FIELDS` in `deburr_drake/runs/report.py`) by "
        "`deburr_drake.runs.metrics_reference` at every docs build. "
        "`deburr-drake simulate` prints these metrics and writes them to "
        "`metrics.json`; `dd.pass_metrics(log)` returns them in Python.",
        "",
        "The name gives the unit where it is not SI (`_mm`, `_mm_s`); a "
        "metric over the cut is computed *after the transient*: from the "
        f"first contact (normal force above {CONTACT_FORCE:g} N) plus "
        f"{TRANSIENT:g} s (`TRANSIENT`). A metric this run cannot give "
        "(a run too short to leave the transient, a pass without burrs) "
        "is printed `n/a` and is `null` in `metrics.json`, with its "
        "reason under `unavailable`.",
        "",
    ]


def _family_table(family: str, docs: Dict[str, MetricDoc]) -> List[str]:
    out = [
        f"## {_FAMILIES.get(family, family)}",
        "",
        f"Computed by `pass_metrics.{family}`.",
        "",
        "| metric | unit | meaning | how it is computed |",
        "|---|---|---|---|",
    ]
    for name, doc in docs.items():
        out.append(
            f"| `{name}` | {doc.unit} | {_cell(doc.meaning)} "
            f"| {_cell(doc.how)} |"
        )
    return out + [""]


def metrics_reference_markdown() -> str:
    """The page (MyST Markdown): one table per family, then the rest of
    metrics.json."""
    families: Dict[str, Dict[str, MetricDoc]] = {}
    for name, doc in METRICS.items():
        families.setdefault(doc.family, {})[name] = doc
    out = _intro()
    for family, docs in families.items():
        out += _family_table(family, docs)
    out += [
        "## The rest of `metrics.json`",
        "",
        "How the run ended (`deburr_drake.runs.report.run_summary`):",
        "",
        "| key | unit | meaning |",
        "|---|---|---|",
    ]
    out += _field_table(SUMMARY_FIELDS)
    out += [
        "## A job's `metrics.json`",
        "",
        "A whole part's run (`deburr_drake.runs.job_report`; the guide is "
        "[a whole part: the job](job.md)) writes `edges`, one entry per "
        "planned cut in the job's order, `job`, and `stop_reason` (the "
        "job's, as in `job`). Each edge's values are the pass metrics "
        "above, computed on that edge's slice of the run (its own "
        "transient excluded), the rest:",
        "",
        "| key of an `edges` entry | unit | meaning |",
        "|---|---|---|",
    ]
    out += _field_table(EDGE_FIELDS)
    out += ["| key of `job` | unit | meaning |", "|---|---|---|"]
    out += _field_table(JOB_FIELDS)
    return "\n".join(out)


def _field_table(fields) -> List[str]:
    """The rows of a (unit, meaning) table, and a blank line."""
    return [
        f"| `{name}` | {unit} | {_cell(meaning)} |"
        for name, (unit, meaning) in fields.items()
    ] + [""]


def write_metrics_reference(path) -> str:
    """Writes :func:`metrics_reference_markdown` to ``path`` (only when it
    changed, so the docs build does not re-read it); returns it."""
    text = metrics_reference_markdown()
    path = Path(path)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    return text
