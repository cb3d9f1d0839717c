"""The ``deburr-drake`` command line. Thin: parses arguments and calls the
library."""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

__all__ = ["main"]


def _load(args):
    from deburr_drake.config import load_scenario
    return load_scenario(args.scenario, text=args.scenario_text)


def _progress(t, wall, feed):
    print(f"  t = {t:6.2f} s simulated, {wall:6.1f} s wall, "
          f"feed {feed * 1e3:5.2f} mm/s", flush=True)


def _simulate(args) -> int:
    from pathlib import Path

    from deburr_drake import demo, figures, report
    from deburr_drake.cell import make_deburring_diagram
    from deburr_drake.simulation import simulate
    scenario = _load(args)
    if args.duration is not None:
        scenario.simulation.duration = args.duration
        scenario.validate()
    out = Path(args.out or f"out/{scenario.name}")
    passes = scenario.simulation.stop_after_passes
    print(f"deburr-drake simulate: scenario '{scenario.name}' "
          f"({scenario.robot.model}, m = {scenario.controller.fuzzy.order}), "
          f"up to {scenario.simulation.duration:g} s"
          + (f" or {passes:g} pass(es)" if passes else "")
          + f", output {out}/", flush=True)
    meshcat = None
    if args.meshcat or args.record:
        from pydrake.geometry import Meshcat
        meshcat = Meshcat()
        if args.meshcat:
            print(f"Meshcat: {meshcat.web_url()}", flush=True)
    diagram = make_deburring_diagram(scenario=scenario, meshcat=meshcat)
    if args.record:
        meshcat.StartRecording(frames_per_second=10.0)
    log = simulate(diagram, scenario, progress=_progress,
                   progress_interval=args.progress_interval)
    if args.record:
        from deburr_drake.replay import write_recording
        path = write_recording(meshcat, args.record)
        print(f"wrote the replay {path}")
    truth = demo.contact_truth(scenario)
    values = report.pass_metrics(
        log, true_force_at_desired_depth=truth.force_at_desired_depth)
    files = report.write_run(log, out, values)
    with np.load(files["logs"]) as logs:
        pngs = figures.make_figures(
            dict(logs), out,
            label=f"{scenario.name} (m = {scenario.controller.fuzzy.order})")
    print()
    width = max(len(k) for k in values)
    for key in sorted(values):
        print(f"  {key:{width}s} {values[key]:12.5g}")
    print(f"\nwrote {files['logs']}, {files['metrics']} and "
          f"{len(pngs)} figures in {out}/")
    return 0


def _demo(args) -> int:
    from deburr_drake import demo
    scenario = _load(args)
    duration = args.duration or 5.0
    print(f"deburr-drake demo: point-mass testbed, scenario "
          f"'{scenario.name}', {duration:g} s")
    truth = demo.contact_truth(scenario)
    print("contact truth (Drake hydroelastic + process threshold): "
          f"||f_n(delta*)|| = {truth.force_at_desired_depth:.3f} N, "
          f"local stiffness {truth.local_stiffness / 1e3:.2f} N/mm")
    print("run 1/2: adaptation off, estimates at the truth (eq. 8)")
    frozen = demo.run(demo.frozen_adaptation(scenario, truth),
                      min(duration, 3.0), progress=_progress)
    print("run 2/2: adaptive (estimator and fuzzy rules on)")
    log = demo.run(scenario, duration, progress=_progress)
    summary = demo.summarize(log, truth, frozen)
    rows = [
        ("delta_d time constant, adaptation off", "depth_time_constant",
         1.0, "s"),
        ("  eq. (8) with the local stiffness", "depth_time_constant_eq8",
         1.0, "s"),
        ("final depth (adaptive)", "depth_final", 1e3, "mm"),
        ("max |delta - delta*| after 2 s", "depth_max_error_after_settle",
         1e3, "mm"),
        ("c0 + c1 delta* (estimated)", "predicted_force_at_desired_depth",
         1.0, "N"),
        ("true ||f_n|| at delta*", "true_force_at_desired_depth", 1.0, "N"),
        ("  relative error", "force_prediction_error_rel", 1.0, ""),
        ("commanded feed (mean after 2 s)", "commanded_feed_mean", 1e3,
         "mm/s"),
        ("feedrate law on measured signals", "feedrate_law_mean", 1e3,
         "mm/s"),
        ("command speed along the contour", "command_speed", 1e3, "mm/s"),
        ("chamfering force (mean after 2 s)", "chamfering_force_mean", 1.0,
         "N"),
        ("fraction of s in the dead zone after 2 s",
         "dead_zone_fraction_after_settle", 1.0, ""),
        ("NaN detected", "nan_detected", 1.0, ""),
        ("wall time of the adaptive run", "wall_time_s", 1.0, "s"),
    ]
    print()
    for label, key, scale, unit in rows:
        print(f"  {label:42s} {summary[key] * scale:10.4f} {unit}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(summary, f, indent=2)
    return 0


def _diagram(args) -> int:
    from pathlib import Path

    from deburr_drake.cell import make_deburring_diagram
    from deburr_drake.graphs import write_graphs
    scenario = _load(args)
    diagram = make_deburring_diagram(scenario=scenario)
    out = Path(args.out or f"out/{scenario.name}/diagram.dot")
    written, message = write_graphs(diagram, out, fmt=args.format,
                                    max_depth=args.depth)
    for path in written:
        print(f"wrote {path}")
    if message:
        print(f"deburr-drake: {message}", file=sys.stderr)
    return 0


def _analyze(args) -> int:
    from pathlib import Path

    from deburr_drake import analysis
    scenario = _load(args)
    grid = analysis.parse_map(scenario, args.map) if args.map else None
    overrides = analysis.parse_settings(scenario, args.set or [])
    out = Path(args.out or f"out/{scenario.name}/analysis")
    out.mkdir(parents=True, exist_ok=True)
    result = analysis.analyze(scenario, at=args.at,
                              after_contact=args.after_contact,
                              overrides=overrides,
                              progress=lambda m: print(f"  {m}", flush=True))
    if args.validate:
        result["boundaries"] = analysis.validate_boundaries(
            result["_objects"]["op"],
            progress=lambda m: print(f"  {m}", flush=True))
    if args.lyapunov:
        trace = analysis.lyapunov_trace(scenario, duration=args.lyapunov)
        result["lyapunov"] = trace.summary
        analysis.plot_lyapunov(trace, out / "lyapunov.png",
                               title=scenario.name)
    if grid is not None:
        result["_objects"]["map"] = analysis.stability_map(
            result["_objects"]["op"], grid)
        result["map"] = result["_objects"]["map"].to_dict()
    files = analysis.write_analysis(result, out)
    print()
    print(analysis.summary_text(result))
    print("\nwrote " + ", ".join(str(p) for p in files.values()))
    return 0


def _scenario_arguments(parser, default: str, duration_help: str):
    parser.add_argument("--scenario", default=default,
                        help=f"scenario name or YAML file (default {default})")
    parser.add_argument("--scenario-text", default=None,
                        help="YAML overrides applied on top of the scenario")
    if duration_help:
        parser.add_argument("--duration", type=float, default=None,
                            help=duration_help)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="deburr-drake",
        description="Adaptive fuzzy hybrid position/force deburring on "
                    "Drake (Hsu & Fu, 2000).")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("demo", help="run the point-mass testbed and print "
                                    "its convergence numbers")
    _scenario_arguments(p, "point_mass",
                        "simulated seconds of the adaptive run (default 5)")
    p.add_argument("--json", default=None, help="also write the numbers")
    p.set_defaults(func=_demo)

    p = sub.add_parser("simulate", help="run a deburring scenario (the "
                                        "paper's experiment by default)")
    _scenario_arguments(p, "paper",
                        "simulated seconds at most (default: the scenario's)")
    p.add_argument("--out", default=None,
                   help="output directory (default out/<scenario>)")
    p.add_argument("--progress-interval", type=float, default=5.0,
                   help="simulated seconds between progress lines")
    p.add_argument("--meshcat", action="store_true",
                   help="show the run live in Meshcat (prints the URL)")
    p.add_argument("--record", default=None, metavar="PATH.html",
                   help="write a self-contained HTML replay of the run")
    p.set_defaults(func=_simulate)

    p = sub.add_parser("diagram", help="export the diagram and the "
                                       "controller as GraphViz graphs")
    _scenario_arguments(p, "paper", None)
    p.add_argument("--depth", type=int, default=None,
                   help="levels of nesting to expand (default: all)")
    p.add_argument("--format", choices=("dot", "svg", "png"), default="dot",
                   help="also render with GraphViz's dot (default: .dot "
                        "only)")
    p.add_argument("--out", default=None,
                   help="output path (default out/<scenario>/diagram.dot)")
    p.set_defaults(func=_diagram)

    p = sub.add_parser("analyze", help="closed-loop stability at an "
                                       "operating point in steady cutting")
    _scenario_arguments(p, "paper", None)
    p.add_argument("--at", type=float, default=None,
                   help="simulated time (s) of the operating point "
                        "(default: --after-contact s after the first "
                        "contact)")
    p.add_argument("--after-contact", type=float, default=3.0,
                   help="seconds of cutting before the operating point "
                        "(default 3)")
    p.add_argument("--map", nargs="+", default=None,
                   metavar="FIELD=LO:HI:N",
                   help="stability map of rho over one or two scenario "
                        "fields by dotted name, e.g. "
                        "sensor.cutoff_frequency=5:80:16 "
                        "controller.sliding_gain[0]=100:3000:16")
    p.add_argument("--set", nargs="+", default=None,
                   metavar="FIELD=VALUE",
                   help="analyse the operating point with these scenario "
                        "fields changed (the scenario as given reaches "
                        "steady cutting first), e.g. "
                        "controller.sliding_gain[0]=4500")
    p.add_argument("--lyapunov", type=float, default=None,
                   metavar="SECONDS",
                   help="also run the scenario this long and trace V1 of "
                        "Prop. 1 and V of (38) (lyapunov.png)")
    p.add_argument("--validate", action="store_true",
                   help="predicted against simulated stability boundaries "
                        "(short runs from the operating point)")
    p.add_argument("--out", default=None,
                   help="output directory (default out/<scenario>/analysis)")
    p.set_defaults(func=_analyze)
    args = parser.parse_args(argv)
    from deburr_drake.config import ConfigError
    try:
        return args.func(args)
    except ConfigError as e:
        print(f"deburr-drake: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
