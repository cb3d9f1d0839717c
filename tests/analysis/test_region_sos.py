"""Known answers of the sums-of-squares region of attraction and its
check after the solve."""

import numpy as np
from pydrake.symbolic import Variable
import pytest

from deburr_drake.analysis.region import (
    Region,
    check_sublevel,
    common_lyapunov,
    improve_quadratic,
    sublevel_certificate,
)


def _scalar():
    """x+ = x / 2 + x^2: with V = x^2, V(x+) - V <= -eps x^2 holds exactly
    for -1.5 + ... < x <= sqrt(1 - eps) - 1/2, so the largest symmetric
    sublevel set has rho = (sqrt(1 - eps) - 1/2)^2."""
    x = Variable("x")
    return x, Region("all", [0.5 * x + x * x])


def _scalar_step(z):
    return [np.array([0.5 * z[0] + z[0] ** 2])]


def test_a_stable_scalar_map_gets_its_known_region():
    x, region = _scalar()
    eps = 0.19
    P = np.eye(1)
    result = sublevel_certificate(
        [x],
        P,
        [region],
        eps=eps,
        rho_max=1.0,
        bisections=12,
        check=lambda rho: check_sublevel(_scalar_step, P, rho, eps),
    )
    known = (np.sqrt(1 - eps) - 0.5) ** 2
    assert result.status == "proven"
    assert known * (1 - 2.0**-10) <= result.rho / (1 - 1e-6) <= known * 1.001
    assert result.check["ok"]


def test_the_check_rejects_a_sublevel_set_too_large():
    P = np.eye(1)
    assert check_sublevel(_scalar_step, P, 0.16, 0.19)["ok"]
    bad = check_sublevel(_scalar_step, P, 0.3, 0.19)
    assert not bad["ok"] and bad["failures"] > 0


def test_the_check_rejects_a_wrong_v():
    """A stable linear map (radius 0.5) that V = |x|^2 does not prove:
    its 2-norm is above 1, so |x|^2 grows somewhere; the P of the
    Lyapunov equation does."""
    A = np.array([[0.5, 3.0], [0.0, 0.5]])

    def step(z):
        return [A @ z]

    assert not check_sublevel(step, np.eye(2), 1.0, 0.0)["ok"]
    P = common_lyapunov([A])
    assert check_sublevel(step, P, 1.0, 0.0)["ok"]


def test_a_solved_program_whose_check_fails_is_inconclusive():
    """The program is given x+ = x / 2 + x^2, the check the true map
    x+ = 1.1 x: the solver's answer does not make the result proven."""
    x, region = _scalar()
    P = np.eye(1)
    result = sublevel_certificate(
        [x],
        P,
        [region],
        eps=0.19,
        rho_max=0.1,
        check=lambda rho: check_sublevel(
            lambda z: [1.1 * z], P, rho, 0.19, samples=200
        ),
    )
    assert result.rho == pytest.approx(0.1)
    assert result.status == "inconclusive"


def test_an_unstable_map_proves_nothing():
    x = Variable("x")
    result = sublevel_certificate(
        [x],
        np.eye(1),
        [Region("all", [1.2 * x])],
        eps=0.0,
        rho_max=1.0,
        bisections=4,
    )
    assert result.status == "failed" and result.rho == 0.0


def test_a_region_missing_the_set_is_skipped():
    region = Region("far", [], linear=[(np.array([1.0]), -2.0)])
    assert not region.meets(np.eye(1), 1.0)
    assert region.meets(np.eye(1), 4.5)


def test_a_new_p_of_the_v_s_iteration_is_proven_anew_and_stays_sound():
    """The scalar map from V = 3 x^2: the proposal P, proven again, keeps
    the set within the known interval for V = P x^2,
    P x^2 ((1/2 + x)^2 - 1) <= -eps x^2, i.e. x <= sqrt(1 - eps / P) - 1/2."""
    x, region = _scalar()
    eps = 0.19
    first = sublevel_certificate(
        [x], 3.0 * np.eye(1), [region], eps=eps, rho_max=3.0, bisections=10
    )
    assert first.status == "proven"
    proposal = improve_quadratic(
        [x],
        3.0 * np.eye(1),
        first.rho,
        [region],
        first.multipliers,
        eps=eps,
        shape=np.eye(1),
    )
    assert proposal is not None
    again = sublevel_certificate(
        [x], proposal, [region], eps=eps, rho_max=3.0, bisections=10
    )
    P = proposal[0, 0]
    half_width = np.sqrt(again.rho / P)
    known = np.sqrt(1 - eps / P) - 0.5
    assert half_width <= known * (1 + 1e-6)
    assert half_width >= known * 0.99


@pytest.mark.slow
def test_the_reduced_model_follows_the_paper_diagram_after_a_depth_step():
    """At the paper's operating point: the model's equilibrium is a fixed
    point of its map, and after a 0.2 mm step of the depth reference the
    full Diagram and the reduced model stay within 0.06 mm and 0.6 N of
    each other for 0.5 s (measured: 0.049 mm, 0.47 N over 1 s at 3 s
    after contact)."""
    from deburr_drake.analysis import find_operating_point
    from deburr_drake.analysis.region import (
        diagram_response,
        normal_axis_model,
    )
    from deburr_drake.config import load_scenario

    op = find_operating_point(load_scenario("paper"))
    model, info = normal_axis_model(op)
    x_star = model.equilibrium()
    np.testing.assert_allclose(model.step(x_star, w=0.0), x_star, atol=1e-12)
    assert 5.0 < info["task_inertia_kg"] < 40.0
    full = diagram_response(op, reference_step=2e-4, duration=0.5)
    reduced = model.simulate(full[0], len(full) - 1)
    assert np.max(np.abs(full[:, 0] - reduced[:, 0])) < 6e-5
    assert np.max(np.abs(full[:, 2] - reduced[:, 2])) < 0.6
    # The step moves the depth by far more than the difference.
    assert np.max(full[:, 0]) - full[0, 0] > 1.2e-4
