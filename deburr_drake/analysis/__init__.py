"""Closed-loop stability analysis of the deburring cell with Drake's tools:
the operating point in steady cutting, the continuous-time linearization
and its modes (eq. (8)'s depth time constant), the one-period map of the
2.5 ms sampled loop and its spectral radius, the normal-force loop's
margins, predicted against simulated stability limits, and stability
maps. Imports downward (math, systems, cell), never the command line."""

from deburr_drake.analysis.operating_point import (
    DEFAULT_TIME_AFTER_CONTACT, OperatingPoint, find_operating_point,
    frozen_scenario, get_field, set_field, transfer_state)
from deburr_drake.analysis.linearization import (
    ContinuousLinearization, Mode, classify_modes, continuous_state_slices,
    eq8_time_constant, linearize_closed_loop, numerical_jacobian)

__all__ = [
    "DEFAULT_TIME_AFTER_CONTACT", "OperatingPoint", "find_operating_point",
    "frozen_scenario", "get_field", "set_field", "transfer_state",
    "ContinuousLinearization", "Mode", "classify_modes",
    "continuous_state_slices", "eq8_time_constant", "linearize_closed_loop",
    "numerical_jacobian",
]
