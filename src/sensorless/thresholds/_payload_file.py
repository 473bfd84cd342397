"""The file form of a payload threshold: the envelope, the declared range, the wrapped threshold.

A fitted :class:`~sensorless.thresholds.PayloadThreshold` is written as every
threshold file (:mod:`sensorless.thresholds.files`): the common envelope with
``method: payload``, the params ``max_mass`` [kg], ``center`` [m], ``radius``
[m] or ``half_widths`` [m] (the declared range in the end-link frame) and
``velocity_error`` [rad/s], and as attribute the fitted wrapped threshold
``threshold_``, a complete description of its own family.

The widening needs the nominal model itself (the end link's regressor), which
the file names by its robot name and fingerprint but does not hold. Reading
takes the model from the caller (``robot=``); without it, from the built-in
robot of that name when its fingerprint is the file's. Any other model is
refused with :class:`~sensorless.exceptions.ModelMismatchError`: a range
declared for one model widens another's bounds by the wrong amount.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from ..exceptions import (
    DimensionError,
    FileFormatError,
    InputValueError,
    ModelMismatchError,
    UnknownNameError,
)
from ..io.file_schema import (
    FileModel,
    NonNegative,
    PerJointNonNegative,
    Vector3,
    absent,
)
from ..robots import load as load_robot
from ..robots.model import RobotModel
from ._nested_file import read_nested
from .file_schema import ThresholdFile
from .files import envelope

if TYPE_CHECKING:
    from .base import Threshold
    from .payload import PayloadThreshold

__all__ = ["PAYLOAD_METHOD", "payload_to_dict", "read_payload"]

PAYLOAD_METHOD = "payload"
"""The ``method`` of a payload threshold in a file."""

_PART = "the wrapped threshold"


def payload_to_dict(threshold: PayloadThreshold) -> dict[str, Any]:
    """A fitted payload threshold as plain values (what ``save`` writes)."""
    declared = threshold.range_
    shape = (
        {"radius": float(declared.radius or 0.0)}
        if declared.half_widths is None
        else {"half_widths": declared.half_widths.tolist()}
    )
    return {
        **envelope(threshold, PAYLOAD_METHOD),
        "params": {
            "max_mass": float(declared.max_mass),
            "center": declared.center.tolist(),
            **shape,
            "velocity_error": threshold.velocity_error_.tolist(),
        },
        "attributes": {"threshold_": threshold.threshold_.to_dict()},
    }


class _PayloadParams(FileModel):
    """The params of a payload threshold in a file (the declared range, end-link frame)."""

    max_mass: NonNegative
    center: Vector3
    radius: NonNegative | None = absent("Radius of the ball [m] (give it or half_widths).")
    half_widths: Vector3 | None = absent("Half-widths of the box [m] (or radius).")
    velocity_error: PerJointNonNegative = 0.0


def _nominal(envelope: ThresholdFile, robot: RobotModel | None, source: str) -> RobotModel:
    """The nominal model the file was fitted with: ``robot``, or the built-in of that name."""
    fingerprint = envelope.fingerprint
    if robot is not None:
        if robot.name != envelope.robot or (fingerprint and robot.fingerprint != fingerprint):
            raise ModelMismatchError(
                f"{source}: the payload threshold was fitted with the nominal model "
                f"{envelope.robot!r} (fingerprint {fingerprint or 'not saved'}); robot is "
                f"{robot.name!r} (fingerprint {robot.fingerprint})"
            )
        return robot
    try:
        builtin = load_robot(envelope.robot)
    except UnknownNameError:
        builtin = None
    if builtin is not None and (not fingerprint or builtin.fingerprint == fingerprint):
        return builtin
    raise ModelMismatchError(
        f"{source}: the payload threshold needs its nominal model {envelope.robot!r} "
        f"(fingerprint {fingerprint or 'not saved'}), which is not a built-in robot with these "
        "parameters: load it with robot= (load_threshold(path, robot=model))"
    )


def read_payload(
    data: Mapping[str, Any],
    source: str,
    robot: RobotModel | None,
    build: Callable[..., Threshold],
) -> Threshold:
    """A fitted payload threshold from its description, checked; every problem in one error.

    ``build`` is ``PayloadThreshold.from_fitted`` (this module does not import the class).

    Raises
    ------
    FileFormatError
        The description does not follow the format (every problem with the path
        of its field), or its wrapped threshold disagrees with its envelope.
    ModelMismatchError
        ``robot`` is not the file's nominal model, or none was given and no
        built-in robot is.
    """
    envelope, params, parts = read_nested(
        data, source, _PayloadParams, ("threshold_",), (_PART, "a threshold")
    )
    nominal = _nominal(envelope, robot, source)
    try:
        threshold = build(
            parts["threshold_"],
            nominal,
            params.max_mass,
            center=params.center,
            radius=params.radius,
            half_widths=params.half_widths,
            velocity_error=params.velocity_error,
        )
    except (DimensionError, InputValueError) as exc:
        raise FileFormatError(f"{source}: {exc}") from None
    threshold.gain_ = np.asarray(envelope.gain, dtype=np.float64)
    threshold.dt_ = float(envelope.dt)
    return threshold
