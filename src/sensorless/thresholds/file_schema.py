"""The declared format of a fitted-threshold file: envelope, hyper-parameters, attributes.

:mod:`sensorless.thresholds.files` reads and writes the files; this module says
what a valid one holds, once:

* :class:`ThresholdFile`, the envelope every family shares (pydantic);
* the hyper-parameters of a family: the keywords and defaults of its
  constructor, each typed by its name in :data:`PARAMETER_TYPES`
  (:func:`params_model`);
* the fitted attributes: :data:`ATTRIBUTES` gives the shape and the sign of
  each (:func:`attribute_problems` checks a file's attributes against it).

Units: gains [1/s], periods [s], torques [N m], velocities [rad/s].
"""

from __future__ import annotations

import functools
import inspect
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated, Any, Literal

import numpy as np
from pydantic import (
    AfterValidator,
    AllowInfNan,
    BaseModel,
    Field,
    StringConstraints,
    ValidationInfo,
    create_model,
    model_validator,
)
from pydantic_core import PydanticCustomError

from ..io.file_schema import (
    FileModel,
    NonNegative,
    PerJointNonNegative,
    Positive,
    PositiveInt,
    Problem,
    Vector3,
    absent,
    context_n_dof,
    did_you_mean,
    joint_list,
    known_name,
    one_of,
    shown,
    version_field,
)
from ..robots import available as available_robots
from ..robots.regressors import q_length

if TYPE_CHECKING:
    from .base import Threshold

__all__ = [
    "ATTRIBUTES",
    "ATTRIBUTE_SELECTORS",
    "PARAMETER_TYPES",
    "THRESHOLD_FORMAT_VERSION",
    "Attribute",
    "ThresholdFile",
    "attribute_problems",
    "params_model",
]

THRESHOLD_FORMAT_VERSION = 1
"""Version of the threshold file format this library reads and writes."""

# ----------------------------------------------------------------------------- envelope


if TYPE_CHECKING:
    Gains = list[float]
else:
    Gains = joint_list(Annotated[float, AllowInfNan()])


Fingerprint = Annotated[str, StringConstraints(pattern=r"^[0-9a-f]{16}$")]
"""16 lower-case hexadecimal digits (:func:`sensorless.robots.fingerprint.model_fingerprint`)."""


class ThresholdFile(FileModel):
    """What every fitted-threshold file holds besides its family's params and attributes."""

    format_version: int = version_field(THRESHOLD_FORMAT_VERSION, "threshold")
    method: str = Field(
        description="Family name: constant, time-variant, hysteretic, velocity, "
        "velocity-combined or model (earlier files: time_variant, model_based, "
        "velocity_combined; checked against the registry by the reader)."
    )
    library_version: str = absent("Version of sensorless that wrote the file.")
    robot: str = Field(description="Robot name of the fit runs.")
    fingerprint: Fingerprint | None = absent(
        "Fingerprint of the fit runs' nominal model (sensorless.robots.fingerprint); "
        "absent: the robot name alone identifies the model (files of earlier versions)."
    )
    joint_fingerprint: Fingerprint | None = absent(
        "velocity-combined only: fingerprint of the nominal model of the r̂_s runs."
    )
    kind: Literal["motor", "joint", "acceleration", "motor+joint"] = Field(
        description="Signal kind of the fit runs."
    )
    n_dof: PositiveInt = Field(description="Number of joints.")
    gain: Gains = Field(description="Observer gain K_I per joint [1/s].")
    dt: Positive = Field(description="Median sample period of the fit runs [s].")
    params: dict[str, Any] = Field(description="Hyper-parameters of the family.")
    attributes: dict[str, Any] = Field(description="Fitted attributes of the family.")

    @model_validator(mode="after")
    def _gains(self) -> ThresholdFile:
        # An acceleration-based estimate has no observer gain: NaN.
        nan_ok = self.kind == "acceleration"
        for k, value in enumerate(self.gain):
            if not (value > 0 and math.isfinite(value)) and not (nan_ok and math.isnan(value)):
                expected = "a finite number > 0" + (" or NaN" if nan_ok else "")
                raise PydanticCustomError(
                    "gain",
                    "expected {expected}; got {value}",
                    {"field": f"gain[{k}]", "expected": expected, "value": value},
                )
        return self


# ----------------------------------------------------------------------------- params


def _joint_numbers(joints: list[int], info: ValidationInfo) -> list[int]:
    n_dof = context_n_dof(info)
    if len(set(joints)) != len(joints) or (n_dof is not None and max(joints) > n_dof):
        raise PydanticCustomError(
            "joints",
            "expected distinct joint numbers in 1..{n_dof}; got {joints}",
            {"n_dof": n_dof if n_dof is not None else "n_dof", "joints": joints},
        )
    return joints


def _rotation(rows: list[list[float]]) -> list[list[float]]:
    matrix = np.asarray(rows)
    if not np.allclose(matrix @ matrix.T, np.eye(3), atol=1e-6) or np.linalg.det(matrix) < 0:
        raise ValueError(f"expected a rotation matrix (orthonormal, det +1); got {rows}")
    return rows


class JointDescription(FileModel):
    """One joint of a saved rigid-body robot (Pinocchio joint type, placement in its parent)."""

    name: str
    type: str
    parent: Annotated[int, Field(ge=0)]
    rotation: Annotated[list[Vector3], Field(min_length=3, max_length=3), AfterValidator(_rotation)]
    translation: Vector3
    axis: Vector3 = absent("Axis of an unaligned revolute joint.")


class RobotDescription(FileModel):
    """A saved rigid-body robot: what the regressor and Θ̂ of a model-based threshold need."""

    name: str
    gravity: Vector3
    joints: Annotated[list[JointDescription], Field(min_length=1)]
    standard_parameters: list[float]


if TYPE_CHECKING:
    Robot = str | RobotDescription
    PerValueNonNegative = float | list[float]
else:
    Robot = one_of(
        "threshold_robot",
        {
            "name": Annotated[str, AfterValidator(known_name("robot", available_robots))],
            "description": RobotDescription,
        },
        pick=lambda v: (
            "name" if isinstance(v, str) else ("description" if isinstance(v, dict) else None)
        ),
        expected="a built-in robot name or a saved robot description (mapping)",
    )
    PerValueNonNegative = one_of(
        "per_value_nonnegative",
        {"number": NonNegative, "list": list[NonNegative]},
        pick=lambda v: "list" if isinstance(v, list) else "number",
        expected="a number or a list of numbers",
    )

PARAMETER_TYPES: dict[str, Any] = {
    "margin": PerJointNonNegative,
    "joints": Annotated[list[PositiveInt], Field(min_length=1), AfterValidator(_joint_numbers)]
    | None,
    "transient": NonNegative,
    "form": Literal["friction", "hysteretic"],
    "fit_method": Literal["least_squares", "minimax"],
    "max_lp_samples": Annotated[int, Field(ge=3)],
    "bin_width": Positive,
    "min_bin_time": NonNegative,
    "extrapolation_margin": NonNegative,
    "weighting": Literal["equal", "inverse_variance"],
    "robot": Robot,
    "btheta": PerValueNonNegative,
    "bq": list[NonNegative] | None,
    "disturbance": PerJointNonNegative,
    "reference_window": Positive,
    "chunk_size": PositiveInt,
    "weights": Annotated[str, StringConstraints(min_length=1)] | None,
}
"""Type of every hyper-parameter by name (a name means the same in every family)."""


@functools.cache
def params_model(family: type[Threshold]) -> type[BaseModel]:
    """The params of ``family``: its constructor's keywords and defaults, typed by name."""
    fields: dict[str, Any] = {}
    for parameter in inspect.signature(family.__init__).parameters.values():
        if parameter.name == "self":
            continue
        default = ... if parameter.default is inspect.Parameter.empty else parameter.default
        fields[parameter.name] = (PARAMETER_TYPES.get(parameter.name, Any), default)
    return create_model(f"{family.__name__}Params", __base__=FileModel, **fields)


# ----------------------------------------------------------------------------- attributes


@dataclass(frozen=True)
class Attribute:
    """A fitted attribute in a file: its shape (sizes by name) and the sign of its values."""

    shape: tuple[str, ...] | None
    sign: Literal["finite", "nonnegative", "count", "fraction", "increasing"]


_PER_JOINT = ("n_dof",)
_PER_BIN = ("n_bins", "n_dof")
ATTRIBUTES: dict[str, Attribute] = {
    "beta_": Attribute(_PER_JOINT, "nonnegative"),
    "alpha_": Attribute(_PER_JOINT, "nonnegative"),
    "gamma_": Attribute(_PER_JOINT, "finite"),
    "eps_fr_": Attribute(_PER_JOINT, "finite"),
    "c_": Attribute(_PER_JOINT, "finite"),
    "bin_edges_": Attribute(("n_edges",), "increasing"),
    "tau_fme_": Attribute(_PER_BIN, "finite"),
    "tau_sfe_": Attribute(_PER_BIN, "finite"),
    "lower_": Attribute(_PER_BIN, "finite"),
    "upper_": Attribute(_PER_BIN, "finite"),
    "lower_motor_": Attribute(_PER_BIN, "finite"),
    "upper_motor_": Attribute(_PER_BIN, "finite"),
    "lower_joint_": Attribute(_PER_BIN, "finite"),
    "upper_joint_": Attribute(_PER_BIN, "finite"),
    "counts_": Attribute(_PER_BIN, "count"),
    "weights_": Attribute(("2", "n_dof"), "fraction"),
    "bq_": Attribute(("n_q",), "nonnegative"),
    "theta_": Attribute(("n_base",), "finite"),
    "independent_": Attribute(("n_base",), "count"),
    "btheta_": Attribute(("n_base",), "nonnegative"),
    "b_fr_": Attribute(_PER_JOINT, "nonnegative"),
    "b_d_": Attribute(_PER_JOINT, "nonnegative"),
}
"""Shape and sign of every fitted attribute a family may save (a name means the same everywhere).

Sizes: ``n_dof`` from the file, ``n_edges`` the length of ``bin_edges_`` (and
``n_bins = n_edges - 1``), ``n_base`` the length of ``theta_``, ``n_q`` the
(n² + 3n + 2)/2 entries of B_Q̃.
"""

_ORDERED = {"upper_": "lower_", "upper_motor_": "lower_motor_", "upper_joint_": "lower_joint_"}
"""An upper bound table and the lower one it may not fall below."""
_SIZERS = {"bin_edges_": "n_edges", "theta_": "n_base"}
_UNDECLARED = Attribute(None, "finite")
ATTRIBUTE_SELECTORS = ("form",)
"""Hyper-parameters that choose which attributes a family has (``form`` of time-variant)."""

_SIGN_TEXT = {
    "finite": "finite numbers",
    "nonnegative": "finite numbers >= 0",
    "count": "integers >= 0",
    "fraction": "numbers in [0, 1]",
    "increasing": "strictly increasing finite numbers",
}


def _leaves(value: Any) -> list[Any]:
    if isinstance(value, list):
        return [leaf for item in value for leaf in _leaves(item)]
    return [value]


def _as_array(value: Any, integer: bool) -> np.ndarray[Any, Any] | None:
    """``value`` as an array if it is a (nested, rectangular) list of numbers, else None."""
    allowed = (int,) if integer else (int, float)
    if any(isinstance(x, bool) or not isinstance(x, allowed) for x in _leaves(value)):
        return None
    try:
        return np.asarray(value, dtype=np.int64 if integer else np.float64)
    except ValueError:  # ragged
        return None


def _sign_ok(values: np.ndarray[Any, Any], sign: str) -> np.ndarray[Any, Any]:
    finite = np.isfinite(values)
    if sign == "nonnegative" or sign == "count":
        return finite & (values >= 0)
    if sign == "fraction":
        return finite & (values >= 0) & (values <= 1)
    if sign == "increasing":
        steps = np.diff(values, prepend=-np.inf) > 0
        return finite & steps
    return finite


def _check_attribute(
    name: str, value: Any, sizes: dict[str, int]
) -> tuple[str | None, np.ndarray[Any, Any] | None]:
    """What is wrong with one attribute (None: nothing) and its array; may fix a size."""
    declared = ATTRIBUTES.get(name, _UNDECLARED)
    array = _as_array(value, declared.sign == "count")
    if array is None:
        wanted = "integers" if declared.sign == "count" else "numbers"
        return f"expected a (nested) list of {wanted}; got {shown(value)}", None
    if name in _SIZERS:  # its length fixes a size: n_edges or n_base
        if array.ndim != 1:
            return f"expected a flat list, shape ({_SIZERS[name]},); got {array.shape}", None
        sizes[_SIZERS[name]] = array.shape[0]
        sizes["n_bins"] = sizes.get("n_edges", 1) - 1
    if declared.shape is not None:  # None: a family's own, checked by its _check_attributes
        if any(size not in sizes for size in declared.shape):
            return None, None  # the attribute that fixes its size is wrong, and reported
        shape = tuple(sizes[size] for size in declared.shape)
        too_few = declared.sign == "increasing" and array.size < 2
        if array.shape != shape or too_few:
            symbols = str(declared.shape).replace("'", "")
            return f"expected shape {symbols} = {shape}; got {array.shape}", None
    good = _sign_ok(array, declared.sign)
    if not good.all():
        at = [int(i) for i in np.argwhere(~good)[0]]
        return f"expected {_SIGN_TEXT[declared.sign]}; got {array[tuple(at)]} at {at}", None
    return None, array


def attribute_problems(
    names: Sequence[str], attributes: Mapping[str, Any], n_dof: int, selected: str
) -> tuple[list[Problem], dict[str, np.ndarray[Any, Any]]]:
    """Check ``attributes`` against :data:`ATTRIBUTES`; the problems and the arrays.

    ``names`` are the attributes the family has with the params of the file,
    which ``selected`` names (e.g. `` for params.form: 'friction'``).
    """
    problems = [
        Problem(("attributes", key), f"unknown key{selected}" + did_you_mean(key, names))
        for key in attributes
        if key not in names
    ]
    problems += [
        Problem(("attributes", name), f"required key is missing{selected}")
        for name in names
        if name not in attributes
    ]
    arrays: dict[str, np.ndarray[Any, Any]] = {}
    sizes: dict[str, int] = {"n_dof": n_dof, "2": 2, "n_q": q_length(n_dof)}
    # The attributes that fix a size come first.
    for name in sorted((n for n in names if n in attributes), key=lambda n: n not in _SIZERS):
        message, array = _check_attribute(name, attributes[name], sizes)
        if message is not None:
            problems.append(Problem(("attributes", name), message))
        elif array is not None:
            arrays[name] = array
    for upper, lower in _ORDERED.items():
        if upper in arrays and lower in arrays and (arrays[upper] < arrays[lower]).any():
            at = [int(i) for i in np.argwhere(arrays[upper] < arrays[lower])[0]]
            message = f"expected {upper} >= {lower} in every bin; got {arrays[upper][tuple(at)]} "
            message += f"< {arrays[lower][tuple(at)]} at {at}"
            problems.append(Problem(("attributes", upper), message))
    return problems, arrays
