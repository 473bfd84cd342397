"""The acceleration-based estimate τ̂_c of eq. (3.8)/(3.16).

Units and shapes as in :mod:`sensorless.observers`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_state_joints, check_type
from ..exceptions import InputTypeError
from ..filters import CausalEstimator, FilterState
from ..robots.model import RobotModel
from ..signals import ObserverSignals
from ._common import ObserverSample, _NominalObserver

__all__ = ["AccelerationObserver"]


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

    _family = "acceleration"

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

    def _repr_parameters(self) -> str:
        return f"estimator={self.estimator!r}"

    def _settings(self) -> dict[str, Any]:
        estimator = self.estimator
        return {"estimator": repr(estimator), "delays": list(estimator.delays), "dt": self.dt}

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
        return self.estimator.initial_state(self._first_sample(q0, "q0")[0])

    def _check_state(self, state: Any) -> FilterState:
        check_type(state, FilterState, "state", " from initial_state, step or run")
        check_state_joints(state.n_dof, self.n_dof, "the observer's robot")
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
        state = self._check_state(state)
        q_arr, tau_arr = self._step_inputs(q=q, tau=tau)
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
        if state is not None:
            state = self._check_state(state)
        t_arr, (q_arr, tau_arr) = self._run_inputs(t, state is not None, q=q, tau=tau)
        if state is None:
            state = self.estimator.initial_state(q_arr[0])
        return self._run_checked(t_arr, q_arr, tau_arr, state)

    def _run_checked(
        self, t: FloatArray, q: FloatArray, tau: FloatArray, state: FilterState
    ) -> tuple[ObserverSignals, FilterState]:
        """:meth:`run` for checked arrays and a checked estimator state."""
        n = self.n_dof
        t_arr, q_arr, tau_arr = t, q, tau
        y, new_state = self.estimator._run(q_arr, state)
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
            fingerprint=self.robot.fingerprint,
            position=q_arr,
            acceleration=y.acceleration,
            metadata=self.settings(),
        )
        return signals, new_state
