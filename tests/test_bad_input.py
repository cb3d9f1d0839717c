"""Every bad input through the command line's entry point: one
line on stderr naming the field (full dotted path) and what is allowed,
exit code 2, nothing run (no output on stdout) and nothing written. No
simulation runs here."""

import pytest

from deburr_drake import cli
from deburr_drake.cell.tube_mesh import ring_mesh_path, ring_surface_path

SIM = ["simulate", "--duration", "0.01"]

CASES = {
    "certify with an unknown field": (
        ["certify", "--set", "controller.no_such_gain=1"],
        ["controller.no_such_gain"],
    ),
    "certify with a value that is not a number": (
        ["certify", "--set", "sensor.cutoff_frequency=fast"],
        ["sensor.cutoff_frequency=fast", "VALUE must be a number"],
    ),
    "certify over a box that leaves out the scenario's own value": (
        [
            "certify",
            "--scenario-text",
            "uncertainty: {cutting_coefficient: [1.1, 1.3]}",
        ],
        ["uncertainty.cutting_coefficient = [1.1, 1.3]", "holding 1"],
    ),
    "certify with a time limit that is not positive": (
        ["certify", "--max-time", "0"],
        ["--max-time 0 is invalid", "positive number of seconds"],
    ),
    "certify over a box parameter that does not exist": (
        ["certify", "--box", "stiffness", "burr"],
        ["--box 'burr' is invalid", "slope_x2"],
    ),
    "malformed YAML text": (
        SIM + ["--scenario-text", "task: {desired_depth: [0.1"],
        ["--scenario-text:1:", "YAML syntax error"],
    ),
    "malformed YAML file": (
        SIM + ["--scenario", "{tmp}/bad.yaml"],
        ["bad.yaml:4:1: YAML syntax error", "flow sequence at 3:18"],
    ),
    "part out of reach": (
        SIM + ["--scenario-text", "part: {pose: {xyz: [0.8, 0.0, 0.0]}}"],
        ["part.pose.xyz", "out of the arm's reach", "start point", "mm beyond"],
    ),
    "a directory named x.yaml": (
        SIM + ["--scenario", "{tmp}/x.yaml"],
        ["x.yaml is a directory"],
    ),
    "missing scenario file": (
        SIM + ["--scenario", "{tmp}/none.yaml"],
        ["no such file"],
    ),
    "progress interval 0": (
        SIM + ["--progress-interval", "0"],
        ["--progress-interval = 0.0", "> 0"],
    ),
    "simulate duration 0": (
        ["simulate", "--duration", "0"],
        ["--duration = 0.0", "> 0"],
    ),
    "demo duration 0": (
        ["demo", "--duration", "0"],
        ["--duration = 0.0", "> 0"],
    ),
    "demo shorter than its settling time": (
        ["demo", "--duration", "1"],
        ["--duration = 1.0", "more than its 2 s"],
    ),
    "outer period shorter than the inner loop": (
        SIM + ["--scenario-text", "command: {period: 0.001}"],
        ["command.period = 0.001", "controller.control_period (0.0025"],
    ),
    "outer period not a multiple of the inner loop": (
        SIM + ["--scenario-text", "command: {period: 0.026}"],
        ["command.period = 0.026", "multiple"],
    ),
    "depth beyond the cutter radius": (
        SIM + ["--scenario-text", "task: {desired_depth: 0.004}"],
        ["task.desired_depth = 0.004", "< tool.cutter_radius (0.003)"],
    ),
    "depth beyond the wall": (
        SIM + ["--scenario-text", "task: {desired_depth: 0.006}"],
        ["task.desired_depth = 0.006", "part.edge.wall_thickness"],
    ),
    "initial depth beyond the cutter radius": (
        SIM + ["--scenario-text", "simulation: {initial_depth: 0.004}"],
        ["simulation.initial_depth = 0.004", "tool.cutter_radius"],
    ),
    "unbounded start angle": (
        SIM + ["--scenario-text", "part: {edge: {start_angle: 1.0e6}}"],
        ["part.edge.start_angle = 1000000.0", "[-2 pi, 2 pi]"],
    ),
    "depth not a number": (
        SIM + ["--scenario-text", "task: {desired_depth: abc}"],
        ["--scenario-text:1:23:", "task.desired_depth = 'abc'", "a number"],
    ),
    "position not a list": (
        SIM + ["--scenario-text", "part: {pose: {xyz: 0.4}}"],
        ["part.pose.xyz = '0.4'", "a list of numbers"],
    ),
    "integer field given a fraction": (
        SIM + ["--scenario-text", "controller: {fuzzy: {order: 1.5}}"],
        ["controller.fuzzy.order = '1.5'", "an integer"],
    ),
    "out-of-range nested field names its parents": (
        SIM + ["--scenario-text", "controller: {fuzzy: {order: 7}}"],
        ["controller.fuzzy.order = 7", "0..3"],
    ),
    "unknown nested key": (
        SIM + ["--scenario-text", "controller: {fuzzy: {ordr: 1}}"],
        ["controller.fuzzy.ordr is unknown", "upsilon"],
    ),
    "unknown key in a list item": (
        SIM + ["--scenario-text", "process: {burrs: [{lenght: 0.01}]}"],
        ["process.burrs[0].lenght is unknown", "length"],
    ),
    "duplicate key": (
        SIM
        + [
            "--scenario-text",
            "task: {desired_depth: 0.0004, desired_depth: 0.0006}",
        ],
        ["task.desired_depth is given twice"],
    ),
    "name escaping out/": (
        SIM + ["--scenario-text", "name: ../../x"],
        ["name = '../../x'", "no path separators"],
    ),
    "existing outputs": (
        SIM + ["--out", "{tmp}/done"],
        ["done already holds metrics.json", "--force"],
    ),
    "--out is a file": (
        SIM + ["--out", "{tmp}/bad.yaml"],
        ["--out", "not a directory"],
    ),
    "--record is a directory": (
        SIM + ["--out", "{tmp}/new", "--record", "{tmp}/x.yaml"],
        ["--record", "is a directory"],
    ),
    "--record exists": (
        SIM + ["--out", "{tmp}/new", "--record", "{tmp}/replay.html"],
        ["--record", "already exists", "--force"],
    ),
    "absurd contact modulus": (
        SIM
        + [
            "--scenario-text",
            "part: {material: {hydroelastic_modulus: 1.0e300}}",
        ],
        ["part.material.hydroelastic_modulus = 1e+300", "(0, 1e12] Pa"],
    ),
    "a burr written in mm": (
        SIM
        + [
            "--scenario-text",
            "process: {burrs: [{length: 8, height: 1.5, thickness: 2}]}",
        ],
        ["process.burrs[0].length = 8.0 is invalid", "m, not mm"],
    ),
    "a burr taller than the cutter above the edge": (
        SIM + ["--scenario-text", "process: {burrs: [{height: 1.5}]}"],
        ["process.burrs[0].height = 1.5 is invalid", "tool.cutter_length"],
    ),
    "a burr thicker than the wall": (
        SIM + ["--scenario-text", "process: {burrs: [{thickness: 2}]}"],
        ["process.burrs[0].thickness = 2.0", "part.edge.wall_thickness"],
    ),
    "a profile started by a vertex and a fraction": (
        SIM
        + [
            "--scenario",
            "pocket",
            "--scenario-text",
            "part: {edge: {start_vertex: 1, start_fraction: 0.5}}",
        ],
        ["part.edge.start_fraction = 0.5", "part.edge.start_vertex (1)"],
    ),
    "a vertex start on a circle": (
        SIM + ["--scenario-text", "part: {edge: {start_vertex: 0}}"],
        ["part.edge.start_vertex does not apply to a circle edge"],
    ),
    "a profile's vertices on a circle edge": (
        SIM
        + [
            "--scenario-text",
            "part: {edge: {kind: circle, vertices: [[0, 0], [1, 0], [0, 1]]}}",
        ],
        [
            "part.edge.vertices does not apply to a circle edge",
            "kind, inner_radius",
        ],
    ),
    "a file in the tube-only form": (
        SIM + ["--scenario-text", "tube: {inner_radius: 0.02}"],
        ["tube is the tube-only form: write part: {pose: {xyz: "],
    ),
    "an L pocket's origin on its inner corner, started by a ray": (
        SIM
        + [
            "--scenario",
            "pocket",
            "--scenario-text",
            "part: {edge: {fillet_radius: 0.006, vertices: [[-0.03, -0.03], "
            "[0.03, -0.03], [0.03, 0.0], [0.0, 0.0], [0.0, 0.03], "
            "[-0.03, 0.03]]}}",
        ],
        ["part.edge.start_angle = 0.0 is invalid", "start_vertex"],
    ),
    "a tool mount on a model holding its own tool": (
        SIM
        + ["--scenario-text", "robot: {tool_mount: {rpy: [0.0, 1.0, 0.0]}}"],
        ["robot.tool_mount = ", "robot.flange_frame is empty"],
    ),
    "unknown scenario": (
        SIM + ["--scenario", "no_such"],
        ["'no_such' is unknown", "paper"],
    ),
}


def _tree(root):
    return sorted(
        (p.relative_to(root).as_posix(), p.stat().st_size)
        for p in root.rglob("*")
    )


@pytest.mark.parametrize("name", list(CASES))
def test_bad_input_gives_one_line_and_exit_2(
    name, tmp_path, monkeypatch, capsys
):
    argv, expected = CASES[name]
    (tmp_path / "bad.yaml").write_text(
        "name: bad\ntask:\n  desired_depth: [0.1\n"
    )
    (tmp_path / "x.yaml").mkdir()
    (tmp_path / "done").mkdir()
    (tmp_path / "done" / "metrics.json").write_text("{}")
    (tmp_path / "replay.html").write_text("")
    monkeypatch.chdir(tmp_path)
    before = _tree(tmp_path)
    code = cli.main([a.replace("{tmp}", str(tmp_path)) for a in argv])
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2, captured
    assert len(lines) == 1, lines
    assert lines[0].startswith("deburr-drake: error: ")
    for text in expected:
        assert text in lines[0], lines[0]
    assert captured.out == ""  # nothing ran
    assert _tree(tmp_path) == before  # nothing written


def test_a_truncated_cached_mesh_is_rebuilt(tmp_path):
    args = (0.03, 0.035, 0.044, 0.05, 32)
    path = ring_mesh_path(*args, cache_dir=tmp_path)
    full = path.read_bytes()
    path.write_bytes(full[: len(full) // 2])
    assert ring_mesh_path(*args, cache_dir=tmp_path).read_bytes() == full
    surface = ring_surface_path(*args, cache_dir=tmp_path)
    good = surface.read_bytes()
    surface.write_bytes(b"")
    assert ring_surface_path(*args, cache_dir=tmp_path).read_bytes() == good
