"""Stability of the sampled loop: the one-period map of the 2.5 ms inner
loop at the operating point, by finite differences through Drake's
Simulator on the real (sampled) diagram, and its spectral radius rho.

The map runs from just before a sample at t_k (the discrete updates due at
t_k pending, as ``Simulator.AdvanceTo(t_k)`` leaves them) to just before
the next one: at t_k the controller samples its law and holds the
actuation, the sensor samples and filters its reading, the cutting process
samples the tool's place on the edge; then the plant (hydroelastic
contact, cenic as the scenario configures it) integrates over T. Its state
is every value carried across t_k that the loop reads: the plant's
[q, v], delta_d, the sensor's filter (3), the held actuation (read at t_k
through the weld's reaction force) and the process's force-law terms. The
adaptation and the outer loop are frozen (see
:mod:`deburr_drake.analysis.operating_point`): their states are not
perturbed, and with ``adapt: false`` they do not move. Each column is a
central difference of two one-period simulations from the perturbed
Context. rho = max |eig| < 1: locally stable.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import List, Sequence

import numpy as np
from pydrake.systems.analysis import (
    ApplySimulatorConfig,
    InitializeParams,
    Simulator,
    SimulatorConfig,
)
from pydrake.systems.framework import Context, Diagram
import scipy.linalg

from deburr_drake.analysis.operating_point import (
    OperatingPoint,
    frozen_scenario,
    transfer_state,
)
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import Scenario
from deburr_drake.runs.simulation import set_monitor

__all__ = [
    "StateEntry",
    "period_map",
    "spectral_radius",
    "SampledLoop",
    "sampled_loop",
    "cell_map_entries",
    "simulator_config",
    "FrozenMap",
]


@dataclass(frozen=True)
class StateEntry:
    """A block of a subsystem's state: ``kind`` "continuous" (``group``
    ignored) or "discrete" (group index), ``indices`` within it (None:
    all), perturbed by ``step``. ``central`` False: its columns are
    one-sided differences (one simulation each instead of two), for an
    entry the period's map is affine in to within the central
    difference's own error (docs/stability-measurements.md)."""

    system: str
    kind: str
    group: int = 0
    indices: tuple = None
    step: float = 1e-6
    label: str = ""
    central: bool = True

    def subcontext(self, diagram: Diagram, context: Context) -> Context:
        """This entry's subsystem's context within root ``context``."""
        return diagram.GetSubsystemByName(
            self.system
        ).GetMyMutableContextFromRoot(context)

    def _mutable(self, sub: Context):
        if self.kind == "continuous":
            return sub.get_mutable_continuous_state_vector()
        return sub.get_mutable_discrete_state(self.group)

    def read(self, sub: Context) -> np.ndarray:
        """The entry's values in its subsystem's context ``sub``."""
        if self.kind == "continuous":
            v = sub.get_continuous_state_vector().CopyToVector()
        else:
            v = sub.get_discrete_state(self.group).CopyToVector()
        return v if self.indices is None else v[list(self.indices)]

    def write(self, sub: Context, values):
        """Sets the entry's values in its subsystem's context ``sub``."""
        vector = self._mutable(sub)
        if self.indices is None:
            vector.SetFromVector(values)
            return
        v = vector.CopyToVector()
        v[list(self.indices)] = values
        vector.SetFromVector(v)

    def get(self, diagram, context) -> np.ndarray:
        return self.read(self.subcontext(diagram, context))

    def set(self, diagram, context, values):
        self.write(self.subcontext(diagram, context), values)


def simulator_config(scenario: Scenario) -> SimulatorConfig:
    sim = scenario.simulation
    return SimulatorConfig(
        integration_scheme=sim.integrator,
        max_step_size=sim.max_step,
        accuracy=sim.accuracy,
        use_error_control=sim.error_control,
    )


def _read(entries, diagram, context):
    return np.concatenate([e.get(diagram, context) for e in entries])


def _write(entries, diagram, context, z):
    k = 0
    for e in entries:
        n = e.get(diagram, context).size
        e.set(diagram, context, z[k : k + n])
        k += n


class _OnePeriod:
    """Simulations of one period from ``context0`` with the entries set
    to z, each from a fresh simulator (cenic carries its state from one
    run to the next) on one working context, its state reset from
    ``context0``."""

    def __init__(self, diagram, context0, entries, period, config):
        self.diagram, self.context0 = diagram, context0
        self.entries, self.period = entries, period
        self.config = copy.copy(config)
        # ApplySimulatorConfig sets the context's time to start_time.
        self.config.start_time = context0.get_time()
        self.simulator = Simulator(diagram, context0.Clone())
        # (with cenic, the plant's cache fresh after each step, as in a run)
        set_monitor(self.simulator, diagram, config.integration_scheme)
        # Each entry's subsystem context in the working context and its
        # slice of z, found once.
        context = self.simulator.get_mutable_context()
        subs = [e.subcontext(diagram, context) for e in entries]
        self.z0 = np.concatenate([e.read(s) for e, s in zip(entries, subs)])
        sizes = [e.read(s).size for e, s in zip(entries, subs)]
        self._targets = [
            (e, sub, slice(end - n, end))
            for e, sub, end, n in zip(entries, subs, np.cumsum(sizes), sizes)
        ]

    def _reset(self, context):
        """``context0``'s time and state into ``context`` (the parameters,
        which a period does not change, are cloned once: copying the
        plant's costs more than the integration)."""
        source = self.context0
        context.SetTime(source.get_time())
        context.get_mutable_continuous_state().SetFrom(
            source.get_continuous_state()
        )
        context.get_mutable_discrete_state().SetFrom(
            source.get_discrete_state()
        )
        context.get_mutable_abstract_state().SetFrom(
            source.get_abstract_state()
        )

    def target_of(self, i: int):
        """(entry, its subsystem context, its slice of z) holding z[i]."""
        for target in self._targets:
            if target[2].start <= i < target[2].stop:
                return target
        raise IndexError(i)

    def set_state(self, z) -> Context:
        """The working context at ``context0``'s state with the entries
        at z."""
        context = self.simulator.get_mutable_context()
        self._reset(context)
        # The reset state holds z0: only the entries z moves are written.
        for e, sub, rows in self._targets:
            if not np.array_equal(z[rows], self.z0[rows]):
                e.write(sub, z[rows])
        return context

    def __call__(self, z):
        simulator, config = self.simulator, self.config
        context = self.set_state(z)
        # A new integrator per run: cenic carries its state from one run
        # to the next.
        ApplySimulatorConfig(config, simulator)
        if config.use_error_control:
            simulator.get_mutable_integrator().set_target_accuracy(
                config.accuracy
            )
        simulator.Initialize(
            InitializeParams(suppress_initialization_events=True)
        )
        status = simulator.AdvanceTo(self.context0.get_time() + self.period)
        if status.reason() != status.ReturnReason.kReachedBoundaryTime:
            raise RuntimeError(
                "a one-period map's simulation ended early at t = "
                f"{context.get_time():.6f} s: {status.FormatMessage()}"
            )
        return np.concatenate([e.read(sub) for e, sub, _ in self._targets])


def _one_period(diagram, context0, entries, z, period, config):
    return _OnePeriod(diagram, context0, entries, period, config)(z)


#: The held entries' check (:func:`period_map`): a perturbation of them
#: that moves none of the ``held_through`` ports may move the period's end
#: by at most this fraction of what one step of a basis entry moves it.
HELD_CHECK = 1e-4
#: A change of the period's end within this fraction of its value is the
#: arithmetic's (where the basis moves an entry only by rounding, too).
HELD_ROUNDING = 1e-12
#: A basis column's share of the ports' change (pivoted QR) below which
#: the held entries' remaining columns are taken as combinations.
HELD_RANK = 1e-8


def period_map(
    diagram: Diagram,
    context: Context,
    entries: Sequence[StateEntry],
    *,
    period: float,
    config: SimulatorConfig,
    held_through: Sequence = (),
) -> np.ndarray:
    """d z(t + period) / d z(t) by finite differences, z the concatenated
    ``entries``, each column two simulations of one period (central) or,
    for an entry not ``central``, one against the unperturbed period,
    from ``context``'s state (initialization events suppressed: the
    periodic events due at the context's time are handled first).

    ``held_through``: input ports (system name, port name) through which
    alone the one-sided entries act on the period, as held values the
    sample at its start reads and overwrites (``context`` just before a
    sample, ``period`` a whole one). Their columns are then the
    combinations of a few (:func:`_held_columns`)."""
    one_period = _OnePeriod(diagram, context, entries, period, config)
    z0 = one_period.z0
    steps, central = [], []
    for e, _, rows in one_period._targets:
        n = rows.stop - rows.start
        steps.append(np.full(n, e.step))
        central.append(np.full(n, e.central))
    steps, central = np.concatenate(steps), np.concatenate(central)
    unperturbed = None if central.all() else one_period(z0)
    columns = {}
    if held_through and not central.all():
        columns = _held_columns(
            one_period,
            held_through,
            np.flatnonzero(~central),
            steps,
            unperturbed,
        )
    for i in range(z0.size):
        if i in columns:
            continue
        dz = np.zeros_like(z0)
        dz[i] = steps[i]
        plus = one_period(z0 + dz)
        if central[i]:
            columns[i] = (plus - one_period(z0 - dz)) / (2 * steps[i])
        else:
            columns[i] = (plus - unperturbed) / steps[i]
    return np.array([columns[i] for i in range(z0.size)]).T


def _held_columns(
    one_period: _OnePeriod, ports, held, steps, unperturbed
) -> dict:
    """{index: column} of the one-sided entries ``held`` (indices in z,
    ``unperturbed`` the period's end from z0), or {} when the check
    fails. Held values the sample overwrites act on
    the period only through what the sample reads at its instant: if
    that is the ports' values, each column is d(end)/d(ports) times the
    ports' change per entry. The ports' change per entry is evaluated
    (no simulation); a basis of entries whose changes span the others'
    (pivoted QR) is simulated; every other column is the combination of
    the basis' that its change is. Checked once: a perturbation of the
    held entries that leaves the ports unchanged must leave the period's
    end within ``HELD_CHECK`` of the basis' effect (or of rounding,
    ``HELD_ROUNDING``)."""
    diagram, z0 = one_period.diagram, one_period.z0
    context = one_period.set_state(z0)
    readers = []
    for system, port in ports:
        subsystem = diagram.GetSubsystemByName(system)
        readers.append(
            (
                subsystem.GetInputPort(port),
                subsystem.GetMyContextFromRoot(context),
            )
        )

    def port_values():
        return np.concatenate([port.Eval(sub) for port, sub in readers])

    def moved(i):
        z = z0.copy()
        z[i] += steps[i]
        return z

    # The ports' change per step of each held entry, each entry moved and
    # put back in turn.
    w0 = port_values()
    W = np.zeros((w0.size, len(held)))
    for column, i in enumerate(held):
        e, sub, rows = one_period.target_of(i)
        e.write(sub, moved(i)[rows])
        W[:, column] = port_values() - w0
        e.write(sub, z0[rows])
    _, R, pivots = scipy.linalg.qr(W, mode="economic", pivoting=True)
    rank = int(np.sum(np.abs(np.diag(R)) > HELD_RANK * abs(R[0, 0])))
    basis = pivots[:rank]
    # The period's end per step of each basis entry.
    Y = np.zeros((z0.size, rank))
    for column, k in enumerate(basis):
        Y[:, column] = one_period(moved(held[k])) - unperturbed
    # The check: a perturbation (one step in all, spread over the held
    # entries) that moves no port.
    null = scipy.linalg.null_space(W, rcond=HELD_RANK)
    if null.shape[1]:
        n = null @ np.random.default_rng(0).standard_normal(null.shape[1])
        z = z0.copy()
        z[held] += steps[held] * n / np.linalg.norm(n)
        bound = np.maximum(
            HELD_CHECK * np.max(np.abs(Y), axis=1, initial=0.0),
            HELD_ROUNDING * np.abs(unperturbed),
        )
        if np.any(np.abs(one_period(z) - unperturbed) > bound):
            return {}
    combination = np.linalg.lstsq(W[:, basis], W, rcond=None)[0]
    return {
        int(i): (Y @ combination[:, j]) / steps[i] for j, i in enumerate(held)
    }


def spectral_radius(
    M: np.ndarray, *, neutral: int = 0, tolerance: float = 1e-3
) -> float:
    """max |eig(M)|, leaving out up to ``neutral`` eigenvalues within
    ``tolerance`` of 1 (a known neutral mode, such as a shift along the
    edge)."""
    eigs = np.linalg.eigvals(M)
    for _ in range(neutral):
        i = int(np.argmin(np.abs(eigs - 1.0)))
        if abs(eigs[i] - 1.0) < tolerance:
            eigs = np.delete(eigs, i)
    return float(np.max(np.abs(eigs)))


def cell_map_entries(diagram: Diagram) -> List[StateEntry]:
    """The states of the deburring cell's one-period map (module
    docstring)."""
    plant = diagram.GetSubsystemByName("plant")
    controller = diagram.GetSubsystemByName("controller")
    process = diagram.GetSubsystemByName("cutting_process")
    nq, nv = plant.num_positions(), plant.num_velocities()
    return [
        StateEntry(
            "plant",
            "continuous",
            indices=tuple(range(nq)),
            step=1e-7,
            label="q",
        ),
        StateEntry(
            "plant",
            "continuous",
            indices=tuple(range(nq, nq + nv)),
            step=1e-5,
            label="v",
        ),
        StateEntry(
            "controller", "continuous", indices=(0,), step=1e-8, label="delta_d"
        ),
        StateEntry("force_sensor", "discrete", 0, step=1e-3, label="y"),
        # The controller's held actuation and the process's held force-law
        # terms (their discrete-state groups, see the classes). The map is
        # affine in the held values over a period (they enter the
        # dynamics as held forces and the sample's law through linear
        # terms), so one-sided differences of them are as good as central
        # ones.
        StateEntry(
            "controller",
            "discrete",
            int(controller._held["actuation"]),
            step=1e-3,
            label="u_held",
            central=False,
        ),
        # delta_d's held rate: overwritten at each sample (a zero column
        # of the one-period map), but carried across a split of the
        # period (maps.fast_rho).
        StateEntry(
            "controller",
            "discrete",
            int(controller._held["derivatives"]),
            indices=(0,),
            step=1e-8,
            label="delta_d_rate",
            central=False,
        ),
        StateEntry(
            "cutting_process",
            "discrete",
            int(process._terms_index),
            step=1e-4,
            label="force_law_terms",
            central=False,
        ),
    ]


def cell_held_through(diagram: Diagram) -> tuple:
    """The input ports through which alone the cell's held entries (the
    held actuation and force-law terms of :func:`cell_map_entries`) act
    at the sample that overwrites them (:func:`period_map`'s
    ``held_through``): the plant's actuation and applied generalized
    force (the cutting law's), and the law's force at the tool, which the
    force sensor reads; () for a diagram without them."""
    ports = (
        ("plant", "actuation"),
        ("plant", "applied_generalized_force"),
        ("force_sensor", "applied_force"),
    )
    for system, port in ports:
        if not (
            diagram.HasSubsystemNamed(system)
            and diagram.GetSubsystemByName(system).HasInputPort(port)
        ):
            return ()
    return ports


@dataclass
class SampledLoop:
    """The one-period map Phi at an operating point."""

    Phi: np.ndarray
    labels: List[str]
    period: float  # s
    spectral_radius: float
    sensor_alpha: float  # the sampled low-pass's gain, y += alpha (raw - y)
    sensor_rows: slice  # y's rows/columns in Phi
    n1: np.ndarray  # the operating point's depth direction (world)
    n2: np.ndarray  # and direction of motion (world)
    diagram: Diagram = None
    context: Context = None

    @property
    def eigenvalues(self) -> np.ndarray:
        return np.linalg.eigvals(self.Phi)


class FrozenMap:
    """The frozen variant of a scenario (with ``overrides`` by dotted
    name; ``plan``: the scenario's, if planned), built once, whose
    one-period map can be taken at any state of a run of the scenario's
    own diagram (:meth:`at`): the maps along a run
    reuse one diagram."""

    def __init__(self, scenario: Scenario, *, plan=None, **overrides):
        from deburr_drake.cell.plan import plan_cell
        from deburr_drake.config import ConfigError

        self.scenario = frozen_scenario(scenario, **overrides)
        period = self.scenario.controller.control_period
        if not (
            period > 0
            and abs(self.scenario.sensor.sample_period - period) < 1e-12
            and abs(self.scenario.process.sample_period - period) < 1e-12
        ):
            raise ConfigError(
                "the sampled-loop analysis needs controller.control_period "
                "> 0 equal to sensor.sample_period and "
                f"process.sample_period, got {period}, "
                f"{self.scenario.sensor.sample_period}, "
                f"{self.scenario.process.sample_period}"
            )
        self.period = period
        self.config = simulator_config(self.scenario)
        # ``plan``: the scenario's own, whose cell the variant shares.
        self.diagram = make_deburring_diagram(
            plan_cell(self.scenario)
            if plan is None
            else plan.varied(self.scenario)
        )
        self.entries = cell_map_entries(self.diagram)
        self.held_through = cell_held_through(self.diagram)

    def context_from(
        self, source: Diagram, source_context: Context, modify=None
    ) -> Context:
        """A context of the frozen diagram holding ``source_context``'s
        state (subsystems matched by name), changed by ``modify(diagram,
        context)`` if given."""
        context = self.diagram.CreateDefaultContext()
        transfer_state(source, source_context, self.diagram, context)
        if modify is not None:
            modify(self.diagram, context)
        return context

    def at(
        self, source: Diagram, source_context: Context, modify=None
    ) -> np.ndarray:
        """The one-period map at ``source_context`` (just before a
        sample)."""
        return self.at_context(
            self.context_from(source, source_context, modify)
        )

    def at_context(self, context: Context) -> np.ndarray:
        """The one-period map at ``context``, a context of this frozen
        diagram (just before a sample)."""
        return period_map(
            self.diagram,
            context,
            self.entries,
            period=self.period,
            config=self.config,
            held_through=self.held_through,
        )


def sampled_loop(
    op: OperatingPoint, *, modify=None, **overrides
) -> SampledLoop:
    """The one-period map of ``op``'s sampled loop, with scenario
    ``overrides`` by dotted name (e.g. ``sensor.cutoff_frequency``);
    ``modify(diagram, context)`` may change the operating point's state
    first (e.g. the fuzzy surface, see
    :func:`deburr_drake.analysis.add_fuzzy_slope`). (A map over one 25 ms
    outer period with the feed law live is not offered: on the paper arm its
    spectral radius contradicts the runs both ways, above 1 for a stable
    gain and below 1 for one whose run oscillates.)"""
    from deburr_drake.control.layout import CHAMFER_STATE

    frozen = FrozenMap(op.scenario, plan=op.plan, **overrides)
    scenario, diagram, entries = frozen.scenario, frozen.diagram, frozen.entries
    context = frozen.context_from(op.diagram, op.context, modify)
    Phi = frozen.at_context(context)
    labels, start, rows = [], 0, None
    for e in entries:
        n = e.get(diagram, context).size
        if e.label == "y":
            rows = slice(start, start + n)
        labels += [f"{e.label}[{i}]" for i in range(n)]
        start += n
    observer = diagram.GetSubsystemByName("chamfer_observer")
    chamfer = observer.GetOutputPort("chamfer_state").Eval(
        observer.GetMyContextFromRoot(context)
    )
    n1 = CHAMFER_STATE.get(chamfer, "n1")
    n2 = CHAMFER_STATE.get(chamfer, "n2")
    alpha = 1.0 - np.exp(
        -2
        * np.pi
        * scenario.sensor.cutoff_frequency
        * scenario.sensor.sample_period
    )
    return SampledLoop(
        Phi=Phi,
        labels=labels,
        period=frozen.period,
        spectral_radius=spectral_radius(Phi),
        sensor_alpha=alpha,
        sensor_rows=rows,
        n1=n1.copy(),
        n2=n2.copy(),
        diagram=diagram,
        context=context,
    )


def frozen_cell(op: OperatingPoint, overrides):
    """(diagram, context, map entries) of ``op``'s frozen scenario with
    ``overrides``, at ``op``'s state."""
    scenario = frozen_scenario(op.scenario, **overrides)
    diagram = make_deburring_diagram(op.variant(scenario))
    context = diagram.CreateDefaultContext()
    transfer_state(op.diagram, op.context, diagram, context)
    return diagram, context, cell_map_entries(diagram)


def frozen_in_place(op: OperatingPoint):
    """(diagram, context, map entries) like :func:`frozen_cell`'s without
    overrides, on ``op``'s own diagram (no build): a default context
    holding ``op``'s state, the sensor noise off (its parameter). The
    sampled loop's map does not see what else the frozen variant turns
    off: the adaptation's states are not in the map and their rates are
    held between samples, a guard that does not trip and a drive clamp
    below the limits pass everything through bit for bit (a period a
    guard ended is an error, :class:`_OnePeriod`)."""
    diagram = op.diagram
    context = diagram.CreateDefaultContext()
    transfer_state(diagram, op.context, diagram, context)
    sensor = diagram.GetSubsystemByName("force_sensor")
    sensor.set_noise_std(sensor.GetMyMutableContextFromRoot(context), 0.0)
    return diagram, context, cell_map_entries(diagram)


def rest_of_period_map(diagram, context, entries, delta, period, config):
    """The map of the integration from t_k + delta to the period's end,
    taken at the state just after the sample."""
    after = context.Clone()
    _write(
        entries,
        diagram,
        after,
        _one_period(
            diagram,
            context,
            entries,
            _read(entries, diagram, context),
            delta,
            config,
        ),
    )
    # _one_period moved only the entries; the rest of the state (FOH,
    # adaptation: frozen or slow) is the operating point's.
    after.SetTime(context.get_time() + delta)
    return period_map(
        diagram, after, entries, period=period - delta, config=config
    )
