"""The probe studies: the fit redone on recorded touches. Parts larger
than drawn, probed in the cell (three probing runs), are
scripts/probe_checks.py (docs/benchmarks.md)."""

import numpy as np

from deburr_drake.cell.edge import make_contour
from deburr_drake.config import load_scenario
from deburr_drake.runs.probe_study import refit_touches


def test_refit_touches_drops_the_burr_and_finds_the_part():
    scenario = load_scenario(
        "pocket",
        text=("part_error: {offset: [0.0006, -0.0004, 0.0], yaw: 0.01}"),
    )
    real = make_contour(scenario)
    arcs = np.arange(8) * real.length / 8 + 0.004
    touches = np.zeros((8, 4))
    for k, s in enumerate(arcs):
        p = real.point_at(s)
        if k == 2:
            p = p - 3e-4 * real.n1(p)  # on a burr
        touches[k] = [*p, 1.0]
    touches[5, 3] = 0.0  # a miss: not used
    rows = refit_touches(scenario, touches.ravel(), [5e-5, 1e-3])
    assert [(r["touches"], r["kept"]) for r in rows] == [(7, 6), (7, 7)]
    assert rows[0]["error"] < 1e-9
    assert rows[1]["error"] > 2e-5  # the burr touch kept
