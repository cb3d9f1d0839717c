"""The sweep's parallel speed-up: studies/bench_sweep.yaml (8 runs of 10 s
alike in cost) with 1 and with 2 local Dask worker processes, each into a
fresh directory; prints both wall times and their ratio.

    python scripts/bench_sweep.py [STUDY] [WORKERS...]
"""

import os
from pathlib import Path
import sys
import tempfile
import time

from deburr_drake import sweep


def main(argv):
    root = Path(__file__).resolve().parent.parent
    study_path = argv[0] if argv else root / "studies" / "bench_sweep.yaml"
    counts = [int(a) for a in argv[1:]] or [1, 2]
    study = sweep.load_study(study_path)
    runs = sweep.expand_runs(study)
    times = {}
    print(
        f"load average before: {os.getloadavg()[0]:.2f} ({os.cpu_count()} CPUs)"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for n in counts:
            start = time.perf_counter()
            outcome = sweep.run_sweep(
                study, runs, Path(tmp) / f"w{n}", workers=n
            )
            times[n] = time.perf_counter() - start
            results = [r for r in outcome.results.values() if r]
            stops = sorted({r["stop_reason"] for r in results})
            wall = sum(r["run_wall_time_s"] for r in results) / len(results)
            cpu = sum(r["run_cpu_time_s"] for r in results) / len(results)
            print(
                f"{n} worker(s): {len(runs)} runs of {study.duration:g} s "
                f"in {times[n]:.1f} s wall (cluster start included; "
                f"stops {stops}); a run {wall:.1f} s wall, {cpu:.1f} s "
                f"CPU; load average now {os.getloadavg()[0]:.2f}",
                flush=True,
            )
    print("\nworkers  wall (s)  ratio to 1 worker")
    for n in counts:
        print(f"{n:7d}  {times[n]:8.1f}  {times[n] / times[counts[0]]:.3f}")


if __name__ == "__main__":
    main(sys.argv[1:])
