"""The :class:`Scenario`: every component's dataclass composed, validated
whole; loaded from a shipped name or a YAML file (plus YAML overrides) with
``yaml_load_typed`` after a schema check that names the bad field by its
dotted path; fields read and set by dotted name."""

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
import re
from typing import List, Optional

from pydrake.common.yaml import yaml_load_typed

from deburr_drake.config.cell import (
    PIP_PREFIX,
    EdgeConfig,
    FaultsConfig,
    GuardsConfig,
    PartConfig,
    PartErrorConfig,
    ProcessConfig,
    RobotConfig,
    SensorConfig,
    ToolConfig,
)
from deburr_drake.config.checks import (
    ConfigError,
    _non_negative,
    _positive,
    _require,
)
from deburr_drake.config.control import (
    CommandConfig,
    ControllerConfig,
    EstimatorConfig,
    TaskConfig,
)
from deburr_drake.config.job import JobConfig
from deburr_drake.config.localisation import LocalisationConfig
from deburr_drake.config.uncertainty import UncertaintyConfig

__all__ = [
    "SimulationConfig",
    "Scenario",
    "get_field",
    "set_field",
    "field_type",
    "scenario_names",
    "scenario_path",
    "load_scenario",
]


@dataclass
class SimulationConfig:
    duration: float = 10.0  # s, simulated time (--duration overrides it)
    plant_time_step: float = 0.0  # s; 0: continuous plant
    contact_approximation: str = "lagged"  # -, discrete plant only
    integrator: str = "cenic"  # -, Drake integrator (INTEGRATORS)
    accuracy: float = 1.0e-4  # -, the integrator's error-control accuracy
    # s. cenic treats only the diagonal of the applied forces' d tau / dv
    # implicitly; the cutting force's g a a^T (a = J^T n2) is off-diagonal
    # on an arm, and process.sample_mean holds it over each sample at its
    # exact mean, so the paper scenarios take one step per sample
    # (paper_6dof two, for its depth's accuracy; docs/numerics.md).
    max_step: float = 0.01
    # -; false: fixed steps of max_step (accuracy unused). With the sampled
    # loop every step ends at a sample anyway, and error control only adds
    # steps the means do not need (docs/numerics.md).
    error_control: bool = True
    # s; the control period: no extra integrator stops (an unaligned log
    # adds steps), and a limit cycle at the loop's Nyquist frequency shows
    # as sample-to-sample alternation instead of aliasing to a constant
    # (docs/numerics.md).
    log_period: float = 0.0025
    initial_depth: float = 0.0  # m, tool starts at this depth (in contact)
    # -, stop when the command has run this many edge lengths (0: run for the
    # whole duration). 1.0 is one full pass of a closed edge.
    stop_after_passes: float = 0.0

    INTEGRATORS = (
        "cenic",
        "runge_kutta2",
        "runge_kutta3",
        "runge_kutta5",
        "explicit_euler",
        "implicit_euler",
        "radau3",
    )

    def validate(self):
        o = "simulation"
        _positive(o, "duration", self.duration)
        _non_negative(o, "plant_time_step", self.plant_time_step)
        _require(
            self.contact_approximation in ("lagged", "similar", "sap", "tamsi"),
            f"{o}.contact_approximation",
            self.contact_approximation,
            "one of lagged, similar, sap, tamsi",
        )
        _require(
            self.integrator in self.INTEGRATORS,
            f"{o}.integrator",
            self.integrator,
            f"one of {', '.join(self.INTEGRATORS)}",
        )
        for name in ("accuracy", "max_step", "log_period"):
            _positive(o, name, getattr(self, name))
        _non_negative(o, "initial_depth", self.initial_depth)
        _non_negative(o, "stop_after_passes", self.stop_after_passes)


@dataclass
class Scenario:
    """Everything one simulation needs."""

    name: str = "point_mass"  # -, names the output directory out/<name>
    # Every section this file does not set, and every field of a section
    # it sets in part; a robot section that names robot.model starts from
    # the defaults instead (the base's flange, seed and friction are its
    # own arm's).
    base: str = ""  # -, a shipped scenario or YAML file this one starts from
    robot: RobotConfig = field(default_factory=RobotConfig)
    part: PartConfig = field(default_factory=PartConfig)
    tool: ToolConfig = field(default_factory=ToolConfig)
    task: TaskConfig = field(default_factory=TaskConfig)
    command: CommandConfig = field(default_factory=CommandConfig)
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)
    controller: ControllerConfig = field(default_factory=ControllerConfig)
    sensor: SensorConfig = field(default_factory=SensorConfig)
    process: ProcessConfig = field(default_factory=ProcessConfig)
    simulation: SimulationConfig = field(default_factory=SimulationConfig)
    guards: GuardsConfig = field(default_factory=GuardsConfig)
    part_error: PartErrorConfig = field(default_factory=PartErrorConfig)
    faults: FaultsConfig = field(default_factory=FaultsConfig)
    localisation: LocalisationConfig = field(default_factory=LocalisationConfig)
    job: JobConfig = field(default_factory=JobConfig)
    uncertainty: UncertaintyConfig = field(default_factory=UncertaintyConfig)

    def validate(self):
        # The default output directory is out/<name>: a plain file name.
        _require(
            isinstance(self.name, str)
            and re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.+-]*", self.name)
            is not None,
            "name",
            self.name,
            "a plain file name of letters, digits and _ . + - "
            "(no path separators, no leading dot)",
        )
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if hasattr(value, "validate"):
                value.validate()
        self._check_tool_on_part()
        self._check_localisation()
        self._check_periods()
        self.uncertainty.check_mass_scale(self.controller.model_mass_scale)
        self.uncertainty.check_axes(self.controller.fuzzy.axes)
        return self

    def _check_tool_on_part(self):
        """The depth, the cutter and the part fit one another."""
        edge = self.part.edge
        wall = edge.wall()
        wall_name = (
            "part.edge.band_width"
            if edge.kind == "mesh"
            else "part.edge.wall_thickness"
        )
        _require(
            self.task.desired_depth < wall,
            "task.desired_depth",
            self.task.desired_depth,
            f"< {wall_name} ({wall})",
        )
        _require(
            self.tool.engagement < self.part.band.height,
            "tool.engagement",
            self.tool.engagement,
            f"< part.band.height ({self.part.band.height})",
        )
        if edge.kind == "circle":
            _require(
                self.tool.cutter_radius < edge.inner_radius,
                "tool.cutter_radius",
                self.tool.cutter_radius,
                f"< part.edge.inner_radius ({edge.inner_radius})",
            )
        _require(
            self.task.desired_depth < self.tool.cutter_radius,
            "task.desired_depth",
            self.task.desired_depth,
            f"< tool.cutter_radius ({self.tool.cutter_radius})",
        )
        _require(
            self.simulation.initial_depth < min(self.tool.cutter_radius, wall),
            "simulation.initial_depth",
            self.simulation.initial_depth,
            f"< tool.cutter_radius and {wall_name} "
            f"({min(self.tool.cutter_radius, wall)})",
        )
        # A job's part is its file's mesh, whatever part.edge says.
        kind = "mesh" if self.job.file else edge.kind
        self.part_error.check_kind(kind)
        self.faults.part_step.check_kind(kind)
        self.part.check(self.tool, self.part_error)
        self._check_burrs(wall, wall_name)

    def _check_burrs(self, wall: float, wall_name: str):
        """Each burr fits on the edge, under the cutter and on the wall (a
        size written in mm is a thousand times too large for all three)."""
        edge = self.part.path_length(self.tool)
        above = self.tool.cutter_length - self.tool.engagement
        for k, burr in enumerate(self.process.burrs):
            name = f"process.burrs[{k}]"
            _require(
                burr.length <= edge,
                f"{name}.length",
                burr.length,
                f"a number in (0, {edge:.6g}] m (the edge's length along "
                "the cutter's path; m, not mm)",
            )
            _require(
                burr.height <= above,
                f"{name}.height",
                burr.height,
                f"a number in [0, {above:.6g}] m (the cutter above the "
                "edge, tool.cutter_length - tool.engagement; m, not mm)",
            )
            _require(
                burr.thickness <= wall,
                f"{name}.thickness",
                burr.thickness,
                f"a number in [0, {wall:.6g}] m ({wall_name}: "
                "the burr stands on the wall; m, not mm)",
            )

    def _check_localisation(self):
        """The believed part is one the cutter fits in."""
        edge = self.part.edge
        wall = edge.wall()
        allowed = f"|radius| < part.edge.wall_thickness ({wall})"
        fits = True
        if edge.kind == "circle":
            fits = self.tool.cutter_radius < (
                edge.inner_radius + self.part_error.radius
            )
            allowed += (
                " with the believed inner radius > tool.cutter_radius "
                f"({self.tool.cutter_radius})"
            )
        _require(
            fits and abs(self.part_error.radius) < wall,
            "part_error.radius",
            self.part_error.radius,
            allowed,
        )

    def _check_periods(self):
        """The outer loop and the guards sample the inner loop."""
        inner = self.controller.control_period
        if inner > 0:
            period = self.command.period
            ratio = period / inner
            _require(
                ratio >= 1 - 1e-9 and abs(ratio - round(ratio)) < 1e-6,
                "command.period",
                period,
                "a whole multiple >= 1 of controller.control_period "
                f"({inner:g} s): the outer loop samples the inner one",
            )
            ratio = self.guards.check_period / inner
            _require(
                ratio >= 1 - 1e-9 and abs(ratio - round(ratio)) < 1e-6,
                "guards.check_period",
                self.guards.check_period,
                "a whole multiple >= 1 of controller.control_period "
                f"({inner:g} s): other times add integrator steps",
            )


def _parse_path(path: str):
    """'controller.sliding_gain[0]' -> [('controller', None),
    ('sliding_gain', 0)]."""
    parts = []
    for token in path.split("."):
        index = None
        if token.endswith("]") and "[" in token:
            token, _, rest = token.partition("[")
            try:
                index = int(rest[:-1])
            except ValueError:
                raise ConfigError(f"{path!r}: bad index [{rest}") from None
        parts.append((token, index))
    return parts


#: Where the fields of the tube-only form went: old dotted prefix -> new.
_OLD_PATHS = {
    "tube.position": "part.pose.xyz",
    "tube.inner_radius": "part.edge.inner_radius",
    "tube.wall_thickness": "part.edge.wall_thickness",
    "tube.height": "part.edge.height",
    "tube.compliant_layer_height": "part.band.height",
    "tube.hydroelastic_modulus": "part.material.hydroelastic_modulus",
    "tube.hunt_crossley_dissipation": (
        "part.material.hunt_crossley_dissipation"
    ),
    "tube.mesh_": "part.band.mesh_",
    "tube": "part",
    "edge.pose": "part.pose",
    "edge": "part.edge",
}


def _old_path(path: str) -> Optional[str]:
    """The new dotted name of a field of the tube-only form, else None."""
    for old, new in _OLD_PATHS.items():
        if path == old or path.startswith(
            old if old.endswith("_") else old + "."
        ):
            return new + path[len(old) :]
        if path.startswith(old + "["):
            return new + path[len(old) :]
    return None


def get_field(scenario, path: str):
    obj = scenario
    for name, index in _parse_path(path):
        if (
            not hasattr(obj, "__dataclass_fields__")
            or name not in obj.__dataclass_fields__
        ):
            new = _old_path(path) if obj is scenario else None
            if new is not None:
                raise ConfigError(
                    f"{path!r} is the tube-only form's field: write {new!r}"
                )
            raise ConfigError(
                f"{path!r} is not a scenario field ({name!r} unknown)"
            )
        obj = getattr(obj, name)
        if index is not None:
            if not isinstance(obj, list) or not -len(obj) <= index < len(obj):
                raise ConfigError(f"{path!r}: index {index} out of range")
            obj = obj[index]
    return obj


def set_field(scenario, path: str, value):
    """Sets a scenario field by dotted name (``sensor.cutoff_frequency``,
    ``controller.sliding_gain[0]``); ConfigError names an unknown one, or
    an edge field that does not apply to the edge's kind."""
    get_field(scenario, path)  # validates the path
    parts = _parse_path(path)
    if len(parts) == 3 and path.startswith("part.edge."):
        _check_edge_field(scenario.part.edge.kind, parts[2][0], path)
    obj = scenario
    for name, index in parts[:-1]:
        obj = getattr(obj, name)
        if index is not None:
            obj = obj[index]
    name, index = parts[-1]
    if index is None:
        current = getattr(obj, name)
        setattr(
            obj,
            name,
            type(current)(value)
            if isinstance(current, (int, float))
            else value,
        )
    else:
        getattr(obj, name)[index] = float(value)


def field_type(scenario, path: str):
    """The declared type of a scenario field by dotted name: ``float``,
    ``int``, ``bool``, ``str``, a ``List[...]`` or a dataclass."""
    import typing

    get_field(scenario, path)  # validates the path
    obj = scenario
    for name, index in _parse_path(path):
        hint = typing.get_type_hints(type(obj))[name]
        obj = getattr(obj, name)
        if index is not None:
            (hint,) = typing.get_args(hint)
            obj = obj[index]
    return hint


_SCENARIO_DIR = Path(__file__).resolve().parents[1] / "scenarios"


def scenario_names() -> List[str]:
    """Names of the scenarios shipped in the package."""
    return sorted(p.stem for p in _SCENARIO_DIR.glob("*.yaml"))


def scenario_path(name: str) -> Path:
    path = _SCENARIO_DIR / f"{name}.yaml"
    if not path.exists():
        raise ConfigError(
            f"scenario {name!r} is unknown: allowed {scenario_names()} "
            "or a path to a YAML file"
        )
    return path


def _schema_error(where: str, node, message: str):
    mark = node.start_mark
    raise ConfigError(f"{where}:{mark.line + 1}:{mark.column + 1}: {message}")


_TAG = "tag:yaml.org,2002:"


def _parsed(operation, text: str):
    """``operation`` (yaml.compose or yaml.load) of ``text`` by libyaml's
    safe loader (the same nodes, marks and values as the pure-Python
    one, parsed several times faster), by the pure-Python one where
    libyaml is missing or refuses the text: its error messages are the
    ones reported."""
    import yaml

    fast = getattr(yaml, "CSafeLoader", None)
    if fast is not None:
        try:
            return operation(text, Loader=fast)
        except yaml.YAMLError:
            pass
    return operation(text, Loader=yaml.SafeLoader)


def _check_node(where: str, node, schema, path: str):
    """Checks a composed YAML node against the dataclass ``schema``: every
    key known (named with its full dotted path), no key twice, every value
    of the field's type. One ConfigError with file:line:column."""
    import typing

    origin = typing.get_origin(schema)
    if dataclasses.is_dataclass(schema):
        _check_dataclass_node(where, node, schema, path)
    elif origin is dict:
        _check_dict_node(where, node, schema, path)
    elif origin in (list, List):
        _check_list_node(where, node, schema, path)
    else:
        _check_scalar_node(where, node, schema, path)


def _check_dataclass_node(where: str, node, schema, path: str):
    import typing

    import yaml

    known = {f.name for f in dataclasses.fields(schema)}
    if not isinstance(node, yaml.MappingNode):
        _schema_error(
            where,
            node,
            f"{path or 'the scenario'} must be a mapping of {sorted(known)}",
        )
    hints = typing.get_type_hints(schema)
    seen = {}
    for key_node, value_node in node.value:
        key = key_node.value
        name = f"{path}.{key}" if path else key
        _check_once(where, key_node, seen, name)
        if not path and key in _OLD_SECTIONS:
            _schema_error(where, key_node, _OLD_SECTIONS[key])
        if key not in known:
            _schema_error(
                where,
                key_node,
                f"{name} is unknown: allowed fields of "
                f"{path or 'the scenario'}: {sorted(known)}",
            )
        _check_node(where, value_node, hints[key], name)


#: The tube-only form's sections, refused with what to write instead.
_OLD_SECTIONS = {
    "tube": "tube is the tube-only form: write part: {pose: {xyz: "
    "<tube.position>}, material: {hydroelastic_modulus, "
    "hunt_crossley_dissipation}, band: {height: <compliant_layer_height>, "
    "mesh_segments, mesh_radial_cells, mesh_height_cells}, edge: {kind: "
    "circle, inner_radius, wall_thickness, height}} instead",
    "edge": "edge is the tube-only form: write it as part: {edge: {...}} "
    "(and edge.pose as part.pose) instead",
}


def _check_edge_field(
    kind: str, name: str, path: str, where: str = "", value=None
):
    """ConfigError when the edge field ``name`` does not apply to an edge
    of ``kind`` (one it would silently ignore). A field at its default
    value changes nothing and passes: a scenario written back whole (the
    run's scenario.yaml) gives every field."""
    fields = EdgeConfig.FIELDS.get(kind)
    if fields is None or name == "kind" or name in fields:
        return
    if name in EdgeConfig.__dataclass_fields__ and value == getattr(
        EdgeConfig(), name
    ):
        return
    raise ConfigError(
        f"{where}{path} does not apply to a {kind} edge: allowed with "
        f"part.edge.kind {kind}: kind, {', '.join(fields)}"
    )


def _check_edge_fields(text: str, where: str, kind: str):
    """Every ``part.edge`` field the YAML ``text`` sets applies to the edge
    of ``kind`` it loads into (file:line:column of the first that does
    not)."""
    import yaml

    root = _parsed(yaml.compose, text)
    data = _parsed(yaml.load, text)
    for section in ("part", "edge"):
        if not isinstance(root, yaml.MappingNode):
            return
        root = next((v for k, v in root.value if k.value == section), None)
        data = data.get(section) if isinstance(data, dict) else None
    if not isinstance(root, yaml.MappingNode) or not isinstance(data, dict):
        return
    for key_node, _ in root.value:
        mark = key_node.start_mark
        _check_edge_field(
            kind,
            key_node.value,
            f"part.edge.{key_node.value}",
            f"{where}:{mark.line + 1}:{mark.column + 1}: ",
            data.get(key_node.value),
        )


def _check_once(where: str, key_node, seen: dict, name: str):
    """ConfigError when ``key_node``'s key is in ``seen`` (key -> its first
    node); else records it."""
    key = key_node.value
    if key in seen:
        _schema_error(
            where,
            key_node,
            f"{name} is given twice (first at line "
            f"{seen[key].start_mark.line + 1})",
        )
    seen[key] = key_node


def _check_dict_node(where: str, node, schema, path: str):
    import typing

    import yaml

    _, item = typing.get_args(schema)
    if not isinstance(node, yaml.MappingNode):
        _schema_error(
            where,
            node,
            f"{path} = {_shown(node)} is invalid: allowed a mapping",
        )
    seen = {}
    for key_node, value_node in node.value:
        name = f"{path}.{key_node.value}"
        _check_once(where, key_node, seen, name)
        _check_node(where, value_node, item, name)


def _check_list_node(where: str, node, schema, path: str):
    import typing

    import yaml

    (item,) = typing.get_args(schema)
    if not isinstance(node, yaml.SequenceNode):
        kind = {
            float: "numbers",
            int: "integers",
            bool: "booleans",
            str: "strings",
        }.get(item, "mappings")
        _schema_error(
            where,
            node,
            f"{path} = {_shown(node)} is invalid: allowed a list of {kind}",
        )
    for k, child in enumerate(node.value):
        _check_node(where, child, item, f"{path}[{k}]")


def _check_scalar_node(where: str, node, schema, path: str):
    import yaml

    tags = {
        float: ("float", "int"),
        int: ("int",),
        bool: ("bool",),
        str: ("str",),
    }.get(schema)
    if tags is None:
        return
    kinds = {
        float: "a number",
        int: "an integer",
        bool: "true or false",
        str: "a string",
    }
    if (
        schema is float
        and isinstance(node, yaml.ScalarNode)
        and node.tag == _TAG + "str"
        and not node.style  # plain: None from PyYAML, "" from libyaml
    ):
        try:  # YAML 1.1 reads 4.5e6 as a string; the loader takes it
            float(node.value)
            return
        except ValueError:
            pass
    if not (
        isinstance(node, yaml.ScalarNode)
        and node.tag in [_TAG + t for t in tags]
    ):
        _schema_error(
            where,
            node,
            f"{path} = {_shown(node)} is invalid: allowed {kinds[schema]}",
        )


def _shown(node) -> str:
    import yaml

    if isinstance(node, yaml.ScalarNode):
        return repr(node.value)
    return "a list" if isinstance(node, yaml.SequenceNode) else "a mapping"


def _check_yaml(text: str, where: str, schema=None, path: str = ""):
    """Syntax (file:line:column), duplicate and unknown keys, and types of
    the YAML ``text`` against ``schema`` (:class:`Scenario` by default;
    fields named under ``path``), before it is loaded."""
    import yaml

    try:
        root = _parsed(yaml.compose, text)
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        problem = e.problem or ""
        if e.context:
            c = e.context_mark
            problem += f" ({e.context}" + (
                f" at {c.line + 1}:{c.column + 1})" if c else ")"
            )
        at = f":{mark.line + 1}:{mark.column + 1}" if mark else ""
        raise ConfigError(
            f"{where}{at}: YAML syntax error: {problem}"
        ) from None
    except yaml.YAMLError as e:
        raise ConfigError(
            f"{where}: YAML error: {' '.join(str(e).split())}"
        ) from None
    if root is None:
        return
    _check_node(where, root, schema or Scenario, path)


def _scenario_file(name_or_path: str) -> Path:
    path = Path(name_or_path)
    looks_like_path = path.suffix in (".yaml", ".yml") or len(path.parts) > 1
    if not looks_like_path:
        return scenario_path(str(name_or_path))
    if path.is_dir():
        raise ConfigError(
            f"--scenario {name_or_path} is a directory: "
            "allowed a YAML file or one of "
            f"{scenario_names()}"
        )
    if not path.is_file():
        raise ConfigError(
            f"--scenario {name_or_path}: no such file: "
            f"allowed a YAML file or one of {scenario_names()}"
        )
    return path


def _resolve_robot_model(robot: RobotConfig, directory: Path):
    """A relative model file, package folder or package in a scenario file
    is relative to that file (``pip:`` entries stay as they are)."""
    if (
        robot.is_file()
        and not robot.is_package_url()
        and not Path(robot.model).is_absolute()
    ):
        candidate = directory / robot.model
        if candidate.is_file():
            robot.model = str(candidate.resolve())

    def resolved(entry):
        if (
            not isinstance(entry, str)
            or entry.startswith(PIP_PREFIX)
            or Path(entry).is_absolute()
        ):
            return entry
        candidate = directory / entry
        return str(candidate.resolve()) if candidate.is_dir() else entry

    robot.package_paths = [resolved(e) for e in robot.package_paths]
    robot.packages = {k: resolved(v) for k, v in robot.packages.items()}


def _resolve_edge_file(part: PartConfig, directory: Path):
    """A relative part file in a scenario file is relative to that file (a
    bare name not found there may be a shipped part: EdgeConfig looks)."""
    edge = part.edge
    if not edge.file or Path(edge.file).is_absolute():
        return
    candidate = directory / edge.file
    if candidate.is_file():
        edge.file = str(candidate.resolve())


def _resolve_job_file(job: JobConfig, directory: Path):
    """A job's relative part file is relative to the scenario file, as the
    edge's."""
    if not job.file or Path(job.file).is_absolute():
        return
    candidate = directory / job.file
    if candidate.is_file():
        job.file = str(candidate.resolve())


def _base_of(source: str, path: Path, depth: int = 0) -> Scenario:
    """The defaults a scenario file starts from: its ``base`` scenario
    (a shipped name or a file relative to it), or the dataclasses'
    defaults. The file's sections then merge field by field over it, except
    a robot section that names ``robot.model``: that starts from the
    defaults."""
    import yaml

    data = _parsed(yaml.load, source)
    base = data.get("base", "") if isinstance(data, dict) else ""
    if not base:
        return Scenario()
    _require(
        isinstance(base, str) and depth < 8,
        "base",
        base,
        "a shipped scenario name or a YAML file (no cycle)",
    )
    if base not in scenario_names():
        candidate = path.parent / base
        base = str(candidate) if candidate.is_file() else base
    base_path = _scenario_file(base)
    text = base_path.read_text()
    _check_yaml(text, str(base_path))
    scenario = yaml_load_typed(
        filename=str(base_path), defaults=_base_of(text, base_path, depth + 1)
    )
    _check_edge_fields(text, str(base_path), scenario.part.edge.kind)
    _resolve_robot_model(scenario.robot, base_path.parent)
    _resolve_edge_file(scenario.part, base_path.parent)
    robot = data.get("robot")
    if isinstance(robot, dict) and "model" in robot:
        # A robot section that names its model describes that arm whole:
        # the base's flange, seed, friction and mount are its own arm's.
        scenario.robot = RobotConfig()
    scenario.base = ""
    return scenario


def load_scenario(
    name_or_path: Optional[str] = None, *, text: Optional[str] = None
) -> Scenario:
    """Loads a scenario by package name or file path, then applies ``text``
    (YAML overrides) on top, and validates it.

    Raises ConfigError with one line naming the problem (unknown field,
    wrong type, value out of range)."""
    scenario = Scenario()
    try:
        if name_or_path is not None:
            path = _scenario_file(str(name_or_path))
            try:
                source = path.read_text()
            except (OSError, UnicodeDecodeError) as e:
                raise ConfigError(
                    f"--scenario {path}: cannot read: {e}"
                ) from None
            _check_yaml(source, str(path))
            scenario = _base_of(source, path)
            scenario = yaml_load_typed(filename=str(path), defaults=scenario)
            _check_edge_fields(source, str(path), scenario.part.edge.kind)
            _resolve_robot_model(scenario.robot, path.parent)
            _resolve_edge_file(scenario.part, path.parent)
            _resolve_job_file(scenario.job, path.parent)
        if text:
            _check_yaml(text, "--scenario-text")
            scenario = yaml_load_typed(data=text, defaults=scenario)
            _check_edge_fields(text, "--scenario-text", scenario.part.edge.kind)
    except ConfigError:
        raise
    except (RuntimeError, ValueError, TypeError, AssertionError) as e:
        where = name_or_path if text is None else "--scenario-text"
        raise ConfigError(f"{where}: {e}") from None
    scenario.part.edge = scenario.part.edge.own_fields()
    return scenario.validate()
