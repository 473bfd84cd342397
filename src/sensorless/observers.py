"""Collision observers: the generalized-momentum residual and the acceleration-based estimate.

Two observers turn joint positions, velocities and torques into a residual
that is zero without contact and follows the external joint torque τ_c
during a contact:

:class:`MomentumObserver`
    The generalized-momentum residual r̂ of eq. (4.4) with motor torques, or
    r̂_s of eq. (4.9) with joint-torque-sensor torques. It needs no
    acceleration: with an exact model, r̂ = K_I/(s+K_I)·τ_c (eq. 3.6).
    Alongside r̂ it produces the model torque h(t) of eq. (4.26)/(5.30), the
    filtered friction K_I/(s+K_I)·τ̂_fr of eq. (5.29) and the filtered sign
    K_I/(s+K_I)·sign(q̇) used by the thresholds of eq. (5.39).
:class:`AccelerationObserver`
    The estimate τ̂_c of eq. (3.8)/(3.16) from velocities and accelerations
    estimated by a causal filter of :mod:`sensorless.filters`.
:func:`observe`
    Either observer over a :class:`~sensorless.io.Log`.

Dynamics and signs (friction convention of :mod:`sensorless.friction`)::

    M(q) q̈ + C(q, q̇) q̇ + g(q) = τ + τ_c − τ_fr                   eq. (4.1)

with τ the motor torque τ_m (``torque="motor"``) or, for the link side of a
flexible-joint arm, the joint-torque-sensor reading τ_J (``torque="joint"``).

Streaming and batch share one implementation, as :func:`scipy.signal.lfilter`
with ``zi``/``zf``: ``initial_state`` gives a state, ``step`` processes one
sample and ``run`` a whole array; both return the state after the last
sample, so a record cut into chunks gives the same signals as in one go.
Units are SI and radians; time series have shape ``(n_samples, n_dof)``
with time along axis 0.

Examples
--------
>>> import numpy as np
>>> from sensorless import robots
>>> from sensorless.observers import MomentumObserver
>>> robot = robots.load("planar2")
>>> observer = MomentumObserver(robot, dt=1e-3, gain=20.0, friction=None)
>>> q = np.zeros((5, 2))
>>> tau = np.tile(robot.gravity(q[0]), (5, 1))      # holding the arm at rest
>>> signals, state = observer.run(np.arange(5) * 1e-3, q, np.zeros((5, 2)), tau)
>>> bool(np.allclose(signals.residual, 0.0))
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike
from scipy import signal

from ._validation import FloatArray, as_joint_array, check_dt, check_finite
from .exceptions import DimensionError, InputTypeError, InputValueError, LogFormatError
from .filters import Butterworth, CausalEstimator, FilterState, FiniteDifference
from .friction import FrictionModel, LuGre, Stribeck
from .io import Log
from .robots.model import RobotModel
from .signals import ObserverSignals

__all__ = [
    "OBSERVER_KINDS",
    "TORQUE_KINDS",
    "VELOCITY_SOURCES",
    "AccelerationObserver",
    "MomentumObserver",
    "ObserverSample",
    "ObserverState",
    "default_estimator",
    "observe",
]

TORQUE_KINDS: tuple[str, ...] = ("motor", "joint")
"""Torque a momentum observer uses: motor torques τ_m (r̂, eq. 4.4) or joint-torque sensors (r̂_s)."""

OBSERVER_KINDS: tuple[str, ...] = ("motor", "joint", "acceleration")
"""Observers :func:`observe` can run."""

VELOCITY_SOURCES: tuple[str, ...] = ("filter", "true")
"""Where :func:`observe` takes the joint velocity from."""

# Relative tolerance on the sample period of a time column (that of sensorless.io).
_TIME_RTOL = 1e-6
# Samples per block in ``MomentumObserver.run``: bounds the memory of the
# per-sample Coriolis matrices (block x n_dof² floats) without slowing the loop.
_BLOCK = 8192
# Signals filtered by K_I/(s+K_I), in the order of ``ObserverState.filtered``.
_RESIDUAL, _MODEL_TORQUE, _FRICTION, _SIGN = range(4)


class ObserverSample(NamedTuple):
    """Output of an observer at one sample, each of shape (n_dof,).

    Attributes
    ----------
    residual : ndarray
        r̂ (eq. 4.4), r̂_s (eq. 4.9) or τ̂_c (eq. 3.16) [N m].
    model_torque : ndarray
        h = K_I/(s+K_I)·(M q̈ + C q̇ + g) (eq. 4.26), or M q̂̈ + C q̂̇ + g for the
        acceleration-based estimate [N m].
    friction : ndarray
        K_I/(s+K_I)·τ̂_fr (eq. 5.29), or τ̂_fr(q̂̇) for the acceleration-based estimate [N m].
    sign : ndarray
        K_I/(s+K_I)·sign(q̇) (eq. 5.39), or sign(q̂̇) [-].
    """

    residual: FloatArray
    model_torque: FloatArray
    friction: FloatArray
    sign: FloatArray


@dataclass(frozen=True, eq=False, slots=True)
class ObserverState:
    """State of a :class:`MomentumObserver` after a sample, as ``zi``/``zf`` of lfilter.

    Get it from :meth:`MomentumObserver.initial_state`, or as the second value
    returned by :meth:`MomentumObserver.step` and :meth:`MomentumObserver.run`;
    do not build it by hand. It is immutable, so an old state can replay a
    signal.

    Attributes
    ----------
    momentum : ndarray of shape (n_dof,)
        Generalized momentum p = M(q) q̇ of the last sample (eq. 4.2) [N m s].
    coriolis_gravity : ndarray of shape (n_dof,)
        Cᵀ(q, q̇) q̇ − g(q) of the last sample [N m].
    friction_torque : ndarray of shape (n_dof,)
        Nominal friction τ̂_fr(q̇) of the last sample [N m].
    velocity_sign : ndarray of shape (n_dof,)
        sign(q̇) of the last sample [-].
    torque : ndarray of shape (n_dof,)
        Torque of the last sample [N m]; it is held over the next period and
        used by the next step (zero-order hold).
    filtered : ndarray of shape (4, n_dof)
        Outputs at the last sample: residual, model torque h, filtered
        friction and filtered sign (rows in this order).
    """

    momentum: FloatArray
    coriolis_gravity: FloatArray
    friction_torque: FloatArray
    velocity_sign: FloatArray
    torque: FloatArray
    filtered: FloatArray

    @property
    def n_dof(self) -> int:
        """Number of joints the state is for."""
        return int(self.momentum.shape[0])

    @property
    def residual(self) -> FloatArray:
        """Residual r̂ at the last sample [N m]."""
        return self.filtered[_RESIDUAL]

    @property
    def model_torque(self) -> FloatArray:
        """Model torque h at the last sample [N m]."""
        return self.filtered[_MODEL_TORQUE]

    @property
    def friction(self) -> FloatArray:
        """Filtered friction K_I/(s+K_I)·τ̂_fr at the last sample [N m]."""
        return self.filtered[_FRICTION]

    @property
    def sign(self) -> FloatArray:
        """Filtered sign K_I/(s+K_I)·sign(q̇) at the last sample [-]."""
        return self.filtered[_SIGN]


# ---------------------------------------------------------------- shared helpers
def _check_robot(robot: Any) -> RobotModel:
    if not isinstance(robot, RobotModel):
        raise InputTypeError(
            f"robot must be a sensorless RobotModel (e.g. sensorless.robots.load('panda')); "
            f"got {type(robot).__name__}"
        )
    return robot


def _check_torque_kind(torque: Any) -> str:
    if torque not in TORQUE_KINDS:
        raise InputValueError(
            f"torque must be one of {list(TORQUE_KINDS)} (motor torques τ_m, eq. 4.4, or "
            f"joint-torque-sensor torques τ_J, eq. 4.9); got {torque!r}"
        )
    return str(torque)


def _check_gain(gain: Any, n_dof: int) -> FloatArray:
    """Observer gain K_I [1/s] as an array of shape (n_dof,), positive and finite."""
    try:
        arr = np.array(gain, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputValueError(
            f"gain K_I must be a positive number [1/s] or an array of shape ({n_dof},); "
            f"got {gain!r}"
        ) from None
    if arr.ndim > 1 or (arr.ndim == 1 and arr.shape[0] != n_dof):
        raise DimensionError(
            f"gain K_I must be a scalar or have shape ({n_dof},) for a robot with {n_dof} "
            f"joints; got shape {arr.shape}"
        )
    arr = np.broadcast_to(arr, (n_dof,)).copy()
    if not np.isfinite(arr).all() or (arr <= 0.0).any():
        raise InputValueError(
            f"gain K_I must be positive and finite [1/s] on every joint; got {arr}"
        )
    arr.setflags(write=False)
    return arr


def _resolve_friction(friction: Any, robot: RobotModel) -> FrictionModel | None:
    """The nominal friction model τ̂_fr(q̇): stateless, LuGre replaced by its steady state."""
    if isinstance(friction, str):
        if friction != "model":
            raise InputValueError(
                "friction must be 'model' (the robot's own friction), None, a FrictionModel "
                f"or a LuGre model; got {friction!r}"
            )
        friction = robot.friction
    if friction is None:
        return None
    if isinstance(friction, LuGre):
        # Steady state of eq. (4.22): the Stribeck curve with fv = σ2 (LuGre.steady_state).
        friction = Stribeck(
            fc=friction.fc, fs=friction.fs, vs=friction.vs, fv=friction.sigma2,
            delta=friction.delta,
        )  # fmt: skip
    if not isinstance(friction, FrictionModel):
        raise InputTypeError(
            "friction must be 'model', None, a sensorless.friction.FrictionModel or LuGre; "
            f"got {type(friction).__name__}"
        )
    if friction.n_dof not in (1, robot.n_dof):
        raise DimensionError(
            f"friction model has {friction.n_dof} joints; the robot has {robot.n_dof}"
        )
    return friction


def _friction_name(friction: FrictionModel | None) -> str:
    return "none" if friction is None else type(friction).__name__


def _coefficients(gain: FloatArray, dt: float) -> tuple[FloatArray, FloatArray]:
    """Pole a = exp(−K_I dt) and input weight 1 − a of K_I/(s+K_I) with held input.

    A zero-order-hold input u_k over [t_k, t_k+1) gives exactly
    y_k+1 = a y_k + (1 − a) u_k; ``expm1`` keeps 1 − a accurate for small K_I dt.
    """
    pole = np.exp(-gain * dt)
    weight = -np.expm1(-gain * dt)
    pole.setflags(write=False)
    weight.setflags(write=False)
    return pole, weight


def _filter_inputs(
    previous: tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray],
    current: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    dt: float,
    out: FloatArray,
) -> None:
    """Inputs over one period of the four K_I/(s+K_I) filters, written to ``out[0..3]``.

    ``previous`` is (p, Cᵀq̇ − g, τ̂_fr, sign(q̇), τ) at t_k and ``current``
    (p, Cᵀq̇ − g, τ̂_fr, sign(q̇)) at t_k+1. The momentum enters by its exact
    increment, the model terms by the trapezoid rule and the torque as held:

        h-input = (p_k+1 − p_k)/dt − ((Cᵀq̇ − g)_k + (Cᵀq̇ − g)_k+1)/2
        r-input = h-input + (τ̂_fr,k + τ̂_fr,k+1)/2 − τ_k

    so that r̂ = h − K_I/(s+K_I)·τ + K_I/(s+K_I)·τ̂_fr holds sample by sample.
    The same code serves one sample (arrays of shape (n_dof,)) and a block
    ((n_samples, n_dof)), which makes ``step`` and ``run`` agree.
    """
    p0, vg0, fr0, s0, tau0 = previous
    p1, vg1, fr1, s1 = current
    # In place in the rows of ``out`` (no temporaries), operation for operation:
    #   h = (p1 - p0) / dt - 0.5 (vg0 + vg1),   f = 0.5 (fr0 + fr1),
    #   s = 0.5 (s0 + s1),                       r = (h + f) - tau0.
    h, fr, sg, r = out[_MODEL_TORQUE], out[_FRICTION], out[_SIGN], out[_RESIDUAL]
    np.subtract(p1, p0, out=h)
    h /= dt
    h -= 0.5 * (vg0 + vg1)
    np.add(fr0, fr1, out=fr)
    fr *= 0.5
    np.add(s0, s1, out=sg)
    sg *= 0.5
    np.add(h, fr, out=r)
    r -= tau0


def _check_time(t: ArrayLike, n_samples: int, dt: float) -> FloatArray:
    """Time column [s] of ``n_samples`` samples spaced by ``dt`` (relative tolerance 1e-6)."""
    arr = np.asarray(t, dtype=np.float64)
    if arr.shape != (n_samples,):
        raise DimensionError(
            f"t must have shape (n_samples,) = ({n_samples},), one time stamp per row of q; "
            f"got shape {arr.shape}"
        )
    check_finite(arr, "t")
    if n_samples > 1:
        steps = np.diff(arr)
        tolerance = _TIME_RTOL * dt + 4.0 * float(np.spacing(max(abs(arr[0]), abs(arr[-1]))))
        bad = np.flatnonzero(np.abs(steps - dt) > tolerance)
        if bad.size:
            k = int(bad[0])
            raise InputValueError(
                f"t must be sampled every dt = {dt:g} s (the observer's period); the step from "
                f"sample {k} to {k + 1} is {steps[k]:.9g} s. Build the observer with the log's "
                "period, or resample the log with sensorless.io.resample(log, dt)"
            )
    return arr


def _series(x: ArrayLike, n_dof: int, name: str, n_samples: int | None = None) -> FloatArray:
    """A checked, C-contiguous array of shape (n_samples, n_dof) (NaN named by sample)."""
    arr, single = as_joint_array(x, n_dof, name)
    if single:
        raise DimensionError(
            f"{name} must have shape (n_samples, {n_dof}); got shape {np.shape(x)}; "
            "use step for one sample"
        )
    if n_samples is not None and arr.shape[0] != n_samples:
        raise DimensionError(f"{name} must have {n_samples} samples, as q; got shape {arr.shape}")
    return np.ascontiguousarray(arr)


def _one_sample(x: ArrayLike, n_dof: int, name: str) -> FloatArray:
    """One checked sample as an array of shape (1, n_dof)."""
    arr, single = as_joint_array(x, n_dof, name)
    if not single:
        raise DimensionError(
            f"{name} must be one sample of shape ({n_dof},); got shape {np.shape(x)}"
        )
    return np.ascontiguousarray(arr)


def _sample(x: ArrayLike, n_dof: int, name: str) -> FloatArray:
    """One sample of shape (n_dof,): the cheap check of the streaming path."""
    try:
        arr = np.ascontiguousarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise DimensionError(
            f"{name} must be a numeric array of shape ({n_dof},); could not convert it: {exc}"
        ) from None
    if arr.shape != (n_dof,):
        raise DimensionError(
            f"{name} must be one sample of shape ({n_dof},); got shape {arr.shape}"
        )
    return arr


def _check_sample_finite(**arrays: FloatArray) -> None:
    """Raise :class:`InputValueError` naming the first array with a NaN or inf."""
    for name, arr in arrays.items():
        if not np.isfinite(arr).all():
            joint = int(np.flatnonzero(~np.isfinite(arr))[0])
            raise InputValueError(f"{name} must be finite; found {arr[joint]} at joint {joint}")


class _FrictionFunction:
    """τ̂_fr(q̇) [N m] of a stateless model without input checks (zeros without a model)."""

    __slots__ = ("_model",)

    def __init__(self, model: FrictionModel | None) -> None:
        self._model = model

    def __call__(self, qd: FloatArray) -> FloatArray:
        if self._model is None:
            return np.zeros(qd.shape, dtype=qd.dtype)
        # Per-joint parameters of shape (n_dof,) or (1,) broadcast against qd.
        return self._model.evaluate(qd)


# ---------------------------------------------------------------- momentum observer
class _NominalObserver:
    """What both observers share: the nominal model, its friction and the torque kind."""

    def __init__(self, robot: RobotModel, friction: Any, torque: str) -> None:
        self._robot = _check_robot(robot)
        self._torque = _check_torque_kind(torque)
        self._friction_model = _resolve_friction(friction, robot)
        self._friction = _FrictionFunction(self._friction_model)
        self._pin_model = robot.pinocchio_model
        self._pin_data = robot.pinocchio_model.createData()

    @property
    def robot(self) -> RobotModel:
        """Nominal model."""
        return self._robot

    @property
    def torque(self) -> str:
        """``"motor"`` (τ_m, eq. 4.4) or ``"joint"`` (τ_J, eq. 4.9): which torque τ is used."""
        return self._torque

    @property
    def friction_model(self) -> FrictionModel | None:
        """Nominal friction τ̂_fr actually used (a LuGre model appears as its Stribeck curve)."""
        return self._friction_model

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return self.robot.n_dof


class MomentumObserver(_NominalObserver):
    """Generalized-momentum residual r̂ (eq. 4.4) or r̂_s (eq. 4.9), discretised exactly.

    With p = M(q) q̇ (eq. 4.2) and w = Cᵀ(q, q̇) q̇ − g(q) − τ̂_fr(q̇),

        r̂ = K_I [p − ∫ (τ + w + r̂) du − p(0)]                          eq. (4.4)

    which is K_I/(s+K_I)·τ_c for an exact model (eq. 3.6). Each joint's filter
    K_I/(s+K_I) is discretised with a = exp(−K_I dt). The torque sample τ[k]
    is held over [t_k, t_k+1) (zero-order hold, as a digital controller applies
    it and as :mod:`sensorless.simulation` logs it), the momentum enters by its
    exact increment and w by the trapezoid rule:

        y_k+1 − y_k = p_k+1 − p_k − (τ[k] + (w_k + w_k+1)/2) dt
        r̂_k+1 = a r̂_k + (1 − a)(y_k+1 − y_k)/dt,    r̂_0 = 0

    So r̂ equals the exact discrete K_I/(s+K_I)·τ_c of a held τ_c, up to the
    trapezoid error of w, when the model is exact. The same step gives

    * h = K_I/(s+K_I)·(M q̈ + C q̇ + g) (eq. 4.26, 5.30), computed without q̈ as
      K_I s/(s+K_I)·p − K_I/(s+K_I)·(Cᵀq̇ − g);
    * K_I/(s+K_I)·τ̂_fr (eq. 5.29) and K_I/(s+K_I)·sign(q̇) (eq. 5.39), with the
      trapezoid rule as w;

    and r̂ = h − K_I/(s+K_I)·τ + K_I/(s+K_I)·τ̂_fr holds sample by sample.

    Start (the p(0) of eq. 4.4): :meth:`initial_state` is the state of a robot
    moving with constant momentum (ṗ = 0) at (q0, q̇0) under the torque that
    balances the model, τ = g − Cᵀq̇0 + τ̂_fr(q̇0). The first sample then gives
    r̂_0 = 0, h_0 = g(q0) − Cᵀ(q0, q̇0) q̇0 (= g(q0), the value at rest, when
    q̇0 = 0), filtered friction τ̂_fr(q̇0) and filtered sign sign(q̇0).

    Parameters
    ----------
    robot : RobotModel
        Nominal model. With ``torque="joint"`` it must be the *link-side*
        model of a flexible-joint arm (eq. 4.7: link inertias without the
        motor armature) and ``friction`` the link-side friction τ_frL that
        the torque sensors do not see.
    dt : float
        Sample period [s].
    gain : float or array-like of shape (n_dof,)
        Observer gain K_I [1/s], > 0; default 20 for every joint (thesis § 5.4).
    friction : "model", None, FrictionModel or LuGre
        Nominal friction τ̂_fr(q̇): ``"model"`` uses ``robot.friction``, None
        none. A LuGre model is used through its steady state (the Stribeck
        curve of :meth:`~sensorless.friction.LuGre.steady_state`), which
        keeps the observer stateless in friction; the presliding and
        stiction transients it leaves out show up in r̂ as friction-model
        error (the ε_fr term of eq. 5.29 bounds it).
    torque : {"motor", "joint"}
        ``"motor"``: τ are motor torques τ_m and the residual is r̂ (eq. 4.4);
        ``"joint"``: τ are joint-torque-sensor readings τ_J and it is r̂_s (eq. 4.9).

    Notes
    -----
    ``step`` does cheap checks only (shape, finiteness); ``run`` validates
    whole arrays once and computes the model terms in one loop of Pinocchio
    calls (private ``pin.Data``), then applies the recursions with
    :func:`scipy.signal.lfilter`. Both use the same model-term, input and
    coefficient functions. Not thread-safe: use one observer per thread.

    Examples
    --------
    >>> import numpy as np
    >>> from sensorless import robots
    >>> robot = robots.load("planar2")
    >>> observer = MomentumObserver(robot, dt=1e-3, gain=[20.0, 30.0])
    >>> state = observer.initial_state(np.zeros(2))
    >>> sample, state = observer.step(state, np.zeros(2), np.zeros(2), robot.gravity(np.zeros(2)))
    >>> sample.residual.tolist()
    [0.0, 0.0]
    """

    def __init__(
        self,
        robot: RobotModel,
        dt: float,
        gain: ArrayLike = 20.0,
        friction: Any = "model",
        torque: str = "motor",
    ) -> None:
        super().__init__(robot, friction, torque)
        self._dt = check_dt(dt)
        self._gain = _check_gain(gain, robot.n_dof)
        self._pole, self._weight = _coefficients(self._gain, self._dt)
        self._zero = np.zeros(robot.n_dof)

    @property
    def dt(self) -> float:
        """Sample period [s]."""
        return self._dt

    @property
    def gain(self) -> FloatArray:
        """Observer gain K_I per joint [1/s] (read-only array)."""
        return self._gain

    def __repr__(self) -> str:
        return (
            f"MomentumObserver(robot={self.robot.name!r}, dt={self.dt!r}, "
            f"gain={self.gain.tolist()}, friction={_friction_name(self.friction_model)}, "
            f"torque={self.torque!r})"
        )

    def settings(self) -> dict[str, Any]:
        """The observer's settings as plain data (for metadata)."""
        return {
            "observer": "momentum",
            "torque": self.torque,
            "gain": self.gain.tolist(),
            "dt": self.dt,
            "friction": _friction_name(self.friction_model),
            "robot": self.robot.name,
        }

    # ------------------------------------------------------------ model terms
    def _terms(
        self, q: FloatArray, qd: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """p = M q̇, Cᵀq̇ − g, τ̂_fr(q̇) and sign(q̇) for arrays of shape (n_samples, n_dof)."""
        model, data, zero = self._pin_model, self._pin_data, self._zero
        n_samples, n_dof = q.shape
        momentum = np.empty_like(q)
        gravity = np.empty_like(q)
        coriolis = np.empty((n_samples, n_dof, n_dof))
        rnea, grav, cor = pin.rnea, pin.computeGeneralizedGravity, pin.computeCoriolisMatrix
        for k in range(n_samples):  # indexing is cheaper than zip over array rows
            qk, qdk = q[k], qd[k]
            gravity[k] = grav(model, data, qk)
            # RNEA at zero velocity with q̈ := q̇ gives M(q) q̇ + g(q), armature included.
            momentum[k] = rnea(model, data, qk, zero, qdk)
            coriolis[k] = cor(model, data, qk, qdk)
        momentum -= gravity
        # Row vector times C: (q̇ᵀ C)ᵀ = Cᵀ q̇, batched over samples.
        coriolis_gravity = np.matmul(qd[:, None, :], coriolis)[:, 0] - gravity
        return momentum, coriolis_gravity, self._friction(qd), np.sign(qd)

    # ------------------------------------------------------------ streaming
    def initial_state(self, q0: ArrayLike, qd0: ArrayLike | None = None) -> ObserverState:
        """State before the first sample (the p(0) of eq. 4.4).

        Parameters
        ----------
        q0 : array-like of shape (n_dof,)
            Joint positions of the first sample [rad].
        qd0 : array-like of shape (n_dof,), optional
            Joint velocities of the first sample [rad/s]; zero (at rest) by default.

        Returns
        -------
        ObserverState
            Feeding (q0, q̇0) as the first sample gives r̂_0 = 0 exactly,
            h_0 = g(q0) − Cᵀ(q0, q̇0) q̇0, filtered friction τ̂_fr(q̇0) and
            filtered sign sign(q̇0) (see the class notes).
        """
        n = self.n_dof
        q = _one_sample(q0, n, "q0")
        qd = np.zeros((1, n)) if qd0 is None else _one_sample(qd0, n, "qd0")
        p, vg, fr, sgn = (x[0] for x in self._terms(q, qd))
        filtered = np.zeros((4, n))
        filtered[_MODEL_TORQUE] = -vg
        filtered[_FRICTION] = fr
        filtered[_SIGN] = sgn
        filtered.setflags(write=False)
        return ObserverState(p, vg, fr, sgn, fr - vg, filtered)

    def _check_state(self, state: Any) -> ObserverState:
        if not isinstance(state, ObserverState):
            raise InputTypeError(
                "state must be an ObserverState from initial_state, step or run; "
                f"got {type(state).__name__}"
            )
        if state.momentum.shape != (self.n_dof,):
            raise DimensionError(
                f"state is for {state.momentum.shape[0]} joints; the observer's robot has "
                f"{self.n_dof}"
            )
        return state

    def step(
        self, state: ObserverState, q: ArrayLike, qd: ArrayLike, tau: ArrayLike
    ) -> tuple[ObserverSample, ObserverState]:
        """Process one sample.

        Parameters
        ----------
        state : ObserverState
            State after the previous sample (or :meth:`initial_state`).
        q, qd : array-like of shape (n_dof,)
            Joint positions [rad] and velocities [rad/s] of this sample.
        tau : array-like of shape (n_dof,)
            Torque of this sample [N m] (τ_m or τ_J). It is held over the
            next period: this step uses the previous sample's torque, stored
            in ``state``, and stores ``tau`` for the next one.

        Returns
        -------
        sample : ObserverSample
            Residual, model torque h, filtered friction and filtered sign, each
            of shape (n_dof,).
        state : ObserverState
            State to pass with the next sample.
        """
        n = self.n_dof
        state = self._check_state(state)
        q_arr = _sample(q, n, "q")
        qd_arr = _sample(qd, n, "qd")
        tau_arr = _sample(tau, n, "tau")
        # Dot products propagate NaN/inf and cost less than isfinite on each array;
        # only then look for the culprit (a huge but finite value merely overflows).
        if not math.isfinite(q_arr @ q_arr + qd_arr @ qd_arr + tau_arr @ tau_arr):
            _check_sample_finite(q=q_arr, qd=qd_arr, tau=tau_arr)
        return self._step_checked(state, q_arr, qd_arr, tau_arr)

    def _step_checked(
        self, state: ObserverState, q: FloatArray, qd: FloatArray, tau: FloatArray
    ) -> tuple[ObserverSample, ObserverState]:
        """The core of :meth:`step` for a checked state and checked samples.

        ``q``, ``qd`` and ``tau`` are finite, C-contiguous float arrays of
        shape (n_dof,); ``tau`` is copied into the new state. The fields of
        the returned sample are the rows of the new state's ``filtered``.
        """
        p, vg, fr, sgn = [x[0] for x in self._terms(q[None], qd[None])]
        inputs = np.empty((4, q.shape[0]))
        previous = (
            state.momentum, state.coriolis_gravity, state.friction_torque,
            state.velocity_sign, state.torque,
        )  # fmt: skip
        _filter_inputs(previous, (p, vg, fr, sgn), self.dt, inputs)
        # Same arithmetic as lfilter([1 - a], [1, -a]): y = (1 - a) u + a y_prev.
        filtered = self._weight * inputs + self._pole * state.filtered
        filtered.setflags(write=False)
        new_state = ObserverState(p, vg, fr, sgn, tau.copy(), filtered)
        return ObserverSample(*filtered), new_state

    # ------------------------------------------------------------ batch
    def run(
        self,
        t: ArrayLike,
        q: ArrayLike,
        qd: ArrayLike,
        tau: ArrayLike,
        state: ObserverState | None = None,
    ) -> tuple[ObserverSignals, ObserverState]:
        """Process whole arrays; equal to :meth:`step` sample by sample.

        Parameters
        ----------
        t : array-like of shape (n_samples,)
            Time [s], spaced by ``dt``.
        q, qd : array-like of shape (n_samples, n_dof)
            Joint positions [rad] and velocities [rad/s].
        tau : array-like of shape (n_samples, n_dof)
            Torques [N m] (τ_m or τ_J); ``tau[k]`` is held over [t_k, t_k+1).
        state : ObserverState, optional
            State before ``q[0]``; by default :meth:`initial_state` at
            (q[0], qd[0]). Pass the returned state to continue with the next chunk.

        Returns
        -------
        signals : ObserverSignals
            ``kind`` is ``torque``; ``velocity`` is ``qd`` and ``position`` is ``q``.
        state : ObserverState
            State after the last sample.
        """
        n = self.n_dof
        if state is not None:
            state = self._check_state(state)
        q_arr = _series(q, n, "q")
        n_samples = q_arr.shape[0]
        qd_arr = _series(qd, n, "qd", n_samples)
        tau_arr = _series(tau, n, "tau", n_samples)
        t_arr = _check_time(t, n_samples, self.dt)
        if state is None:
            if n_samples == 0:
                raise DimensionError(
                    "q has no samples; pass a state to process an empty chunk, or at least one "
                    "sample to start at q[0]"
                )
            state = self.initial_state(q_arr[0], qd_arr[0])
        out = np.empty((4, n_samples, n))
        for start in range(0, n_samples, _BLOCK):
            block = slice(start, start + _BLOCK)
            state = self._run_block(
                state, q_arr[block], qd_arr[block], tau_arr[block], out[:, block]
            )
        signals = ObserverSignals(
            t=t_arr,
            residual=out[_RESIDUAL],
            model_torque=out[_MODEL_TORQUE],
            friction=out[_FRICTION],
            sign=out[_SIGN],
            velocity=qd_arr,
            gain=self.gain,
            kind=self.torque,
            robot=self.robot.name,
            position=q_arr,
            metadata=self.settings(),
        )
        return signals, state

    def _run_block(
        self,
        state: ObserverState,
        q: FloatArray,
        qd: FloatArray,
        tau: FloatArray,
        out: FloatArray,
    ) -> ObserverState:
        p, vg, fr, sgn = self._terms(q, qd)

        def shifted(current: FloatArray, last: FloatArray) -> FloatArray:
            return np.concatenate([last[None], current[:-1]])

        previous = (
            shifted(p, state.momentum), shifted(vg, state.coriolis_gravity),
            shifted(fr, state.friction_torque), shifted(sgn, state.velocity_sign),
            shifted(tau, state.torque),
        )  # fmt: skip
        inputs = np.empty_like(out)
        _filter_inputs(previous, (p, vg, fr, sgn), self.dt, inputs)
        for j in range(self.n_dof):
            pole, weight = self._pole[j], self._weight[j]
            zi = (pole * state.filtered[:, j])[:, None]
            out[:, :, j] = signal.lfilter([weight], [1.0, -pole], inputs[:, :, j], axis=1, zi=zi)[0]
        filtered = out[:, -1, :].copy()
        filtered.setflags(write=False)
        return ObserverState(
            p[-1].copy(), vg[-1].copy(), fr[-1].copy(), sgn[-1].copy(), tau[-1].copy(), filtered
        )


# ---------------------------------------------------------------- acceleration observer
class AccelerationObserver(_NominalObserver):
    """Acceleration-based estimate τ̂_c of eq. (3.8)/(3.16) with a causal filter F.

        τ̂_c = M(q) q̂̈ + C(q, q̂̇) q̂̇ + g(q) − τ + τ̂_fr(q̂̇)

    with q̂̇ and q̂̈ estimated from the measured q by ``estimator`` and the rigid-body
    terms evaluated at the measured q (RNEA, eq. 3.16 with the nominal
    parameters). Unlike :class:`MomentumObserver`, the torque used at sample k
    is τ[k] itself (no hold shift): the estimate is an algebraic function of
    the sample. The filter delays q̂̇ and q̂̈ (``estimator.delays``), and so
    τ̂_c: a causal filter always lags and low-passes (thesis § 3.4.1).

    Parameters
    ----------
    robot : RobotModel
        Nominal model (link-side model with ``torque="joint"``, as in
        :class:`MomentumObserver`).
    estimator : CausalEstimator
        Velocity and acceleration estimator of :mod:`sensorless.filters`
        (e.g. ``Butterworth(dt, cutoff=20.0)``, 5th order as in the thesis);
        its ``dt`` is the observer's sample period.
    friction : "model", None, FrictionModel or LuGre
        Nominal friction, as in :class:`MomentumObserver`.
    torque : {"motor", "joint"}
        Motor torques τ_m or joint-torque-sensor torques τ_J (τ_L of eq. 3.8).

    Examples
    --------
    >>> import numpy as np
    >>> from sensorless import robots
    >>> from sensorless.filters import FiniteDifference
    >>> robot = robots.load("planar2")
    >>> observer = AccelerationObserver(robot, FiniteDifference(1e-3), friction=None)
    >>> q = np.zeros((3, 2))
    >>> tau = np.tile(robot.gravity(q[0]), (3, 1))
    >>> signals, state = observer.run(np.arange(3) * 1e-3, q, tau)
    >>> bool(np.allclose(signals.residual, 0.0))
    True
    """

    def __init__(
        self,
        robot: RobotModel,
        estimator: CausalEstimator,
        friction: Any = "model",
        torque: str = "motor",
    ) -> None:
        super().__init__(robot, friction, torque)
        if not isinstance(estimator, CausalEstimator):
            raise InputTypeError(
                "estimator must be a causal estimator of sensorless.filters (FiniteDifference, "
                f"DirtyDerivative, Butterworth); got {type(estimator).__name__}"
            )
        self._estimator = estimator

    @property
    def estimator(self) -> CausalEstimator:
        """Velocity and acceleration estimator."""
        return self._estimator

    @property
    def dt(self) -> float:
        """Sample period of the estimator [s]."""
        return self.estimator.dt

    def __repr__(self) -> str:
        return (
            f"AccelerationObserver(robot={self.robot.name!r}, estimator={self.estimator!r}, "
            f"friction={_friction_name(self.friction_model)}, torque={self.torque!r})"
        )

    def settings(self) -> dict[str, Any]:
        """The observer's settings as plain data (for metadata)."""
        return {
            "observer": "acceleration",
            "torque": self.torque,
            "estimator": repr(self.estimator),
            "delays": list(self.estimator.delays),
            "dt": self.dt,
            "friction": _friction_name(self.friction_model),
            "robot": self.robot.name,
        }

    def _estimate(
        self, q: FloatArray, qd: FloatArray, qdd: FloatArray, tau: FloatArray
    ) -> ObserverSample:
        """τ̂_c, M q̈ + C q̇ + g, τ̂_fr and sign(q̇) for arrays of shape (n_samples, n_dof)."""
        model, data = self._pin_model, self._pin_data
        rigid = np.empty_like(q)
        for k in range(q.shape[0]):
            rigid[k] = pin.rnea(model, data, q[k], qd[k], qdd[k])
        friction = self._friction(qd)
        return ObserverSample(rigid - tau + friction, rigid, friction, np.sign(qd))

    def initial_state(self, q0: ArrayLike) -> FilterState:
        """Filter state of a robot at rest at ``q0`` [rad], shape (n_dof,)."""
        return self.estimator.initial_state(_one_sample(q0, self.n_dof, "q0")[0])

    def _check_state(self, state: Any) -> FilterState:
        if not isinstance(state, FilterState):
            raise InputTypeError(
                "state must be a FilterState from initial_state, step or run; "
                f"got {type(state).__name__}"
            )
        if state.n_dof != self.n_dof:
            raise DimensionError(
                f"state is for {state.n_dof} joints; the observer's robot has {self.n_dof}"
            )
        return state

    def step(
        self, state: FilterState, q: ArrayLike, tau: ArrayLike
    ) -> tuple[ObserverSample, FilterState]:
        """Process one sample.

        Parameters
        ----------
        state : FilterState
            Estimator state after the previous sample (or :meth:`initial_state`).
        q : array-like of shape (n_dof,)
            Measured joint positions [rad].
        tau : array-like of shape (n_dof,)
            Torque of this sample [N m], used at this sample.

        Returns
        -------
        sample : ObserverSample
            τ̂_c, M q̂̈ + C q̂̇ + g, τ̂_fr(q̂̇) and sign(q̂̇), each of shape (n_dof,).
        state : FilterState
        """
        n = self.n_dof
        state = self._check_state(state)
        q_arr = _sample(q, n, "q")
        tau_arr = _sample(tau, n, "tau")
        _check_sample_finite(q=q_arr, tau=tau_arr)
        y, new_state = self.estimator.step(q_arr, state)
        out = self._estimate(q_arr[None], y.velocity[None], y.acceleration[None], tau_arr[None])
        return ObserverSample(*(x[0] for x in out)), new_state

    def run(
        self, t: ArrayLike, q: ArrayLike, tau: ArrayLike, state: FilterState | None = None
    ) -> tuple[ObserverSignals, FilterState]:
        """Process whole arrays; equal to :meth:`step` sample by sample.

        Parameters
        ----------
        t : array-like of shape (n_samples,)
            Time [s], spaced by the estimator's ``dt``.
        q : array-like of shape (n_samples, n_dof)
            Measured joint positions [rad].
        tau : array-like of shape (n_samples, n_dof)
            Torques [N m] (τ_m or τ_J).
        state : FilterState, optional
            Estimator state before ``q[0]``; by default at rest at ``q[0]``.

        Returns
        -------
        signals : ObserverSignals
            ``kind="acceleration"``, ``residual`` τ̂_c, ``model_torque``
            M q̂̈ + C q̂̇ + g, ``friction`` τ̂_fr(q̂̇), ``sign`` sign(q̂̇),
            ``velocity`` q̂̇, ``acceleration`` q̂̈, ``position`` q. ``gain`` is NaN:
            this estimate has no K_I.
        state : FilterState
            Estimator state after the last sample.
        """
        n = self.n_dof
        if state is not None:
            state = self._check_state(state)
        q_arr = _series(q, n, "q")
        n_samples = q_arr.shape[0]
        tau_arr = _series(tau, n, "tau", n_samples)
        t_arr = _check_time(t, n_samples, self.dt)
        if state is None and n_samples == 0:
            raise DimensionError(
                "q has no samples; pass a state to process an empty chunk, or at least one "
                "sample to start at rest at q[0]"
            )
        y, new_state = self.estimator.filter(q_arr, state)
        out = self._estimate(q_arr, y.velocity, y.acceleration, tau_arr)
        signals = ObserverSignals(
            t=t_arr,
            residual=out.residual,
            model_torque=out.model_torque,
            friction=out.friction,
            sign=out.sign,
            velocity=y.velocity,
            gain=np.full(n, np.nan),
            kind="acceleration",
            robot=self.robot.name,
            position=q_arr,
            acceleration=y.acceleration,
            metadata=self.settings(),
        )
        return signals, new_state


# ---------------------------------------------------------------- convenience
def default_estimator(dt: float, kind: str = "motor") -> CausalEstimator:
    """The velocity/acceleration estimator :func:`observe` uses when none is given.

    * Momentum observers (``kind`` "motor" or "joint"): backward differences,
      :class:`~sensorless.filters.FiniteDifference`. The observer's own
      K_I/(s+K_I) already low-passes the momentum, while any delay d of q̂̇
      puts an error of about d·(dτ/dt) into the residual. On the PUMA 560
      benchmark (exact model, 1e-5 rad encoders, 0.02 N m torque noise,
      K_I = 20) the collision-free peak of joint 1 was 1.0 N m with backward
      differences, 4.7 N m with a 2nd-order 50-Hz Butterworth and 15 N m with
      the thesis's 5th-order 20-Hz one. With coarse encoders pass a filter.
    * The acceleration-based estimate needs q̂̈, which differentiation makes
      much noisier: the thesis's 5th-order Butterworth at 20 Hz (§ 3.6;
      velocity delay ≈ 26 ms at 1 kHz), its cutoff lowered to 0.25/dt [Hz]
      (half the Nyquist frequency) for slow sampling.

    Parameters
    ----------
    dt : float
        Sample period [s].
    kind : {"motor", "joint", "acceleration"}
        Observer the estimator is for.

    Returns
    -------
    CausalEstimator

    Examples
    --------
    >>> default_estimator(1e-3, "motor")
    FiniteDifference(dt=0.001)
    >>> default_estimator(1e-3, "acceleration")
    Butterworth(dt=0.001, cutoff=20.0, order=5)
    """
    period = check_dt(dt)
    if _check_observer_kind(kind) == "acceleration":
        return Butterworth(period, cutoff=min(20.0, 0.25 / period), order=5)
    return FiniteDifference(period)


def _check_observer_kind(kind: Any) -> str:
    if kind not in OBSERVER_KINDS:
        raise InputValueError(
            f"kind must be one of {list(OBSERVER_KINDS)} (momentum residual with motor "
            f"torques, with joint-torque sensors, or the acceleration-based estimate); "
            f"got {kind!r}"
        )
    return str(kind)


def _log_torque(log: Log, kind: str) -> FloatArray:
    group = "tau_j" if kind == "joint" else "tau_m"
    values = getattr(log, group)
    if values is None:
        meaning = "joint-torque-sensor" if group == "tau_j" else "motor"
        raise LogFormatError(
            f"kind={kind!r} needs the {meaning} torques {group}_1..{group}_{log.n_dof}; "
            f"the log has no {group} columns (present groups: {log.groups})"
        )
    return np.asarray(values)


def observe(
    log: Log,
    robot: RobotModel,
    *,
    kind: str = "motor",
    gain: ArrayLike = 20.0,
    velocity: str = "filter",
    estimator: CausalEstimator | None = None,
    friction: Any = "model",
) -> ObserverSignals:
    """Run an observer over a log.

    Parameters
    ----------
    log : Log
        The run; its time column must be regular.
    robot : RobotModel
        Nominal model (link-side for ``kind="joint"``, see :class:`MomentumObserver`).
    kind : {"motor", "joint", "acceleration"}
        ``"motor"``: r̂ (eq. 4.4) from ``log.tau_m``; ``"joint"``: r̂_s (eq. 4.9)
        from ``log.tau_j``; ``"acceleration"``: τ̂_c (eq. 3.16) from ``log.tau_m``.
    gain : float or array-like of shape (n_dof,)
        K_I [1/s] of the momentum observers (ignored by ``"acceleration"``).
    velocity : {"filter", "true"}
        Joint velocity of the momentum observers: ``"filter"`` estimates it
        from ``log.q`` with ``estimator``; ``"true"`` uses the ground truth
        ``log.qd_true`` (simulated logs; ideal studies and tests). The
        acceleration-based estimate always uses ``estimator``.
    estimator : CausalEstimator, optional
        Causal velocity/acceleration estimator with ``dt`` = the log's period;
        default :func:`default_estimator` (backward differences for the momentum
        observers, the thesis's 5th-order 20-Hz Butterworth for ``"acceleration"``).
    friction : "model", None, FrictionModel or LuGre
        Nominal friction, see :class:`MomentumObserver`.

    Returns
    -------
    ObserverSignals
        ``position`` is ``log.q``; ``metadata`` holds the log's metadata plus
        the settings under the key ``"observer"``.

    Raises
    ------
    DimensionError
        The robot and the log have different joint counts.
    LogFormatError
        A needed column group (tau_m, tau_j, qd_true) is absent.
    InputValueError
        Unknown ``kind`` or ``velocity``, or an estimator of another period.
    """
    if not isinstance(log, Log):
        raise InputTypeError(f"log must be a sensorless.io.Log; got {type(log).__name__}")
    robot = _check_robot(robot)
    if robot.n_dof != log.n_dof:
        raise DimensionError(
            f"robot has {robot.n_dof} joints, log has {log.n_dof} (robot {robot.name!r})"
        )
    kind = _check_observer_kind(kind)
    if velocity not in VELOCITY_SOURCES:
        raise InputValueError(
            f"velocity must be one of {list(VELOCITY_SOURCES)} (estimate it from q, or the "
            f"ground-truth qd_true); got {velocity!r}"
        )
    if kind == "acceleration" and velocity == "true":
        raise InputValueError(
            "velocity='true' applies to the momentum observers (kind 'motor' or 'joint'); "
            "the acceleration-based estimate takes velocity and acceleration from q with "
            "its estimator: use velocity='filter'"
        )
    tau = _log_torque(log, kind)
    dt = log.dt
    settings: dict[str, Any] = {"velocity": velocity}
    if velocity == "filter" or kind == "acceleration":
        if estimator is None:
            estimator = default_estimator(dt, kind)
        elif not isinstance(estimator, CausalEstimator):
            raise InputTypeError(
                "estimator must be a causal estimator of sensorless.filters; got "
                f"{type(estimator).__name__}"
            )
        if not math.isclose(estimator.dt, dt, rel_tol=_TIME_RTOL):
            raise InputValueError(
                f"estimator has dt = {estimator.dt:g} s but the log is sampled every "
                f"{dt:g} s; build the estimator with dt = log.dt"
            )
        settings["estimator"] = repr(estimator)

    if kind == "acceleration":
        assert estimator is not None  # set above
        observer = AccelerationObserver(robot, estimator, friction=friction, torque="motor")
        signals, _ = observer.run(log.t, log.q, tau)
        settings |= observer.settings()
    else:
        if velocity == "true":
            if log.qd_true is None:
                raise LogFormatError(
                    "velocity='true' needs the ground-truth velocities qd_true_1..qd_true_"
                    f"{log.n_dof}; the log has none (present groups: {log.groups}). Use "
                    "velocity='filter'"
                )
            qd = np.asarray(log.qd_true)
        else:
            assert estimator is not None  # set above
            qd = estimator.filter(log.q)[0].velocity
        momentum = MomentumObserver(robot, dt, gain, friction=friction, torque=kind)
        signals, _ = momentum.run(log.t, log.q, qd, tau)
        settings |= momentum.settings()
    metadata = dict(log.metadata)
    metadata["observer"] = settings
    return ObserverSignals(
        t=signals.t,
        residual=signals.residual,
        model_torque=signals.model_torque,
        friction=signals.friction,
        sign=signals.sign,
        velocity=signals.velocity,
        gain=signals.gain,
        kind=signals.kind,
        robot=signals.robot,
        position=signals.position,
        acceleration=signals.acceleration,
        metadata=metadata,
    )
