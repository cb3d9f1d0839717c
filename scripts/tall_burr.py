"""A tall long burr on the paper cell, 2 mm x 20 mm at 10 N, the cutter's
front reaching it 3 s after the contact transient, simulated for 17 s (to
6 mm past the burr's top): the window where a cutting force not held at
its sample mean surges (286 N, 18 mm/s at 15.9 s). Prints the run's
figures against their bounds and exits 1 when one is not met: the force
under the envelope's bound and under 30 N, the speed under 1.5 times the
off-burr feed, the depth RMS error on the burr under the envelope's
limit, the feed on the burr below 1.2 mm/s (it falls from 2.4 mm/s toward
(f_d - P'_th) / g) and within 25 % of the feed law there.

    python scripts/tall_burr.py
"""

import sys

from check_table import report  # scripts/check_table.py

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.runs import envelope
from deburr_drake.runs.simulation import simulate


def main() -> int:
    cell = envelope.BurrCell(height=0.002, length=0.02, force=10.0)
    sc = envelope.burr_scenario(load_scenario("paper"), cell)
    log = simulate(
        make_deburring_diagram(scenario=sc),
        sc,
        duration=17.0,
        loggers=("process", "chamfer"),
    )
    m = envelope.burr_metrics(log.signals, sc, cell)
    bounds = envelope.burr_bounds(sc, cell)
    force_bound = min(30.0, bounds["max_chamfering_force_N"])
    checks = [
        ("no NaN", m["nan"], "== 0", m["nan"] == 0.0),
        ("burr reached", m["burr_reached"], "== 1", m["burr_reached"] == 1.0),
        (
            "max chamfering force (N)",
            m["max_chamfering_force_N"],
            f"< {force_bound:.4g}",
            m["max_chamfering_force_N"] < force_bound,
        ),
        (
            "max tool speed (mm/s)",
            1e3 * m["max_tool_speed_m_s"],
            f"< {1e3 * bounds['max_tool_speed_m_s']:.4g}",
            m["max_tool_speed_m_s"] < bounds["max_tool_speed_m_s"],
        ),
        (
            "depth RMS error on the burr (mm)",
            1e3 * m["depth_rms_error_on_burr_m"],
            f"< {1e3 * envelope.DEPTH_RMS_LIMIT:.4g}",
            m["depth_rms_error_on_burr_m"] < envelope.DEPTH_RMS_LIMIT,
        ),
        (
            "feed on the burr (mm/s)",
            1e3 * m["feed_on_burr_m_s"],
            "< 1.2",
            m["feed_on_burr_m_s"] < 1.2e-3,
        ),
        (
            "feed on the burr / the law's",
            m["feed_on_burr_m_s"] / m["feed_law_on_burr_m_s"],
            "1 +- 0.25",
            abs(m["feed_on_burr_m_s"] - m["feed_law_on_burr_m_s"])
            <= max(0.25 * abs(m["feed_law_on_burr_m_s"]), 1e-12),
        ),
    ]
    return report([("paper cell, burr 2 mm x 20 mm, f_d = 10 N, 17 s", checks)])


if __name__ == "__main__":
    sys.exit(main())
