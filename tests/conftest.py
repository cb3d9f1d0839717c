"""Fixtures the test folders share."""

import math

import numpy as np
import pytest
import trimesh

from deburr_drake.math.geometry import Contour


def _min_rotation(a, b):
    """The minimal rotation (3 x 3) taking unit vector a onto b."""
    v, c = np.cross(a, b), float(a @ b)
    vx = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + vx + vx @ vx / (1.0 + c)


class TiltedCircle(Contour):
    """A tool path round a circle of ``radius`` about ``center`` (m) in a
    plane turned ``incline`` (rad) about world x, material outside (a bore
    in an inclined face); the tool axis the plane's normal tilted ``tilt``
    (rad) outwards, so with a tilt it turns along the circle. A closed form
    of a 3-D edge's frame for the tests (float only)."""

    varying_frame = True

    def __init__(self, center, radius, incline, tilt=0.0):
        self._c = np.asarray(center, float)
        self._r = float(radius)
        ci, si = math.cos(incline), math.sin(incline)
        self._normal = np.array([0.0, -si, ci])
        self._e1 = np.array([1.0, 0.0, 0.0])
        self._e2 = np.cross(self._normal, self._e1)
        self._tilt = float(tilt)

    def _angle(self, p):
        d = np.asarray(p, float) - self._c
        return math.atan2(d @ self._e2, d @ self._e1) % (2.0 * math.pi)

    def _radial(self, angle):
        return math.cos(angle) * self._e1 + math.sin(angle) * self._e2

    @property
    def length(self):
        return 2.0 * math.pi * self._r

    @property
    def closed(self):
        return True

    @property
    def height(self):
        return float(self.point_at(0.0)[2])

    def phi(self, p):
        d = np.asarray(p, float) - self._c
        d = d - (d @ self._normal) * self._normal
        return self._r - float(np.linalg.norm(d))

    def grad_phi(self, p):
        return -self._radial(self._angle(p))

    def tangent(self, p):
        angle = self._angle(p)
        return -math.sin(angle) * self._e1 + math.cos(angle) * self._e2

    def curvature(self, p):
        return 1.0 / self._r

    def n1_rate(self, p, v):
        n1 = -self._radial(self._angle(p))
        v = np.asarray(v, float)
        v = v - (v @ self._normal) * self._normal
        return (v - (n1 @ v) * n1) / self._r

    def project(self, p):
        return self.point_at(self.arc_position(p))

    def arc_position(self, p):
        return self._r * self._angle(p)

    def point_at(self, s):
        return self._c + self._r * self._radial(s / self._r)

    def tool_axis_at(self, s):
        radial = self._radial(s / self._r)
        return (
            math.cos(self._tilt) * self._normal + math.sin(self._tilt) * radial
        )

    def axis_turn(self, s):
        return _min_rotation(self.tool_axis_at(0.0), self.tool_axis_at(s))


@pytest.fixture
def tilted_circle():
    """The TiltedCircle class (a Contour whose tool axis turns)."""
    return TiltedCircle


@pytest.fixture(scope="session")
def paper_cell():
    """The paper cell per controller kind, built once for the whole run:
    ``paper_cell(kind=None)`` -> (the scenario as loaded, with ``kind``,
    and its Diagram). Tests that share one only read it or simulate it
    from a fresh context (each Simulator makes its own), and never change
    the scenario."""
    from deburr_drake.cell.diagram import make_deburring_diagram
    from deburr_drake.config import load_scenario

    built = {}

    def cell(kind=None):
        scenario = load_scenario("paper")
        if kind is not None:
            scenario.controller.kind = kind
        key = scenario.controller.kind
        if key not in built:
            diagram = make_deburring_diagram(scenario=scenario)
            built[key] = (scenario, diagram)
        return built[key]

    return cell


@pytest.fixture(scope="session")
def paper_log(paper_cell):
    """5 simulated seconds of the paper cell (contact, the depth's
    convergence, no guard trip), run once for the tests that read it."""
    from deburr_drake.runs.simulation import simulate

    scenario, diagram = paper_cell()
    return simulate(diagram, scenario, duration=5.0)


def _roof_stl(angle_deg, path):
    """Writes to ``path`` (mm) a prism 60 mm long along y: a flat top
    (z = 20 mm, x <= 40 mm) meeting a face that slopes down towards +x at
    ``angle_deg`` between the two faces through the material, the edge
    along y at x = 40 mm, z = 20 mm; returns ``path``."""
    run = 20.0 / math.tan(math.radians(180.0 - angle_deg))
    section = [[0.0, 0.0], [40.0 + run, 0.0], [40.0, 20.0], [0.0, 20.0]]
    front = np.array([[x, 0.0, z] for x, z in section])
    vertices = np.vstack([front, front + [0.0, 60.0, 0.0]])
    faces = [[0, 1, 2], [0, 2, 3], [4, 6, 5], [4, 7, 6]]  # the y ends
    for i in range(4):
        j = (i + 1) % 4
        faces += [[i, i + 4, j + 4], [i, j + 4, j]]
    trimesh.Trimesh(vertices, faces).export(path)
    return path


@pytest.fixture
def roof_stl():
    """The writer of a roof-like prism (``_roof_stl``): an open straight
    edge between a flat top and a sloped face at a given angle."""
    return _roof_stl
