"""Compiled (numba) torque of the stateless friction models, one joint at a time.

Importing this module requires numba. The kind codes and the parameter order
are those of :mod:`sensorless.friction._kinds`; the arithmetic follows
:mod:`sensorless.friction.static` operation by operation.
"""

from __future__ import annotations

import math

from numba import njit

from .._validation import FloatArray
from ._kinds import COULOMB, COULOMB_VISCOUS, HYSTERETIC, SIGMOID, STRIBECK, VISCOUS

__all__ = ["expit", "sign", "static_torque"]


@njit(cache=True)
def sign(x: float) -> float:
    """−1, 0 or 1."""
    return 1.0 if x > 0.0 else (-1.0 if x < 0.0 else 0.0)


@njit(cache=True)
def expit(x: float) -> float:
    """1 / (1 + exp(−x)) without overflow."""
    if x >= 0.0:
        return 1.0 / (1.0 + math.exp(-x))
    z = math.exp(x)
    return z / (1.0 + z)


@njit(cache=True)
def static_torque(kind: int, table: FloatArray, j: int, at: int, v: float) -> float:
    """τ_fr(q̇) [N m] of joint j at velocity ``v`` [rad/s]; parameters ``table[j, at:at + 5]``.

    Indexed, not sliced: a view per joint and sample costs more than the
    arithmetic. Any other kind (none, or a stateful model) gives 0.
    """
    c0, c1, c2 = table[j, at], table[j, at + 1], table[j, at + 2]
    if kind == COULOMB or kind == COULOMB_VISCOUS:
        coulomb = c0 if v > 0.0 else (c1 if v < 0.0 else 0.0)
        return coulomb + c2 * v if kind == COULOMB_VISCOUS else coulomb
    if kind == VISCOUS:
        return c0 * v
    if kind == STRIBECK:
        fv, delta = table[j, at + 3], table[j, at + 4]
        level = c0 + (c1 - c0) * math.exp(-((abs(v) / c2) ** delta))
        return sign(v) * level + fv * v
    if kind == SIGMOID:
        return c0 * expit(c1 * (v + c2)) - c0 * expit(c1 * c2)
    if kind == HYSTERETIC:
        return -c0 * sign(v)
    return 0.0
