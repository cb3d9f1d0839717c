"""Fault injection (scenario section ``faults:``) by Drake systems in the
diagram, between the force sensor and what reads it:

- ``sensor_noise_scale``: a ``Gain`` on the sensor's unit-variance noise
  (``faults.noise_scale`` x ``sensor.noise_std``);
- ``sensor_faults``: :class:`SensorFaults`, the reading plus a bias, and in
  each dropout window the last reading held or zero.

With no fault configured neither system is added: the diagram is the
fault-free one.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem
from pydrake.systems.primitives import Gain

from deburr_drake.config import FaultsConfig

__all__ = ["SensorFaults", "add_sensor_faults", "add_noise_scale"]


class SensorFaults(LeafSystem):
    """The force sensor's reading as the faults leave it: the reading plus
    ``sensor_bias``; inside a dropout window [start, start + duration)
    the reading held at its last value before the window (``hold``) or
    zero (``zero``).

    .. pydrake_system::

        name: SensorFaults
        input_ports:
        - measured_force
        output_ports:
        - faulted_force

    - ``measured_force`` (3, N, world): the force sensor's reading.
    - ``faulted_force`` (3, N, world): what the observer and the
      controller read.
    - Discrete state ``last`` (3, N): the output at the last sample
      outside a window, updated every ``sample_period``.
    """

    def __init__(self, config: FaultsConfig, sample_period: float):
        super().__init__()
        config.validate()
        self._bias = np.array(config.sensor_bias, float)
        self._windows = [
            (d.start, d.start + d.duration, d.mode) for d in config.dropouts
        ]
        self._input = self.DeclareVectorInputPort("measured_force", 3)
        self._last = self.DeclareDiscreteState(BasicVector(np.zeros(3)))
        self.DeclareVectorOutputPort(
            "faulted_force",
            3,
            self._output,
            prerequisites_of_calc={
                self._input.ticket(),
                self.time_ticket(),
                self.xd_ticket(),
            },
        )
        self.DeclarePeriodicDiscreteUpdateEvent(sample_period, 0.0, self._store)

    def window(self, t: float):
        """The dropout mode at time t (s), or None outside every window."""
        for start, stop, mode in self._windows:
            if start <= t < stop:
                return mode
        return None

    def _store(self, context, discrete_state):
        if self.window(context.get_time()) is None:
            discrete_state.set_value(
                self._last, self._input.Eval(context) + self._bias
            )

    def _output(self, context, output):
        mode = self.window(context.get_time())
        if mode is None:
            output.SetFromVector(self._input.Eval(context) + self._bias)
        elif mode == "zero":
            output.SetFromVector(np.zeros(3))
        else:
            output.SetFromVector(context.get_discrete_state(self._last).value())


def add_sensor_faults(
    builder, faults: FaultsConfig, measured_force, *, sample_period: float
):
    """The port that carries the force reading to the observer and the
    controller: ``measured_force`` (the sensor's output port) through
    :class:`SensorFaults` named ``sensor_faults``, or ``measured_force``
    itself without sensor faults."""
    if not faults.sensor_faults():
        return measured_force
    system = builder.AddNamedSystem(
        "sensor_faults", SensorFaults(faults, sample_period)
    )
    builder.Connect(measured_force, system.get_input_port())
    return system.get_output_port()


def add_noise_scale(builder, faults: FaultsConfig, noise):
    """The sensor's noise input: ``noise`` scaled by ``faults.noise_scale``
    through a ``Gain`` named ``sensor_noise_scale`` (``noise`` itself at
    scale 1)."""
    if faults.noise_scale == 1.0:
        return noise
    gain = builder.AddNamedSystem(
        "sensor_noise_scale", Gain(faults.noise_scale, noise.size())
    )
    builder.Connect(noise, gain.get_input_port())
    return gain.get_output_port()
