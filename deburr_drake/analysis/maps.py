"""Stability maps: the sampled loop's spectral radius rho over a grid of
one or two scenario fields given by dotted name, drawn as a heat map with
the rho = 1 contour."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, List, Optional, Sequence

import numpy as np

from deburr_drake.analysis.operating_point import (
    OperatingPoint,
    frozen_scenario,
    get_field,
)
from deburr_drake.config import ConfigError, Scenario

__all__ = [
    "MapAxis",
    "StabilityMap",
    "parse_map",
    "parse_settings",
    "stability_map",
    "fast_rho",
    "plot_map",
    "field_unit",
    "rho_colour_norm",
]


def field_unit(scenario: Scenario, path: str) -> str:
    """The unit of a scenario field by dotted name, from its dataclass's
    comment by the configuration's convention
    (:func:`deburr_drake.config.reference.field_comments`,
    ``split_unit``): "" when there is none or it is ``-``; an element's
    unit for an indexed field whose elements differ (``[N, N/m, N s/m]``)."""
    from deburr_drake.config.reference import field_comments, split_unit

    parent_path, _, leaf = path.rpartition(".")
    name, _, index = leaf.partition("[")
    parent = get_field(scenario, parent_path) if parent_path else scenario
    try:
        comment = field_comments(type(parent)).get(name)
    except (OSError, TypeError):
        return ""
    if comment is None:
        return ""
    unit = split_unit(comment.trailing)[0] or split_unit(comment.block)[0]
    if unit.startswith("["):
        units = [u.strip() for u in unit[1:-1].split(",")]
        k = int(index.rstrip("]")) if index else -1
        unit = units[k] if index and -len(units) <= k < len(units) else ""
    return "" if unit == "-" else unit


def parse_settings(scenario: Scenario, specs: Sequence[str]):
    """``["controller.sliding_gain[0]=4500", ...]`` -> {field: value};
    ConfigError, one line, for a malformed spec, an unknown field or a
    value the scenario rejects."""
    out = {}
    for spec in specs:
        field, eq, value = spec.partition("=")
        if not eq:
            raise ConfigError(f"--set {spec!r}: expected FIELD=VALUE")
        get_field(scenario, field)
        try:
            out[field] = float(value)
        except ValueError:
            raise ConfigError(
                f"--set {spec!r}: VALUE must be a number"
            ) from None
    if out:
        frozen_scenario(scenario, **out)  # ConfigError if out of range
    return out


@dataclass
class MapAxis:
    field: str  # dotted scenario field, e.g. controller.sliding_gain[0]
    values: np.ndarray


def parse_map(scenario: Scenario, specs: Sequence[str]) -> List[MapAxis]:
    """``["sensor.cutoff_frequency=5:80:16", ...]`` (one or two) ->
    axes. ConfigError, one line, for an unknown field, a malformed spec,
    an empty range (N < 1, or LO = HI with N > 1) or a value the scenario
    rejects."""
    if not 1 <= len(specs) <= 2:
        raise ConfigError(
            f"--map takes one or two FIELD=LO:HI:N, got {len(specs)}"
        )
    axes = []
    for spec in specs:
        field, eq, rng = spec.partition("=")
        parts = rng.split(":")
        if not eq or len(parts) != 3:
            raise ConfigError(f"--map {spec!r}: expected FIELD=LO:HI:N")
        try:
            lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
        except ValueError:
            raise ConfigError(
                f"--map {spec!r}: LO, HI must be numbers and N an integer"
            ) from None
        current = get_field(scenario, field)
        if (
            isinstance(current, (list, dict))
            or not isinstance(current, (int, float))
            or isinstance(current, bool)
        ):
            raise ConfigError(
                f"--map {field!r} is not a numeric scenario field"
            )
        if (
            n < 1
            or (n > 1 and not hi > lo)
            or not (np.isfinite(lo) and np.isfinite(hi))
        ):
            raise ConfigError(
                f"--map {spec!r}: empty range (need LO < HI and N >= 1)"
            )
        values = np.linspace(lo, hi, n) if n > 1 else np.array([lo])
        for v in (values[0], values[-1]):
            frozen_scenario(scenario, **{field: v})  # ConfigError if bad
        axes.append(MapAxis(field, values))
    return axes


@dataclass
class StabilityMap:
    axes: List[MapAxis]
    rho: np.ndarray  # (n0,) or (n0, n1)
    scenario: str = ""
    units: dict = None  # field -> unit ("" none)

    def __post_init__(self):
        self.units = self.units or {}

    def to_dict(self):
        return {
            "fields": [a.field for a in self.axes],
            "units": [self.units.get(a.field, "") for a in self.axes],
            "values": [a.values.tolist() for a in self.axes],
            "rho": self.rho.tolist(),
        }


def _affine_coordinate(scenario: Scenario, field: str):
    """The coordinate in which the sample law is affine in ``field``, or
    None: the sensor's filter gain alpha = 1 - exp(-2 pi f_c T_s) for its
    cutoff (y += alpha (raw - y)), the gain itself for a sliding gain
    (f_tau = K s - f + ...)."""
    if field == "sensor.cutoff_frequency":
        Ts = scenario.sensor.sample_period
        return lambda f: 1.0 - np.exp(-2 * np.pi * f * Ts)
    if field.startswith("controller.sliding_gain["):
        return lambda k: k
    return None


def fast_rho(op: OperatingPoint, fields: Sequence[str], *, delta: float = 1e-9):
    """``rho_of(**overrides)`` for :func:`stability_map` that reuses what
    does not change between grid points, or None when a field is not one
    it knows. The one-period map is split at t_k + delta into the sample
    (the discrete updates at t_k: sensor, controller, process) and the
    integration over the rest of the period. The integration's map is
    taken once, at the operating point's own parameters (first order: the
    held actuation and reading move little between grid points at a
    steady operating point); the sample map is affine in the sensor's
    alpha and in the sliding gains (separate rows), so it is taken at the
    base and once per field, and each grid point costs one 48 x 48
    eigenvalue problem. Fixed-step scenarios only (None otherwise).
    On the paper arm at its 3 s operating point it matches the full map
    within 2e-5 at cutoffs 10-100 Hz and gains 400-6000 N s/m; 1 s after
    contact (less steady) it gives 1.50 against 1.42 at 60 Hz and
    5000 N s/m."""
    from deburr_drake.analysis.sampled import (
        frozen_cell,
        period_map,
        rest_of_period_map,
        simulator_config,
        spectral_radius,
    )

    coords = [_affine_coordinate(op.scenario, f) for f in fields]
    base = frozen_scenario(op.scenario)
    if any(c is None for c in coords) or base.simulation.error_control:
        # An error-controlled integrator steps differently over a split
        # period, so the pieces do not compose into the one-period map;
        # fixed steps (the paper's) compose exactly.
        return None
    period = base.controller.control_period
    config = simulator_config(base)

    diagram, context, entries = frozen_cell(op, {})
    sample0 = period_map(diagram, context, entries, period=delta, config=config)
    integrate = rest_of_period_map(
        diagram, context, entries, delta, period, config
    )
    slopes = []
    for field, coord in zip(fields, coords):
        v0 = float(get_field(op.scenario, field))
        v1 = v0 * 1.5 if v0 else 1.0
        d, c, e = frozen_cell(op, {field: v1})
        sample = period_map(d, c, e, period=delta, config=config)
        slopes.append(
            (
                field,
                coord,
                coord(v0),
                (sample - sample0) / (coord(v1) - coord(v0)),
            )
        )

    def rho_of(**overrides):
        S = sample0.copy()
        for field, coord, c0, slope in slopes:
            S += (coord(overrides[field]) - c0) * slope
        return spectral_radius(integrate @ S)

    return rho_of


def stability_map(
    op: OperatingPoint,
    axes: Sequence[MapAxis],
    *,
    rho_of: Optional[Callable[..., float]] = None,
    progress: Optional[Callable[[str], None]] = None,
) -> StabilityMap:
    """rho at every grid point, all from the one operating point (the
    simulation to steady cutting is done once); with fields
    :func:`fast_rho` knows, the maps are reused between grid points,
    otherwise each point rebuilds the diagram and its map."""
    from deburr_drake.analysis.sampled import sampled_loop

    if rho_of is None:
        rho_of = fast_rho(op, [a.field for a in axes])
    if rho_of is None:

        def rho_of(**overrides):
            return sampled_loop(op, **overrides).spectral_radius

    shape = tuple(len(a.values) for a in axes)
    rho = np.zeros(shape)
    for index in np.ndindex(*shape):
        overrides = {a.field: float(a.values[i]) for a, i in zip(axes, index)}
        rho[index] = rho_of(**overrides)
        if progress:
            progress(f"map {index}: rho = {rho[index]:.4f}")
    return StabilityMap(
        list(axes),
        rho,
        op.scenario.name,
        {a.field: field_unit(op.scenario, a.field) for a in axes},
    )


def rho_colour_norm(rho):
    """The colour scale of a stability map: centred on rho = 1 (the
    colour map's middle, yellow in RdYlGn_r), symmetric, wide enough for
    every value: a cell is green only if rho < 1."""
    from matplotlib.colors import TwoSlopeNorm

    spread = max(1e-3, float(np.max(np.abs(np.asarray(rho) - 1.0))))
    return TwoSlopeNorm(vcenter=1.0, vmin=1.0 - spread, vmax=1.0 + spread)


def plot_map(m: StabilityMap, path, *, boundaries=None, units=None):
    """Heat map of rho with the rho = 1 contour, the colour scale centred
    on rho = 1 (green below, red above; one field: rho against it), axes
    labelled with the fields' ``units`` (by field; "" none), simulated
    boundary points on top when given."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    units = units or m.units

    def label(field):
        unit = units.get(field, "")
        return f"{field} ({unit})" if unit else field

    fig, ax = plt.subplots(figsize=(6.5, 5))
    rho_label = "rho, spectral radius of the 2.5 ms map (-)"
    if len(m.axes) == 1:
        ax.plot(m.axes[0].values, m.rho, "o-")
        ax.axhline(1.0, color="r", lw=1, label="rho = 1")
        ax.set(xlabel=label(m.axes[0].field), ylabel=rho_label)
        for b in boundaries or []:
            if b["parameter"] == m.axes[0].field and b.get("simulated"):
                ax.axvline(
                    b["simulated"],
                    color="k",
                    ls="--",
                    label="simulated boundary",
                )
    else:
        x, y = m.axes[0].values, m.axes[1].values
        mesh = ax.pcolormesh(
            x,
            y,
            m.rho.T,
            shading="nearest",
            cmap="RdYlGn_r",
            norm=rho_colour_norm(m.rho),
        )
        fig.colorbar(mesh, ax=ax, label=rho_label + ", centred on 1")
        if m.rho.min() < 1 < m.rho.max():
            ax.contour(x, y, m.rho.T, levels=[1.0], colors="k")
        ax.set(xlabel=label(m.axes[0].field), ylabel=label(m.axes[1].field))
        for b in boundaries or []:
            if b["parameter"] == m.axes[0].field and b.get("simulated"):
                ax.axvline(b["simulated"], color="k", ls="--")
            if b["parameter"] == m.axes[1].field and b.get("simulated"):
                ax.axhline(b["simulated"], color="k", ls="--")
    ax.set_title(
        f"{m.scenario}: stability of the sampled loop (rho < 1 stable)"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
