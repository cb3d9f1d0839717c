"""Sphinx configuration of the deburr_drake site.

Build it (warnings are errors, internal links checked) with the command in the
README: ``python -m sphinx -W --keep-going -n -b html docs docs/_build/html``
(``.ci/run`` runs it). Three pages are generated here at every build, never
written by hand: ``scenario-reference.md`` from the config dataclasses
(``deburr_drake.config.reference``), ``metrics-reference.md`` from the
metrics' descriptions next to their code
(``deburr_drake.runs.metrics_reference``) and ``api/*.md``, one page per module
of the package (autodoc), so a module, a field or a metric added later is
documented without touching the docs.
"""

from pathlib import Path
import pkgutil
import sys

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS.parent))

import deburr_drake  # noqa: E402
from deburr_drake.config.reference import write_scenario_reference  # noqa
from deburr_drake.runs.metrics_reference import write_metrics_reference  # noqa

project = "deburr_drake"
author = "the deburr_drake developers"
copyright = "2026, the deburr_drake developers"
release = "0.1.0"

extensions = [
    "myst_nb",  # Markdown (myst-parser) and the notebook
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",  # the docstrings' Args: and Returns:
    "sphinx.ext.mathjax",
]
source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb"}
# docs/drafts/: other branches' feature notes, moved into the pages at merge.
exclude_patterns = ["_build", "drafts", "**/.ipynb_checkpoints"]
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]
# The tutorial is committed without outputs and executed by the tests
# (tests/test_examples.py); the site shows its code and text only, so the
# build needs no kernel and takes seconds.
nb_execution_mode = "off"

html_theme = "furo"
html_title = "deburr_drake"
html_static_path = []

autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_typehints = "none"
# Types in docstrings name numpy and pydrake classes this site does not
# document; a link that cannot resolve is not a broken link of the site.
# (?s): a role whose target a docstring wraps over two lines (``Contour.
# curvature`` in math.geometry.removal_scale) has a newline in its target.
nitpick_ignore_regex = [(r"py:.*", r"(?s).*")]


def _modules():
    """Every module of the package, by layer (package order)."""
    names = []
    for info in pkgutil.walk_packages(deburr_drake.__path__, "deburr_drake."):
        # A package's __main__ runs its command when imported.
        if not info.name.endswith(".__main__"):
            names.append(info.name)
    return sorted(names)


LAYERS = [
    ("Ground: math", "deburr_drake.math"),
    ("Ground: config", "deburr_drake.config"),
    ("The paper's controller: control", "deburr_drake.control"),
    ("The simulated cell: cell", "deburr_drake.cell"),
    ("Running and reporting: runs", "deburr_drake.runs"),
    ("Stability analysis: analysis", "deburr_drake.analysis"),
    ("Sweeps and studies: sweep", "deburr_drake.sweep"),
    ("Command line: cli", "deburr_drake.cli"),
]


def _write(path: Path, text: str):
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def write_api_pages():
    api = DOCS / "api"
    api.mkdir(exist_ok=True)
    modules = _modules()
    wanted = set()
    index = [
        "# API reference",
        "",
        "Generated from the docstrings of every module (autodoc). The "
        "public names are importable from the package itself "
        "(`import deburr_drake as dd`; [Python API](../python-api.md)); "
        "the modules are listed by layer, top to bottom as in "
        "[What is where](../layout.md) read upwards.",
        "",
    ]
    top = [
        "# `deburr_drake`",
        "",
        "```{eval-rst}",
        ".. automodule:: deburr_drake",
        "   :no-members:",
        "```",
        "",
    ]
    _write(api / "deburr_drake.md", "\n".join(top))
    wanted.add("deburr_drake.md")
    toc = ["deburr_drake"]
    for title, package in LAYERS:
        members = [
            m for m in modules if m == package or m.startswith(package + ".")
        ]
        if not members:
            continue
        index += [f"## {title}", ""]
        for name in members:
            page = f"{name}.md"
            wanted.add(page)
            toc.append(name)
            index.append(f"- [`{name}`]({page})")
            _write(
                api / page,
                "\n".join(
                    [
                        f"# `{name}`",
                        "",
                        "```{eval-rst}",
                        f".. automodule:: {name}",
                        "```",
                        "",
                    ]
                ),
            )
        index.append("")
    index += ["```{toctree}", ":hidden:", ""] + toc + ["```", ""]
    _write(api / "index.md", "\n".join(index))
    wanted.add("index.md")
    for old in api.glob("*.md"):
        if old.name not in wanted:
            old.unlink()


def _escape_bars(app, what, name, obj, options, lines):
    """The docstrings write norms as |x| (plain text for help()); in
    reStructuredText |x| is a substitution, so a bar outside ``literals``
    is escaped."""
    for i, line in enumerate(lines):
        parts = line.split("``")
        for k in range(0, len(parts), 2):  # outside the literals
            parts[k] = parts[k].replace("|", "\\|")
        lines[i] = "``".join(parts)


def _setup_pydrake_system(app):
    """Drake's ``.. pydrake_system::`` directive (a system's ports as YAML
    in its docstring, as Drake's own docs have), shown as the block of
    ports."""
    from docutils import nodes
    from docutils.parsers.rst import Directive

    class PydrakeSystem(Directive):
        has_content = True

        def run(self):
            text = "\n".join(self.content)
            block = nodes.literal_block(text, text)
            block["language"] = "yaml"
            return [nodes.paragraph(text="Ports:"), block]

    app.add_directive("pydrake_system", PydrakeSystem)


def setup(app):
    app.connect("autodoc-process-docstring", _escape_bars)
    _setup_pydrake_system(app)


write_scenario_reference(DOCS / "scenario-reference.md")
write_metrics_reference(DOCS / "metrics-reference.md")
write_api_pages()
