"""The observer's filter K_I/(s+K_I), discretised with a zero-order hold on the input.

Every filtered signal of the observer, and the filtered friction term of the
velocity-based thresholds, is

    y[0] = zi,    y[k+1] = a y[k] + (1 - a) x[k],    a = exp(-K_I dt).

:func:`first_order` applies it to an array (with :func:`scipy.signal.lfilter`)
and :func:`first_order_step` to one sample; the state is the next output,
so ``zi`` defaults to ``x[0]`` (the input held since forever).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy import signal

from .._validation import FloatArray, check_dt
from ..exceptions import DimensionError, InputValueError

__all__ = ["first_order", "first_order_step"]


def _filter_coefficients(gain: FloatArray, dt: float) -> tuple[FloatArray, FloatArray]:
    """Pole ``a = exp(-K_I dt)`` and input weight ``1 - a`` of every column."""
    if not np.all(np.isfinite(gain)) or np.any(gain <= 0.0):
        raise InputValueError(
            f"gain K_I must be positive and finite [1/s]; got {np.asarray(gain).tolist()}"
        )
    step = gain * check_dt(dt)
    return np.exp(-step), -np.expm1(-step)


def _broadcast(value: ArrayLike, shape: tuple[int, ...], name: str) -> FloatArray:
    try:
        return np.broadcast_to(np.asarray(value, dtype=np.float64), shape)
    except ValueError:
        raise DimensionError(
            f"{name} must be a scalar or broadcast to shape {shape}; got shape {np.shape(value)}"
        ) from None


def first_order(
    x: ArrayLike, gain: ArrayLike, dt: float, zi: ArrayLike | None = None
) -> tuple[FloatArray, FloatArray]:
    """Filter ``x`` by K_I/(s+K_I), discretised with a zero-order hold (the observer's filter).

    ``y[0] = zi`` and ``y[k+1] = a y[k] + (1 - a) x[k]`` with ``a = exp(-K_I dt)``.

    Parameters
    ----------
    x : array-like of shape (n_samples, ...)
        Input, time along axis 0 (any unit; the output has the same).
    gain : float or array-like broadcastable to ``x.shape[1:]``
        K_I of each column [1/s].
    dt : float
        Sample period [s].
    zi : array-like broadcastable to ``x.shape[1:]``, optional
        Filter state before ``x[0]``, which is also ``y[0]``. By default
        ``x[0]``: the input held since forever, no start-up transient.

    Returns
    -------
    y : ndarray of shape (n_samples, ...)
        Filtered signal.
    zf : ndarray of shape ``x.shape[1:]``
        State after the last sample, the ``zi`` of the next chunk.

    Examples
    --------
    >>> y, zf = first_order([0.0, 1.0, 1.0, 1.0], gain=10.0, dt=0.1)
    >>> np.round(y, 4)
    array([0.    , 0.    , 0.6321, 0.8647])
    >>> y2, _ = first_order([1.0, 1.0], gain=10.0, dt=0.1, zi=y[2])
    >>> bool(np.allclose(y2, y[2:]))
    True
    """
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim == 0:
        raise DimensionError("x must have a time axis: shape (n_samples, ...); got a scalar")
    trailing = arr.shape[1:]
    if zi is None:
        if arr.shape[0] == 0:
            raise DimensionError("x has no samples; pass zi to filter an empty chunk")
        zi = arr[0]
    state = _broadcast(zi, trailing, "zi").reshape(-1)
    pole, weight = _filter_coefficients(_broadcast(gain, trailing, "gain").reshape(-1), dt)
    flat = arr.reshape(arr.shape[0], -1)
    y = np.empty_like(flat)
    zf = state.copy()
    if arr.shape[0] > 0:
        # Columns with equal gain share one lfilter call; usually K_I is the same for all.
        for value in np.unique(pole):
            cols = pole == value
            b = [0.0, float(weight[cols][0])]
            y[:, cols], z = signal.lfilter(
                b, [1.0, -float(value)], flat[:, cols], axis=0, zi=state[cols][None, :]
            )
            zf[cols] = z[0]
    return y.reshape(arr.shape), zf.reshape(trailing)


def first_order_step(
    x: ArrayLike, gain: ArrayLike, dt: float, z: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """One sample of :func:`first_order`.

    Parameters
    ----------
    x : array-like
        Input at this sample.
    gain : float or array-like broadcastable to the shape of ``x``
        K_I [1/s].
    dt : float
        Sample period [s].
    z : array-like of the shape of ``x``
        State (the output at this sample), e.g. ``x`` at the first sample.

    Returns
    -------
    y : ndarray
        Output at this sample (equal to ``z``).
    z_next : ndarray
        State for the next sample.

    Examples
    --------
    >>> y, z = first_order_step(1.0, 10.0, 0.1, 0.0)
    >>> float(y), round(float(z), 4)
    (0.0, 0.6321)
    """
    arr = np.asarray(x, dtype=np.float64)
    y = _broadcast(z, arr.shape, "z").copy()
    pole, weight = _filter_coefficients(_broadcast(gain, arr.shape, "gain"), dt)
    return y, weight * arr + pole * y
