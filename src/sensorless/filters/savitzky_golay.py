"""Savitzky–Golay smoothing and differentiation of a whole record (offline only)."""

from __future__ import annotations

from numpy.typing import ArrayLike
from scipy import signal

from .._validation import as_joint_array, check_dt, check_int
from ..exceptions import DimensionError, InputValueError
from ._derivatives import Derivatives, n_dof_of

__all__ = ["SavitzkyGolay"]


class SavitzkyGolay:
    """Savitzky–Golay smoothing and differentiation: non-causal, OFFLINE only.

    Fits a polynomial of degree ``polyorder`` to each window of ``window``
    samples centred on the sample (:func:`scipy.signal.savgol_filter`,
    ``mode='interp'``: the first and last half-windows use the fit of the
    first and last full window). It has no delay and is exact for polynomials
    up to ``polyorder``, but it needs future samples: there is no
    ``initial_state``/``step``, and it is not a :class:`CausalEstimator`.
    Use it to make reference derivatives from a recorded log.

    Parameters
    ----------
    dt : float
        Sample period [s].
    window : int
        Window length [samples]; odd and > ``polyorder``.
    polyorder : int
        Degree of the fitted polynomial, >= 2 (the acceleration of a lower
        degree fit is identically zero). Default 3.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(50)[:, None] * 0.01
    >>> y = SavitzkyGolay(0.01, window=11).filter(t**3)
    >>> bool(np.allclose(y.velocity, 3 * t**2)), bool(np.allclose(y.acceleration, 6 * t))
    (True, True)
    """

    __slots__ = ("_dt", "_polyorder", "_window")

    def __init__(self, dt: float, window: int, polyorder: int = 3) -> None:
        self._dt = check_dt(dt)
        self._polyorder = check_int(polyorder, "polyorder", 2, "SavitzkyGolay")
        self._window = check_int(window, "window", self._polyorder + 1, "SavitzkyGolay")
        if self._window % 2 == 0:
            raise InputValueError(
                f"SavitzkyGolay: window must be an odd number of samples > polyorder "
                f"({self._polyorder}); got {window!r}"
            )

    @property
    def dt(self) -> float:
        """Sample period [s]."""
        return self._dt

    @property
    def window(self) -> int:
        """Window length [samples]."""
        return self._window

    @property
    def polyorder(self) -> int:
        """Degree of the fitted polynomial."""
        return self._polyorder

    def filter(self, x: ArrayLike) -> Derivatives:
        """Smooth and differentiate a whole record.

        Parameters
        ----------
        x : array-like of shape (n_samples, n_dof)
            Joint positions [rad], time along axis 0, ``n_samples >= window``.

        Returns
        -------
        Derivatives
            Smoothed position [rad], velocity [rad/s], acceleration [rad/s²],
            each of shape (n_samples, n_dof).
        """
        n_dof = n_dof_of(x, "x", ndim=2)
        arr, _ = as_joint_array(x, n_dof, "x")
        if arr.shape[0] < self._window:
            raise DimensionError(
                f"SavitzkyGolay(window={self._window}) needs at least {self._window} samples; "
                f"x has {arr.shape[0]}"
            )
        return Derivatives(
            *(
                signal.savgol_filter(
                    arr,
                    self._window,
                    self._polyorder,
                    deriv=deriv,
                    delta=self._dt,
                    axis=0,
                    mode="interp",
                )
                for deriv in range(3)
            )
        )

    def __repr__(self) -> str:
        return f"SavitzkyGolay(dt={self._dt!r}, window={self._window}, polyorder={self._polyorder})"
