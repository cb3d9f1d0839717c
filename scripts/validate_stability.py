"""Predicted against simulated stability: (1) analyze's verdict against
20 s simulations with the guards off, over scenarios written with
--scenario-text (gains, sensor, fuzzy surface, burrs, depth gain, the
6-DOF arm); (2) predicted (rho of the one-period map = 1) against
simulated (short runs from the operating point) stability boundaries for
the sensor's cutoff frequency, the sliding gain on the fuzzy axes and the
fuzzy surface's slope.

    python scripts/validate_stability.py verdicts [--rows 0 1 ...]
        [--duration 20] [--numerics refined|shipped] [--json OUT.json]
    python scripts/validate_stability.py boundaries
        [--scenario point_mass paper] [--duration 1.0]
        [--tolerance 0.02] [--json OUT.json]
"""

import argparse
import json
import sys
import time

from deburr_drake.analysis import (
    VERDICT_SCENARIOS,
    find_operating_point,
    validate_boundaries,
    verdict_row,
)
from deburr_drake.config import ConfigError, load_scenario


def _fmt(x):
    if x is None:
        return "none in range"
    return f"{x:.4g}"


def _verdicts(args):
    rows = []
    picked = args.rows if args.rows else range(len(VERDICT_SCENARIOS))
    print(
        f"{'#':>2s} {'scenario':40s} {'analyze':>8s} {'simulation':>10s} "
        f"{'max f_t (N)':>11s} {'rho max':>8s} {'osc (Hz)':>8s} "
        f"{'guard':>13s} {'agree':>5s}",
        flush=True,
    )
    for i in picked:
        label, base, text = VERDICT_SCENARIOS[i]
        r = verdict_row(
            label, base, text, duration=args.duration, numerics=args.numerics
        )
        r["index"] = i
        rows.append(r)
        sim = r["simulation"]
        ft = sim["max_f_t_N"]
        guard = f"{r['guard']}@{r['guard_time_s']:.2f}" if r["guard"] else "-"
        rho = r["rho_max_along_run"]
        hz = r["oscillation_hz"]
        print(
            f"{i:2d} {label:40s} {r['verdict']:>8s} "
            f"{sim['verdict']:>10s} "
            f"{'-' if ft is None else f'{ft:.1f}':>11s} "
            f"{'-' if rho is None else format(rho, '.5f'):>8s} "
            f"{'-' if hz is None else format(hz, '.1f'):>8s} "
            f"{guard:>13s} {'yes' if r['agree'] else 'NO':>5s}",
            flush=True,
        )
        if args.json:  # row by row: a long table survives an interruption
            _write(args.json, rows)
    agree = sum(r["agree"] for r in rows)
    print(
        f"\n{agree}/{len(rows)} agree (simulation: {args.duration:g} s, "
        "guards off; unstable when, after 2 s of contact, the measured "
        "|f_t| exceeds 2 x the desired force or the depth leaves "
        "delta* +- 50 %, or the run fails)"
    )
    for r in rows:
        print(f"  {r['index']:2d} {r['label']}: {r['verdict_reason']}")
    return rows


def _write(path, out):
    with open(path, "w") as f:
        json.dump(out, f, indent=2, default=str)


def _boundaries(args):
    table = {}
    for name in args.scenario:
        start = time.perf_counter()
        op = find_operating_point(load_scenario(name))
        rows = validate_boundaries(
            op,
            duration=args.duration,
            rel_tol=args.tolerance,
            progress=lambda m: print(f"  [{name}] {m}", flush=True),
        )
        table[name] = rows
        print(
            f"\n{name} (operating point t = {op.time:.3f} s, "
            f"{time.perf_counter() - start:.0f} s wall)"
        )
        print(
            f"  {'parameter':52s} {'range':>15s} {'predicted':>13s} "
            f"{'simulated':>13s} {'apart':>7s}"
        )
        for r in rows:
            apart = (
                f"{100 * r['error_rel']:.1f} %"
                if r["error_rel"] is not None
                else "-"
            )
            rng = f"{r['range'][0]:g}-{r['range'][1]:g}"
            print(
                f"  {r['parameter'] + ' (' + r['unit'] + ')':52s} "
                f"{rng:>15s} {_fmt(r['predicted']):>13s} "
                f"{_fmt(r['simulated']):>13s} {apart:>7s}",
                flush=True,
            )
    return table


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="what", required=True)
    p = sub.add_parser("verdicts")
    p.add_argument(
        "--rows",
        type=int,
        nargs="+",
        default=None,
        help="indices into VERDICT_SCENARIOS (default all)",
    )
    p.add_argument("--duration", type=float, default=20.0)
    p.add_argument(
        "--numerics",
        choices=("refined", "shipped"),
        default="refined",
        help="of analyze's run and of the reference simulation",
    )
    p.add_argument("--json", default=None)
    p = sub.add_parser("boundaries")
    p.add_argument("--scenario", nargs="+", default=["point_mass", "paper"])
    p.add_argument(
        "--duration",
        type=float,
        default=1.0,
        help="simulated seconds per stability run",
    )
    p.add_argument(
        "--tolerance",
        type=float,
        default=0.02,
        help="relative bisection tolerance",
    )
    p.add_argument("--json", default=None)
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] not in ("verdicts", "boundaries", "-h", "--help"):
        argv.insert(0, "boundaries")  # the script's earlier usage
    args = parser.parse_args(argv)
    try:
        out = _verdicts(args) if args.what == "verdicts" else _boundaries(args)
    except ConfigError as e:
        print(f"validate_stability: error: {e}", file=sys.stderr)
        return 2
    if args.json:
        _write(args.json, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
