"""The part (tube) in Drake: its compliant hydroelastic top ring, and the
tool/ring contact law it yields.

The normal contact force of the paper's eq. (4) (R7: c2*delta_dot + c1*delta +
c0) is not modelled by hand: it emerges from Drake's hydroelastic contact
between the rigid cutter and this compliant ring (docs/cell-and-paper.md).
`measure_normal_force` measures that force as a function of the radial depth,
for calibration and tests.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.geometry import (
    AddCompliantHydroelasticProperties,
    AddContactMaterial,
    AddRigidHydroelasticProperties,
    Box,
    Cylinder,
    GeometryInstance,
    MakePhongIllustrationProperties,
    Mesh,
    ProximityProperties,
)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import (
    AddMultibodyPlantSceneGraph,
    ContactModel,
    CoulombFriction,
)
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.framework import DiagramBuilder

from deburr_drake.cell.models import POINT_MASS_URL, make_parser
from deburr_drake.cell.tube_mesh import (
    edge_band_mesh_path,
    mesh_obj_path,
    profile_mesh_paths,
    ring_mesh_path,
    ring_surface_path,
)

__all__ = [
    "CALIBRATED_HYDROELASTIC_MODULUS",
    "CALIBRATED_FORCE_AT_HALF_MM",
    "contact_force_on_body",
    "register_compliant_ring",
    "register_compliant_wall",
    "register_compliant_profile",
    "register_compliant_edge",
    "register_part_visual",
    "register_tube_visual",
    "register_cutter",
    "add_tool_robot",
    "add_cartesian_tool",
    "RingContactProbe",
    "EdgeContactProbe",
    "measure_normal_force",
    "local_stiffness",
    "power_law_exponent",
    "calibrate_hydroelastic_modulus",
    "force_ripple",
]

# Calibration by scripts/contact_stiffness.py (n_theta = 240, n_radial = n_z =
# 2, the default geometry of measure_normal_force): with this modulus the local
# stiffness dF/d(delta) at delta = 0.5 mm is about 10 N/mm; the force there is
# as stated. The scenarios' coarser default (120 segments, 0.6 mm cutter mesh)
# gives the same force within 0.3 % (docs/numerics.md,
# scripts/contact_mesh.py).
CALIBRATED_HYDROELASTIC_MODULUS = 4.5e6  # Pa
CALIBRATED_FORCE_AT_HALF_MM = 3.72  # N


def _compliant_properties(resolution_hint, modulus, dissipation):
    """The part's compliant hydroelastic proximity properties: no friction,
    since the tangential force is the cutting process's."""
    props = ProximityProperties()
    AddCompliantHydroelasticProperties(
        resolution_hint=resolution_hint,
        hydroelastic_modulus=modulus,
        properties=props,
    )
    AddContactMaterial(
        dissipation=dissipation,
        friction=CoulombFriction(0.0, 0.0),
        properties=props,
    )
    return props


def _check_positive(name, value):
    if not (
        isinstance(value, (int, float, np.floating, np.integer))
        and math.isfinite(value)
        and value > 0
    ):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")


def _check_dissipation(value):
    if not (
        isinstance(value, (int, float, np.floating, np.integer))
        and math.isfinite(value)
        and value >= 0
    ):
        raise ValueError(
            "hunt_crossley_dissipation must be a finite number >= 0, "
            f"got {value!r}"
        )


def register_compliant_ring(
    plant,
    *,
    inner_radius,
    outer_radius,
    z_bottom,
    z_top,
    hydroelastic_modulus,
    hunt_crossley_dissipation,
    center_xy=(0.0, 0.0),
    n_theta=240,
    n_radial=2,
    n_z=2,
    name="tube_edge",
):
    """Register the ring inner_radius <= r <= outer_radius, z_bottom <= z <=
    z_top (m) about the vertical axis through center_xy (m, world) on the world
    body.

    Collision: the tetrahedral mesh of `tube_mesh.ring_mesh_path` (an
    n_theta-gon annulus) as a compliant hydroelastic `Mesh` with modulus E =
    hydroelastic_modulus (Pa), Hunt-Crossley dissipation (s/m) and zero friction
    (tool-part friction is 0: the tangential force is the cutting process's).
    Visual: the ring's surface as .obj (`tube_mesh.ring_surface_path`; Meshcat
    does not draw .vtk), illustration role only. Call before plant.Finalize().
    Returns the collision GeometryId.
    """
    if plant.is_finalized():
        raise ValueError(
            "plant must not be finalized yet "
            "(register the ring before Finalize())"
        )
    _check_positive("hydroelastic_modulus", hydroelastic_modulus)
    _check_dissipation(hunt_crossley_dissipation)
    path = ring_mesh_path(
        inner_radius, outer_radius, z_bottom, z_top, n_theta, n_radial, n_z
    )
    mesh = Mesh(str(path))
    # The resolution hint is ignored for a Mesh (its tetrahedra are used as
    # they are).
    props = _compliant_properties(
        outer_radius - inner_radius,
        hydroelastic_modulus,
        hunt_crossley_dissipation,
    )
    world = plant.world_body()
    X_WG = RigidTransform([float(center_xy[0]), float(center_xy[1]), 0.0])
    geometry_id = plant.RegisterCollisionGeometry(
        world, X_WG, mesh, name, props
    )
    surface = ring_surface_path(
        inner_radius, outer_radius, z_bottom, z_top, n_theta
    )
    visual = GeometryInstance(X_WG, Mesh(str(surface)), name + "_visual")
    visual.set_illustration_properties(
        MakePhongIllustrationProperties(np.array([0.7, 0.6, 0.4, 1.0]))
    )
    plant.RegisterVisualGeometry(world, visual)
    return geometry_id


def register_compliant_wall(
    plant,
    *,
    mid,
    tangent,
    normal,
    length,
    thickness,
    height,
    layer_height,
    hydroelastic_modulus,
    hunt_crossley_dissipation,
    margin=0.01,
    name="wall_edge",
):
    """A straight wall whose top edge runs through `mid` (m, world, on the wall
    face at the top) along `tangent`, the material on the side of `normal`
    (unit, horizontal): its top `layer_height` as a compliant hydroelastic Box
    (Drake meshes it; pressure zero on the surface, rising to E at its medial
    axis), `margin` longer than the edge at both ends, frictionless; the rest of
    the wall as illustration. Call before Finalize. Returns the
    collision GeometryId."""
    _check_positive("hydroelastic_modulus", hydroelastic_modulus)
    for label, value in (
        ("length", length),
        ("thickness", thickness),
        ("height", height),
        ("layer_height", layer_height),
    ):
        _check_positive(label, value)
    tangent, normal = np.asarray(tangent, float), np.asarray(normal, float)
    R = RotationMatrix(
        np.column_stack([tangent, normal, np.cross(tangent, normal)])
    )
    top = np.asarray(mid, float) + 0.5 * thickness * normal
    X_layer = RigidTransform(R, top - [0.0, 0.0, 0.5 * layer_height])
    props = _compliant_properties(
        thickness, hydroelastic_modulus, hunt_crossley_dissipation
    )
    shape = Box(length + 2 * margin, thickness, layer_height)
    world = plant.world_body()
    geometry_id = plant.RegisterCollisionGeometry(
        world, X_layer, shape, name, props
    )
    plant.RegisterVisualGeometry(
        world, X_layer, shape, name + "_visual", np.array([0.7, 0.6, 0.4, 1.0])
    )
    body_height = height - layer_height
    X_body = RigidTransform(
        R, top - [0.0, 0.0, layer_height + 0.5 * body_height]
    )
    plant.RegisterVisualGeometry(
        world,
        X_body,
        Box(length + 2 * margin, thickness, body_height),
        name + "_body",
        np.array([0.6, 0.6, 0.65, 1.0]),
    )
    return geometry_id


def register_compliant_profile(
    plant,
    edge,
    *,
    wall_thickness,
    z_bottom,
    z_top,
    hydroelastic_modulus,
    hunt_crossley_dissipation,
    segments_per_turn=120,
    n_radial=2,
    n_z=2,
    visual_z_bottom=None,
    name="profile_edge",
):
    """The material along a closed profile's edge (`edge`: a
    math.profile.ProfileContour with offset 0, its centre's x, y in the world):
    `wall_thickness` deep into the material (a pocket's plate around it, a
    boss's outer wall; thinner only inside fillets whose centre is in the
    material, ProfileContour.material_band), z_bottom <= z <= z_top, as a
    compliant hydroelastic tetrahedral mesh made and cached as the ring's is
    (tube_mesh.profile_mesh_paths: our structured sweep of the ring's
    cross-section along the profile, stations every 2 pi / `segments_per_turn`
    on the fillets and at most `wall_thickness` apart on the lines),
    frictionless; visuals of the layer and of the wall down to
    `visual_z_bottom`. Call before Finalize. Returns the collision
    GeometryId."""
    _check_positive("hydroelastic_modulus", hydroelastic_modulus)
    points, normals, depths = edge.material_band(
        wall_thickness,
        segments_per_turn=segments_per_turn,
        max_step=wall_thickness,
    )
    volume, surface, body = profile_mesh_paths(
        points,
        normals,
        depths,
        z_bottom,
        z_top,
        n_radial,
        n_z,
        visual_z_bottom=visual_z_bottom,
    )
    props = _compliant_properties(
        wall_thickness, hydroelastic_modulus, hunt_crossley_dissipation
    )
    world = plant.world_body()
    center = edge.center
    X_WG = RigidTransform([float(center[0]), float(center[1]), 0.0])
    geometry_id = plant.RegisterCollisionGeometry(
        world, X_WG, Mesh(str(volume)), name, props
    )
    for path, label, rgba in (
        (surface, "_visual", [0.7, 0.6, 0.4, 1.0]),
        (body, "_body", [0.6, 0.6, 0.65, 1.0]),
    ):
        if path is not None:
            visual = GeometryInstance(X_WG, Mesh(str(path)), name + label)
            visual.set_illustration_properties(
                MakePhongIllustrationProperties(np.array(rgba))
            )
            plant.RegisterVisualGeometry(world, visual)
    return geometry_id


def register_compliant_edge(
    plant,
    stations,
    *,
    width,
    height,
    hydroelastic_modulus,
    hunt_crossley_dissipation,
    closed,
    n_radial=2,
    n_z=2,
    name="part_edge",
):
    """The material along a 3-D edge as a compliant hydroelastic band on
    the world body: at each of the ``stations`` (s (N,), edge points (N, 3),
    n1 (N, 3), tool axis (N, 3), face angle (N,); m, world) the rectangle
    ``width`` (m) into the material along n1 by ``height`` (m) below the
    edge along -axis, swept with the moving frame
    (tube_mesh.edge_band_mesh_path; ``closed`` joins the last station to
    the first), modulus (Pa), Hunt-Crossley dissipation (s/m), frictionless
    as the ring. No visual: the part's own mesh is drawn
    (:func:`register_part_visual`). Call before Finalize. Returns the
    collision GeometryId."""
    if plant.is_finalized():
        raise ValueError(
            "plant must not be finalized yet "
            "(register the edge before Finalize())"
        )
    _check_positive("hydroelastic_modulus", hydroelastic_modulus)
    _check_dissipation(hunt_crossley_dissipation)
    s, points, n1, axis, _ = stations
    path = edge_band_mesh_path(
        points,
        n1,
        axis,
        width,
        height,
        closed=closed,
        n_radial=n_radial,
        n_z=n_z,
    )
    props = _compliant_properties(
        width, hydroelastic_modulus, hunt_crossley_dissipation
    )
    return plant.RegisterCollisionGeometry(
        plant.world_body(), RigidTransform(), Mesh(str(path)), name, props
    )


def register_part_visual(plant, mesh_part, *, name="part_visual"):
    """The part's own mesh (a math.mesh_part.MeshPart: triangles in the
    world, m) as a rigid visual on the world body, written as an OBJ to the
    mesh cache (tube_mesh.mesh_obj_path); illustration only, no collision
    (the tool touches the compliant edge band). Call before Finalize."""
    path = mesh_obj_path(
        mesh_part.mesh.vertices, mesh_part.mesh.faces, name="part"
    )
    visual = GeometryInstance(RigidTransform(), Mesh(str(path)), name)
    visual.set_illustration_properties(
        MakePhongIllustrationProperties(np.array([0.6, 0.6, 0.65, 1.0]))
    )
    plant.RegisterVisualGeometry(plant.world_body(), visual)


def register_tube_visual(
    plant,
    *,
    inner_radius,
    outer_radius,
    z_bottom,
    z_top,
    center_xy=(0.0, 0.0),
    n_theta=240,
    name="tube_body",
):
    """The rest of the tube below the compliant edge ring, for illustration only
    (it never touches the tool). Call before Finalize."""
    surface = ring_surface_path(
        inner_radius, outer_radius, z_bottom, z_top, n_theta
    )
    X_WG = RigidTransform([float(center_xy[0]), float(center_xy[1]), 0.0])
    visual = GeometryInstance(X_WG, Mesh(str(surface)), name)
    visual.set_illustration_properties(
        MakePhongIllustrationProperties(np.array([0.6, 0.6, 0.65, 1.0]))
    )
    plant.RegisterVisualGeometry(plant.world_body(), visual)


def register_cutter(
    plant,
    body,
    *,
    cutter_radius=0.003,
    cutter_length=0.020,
    resolution_hint=4e-4,
    X_BT=None,
):
    """The cylindrical cutter on `body`, tip at the tool frame T (pose X_BT in
    the body; default the body origin), axis T's +z (m): rigid hydroelastic,
    frictionless (the tangential force is the cutting process's),
    with a visual. The default resolution hint gives ceil(2 pi r / hint) = 48
    side facets for r = 3 mm. Call before Finalize. Returns the collision
    GeometryId."""
    _check_positive("cutter_radius", cutter_radius)
    _check_positive("cutter_length", cutter_length)
    X_BG = RigidTransform([0.0, 0.0, cutter_length / 2])
    if X_BT is not None:
        X_BG = X_BT @ X_BG
    shape = Cylinder(cutter_radius, cutter_length)
    props = ProximityProperties()
    AddRigidHydroelasticProperties(resolution_hint, props)
    AddContactMaterial(friction=CoulombFriction(0.0, 0.0), properties=props)
    geometry_id = plant.RegisterCollisionGeometry(
        body, X_BG, shape, "cutter", props
    )
    plant.RegisterVisualGeometry(
        body, X_BG, shape, "cutter_visual", np.array([0.8, 0.8, 0.85, 1.0])
    )
    return geometry_id


def add_tool_robot(
    plant,
    url,
    *,
    cutter_radius=0.003,
    cutter_length=0.020,
    resolution_hint=4e-4,
):
    """Add the robot model at `url` (its body `tool` has its origin at the tool
    tip, weld `ft_sensor` holds it) and register the cutter on `tool`. Returns
    the model instance."""
    (instance,) = make_parser(plant).AddModels(url=url)
    register_cutter(
        plant,
        plant.GetBodyByName("tool", instance),
        cutter_radius=cutter_radius,
        cutter_length=cutter_length,
        resolution_hint=resolution_hint,
    )
    return instance


def add_cartesian_tool(plant, **cutter):
    """Add models/cartesian_tool.sdf (joints x, y, z, weld ft_sensor) and its
    cutter (`add_tool_robot`'s keyword arguments). Returns the model
    instance."""
    return add_tool_robot(plant, POINT_MASS_URL, **cutter)


def contact_force_on_body(results, geometry_id, body_index):
    """Sum of the contact forces (N, world) that ContactResults `results` apply
    ON the body `body_index`, whose collision geometry is `geometry_id`:
    hydroelastic (F_Ac_W acts on the body of the surface's geometry M) and
    fallback point contacts (contact_force() acts on B)."""
    f = np.zeros(3)
    for i in range(results.num_hydroelastic_contacts()):
        info = results.hydroelastic_contact_info(i)
        sign = 1.0 if info.contact_surface().id_M() == geometry_id else -1.0
        f += sign * info.F_Ac_W().translational()
    for i in range(results.num_point_pair_contacts()):
        info = results.point_pair_contact_info(i)
        sign = 1.0 if info.bodyB_index() == body_index else -1.0
        f += sign * info.contact_force()
    return f


class RingContactProbe:
    """A continuous plant with the cartesian tool and a compliant ring, to
    evaluate contact forces statically.

    Contact model hydroelastic_with_fallback, time_step 0. The ring is
    inner_radius <= r <= inner_radius + wall, z_top - layer_height <= z <=
    z_top.
    """

    def __init__(
        self,
        *,
        inner_radius=0.030,
        wall=0.005,
        layer_height=0.006,
        z_top=0.050,
        hydroelastic_modulus,
        hunt_crossley_dissipation=0.0,
        n_theta=240,
        n_radial=2,
        n_z=2,
    ):
        for name, value in (
            ("inner_radius", inner_radius),
            ("wall", wall),
            ("layer_height", layer_height),
        ):
            _check_positive(name, value)
        builder = DiagramBuilder()
        plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
        plant.set_contact_model(ContactModel.kHydroelasticWithFallback)
        self._instance = add_cartesian_tool(plant)
        self.ring_id = register_compliant_ring(
            plant,
            inner_radius=inner_radius,
            outer_radius=inner_radius + wall,
            z_bottom=z_top - layer_height,
            z_top=z_top,
            hydroelastic_modulus=hydroelastic_modulus,
            hunt_crossley_dissipation=hunt_crossley_dissipation,
            n_theta=n_theta,
            n_radial=n_radial,
            n_z=n_z,
        )
        plant.Finalize()
        self.plant = plant
        self.diagram = builder.Build()
        self.context = self.diagram.CreateDefaultContext()
        self.plant_context = plant.GetMyMutableContextFromRoot(self.context)
        self.inner_radius, self.z_top = inner_radius, z_top
        self.cutter_id = plant.GetCollisionGeometriesForBody(
            plant.GetBodyByName("tool", self._instance)
        )[0]

    def set_tip_position(self, p_WT):
        """Place the tool tip at p_WT (m, world frame); joints x, y, z are the
        tip's coordinates."""
        self.plant.SetPositions(
            self.plant_context, self._instance, np.asarray(p_WT, dtype=float)
        )

    def contact_force_on_tool(self, p_WT):
        """Sum of the hydroelastic (and fallback point) contact forces ON the
        tool (N, world frame)."""
        self.set_tip_position(p_WT)
        results = self.plant.get_contact_results_output_port().Eval(
            self.plant_context
        )
        tool = self.plant.GetBodyByName("tool", self._instance).index()
        return contact_force_on_body(results, self.cutter_id, tool)

    def radial_force(
        self, depth, angle=0.0, *, cutter_radius=0.003, engagement=0.002
    ):
        """Radial component magnitude (N) of the contact force on the tool.

        The cutter axis is at rho = inner_radius - cutter_radius + depth,
        azimuth `angle` (rad), tip at z = z_top - engagement: the cutter's side
        presses radially outward into the wall by `depth` (m) and extends above
        the ring's top.
        """
        rho = self.inner_radius - cutter_radius + depth
        e_r = np.array([math.cos(angle), math.sin(angle), 0.0])
        f = self.contact_force_on_tool(
            rho * e_r + np.array([0.0, 0.0, self.z_top - engagement])
        )
        return abs(float(f @ e_r))


def _axis_rotation(axis):
    """The minimal rotation taking +z onto the unit vector ``axis``."""
    a = np.asarray(axis, float)
    v, c = np.cross([0.0, 0.0, 1.0], a), float(a[2])
    if c < -1.0 + 1e-12:
        return RotationMatrix(np.diag([1.0, -1.0, -1.0]))
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return RotationMatrix(np.eye(3) + K + K @ K / (1.0 + c))


class EdgeContactProbe:
    """A continuous plant with a free cutter and the compliant band of
    :func:`register_compliant_edge` along ``stations``, to evaluate the
    contact force statically with the tool held along any axis (contact
    model hydroelastic_with_fallback, time_step 0). Keyword arguments go to
    register_compliant_edge (``closed``, ``width``, ``height``,
    ``hydroelastic_modulus`` required) and, for ``cutter_radius``,
    ``cutter_length`` and ``resolution_hint``, to register_cutter."""

    def __init__(self, stations, **kwargs):
        cutter = {
            k: kwargs.pop(k)
            for k in ("cutter_radius", "cutter_length", "resolution_hint")
            if k in kwargs
        }
        kwargs.setdefault("hunt_crossley_dissipation", 0.0)
        builder = DiagramBuilder()
        plant, _ = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
        plant.set_contact_model(ContactModel.kHydroelasticWithFallback)
        self._tool = plant.AddRigidBody(
            "tool", SpatialInertia.SolidBoxWithMass(0.1, 0.01, 0.01, 0.01)
        )
        self.cutter_id = register_cutter(plant, self._tool, **cutter)
        self.edge_id = register_compliant_edge(plant, stations, **kwargs)
        plant.Finalize()
        self.plant = plant
        self.diagram = builder.Build()
        self.context = self.diagram.CreateDefaultContext()
        self.plant_context = plant.GetMyMutableContextFromRoot(self.context)
        self.cutter_radius = cutter.get("cutter_radius", 0.003)

    def contact_force_on_tool(self, p_WT, axis):
        """Sum of the contact forces ON the tool (N, world), its tip at
        p_WT (m, world) and its axis (from the tip to the holder) along the
        unit vector ``axis``, turned from vertical by the minimal
        rotation."""
        X_WT = RigidTransform(_axis_rotation(axis), np.asarray(p_WT, float))
        self.plant.SetFreeBodyPose(self.plant_context, self._tool, X_WT)
        results = self.plant.get_contact_results_output_port().Eval(
            self.plant_context
        )
        return contact_force_on_body(
            results, self.cutter_id, self._tool.index()
        )

    def normal_force(self, point, n1, axis, depth, *, engagement=0.002):
        """The normal force (N, along -n1 on the tool) with the cutter's
        side ``depth`` (m) into the material past the edge point ``point``
        along ``n1``, its tip ``engagement`` (m) below the edge along
        -``axis``: the planar contours' tool point, z = point - r n1 - e
        axis, moved by depth n1."""
        point, n1, axis = (np.asarray(x, float) for x in (point, n1, axis))
        tip = point + (depth - self.cutter_radius) * n1 - engagement * axis
        return -float(self.contact_force_on_tool(tip, axis) @ n1)


def measure_normal_force(
    depths,
    *,
    inner_radius=0.030,
    wall=0.005,
    layer_height=0.006,
    engagement=0.002,
    hydroelastic_modulus,
    cutter_radius=0.003,
    angle=0.0,
    n_theta=240,
):
    """Normal (radial) contact force (N) on the cartesian tool's cutter for each
    radial depth (m).

    Static evaluation of Drake's hydroelastic contact (continuous plant, contact
    model hydroelastic_with_fallback) between the rigid cutter (radius
    cutter_radius) and the compliant ring of modulus hydroelastic_modulus (Pa);
    the contact part of the paper's eq. (4) at delta_dot = 0. Depth <= -0 gives
    zero force (out of contact).
    """
    _check_positive("engagement", engagement)
    _check_positive("cutter_radius", cutter_radius)
    depths = np.atleast_1d(np.asarray(depths, dtype=float))
    if not np.all(np.isfinite(depths)):
        raise ValueError("depths must be finite")
    probe = RingContactProbe(
        inner_radius=inner_radius,
        wall=wall,
        layer_height=layer_height,
        hydroelastic_modulus=hydroelastic_modulus,
        n_theta=n_theta,
    )
    return np.array(
        [
            probe.radial_force(
                d, angle, cutter_radius=cutter_radius, engagement=engagement
            )
            for d in depths
        ]
    )


def local_stiffness(depths, *, step=2e-5, **kwargs):
    """Local stiffness dF/d(delta) (N/m) at each depth (m), central differences
    of +-step (m).

    kwargs go to measure_normal_force (hydroelastic_modulus is required).
    """
    _check_positive("step", step)
    depths = np.atleast_1d(np.asarray(depths, dtype=float))
    f = measure_normal_force(
        np.concatenate([depths + step, depths - step]), **kwargs
    )
    return (f[: len(depths)] - f[len(depths) :]) / (2.0 * step)


def power_law_exponent(depths, forces):
    """Least-squares exponent n of F = a * delta**n over the given samples (all
    must be > 0)."""
    depths, forces = (
        np.asarray(depths, dtype=float),
        np.asarray(forces, dtype=float),
    )
    if np.any(depths <= 0) or np.any(forces <= 0):
        raise ValueError(
            "depths and forces must all be > 0 for a power-law fit"
        )
    return float(np.polyfit(np.log(depths), np.log(forces), 1)[0])


def calibrate_hydroelastic_modulus(
    *,
    target_stiffness=1.0e4,
    depth=5.0e-4,
    reference_modulus=1.0e7,
    significant_digits=2,
    **kwargs,
):
    """Hydroelastic modulus E (Pa) giving dF/d(delta) = target_stiffness (N/m)
    at `depth` (m).

    Soft-rigid hydroelastic force is linear in E (pressure p = E * e, geometry
    fixed), so one measurement at reference_modulus suffices; E is rounded to
    significant_digits. kwargs go to measure_normal_force.
    """
    _check_positive("target_stiffness", target_stiffness)
    _check_positive("depth", depth)
    k_ref = float(
        local_stiffness(
            [depth], hydroelastic_modulus=reference_modulus, **kwargs
        )[0]
    )
    if not k_ref > 0:
        raise ValueError(
            f"no contact stiffness at depth={depth!r} m: "
            "the tool does not touch the ring there"
        )
    E = reference_modulus * target_stiffness / k_ref
    return float(f"{E:.{significant_digits - 1}e}")


def force_ripple(depth, *, n_samples=25, n_theta=240, **kwargs):
    """Force ripple (max - min) / mean over one mesh segment (2 pi / n_theta
    rad) around the ring at `depth` (m).

    Also returns the forces (N) at the n_samples angles in [0, 2 pi / n_theta].
    kwargs (hydroelastic_modulus required; inner_radius, wall, ...) go to
    RingContactProbe.
    """
    if (
        isinstance(n_samples, bool)
        or not isinstance(n_samples, (int, np.integer))
        or n_samples < 2
    ):
        raise ValueError(
            f"n_samples must be an integer >= 2, got {n_samples!r}"
        )
    cutter = {
        k: kwargs.pop(k) for k in ("cutter_radius", "engagement") if k in kwargs
    }
    probe = RingContactProbe(n_theta=n_theta, **kwargs)
    angles = np.linspace(0.0, 2.0 * math.pi / n_theta, n_samples)
    f = np.array([probe.radial_force(depth, a, **cutter) for a in angles])
    return float((f.max() - f.min()) / f.mean()), f
