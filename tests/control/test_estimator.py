"""ContactParameterEstimator: (13)-(18) with the regressor and projection of
R3, adapting only in contact."""

import numpy as np
import pytest

from deburr_drake.config import EstimatorConfig, TaskConfig
from deburr_drake.control.estimator import ContactParameterEstimator
from deburr_drake.control.observer import chamfer_quantities
from deburr_drake.math.geometry import CircularContour

CONTOUR = CircularContour([0.0, 0.0, 0.0], 0.027)


def _setup(config, delta, delta_dot, f_n, c_hat):
    estimator = ContactParameterEstimator(config, TaskConfig())
    context = estimator.CreateDefaultContext()
    p0 = CONTOUR.point_at(0.0)
    n1 = CONTOUR.n1(p0)
    x_p = p0 + delta * n1
    chamfer = chamfer_quantities(
        CONTOUR, x_p, delta_dot * n1, -f_n * n1, min_tangential_speed=1e-5
    )
    estimator.GetInputPort("chamfer_state").FixValue(context, chamfer)
    estimator.set_estimates(context, c_hat)
    return estimator, context


def test_rate_uses_regressor_r3():
    config = EstimatorConfig(gains=[2.0, 3.0, 5.0])
    c_hat = np.array([1.0, 4000.0, 10.0])
    delta, delta_dot, f_n = 4e-4, 1e-3, 6.0
    estimator, context = _setup(config, delta, delta_dot, f_n, c_hat)
    e_n = f_n - (1.0 + 4000.0 * delta + 10.0 * delta_dot)
    rate = estimator.EvalTimeDerivatives(context).CopyToVector()
    np.testing.assert_allclose(
        rate, [2.0 * e_n, 3.0 * e_n * delta, 5.0 * e_n * delta_dot], rtol=1e-12
    )
    out = estimator.GetOutputPort("desired_normal_force").Eval(context)[0]
    assert out == pytest.approx(1.0 + 4000.0 * TaskConfig().desired_depth)
    np.testing.assert_allclose(
        estimator.GetOutputPort("estimates").Eval(context), c_hat
    )


def test_projection_freezes_at_lower_bound():
    config = EstimatorConfig(lower_bounds=[0.5, 1000.0, 0.0])
    # Force far below the prediction: e_n < 0 pushes every estimate down.
    estimator, context = _setup(config, 4e-4, 0.0, 0.5, [0.5, 5000.0, 1.0])
    rate = estimator.EvalTimeDerivatives(context).CopyToVector()
    assert rate[0] == 0.0  # c0 at eps0, pushed down: frozen
    assert rate[1] < 0.0  # c1 above eps1: still adapts
    # e_n > 0 moves a parameter at its bound up again.
    estimator, context = _setup(config, 4e-4, 0.0, 9.0, [0.5, 5000.0, 1.0])
    assert estimator.EvalTimeDerivatives(context)[0] > 0.0


@pytest.mark.parametrize("delta, f_n", [(-1e-4, 5.0), (4e-4, 0.1)])
def test_no_adaptation_out_of_contact(delta, f_n):
    estimator, context = _setup(
        EstimatorConfig(), delta, 0.0, f_n, [3.0, 4000.0, 20.0]
    )
    np.testing.assert_array_equal(
        estimator.EvalTimeDerivatives(context).CopyToVector(), 0.0
    )


def test_converges_to_linear_truth():
    """Integrating (16)-(18) against a linear truth with a persistently
    exciting depth recovers c0 and c1 (Proposition 1's e_n -> 0). Without
    excitation only c0 + c1 delta at the operating depth is identifiable."""
    config = EstimatorConfig(
        gains=[5.0, 2.0e7, 0.0], initial_estimates=[3.0, 5000.0, 20.0]
    )
    c_true = np.array([2.0, 10000.0])
    estimator = ContactParameterEstimator(config, TaskConfig())
    context = estimator.CreateDefaultContext()
    dt = 2e-3
    for k in range(15000):
        t = k * dt
        delta = 5e-4 + 2e-4 * np.sin(20.0 * t)
        f_n = c_true[0] + c_true[1] * delta
        p0 = CONTOUR.point_at(0.0)
        n1 = CONTOUR.n1(p0)
        estimator.GetInputPort("chamfer_state").FixValue(
            context,
            chamfer_quantities(
                CONTOUR,
                p0 + delta * n1,
                np.zeros(3),
                -f_n * n1,
                min_tangential_speed=1e-5,
            ),
        )
        x = context.get_continuous_state_vector().CopyToVector()
        context.SetContinuousState(
            x + dt * estimator.EvalTimeDerivatives(context).CopyToVector()
        )
    c_hat = context.get_continuous_state_vector().CopyToVector()
    np.testing.assert_allclose(c_hat[:2], c_true, rtol=0.03)


def test_sampled_rate_is_held_between_samples():
    """sample_period > 0: the update law's rate is taken at the sample and
    held while the chamfer state moves on."""
    config = EstimatorConfig()
    continuous, cc = _setup(config, 5e-4, 0.0, 6.0, [3.0, 4000.0, 20.0])
    sampled = ContactParameterEstimator(
        config, TaskConfig(), sample_period=0.0025
    )
    sc = sampled.CreateDefaultContext()
    chamfer = continuous.GetInputPort("chamfer_state").Eval(cc)
    sampled.GetInputPort("chamfer_state").FixValue(sc, chamfer)
    sc.SetDiscreteState(sampled.EvalUniquePeriodicDiscreteUpdate(sc))
    rate = continuous.EvalTimeDerivatives(cc).CopyToVector()
    assert np.linalg.norm(rate) > 0
    np.testing.assert_allclose(
        sampled.EvalTimeDerivatives(sc).CopyToVector(), rate, rtol=1e-12
    )
    sampled.GetInputPort("chamfer_state").FixValue(sc, np.zeros_like(chamfer))
    np.testing.assert_allclose(
        sampled.EvalTimeDerivatives(sc).CopyToVector(), rate, rtol=1e-12
    )
    with pytest.raises(ValueError, match="sample_period"):
        ContactParameterEstimator(config, TaskConfig(), sample_period=-1.0)
