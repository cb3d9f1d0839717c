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

Along a 3-D edge (``contour.varying_frame``: a mesh part's) the offset is
a small rigid move of the part seen through n1, d = g(x) . (v, L omega)
(deburr_drake.math.edge_registration), in the directions whose d varies
along the arc beyond what else varies the force (the engaged height as
a turn of the part raises and lowers the edge along the tool, the tool's
lean): those are estimated alongside and never applied, and a move the
force cannot tell from them is left alone (around a hole's rim, every
move: its first harmonic is also a tilt's). The correction (v, omega)
moves the probe's pose registration about the pivot it carries, and the
model learns all along the edge. The model is chosen once, when the
system is built.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.systems.framework import LeafSystem

from deburr_drake.config import EstimatorConfig, OnlineRegistrationConfig
from deburr_drake.control.layout import CHAMFER_STATE, VectorLayout
from deburr_drake.control.observer import RegisteredContour
from deburr_drake.math.edge_registration import (
    CORRECTION_SIZE,
    corrected,
    edge_contact_regressor,
    edge_model,
    edge_onset_regressor,
    edge_registration_of,
)
from deburr_drake.math.geometry import Contour
from deburr_drake.math.registration import (
    MAX_AMPLIFICATION,
    ONLINE_PARAMETERS,
    POSE_REGISTRATION_SIZE,
    REGISTRATION_SIZE,
    contact_regressor,
    learning_curvature,
    onset_regressor,
    registration_of,
    rls_update,
)

__all__ = ["OnlineRegistration", "ONLINE_STATE", "online_state"]

_N = len(ONLINE_PARAMETERS)


def online_state(parameters: int, registration: int) -> VectorLayout:
    """The discrete state of a model with ``parameters`` parameters and a
    ``registration``-long correction."""
    return VectorLayout(
        "online_registration",
        [
            ("theta", parameters),  # c0 (N), c1 (N/m), then c1 x the move
            ("covariance", parameters * parameters),  # P, row-major
            ("correction", registration),  # applied on top of the base
            ("onset", 1),  # 1 once the contact onset was used
            ("arc", 1),  # m of edge cut since the onset
            ("last_arc", 1),  # m, the arc position at the last sample
        ],
    )


#: A planar edge's: theta = (c0, c1, c1 w, c1 psi), the correction
#: (dx, dy, dyaw, dradius).
ONLINE_STATE = online_state(_N, REGISTRATION_SIZE)


class _PlanarModel:
    """A planar edge's model (deburr_drake.math.registration): the first
    harmonic of the offset or the heading; learns where the curvature is
    that of most of the edge; a registration adds to the base."""

    def __init__(self, contour: Contour, config, estimator, prior):
        self.layout = ONLINE_STATE
        self.registration_size = self.correction_size = REGISTRATION_SIZE
        # The model learns where the edge's curvature is that of most of
        # it (a profile: its straight sides, not its fillets).
        self._curvature = learning_curvature(contour)
        T = config.sample_period
        half = 0.5 * contour.length if math.isfinite(contour.length) else 0.05
        self.max_step = (
            config.max_rate * T * np.array([1.0, 1.0, 1.0 / half, 1.0])
        )
        c0, c1, _ = estimator.initial_estimates
        # Priors: c0 and c1 within their own size, c1 w within c1 x prior.
        self.P0 = np.diag(
            [
                c0**2,
                c1**2,
                (c1 * prior) ** 2,
                (c1 * prior) ** 2,
                (c1 * prior / half) ** 2,
            ]
        )
        self.theta0 = np.array([c0, c1, 0.0, 0.0, 0.0])

    def learns(self, reference, x_p) -> bool:
        # Not in a fillet (another contact law: learning_curvature).
        return abs(
            float(reference.curvature(x_p)) - self._curvature
        ) <= 1e-6 * (1.0 + abs(self._curvature))

    def regressor(self, reference, x_p, base):
        return contact_regressor(reference, x_p)

    def onset(self, reference, x_p, depth, base):
        return onset_regressor(reference, x_p, depth)

    def target(self, reference, theta):
        return registration_of(reference, theta)

    def applied(self, base, correction):
        return base + correction


class _EdgeModel:
    """A 3-D edge's model (deburr_drake.math.edge_registration): the small
    rigid move seen through n1 in the directions the force shows beyond
    the nuisances (estimated with it, never applied); learns
    all along the edge (its contact law varies smoothly with the faces'
    angle); the correction (v, omega) moves the base's pose registration
    about the pivot it carries."""

    def __init__(self, contour: Contour, config, estimator, prior):
        self.model = edge_model(contour, 1.0 / MAX_AMPLIFICATION)
        k = self.model.basis.shape[1]
        j = self.model.nuisance.shape[1]
        self.layout = online_state(2 + k + j, CORRECTION_SIZE)
        self.registration_size = POSE_REGISTRATION_SIZE
        self.correction_size = CORRECTION_SIZE
        T = config.sample_period
        step = config.max_rate * T
        self.max_step = np.array([step] * 3 + [step / self.model.length] * 3)
        c0, c1, _ = estimator.initial_estimates
        # Priors: c0 and c1 within their own size, c1 a within c1 x prior
        # (a: metres of (v, L omega)), the nuisances' force within c0's
        # size (the contact law's own, which they scale).
        self.P0 = np.diag(
            [c0**2, c1**2] + [(c1 * prior) ** 2] * k + [c0**2] * j
        )
        self.theta0 = np.concatenate([[c0, c1], np.zeros(k + j)])

    def learns(self, reference, x_p) -> bool:
        return True

    def regressor(self, reference, x_p, base):
        return edge_contact_regressor(self.model, reference, x_p, base)

    def onset(self, reference, x_p, depth, base):
        return edge_onset_regressor(self.model, reference, x_p, depth, base)

    def target(self, reference, theta):
        return edge_registration_of(self.model, theta)

    def applied(self, base, correction):
        return corrected(base, correction, self.model.pivot)


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
    - ``base_registration`` (4; a 3-D edge's pose and size, 7): the
      registration the probe found (zero without probing): the reference
      contour.
    - ``active`` (1): 1 while the spindle cuts (0 while probing: nothing
      is learned).
    - ``registration`` (as ``base_registration``): base + the correction
      (a 3-D edge's: composed), to the observer and the command
      generator.
    - ``registration_state`` (``layout``: ONLINE_STATE on a planar edge,
      :func:`online_state` of the model's size on a 3-D edge): the
      discrete state, for the logs.

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
        prior = config.probed_offset_prior if probed else config.offset_prior
        # The model, chosen once: a planar edge's or a 3-D edge's.
        kind = _EdgeModel if contour.varying_frame else _PlanarModel
        self._model = kind(contour, config, estimator, prior)
        self.layout = self._model.layout
        size = self._model.registration_size
        self._threshold = estimator.contact_force_threshold
        self._latency = latency
        T = config.sample_period
        self._forgetting = math.exp(-T / config.forgetting_time)
        self._lag = 1.0 - math.exp(-T / config.time_constant)
        self._state = self.DeclareDiscreteState(
            self.layout.pack(
                theta=self._model.theta0,
                covariance=self._model.P0.ravel(),
                correction=np.zeros(self._model.correction_size),
                onset=0.0,
                arc=0.0,
                last_arc=0.0,
            )
        )
        self._chamfer = self.DeclareVectorInputPort(
            "chamfer_state", CHAMFER_STATE.size
        )
        self._reference = RegisteredContour(
            self.DeclareVectorInputPort("base_registration", size)
        )
        self._base = self._reference.port
        self._active = self.DeclareVectorInputPort("active", 1)
        self.DeclarePeriodicDiscreteUpdateEvent(T, 0.0, self._update)
        self.DeclareVectorOutputPort(
            "registration",
            size,
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
        layout, model = self.layout, self._model
        x = context.get_discrete_state(self._state).get_value().copy()
        c = self._config
        reference, _ = self._reference(context, self._contour)
        base = self._base.Eval(context)
        x_p = CHAMFER_STATE.get(chamfer, "x_p")
        theta = layout.get(x, "theta")
        n = len(theta)
        P = layout.get(x, "covariance").reshape(n, n)
        noise = c.force_noise**2
        arc = float(reference.arc_position(x_p))
        if layout.get(x, "onset") < 0.5:
            # The entry: the real depth is how far the tool moved in before
            # the sensor showed the contact.
            speed = float(
                CHAMFER_STATE.get(chamfer, "xdot_p") @ reference.n1(x_p)
            )
            phi = model.onset(
                reference, x_p, max(speed, 0.0) * self._latency, base
            )
            theta, P = rls_update(
                theta, P, phi, 0.0, noise_var=noise, forgetting=1.0
            )
            x[layout.slice("onset")] = 1.0
        else:
            if model.learns(reference, x_p):
                theta, P = rls_update(
                    theta,
                    P,
                    model.regressor(reference, x_p, base),
                    f_n,
                    noise_var=noise,
                    forgetting=self._forgetting,
                )
            step = abs(arc - float(layout.get(x, "last_arc")))
            if reference.closed:
                step = min(step, reference.length - step)
            x[layout.slice("arc")] += step
        x[layout.slice("last_arc")] = arc
        x[layout.slice("theta")] = theta
        x[layout.slice("covariance")] = P.ravel()
        if layout.get(x, "arc") >= c.min_arc:
            correction = layout.get(x, "correction")
            target = model.target(reference, theta)
            x[layout.slice("correction")] = correction + np.clip(
                self._lag * (target - correction),
                -model.max_step,
                model.max_step,
            )
        discrete_state.set_value(self._state, x)

    def _calc_registration(self, context, output):
        x = context.get_discrete_state(self._state).get_value()
        output.SetFromVector(
            self._model.applied(
                self._base.Eval(context), self.layout.get(x, "correction")
            )
        )
