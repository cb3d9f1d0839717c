"""Running a deburring diagram and collecting its logs as named arrays."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Dict, Optional

import numpy as np
from pydrake.common import RandomGenerator
from pydrake.systems.analysis import (ApplySimulatorConfig, Simulator,
                                      SimulatorConfig)
from pydrake.systems.framework import Diagram

from deburr_drake.config import Scenario
from deburr_drake.layout import (CHAMFER_STATE, COMMAND_STATE,
                                 CONTROLLER_DIAGNOSTICS)
from deburr_drake.process import PROCESS_STATE

__all__ = ["RunLog", "simulate", "make_simulator"]

_LAYOUTS = {
    "chamfer": CHAMFER_STATE,
    "controller": CONTROLLER_DIAGNOSTICS,
    "command": COMMAND_STATE,
    "process": PROCESS_STATE,
}


@dataclass
class RunLog:
    """Logged signals of one run. ``signals[logger]`` is a dict with
    ``t`` (s) and one array per named block (rows: samples)."""

    scenario: Scenario
    signals: Dict[str, Dict[str, np.ndarray]] = field(default_factory=dict)
    wall_time: float = 0.0  # s
    sim_time: float = 0.0  # s
    steps: int = 0

    def __getitem__(self, key: str) -> Dict[str, np.ndarray]:
        return self.signals[key]

    def flat(self) -> Dict[str, np.ndarray]:
        """Every array as ``"<logger>.<block>"`` (for np.savez)."""
        return {f"{k}.{b}": v for k, blocks in self.signals.items()
                for b, v in blocks.items()}


def make_simulator(diagram: Diagram, scenario: Scenario) -> Simulator:
    sim = scenario.simulation
    simulator = Simulator(diagram)
    ApplySimulatorConfig(SimulatorConfig(
        integration_scheme=sim.integrator, max_step_size=sim.max_step,
        accuracy=sim.accuracy, use_error_control=True), simulator)
    simulator.get_mutable_integrator().set_target_accuracy(sim.accuracy)
    return simulator


def _collect(diagram, context, loggers) -> Dict[str, Dict[str, np.ndarray]]:
    out = {}
    for name in loggers:
        sink = diagram.GetSubsystemByName(f"log_{name}")
        log = sink.FindLog(context)
        data = log.data().T
        layout = _LAYOUTS.get(name)
        blocks = layout.split(data) if layout else {"value": data}
        out[name] = {"t": log.sample_times().copy(), **blocks}
    return out


def simulate(diagram: Diagram, scenario: Scenario, *,
             duration: Optional[float] = None,
             progress: Optional[Callable[[float, float], None]] = None,
             progress_interval: float = 1.0, loggers=None) -> RunLog:
    """Simulates from the diagram's default context for ``duration`` (the
    scenario's by default) and returns the logs. ``progress(t, wall)`` is
    called every ``progress_interval`` simulated seconds."""
    from deburr_drake.testbed import LOGGED
    duration = scenario.simulation.duration if duration is None else duration
    simulator = make_simulator(diagram, scenario)
    context = simulator.get_mutable_context()
    diagram.SetRandomContext(
        context, RandomGenerator(scenario.sensor.noise_seed))
    start = time.perf_counter()
    simulator.Initialize()
    t = 0.0
    while t < duration - 1e-12:
        t = min(duration, t + progress_interval)
        simulator.AdvanceTo(t)
        if progress is not None:
            progress(t, time.perf_counter() - start)
    wall = time.perf_counter() - start
    return RunLog(scenario=scenario,
                  signals=_collect(diagram, context, loggers or LOGGED),
                  wall_time=wall, sim_time=duration,
                  steps=simulator.get_num_steps_taken())
