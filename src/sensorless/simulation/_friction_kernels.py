"""Compiled (numba) friction of the simulated plants, one joint at a time.

Importing this module requires numba. A friction model is packed by
:func:`sensorless.simulation.compiled.pack_friction` into one float64 array
``fr`` of shape (n_dof, 24); per joint:

- 0: kind — 0 none, 1 Coulomb (c₊, c₋), 2 viscous (f_v), 3 Coulomb + viscous
  (c₊, c₋, f_v), 4 Stribeck (F_c, F_s, v_s, f_v, δ), 5 sigmoid (φ₁, φ₂, φ₃),
  6 hysteretic error (c), 7 LuGre (σ₀, σ₁, σ₂, F_c, F_s, v_s, δ);
- 1: 1 when the model drifts with time (:class:`~sensorless.friction.DriftingFriction`);
- 2–8: the parameters of the kind, in the order above;
- 9–21 (drifting only): warm-up fractions w_c, w_v, time constant T [s], the
  base's viscous coefficient, amplitudes [N m], angular frequencies [rad/s]
  and phases [rad] of the three offset sinusoids;
- 22: 1 when a LuGre model uses the Gaussian Stribeck curve on every joint.

What is held over a period or a substep lives in ``held`` (n_dof, 5): the
Coulomb and viscous scales and the offset of a drifting model at the
period's time, the bristle spring σ₀ z and its coupling σ₁ σ₀ z of LuGre.
The arithmetic follows :mod:`sensorless.friction` operation by operation.
"""

from __future__ import annotations

import math

from numba import njit

from .._validation import FloatArray
from ..friction._static_kernel import sign, static_torque

__all__ = ["advance_bristles", "hold_bristles", "hold_drift", "recorded", "stage"]

_LUGRE = 7.0


@njit(cache=True)
def _static(fr: FloatArray, j: int, v: float) -> float:
    """Torque of a stateless model at velocity v [rad/s] on joint j."""
    return static_torque(int(fr[j, 0]), fr, j, 2, v)


@njit(cache=True)
def _level(fr: FloatArray, j: int, v: float) -> float:
    """Stribeck level s(q̇) [N m] of a LuGre joint, eq. (4.22c)."""
    fc, fs, vs = fr[j, 5], fr[j, 6], fr[j, 7]
    if fr[j, 22] == 1.0:
        ratio = v / vs
        return fc + (fs - fc) * math.exp(-(ratio * ratio))
    return fc + (fs - fc) * math.exp(-((abs(v) / vs) ** fr[j, 8]))


@njit(cache=True)
def hold_drift(fr: FloatArray, t: float, held: FloatArray) -> None:
    """The scales and the offset of a drifting model at time t [s] into held[:, 0:3]."""
    for j in range(fr.shape[0]):
        if fr[j, 1] != 1.0:
            continue
        warmed = -math.expm1(-t / fr[j, 11])
        held[j, 0] = 1.0 - fr[j, 9] * warmed
        held[j, 1] = 1.0 - fr[j, 10] * warmed
        offset = 0.0
        for m in range(3):
            phase = fr[j, 19 + m]
            offset += fr[j, 13 + m] * (math.sin(t * fr[j, 16 + m] + phase) - math.sin(phase))
        held[j, 2] = offset


@njit(cache=True)
def hold_bristles(fr: FloatArray, z: FloatArray, held: FloatArray) -> None:
    """σ₀ z and σ₁ σ₀ z of a LuGre model into held[:, 3:5] (bristles held over a substep)."""
    for j in range(fr.shape[0]):
        if fr[j, 0] == _LUGRE:
            spring = fr[j, 2] * z[j]
            held[j, 3] = spring
            held[j, 4] = fr[j, 3] * spring


@njit(cache=True)
def stage(fr: FloatArray, held: FloatArray, j: int, v: float) -> float:
    """Friction torque [N m] of joint j at velocity v with the held terms (a stage of a step)."""
    kind = fr[j, 0]
    if kind == 0.0:
        return 0.0
    if kind == _LUGRE:
        return (fr[j, 3] + fr[j, 4]) * v + held[j, 3] - held[j, 4] * abs(v) / _level(fr, j, v)
    base = _static(fr, j, v)
    if fr[j, 1] != 1.0:
        return base
    viscous = fr[j, 12] * v
    return held[j, 0] * (base - viscous) + held[j, 1] * viscous + held[j, 2]


@njit(cache=True)
def recorded(fr: FloatArray, held: FloatArray, z: FloatArray, j: int, v: float) -> float:
    """Friction torque [N m] at the state (LuGre: eq. 4.22b at z), as the simulator logs it."""
    if fr[j, 0] == _LUGRE:
        sigma0 = fr[j, 2]
        zdot = v - sigma0 * abs(v) / _level(fr, j, v) * z[j]
        return sigma0 * z[j] + fr[j, 3] * zdot + fr[j, 4] * v
    return stage(fr, held, j, v)


@njit(cache=True)
def advance_bristles(fr: FloatArray, z: FloatArray, j: int, v: float, h: float) -> None:
    """Exact bristle update of a LuGre joint over h [s] at velocity v held (LuGre.advance_state)."""
    if fr[j, 0] != _LUGRE:
        return
    sigma0 = fr[j, 2]
    level = _level(fr, j, v)
    rate_h = (sigma0 * h) * abs(v) / level
    z_ss = sign(v) * level / sigma0
    z[j] = z[j] * math.exp(-rate_h) - z_ss * math.expm1(-rate_h)
