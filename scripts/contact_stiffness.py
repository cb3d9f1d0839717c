#!/usr/bin/env python3
"""Calibrate and tabulate the tool/ring hydroelastic contact law (force vs
radial depth).

Prints: the hydroelastic modulus E giving the target local stiffness at 0.5 mm,
the table of force and dF/d(delta) for depths 0.1..1.0 mm, the power-law
exponent, the force ripple over one mesh segment, and the cost of one
contact-force evaluation.
"""

import argparse
import time

import numpy as np

from deburr_drake.cell.part import (
    RingContactProbe,
    calibrate_hydroelastic_modulus,
    force_ripple,
    local_stiffness,
    measure_normal_force,
    power_law_exponent,
)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument(
        "--target-stiffness", type=float, default=10.0, help="N/mm at --depth"
    )
    ap.add_argument(
        "--depth", type=float, default=0.5, help="calibration depth, mm"
    )
    ap.add_argument(
        "--modulus",
        type=float,
        default=None,
        help="use this E (Pa) instead of calibrating",
    )
    ap.add_argument("--n-theta", type=int, default=720)
    args = ap.parse_args()

    common = dict(n_theta=args.n_theta)
    E = args.modulus or calibrate_hydroelastic_modulus(
        target_stiffness=args.target_stiffness * 1e3,
        depth=args.depth * 1e-3,
        **common,
    )
    print(f"hydroelastic modulus E = {E:.3g} Pa (n_theta = {args.n_theta})")

    depths = np.arange(1, 11) * 1e-4
    forces = measure_normal_force(depths, hydroelastic_modulus=E, **common)
    stiffness = local_stiffness(depths, hydroelastic_modulus=E, **common)
    print(f"{'depth mm':>9} {'F N':>8} {'dF/dd N/mm':>11} {'local exp':>9}")
    for d, f, k in zip(depths, forces, stiffness):
        print(f"{d * 1e3:9.2f} {f:8.3f} {k * 1e-3:11.2f} {k * d / f:9.2f}")
    exponent = power_law_exponent(depths, forces)
    print(f"power-law exponent (fit 0.1..1.0 mm): {exponent:.3f}")
    (f_out,) = measure_normal_force([-1e-4], hydroelastic_modulus=E, **common)
    print(f"out of contact (depth -0.1 mm): F = {f_out} N")

    ripple, f_seg = force_ripple(
        args.depth * 1e-3, hydroelastic_modulus=E, **common
    )
    print(
        f"ripple over one mesh segment at {args.depth} mm: "
        f"(max-min)/mean = {ripple:.2e} "
        f"(F {f_seg.min():.4f}..{f_seg.max():.4f} N)"
    )

    probe = RingContactProbe(hydroelastic_modulus=E, **common)
    angles = np.linspace(0.0, 0.01, 201)
    probe.radial_force(args.depth * 1e-3, 0.0)
    t0 = time.perf_counter()
    for a in angles:
        probe.radial_force(args.depth * 1e-3, a)
    dt = (time.perf_counter() - t0) / len(angles)
    print(
        "one contact-force evaluation (new pose, contact results port): "
        f"{dt * 1e3:.3f} ms"
    )


if __name__ == "__main__":
    main()
