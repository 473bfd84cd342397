"""The file form of a phased threshold: the envelope, its params, its two parts nested.

A fitted :class:`~sensorless.thresholds.PhasedThreshold` is written as every
threshold file (:mod:`sensorless.thresholds.files`): the common envelope with
``method: phased``, the params ``level`` [rad/s²], ``hysteresis`` [-],
``hold`` [s], ``smoothing`` [s] and ``transient`` [s], and as attributes its
fitted parts ``accelerating_`` and ``steady_``, each a complete threshold
description of its own family. Reading checks all of it and reports every
problem with the path of its field.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
from pydantic import ValidationError

from ..exceptions import DimensionError, FileFormatError, InputValueError
from ..io.file_schema import (
    FileModel,
    Fraction,
    NonNegative,
    PerJointPositive,
    Problem,
    check_format_version,
    file_error,
    problems_of,
    shown,
)
from .file_schema import THRESHOLD_FORMAT_VERSION, ThresholdFile
from .files import envelope, threshold_from_dict

if TYPE_CHECKING:
    from .base import Threshold
    from .phased import PhasedThreshold

__all__ = ["PHASED_METHOD", "phased_to_dict", "read_phased"]

PHASED_METHOD = "phased"
"""The ``method`` of a phased threshold in a file."""


def phased_to_dict(threshold: PhasedThreshold) -> dict[str, Any]:
    """A fitted phased threshold as plain values (what ``save`` writes)."""
    return {
        **envelope(threshold, PHASED_METHOD),
        "params": {
            "level": threshold.level_.tolist(),
            "hysteresis": float(threshold.hysteresis),
            "hold": float(threshold.hold),
            "smoothing": float(threshold.smoothing),
            "transient": float(threshold.transient),
        },
        "attributes": {
            "accelerating_": threshold.accelerating_.to_dict(),
            "steady_": threshold.steady_.to_dict(),
        },
    }


class _PhasedParams(FileModel):
    """The params of a phased threshold in a file."""

    level: PerJointPositive
    hysteresis: Fraction
    hold: NonNegative
    smoothing: NonNegative
    transient: NonNegative = 0.0


_PARTS = ("accelerating_", "steady_")
_PART = "the part"


def read_phased(data: Mapping[str, Any], source: str, build: Callable[..., Threshold]) -> Threshold:
    """A fitted phased threshold from its description, checked; every problem in one error.

    ``build`` is ``PhasedThreshold.from_fitted`` (this module does not import the class).
    """
    if not isinstance(data, Mapping):
        raise file_error(source, [Problem((), f"expected a mapping; got {shown(data)}")])
    check_format_version(data, THRESHOLD_FORMAT_VERSION, source, "threshold")
    n_dof = data.get("n_dof")
    context = {"n_dof": n_dof} if isinstance(n_dof, int) and n_dof >= 1 else None
    problems: list[Problem] = []
    envelope = params = None
    try:
        envelope = ThresholdFile.model_validate(dict(data), context=context)
    except ValidationError as exc:
        problems += problems_of(exc, ThresholdFile)
    try:
        params = _PhasedParams.model_validate(data.get("params"), context=context)
    except ValidationError as exc:
        problems += problems_of(exc, _PhasedParams, ("params",))
    attributes = data.get("attributes")
    parts: dict[str, Threshold] = {}
    if isinstance(attributes, Mapping):
        problems += [
            Problem(("attributes", key), f"unknown key; expected {', '.join(_PARTS)}")
            for key in attributes
            if key not in _PARTS
        ]
        for name in _PARTS:
            if name not in attributes:
                problems.append(Problem(("attributes", name), "required key is missing"))
                continue
            try:
                parts[name] = threshold_from_dict(attributes[name], None, source=_PART)
            except (FileFormatError, InputValueError) as exc:
                problems.append(Problem(("attributes", name), str(exc).removeprefix(_PART + ": ")))
    if problems or envelope is None or params is None or len(parts) < len(_PARTS):
        raise file_error(source, problems)
    for name, part in parts.items():
        if (part.robot_, part.kind_, part.n_dof_) != (envelope.robot, envelope.kind, n_dof):
            raise file_error(
                source,
                [
                    Problem(
                        ("attributes", name),
                        f"a part for robot {part.robot_!r}, {part.kind_!r} signals and "
                        f"{part.n_dof_} joints; the file is for {envelope.robot!r}, "
                        f"{envelope.kind!r} and {n_dof}",
                    )
                ],
            )
    try:
        threshold = build(
            parts["accelerating_"],
            parts["steady_"],
            level=params.level,
            hysteresis=params.hysteresis,
            hold=params.hold,
            smoothing=params.smoothing,
        )
    except (DimensionError, InputValueError) as exc:
        raise FileFormatError(f"{source}: {exc}") from None
    threshold.transient = params.transient
    threshold.fingerprint_ = envelope.fingerprint or ""
    threshold.gain_ = np.asarray(envelope.gain, dtype=np.float64)
    threshold.dt_ = float(envelope.dt)
    return threshold
