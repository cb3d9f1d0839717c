"""The cell's MultibodyPlant: the robot with its cutter and joint
friction, and the compliant hydroelastic part its edge belongs to."""

from __future__ import annotations

import math

from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.systems.framework import DiagramBuilder

from deburr_drake.cell.edge import make_contour, straight_frame
from deburr_drake.cell.friction import add_joint_friction
from deburr_drake.cell.part import (
    register_compliant_edge,
    register_compliant_profile,
    register_compliant_ring,
    register_compliant_wall,
    register_part_visual,
    register_tube_visual,
)
from deburr_drake.cell.robot import add_robot, finalize
from deburr_drake.cell.tube_mesh import band_width_limit, sag_spacing
from deburr_drake.config import Scenario

__all__ = ["add_cell_plant", "mesh_edge_band"]


def add_cell_plant(builder: DiagramBuilder, scenario: Scenario, *, edges=None):
    """(plant, scene_graph), finalized: the robot (``robot``), its
    friction, and the part (``part``); ``edges`` (single-edge scenarios
    of one CAD part, a job's cuts): a band along each of them instead."""
    sim = scenario.simulation
    config = MultibodyPlantConfig(
        time_step=sim.plant_time_step,
        contact_model="hydroelastic_with_fallback",
    )
    if sim.plant_time_step > 0:
        config.discrete_contact_approximation = sim.contact_approximation
    plant, scene_graph = AddMultibodyPlant(config, builder)
    add_robot(
        plant,
        scenario.robot,
        cutter=dict(
            cutter_radius=scenario.tool.cutter_radius,
            cutter_length=scenario.tool.cutter_length,
            resolution_hint=scenario.tool.resolution_hint,
        ),
    )
    add_joint_friction(plant, scenario.robot)
    kind = scenario.part.edge.kind
    if edges is not None:
        _add_mesh_edges(plant, edges)
    elif kind == "straight":
        _add_wall(plant, scenario)
    elif kind == "profile":
        _add_profile(plant, scenario)
    elif kind == "mesh":
        _add_mesh_edge(plant, scenario)
    else:
        _add_ring(plant, scenario)
    finalize(plant)
    return plant, scene_graph


def _add_wall(plant, scenario: Scenario):
    """A straight edge: a compliant wall as long as the edge."""
    part = scenario.part
    mid, tangent, normal = straight_frame(scenario)
    register_compliant_wall(
        plant,
        mid=mid,
        tangent=tangent,
        normal=normal,
        length=part.edge.length,
        thickness=part.edge.wall_thickness,
        height=part.edge.height,
        layer_height=part.band.height,
        hydroelastic_modulus=part.material.hydroelastic_modulus,
        hunt_crossley_dissipation=part.material.hunt_crossley_dissipation,
        # The wall is the edge: the process cuts only where it is
        # (process.material_overlap), and off its ends there is no
        # contact either.
        margin=0.0,
    )


def _add_profile(plant, scenario: Scenario):
    """A profiled edge: a compliant layer along the contour."""
    part = scenario.part
    band, material = part.band, part.material
    z_top = part.pose.xyz[2] + part.edge.height
    register_compliant_profile(
        plant,
        make_contour(scenario).with_offset(0.0),
        wall_thickness=part.edge.wall_thickness,
        z_bottom=z_top - band.height,
        z_top=z_top,
        hydroelastic_modulus=material.hydroelastic_modulus,
        hunt_crossley_dissipation=material.hunt_crossley_dissipation,
        segments_per_turn=band.mesh_segments,
        n_radial=band.mesh_radial_cells,
        n_z=band.mesh_height_cells,
        visual_z_bottom=part.pose.xyz[2],
    )


def _add_ring(plant, scenario: Scenario):
    """The tube's inner edge: a compliant ring on a rigid tube's visual."""
    part = scenario.part
    edge, band, material = part.edge, part.band, part.material
    z_top = part.pose.xyz[2] + edge.height
    register_compliant_ring(
        plant,
        inner_radius=edge.inner_radius,
        outer_radius=edge.inner_radius + edge.wall_thickness,
        z_bottom=z_top - band.height,
        z_top=z_top,
        center_xy=part.pose.xyz[:2],
        hydroelastic_modulus=material.hydroelastic_modulus,
        hunt_crossley_dissipation=material.hunt_crossley_dissipation,
        n_theta=band.mesh_segments,
        n_radial=band.mesh_radial_cells,
        n_z=band.mesh_height_cells,
    )
    register_tube_visual(
        plant,
        inner_radius=edge.inner_radius,
        outer_radius=edge.inner_radius + edge.wall_thickness,
        z_bottom=part.pose.xyz[2],
        z_top=z_top - band.height,
        center_xy=part.pose.xyz[:2],
        n_theta=band.mesh_segments,
    )


# m: the first sampling of a mesh edge, to find where it curves most
_CURVATURE_SPACING = 2.5e-4
# m: a mesh edge's stations are no coarser than a ring of this radius in
# part.band.mesh_segments would have (the default tube's), so a band's
# resolution reads the same for every kind
_RING_RADIUS = 0.030
# -, of the widest band that does not fold: its far side keeps at least
# half the near side's station spacing
_BAND_FIT = 0.5


def mesh_edge_band(scenario: Scenario):
    """(stations, keyword arguments of register_compliant_edge but the
    stations) of the compliant band along a CAD part's edge:
    ``part.edge.band_width`` wide where it fits, ``part.band.height``
    high, stations no coarser than a ring's of ``_RING_RADIUS`` would be
    and, where the edge curves more, close enough for the ring's sag."""
    part = scenario.part
    band, material = part.band, part.material
    contour = make_contour(scenario)
    ring_spacing = 2.0 * math.pi * _RING_RADIUS / band.mesh_segments
    ring_sag = _RING_RADIUS * (1.0 - math.cos(math.pi / band.mesh_segments))
    fine = contour.stations(_CURVATURE_SPACING)
    spacing = min(
        ring_spacing,
        sag_spacing(fine.points, closed=contour.closed, sag=ring_sag),
    )
    stations = contour.stations(spacing)
    height = band.height
    fits = band_width_limit(
        stations.points,
        stations.n1,
        stations.axis,
        height,
        closed=contour.closed,
    )
    return stations, dict(
        width=min(part.edge.band_width, _BAND_FIT * fits),
        height=height,
        hydroelastic_modulus=material.hydroelastic_modulus,
        hunt_crossley_dissipation=material.hunt_crossley_dissipation,
        closed=contour.closed,
        n_radial=band.mesh_radial_cells,
        n_z=band.mesh_height_cells,
    )


def _add_mesh_edges(plant, edges):
    """A job's CAD part: the compliant band of ``mesh_edge_band`` along
    each edge cut (``part_edge_<k>``); the part's mesh drawn once."""
    for k, scenario in enumerate(edges):
        stations, band = mesh_edge_band(scenario)
        register_compliant_edge(plant, stations, name=f"part_edge_{k}", **band)
    part = edges[0].part  # the real part: moved by part_error
    register_part_visual(
        plant, part.mesh_edge(part.real_pose(edges[0].part_error))[0]
    )


def _add_mesh_edge(plant, scenario: Scenario):
    """A CAD part's edge: the compliant band of ``mesh_edge_band`` along
    it; the part's mesh drawn."""
    stations, band = mesh_edge_band(scenario)
    register_compliant_edge(plant, stations, **band)
    part = scenario.part  # the real part: moved by part_error
    register_part_visual(
        plant, part.mesh_edge(part.real_pose(scenario.part_error))[0]
    )
