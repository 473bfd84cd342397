"""The stateless friction models as a kind code and a parameter table, for compiled kernels.

The compiled stream (:mod:`sensorless.monitor._compiled`) and the compiled
simulator (:mod:`sensorless.simulation._friction_kernels`) evaluate the
models of :mod:`sensorless.friction.static` joint by joint from a kind code and
up to five parameters per joint, in the order of :data:`STATIC_KINDS`, with
:func:`sensorless.friction._static_kernel.static_torque`. This module needs no
numba. Units: [N m], [N m s/rad], [rad/s] as the models state.
"""

from __future__ import annotations

import numpy as np

from .._validation import FloatArray
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
    "COULOMB",
    "COULOMB_VISCOUS",
    "HYSTERETIC",
    "NO_FRICTION",
    "SIGMOID",
    "STATIC_KINDS",
    "STRIBECK",
    "VISCOUS",
    "static_parameters",
]

NO_FRICTION, COULOMB, VISCOUS, COULOMB_VISCOUS, STRIBECK, SIGMOID, HYSTERETIC = range(7)

STATIC_KINDS: dict[type, tuple[int, tuple[str, ...]]] = {
    Coulomb: (COULOMB, ("c_pos", "c_neg")),
    Viscous: (VISCOUS, ("fv",)),
    CoulombViscous: (COULOMB_VISCOUS, ("c_pos", "c_neg", "fv")),
    Stribeck: (STRIBECK, ("fc", "fs", "vs", "fv", "delta")),
    Sigmoid: (SIGMOID, ("phi1", "phi2", "phi3")),
    HystereticError: (HYSTERETIC, ("c",)),
}
"""Kind code and parameter names of each stateless model (exact types only)."""


def static_parameters(model: FrictionModel | None, n_dof: int) -> tuple[int, FloatArray]:
    """Kind code and parameters (n_dof, 5) of ``model`` (None: no friction).

    ``model`` must be of a type in :data:`STATIC_KINDS`.
    """
    parameters = np.zeros((n_dof, 5))
    if model is None:
        return NO_FRICTION, parameters
    kind, names = STATIC_KINDS[type(model)]
    for column, name in enumerate(names):
        parameters[:, column] = np.broadcast_to(getattr(model, name), (n_dof,))
    return kind, parameters
