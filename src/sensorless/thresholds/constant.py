"""Constant threshold β = max_t |r̂| on collision-free runs (eq. 5.32).

The bounds are ``-beta_`` and ``+beta_`` at every sample: a collision is
``|r̂_j(t)| > β_j`` (section 5.2). β_j is the largest |r̂_j| seen over all
fit runs, widened by ``margin``.

Examples
--------
>>> import numpy as np
>>> from sensorless.signals import ObserverSignals
>>> t = np.arange(4) * 1e-3
>>> r = np.array([[0.5], [-0.7], [0.2], [0.1]])
>>> z = np.zeros_like(r)
>>> run = ObserverSignals(t, r, z, z, z, z, gain=25.0, robot="demo")
>>> ConstantThreshold().fit(run).beta_
array([0.7])
"""

from __future__ import annotations

import numpy as np

from .._validation import FloatArray
from ..signals import ObserverSignals
from .base import StreamBounds, Threshold
from .fitting import BoolArray, stack
from .state import ThresholdInputs, ThresholdState

__all__ = ["ConstantThreshold"]


class ConstantThreshold(Threshold):
    """Constant bounds ±β per joint (eq. 5.32).

    Parameters
    ----------
    margin : float or array-like of shape (n_dof,)
        Added to β [N m], >= 0.
    joints, transient
        As for every family, see :class:`~sensorless.thresholds.base.Threshold`.

    Attributes
    ----------
    beta_ : ndarray of shape (n_dof,)
        max_t |r̂_j| over the fit runs plus ``margin`` [N m].
    """

    name = "constant"

    beta_: FloatArray

    def _attribute_names(self) -> tuple[str, ...]:
        return ("beta_",)

    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        residual = stack(runs, keep, "residual")
        self.beta_ = np.max(np.abs(residual), axis=0) + margin

    def _run(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        upper = np.broadcast_to(self.beta_, inputs.model_torque.shape).copy()
        return -upper, upper, state
