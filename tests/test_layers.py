"""The package's layer contract (pyproject.toml, [tool.importlinter]):
cli > analysis | sweep > runs > cell > control > config > math, no import
cycle among the modules of any package, deburr_drake.math free of Drake.
Checked with import-linter's ``lint-imports``, as .ci/run does."""

import ast
import os
from pathlib import Path
import shutil
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINT = shutil.which("lint-imports") or str(
    Path(sys.executable).with_name("lint-imports")
)


def _lint(tree: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(tree))
    return subprocess.run(
        [LINT, "--no-cache"],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_the_package_keeps_its_layer_contracts():
    result = _lint(ROOT)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Contracts: 4 kept, 0 broken." in result.stdout


@pytest.mark.parametrize(
    "module, line, contract",
    [
        # the paper's controller reaching up into the cell
        (
            "control/loop.py",
            "from deburr_drake.cell import diagram",
            "cli > analysis | sweep > runs > cell > control > config > math",
        ),
        # pure math importing Drake
        (
            "math/geometry.py",
            "import pydrake.systems.framework",
            "deburr_drake.math is pure numpy: no Drake",
        ),
        # two cell modules importing each other (arm imports robot's names)
        (
            "cell/robot.py",
            "import deburr_drake.cell.reach",
            "no import cycle among the modules and subpackages of any package",
        ),
    ],
)
def test_an_import_against_the_contract_is_caught(
    tmp_path, module, line, contract
):
    shutil.copytree(
        ROOT / "deburr_drake",
        tmp_path / "deburr_drake",
        ignore=shutil.ignore_patterns("__pycache__"),
    )
    shutil.copy(ROOT / "pyproject.toml", tmp_path)
    path = tmp_path / "deburr_drake" / module
    path.write_text(path.read_text() + f"\n{line}  # noqa\n")
    result = _lint(tmp_path)
    assert result.returncode != 0
    assert f"{contract} BROKEN" in result.stdout, result.stdout


#: A function longer than this reads as more than one step: split it.
MAX_FUNCTION_LINES = 80


def _function_lengths(source: str):
    """(name, first line, lines) of every function in ``source``, a
    class defined inside a function (a template factory's system) not
    counted in it: its methods count by themselves."""
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            inner = sum(
                c.end_lineno - c.lineno + 1
                for c in ast.walk(node)
                if isinstance(c, ast.ClassDef)
            )
            lines = node.end_lineno - node.lineno + 1 - inner
            yield node.name, node.lineno, lines


def test_function_lengths_count_a_factorys_class_by_its_methods():
    source = "def f():\n    class A:\n        def g(self):\n" + (
        "            x = 1\n" * 90
    )
    lengths = {name: lines for name, _, lines in _function_lengths(source)}
    assert lengths == {"f": 1, "g": 91}


def test_no_function_in_the_package_is_over_80_lines():
    long = [
        f"{path.relative_to(ROOT)}:{line} {name} ({lines} lines)"
        for path in sorted((ROOT / "deburr_drake").rglob("*.py"))
        for name, line, lines in _function_lengths(path.read_text())
        if lines > MAX_FUNCTION_LINES
    ]
    assert long == []
