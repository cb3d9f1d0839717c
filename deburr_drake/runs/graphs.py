"""GraphViz export of a deburring diagram and of its controller.

Use: ``write_graphs(diagram, "out/diagram.dot", fmt="svg")`` (the
``deburr-drake diagram`` command); ``diagram.GetGraphvizString()`` is the
text itself."""

from __future__ import annotations

from pathlib import Path
import shutil
import subprocess
from typing import List, Optional, Tuple

from pydrake.systems.framework import Diagram

from deburr_drake.config import ConfigError

__all__ = ["write_graphs", "FORMATS", "GRAPHVIZ_HINT"]

FORMATS = ("dot", "svg", "png")
GRAPHVIZ_HINT = (
    "GraphViz's `dot` was not found: install it (Debian/Ubuntu: "
    "sudo apt-get install graphviz; macOS: brew install "
    "graphviz) to render svg/png; the .dot files are written"
)


def write_graphs(
    diagram: Diagram,
    out: Path,
    *,
    fmt: str = "dot",
    max_depth: Optional[int] = None,
) -> Tuple[List[Path], Optional[str]]:
    """Writes ``<out>.dot`` (the whole diagram, to ``max_depth`` levels of
    nesting) and ``<out>_controller.dot`` (the controller alone), and
    renders both as ``fmt`` when it is svg or png. Returns the paths written
    and, when rendering was asked for but GraphViz's ``dot`` is missing, a
    one-line message with the install hint."""
    if fmt not in FORMATS:
        raise ConfigError(f"format {fmt!r} is invalid: allowed {FORMATS}")
    out = Path(out)
    if out.suffix in (".dot", ".svg", ".png"):
        out = out.with_suffix("")
    out.parent.mkdir(parents=True, exist_ok=True)
    controller = diagram.GetSubsystemByName("controller")
    sources = {
        out.with_suffix(".dot"): diagram.GetGraphvizString(max_depth=max_depth)
        if max_depth is not None
        else diagram.GetGraphvizString(),
        out.parent
        / f"{out.name}_controller.dot": controller.GetGraphvizString(),
    }
    written = []
    for path, text in sources.items():
        path.write_text(text)
        written.append(path)
    if fmt == "dot":
        return written, None
    dot = shutil.which("dot")
    if dot is None:
        return written, GRAPHVIZ_HINT
    for path in list(written):
        target = path.with_suffix(f".{fmt}")
        subprocess.run(
            [dot, f"-T{fmt}", str(path), "-o", str(target)], check=True
        )
        written.append(target)
    return written, None
