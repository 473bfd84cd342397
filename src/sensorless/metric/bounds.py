"""Error bounds of an acceleration-based torque estimate, eq. 3.10–3.12, 3.26–3.27, 3.36.

The vector Q of eq. 3.11 and its error bound B_Q̃ (Table 3.1,
:func:`q_error_bounds`), the parameter bound B_Θ̃ (:func:`parameter_bounds`)
and the per-sample terms that combine them with the split regressor
(:func:`error_bound_terms`). :mod:`sensorless.metric.estimation` integrates
them into EM[q]; :mod:`sensorless.thresholds.model_based` turns them into a
threshold. Notation: :mod:`sensorless.metric`.
"""

from __future__ import annotations

from types import ModuleType
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_joint_array, check_dt, check_finite, check_int
from ..exceptions import DimensionError, InputTypeError, InputValueError, UnknownNameError
from ..filters import CausalEstimator
from ..robots.model import RobotModel
from ..robots.regressors import q_length, q_vector
from ._checks import nonnegative, per_joint_nonnegative
from ._kernel_numpy import bound_terms_block
from ._plan import BoundWeights, plan_for

_numba_kernel: ModuleType | None
try:
    from . import _kernel_numba as _numba_kernel
except ImportError:  # numba is an optional extra
    _numba_kernel = None

__all__ = [
    "DEFAULT_CHUNK_SIZE",
    "BoundTerms",
    "check_bq",
    "error_bound_terms",
    "parameter_bounds",
    "q_error_bounds",
    "q_length",
    "q_vector",
]

_BACKENDS = ("auto", "numba", "numpy")

#: Samples per block of the numpy form of :func:`error_bound_terms`, which holds
#: about 240 kB per sample at seven joints: 256 samples ≈ 60 MB.
DEFAULT_CHUNK_SIZE = 256


def q_error_bounds(
    q: ArrayLike,
    dt: float,
    estimator: CausalEstimator,
    *,
    noise_std: float | ArrayLike,
    seed: int | np.random.Generator | None = 0,
    reference: tuple[ArrayLike, ArrayLike] | None = None,
    transient: float = 0.0,
) -> FloatArray:
    """Bounds B_Q̃ of eq. 3.26 by the method of thesis Table 3.1.

    White Gaussian noise of standard deviation ``noise_std`` is added to the
    positions, the causal ``estimator`` turns them into q̂̇ and q̂̈, and
    B_Q̃k = max_t |Q̂_k(t) − Q_k(t)| (eq. 3.18); the last entry (the constant
    1) is 0. The estimator's delay is part of the error on purpose: the
    online estimate τ̂_c suffers it too.

    Parameters
    ----------
    q : array-like of shape (n_samples, n_dof)
        Noise-free joint positions of the trajectory on a regular grid [rad].
    dt : float
        Sample period [s].
    estimator : CausalEstimator
        The velocity/acceleration estimator used online (e.g. a 5th-order
        :class:`~sensorless.filters.Butterworth`, as in the thesis). Its
        ``dt`` must equal ``dt``. It starts at rest at ``q[0]``.
    noise_std : float or array-like of shape (n_dof,)
        Standard deviation of the position noise [rad], >= 0.
    seed : int, numpy Generator or None
        Seed of the noise.
    reference : (qd, qdd), optional
        True joint velocities [rad/s] and accelerations [rad/s²], each of
        shape (n_samples, n_dof), e.g. from :meth:`Trajectory.sample`. By
        default second-order central differences of the noise-free ``q``
        (:func:`numpy.gradient`), accurate for a smooth ``q`` sampled finely.
    transient : float
        Time [s] skipped at the start, where the estimator's start-up
        transient would dominate (useful when the trajectory does not start
        at rest); ``0 <= transient < n_samples · dt``.

    Returns
    -------
    ndarray of shape (l,)
        B_Q̃ in the units of Q: [rad/s²] for q̈, [rad²/s²] for the products.

    Examples
    --------
    >>> import numpy as np
    >>> from sensorless.filters import FiniteDifference
    >>> t = np.arange(200)[:, None] * 0.01
    >>> q = np.hstack([0.5 * t**2, -t**2])
    >>> b = q_error_bounds(q, 0.01, FiniteDifference(0.01), noise_std=0.0,
    ...                    reference=(np.hstack([t, -2 * t]), np.tile([1.0, -2.0], (200, 1))),
    ...                    transient=0.02)
    >>> bool(b.max() < 0.1), float(b[-1])
    (True, 0.0)
    """
    dt = check_dt(dt)
    positions = _series(q, "q")
    n_samples, n_dof = positions.shape
    if not isinstance(estimator, CausalEstimator):
        raise InputTypeError(
            "estimator must be a causal estimator of sensorless.filters (FiniteDifference, "
            f"DirtyDerivative, Butterworth); got {type(estimator).__name__}"
        )
    if not np.isclose(estimator.dt, dt, rtol=1e-9, atol=0.0):
        raise InputValueError(
            f"the estimator was designed for dt = {estimator.dt:g} s but the trajectory is "
            f"sampled with dt = {dt:g} s; design it with the same sample period"
        )
    std = per_joint_nonnegative(noise_std, n_dof, "noise_std", "rad")
    skip = _transient_samples(transient, dt, n_samples)
    if reference is None:
        if n_samples < 3:
            raise DimensionError(f"q needs at least 3 samples to differentiate it; got {n_samples}")
        qd_true = np.gradient(positions, dt, axis=0, edge_order=2)
        qdd_true = np.gradient(qd_true, dt, axis=0, edge_order=2)
    else:
        if len(reference) != 2:
            raise DimensionError(
                f"reference must be a pair (qd, qdd) of true derivatives; got {len(reference)} "
                "arrays"
            )
        qd_true, _ = as_joint_array(reference[0], n_dof, "reference qd")
        qdd_true, _ = as_joint_array(reference[1], n_dof, "reference qdd")
        if qd_true.shape != positions.shape or qdd_true.shape != positions.shape:
            raise DimensionError(
                f"reference qd and qdd must have the shape of q, {positions.shape}; got "
                f"{qd_true.shape} and {qdd_true.shape}"
            )
    rng = np.random.default_rng(seed)
    noisy = positions + rng.standard_normal(positions.shape) * std
    estimate, _ = estimator.filter(noisy)
    error = q_vector(estimate.velocity, estimate.acceleration) - q_vector(qd_true, qdd_true)
    bounds = np.abs(error[skip:]).max(axis=0)
    bounds[-1] = 0.0
    return np.asarray(bounds)


class BoundTerms(NamedTuple):
    """The three trajectory-dependent terms of the error bound (eq. 3.28, 3.36).

    Each has shape (n_samples, n_dof) [N m].

    Attributes
    ----------
    q_error : ndarray
        Σ_k |Y_kj^q(q) Θ̂| B_Q̃k, objective A of eq. 3.22 (error of Q̂).
    cross : ndarray
        Σ_p Σ_k |Y_kjp^q(q)| B_Q̃k B_Θ̃p, the product term of eq. 3.36.
    parameter_error : ndarray
        Σ_p |Y_jp(q, q̇, q̈)| B_Θ̃p, objective B of eq. 3.22 (error of Θ̂),
        with the q̇, q̈ given (true ones for the metric, estimated ones for
        the threshold).
    """

    q_error: FloatArray
    cross: FloatArray
    parameter_error: FloatArray


def parameter_bounds(btheta: float | ArrayLike, theta: FloatArray) -> FloatArray:
    """B_Θ̃ from a relative bound (eq. 3.40) or a bound per base parameter.

    Parameters
    ----------
    btheta : float or array-like of shape (n_base,)
        A float r >= 0 gives B_Θ̃ = r·|Θ̂| (0.02 in the thesis); an array is
        the bound of each base parameter in its own unit, >= 0.
    theta : ndarray of shape (n_base,)
        Base-parameter values Θ̂.

    Returns
    -------
    ndarray of shape (n_base,)
    """
    value = np.asarray(btheta, dtype=float)
    if value.ndim == 0:
        if not np.isfinite(value) or value < 0:
            raise InputValueError(
                f"btheta as a relative bound must be a finite number >= 0 (0.02 = 2 %); "
                f"got {btheta!r}"
            )
        return np.asarray(float(value) * np.abs(theta))
    if value.shape != theta.shape:
        raise DimensionError(
            f"btheta must be a relative bound (float) or one bound per base parameter, shape "
            f"{theta.shape}; got shape {value.shape}"
        )
    return nonnegative(value, "btheta")


def check_bq(bq: ArrayLike, n_dof: int) -> FloatArray:
    """Check B_Q̃: finite, >= 0, shape (l,) with l = (n² + 3n + 2)/2."""
    value = np.asarray(bq, dtype=float)
    length = q_length(n_dof)
    if value.shape != (length,):
        raise DimensionError(
            f"bq must have shape ({length},) for {n_dof} joints (one bound per entry of Q, "
            f"eq. 3.11); got shape {value.shape}"
        )
    return nonnegative(value, "bq")


def error_bound_terms(
    robot: RobotModel,
    columns: ArrayLike,
    theta: ArrayLike,
    q: FloatArray,
    qd: FloatArray,
    qdd: FloatArray,
    bq: FloatArray,
    btheta: FloatArray,
    *,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
    backend: str = "auto",
) -> BoundTerms:
    """Per-sample, per-joint terms of eq. 3.28 and 3.36.

    The entries of the split regressor Y_k^q(q) and of Y(q, q̇, q̈) come from
    the kinematics of each sample (:mod:`sensorless.metric._kernel`), equal
    to those of :meth:`RobotModel.regressor_terms` and
    :meth:`RobotModel.regressor` without building either. Inputs are not
    checked here (the public functions of :mod:`sensorless.metric` and the
    thresholds check them).

    Parameters
    ----------
    robot : RobotModel
        Robot with the kinematics of the nominal model (its joints must be
        revolute or prismatic).
    columns : array-like of int of shape (n_base,)
        Base-parameter columns of the standard regressor
        (:attr:`BaseParameters.independent`).
    theta : array-like of shape (n_base,)
        Base-parameter values Θ̂ (:meth:`BaseParameters.values_of` the nominal robot).
    q, qd, qdd : ndarray of shape (n_samples, n_dof)
        Joint positions [rad], velocities [rad/s], accelerations [rad/s²].
    bq : ndarray of shape (l,)
        B_Q̃ (eq. 3.26), checked by :func:`check_bq`.
    btheta : ndarray of shape (n_base,)
        Absolute B_Θ̃ (eq. 3.27), e.g. from :func:`parameter_bounds`.
    chunk_size : int
        Samples per block of the numpy form (bounds its memory, about
        240 kB per sample at seven joints); the compiled form needs none.
    backend : {"auto", "numba", "numpy"}
        Compiled kernel or numpy; ``"auto"`` takes numba when it is installed
        (``pip install sensorless[fast]``). Both give the same terms.

    Returns
    -------
    BoundTerms
    """
    chunk = check_int(chunk_size, "chunk_size", 1)
    if backend not in _BACKENDS:
        raise UnknownNameError(f"unknown backend {backend!r}; options: {list(_BACKENDS)}")
    if backend == "numba" and _numba_kernel is None:
        raise InputValueError(
            "backend 'numba' needs numba (pip install sensorless[fast]); use 'auto' or 'numpy'"
        )
    plan = plan_for(robot)
    weights = BoundWeights.from_base(
        robot.n_dof,
        np.asarray(columns, dtype=np.intp),
        np.asarray(theta, dtype=float),
        np.asarray(btheta, dtype=float),
        np.asarray(bq, dtype=float),
    )
    q, qd, qdd = (np.ascontiguousarray(x, dtype=float) for x in (q, qd, qdd))
    out = np.empty((3, *q.shape))
    if _numba_kernel is not None and backend != "numpy":
        _numba_kernel.bound_terms_batch(
            q, qd, qdd, plan.joint_table, plan.axes, plan.placement_rotations,
            plan.placement_translations, plan.gravity, plan.jacobian, plan.gravity_row,
            plan.ancestors, plan.cross_rows, plan.pair_row, plan.velocity_cross,
            plan.product_x, plan.product_w, plan.entry_product, plan.entry_sign,
            plan.entry_table, plan.n_vectors, plan.n_split_entries, weights.theta,
            weights.btheta, weights.bq, out,
        )  # fmt: skip
    else:
        for start in range(0, q.shape[0], chunk):
            rows = slice(start, start + chunk)
            bound_terms_block(plan, weights, q[rows], qd[rows], qdd[rows], out[:, rows])
    return BoundTerms(out[0], out[1], out[2])


# ---------------------------------------------------------------------------- helpers


def _series(x: ArrayLike, name: str) -> FloatArray:
    arr = np.asarray(x, dtype=float)
    if arr.ndim != 2 or arr.shape[1] < 1:
        raise DimensionError(
            f"{name} must have shape (n_samples, n_dof) with n_dof >= 1; got {arr.shape}"
        )
    check_finite(arr, name)
    return arr


def _transient_samples(transient: float, dt: float, n_samples: int) -> int:
    try:
        value = float(transient)
    except (TypeError, ValueError):
        raise InputValueError(f"transient must be a time >= 0 [s]; got {transient!r}") from None
    skip = int(np.ceil(value / dt - 1e-9)) if np.isfinite(value) else n_samples
    if value < 0 or skip >= n_samples:
        raise InputValueError(
            f"transient must be a time [s] with 0 <= transient < n_samples·dt = "
            f"{n_samples * dt:g} s; got {transient!r}"
        )
    return skip
