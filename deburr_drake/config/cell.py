"""Configuration of the simulated cell: the part (``part``: its pose,
material, contact band and edge; ``part_error``), the tool, the robot, the
cutting process and its burrs, the sensor, faults and guards. SI units;
each field's comment gives its unit."""

import copy
from dataclasses import dataclass, field
import math
import os
from pathlib import Path
from typing import Dict, List

import numpy as np

from deburr_drake.config.checks import (
    ConfigError,
    _finite,
    _non_negative,
    _positive,
    _require,
    _vector,
)
from deburr_drake.math.profile import ProfileContour
from deburr_drake.math.units import UNITS

__all__ = [
    "package_folder",
    "PIP_PREFIX",
    "MaterialConfig",
    "ContactBandConfig",
    "ToolConfig",
    "PoseConfig",
    "EdgeConfig",
    "PartConfig",
    "SensorConfig",
    "BurrConfig",
    "ProcessConfig",
    "ToolMountConfig",
    "RobotConfig",
    "PartErrorConfig",
    "DropoutConfig",
    "PartStepConfig",
    "FaultsConfig",
    "GuardsConfig",
]


@dataclass
class MaterialConfig:
    """What the part is made of, as the contact sees it: the compliant
    band's hydroelastic modulus and Hunt-Crossley dissipation."""

    hydroelastic_modulus: float = 4.5e6  # Pa, 10 N/mm at 0.5 mm
    hunt_crossley_dissipation: float = (
        5.0  # s/m, the contact's Hunt-Crossley dissipation
    )

    def validate(self, owner="part.material"):
        _positive(owner, "hydroelastic_modulus", self.hydroelastic_modulus)
        _non_negative(
            owner, "hunt_crossley_dissipation", self.hunt_crossley_dissipation
        )
        # An absurd modulus (1e300 Pa) stops the process inside Drake's
        # contact solver, a C++ failure Python cannot catch, so nothing
        # would be written.
        _require(
            self.hydroelastic_modulus <= 1e12,
            f"{owner}.hydroelastic_modulus",
            self.hydroelastic_modulus,
            "a number in (0, 1e12] Pa (steel's Young's modulus is 2e11)",
        )


@dataclass
class ContactBandConfig:
    """The part's contact band: only the material along the edge, the top
    ``height`` below it, is modelled, as a compliant hydroelastic volume
    mesh of this resolution (the rest of the part is drawn, not touched)."""

    height: float = 0.006  # m, the band's depth below the edge
    # -, segments around a full turn (circle, profile; a mesh edge's
    # stations are no coarser than a 30 mm ring's of as many). The cutter's
    # mesh (tool.resolution_hint) and the sensor's noise set it: finer
    # changes the force less than the noise (docs/numerics.md).
    mesh_segments: int = 120
    mesh_radial_cells: int = 2  # -, mesh cells across the band
    mesh_height_cells: int = 2  # -, mesh cells through the band's height

    def validate(self, owner="part.band"):
        _positive(owner, "height", self.height)
        _require(
            isinstance(self.mesh_segments, int) and self.mesh_segments >= 16,
            f"{owner}.mesh_segments",
            self.mesh_segments,
            "an integer >= 16",
        )
        for name in ("mesh_radial_cells", "mesh_height_cells"):
            v = getattr(self, name)
            _require(
                isinstance(v, int) and v >= 2,
                f"{owner}.{name}",
                v,
                "an integer >= 2 (the mesh needs interior vertices)",
            )


@dataclass
class ToolConfig:
    """The cylindrical burr cutter (vertical axis)."""

    cutter_radius: float = 0.003  # m, of the cylindrical cutter
    cutter_length: float = 0.020  # m, along the tool axis
    engagement: float = 0.002  # m, cutter tip below the top edge
    resolution_hint: float = 6.0e-4  # m, the cutter's mesh (part.band)

    def validate(self):
        for name in (
            "cutter_radius",
            "cutter_length",
            "engagement",
            "resolution_hint",
        ):
            _positive("tool", name, getattr(self, name))
        _require(
            self.engagement < self.cutter_length,
            "tool.engagement",
            self.engagement,
            f"< tool.cutter_length ({self.cutter_length})",
        )


@dataclass
class PoseConfig:
    """A frame in the world: moved by ``xyz`` after turning by ``rpy``
    (R = Rz(yaw) Ry(pitch) Rx(roll), Drake's RollPitchYaw)."""

    xyz: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0]
    )  # m, the frame's origin in the world
    rpy: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0]
    )  # rad, roll, pitch and yaw

    def validate(self, owner: str):
        _vector(owner, "xyz", self.xyz, 3, _finite)
        _vector(owner, "rpy", self.rpy, 3, _finite)


def parts_folder() -> Path:
    """``models/parts/``: the shipped part files ($DEBURR_DRAKE_MODELS, else
    the models/ beside the package)."""
    env = os.environ.get("DEBURR_DRAKE_MODELS")
    models = (
        Path(env) if env else Path(__file__).resolve().parents[2] / "models"
    )
    return models / "parts"


#: spindle_clash's answers, by the cell they were worked out for.
_SPINDLE_CLASHES: Dict[str, str] = {}


@dataclass
class EdgeConfig:
    """Which edge of the part is cut, and where and which way the tool runs
    along it; ``kind`` says which edge it is, and only that kind's fields
    (``FIELDS``) may be given with it. The part frame is ``part.pose``.

    ``circle``: the inner top edge of a tube of ``inner_radius``,
    ``wall_thickness`` and ``height`` standing on the part frame's origin,
    from ``start_angle`` in ``direction``. ``straight``: the top edge of a
    straight wall ``wall_thickness`` thick, ``height`` high and ``length``
    long, its middle above the part frame's origin; the tool runs along
    ``heading`` with the material on its right. ``profile``: the top edge of
    a closed profile ``height`` high, the polygon ``vertices`` about the
    part frame's origin with every corner rounded by ``fillet_radius``, its
    wall ``wall_thickness`` thick; ``side`` inner: a pocket's edge (the
    material outside, as the tube's bore), outer: a boss's edge (the
    material inside). The pass starts where the ray from the origin at
    polar angle ``start_angle`` meets the cutter's path (the crossing
    nearest the origin), or at the middle of vertex ``start_vertex``'s
    fillet, or ``start_fraction`` of the path counter-clockwise from there
    for vertex 0 (one of the three), and runs in ``direction``.

    ``mesh``: an edge of the part in ``file`` (STL, OBJ or STEP; a relative
    path is relative to the scenario file, a bare name may also be one of
    models/parts/), its coordinates in ``units``: the sharp edge (faces'
    normals more than ``sharp_angle`` apart) nearest the point ``near`` of
    the part frame, its contact band ``band_width`` wide where it fits. The
    tool's axis follows the outward normal of the face the tool stands on:
    the one whose normal is nearest ``tool_face`` (a direction in the part
    frame, e.g. [0, 0, 1]: the face looking up), or the one ``tool_rule``
    names (left or right of the edge's own direction; a loop runs
    counter-clockwise seen from outside). Neither given, the default: a
    loop round a cylindrical or conical wall (a hole, a bore, a boss) has
    the axis along the wall's axis, out of the part, the cutter's side on
    the wall; any other edge the tool on the face whose outward normal is
    nearest the world's up. The tool axis is then turned by
    ``tilt`` about the edge and leaned by ``lead`` towards the travel; the
    cutter cuts with its side, ``tool.engagement`` below the edge along the
    axis. ``direction`` +1 runs the edge its own way, -1 the other; the
    pass starts at the edge's point nearest ``start_near`` (a point in the
    part frame, m), or ``start_fraction`` of the edge from its start (-1:
    at the start; an open edge run backwards: at its end)."""

    kind: str = "circle"  # -, circle, straight, profile or mesh
    inner_radius: float = 0.030  # m, circle: the edge's radius, the bore's
    # m, circle, straight, profile: the wall's thickness across the edge
    wall_thickness: float = 0.005
    # m, circle, straight, profile: the wall's top above the part frame
    height: float = 0.050
    start_angle: float = 0.0  # rad, polar angle of the contour start
    direction: int = 1  # -, +1 counter-clockwise seen from +z, -1 clockwise
    length: float = 0.1  # m, straight edge only
    heading: float = 1.5707963267948966  # rad, straight: travel direction
    # m, [x, y] about the part frame's origin, counter-clockwise, at least
    # 3, not self-intersecting (profile only)
    vertices: list[list[float]] = field(default_factory=list)
    fillet_radius: float = 0.008  # m, every corner rounded (profile)
    side: str = "inner"  # -, profile: inner (pocket) or outer (boss)
    # -, profile: the start at the middle of this vertex's fillet; -1: by
    # start_angle
    start_vertex: int = -1
    # -, profile: the start this fraction of the path counter-clockwise
    # from vertex 0's fillet; mesh: of the edge from its start; -1: by
    # start_angle (profile) or at the start (mesh)
    start_fraction: float = -1.0
    # -, mesh: the part's STL, OBJ or STEP file (relative to the scenario
    # file, or a name in models/parts/)
    file: str = ""
    units: str = "m"  # -, mesh: the file's length unit (m, mm, cm or in)
    # m, mesh: a point in the part frame; the pass cuts the edge nearest it
    near: List[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    # m, mesh: the contact band's width into the material, where it fits
    band_width: float = 0.005
    # -, mesh: the tool axis along the left or right face's outward normal
    # ("": by tool_face, else the default: a hole's axis or the face up)
    tool_rule: str = ""
    # -, mesh: a direction in the part frame: the tool stands on the face
    # whose outward normal is nearest it ([]: by tool_rule)
    tool_face: List[float] = field(default_factory=list)
    # m, mesh: the pass starts at the edge's point nearest this point of
    # the part frame ([]: by start_fraction)
    start_near: List[float] = field(default_factory=list)
    tilt: float = 0.0  # rad, mesh: the tool axis turned about the edge
    lead: float = 0.0  # rad, mesh: the tool axis leaned towards the travel
    # rad, mesh: an edge where the faces' normals differ by more
    sharp_angle: float = 0.5236

    #: The fields each kind reads (``kind`` itself goes with every kind).
    FIELDS = {
        "circle": (
            "inner_radius",
            "wall_thickness",
            "height",
            "start_angle",
            "direction",
        ),
        "straight": ("wall_thickness", "height", "length", "heading"),
        "profile": (
            "wall_thickness",
            "height",
            "vertices",
            "fillet_radius",
            "side",
            "start_angle",
            "start_vertex",
            "start_fraction",
            "direction",
        ),
        "mesh": (
            "file",
            "units",
            "near",
            "band_width",
            "tool_rule",
            "tool_face",
            "start_near",
            "tilt",
            "lead",
            "sharp_angle",
            "start_fraction",
            "direction",
        ),
    }
    KINDS = ("circle", "straight", "profile", "mesh")
    TOOL_RULES = ("left", "right")
    # the nearest edge farther from ``near`` than this share of the part's
    # size is no edge near it (a point given in mm, or in the world frame)
    NEAR_SHARE = 0.25
    SIDES = ("inner", "outer")

    def profile_path(self, center, offset, *, grow=0.0) -> ProfileContour:
        """The profile's edge grown outward by ``grow`` (m: a pocket
        larger, a boss larger), offset by ``offset`` (m, the cutter radius)
        towards the free side, at ``center`` (x, y, z; z the path's
        height). ValueError says what is wrong with the profile."""
        pocket = self.side == "inner"
        return ProfileContour(
            self.vertices,
            self.fillet_radius,
            material="outside" if pocket else "inside",
            offset=offset - grow if pocket else offset + grow,
            center=center,
            start_angle=self.start_angle,
            direction=self.direction,
            start_vertex=self.start_vertex if self.start_vertex >= 0 else None,
            start_fraction=(
                self.start_fraction if self.start_fraction >= 0 else None
            ),
        )

    def own_fields(self) -> "EdgeConfig":
        """This edge with every field its kind does not read at its
        default: what a base of another kind left in them is dropped, and
        the scenario written back reads again."""
        own = EdgeConfig(kind=self.kind)
        for name in self.FIELDS.get(self.kind, ()):
            setattr(own, name, copy.deepcopy(getattr(self, name)))
        return own

    def wall(self) -> float:
        """The material's depth across the edge (m): the wall's thickness,
        a mesh edge's band width; no cut or burr is deeper."""
        return self.band_width if self.kind == "mesh" else self.wall_thickness

    def mesh_file(self) -> Path:
        """The part's file: ``file`` as given (the scenario loader makes a
        relative one relative to the scenario file), else the shipped part
        of that name."""
        path = Path(self.file)
        if path.is_file() or path.is_absolute() or len(path.parts) != 1:
            return path
        shipped = parts_folder() / path
        return shipped if shipped.is_file() else path

    def mesh_edge(self, pose: PoseConfig):
        """(part, EdgeCurve, the edge's distance from ``near`` (m)): the
        edge nearest ``near`` of the part placed at ``pose``, read once per
        file (ValueError: a bad file or mesh)."""
        # Imported here: the mesh libraries load only for a mesh edge.
        from deburr_drake.math.edge_contour import load_edge

        return load_edge(
            self.mesh_file(),
            units=self.units,
            xyz=pose.xyz,
            rpy=pose.rpy,
            sharp_angle=self.sharp_angle,
            near=self.near,
        )

    def mesh_rule(self, pose: PoseConfig):
        """The ``ToolRule`` of the mesh edge at ``pose``: ``tool_rule``'s
        face, or the face whose normal is nearest ``tool_face``, or
        neither given, the default (a hole's axis, else the face looking
        up: deburr_drake.math.mesh_part.default_tool_rule)."""
        from deburr_drake.math.edge_contour import face_rule
        from deburr_drake.math.mesh_part import ToolRule, default_tool_rule

        part, curve, _ = self.mesh_edge(pose)
        if self.tool_rule:
            return ToolRule(
                "face", side=self.tool_rule, reason="part.edge.tool_rule"
            )
        if self.tool_face:
            side = face_rule(curve, part.rotation @ self.tool_face)
            return ToolRule(
                "face",
                side=side,
                reason="its normal nearest part.edge.tool_face "
                f"{list(self.tool_face)}",
            )
        return default_tool_rule(curve.chain)

    def mesh_path(self, tool, pose: PoseConfig):
        """The cutter tip's path along the mesh edge of the part at
        ``pose``, an ``EdgeContour`` (ValueError: see it)."""
        from deburr_drake.math.edge_contour import EdgeContour

        part, curve, _ = self.mesh_edge(pose)
        rule = self.mesh_rule(pose)
        return EdgeContour(
            curve,
            cutter_radius=tool.cutter_radius,
            engagement=tool.engagement,
            rule=rule.kind if rule.kind == "axis" else rule.side,
            axis=rule.axis or None,
            rule_note=rule.reason,
            # a tilt given replaces the one the default rule chose
            tilt=self.tilt or rule.tilt,
            lead=self.lead,
            direction=self.direction,
            start_fraction=(
                self.start_fraction if self.start_fraction >= 0 else None
            ),
            start_near=(
                part.to_world(self.start_near) if self.start_near else None
            ),
        )

    def check_mesh(self, tool, pose: PoseConfig):
        """One ConfigError naming the field if the part's file, its edge
        near ``near`` or the cutter's path along it cannot be built."""
        try:
            part, _, distance = self.mesh_edge(pose)
        except ValueError as e:
            field = (
                "part.edge.units"
                if "unknown units" in str(e)
                else "part.edge.file"
            )
            value = self.units if field == "part.edge.units" else self.file
            raise ConfigError(f"{field} = {value!r} is invalid: {e}") from None
        size = float(part.mesh.scale)
        _require(
            distance <= self.NEAR_SHARE * size,
            "part.edge.near",
            self.near,
            f"a point (m, part frame) near an edge of the part: the nearest "
            f"is {distance:.4g} m away, the part {size:.4g} m across (near "
            "is in metres, in the part's frame, not the world's)",
        )
        try:
            path = self.mesh_path(tool, pose)
        except ValueError as e:
            message = str(e)
            field, value = "part.edge.tilt", self.tilt
            if "outward normals" in message:
                field, value = "part.edge.tool_face", self.tool_face
            elif "lead" in message:
                field, value = "part.edge.lead", self.lead
            elif "pass is empty" in message:
                field, value = "part.edge.start_fraction", self.start_fraction
            elif "tighter than the cutter" in message:
                field, value = "tool.cutter_radius", tool.cutter_radius
            raise ConfigError(
                f"{field} = {value!r} is invalid: {message}"
            ) from None
        self._check_spindle(part, path, tool, pose)

    def _rule_field(self):
        """(the field that set the tool rule, its value)."""
        if self.tool_rule:
            return "part.edge.tool_rule", self.tool_rule
        if self.tool_face:
            return "part.edge.tool_face", self.tool_face
        if self.tilt:
            return "part.edge.tilt", self.tilt
        return "part.edge.tool_face", self.tool_face

    def _check_spindle(self, part, path, tool, pose):
        """One ConfigError naming the field that set the tool axis when
        the spindle, along the axis beyond the cutter, stands in the part
        (deburr_drake.math.mesh_part.spindle_hits): the tool stands on a
        face it cannot stand on (its axis points across the part)."""
        from deburr_drake.math.edge_contour import spindle_clash

        # a scenario is validated again and again (every variant an
        # analysis or a sweep makes): the check runs once per cell
        key = repr(
            (
                self,
                self.mesh_file().stat().st_mtime_ns,
                pose,
                tool.cutter_radius,
                tool.cutter_length,
                tool.engagement,
            )
        )
        if key not in _SPINDLE_CLASHES:
            _SPINDLE_CLASHES[key] = spindle_clash(
                part, path, tool.cutter_radius, tool.cutter_length
            )
        clash = _SPINDLE_CLASHES[key]
        if not clash:
            return
        field, value = self._rule_field()
        rule = self.mesh_rule(pose).describe()
        raise ConfigError(
            f"{field} = {value!r} is invalid: with {rule} {clash}: the axis "
            "points across the part, not out of its open side; allowed "
            "the face the tool can stand on (part.edge.tool_face, e.g. "
            "[0, 0, 1], or neither tool_face nor tool_rule: the default)"
        )

    def check_profile(self, pose, band, tool, part_error):
        """One ConfigError naming the field if the profile, the cutter's
        path on it (real and believed), or the wall ``wall_thickness``
        deep along it cannot be built."""
        center = list(pose.xyz[:2]) + [0.0]
        field, value = "part.edge.vertices", self.vertices
        try:
            path = self.profile_path(center, tool.cutter_radius)
            field, value = "part.edge.wall_thickness", self.wall_thickness
            path.with_offset(0.0).material_band(
                self.wall_thickness,
                segments_per_turn=band.mesh_segments,
                max_step=self.wall_thickness,
            )
            field, value = "part_error.radius", part_error.radius
            self.profile_path(
                center, tool.cutter_radius, grow=part_error.radius
            )
        except ValueError as e:
            message = str(e)
            if "larger than the cutter" in message:
                field, value = (
                    ("part.edge.fillet_radius", self.fillet_radius)
                    if field == "part.edge.vertices"
                    else (field, value)
                )
                message = (
                    f"a fillet whose centre is on the free side must "
                    f"be larger than tool.cutter_radius "
                    f"({tool.cutter_radius}): {message}"
                )
            elif "start_angle" in message:
                field, value = "part.edge.start_angle", self.start_angle
            raise ConfigError(
                f"{field} = {value!r} is invalid: {message}"
            ) from None

    def _check_start(self):
        """At most one of start_angle, start_vertex, start_fraction places
        a profile's start; the other edges start by angle or heading."""
        vertex, fraction = self.start_vertex, self.start_fraction
        _require(
            isinstance(vertex, int)
            and not isinstance(vertex, bool)
            and -1 <= vertex < max(len(self.vertices), 0),
            "part.edge.start_vertex",
            vertex,
            f"-1 or an index into part.edge.vertices (0 to "
            f"{len(self.vertices) - 1})"
            if self.kind == "profile"
            else "-1 (only a profile edge starts at a vertex)",
        )
        _require(
            isinstance(fraction, (int, float))
            and (fraction == -1 or 0 <= fraction < 1)
            and (fraction == -1 or self.kind in ("profile", "mesh")),
            "part.edge.start_fraction",
            fraction,
            "-1 or a number in [0, 1) (a profile or mesh edge only)",
        )
        _require(
            vertex == -1 or fraction == -1,
            "part.edge.start_fraction",
            fraction,
            f"-1 while part.edge.start_vertex ({vertex}) places the start (one "
            "of start_angle, start_vertex, start_fraction)",
        )
        placed = "start_vertex" if vertex != -1 else "start_fraction"
        _require(
            (vertex == -1 and fraction == -1) or self.start_angle == 0,
            "part.edge.start_angle",
            self.start_angle,
            f"0 while part.edge.{placed} places the start (one of start_angle, "
            "start_vertex, start_fraction)",
        )

    def _check_mesh_fields(self):
        """The mesh edge's fields (numbers checked whatever the kind)."""
        _vector("part.edge", "near", self.near, 3, _finite)
        for name in ("tilt", "lead"):
            v = getattr(self, name)
            _require(
                isinstance(v, (int, float))
                and math.isfinite(v)
                and abs(v) < 0.5 * math.pi,
                f"part.edge.{name}",
                v,
                "a number in (-pi/2, pi/2) rad",
            )
        _require(
            isinstance(self.sharp_angle, (int, float))
            and 0.0 < self.sharp_angle < math.pi,
            "part.edge.sharp_angle",
            self.sharp_angle,
            "a number in (0, pi) rad",
        )
        for name in ("start_near", "tool_face"):
            if getattr(self, name):
                _vector("part.edge", name, getattr(self, name), 3, _finite)
        if self.kind != "mesh":
            return
        _require(
            self.units in UNITS,
            "part.edge.units",
            self.units,
            f"one of {', '.join(UNITS)}",
        )
        _require(
            self.tool_rule in ("", *self.TOOL_RULES),
            "part.edge.tool_rule",
            self.tool_rule,
            "left or right (the bisector leaves n1 undefined: the cutter's "
            "side would face neither face)",
        )
        if self.start_near:
            _require(
                self.start_fraction == -1,
                "part.edge.start_fraction",
                self.start_fraction,
                "-1 while part.edge.start_near places the start (one of the "
                "two)",
            )
        if self.tool_face:
            _require(
                any(x != 0 for x in self.tool_face),
                "part.edge.tool_face",
                self.tool_face,
                "a non-zero direction (part frame)",
            )
            _require(
                not self.tool_rule,
                "part.edge.tool_rule",
                self.tool_rule,
                "unset while part.edge.tool_face picks the face (one of the "
                "two)",
            )
        _require(
            self.start_angle == 0,
            "part.edge.start_angle",
            self.start_angle,
            "0 for a mesh edge (part.edge.start_fraction places its start)",
        )
        _require(
            isinstance(self.file, str) and self.mesh_file().is_file(),
            "part.edge.file",
            self.file,
            "an STL, OBJ or STEP file relative to the scenario file, or "
            f"the name of one in {parts_folder()}: no such file",
        )

    def validate(self):
        _require(
            self.kind in self.KINDS,
            "part.edge.kind",
            self.kind,
            f"one of {self.KINDS}",
        )
        for name in ("start_angle", "heading"):
            v = getattr(self, name)
            _require(
                isinstance(v, (int, float))
                and math.isfinite(v)
                and abs(v) <= 2 * math.pi,
                f"part.edge.{name}",
                v,
                "a number in [-2 pi, 2 pi] rad",
            )
        _require(
            self.direction in (1, -1),
            "part.edge.direction",
            self.direction,
            "1 or -1",
        )
        for name in (
            "inner_radius",
            "wall_thickness",
            "height",
            "length",
            "fillet_radius",
            "band_width",
        ):
            _positive("part.edge", name, getattr(self, name))
        _require(
            self.side in self.SIDES,
            "part.edge.side",
            self.side,
            f"one of {self.SIDES}",
        )
        self._check_start()
        self._check_mesh_fields()
        if self.kind != "profile":
            return
        _require(
            len(self.vertices) >= 3,
            "part.edge.vertices",
            self.vertices,
            "at least 3 points [x, y] (m) for a profile edge",
        )
        for i, v in enumerate(self.vertices):
            _vector("part.edge", f"vertices[{i}]", v, 2, _finite)


@dataclass
class PartConfig:
    """The part: where it is (``pose``, its frame in the world), what it is
    made of (``material``), how much of it the contact models (``band``)
    and the edge the tool cuts on it (``edge``, one of its kinds)."""

    pose: PoseConfig = field(default_factory=PoseConfig)
    material: MaterialConfig = field(default_factory=MaterialConfig)
    band: ContactBandConfig = field(default_factory=ContactBandConfig)
    edge: EdgeConfig = field(default_factory=EdgeConfig)

    def validate(self):
        self.pose.validate("part.pose")
        self.material.validate()
        self.band.validate()
        self.edge.validate()
        if self.edge.kind != "mesh":
            # Only a mesh part is read in a frame of its own; the walls
            # are built upright about the pose's origin.
            _require(
                not any(self.pose.rpy),
                "part.pose.rpy",
                self.pose.rpy,
                f"[0, 0, 0] for a {self.edge.kind} edge (only a mesh part "
                "turns)",
            )
            _require(
                self.band.height <= self.edge.height,
                "part.band.height",
                self.band.height,
                f"<= part.edge.height ({self.edge.height})",
            )

    def mesh_edge(self, pose=None):
        """A mesh edge's (part, EdgeCurve, distance from ``near``) at
        ``pose`` (default ``part.pose``; EdgeConfig.mesh_edge)."""
        return self.edge.mesh_edge(pose or self.pose)

    def mesh_path(self, tool, pose=None):
        """A mesh edge's cutter path at ``pose`` (default ``part.pose``;
        EdgeConfig.mesh_path)."""
        return self.edge.mesh_path(tool, pose or self.pose)

    def real_pose(self, part_error) -> PoseConfig:
        """Where the real part is: a mesh part's ``pose`` is the believed
        one, the real part's is moved back by ``part_error``
        (PartErrorConfig); a planar part's ``pose`` is the real one."""
        if self.edge.kind != "mesh" or not part_error.moves():
            return self.pose
        # Imported here: scipy's rotations load only for a moved mesh part.
        from deburr_drake.math.rigid import (
            matrix_rpy,
            real_from_believed,
            rpy_matrix,
        )

        R, p = real_from_believed(
            (rpy_matrix(self.pose.rpy), np.asarray(self.pose.xyz, float)),
            part_error.offset,
            part_error.rpy,
        )
        return PoseConfig(
            xyz=[float(x) for x in p], rpy=[float(a) for a in matrix_rpy(R)]
        )

    def path_length(self, tool) -> float:
        """The cutter's path along the edge (m): the length a burr's arc
        and ``center_fraction`` are measured on."""
        edge = self.edge
        if edge.kind == "profile":
            return edge.profile_path([0.0, 0.0, 0.0], tool.cutter_radius).length
        if edge.kind == "mesh":
            return self.mesh_path(tool).length
        if edge.kind == "straight":
            return edge.length
        return 2 * math.pi * (edge.inner_radius - tool.cutter_radius)

    def check(self, tool, part_error):
        """One ConfigError naming the field if the edge's path cannot be
        built with this cutter (a profile's, real and believed; a mesh
        part's file, edge and path)."""
        if self.edge.kind == "profile":
            self.edge.check_profile(self.pose, self.band, tool, part_error)
        if self.edge.kind == "mesh":
            self.edge.check_mesh(tool, self.pose)
            if part_error.moves():
                self._check_real_mesh(tool, part_error)

    def _check_real_mesh(self, tool, part_error):
        """The cutter's path along the real part's edge (``part_error``
        moves it from ``pose``) can be built."""
        try:
            self.mesh_path(tool, self.real_pose(part_error))
        except ValueError as e:
            raise ConfigError(
                f"part_error.offset = {part_error.offset!r} and "
                f"part_error.rpy = {part_error.rpy!r} are invalid: the real "
                f"part's edge: {e}"
            ) from None


@dataclass
class SensorConfig:
    """Tool force measurement."""

    sample_period: float = 0.0025  # s, the reading is sampled this often
    # Hz, first-order low-pass. The controller cancels the measured force
    # (-f in (36)), which holds the process damping g of (3) through the
    # sampled sensor: on the light point-mass testbed a wide band makes
    # that loop unstable (docs/numerics.md).
    cutoff_frequency: float = 20.0
    noise_std: float = 0.0  # N, white noise per axis before the filter
    noise_seed: int = 0  # -, seeds the noise (RandomSource)

    def validate(self):
        _positive("sensor", "sample_period", self.sample_period)
        _positive("sensor", "cutoff_frequency", self.cutoff_frequency)
        _non_negative("sensor", "noise_std", self.noise_std)
        _require(
            self.cutoff_frequency < 0.5 / self.sample_period,
            "sensor.cutoff_frequency",
            self.cutoff_frequency,
            f"< the Nyquist frequency {0.5 / self.sample_period:g} Hz",
        )
        _require(
            isinstance(self.noise_seed, int) and self.noise_seed >= 0,
            "sensor.noise_seed",
            self.noise_seed,
            "an integer >= 0",
        )


@dataclass
class BurrConfig:
    """One burr on the edge: a raised-cosine bump of material the cutter
    removes (its cross-section area adds to g of (3))."""

    center_fraction: float = (
        0.125  # -, fraction of the edge length from the start
    )
    length: float = 0.008  # m, of arc
    height: float = 0.001  # m, above the edge
    thickness: float = 0.002  # m; cross-section area = height * thickness

    def validate(self, owner="process.burrs[]"):
        _require(
            isinstance(self.center_fraction, (int, float))
            and 0.0 <= self.center_fraction < 1.0,
            f"{owner}.center_fraction",
            self.center_fraction,
            "a number in [0, 1)",
        )
        for name in ("length", "height", "thickness"):
            _non_negative(owner, name, getattr(self, name))
        _positive(owner, "length", self.length)


@dataclass
class ProcessConfig:
    """Plant-side truth of the cutting process, eq. (3) and the threshold
    c0 of (4). The controller never reads these values."""

    cutting_coefficient: float = 3.3e9  # N s/m^3, k_c: g = k_c * area
    plunge_coefficient: float = 0.0  # N s/m, h of (3)
    threshold_power_force: float = 2.0  # N, P'_th
    contact_threshold_force: float = 2.0  # N, c0 of (4)
    threshold_depth: float = 2.0e-5  # m, c0 ramps in over this depth
    # m/s: the direction of the threshold force P'_th is sat(v_t / this).
    # The integrator treats a sign flip beyond this band explicitly, so the
    # band must exceed the speed one sample's step can give it (P'_th h /
    # m), or the light point mass chatters (docs/numerics.md). No operating
    # point is this slow.
    smoothing_speed: float = 5.0e-4
    burrs: List[BurrConfig] = field(default_factory=list)
    finish_bin_length: float = 2.0e-4  # m, of arc per surface-finish bin
    # s: the process samples the tool's place on the edge for the force law
    # (depth, directions, burr at the cutter), records the finish and
    # removes the burr this often.
    sample_period: float = 0.0025
    # -; true (the default): along the edge the cutting law is held over
    # each sample at its exact mean (cell.process.force_law_terms' held;
    # math.damping): the damper g a a^T (a = J^T n2) is integrated in
    # closed form with every other force on the arm held over the sample,
    # the controller's torque of that sample included, so the speed along
    # the edge at the sample's end is the damper's own whatever g h / m
    # is, at any integrator step. cenic, which treats only the diagonal of
    # the applied forces' d tau / dv implicitly, then holds the tallest
    # burr at one step per 2.5 ms sample without moving the loop's limits.
    # False: eq. (3) follows the velocities between samples (then the
    # off-diagonal of g a a^T is explicit in cenic, and tall burrs need
    # more steps per sample: docs/numerics.md).
    sample_mean: bool = True
    # -; true (with sample_mean false): the force law adds S (v - v0),
    # zero at each sample's joint velocities v0, that makes its derivative
    # in v diagonal and dominant (cell.process.force_law_terms), so cenic,
    # which treats only that diagonal implicitly, holds any g of (3) at one
    # step per sample. The term
    # is a discretization device: within a step it adds h (D - g a a^T) of
    # inertia across the cut, which moves the sampled loop's limits (it
    # raises the sliding-gain limit and hides the loop's limit cycle:
    # docs/numerics.md). No shipped scenario turns it on.
    implicit_damping: bool = False
    # N/m: with the spindle off (touch probing) a burr is not cut: it
    # pushes the tool back along -n1 where the tool reaches into it.
    burr_contact_stiffness: float = 1.0e4

    def validate(self):
        o = "process"
        for name in ("sample_mean", "implicit_damping"):
            _require(
                isinstance(getattr(self, name), bool),
                f"{o}.{name}",
                getattr(self, name),
                "true or false",
            )
        _require(
            not (self.sample_mean and self.implicit_damping),
            f"{o}.implicit_damping",
            self.implicit_damping,
            "false while process.sample_mean is true (two treatments "
            "of the same damping)",
        )
        for name in (
            "cutting_coefficient",
            "plunge_coefficient",
            "threshold_power_force",
            "contact_threshold_force",
            "burr_contact_stiffness",
        ):
            _non_negative(o, name, getattr(self, name))
        _positive(o, "threshold_depth", self.threshold_depth)
        _positive(o, "smoothing_speed", self.smoothing_speed)
        _positive(o, "sample_period", self.sample_period)
        _require(
            isinstance(self.finish_bin_length, (int, float))
            and 0 < self.finish_bin_length <= 2.0e-4,
            f"{o}.finish_bin_length",
            self.finish_bin_length,
            "a number in (0, 0.0002] m",
        )
        for k, burr in enumerate(self.burrs):
            burr.validate(f"{o}.burrs[{k}]")


@dataclass
class ToolMountConfig:
    """The spindle's pose in the flange frame (URDF's convention: the
    flange-to-spindle transform, rotation R = Rz(yaw) Ry(pitch) Rx(roll)
    about the flange's fixed axes). The spindle points its tool along its
    own +z, so ``rpy: [0, 1.5707963, 0]`` points it along the flange's +x;
    the default (identity) along the flange's +z (ISO 9409-1)."""

    xyz: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0]
    )  # m, the spindle's origin in the flange frame
    rpy: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0]
    )  # rad, roll, pitch, yaw about the flange's fixed x, y, z

    def validate(self, owner="robot.tool_mount"):
        _vector(owner, "xyz", self.xyz, 3, _finite)
        _vector(owner, "rpy", self.rpy, 3, _finite)
        for i, xyz in enumerate(self.xyz):
            _require(
                abs(xyz) <= 2.0,
                f"{owner}.xyz[{i}]",
                xyz,
                "a number in [-2, 2] m (the spindle's origin near the "
                "flange, in metres)",
            )

    def is_identity(self) -> bool:
        return not any(self.xyz) and not any(self.rpy)


@dataclass
class RobotConfig:
    """Which robot holds the tool, the names the cell needs on it, and the
    plant's joint friction (the D term of (1)): viscous damping comes from
    the model file, smooth Coulomb friction F_c tanh(v / v_s) from here.

    ``model`` is a shipped name (``SHIPPED``) or a path to a URDF or SDF
    file (``package://`` URIs inside it resolve as Drake's parser resolves
    them: the ``package.xml`` files in the directories above the file, and
    ``ROS_PACKAGE_PATH``); a relative path in a scenario file is relative to
    that file. The tool: either the model has a body holding the tool, with
    frame ``tool_frame`` at the tool tip (+z along the tool axis, away from
    the part) and a weld joint ``sensor_joint`` (the force/torque sensor)
    as its parent joint (``flange_frame`` empty: arm5 and cartesian_tool),
    or ``flange_frame`` names the model's mounting face and the cell welds
    the sensor (joint ``sensor_joint``) and a spindle of ``tool_mass``
    there, at ``tool_mount`` in the flange frame (default: on the flange,
    along its +z), its tip ``tool_length`` along the spindle's +z
    (deburr_drake.cell.robot). The controller's model of the arm
    differs from the plant by ``controller.model_mass_scale``."""

    model: str = "cartesian_tool"  # -, shipped name, or a .urdf / .sdf path
    joint_coulomb_friction: List[float] = field(
        default_factory=list
    )  # N or N m, per joint; empty: none
    friction_smoothing_speed: float = (
        1.0e-3  # m/s or rad/s, v_s of F_c tanh(v / v_s)
    )
    tool_frame: str = "tool_tip"  # -, frame at the tool tip
    sensor_joint: str = "ft_sensor"  # -, weld joint: the force/torque sensor
    flange_frame: str = ""  # -, frame the spindle is mounted on; "": none
    tool_length: float = 0.12  # m, flange face to tool tip (flange_frame)
    tool_mass: float = 1.5  # kg, sensor and spindle (flange_frame)
    # The spindle's pose in the flange frame (flange_frame): a flange
    # whose tool axis is not its +z, or a tilted or offset spindle.
    tool_mount: ToolMountConfig = field(default_factory=ToolMountConfig)
    # rad, one per joint: the inverse kinematics' start and the posture it
    # stays near (elbow up, wrist flipped or not); empty: the model's
    # default (arm5: its ready pose turned towards the part).
    ik_seed: List[float] = field(default_factory=list)
    # Where the model's package:// URIs (and a package:// robot.model)
    # resolve, beside the package.xml files above the model and
    # ROS_PACKAGE_PATH. Relative to the scenario file; an entry
    # "pip:DIST/sub/folder" is a folder inside the installed Python
    # distribution DIST (e.g. "pip:example-robot-data/cmeel.prefix/share").
    package_paths: List[str] = field(
        default_factory=list
    )  # -, folders whose sub-folders are packages by name
    packages: Dict[str, str] = field(
        default_factory=dict
    )  # -, {package name: its folder}
    # Where the model file gives none (drake:rotor_inertia); empty: the file's.
    reflected_inertia: List[float] = field(
        default_factory=list
    )  # kg m^2, per joint: the drives' reflected inertia

    #: Models shipped in models/ (deburr_drake.cell.robot.SHIPPED_ROBOTS).
    SHIPPED = ("cartesian_tool", "arm5", "arm6")
    FILE_SUFFIXES = (".urdf", ".sdf")

    def is_file(self) -> bool:
        """Whether ``model`` names a file rather than a shipped model."""
        return self.model not in self.SHIPPED

    def is_package_url(self) -> bool:
        """Whether ``model`` is a ``package://NAME/...`` URL (resolved
        through the package folders)."""
        return isinstance(self.model, str) and self.model.startswith(
            "package://"
        )

    def validate(self):
        o = "robot"
        _require(
            isinstance(self.model, str)
            and (
                self.model in self.SHIPPED
                or Path(self.model).suffix.lower() in self.FILE_SUFFIXES
            ),
            f"{o}.model",
            self.model,
            f"one of {self.SHIPPED} or a path (or package:// URL) to a .urdf "
            "or .sdf file",
        )
        if self.is_file() and not self.is_package_url():
            _require(
                Path(self.model).is_file(),
                f"{o}.model",
                self.model,
                "an existing .urdf or .sdf file (no such file)",
            )
        for i, f in enumerate(self.joint_coulomb_friction):
            _non_negative(o, f"joint_coulomb_friction[{i}]", f)
        _positive(o, "friction_smoothing_speed", self.friction_smoothing_speed)
        for name in ("tool_frame", "sensor_joint"):
            _require(
                isinstance(getattr(self, name), str)
                and getattr(self, name) != "",
                f"{o}.{name}",
                getattr(self, name),
                "a frame or joint name",
            )
        _positive(o, "tool_length", self.tool_length)
        _positive(o, "tool_mass", self.tool_mass)
        self.tool_mount.validate(f"{o}.tool_mount")
        _require(
            self.flange_frame != "" or self.tool_mount.is_identity(),
            f"{o}.tool_mount",
            {"xyz": self.tool_mount.xyz, "rpy": self.tool_mount.rpy},
            "the identity when robot.flange_frame is empty (the model "
            "holds its own tool; name its mounting face in "
            "robot.flange_frame for the cell to mount the spindle)",
        )
        for i, q in enumerate(self.ik_seed):
            _require(
                isinstance(q, (int, float)) and math.isfinite(q),
                f"{o}.ik_seed[{i}]",
                q,
                "a finite angle (rad)",
            )
        for i, inertia in enumerate(self.reflected_inertia):
            _non_negative(o, f"reflected_inertia[{i}]", inertia)
        for i, entry in enumerate(self.package_paths):
            _require(
                package_folder(entry).is_dir(),
                f"{o}.package_paths[{i}]",
                entry,
                "an existing folder" + _dist_hint(entry),
            )
        for name, entry in self.packages.items():
            _require(
                name != "" and "/" not in name,
                f"{o}.packages",
                name,
                "package names without '/'",
            )
            _require(
                package_folder(entry).is_dir(),
                f"{o}.packages.{name}",
                entry,
                "an existing folder" + _dist_hint(entry),
            )


#: A package folder inside an installed Python distribution:
#: ``pip:DIST/sub/folder``.
PIP_PREFIX = "pip:"


def package_folder(entry: str) -> Path:
    """The folder a ``robot.package_paths`` / ``robot.packages`` entry
    names: a path, or ``pip:DIST/sub/folder``, the folder ``sub/folder``
    where pip installed the distribution DIST (its site-packages, e.g.
    ``pip:example-robot-data/cmeel.prefix/share``); a distribution that is
    not installed gives a path that does not exist."""
    if not isinstance(entry, str):
        return Path("/nonexistent")
    if not entry.startswith(PIP_PREFIX):
        return Path(entry)
    from importlib import metadata

    dist, _, rest = entry[len(PIP_PREFIX) :].partition("/")
    try:
        root = Path(str(metadata.distribution(dist).locate_file("")))
    except metadata.PackageNotFoundError:
        return Path("/nonexistent") / dist
    return root / rest


def _dist_hint(entry) -> str:
    if isinstance(entry, str) and entry.startswith(PIP_PREFIX):
        dist = entry[len(PIP_PREFIX) :].partition("/")[0]
        from importlib import metadata

        try:
            metadata.distribution(dist)
        except metadata.PackageNotFoundError:
            return (
                f" (no installed Python distribution {dist!r}: "
                f"pip install {dist})"
            )
    return " (relative to the scenario file, or pip:DIST/sub/folder)"


@dataclass
class PartErrorConfig:
    """How the part the controller believes in differs from the real one,
    believed - real, in six degrees of freedom: the believed part is the
    real one turned by ``rpy`` about the real part frame's own axes at its
    origin (R = Rz Ry Rx, Drake's RollPitchYaw), then moved by ``offset``
    along the world's axes, R_WB = R_WR R(rpy), p_WB = p_WR + offset
    (deburr_drake.math.rigid.believed_from_real). The plant, the contact,
    the cutting process and the metrics use the real part; the command
    generator, the first-order hold, the observer and the start pose the
    believed one.

    - A planar part (circle, straight, profile): ``part`` describes the
      real part; its frame is the world's turned by nothing, so ``rpy``
      is a turn about the world's vertical through ``part.pose.xyz``
      (roll and pitch 0: its walls stand upright), as ``yaw`` is (circle:
      the start angle; straight: the heading; profile: its vertices and
      start angle); ``radius``: the inner radius that much larger
      (profile: grown outward by it, a pocket's or a boss's).
    - A mesh part: ``part.pose`` is where the controller believes the
      file is (the fixture's nominal pose); the real part is at
      R_WR = R_WB R(rpy)^T, p_WR = p_WB - offset. ``yaw`` and ``radius``
      are 0 (its turn is ``rpy``)."""

    offset: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0]
    )  # m, world, believed - real
    rpy: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0]
    )  # rad, believed - real, about the real part frame's axes
    yaw: float = 0.0  # rad, believed - real, about the vertical (planar)
    radius: float = 0.0  # m, believed - real inner radius; profile: growth

    def validate(self):
        o = "part_error"
        _vector(o, "offset", self.offset, 3, _finite)
        _rpy(o, self.rpy)
        _require(
            isinstance(self.yaw, (int, float))
            and math.isfinite(self.yaw)
            and abs(self.yaw) <= math.pi,
            f"{o}.yaw",
            self.yaw,
            "a number in [-pi, pi] rad",
        )
        _require(
            self.yaw == 0.0 or self.rpy[2] == 0.0,
            f"{o}.yaw",
            self.yaw,
            f"0 when {o}.rpy[2] is not (both are the turn about the "
            "vertical: give one)",
        )
        _finite(o, "radius", self.radius)

    def moves(self) -> bool:
        """True if the believed part is moved or turned."""
        return any(self.offset) or any(self.rpy) or self.yaw != 0.0

    def planar_yaw(self) -> float:
        """rad: a planar part's turn about the vertical (``yaw`` or
        ``rpy[2]``, whichever is given)."""
        return self.yaw if self.yaw != 0.0 else float(self.rpy[2])

    def check_kind(self, kind: str):
        """One ConfigError naming the field this kind of part cannot take:
        a planar part's roll and pitch (its walls stand upright), a mesh
        part's ``yaw`` and ``radius``."""
        o = "part_error"
        if kind != "mesh":
            _upright(o, self.rpy, kind)
            return
        _require(
            self.yaw == 0.0,
            f"{o}.yaw",
            self.yaw,
            "0 with part.edge.kind mesh (its turn is part_error.rpy, "
            "about the part frame's axes)",
        )
        _require(
            self.radius == 0.0,
            f"{o}.radius",
            self.radius,
            "0 with part.edge.kind mesh (a mesh part's size is its file's)",
        )


def _upright(owner: str, rpy, kind: str):
    """A planar part's turn: about the vertical only."""
    _require(
        rpy[0] == 0.0 and rpy[1] == 0.0,
        f"{owner}.rpy",
        rpy,
        f"[0, 0, yaw] for a {kind} edge (a planar part turns about the "
        "vertical only; roll and pitch on a mesh part)",
    )


def _rpy(owner: str, rpy):
    """A turn of at most pi about each axis (rad)."""
    _vector(owner, "rpy", rpy, 3, _finite)
    for i, v in enumerate(rpy):
        _require(
            abs(v) <= math.pi,
            f"{owner}.rpy[{i}]",
            v,
            "a number in [-pi, pi] rad",
        )


@dataclass
class DropoutConfig:
    """A window in which the force sensor's reading is lost."""

    start: float = 0.0  # s, when the reading is lost
    duration: float = 0.0  # s, for how long
    mode: str = "hold"  # -, hold: the last reading; zero: 0 N

    MODES = ("hold", "zero")

    def validate(self, owner="faults.dropouts[]"):
        _non_negative(owner, "start", self.start)
        _positive(owner, "duration", self.duration)
        _require(
            self.mode in self.MODES,
            f"{owner}.mode",
            self.mode,
            f"one of {self.MODES}",
        )


@dataclass
class PartStepConfig:
    """The part moves in its fixture at ``time``: turned by ``rpy`` about
    its own axes at its origin, then moved by ``offset`` along the world's
    (as ``part_error`` turns and moves the believed part; a planar part
    turns about the vertical only). The real part is fixed in the plant
    (welded hydroelastic geometry), so the step is applied to the part
    the controller believes in: from ``time`` on it takes the pose
    against the unmoved real part that it has against the stepped one
    (deburr_drake.math.rigid.stepped_belief), the error a slipped fixture
    gives the controller (without the contact's own jolt)."""

    time: float = 0.0  # s; 0: no step
    offset: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0]
    )  # m, world, real part's move
    rpy: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0]
    )  # rad, real part's turn about its own axes

    def validate(self, owner="faults.part_step"):
        _non_negative(owner, "time", self.time)
        _vector(owner, "offset", self.offset, 3, _finite)
        _rpy(owner, self.rpy)
        _require(
            self.time == 0.0 or any(self.offset) or any(self.rpy),
            f"{owner}.offset",
            self.offset,
            f"not all zero when {owner}.time > 0 (and {owner}.rpy is)",
        )

    def check_kind(self, kind: str, owner="faults.part_step"):
        """A planar part steps about the vertical only."""
        if kind != "mesh":
            _upright(owner, self.rpy, kind)

    def active(self) -> bool:
        return self.time > 0.0


@dataclass
class FaultsConfig:
    """Faults a deburring cell meets, injected by Drake systems in the
    diagram (deburr_drake.cell.faults); none by default. See also
    ``part_error`` (the part not where the controller thinks it is)."""

    # N, world, added to the force reading the controller and observer get
    sensor_bias: List[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    noise_scale: float = 1.0  # -, multiplies sensor.noise_std
    dropouts: List[DropoutConfig] = field(default_factory=list)
    part_step: PartStepConfig = field(default_factory=PartStepConfig)

    def validate(self):
        o = "faults"
        _vector(o, "sensor_bias", self.sensor_bias, 3, _finite)
        _non_negative(o, "noise_scale", self.noise_scale)
        for k, d in enumerate(self.dropouts):
            d.validate(f"{o}.dropouts[{k}]")
        self.part_step.validate(f"{o}.part_step")

    def sensor_faults(self) -> bool:
        """True if the force reading is biased or drops out."""
        return any(self.sensor_bias) or bool(self.dropouts)


@dataclass
class GuardsConfig:
    """Runtime safety guards (deburr_drake.cell.guards): each stops the run with
    ``stop_reason`` ``guard:<name>`` and its values at the trip. A limit of
    0 takes the default derived from the models and the task."""

    enabled: bool = True  # -, false: no guard runs
    # -, trip when any |tau_i| exceeds this fraction of the joint's effort
    # limit (the robot model's <effort>); joints without one are not checked.
    joint_torque_fraction: float = 1.0
    tool_force: float = 0.0  # N, |measured f|; 0: 10 x desired |f_t|
    depth: float = 0.0  # m, chamfer depth; 0: min(4 x desired, cutter radius)
    workspace_margin: float = 0.02  # m, around the edge's bounding box
    contact_lost_time: float = 1.0  # s, below contact_force after contact
    contact_force: float = 1.0  # N, ||f_n|| above it is contact
    nan: bool = True  # -, any NaN or infinity in a logged signal
    # s; all guards are checked this often, the joint torque also at every
    # inner-loop sample. A multiple of the inner loop's period adds no
    # integrator steps; checking every guard at every sample costs CPU time
    # the torque alone does not (docs/numerics.md).
    check_period: float = 0.02
    # -; the drives clamp the commanded torque at the effort limits, as real
    # ones do: a guard sees a torque one sample after it is commanded, so
    # without the clamp the plant would take one sample of it.
    saturate_effort: bool = True

    def validate(self):
        o = "guards"
        _positive(o, "joint_torque_fraction", self.joint_torque_fraction)
        for name in ("tool_force", "depth"):
            _non_negative(o, name, getattr(self, name))
        for name in (
            "workspace_margin",
            "contact_lost_time",
            "contact_force",
            "check_period",
        ):
            _positive(o, name, getattr(self, name))
        _require(
            self.contact_lost_time > self.check_period,
            "guards.contact_lost_time",
            self.contact_lost_time,
            f"> guards.check_period ({self.check_period})",
        )
