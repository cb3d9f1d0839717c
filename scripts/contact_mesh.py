#!/usr/bin/env python3
"""The tool/ring contact law and its cost for several mesh resolutions of a
scenario: the ring's segments around the circumference and the cutter's
resolution hint. Prints, per variant, the normal force at 0.3, 0.5 and
0.7 mm (the cutter vertical, at rest), its ripple (max - min) / 2 over one
ring segment at 0.5 mm, and the cost of one contact evaluation (the
hydroelastic query and the contact results: what the force sensor and,
with its own query, cenic pay every step).

    python scripts/contact_mesh.py [--scenario paper]
"""

import argparse
import copy
import time

import numpy as np

from deburr_drake.cell.truth import contact_normal_force
from deburr_drake.config import load_scenario

DEPTHS = (3e-4, 5e-4, 7e-4)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenario", default="paper")
    ap.add_argument("--evaluations", type=int, default=400)
    args = ap.parse_args()
    base = load_scenario(args.scenario)
    variants = [(240, 4e-4), (240, 6e-4), (120, 4e-4), (120, 6e-4)]
    current = (base.part.band.mesh_segments, base.tool.resolution_hint)
    if current not in variants:
        variants.append(current)
    print(
        f"{'segments':>8} {'hint mm':>7} | {'F(0.3) N':>8} {'F(0.5) N':>8} "
        f"{'F(0.7) N':>8} | {'ripple N':>8} | {'us/eval':>7}"
    )
    for segments, hint in variants:
        scenario = copy.deepcopy(base)
        scenario.part.band.mesh_segments = segments
        scenario.tool.resolution_hint = hint
        forces = contact_normal_force(scenario, DEPTHS)
        # One ring segment is 1 / segments of the edge.
        arc = 0.5 + np.linspace(0.0, 1.0, 9) / segments
        ripple = [
            contact_normal_force(scenario, [5e-4], arc_fraction=a)[0]
            for a in arc
        ]
        # Per evaluation: n evaluations at depths 0.5 mm +- 1 nm (each a
        # new query), less one evaluation's share of the set-up.
        depths = 5e-4 + 1e-9 * np.sin(np.arange(args.evaluations))
        wall = time.perf_counter()
        contact_normal_force(scenario, depths[:1])
        one = time.perf_counter() - wall
        wall = time.perf_counter()
        contact_normal_force(scenario, depths)
        many = time.perf_counter() - wall
        cost = (many - one) / (args.evaluations - 1)
        mark = "  (scenario)" if (segments, hint) == current else ""
        print(
            f"{segments:8d} {1e3 * hint:7.2f} | "
            + " ".join(f"{f:8.3f}" for f in forces)
            + f" | {(max(ripple) - min(ripple)) / 2:8.4f} | "
            f"{1e6 * cost:7.0f}{mark}"
        )


if __name__ == "__main__":
    main()
