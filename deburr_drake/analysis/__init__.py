"""Closed-loop stability analysis of the deburring cell with Drake's tools:
the verdict on the scenario's run (settled into steady cutting, or an
oscillation with its frequency, growth and the guard that would stop it),
the operating point in steady cutting, the 2.5 ms map along the run and
over the uncertain parameters' ranges, the continuous-time linearization
and its modes (eq. (8)'s depth time constant), the one-period map of the
2.5 ms sampled loop and its spectral radius, the normal-force loop's
margins, predicted against simulated stability limits, and stability
maps. Imports downward (math, systems, cell), never the command line."""

from deburr_drake.analysis.along import (
    DEFAULT_SPACING,
    AnalysisRun,
    RhoPoint,
    analysis_run,
    guard_that_would_stop,
    plot_rho_along_run,
    rho_of_map,
    without_guards,
)
from deburr_drake.analysis.analyze_run import SUMMARY_KEYS, analyze
from deburr_drake.analysis.box_certificate import certificate_summary, certify
from deburr_drake.analysis.certificate import Certificate, certify_family
from deburr_drake.analysis.frequency import (
    NormalForceLoop,
    frequency_response,
    loop_from_map,
    margins,
    normal_force_loop,
    plot_bode_nyquist,
)
from deburr_drake.analysis.linearization import (
    ContinuousLinearization,
    Mode,
    classify_modes,
    continuous_state_slices,
    eq8_time_constant,
    linearize_closed_loop,
    numerical_jacobian,
)
from deburr_drake.analysis.lyapunov import (
    LyapunovTrace,
    lyapunov_trace,
    plot_lyapunov,
)
from deburr_drake.analysis.maps import (
    MapAxis,
    StabilityMap,
    fast_rho,
    field_unit,
    parse_map,
    parse_settings,
    plot_map,
    stability_map,
)
from deburr_drake.analysis.operating_point import (
    DEFAULT_TIME_AFTER_CONTACT,
    OperatingPoint,
    find_operating_point,
    frozen_scenario,
    get_field,
    set_field,
    transfer_state,
)

# The pre-flight's function is deburr_drake.analysis.preflight.preflight
# (not exported here: the name would hide its module).
from deburr_drake.analysis.preflight import (
    GAIN_MARGIN,
    GainMaps,
    Preflight,
    start_operating_point,
)
from deburr_drake.analysis.report import (
    plot_poles,
    summary_text,
    write_analysis,
)
from deburr_drake.analysis.robust import (
    UNCERTAIN_PARAMETERS,
    UncertainParameter,
    robust_margin,
)
from deburr_drake.analysis.sampled import (
    FrozenMap,
    SampledLoop,
    StateEntry,
    cell_map_entries,
    period_map,
    sampled_loop,
    simulator_config,
    spectral_radius,
)
from deburr_drake.analysis.settled import (
    RunSignals,
    SettleCheck,
    SettleTolerances,
    describe_oscillation,
    fast_part,
    first_guard_trip,
    scan_run,
    settle_check,
)
from deburr_drake.analysis.validation import (
    PARAMETERS,
    VERDICT_SCENARIOS,
    Parameter,
    add_fuzzy_slope,
    predicted_boundary,
    simulated_boundary,
    simulated_growth,
    simulated_verdict,
    validate_boundaries,
    verdict_row,
)

__all__ = [
    "DEFAULT_TIME_AFTER_CONTACT",
    "Certificate",
    "certify_family",
    "certify",
    "certificate_summary",
    "OperatingPoint",
    "find_operating_point",
    "frozen_scenario",
    "get_field",
    "set_field",
    "transfer_state",
    "ContinuousLinearization",
    "Mode",
    "classify_modes",
    "continuous_state_slices",
    "eq8_time_constant",
    "linearize_closed_loop",
    "numerical_jacobian",
    "SampledLoop",
    "StateEntry",
    "cell_map_entries",
    "period_map",
    "sampled_loop",
    "simulator_config",
    "spectral_radius",
    "NormalForceLoop",
    "frequency_response",
    "loop_from_map",
    "margins",
    "normal_force_loop",
    "plot_bode_nyquist",
    "MapAxis",
    "StabilityMap",
    "fast_rho",
    "parse_map",
    "parse_settings",
    "plot_map",
    "stability_map",
    "field_unit",
    "PARAMETERS",
    "Parameter",
    "add_fuzzy_slope",
    "predicted_boundary",
    "simulated_boundary",
    "simulated_growth",
    "validate_boundaries",
    "VERDICT_SCENARIOS",
    "simulated_verdict",
    "verdict_row",
    "LyapunovTrace",
    "lyapunov_trace",
    "plot_lyapunov",
    "GAIN_MARGIN",
    "GainMaps",
    "Preflight",
    "start_operating_point",
    "RunSignals",
    "SettleCheck",
    "SettleTolerances",
    "describe_oscillation",
    "fast_part",
    "first_guard_trip",
    "scan_run",
    "settle_check",
    "DEFAULT_SPACING",
    "AnalysisRun",
    "RhoPoint",
    "analysis_run",
    "guard_that_would_stop",
    "plot_rho_along_run",
    "rho_of_map",
    "without_guards",
    "UNCERTAIN_PARAMETERS",
    "UncertainParameter",
    "robust_margin",
    "FrozenMap",
    "SUMMARY_KEYS",
    "analyze",
    "plot_poles",
    "summary_text",
    "write_analysis",
]
