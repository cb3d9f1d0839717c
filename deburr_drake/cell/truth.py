"""The plant's contact truth, measured on the part the cell builds: the
hydroelastic normal force on the cutter at a depth into the part, and the
normal-force law near the desired depth (what an ideal estimator would
report). The metrics (force prediction), the analysis and the baselines'
ideal law read it."""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass
import hashlib
import json
import os
from pathlib import Path
import tempfile

import numpy as np
from pydrake.systems.framework import DiagramBuilder

from deburr_drake.cell.edge import make_contour
from deburr_drake.cell.models import models_dir
from deburr_drake.cell.part import EdgeContactProbe, contact_force_on_body
from deburr_drake.cell.plant import add_cell_plant, mesh_edge_band
from deburr_drake.config import RobotConfig, Scenario

__all__ = [
    "contact_normal_force",
    "ContactTruth",
    "contact_truth",
    "truth_stations",
]


def contact_normal_force(
    scenario: Scenario, depths, *, arc_fraction=0.5
) -> np.ndarray:
    """The hydroelastic normal force (N) on the scenario's cutter at each
    depth (m) into its part along n1, the tool along the contour's axis
    there (vertical on a planar edge) at ``arc_fraction`` of the edge, at
    rest: the contact part of (4), measured on the same geometry the cell
    simulates (a Cartesian tool holds the cutter; along a mesh edge, whose
    axis turns, a free cutter on the same band). An array of fractions
    gives one row of forces per fraction (one plant built)."""
    fractions = np.atleast_1d(np.asarray(arc_fraction, float))
    measure = (
        _edge_normal_forces
        if scenario.part.edge.kind == "mesh"
        else _normal_forces
    )
    forces = measure(scenario, depths, fractions)
    return forces if np.ndim(arc_fraction) else forces[0]


def truth_stations(scenario: Scenario) -> np.ndarray:
    """Fractions of the edge where :func:`contact_truth` measures, the
    first giving its law: the middle of a circle (every place is alike
    there) or of a straight edge; on a profile, whose lines and fillets
    differ, 64 evenly spaced places from the start, which is where a
    closed pass ends: the estimator follows the local law within a few
    seconds (on the pocket c0 + c1 delta* goes from 5.1 N on the lines to
    5.9 N in each fillet and back), so its last estimate is that
    place's. A mesh edge's frame and faces' angle vary along it: the same
    64 places."""
    if scenario.part.edge.kind in ("profile", "mesh"):
        return np.arange(64) / 64.0
    return np.array([0.5])


def _normal_forces(scenario: Scenario, depths, fractions) -> np.ndarray:
    probe = copy.deepcopy(scenario)
    probe.robot = RobotConfig(model="cartesian_tool")
    probe.simulation.plant_time_step = 0.0
    builder = DiagramBuilder()
    plant, _ = add_cell_plant(builder, probe)
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    pc = plant.GetMyMutableContextFromRoot(context)
    tool = plant.GetBodyByName("tool")
    (cutter,) = plant.GetCollisionGeometriesForBody(tool)
    contour = make_contour(scenario)
    port = plant.get_contact_results_output_port()
    rows = []
    for fraction in fractions:
        p = contour.point_at(fraction * contour.length)
        n1 = contour.n1(p)
        forces = []
        for depth in np.atleast_1d(np.asarray(depths, float)):
            plant.SetPositions(pc, p + depth * n1)
            f = contact_force_on_body(port.Eval(pc), cutter, tool.index())
            forces.append(-float(f @ n1))
        rows.append(forces)
    return np.array(rows)


def _edge_normal_forces(scenario: Scenario, depths, fractions):
    """The forces of :func:`contact_normal_force` along a mesh edge: a
    free cutter, its axis the contour's at each place, on the band the
    cell builds (``mesh_edge_band``)."""
    tool = scenario.tool
    stations, band = mesh_edge_band(scenario)
    probe = EdgeContactProbe(
        stations,
        **band,
        cutter_radius=tool.cutter_radius,
        cutter_length=tool.cutter_length,
        resolution_hint=tool.resolution_hint,
    )
    contour = make_contour(scenario)
    rows = []
    for fraction in fractions:
        s = fraction * contour.length
        p = contour.point_at(s)
        n1, axis = contour.n1(p), contour.tool_axis_at(s)
        rows.append(
            [
                -float(probe.contact_force_on_tool(p + depth * n1, axis) @ n1)
                for depth in np.atleast_1d(np.asarray(depths, float))
            ]
        )
    return np.array(rows)


@dataclass
class ContactTruth:
    """The plant's normal-force law near the desired depth, measured on
    Drake's hydroelastic contact plus the process threshold c0 (N, N/m,
    N s/m); what an ideal estimator would report."""

    force_at_desired_depth: float  # N, ||f_n|| at delta*
    c0: float  # N
    secant_stiffness: float  # N/m, (F(delta*) - c0) / delta*
    local_stiffness: float  # N/m, dF/d(delta) at delta*
    c2: float  # N s/m, Hunt-Crossley: d * F_hydro(delta*)
    # N, the least and the greatest ||f_n(delta*)|| where it was measured
    # (truth_stations): they differ between a profile's lines and fillets
    force_range: tuple = (float("nan"), float("nan"))


def contact_truth(
    scenario: Scenario, *, step: float = 2e-5, cache_dir=None
) -> ContactTruth:
    """The normal-force law at ``task.desired_depth`` on the part the cell
    builds for the scenario's edge (ring, wall, profile or mesh band), by
    central differences of :func:`contact_normal_force` over +-``step``
    (m), at the first of :func:`truth_stations` (``force_range`` over
    all).

    Measured once for the same inputs: kept in ``cache_dir``
    ($XDG_CACHE_HOME/deburr_drake/truth by default) under a hash of all it
    reads (the scenario, the package's source and models, the part's
    file, Drake's and numpy's versions), so any change measures again."""
    path = _truth_cache(cache_dir) / f"{_truth_key(scenario, step)}.json"
    try:
        fields = json.loads(path.read_text())
        return ContactTruth(
            **{**fields, "force_range": tuple(fields["force_range"])}
        )
    except (OSError, ValueError, TypeError, KeyError):
        pass  # absent or unreadable: measured and written below
    truth = _measured_truth(scenario, step)
    _write_atomically(path, json.dumps(dataclasses.asdict(truth)))
    return truth


def _measured_truth(scenario: Scenario, step: float) -> ContactTruth:
    material, d = scenario.part.material, scenario.task.desired_depth
    rows = contact_normal_force(
        scenario, [d - step, d, d + step], arc_fraction=truth_stations(scenario)
    )
    forces = rows[0]
    c0 = scenario.process.contact_threshold_force
    return ContactTruth(
        force_at_desired_depth=float(forces[1] + c0),
        c0=c0,
        secant_stiffness=float(forces[1] / d),
        local_stiffness=float((forces[2] - forces[0]) / (2 * step)),
        c2=float(material.hunt_crossley_dissipation * forces[1]),
        force_range=(
            float(rows[:, 1].min() + c0),
            float(rows[:, 1].max() + c0),
        ),
    )


def _truth_cache(cache_dir) -> Path:
    if cache_dir is not None:
        return Path(cache_dir)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(
        os.path.expanduser("~"), ".cache"
    )
    return Path(base) / "deburr_drake" / "truth"


def _truth_key(scenario: Scenario, step: float) -> str:
    """SHA-256 of everything the measurement reads: the scenario as
    written, the step, the package's source, the models, the part's file
    and the versions of Drake and numpy."""
    from importlib.metadata import version

    from pydrake.common.yaml import yaml_dump_typed

    digest = hashlib.sha256()
    digest.update(yaml_dump_typed(scenario).encode())
    digest.update(repr(float(step)).encode())
    digest.update(f"{version('drake')} {np.__version__}".encode())
    package = Path(__file__).resolve().parents[1]
    files = sorted(package.rglob("*.py")) + sorted(
        p for p in models_dir().rglob("*") if p.is_file()
    )
    part_file = getattr(scenario.part.edge, "file", "")
    if part_file and Path(part_file).is_file():
        files.append(Path(part_file))
    for f in files:
        digest.update(str(f).encode())
        digest.update(f.read_bytes())
    return digest.hexdigest()[:32]


def _write_atomically(path: Path, text: str):
    """``text`` into ``path`` through a temporary file and os.replace, so
    a concurrent run never reads a partial file; a cache that cannot be
    written is left out."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(
            prefix=path.stem + ".", suffix=".tmp", dir=path.parent
        )
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.replace(tmp, path)
    except OSError:
        pass
