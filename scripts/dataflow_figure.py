"""The docs' dataflow figure, drawn from the real diagram's connections.

    python scripts/dataflow_figure.py [OUT_DIR]   # default docs/figures

builds the `paper` diagram, keeps the closed loop (the loggers, the guards
and the scene graph, which only read or serve it, are left out), and writes
``dataflow.dot`` (one box per system with its class, one arrow per
connection labelled with the output port and, where it differs, the input
port) and ``dataflow.svg`` rendered by GraphViz's ``dot``.
``tests/test_docs.py`` fails when the committed ``dataflow.dot`` is no
longer what the diagram gives: rerun this script then.
"""

from pathlib import Path
import subprocess
import sys

ROOT = Path(__file__).resolve().parents[1]

#: Systems drawn in the controller's cluster (deburr_drake.control); the
#: others are the simulated cell's.
CONTROLLER = (
    "command_generator",
    "first_order_hold",
    "chamfer_observer",
    "contact_estimator",
    "controller",
)
LEFT_OUT = ("guards", "scene_graph")


def _kept(system) -> bool:
    name = system.get_name()
    return not (name.startswith("log_") or name in LEFT_OUT)


def dataflow_dot(diagram) -> str:
    """GraphViz text of the diagram's closed loop (see the module)."""
    systems = [s for s in diagram.GetSystems() if _kept(s)]
    edges = set()
    for (dst, in_index), (src, out_index) in diagram.connection_map().items():
        if not (_kept(src) and _kept(dst)):
            continue
        out_name = src.get_output_port(out_index).get_name()
        in_name = dst.get_input_port(in_index).get_name()
        label = out_name if out_name == in_name else f"{out_name} → {in_name}"
        edges.add((src.get_name(), dst.get_name(), label))
    lines = [
        "digraph dataflow {",
        "  rankdir=TB;",
        '  node [shape=box, style="rounded,filled", fontname="Helvetica",'
        " fontsize=11];",
        '  edge [fontname="Helvetica", fontsize=9];',
    ]
    for cluster, title, colour, members in (
        (
            "control",
            "the paper's controller (deburr_drake.control)",
            "#dbe9f6",
            [s for s in systems if s.get_name() in CONTROLLER],
        ),
        (
            "cell",
            "the simulated cell (deburr_drake.cell)",
            "#f6ead8",
            [s for s in systems if s.get_name() not in CONTROLLER],
        ),
    ):
        lines.append(f"  subgraph cluster_{cluster} {{")
        lines.append(f'    label="{title}"; fontname="Helvetica";')
        for s in sorted(members, key=lambda s: s.get_name()):
            kind = type(s).__name__.split("_")[0]
            lines.append(
                f'    "{s.get_name()}" [label="{s.get_name()}\\n'
                f'{kind}", fillcolor="{colour}"];'
            )
        lines.append("  }")
    for src, dst, label in sorted(edges):
        lines.append(f'  "{src}" -> "{dst}" [label="{label}"];')
    lines.append("}")
    return "\n".join(lines) + "\n"


def paper_dataflow_dot() -> str:
    from deburr_drake.cell.diagram import make_deburring_diagram
    from deburr_drake.config import load_scenario

    return dataflow_dot(make_deburring_diagram(scenario=load_scenario("paper")))


def main(out_dir=ROOT / "docs" / "figures"):
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    dot = out_dir / "dataflow.dot"
    dot.write_text(paper_dataflow_dot())
    subprocess.run(
        ["dot", "-Tsvg", str(dot), "-o", str(out_dir / "dataflow.svg")],
        check=True,
    )
    print(f"wrote {dot} and {out_dir / 'dataflow.svg'}")


if __name__ == "__main__":
    main(*sys.argv[1:])
