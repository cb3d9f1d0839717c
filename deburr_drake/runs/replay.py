"""A run's 3-D replay: Meshcat's recording of the cell (drawn by
:func:`deburr_drake.cell.meshcat.add_meshcat`) as one self-contained HTML
file.

Use: ``meshcat = Meshcat()``, ``make_deburring_diagram(scenario=s,
meshcat=meshcat)``, ``meshcat.StartRecording(frames_per_second=10.0)``,
simulate, then ``write_recording(meshcat, "out/replay.html")``: one file to
open in a browser (or an IFrame in a notebook)."""

from __future__ import annotations

from pathlib import Path

from pydrake.geometry import Meshcat

__all__ = ["write_recording"]


def write_recording(meshcat: Meshcat, path) -> Path:
    """Stops Meshcat's recording and writes it as one self-contained HTML
    file (three.js and the scene inlined) at ``path``."""
    meshcat.StopRecording()
    meshcat.PublishRecording()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(meshcat.StaticHtml())
    return out
