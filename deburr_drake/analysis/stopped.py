"""What ``analyze`` says before and instead of an analysis: its own
options checked before anything is simulated, and, for a scenario that
never reaches steady cutting, what stopped it (a guard with its values, a
NaN, an error, and when) instead of "no operating point"."""

from __future__ import annotations

import math

from deburr_drake.analysis.operating_point import (
    DEFAULT_TIME_AFTER_CONTACT, MAX_TIME_TO_CONTACT)
from deburr_drake.config import ConfigError, Scenario

__all__ = ["check_analyze_options", "explain_no_operating_point"]


def check_analyze_options(*, at=None, after_contact=DEFAULT_TIME_AFTER_CONTACT,
                          lyapunov=None):
    """ConfigError, one line naming the option, for ``--at`` not > 0,
    ``--after-contact`` not >= 0, ``--lyapunov`` not > 0 (all finite):
    before anything is simulated or written."""
    def finite(x):
        return isinstance(x, (int, float)) and math.isfinite(x)
    if at is not None and not (finite(at) and at > 0):
        raise ConfigError(f"--at = {at!r} is invalid: allowed a finite time "
                          "> 0 s")
    if not (finite(after_contact) and after_contact >= 0):
        raise ConfigError(f"--after-contact = {after_contact!r} is invalid: "
                          "allowed a finite number >= 0 s")
    if lyapunov is not None and not (finite(lyapunov) and lyapunov > 0):
        raise ConfigError(f"--lyapunov = {lyapunov!r} is invalid: allowed a "
                          "finite duration > 0 s")


def explain_no_operating_point(scenario: Scenario, error: Exception, *,
                               at=None,
                               after_contact=DEFAULT_TIME_AFTER_CONTACT
                               ) -> ConfigError:
    """The error to give when the analysis found no operating point: if the
    scenario's own run stops (a guard, NaN, an error) before the operating
    point's time, that, with its values and time; otherwise ``error``. Runs
    the scenario as ``simulate`` would, up to the time the operating point
    would have been taken. ``error``: what the analysis raised (a
    ConfigError saying "no operating point", or a RuntimeError from the
    simulation, e.g. a NaN)."""
    if isinstance(error, ConfigError) and \
            "no operating point" not in str(error):
        return error
    from deburr_drake.cell.diagram import make_deburring_diagram
    from deburr_drake.runs.simulation import simulate
    horizon = at if at is not None else MAX_TIME_TO_CONTACT + after_contact
    horizon = min(horizon, scenario.simulation.duration)
    log = simulate(make_deburring_diagram(scenario=scenario), scenario,
                   duration=horizon)
    if log.stop_reason in ("duration", "pass_complete"):
        return error
    detail = f" ({log.stop_detail})" if log.stop_detail else ""
    return ConfigError(
        f"scenario '{scenario.name}' never reaches steady cutting: its run "
        f"stopped at t = {log.stop_time:.3f} s by {log.stop_reason}{detail}:"
        " no operating point to analyse")
