"""Known answers of the common-Lyapunov certificate, on small matrices."""

import numpy as np
import pytest

from deburr_drake.analysis import certificate
from deburr_drake.analysis.certificate import (
    FOUND_BY_NOMINAL,
    FOUND_BY_PROGRAM,
    LmiSolution,
    certify_family,
    certify_rate_bounded,
    check_lyapunov,
    lift,
    mixed_norm,
    p_norm,
    reach,
    reduce_family,
    schedule_rate,
    search_basis,
)


def _rotation(theta):
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def _known_family():
    """S^-1 (0.8 R_i) S: V = x^T S^T S x decays by 0.8 under every map,
    though each map's 2-norm is far above 1."""
    S = np.array([[1.0, 5.0], [0.0, 0.2]])
    Si = np.linalg.inv(S)
    return [Si @ (0.8 * _rotation(t)) @ S for t in (0.0, 0.7, 2.0, -1.1)]


def test_a_family_with_a_known_common_lyapunov_function_is_certified():
    maps = _known_family()
    assert max(np.linalg.norm(A, 2) for A in maps) > 5.0
    cert = certify_family(maps, ["a", "b"])
    assert cert.status == "certified"
    # The first map is 0.8 I: its own Lyapunov function, I, does not
    # serve the others (2-norms above 5), so the program found P.
    assert cert.found_by == FOUND_BY_PROGRAM
    assert cert.solver == "Clarabel" and cert.solver_status == "kSolutionFound"
    # The checked P is a Lyapunov function of every map, in numpy.
    P = cert.P
    assert np.linalg.eigvalsh(P)[0] > 0
    rate = cert.decay_rate
    for A in cert.reduced.maps:
        assert (
            np.linalg.eigvalsh(A.T @ P @ A - rate**2 * P)[-1]
            <= 1e-9 * (np.linalg.eigvalsh(P)[-1])
        )
    # The bisection reaches close to the known rate 0.8.
    assert 0.8 - 1e-6 <= rate < 0.8 + 0.01


def test_the_nominal_maps_lyapunov_function_serves_maps_near_it():
    A0 = np.array([[0.5, 0.2], [0.0, 0.6]])
    maps = [A0, A0 + 0.02 * np.eye(2), A0 - np.array([[0, 0.05], [0, 0]])]
    cert = certify_family(maps, ["a", "b"], bisections=0)
    assert cert.status == "certified"
    assert cert.found_by == FOUND_BY_NOMINAL
    assert cert.solver_status == "not run" and cert.solves == 0
    assert cert.decay_rate < 1.0 - cert.check["margin"]


def test_p_is_searched_in_the_common_row_space_and_checked_on_the_family():
    # Maps that read the state through two coordinates (A = F_i G): the
    # search runs in 2 of 4 dimensions; the lifted P is checked on all 4.
    rng = np.random.default_rng(3)
    G = np.linalg.qr(rng.normal(size=(4, 2)))[0].T
    family = [
        S @ G
        for S in (
            G.T @ (0.8 * _rotation(t)) + 0.1 * rng.normal(size=(4, 2))
            for t in (0.0, 0.5, 1.3)
        )
    ]
    V = search_basis(family)
    assert V.shape == (4, 2)
    np.testing.assert_allclose(V @ V.T, G.T @ G, atol=1e-12)
    cert = certify_family(family, list("abcd"), bisections=0)
    assert cert.status == "certified"
    assert cert.search_dimension == 2
    assert cert.P.shape == (4, 4)
    assert check_lyapunov(cert.reduced.maps, cert.P)["passed"]


def test_the_lift_keeps_the_search_coordinates_decay():
    A = np.diag([0.5, 0.0])
    V = np.array([[1.0], [0.0]])
    P = lift(np.array([[2.0]]), V, [A])
    assert P[0, 0] == pytest.approx(2.0)
    assert p_norm(A, P) == pytest.approx(0.5)


def _switched_pair():
    A1 = np.array([[0.9, 2.0], [0.0, 0.9]])
    return [A1, A1.T]


def test_a_switched_pair_unstable_under_switching_is_not_certified():
    A1, A2 = _switched_pair()
    for A in (A1, A2):
        assert np.max(np.abs(np.linalg.eigvals(A))) < 1.0
    assert np.max(np.abs(np.linalg.eigvals(A1 @ A2))) > 1.0
    cert = certify_family([A1, A2], ["a", "b"])
    assert cert.status == "not_certified"
    assert cert.breaking in (0, 1)
    assert "no common P" in cert.breaking_reason


def test_a_map_unstable_by_itself_is_named():
    stable = np.diag([0.5, 0.6])
    unstable = np.array([[1.02, 0.0], [0.1, 0.3]])
    cert = certify_family([stable, unstable, stable * 0.9], ["a", "b"])
    assert cert.status == "not_certified"
    assert cert.breaking == 1
    assert "spectral radius is 1.02" in cert.breaking_reason


def test_a_solved_program_whose_p_fails_the_check_is_inconclusive(
    monkeypatch,
):
    # Schur-stable (rho 0.5), but V = |x|^2 grows under it: ||A||_2 > 1.
    A = np.array([[0.5, 3.0], [0.0, 0.5]])
    assert np.linalg.norm(A, 2) > 1.0
    # The solver itself finds a P that passes.
    assert certify_family([A], ["a", "b"]).status == "certified"

    def solver_says_solved(maps, gamma, **kwargs):
        return LmiSolution(np.eye(2), "Clarabel", "kSolutionFound", True)

    # The nominal map's Lyapunov function would pass; replaced by P = I
    # it fails the check and the program is asked, whose P fails too.
    monkeypatch.setattr(certificate, "nominal_lyapunov", lambda maps: np.eye(2))
    monkeypatch.setattr(
        certificate, "solve_common_lyapunov", solver_says_solved
    )
    cert = certify_family([A], ["a", "b"])
    assert cert.status == "inconclusive"
    assert cert.solver_status == "kSolutionFound"
    # The injected P = I is checked on the balanced map the program saw.
    balanced = cert.reduced.maps[0]
    assert cert.check["decay_rate"] == pytest.approx(
        np.linalg.norm(balanced, 2)
    )
    assert cert.check["decay_rate"] >= 1.0 - cert.check["margin"]
    assert "fails the check" in cert.breaking_reason


def test_the_check_rejects_an_indefinite_or_ill_conditioned_p():
    A = np.diag([0.5, 0.5])
    assert not check_lyapunov([A], np.diag([1.0, -1.0]))["passed"]
    assert not check_lyapunov([A], np.diag([1.0, 1e-12]))["passed"]
    assert check_lyapunov([A], np.diag([1.0, 2.0]))["passed"]
    assert p_norm(A, np.eye(2)) == pytest.approx(0.5)
    # A P that is not positive definite has no norm: the check fails.
    assert p_norm(A, np.diag([1.0, -1.0])) == np.inf


def _with_shift(B, T):
    """T blockdiag(1, B) T^-1: a mode at 1 (state "s") that B does not
    touch, in coordinates that mix it with the others."""
    M = np.zeros((3, 3))
    M[0, 0] = 1.0
    M[1:, 1:] = B
    return T @ M @ np.linalg.inv(T)


def test_a_mode_at_one_shared_by_every_map_is_separated_and_named():
    T = np.array([[1.0, 0.0, 0.0], [0.3, 1.0, 0.0], [0.0, 0.5, 1.0]])
    maps = [_with_shift(0.7 * _rotation(t), T) for t in (0.1, 0.9)]
    for A in maps:
        assert np.isclose(np.max(np.abs(np.linalg.eigvals(A))), 1.0)
    cert = certify_family(maps, ["s", "x", "y"])
    assert cert.status == "certified"
    assert [m.label for m in cert.reduced.separated] == ["s"]
    assert cert.reduced.separated[0].eigenvalue == pytest.approx(1.0)
    assert cert.reduced.maps[0].shape == (2, 2)
    assert cert.decay_rate < 0.71


def test_a_mode_at_one_that_a_map_moves_is_not_separated():
    T = np.eye(3)
    maps = [_with_shift(0.5 * np.eye(2), T), _with_shift(0.5 * np.eye(2), T)]
    maps[1][0, 0] = 1.01  # this map moves the neutral mode
    cert = certify_family(maps, ["s", "x", "y"])
    assert cert.reduced.separated == []
    assert cert.status == "not_certified"
    assert cert.breaking == 1


def test_states_every_map_overwrites_are_left_out():
    A = np.array([[0.5, 0.1, 2.0], [0.0, 0.4, 1.0], [0.0, 0.0, 0.0]])
    reduced = reduce_family([A, 0.9 * A], ["a", "b", "held"])
    assert reduced.overwritten == ["held"]
    assert reduced.kept == ["a", "b"]
    assert certify_family([A, 0.9 * A], ["a", "b", "held"]).status == (
        "certified"
    )


def test_transform_takes_a_matrix_into_the_certified_coordinates():
    T = np.array([[1.0, 0.0, 0.0], [0.3, 1.0, 0.0], [0.0, 0.5, 1.0]])
    maps = [_with_shift(0.7 * _rotation(t), T) for t in (0.1, 0.9)]
    reduced = reduce_family(maps, ["s", "x", "y"])
    for A, B in zip(maps, reduced.maps):
        np.testing.assert_allclose(reduced.transform(A), B, atol=1e-12)


def test_what_the_corners_leave_out_is_added_to_the_decay_rate():
    from deburr_drake.analysis.box_certificate import _model_error

    A0 = np.diag([0.5, 0.6])
    B = np.array([[0.0, 0.1], [0.0, 0.0]])
    # Parameter "a" has a corner axis and is curved (its midpoint map off
    # the chord by 0.05 I); "b" has none: its half-range counts whole.
    ends = [(A0 - B, A0 + B), (A0 - 0.5 * B, A0 + 0.5 * B)]
    mids = [A0 + 0.05 * np.eye(2), A0]
    cert = certify_family([A0] + [m for e in ends for m in e], ["x", "y"])
    assert cert.status == "certified"
    box = [{"name": "a"}, {"name": "b"}]
    curvatures = [[m - 0.5 * (lo + hi)] for m, (lo, hi) in zip(mids, ends)]
    out = _model_error(cert, box, {"ends": ends, "curvatures": curvatures}, [0])
    a, b = out["model_error"]
    assert a["p_norm"] == pytest.approx(
        p_norm(cert.reduced.transform(0.05 * np.eye(2)), cert.P)
    )
    assert b["p_norm"] == pytest.approx(
        p_norm(cert.reduced.transform(0.5 * B), cert.P)
    )
    assert out["decay_rate_with_model_error"] == pytest.approx(
        cert.decay_rate + a["p_norm"] + b["p_norm"]
    )
    assert "status" not in out
    # A curvature that takes the rate to 1: inconclusive.
    curvatures[0] = [np.eye(2)]
    out = _model_error(cert, box, {"ends": ends, "curvatures": curvatures}, [0])
    assert out["status"] == "inconclusive"
    # Cut into pieces, the parameter is in one at a time: the worst one's
    # chord counts, not their sum.
    curvatures[0] = [0.01 * np.eye(2), 0.05 * np.eye(2)]
    out = _model_error(cert, box, {"ends": ends, "curvatures": curvatures}, [0])
    a = out["model_error"][0]
    assert a["pieces"] == 2
    assert a["p_norm"] == pytest.approx(
        p_norm(cert.reduced.transform(0.05 * np.eye(2)), cert.P)
    )


def test_the_certified_limit_lies_between_a_certified_and_a_refused_value(
    monkeypatch,
):
    from deburr_drake.analysis import box_certificate
    from deburr_drake.config import Scenario

    def certify(scenario, **options):
        ok = (
            scenario.controller.sliding_gain[0] <= 1234.0
            and scenario.sensor.cutoff_frequency >= 12.3
        )
        return {
            "status": "certified" if ok else "not_certified",
            "decay_rate_per_period": 0.9,
            "timings_s": {"total": 0.0},
        }

    monkeypatch.setattr(box_certificate, "certify", certify)
    gain = lambda v: {"controller.sliding_gain[0]": v}  # noqa: E731
    out = box_certificate.certified_limit(
        Scenario(), gain, 400.0, 8000.0, rel_tol=1e-3
    )
    assert out["certified"] <= 1234.0 < out["refused"]
    assert out["refused"] - out["certified"] <= 1e-3 * out["refused"]
    assert [t["value"] for t in out["trials"][:2]] == [400.0, 8000.0]
    # A cutoff: the lowest certified value; the easy end is the high one.
    cutoff = lambda v: {"sensor.cutoff_frequency": v}  # noqa: E731
    out = box_certificate.certified_limit(
        Scenario(), cutoff, 2.0, 40.0, harder_above=False, rel_tol=1e-3
    )
    assert out["refused"] < 12.3 <= out["certified"]
    assert out["certified"] - out["refused"] <= 1e-3 * out["certified"]
    # An easy end refused: no certified value.
    out = box_certificate.certified_limit(Scenario(), gain, 2000.0, 8000.0)
    assert out["certified"] is None and out["refused"] == 2000.0


@pytest.mark.slow
def test_a_box_map_is_taken_at_its_own_steady_state():
    from deburr_drake.analysis import box_certificate as bc
    from deburr_drake.analysis import find_operating_point
    from deburr_drake.config import load_scenario
    from deburr_drake.control.layout import CONTROLLER_DIAGNOSTICS

    op = find_operating_point(load_scenario("point_mass"), after_contact=0.5)
    box = bc._box(op)
    slope = next(p for p in box if p["key"] == "slope_x1")
    maps = bc._Maps(op, box, 0)
    stiff = maps.frozen(
        {"part.material.hydroelastic_modulus": box[0]["range"][1]}
    )
    context = stiff.context_from(
        op.diagram,
        op.context,
        bc._pivoted_slope(0, 1000.0 - slope["nominal"], slope["s0"]),
    )
    # The surface now has slope 1000 at the operating s, and its value
    # there is the learned one: the operating point stays put.
    point = bc._fuzzy_point(
        type(op)(op.scenario, stiff.diagram, context, op.time, 0.0)
    )[0]
    assert point["slope"] == pytest.approx(1000.0, rel=1e-6)
    assert point["s0"] == pytest.approx(slope["s0"], abs=1e-12)

    def u_fuzzy(diagram, context):
        controller = diagram.GetSubsystemByName("controller")
        diagnostics = controller.GetOutputPort("diagnostics").Eval(
            controller.GetMyContextFromRoot(context)
        )
        return CONTROLLER_DIAGNOSTICS.get(diagnostics, "u_fuzzy")

    np.testing.assert_allclose(
        u_fuzzy(stiff.diagram, context),
        u_fuzzy(op.diagram, op.context),
        atol=1e-9,
    )
    # The steady state of the stiffer contact: the desired force is the
    # normal force the sensor reads.
    context, moved, residual = bc.steady_context(stiff, context, 0)
    assert abs(moved) > 0.01 and residual == 0.0
    assert bc._match_estimates(stiff.diagram, context) == pytest.approx(
        0.0, abs=1e-9
    )


def _turned(theta, k=2.0):
    """0.9 Q(theta) E R(0.5) E^-1 Q(theta)^T: every map's radius 0.9, the
    same map seen in axes turned by theta."""
    E = np.diag([k, 1.0 / k])
    Q = _rotation(theta)
    return 0.9 * Q @ E @ _rotation(0.5) @ np.linalg.inv(E) @ Q.T


def test_a_slowly_moving_parameter_is_certified_where_fast_switching_is_not():
    thetas = np.linspace(0.0, np.pi / 2, 65)
    maps = [_turned(t) for t in thetas]
    mids = [_turned(0.5 * (a + b)) for a, b in zip(thetas[:-1], thetas[1:])]
    # Switching between the ends grows: no common quadratic P, and no
    # P(theta) when theta may jump across the whole range.
    product = maps[0] @ maps[-1]
    assert np.max(np.abs(np.linalg.eigvals(product))) > 1.19
    assert certify_family(maps, ["a", "b"]).status == "not_certified"
    fast = certify_rate_bounded(maps, thetas, np.pi / 2, ["a", "b"], mids=mids)
    assert fast.status == "not_certified"
    # Moving by at most 1 mrad per period, P(theta) exists and is checked
    # with what the chord between nodes leaves out.
    slow = certify_rate_bounded(maps, thetas, 1e-3, ["a", "b"], mids=mids)
    assert slow.status == "certified"
    check = slow.check
    assert 0.0 < check["chord_miss"] < 1e-2
    assert check["decay_rate_with_model_error"] < 1.0 - 1e-6
    # The check is the numpy one, and it bounds what it claims: the
    # chord's map at any theta decays from P(theta) to P(theta') for
    # every theta' within the step (sampled).
    assert _sampled_rate(slow.reduced.maps, thetas, 1e-3, slow.Ps) <= (
        check["decay_rate"] + 1e-9
    )


def _sampled_rate(maps, thetas, step, Ps, samples=4000):
    rng = np.random.default_rng(3)
    worst = 0.0
    for t, d in zip(
        rng.uniform(thetas[0], thetas[-1], samples),
        rng.uniform(-step, step, samples),
    ):
        weights = certificate._weights(np.asarray(thetas), t)
        A = sum(w * maps[j] for j, w in weights.items())
        P = certificate._interpolated(Ps, thetas, t)
        after = min(max(t + d, thetas[0]), thetas[-1])
        P_to = certificate._interpolated(Ps, thetas, after)
        worst = max(worst, mixed_norm(A, P_to, P))
    return worst


def test_a_slope_tied_to_the_next_one_needs_fewer_nodes():
    # A node's map need not decay into its neighbours' P: on 9 nodes the
    # tied program certifies what the neighbour-wise one needs 33 for.
    thetas = np.linspace(0.0, np.pi / 2, 9)
    maps = [_turned(t) for t in thetas]
    mids = [_turned(0.5 * (a + b)) for a, b in zip(thetas[:-1], thetas[1:])]
    cert = certify_rate_bounded(maps, thetas, 1e-3, ["a", "b"], mids=mids)
    assert cert.status == "certified"
    assert cert.to_dict()["program"] == "tied"
    # Decaying into the next node's P is what the neighbour-wise program
    # asks, and this P does not give it.
    Ps = cert.Ps
    assert mixed_norm(cert.reduced.maps[3], Ps[4], Ps[3]) > 1.0
    assert _sampled_rate(cert.reduced.maps, thetas, 1e-3, Ps) <= (
        cert.check["decay_rate"] + 1e-9
    )


def test_reach_covers_the_cells_within_the_step_on_each_side():
    thetas = [0.0, 1.0, 2.0, 3.0]
    assert reach(thetas, 1, 0.25) == [(-1, 0), (-1, 1), (1, 1), (1, 2)]
    assert reach(thetas, 0, 1.5) == [(-1, 0), (1, 0), (1, 1), (1, 2)]
    assert reach(thetas, 2, 0.25) == [(-1, 1), (-1, 2), (1, 2)]
    assert reach(thetas, 1, 0.0) == [(1, 1)]


def _turned_cells(edges):
    """Per cell [theta_lo, theta_hi] of ``edges``: its family (the centre's
    map, then the ends') and what the ends leave out (the centre against
    the chord)."""
    cells, left_out = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        a, b, mid = _turned(lo), _turned(hi), _turned(0.5 * (lo + hi))
        cells.append([mid, a, b])
        left_out.append([mid - 0.5 * (a + b)])
    return cells, left_out


def test_a_constant_parameter_is_certified_per_cell_where_no_common_p_is():
    from deburr_drake.analysis.certificate import certify_cells

    # theta constant somewhere in [0, pi/2]: each value is stable with its
    # own P (radius 0.9), but no P serves them all (the ends' product
    # grows), so as a time-varying parameter it is not certified.
    edges = np.linspace(0.0, np.pi / 2, 17)
    everything = [_turned(t) for t in np.linspace(0.0, np.pi / 2, 9)]
    assert certify_family(everything, ["a", "b"]).status == "not_certified"
    cells, left_out = _turned_cells(edges)
    cert = certify_cells(cells, ["a", "b"], left_out=left_out)
    assert cert.status == "certified"
    assert len(cert.cells) == 16
    worst = cert.cells[cert.worst]
    assert worst["decay_rate_with_model_error"] < 1.0 - 1e-6
    assert worst["decay_rate_with_model_error"] > worst["decay_rate"]
    # Each cell's P is checked on the maps at its theta, in numpy: a map
    # inside a cell decays in that cell's P.
    inside = cert.certificates[3]
    theta = edges[3] + 0.3 * (edges[4] - edges[3])
    assert (
        p_norm(inside.reduced.transform(_turned(theta)), inside.P)
        <= (cert.cells[3]["decay_rate_with_model_error"])
    )
    # One cell over the whole range is the common P again: not certified,
    # and the search stops at it.
    cells, left_out = _turned_cells(np.array([0.0, np.pi / 4, np.pi / 2]))
    wide = certify_cells(cells, ["a", "b"], left_out=left_out)
    assert wide.status != "certified"
    assert wide.worst == 0 and len(wide.cells) == 1


def test_the_constants_cells_narrow_only_the_constants_ranges():
    from deburr_drake.analysis.box_certificate import _cells

    box = [
        {"key": "k_c", "name": "k", "range": [0.7, 1.3], "nominal": 1.0},
        {"key": "stiffness", "name": "s", "range": [0.5, 1.5], "nominal": 1},
        {"key": "c0", "name": "c", "range": [1.0, 3.0], "nominal": 2.0},
    ]
    cells = _cells(box, {"k_c": 3, "c0": 1})
    assert len(cells) == 3
    np.testing.assert_allclose(
        [c[0]["range"] for c in cells], [[0.7, 0.9], [0.9, 1.1], [1.1, 1.3]]
    )
    assert [c[0]["nominal"] for c in cells] == pytest.approx([0.8, 1.0, 1.2])
    for cell in cells:
        # The time-varying stiffness keeps its whole range; c0 is a
        # constant in one cell; the box itself is not changed.
        assert cell[1] == box[1] and "constant" not in cell[1]
        assert cell[2]["range"] == [1.0, 3.0] and cell[2]["constant"]
    assert "constant" not in box[0] and box[0]["range"] == [0.7, 1.3]
    # No constants: the box is its only cell.
    assert _cells(box, {}) == [box]


def test_the_program_holds_only_the_inequalities_that_bind():
    from deburr_drake.analysis.certificate import solve_common_lyapunov

    # Many maps share V = x^T S^T S x, the slow ones (0.8) bind, the fast
    # ones (0.3) never do: the program ends holding a few, and its P
    # serves every map of the family in numpy.
    S = np.array([[1.0, 5.0], [0.0, 0.2]])
    Si = np.linalg.inv(S)
    turns = np.linspace(-2.0, 2.0, 40)
    maps = [Si @ (0.3 * _rotation(t)) @ S for t in turns]
    maps += [Si @ (0.8 * _rotation(t)) @ S for t in (0.7, -1.1)]
    solution = solve_common_lyapunov(maps, 0.85)
    assert solution.success
    assert solution.inequalities < 10 < len(maps)
    assert max(p_norm(A, solution.P) for A in maps) < 0.85 + 1e-7
    # A subset that is infeasible is the family's answer: the switched
    # pair among stable maps is refused.
    pair = _switched_pair()
    assert not solve_common_lyapunov(maps[:5] + pair, 0.999).success


@pytest.mark.parametrize("tied", [False, True])
def test_a_schedule_generates_its_inequalities_and_still_serves_every_map(tied):
    from deburr_drake.analysis.certificate import solve_rate_bounded

    thetas = np.linspace(0.0, np.pi / 2, 65)
    # Per node, the turned map and three faster copies of it: the fast
    # ones never bind.
    maps = [
        [_turned(t)] + [s * _turned(t) for s in (0.2, 0.3, 0.4)] for t in thetas
    ]
    step = 1e-3
    gamma = 1.0 - 1e-4
    Ps, status, success, stats = solve_rate_bounded(
        maps, thetas, step, gamma, tied=tied
    )
    assert success, status
    assert stats["inequalities"] < stats["of"]
    # Each program's own numpy check: its P serves every map.
    rate_of = schedule_rate if tied else certificate._node_rate
    rate, _ = rate_of(maps, thetas, step, Ps)
    assert rate < gamma + 1e-7


def test_a_slope_whose_ends_have_no_common_p_is_found_before_the_family():
    from deburr_drake.analysis.box_certificate import _slope_ends

    A1, A2 = _switched_pair()
    A0 = 0.5 * np.eye(2)
    box = [
        {"key": "stiffness", "field": "part.material.hydroelastic_modulus"},
        {"key": "slope_x1", "field": None},
        {"key": "slope_x2", "field": None},
    ]
    maps = {
        "A0": A0,
        # The stiffness's ends alone have no common P either, but only a
        # slope can be scheduled; slope_x1's ends share V = |x|^2.
        "ends": [(A1, A2), (0.4 * np.eye(2), 0.6 * np.eye(2)), (A1, A2)],
        "labels": ["a", "b"],
    }
    k, cert = _slope_ends(box, maps, "Clarabel")
    assert k == 2 and cert.status == "not_certified"
    maps["ends"][2] = (0.3 * np.eye(2), 0.7 * np.eye(2))
    assert _slope_ends(box, maps, "Clarabel") == (None, None)


def _turned_try(cell, splittable):
    """A cell of the constant theta of the turned family, certified by
    one P of its centre's and ends' maps (the result keys search_cells
    reads)."""
    lo, hi = cell[0]["range"]
    mid = 0.5 * (lo + hi)
    a, b, m = _turned(lo), _turned(hi), _turned(mid)
    cert = certify_family([m, a, b], ["a", "b"], bisections=6)
    status = cert.status
    if status == "certified":
        miss = p_norm(cert.reduced.transform(m - 0.5 * (a + b)), cert.P)
        status = "certified" if cert.decay_rate + miss < 1.0 else "inconclusive"
    radii = max(np.max(np.abs(np.linalg.eigvals(A))) for A in (a, b, m))
    return {
        "status": status,
        "range": [lo, hi],
        "_stable": radii < 1.0,
        "_moves": [np.linalg.norm(b - a)],
        "_ends_failed": None,
    }


def test_a_cell_that_is_not_certified_is_halved_until_its_halves_are():
    from deburr_drake.analysis.box_certificate import search_cells

    box = [
        {
            "key": "theta",
            "field": "f",
            "range": [0.0, np.pi / 2],
            "nominal": np.pi / 4,
            "constant": True,
        }
    ]
    results = search_cells([box], _turned_try)
    leaves = [r for r in results if "halved" not in r]
    assert all(r["status"] == "certified" for r in leaves)
    # The whole range has no common P: it was halved, and the certified
    # cells tile the range without a gap.
    assert results[0]["halved"] == "theta" and len(leaves) > 1
    edges = sorted(r["range"] for r in leaves)
    assert edges[0][0] == 0.0 and edges[-1][1] == pytest.approx(np.pi / 2)
    for (_, hi), (lo, _) in zip(edges[:-1], edges[1:]):
        assert hi == lo
    # A cell that cannot be halved any more ends the search uncertified.
    narrow = search_cells([box], _turned_try, max_cells=1)
    assert len(narrow) == 1 and narrow[0]["status"] != "certified"
    assert "halved" not in narrow[0]


def test_a_cell_with_a_map_unstable_by_itself_is_not_halved():
    from deburr_drake.analysis.box_certificate import search_cells

    box = [{"key": "c", "field": "f", "range": [0.0, 1.0], "constant": True}]

    def unstable(cell, splittable):
        return {"status": "not_certified", "_stable": False, "_moves": [1.0]}

    results = search_cells([box], unstable)
    assert len(results) == 1 and "halved" not in results[0]


def test_a_cell_is_halved_along_a_held_slope_whose_ends_fail_not_a_moving_one():
    from deburr_drake.analysis.box_certificate import search_cells

    box = [
        {"key": "c", "field": "f", "range": [0.0, 1.0], "constant": True},
        {"key": "held", "field": None, "range": [0.0, 1.0], "constant": True},
        {"key": "moving", "field": None, "range": [0.0, 1.0]},
    ]

    def ends_fail(j):
        def try_cell(cell, splittable):
            return {
                "status": "not_certified",
                "_stable": True,
                "_moves": [1.0, 0.1, 5.0],
                "_ends_failed": j,
            }

        return try_cell

    # The held slope's ends: halved along it, though c moves the map more.
    held = search_cells([box], ends_fail(1), max_cells=3)
    assert held[0]["halved"] == "held"
    # No ends fail: along the constant that moves the map most (the
    # moving slope is not a constant).
    none = search_cells([box], ends_fail(None), max_cells=3)
    assert none[0]["halved"] == "c"

    # A P without room for the curvature: along the constant whose
    # curvature is the most of it.
    def no_room(cell, splittable):
        return {
            "status": "inconclusive",
            "_stable": True,
            "_moves": [1.0, 0.1, 5.0],
            "model_error": [{"p_norm": 1e-5}, {"p_norm": 1e-3}, {"p_norm": 0}],
        }

    assert search_cells([box], no_room, max_cells=3)[0]["halved"] == "held"
    # The moving slope's ends: not halved at all.
    moving = search_cells([box], ends_fail(2))
    assert len(moving) == 1 and "halved" not in moving[0]


def test_a_slope_is_held_only_inside_the_dead_zone_and_within_its_bound():
    from deburr_drake.analysis.box_certificate import slope_held
    from deburr_drake.config.control import FuzzyConfig
    from deburr_drake.math.fuzzy import RuleBase

    rb = RuleBase(
        m=2, upsilon=5, delta0=0.01, deltak=0.004, dead_zone_half_width=3e-4
    )
    fuzzy = FuzzyConfig(max_slope=3000.0)
    j = np.arange(-5, 6)
    # A surface of slope 1000 N s/m along s_k: within the bound.
    theta = np.tile(1000.0 * j * 0.004, (11, 1)).ravel()
    assert "dead zone" in slope_held(rb, 2.4e-4, theta, fuzzy)
    assert slope_held(rb, -2.4e-4, theta, fuzzy) is not None
    # Outside the dead zone the law moves the rules.
    assert slope_held(rb, 8.7e-4, theta, fuzzy) is None
    # A slope beyond the bound anywhere: the bound pulls the rules.
    steep = theta.copy()
    steep[5] += 100.0
    assert slope_held(rb, 2.4e-4, steep, fuzzy) is None
    # Rules that do not adapt hold whatever s is.
    fuzzy.adapt = False
    assert slope_held(rb, 8.7e-4, steep, fuzzy) == "the rules do not adapt"


def test_a_half_range_that_leaves_no_room_gets_a_corner_axis():
    from deburr_drake.analysis.box_certificate import (
        _axes_for_room,
        _common_with_room,
        _family,
    )

    A0 = np.diag([0.95, 0.5])
    Ba = np.diag([0.02, 0.0])
    Bb = np.array([[0.0, 0.0], [0.45, 0.0]])

    def maps_at(values):
        return A0 + values["a"] * Ba + values["b"] * Bb

    box = [
        {"name": n, "key": n, "nominal": 0.0, "range": [-1.0, 1.0]}
        for n in "ab"
    ]
    maps = {
        "A0": A0,
        "ends": [(A0 - B, A0 + B) for B in (Ba, Bb)],
        # Affine in both: no curvature.
        "mids": [A0, A0],
        "curvatures": [[0 * A0], [0 * A0]],
        "labels": ["x", "y"],
    }
    family, names = _family(maps_at, box, maps, [0], lambda m: None)
    assert len(family) == 7 and names[-1].startswith("corner")
    options = ("Clarabel", 1e-2, 0, {})
    cert, error, axes, family, _ = _common_with_room(
        maps_at, box, maps, ([0], family, names), options, False, print
    )
    # b's half-range bounded in P's norm left no room; its corners (the
    # true maps, lower triangular with the nominal eigenvalues) do.
    assert axes == [0, 1] and len(family) == 9
    assert cert.status == "certified" and "status" not in error
    assert "half_range_p_norm" not in error["model_error"][1]
    # Nothing is added to a P that leaves room.
    assert _axes_for_room(cert, error) == []


def _curved_box(constant):
    """A map curved along a time-varying ``a`` in [-1, 1]: 0.98 at both
    ends, 0.88 at the centre, so the chord through the ends misses the
    centre by 0.1 and one piece leaves no room (0.98 + 0.1), two neither
    (+ 0.025), four do (+ 0.00625)."""
    A0 = np.diag([0.88, 0.5])

    def maps_at(values):
        return A0 + 0.1 * values["a"] ** 2 * np.diag([1.0, 0.0])

    box = [
        {
            "name": "a",
            "key": "a",
            "field": "f",
            "nominal": 0.0,
            "range": [-1.0, 1.0],
            "constant": constant,
        }
    ]
    ends = (maps_at({"a": -1.0}), maps_at({"a": 1.0}))
    maps = {
        "A0": A0,
        "ends": [ends],
        "mids": [A0],
        "curvatures": [[A0 - 0.5 * (ends[0] + ends[1])]],
        "labels": ["x", "y"],
    }
    return maps_at, box, maps


def _with_room(maps_at, box, maps, axes):
    """:func:`_common_with_room` of the family on ``axes``, the cell not
    to be halved."""
    from deburr_drake.analysis.box_certificate import (
        _common_with_room,
        _family,
    )

    family, names = _family(maps_at, box, maps, axes, lambda m: None)
    options = ("Clarabel", 1e-2, 0, {})
    return _common_with_room(
        maps_at, box, maps, (axes, family, names), options, False, print
    )


def test_a_time_varying_parameter_is_cut_into_pieces_until_its_chords_fit():
    maps_at, box, maps = _curved_box(constant=False)
    cert, error, axes, family, names = _with_room(maps_at, box, maps, [0])
    assert cert.status == "certified" and "status" not in error
    # Four pieces: a vertex at each of their five ends.
    assert box[0]["nodes"] == [-1.0, -0.5, 0.0, 0.5, 1.0]
    assert sum(n.startswith("corner") for n in names) == 5
    (a,) = error["model_error"]
    assert a["pieces"] == 4
    assert a["p_norm"] == pytest.approx(0.00625, rel=1e-3)
    assert error["decay_rate_with_model_error"] < 1.0


def test_a_constant_is_not_cut_into_pieces_its_cell_is_halved():
    maps_at, box, maps = _curved_box(constant=True)
    cert, error, _, _, _ = _with_room(maps_at, box, maps, [0])
    assert error["status"] == "inconclusive" and "nodes" not in box[0]


def test_the_limits_figure_marks_each_trial_and_both_brackets(tmp_path):
    from deburr_drake.analysis.limits_plot import (
        SIMULATED,
        plot_certified_limits,
        simulated_text,
    )

    limits = {
        "sliding": {
            "unit": "N s/m",
            "certified": 5506.25,
            "refused": 5565.625,
            "trials": [
                {"value": 400.0, "status": "certified"},
                {"value": 8000.0, "status": "no_operating_point"},
                {"value": 5565.625, "status": "not_certified"},
            ],
            "simulated": SIMULATED[("paper", "sliding")],
            "lowest": {"certified": 1000.0, "refused": 900.0},
        }
    }
    axes = plot_certified_limits(limits, tmp_path / "limits.png")
    assert (tmp_path / "limits.png").stat().st_size > 0
    ax = axes["sliding"]
    xs = [line.get_xdata()[0] for line in ax.get_lines()]
    assert xs[:3] == [400.0, 8000.0, 5565.625]
    # The certified and refused values' lines, the simulated bracket.
    assert 5506.25 in xs and xs.count(5565.625) == 2
    # The low end's certified and refused values.
    assert xs[-2:] == [1000.0, 900.0]
    (span,) = ax.patches
    x0, x1 = span.get_x(), span.get_x() + span.get_width()
    assert (x0, x1) == pytest.approx((5742.0, 5828.0))
    labels = ax.get_legend().get_texts()
    assert {t.get_text() for t in labels} == {
        "certified",
        "no_operating_point",
        "not_certified",
    }
    assert simulated_text(SIMULATED[("paper", "cutoff")], "Hz") == (
        "none in 120-199.9 Hz (both ends stable)"
    )


def test_a_solver_that_stops_without_an_answer_is_inconclusive(monkeypatch):
    def stopped(maps, gamma, *, solver="Clarabel", epsilon=1e-9, first=()):
        return LmiSolution(None, solver, "kSolverSpecificError", False)

    monkeypatch.setattr(certificate, "solve_common_lyapunov", stopped)
    # Not the nominal map's Lyapunov function: the program decides.
    A1, A2 = _switched_pair()
    cert = certify_family([0.5 * np.eye(2), A1, A2], ["x", "y"])
    assert cert.status == "inconclusive"
    assert "kSolverSpecificError" in cert.breaking_reason


def _shear_maps(top):
    """values -> the shear pair alpha [[1, 1], [0, 1]] (parameter "a" at
    its low end) or alpha [[1, 0], [1, 1]] (at its high end), alpha = 0.5
    + (top - 0.5) c: each map of radius alpha, their alternation
    growing by alpha (1 + sqrt 5) / 2 per period."""

    def maps_at(values):
        alpha = 0.5 + (top - 0.5) * values["c"]
        shear = (
            [[1.0, 1.0], [0.0, 1.0]]
            if values["a"] == 0.0
            else [
                [1.0, 0.0],
                [1.0, 1.0],
            ]
        )
        return alpha * np.array(shear)

    return maps_at


_SWITCHED_CELL = [
    {"name": "a", "key": "a", "range": [0.0, 1.0], "nominal": 0.5},
    {
        "name": "c",
        "key": "c",
        "range": [0.0, 1.0],
        "nominal": 0.5,
        "constant": True,
    },
]


def test_switching_that_grows_refuses_the_box_whatever_the_function():
    from deburr_drake.analysis import box_certificate as bc

    labels = ["x", "y"]
    record = bc.switching_growth(_shear_maps(0.7), _SWITCHED_CELL, labels)
    # Found at the constant's high corner (alpha 0.7), the first pair
    # that grows: the search stops there.
    assert record["growth_per_period"] == pytest.approx(0.7 * (1 + 5**0.5) / 2)
    assert record["switched"] == {"a": [0.0, 1.0]}
    assert record["others"] == {"c": 1.0}
    assert record["dwell_periods"] == [1, 1] and record["pairs"] == 2
    # An inconclusive cell in which the loop grows is not certified.
    result = {"status": "inconclusive", "breaking_reason": "no room"}
    cells = [{"_stable": True, "_cell": _SWITCHED_CELL, "labels": labels}]
    maps = _shear_maps(0.7)
    bc._add_switching(result, cells, maps, lambda m: None)
    assert result["status"] == "not_certified"
    assert "grows by 1.132" in result["breaking_reason"]
    assert "held 1 periods at a = 0 and 1 at a = 1" in result["breaking_reason"]
    # A map unstable by itself decides already: no search.
    result = {"status": "not_certified"}
    bc._add_switching(result, [{"_stable": False}], maps, lambda m: None)
    assert "switching" not in result


def test_switching_that_does_not_grow_says_what_it_bounds():
    from deburr_drake.analysis import box_certificate as bc

    record = bc.switching_growth(_shear_maps(0.6), _SWITCHED_CELL, ["x", "y"])
    assert record["growth_per_period"] == pytest.approx(0.6 * (1 + 5**0.5) / 2)
    assert record["pairs"] == 2
    text = bc._switching_text(record)
    assert text.startswith("no growth found under periodic switching")
    assert "lower bound of the joint spectral radius" in text
    # Nothing time-varying: nothing to switch.
    fixed = [dict(_SWITCHED_CELL[1])]
    assert bc.switching_growth(_shear_maps(0.6), fixed, ["x", "y"]) is None


def test_an_interrupted_search_keeps_the_cells_it_finished():
    from deburr_drake.analysis import box_certificate as bc

    cell = {"key": "c", "field": "c", "range": [0.0, 1.0], "constant": True}
    grid = [[cell]] * 3
    tried = []

    def trier(cell, splittable):
        if tried:
            raise KeyboardInterrupt
        tried.append(cell)
        return {"status": "certified"}

    results, stopped = bc._search(grid, trier)
    assert stopped == "interrupted" and len(results) == 1
    # Interrupted before a cell was finished: nothing to keep.
    with pytest.raises(KeyboardInterrupt):
        bc._search(
            grid,
            lambda cell, splittable: (_ for _ in ()).throw(KeyboardInterrupt),
        )


def test_certify_interrupted_writes_its_certificate_and_exits_130(
    tmp_path, monkeypatch
):
    import json

    from deburr_drake import analysis, cli

    def interrupted(scenario, **options):
        raise KeyboardInterrupt

    monkeypatch.setattr(analysis, "certify", interrupted)
    (tmp_path / "maps.npz").write_text("an earlier run's")
    code = cli.main(["certify", "--out", str(tmp_path), "--force"])
    assert code == 130
    written = json.loads((tmp_path / "certificate.json").read_text())
    assert written["status"] == "inconclusive"
    assert written["stop_reason"] == "interrupted"
    assert not (tmp_path / "maps.npz").exists()


def test_switching_tries_parameters_switched_together():
    # Only a and b jumping together grow: a corner with one of them
    # switched is a contraction.
    from deburr_drake.analysis import box_certificate as bc

    def maps_at(values):
        a, b = values["a"], values["b"]
        if a != b:
            return 0.5 * np.eye(2)
        return _shear_maps(0.7)({"a": a, "c": 1.0})

    cell = [
        {"name": "a", "key": "a", "range": [0.0, 1.0], "nominal": 0.5},
        {"name": "b", "key": "b", "range": [0.0, 1.0], "nominal": 0.5},
    ]
    record = bc.switching_growth(maps_at, cell, ["x", "y"])
    assert record["growth_per_period"] > 1.1
    assert record["switched"] == {"a": [0.0, 1.0], "b": [0.0, 1.0]}
    assert record["others"] == {}


def test_a_switch_of_the_scheduled_slope_leaves_its_claim_open():
    # The schedule claims the slope only at its rate bound: the loop
    # growing when the slope jumps does not refute it.
    from deburr_drake.analysis import box_certificate as bc

    maps = _shear_maps(0.7)
    cell = {
        "_stable": True,
        "_cell": _SWITCHED_CELL,
        "scheduled": "a",
        "labels": ["x", "y"],
    }
    result = {"status": "inconclusive", "breaking_reason": "schedule"}
    bc._add_switching(result, [cell], maps, lambda m: None)
    assert result["status"] == "inconclusive"
    assert result["breaking_reason"] == "schedule"
    assert result["switching"]["growth_per_period"] > 1.0


def test_a_program_started_from_the_inequalities_that_bound_needs_one_round():
    # Contractions in one norm: a common P exists; generated from the
    # nominal map and the largest radius it takes rounds, started from
    # the inequalities that bound it takes one, with the same answer.
    rng = np.random.default_rng(11)
    T = rng.standard_normal((5, 5)) + 3 * np.eye(5)
    maps = []
    for _ in range(30):
        Q, _ = np.linalg.qr(rng.standard_normal((5, 5)))
        maps.append(T @ (0.9 * Q) @ np.linalg.inv(T))
    cold = certificate.solve_common_lyapunov(maps, 0.99)
    assert cold.success and cold.rounds > 1
    warm = certificate.solve_common_lyapunov(maps, 0.99, first=cold.active)
    assert warm.success and warm.rounds == 1
    assert warm.active == cold.active
    cert = certify_family(maps, [str(i) for i in range(5)], bisections=2)
    seeded = certify_family(
        maps, [str(i) for i in range(5)], bisections=2, seed=cert.held
    )
    assert seeded.status == cert.status == "certified"
    assert seeded.decay_rate == pytest.approx(cert.decay_rate, abs=1e-6)


def test_a_curvature_that_alone_keeps_the_rest_from_fitting_is_cut():
    # Both maps decay at 0.95 at their corners; the time-varying "a" is
    # curved by 0.03, the constant "c" by 0.04 (the most): 1.02 in all,
    # but without a's curvature the rest fits, so "a" is cut in two
    # (0.0075): 0.9975.
    def maps_at(values):
        a, c = values["a"], values["c"]
        return np.diag([0.95 - 0.03 * (1 - a**2), 0.95 - 0.04 * (1 - c**2)])

    box = [
        {
            "name": n,
            "key": n,
            "field": "f",
            "nominal": 0.0,
            "range": [-1.0, 1.0],
            "constant": n == "c",
        }
        for n in "ac"
    ]
    A0 = maps_at({"a": 0.0, "c": 0.0})
    ends = [
        (
            maps_at({**{"a": 0.0, "c": 0.0}, n: -1.0}),
            maps_at({"a": 0.0, "c": 0.0, n: 1.0}),
        )
        for n in "ac"
    ]
    maps = {
        "A0": A0,
        "ends": ends,
        "mids": [A0, A0],
        "curvatures": [[A0 - 0.5 * (lo + hi)] for lo, hi in ends],
        "labels": ["x", "y"],
    }
    cert, error, _, _, _ = _with_room(maps_at, box, maps, [0, 1])
    assert box[0]["nodes"] == [-1.0, 0.0, 1.0] and "nodes" not in box[1]
    assert cert.status == "certified" and "status" not in error
    assert error["decay_rate_with_model_error"] == pytest.approx(
        0.9975, abs=1e-4
    )


def test_a_search_out_of_time_keeps_the_cells_it_finished():
    from deburr_drake.analysis import box_certificate as bc
    from deburr_drake.analysis.certificate import OutOfTime

    cell = {"key": "c", "field": "c", "range": [0.0, 1.0], "constant": True}
    tried = []

    def trier(cell, splittable):
        if len(tried) == 2:
            raise OutOfTime("the time limit ran out")
        tried.append(cell)
        return {"status": "certified"}

    results, stopped = bc._search([[cell]] * 3, trier)
    assert stopped == "time_limit" and len(results) == 2


def test_no_program_starts_after_the_deadline_and_one_running_gets_the_rest(
    monkeypatch,
):
    import time

    from pydrake.solvers import ClarabelSolver

    from deburr_drake.analysis import certificate

    maps = [0.9 * _rotation(t) for t in (0.1, 0.5)]
    with certificate.solve_deadline(time.monotonic() - 1.0):
        with pytest.raises(certificate.OutOfTime):
            certify_family(maps, ["x", "y"])
    limits = []

    class Recording(ClarabelSolver):
        def Solve(self, prog, guess, options):
            limits.append(options.options.get("Clarabel", {}).get("time_limit"))
            return super().Solve(prog, guess, options)

    monkeypatch.setitem(certificate._SOLVERS, "Clarabel", Recording)
    with certificate.solve_deadline(time.monotonic() + 100.0):
        assert certify_family(maps, ["x", "y"]).status == "certified"
    assert limits and all(0.0 < t <= 100.0 for t in limits)
    # Without a deadline: no limit given, and none checked.
    limits.clear()
    assert certify_family(maps, ["x", "y"]).status == "certified"
    assert limits and all(t is None for t in limits)
    assert certificate.check_deadline() is None


def _out_of_time_case(moving):
    """(op, cell) for :func:`_out_of_time`: the shear pair's cell, ``a``
    a moving fuzzy slope or a time-varying stiffness."""
    from types import SimpleNamespace

    cell = [
        {**_SWITCHED_CELL[0], "field": None if moving else "f"},
        {**_SWITCHED_CELL[1], "field": "g"},
    ]
    op = SimpleNamespace(scenario=SimpleNamespace(name="s"), summary=dict)
    return op, cell


@pytest.mark.parametrize("moving", [True, False])
def test_out_of_time_before_a_cell_still_says_whether_the_loop_grows(
    monkeypatch, moving
):
    from deburr_drake.analysis import box_certificate as bc

    op, cell = _out_of_time_case(moving)
    shear = _shear_maps(0.7)

    class MapsAt:
        def __call__(self, values):
            return shear(values)

        def frozen(self, fields):
            return None

    monkeypatch.setattr(bc, "_labels", lambda frozen: ["x", "y"])
    result = bc._out_of_time(op, cell, cell, MapsAt(), 60.0, print)
    assert result["stop_reason"] == "time_limit"
    assert result["switching"]["growth_per_period"] > 1.0
    # A moving slope's switch leaves its rate-bounded schedule open; a
    # stiffness's refuses the box whatever the function.
    assert result["status"] == ("inconclusive" if moving else "not_certified")
    assert "time limit (60 s) ran out" in result["breaking_reason"]


@pytest.mark.parametrize(
    "status, stop, said",
    [
        ("certified", "search_ended", "  proves: "),
        ("inconclusive", "time_limit", "  would prove: "),
        ("not_certified", "search_ended", "  would prove: "),
    ],
)
def test_the_summary_claims_a_proof_only_of_a_certified_box(status, stop, said):
    from deburr_drake.analysis.box_certificate import certificate_summary

    result = {
        "scenario": "s",
        "status": status,
        "stop_reason": stop,
        "vertices": 3,
        "numerics": "shipped",
        "solver": "Clarabel",
        "solver_status": "kSolutionFound",
        "decay_rate_per_period": None,
        "separated_modes": [],
        "proves": "the loop is stable",
        "does_not_prove": "loss of contact",
        "timings_s": {"total": 1.0},
    }
    lines = certificate_summary(result).splitlines()
    assert f"{said}the loop is stable" in lines
    assert "  does not prove: loss of contact" in lines


def test_a_schedule_counts_the_worst_of_alternatives_and_the_sum_of_the_rest():
    from deburr_drake.analysis.certificate import check_rate_bounded

    A = 0.5 * np.eye(2)
    small, large = 0.1 * np.eye(2), 0.2 * np.eye(2)

    def left(entries):
        check = check_rate_bounded(
            [A, A], [0.0, 1.0], 0.1, [np.eye(2)] * 2, left_out=entries
        )
        return check["model_error"][0]["p_norm"]

    # A parameter's pieces hold one at a time; its half-range adds.
    assert left([("p", [(small, large)])]) == pytest.approx(0.2)
    assert left([("p", [small, large])]) == pytest.approx(0.3)
    assert left([("p", [(small, large), small])]) == pytest.approx(0.3)
