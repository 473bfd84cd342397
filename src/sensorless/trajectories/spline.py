"""B-spline trajectories: one spline of one degree per joint on shared knots.

The form of the trajectories that :func:`sensorless.metric.optimize_trajectory`
plans (thesis § 3.4): q(t) = Σ_i c_i N_{i,k}(t) with clamped knots on
``[0, duration]``, so that q(0) = c_0 and q(duration) = c_last, and q̇, q̈
follow from the derivative splines (:class:`scipy.interpolate.BSpline`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.interpolate import BSpline

from .._validation import FloatArray, as_float_array, check_finite
from ..exceptions import DimensionError, InputTypeError, InputValueError
from .base import Evaluation, Trajectory, _check_radians, _vector

__all__ = ["SplineTrajectory"]

_KEYS = ("type", "degree", "knots", "control_points")


class SplineTrajectory(Trajectory):
    """Joint trajectory q(t) = Σ_i c_i N_{i,k}(t), a B-spline of degree k per joint.

    Parameters
    ----------
    knots : array-like of shape (n_control + degree + 1,)
        Knot vector [s]: non-decreasing, clamped (the first ``degree + 1``
        knots equal 0, the last ``degree + 1`` equal the duration > 0).
    control_points : array-like of shape (n_control, n_dof)
        Control points c_i [rad]; q(0) = c_0 and q(duration) = c_last.
    degree : int, default 5
        Degree k of the spline, >= 1; q̈ is continuous for k >= 3.

    Raises
    ------
    DimensionError
        If the shapes do not fit together.
    InputValueError
        If a value is not finite, the knots are not clamped and non-decreasing,
        or a control point looks like degrees (|c| > 2π).

    Examples
    --------
    >>> traj = SplineTrajectory([0, 0, 0, 0, 2, 2, 2, 2], [[0.0], [0.0], [1.0], [1.0]], degree=3)
    >>> q, qd, qdd = traj.evaluate(1.0)
    >>> float(q[0]), float(qd[0])
    (0.5, 0.75)
    >>> SplineTrajectory.from_dict(traj.to_dict()).duration
    2.0
    """

    def __init__(self, knots: ArrayLike, control_points: ArrayLike, degree: int = 5) -> None:
        if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or degree < 1:
            raise InputValueError(f"degree must be an integer >= 1; got {degree!r}")
        k = int(degree)
        points = as_float_array(control_points, "control_points", "(n_control, n_dof)")
        if points.ndim != 2 or points.shape[0] < k + 1 or points.shape[1] < 1:
            raise DimensionError(
                f"control_points must have shape (n_control, n_dof) with n_control >= degree + 1 "
                f"= {k + 1} and n_dof >= 1; got shape {points.shape}"
            )
        check_finite(points, "control_points")
        _check_radians(points, "control_points")
        n_knots = points.shape[0] + k + 1
        t = _vector(knots, "knots", "n_control + degree + 1", n_knots, f"{n_knots} knots [s]")
        if t.size != n_knots:
            raise DimensionError(
                f"knots must have n_control + degree + 1 = {n_knots} entries for "
                f"{points.shape[0]} control points of degree {k}; got {t.size}"
            )
        if (np.diff(t) < 0).any() or t[0] != 0.0 or t[-1] <= 0.0:
            raise InputValueError(
                f"knots must be non-decreasing from 0 to a duration > 0 [s]; got {t.tolist()}"
            )
        if (t[: k + 1] != 0.0).any() or (t[-k - 1 :] != t[-1]).any():
            raise InputValueError(
                f"knots must be clamped: the first and last degree + 1 = {k + 1} knots equal 0 "
                f"and the duration; got {t.tolist()}"
            )
        for arr in (t, points):
            arr.setflags(write=False)
        self._knots, self._points, self._degree = t, points, k
        self._q = BSpline(t, points, k)
        self._qd = self._q.derivative(1)
        self._qdd = self._q.derivative(2) if k >= 2 else None

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self._points.shape[1])

    @property
    def duration(self) -> float:
        """Last knot [s]."""
        return float(self._knots[-1])

    @property
    def knots(self) -> FloatArray:
        """Knot vector [s], shape (n_control + degree + 1,); read-only."""
        return self._knots

    @property
    def control_points(self) -> FloatArray:
        """Control points [rad], shape (n_control, n_dof); read-only."""
        return self._points

    @property
    def degree(self) -> int:
        """Degree of the spline."""
        return self._degree

    def _evaluate_inside(self, t: FloatArray) -> Evaluation:
        q = np.asarray(self._q(t), dtype=np.float64)
        qd = np.asarray(self._qd(t), dtype=np.float64)
        qdd = np.zeros_like(q) if self._qdd is None else np.asarray(self._qdd(t), dtype=np.float64)
        return q, qd, qdd

    def to_dict(self) -> dict[str, Any]:
        """The spline as plain Python values, SI units, for a YAML or JSON file.

        Returns
        -------
        dict
            ``{"type": "bspline", "degree": k, "knots": [s], "control_points":
            [rad] (n_control lists of n_dof)}``; :meth:`from_dict` rebuilds the
            identical trajectory (floats keep all their digits).
        """
        return {
            "type": "bspline",
            "degree": self._degree,
            "knots": [float(v) for v in self._knots],
            "control_points": [[float(v) for v in row] for row in self._points],
        }

    @classmethod
    def from_dict(cls, spec: Mapping[str, Any]) -> SplineTrajectory:
        """Build from a specification such as :meth:`to_dict` writes.

        Parameters
        ----------
        spec : mapping
            Keys ``knots`` [s] and ``control_points`` [rad]; optional
            ``degree`` (default 5) and ``type``, which must be ``"bspline"``.

        Raises
        ------
        InputTypeError
            If ``spec`` is not a mapping or has other keys.
        InputValueError
            If a required key is missing, ``type`` is not ``"bspline"``, or
            for the checks of the constructor.
        """
        if not isinstance(spec, Mapping):
            raise InputTypeError(
                f"a B-spline trajectory specification must be a mapping with keys {list(_KEYS)}; "
                f"got {type(spec).__name__}"
            )
        unknown = sorted(str(key) for key in spec if key not in _KEYS)
        if unknown:
            raise InputTypeError(
                f"unknown keys {unknown} in a B-spline trajectory specification; valid keys: "
                f"{list(_KEYS)}"
            )
        missing = [key for key in ("knots", "control_points") if key not in spec]
        if missing:
            raise InputValueError(
                f"a B-spline trajectory specification needs keys ['knots', 'control_points']; "
                f"missing {missing}"
            )
        if spec.get("type", "bspline") != "bspline":
            raise InputValueError(
                f"type must be 'bspline' for a SplineTrajectory specification; got {spec['type']!r}"
            )
        return cls(spec["knots"], spec["control_points"], spec.get("degree", 5))
