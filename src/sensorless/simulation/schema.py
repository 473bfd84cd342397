"""The scenario file format, declared once: pydantic models and their JSON Schema.

:class:`ScenarioFile` and the models of its sections
(:mod:`sensorless.simulation.schema_parts`) declare every key a
scenario may hold, its type, its range and its default (the default of the
code that builds the scenario, :mod:`sensorless.simulation.scenario`). A key
"absent by default" may be left out but not set to null; what it means when
absent is in its description. :func:`validate_scenario` checks a mapping
against them, per-joint lengths against the robot's joints, and raises one
:class:`~sensorless.exceptions.FileFormatError` that lists every problem
with the path of its field (``controller.bandwith: unknown key; did you mean
'bandwidth'?``).

:func:`scenario_json_schema` is the JSON Schema of the format, for editors:
``sensorless/data/scenarios/scenario.schema.json`` is the committed copy
(:func:`write_scenario_json_schema` regenerates it).

Units SI and radians (via points in degrees unless ``degrees: false``).
"""

from __future__ import annotations

import functools
import importlib.resources
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import Field, ValidationError, model_validator
from pydantic_core import PydanticCustomError

from .. import robots
from ..io.file_schema import (
    FileModel,
    Positive,
    Problem,
    absent,
    check_format_version,
    file_error,
    problems_of,
    shown,
    version_field,
)
from .schema_interactions import Contact, RandomInteractionsSpec
from .schema_parts import (
    FRICTION_HELP,
    Controller,
    Friction,
    LuGreFriction,
    ModelErrorSpec,
    PayloadSpec,
    Plant,
    RandomCollisionsSpec,
    RigidPlantSpec,
    RobotName,
    Seed,
    SensorsSpec,
    Trajectory,
)

__all__ = [
    "SCENARIO_FORMAT_VERSION",
    "ScenarioFile",
    "scenario_json_schema",
    "validate_scenario",
    "write_scenario_json_schema",
]

SCENARIO_FORMAT_VERSION = 1
"""Version of the scenario format this library reads and writes."""

SCHEMA_FILE = "scenario.schema.json"


# ----------------------------------------------------------------------------- the file


class ScenarioFile(FileModel):
    """A scenario: a labelled simulated run (true and nominal robot, control, motion, contacts)."""

    format_version: int = version_field(SCENARIO_FORMAT_VERSION, "scenario")
    name: str = absent("Name of the scenario (absent: the file name without .yaml).")
    description: str = Field(default="", description="What the scenario is, for people.")
    duration: Positive = Field(description="Simulated time [s].")
    dt: Positive = Field(default=1e-3, description="Control period [s].")
    seed: Seed = Field(
        default=0, description="Default run seed (noise, random motion and contacts)."
    )
    robot: RobotName = Field(description="The true robot (a built-in robot).")
    nominal_robot: RobotName = absent("The model the user has (absent: robot).")
    model_error: ModelErrorSpec | None = Field(
        default=None, description="Error of the nominal model."
    )
    true_friction: Friction | None = Field(
        default="robot", description=f"True friction: {FRICTION_HELP}."
    )
    nominal_friction: Friction | None = absent(
        "Friction of the nominal model instead of the nominal robot's own (absent: its own; "
        f"Scenario.with_exact_model sets it): {FRICTION_HELP}."
    )
    plant: Plant = Field(default=RigidPlantSpec(), description="Plant: rigid or flexible joints.")
    controller: Controller = Field(description="Controller on the nominal model.")
    trajectory: Trajectory = Field(description="Desired motion.")
    sensors: SensorsSpec = Field(default=SensorsSpec(), description="Measurement model.")
    collisions: list[Contact] = Field(default=[], description="Contacts at given times.")
    random_collisions: RandomCollisionsSpec = absent(
        "Contacts drawn at random (not with collisions)."
    )
    random_interactions: RandomInteractionsSpec = absent(
        "Guiding (intended), clamp and impact contacts drawn at random, labelled in the "
        "ground truth (not with collisions or random_collisions)."
    )
    payload: PayloadSpec = absent(
        "A payload on the true robot's end link that the nominal model lacks (absent: none)."
    )

    @model_validator(mode="after")
    def _consistent(self) -> ScenarioFile:
        if self.random_collisions is not None and self.collisions:
            raise PydanticCustomError(
                "contacts",
                "give collisions or random_collisions, not both",
                {"field": "random_collisions"},
            )
        drawn = self.random_collisions is not None or bool(self.collisions)
        if self.random_interactions is not None and drawn:
            raise PydanticCustomError(
                "contacts",
                "give random_interactions alone, not with collisions or random_collisions",
                {"field": "random_interactions"},
            )
        ids = [contact.id for contact in self.collisions]
        repeated = sorted({i for i in ids if ids.count(i) > 1})
        if repeated:
            raise PydanticCustomError(
                "contacts",
                "contact ids must be unique; repeated: {ids}",
                {"field": "collisions", "ids": repeated},
            )
        if self.nominal_robot is not None and self.nominal_robot != self.robot:
            n_true, n_nominal = _robot_dof(self.robot), _robot_dof(self.nominal_robot)
            if n_true != n_nominal:
                raise PydanticCustomError(
                    "robots",
                    "{nominal} has {n_nominal} joints, robot {robot} has {n_true}",
                    {
                        "field": "nominal_robot",
                        "nominal": self.nominal_robot,
                        "robot": self.robot,
                        "n_nominal": n_nominal,
                        "n_true": n_true,
                    },
                )
        drift = isinstance(self.plant, RigidPlantSpec) and self.plant.friction_drift is not None
        if drift and isinstance(self.true_friction, LuGreFriction):
            raise PydanticCustomError(
                "drift",
                "friction_drift needs a stateless true_friction, not lugre",
                {"field": "plant.friction_drift"},
            )
        return self


@functools.cache
def _robot_dof(name: str) -> int:
    return robots.load(name).n_dof


def validate_scenario(data: Any, source: str = "scenario") -> ScenarioFile:
    """Check a scenario mapping against :class:`ScenarioFile`.

    Parameters
    ----------
    data : mapping
        The scenario, e.g. a YAML file read with :func:`yaml.safe_load`.
    source : str
        What ``data`` is, for the message (e.g. ``"scenario file run.yaml"``).

    Returns
    -------
    ScenarioFile
        The validated scenario (per-joint lengths checked against the robot).

    Raises
    ------
    FileFormatError
        One error listing every problem with the path of its field.
    """
    if not isinstance(data, Mapping):
        raise file_error(source, [_not_a_mapping(data)])
    check_format_version(data, SCENARIO_FORMAT_VERSION, source, "scenario")
    robot = data.get("robot")
    known = isinstance(robot, str) and robot in robots.available()
    context = {"n_dof": _robot_dof(robot)} if known else None
    try:
        return ScenarioFile.model_validate(dict(data), context=context)
    except ValidationError as exc:
        raise file_error(source, problems_of(exc, ScenarioFile)) from None


def _not_a_mapping(data: Any) -> Problem:
    return Problem((), f"a scenario is a mapping (key: value); got {shown(data)}")


def scenario_json_schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a scenario file, for editors and other tools."""
    schema = ScenarioFile.model_json_schema()
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "sensorless scenario",
        **{k: v for k, v in schema.items() if k != "title"},
    }


def schema_path() -> Path:
    """Where the committed JSON Schema of the scenario format lives (next to the scenarios)."""
    return Path(str(importlib.resources.files("sensorless") / "data" / "scenarios" / SCHEMA_FILE))


def scenario_json_schema_text() -> str:
    """:func:`scenario_json_schema` as the text of the committed file."""
    return json.dumps(scenario_json_schema(), indent=2, ensure_ascii=False) + "\n"


def write_scenario_json_schema(path: str | Path | None = None) -> Path:
    """Write the JSON Schema of the scenario format (default: the committed copy); its path."""
    out = schema_path() if path is None else Path(path)
    out.write_text(scenario_json_schema_text(), encoding="utf-8")
    return out
