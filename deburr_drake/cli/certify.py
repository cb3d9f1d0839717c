"""``deburr-drake certify``: a stability certificate of the sampled loop
over a box of parameters, certificate.json in --out."""

from __future__ import annotations

from deburr_drake.cli.common import (
    _check_writable_target,
    _interrupted_exit_code,
    _load,
    _output_arguments,
    _scenario_arguments,
    _sigterm_as_interrupt,
)

#: The search's default time limit (s): a slope schedule's program can
#: run for tens of minutes without an answer, and a command should end
#: by itself.
MAX_TIME = 1800.0

#: What ``certify`` writes into its output directory.
_CERTIFY_OUTPUTS = ("certificate.json", "maps.npz")


def _certify(args) -> int:
    import json
    from pathlib import Path

    import numpy as np

    from deburr_drake import analysis
    from deburr_drake.analysis.box_certificate import BOX_KEYS
    from deburr_drake.config import ConfigError, set_field

    # The scenario and every option, checked before anything runs.
    scenario = _load(args)
    settings = analysis.parse_settings(scenario, args.set or [])
    for path, value in settings.items():
        set_field(scenario, path, value)
    scenario.validate()
    if args.box is not None:
        allowed = list(BOX_KEYS.values()) + [
            f"slope_x{axis + 1}" for axis in scenario.controller.fuzzy.axes
        ]
        for key in args.box:
            if key not in allowed:
                raise ConfigError(
                    f"--box {key!r} is invalid: allowed {', '.join(allowed)}"
                )
    if not args.max_time > 0:
        raise ConfigError(
            f"--max-time {args.max_time:g} is invalid: a positive number "
            "of seconds"
        )
    out = Path(args.out or f"out/{scenario.name}/certificate")
    _check_writable_target(
        out, "--out", args.force, is_dir=True, names=_CERTIFY_OUTPUTS
    )
    out.mkdir(parents=True, exist_ok=True)

    def say(message):
        print(f"  {message}", flush=True)

    # As Ctrl-C: the cells finished so far are written.
    with _sigterm_as_interrupt() as received:
        try:
            result = analysis.certify(
                scenario,
                numerics=args.numerics,
                solver=args.solver,
                bisections=args.bisections,
                only=args.box,
                progress=say,
                max_time=args.max_time,
            )
        except KeyboardInterrupt:
            result = {
                "scenario": scenario.name,
                "status": "inconclusive",
                "stop_reason": "interrupted",
                "breaking_reason": "interrupted before a cell was finished",
            }
    result["settings"] = settings
    path = out / "certificate.json"
    maps = result.pop("_maps", None)
    path.write_text(json.dumps(result, indent=2) + "\n")
    if maps is not None:
        np.savez_compressed(
            out / "maps.npz",
            maps=np.array(maps["family"]),
            names=np.array(maps["names"]),
            labels=np.array(maps["labels"]),
        )
        print(analysis.certificate_summary(result))
    else:
        (out / "maps.npz").unlink(missing_ok=True)  # not this run's
        # No cell finished: no summary, only why.
        print(result["breaking_reason"])
    print(f"\nwrote {path}")
    if result["stop_reason"] == "interrupted":
        return _interrupted_exit_code(received)
    return 0


def _add_certify_parser(subparsers):
    p = subparsers.add_parser(
        "certify",
        help="a stability certificate: a common Lyapunov function of the "
        "sampled loop's maps over a box of parameters",
    )
    _scenario_arguments(p, "paper", None)
    p.add_argument(
        "--set",
        nargs="+",
        default=None,
        metavar="FIELD=VALUE",
        help="certify the scenario with these fields changed (its run "
        "too), e.g. controller.sliding_gain[0]=4500",
    )
    p.add_argument(
        "--numerics",
        choices=("shipped", "refined"),
        default="shipped",
        help="how the run to the operating point and the maps are "
        "integrated: shipped (default, the scenario's step) or refined "
        "(a quarter of it, as analyze's verdict)",
    )
    p.add_argument(
        "--bisections",
        type=int,
        default=0,
        help="bisect the decay rate this many times after the first P "
        "(each one more solve; default 0: the decay rate the first P is "
        "checked to give, bisected 6 times only when it leaves no room "
        "for what the corners leave out)",
    )
    p.add_argument(
        "--box",
        nargs="*",
        default=None,
        metavar="KEY",
        help="certify over these parameters of the box only, the others "
        "at their nominal values (stiffness, c0, k_c, mass_scale, "
        "slope_x1, slope_x2; none: the nominal map alone; default: all)",
    )
    p.add_argument(
        "--max-time",
        type=float,
        default=MAX_TIME,
        metavar="SECONDS",
        help="stop the search after this many seconds (wall, the run to "
        "the operating point included): the certificate is then "
        "inconclusive with the cells finished, and says whether the loop "
        "grows under a variation within the box (default %(default)g: "
        "half an hour)",
    )
    p.add_argument(
        "--solver",
        choices=("Clarabel", "CSDP", "SCS"),
        default="Clarabel",
        help="the semidefinite solver (all ship with Drake's wheel)",
    )
    _output_arguments(
        p, "out/<scenario>/certificate", "an existing certificate.json"
    )
    p.set_defaults(func=_certify)
