"""Startup of ``deburr-drake simulate`` before and after, side by side:
a 0.01 s run, command to exit (pre-flight, metrics, files and figures
included), as a subprocess, for each case on a base revision (a git
worktree of it, run with PYTHONPATH to it) and on this tree, alternating,
``--repeats`` times. Prints the median wall and CPU time per case and
tree, and the Diagrams built and inverse-kinematics problems solved per
run (counted the same way in both trees: make_deburring_diagram and the
IK solver's Solve wrapped before the command runs).

    python scripts/bench_plan.py [--base REV] [--repeats N]
"""

import argparse
import json
import os
from pathlib import Path
import resource
import statistics
import subprocess
import sys
import tempfile
import time

HERE = Path(__file__).resolve().parent.parent
CASES = (
    ("paper", "paper"),
    ("cross_hole_6dof", "examples/cross_hole_6dof.yaml"),
)

#: Runs the command with the two steps counted; the counts go to the file
#: named by BENCH_COUNTS.
COUNTED = """
import json, os, sys
import deburr_drake.cell.arm as arm
import deburr_drake.cell.diagram as diagram
n = {"diagrams": 0, "ik": 0}
build, solve = diagram.make_deburring_diagram, arm.Solve
def counted_build(*a, **k):
    n["diagrams"] += 1
    return build(*a, **k)
def counted_solve(*a, **k):
    n["ik"] += 1
    return solve(*a, **k)
diagram.make_deburring_diagram, arm.Solve = counted_build, counted_solve
from deburr_drake.cli import main
try:
    code = main(sys.argv[1:])
finally:
    with open(os.environ["BENCH_COUNTS"], "w") as f:
        json.dump(n, f)
sys.exit(code)
"""


def _worktree(rev: str) -> Path:
    """A detached worktree of ``rev`` (made once, kept for reruns)."""
    sha = subprocess.run(
        ["git", "-C", str(HERE), "rev-parse", "--short", rev],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    path = Path(tempfile.gettempdir()) / f"deburr-bench-{sha}"
    if not path.exists():
        subprocess.run(
            ["git", "-C", str(HERE), "worktree", "add", "--detach", str(path)]
            + [sha],
            check=True,
            capture_output=True,
        )
    return path


def _run(tree: Path, scenario: str, out: Path) -> dict:
    counts = out / "counts.json"
    env = dict(os.environ, PYTHONPATH=str(tree), BENCH_COUNTS=str(counts))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", COUNTED, "simulate", "--scenario", scenario]
        + ["--duration", "0.01", "--out", str(out), "--force"],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise RuntimeError(f"{tree} {scenario}: {done.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (
        after.ru_stime - before.ru_stime
    )
    return {"wall": wall, "cpu": cpu, **json.loads(counts.read_text())}


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", default="main", help="the before revision")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    trees = {"before": _worktree(args.base), "after": HERE}
    runs = {(c, t): [] for c, _ in CASES for t in trees}
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.repeats):
            for case, scenario in CASES:
                # Alternating, so a busy machine weighs on both alike.
                order = list(trees) if k % 2 == 0 else list(trees)[::-1]
                for name in order:
                    out = Path(tmp) / f"{case}_{name}"
                    out.mkdir(exist_ok=True)
                    # Each tree's own file: the form of a scenario
                    # changes between revisions.
                    scenario_path = (
                        str(trees[name] / scenario)
                        if scenario.endswith(".yaml")
                        else scenario
                    )
                    runs[case, name].append(
                        _run(trees[name], scenario_path, out)
                    )
    print(
        f"base {args.base} ({trees['before']}), {args.repeats} repeats, "
        "medians; a 0.01 s `deburr-drake simulate`, command to exit"
    )
    print(
        f"{'case':18s} {'tree':7s} {'wall s':>7s} {'cpu s':>7s} "
        f"{'after/before':>12s} {'diagrams':>8s} {'IK solves':>9s}"
    )
    for case, _ in CASES:
        base = statistics.median(r["wall"] for r in runs[case, "before"])
        for name in trees:
            rs = runs[case, name]
            wall = statistics.median(r["wall"] for r in rs)
            cpu = statistics.median(r["cpu"] for r in rs)
            print(
                f"{case:18s} {name:7s} {wall:7.2f} {cpu:7.2f} "
                f"{wall / base:12.2f} "
                f"{statistics.median(r['diagrams'] for r in rs):8.0f} "
                f"{statistics.median(r['ik'] for r in rs):9.0f}"
            )


if __name__ == "__main__":
    main(sys.argv[1:])
