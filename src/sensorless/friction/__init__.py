"""Joint friction models: Coulomb, viscous, Stribeck, sigmoid (Panda) and LuGre.

Sign convention
---------------
The friction torque ``tau_fr`` [N m] returned by every model in this package
is the torque that friction *dissipates*: it has the sign of the joint
velocity ``qd`` and enters the rigid-body dynamics with a minus sign,

    M(q) qdd + C(q, qd) qd + g(q) = tau_m + tau_c - tau_fr        eq. (5.1)

so ``tau_fr * qd >= 0`` for every dissipative model here. The one exception
is :class:`HystereticError`, which models the *error* of a friction
compensation, eq. (5.37), and has the sign that the thesis gives it.

Units are SI and angles are radians. Joint quantities have shape
``(n_dof,)`` for one sample or ``(n_samples, n_dof)`` for a time series (time
along axis 0); results have the shape of the input. Model parameters are per
joint: each accepts a scalar or an array of shape ``(n_dof,)``; scalars are
broadcast, and ``n_dof`` is the common length (1 when all are scalars).

Stateless models (:class:`Coulomb`, :class:`Viscous`, :class:`CoulombViscous`,
:class:`Stribeck`, :class:`Sigmoid`, :class:`HystereticError`) derive from
:class:`FrictionModel` and map a velocity to a torque with ``torque(qd)``.
The dynamic :class:`LuGre` model keeps its bristle deflection ``z`` [rad] in
an explicit state array, as ``zi``/``zf`` in :func:`scipy.signal.lfilter`:
``step`` advances one sample and ``torque`` a whole series, and a series cut
into chunks with the state carried over gives the same result as in one go.
"""

from __future__ import annotations

from .drift import DriftingFriction
from .lugre import LuGre
from .static import (
    Coulomb,
    CoulombViscous,
    FrictionModel,
    HystereticError,
    Sigmoid,
    Stribeck,
    Viscous,
)

__all__ = [
    "Coulomb",
    "CoulombViscous",
    "DriftingFriction",
    "FrictionModel",
    "HystereticError",
    "LuGre",
    "Sigmoid",
    "Stribeck",
    "Viscous",
]
