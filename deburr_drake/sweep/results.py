"""A sweep's results: the table (``results.csv``, one row per run), the
summary (``summary.json``: success rate per rule with a 95 % Wilson
interval) and the figures (each metric's distribution; success and
failure against the two parameters that separate them best). Pure numpy
and matplotlib: nothing here imports Drake."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

__all__ = [
    "METRICS",
    "LOCALISATION_METRICS",
    "wilson_interval",
    "association",
    "badness",
    "binned_success",
    "table_rows",
    "write_table",
    "summarize",
    "write_summary",
    "plot_metrics",
    "plot_failures",
    "write_results",
]


#: What a run can report (runs.pass_metrics, plus the sweep's own
#: ``guard_tripped`` and ``run_failed``: 1.0 or 0.0); a metric a run does
#: not report (the probe's without probing) is null in its row.
METRICS = (
    "contact_time_s",
    "chamfer_depth_mean_error_mm",
    "chamfer_depth_rms_error_mm",
    "chamfer_depth_max_error_mm",
    "edge_coverage",
    "burr_remaining_max_mm",
    "chamfering_force_rms_error_N",
    "normal_force_rms_error_N",
    "depth_tracking_rms_error_mm",
    "feed_mean_on_burrs_mm_s",
    "feed_mean_off_burrs_mm_s",
    "predicted_force_at_desired_depth_N",
    "true_force_at_desired_depth_N",
    "force_prediction_error_rel",
    "torque_total_variation",
    "fuzzy_term_total_variation",
    "control_surface_roughness_N",
    "sliding_variable_p01_mm_s",
    "sliding_variable_p99_mm_s",
    "feed_at_max_fraction",
    "sim_time_s",
    "wall_time_s",
    "completed_pass",
    "nan_detected",
    "guard_tripped",
    "run_failed",
)

#: What a run with localisation reports besides: its probing and
#: registration (the localisation family of runs.pass_metrics.METRICS).
LOCALISATION_METRICS = (
    "probing_time_s",
    "pass_time_s",
    "cycle_time_s",
    "probe_touches",
    "probe_touches_kept",
    "probe_fit_rms_mm",
    "probe_offset_x_mm",
    "probe_offset_y_mm",
    "probe_yaw_rad",
    "probe_radius_mm",
    "probe_registration_error_mm",
    "online_offset_x_mm",
    "online_offset_y_mm",
    "online_yaw_rad",
    "online_registration_error_mm",
    *(
        f"{name}{axis}_{unit}"
        for name, unit in (
            ("probe_position_error", "mm"),
            ("probe_orientation_error", "deg"),
            ("probe_sigma_position", "mm"),
            ("probe_sigma_orientation", "deg"),
        )
        for axis in ("", "_x", "_y", "_z")
    ),
    "probe_mahalanobis",
    "probe_hole_size_mm",
    "probe_sigma_hole_size_mm",
    "probe_amplification",
    # a mesh part's registration while cutting and its final registration
    "online_offset_z_mm",
    "online_rotation_deg",
    "registration_position_error_mm",
    "registration_orientation_error_deg",
)
METRICS = METRICS + LOCALISATION_METRICS


def wilson_interval(successes: int, n: int, z: float = 1.959964):
    """The Wilson score interval of a binomial proportion (95 % for the
    default z); (nan, nan) for n = 0."""
    if n == 0:
        return (math.nan, math.nan)
    p = successes / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


def _ranks(x: np.ndarray) -> np.ndarray:
    """Ranks 1..n, ties given their average rank."""
    order = np.argsort(x, kind="mergesort")
    ranks = np.empty(len(x))
    sorted_x = x[order]
    i = 0
    while i < len(x):
        j = i
        while j + 1 < len(x) and sorted_x[j + 1] == sorted_x[i]:
            j += 1
        ranks[order[i : j + 1]] = (i + j) / 2 + 1
        i = j + 1
    return ranks


def _spearman(x: np.ndarray, y: np.ndarray) -> float:
    rx, ry = _ranks(x), _ranks(y)
    if np.ptp(rx) == 0 or np.ptp(ry) == 0:
        return math.nan
    return float(np.corrcoef(rx, ry)[0, 1])


def association(values: Sequence[float], badness: Sequence[float]) -> float:
    """How well one parameter explains how badly the runs did: |Spearman
    rank correlation| of the parameter with ``badness`` (0: not at all, 1:
    monotonically), or of its distance from its median if that is larger
    (runs that fail at both ends of a symmetric range, e.g. a position error
    of either sign). nan when either is constant."""
    x = np.asarray(values, float)
    b = np.asarray(badness, float)
    ok = np.isfinite(x) & np.isfinite(b)
    x, b = x[ok], b[ok]
    if x.size < 3:
        return math.nan
    scores = [abs(_spearman(x, b)), abs(_spearman(np.abs(x - np.median(x)), b))]
    scores = [v for v in scores if math.isfinite(v)]
    return max(scores) if scores else math.nan


def badness(rows: List[dict], rules) -> np.ndarray:
    """How badly each run did on the rule the most runs fail: its metric
    (larger is worse for <= and <, smaller for >= and >, a null the worst);
    for == and != rules, or without rules, 1 for a failed run, 0 else."""
    failed = np.array([not row["pass_all"] for row in rows], float)
    if not rules:
        return failed
    counts = [
        sum(not row[f"pass: {rule.text}"] for row in rows) for rule in rules
    ]
    rule = rules[int(np.argmax(counts))]
    if rule.op not in ("<=", "<", ">=", ">") or not max(counts):
        return np.array([float(not row[f"pass: {rule.text}"]) for row in rows])
    sign = 1.0 if rule.op in ("<=", "<") else -1.0
    values = np.array(
        [
            np.nan if row[rule.metric] is None else sign * row[rule.metric]
            for row in rows
        ]
    )
    worst = np.nanmax(values) + 1.0 if np.isfinite(values).any() else 1.0
    return np.where(np.isfinite(values), values, worst)


def _number(value):
    if value is None or isinstance(value, bool):
        return None if value is None else float(value)
    try:
        value = float(value)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def table_rows(
    runs, results: Dict[str, Optional[dict]], metrics: List[str], rules
) -> List[dict]:
    """One row per run with a result: index, key, stop reason, the run's
    parameters, every metric (None: null) and each rule's verdict."""
    rows = []
    for run in runs:
        result = results.get(run.key)
        if result is None:
            continue
        row = {
            "index": run.index,
            "key": run.key,
            "stop_reason": result.get("stop_reason"),
            "stop_time_s": _number(result.get("stop_time_s")),
        }
        row.update(run.params)
        for name in metrics:
            row[name] = _number(result.get(name))
        # A run that raised or crashed has no metrics to judge: it fails
        # every rule (guard_tripped == 0 would pass it).
        broken = row["stop_reason"] in ("error", "crash")
        verdicts = [
            not broken and rule.passes(_number(result.get(rule.metric)))
            for rule in rules
        ]
        for rule, ok in zip(rules, verdicts):
            row[f"pass: {rule.text}"] = ok
        row["pass_all"] = all(verdicts)
        row["run_wall_time_s"] = _number(result.get("run_wall_time_s"))
        row["stop_detail"] = (result.get("stop_detail") or "").split("\n")[0][
            :200
        ]
        rows.append(row)
    return rows


def write_table(rows: List[dict], path) -> Path:
    """CSV, empty cells for null metrics."""
    path = Path(path)
    columns = list(rows[0]) if rows else ["index", "key", "stop_reason"]
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        writer.writeheader()
        for row in rows:
            writer.writerow(
                {k: ("" if v is None else v) for k, v in row.items()}
            )
    return path


def _explaining(rows, params: List[str], rules) -> List[dict]:
    bad = badness(rows, rules)
    scores = [
        {"parameter": p, "association": association([r[p] for r in rows], bad)}
        for p in params
    ]
    return sorted(
        scores,
        key=lambda s: (
            -(s["association"] if math.isfinite(s["association"]) else -1)
        ),
    )


def summarize(
    study,
    rows: List[dict],
    rules,
    metrics: List[str],
    params: List[str],
    *,
    runs_total: int,
    wall_time_s=None,
) -> dict:
    """The sweep in numbers (strict JSON: no nan)."""
    n = len(rows)
    summary = {
        "study": study.name,
        "duration_s": study.duration,
        "metric_window": "from 2 s after the first contact "
        "(pass_metrics.TRANSIENT) to the run's end",
        "runs_requested": runs_total,
        "runs_finished": n,
        "stop_reasons": {},
        "rules": [],
        "metrics": {},
    }
    for row in rows:
        reason = row["stop_reason"]
        summary["stop_reasons"][reason] = (
            summary["stop_reasons"].get(reason, 0) + 1
        )
    summary["rules"] = _rule_rates(rows, rules)
    summary["metrics"] = {name: _metric_stats(rows, name) for name in metrics}
    scores = _explaining(rows, params, rules)
    summary["failures_explained_by"] = [
        {
            "parameter": s["parameter"],
            "association": s["association"]
            if math.isfinite(s["association"])
            else None,
        }
        for s in scores
    ]
    passed = [row["pass_all"] for row in rows]
    summary["success_by_parameter"] = {
        s["parameter"]: binned_success(
            [row[s["parameter"]] for row in rows], passed
        )
        for s in scores[:2]
        if math.isfinite(s["association"])
    }
    summary["wall_time_s"] = wall_time_s
    summary["run_cpu_time_s"] = float(
        sum(row["run_wall_time_s"] or 0.0 for row in rows)
    )
    return summary


def _rule_rates(rows: List[dict], rules) -> List[dict]:
    """Each rule's (and all rules') passes, success rate and its 95 %
    Wilson interval."""
    n = len(rows)
    verdicts = [
        (rule.text, [row[f"pass: {rule.text}"] for row in rows])
        for rule in rules
    ]
    verdicts.append(("all rules", [row["pass_all"] for row in rows]))
    out = []
    for text, ok in verdicts:
        k = int(sum(ok))
        lo, hi = wilson_interval(k, n)
        out.append(
            {
                "rule": text,
                "passed": k,
                "runs": n,
                "success_rate": k / n if n else None,
                "ci95": [lo, hi] if n else None,
            }
        )
    return out


def _metric_stats(rows: List[dict], name: str) -> dict:
    """The metric's count, nulls and, when any, its distribution."""
    values = np.array(
        [row[name] for row in rows if row[name] is not None], float
    )
    entry = {"n": int(values.size), "null": len(rows) - int(values.size)}
    if values.size:
        entry.update(
            mean=float(values.mean()),
            median=float(np.median(values)),
            p5=float(np.percentile(values, 5)),
            p95=float(np.percentile(values, 95)),
            min=float(values.min()),
            max=float(values.max()),
        )
    return entry


def binned_success(
    values: Sequence[float], passed: Sequence[bool], bins: int = 5
) -> List[dict]:
    """The success rate in ``bins`` equal-count bins of one parameter
    (with each bin's range and 95 % Wilson interval): where in that
    parameter's range the runs fail."""
    x = np.asarray(values, float)
    ok = np.asarray(passed, bool)
    keep = np.isfinite(x)
    x, ok = x[keep], ok[keep]
    if not x.size:
        return []
    order = np.argsort(x, kind="mergesort")
    out = []
    for chunk in np.array_split(order, min(bins, x.size)):
        k, n = int(ok[chunk].sum()), int(chunk.size)
        lo, hi = wilson_interval(k, n)
        out.append(
            {
                "low": float(x[chunk].min()),
                "high": float(x[chunk].max()),
                "passed": k,
                "runs": n,
                "success_rate": k / n,
                "ci95": [lo, hi],
            }
        )
    return out


def write_summary(summary: dict, path) -> Path:
    path = Path(path)
    with open(path, "w") as f:
        json.dump(summary, f, indent=2, allow_nan=False)
    return path


def plot_metrics(
    rows: List[dict], metrics: List[str], rules, path, title: str = ""
) -> Path:
    """One histogram per metric, the rules' bounds as dashed lines, the
    count of null values in each title."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(metrics)
    cols = min(3, max(n, 1))
    nrows = max(1, math.ceil(n / cols))
    fig, axes = plt.subplots(
        nrows, cols, figsize=(4.2 * cols, 3.2 * nrows), squeeze=False
    )
    for ax, name in zip(axes.flat, metrics):
        values = np.array([r[name] for r in rows if r[name] is not None], float)
        nulls = len(rows) - values.size
        if values.size:
            ax.hist(
                values,
                bins=min(40, max(5, values.size // 4)),
                color="tab:blue",
                alpha=0.8,
            )
        for rule in rules:
            if rule.metric == name:
                ax.axvline(
                    rule.value, color="tab:red", ls="--", label=rule.text
                )
                ax.legend(fontsize=7)
        ax.set_title(
            f"{name}" + (f" ({nulls} null)" if nulls else ""), fontsize=8
        )
        ax.set_ylabel("runs")
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    fig.suptitle(title or "metric distributions")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def plot_failures(
    rows: List[dict], params: List[str], rules, path, title: str = ""
) -> Path:
    """Passed and failed runs (all rules) against the two parameters that
    explain best how badly the runs did (:func:`association` with
    :func:`badness`), failed runs marked by how they stopped."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    failed = np.array([not r["pass_all"] for r in rows], bool)
    explained = _explaining(rows, params, rules)
    ranked = [s["parameter"] for s in explained]
    fig, ax = plt.subplots(figsize=(6.5, 5))
    if not ranked:
        ax.text(0.5, 0.5, "no parameters", ha="center")
    else:
        px = ranked[0]
        py = ranked[1] if len(ranked) > 1 else None
        x = np.array([r[px] for r in rows], float)
        y = (
            np.array([r[py] for r in rows], float)
            if py
            else np.zeros(len(rows))
        )
        stops = np.array([r["stop_reason"] or "" for r in rows])
        normal = np.isin(stops, ("duration", "pass_complete"))
        ax.scatter(
            x[~failed],
            y[~failed],
            c="tab:green",
            s=18,
            label=f"pass ({int((~failed).sum())})",
        )
        sel = failed & normal
        ax.scatter(
            x[sel],
            y[sel],
            c="tab:red",
            marker="x",
            s=30,
            label=f"fail, ran to the end ({int(sel.sum())})",
        )
        sel = failed & ~normal
        if sel.any():
            ax.scatter(
                x[sel],
                y[sel],
                c="black",
                marker="^",
                s=30,
                label=f"fail, stopped: guard / nan / error / crash "
                f"({int(sel.sum())})",
            )
        scores = {s["parameter"]: s["association"] for s in explained}
        ax.set_xlabel(f"{px} (association {scores[px]:.2f})")
        if py:
            ax.set_ylabel(f"{py} (association {scores[py]:.2f})")
        ax.legend(fontsize=8)
    ax.set_title(title or "success and failure (all rules)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def write_results(
    study, runs, results, out_dir, *, rules, metrics, wall_time_s=None
) -> Dict[str, Path]:
    """results.csv, summary.json, metrics.png and failures.png in
    ``out_dir``, from every run of ``runs`` that has a result."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    params = list(runs[0].params) if runs else []
    # The table holds every metric a run reports, the study's first; the
    # summary and the figures the study's.
    rows = table_rows(
        runs,
        results,
        list(metrics) + [m for m in METRICS if m not in metrics],
        rules,
    )
    files = {"table": write_table(rows, out / "results.csv")}
    summary = summarize(
        study,
        rows,
        rules,
        metrics,
        params,
        runs_total=len(runs),
        wall_time_s=wall_time_s,
    )
    files["summary"] = write_summary(summary, out / "summary.json")
    if rows:
        files["metrics_figure"] = plot_metrics(
            rows,
            metrics,
            rules,
            out / "metrics.png",
            title=f"{study.name}: {len(rows)} runs of {study.duration:g} s",
        )
        files["failures_figure"] = plot_failures(
            rows,
            params,
            rules,
            out / "failures.png",
            title=f"{study.name}: {len(rows)} runs, all rules",
        )
    files["summary_data"] = summary
    return files
