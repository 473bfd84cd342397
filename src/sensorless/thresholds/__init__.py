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
TimeVariantThreshold   ``"time-variant"``     ±α + γ h + ε_fr f, eq. (5.33); -C·sign, (5.39)
VelocityThreshold      ``"velocity"``         LT/UT of eq. (4.35)-(4.39), fit eq. (4.45)
ModelBasedThreshold    ``"model"``            ±B_c(t) of eq. (3.36) for τ̂_c (eq. 3.16)
=====================  =====================  ==========================================

:class:`CombinedVelocityThreshold` (``"velocity-combined"``) fits the
velocity-based bounds of r̂ and r̂_s together (eq. 4.47). Thresholds give
bounds only; :class:`sensorless.detection.Detector` turns them into events.
:class:`PayloadThreshold` wraps any fitted family and widens its bounds for
a payload of a declared range (mass, region in the end-link frame).

Modules: :mod:`.base` (the estimator skeleton), :mod:`.fitting` (what the
fits share), :mod:`.filtering` (K_I/(s+K_I)), :mod:`.checks`, :mod:`.state`
(stream inputs and states), :mod:`.files` (YAML format, :data:`METHODS`),
one module per family (:mod:`.velocity` gathers :mod:`.velocity_single`,
:mod:`.velocity_combined` and their bins, :mod:`.velocity_bins`). Nothing
here imports :mod:`sensorless.detection`.
"""

from __future__ import annotations

from ._learned_files import LearnedWeights, builtin_weights, load_weights, save_weights
from .base import Threshold
from .constant import ConstantThreshold
from .files import METHODS, load_threshold
from .filtering import first_order, first_order_step
from .learned import LearnedState, LearnedThreshold
from .model_based import ModelBasedThreshold
from .payload import PayloadRange, PayloadThreshold
from .phased import PhasedState, PhasedThreshold, Phases
from .state import ThresholdInputs, ThresholdState
from .time_variant import TimeVariantThreshold
from .velocity import CombinedVelocityState, CombinedVelocityThreshold, VelocityThreshold

__all__ = [
    "METHODS",
    "CombinedVelocityState",
    "CombinedVelocityThreshold",
    "ConstantThreshold",
    "LearnedState",
    "LearnedThreshold",
    "LearnedWeights",
    "ModelBasedThreshold",
    "PayloadRange",
    "PayloadThreshold",
    "PhasedState",
    "PhasedThreshold",
    "Phases",
    "Threshold",
    "ThresholdInputs",
    "ThresholdState",
    "TimeVariantThreshold",
    "VelocityThreshold",
    "builtin_weights",
    "first_order",
    "first_order_step",
    "load_threshold",
    "load_weights",
    "save_weights",
]
