"""Adaptive nominal friction and offset: a rate-limited RLS correction of the momentum residual.

Friction drifts as a joint warms up, and torque offsets wander; a nominal
friction model fixed at tuning time then leaves a slowly changing bias in the
residual r̂, and thresholds tuned on a cold arm alarm on a warm one. Without
contact, the momentum observer (eq. 4.4) gives the low-pass filtered model
error,

    r̂ = F(τ̂_fr − τ_fr + τ_c − ...),   F = K_I/(s+K_I),

and since the observer is linear in its input torque, a correction δτ of the
nominal friction can be applied *after* the observer: the corrected residual
is r̂ − F(δτ). :class:`FrictionAdapter` learns, per joint j,

    δτ_j(q̇) = θ_c·tanh(q̇/v_s) + θ_v·q̇ + θ_0

(Coulomb, viscous, offset; tanh is a smooth sign that does not chatter at
tiny velocities) by recursive least squares with exponential forgetting,
regressing r̂_j on the *filtered* regressor ψ = F(φ), φ = (tanh(q̇/v_s), q̇, 1),
so the filter's lag does not bias the estimate. F is discretised exactly as
the observer discretises its friction input (pole a = exp(−K_I dt), weight
1 − a, trapezoid of two samples, zero at the first sample as r̂_0 = 0), so
with a constant θ the correction F(δτ) equals ψᵀθ sample by sample.

With ``max_model_torque`` set, a fourth column learns a relative model
error: ψ_h = h_j, the observer's filtered model torque
h = F(M̂q̈ + Ĉq̇ + ĝ) (eq. 4.26), and the corrected residual is
r̂ − F(δτ) − θ_h·h. This is the ε·h of the thesis's time-variant bound
(eq. 5.34) learned instead of bounded: as friction warms, a controller that
compensates the cold friction kicks the arm at each start and stop, and
those accelerations reach the residual through the inertial model error,
with no friction shape (measured on ``puma560-warmup``; see
``benchmarks/drift_evidence.py``).

Safety, because r̂ also carries the contacts the monitor must detect:

* learning happens only on samples the caller marks ``trusted`` (the monitor
  trusts a sample when its detector is not in alarm, not within a guard time
  around an alarm, and the observer has settled); other samples leave θ and
  the covariance P exactly unchanged (the filters F go on);
* rate limit: the RLS estimate is not applied directly; the applied θ
  slews towards it with |Δθ_c| + v_max|Δθ_v| + |Δθ_0| ≤ ``rate_limit``·dt
  per sample, so the correction δτ(q̇) at any |q̇| ≤ v_max changes by at
  most ``rate_limit`` [N m/s]: a push ramped over 2 s cannot be learned
  away faster than that. (Limiting the RLS step itself instead leaves the
  covariance shrinking as if the full step had been taken, and the
  estimate stalls far from the least-squares solution.)
* magnitude: δτ is clipped to ±``max_correction`` and θ kept in the box
  |θ_c|, v_max|θ_v|, |θ_0| ≤ ``max_correction``;
* covariance: trace(P) ≤ ``max_trace`` (scaled down when forgetting with
  poor excitation would wind it up);
* a sample with a non-finite r̂ or q̇ (or one that would make the state
  non-finite) changes nothing; its output is r̂ minus the last correction.
  Finite but physically impossible velocities are the caller's to refuse
  (the monitor's velocity limit does).

The monitor integrates it as: observer → adapter → threshold → detector,
with ``trusted`` from its own detector, and r̂ − F(δτ) in place of r̂ for
the threshold; :meth:`FrictionAdapter.correction` gives δτ(q̇) for the
adapted nominal friction τ̂_fr − δτ should a threshold family need it.

Units SI; time along axis 0: arrays of shape (n_samples, n_dof), one sample
(n_dof,). ``step`` and ``run`` share one implementation; chunked input
equals whole input when the state is carried over.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import (
    FloatArray,
    as_joint_array,
    check_dt,
    check_int,
    check_scalar,
    check_state_joints,
    check_type,
    per_joint,
)
from ..exceptions import DimensionError, InputValueError
from . import _adaptive_kernel as _kernel
from ._adaptive_state import (
    AdapterState,
    BoolArray,
    _array,
    _positive_or_inf,
    _trusted,
    _Work,
)
from ._common import _check_gain
from .momentum import MomentumObserver

__all__ = ["AdapterState", "FrictionAdapter"]


def _listed(value: FloatArray | None) -> Any:
    return None if value is None else value.tolist()


class FrictionAdapter:
    """Per-joint RLS estimate of a friction/offset correction, applied after the observer.

    Parameters
    ----------
    n_dof : int
        Number of joints.
    dt : float
        Sample period [s], that of the observer.
    gain : float or array-like of shape (n_dof,)
        Observer gain K_I [1/s], that of the observer (see :meth:`from_observer`).
    rate_limit : float or array-like of shape (n_dof,)
        Largest rate of change of the learned correction δτ(q̇) for |q̇| ≤
        ``max_velocity`` [N m/s], > 0 (``inf`` for none). Keep it well below
        the torque rate of the slowest contact to be detected.
    max_correction : float or array-like of shape (n_dof,)
        Bound on |δτ| [N m], > 0 (``inf`` for none).
    forgetting_time : float
        Time constant T_f of the exponential forgetting [s], > 0; the
        forgetting factor is λ = exp(−dt/T_f). ``inf`` for none (λ = 1).
    smooth_velocity : float or array-like of shape (n_dof,)
        v_s of the smooth sign tanh(q̇/v_s) [rad/s], > 0.
    max_velocity : float or array-like of shape (n_dof,)
        v_max, the velocity range over which the rate limit and the box on θ
        hold [rad/s], > 0.
    initial_covariance : float
        Diagonal of the initial covariance P_0 [-], > 0.
    max_trace : float
        Bound on trace(P) per joint, > 0 (``inf`` for none).
    max_model_torque : float or array-like of shape (n_dof,), optional
        Learn the relative model error θ_h on the filtered model torque h too;
        the bound on |h| [N m] over which ``rate_limit`` and
        ``max_correction`` hold for that term, > 0. None (default): the three
        friction/offset columns only.

    Notes
    -----
    With ``max_trace`` infinite, the estimate after N samples is the
    exponentially weighted least-squares solution
    argmin λ^n (θ − θ_0)ᵀP_0⁻¹(θ − θ_0) + Σ_k λ^(N−k) (r̂_k − ψ_kᵀθ)²
    over the n learning samples (the standard RLS identity); with
    ``rate_limit`` and ``max_correction`` infinite too, θ is the estimate.

    Examples
    --------
    >>> import numpy as np
    >>> adapter = FrictionAdapter(1, dt=1e-3, gain=20.0, rate_limit=0.05, max_correction=5.0)
    >>> state = adapter.initial_state()
    >>> out, state = adapter.step(state, [0.3], [0.5], True)
    >>> out.tolist()  # nothing learned yet: the first sample passes unchanged
    [0.3]
    """

    def __init__(
        self,
        n_dof: int,
        dt: float,
        gain: ArrayLike = 20.0,
        *,
        rate_limit: ArrayLike,
        max_correction: ArrayLike,
        forgetting_time: float = 120.0,
        smooth_velocity: ArrayLike = 0.02,
        max_velocity: ArrayLike = 2.0,
        initial_covariance: float = 10.0,
        max_trace: float = 1.0e3,
        max_model_torque: ArrayLike | None = None,
    ) -> None:
        n = check_int(n_dof, "n_dof", 1, "FrictionAdapter")
        self._n_dof = n
        self._dt = check_dt(dt)
        self._gain = _check_gain(gain, n)
        self._pole = np.exp(-self._gain * self._dt)
        self._weight = -np.expm1(-self._gain * self._dt)
        self._rate_limit = per_joint(
            rate_limit, n, "rate_limit", "N m/s", "positive", allow_inf=True
        )
        self._max_correction = per_joint(
            max_correction, n, "max_correction", "N m", "positive", allow_inf=True
        )
        forgetting = _positive_or_inf(forgetting_time, "forgetting_time", "s")
        self._forgetting_time = forgetting
        self._lambda = float(np.exp(-self._dt / forgetting))
        self._smooth_velocity = per_joint(
            smooth_velocity, n, "smooth_velocity", "rad/s", "positive"
        )
        self._max_velocity = per_joint(max_velocity, n, "max_velocity", "rad/s", "positive")
        self._initial_covariance = check_scalar(initial_covariance, "initial_covariance", "-")
        self._max_trace = _positive_or_inf(max_trace, "max_trace", "-")
        self._step_bound = self._rate_limit * self._dt
        self._max_model_torque = (
            None
            if max_model_torque is None
            else per_joint(max_model_torque, n, "max_model_torque", "N m", "positive")
        )
        # Norm weights of Δθ for the rate limit, and the box on θ.
        weights = [np.ones(n), self._max_velocity, np.ones(n)]
        if self._max_model_torque is not None:
            weights.append(self._max_model_torque)
        self._norm_weight = np.stack(weights, axis=1)
        self._columns = len(weights)
        with np.errstate(invalid="ignore"):
            self._box = self._max_correction[:, None] / self._norm_weight
        for arr in (self._pole, self._weight, self._norm_weight, self._box):
            arr.setflags(write=False)
        self._params = (
            self._pole, self._weight, self._smooth_velocity, self._max_correction,
            np.ascontiguousarray(self._norm_weight), np.ascontiguousarray(self._box),
            self._step_bound,
        )  # fmt: skip
        self._scalars = np.array([self._lambda, self._max_trace, float(self._columns)])

    @classmethod
    def from_observer(cls, observer: MomentumObserver, **options: Any) -> FrictionAdapter:
        """An adapter with the joints, ``dt`` and gain K_I of ``observer``.

        Parameters
        ----------
        observer : MomentumObserver
            The observer whose residual the adapter corrects.
        **options
            The keyword parameters of :class:`FrictionAdapter`.
        """
        observer = check_type(observer, MomentumObserver, "observer")
        return cls(observer.n_dof, observer.dt, observer.gain, **options)

    # ------------------------------------------------------------ parameters
    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return self._n_dof

    @property
    def dt(self) -> float:
        """Sample period [s]."""
        return self._dt

    @property
    def gain(self) -> FloatArray:
        """Observer gain K_I per joint [1/s]."""
        return self._gain

    @property
    def forgetting_factor(self) -> float:
        """λ = exp(−dt/T_f) [-]."""
        return self._lambda

    @property
    def rate_limit(self) -> FloatArray:
        """Largest rate of change of δτ per joint [N m/s]."""
        return self._rate_limit

    @property
    def max_correction(self) -> FloatArray:
        """Bound on |δτ| per joint [N m]."""
        return self._max_correction

    @property
    def columns(self) -> int:
        """Number of learned parameters per joint: 3, or 4 with the model-torque term."""
        return self._columns

    def __repr__(self) -> str:
        return (
            f"FrictionAdapter(n_dof={self._n_dof}, dt={self._dt!r}, gain={self._gain.tolist()}, "
            f"rate_limit={self._rate_limit.tolist()}, "
            f"max_correction={self._max_correction.tolist()}, "
            f"forgetting_time={self._forgetting_time!r}, "
            f"smooth_velocity={self._smooth_velocity.tolist()}, "
            f"max_velocity={self._max_velocity.tolist()}, "
            f"initial_covariance={self._initial_covariance!r}, max_trace={self._max_trace!r}, "
            f"max_model_torque={_listed(self._max_model_torque)})"
        )

    # ------------------------------------------------------------ state
    def initial_state(
        self, theta: ArrayLike | None = None, covariance: ArrayLike | None = None
    ) -> AdapterState:
        """State before the first sample of a run (start it with the observer).

        Parameters
        ----------
        theta : array-like of shape (n_dof, columns), optional
            Starting θ (θ_c [N m], θ_v [N m s/rad], θ_0 [N m], and θ_h [-]
            with the model-torque term, per joint), e.g. learned on an earlier
            run; zeros by default. Must lie in the box.
        covariance : array-like of shape (n_dof, columns, columns), optional
            Starting covariance; ``initial_covariance``·I by default.

        Returns
        -------
        AdapterState
            The filters start from zero, as the observer's r̂_0 = 0.
        """
        n, m = self._n_dof, self._columns
        start = np.zeros((n, m)) if theta is None else _array(theta, (n, m), "theta")
        if (np.abs(start) > self._box).any():
            raise InputValueError(
                "theta must lie in the box |θ_c|, max_velocity·|θ_v|, |θ_0| "
                "(, max_model_torque·|θ_h|) <= max_correction; "
                f"got {start.tolist()}"
            )
        if covariance is None:
            cov = np.broadcast_to(self._initial_covariance * np.eye(m), (n, m, m)).copy()
        else:
            cov = _array(covariance, (n, m, m), "covariance")
            cov = 0.5 * (cov + np.swapaxes(cov, 1, 2))
            if (np.linalg.eigvalsh(cov) <= 0.0).any():
                raise InputValueError("covariance must be positive definite for every joint")
        return _Work.fresh(start, start, cov)

    def restart(self, state: AdapterState) -> AdapterState:
        """The state for a new run (or after a gap): what was learned kept, filters from zero.

        Parameters
        ----------
        state : AdapterState
            State at the end of the previous run.

        Returns
        -------
        AdapterState
            θ, the RLS estimate, P and the update counts of ``state``; the
            filters start from zero with the observer (r̂_0 = 0).
        """
        state = self._check_state(state)
        return _Work.fresh(state.theta, state.estimate, state.covariance, state.updates)

    def correction(self, state: AdapterState, qd: ArrayLike) -> FloatArray:
        """The learned correction δτ(q̇) of ``state`` at velocities ``qd``.

        Parameters
        ----------
        state : AdapterState
        qd : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint velocities [rad/s].

        Returns
        -------
        ndarray of the shape of ``qd``
            δτ [N m], clipped to ±``max_correction``; add −δτ to the nominal
            friction τ̂_fr to get the adapted nominal friction. (The
            model-torque term θ_h is a relative error of the whole model, not
            friction: it is not part of δτ.)
        """
        state = self._check_state(state)
        arr, single = as_joint_array(qd, self._n_dof, "qd")
        delta = np.clip(
            np.einsum("knc,nc->kn", self._regressor(arr), state.theta[:, :3]),
            -self._max_correction, self._max_correction,
        )  # fmt: skip
        return delta[0] if single else delta

    def _check_state(self, state: Any) -> AdapterState:
        check_type(state, AdapterState, "state", " from initial_state, step or run")
        check_state_joints(state.n_dof, self._n_dof, "the adapter")
        if state.theta.shape[1] != self._columns:
            raise DimensionError(
                f"state has {state.theta.shape[1]} parameters per joint; this adapter learns "
                f"{self._columns} (max_model_torque {'set' if self._columns == 4 else 'unset'})"
            )
        return state

    def _model_torque(self, value: ArrayLike | None, shape: tuple[int, ...]) -> FloatArray:
        """h checked against ``shape``; zeros (unused) without the model-torque term."""
        if self._max_model_torque is None:
            if value is not None:
                raise InputValueError(
                    "model_torque is given but the adapter has no model-torque term; "
                    "construct it with max_model_torque"
                )
            return np.zeros(shape)
        if value is None:
            raise InputValueError(
                "this adapter learns a model-torque term (max_model_torque is set); pass "
                "model_torque, the observer's filtered model torque h [N m]"
            )
        arr = np.asarray(
            as_joint_array(value, self._n_dof, "model_torque", allow_nonfinite=True)[0]
        )
        if arr.shape[0] == 1 and len(shape) == 1:
            arr = arr[0]
        if arr.shape != shape:
            raise DimensionError(f"model_torque must have shape {shape}; got {np.shape(value)}")
        return arr

    # ------------------------------------------------------------ stream and batch
    def step(
        self,
        state: AdapterState,
        r_hat: ArrayLike,
        qd: ArrayLike,
        trusted: ArrayLike,
        model_torque: ArrayLike | None = None,
    ) -> tuple[FloatArray, AdapterState]:
        """Correct one sample of the residual, and learn from it if it is trusted.

        Parameters
        ----------
        state : AdapterState
            State after the previous sample (or :meth:`initial_state`).
        r_hat : array-like of shape (n_dof,)
            Observer residual r̂ of this sample [N m].
        qd : array-like of shape (n_dof,)
            Joint velocities of this sample [rad/s], those the observer used.
        trusted : bool or array-like of bool of shape (n_dof,)
            Whether the sample may be learned from (all joints, or per joint).
        model_torque : array-like of shape (n_dof,), optional
            The observer's filtered model torque h of this sample [N m];
            required with ``max_model_torque``, refused without it.

        Returns
        -------
        r_corrected : ndarray of shape (n_dof,)
            r̂ − F(δτ) (− θ_h·h) [N m].
        state : AdapterState
        """
        state = self._check_state(state)
        r_arr, qd_arr = self._sample(r_hat, "r_hat"), self._sample(qd, "qd")
        h = self._model_torque(model_torque, (self._n_dof,))
        return self._step_checked(state, r_arr, qd_arr, _trusted(trusted, (self._n_dof,)), h)

    def _step_checked(
        self,
        state: AdapterState,
        r_hat: FloatArray,
        qd: FloatArray,
        trusted: BoolArray,
        model_torque: FloatArray,
    ) -> tuple[FloatArray, AdapterState]:
        """:meth:`step` for arrays of shape (n_dof,) a caller has checked (the monitor)."""
        work = _Work(state)
        if _kernel.compiled is None:
            out = self._advance(work, r_hat, qd, trusted, model_torque)
        else:
            out = _kernel.run(
                work,
                (r_hat[None], qd[None], model_torque[None]),
                trusted[None],
                self._params,
                self._scalars,
            )[0]
        return out, work.freeze()

    def run(
        self,
        r_hat: ArrayLike,
        qd: ArrayLike,
        trusted: ArrayLike,
        state: AdapterState | None = None,
        model_torque: ArrayLike | None = None,
    ) -> tuple[FloatArray, AdapterState]:
        """Correct a whole residual; equal to :meth:`step` sample by sample.

        Parameters
        ----------
        r_hat : array-like of shape (n_samples, n_dof)
            Observer residual r̂ [N m] (time along axis 0).
        qd : array-like of shape (n_samples, n_dof)
            Joint velocities [rad/s].
        trusted : array-like of bool of shape (n_samples,) or (n_samples, n_dof)
            Samples (or samples and joints) that may be learned from.
        state : AdapterState, optional
            State before the first sample; :meth:`initial_state` by default.
            Pass the returned state to continue with the next chunk.
        model_torque : array-like of shape (n_samples, n_dof), optional
            The observer's filtered model torque h [N m]; required with
            ``max_model_torque``, refused without it.

        Returns
        -------
        r_corrected : ndarray of shape (n_samples, n_dof)
            r̂ − F(δτ) (− θ_h·h) [N m].
        state : AdapterState
            State after the last sample.
        """
        state = self.initial_state() if state is None else self._check_state(state)
        r_arr, _ = as_joint_array(r_hat, self._n_dof, "r_hat", allow_nonfinite=True)
        qd_arr, _ = as_joint_array(qd, self._n_dof, "qd", allow_nonfinite=True)
        if qd_arr.shape != r_arr.shape:
            raise DimensionError(
                f"qd must have the shape of r_hat {r_arr.shape}; got {qd_arr.shape}"
            )
        mask = _trusted(trusted, r_arr.shape)
        h = self._model_torque(model_torque, r_arr.shape)
        work = _Work(state)
        if _kernel.compiled is not None:
            return _kernel.run(
                work, (r_arr, qd_arr, h), mask, self._params, self._scalars
            ), work.freeze()
        out = np.empty_like(r_arr)
        for k in range(r_arr.shape[0]):
            out[k] = self._advance(work, r_arr[k], qd_arr[k], mask[k], h[k])
        return out, work.freeze()

    # ------------------------------------------------------------ the kernel
    def _sample(self, x: ArrayLike, name: str) -> FloatArray:
        arr, single = as_joint_array(x, self._n_dof, name, allow_nonfinite=True)
        if not single:
            raise DimensionError(f"{name} must have shape ({self._n_dof},); got {np.shape(x)}")
        return arr[0]

    def _regressor(self, qd: FloatArray) -> FloatArray:
        """φ = (tanh(q̇/v_s), q̇, 1) of shape (..., n_dof, 3)."""
        return np.stack([np.tanh(qd / self._smooth_velocity), qd, np.ones_like(qd)], axis=-1)

    def _advance(
        self, work: _Work, r_hat: FloatArray, qd: FloatArray, trusted: BoolArray, h: FloatArray
    ) -> FloatArray:
        """One sample: filters, output and (trusted joints) the RLS update, in place.

        ``h`` is the model torque (zeros without that term). Nothing is
        written to ``work`` unless every new value is finite.
        """
        if not (np.isfinite(r_hat).all() and np.isfinite(qd).all() and np.isfinite(h).all()):
            return np.asarray(r_hat - work.filtered_correction)
        phi = self._regressor(qd)
        delta = np.clip(
            np.einsum("nc,nc->n", phi, work.theta[:, :3]),
            -self._max_correction, self._max_correction,
        )  # fmt: skip
        if not work.started:
            if np.isfinite(phi).all() and np.isfinite(delta).all():
                work.regressor, work.correction, work.started = phi, delta, True
            return np.array(r_hat, dtype=float)
        pole, weight = self._pole, self._weight
        psi = pole[:, None] * work.filtered_regressor[:, :3] + (weight * 0.5)[:, None] * (
            work.regressor + phi
        )
        if self._columns == 4:
            psi = np.concatenate([psi, h[:, None]], axis=1)
        filtered = pole * work.filtered_correction + weight * 0.5 * (work.correction + delta)
        # θ_h·h with the θ_h learned up to the previous sample, as δτ.
        model_part = work.theta[:, 3] * h if self._columns == 4 else 0.0
        theta, estimate, covariance, updated = self._learn(work, psi, r_hat, trusted)
        candidates = (psi, filtered, phi, delta, theta, estimate, covariance)
        if not all(np.isfinite(x).all() for x in candidates):
            return np.asarray(r_hat - work.filtered_correction)
        work.filtered_regressor, work.filtered_correction = psi, filtered
        work.regressor, work.correction = phi, delta
        work.theta, work.estimate, work.covariance = theta, estimate, covariance
        work.updates = work.updates + updated
        return np.asarray(r_hat - filtered - model_part)

    def _learn(
        self, work: _Work, psi: FloatArray, r_hat: FloatArray, trusted: BoolArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, NDArray[np.int64]]:
        """RLS step of the estimate, then the applied θ slews towards it (trusted joints).

        The estimate is plain RLS with forgetting and a bounded trace; the
        applied θ moves towards the estimate (clipped to the box) by at most
        ``rate_limit``·dt in the norm |Δθ_c| + v_max|Δθ_v| + |Δθ_0| (+ h_max|Δθ_h|).
        """
        if not trusted.any():
            unchanged = np.zeros(self._n_dof, dtype=np.int64)
            return work.theta, work.estimate, work.covariance, unchanged
        lam = self._lambda
        estimate, cov = work.estimate, work.covariance
        p_psi = np.einsum("nij,nj->ni", cov, psi)
        gain = p_psi / (lam + np.einsum("ni,ni->n", psi, p_psi))[:, None]
        error = r_hat - np.einsum("ni,ni->n", psi, estimate)
        new_estimate = estimate + gain * error[:, None]
        new_cov = (cov - gain[:, :, None] * p_psi[:, None, :]) / lam
        new_cov = 0.5 * (new_cov + np.swapaxes(new_cov, 1, 2))
        trace = np.einsum("nii->n", new_cov)
        with np.errstate(invalid="ignore", divide="ignore"):
            cap = np.where(trace > self._max_trace, self._max_trace / trace, 1.0)
        new_cov *= cap[:, None, None]
        # Slew: θ + s (target − θ) with s in [0, 1] stays in the box with θ and target.
        move = np.clip(new_estimate, -self._box, self._box) - work.theta
        size = np.einsum("ni,ni->n", np.abs(move), self._norm_weight)
        with np.errstate(invalid="ignore", divide="ignore"):
            shrink = np.where(size > self._step_bound, self._step_bound / size, 1.0)
        new_theta = work.theta + move * shrink[:, None]
        keep = trusted[:, None]
        return (
            np.where(keep, new_theta, work.theta),
            np.where(keep, new_estimate, estimate),
            np.where(keep[:, :, None], new_cov, cov),
            trusted.astype(np.int64),
        )
