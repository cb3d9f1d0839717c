"""Writes the test parts of models/parts/ as binary STL files in mm.

tube.stl        the paper's tube: bore radius 30 mm, wall 5 mm, 0 <= z <= 50
cross_hole.stl  a radial hole of radius 8 mm through the wall of a tube of
                outer radius 30 mm (wall 10 mm, 0 <= z <= 80), its axis
                along +x at z = 40 mm
inclined_hole.stl  a 20 mm hole (radius 10 mm) through an 80 x 80 x 20 mm
                plate tilted 30 degrees about x; the hole's axis is the
                plate's normal through the origin, which is the centre of
                the hole's rim on the top face
angled_hole.stl a 16 mm hole (radius 8 mm) drilled 30 degrees off the
                normal of an 80 x 80 x 20 mm plate lying flat (top face at
                z = 0), its axis turned about x and through the origin, the
                centre of its elliptic rim on the top face
pipe_hole.stl   a 16 mm radial hole (radius 8 mm) through the top of a
                pipe lying along x (outer radius 30 mm, wall 10 mm, 100 mm
                long, resting on z = 0), the hole's axis along +z at x = 0
wedge.stl       a prism 60 mm long along y whose top face and sloped face
                meet at 120 degrees in a straight open edge at x = 40 mm,
                z = 20 mm
block.stl       the job example: a 140 x 100 x 30 mm block, vertical
                corners rounded 12 mm, its top face at z = 0 with the
                origin at its centre, and on the top side: a through bore
                of radius 10 mm at (-40, 15); holes of radius 6 mm drilled
                15 degrees off the top's normal (about x) at (-40, -28) and
                30 degrees off it (about y) at (0, -25); a slot 12 mm wide,
                48 mm long and 10 mm deep along x centred at (5, 22); the
                outer rim; a chamfer along y = 32 mm sloping down at 60
                degrees to the +y side, down to the bottom (120 degrees
                between it and the top: a tool standing on the top needs
                a 30-degree tilt, leaning across the arm, not towards it)

plate_holes.stl a 120 x 80 x 15 mm plate (top face at z = 0) with holes of
                radius 4 mm 45 degrees off the normal (about y), 7 mm
                20 degrees off it (about the diagonal x = y), 12 mm and
                3 mm along it (plate_holes)
casting.stl     a 110 x 80 x 35 mm casting-like block (top at z = 0): a
                rounded pocket 60 x 40 x 12 mm leaving a rim, its -x end an
                inclined face 40 degrees down from the top, a hole of
                radius 6 mm along that face's normal (casting)

Not shipped, for trying the planner on other parts (--out elsewhere):
flange (a disc with a hub, a bore and six bolt holes) and small_block (a
90 x 70 x 25 mm block with a bore, a hole 25 degrees off the normal and a
pocket).

The hole parts need manifold3d (trimesh's boolean engine; pip install
deburr_drake[parts]). Facets: 256 round a tube, 160 round a hole, so that
the smoothed edges are within a few micrometres of the true curves.

    python scripts/make_test_parts.py [--out models/parts] [block ...]
"""

import argparse
import math
from pathlib import Path

import numpy as np
import trimesh

ROOT = Path(__file__).resolve().parents[1]


def tube(inner_radius, outer_radius, height, sections=256):
    """A tube about z, 0 <= z <= height (mm)."""
    mesh = trimesh.creation.annulus(
        r_min=inner_radius, r_max=outer_radius, height=height, sections=sections
    )
    mesh.apply_translation([0.0, 0.0, 0.5 * height])
    return mesh


def cross_hole():
    body = tube(20.0, 30.0, 80.0)
    drill = trimesh.creation.cylinder(radius=8.0, height=40.0, sections=160)
    # the drill's axis along +x, from x = 10 mm (in the bore) to 50 mm
    drill.apply_transform(
        trimesh.transformations.rotation_matrix(math.pi / 2, [0, 1, 0])
    )
    drill.apply_translation([30.0, 0.0, 40.0])
    return trimesh.boolean.difference([body, drill], engine="manifold")


def inclined_hole():
    plate = trimesh.creation.box(extents=[80.0, 80.0, 20.0])
    plate.apply_translation([0.0, 0.0, -10.0])  # top face at z = 0
    drill = trimesh.creation.cylinder(radius=10.0, height=60.0, sections=160)
    part = trimesh.boolean.difference([plate, drill], engine="manifold")
    part.apply_transform(
        trimesh.transformations.rotation_matrix(math.radians(30.0), [1, 0, 0])
    )
    return part


def angled_hole():
    plate = trimesh.creation.box(extents=[80.0, 80.0, 20.0])
    plate.apply_translation([0.0, 0.0, -10.0])  # top face at z = 0
    drill = trimesh.creation.cylinder(radius=8.0, height=80.0, sections=160)
    drill.apply_transform(
        trimesh.transformations.rotation_matrix(math.radians(30.0), [1, 0, 0])
    )
    return trimesh.boolean.difference([plate, drill], engine="manifold")


def pipe_hole():
    body = tube(20.0, 30.0, 100.0)
    body.apply_translation([0.0, 0.0, -50.0])
    # the pipe's axis along x, resting on z = 0
    body.apply_transform(
        trimesh.transformations.rotation_matrix(math.pi / 2, [0, 1, 0])
    )
    body.apply_translation([0.0, 0.0, 30.0])
    drill = trimesh.creation.cylinder(radius=8.0, height=40.0, sections=160)
    drill.apply_translation([0.0, 0.0, 50.0])  # from z = 30 (the bore) up
    return trimesh.boolean.difference([body, drill], engine="manifold")


def wedge(length=60.0):
    """Cross-section in xz: the top (z = 20) meets a face sloping down at
    60 degrees from the horizontal, 120 degrees between the faces."""
    run = 20.0 / math.tan(math.radians(60.0))
    section = np.array([[0.0, 0.0], [40.0 + run, 0.0], [40.0, 20.0], [0, 20]])
    bottom = np.column_stack([section[:, 0], np.zeros(4), section[:, 1]])
    top = bottom + [0.0, length, 0.0]
    vertices = np.vstack([bottom, top])
    faces = [[0, 1, 2], [0, 2, 3], [4, 6, 5], [4, 7, 6]]  # the y ends
    for i in range(4):
        j = (i + 1) % 4
        faces += [[i, i + 4, j + 4], [i, j + 4, j]]
    mesh = trimesh.Trimesh(vertices, faces)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def _drill(radius, depth, *, at, tilt_deg=0.0, about=(1, 0, 0), sections=160):
    """A drill of ``radius`` through z = 0 at ``at`` (x, y), its axis
    turned ``tilt_deg`` about ``about``, reaching ``depth`` both ways."""
    drill = trimesh.creation.cylinder(
        radius=radius, height=2.0 * depth, sections=sections
    )
    drill.apply_transform(
        trimesh.transformations.rotation_matrix(math.radians(tilt_deg), about)
    )
    drill.apply_translation([at[0], at[1], 0.0])
    return drill


def _rounded_box(length, width, height, corner, sections=64):
    """A rounded rectangle (corners of radius ``corner``) extruded
    ``height`` about the origin: two boxes and the four corners' posts."""
    pieces = [
        trimesh.creation.box(extents=[length, width - 2 * corner, height]),
        trimesh.creation.box(extents=[length - 2 * corner, width, height]),
    ]
    for sx in (-1, 1):
        for sy in (-1, 1):
            post = trimesh.creation.cylinder(
                radius=corner, height=height, sections=sections
            )
            post.apply_translation(
                [sx * (length / 2 - corner), sy * (width / 2 - corner), 0]
            )
            pieces.append(post)
    return trimesh.boolean.union(pieces, engine="manifold")


def block(
    length=140.0,
    width=100.0,
    height=30.0,
    corner=12.0,
    chamfer_at=32.0,
    chamfer_slope=60.0,
    chamfer_heading=90.0,
):
    """The job example (see the module docstring); the chamfer's top edge
    ``chamfer_at`` from the centre, its face sloping down
    ``chamfer_slope`` degrees from the top towards the heading
    ``chamfer_heading`` (degrees about z from +x)."""
    body = _rounded_box(length, width, height, corner)
    body.apply_translation([0.0, 0.0, -0.5 * height])
    # the chamfer: a box whose bottom face is the sloping plane through
    # the line x = chamfer_at, z = 0
    chamfer = trimesh.creation.box(extents=[100.0, 200.0, 100.0])
    chamfer.apply_translation([0.0, 0.0, 50.0])
    chamfer.apply_transform(
        trimesh.transformations.rotation_matrix(
            math.radians(chamfer_slope), [0, 1, 0]
        )
    )
    chamfer.apply_translation([chamfer_at, 0.0, 0.0])
    chamfer.apply_transform(
        trimesh.transformations.rotation_matrix(
            math.radians(chamfer_heading), [0, 0, 1]
        )
    )
    slot = [trimesh.creation.box(extents=[36.0, 12.0, 20.0])]
    slot += [_drill(6.0, 10.0, at=(x, 0.0), sections=96) for x in (-18, 18)]
    slot = trimesh.boolean.union(slot, engine="manifold")
    slot.apply_translation([5.0, 22.0, 0.0])  # 10 mm deep
    cuts = [
        chamfer,
        _drill(10.0, 40.0, at=(-40.0, 15.0)),
        _drill(6.0, 50.0, at=(-40.0, -28.0), tilt_deg=15.0),
        _drill(6.0, 50.0, at=(0.0, -25.0), tilt_deg=30.0, about=(0, 1, 0)),
        slot,
    ]
    return trimesh.boolean.difference([body, *cuts], engine="manifold")


def flange(radius=60.0, thickness=12.0, hub_radius=25.0, hub_height=18.0):
    """A flange: a disc about z (0 <= z <= ``thickness``), a hub on it up
    to ``thickness + hub_height``, a bore of radius 12 mm through both and
    six bolt holes of radius 5 mm on a 45 mm radius."""
    disc = trimesh.creation.cylinder(
        radius=radius, height=thickness, sections=192
    )
    disc.apply_translation([0.0, 0.0, 0.5 * thickness])
    hub = trimesh.creation.cylinder(
        radius=hub_radius, height=hub_height + 1.0, sections=128
    )
    hub.apply_translation([0.0, 0.0, thickness + 0.5 * hub_height - 0.5])
    body = trimesh.boolean.union([disc, hub], engine="manifold")
    holes = [_drill(12.0, 60.0, at=(0.0, 0.0), sections=128)]
    for k in range(6):
        angle = math.radians(30.0 + 60.0 * k)
        at = (45.0 * math.cos(angle), 45.0 * math.sin(angle))
        holes.append(_drill(5.0, 30.0, at=at, sections=64))
    return trimesh.boolean.difference([body, *holes], engine="manifold")


def plate_holes(length=120.0, width=80.0, thickness=15.0):
    """A plate (top face at z = 0) with holes of other sizes and angles
    than the block's: radius 4 mm 45 degrees off the normal (about y) at
    (-35, 15); radius 7 mm 20 degrees off it about the diagonal x = y at
    (0, -15); radius 12 mm along the normal at (35, 10); radius 3 mm
    along the normal at (-35, -22)."""
    plate = trimesh.creation.box(extents=[length, width, thickness])
    plate.apply_translation([0.0, 0.0, -0.5 * thickness])
    diagonal = (1.0 / math.sqrt(2.0), 1.0 / math.sqrt(2.0), 0.0)
    holes = [
        _drill(4.0, 40.0, at=(-35.0, 15.0), tilt_deg=45.0, about=(0, 1, 0)),
        _drill(7.0, 40.0, at=(0.0, -15.0), tilt_deg=20.0, about=diagonal),
        _drill(12.0, 40.0, at=(35.0, 10.0)),
        _drill(3.0, 40.0, at=(-35.0, -22.0), sections=64),
    ]
    return trimesh.boolean.difference([plate, *holes], engine="manifold")


def casting(length=110.0, width=80.0, height=35.0):
    """A casting-like part, its top at z = 0: a block with a pocket 60 x
    40 mm and 12 mm deep (corners rounded 8 mm) leaving a rim round it,
    its -x end an inclined face sloping down at 40 degrees from the top
    (140 degrees between them), and a hole of radius 6 mm drilled along
    that face's normal through its middle."""
    body = trimesh.creation.box(extents=[length, width, height])
    body.apply_translation([0.0, 0.0, -0.5 * height])
    # the pocket: a rounded rectangle 12 mm deep, centred at (10, 0)
    pocket = _rounded_box(60.0, 40.0, 24.0, 8.0)
    pocket.apply_translation([10.0, 0.0, 0.0])  # 12 mm deep
    # the inclined face: its top edge along y at x = -35
    slope = math.radians(40.0)
    cut = trimesh.creation.box(extents=[100.0, 200.0, 100.0])
    cut.apply_translation([0.0, 0.0, 50.0])
    cut.apply_transform(
        trimesh.transformations.rotation_matrix(-slope, [0, 1, 0])
    )
    cut.apply_translation([-35.0, 0.0, 0.0])
    # the hole along the inclined face's normal (the drill's z turned
    # about y by -slope), through its middle
    middle = np.array([-35.0, 0.0, 0.0]) + 15.0 * np.array(
        [-math.cos(slope), 0.0, -math.sin(slope)]
    )
    drill = trimesh.creation.cylinder(radius=6.0, height=80.0, sections=128)
    drill.apply_transform(
        trimesh.transformations.rotation_matrix(-slope, [0, 1, 0])
    )
    drill.apply_translation(middle)
    return trimesh.boolean.difference(
        [body, pocket, cut, drill], engine="manifold"
    )


def small_block():
    """Another block: 90 x 70 x 25 mm, corners rounded 6 mm, top at z = 0,
    with a through bore of radius 8 mm at (-20, 10), a hole of radius 5 mm
    25 degrees off the normal (about x) at (20, -15), and a pocket 30 x
    20 mm, 8 mm deep, at (15, 15)."""
    height = 25.0
    body = _rounded_box(90.0, 70.0, height, 6.0, sections=48)
    body.apply_translation([0.0, 0.0, -0.5 * height])
    pocket = trimesh.creation.box(extents=[30.0, 20.0, 16.0])
    pocket.apply_translation([15.0, 15.0, 0.0])
    cuts = [
        _drill(8.0, 40.0, at=(-20.0, 10.0)),
        _drill(5.0, 40.0, at=(20.0, -15.0), tilt_deg=25.0),
        pocket,
    ]
    return trimesh.boolean.difference([body, *cuts], engine="manifold")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "models" / "parts")
    parser.add_argument(
        "parts",
        nargs="*",
        help="the parts to write (default: the shipped ones)",
    )
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    parts = {
        "tube": lambda: tube(30.0, 35.0, 50.0),
        "cross_hole": cross_hole,
        "inclined_hole": inclined_hole,
        "wedge": wedge,
        "angled_hole": angled_hole,
        "pipe_hole": pipe_hole,
        "block": block,
        "flange": flange,
        "plate_holes": plate_holes,
        "casting": casting,
        "small_block": small_block,
    }
    shipped = [p for p in parts if p not in ("flange", "small_block")]
    for name in args.parts or shipped:
        mesh = parts[name]()
        assert mesh.is_watertight and mesh.volume > 0, name
        path = args.out / f"{name}.stl"
        mesh.export(path)
        print(f"{path}: {len(mesh.faces)} triangles")


if __name__ == "__main__":
    main()
