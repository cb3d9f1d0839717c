"""One plan of a run: everything the cell derives from a scenario, worked
out once, before anything is built.

Use: ``plan = plan_cell(scenario)``, then
``make_deburring_diagram(plan)`` and
:func:`deburr_drake.runs.simulation.run_pass`. The plan holds the scenario
as it will run (its designed values resolved, the gains designed at the
pose the run starts from), the real and the believed edge, the
controller's robot model (parsed once), the start (joint angles, tool
position and orientation, as the diagram sets them) and, computed when
first asked for, the contact truth. The reach and joint-path checks are
done once, by :func:`plan_cell`; everything built from the plan reads it
and derives nothing again from the raw scenario."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import NamedTuple, Optional

import numpy as np
from pydrake.multibody.plant import MultibodyPlant

from deburr_drake.cell.arm import solve_tool_pose
from deburr_drake.cell.edge import (
    believed_contour,
    believed_contour_step,
    make_contour,
    start_position,
)
from deburr_drake.cell.gains import (
    GainDesign,
    apply_gains,
    design_gains,
    resolve_slope_bound,
)
from deburr_drake.cell.reach import check_part_in_reach
from deburr_drake.cell.robot import check_robot, ik_seed
from deburr_drake.config import Scenario
from deburr_drake.control.mesh_probe import MeshProbePlan
from deburr_drake.math.geometry import Contour
from deburr_drake.math.mesh_registration import MeshSurface

__all__ = ["CellPlan", "Start", "plan_cell"]


class Start(NamedTuple):
    """Where the pass starts."""

    position: np.ndarray  # m, world: the tool tip
    q: np.ndarray  # the plant's positions there
    rotation: np.ndarray  # the tool's orientation there, held on the pass


@dataclass(frozen=True)
class CellPlan:
    """A scenario resolved for a run (see the module docstring).

    ``scenario``: as it will run (``controller.design`` written, the slope
    bound resolved); ``source``: the scenario planned, as given;
    ``design``: the gains designed (``controller.design`` auto) or None;
    ``contour`` / ``belief``: the real edge and the one the controller
    believes in, ``belief_step`` the believed edge after
    ``faults.part_step`` (or None); ``model``: the controller's robot
    model; ``start``: the tool's start, in contact (with touch probing,
    the probe's standoff off the part); ``mesh_probe``: with touch
    probing on a mesh part, its touches on the believed part
    (deburr_drake.cell.touches.plan_mesh_probe), and ``touch_surface``
    the real part's surface the probe touches (else None)."""

    scenario: Scenario
    source: Scenario
    design: Optional[GainDesign]
    contour: Contour
    belief: Contour
    belief_step: Optional[tuple]
    model: MultibodyPlant
    start: Start
    mesh_probe: Optional[MeshProbePlan] = None
    touch_surface: Optional[MeshSurface] = None
    _cache: dict = field(
        default_factory=dict, compare=False, repr=False, hash=False
    )

    def contact_truth(self):
        """The contact model's force law at the desired depth
        (deburr_drake.cell.truth.contact_truth), computed on first use and
        kept."""
        if "truth" not in self._cache:
            from deburr_drake.cell.truth import contact_truth

            self._cache["truth"] = contact_truth(self.scenario)
        return self._cache["truth"]

    def with_design(self, design: GainDesign) -> "CellPlan":
        """The plan with ``design``'s gains written into its source (and
        the slope bound resolved from them); the edges, the model and the
        start are this plan's."""
        scenario = apply_gains(self.source, design)
        return self.varied(
            resolve_slope_bound(scenario, self.start.q, model=self.model),
            design=design,
        )

    def varied(self, scenario: Scenario, **changes) -> "CellPlan":
        """The plan of ``scenario``, a variant of this plan's scenario in
        what does not move the part, the robot or the start (gains,
        adaptation, noise, guards, the integrator: what the analyses
        vary), resolved already; the edges, the model and the start are
        this plan's."""
        return dataclasses.replace(
            self, scenario=scenario.validate(), _cache={}, **changes
        )


def _start_position(scenario: Scenario, belief: Contour) -> np.ndarray:
    """The tool at the believed contour's start, in contact; with touch
    probing the probe's standoff off the part before it."""
    x0 = start_position(scenario, belief)
    if scenario.localisation.probe.enabled:
        x0 = x0 - (
            scenario.simulation.initial_depth
            + scenario.localisation.probe.standoff
        ) * belief.n1(x0)
    return x0


def _start(
    scenario: Scenario, model: MultibodyPlant, belief, q_spun=None
) -> Start:
    """The start: :func:`_start_position`, the arm posed there by inverse
    kinematics with the tool vertical (along a 3-D edge, along its axis
    there), nearest the seed, or nearest ``q_spun`` (the posture with the
    tool spun about its axis that the reach check found the arm follows
    the edge from)."""
    robot = scenario.robot
    x0 = _start_position(scenario, belief)
    if robot.model == "cartesian_tool":
        # World-aligned prismatic joints, tip at the origin for q = 0.
        q0 = np.asarray(x0, float)
    else:
        axis = (
            belief.tool_axis_at(belief.arc_position(x0))
            if belief.varying_frame
            else None
        )
        frame = model.GetFrameByName(robot.tool_frame)
        q0 = solve_tool_pose(
            model,
            x0,
            instance=frame.model_instance(),
            q_guess=ik_seed(robot, x0) if q_spun is None else q_spun,
            tool_frame=robot.tool_frame,
            tool_axis=axis,
        )
    context = model.CreateDefaultContext()
    model.SetPositions(context, q0)
    # The tool's axis; on a 6-DOF arm also its rotation about it.
    rotation = (
        model.GetFrameByName(robot.tool_frame)
        .CalcPoseInWorld(context)
        .rotation()
        .matrix()
    )
    return Start(x0, q0, rotation)


def plan_cell(scenario: Scenario) -> CellPlan:
    """The plan of ``scenario`` (left as it is): validated, the robot
    checked against the part (reach, joint path), the edges and the start
    worked out, the gains designed at the start where
    ``controller.design`` resolves to auto, the fuzzy slope bound
    resolved at the start too."""
    scenario.validate()
    # The controller's model of the robot, checked against the cell.
    model = check_robot(scenario.robot)
    q_spun = check_part_in_reach(scenario, model=model)
    # Neither the edges, the model nor the start depend on the gains.
    contour, belief = make_contour(scenario), believed_contour(scenario)
    start = _start(scenario, model, belief, q_spun)
    # A mesh part's touches, planned on the believed part.
    mesh_probe = touch_surface = None
    if (
        scenario.localisation.probe.enabled
        and scenario.part.edge.kind == "mesh"
    ):
        from deburr_drake.cell.touches import plan_mesh_probe, real_surface

        mesh_probe = plan_mesh_probe(scenario, start.position)
        touch_surface = real_surface(scenario)
    design = None
    resolved = scenario
    c = scenario.controller
    if c.resolved_design(scenario.robot) == "auto":
        design = design_gains(scenario, start.q, model=model)
        resolved = apply_gains(scenario, design)
    return CellPlan(
        scenario=resolve_slope_bound(resolved, start.q, model=model),
        source=scenario,
        design=design,
        contour=contour,
        belief=belief,
        belief_step=believed_contour_step(scenario),
        model=model,
        start=start,
        mesh_probe=mesh_probe,
        touch_surface=touch_surface,
    )
