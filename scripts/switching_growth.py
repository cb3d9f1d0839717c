"""Whether a scenario's loop grows under a variation within its box, at
one or more integration steps: ``certify``'s switching search
(:func:`deburr_drake.analysis.box_certificate.switching_growth`) over the
whole box, the constants (k_c, c0, the mass scale, held slopes) at each
corner of the box, every two corners of the time-varying parameters
switched periodically. A growth above 1 at every step means no Lyapunov
function of any form proves the box for variations however fast; below
1 it is a lower bound of the joint spectral radius.

    python scripts/switching_growth.py --scenario paper_6dof --halvings 0 2 3
    python scripts/switching_growth.py --scenario paper --halvings 0 2

``--halvings H``: the scenario's max step halved H times (0: as shipped;
2: ``certify --numerics refined``), with eq. (3) between samples as the
refined runs take it.
"""

import argparse
import time

from deburr_drake.analysis import box_certificate as bc
from deburr_drake.analysis.operating_point import find_operating_point
from deburr_drake.config import ConfigError, load_scenario
from deburr_drake.runs.convergence import refined


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="paper_6dof")
    parser.add_argument("--scenario-text", default=None)
    parser.add_argument("--halvings", type=int, nargs="+", default=[0, 2])
    args = parser.parse_args()
    try:
        shipped = load_scenario(args.scenario, text=args.scenario_text)
    except ConfigError as error:
        raise SystemExit(f"switching_growth.py: {error}") from None
    for halvings in args.halvings:
        scenario = refined(shipped, halvings) if halvings else shipped
        start = time.process_time()
        op = find_operating_point(
            scenario, after_contact=bc.DEFAULT_TIME_AFTER_CONTACT
        )
        box, _ = bc._select_box(bc._box(op), None)
        constants = bc._first_grid(box, None)
        cell = [{**p, "constant": p["key"] in constants} for p in box]
        maps_at = bc._Maps(op, box, bc.SETTLE_PERIODS)
        labels = bc._labels(maps_at.frozen({}))
        record = bc.switching_growth(maps_at, cell, labels)
        print(
            f"{scenario.name}, max step {scenario.simulation.max_step:g} s "
            f"({len(maps_at.taken)} maps, {time.process_time() - start:.1f} "
            f"s CPU): {bc._switching_text(record)}; the others at "
            f"{record['others']}",
            flush=True,
        )


if __name__ == "__main__":
    main()
