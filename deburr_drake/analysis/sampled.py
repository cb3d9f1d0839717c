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
from pydrake.systems.analysis import (ApplySimulatorConfig, InitializeParams,
                                      Simulator, SimulatorConfig)
from pydrake.systems.framework import Context, Diagram

from deburr_drake.analysis.operating_point import (OperatingPoint,
                                                   frozen_scenario,
                                                   transfer_state)
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import Scenario

__all__ = ["StateEntry", "period_map", "spectral_radius", "SampledLoop",
           "sampled_loop", "cell_map_entries", "outer_loop_entries",
           "simulator_config"]


@dataclass(frozen=True)
class StateEntry:
    """A block of a subsystem's state: ``kind`` "continuous" (``group``
    ignored) or "discrete" (group index), ``indices`` within it (None:
    all), perturbed by ``step``."""

    system: str
    kind: str
    group: int = 0
    indices: tuple = None
    step: float = 1e-6
    label: str = ""

    def _vector(self, diagram: Diagram, context: Context):
        sub = diagram.GetSubsystemByName(self.system).GetMyMutableContextFromRoot(
            context)
        if self.kind == "continuous":
            return sub.get_mutable_continuous_state_vector()
        return sub.get_mutable_discrete_state(self.group)

    def get(self, diagram, context) -> np.ndarray:
        v = self._vector(diagram, context).CopyToVector()
        return v if self.indices is None else v[list(self.indices)]

    def set(self, diagram, context, values):
        vector = self._vector(diagram, context)
        v = vector.CopyToVector()
        if self.indices is None:
            v[:] = values
        else:
            v[list(self.indices)] = values
        vector.SetFromVector(v)


def simulator_config(scenario: Scenario) -> SimulatorConfig:
    sim = scenario.simulation
    return SimulatorConfig(
        integration_scheme=sim.integrator, max_step_size=sim.max_step,
        accuracy=sim.accuracy, use_error_control=sim.error_control)


def _read(entries, diagram, context):
    return np.concatenate([e.get(diagram, context) for e in entries])


def _write(entries, diagram, context, z):
    k = 0
    for e in entries:
        n = e.get(diagram, context).size
        e.set(diagram, context, z[k:k + n])
        k += n


def _one_period(diagram, context0, entries, z, period, config):
    context = context0.Clone()
    _write(entries, diagram, context, z)
    simulator = Simulator(diagram, context)
    config = copy.copy(config)
    # ApplySimulatorConfig sets the context's time to start_time.
    config.start_time = context0.get_time()
    ApplySimulatorConfig(config, simulator)
    if config.use_error_control:
        simulator.get_mutable_integrator().set_target_accuracy(
            config.accuracy)
    simulator.Initialize(InitializeParams(suppress_initialization_events=True))
    simulator.AdvanceTo(context0.get_time() + period)
    return _read(entries, diagram, context)


def period_map(diagram: Diagram, context: Context,
               entries: Sequence[StateEntry], *, period: float,
               config: SimulatorConfig) -> np.ndarray:
    """d z(t + period) / d z(t) by central differences, z the
    concatenated ``entries``, each column two simulations of one period
    from a clone of ``context`` (initialization events suppressed: the
    periodic events due at the context's time are handled first)."""
    z0 = _read(entries, diagram, context)
    steps = np.concatenate([
        np.full(e.get(diagram, context).size, e.step) for e in entries])
    columns = []
    for i in range(z0.size):
        dz = np.zeros_like(z0)
        dz[i] = steps[i]
        plus = _one_period(diagram, context, entries, z0 + dz, period, config)
        minus = _one_period(diagram, context, entries, z0 - dz, period,
                            config)
        columns.append((plus - minus) / (2 * steps[i]))
    return np.array(columns).T


def spectral_radius(M: np.ndarray, *, neutral: int = 0,
                    tolerance: float = 1e-3) -> float:
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
        StateEntry("plant", "continuous", indices=tuple(range(nq)),
                   step=1e-7, label="q"),
        StateEntry("plant", "continuous", indices=tuple(range(nq, nq + nv)),
                   step=1e-5, label="v"),
        StateEntry("controller", "continuous", indices=(0,), step=1e-8,
                   label="delta_d"),
        StateEntry("force_sensor", "discrete", 0, step=1e-3, label="y"),
        # The controller's held actuation and the process's held force-law
        # terms (their discrete-state groups, see the classes).
        StateEntry("controller", "discrete",
                   int(controller._held["actuation"]), step=1e-3,
                   label="u_held"),
        # delta_d's held rate: overwritten at each sample (a zero column
        # of the one-period map), but carried across a split of the
        # period (maps.fast_rho).
        StateEntry("controller", "discrete",
                   int(controller._held["derivatives"]), indices=(0,),
                   step=1e-8, label="delta_d_rate"),
        StateEntry("cutting_process", "discrete",
                   int(process._terms_index), step=1e-4,
                   label="force_law_terms"),
    ]


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


def outer_loop_entries(diagram: Diagram) -> List[StateEntry]:
    """The outer loop's states: the command generator's x_c(kT), feed and
    arc position, the first-order hold's x*(t) and its knots."""
    return [
        StateEntry("command_generator", "discrete", 0, step=1e-7,
                   label="command_state"),
        StateEntry("first_order_hold", "continuous", step=1e-7,
                   label="x_star"),
        StateEntry("first_order_hold", "discrete", 0, step=1e-7,
                   label="hold_knots"),
    ]


def sampled_loop(op: OperatingPoint, *, modify=None, outer_loop=False,
                 **overrides) -> SampledLoop:
    """The one-period map of ``op``'s sampled loop, with scenario
    ``overrides`` by dotted name (e.g. ``sensor.cutoff_frequency``);
    ``modify(diagram, context)`` may change the operating point's state
    first (e.g. the fuzzy surface, see
    :func:`deburr_drake.analysis.add_fuzzy_slope`)."""
    from deburr_drake.control.layout import CHAMFER_STATE
    scenario = frozen_scenario(op.scenario, **overrides)
    period = scenario.controller.control_period
    if not (period > 0 and abs(scenario.sensor.sample_period - period) < 1e-12
            and abs(scenario.process.sample_period - period) < 1e-12):
        from deburr_drake.config import ConfigError
        raise ConfigError(
            "the sampled-loop analysis needs controller.control_period > 0 "
            "equal to sensor.sample_period and process.sample_period, got "
            f"{period}, {scenario.sensor.sample_period}, "
            f"{scenario.process.sample_period}")
    diagram = make_deburring_diagram(scenario=scenario)
    context = diagram.CreateDefaultContext()
    transfer_state(op.diagram, op.context, diagram, context)
    if modify is not None:
        modify(diagram, context)
    entries = cell_map_entries(diagram)
    if outer_loop:
        outer = scenario.command.period
        t = context.get_time()
        start = np.ceil(t / outer - 1e-9) * outer
        if start > t:  # run on to just before the next outer sample
            simulator = Simulator(diagram, context)
            config = copy.copy(simulator_config(scenario))
            config.start_time = t
            ApplySimulatorConfig(config, simulator)
            simulator.Initialize(
                InitializeParams(suppress_initialization_events=True))
            simulator.AdvanceTo(start)
        period = outer
        entries = entries + outer_loop_entries(diagram)
    Phi = period_map(diagram, context, entries, period=period,
                     config=simulator_config(scenario))
    labels, start, rows = [], 0, None
    for e in entries:
        n = e.get(diagram, context).size
        if e.label == "y":
            rows = slice(start, start + n)
        labels += [f"{e.label}[{i}]" for i in range(n)]
        start += n
    observer = diagram.GetSubsystemByName("chamfer_observer")
    chamfer = observer.GetOutputPort("chamfer_state").Eval(
        observer.GetMyContextFromRoot(context))
    n1 = CHAMFER_STATE.get(chamfer, "n1")
    n2 = CHAMFER_STATE.get(chamfer, "n2")
    alpha = 1.0 - np.exp(-2 * np.pi * scenario.sensor.cutoff_frequency
                         * scenario.sensor.sample_period)
    return SampledLoop(Phi=Phi, labels=labels, period=period,
                       spectral_radius=spectral_radius(
                           Phi, neutral=1 if outer_loop else 0),
                       sensor_alpha=alpha, sensor_rows=rows, n1=n1.copy(), n2=n2.copy(),
                       diagram=diagram, context=context)
