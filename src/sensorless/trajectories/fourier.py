"""Finite Fourier series excitation trajectories (Swevers et al. 1997).

The usual parametrisation of excitation trajectories for identification;
:mod:`sensorless.identification.excitation` optimises its coefficients.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_float_array, check_dt, check_finite
from ..exceptions import DimensionError, InputTypeError, InputValueError
from .base import Evaluation, Trajectory, _with_shape

__all__ = ["FourierSeries"]


def _check_frequency(value: float) -> float:
    """Return ``base_frequency`` [Hz] as a float after checking it is positive and finite."""
    try:
        frequency = float(value)
    except (TypeError, ValueError):
        frequency = np.nan
    if not (np.isfinite(frequency) and frequency > 0.0):
        raise InputValueError(
            f"base_frequency must be a positive, finite number [Hz]; got {value!r}"
        )
    return frequency


class FourierSeries(Trajectory):
    """Finite Fourier series excitation trajectory of Swevers et al. (1997).

    .. math::

        q_j(t) = q_{0,j} + \\sum_{l=1}^{N} \\frac{a_{lj}}{\\omega_f l} \\sin(\\omega_f l t)
                 - \\frac{b_{lj}}{\\omega_f l} \\cos(\\omega_f l t),
        \\qquad \\omega_f = 2 \\pi f,

    with analytic velocity and acceleration. The motion is periodic with
    period ``1 / base_frequency``. Note that ``q(0) = q0 - Σ_l b_l / (ω_f l)``.

    Parameters
    ----------
    base_frequency : float
        Fundamental frequency ``f`` [Hz], positive.
    a, b : array-like of shape (n_harmonics, n_dof)
        Sine and cosine coefficients [rad/s]; row ``l - 1`` is harmonic ``l``.
    q0 : array-like of shape (n_dof,)
        Offset of the joint positions [rad].
    duration : float, optional
        Duration [s]; one period ``1 / base_frequency`` by default.

    References
    ----------
    J. Swevers, C. Ganseman, D. B. Tükel, J. De Schutter, H. Van Brussel,
    "Optimal robot excitation and identification", IEEE Trans. Robotics and
    Automation 13(5), 1997.

    Examples
    --------
    >>> traj = FourierSeries(0.5, a=[[1.0]], b=[[0.0]], q0=[0.0])
    >>> q, qd, qdd = traj.evaluate(0.0)
    >>> float(qd[0])
    1.0
    """

    def __init__(
        self,
        base_frequency: float,
        a: ArrayLike,
        b: ArrayLike,
        q0: ArrayLike,
        duration: float | None = None,
    ) -> None:
        self.base_frequency = _check_frequency(base_frequency)
        a_arr = as_float_array(a, "a", "(n_harmonics, n_dof)")
        if a_arr.ndim != 2 or 0 in a_arr.shape:
            raise DimensionError(
                f"a must have shape (n_harmonics, n_dof) with at least one harmonic and joint; "
                f"got shape {a_arr.shape}"
            )
        check_finite(a_arr, "a")
        b_arr = _with_shape(b, "b", a_arr.shape, "the shape of a (n_harmonics, n_dof)")
        q0_arr = _with_shape(q0, "q0", (a_arr.shape[1],), "shape (n_dof,)")
        for arr in (a_arr, b_arr, q0_arr):
            arr.setflags(write=False)
        self.a = a_arr
        self.b = b_arr
        self.q0 = q0_arr
        period = 1.0 / self.base_frequency
        self._duration = period if duration is None else check_dt(duration, "duration")

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self.a.shape[1])

    @property
    def duration(self) -> float:
        """Duration of the trajectory [s]."""
        return self._duration

    @property
    def n_harmonics(self) -> int:
        """Number of harmonics ``N``."""
        return int(self.a.shape[0])

    def to_dict(self) -> dict[str, Any]:
        """The series as plain Python values, SI units, for a YAML or JSON file.

        Returns
        -------
        dict
            ``{"type": "fourier", "base_frequency": f [Hz], "duration": T [s],
            "offset": q0 [rad] (n_dof list), "a": [rad/s] and "b": [rad/s]
            (n_harmonics lists of n_dof)}``; :meth:`from_dict` rebuilds the
            identical series (floats are written with all their digits).

        Examples
        --------
        >>> FourierSeries(0.5, a=[[1.0]], b=[[0.0]], q0=[0.2]).to_dict()["offset"]
        [0.2]
        """
        return {
            "type": "fourier",
            "base_frequency": float(self.base_frequency),
            "duration": float(self.duration),
            "offset": [float(v) for v in self.q0],
            "a": [[float(v) for v in row] for row in self.a],
            "b": [[float(v) for v in row] for row in self.b],
        }

    @classmethod
    def from_dict(cls, spec: Mapping[str, Any]) -> FourierSeries:
        """Build from a specification such as :meth:`to_dict` writes.

        Parameters
        ----------
        spec : mapping
            Keys ``base_frequency`` [Hz], ``offset`` [rad] of length n_dof,
            ``a`` and ``b`` [rad/s] of shape (n_harmonics, n_dof); optional
            ``duration`` [s] (one period by default) and ``type``, which must
            be ``"fourier"`` when present.

        Returns
        -------
        FourierSeries

        Raises
        ------
        InputTypeError
            If ``spec`` is not a mapping or has keys other than those above.
        InputValueError
            If a required key is missing or ``type`` is not ``"fourier"``, or
            for the checks of the constructor.

        Examples
        --------
        >>> spec = {"type": "fourier", "base_frequency": 0.5, "offset": [0.0],
        ...         "a": [[1.0]], "b": [[0.0]]}
        >>> FourierSeries.from_dict(spec).duration
        2.0
        """
        required = ("base_frequency", "offset", "a", "b")
        optional = ("type", "duration")
        if not isinstance(spec, Mapping):
            raise InputTypeError(
                f"a Fourier trajectory specification must be a mapping with keys "
                f"{list(required)}; got {type(spec).__name__}"
            )
        unknown = sorted(str(key) for key in spec if key not in required + optional)
        if unknown:
            raise InputTypeError(
                f"unknown keys {unknown} in a Fourier trajectory specification; valid keys: "
                f"{list(required + optional)}"
            )
        missing = [key for key in required if key not in spec]
        if missing:
            raise InputValueError(
                f"a Fourier trajectory specification needs keys {list(required)}; missing {missing}"
            )
        kind = spec.get("type", "fourier")
        if kind != "fourier":
            raise InputValueError(
                f"type must be 'fourier' for a FourierSeries specification; got {kind!r}"
            )
        return cls(
            spec["base_frequency"], spec["a"], spec["b"], spec["offset"], spec.get("duration")
        )

    def _evaluate_inside(self, t: FloatArray) -> Evaluation:
        omega = 2.0 * np.pi * self.base_frequency * np.arange(1, self.n_harmonics + 1)
        phase = np.outer(t, omega)
        sin, cos = np.sin(phase), np.cos(phase)
        q = self.q0 + sin @ (self.a / omega[:, None]) - cos @ (self.b / omega[:, None])
        qd = cos @ self.a + sin @ self.b
        qdd = -sin @ (self.a * omega[:, None]) + cos @ (self.b * omega[:, None])
        return q, qd, qdd
