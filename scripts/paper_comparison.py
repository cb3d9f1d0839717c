"""The paper's comparisons reproduced: the paper scenario, one full
pass, with every controller (fuzzy m = 2, fuzzy m = 0, impedance at constant
feed, the robust law (22), the ideal law (12), stiff position control),
then prints comparison.md. Minutes per controller; not a test. Usage:
    python scripts/paper_comparison.py [OUT_DIR] [WORKERS] [DURATION]
(default out/paper_comparison, 1 worker, the full pass)."""

from pathlib import Path
import sys

from deburr_drake.config import load_scenario
from deburr_drake.runs.compare import DEFAULT_CONTROLLERS, compare


def main(argv):
    out = Path(argv[0] if argv else "out/paper_comparison")
    workers = int(argv[1]) if len(argv) > 1 else 1
    duration = float(argv[2]) if len(argv) > 2 else None
    compare(
        load_scenario("paper"),
        list(DEFAULT_CONTROLLERS),
        duration=duration,
        out_dir=out,
        workers=workers,
    )
    print((out / "comparison.md").read_text())


if __name__ == "__main__":
    main(sys.argv[1:])
