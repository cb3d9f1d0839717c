"""A robot description package as the cell reads it.

Real description packages (ROS packages, pip and conda wheels such as
``example-robot-data``) ship URDFs whose ``package://NAME/...`` URIs name a
folder rather than the ``package.xml`` beside it, visual meshes in formats
Drake's renderers do not read (``.stl``, ``.dae``, upper-case extensions),
collision meshes the cell never uses, joints without a ``<transmission>``
and grippers past the flange. :func:`prepared_model` turns such a file into
the text Drake's parser reads:

- **packages** (:func:`add_packages`): ``robot.packages`` ({name: folder}),
  the sub-folders of ``robot.package_paths`` by folder name, the
  ``package.xml`` files above the model file and ``ROS_PACKAGE_PATH``, in
  that order (the first of a name wins); an unknown package is one
  ConfigError line naming it and where it was looked for;
- **collision geometry** of the arm is left out: only the cutter touches
  the part (deburr_drake.cell.part);
- **visual meshes** Drake cannot read are converted once, with trimesh
  (and pycollada for ``.dae``), into ``.obj`` files in the mesh cache
  ($XDG_CACHE_HOME/deburr_drake/meshes/robot, named by a hash of the
  source file's bytes); a mesh that cannot be read is dropped with one
  warning line naming it;
- **drives**: a URDF joint with an effort limit and no ``<transmission>``
  gets one (a simple transmission, gear ratio 1, the effort limit the
  file's);
- **past the flange**: joints that move off the chain from the base to
  ``robot.flange_frame`` (a gripper's fingers, past the flange or beside
  it) are welded at their default position (0, or the nearest limit), their
  ``<mimic>`` and transmissions removed.

What ROS tools read and Drake's parser refuses, repaired (URDF):

- **a material defined twice** at the robot level (two files composed by
  xacro): the first definition kept. Drake refuses the repeat whatever its
  colour; ROS's Python reader (urdf_parser_py) reads it; urdfdom refuses a
  robot-level repeat but keeps the first definition of a name a link's
  visual defines again, the rule followed here;
- **a ``<mimic>`` on a fixed joint** (a gripper's passive links written
  fixed): removed; a fixed joint has no coordinate to couple;
- **a transmission naming a joint the file does not have** (an arm cut
  from a whole robot's file): removed; it drives nothing here;
- **a transmission of a type Drake does not model** (a wrist's
  ``DifferentialTransmission``, which Drake skips and leaves its joints
  undriven): removed, and its joints get a drive each as joints without a
  transmission do.

Every change is said once per process in one line on stderr.
"""

from __future__ import annotations

import hashlib
import math
import os
from pathlib import Path
import re
import sys
from typing import Dict, List, Tuple
import xml.etree.ElementTree as ET

import numpy as np

from deburr_drake.config import ConfigError, RobotConfig
from deburr_drake.config.cell import package_folder

__all__ = [
    "add_packages",
    "prepared_model",
    "convert_mesh",
    "DRAKE_MESH_SUFFIXES",
    "model_path",
    "notice",
]

#: Visual mesh files Drake reads as they are (case-sensitive, as Drake).
DRAKE_MESH_SUFFIXES = (".obj", ".gltf", ".vtk")
#: Bump when the conversion changes, so cached meshes are made again.
_CONVERTER_VERSION = "1"
_MOVING = ("revolute", "continuous", "prismatic")
_said = set()


def notice(line: str):
    """Prints ``line`` to stderr once per process."""
    if line not in _said:
        _said.add(line)
        print(f"deburr-drake: {line}", file=sys.stderr, flush=True)


def _package_xmls(model_file: Path):
    for directory in model_file.parents:
        xml = directory / "package.xml"
        if xml.is_file():
            yield xml


def add_packages(
    package_map, config: RobotConfig, model_file: Path | None = None
):
    """Adds to a Drake PackageMap the packages of the robot: see the module
    docstring. ``model_file`` (the resolved model) adds the package.xml
    files above it."""

    def add(name, folder):
        if not package_map.Contains(name):
            package_map.Add(name, str(folder))

    for name, entry in config.packages.items():
        add(name, package_folder(entry).resolve())
    for entry in config.package_paths:
        folder = package_folder(entry)
        for sub in sorted(folder.iterdir()) if folder.is_dir() else []:
            if sub.is_dir() and not sub.name.startswith("."):
                add(sub.name, sub.resolve())
    if model_file is not None:
        for xml in _package_xmls(model_file):
            try:
                package_map.AddPackageXml(str(xml))
            except RuntimeError:
                pass  # a name already mapped (a nearer package) or bad XML
    package_map.PopulateFromRosPackagePath()


def _where_looked(config: RobotConfig) -> str:
    return (
        f"robot.packages {sorted(config.packages)}, the sub-folders of "
        f"robot.package_paths {list(config.package_paths)}, the "
        "package.xml files above the model, ROS_PACKAGE_PATH"
    )


def _package_path(package_map, config, url: str, field: str) -> Path:
    """The file a ``package://NAME/rest`` URL names; ConfigError naming the
    package and where it was looked for."""
    name, _, rest = url[len("package://") :].partition("/")
    if not package_map.Contains(name):
        raise ConfigError(
            f"{field} = {url!r} is invalid: package {name!r} is unknown: "
            f"looked in {_where_looked(config)}"
        )
    return Path(package_map.GetPath(name)) / rest


def model_path(package_map, config: RobotConfig) -> Path:
    """The model file ``robot.model`` names (a path or a package:// URL
    resolved through the package folders)."""
    if config.is_package_url():
        path = _package_path(package_map, config, config.model, "robot.model")
        if not path.is_file():
            raise ConfigError(
                f"robot.model = {config.model!r} is invalid: no such file "
                f"{path}"
            )
        return path.resolve()
    return Path(config.model).resolve()


def _cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(
        os.path.expanduser("~"), ".cache"
    )
    return Path(base) / "deburr_drake" / "meshes" / "robot"


def convert_mesh(source: Path, cache_dir: Path | None = None) -> Path:
    """The ``.obj`` (with its ``.mtl`` colours) of a mesh file trimesh
    reads (``.stl``, ``.dae`` through pycollada, ``.ply``, ...), made once
    in the cache and named by a hash of the source's bytes; raises
    ValueError if it cannot be read or holds no triangles."""
    data = Path(source).read_bytes()
    digest = hashlib.sha256(data + _CONVERTER_VERSION.encode()).hexdigest()[:20]
    folder = Path(cache_dir or _cache_dir()) / digest
    target = folder / "mesh.obj"
    if target.is_file():
        return target
    import trimesh

    try:
        scene = trimesh.load(str(source), force="scene")
    except Exception as e:  # trimesh raises many kinds
        raise ValueError(f"{type(e).__name__}: {e}") from None
    if (
        not scene.geometry
        or sum(len(getattr(g, "faces", ())) for g in scene.geometry.values())
        == 0
    ):
        raise ValueError("no triangles in it")
    folder.mkdir(parents=True, exist_ok=True)
    tmp = folder.with_name(folder.name + f".tmp{os.getpid()}")
    tmp.mkdir(parents=True, exist_ok=True)
    scene.export(str(tmp / "mesh.obj"), include_normals=True)
    for f in tmp.iterdir():
        os.replace(f, folder / f.name)
    tmp.rmdir()
    return target


def _mesh_file(uri: str, package_map, config, model_dir: Path):
    if uri.startswith("package://"):
        return _package_path(package_map, config, uri, "robot.model mesh")
    if uri.startswith("file://"):
        return Path(uri[len("file://") :])
    if "://" in uri:
        return None  # model:// and the like: left to Drake
    return model_dir / uri


def _visual_meshes(root, urdf: bool):
    """(visual element, the element holding its mesh URI, the URI) of
    every visual mesh (URDF: ``mesh@filename``; SDF: ``mesh/uri``)."""
    for visual in list(root.iter("visual")):
        mesh = visual.find("geometry/mesh")
        if mesh is None:
            continue
        if urdf:
            yield visual, mesh, mesh.get("filename", "")
        else:
            uri = mesh.find("uri")
            if uri is not None:
                yield visual, uri, (uri.text or "").strip()


def _parents(root):
    return {child: parent for parent in root.iter() for child in parent}


def _convert_visuals(root, urdf, package_map, config, model_dir, notes):
    parents = _parents(root)
    converted = 0
    for visual, element, uri in list(_visual_meshes(root, urdf)):
        try:
            path = _mesh_file(uri, package_map, config, model_dir)
        except ConfigError as e:
            path, reason = None, str(e)
        else:
            reason = "not found"
        if (
            path is None
            and "://" in uri
            and not uri.startswith(("package://", "file://"))
        ):
            continue
        target = None
        if path is not None and path.is_file():
            if path.suffix in DRAKE_MESH_SUFFIXES:
                target = path.resolve()
            else:
                try:
                    target = convert_mesh(path)
                    converted += 1
                except ValueError as e:
                    reason = f"cannot be converted ({e})"
        if target is None:
            parents[visual].remove(visual)
            notice(
                f"warning: robot.model {config.model!r}: visual mesh "
                f"{uri} {reason}: dropped"
            )
            continue
        # A parsed string takes absolute file:// URIs only.
        if urdf:
            element.set("filename", f"file://{target}")
        else:
            element.text = f"file://{target}"
    if converted:
        notes.append(
            f"{converted} visual mesh(es) Drake cannot read "
            f"shown through .obj copies in {_cache_dir()}"
        )


def _strip_collisions(root) -> int:
    parents = _parents(root)
    collisions = list(root.iter("collision"))
    for c in collisions:
        parents[c].remove(c)
    return len(collisions)


def _rpy_matrix(rpy):
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = (
        math.cos(r),
        math.sin(r),
        math.cos(p),
        math.sin(p),
        math.cos(y),
        math.sin(y),
    )
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def _matrix_rpy(R):
    p = math.asin(max(-1.0, min(1.0, -R[2, 0])))
    return [math.atan2(R[2, 1], R[2, 2]), p, math.atan2(R[1, 0], R[0, 0])]


def _axis_rotation(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _numbers(text, default):
    return [float(v) for v in text.split()] if text else list(default)


def _weld_urdf_joint(joint):
    """Makes a URDF joint fixed at its default position: 0, or the limit
    nearest 0, folded into its origin."""
    limit = joint.find("limit")
    q0 = 0.0
    if limit is not None and joint.get("type") != "continuous":
        lo = float(limit.get("lower", 0.0))
        hi = float(limit.get("upper", 0.0))
        q0 = min(max(0.0, lo), hi) if lo <= hi else 0.0
    if q0 != 0.0:
        origin = joint.find("origin")
        if origin is None:
            origin = ET.SubElement(joint, "origin")
        xyz = np.array(_numbers(origin.get("xyz"), [0, 0, 0]))
        R = _rpy_matrix(_numbers(origin.get("rpy"), [0, 0, 0]))
        axis_el = joint.find("axis")
        axis = _numbers(
            axis_el.get("xyz") if axis_el is not None else "", [1, 0, 0]
        )
        if joint.get("type") == "prismatic":
            xyz = xyz + R @ (q0 * np.asarray(axis) / np.linalg.norm(axis))
        else:
            R = R @ _axis_rotation(axis, q0)
        origin.set("xyz", " ".join(f"{v:.12g}" for v in xyz))
        origin.set("rpy", " ".join(f"{v:.12g}" for v in _matrix_rpy(R)))
    joint.set("type", "fixed")
    for tag in (
        "mimic",
        "limit",
        "axis",
        "dynamics",
        "safety_controller",
        "calibration",
    ):
        for child in joint.findall(tag):
            joint.remove(child)


def _off_chain_joints(joints, flange: str) -> List:
    """The joints not on the chain from the base to link ``flange``
    (``joints``: (element, parent link, child link)): a gripper's fingers
    past the flange or beside it."""
    by_child = {j[2]: j for j in joints}
    chain, link = set(), flange
    while link in by_child and by_child[link][0] not in chain:
        chain.add(by_child[link][0])
        link = by_child[link][1]
    return [j[0] for j in joints if j[0] not in chain]


def _flange_link(root, name: str):
    """The link ``robot.flange_frame`` names: a link, or an SDF frame's
    link (``attached_to``, through other frames); None if neither."""
    links = {link.get("name") for link in root.iter("link")}
    frames = {f.get("name"): f.get("attached_to") for f in root.iter("frame")}
    seen = set()
    while name not in links and name in frames and name not in seen:
        seen.add(name)
        name = frames[name]
    return name if name in links else None


def _urdf_joints(root):
    return [
        (j, j.find("parent").get("link"), j.find("child").get("link"))
        for j in root.findall("joint")
        if j.find("parent") is not None and j.find("child") is not None
    ]


def _sdf_joints(root):
    out = []
    for j in root.iter("joint"):
        parent, child = j.find("parent"), j.find("child")
        if parent is not None and child is not None:
            out.append(
                (j, (parent.text or "").strip(), (child.text or "").strip())
            )
    return out


def _weld_past_flange(root, urdf, config, notes):
    """Every joint that moves off the chain from the base to the flange
    (fingers) welded at its default position; the joint names."""
    flange = (
        _flange_link(root, config.flange_frame) if config.flange_frame else None
    )
    if flange is None:
        return set()
    joints = _urdf_joints(root) if urdf else _sdf_joints(root)
    welded = []
    for joint in _off_chain_joints(joints, flange):
        if joint.get("type") in _MOVING:
            welded.append(joint.get("name"))
            if urdf:
                _weld_urdf_joint(joint)
            else:
                joint.set("type", "fixed")
                for child in list(joint):
                    if child.tag not in ("parent", "child", "pose"):
                        joint.remove(child)
    if welded:
        notes.append(
            f"joints off the chain to robot.flange_frame "
            f"{config.flange_frame!r} (past it or beside it) welded "
            f"at their default position: {welded}"
        )
    return set(welded)


def _rgba(text):
    try:
        return tuple(_numbers(text, ()))
    except ValueError:
        return text  # left for Drake to refuse


def _definition(material):
    """(rgba, texture) a material element defines; None if it only names
    one."""
    colour, texture = material.find("color"), material.find("texture")
    if colour is None and texture is None:
        return None
    return (
        _rgba(colour.get("rgba", "")) if colour is not None else None,
        texture.get("filename") if texture is not None else None,
    )


def _said_definition(definition) -> str:
    rgba, texture = definition
    words = []
    if rgba is not None:
        numbers = isinstance(rgba, tuple)
        words.append(
            "rgba " + (" ".join(f"{v:g}" for v in rgba) if numbers else rgba)
        )
    if texture is not None:
        words.append(f"texture {texture}")
    return ", ".join(words)


def _one_definition_per_material(root, notes):
    """The robot-level materials defined more than once: the first
    definition kept, the later ones removed."""
    first, later = {}, {}
    for material in root.findall("material"):
        name = material.get("name")
        if name not in first:
            first[name] = material
            continue
        root.remove(material)
        later.setdefault(name, []).append(_definition(material))
    times = {1: "twice", 2: "three times"}
    for name, repeats in later.items():
        kept = _definition(first[name])
        others = [d for d in repeats if d is not None and d != kept]
        count = times.get(len(repeats), f"{len(repeats) + 1} times")
        if not others or kept is None:
            what = "same colour"
        else:
            dropped = "; ".join(dict.fromkeys(map(_said_definition, others)))
            what = (
                f"different colours: {_said_definition(kept)} kept, "
                f"{dropped} dropped, as urdfdom does for a name a visual "
                "defines again"
            )
        notes.append(
            f"material {name!r} defined {count} ({what}): kept the first"
        )


def _unmimic_fixed_joints(root, notes):
    """``<mimic>`` removed from fixed joints: nothing to couple."""
    fixed = [
        j
        for j in root.findall("joint")
        if j.get("type") == "fixed" and j.find("mimic") is not None
    ]
    for joint in fixed:
        for mimic in joint.findall("mimic"):
            joint.remove(mimic)
    if fixed:
        notes.append(
            f"<mimic> removed from {len(fixed)} fixed joint(s), which have "
            f"no coordinate to couple: {[j.get('name') for j in fixed]}"
        )


def _transmission_type(transmission) -> str:
    """A transmission's type, as a child ``<type>`` or (older files) an
    attribute; Drake drives joints through SimpleTransmissions only."""
    child = transmission.find("type")
    if child is not None:
        return (child.text or "").strip()
    return transmission.get("type", "")


def _add_drives(root, welded, notes):
    """A transmission for every URDF joint that moves, has an effort limit
    and none. Removed: transmissions of welded joints, those naming a joint
    the file does not have and those of a type Drake skips (their joints
    then get a drive each)."""
    joints = {j.get("name") for j in root.findall("joint")}
    transmitted, absent, replaced = set(), {}, {}
    for t in list(root.findall("transmission")):
        names = [j.get("name") for j in t.findall("joint")]
        kind = _transmission_type(t)
        if set(names) & welded:
            root.remove(t)
        elif set(names) - joints:
            root.remove(t)
            absent[t.get("name")] = sorted(set(names) - joints)
        elif kind and "SimpleTransmission" not in kind:
            # Older types name their joints in other tags (PR2's
            # WristTransmission: <flexJoint>, <rollJoint>).
            named = [e.get("name") for e in t.iter() if e is not t]
            replaced[t.get("name")] = (
                kind.rpartition("/")[2],
                [name for name in named if name in joints],
            )
            root.remove(t)
        else:
            transmitted |= set(names)
    if absent:
        notes.append(
            "transmission(s) naming joints the file does not have removed "
            f"(they drive nothing in it): {absent}"
        )
    if replaced:
        notes.append(
            f"{len(replaced)} transmission(s) of a type Drake does not "
            "model, which would leave their joints undriven, replaced by a "
            "drive per joint at its URDF effort limit (the coupling of "
            f"their motors' limits is not modelled): {replaced}"
        )
    driven = []
    for joint in root.findall("joint"):
        name, limit = joint.get("name"), joint.find("limit")
        if (
            joint.get("type") not in _MOVING
            or name in transmitted
            or limit is None
            or float(limit.get("effort", 0.0)) <= 0.0
        ):
            continue
        t = ET.SubElement(root, "transmission", name=f"{name}_drive")
        ET.SubElement(
            t, "type"
        ).text = "transmission_interface/SimpleTransmission"
        j = ET.SubElement(t, "joint", name=name)
        ET.SubElement(j, "hardwareInterface").text = "EffortJointInterface"
        a = ET.SubElement(t, "actuator", name=f"{name}_motor")
        ET.SubElement(a, "mechanicalReduction").text = "1"
        driven.append(name)
    if driven:
        notes.append(
            f"{len(driven)} joint(s) without a <transmission> get a "
            f"drive at their URDF effort limit: {driven}"
        )


def _declare_drake_namespace(text: str) -> str:
    """Drake's ``drake:`` tags, declared (many files leave the prefix
    unbound, which tinyxml2 accepts and ElementTree does not) and kept as
    ``drake:`` when the tree is written back."""
    match = re.search(r'xmlns:drake\s*=\s*["\']([^"\']+)', text)
    uri = match.group(1) if match else "http://drake.mit.edu"
    ET.register_namespace("drake", uri)
    if match is None and "drake:" in text:
        text = re.sub(
            r"<(robot|sdf)(\s|>)",
            lambda m: f'<{m.group(1)} xmlns:drake="{uri}"{m.group(2)}',
            text,
            count=1,
        )
    return text


def _drop_unread_joint_tags(root, notes):
    """Joint and actuator tags Drake ignores with a warning at every
    parse, removed; what they held that the cell can model instead is
    said in ``notes``."""
    # Joint tags Drake does not read (it warns at every parse); the cell
    # uses neither. URDF joint friction Drake does not model either: said
    # once, with the values, for robot.joint_coulomb_friction.
    friction = {}
    for joint in root.iter("joint"):
        for tag in ("safety_controller", "calibration"):
            for child in joint.findall(tag):
                joint.remove(child)
        dynamics = joint.find("dynamics")
        if dynamics is not None and "friction" in dynamics.attrib:
            value = dynamics.attrib.pop("friction")
            if float(value) != 0.0:
                friction[joint.get("name")] = float(value)
    # A transmission's mechanicalReduction: Drake warns at every parse and
    # ignores it (the reflected inertia is drake:rotor_inertia x
    # drake:gear_ratio^2, robot.reflected_inertia).
    reductions = 0
    for actuator in root.iter("actuator"):
        for child in actuator.findall("mechanicalReduction"):
            reductions += child.text is not None and child.text.strip() not in (
                "1",
                "1.0",
            )
            actuator.remove(child)
    if reductions:
        notes.append(
            f"{reductions} <mechanicalReduction>s are not modelled "
            "(no rotor inertia with them): give the drives' "
            "reflected inertia in robot.reflected_inertia"
        )
    if friction:
        notes.append(
            f"its joint friction {friction} (N m) is not modelled: "
            "give it in robot.joint_coulomb_friction"
        )


_PREPARED: Dict[Tuple, Tuple[str, str, Path, List[str]]] = {}


def prepared_model(package_map, config: RobotConfig):
    """(text, "urdf" or "sdf", model file, notes): the model file of
    ``robot.model`` as the cell reads it (module docstring), its
    package:// URIs resolvable through ``package_map`` (filled by
    :func:`add_packages`). Cached per process."""
    path = model_path(package_map, config)
    key = (
        str(path),
        path.stat().st_mtime_ns,
        config.flange_frame,
        tuple(sorted(config.packages.items())),
        tuple(config.package_paths),
    )
    if key in _PREPARED:
        return _PREPARED[key]
    text = _declare_drake_namespace(path.read_text())
    try:
        root = ET.fromstring(text)
    except ET.ParseError as e:
        raise ConfigError(
            f"robot.model = {config.model!r} is invalid: bad XML ({e})"
        ) from None
    urdf = root.tag == "robot"
    notes = []
    # Unknown packages anywhere in the file: one line each.
    for url in sorted(set(re.findall(r"package://[^\s\"'<>]+", text))):
        _package_path(package_map, config, url, "robot.model URI")
    _drop_unread_joint_tags(root, notes)
    if urdf:
        _one_definition_per_material(root, notes)
        _unmimic_fixed_joints(root, notes)
    collisions = _strip_collisions(root)
    if collisions:
        notes.append(
            f"its {collisions} collision geometries are not loaded "
            "(only the cutter touches the part)"
        )
    _convert_visuals(root, urdf, package_map, config, path.parent, notes)
    welded = _weld_past_flange(root, urdf, config, notes)
    if urdf:
        _add_drives(root, welded, notes)
    result = (
        ET.tostring(root, encoding="unicode"),
        "urdf" if urdf else "sdf",
        path,
        notes,
    )
    _PREPARED[key] = result
    return result
