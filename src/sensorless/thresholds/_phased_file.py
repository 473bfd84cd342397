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

from ..exceptions import DimensionError, FileFormatError, InputValueError
from ..io.file_schema import (
    FileModel,
    Fraction,
    NonNegative,
    PerJointPositive,
)
from ._nested_file import read_nested
from .files import envelope

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
    envelope, params, parts = read_nested(data, source, _PhasedParams, _PARTS, (_PART, "a part"))
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
