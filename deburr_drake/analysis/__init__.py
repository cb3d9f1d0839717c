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
from deburr_drake.analysis.sampled import (
    SampledLoop, StateEntry, cell_map_entries, period_map, sampled_loop,
    simulator_config, spectral_radius)
from deburr_drake.analysis.frequency import (
    NormalForceLoop, frequency_response, loop_from_map, margins,
    normal_force_loop, plot_bode_nyquist)
from deburr_drake.analysis.maps import (
    MapAxis, StabilityMap, fast_rho, parse_map, parse_settings, plot_map,
    stability_map)
from deburr_drake.analysis.validation import (
    PARAMETERS, Parameter, add_fuzzy_slope, predicted_boundary,
    simulated_boundary, simulated_growth, validate_boundaries)
from deburr_drake.analysis.lyapunov import (
    LyapunovTrace, lyapunov_trace, plot_lyapunov)
# The pre-flight's function is deburr_drake.analysis.preflight.preflight
# (not exported here: the name would hide its module).
from deburr_drake.analysis.preflight import (
    GAIN_MARGIN, GainMaps, Preflight, start_operating_point)
from deburr_drake.analysis.stopped import (check_analyze_options,
                                           explain_no_operating_point)
from deburr_drake.analysis.report import (
    SUMMARY_KEYS, analyze, plot_poles, summary_text, write_analysis)

__all__ = [
    "DEFAULT_TIME_AFTER_CONTACT", "OperatingPoint", "find_operating_point",
    "frozen_scenario", "get_field", "set_field", "transfer_state",
    "ContinuousLinearization", "Mode", "classify_modes",
    "continuous_state_slices", "eq8_time_constant", "linearize_closed_loop",
    "numerical_jacobian",
    "SampledLoop", "StateEntry", "cell_map_entries", "period_map",
    "sampled_loop", "simulator_config", "spectral_radius",
    "NormalForceLoop", "frequency_response", "loop_from_map", "margins",
    "normal_force_loop", "plot_bode_nyquist",
    "MapAxis", "StabilityMap", "fast_rho", "parse_map", "parse_settings", "plot_map", "stability_map",
    "PARAMETERS", "Parameter", "add_fuzzy_slope", "predicted_boundary",
    "simulated_boundary", "simulated_growth", "validate_boundaries",
    "LyapunovTrace", "lyapunov_trace", "plot_lyapunov",
    "GAIN_MARGIN", "GainMaps", "Preflight",
    "start_operating_point", "check_analyze_options",
    "explain_no_operating_point",
    "SUMMARY_KEYS", "analyze", "plot_poles", "summary_text",
    "write_analysis",
]
