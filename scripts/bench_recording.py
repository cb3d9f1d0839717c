"""Wall time of the paper scenario without Meshcat and with an HTML replay
being recorded (Meshcat headless, 10 frames/s); prints both and the
overhead. Usage: python scripts/bench_recording.py [simulated seconds]."""

from pathlib import Path
import sys
import tempfile
import time

from pydrake.geometry import Meshcat

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.runs.replay import write_recording
from deburr_drake.runs.simulation import simulate


def run(duration: float, record: bool) -> float:
    scenario = load_scenario("paper")
    meshcat = Meshcat() if record else None
    diagram = make_deburring_diagram(scenario=scenario, meshcat=meshcat)
    start = time.perf_counter()
    if record:
        meshcat.StartRecording(frames_per_second=10.0)
    simulate(diagram, scenario, duration=duration)
    if record:
        with tempfile.TemporaryDirectory() as tmp:
            path = write_recording(meshcat, Path(tmp) / "replay.html")
            size = path.stat().st_size
        print(f"  replay file: {size / 1e6:.2f} MB")
    return time.perf_counter() - start


def main(duration: float = 10.0, repeats: int = 2) -> None:
    # Alternate the two and keep each one's best, against machine noise.
    plain, recorded = float("inf"), float("inf")
    for _ in range(repeats):
        plain = min(plain, run(duration, record=False))
        recorded = min(recorded, run(duration, record=True))
    print(
        f"paper scenario, {duration:g} s simulated, best of {repeats}: "
        f"{plain:.2f} s wall "
        f"without Meshcat, {recorded:.2f} s wall recording the replay "
        f"(overhead {100 * (recorded / plain - 1):+.1f} %)"
    )


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 10.0)
