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

The hole parts need manifold3d (trimesh's boolean engine; pip install
deburr_drake[parts]). Facets: 256 round a tube, 160 round a hole, so that
the smoothed edges are within a few micrometres of the true curves.

    python scripts/make_test_parts.py [--out models/parts]
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


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "models" / "parts")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    parts = {
        "tube": tube(30.0, 35.0, 50.0),
        "cross_hole": cross_hole(),
        "inclined_hole": inclined_hole(),
        "wedge": wedge(),
        "angled_hole": angled_hole(),
        "pipe_hole": pipe_hole(),
    }
    for name, mesh in parts.items():
        assert mesh.is_watertight and mesh.volume > 0, name
        path = args.out / f"{name}.stl"
        mesh.export(path)
        print(f"{path}: {len(mesh.faces)} triangles")


if __name__ == "__main__":
    main()
