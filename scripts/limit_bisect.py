"""Bisects a scenario's simulated stability limit in one parameter: runs
of ``--duration`` s with the guards off, at the shipped or the refined
numerics (:func:`deburr_drake.analysis.along.at_numerics`), each judged
by :func:`deburr_drake.analysis.validation.simulated_verdict` (the
verdict table's truth), until the bracket is within ``--tolerance``.

    python scripts/limit_bisect.py --scenario paper \\
        --text 'controller: {sliding_gain: [{v}, {v}, 1500.0]}' \\
        --lo 5656 --hi 6000 --duration 40 --numerics refined

``{v}`` in ``--text`` is the value tried. Each run prints its verdict,
the largest measured f_t after 2 s of contact and the std of the true
chamfering force's fast part (:func:`force_stability`).
"""

import argparse
import json
import time

import numpy as np

from deburr_drake.analysis.along import at_numerics, without_guards
from deburr_drake.analysis.validation import simulated_verdict
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.runs.convergence import force_stability
from deburr_drake.runs.simulation import simulate


def _contact_time(log):
    ch = log["chamfer"]
    on = (np.asarray(ch["delta"]) > 0) & (np.asarray(ch["f_n"]) > 0.5)
    return float(np.asarray(ch["t"])[np.argmax(on)]) if on.any() else np.inf


def judge(base, text, value, *, duration, numerics):
    """{value, verdict, max_f_t_N, fast_std_N, stop_reason, wall_s}."""
    scenario = load_scenario(base, text=text.replace("{v}", repr(value)))
    run = without_guards(at_numerics(scenario, numerics))
    wall = time.perf_counter()
    log = simulate(make_deburring_diagram(scenario=run), run, duration=duration)
    wall = time.perf_counter() - wall
    reference = simulated_verdict(log, scenario)
    fast = force_stability(log, _contact_time(log))
    return {
        "value": value,
        "verdict": reference["verdict"],
        "max_f_t_N": reference["max_f_t_N"],
        "fast_std_N": fast["fast_chamfering_force_std_N"],
        "max_true_f_t_N": fast["max_chamfering_force_N"],
        "stop_reason": log.stop_reason,
        "stop_time_s": log.stop_time,
        "wall_s": wall,
    }


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", default="paper")
    p.add_argument("--text", required=True, help="YAML with {v}")
    p.add_argument("--lo", type=float, required=True, help="stable")
    p.add_argument("--hi", type=float, required=True, help="unstable")
    p.add_argument("--duration", type=float, default=40.0)
    p.add_argument(
        "--numerics", choices=("refined", "shipped"), default="refined"
    )
    p.add_argument("--tolerance", type=float, default=0.02)
    p.add_argument(
        "--check-ends",
        action="store_true",
        help="run lo and hi first (else they are taken as given)",
    )
    p.add_argument("--json", default=None)
    args = p.parse_args(argv)
    lo, hi = args.lo, args.hi
    runs = []

    def unstable(v):
        r = judge(
            args.scenario,
            args.text,
            round(v, 1),
            duration=args.duration,
            numerics=args.numerics,
        )
        runs.append(r)
        print(
            f"{r['value']:10.1f} {r['verdict']:>8s} max f_t "
            f"{r['max_f_t_N']} N, fast std {r['fast_std_N']:.3g} N, "
            f"{r['stop_reason']} at {r['stop_time_s']:.2f} s "
            f"({r['wall_s']:.0f} s wall)",
            flush=True,
        )
        return r["verdict"] != "stable"

    if args.check_ends and (unstable(lo) or not unstable(hi)):
        print("the ends do not bracket a limit")
        _write(args.json, {"lo": lo, "hi": hi, "bracket": False, "runs": runs})
        return 1
    while hi - lo > args.tolerance * hi:
        mid = 0.5 * (lo + hi)
        if unstable(mid):
            hi = mid
        else:
            lo = mid
    print(
        f"limit between {lo:.1f} (stable) and {hi:.1f} (unstable): "
        f"{0.5 * (lo + hi):.1f} ({args.numerics}, {args.duration:g} s runs)"
    )
    _write(args.json, {"lo": lo, "hi": hi, "bracket": True, "runs": runs})
    return 0


def _write(path, out):
    if path:
        with open(path, "w") as f:
            json.dump(out, f, indent=2)


if __name__ == "__main__":
    raise SystemExit(main())
