"""Cost of one HybridController evaluation: actuation output plus the time
derivatives of its 243 continuous states (m = 2, Upsilon = 5: 242 rules),
through the Drake API with the cache invalidated each time (the law itself:
control_period = 0; the sampled controller evaluates it once per sample).
Prints microseconds per evaluation."""

import sys
import time

import numpy as np

from deburr_drake.cell.models import POINT_MASS_URL, make_kinematic_model
from deburr_drake.config import ControllerConfig
from deburr_drake.control.controller import HybridController
from deburr_drake.control.observer import chamfer_quantities
from deburr_drake.math.geometry import CircularContour


def main(n: int = 5000) -> None:
    config = ControllerConfig(control_period=0.0)
    config.fuzzy.order = 2
    model = make_kinematic_model(POINT_MASS_URL)
    controller = HybridController(model, "tool_tip", config)
    contour = CircularContour([0.0, 0.0, 0.048], 0.027)
    p = contour.point_at(0.01)
    n1, t = contour.n1(p), contour.tangent(p)
    x_p, v = p + 4e-4 * n1, 2e-3 * t
    force = -5.0 * n1 - 9.0 * t
    context = controller.CreateDefaultContext()
    for name, value in dict(
        plant_state=np.concatenate([x_p, v]),
        chamfer_state=chamfer_quantities(
            contour, x_p, v, force, min_tangential_speed=1e-5
        ),
        measured_force=force,
        commanded_position=p + 3e-5 * t,
        commanded_velocity=2.4e-3 * t,
        desired_normal_force=[6.0],
    ).items():
        controller.GetInputPort(name).FixValue(context, value)
    rng = np.random.default_rng(0)
    n_x = controller.num_continuous_states()
    states = rng.normal(scale=0.5, size=(n, n_x))
    states[:, 0] = 3e-4 + 1e-4 * rng.random(n)  # delta_d: s spans +-Omega
    actuation = controller.GetOutputPort("actuation")
    start = time.perf_counter()
    for x in states:
        context.SetContinuousState(x)
        actuation.Eval(context)
        controller.EvalTimeDerivatives(context)
    elapsed = time.perf_counter() - start
    print(
        f"HybridController, m = {config.fuzzy.order}, "
        f"{2 * (2 * config.fuzzy.upsilon + 1) ** 2} rules, {n_x} states: "
        f"{elapsed / n * 1e6:.1f} us per actuation + derivative "
        f"evaluation ({n} evaluations)"
    )


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5000)
