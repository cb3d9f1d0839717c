"""What the commands share: loading the scenario, the progress line, the
exit codes, refusing bad input (one line, exit 2) and unwritable
targets, the pre-flight, and the arguments every command takes."""

from __future__ import annotations

import contextlib
import json
import signal

import numpy as np


def _load(args):
    from deburr_drake.config import load_scenario

    return load_scenario(args.scenario, text=args.scenario_text)


def _progress(t, wall, feed):
    print(
        f"  t = {t:6.2f} s simulated, {wall:6.1f} s wall, "
        f"feed {feed * 1e3:5.2f} mm/s",
        flush=True,
    )


#: Exit codes of ``deburr-drake`` (also in docs/scenarios.md, "Stop
#: reasons", and ``--help``).
EXIT_CODES = {
    "pass_complete": 0,
    "job_complete": 0,  # a job's every cut reached its end
    "duration": 0,  # a normal ending
    "error": 1,  # an exception during the run (outputs written)
    # 2: bad input (nothing run or written)
    "guard": 3,  # a runtime guard stopped the run (outputs written)
    "nan": 4,  # Drake detected a NaN (outputs written)
    "diverged": 5,  # the numerical sanity check ended it (outputs written)
    "probe_missed": 6,  # a touch found nothing (outputs written)
    "interrupted": 130,  # SIGINT (Ctrl-C); SIGTERM gives 143
}


_EXIT_HELP = (
    "exit codes: 0 the pass completed or the duration was reached; "
    "1 error during the run; 2 bad input (nothing run or written); "
    "3 a guard stopped the run; 4 NaN detected; 5 the run diverged "
    "(numerical sanity, guards or not); 6 a probing touch found "
    "nothing within its search distance; 130 interrupted "
    "(SIGINT), 143 terminated (SIGTERM). Every ending after the "
    "start writes logs.npz and metrics.json (stop_reason: "
    "pass_complete, duration, interrupted, guard:<name>, "
    "probe_missed:<touch index>, diverged, nan, error)."
)


def _bad(message: str):
    from deburr_drake.config import ConfigError

    raise ConfigError(message)


def _check_writable_target(
    path, what: str, force: bool, *, is_dir: bool, names=()
):
    """Refuses, before anything runs, a path that cannot be written or
    would overwrite existing results without ``--force``."""
    import os
    from pathlib import Path

    path = Path(path)
    if is_dir:
        if path.exists() and not path.is_dir():
            _bad(f"{what} {path} is not a directory")
        existing = [n for n in names if (path / n).exists()]
        if existing and not force:
            _bad(
                f"{what} {path} already holds {', '.join(existing)}: "
                "choose another directory or pass --force to overwrite"
            )
    else:
        if path.is_dir():
            _bad(f"{what} {path} is a directory: allowed a file path")
        if path.exists() and not force:
            _bad(f"{what} {path} already exists: pass --force to overwrite")
    probe = path if is_dir else path.parent
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        _bad(f"{what} {path} cannot be created: {probe} is not a directory")
    if not os.access(probe, os.W_OK | os.X_OK):
        _bad(f"{what} {path} cannot be written: no write permission in {probe}")


@contextlib.contextmanager
def _sigterm_as_interrupt():
    """Within the block SIGTERM raises KeyboardInterrupt, as Ctrl-C does,
    so a command keeps what it finished; yields the signals received."""
    received = []

    def on_term(number, frame):
        received.append(number)
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, on_term)
    try:
        yield received
    finally:
        signal.signal(signal.SIGTERM, previous)


def _check_duration(duration):
    if not (np.isfinite(duration) and duration > 0):
        _bad(
            f"--duration = {duration!r} is invalid: allowed a finite "
            "number > 0 (simulated seconds)"
        )


def _interrupted_exit_code(received) -> int:
    """130 (SIGINT, Ctrl-C), or 143 when SIGTERM is among the signals
    ``received``."""
    return 143 if signal.SIGTERM in received else EXIT_CODES["interrupted"]


def _exit_code(log, signal_number) -> int:
    reason = log.stop_reason
    if reason == "interrupted":
        return _interrupted_exit_code([signal_number])
    return EXIT_CODES.get(reason.split(":", 1)[0], 1)


def _print_metrics(values: dict):
    import math

    reasons = getattr(values, "reasons", {})
    width = max(len(k) for k in values)
    missing = {}
    for key in sorted(values):
        v = values[key]
        if isinstance(v, float) and not math.isfinite(v):
            print(f"  {key:{width}s} {'n/a':>12s}")
            missing.setdefault(reasons.get(key, "not finite"), []).append(key)
        else:
            print(f"  {key:{width}s} {v:12.5g}")
    for reason, keys in missing.items():
        print(f"  n/a: {reason}: {', '.join(keys)}")


def _preflight(args, plan, diagram=None):
    """The designed gains (controller.design auto) proven and the sampled
    loop's check at the start pose (deburr_drake.analysis.preflight), on
    ``diagram`` (the run's) if given, unless --no-preflight; ConfigError
    (exit 2) if predicted unstable. Returns what it found, or None."""
    from deburr_drake.analysis.preflight import preflight

    if getattr(args, "no_preflight", False):
        print("pre-flight skipped (--no-preflight)", flush=True)
        return None
    return preflight(
        plan, diagram=diagram, say=lambda line: print(line, flush=True)
    )


def _planned(args, scenario, build=None, meshcat=None):
    """(plan, diagram, found): the scenario planned (the reach checked),
    its pre-flight (None with --no-preflight) on the diagram ``build(plan)``
    builds, if given (else None); where the pre-flight scaled the design
    down, the plan it checked and its diagram (built anew to draw in
    ``meshcat``)."""
    from deburr_drake.cell.diagram import make_deburring_diagram
    from deburr_drake.cell.plan import plan_cell

    plan = plan_cell(scenario)
    diagram = None if build is None else build(plan)
    found = _preflight(args, plan, diagram)
    if found is not None and found.plan is not plan:
        plan = found.plan
        if diagram is not None:
            diagram = (
                found.diagram
                if meshcat is None
                else make_deburring_diagram(plan, meshcat=meshcat)
            )
    return plan, diagram, found


def _write_resolved(out, scenario, found):
    """scenario.yaml (the scenario as run: the designed gains written) and,
    after a pre-flight, preflight.json, so the run can be repeated."""
    from pathlib import Path

    from pydrake.common.yaml import yaml_dump_typed

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "scenario.yaml").write_text(yaml_dump_typed(scenario))
    if found is not None:
        (out / "preflight.json").write_text(
            json.dumps(found.to_dict(), indent=2, sort_keys=True)
        )


def _scenario_arguments(parser, default: str, duration_help: str):
    parser.add_argument(
        "--scenario",
        default=default,
        help=f"scenario name or YAML file (default {default})",
    )
    parser.add_argument(
        "--scenario-text",
        default=None,
        help="YAML overrides applied on top of the scenario",
    )
    if duration_help:
        parser.add_argument(
            "--duration", type=float, default=None, help=duration_help
        )


def _preflight_argument(parser):
    parser.add_argument(
        "--no-preflight",
        action="store_true",
        help="run even if the sampled loop at the start pose is predicted "
        "unstable (the gains of controller.design: auto are still "
        "designed, not proven)",
    )


def _output_arguments(parser, default, overwritten):
    """--out (``default`` when not given) and --force, which overwrites
    ``overwritten``: every command refuses its own outputs in --out
    without it."""
    parser.add_argument(
        "--out", default=None, help=f"output directory (default {default})"
    )
    parser.add_argument(
        "--force", action="store_true", help=f"overwrite {overwritten}"
    )
