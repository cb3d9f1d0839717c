"""The docs site (docs/, README.md): the dataflow figure is the diagram's
wiring, the README stays short and its links resolve, every page's Python
runs (tests/test_examples.py runs them), and the site builds with warnings
as errors (the build itself is .ci/run's command, not a timed test)."""

import importlib.util
from pathlib import Path
import re

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
