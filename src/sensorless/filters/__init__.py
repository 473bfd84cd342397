"""Velocity and acceleration estimation from sampled joint positions.

Thesis § 3.4.1: the velocity and acceleration used by a model-based estimator
are filtered estimates, and a causal filter always delays and low-passes the
true signal. This module gives the usual estimators with their delay made
explicit.

Causal estimators (usable in a control loop)
    :class:`FiniteDifference`, :class:`DirtyDerivative`, :class:`Butterworth`.
Offline estimator (needs the whole record)
    :class:`SavitzkyGolay`.

Conventions
-----------
Units are SI and angles radians. Positions ``x`` have shape
``(n_samples, n_dof)`` (time along axis 0) or ``(n_dof,)`` for one sample;
results are :class:`Derivatives` ``(position, velocity, acceleration)`` in
[rad], [rad/s], [rad/s²].

Design is separate from application, as in :mod:`scipy.signal`: the
constructor designs, once, three cascades of second-order sections acting on
the raw position,

    position     = sosfilt(sos_position, x)
    velocity     = sosfilt(sos_velocity, x) / dt
    acceleration = sosfilt(sos_acceleration, x) / dt**2

where ``sos_velocity`` is one backward-difference section ``1 - z⁻¹`` followed
by the estimator's low-pass, and ``sos_acceleration`` two of them followed by
its low-pass. Putting the differences first, and on the raw position, makes a
robot at rest give a velocity and an acceleration of exactly zero, and makes
:class:`FiniteDifference` bit-for-bit ``np.diff(x, axis=0) / dt``.

The filter state is an explicit, immutable :class:`FilterState` holding the
``zi`` of :func:`scipy.signal.sosfilt` for the three cascades (shape
``(n_sections, 2, n_dof)`` each). :meth:`CausalEstimator.initial_state` gives
the state of a robot standing still at ``x0`` (no start-up transient);
:meth:`CausalEstimator.step` (one sample) and :meth:`CausalEstimator.filter`
(a whole array) run the same code, so a signal processed sample by sample or
in chunks, carrying the returned state, gives the same result as in one go.

Examples
--------
>>> import numpy as np
>>> from sensorless.filters import Butterworth
>>> dt = 1e-3
>>> t = np.arange(2000)[:, None] * dt
>>> q = np.hstack([np.sin(np.pi * t), 0.5 * t])          # two joints [rad]
>>> est = Butterworth(dt, cutoff=20.0)                    # 5th order, as in the thesis
>>> y, state = est.filter(q)
>>> y.velocity.shape
(2000, 2)
>>> bool(np.allclose(y.velocity[-1, 1], 0.5))            # ramp of 0.5 rad/s
True
>>> round(est.delay * 1e3, 1)                            # velocity delay [ms]
26.2
"""

from __future__ import annotations

from ._derivatives import Derivatives
from .causal import (
    Butterworth,
    CausalEstimator,
    Delays,
    DirtyDerivative,
    FilterState,
    FiniteDifference,
)
from .savitzky_golay import SavitzkyGolay

__all__ = [
    "Butterworth",
    "CausalEstimator",
    "Delays",
    "Derivatives",
    "DirtyDerivative",
    "FilterState",
    "FiniteDifference",
    "SavitzkyGolay",
]
