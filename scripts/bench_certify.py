"""What ``certify`` costs on a scenario: the status, the cells tried, the
programs solved (the load-independent count), the true maps taken, and
the process's CPU and wall time. Two code versions are compared by
running this in each one's tree side by side (the same host, the same
hour).

    python scripts/bench_certify.py --scenario paper
    python scripts/bench_certify.py --scenario paper \\
        --scenario-text 'controller: {sliding_gain: [5150.0, 5150.0, 1500.0]}'
"""

import argparse
import time

from deburr_drake.analysis.box_certificate import certify
from deburr_drake.config import load_scenario


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="paper")
    parser.add_argument("--scenario-text", default=None)
    parser.add_argument("--box", nargs="*", default=None)
    args = parser.parse_args()
    scenario = load_scenario(args.scenario, text=args.scenario_text)
    wall, cpu = time.perf_counter(), time.process_time()
    result = certify(scenario, only=args.box)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    cells = result["constant_cells"]
    solves = sum(c["solves"] or 0 for c in cells)
    pieces = {}
    for c in cells:
        for key, n in c.get("pieces", {}).items():
            pieces[key] = max(pieces.get(key, 1), n)
    cut = "".join(f"; {k} in up to {n} pieces" for k, n in pieces.items())
    print(
        f"{result['status']}, {result['cells_tried']}; {solves} programs "
        f"solved; {result['vertices']} true maps; worst cell "
        f"{result.get('decay_rate_per_period') or float('nan'):.6f}, "
        f"{result.get('decay_rate_with_model_error') or float('nan'):.6f} "
        f"with what its corners leave out{cut}; CPU {cpu:.1f} s, wall "
        f"{wall:.1f} s",
        flush=True,
    )


if __name__ == "__main__":
    main()
