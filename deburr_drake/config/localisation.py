"""Configuration of localisation: touch probing before the pass
(``localisation.probe``) and registration while cutting
(``localisation.online``). Both are off by default; the ``paper_localised``
scenario turns both on. SI units; each field's comment gives its unit."""

from dataclasses import dataclass, field
import math

from deburr_drake.config.checks import _non_negative, _positive, _require

__all__ = ["ProbeConfig", "OnlineRegistrationConfig", "LocalisationConfig"]


@dataclass
class ProbeConfig:
    """Touch probing with the spindle off: guarded moves along the believed
    normal n1 at ``points`` places of the edge, contact detected on the
    force sensor, a circle (centre and radius), a straight edge (offset,
    heading) or a profile (move, turn and, where the touches tell it,
    size) fitted, touches on a burr dropped (they come early), and the
    believed part corrected before the pass."""

    enabled: bool = False  # -, touch probing before the pass
    points: int = 8  # -, number of touches
    # m, arc between touches; 0: spread evenly over the edge (a closed
    # edge: L / N apart; an open one: centred, L / N apart; a profile:
    # L / N apart, shifted from first_arc by up to L / N where they best
    # fix its move and turn, control/probe.py probe_arcs).
    spacing: float = 0.0
    first_arc: float = 0.0  # m, arc position of the first touch (closed edge)
    approach_speed: float = 0.002  # m/s, the guarded move along n1
    travel_speed: float = 0.02  # m/s, between touches at the standoff
    # m/s, a mesh part's moves between touches: out along the face's
    # normal, above the part and down to the next standoff, clear of it
    clear_travel_speed: float = 0.15
    # m/s, a mesh part: the same moves from the last touch to the pass's
    # start: where they stop the arm's friction holds the tool, up to
    # 0.9 mm off the command along the entry after 0.15 m/s, and the
    # entry cuts that much deeper (docs/part-errors.md)
    entry_travel_speed: float = 0.08
    # s, a mesh part: held at a touch's standoff after that move before
    # the tare (the arm rings for longer after it than after a travel
    # along the edge; docs/part-errors.md has the ringing measured)
    clear_settle_time: float = 0.2
    # m/s, a mesh part: each touch first finds the face fast (a smooth
    # move along the normal, up to 1.5 times this mean speed about the
    # middle of its search), backs off it and measures it with the
    # guarded move at approach_speed; 0: the guarded move alone, from the
    # standoff
    find_speed: float = 0.015
    # m, the tool (its measured point) off the face the find touch found
    # before the measuring touch: its run-up to the approach speed (the
    # detection bias is qualified on a long one; docs/part-errors.md)
    find_backoff: float = 0.0006
    # s, held after the back-off before the measuring touch's tare (the
    # arm rings after the find touch)
    find_settle_time: float = 0.2
    # m, a mesh part: how far its pose may be off along each axis (its
    # frame's origin); each touch's standoff and search grow by what that
    # can move its face along the normal
    pose_offset_allowance: float = 0.001
    # rad, a mesh part: how far its pose may be turned about each axis,
    # the same way
    pose_turn_allowance: float = 0.0175
    force_threshold: float = 1.0  # N, contact when -f . n1 exceeds it
    standoff: float = (
        0.002  # m, the guarded move starts this far before the believed edge
    )
    search_distance: float = (
        0.004  # m, the guarded move gives up after this (a miss)
    )
    retract: float = 0.002  # m, back from the touch before travelling
    settle_time: float = (
        0.15  # s, held at the standoff before each guarded move
    )
    # N, the guarded move goes on past force_threshold to this force; the
    # way between the two gives the stiffness of the contact touched
    # (control/probe.py measured_stiffness), the depth at detection is
    # modelled with it. 0: stop at force_threshold, contact_stiffness.
    stiffness_threshold: float = 3.0
    # -, n of the contact's law F = c depth^n exp(-b depth), whose local
    # exponent n - b depth falls with depth, so a soft part, touched
    # deeper, is not read with the exponent of a stiff one (1 with b 0: a
    # linear contact). The defaults are the hydroelastic ring's under the
    # cutter, fitted to cell/part.py measure_normal_force
    # (docs/numerics.md).
    contact_exponent: float = 1.54
    # 1/m, b: how fast the local exponent falls with depth
    contact_exponent_slope: float = 412.0
    # N/m, the contact stiffness (threshold / depth at the threshold) the
    # detection depth is modelled with when the touches measured none.
    contact_stiffness: float = 5.0e3
    # -, fit the part's size where the touches can tell it: a circle's
    # radius (touches over more than a half circle), a profile's uniform
    # growth (5 or more touches on sides facing apart); a straight edge
    # has no size. false: the drawing's size (math/registration.py
    # registration_from_points).
    fit_radius: bool = True
    # m, how far past the zero-depth path along n1 a touch still lies
    # once the modelled detection depth is taken off: the probe's
    # qualification on a ring of known radius (fitted minus true radius,
    # runs/probe_study.py probe_qualification); taken off every touch.
    detection_bias: float = -10.3e-6
    # m, a mesh part: the error of one compensated touch along its face's
    # normal that the detection model leaves (its spread by face and
    # approach direction): the RMS distance of the touches from the real
    # part over 4 random runs of studies/cad_inclined_hole.yaml with the
    # single touch (32 touches; hole wall 33 um, faces 15 um). The
    # registration's covariance takes no smaller per-touch error.
    touch_error: float = 23.0e-6
    # m, a touch off the circle, line or profile most touches agree on by
    # more is dropped: a burr under it (math.fits.fit_consensus)
    max_residual: float = (
        5.0e-5  # m, a touch off the consensus fit by more is dropped
    )
    # s, after probing the controller's fuzzy compensator (off while
    # probing) ramps back in over this time, so weights learned on an
    # earlier part (a batch) do not push the tool along before the cut is
    # established; 0: at once.
    fuzzy_ramp_time: float = 2.0
    # s, after probing the feed waits at the start (the command generator
    # holds) until the cut reaches 0.9 of the desired depth
    # (control.probe.CUT_ESTABLISHED), at most this long; 0: no dwell.
    entry_dwell: float = 3.0  # s, longest wait at the entry for the cut's depth

    def validate(self):
        o = "localisation.probe"
        _require(
            isinstance(self.enabled, bool),
            f"{o}.enabled",
            self.enabled,
            "true or false",
        )
        _require(
            isinstance(self.points, int) and self.points >= 3,
            f"{o}.points",
            self.points,
            "an integer >= 3",
        )
        _non_negative(o, "spacing", self.spacing)
        _non_negative(o, "first_arc", self.first_arc)
        for name in (
            "approach_speed",
            "travel_speed",
            "clear_travel_speed",
            "entry_travel_speed",
            "force_threshold",
            "standoff",
            "search_distance",
            "retract",
            "contact_stiffness",
            "contact_exponent",
            "max_residual",
        ):
            _positive(o, name, getattr(self, name))
        _non_negative(o, "settle_time", self.settle_time)
        _non_negative(o, "clear_settle_time", self.clear_settle_time)
        _non_negative(o, "find_speed", self.find_speed)
        _positive(o, "find_backoff", self.find_backoff)
        _non_negative(o, "find_settle_time", self.find_settle_time)
        _non_negative(o, "pose_offset_allowance", self.pose_offset_allowance)
        _non_negative(o, "pose_turn_allowance", self.pose_turn_allowance)
        _non_negative(o, "contact_exponent_slope", self.contact_exponent_slope)
        _non_negative(o, "touch_error", self.touch_error)
        _require(
            isinstance(self.stiffness_threshold, (int, float))
            and math.isfinite(self.stiffness_threshold)
            and (
                self.stiffness_threshold == 0
                or self.stiffness_threshold > self.force_threshold
            ),
            f"{o}.stiffness_threshold",
            self.stiffness_threshold,
            f"0 or > {o}.force_threshold ({self.force_threshold}) N",
        )
        _require(
            isinstance(self.detection_bias, (int, float))
            and abs(self.detection_bias) < self.search_distance,
            f"{o}.detection_bias",
            self.detection_bias,
            f"a number of magnitude < {o}.search_distance "
            f"({self.search_distance}) m",
        )
        _non_negative(o, "fuzzy_ramp_time", self.fuzzy_ramp_time)
        _non_negative(o, "entry_dwell", self.entry_dwell)
        _require(
            self.search_distance > self.standoff,
            f"{o}.search_distance",
            self.search_distance,
            f"> {o}.standoff ({self.standoff})",
        )
        _require(
            isinstance(self.fit_radius, bool),
            f"{o}.fit_radius",
            self.fit_radius,
            "true or false",
        )


@dataclass
class OnlineRegistrationConfig:
    """Registration while cutting: the part of the offset the force loop
    can tell apart from the contact threshold (around a circle the first
    harmonic of the offset, along a straight edge the heading) estimated by
    recursive least squares together with c0 and c1 (from the contact
    onset at the entry as well), and the believed part moved smoothly
    towards the estimate."""

    enabled: bool = False  # -, registration while cutting
    sample_period: float = 0.025  # s, the RLS update's period
    forgetting_time: float = 60.0  # s, RLS exponential forgetting horizon
    # Prior standard deviation of the offset (m; c0 and c1 start from
    # estimator.initial_estimates with their own size as prior).
    offset_prior: float = 0.001  # m, without probing (the fixture's)
    probed_offset_prior: float = 5.0e-5  # m, after probing (the probe's)
    # N, the RLS measurement's standard deviation: the sensor's noise and
    # what the linear contact model leaves (the force loop's transients).
    force_noise: float = 1.0
    # The believed part moves towards the estimate with this time constant
    # (s), no faster than ``max_rate`` (m/s): no step in the command.
    time_constant: float = (
        1.0  # s, the believed part's approach to the estimate
    )
    max_rate: float = 0.0005  # m/s, the believed part's fastest move
    # The estimate is used only after the tool has cut this much arc
    # (m): a short arc does not separate the offset from c0.
    min_arc: float = 0.0  # m, arc cut before the estimate is used

    def validate(self):
        o = "localisation.online"
        _require(
            isinstance(self.enabled, bool),
            f"{o}.enabled",
            self.enabled,
            "true or false",
        )
        for name in (
            "sample_period",
            "forgetting_time",
            "offset_prior",
            "probed_offset_prior",
            "force_noise",
            "time_constant",
            "max_rate",
        ):
            _positive(o, name, getattr(self, name))
        _non_negative(o, "min_arc", self.min_arc)


@dataclass
class LocalisationConfig:
    probe: ProbeConfig = field(default_factory=ProbeConfig)
    online: OnlineRegistrationConfig = field(
        default_factory=OnlineRegistrationConfig
    )

    @property
    def enabled(self) -> bool:
        return self.probe.enabled or self.online.enabled

    def validate(self):
        self.probe.validate()
        self.online.validate()
