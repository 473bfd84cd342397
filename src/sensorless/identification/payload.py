"""Mass and centre of mass of an unknown payload from the residuals of a collision-free motion.

A payload gripped by the end link and missing from the nominal model is,
for the momentum observer, an external torque that lasts: in free motion
r̂ ≈ Ψ(q, q̂̇) π_L, where π_L are the payload's ten standard parameters about
the end-link origin (``XX, XY, XZ, YY, YZ, ZZ`` [kg m²], ``mX, mY, mZ`` [kg m],
``m`` [kg]) and Ψ the end link's columns of the joint-torque regressor
filtered by K_I/(s+K_I) exactly as the observer filters
(:mod:`sensorless.identification._payload_regressor`; no q̈ is needed). Least
squares over the samples and joints of the motion gives π̂_L, hence the mass
m̂ and the centre of mass ĉ = (mX, mY, mZ)/m̂ in the end-link frame [m].

Method
------
* The rows [Ψ_j | r̂_j] of every used sample and joint are reduced to one
  11×11 triangular factor R by QR (``numpy.linalg.qr``), updated chunk by
  chunk: the stream (:meth:`PayloadEstimator.step`, :meth:`~PayloadEstimator.process`)
  and the batch (:func:`estimate_payload`) run the same code, and any cut of
  a run into chunks gives the estimate of the whole run up to round-off.
  π̂_L solves the triangular system with :func:`scipy.linalg.lstsq` (rank
  reported; a motion that leaves a parameter unexcited gives the
  minimum-norm solution).
* **m ≥ 0**: a negative m̂ is not a body. The problem is convex with one
  bound, so its constrained minimum then lies on m = 0: the fit is redone
  without the mass column (``mass_clipped``); the centre of mass of no
  mass is undefined (NaN).
* **Standard errors**: r̂ is a filtered signal, its errors are correlated
  over a few 1/K_I, and the textbook σ²(XᵀX)⁻¹ would be far too small.
  The samples are cut into blocks of ``block`` seconds (≫ 1/K_I) and the
  covariance is the cluster-robust sandwich (XᵀX)⁻¹ (Σ_b s_b s_bᵀ) (XᵀX)⁻¹ ·
  G/(G−1), s_b = X_bᵀ(y_b − X_b π̂) over the G blocks; the centre of mass
  gets its errors by the delta method. Σ_b s_b s_bᵀ is kept as a fixed-size
  sum of Kronecker products, so the stream's memory does not grow.
* The first ``transient`` seconds of every run are left out of the fit
  (default 5/K_I: an observer restarted inside a run, as the monitor's at
  its second sample, needs them); the regressor filter runs through them.

Examples
--------
>>> import numpy as np
>>> import sensorless as sl
>>> from sensorless.identification.payload import PayloadEstimator
>>> robot = sl.robots.load("planar2")
>>> estimator = PayloadEstimator(robot, dt=1e-3, transient=0.0)
>>> t = np.arange(2000) * 1e-3
>>> q = np.column_stack([np.sin(2 * t), np.cos(3 * t)])
>>> qd = np.column_stack([2 * np.cos(2 * t), -3 * np.sin(3 * t)])
>>> truth = np.array([0.01, 0, 0, 0.01, 0, 0.01, 0.05, 0.0, 0.0, 0.5])
>>> psi = estimator.regressor(q, qd)            # Ψ, shape (2000, 2, 10)
>>> state = estimator.initial_state(q[0], qd[0])
>>> state = estimator.process(state, q, qd, psi @ truth)
>>> print(f"{estimator.estimate(state).mass:.6f}")
0.500000
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from .._validation import (
    FloatArray,
    as_joint_array,
    check_dt,
    check_duration,
    check_increasing,
    check_type,
    per_joint,
)
from ..exceptions import DimensionError, InputValueError, ModelMismatchError
from ..robots.model import RobotModel
from ..signals import ObserverSignals
from ._payload_regressor import (
    FIRST_MOMENTS,
    MASS,
    N_PAYLOAD_PARAMETERS,
    PAYLOAD_PARAMETER_NAMES,
    PayloadRegressor,
)
from ._payload_result import EstimatorState, PayloadEstimate

__all__ = [
    "PAYLOAD_PARAMETER_NAMES",
    "EstimatorState",
    "PayloadEstimate",
    "PayloadEstimator",
    "estimate_payload",
]

_P = N_PAYLOAD_PARAMETERS
# Singular values of R below this fraction of the largest count as zero (rank).
_RCOND = 1e-10
_TIME_RTOL = 1e-6


class PayloadEstimator:
    """Least squares of a payload's parameters on the momentum residual, batch and stream.

    Parameters
    ----------
    robot : RobotModel
        The nominal model of the observer (without the payload).
    dt : float
        Sample period [s].
    gain : float or array-like of shape (n_dof,)
        Observer gain K_I [1/s], as the observer's; default 20.
    joints : sequence of int, optional
        Joints (1-based) whose residuals enter the fit; all by default.
    transient : float, optional
        Time left out at the start of every run [s]; default 5/min(K_I).
    block : float
        Length of the blocks of the standard errors [s], > 0; default 0.25 s.
    """

    def __init__(
        self,
        robot: RobotModel,
        dt: float,
        gain: ArrayLike = 20.0,
        *,
        joints: Sequence[int] | None = None,
        transient: float | None = None,
        block: float = 0.25,
    ) -> None:
        check_type(robot, RobotModel, "robot", " (the nominal model the observer uses)")
        self.robot = robot
        self.dt = check_dt(dt)
        self.gain = per_joint(gain, robot.n_dof, "gain", "1/s", "positive")
        self.joints = _check_joints(joints, robot.n_dof)
        seconds = 5.0 / float(self.gain.min()) if transient is None else transient
        self.transient = check_duration(seconds, "transient")
        self.block = check_dt(block, "block")
        self._skip = round(self.transient / self.dt)
        self._block_samples = max(1, round(self.block / self.dt))
        self._columns = np.asarray(self.joints) - 1
        self._regressor = PayloadRegressor(robot)

    def __repr__(self) -> str:
        return (
            f"PayloadEstimator(robot={self.robot.name!r}, dt={self.dt!r}, "
            f"joints={list(self.joints)}, transient={self.transient!r}, block={self.block!r})"
        )

    # ------------------------------------------------------------ regressor
    def _samples(self, *arrays: tuple[ArrayLike, str]) -> list[FloatArray]:
        out = [as_joint_array(value, self.robot.n_dof, name)[0] for value, name in arrays]
        if len({arr.shape[0] for arr in out}) > 1:
            names = ", ".join(name for _, name in arrays)
            raise DimensionError(
                f"{names} must have the same number of samples; got {[arr.shape[0] for arr in out]}"
            )
        return out

    def regressor(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """Ψ of a run from the observer's start: r̂ ≈ Ψ π_L.

        Parameters
        ----------
        q, qd : array-like of shape (n_samples, n_dof)
            Joint positions [rad] and the velocities the observer used [rad/s].

        Returns
        -------
        ndarray of shape (n_samples, n_dof, 10)
            Columns in the order of :data:`PAYLOAD_PARAMETER_NAMES`.
        """
        q_arr, qd_arr = self._samples((q, "q"), (qd, "qd"))
        state = self._regressor.initial_state(q_arr[:1], qd_arr[:1], held=False)
        return self._regressor.filter(state, q_arr, qd_arr, self.gain, self.dt)[0]

    # ------------------------------------------------------------ stream
    def initial_state(
        self, q0: ArrayLike, qd0: ArrayLike | None = None, *, pooled: EstimatorState | None = None
    ) -> EstimatorState:
        """State before the first sample of a run (the observer's start).

        Parameters
        ----------
        q0, qd0 : array-like of shape (n_dof,)
            First sample's position [rad] and velocity [rad/s] (zero by default).
        pooled : EstimatorState, optional
            State after earlier runs whose rows this run joins.
        """
        (q,) = self._samples((q0, "q0"))
        qd = np.zeros_like(q) if qd0 is None else self._samples((qd0, "qd0"))[0]
        if q.shape[0] != 1 or qd.shape[0] != 1:
            raise DimensionError(
                f"initial_state takes one sample of shape ({self.robot.n_dof},); "
                f"got {q.shape[0]} and {qd.shape[0]} samples"
            )
        regressor = self._regressor.initial_state(q, qd, held=False)
        if pooled is not None:
            check_type(pooled, EstimatorState, "pooled", " from initial_state, step or process")
            return replace(pooled, regressor=regressor, seen=0)
        return EstimatorState(
            regressor,
            0,
            np.zeros((_P + 1, _P + 1)),
            np.zeros((_P, _P + 1)),
            0,
            np.zeros((_P, _P + 1, _P, _P + 1)),
            0,
            0,
        )

    def step(
        self, state: EstimatorState, q: ArrayLike, qd: ArrayLike, residual: ArrayLike
    ) -> EstimatorState:
        """Add one sample: q [rad], the observer's q̂̇ [rad/s] and r̂ [N m], each (n_dof,)."""
        q_arr, qd_arr, r_arr = self._samples((q, "q"), (qd, "qd"), (residual, "residual"))
        if q_arr.shape[0] != 1:
            raise DimensionError(
                f"step takes one sample of shape ({self.robot.n_dof},); got {q_arr.shape[0]}"
            )
        return self._process_checked(self._check_state(state), q_arr, qd_arr, r_arr)

    def process(
        self, state: EstimatorState, q: ArrayLike, qd: ArrayLike, residual: ArrayLike
    ) -> EstimatorState:
        """Add a chunk of samples, arrays of shape (n_samples, n_dof) as in :meth:`step`."""
        q_arr, qd_arr, r_arr = self._samples((q, "q"), (qd, "qd"), (residual, "residual"))
        return self._process_checked(self._check_state(state), q_arr, qd_arr, r_arr)

    def _check_state(self, state: object) -> EstimatorState:
        checked = check_type(state, EstimatorState, "state", " from initial_state, step or process")
        if checked.regressor.momentum.shape[0] != self.robot.n_dof:
            raise DimensionError(
                f"state is for {checked.regressor.momentum.shape[0]} joints; the estimator's "
                f"robot has {self.robot.n_dof}"
            )
        return checked

    def _process_checked(
        self, state: EstimatorState, q: FloatArray, qd: FloatArray, residual: FloatArray
    ) -> EstimatorState:
        psi, regressor = self._regressor.filter(state.regressor, q, qd, self.gain, self.dt)
        first = max(0, self._skip - state.seen)
        x = psi[first:, self._columns]
        y = residual[first:, self._columns]
        factor, block, in_block = state.factor, state.block, state.in_block
        meat, n_blocks = state.meat, state.n_blocks
        if x.shape[0]:
            rows = np.concatenate([x.reshape(-1, _P), y.reshape(-1, 1)], axis=1)
            factor = _triangular(np.concatenate([factor, rows]))
            start = 0
            while start < x.shape[0]:
                stop = min(x.shape[0], start + self._block_samples - in_block)
                xb = x[start:stop].reshape(-1, _P)
                yb = y[start:stop].reshape(-1, 1)
                block = block + xb.T @ np.concatenate([yb, xb], axis=1)
                in_block += stop - start
                if in_block == self._block_samples:
                    meat = meat + np.einsum("ik,jl->ikjl", block, block)
                    n_blocks += 1
                    block, in_block = np.zeros_like(block), 0
                start = stop
        return EstimatorState(
            regressor,
            state.seen + q.shape[0],
            factor,
            block,
            in_block,
            meat,
            n_blocks,
            state.n_samples + x.shape[0],
        )

    # ------------------------------------------------------------ the estimate
    def estimate(self, state: EstimatorState) -> PayloadEstimate:
        """The estimate from the samples added so far (the block being filled included).

        Raises
        ------
        InputValueError
            No sample has been used yet (all inside the transient).
        """
        state = self._check_state(state)
        if state.n_samples == 0:
            raise InputValueError(
                f"no sample is in the fit yet: the first {self.transient} s of every run "
                "(transient) are left out; add more samples"
            )
        r_matrix, rhs = state.factor[:_P, :_P], state.factor[:_P, _P]
        singular = np.linalg.svd(r_matrix, compute_uv=False)
        rank = int(np.sum(singular > _RCOND * singular[0]))
        condition = float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")
        parameters = _solve(r_matrix, rhs, list(range(_P)))
        clipped = bool(parameters[MASS] < 0.0)
        if clipped:
            parameters = _solve(r_matrix, rhs, [k for k in range(_P) if k != MASS])
        covariance = self._covariance(state, r_matrix, parameters)
        mass = float(parameters[MASS])
        first_moments = parameters[FIRST_MOMENTS]
        if mass > 0.0:
            com = first_moments / mass
            jacobian = np.zeros((3, _P))
            jacobian[:, MASS] = -first_moments / mass**2
            jacobian[:, FIRST_MOMENTS] = np.eye(3) / mass
            com_std = np.sqrt(np.maximum(np.diag(jacobian @ covariance @ jacobian.T), 0.0))
        else:
            com = np.full(3, np.nan)
            com_std = np.full(3, np.nan)
        rows = state.n_samples * len(self.joints)
        residual_norm = float(np.linalg.norm(r_matrix @ parameters - rhs) ** 2)
        residual_norm += float(state.factor[_P, _P] ** 2)
        return PayloadEstimate(
            mass=mass,
            com=com,
            mass_std=float(np.sqrt(max(covariance[MASS, MASS], 0.0))),
            com_std=com_std,
            parameters=parameters,
            covariance=covariance,
            duration=state.n_samples * self.dt,
            n_samples=state.n_samples,
            n_blocks=state.n_blocks + int(state.in_block > 0),
            rank=rank,
            condition=condition,
            rms=float(np.sqrt(residual_norm / rows)),
            mass_clipped=clipped,
        )

    def _covariance(
        self, state: EstimatorState, r_matrix: FloatArray, parameters: FloatArray
    ) -> FloatArray:
        """Cluster-robust covariance of π̂ over the blocks (module docstring); NaN below 2 blocks."""
        meat = state.meat
        n_blocks = state.n_blocks
        if state.in_block:
            meat = meat + np.einsum("ik,jl->ikjl", state.block, state.block)
            n_blocks += 1
        if n_blocks < 2:
            return np.full((_P, _P), np.nan)
        v = np.concatenate([[1.0], -parameters])
        scores = np.einsum("ikjl,k,l->ij", meat, v, v)
        bread = np.linalg.pinv(r_matrix.T @ r_matrix, rcond=_RCOND)
        return np.asarray(bread @ scores @ bread * (n_blocks / (n_blocks - 1)))


def _triangular(rows: FloatArray) -> FloatArray:
    """The 11×11 upper-triangular R of the rows (zero rows below when there are fewer)."""
    factor = np.asarray(np.linalg.qr(rows, mode="r"))
    out = np.zeros((_P + 1, _P + 1))
    out[: factor.shape[0]] = factor
    return out


def _solve(r_matrix: FloatArray, rhs: FloatArray, free: list[int]) -> FloatArray:
    """Least squares ‖R π − z‖ over the parameters ``free`` (the others zero)."""
    parameters = np.zeros(_P)
    solution = scipy.linalg.lstsq(r_matrix[:, free], rhs, cond=_RCOND)[0]
    parameters[free] = solution
    return parameters


def _check_joints(joints: Sequence[int] | None, n_dof: int) -> tuple[int, ...]:
    if joints is None:
        return tuple(range(1, n_dof + 1))
    try:
        chosen = tuple(int(j) for j in joints if int(j) == j and not isinstance(j, bool))
    except (TypeError, ValueError):
        chosen = ()
    if not chosen or len(chosen) != len(list(joints)) or len(set(chosen)) != len(chosen):
        raise InputValueError(f"joints must be distinct joint numbers 1..{n_dof}; got {joints!r}")
    if min(chosen) < 1 or max(chosen) > n_dof:
        raise InputValueError(f"joints must be numbers from 1 to {n_dof}; got {list(chosen)}")
    return chosen


def estimate_payload(
    signals: ObserverSignals | Sequence[ObserverSignals],
    robot: RobotModel,
    *,
    joints: Sequence[int] | None = None,
    transient: float | None = None,
    block: float = 0.25,
) -> PayloadEstimate:
    """Estimate a payload's mass and centre of mass from collision-free momentum residuals.

    Parameters
    ----------
    signals : ObserverSignals or sequence of ObserverSignals
        Runs of a momentum observer (kind ``"motor"`` or ``"joint"``) on the
        nominal ``robot``, with ``position``, from the observer's start,
        regularly sampled; the rows of all runs are pooled.
    robot : RobotModel
        The nominal model the observer used.
    joints, transient, block
        As for :class:`PayloadEstimator`.

    Returns
    -------
    PayloadEstimate

    Raises
    ------
    InputTypeError
        Not ObserverSignals, or ``robot`` not a RobotModel.
    InputValueError
        Acceleration-based signals, signals without positions, irregular
        time, different gains or periods between runs.
    ModelMismatchError
        Signals of another nominal model (name or fingerprint).
    """
    runs = [signals] if isinstance(signals, ObserverSignals) else list(signals)
    if not runs:
        raise InputValueError("estimate_payload needs at least one run of signals")
    for run in runs:
        _check_run(run, robot)
    dt, gain = _regular_period(runs[0]), runs[0].gain
    for run in runs[1:]:
        if not np.isclose(_regular_period(run), dt, rtol=_TIME_RTOL, atol=0.0) or not np.allclose(
            run.gain, gain, rtol=1e-12, atol=0.0
        ):
            raise InputValueError(
                "every run must have the sample period and observer gain of the first: "
                f"dt = {dt} s, K_I = {gain.tolist()} 1/s"
            )
    estimator = PayloadEstimator(robot, dt, gain, joints=joints, transient=transient, block=block)
    state: EstimatorState | None = None
    for run in runs:
        assert run.position is not None  # checked by _check_run
        state = estimator.initial_state(run.position[0], run.velocity[0], pooled=state)
        state = estimator._process_checked(state, run.position, run.velocity, run.residual)
    assert state is not None  # runs is not empty
    return estimator.estimate(state)


def _check_run(run: object, robot: RobotModel) -> None:
    check_type(run, ObserverSignals, "signals", " (from sensorless.observers.observe)")
    check_type(robot, RobotModel, "robot", " (the nominal model the observer used)")
    assert isinstance(run, ObserverSignals)
    if run.kind not in ("motor", "joint"):
        raise InputValueError(
            "estimate_payload needs the momentum residual (kind 'motor' or 'joint'); got "
            f"{run.kind!r} signals"
        )
    if run.position is None:
        raise InputValueError("estimate_payload needs signals with positions (signals.position)")
    if run.n_dof != robot.n_dof:
        raise DimensionError(
            f"signals have {run.n_dof} joints; robot {robot.name!r} has {robot.n_dof}"
        )
    other_name = bool(run.robot) and run.robot != robot.name
    other_parameters = bool(run.fingerprint) and run.fingerprint != robot.fingerprint
    if other_name or other_parameters:
        raise ModelMismatchError(
            f"signals come from the model {run.robot!r} (fingerprint {run.fingerprint or '?'}); "
            f"the robot given is {robot.name!r} (fingerprint {robot.fingerprint}): pass the "
            "nominal model the observer used"
        )
    for name in ("position", "velocity", "residual"):
        values = getattr(run, name)
        if not np.isfinite(values).all():
            raise InputValueError(f"signals.{name} must be finite")


def _regular_period(run: ObserverSignals) -> float:
    check_increasing(run.t, "signals")
    if run.n_samples < 2:
        raise InputValueError(f"signals have {run.n_samples} sample(s); at least 2 are needed")
    steps = np.diff(run.t)
    period = float(np.median(steps))
    if np.abs(steps - period).max() > _TIME_RTOL * period:
        raise InputValueError(
            "t of the signals is not regularly sampled (largest deviation from the median "
            f"step {period:.9g} s: {np.abs(steps - period).max():.3g} s); resample explicitly "
            "with sensorless.io.resample"
        )
    return period
