"""Every LeafSystem of the package documents its ports: the class
docstring's ``.. pydrake_system::`` block lists exactly the input and
output ports the system declares (a port marked ``(optional)`` in the
block may be absent, as the system declares it only when asked to).

The systems checked are those the cell really builds: the diagrams of the
shipped ``paper`` scenario with every ``controller.kind``, of
``paper_localised`` (touch probing and registration while cutting) and of
``paper`` drawn in Meshcat (the edge visualizer). Systems from pydrake
itself (the plant, the scene graph, loggers, primitives) are left to
Drake's own documentation."""

import inspect
import textwrap

from pydrake.systems.framework import Diagram, LeafSystem
import pytest
import yaml

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario

DIRECTIVE = ".. pydrake_system::"
KINDS = ("fuzzy", "robust", "ideal", "impedance", "position")


def port_block(doc):
    """{"name": ..., "input_ports": [(port, optional)], "output_ports":
    [...]} from the ``.. pydrake_system::`` block of ``doc``; None when
    the docstring has none."""
    lines = inspect.cleandoc(doc or "").splitlines()
    starts = [i for i, line in enumerate(lines) if line.strip() == DIRECTIVE]
    if not starts:
        return None
    directive = lines[starts[0]]
    indent = len(directive) - len(directive.lstrip())
    body = []
    for line in lines[starts[0] + 1 :]:
        if line.strip() and len(line) - len(line.lstrip()) <= indent:
            break
        body.append(line)
    block = yaml.safe_load(textwrap.dedent("\n".join(body))) or {}

    def ports(key):
        entries = [str(entry).split() for entry in block.get(key) or []]
        return [(e[0], "(optional)" in e[1:]) for e in entries]

    return {
        "name": block.get("name"),
        "input_ports": ports("input_ports"),
        "output_ports": ports("output_ports"),
    }


def test_port_block_parsing():
    doc = """A system.

    .. pydrake_system::

        name: Example
        input_ports:
        - u0
        - u1 (optional)
        output_ports:
        - y0

    - ``u0`` (3, m): a port's description.
    """
    assert port_block(doc) == {
        "name": "Example",
        "input_ports": [("u0", False), ("u1", True)],
        "output_ports": [("y0", False)],
    }
    assert port_block("No block here.") is None


def _leaf_systems(system):
    """The LeafSystems under ``system``, through nested diagrams."""
    for sub in system.GetSystems():
        if isinstance(sub, Diagram):
            yield from _leaf_systems(sub)
        elif isinstance(sub, LeafSystem):
            yield sub


def _diagrams(paper_cell):
    """(label, diagram) for every diagram the checked cells build (the
    paper cell's per kind from ``paper_cell``, tests/conftest.py)."""
    for kind in KINDS:
        yield f"paper/{kind}", paper_cell(kind)[1]
    yield (
        "paper_localised",
        make_deburring_diagram(scenario=load_scenario("paper_localised")),
    )
    from pydrake.geometry import Meshcat

    yield (
        "paper/meshcat",
        make_deburring_diagram(
            scenario=load_scenario("paper"), meshcat=Meshcat()
        ),
    )


def _declared(system, key):
    """The names of the ports ``system`` declares, ``key`` "input_ports"
    or "output_ports"."""
    if key == "input_ports":
        ports = [
            system.get_input_port(i) for i in range(system.num_input_ports())
        ]
    else:
        ports = [
            system.get_output_port(i) for i in range(system.num_output_ports())
        ]
    return {port.get_name() for port in ports}


def _mismatch(system):
    """What is wrong with ``system``'s port block (None: nothing)."""
    block = port_block(type(system).__doc__)
    if block is None:
        return f"no {DIRECTIVE} block in its class docstring"
    problems = []
    for key in ("input_ports", "output_ports"):
        listed = {name for name, _ in block[key]}
        required = {name for name, optional in block[key] if not optional}
        declared = _declared(system, key)
        if declared - listed:
            problems.append(f"{key} not listed: {sorted(declared - listed)}")
        if required - declared:
            problems.append(
                f"{key} listed but not declared: {sorted(required - declared)}"
            )
    return "; ".join(problems) or None


@pytest.fixture(scope="module")
def package_systems(paper_cell):
    """{(class name, input ports, output ports): (where it was first seen,
    system)} of every deburr_drake LeafSystem of :func:`_diagrams`, one
    per class and set of ports (a system declares some ports only when
    asked to)."""
    systems = {}
    diagrams = []  # the diagrams own their systems: keep them alive
    for label, diagram in _diagrams(paper_cell):
        diagrams.append(diagram)
        for system in _leaf_systems(diagram):
            cls = type(system)
            if not cls.__module__.startswith("deburr_drake"):
                continue
            key = (
                cls.__qualname__,
                frozenset(_declared(system, "input_ports")),
                frozenset(_declared(system, "output_ports")),
            )
            systems.setdefault(key, (f"{label}: {system.get_name()}", system))
    yield systems


def test_the_cells_hold_the_package_systems(package_systems):
    names = {key[0].split("_")[0] for key in package_systems}
    # The loop's own systems, at least, are found (through the template
    # classes' instance types too).
    assert {
        "CuttingProcess",
        "ForceSensor",
        "ChamferObserver",
        "CommandGenerator",
        "FirstOrderHold",
        "ContactParameterEstimator",
        "HybridController",
        "ProbingSequence",
        "OnlineRegistration",
        "EdgeVisualizer",
    } <= names


def test_every_package_system_lists_exactly_its_ports(package_systems):
    wrong = {
        where: problem
        for where, system in package_systems.values()
        if (problem := _mismatch(system)) is not None
    }
    assert not wrong, "\n".join(f"{w}: {p}" for w, p in sorted(wrong.items()))
