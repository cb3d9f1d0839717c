"""The docs site (docs/, README.md): the dataflow figure is the diagram's
wiring, the README stays short and its links resolve, every page's Python
runs (tests/test_examples.py runs them), and the site builds with warnings
as errors (the build itself is .ci/run's command, not a timed test)."""

import importlib.util
from pathlib import Path
import re

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _script(name):
    spec = importlib.util.spec_from_file_location(
        name, ROOT / "scripts" / f"{name}.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_dataflow_figure_is_the_diagrams_wiring():
    figure = _script("dataflow_figure")
    committed = (DOCS / "figures" / "dataflow.dot").read_text()
    assert committed == figure.paper_dataflow_dot(), (
        "the diagram's wiring changed: run python scripts/dataflow_figure.py"
    )
    assert (DOCS / "figures" / "dataflow.svg").stat().st_size > 10_000
    # The loop is there: the sensor reaches the controller, the controller
    # the plant.
    assert (
        '"force_sensor" -> "controller" [label="measured_force"]' in committed
    )
    assert '"controller" -> "drive_saturation"' in committed


def test_readme_is_short_and_its_links_resolve():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    links = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text)
    local = [link for link in links if "://" not in link]
    assert len(local) >= 10
    missing = [link for link in local if not (ROOT / link).exists()]
    assert missing == []


def test_every_page_is_in_the_site():
    """Each page under docs/ (not the drafts) is in a toctree of index.md
    (Sphinx warns about orphans too; this names them without a build)."""
    index = (DOCS / "index.md").read_text()
    pages = {p.stem for p in DOCS.glob("*.md")} - {"index"}
    pages.add("tutorial")
    missing = [p for p in sorted(pages) if f"\n{p}\n" not in index]
    assert missing == []


@pytest.mark.slow
def test_the_metrics_reference_describes_every_metric_of_a_run():
    """A short run with localisation gives every metric (null where it is
    too short); metrics.json holds them and how the run ended. Each is
    described next to its code, and nothing described is gone."""
    import deburr_drake as dd
    from deburr_drake.runs.metrics_reference import (
        metrics_reference_markdown,
    )
    from deburr_drake.runs.pass_metrics import (
        MESH_ONLINE_METRICS,
        MESH_PROBE_METRICS,
        METRICS,
        force_at_desired_depth,
        pass_metrics,
    )
    from deburr_drake.runs.report import SUMMARY_FIELDS, run_summary

    scenario = dd.load_scenario("paper_localised")
    log = dd.run(scenario, 0.5)
    values = pass_metrics(
        log, true_force_at_desired_depth=force_at_desired_depth(scenario)
    )
    assert set(values) <= set(METRICS)
    assert set(run_summary(log, values)) <= set(METRICS) | set(SUMMARY_FIELDS)
    # Given only when probing finished, and only by a mesh part's probe
    # or registration while cutting: the code computes them still.
    assert set(METRICS) - set(values) == {"probe_registration_error_mm"} | set(
        MESH_PROBE_METRICS
    ) | set(MESH_ONLINE_METRICS)
    code = (ROOT / "deburr_drake" / "runs" / "pass_metrics.py").read_text()
    described = code.index("METRICS: Dict")
    code = code[:described] + code[code.index("\n}\n", described) :]
    for name in ("probe_registration_error_mm", "probe_mahalanobis"):
        assert f'"{name}"' in code
    page = metrics_reference_markdown()
    for name in set(METRICS) | set(SUMMARY_FIELDS):
        assert f"| `{name}` |" in page
    for name, doc in METRICS.items():
        assert doc.unit and doc.meaning and doc.how, name


def test_readme_lists_every_shipped_scenario():
    shipped = sorted(
        p.stem for p in (ROOT / "deburr_drake" / "scenarios").glob("*.yaml")
    )
    text = (ROOT / "README.md").read_text()
    assert [name for name in shipped if f"`{name}`" not in text] == []


def test_pytest_names_the_reason_of_each_skip():
    """The README promises the skipped tests' reasons: -rs prints them."""
    config = (ROOT / "pyproject.toml").read_text()
    assert re.search(r'^addopts = ".*-rs', config, re.M)
