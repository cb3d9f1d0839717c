"""Registration while cutting: :class:`OnlineRegistration`.

The contact force against the depth delta_0 on a reference contour (the
believed part moved by the probe's registration) is

    ||f_n|| = c0 + c1 (delta_0 - d),  d = w . n1 + psi (s - s_pivot),

d how far the real edge lies beyond the reference along n1
(deburr_drake.math.registration.contact_regressor): around a circle the
first harmonic of the offset (w), along a straight edge the heading (psi);
a constant part of d is what the force loop cannot tell from the contact
threshold c0 (it goes into c0). At the contact onset (the entry) the real
depth is known (about zero): 0 = c1 (delta_0 - d), which also pins the
constant part. The parameters (c0, c1, c1 w, c1 psi: the offset estimated
together with the contact parameters) are fitted by recursive least
squares with forgetting, starting from the contact estimator's initial
estimates, and the believed part is moved towards the fit with a
first-order lag and a rate limit (no step in the command). The model
learns only where the edge's curvature is that of most of it
(deburr_drake.math.registration.learning_curvature: a profile's straight
sides; in its fillets the contact is stiffer or softer and the model
would take that for an offset).
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.systems.framework import LeafSystem

from deburr_drake.config import EstimatorConfig, OnlineRegistrationConfig
from deburr_drake.control.layout import CHAMFER_STATE, VectorLayout
from deburr_drake.control.observer import RegisteredContour
from deburr_drake.math.geometry import Contour
from deburr_drake.math.registration import (
    ONLINE_PARAMETERS,
    REGISTRATION_SIZE,
    contact_regressor,
    learning_curvature,
    onset_regressor,
    registration_of,
    rls_update,
)

__all__ = ["OnlineRegistration", "ONLINE_STATE"]

_N = len(ONLINE_PARAMETERS)

ONLINE_STATE = VectorLayout(
    "online_registration",
    [
        ("theta", _N),  # c0 (N), c1 (N/m), c1 w (N), c1 psi (N/m)
        ("covariance", _N * _N),  # P, row-major
        ("correction", REGISTRATION_SIZE),  # applied on top of the base
        ("onset", 1),  # 1 once the contact onset was used
        ("arc", 1),  # m of edge cut since the onset
        ("last_arc", 1),  # m, the arc position at the last sample
    ],
)


class OnlineRegistration(LeafSystem):
    """Registration of the believed part while cutting.

    .. pydrake_system::

        name: OnlineRegistration
        input_ports:
        - chamfer_state
        - base_registration
        - active
        output_ports:
        - registration
        - registration_state

    - ``chamfer_state`` (CHAMFER_STATE, the observer's): x_p, xdot_p,
      ||f_n|| are read.
    - ``base_registration`` (4): the registration the probe found (zero
      without probing): the reference contour.
    - ``active`` (1): 1 while the spindle cuts (0 while probing: nothing
      is learned).
    - ``registration`` (4): base + the correction, to the observer and the
      command generator.
    - ``registration_state`` (ONLINE_STATE layout): the discrete state, for
      the logs.

    ``probed``: the reference is the probe's fit, so the offset's prior is
    ``probed_offset_prior`` (the probe's accuracy) rather than
    ``offset_prior`` (the fixture's).
    """

    def __init__(
        self,
        contour: Contour,
        config: OnlineRegistrationConfig,
        estimator: EstimatorConfig,
        *,
        latency: float,
        probed: bool = False,
    ):
        super().__init__()
        config.validate()
        self.set_name("online_registration")
        self._contour = contour
        self._config = config
        # The model learns where the edge's curvature is that of most of
        # it (a profile: its straight sides, not its fillets).
        self._curvature = learning_curvature(contour)
        self._threshold = estimator.contact_force_threshold
        self._latency = latency
        T = config.sample_period
        self._forgetting = math.exp(-T / config.forgetting_time)
        self._lag = 1.0 - math.exp(-T / config.time_constant)
        half = 0.5 * contour.length if math.isfinite(contour.length) else 0.05
        self._max_step = (
            config.max_rate * T * np.array([1.0, 1.0, 1.0 / half, 1.0])
        )
        prior = config.probed_offset_prior if probed else config.offset_prior
        c0, c1, _ = estimator.initial_estimates
        # Priors: c0 and c1 within their own size, c1 w within c1 x prior.
        P0 = np.diag(
            [
                c0**2,
                c1**2,
                (c1 * prior) ** 2,
                (c1 * prior) ** 2,
                (c1 * prior / half) ** 2,
            ]
        )
        theta0 = np.array([c0, c1, 0.0, 0.0, 0.0])
        self._state = self.DeclareDiscreteState(
            ONLINE_STATE.pack(
                theta=theta0,
                covariance=P0.ravel(),
                correction=np.zeros(REGISTRATION_SIZE),
                onset=0.0,
                arc=0.0,
                last_arc=0.0,
            )
        )
        self._chamfer = self.DeclareVectorInputPort(
            "chamfer_state", CHAMFER_STATE.size
        )
        self._reference = RegisteredContour(
            self.DeclareVectorInputPort("base_registration", REGISTRATION_SIZE)
        )
        self._base = self._reference.port
        self._active = self.DeclareVectorInputPort("active", 1)
        self.DeclarePeriodicDiscreteUpdateEvent(T, 0.0, self._update)
        self.DeclareVectorOutputPort(
            "registration",
            REGISTRATION_SIZE,
            self._calc_registration,
            prerequisites_of_calc={self.xd_ticket(), self._base.ticket()},
        )
        self.DeclareStateOutputPort("registration_state", self._state)

    def _update(self, context, discrete_state):
        if self._active.Eval(context)[0] < 0.5:
            return
        chamfer = self._chamfer.Eval(context)
        f_n = float(CHAMFER_STATE.get(chamfer, "f_n"))
        if f_n <= self._threshold:
            return
        x = context.get_discrete_state(self._state).get_value().copy()
        c = self._config
        reference, _ = self._reference(context, self._contour)
        x_p = CHAMFER_STATE.get(chamfer, "x_p")
        theta = ONLINE_STATE.get(x, "theta")
        P = ONLINE_STATE.get(x, "covariance").reshape(_N, _N)
        noise = c.force_noise**2
        arc = float(reference.arc_position(x_p))
        if ONLINE_STATE.get(x, "onset") < 0.5:
            # The entry: the real depth is how far the tool moved in before
            # the sensor showed the contact.
            speed = float(
                CHAMFER_STATE.get(chamfer, "xdot_p") @ reference.n1(x_p)
            )
            phi = onset_regressor(
                reference, x_p, max(speed, 0.0) * self._latency
            )
            theta, P = rls_update(
                theta, P, phi, 0.0, noise_var=noise, forgetting=1.0
            )
            x[ONLINE_STATE.slice("onset")] = 1.0
        else:
            if abs(
                float(reference.curvature(x_p)) - self._curvature
            ) <= 1e-6 * (1.0 + abs(self._curvature)):
                # Not in a fillet (another contact law: learning_curvature).
                theta, P = rls_update(
                    theta,
                    P,
                    contact_regressor(reference, x_p),
                    f_n,
                    noise_var=noise,
                    forgetting=self._forgetting,
                )
            step = abs(arc - float(ONLINE_STATE.get(x, "last_arc")))
            if reference.closed:
                step = min(step, reference.length - step)
            x[ONLINE_STATE.slice("arc")] += step
        x[ONLINE_STATE.slice("last_arc")] = arc
        x[ONLINE_STATE.slice("theta")] = theta
        x[ONLINE_STATE.slice("covariance")] = P.ravel()
        if ONLINE_STATE.get(x, "arc") >= c.min_arc:
            correction = ONLINE_STATE.get(x, "correction")
            target = registration_of(reference, theta)
            x[ONLINE_STATE.slice("correction")] = correction + np.clip(
                self._lag * (target - correction),
                -self._max_step,
                self._max_step,
            )
        discrete_state.set_value(self._state, x)

    def _calc_registration(self, context, output):
        x = context.get_discrete_state(self._state).get_value()
        output.SetFromVector(
            self._base.Eval(context) + ONLINE_STATE.get(x, "correction")
        )
