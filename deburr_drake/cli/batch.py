"""``deburr-drake batch``: a batch of parts, each with its own part
error, the controller's learning carried from part to part."""

from __future__ import annotations

from deburr_drake.cli.common import (
    _EXIT_HELP,
    _bad,
    _check_duration,
    _load,
    _scenario_arguments,
)


def _batch(args) -> int:
    from pathlib import Path

    from deburr_drake.runs.batch import batch_table, run_batch, write_batch

    scenario = _load(args)
    if args.duration is not None:
        _check_duration(args.duration)
    if not args.parts >= 1:
        _bad(f"--parts = {args.parts!r} is invalid: allowed an integer >= 1")
    out = Path(args.out or f"out/batch_{scenario.name}")
    carried = {
        "all": "c hat and theta",
        "estimates": "c hat",
        "weights": "theta",
    }[args.carry]
    mode = (
        "fresh (a cold start per part)"
        if args.fresh
        else f"carrying {carried} from part to part"
    )
    print(
        f"deburr-drake batch: {args.parts} parts of '{scenario.name}', "
        f"offsets up to {args.max_offset * 1e3:g} mm (seed {args.seed}), "
        f"{mode}, output {out}/",
        flush=True,
    )

    done = []

    def on_part(part, log):
        from deburr_drake.runs import report

        done.append(part)
        write_batch(done, out, label=f"{scenario.name}, {mode}")
        report.write_run(log, out / f"part{part.part}", part.values)
        m = part.metrics
        print(
            f"  part {part.part}: offset ({part.offset[0] * 1e3:+.3f}, "
            f"{part.offset[1] * 1e3:+.3f}) mm, {log.stop_reason} at "
            f"{log.stop_time:.2f} s, depth RMS "
            f"{m.get('chamfer_depth_rms_error_mm', float('nan')):.4f} mm, "
            f"first 10 % "
            f"{m.get('first_10pct_depth_rms_error_mm', float('nan')):.4f}"
            f" mm, {log.wall_time:.0f} s wall",
            flush=True,
        )

    parts = run_batch(
        scenario,
        count=args.parts,
        seed=args.seed,
        max_offset=args.max_offset,
        max_yaw=args.max_yaw,
        fresh=args.fresh,
        carry=args.carry,
        duration=args.duration,
        on_part=on_part,
    )
    paths = write_batch(parts, out, label=f"{scenario.name}, {mode}")
    print()
    print(batch_table(parts))
    print(f"\nwrote {', '.join(str(p) for p in paths.values())}")
    bad = [
        p.part
        for p in parts
        if p.stop_reason.split(":")[0] not in ("pass_complete", "duration")
    ]
    return 3 if bad else 0


def _add_batch_parser(subparsers):
    p = subparsers.add_parser(
        "batch",
        help="K parts in sequence through one cell "
        "(probe, cut, next), the learning "
        "carried from part to part",
        epilog=_EXIT_HELP,
    )
    _scenario_arguments(
        p,
        "paper_localised",
        "simulated seconds at most per part (default: the "
        "scenario's, a full pass)",
    )
    p.add_argument("--parts", type=int, default=10, help="K (default 10)")
    p.add_argument(
        "--seed", type=int, default=1, help="seeds the part errors (default 1)"
    )
    p.add_argument(
        "--max-offset",
        type=float,
        default=0.001,
        help="m: part offsets uniform over a disc of this "
        "radius (default 0.001)",
    )
    p.add_argument(
        "--max-yaw",
        type=float,
        default=0.0,
        help="rad: part yaw uniform within +- this (default 0)",
    )
    p.add_argument(
        "--fresh",
        action="store_true",
        help="a cold start per part (nothing carried over)",
    )
    p.add_argument(
        "--carry",
        choices=["all", "estimates", "weights"],
        default="all",
        help="what passes from part to part: the contact "
        "estimates c hat and the fuzzy weights theta (all, "
        "default), or one of them",
    )
    p.add_argument(
        "--out",
        default=None,
        help="output directory (default out/batch_<scenario>)",
    )
    p.set_defaults(func=_batch)
