"""Contact-parameter estimator, eqs. (13)-(18) with correction R3.

Use: ``ContactParameterEstimator(scenario.estimator, scenario.task,
sample_period=scenario.controller.control_period)``, fed the observer's
``chamfer_state``; :func:`estimator_rate` is its law as a pure function."""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem

from deburr_drake.config import ConfigError, EstimatorConfig, TaskConfig
from deburr_drake.control.layout import CHAMFER_STATE

__all__ = ["ContactParameterEstimator", "estimator_rate"]


def estimator_rate(
    c_hat,
    delta,
    delta_dot,
    f_n,
    *,
    gains,
    lower_bounds,
    contact_force_threshold,
    adapt=True,
):
    """d(c_hat)/dt of (16)-(18) with the regressor of R3.

    e_n = ||f_n|| - (c0 + c1 delta + c2 delta_dot) (15); each parameter moves
    along its regressor (1, delta, delta_dot) with its own gain r_i (a
    diagonal gain keeps Proposition 1's Lyapunov argument with
    V = sum c~_i^2 / (2 r_i)); a parameter at or below its bound eps_i is
    frozen when its update would push it lower (projection). Zero out of
    contact (delta <= 0 or ||f_n|| <= threshold): eq. (4) is zero there.
    """
    if not adapt or delta <= 0.0 or f_n <= contact_force_threshold:
        return np.zeros(3)
    # Three scalars: plain floats are several times faster than arrays.
    c_hat = [float(c) for c in c_hat]
    regressor = (1.0, float(delta), float(delta_dot))
    e_n = float(f_n) - sum(c * y for c, y in zip(c_hat, regressor))
    rate = [float(r) * e_n * y for r, y in zip(gains, regressor)]
    return np.array(
        [
            0.0 if (c <= eps and r < 0.0) else r
            for c, eps, r in zip(c_hat, lower_bounds, rate)
        ]
    )


_DELTA, _DELTA_DOT, _F_N = (
    CHAMFER_STATE.slice(name).start for name in ("delta", "delta_dot", "f_n")
)


class ContactParameterEstimator(LeafSystem):
    """Estimates c0, c1, c2 of the contact-force model (4) and outputs the
    refined desired normal force ||f_nd hat|| = c0 + c1 delta_d^* (13).

    .. pydrake_system::

        name: ContactParameterEstimator
        input_ports:
        - chamfer_state
        output_ports:
        - estimates
        - desired_normal_force

    - ``chamfer_state`` (CHAMFER_STATE layout): delta (m), delta_dot (m/s),
      ||f_n|| (N) are read.
    - ``estimates`` (3): c0 hat (N), c1 hat (N/m), c2 hat (N s/m).
    - ``desired_normal_force`` (1, N): c0 hat + c1 hat delta_d^*.
    - Continuous state (3): the estimates.
    - With ``sample_period`` T > 0 the update law is evaluated at t = kT
      (and at initialization) and its rate held until the next sample (a
      discrete state), as in the digital inner loop; T = 0: continuous.
    """

    def __init__(
        self,
        config: EstimatorConfig,
        task: TaskConfig,
        *,
        sample_period: float = 0.0,
    ):
        super().__init__()
        config.validate()
        task.validate()
        if not sample_period >= 0.0:
            raise ConfigError(
                f"sample_period = {sample_period!r} is invalid: allowed a "
                "number >= 0 (s)"
            )
        self.set_name("contact_estimator")
        self._law = dict(
            gains=tuple(map(float, config.gains)),
            lower_bounds=tuple(map(float, config.lower_bounds)),
            contact_force_threshold=config.contact_force_threshold,
            adapt=config.adapt,
        )
        self._desired_depth = task.desired_depth
        xc = self.DeclareContinuousState(
            BasicVector(np.asarray(config.initial_estimates, float))
        )
        self._chamfer_port = self.DeclareVectorInputPort(
            "chamfer_state", CHAMFER_STATE.size
        )
        self._rate_index = None
        if sample_period > 0:
            self._rate_index = self.DeclareDiscreteState(3)
            self.DeclareInitializationDiscreteUpdateEvent(self._sample)
            self.DeclarePeriodicDiscreteUpdateEvent(
                sample_period, 0.0, self._sample
            )
        self.DeclareStateOutputPort("estimates", xc)
        self.DeclareVectorOutputPort(
            "desired_normal_force",
            1,
            self._calc_desired_force,
            prerequisites_of_calc={self.xc_ticket()},
        )

    def set_estimates(self, context, c_hat):
        context.SetContinuousState(np.asarray(c_hat, float))

    def _estimates(self, context):
        return context.get_continuous_state_vector().CopyToVector()

    def _rate(self, context):
        chamfer = self._chamfer_port.Eval(context)
        return estimator_rate(
            self._estimates(context),
            chamfer[_DELTA],
            chamfer[_DELTA_DOT],
            chamfer[_F_N],
            **self._law,
        )

    def _sample(self, context, discrete_state):
        discrete_state.set_value(self._rate_index, self._rate(context))

    def DoCalcTimeDerivatives(self, context, derivatives):
        rate = (
            self._rate(context)
            if self._rate_index is None
            else context.get_discrete_state(self._rate_index).get_value()
        )
        derivatives.get_mutable_vector().SetFromVector(rate)

    def _calc_desired_force(self, context, output):
        c_hat = self._estimates(context)
        output.SetAtIndex(0, c_hat[0] + c_hat[1] * self._desired_depth)
