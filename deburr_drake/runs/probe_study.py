"""Studies of touch probing, each run probing only (the pass is
not cut: the run stops once the sequence is done):

- :func:`probe_once`: one probing of a scenario; the registration found
  against the truth (minus ``part_error``);
- :func:`probe_accuracy`: the centre error against the number of touches
  and the sensor's noise, part errors drawn within a disc;
- :func:`probe_qualification`: in the spirit of ISO 10360-5, the same
  reference ring probed ``repeats`` times (noise seeds differ), centre and
  radius fitted: the errors of both. With ``detection_bias`` 0 (the
  default here) the mean radius error is the detection bias the model
  leaves: the value ``localisation.probe.detection_bias`` calibrates.

``scripts/probe_study.py`` runs them and prints the tables.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
import math
from typing import Dict, List, Sequence

import numpy as np

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.cell.edge import believed_contour, make_contour
from deburr_drake.config import Scenario
from deburr_drake.control.probe import PROBE_STATE
from deburr_drake.runs.simulation import simulate

__all__ = [
    "ProbeResult",
    "probe_once",
    "probe_accuracy",
    "probe_qualification",
    "probing_duration",
    "summarize",
    "refit_touches",
]


@dataclass
class ProbeResult:
    points: int
    noise_std: float  # N
    offset: np.ndarray  # m, part_error.offset (believed - real)
    registration: np.ndarray  # dx, dy, dyaw, dradius found
    touches: int
    kept: int
    fit_rms: float  # m
    probing_time: float  # s, nan when it did not finish
    radius_offset: float = 0.0  # m, part_error.radius (believed - real)

    @property
    def centre_error(self) -> np.ndarray:
        """m: found minus true (the real part is the believed one moved by
        minus ``offset``)."""
        return self.registration[:2] + self.offset[:2]

    @property
    def radius_error(self) -> float:
        """m: the fitted radius minus the real one (with the radius
        fitted; 0 when it was held)."""
        return float(self.registration[3] + self.radius_offset)


def probing_duration(scenario: Scenario) -> float:
    """s: a bound on the probing time of ``scenario`` (each touch: the
    travel from the touch before, settle, the whole search, retract; then
    the way back and the entry)."""
    p = scenario.localisation.probe
    contour = make_contour(scenario)
    spacing = p.spacing or contour.length / p.points
    per = (
        spacing / p.travel_speed * 1.5
        + 0.1
        + p.settle_time
        + p.search_distance / p.approach_speed
        + p.retract / p.travel_speed * 1.5
        + 0.1
    )
    back = spacing if contour.closed else spacing * p.points
    return (
        p.points * per
        + back / p.travel_speed * 1.5
        + p.standoff / p.approach_speed
        + 1.0
    )


def probe_once(scenario: Scenario) -> ProbeResult:
    """Probes ``scenario`` (its probe enabled, registration while cutting
    off) and returns what the probe found."""
    s = copy.deepcopy(scenario)
    s.localisation.probe.enabled = True
    s.localisation.online.enabled = False
    s.simulation.stop_after_passes = 0.0
    s.validate()
    seen = {}

    def capture(diagram, context):
        seen["probe"] = diagram.GetSubsystemByName("probing_sequence")
        seen["context"] = seen["probe"].GetMyContextFromRoot(context)

    def probed():
        x = seen["context"].get_discrete_state(0).get_value()
        return "probed" if PROBE_STATE.get(x, "done_time") >= 0 else None

    log = simulate(
        make_deburring_diagram(scenario=s),
        s,
        duration=probing_duration(s),
        loggers=["probe"],
        initial_state=capture,
        should_stop=probed,
    )
    # The sequence's state where the run stopped (the log's last sample
    # may be one before the update that finished it).
    last = (
        seen["context"].get_discrete_state(0).get_value()
        if "context" in seen
        else log["probe"]["value"][-1]
    )
    done = float(PROBE_STATE.get(last, "done_time"))
    return ProbeResult(
        points=s.localisation.probe.points,
        noise_std=s.sensor.noise_std,
        offset=np.array(s.part_error.offset, float),
        registration=np.array(PROBE_STATE.get(last, "registration")),
        touches=int(PROBE_STATE.get(last, "touches")),
        kept=int(PROBE_STATE.get(last, "kept")),
        fit_rms=float(PROBE_STATE.get(last, "fit_rms")),
        probing_time=done if done >= 0 else float("nan"),
        radius_offset=float(s.part_error.radius)
        if s.localisation.probe.fit_radius
        else 0.0,
    )


def probe_accuracy(
    scenario: Scenario,
    *,
    points: Sequence[int],
    noise: Sequence[float],
    repeats: int,
    max_offset: float,
    seed: int = 0,
) -> List[ProbeResult]:
    """Every (N, noise) ``repeats`` times, each repeat with its own part
    offset (uniform over a disc of ``max_offset``) and noise seed; the same
    offsets for every (N, noise)."""
    rng = np.random.default_rng(seed)
    draws = []
    for k in range(repeats):
        r = max_offset * math.sqrt(rng.uniform())
        a = rng.uniform(0, 2 * math.pi)
        draws.append(
            (
                [r * math.cos(a), r * math.sin(a), 0.0],
                int(rng.integers(1, 1_000_000)),
            )
        )
    out = []
    for n in points:
        for sigma in noise:
            for offset, noise_seed in draws:
                s = copy.deepcopy(scenario)
                s.localisation.probe.points = int(n)
                s.sensor.noise_std = float(sigma)
                s.sensor.noise_seed = noise_seed
                s.part_error.offset = list(offset)
                out.append(probe_once(s))
    return out


def probe_qualification(
    scenario: Scenario,
    *,
    repeats: int = 25,
    seed: int = 0,
    detection_bias: float = 0.0,
) -> List[ProbeResult]:
    """The reference ring (no part error) probed ``repeats`` times with
    the radius fitted, each with its own noise seed, every touch
    corrected by ``detection_bias`` (m; 0: the raw probe, whose mean
    radius error is the bias to calibrate; the configured one: what the
    calibration leaves)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(repeats):
        s = copy.deepcopy(scenario)
        s.part_error.offset = [0.0, 0.0, 0.0]
        s.part_error.yaw = 0.0
        s.part_error.radius = 0.0
        s.localisation.probe.fit_radius = True
        s.localisation.probe.detection_bias = float(detection_bias)
        s.sensor.noise_seed = int(rng.integers(1, 1_000_000))
        out.append(probe_once(s))
    return out


def summarize(results: List[ProbeResult]) -> Dict[str, float]:
    """Centre error per axis (std, mm), its norm (RMS and max, mm), the
    radius error (mean and std, mm), the fit RMS (mean, um), touches kept
    and probing time (mean, s)."""
    e = np.array([r.centre_error for r in results]) * 1e3
    norm = np.linalg.norm(e, axis=1)
    rad = np.array([r.radius_error for r in results]) * 1e3
    return {
        "runs": len(results),
        "centre_std_x_mm": float(np.std(e[:, 0])),
        "centre_std_y_mm": float(np.std(e[:, 1])),
        "centre_error_rms_mm": float(np.sqrt(np.mean(norm**2))),
        "centre_error_max_mm": float(np.max(norm)),
        "radius_error_mean_mm": float(np.mean(rad)),
        "radius_error_std_mm": float(np.std(rad)),
        "fit_rms_mean_um": float(np.mean([r.fit_rms for r in results]) * 1e6),
        "kept_mean": float(np.mean([r.kept for r in results])),
        "probing_time_mean_s": float(
            np.nanmean([r.probing_time for r in results])
        ),
    }


def refit_touches(
    scenario: Scenario, touch_points, thresholds: Sequence[float]
) -> List[Dict[str, float]]:
    """The probe's fit redone on a run's recorded touches (its
    ``touch_points`` log's last row, N x 4: x, y, z, made) with each
    ``max_residual`` of ``thresholds`` (m): the touches kept and the
    registration's error against the real edge (m,
    runs.pass_metrics.registration_error). What a threshold would have
    done, without running the cell again."""
    from deburr_drake.math.registration import registration_from_points
    from deburr_drake.runs.pass_metrics import registration_error

    t = np.asarray(touch_points, float).reshape(-1, 4)
    points = t[t[:, 3] > 0.5, :3]
    believed = believed_contour(scenario)
    out = []
    for threshold in thresholds:
        fit = registration_from_points(
            believed,
            points,
            max_residual=float(threshold),
            fit_radius=scenario.localisation.probe.fit_radius,
        )
        out.append(
            {
                "max_residual": float(threshold),
                "touches": int(len(points)),
                "kept": int(fit.kept.sum()),
                "error": registration_error(scenario, fit.registration),
                "fit_rms": fit.rms,
            }
        )
    return out
