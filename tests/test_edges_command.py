"""``deburr-drake edges``: a part's sharp edges listed (index, loop or
open, length, dihedral, convex or concave, a point, reach) and drawn."""

from pathlib import Path
import re

import pytest

from deburr_drake.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _rows(text):
    """The listing's edge rows: (index, shape, length_mm, kind, reach)."""
    rows = []
    for line in text.splitlines():
        m = re.match(
            r"\s*(\d+)\s+(loop|open)\s+([\d.]+)\s+([\d.]+)-\s*([\d.]+)\s+"
            r"(convex|concave|mixed)\s+\[([^\]]*)\]\s+(yes|no: .*?)"
            r"(\s+<- the scenario's edge)?$",
            line,
        )
        if m:
            rows.append(m.groups())
    return rows


def test_the_pipes_edges_listed_and_drawn(tmp_path, capsys):
    figure = tmp_path / "pipe.png"
    assert (
        main(["edges", "pipe_hole.stl", "--units", "mm", "--out", str(figure)])
        == 0
    )
    out = capsys.readouterr().out
    rows = _rows(out)
    assert len(rows) == 6 and [int(r[0]) for r in rows] == list(range(6))
    assert all(r[1] == "loop" and r[5] == "convex" for r in rows)
    lengths = sorted(float(r[2]) for r in rows)
    assert lengths[-1] == pytest.approx(2 * 3.14159 * 30, abs=0.2)
    # the hole's rim at the bore: the spindle would stand in the far wall
    inner = [r for r in rows if r[7].startswith("no")]
    assert len(inner) == 1 and "spindle" in inner[0][7]
    assert out.count("tool axis along [0.000, 0.000, 1.000]") == 1
    assert figure.stat().st_size > 10_000


def test_a_scenarios_part_and_its_edge(tmp_path, capsys):
    scenario = EXAMPLES / "angled_hole_6dof.yaml"
    assert (
        main(
            [
                "edges",
                "--scenario",
                str(scenario),
                "--out",
                str(tmp_path / "a.png"),
            ]
        )
        == 0
    )
    rows = _rows(capsys.readouterr().out)
    marked = [r for r in rows if r[8]]
    assert len(marked) == 1
    index, shape, _, low, high, kind, point, reach, _ = marked[0]
    assert (shape, kind, reach) == ("loop", "convex", "yes")
    # the faces meet at 90 +- 30 deg round a hole 30 deg off the normal
    assert float(low) == pytest.approx(60.0, abs=1.0)
    assert float(high) == pytest.approx(120.0, abs=1.0)
    # the point is in the part frame (m): on the rim round the origin
    x, y, z = (float(v) for v in point.split(","))
    assert abs(z) < 1e-4 and 0.007 < (x * x + y * y) ** 0.5 < 0.0095


def test_refusals_name_the_argument(capsys):
    assert main(["edges"]) == 2
    assert "give a part's file" in capsys.readouterr().err
    assert main(["edges", "no_such_part.stl"]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["edges", "tube.stl", "--sharp-angle", "200"]) == 2
    assert "--sharp-angle 200.0 is invalid" in capsys.readouterr().err
