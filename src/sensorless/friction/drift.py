"""Friction that drifts with time: a joint warming up and a torque offset that wanders.

A robot joint's friction is not a constant of the arm. Bittencourt and
Gunnarsson ("Static friction in a robot joint: modeling and identification
of load and temperature effects", J. Dyn. Sys. Meas. Control 134(5):051013,
2012) study the friction of a joint of a standard industrial robot under
changes of joint angle, load torque and temperature, and find load and
temperature significant enough to enter their extended static friction model;
the conference version (Bittencourt, Wernholt, Sander-Tavallaey, Brogårdh,
IROS 2010) reports that this model reduces the average error by a factor of 6
against a standard static model. Wolf and Iskandar ("Extending a dynamic
friction model with nonlinear viscous and thermal dependency for a motor and
harmonic drive gear") measure a motor and a harmonic drive between 24 and
50 °C and find velocity and temperature the dominant effects. Those are the
statements we could check (in the published abstracts); the *sizes* we
simulate are not taken from them: the default warm-up (Coulomb and viscous
friction falling by 30 % with a time constant of 15 min) is our assumption,
chosen as the order of magnitude that issue 19 reports from a real arm
(friction identified on two days differing by up to 2.5 times on a joint, a
payload change mixed in).

:class:`DriftingFriction` wraps a stateless :class:`~sensorless.friction.FrictionModel`
and makes it a function of time t [s] as well as of the velocity q̇ [rad/s]:

    τ_fr(t, q̇) = s_c(t)·(τ_base(q̇) − f_v q̇) + s_v(t)·f_v q̇ + o(t)
    s(t) = 1 − w·(1 − exp(−t/T))                        (first-order warm-up)
    o(t) = Σ_m a_m [sin(ω_m t + φ_m) − sin φ_m]          (offset drift)

per joint, with f_v the viscous coefficient of the base model (0 if it has
none), w the fraction of friction lost once warm (``warmup`` for the Coulomb
part, ``warmup_viscous`` for the viscous one), T the thermal time constant,
and o(t) a smooth offset (a current-sensor offset drifting, say) made of
three sinusoids with seeded periods, phases and signs, scaled so that
|ȯ(t)| ≤ Σ_m a_m ω_m = ``offset_rate`` exactly. At t = 0 the model equals
the base model: s = 1, o = 0. Sign convention and shapes:
:mod:`sensorless.friction`; ``t`` is a scalar or an array of shape
(n_samples,) matching the rows of ``qd``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_joint_array, check_int, per_joint
from ..exceptions import InputTypeError, InputValueError
from .static import FrictionModel

__all__ = ["DriftingFriction", "FrictionAt"]

_COMPONENTS = 3


def _frozen(arr: FloatArray) -> FloatArray:
    arr.setflags(write=False)
    return arr


class DriftingFriction:
    """A stateless friction model whose Coulomb and viscous parts warm up and whose offset drifts.

    Parameters
    ----------
    base : FrictionModel
        The friction of the cold joint (t = 0), e.g. the robot's
        :class:`~sensorless.friction.CoulombViscous`. Its ``fv`` attribute, when
        it has one, is the viscous part; the rest of its torque is the Coulomb part.
    warmup : float or array-like of shape (n_dof,), default 0.3
        Fraction w_c of the Coulomb part lost once warm [-], in [0, 1).
    time_constant : float or array-like of shape (n_dof,), default 900.0
        Thermal time constant T of each joint [s], > 0.
    warmup_viscous : float or array-like of shape (n_dof,), optional
        Fraction w_v of the viscous part lost once warm [-], in [0, 1);
        ``warmup`` by default.
    offset_rate : float or array-like of shape (n_dof,), default 0.0
        Largest rate of the torque offset o(t) [N m/s], >= 0; 0 for no offset.
    offset_periods : tuple of two floats, default (600.0, 3600.0)
        Range of the periods of the offset's sinusoids [s] (drawn log-uniformly).
    seed : int, default 0
        Seed of the offset's periods, phases, signs and weights.

    Examples
    --------
    >>> from sensorless.friction import CoulombViscous
    >>> cold = CoulombViscous(c_pos=2.0, c_neg=-2.0, fv=1.0)
    >>> model = DriftingFriction(cold, warmup=0.3, time_constant=600.0)
    >>> model.torque(0.0, [1.0]).tolist()
    [3.0]
    >>> round(float(model.torque(600.0, [1.0])[0]), 6)  # 3 (1 - 0.3 (1 - 1/e))
    2.431091
    """

    def __init__(
        self,
        base: FrictionModel,
        warmup: ArrayLike = 0.3,
        time_constant: ArrayLike = 900.0,
        *,
        warmup_viscous: ArrayLike | None = None,
        offset_rate: ArrayLike = 0.0,
        offset_periods: tuple[float, float] = (600.0, 3600.0),
        seed: int = 0,
    ) -> None:
        if not isinstance(base, FrictionModel):
            raise InputTypeError(
                "base must be a stateless FrictionModel (Coulomb, viscous, Stribeck, sigmoid); "
                f"got {type(base).__name__}"
            )
        self._base = base
        n = base.n_dof
        self._warmup = _frozen(_fraction(warmup, n, "warmup"))
        self._warmup_viscous = _frozen(
            self._warmup.copy() if warmup_viscous is None
            else _fraction(warmup_viscous, n, "warmup_viscous")
        )  # fmt: skip
        self._time_constant = _frozen(per_joint(time_constant, n, "time_constant", "s", "positive"))
        self._offset_rate = _frozen(
            per_joint(offset_rate, n, "offset_rate", "N m/s", "nonnegative")
        )
        self._seed = check_int(seed, "seed", 0, "DriftingFriction")
        shortest, longest = _periods(offset_periods)
        self._offset_periods = (shortest, longest)
        self._viscous = _frozen(np.broadcast_to(getattr(base, "fv", 0.0), (n,)).astype(float))
        amplitude, omega, phase = _offset_components(
            self._offset_rate, shortest, longest, self._seed
        )
        self._amplitude, self._omega, self._phase = amplitude, omega, phase

    # ------------------------------------------------------------ parameters
    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return self._base.n_dof

    @property
    def base(self) -> FrictionModel:
        """Friction of the cold joint (t = 0)."""
        return self._base

    @property
    def warmup(self) -> FloatArray:
        """Fraction of the Coulomb part lost once warm, per joint [-]."""
        return self._warmup

    @property
    def warmup_viscous(self) -> FloatArray:
        """Fraction of the viscous part lost once warm, per joint [-]."""
        return self._warmup_viscous

    @property
    def time_constant(self) -> FloatArray:
        """Thermal time constant per joint [s]."""
        return self._time_constant

    @property
    def offset_rate(self) -> FloatArray:
        """Largest rate of the torque offset per joint [N m/s]."""
        return self._offset_rate

    @property
    def seed(self) -> int:
        """Seed of the offset drift."""
        return self._seed

    @property
    def offset_components(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Amplitude [N m], angular frequency [rad/s] and phase [rad] of the offset's sines.

        Each of shape (n_dof, n_sines): the offset of joint j at time t is
        Σ_i a_ji (sin(ω_ji t + φ_ji) − sin φ_ji), drawn from ``seed``.
        """
        return self._amplitude, self._omega, self._phase

    @property
    def base_viscous(self) -> FloatArray:
        """The base model's viscous coefficient per joint [N m s/rad] (0 without one)."""
        return self._viscous

    def __repr__(self) -> str:
        return (
            f"DriftingFriction({self._base!r}, warmup={self._warmup.tolist()}, "
            f"time_constant={self._time_constant.tolist()}, "
            f"warmup_viscous={self._warmup_viscous.tolist()}, "
            f"offset_rate={self._offset_rate.tolist()}, "
            f"offset_periods={self._offset_periods}, seed={self._seed})"
        )

    # ------------------------------------------------------------ time laws
    def scales(self, t: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Factors s_c(t), s_v(t) of the Coulomb and viscous parts [-].

        Parameters
        ----------
        t : float or array-like of shape (n_samples,)
            Time since the cold start [s], >= 0.

        Returns
        -------
        coulomb, viscous : ndarray of shape (n_dof,) or (n_samples, n_dof)
            ``1 - w (1 - exp(-t / T))`` per joint (time along axis 0).
        """
        times = _times(t)
        return self._scales(times)

    def offset(self, t: ArrayLike) -> FloatArray:
        """Torque offset o(t) [N m], 0 at t = 0.

        Parameters
        ----------
        t : float or array-like of shape (n_samples,)
            Time since the cold start [s], >= 0.

        Returns
        -------
        ndarray of shape (n_dof,) or (n_samples, n_dof)
            Offset per joint (time along axis 0).
        """
        return self._offset(_times(t))

    def torque(self, t: ArrayLike, qd: ArrayLike) -> FloatArray:
        """Friction torque at time ``t`` and velocity ``qd``.

        Parameters
        ----------
        t : float or array-like of shape (n_samples,)
            Time since the cold start [s], >= 0; a scalar, or one per row of ``qd``.
        qd : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint velocities [rad/s].

        Returns
        -------
        ndarray of the shape of ``qd``
            Friction torque [N m], sign convention of :mod:`sensorless.friction`.
        """
        arr, single = as_joint_array(qd, self.n_dof, "qd")
        times = _times(t)
        if times.ndim == 1 and (single or times.shape[0] != arr.shape[0]):
            raise InputValueError(
                f"t must be a scalar or have one time per row of qd ({arr.shape[0]}); "
                f"got {times.shape[0]} times"
            )
        tau = self.evaluate_at(times, arr)
        return tau[0] if single else tau

    def at(self, t: float) -> FrictionAt:
        """The friction of time ``t`` [s] as a stateless model of the velocity alone.

        The simulator holds the time over a control period and evaluates the
        friction several times in it; this computes the time laws once.

        Parameters
        ----------
        t : float
            Time since the cold start [s], >= 0.

        Returns
        -------
        FrictionAt
            A :class:`~sensorless.friction.FrictionModel` with
            ``evaluate(qd) == evaluate_at(t, qd)``.
        """
        times = _times(t)
        if times.ndim != 0:
            raise InputValueError(f"t must be one time [s]; got shape {times.shape}")
        coulomb_scale, viscous_scale = self._scales(float(times))
        return FrictionAt(self, coulomb_scale, viscous_scale, self._offset(float(times)))

    def evaluate_at(self, t: float | FloatArray, qd: FloatArray) -> FloatArray:
        """Torque [N m] without input checks: the fast path of the simulator.

        ``t`` [s] is a float, or an array of shape (n_samples,) with one time per
        row of ``qd``; ``qd`` is a finite array of shape (n_dof,) or
        (n_samples, n_dof) [rad/s].
        """
        coulomb_scale, viscous_scale = self._scales(t)
        viscous = self._viscous * qd
        static = self._base.evaluate(qd) - viscous
        return coulomb_scale * static + viscous_scale * viscous + self._offset(t)

    # ------------------------------------------------------------ internals
    def _scales(self, t: float | FloatArray) -> tuple[FloatArray, FloatArray]:
        warmed = -np.expm1(-np.asarray(t, dtype=float)[..., None] / self._time_constant)
        return 1.0 - self._warmup * warmed, 1.0 - self._warmup_viscous * warmed

    def _offset(self, t: float | FloatArray) -> FloatArray:
        angle = np.asarray(t, dtype=float)[..., None, None] * self._omega + self._phase
        return np.sum(self._amplitude * (np.sin(angle) - np.sin(self._phase)), axis=-1)


class FrictionAt(FrictionModel):
    """A :class:`DriftingFriction` frozen at one instant: a function of the velocity only.

    Get it from :meth:`DriftingFriction.at`; the factors are per joint, shape (n_dof,).
    """

    def __init__(
        self,
        drifting: DriftingFriction,
        coulomb_scale: FloatArray,
        viscous_scale: FloatArray,
        offset: FloatArray,
    ) -> None:
        self._base = drifting.base
        self._viscous = drifting._viscous
        self._coulomb_scale = _frozen(np.asarray(coulomb_scale, dtype=float))
        self._viscous_scale = _frozen(np.asarray(viscous_scale, dtype=float))
        self._offset_torque = _frozen(np.asarray(offset, dtype=float))
        self._n_dof = drifting.n_dof

    def __repr__(self) -> str:
        return (
            f"FrictionAt(base={self._base!r}, coulomb_scale={self._coulomb_scale.tolist()}, "
            f"viscous_scale={self._viscous_scale.tolist()}, offset={self._offset_torque.tolist()})"
        )

    def evaluate(self, qd: FloatArray) -> FloatArray:
        viscous = self._viscous * qd
        static = self._base.evaluate(qd) - viscous
        return self._coulomb_scale * static + self._viscous_scale * viscous + self._offset_torque


def _fraction(value: ArrayLike, n_dof: int, name: str) -> FloatArray:
    arr = per_joint(value, n_dof, name, "-", "nonnegative")
    if (arr >= 1.0).any():
        raise InputValueError(
            f"{name} must be a fraction in [0, 1) of the friction lost once warm; got {value!r}"
        )
    return arr


def _periods(value: tuple[float, float]) -> tuple[float, float]:
    try:
        shortest, longest = (float(v) for v in value)
    except (TypeError, ValueError):
        raise InputValueError(
            f"offset_periods must be two periods (shortest, longest) [s]; got {value!r}"
        ) from None
    if not (math.isfinite(longest) and 0.0 < shortest <= longest):
        raise InputValueError(
            f"offset_periods must satisfy 0 < shortest <= longest < inf [s]; got {value!r}"
        )
    return shortest, longest


def _times(t: ArrayLike) -> FloatArray:
    try:
        times = np.asarray(t, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputValueError(f"t must be a time or an array of times [s]; got {t!r}") from None
    if times.ndim > 1 or not np.isfinite(times).all() or (times < 0.0).any():
        raise InputValueError(
            f"t must be a finite time >= 0 or an array of shape (n_samples,) of them [s]; got {t!r}"
        )
    return times


def _offset_components(
    rate: FloatArray, shortest: float, longest: float, seed: int
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Amplitudes [N m], angular frequencies [rad/s] and phases [rad], each (n_dof, 3).

    The weights are normalised so that Σ_m a_m ω_m equals ``rate`` per joint:
    the bound on |ȯ(t)| is exact.
    """
    rng = np.random.default_rng(seed)
    shape = (rate.shape[0], _COMPONENTS)
    period = np.exp(rng.uniform(math.log(shortest), math.log(longest), shape))
    phase = rng.uniform(0.0, 2.0 * math.pi, shape)
    weight = rng.uniform(0.5, 1.0, shape) * rng.choice([-1.0, 1.0], shape)
    omega = 2.0 * math.pi / period
    share = np.abs(weight) / np.abs(weight).sum(axis=1, keepdims=True)
    amplitude = np.sign(weight) * share * rate[:, None] / omega
    return _frozen(amplitude), _frozen(omega), _frozen(phase)
