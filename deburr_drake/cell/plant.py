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


def add_cell_plant(builder: DiagramBuilder, scenario: Scenario):
    """(plant, scene_graph), finalized: the robot (``robot``), its
    friction, and the part (``tube``, ``edge``)."""
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
    if scenario.edge.kind == "straight":
        _add_wall(plant, scenario)
    elif scenario.edge.kind == "profile":
        _add_profile(plant, scenario)
    elif scenario.edge.kind == "mesh":
        _add_mesh_edge(plant, scenario)
    else:
        _add_ring(plant, scenario)
    finalize(plant)
    return plant, scene_graph


def _add_wall(plant, scenario: Scenario):
    """A straight edge: a compliant wall as long as the edge."""
    tube = scenario.tube
    mid, tangent, normal = straight_frame(scenario)
    register_compliant_wall(
        plant,
        mid=mid,
        tangent=tangent,
        normal=normal,
        length=scenario.edge.length,
        thickness=tube.wall_thickness,
        height=tube.height,
        layer_height=tube.compliant_layer_height,
        hydroelastic_modulus=tube.hydroelastic_modulus,
        hunt_crossley_dissipation=tube.hunt_crossley_dissipation,
        # The wall is the edge: the process cuts only where it is
        # (process.material_overlap), and off its ends there is no
        # contact either.
        margin=0.0,
    )


def _add_profile(plant, scenario: Scenario):
    """A profiled edge: a compliant layer along the contour."""
    tube = scenario.tube
    z_top = tube.position[2] + tube.height
    register_compliant_profile(
        plant,
        make_contour(scenario).with_offset(0.0),
        wall_thickness=tube.wall_thickness,
        z_bottom=z_top - tube.compliant_layer_height,
        z_top=z_top,
        hydroelastic_modulus=tube.hydroelastic_modulus,
        hunt_crossley_dissipation=tube.hunt_crossley_dissipation,
        segments_per_turn=tube.mesh_segments,
        n_radial=tube.mesh_radial_cells,
        n_z=tube.mesh_height_cells,
        visual_z_bottom=tube.position[2],
    )


def _add_ring(plant, scenario: Scenario):
    """The tube's inner edge: a compliant ring on a rigid tube's visual."""
    tube = scenario.tube
    z_top = tube.position[2] + tube.height
    register_compliant_ring(
        plant,
        inner_radius=tube.inner_radius,
        outer_radius=tube.inner_radius + tube.wall_thickness,
        z_bottom=z_top - tube.compliant_layer_height,
        z_top=z_top,
        center_xy=tube.position[:2],
        hydroelastic_modulus=tube.hydroelastic_modulus,
        hunt_crossley_dissipation=tube.hunt_crossley_dissipation,
        n_theta=tube.mesh_segments,
        n_radial=tube.mesh_radial_cells,
        n_z=tube.mesh_height_cells,
    )
    register_tube_visual(
        plant,
        inner_radius=tube.inner_radius,
        outer_radius=tube.inner_radius + tube.wall_thickness,
        z_bottom=tube.position[2],
        z_top=z_top - tube.compliant_layer_height,
        center_xy=tube.position[:2],
        n_theta=tube.mesh_segments,
    )


# m: the first sampling of a mesh edge, to find where it curves most
_CURVATURE_SPACING = 2.5e-4
# -, of the widest band that does not fold: its far side keeps at least
# half the near side's station spacing
_BAND_FIT = 0.5


def mesh_edge_band(scenario: Scenario):
    """(stations, keyword arguments of register_compliant_edge but the
    stations) of the compliant band along a CAD part's edge: the tube's
    wall thickness wide where it fits, its compliant layer high, stations
    no coarser than the tube's ring would be and, where the edge curves
    more, close enough for the ring's sag."""
    tube = scenario.tube
    contour = make_contour(scenario)
    ring_spacing = 2.0 * math.pi * tube.inner_radius / tube.mesh_segments
    ring_sag = tube.inner_radius * (
        1.0 - math.cos(math.pi / tube.mesh_segments)
    )
    fine = contour.stations(_CURVATURE_SPACING)
    spacing = min(
        ring_spacing,
        sag_spacing(fine.points, closed=contour.closed, sag=ring_sag),
    )
    stations = contour.stations(spacing)
    height = tube.compliant_layer_height
    fits = band_width_limit(
        stations.points,
        stations.n1,
        stations.axis,
        height,
        closed=contour.closed,
    )
    return stations, dict(
        width=min(tube.wall_thickness, _BAND_FIT * fits),
        height=height,
        hydroelastic_modulus=tube.hydroelastic_modulus,
        hunt_crossley_dissipation=tube.hunt_crossley_dissipation,
        closed=contour.closed,
        n_radial=tube.mesh_radial_cells,
        n_z=tube.mesh_height_cells,
    )


def _add_mesh_edge(plant, scenario: Scenario):
    """A CAD part's edge: the compliant band of ``mesh_edge_band`` along
    it; the part's mesh drawn."""
    stations, band = mesh_edge_band(scenario)
    register_compliant_edge(plant, stations, **band)
    register_part_visual(plant, scenario.edge.mesh_edge()[0])
