"""The feed along a profile after a pass: the tool's mean speed along the
edge on the lines and in each kind of fillet (concave: a pocket's corner,
convex: a boss's), off the burrs and after the contact transient, against
the feed law's steady values (f_d - P'_th) / (k_c s delta* h), s the
removal scale of the edge's curvature (control.command.edge_steady_feed).
Usage:

    python scripts/profile_feed.py OUT_DIR SCENARIO [--scenario-text YAML]

(OUT_DIR holds the logs.npz of ``deburr-drake simulate --scenario
SCENARIO --out OUT_DIR``.)
"""

import argparse
from pathlib import Path

import numpy as np

from deburr_drake.cell.edge import make_contour
from deburr_drake.config import load_scenario
from deburr_drake.control.command import edge_steady_feed
from deburr_drake.runs.pass_metrics import TRANSIENT


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out")
    p.add_argument("scenario")
    p.add_argument("--scenario-text", default=None)
    args = p.parse_args(argv)
    sc = load_scenario(args.scenario, text=args.scenario_text)
    contour = make_contour(sc)
    with np.load(Path(args.out) / "logs.npz") as z:
        t, arc = z["process.t"], z["process.arc_position"]
        v, burr = z["process.v_t"], z["process.burr_area"]
        ct, fn = z["chamfer.t"], z["chamfer.f_n"]
    contact = ct[np.argmax(fn > 1.0)]
    kappa = np.array([contour.curvature(contour.point_at(s)) for s in arc])
    keep = (t >= contact + TRANSIENT) & (burr == 0.0)
    print(f"{'where':>24s} {'samples':>8s} {'feed mm/s':>10s} {'law mm/s':>9s}")
    for k in np.unique(np.round(kappa[keep], 6)):
        on = keep & np.isclose(kappa, k)
        law = edge_steady_feed(sc, curvature=k)
        name = (
            "line"
            if k == 0
            else f"{'concave' if k > 0 else 'convex'} fillet "
            f"r {1e3 / abs(k):.0f} mm"
        )
        print(
            f"{name:>24s} {int(on.sum()):8d} {np.mean(v[on]) * 1e3:10.3f} "
            f"{law * 1e3:9.3f}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
