"""The stability envelope of the paper cell over burr size and desired force
(one burr per run, 40 s at most or until the cutter is past the burr), in
parallel processes. Prints one line per cell and the pass count; the bounds
are deburr_drake.runs.envelope's. Usage:

    python scripts/envelope.py [--workers N] [--json PATH]
        [--heights MM,..] [--lengths MM,..] [--forces N,..]
        [--scenario NAME] [--scenario-text YAML]
"""

import argparse
import json
import sys
import time

from deburr_drake.runs import envelope


def _floats(text, scale=1.0):
    return [float(x) * scale for x in text.split(",") if x.strip()]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--json", default=None, help="also write the rows here")
    p.add_argument("--heights", default=None, help="burr heights, mm")
    p.add_argument("--lengths", default=None, help="burr lengths, mm")
    p.add_argument("--forces", default=None, help="desired forces, N")
    p.add_argument("--scenario", default="paper")
    p.add_argument("--scenario-text", default=None)
    args = p.parse_args(argv)
    if args.workers < 1:
        p.error("--workers must be >= 1")
    cells = envelope.grid(
        _floats(args.heights, 1e-3) if args.heights else envelope.GRID_HEIGHTS,
        _floats(args.lengths, 1e-3) if args.lengths else envelope.GRID_LENGTHS,
        _floats(args.forces) if args.forces else envelope.GRID_FORCES,
    )
    print(
        f"{len(cells)} cells, {args.workers} worker processes, scenario "
        f"{args.scenario}"
        + (f" + {args.scenario_text!r}" if args.scenario_text else ""),
        flush=True,
    )
    header = (
        f"{'burr h x L (mm)':>16s} {'f_d':>4s} | {'max f_t':>8s} "
        f"{'bound':>6s} | {'max v':>6s} {'bound':>6s} | "
        f"{'depth rms':>9s} | {'feed on':>7s} {'law':>6s} | {'NaN':>3s}"
        f" | {'sim':>5s} {'wall':>5s} | pass"
    )
    print(header)
    print(
        f"{'':>16s} {'N':>4s} | {'N':>8s} {'N':>6s} | {'mm/s':>6s} "
        f"{'mm/s':>6s} | {'mm':>9s} | {'mm/s':>7s} {'mm/s':>6s} | "
        f"{'':>3s} | {'s':>5s} {'s':>5s} |"
    )
    start = time.perf_counter()

    def show(cell, row):
        if "error" in row:
            print(f"{cell.label}: ERROR {row['error']}", flush=True)
            return
        b = row["bounds"]
        print(
            f"{cell.height * 1e3:7.1f} x {cell.length * 1e3:5.0f} "
            f"{cell.force:4.0f} | "
            f"{row['max_chamfering_force_N']:8.2f} "
            f"{b['max_chamfering_force_N']:6.1f} | "
            f"{row['max_tool_speed_m_s'] * 1e3:6.2f} "
            f"{b['max_tool_speed_m_s'] * 1e3:6.2f} | "
            f"{row['depth_rms_error_on_burr_m'] * 1e3:9.4f} | "
            f"{row['feed_on_burr_m_s'] * 1e3:7.3f} "
            f"{row['feed_law_on_burr_m_s'] * 1e3:6.3f} | "
            f"{'yes' if row['nan'] else 'no':>3s} | "
            f"{row['sim_time_s']:5.1f} {row['wall_time_s']:5.1f} | "
            f"{'PASS' if row['passed'] else 'FAIL'}",
            flush=True,
        )

    rows = envelope.run_cells(
        envelope.run_burr_cell,
        cells,
        args.scenario,
        args.scenario_text,
        workers=args.workers,
        on_row=show,
    )
    wall = time.perf_counter() - start
    passed = sum(int(r["passed"]) for r in rows)
    print(
        f"\n{passed}/{len(rows)} cells pass; wall time {wall:.0f} s "
        f"with {args.workers} workers"
    )
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"rows": rows, "wall_time_s": wall}, f, indent=2)
    return 0 if passed == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
