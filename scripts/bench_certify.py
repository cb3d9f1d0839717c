"""What ``certify`` costs on a scenario, and what a neighbouring cell's P
saves: the certificate run with ``NEIGHBOUR_CANDIDATES`` at each value
given, one after the other in this process (the same host, the same
hour), printing for each the status, the cells tried, the programs
solved (the load-independent count), how many cells a neighbour's P
served, and the process's CPU and wall time.

    python scripts/bench_certify.py --scenario paper --candidates 0 2
    python scripts/bench_certify.py --scenario paper \\
        --scenario-text 'controller: {fuzzy: {adapt: false}}' --candidates 0 2
"""

import argparse
import time

from deburr_drake.analysis import box_certificate
from deburr_drake.analysis.certificate import FOUND_BY_NEIGHBOUR
from deburr_drake.config import load_scenario


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="paper")
    parser.add_argument("--scenario-text", default=None)
    parser.add_argument("--box", nargs="*", default=None)
    parser.add_argument("--candidates", nargs="+", type=int, default=[0, 2])
    args = parser.parse_args()
    scenario = load_scenario(args.scenario, text=args.scenario_text)
    for n in args.candidates:
        box_certificate.NEIGHBOUR_CANDIDATES = n
        wall, cpu = time.perf_counter(), time.process_time()
        result = box_certificate.certify(scenario, only=args.box)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        cells = result["constant_cells"]
        solves = sum(c["solves"] or 0 for c in cells)
        served = sum(c["found_by"] == FOUND_BY_NEIGHBOUR for c in cells)
        print(
            f"candidates {n}: {result['status']}, {result['cells_tried']}; "
            f"{solves} programs solved, {served} cells served by a "
            f"neighbour's P; {result['vertices']} true maps; "
            f"CPU {cpu:.1f} s, wall {wall:.1f} s",
            flush=True,
        )


if __name__ == "__main__":
    main()
