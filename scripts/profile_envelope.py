"""The envelope of the paper cell over profile edges: fillet radius x side
x desired force on a 60 mm square, a partial pass through one corner per
cell (deburr_drake.runs.profile_envelope), in parallel processes. Prints
one line per cell and the pass count. Usage:

    nice -n 5 python scripts/profile_envelope.py [--workers N] [--json PATH]
        [--fillets MM,..] [--sides inner,outer] [--forces N,..]
        [--scenario NAME] [--scenario-text YAML]
"""

import argparse
import json
import sys
import time

from deburr_drake.runs import profile_envelope as pe
from deburr_drake.runs.envelope import run_cells


def _floats(text, scale=1.0):
    return [float(x) * scale for x in text.split(",") if x.strip()]


def _show(cell, row):
    """One cell's row of the table."""
    if "error" in row:
        print(f"{cell.label:>26s}: ERROR {row['error']}", flush=True)
        return
    print(
        f"{cell.label:>26s} | "
        f"{row['chamfer_depth_rms_error_mm']:9.4f} "
        f"{row['chamfer_depth_max_error_mm']:6.3f} | "
        f"{row['chamfering_force_rms_error_N']:7.3f} | "
        f"{row['feed_line_mm_s']:9.2f} {row['law_line_mm_s']:5.2f} "
        f"| {row['feed_fillet_mm_s']:6.2f} "
        f"{row['law_fillet_mm_s']:5.2f} | "
        f"{row['edge_coverage']:5.3f} | {row['stop_reason']:>13s} "
        f"| {row['sim_time_s']:4.0f} {row['wall_time_s']:4.0f} | "
        f"{'PASS' if row['passed'] else 'FAIL'}",
        flush=True,
    )


def _replay_json(args):
    """The rows of a --json file, the feed law's columns recomputed, each
    shown; returns the file's content."""
    from deburr_drake.config import load_scenario

    with open(args.from_json) as f:
        saved = json.load(f)
    base = load_scenario(args.scenario, text=args.scenario_text)
    for row in saved["rows"]:
        cell = pe.FilletCell(**row["cell"])
        if "error" not in row:
            laws = pe.law_feeds(
                pe.fillet_scenario(base, cell), row["fillet_curvature_1_m"]
            )
            row["law_line_mm_s"], row["law_fillet_mm_s"] = (
                v * 1e3 for v in laws
            )
        _show(cell, row)
    return saved


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--json", default=None, help="also write the rows here")
    p.add_argument("--fillets", default=None, help="fillet radii, mm")
    p.add_argument("--sides", default=None, help="inner and/or outer")
    p.add_argument("--forces", default=None, help="desired forces, N")
    p.add_argument("--scenario", default="paper")
    p.add_argument("--scenario-text", default=None)
    p.add_argument(
        "--from-json",
        default=None,
        help="print the table of a --json file instead of running"
        " (the feed law's columns recomputed)",
    )
    args = p.parse_args(argv)
    if args.workers < 1:
        p.error("--workers must be >= 1")
    cells = pe.grid(
        _floats(args.fillets, 1e-3) if args.fillets else pe.GRID_FILLETS,
        args.sides.split(",") if args.sides else pe.GRID_SIDES,
        _floats(args.forces) if args.forces else pe.GRID_FORCES,
    )
    print(
        f"{len(cells)} cells, {args.workers} worker processes, scenario "
        f"{args.scenario}"
        + (f" + {args.scenario_text!r}" if args.scenario_text else "")
        + "; bounds: "
        + ", ".join(f"{k} <= {v:g}" for k, v in pe.LIMITS.items()),
        flush=True,
    )
    print(
        f"{'cell':>26s} | {'depth rms':>9s} {'max':>6s} | {'f_t rms':>7s}"
        f" | {'feed line':>9s} {'law':>5s} | {'fillet':>6s} {'law':>5s} |"
        f" {'cover':>5s} | {'stop':>13s} | {'sim':>4s} {'wall':>4s} | pass"
    )
    print(
        f"{'':>26s} | {'mm':>9s} {'mm':>6s} | {'N':>7s} | {'mm/s':>9s} "
        f"{'mm/s':>5s} | {'mm/s':>6s} {'mm/s':>5s} | {'':>5s} | "
        f"{'':>13s} | {'s':>4s} {'s':>4s} |"
    )
    start = time.perf_counter()

    if args.from_json:
        saved = _replay_json(args)
        rows = saved["rows"]
    else:
        rows = run_cells(
            pe.run_fillet_cell,
            cells,
            args.scenario,
            args.scenario_text,
            workers=args.workers,
            on_row=_show,
        )
    wall = (
        saved["wall_time_s"] if args.from_json else time.perf_counter() - start
    )
    passed = sum(int(r["passed"]) for r in rows)
    print(
        f"\n{passed}/{len(rows)} cells pass; wall time {wall:.0f} s "
        f"with {args.workers} workers"
    )
    if args.json and not args.from_json:
        with open(args.json, "w") as f:
            json.dump({"rows": rows, "wall_time_s": wall}, f, indent=2)
    return 0 if passed == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
