"""Where the robot, tool and part models live, and how to load them. Models
resolve locally through ``models/package.xml`` (package
``deburr_drake_models``); nothing is fetched from the network."""

from __future__ import annotations

import os
from pathlib import Path

from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant

__all__ = [
    "models_dir",
    "make_parser",
    "POINT_MASS_URL",
    "make_kinematic_model",
]

POINT_MASS_URL = "package://deburr_drake_models/cartesian_tool.sdf"


def models_dir() -> Path:
    """The ``models/`` directory: $DEBURR_DRAKE_MODELS, else the one beside
    the package (source checkout or editable install)."""
    env = os.environ.get("DEBURR_DRAKE_MODELS")
    path = Path(env) if env else Path(__file__).resolve().parents[2] / "models"
    if not (path / "package.xml").is_file():
        raise FileNotFoundError(
            f"deburr_drake models not found at {path} (no package.xml): "
            "install from a source checkout (pip install -e .) or set "
            "DEBURR_DRAKE_MODELS to the repository's models/ directory"
        )
    return path


def make_parser(plant: MultibodyPlant) -> Parser:
    parser = Parser(plant)
    parser.package_map().AddPackageXml(str(models_dir() / "package.xml"))
    return parser


def make_kinematic_model(url: str) -> MultibodyPlant:
    """A standalone, finalized MultibodyPlant of the robot alone (no
    geometry simulation): the controller's and observers' model."""
    plant = MultibodyPlant(0.0)
    make_parser(plant).AddModels(url=url)
    plant.Finalize()
    return plant
