"""Microseconds per RuleBase.evaluate_and_rate call (m = 2, Upsilon = 5,
floats)."""

from pathlib import Path
import sys
import time

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from deburr_drake.math.fuzzy import RuleBase


def main(n_calls=10_000, seed=0):
    rb = RuleBase(m=2, upsilon=5, delta0=0.2, deltak=0.2)
    rng = np.random.default_rng(seed)
    theta = rng.normal(size=rb.n_rules)
    y0 = rng.uniform(
        -rb.omega0_half_width, rb.omega0_half_width, n_calls
    ).tolist()
    yk = rng.uniform(
        -rb.omegak_half_width, rb.omegak_half_width, n_calls
    ).tolist()
    f = rb.evaluate_and_rate
    for a, b in zip(y0[:100], yk[:100]):  # warm-up
        f(theta, a, b, 1.0)
    t0 = time.perf_counter()
    for a, b in zip(y0, yk):
        f(theta, a, b, 1.0)
    dt = time.perf_counter() - t0
    print(
        f"evaluate_and_rate: {1e6 * dt / n_calls:.2f} us/call "
        f"(m=2, U=5, {n_calls} random calls)"
    )


if __name__ == "__main__":
    main()
