"""Fixtures of the control tests."""

import numpy as np
import pytest


@pytest.fixture
def run_untouched():
    """A probing sequence simulated alone with no force ever read, its
    tool held at the chamfer state ``chamfer``: returns the simulator's
    status at its end (``until`` s at most) and its context."""
    from pydrake.systems.analysis import Simulator

    def run(probe, chamfer, until=10.0):
        simulator = Simulator(probe)
        context = simulator.get_mutable_context()
        probe.GetInputPort("command_in").FixValue(context, np.zeros(3))
        probe.GetInputPort("chamfer_state").FixValue(context, chamfer)
        probe.GetInputPort("measured_force").FixValue(context, np.zeros(3))
        return simulator.AdvanceTo(until), context

    return run
