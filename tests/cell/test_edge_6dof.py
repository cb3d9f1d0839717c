"""The part's error in six degrees of freedom (part_error.offset and rpy,
faults.part_step): a mesh part believed at its nominal pose while the real
one is moved; a planar part turned about the vertical."""

import numpy as np
import pytest

from deburr_drake.cell.edge import (
    believed_contour,
    believed_contour_step,
    make_contour,
)
from deburr_drake.config import ConfigError, load_scenario
from deburr_drake.math.rigid import compose, inverse, rpy_matrix

DEG = np.pi / 180.0
ERROR = "{offset: [0.001, -0.001, 0.001], rpy: [%r, %r, %r]}" % (
    DEG,
    -DEG,
    DEG,
)


def _pose(pose):
    return rpy_matrix(pose.rpy), np.asarray(pose.xyz, float)


def _on(contour, points):
    """Distances (m) of ``points`` from ``contour``'s path."""
    return [np.linalg.norm(contour.project(p) - p) for p in points]


@pytest.fixture(scope="module")
def cross_hole():
    return load_scenario(
        "examples/cross_hole_6dof.yaml", text=f"part_error: {ERROR}"
    ).validate()


def test_mesh_part_believed_at_its_pose_real_one_moved(cross_hole):
    sc = cross_hole
    real, belief = make_contour(sc), believed_contour(sc)
    nominal = load_scenario("examples/cross_hole_6dof.yaml")
    np.testing.assert_allclose(
        belief.point_at(0.3 * belief.length),
        make_contour(nominal).point_at(0.3 * belief.length),
        atol=1e-12,
    )
    # believed = real turned about the real part's axes, then moved
    X_WR = _pose(sc.part.real_pose(sc.part_error))
    X_WB = _pose(sc.part.pose)
    np.testing.assert_allclose(
        X_WB[0], X_WR[0] @ rpy_matrix(sc.part_error.rpy), atol=1e-14
    )
    np.testing.assert_allclose(X_WB[1], X_WR[1] + sc.part_error.offset)
    # every believed point, carried with the part, lies on the real edge
    X_RB = compose(X_WR, inverse(X_WB))
    s = np.linspace(0.0, belief.length, 9, endpoint=False)
    carried = [X_RB[0] @ belief.point_at(x) + X_RB[1] for x in s]
    assert max(_on(real, carried)) < 1e-7
    # and the edges lie apart by up to more than a millimetre
    apart = _on(belief, [real.point_at(x) for x in s])
    assert 0.3e-3 < min(apart) and max(apart) > 1e-3


@pytest.mark.parametrize(
    "rpy",
    # a move alone too: it once fell to the planar shortcut, which a mesh
    # part's belief ignores
    [[0, 0.01, 0], [0, 0, 0]],
)
def test_mesh_part_step_moves_the_belief(rpy):
    sc = load_scenario(
        "examples/cross_hole_6dof.yaml",
        text="faults: {part_step: {time: 1.0, offset: [0.0005, 0, 0], "
        f"rpy: {rpy}}}}}",
    ).validate()
    time, after = believed_contour_step(sc)
    assert time == 1.0
    real = make_contour(sc)
    # believed after the step, against the unmoved real part, is where
    # the stepped real part puts the old belief's points:
    # X_WB' = X_WR X_WR'^-1 X_WB, X_WR = X_WB (no part_error)
    X = _pose(sc.part.pose)
    R_s = rpy_matrix(rpy)
    X_stepped = (X[0] @ R_s, X[1] + [0.0005, 0, 0])
    X_move = compose(X, inverse(X_stepped))
    s = np.linspace(0.0, real.length, 7, endpoint=False)
    moved = [X_move[0] @ real.point_at(x) + X_move[1] for x in s]
    assert max(_on(after, moved)) < 1e-7


def test_planar_rpy_yaw_is_yaw():
    a = load_scenario("paper", text="part_error: {rpy: [0, 0, 0.02]}")
    b = load_scenario("paper", text="part_error: {yaw: 0.02}")
    p = np.array([0.95, 0.01, 0.5])
    np.testing.assert_array_equal(
        believed_contour(a).project(p), believed_contour(b).project(p)
    )


def test_planar_part_step_turns_about_the_vertical():
    sc = load_scenario(
        "pocket",
        text="part_error: {offset: [0.001, 0, 0]}\n"
        "faults: {part_step: {time: 0.5, offset: [0, 0.001, 0], "
        "rpy: [0, 0, 0.05]}}",
    ).validate()
    _, after = believed_contour_step(sc)
    real = make_contour(sc)
    # the belief against the real part: Rz(-0.05) (e - step) and -0.05
    c, s_ = np.cos(0.05), np.sin(0.05)
    Rz = np.array([[c, -s_, 0], [s_, c, 0], [0, 0, 1]])
    o = Rz.T @ np.array([0.001, -0.001, 0.0])
    pivot = np.array([*sc.part.pose.xyz[:2], real.height])
    arc = np.linspace(0.0, real.length, 5, endpoint=False)
    want = [Rz.T @ (real.point_at(x) - pivot) + pivot + o for x in arc]
    assert max(_on(after, want)) < 1e-9


@pytest.mark.parametrize(
    "text, starts",
    [
        ("part_error: {rpy: [0.01, 0, 0]}", "part_error.rpy = [0.01, 0.0"),
        ("part_error: {yaw: 0.01, rpy: [0, 0, 0.01]}", "part_error.yaw ="),
        (
            "faults: {part_step: {time: 1.0, rpy: [0, 0.01, 0]}}",
            "faults.part_step.rpy = [0.0, 0.01, 0.0]",
        ),
        ("faults: {part_step: {time: 1.0}}", "faults.part_step.offset"),
    ],
)
def test_planar_refusals_name_the_field(text, starts):
    with pytest.raises(ConfigError) as e:
        load_scenario("paper", text=text).validate()
    assert str(e.value).startswith(starts)
    assert "\n" not in str(e.value)
