"""Collision-detection thresholds: lower and upper bounds of a residual, per joint and sample.

Every family is an estimator: ``fit`` on collision-free
:class:`~sensorless.signals.ObserverSignals` runs, then ``bounds`` (a whole
run) or ``initial_state``/``step``/``process`` (a live stream); fitted
thresholds ``save`` to a readable YAML file and :func:`load_threshold`
reads them back.

=====================  =====================  ==========================================
family                 name                   thesis
=====================  =====================  ==========================================
ConstantThreshold      ``"constant"``         ±β, eq. (5.32)
TimeVariantThreshold   ``"time_variant"``     ±α + γ h + ε_fr f, eq. (5.33); -C·sign, (5.39)
VelocityThreshold      ``"velocity"``         LT/UT of eq. (4.35)-(4.39), fit eq. (4.45)
ModelBasedThreshold    ``"model_based"``      ±B_c(t) of eq. (3.36) for τ̂_c (eq. 3.16)
=====================  =====================  ==========================================
"""

from __future__ import annotations

from .base import (
    METHODS,
    Threshold,
    ThresholdInputs,
    ThresholdState,
    first_order,
    first_order_step,
    load_threshold,
)
from .constant import ConstantThreshold
from .model_based import ModelBasedThreshold
from .time_variant import TimeVariantThreshold
from .velocity import CombinedVelocityState, CombinedVelocityThreshold, VelocityThreshold

__all__ = [
    "METHODS",
    "CombinedVelocityState",
    "CombinedVelocityThreshold",
    "ConstantThreshold",
    "ModelBasedThreshold",
    "Threshold",
    "ThresholdInputs",
    "ThresholdState",
    "TimeVariantThreshold",
    "VelocityThreshold",
    "first_order",
    "first_order_step",
    "load_threshold",
]
