"""The 5-DOF deburring arm (models/arm5.sdf), and the tool-vertical inverse
kinematics of any arm.

The arm is the paper's class of robot (an industrial arm with a spindle and a
wrist force/torque sensor, Section IV); its dynamics (1) are the
MultibodyPlant's, with the motors' reflected inertia (drake:rotor_inertia,
drake:gear_ratio) and viscous joint damping from the SDF. The
task coordinates are the tool tip's position (frame `tool_tip`, the origin of
body `tool`); the tool axis is kept vertical (tool +z = world +z), which fixes
the wrist pitch; wrist_roll turns about the tool axis and does not move the tip.

`solve_tool_pose`, `closest_tool_position` and `check_reach` work on any arm of
n >= 5 joints (deburr_drake.cell.robot loads other models): the tool axis
vertical, the rest of the posture (for n = 6 the tool's rotation about its axis)
the one nearest the initial guess among the postures away from a singular
configuration (:data:`MIN_CONDITIONING`): at a singular posture (a UR's wrist
with two axes in line) the task-space numbers the gains are designed from
(J's pseudo-inverse, the task mass) and the controller's J^T law lose a
direction.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Optional

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.inverse_kinematics import InverseKinematics
from pydrake.solvers import SnoptSolver, Solve, SolverOptions

from deburr_drake.cell.counts import IK_SOLVES, count
from deburr_drake.cell.part import add_tool_robot

__all__ = [
    "ARM_URL",
    "ARM_MODEL_NAME",
    "ARM_JOINTS",
    "DEFAULT_PART_POSITION",
    "Q_READY",
    "add_arm",
    "solve_tool_pose",
    "default_q_guess",
    "closest_tool_position",
    "check_reach",
    "tool_conditioning",
    "path_conditioning",
    "SingularPose",
    "MIN_CONDITIONING",
]

ARM_URL = "package://deburr_drake_models/arm5.sdf"
ARM_MODEL_NAME = "arm5"
ARM_JOINTS = ("waist", "shoulder", "elbow", "wrist_pitch", "wrist_roll")

# Where the tube's axis stands (m, world; the tube's bottom at z = 0). Chosen by
# IK around circles of radius 17..57 mm at z = 0.048 m (tests/cell/test_arm.py):
# the wrist centre is then 0.34..0.46 m from the shoulder (links 0.30 + 0.30 m),
# elbow up, every joint at least 0.78 rad from its limits (the largest margin of
# x = 0.30..0.50 m), static gravity torques at most 21 % of the effort limits
# (shoulder, about 31 N m).
DEFAULT_PART_POSITION = [0.40, 0.0, 0.0]

# Elbow-up pose with the tool vertical, tip at (0.40, 0, 0.048) m (rad, order
# ARM_JOINTS).
Q_READY = np.array([0.0, 0.8393, 0.1015, -0.9408, 0.0])

_AXIS_POINT = (
    0.10  # m, second point on the tool axis used for the verticality constraint
)

#: The least sigma_min / sigma_max of the tool frame's spatial velocity
#: Jacobian (rad and m rows) a posture the IK gives may have. The arms the
#: cell runs have 0.08-0.19 along their edges (a Z1, the smallest, 0.08); a
#: UR wrist at 5 deg from two axes in line has about 0.01, and there the
#: gravity error the design maps to the tool grows as 1 / sigma_min.
MIN_CONDITIONING = 0.02

#: Starts (seeded, within the joint limits) tried when the posture nearest
#: the guess is singular.
_NONSINGULAR_STARTS = 24


class SingularPose(RuntimeError):
    """The tool tip reaches ``point`` (m) with the tool vertical only in
    postures whose conditioning (:func:`tool_conditioning`) is below
    :data:`MIN_CONDITIONING`; ``conditioning`` is the best one found."""

    def __init__(self, message, point, conditioning):
        super().__init__(message)
        self.point = np.asarray(point, float)
        self.conditioning = float(conditioning)
        self.index = None  # the path point's index (check_reach)


def add_arm(plant, **cutter):
    """Add models/arm5.sdf (welded to the world at the origin; body `tool` with
    origin at the tool tip, weld `ft_sensor` flange -> tool) and its cutter
    (part.add_tool_robot's keyword arguments). The plant must be registered with
    a SceneGraph (the cutter is geometry); for a geometry-free model of the arm
    use models.make_kinematic_model(ARM_URL). Call before Finalize. Returns the
    model instance."""
    return add_tool_robot(plant, ARM_URL, **cutter)


def default_q_guess(p_W_tip):
    """Elbow-up initial guess (rad) for a tip target p_W_tip (m): Q_READY turned
    by the waist towards the target."""
    p = np.asarray(p_W_tip, dtype=float)
    q = Q_READY.copy()
    if math.hypot(p[0], p[1]) > 1e-9:
        q[0] = math.atan2(p[1], p[0])
    return q


def _arm_instance(plant, instance):
    if instance is not None:
        return instance
    if not plant.HasModelInstanceNamed(ARM_MODEL_NAME):
        raise ValueError(
            f"plant has no model instance named {ARM_MODEL_NAME!r}: "
            "pass instance="
        )
    return plant.GetModelInstanceByName(ARM_MODEL_NAME)


def _joint_indices(plant, instance, span):
    """Sorted indices of the instance's joints in the plant's q or v:
    ``span(joint)`` is (start, count) in that vector."""
    starts = []
    for index in plant.GetJointIndices(instance):
        start, count = span(plant.get_joint(index))
        starts.extend(range(start, start + count))
    return np.array(sorted(starts), dtype=int)


def _arm_positions(plant, instance):
    """Indices into the plant's q of the instance's joint positions, in joint
    position order."""
    return _joint_indices(
        plant, instance, lambda j: (j.position_start(), j.num_positions())
    )


def _default_guess(plant, instance, arm_idx, p):
    if plant.GetModelInstanceName(instance) == ARM_MODEL_NAME:
        return default_q_guess(p)
    return plant.GetDefaultPositions()[arm_idx]


def _arm_velocities(plant, instance):
    """Indices into the plant's v of the instance's joint velocities."""
    return _joint_indices(
        plant, instance, lambda j: (j.velocity_start(), j.num_velocities())
    )


def tip_jacobian(plant, tip, q_full):
    """Frame ``tip``'s spatial velocity Jacobian (world, 6 x n: the
    columns of its model instance's joints) at the plant's positions
    q_full."""
    from pydrake.multibody.tree import JacobianWrtVariable

    context = plant.CreateDefaultContext()
    plant.SetPositions(context, q_full)
    J = plant.CalcJacobianSpatialVelocity(
        context,
        JacobianWrtVariable.kV,
        tip,
        np.zeros(3),
        plant.world_frame(),
        plant.world_frame(),
    )
    return J[:, _arm_velocities(plant, tip.model_instance())]


def _conditioning(plant, tip, q_full):
    """sigma_min / sigma_max of :func:`tip_jacobian` at q_full."""
    sv = np.linalg.svd(tip_jacobian(plant, tip, q_full), compute_uv=False)
    return float(sv[-1] / sv[0])


def tool_conditioning(plant, q, *, instance=None, tool_frame="tool_tip"):
    """How far the arm's joint angles q (rad, the instance's joints) are
    from a singular configuration: sigma_min / sigma_max of the tool
    frame's spatial velocity Jacobian (0 at a singularity; compare with
    :data:`MIN_CONDITIONING`). Other models at the plant's defaults."""
    instance = _arm_instance(plant, instance)
    q_full = plant.GetDefaultPositions().copy()
    q_full[_arm_positions(plant, instance)] = q
    return _conditioning(
        plant, plant.GetFrameByName(tool_frame, instance), q_full
    )


def path_conditioning(
    plant, points, q_start, *, instance=None, tool_frame="tool_tip"
):
    """The conditioning (:func:`tool_conditioning`) at each point (m,
    world, rows) of a path the arm follows from joint angles q_start
    (rad, the first point's posture): each posture solved from the
    previous one, singular or not, as the controller moves the arm
    through them."""
    q, out = np.asarray(q_start, float), []
    for p in np.asarray(points, dtype=float):
        # SNOPT can report failure when started at its own optimum (the
        # first edge point is often the start): then from 1 mrad off it.
        for nudge in (0.0, 1e-3):
            try:
                q = solve_tool_pose(
                    plant,
                    p,
                    q_guess=q + nudge,
                    instance=instance,
                    tool_frame=tool_frame,
                    min_conditioning=0.0,
                )
                break
            except RuntimeError:
                if nudge:
                    raise
        out.append(
            tool_conditioning(
                plant, q, instance=instance, tool_frame=tool_frame
            )
        )
    return np.array(out)


def solve_tool_pose(
    plant,
    p_W_tip,
    *,
    q_guess=None,
    instance=None,
    tolerance=1e-7,
    tool_frame="tool_tip",
    min_conditioning=MIN_CONDITIONING,
    tool_axis=None,
):
    """Arm joint angles q (n,) (rad, the instance's joints in position order;
    arm5: ARM_JOINTS) with the tool tip at p_W_tip (m, world) and the tool axis
    vertical (tool +z = world +z; along the unit vector ``tool_axis``, world,
    when given), within the joint limits.

    Drake InverseKinematics (SNOPT) on the finalized `plant`, which may hold
    other models: their positions stay at the plant's defaults. Constraints:
    frame `tool_frame` at p_W_tip; the axis point 0.1 m up the tool axis lies
    on the line through the tip along the axis, on its positive side. Cost:
    |q - q_guess|^2 (fixes what the constraints leave free: arm5's wrist_roll,
    a 6-DOF arm's rotation about the tool axis). q_guess defaults to
    default_q_guess(p_W_tip) (elbow up) on arm5 and to the plant's default
    positions on other arms. Raises RuntimeError
    naming the target if the solver fails or the result misses the target by
    more than `tolerance` (m; axis tilt times 0.1 m).

    A posture whose conditioning (:func:`tool_conditioning`) is below
    ``min_conditioning`` is solved again from seeded starts within the
    joint limits, and the posture nearest q_guess among those above it
    returned; SingularPose if none is.
    """
    if not plant.is_finalized():
        raise ValueError("plant must be finalized")
    p = np.asarray(p_W_tip, dtype=float).reshape(-1)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(
            f"p_W_tip must be 3 finite numbers (m), got {p_W_tip!r}"
        )
    instance = _arm_instance(plant, instance)
    arm_idx = _arm_positions(plant, instance)
    n = len(arm_idx)
    if q_guess is None:
        q_guess = _default_guess(plant, instance, arm_idx, p)
    q_guess = np.asarray(q_guess, dtype=float).reshape(-1)
    if q_guess.shape != (n,) or not np.all(np.isfinite(q_guess)):
        raise ValueError(
            f"q_guess must be {n} finite joint angles (rad), got {q_guess!r}"
        )

    tip = plant.GetFrameByName(tool_frame, instance)
    target = _ToolTarget(p, _unit_axis(tool_axis))
    q_sol = _solve_pose(plant, tip, target, arm_idx, q_guess, tolerance)
    conditioning = _conditioning(plant, tip, q_sol)
    if conditioning >= min_conditioning:
        return q_sol[arm_idx]
    return _nonsingular_pose(
        plant,
        tip,
        target,
        arm_idx,
        q_guess,
        tolerance,
        min_conditioning,
        conditioning,
    )[arm_idx]


def _nonsingular_pose(
    plant, tip, target, arm_idx, q_guess, tolerance, min_conditioning, found
):
    """The posture nearest ``q_guess`` with the tool tip at ``p`` whose
    conditioning is at least ``min_conditioning``, solved from the guess
    with one joint turned a quarter turn either way (a wrist turned off its
    singular line), then from starts anywhere; SingularPose (with the best
    conditioning found, at least ``found``) if none is."""
    n = len(arm_idx)
    best, conditioning = None, found
    turned = [
        q_guess + sign * 0.5 * np.pi * np.eye(n)[j]
        for j in range(n)
        for sign in (1.0, -1.0)
    ]
    for start in turned + _starts(plant, arm_idx, _NONSINGULAR_STARTS):
        try:
            q_other = _solve_pose(plant, tip, target, arm_idx, start, tolerance)
        except RuntimeError:
            continue
        c = _conditioning(plant, tip, q_other)
        conditioning = max(conditioning, c)
        if c < min_conditioning:
            continue
        d = np.linalg.norm(q_other[arm_idx] - q_guess)
        if best is None or d < best[0]:
            best = (d, q_other)
    if best is None:
        p = target.p
        raise SingularPose(
            f"tool pose IK for tool tip target p_W_tip={p.tolist()} m "
            "finds only postures near a singular configuration "
            f"(conditioning {conditioning:.2g} < {min_conditioning:g})",
            p,
            conditioning,
        )
    return best[1]


def _starts(plant, arm_idx, count):
    """``count`` joint angle vectors (rad) drawn (seeded) within the joint
    limits (at most +-pi)."""
    lower = np.maximum(plant.GetPositionLowerLimits()[arm_idx], -np.pi)
    upper = np.minimum(plant.GetPositionUpperLimits()[arm_idx], np.pi)
    rng = np.random.default_rng(0)
    return [rng.uniform(lower, upper) for _ in range(count)]


class _ToolTarget(NamedTuple):
    """Where the tool goes: the tip at ``p`` (m, world), its +z along
    ``axis`` (unit, world; None: vertical)."""

    p: np.ndarray
    axis: Optional[np.ndarray] = None


def _unit_axis(tool_axis):
    """``tool_axis`` as a unit vector (None stays None: vertical)."""
    if tool_axis is None:
        return None
    a = np.asarray(tool_axis, dtype=float).reshape(-1)
    norm = np.linalg.norm(a) if a.shape == (3,) else 0.0
    if not (np.all(np.isfinite(a)) and norm > 1e-9):
        raise ValueError(
            f"tool_axis must be 3 finite numbers, not all 0, got {tool_axis!r}"
        )
    return a / norm


def _solve_pose(
    plant, tip, target, arm_idx, q_guess, tolerance, with_joint_limits=True
):
    """All the plant's positions with the tool tip and axis at ``target``
    (a _ToolTarget), nearest q_guess (RuntimeError if not found)."""
    p = target.p
    prog, q, q_full_guess = _tool_pose_program(
        plant, tip, target, arm_idx, q_guess, with_joint_limits
    )
    options = SolverOptions()
    snopt = SnoptSolver().solver_id()
    options.SetOption(snopt, "Major feasibility tolerance", 1e-10)
    options.SetOption(snopt, "Major optimality tolerance", 1e-10)
    count(IK_SOLVES)
    result = Solve(prog, q_full_guess, options)
    q_sol = result.GetSolution(q)
    if not result.is_success():
        raise RuntimeError(
            f"tool pose IK failed for tool tip target p_W_tip={p.tolist()} m "
            f"({result.get_solution_result()})"
        )
    _check_tool_pose(plant, tip, q_sol, target, tolerance)
    return q_sol


def _tool_pose_program(
    plant, tip, target, arm_idx, q_guess, with_joint_limits=True
):
    """(program, q, initial guess of all positions): the tool tip and axis
    at ``target``, the other models' positions at the plant's defaults, the
    cost |q_arm - q_guess|^2."""
    p = target.p
    world = plant.world_frame()
    ik = InverseKinematics(plant, with_joint_limits=with_joint_limits)
    q = ik.q()
    prog = ik.get_mutable_prog()
    ik.AddPositionConstraint(tip, np.zeros(3), world, p, p)
    up = np.array([0.0, 0.0, _AXIS_POINT])
    inf = np.inf
    if target.axis is None:
        ik.AddPositionConstraint(
            tip,
            up,
            world,
            np.array([p[0], p[1], p[2] + 0.5 * _AXIS_POINT]),
            np.array([p[0], p[1], inf]),
        )
    else:
        # The same box in a frame at the tip whose z is the axis.
        X_WA = RigidTransform(
            RotationMatrix.MakeFromOneVector(target.axis, 2), p
        )
        ik.AddPositionConstraint(
            tip,
            up,
            world,
            X_WA,
            np.array([0.0, 0.0, 0.5 * _AXIS_POINT]),
            np.array([0.0, 0.0, inf]),
        )

    q0 = plant.GetDefaultPositions()
    q_full_guess = q0.copy()
    q_full_guess[arm_idx] = q_guess
    arm_mask = np.zeros(plant.num_positions(), dtype=bool)
    arm_mask[arm_idx] = True
    others = np.flatnonzero(~arm_mask)
    if others.size:
        prog.AddBoundingBoxConstraint(q0[others], q0[others], q[others])
    prog.AddQuadraticErrorCost(np.eye(len(arm_idx)), q_guess, q[arm_idx])
    return prog, q, q_full_guess


def _check_tool_pose(plant, tip, q_sol, target, tolerance):
    """RuntimeError when the positions q_sol miss the tip target or tilt
    the tool axis off the target's by more than ``tolerance`` (m; tilt
    times 0.1 m)."""
    p = target.p
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, q_sol)
    X_WT = tip.CalcPoseInWorld(context)
    pos_err = np.linalg.norm(X_WT.translation() - p)
    z = X_WT.rotation().matrix()[:, 2]
    a = np.array([0.0, 0.0, 1.0]) if target.axis is None else target.axis
    axis_err = _AXIS_POINT * math.atan2(np.linalg.norm(np.cross(z, a)), z @ a)
    if pos_err > tolerance or axis_err > tolerance:
        raise RuntimeError(
            f"tool pose IK missed tool tip target p_W_tip={p.tolist()} m: "
            f"position error {pos_err:.3g} m, "
            f"axis error {axis_err / _AXIS_POINT:.3g} rad"
        )


def closest_tool_position(
    plant,
    p_W_tip,
    *,
    instance=None,
    q_guess=None,
    tool_frame="tool_tip",
    return_positions=False,
    tool_axis=None,
):
    """The tool tip position (m, world) nearest to p_W_tip that the arm reaches
    with the tool axis vertical (along ``tool_axis`` when given) within its
    joint limits: how far out of reach a target is. With ``return_positions``
    also the arm's joint angles there (rad)."""
    axis = _unit_axis(tool_axis)
    p = np.asarray(p_W_tip, dtype=float).reshape(3)
    instance = _arm_instance(plant, instance)
    tip = plant.GetFrameByName(tool_frame, instance)
    world = plant.world_frame()
    ik = InverseKinematics(plant, with_joint_limits=True)
    q = ik.q()
    ik.AddPositionCost(world, p, tip, np.zeros(3), np.eye(3))
    # The tool axis as solve_tool_pose keeps it.
    ik.AddAngleBetweenVectorsConstraint(
        tip,
        np.array([0.0, 0.0, 1.0]),
        world,
        np.array([0.0, 0.0, 1.0]) if axis is None else axis,
        0.0,
        1e-6,
    )
    arm_idx = _arm_positions(plant, instance)
    q_full_guess = plant.GetDefaultPositions().copy()
    q_full_guess[arm_idx] = (
        _default_guess(plant, instance, arm_idx, p)
        if q_guess is None
        else q_guess
    )
    count(IK_SOLVES)
    result = Solve(ik.get_mutable_prog(), q_full_guess)
    context = plant.CreateDefaultContext()
    q_sol = result.GetSolution(q)
    plant.SetPositions(context, q_sol)
    reached = tip.CalcPoseInWorld(context).translation()
    return (reached, q_sol[arm_idx]) if return_positions else reached


def _closest_of_many(
    plant, p, instance, guess, tool_frame, starts=8, tool_axis=None
):
    """closest_tool_position from the guess, the model's default posture and
    ``starts`` postures drawn (seeded) within the joint limits: the nearest
    of them (one local solve can stop far from the nearest reachable
    position)."""
    instance = _arm_instance(plant, instance)
    arm_idx = _arm_positions(plant, instance)
    guesses = [guess, plant.GetDefaultPositions()[arm_idx]] + _starts(
        plant, arm_idx, starts
    )
    best = None
    for g in guesses:
        reached, q = closest_tool_position(
            plant,
            p,
            instance=instance,
            q_guess=g,
            tool_frame=tool_frame,
            return_positions=True,
            tool_axis=tool_axis,
        )
        d = np.linalg.norm(reached - p)
        if best is None or d < best[0]:
            best = (d, reached, q)
    return best[1], best[2]


#: A point the closest-position search reaches within this (m) is tried from
#: there.
REACHED = 1e-5


def check_reach(
    plant,
    points,
    *,
    instance=None,
    q_guess=None,
    tool_frame="tool_tip",
    tool_axes=None,
):
    """None if the tool reaches every point (m, world, rows) vertically
    (along ``tool_axes``' row for the point, unit vectors, when given);
    otherwise (index, point, distance (m) to the nearest reachable tool
    position, joint angles) of the first one it does not reach. `q_guess` (a
    function of the point, or None) seeds each solve; a point it does not reach
    from there is tried from the previous point's solution (the arm moves along
    the path), then from the nearest reachable position's posture. A point
    reached only from that last one gives distance 0 and the posture (rad) that
    reaches it (the seed to give); otherwise the posture is None. Raises
    SingularPose (its ``index`` the point's) for a point the tool reaches
    only in postures near a singular configuration."""
    previous = None
    points = np.asarray(points, dtype=float)
    axes = [None] * len(points) if tool_axes is None else tool_axes
    for k, (p, axis) in enumerate(zip(points, axes)):
        guess = None if q_guess is None else q_guess(p)
        guesses = [guess] + ([previous] if previous is not None else [])
        singular = None
        for g in guesses:
            try:
                previous = solve_tool_pose(
                    plant,
                    p,
                    instance=instance,
                    q_guess=g,
                    tool_frame=tool_frame,
                    tool_axis=axis,
                )
                break
            except SingularPose as e:
                singular = e
            except RuntimeError:
                continue
        else:
            if singular is not None:
                singular.index = k
                raise singular
            reached, q_near = _closest_of_many(
                plant, p, instance, guess, tool_frame, tool_axis=axis
            )
            distance = float(np.linalg.norm(reached - p))
            if distance < REACHED:
                try:
                    q_other = solve_tool_pose(
                        plant,
                        p,
                        instance=instance,
                        q_guess=q_near,
                        tool_frame=tool_frame,
                        tool_axis=axis,
                    )
                    return k, p, 0.0, q_other
                except RuntimeError:
                    pass
            return k, p, distance, None
    return None
