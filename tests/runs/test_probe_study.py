"""The probe studies: the fit redone on recorded touches, and a part
larger than drawn probed in the cell."""

import numpy as np
import pytest

from deburr_drake.cell.edge import make_contour
from deburr_drake.config import load_scenario
from deburr_drake.runs.probe_study import probe_once, refit_touches


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


@pytest.mark.slow
def test_a_bore_larger_than_drawn_is_probed_to_its_size():
    # The real bore 0.25 mm larger than the drawing (believed - real) and
    # off by (0.3, -0.2) mm; 4 touches (0, 90, 180, 270 degrees: clear of
    # the burrs) with the defaults: the radius fitted, the calibrated
    # detection bias taken off.
    scenario = load_scenario(
        "paper_localised",
        text="{part_error: {offset: [0.0003, -0.0002, 0.0], "
        "radius: -0.00025}, localisation: {probe: {points: 4}}}",
    )
    found = probe_once(scenario)
    assert found.kept == 4
    # The believed part's radius corrected to the real one.
    assert found.registration[3] == pytest.approx(2.5e-4, abs=1.5e-5)
    assert abs(found.radius_error) < 1.5e-5
    assert np.linalg.norm(found.centre_error) < 2e-5


@pytest.mark.slow
@pytest.mark.parametrize("scale,tolerance", [(0.5, 5e-5), (1.5, 1.5e-5)])
def test_the_radius_is_found_on_a_softer_and_a_stiffer_part(scale, tolerance):
    # The part's modulus x0.5 and x1.5 of the paper cell's (where the
    # configured contact_stiffness and the detection bias were
    # calibrated), the real bore 0.2 mm larger than drawn: the touches
    # measure the stiffness they touch. The fixed stiffness would leave
    # +120 um on the softer part; one power law (1.38) -48 um, its
    # touches 0.3 to 0.8 mm deep where the ring's local exponent has
    # fallen below 1.38 (contact_exponent_slope).
    scenario = load_scenario(
        "paper_localised",
        text="{part_error: {offset: [0.0002, 0.0001, 0.0], radius: -0.0002}, "
        f"part: {{material: {{hydroelastic_modulus: {4.5e6 * scale}}}}}, "
        "localisation: {probe: {points: 4}}}",
    )
    found = probe_once(scenario)
    assert found.kept == 4
    assert abs(found.radius_error) < tolerance
    assert np.linalg.norm(found.centre_error) < 2e-5
