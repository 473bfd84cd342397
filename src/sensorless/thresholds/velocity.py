"""Velocity-based variable thresholds UT/LT of eq. (4.33)-(4.39), tuned by eq. (4.45)-(4.47).

The friction error of a robot depends on its velocity (eq. 4.23-4.24), and
the error of the rigid-body model is roughly proportional to h (eq. 4.25).
Removing both from the residual leaves r̂_c ≈ 0 (eq. 4.30), bounded by
L(q̇) < r̂_c < U(q̇) (eq. 4.32), hence for joint j (eq. 4.34-4.36)

    LT(t) = L(q̇) + γ h(t) + K_I/(s+K_I)·τ̂_fme(q̇)(t)
    UT(t) = U(q̇) + γ h(t) + K_I/(s+K_I)·τ̂_fme(q̇)(t).

τ̂_fme(q̇) is piecewise constant over velocity bins of width ``bin_width``
(the thesis quantised q̇ with 0.06 rad/s); bin ``k`` covers
``[k w, (k + 1) w)``. Zero velocity is a bin edge so that no bin mixes the
two directions of motion across the Coulomb friction jump.

Fit (eq. 4.45, section 4.5.2), per joint: least squares of r̂ on the columns
[h, K_I/(s+K_I)·1{q̇ ∈ bin b} for every visited bin b]; their coefficients
are γ and τ̂_fme(b). The indicators are filtered with the observer's
zero-order-hold recursion (:func:`~sensorless.thresholds.filtering.first_order`),
starting from their first value. With e = r̂ - γ h - K_I/(s+K_I)·τ̂_fme(q̇),
L(b) = min e and U(b) = max e over the fit samples in bin b (pooled with
neighbouring bins when b holds less than ``min_bin_time`` of fit data, see
:mod:`sensorless.thresholds.velocity_bins`), widened by ``margin``. The
same fit serves r̂_s (eq. 4.37-4.39, 4.46): the sign of the τ̂_sfe term is
absorbed by the fitted τ̂_fme, which is then -τ̂_sfe.

Combined form (eq. 4.19-4.21, 4.47): :class:`CombinedVelocityThreshold`
fits r̂ and r̂_s of the same runs with one γ; see
:mod:`sensorless.thresholds.velocity_combined`.

Velocities outside the fitted range take the nearest visited bin, widened by
``extrapolation_margin``; see :mod:`sensorless.thresholds.velocity_bins`.

This module gathers the velocity-based family:
:class:`VelocityThreshold` (:mod:`.velocity_single`),
:class:`CombinedVelocityThreshold` (:mod:`.velocity_combined`) and the bins
both use (:mod:`.velocity_bins`).

Examples
--------
>>> import numpy as np
>>> from sensorless.signals import ObserverSignals
>>> t = np.arange(2000) * 1e-3
>>> v = np.sin(2 * t)[:, None]
>>> z = np.zeros_like(v)
>>> run = ObserverSignals(t, 0.1 * np.tanh(5 * v), z, z, z, v, gain=20.0, robot="demo")
>>> th = VelocityThreshold(bin_width=0.1).fit(run)
>>> th.bin_edges_[[0, -1]]
array([-0.8,  1. ])
>>> lower, upper = th.bounds(run)
>>> bool(np.all((lower <= run.residual) & (run.residual <= upper)))
True
"""

from __future__ import annotations

from .velocity_bins import MAX_BINS
from .velocity_combined import (
    COMBINED_KIND,
    KINDS,
    WEIGHTINGS,
    CombinedVelocityState,
    CombinedVelocityThreshold,
)
from .velocity_single import VelocityThreshold

__all__ = [
    "COMBINED_KIND",
    "KINDS",
    "MAX_BINS",
    "WEIGHTINGS",
    "CombinedVelocityState",
    "CombinedVelocityThreshold",
    "VelocityThreshold",
]
