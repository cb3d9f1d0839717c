"""scripts/edge_depth_split.py: its split of the depth error adds up, and
the cross hole's fitted path is as near the true rim as docs/cad-edges.md
says (its hypothesis (a))."""

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def _split_script():
    path = ROOT / "scripts" / "edge_depth_split.py"
    spec = importlib.util.spec_from_file_location("edge_depth_split", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class _WorldFrame:
    """A contour whose task axes are the world's."""

    def task_frame(self, s):
        return np.eye(3)


def test_the_depth_splits_into_reference_command_and_tracking():
    split = _split_script()
    rng = np.random.default_rng(0)
    n, d_star = 400, 5e-4
    t = np.linspace(0.0, 4.0, n)
    n1 = np.tile([1.0, 0.0, 0.0], (n, 1))
    z = np.column_stack([np.zeros(n), 1e-3 * t, np.zeros(n)])
    delta_d = d_star + 2e-5 * rng.standard_normal(n)
    offset = 1e-6 * rng.standard_normal(n)  # the command off the path
    e = 3e-5 * rng.standard_normal((n, 3))
    x_c = z + offset[:, None] * n1
    x_p = x_c + delta_d[:, None] * n1 - e
    delta = np.einsum("ij,ij->i", x_p - z, n1)
    f_nd = np.full(n, 6.0)
    logs = {
        "chamfer.t": t,
        "meta.contact_start": np.array(0.5),
        "meta.desired_depth": np.array(d_star),
        "chamfer.n1": n1,
        "chamfer.x_p": x_p,
        "chamfer.delta": delta,
        "chamfer.arc_position": 1e-3 * t,
        "controller.e": e,
        "chamfer.f_n": f_nd + 1e4 * (delta - d_star),
        "desired_normal_force.value": f_nd[:, None],
        "controller.delta_d": delta_d,
        "reference.value": x_c,
    }
    out = split.depth_split(logs, _WorldFrame())
    late = t > 0.5 + 2.0

    def rms(x):
        return math.sqrt(np.mean(np.square(x[late]))) * 1e3

    assert math.isclose(out["depth_rms_mm"], rms(delta - d_star))
    assert math.isclose(out["reference_delta_d_rms_mm"], rms(delta_d - d_star))
    assert math.isclose(out["command_along_n1_rms_mm"], rms(offset))
    assert math.isclose(out["tracking_along_n1_rms_mm"], rms(-e[:, 0]))
    # the force here is the depth's, 1e4 N/m: all of it is explained
    assert math.isclose(out["depth_per_force_mm_N"], 0.1, rel_tol=1e-9)
    assert out["force_unexplained_rms_mm"] < 1e-9


@pytest.mark.slow
def test_the_cross_hole_path_is_within_half_a_facet_of_the_true_rim():
    from deburr_drake.cell.edge import make_contour
    from deburr_drake.config.scenario import load_scenario

    scenario = load_scenario(ROOT / "examples" / "cross_hole_6dof.yaml")
    contour = make_contour(scenario)
    out = _split_script().cross_hole_reference(scenario, contour, samples=400)
    half_facet = math.pi / 256  # rad, of the tube's 256 facets
    assert out["edge_point_rms_um"] < 3.0
    assert out["tool_axis_max_mrad"] < 1.01e3 * half_facet
    assert 3.0 < out["tool_axis_rms_mrad"] < 6.0
    # the path moves e times the axis's error along n1
    engagement = scenario.tool.engagement
    assert out["path_depth_offset_max_um"] < 1.05e6 * engagement * half_facet
