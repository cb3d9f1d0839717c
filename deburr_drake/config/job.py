"""The ``job:`` section: a whole part deburred in one program, its edges
chosen, ordered and joined by planned moves (deburr_drake.cell.moves).

A job's part is its own: ``file`` (STL or OBJ; relative to the scenario
file, or a name in models/parts/) in ``units``, placed at ``pose``. Its
edges are every convex edge the tool reaches from the part's open side
(``edges`` left empty: the others are listed with why, not counted as
failures), or those ``edges`` names, each by a point near it or by its
index in ``deburr-drake edges``' listing. They are cut in the order listed
(``order: listed``) or nearest-next (``order: nearest``) from the edge
nearest ``start``. Between two cuts the tool retracts ``retract`` up its
axis, moves clear of the part by ``clearance`` at least, and comes down
``approach`` along the next cut's axis; the feed starts once the cut's
depth is reached, or after ``entry_dwell``."""

from dataclasses import dataclass, field
from pathlib import Path
from typing import List

from deburr_drake.config.cell import PoseConfig, parts_folder
from deburr_drake.config.checks import (
    _finite,
    _non_negative,
    _positive,
    _require,
    _vector,
)
from deburr_drake.math.units import UNITS

__all__ = ["JobConfig", "JobEdgeConfig"]


@dataclass
class JobEdgeConfig:
    """One edge of a job: the edge nearest ``near`` (m, part frame) or the
    one at ``index`` of the part's listing; one of them. ``tilt`` turns
    the tool axis about the edge, as ``part.edge.tilt``."""

    near: List[float] = field(default_factory=list)  # m, part frame
    index: int = -1  # -, in deburr-drake edges' listing (-1: by near)
    tilt: float = 0.0  # rad, the tool axis turned about the edge

    def validate(self, owner: str):
        _finite(owner, "tilt", self.tilt)
        _require(
            bool(self.near) != (self.index >= 0),
            owner,
            {"near": self.near, "index": self.index},
            "one of near (a point, m, part frame) or index (>= 0)",
        )
        if self.near:
            _vector(owner, "near", self.near, 3, _finite)
        else:
            _require(
                isinstance(self.index, int),
                f"{owner}.index",
                self.index,
                "an integer >= 0",
            )


@dataclass
class JobConfig:
    """A whole part's job (see the module docstring); no job when
    ``file`` is empty."""

    # -, the part's STL or OBJ file (relative to the scenario file, or a
    # name in models/parts/); "": no job
    file: str = ""
    units: str = "m"  # -, the file's length unit (m, mm, cm or in)
    pose: PoseConfig = field(default_factory=PoseConfig)
    # -, the edges cut ([]: every convex edge reachable from the open side)
    edges: List[JobEdgeConfig] = field(default_factory=list)
    order: str = "nearest"  # -, nearest (nearest-next) or listed
    # m, part frame: nearest-next starts at the edge nearest this point
    # ([]: at the first edge of the selection)
    start: List[float] = field(default_factory=list)
    approach: float = 0.02  # m, down the next cut's tool axis to its start
    retract: float = 0.02  # m, up the tool axis from a cut's end
    clearance: float = 0.005  # m, least distance to the part on a move
    # s, longest wait on a cut's entry for its depth before the feed starts
    entry_dwell: float = 1.0
    # rad, an edge where the faces' normals differ by more
    sharp_angle: float = 0.5236

    ORDERS = ("nearest", "listed")

    def part_file(self) -> Path:
        """``file`` as given (the scenario loader makes a relative one
        relative to the scenario file), else the shipped part of that
        name."""
        path = Path(self.file)
        if path.is_file() or path.is_absolute() or len(path.parts) != 1:
            return path
        shipped = parts_folder() / path
        return shipped if shipped.is_file() else path

    def validate(self, owner: str = "job"):
        _require(
            not self.file or self.part_file().is_file(),
            f"{owner}.file",
            self.file,
            "an STL or OBJ file (relative to the scenario file, or a name "
            "in models/parts/)",
        )
        _require(
            self.units in UNITS,
            f"{owner}.units",
            self.units,
            f"one of {', '.join(UNITS)}",
        )
        self.pose.validate(f"{owner}.pose")
        for i, edge in enumerate(self.edges):
            edge.validate(f"{owner}.edges[{i}]")
        _require(
            self.order in self.ORDERS,
            f"{owner}.order",
            self.order,
            f"one of {', '.join(self.ORDERS)}",
        )
        if self.start:
            _vector(owner, "start", self.start, 3, _finite)
        for name in ("approach", "retract"):
            _positive(owner, name, getattr(self, name))
        _non_negative(owner, "clearance", self.clearance)
        _non_negative(owner, "entry_dwell", self.entry_dwell)
        _require(
            0.0 < self.sharp_angle < 3.14159,
            f"{owner}.sharp_angle",
            self.sharp_angle,
            "an angle in (0, pi) rad",
        )
