"""The feedrate law of math.feedrate: its branches by hand, arrays against
the per-sample scalars, the max_feed clamp, the integrating variant, the
steady feed and the slope."""

import math

import numpy as np
import pytest

from deburr_drake.math.feedrate import FeedrateLaw, cutting_damping

#: 10 N desired over a 2 N threshold: f_td - P'_th = 8 N.
LAW = FeedrateLaw(
    desired_force=10.0,
    threshold_force=2.0,
    force_offset=0.5,
    default_feed=0.001,
)


def test_branches_by_hand():
    # ||f_t|| - P' = 4 > v_eps: v = |v_t| * 8 / 4, either sign of v_t.
    assert LAW(0.002, 6.0) == pytest.approx(0.004)
    assert LAW(-0.002, 6.0) == pytest.approx(0.004)
    # ||f_t|| - P' = 0.4 <= v_eps (and exactly v_eps): the default feed.
    assert LAW(0.002, 2.4) == 0.001
    assert LAW(0.002, 2.5) == 0.001
    assert LAW(0.0, 0.0) == 0.001
    # ||f_t|| - P' = 0.51 on a vanishing chamfer: 8 / 0.51 x the speed.
    assert LAW(0.002, 2.51) == pytest.approx(0.002 * 8 / 0.51)
    assert LAW.cutting(2.51) and not LAW.cutting(2.5)


def test_max_feed_clamps_the_cutting_branch_only():
    law = FeedrateLaw(10.0, 2.0, 0.5, 0.001, max_feed=0.02)
    # 15 mm/s x 8 / 0.6 = 200 mm/s asked, 20 mm/s given.
    assert LAW(0.015, 2.6) == pytest.approx(0.2)
    assert law(0.015, 2.6) == 0.02
    # Below the clamp the law is untouched; the default feed is not clamped.
    assert law(0.002, 6.0) == pytest.approx(0.004)
    assert law(0.002, 2.0) == 0.001
    # A NaN speed stays NaN: the clamp does not hide it.
    assert math.isnan(law(math.nan, 6.0))


def test_integrating_scales_the_last_feed():
    law = FeedrateLaw(10.0, 2.0, 0.5, 0.001, max_feed=0.02, integrating=True)
    # v_{k+1} = v_k 8 / 4, whatever the tool's tangential speed.
    assert law(0.0005, 6.0, 0.003) == pytest.approx(0.006)
    assert law(0.009, 6.0, 0.003) == pytest.approx(0.006)
    assert law(0.009, 2.4, 0.003) == 0.001
    assert law(0.009, 2.6, 0.003) == 0.02
    # The paper's law reads the tangential speed and ignores the last feed.
    assert LAW(0.0005, 6.0, 0.003) == pytest.approx(0.001)


@pytest.mark.parametrize("integrating", [False, True])
def test_arrays_agree_with_the_scalars(integrating):
    law = FeedrateLaw(
        10.0, 2.0, 0.5, 0.001, max_feed=0.02, integrating=integrating
    )
    rng = np.random.default_rng(3)
    speed = rng.uniform(-0.01, 0.01, 200)
    force = rng.uniform(0.0, 20.0, 200)
    last = rng.uniform(0.0, 0.01, 200)
    force[:3] = [2.5, 2.50001, 2.0]  # the branch's edge
    v = law(speed, force, last)
    assert v.shape == (200,)
    expected = [
        law(float(s), float(f), float(l)) for s, f, l in zip(speed, force, last)
    ]
    np.testing.assert_allclose(v, expected, rtol=1e-15)
    np.testing.assert_array_equal(law.cutting(force), force - 2.0 > 0.5)
    # np.float64 samples take the scalar path; 0-d arrays the array path,
    # to the same value.
    assert isinstance(law(np.float64(0.002), np.float64(6.0), 0.003), float)
    assert float(law(np.array(0.002), np.array(6.0), np.array(0.003))) == (
        law(0.002, 6.0, 0.003)
    )


def test_steady_feed_is_the_fixed_point():
    # g = 3e9 N s/m^3 x (0.5 mm x 2 mm): 3000 N s/m, v = 8 N / g.
    g = cutting_damping(3.0e9, 0.0005 * 0.002)
    assert g == pytest.approx(3000.0)
    v = LAW.steady_feed(g)
    assert v == pytest.approx(8.0 / 3000.0)
    # There ||f_t|| = P'_th + g v = ||f_td||: the law returns its speed.
    assert LAW(v, 2.0 + g * v) == pytest.approx(v)
    assert LAW(v, 2.0 + g * v, v) == pytest.approx(v)
    # A burr adds its section: 1 mm x 2 mm more, a third of the feed.
    assert LAW.steady_feed(
        cutting_damping(3.0e9, 0.0005 * 0.002, 0.001 * 0.002)
    ) == pytest.approx(8.0 / 9000.0)


def test_steady_feed_branches_and_arrays():
    clamped = FeedrateLaw(10.0, 2.0, 0.5, 0.001, max_feed=0.02)
    # Below v0 the law still settles at 8 / g: v0 is its non-cutting
    # branch, not a floor.
    assert LAW.steady_feed(16000.0) == pytest.approx(0.0005)
    # 8 N / 100 N s/m = 80 mm/s asked: max_feed.
    assert LAW.steady_feed(100.0) == pytest.approx(0.08)
    assert clamped.steady_feed(100.0) == 0.02
    # Nothing cut, or f_td - P'_th within v_eps: the default feed.
    assert LAW.steady_feed(0.0) == 0.001
    weak = FeedrateLaw(2.5, 2.0, 0.5, 0.001)
    assert weak.steady_feed(3000.0) == 0.001
    g = np.array([0.0, 100.0, 3000.0, 16000.0])
    np.testing.assert_allclose(
        clamped.steady_feed(g), [0.001, 0.02, 8.0 / 3000.0, 0.0005]
    )
    assert isinstance(LAW.steady_feed(3000.0), float)


def test_steady_feed_on_the_process_threshold():
    # The controller believes P'_th = 2 N, the cut carries 3 N: the force
    # settles at f_td all the same, v = (10 - 3) N / g.
    assert LAW.steady_feed(3000.0, 3.0) == pytest.approx(7.0 / 3000.0)
    assert LAW(7.0 / 3000.0, 3.0 + 7.0) == pytest.approx(7.0 / 3000.0)
    # The branch is the law's: f_td - 2 N > v_eps whatever the process's.
    assert LAW.steady_feed(3000.0, 9.8) == pytest.approx(0.2 / 3000.0)
    # A threshold above f_td leaves no feed that reaches it.
    assert LAW.steady_feed(3000.0, 12.0) == 0.0


def test_slope_is_the_laws_elasticity_at_the_desired_force():
    # f_td / (f_td - P'_th) = 10 / 8.
    assert LAW.slope == pytest.approx(1.25)
    # -d ln v / d ln f_t by central difference at f_t = f_td.
    h = 1e-6
    up, down = LAW(0.002, 10.0 * (1 + h)), LAW(0.002, 10.0 * (1 - h))
    assert -(math.log(up) - math.log(down)) / (2 * h) == pytest.approx(
        LAW.slope, rel=1e-6
    )
