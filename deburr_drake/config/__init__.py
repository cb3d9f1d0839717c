"""Typed configuration of deburr_drake: one dataclass per component, composed
into a :class:`Scenario` and loaded from YAML with ``yaml_load_typed``.

Every field is in SI units (m, N, s, rad); the comment on each field gives the
unit. ``validate()`` on each class raises :class:`ConfigError` naming the field
and the allowed range; nothing is clamped. :func:`load_scenario` validates the
whole tree, so a loaded scenario is always usable.

The layer on ``math``: it imports nothing else of the package (the pure geometry
checks a profile edge), so a scenario (or a study of 200) is read and validated
before any Drake system exists. The modules: ``checks`` (:class:`ConfigError`),
``control`` (the paper's controller), ``cell`` (the simulated cell),
``scenario`` (the whole, its files and dotted field names), ``uncertainty``
(the box of the robust margin and the certificate). Import the names
from here.
"""

from deburr_drake.config.cell import (
    BurrConfig,
    ContactBandConfig,
    DropoutConfig,
    EdgeConfig,
    FaultsConfig,
    GuardsConfig,
    MaterialConfig,
    PartConfig,
    PartErrorConfig,
    PartStepConfig,
    PoseConfig,
    ProcessConfig,
    RobotConfig,
    SensorConfig,
    ToolConfig,
    ToolMountConfig,
)
from deburr_drake.config.checks import ConfigError
from deburr_drake.config.control import (
    CommandConfig,
    ControllerConfig,
    EstimatorConfig,
    FuzzyConfig,
    ImpedanceConfig,
    PositionConfig,
    RobustConfig,
    TaskConfig,
)
from deburr_drake.config.job import JobConfig, JobEdgeConfig
from deburr_drake.config.localisation import (
    LocalisationConfig,
    OnlineRegistrationConfig,
    ProbeConfig,
)
from deburr_drake.config.scenario import (
    Scenario,
    SimulationConfig,
    field_type,
    get_field,
    load_scenario,
    scenario_names,
    scenario_path,
    set_field,
)
from deburr_drake.config.uncertainty import UncertaintyConfig

__all__ = [
    "ConfigError",
    "UncertaintyConfig",
    "JobConfig",
    "JobEdgeConfig",
    "PartConfig",
    "PoseConfig",
    "MaterialConfig",
    "ContactBandConfig",
    "EdgeConfig",
    "ToolConfig",
    "TaskConfig",
    "CommandConfig",
    "EstimatorConfig",
    "FuzzyConfig",
    "RobustConfig",
    "ImpedanceConfig",
    "PositionConfig",
    "ControllerConfig",
    "SensorConfig",
    "ProcessConfig",
    "BurrConfig",
    "RobotConfig",
    "ToolMountConfig",
    "SimulationConfig",
    "GuardsConfig",
    "PartErrorConfig",
    "DropoutConfig",
    "PartStepConfig",
    "FaultsConfig",
    "LocalisationConfig",
    "ProbeConfig",
    "OnlineRegistrationConfig",
    "Scenario",
    "load_scenario",
    "scenario_names",
    "scenario_path",
    "get_field",
    "set_field",
    "field_type",
]
