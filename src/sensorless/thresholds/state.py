"""What a threshold reads at every sample and what it carries from one sample to the next.

:class:`ThresholdInputs` holds the per-sample signals besides the residual,
each of shape ``(n_samples, n_dof)`` and already checked;
:class:`ThresholdState` is the streaming state a family returns from
``initial_state``, ``step`` and ``process``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .._validation import FloatArray
from ..signals import ObserverSignals

__all__ = ["ThresholdInputs", "ThresholdState"]

IntArray = NDArray[np.int64]


class ThresholdInputs(NamedTuple):
    """Per-sample signals a threshold needs besides the residual, each (n_samples, n_dof).

    ``position`` and ``acceleration`` are only used by families that need
    them (model-based thresholds) and may be None otherwise.
    """

    model_torque: FloatArray
    friction: FloatArray
    sign: FloatArray
    velocity: FloatArray
    position: FloatArray | None = None
    acceleration: FloatArray | None = None

    @classmethod
    def from_signals(
        cls, signals: ObserverSignals, rows: IntArray | None = None
    ) -> ThresholdInputs:
        """The inputs of a run, or of its samples ``rows``, as they are (not checked)."""
        taken = slice(None) if rows is None else rows

        def series(values: FloatArray | None) -> FloatArray | None:
            return None if values is None else values[taken]

        return cls(
            signals.model_torque[taken],
            signals.friction[taken],
            signals.sign[taken],
            signals.velocity[taken],
            series(signals.position),
            series(signals.acceleration),
        )


@dataclass(frozen=True, eq=False)
class ThresholdState:
    """Streaming state of a threshold; obtain it from ``Threshold.initial_state``.

    Attributes
    ----------
    dt : float
        Sample period of the stream [s].
    zi : ndarray
        Filter state of the family (the next output of its K_I/(s+K_I)
        filter, shape (n_dof,)); empty for families without memory.
    """

    dt: float
    zi: FloatArray
