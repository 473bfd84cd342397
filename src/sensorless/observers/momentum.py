"""The generalized-momentum residual r̂ (eq. 4.4) and r̂_s (eq. 4.9), discretised exactly.

Units and shapes as in :mod:`sensorless.observers`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy import signal

from .._validation import FloatArray, check_dt, check_state_joints, check_type
from ..robots.model import RobotModel
from ..robots.recursion import MomentumTerms
from ..signals import ObserverSignals
from ._common import (
    _BLOCK,
    _FRICTION,
    _MODEL_TORQUE,
    _RESIDUAL,
    _SIGN,
    ObserverSample,
    _check_gain,
    _NominalObserver,
)

__all__ = ["MomentumObserver", "ObserverState"]


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
    backend : {"auto", "numba", "numpy"}
        How p, Cᵀq̇ and g are computed (:class:`~sensorless.robots.recursion.MomentumTerms`):
        compiled with numba when it is installed (``pip install sensorless[fast]``),
        else numpy over whole arrays and Pinocchio for one sample.

    Notes
    -----
    ``step`` does cheap checks only (shape, finiteness); ``run`` validates
    whole arrays once and computes the model terms by one O(n) recursion over
    the whole array, then applies the recursions with
    :func:`scipy.signal.lfilter`. Both use the same input and coefficient
    functions. Not thread-safe: use one observer per thread.

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

    _family = "momentum"

    def __init__(
        self,
        robot: RobotModel,
        dt: float,
        gain: ArrayLike = 20.0,
        friction: Any = "model",
        torque: str = "motor",
        backend: str = "auto",
    ) -> None:
        super().__init__(robot, friction, torque)
        self._dt = check_dt(dt)
        self._gain = _check_gain(gain, robot.n_dof)
        self._pole, self._weight = _coefficients(self._gain, self._dt)
        self._kernel = MomentumTerms.from_robot(robot, backend=backend)
        self._scratch = np.empty((3, robot.n_dof))

    @property
    def dt(self) -> float:
        """Sample period [s]."""
        return self._dt

    @property
    def gain(self) -> FloatArray:
        """Observer gain K_I per joint [1/s] (read-only array)."""
        return self._gain

    def _repr_parameters(self) -> str:
        return f"dt={self.dt!r}, gain={self.gain.tolist()}"

    def _settings(self) -> dict[str, Any]:
        return {"gain": self.gain.tolist(), "dt": self.dt}

    # ------------------------------------------------------------ model terms
    def _terms(
        self, q: FloatArray, qd: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """p = M q̇, Cᵀq̇ − g, τ̂_fr(q̇) and sign(q̇) for arrays of shape (n_samples, n_dof).

        The rigid-body terms come from one O(n) recursion per sample
        (:class:`~sensorless.robots.recursion.MomentumTerms`), over the whole
        array at once: no M, no C and no per-sample Python loop.
        """
        p, coriolis, gravity = self._kernel.terms_checked(q, qd)
        return p, coriolis - gravity, self._friction(qd), np.sign(qd)

    def _terms_one(
        self, q: FloatArray, qd: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """:meth:`_terms` of one sample of shape (n_dof,) (the streaming path)."""
        p, coriolis, gravity = self._kernel.terms_one(q, qd, self._scratch)
        return p.copy(), coriolis - gravity, self._friction(qd), np.sign(qd)

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
        q = self._first_sample(q0, "q0")
        qd = np.zeros_like(q) if qd0 is None else self._first_sample(qd0, "qd0")
        return self._initial_state_checked(q, qd)

    def _initial_state_checked(self, q: FloatArray, qd: FloatArray) -> ObserverState:
        """:meth:`initial_state` for checked samples of shape (1, n_dof)."""
        p, vg, fr, sgn = (x[0] for x in self._terms(q, qd))
        filtered = np.zeros((4, q.shape[1]))
        filtered[_MODEL_TORQUE] = -vg
        filtered[_FRICTION] = fr
        filtered[_SIGN] = sgn
        filtered.setflags(write=False)
        return ObserverState(p, vg, fr, sgn, fr - vg, filtered)

    def _check_state(self, state: Any) -> ObserverState:
        check_type(state, ObserverState, "state", " from initial_state, step or run")
        check_state_joints(state.momentum.shape[0], self.n_dof, "the observer's robot")
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
        state = self._check_state(state)
        q_arr, qd_arr, tau_arr = self._step_inputs(q=q, qd=qd, tau=tau)
        return self._step_checked(state, q_arr, qd_arr, tau_arr)

    def _step_checked(
        self, state: ObserverState, q: FloatArray, qd: FloatArray, tau: FloatArray
    ) -> tuple[ObserverSample, ObserverState]:
        """The core of :meth:`step` for a checked state and checked samples.

        ``q``, ``qd`` and ``tau`` are finite, C-contiguous float arrays of
        shape (n_dof,); ``tau`` is copied into the new state. The fields of
        the returned sample are the rows of the new state's ``filtered``.
        """
        p, vg, fr, sgn = self._terms_one(q, qd)
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
        if state is not None:
            state = self._check_state(state)
        t_arr, (q_arr, qd_arr, tau_arr) = self._run_inputs(
            t, state is not None, q=q, qd=qd, tau=tau
        )
        if state is None:
            state = self._initial_state_checked(q_arr[:1], qd_arr[:1])
        return self._run_checked(t_arr, q_arr, qd_arr, tau_arr, state)

    def _run_checked(
        self,
        t: FloatArray,
        q: FloatArray,
        qd: FloatArray,
        tau: FloatArray,
        state: ObserverState,
    ) -> tuple[ObserverSignals, ObserverState]:
        """:meth:`run` for checked, C-contiguous arrays and a checked state."""
        t_arr, q_arr, qd_arr, tau_arr = t, q, qd, tau
        n_samples, n = q.shape
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
            fingerprint=self.robot.fingerprint,
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
