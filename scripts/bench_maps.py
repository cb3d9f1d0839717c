#!/usr/bin/env python3
"""CPU time of one one-period map of the sampled loop, this tree against a
base revision, side by side in one process: the paper operating point
(``certify``'s: 3 s of cutting, its own steady state), one frozen diagram,
then maps taken alternately by the base's ``period_map`` (its
``analysis/sampled.py`` read from git, with its own map entries) and this
tree's ``FrozenMap.at_context``. Prints the median user CPU per map of
each, their ratio, and how far the two maps are apart (the largest entry
difference over the largest entry, the difference's norm in the balanced
coordinates the certificate uses, the spectral radii).

    python scripts/bench_maps.py [--scenario paper] [--base REV]
        [--repeats N]
"""

import argparse
import importlib.util
from pathlib import Path
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import scipy.linalg

from deburr_drake.analysis import box_certificate, sampled
from deburr_drake.analysis.along import at_numerics
from deburr_drake.analysis.operating_point import (
    DEFAULT_TIME_AFTER_CONTACT,
    find_operating_point,
)
from deburr_drake.analysis.sampled import spectral_radius
from deburr_drake.config import load_scenario

HERE = Path(__file__).resolve().parent.parent
SAMPLED = "deburr_drake/analysis/sampled.py"


def _base_module(rev: str):
    """The base revision's ``deburr_drake.analysis.sampled``, loaded
    under another name (it imports the rest from this tree)."""
    source = subprocess.run(
        ["git", "-C", str(HERE), "show", f"{rev}:{SAMPLED}"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    path = Path(tempfile.mkdtemp()) / "base_sampled.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location("base_sampled", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # (dataclasses look their module up)
    spec.loader.exec_module(module)
    return module


def _counted(module) -> dict:
    """{"runs": n}: the one-period simulations ``module``'s maps run."""
    count = {"runs": 0}
    run = module._OnePeriod.__call__

    def counted(self, z):
        count["runs"] += 1
        return run(self, z)

    module._OnePeriod.__call__ = counted
    return count


def _cpu(f):
    t0 = time.process_time()
    result = f()
    return result, time.process_time() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenario", default="paper")
    ap.add_argument("--base", default="main", help="git revision")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    base = _base_module(args.base)
    scenario = at_numerics(load_scenario(args.scenario), "shipped")
    op = find_operating_point(
        scenario, after_contact=DEFAULT_TIME_AFTER_CONTACT
    )
    frozen, build = _cpu(lambda: box_certificate._Maps(op, [], 0).frozen({}))
    context = frozen.context_from(op.diagram, op.context)
    context, _, _ = box_certificate.steady_context(frozen, context, 0)
    base_entries = base.cell_map_entries(frozen.diagram)

    def base_map():
        return base.period_map(
            frozen.diagram,
            context,
            base_entries,
            period=frozen.period,
            config=frozen.config,
        )

    runs = {"base": _counted(base), "this": _counted(sampled)}
    times = {"base": [], "this": []}
    for _ in range(args.repeats):
        A_base, t = _cpu(base_map)
        times["base"].append(t)
        A, t = _cpu(lambda: frozen.at_context(context))
        times["this"].append(t)
    _, (scale, _) = scipy.linalg.matrix_balance(
        A_base, permute=False, separate=True
    )

    def balanced(M):
        return M * (1.0 / scale)[:, None] * scale[None, :]

    rho_base, rho = spectral_radius(A_base), spectral_radius(A)
    base_cpu = statistics.median(times["base"])
    this_cpu = statistics.median(times["this"])
    print(f"{args.scenario}: {A.shape[0]} states, frozen build {build:.3f} s")
    per_map = {k: v["runs"] // args.repeats for k, v in runs.items()}
    print(
        f"per map, median user CPU of {args.repeats} alternated "
        "(one-period simulations):"
    )
    print(f"  base {args.base}: {base_cpu:.3f} s ({per_map['base']})")
    print(
        f"  this tree: {this_cpu:.3f} s ({per_map['this']})  "
        f"{base_cpu / this_cpu:.2f}x"
    )
    print(
        "  max |dA| / max |A|: "
        f"{np.max(np.abs(A - A_base)) / np.max(np.abs(A_base)):.2e}; "
        "balanced ||dA|| / ||A||: "
        f"{np.linalg.norm(balanced(A - A_base), 2) / np.linalg.norm(balanced(A_base), 2):.2e}"  # noqa: E501
    )
    print(
        f"  spectral radius: base {rho_base:.12f}, this {rho:.12f} "
        f"(difference {rho - rho_base:.1e})"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
