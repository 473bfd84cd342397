"""Direct transcription of the trajectory problem of eq. 3.29 on a clamped B-spline.

Each joint is a B-spline of degree 5 on shared clamped knots; the decision
variables are the control points that the boundary conditions leave free.
q(0), q̇(0) and (when fixed) q̈(0) involve only the first one, two and three
control points (likewise at the end), so the boundary conditions E c = r
are solved for those "pivot" control points: c = c₀ + S Z, with Z the free
control points (n_free, n_dof), the same S for every joint. On any time grid
q, q̇, q̈ are then affine in Z: q = (B S) Z + B c₀ with the basis matrix B.

:class:`Problem` holds that map and the variables x = [vec(Z), s]: s are the
B_Q̃ terms of the estimator's lag (:mod:`sensorless.metric._lag`), absent when
B_Q̃ is given. It evaluates OBJ[q] (trapezoid rule on the collocation grid,
times w_t) and its gradient: the exact chain rule through the basis from the
per-sample gradient of :class:`~sensorless.metric._objective.SmoothIntegrand`,
and ∂OBJ/∂B_Q̃k for s. The constraints are in :mod:`sensorless.metric._constraints`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import BSpline

from .._validation import FloatArray
from ..robots.model import RobotModel
from ._lag import LagModel
from ._objective import SmoothIntegrand

__all__ = ["DEGREE", "Boundary", "Limits", "Problem", "clamped_knots"]

#: Degree of the B-splines: q̈ is C² (jerk continuous), like the quintics it replaces.
DEGREE = 5


def clamped_knots(duration: float, n_control: int, degree: int = DEGREE) -> FloatArray:
    """Clamped, uniform knot vector on [0, duration] [s] for ``n_control`` control points."""
    interior = np.linspace(0.0, duration, n_control - degree + 1)[1:-1]
    return np.concatenate([np.zeros(degree + 1), interior, np.full(degree + 1, duration)])


def basis(knots: FloatArray, t: FloatArray, order: int) -> FloatArray:
    """``order``-th derivative of every basis function at ``t``, shape (len(t), n_control)."""
    n_control = knots.size - DEGREE - 1
    spline = BSpline(knots, np.eye(n_control), DEGREE)
    return np.asarray(spline.derivative(order)(t) if order else spline(t))


@dataclass(frozen=True)
class Boundary:
    """Boundary conditions, each of shape (n_dof,): positions [rad], velocities [rad/s],
    accelerations [rad/s²] (None: free)."""

    q_start: FloatArray
    q_end: FloatArray
    qd_start: FloatArray
    qd_end: FloatArray
    qdd_start: FloatArray | None
    qdd_end: FloatArray | None


@dataclass(frozen=True)
class Limits:
    """Joint limits of shape (n_dof,), inf where none: positions (lower, upper) [rad],
    speed [rad/s], acceleration [rad/s²], rigid-body torque [N m]."""

    lower: FloatArray
    upper: FloatArray
    velocity: FloatArray
    acceleration: FloatArray
    torque: FloatArray

    def violation(
        self, robot: RobotModel, q: FloatArray, qd: FloatArray, qdd: FloatArray
    ) -> FloatArray:
        """Per sample, the largest excess over a limit relative to it (<= 0: all hold)."""
        span = self.upper - self.lower
        excess = [
            _relative(self.lower - q, span),
            _relative(q - self.upper, span),
            _relative(np.abs(qd) - self.velocity, self.velocity),
            _relative(np.abs(qdd) - self.acceleration, self.acceleration),
        ]
        if np.isfinite(self.torque).any():
            tau = robot.inverse_dynamics(q, qd, qdd)
            excess.append(_relative(np.abs(tau) - self.torque, self.torque))
        return np.asarray(np.stack(excess).max(axis=(0, 2)))


def _relative(excess: FloatArray, scale: FloatArray) -> FloatArray:
    """``excess / scale`` where the limit is finite, −inf where there is none."""
    finite = np.isfinite(scale)
    out = np.full(excess.shape, -np.inf)
    out[:, finite] = excess[:, finite] / np.maximum(scale[finite], 1e-12)
    return out


class Problem:
    """The transcribed problem: variables, objective and gradient.

    Parameters
    ----------
    robot : RobotModel
    knots : ndarray
        Clamped knots [s].
    boundary : Boundary
    limits : Limits
    integrand : SmoothIntegrand
        L of eq. 3.30 and its gradient.
    grid : ndarray of shape (n_grid,)
        Collocation grid [s] of the quadrature of OBJ.
    time_weight : ndarray of shape (n_grid,)
        w_t on the grid.
    via : (times, positions) or None
        Via points: times (n_via,) [s] inside (0, duration), positions (n_via, n_dof) [rad].
    bq : ndarray of shape (l,)
        B_Q̃ held fixed, or, with :meth:`use_lag`, ν of the lag model.
    """

    def __init__(
        self,
        robot: RobotModel,
        knots: FloatArray,
        boundary: Boundary,
        limits: Limits,
        integrand: SmoothIntegrand,
        grid: FloatArray,
        time_weight: FloatArray,
        via: tuple[FloatArray, FloatArray] | None,
        bq: FloatArray,
    ) -> None:
        self.robot, self.knots, self.limits, self.integrand = robot, knots, limits, integrand
        self.n_dof = robot.n_dof
        self.n_control = knots.size - DEGREE - 1
        self.shift, self.free = self._eliminate(boundary)
        self.n_free = self.free.shape[1]
        self.n_z = self.n_free * self.n_dof
        self.grid = grid
        self.maps = self.affine(grid)
        # Trapezoid weights times w_t: OBJ ≈ Σ_s weight_s L_s.
        self.quadrature = time_weight * trapezoid_weights(grid)
        self.via = via
        self.bq = bq
        self.lag: LagModel | None = None
        self.lag_scale = np.ones(0)
        self.scale = 1.0
        self.n_value = 0
        self.n_gradient = 0
        self._cache: tuple[FloatArray, float, FloatArray | None] | None = None

    @property
    def n_s(self) -> int:
        """Lag variables s (l − 1 with the lag model, else 0)."""
        return 0 if self.lag is None else self.bq.size - 1

    def use_lag(self, lag: LagModel, scale: FloatArray) -> None:
        """Make B_Q̃ = ν + [s; 0] with s the lag variables (``self.bq`` must hold ν);
        ``scale`` (l − 1,) is a typical size of each s_k, for the constraints."""
        self.lag = lag
        self.lag_scale = scale

    # ------------------------------------------------------------------ variables
    def _eliminate(self, boundary: Boundary) -> tuple[FloatArray, FloatArray]:
        """c = shift + free @ Z: solve E c = r for the pivot control points."""
        ends = np.array([0.0, self.knots[-1]])
        rows: list[FloatArray] = []
        values: list[FloatArray] = []
        conditions = [
            (0, (boundary.q_start, boundary.qd_start, boundary.qdd_start)),
            (1, (boundary.q_end, boundary.qd_end, boundary.qdd_end)),
        ]
        pivots: list[int] = []
        for end, given in conditions:
            for order, value in enumerate(given):
                if value is None:
                    continue
                rows.append(basis(self.knots, ends[end : end + 1], order)[0])
                values.append(value)
                pivots.append(order if end == 0 else self.n_control - 1 - order)
        matrix, right = np.array(rows), np.array(values)
        free = np.setdiff1d(np.arange(self.n_control), pivots)
        solve = np.linalg.solve(matrix[:, pivots], np.hstack([right, -matrix[:, free]]))
        shift = np.zeros((self.n_control, self.n_dof))
        shift[pivots] = solve[:, : self.n_dof]
        selection = np.zeros((self.n_control, free.size))
        selection[pivots] = solve[:, self.n_dof :]
        selection[free, np.arange(free.size)] = 1.0
        return shift, selection

    def control_points(self, x: FloatArray) -> FloatArray:
        """Control points (n_control, n_dof) [rad] of the variables ``x``."""
        return np.asarray(self.shift + self.free @ self.z_of(x))

    def z_of(self, x: FloatArray) -> FloatArray:
        """The free control points Z (n_free, n_dof) [rad] in ``x``."""
        return x[: self.n_z].reshape(self.n_free, self.n_dof)

    def bq_of(self, x: FloatArray) -> FloatArray:
        """B_Q̃ (l,) at ``x``: fixed, or ν + [s; 0]."""
        if self.lag is None:
            return self.bq
        return np.asarray(self.bq + np.append(x[self.n_z :], 0.0))

    def start(self, q: FloatArray, t: FloatArray) -> FloatArray:
        """Variables of the spline closest (least squares) to positions ``q`` at ``t``,
        with s at the lag of that spline."""
        design = basis(self.knots, t, 0)
        z, *_ = np.linalg.lstsq(design @ self.free, q - design @ self.shift, rcond=None)
        x = np.asarray(z.ravel())
        if self.lag is None:
            return x
        return np.concatenate([x, self.largest_lag(x)])

    def largest_lag(self, x: FloatArray) -> FloatArray:
        """max over draws and samples of |e_k| (l − 1,): B_Q̃ of Table 3.1 at ``x``."""
        assert self.lag is not None  # only with the lag model
        return np.asarray(np.abs(self.lag.errors(x[: self.n_z])).max(axis=(0, 1)))

    def affine(self, t: FloatArray) -> list[tuple[FloatArray, FloatArray]]:
        """(G, offset) per derivative order: q⁽ᵒ⁾(t) = G Z + offset."""
        out = []
        for order in range(3):
            design = basis(self.knots, t, order)
            out.append((design @ self.free, design @ self.shift))
        return out

    def states(
        self, x: FloatArray, maps: list[tuple[FloatArray, FloatArray]] | None = None
    ) -> list[FloatArray]:
        """q, q̇, q̈ of shape (n_t, n_dof) on the grid of ``maps`` (default the collocation grid)."""
        zz = self.z_of(x)
        return [g @ zz + offset for g, offset in maps or self.maps]

    # ------------------------------------------------------------------ objective
    def set_epsilon(self, epsilon: float) -> None:
        """Use ε of eq. 3.30 from now on."""
        self.integrand.epsilon = float(epsilon)
        self._cache = None

    def _evaluate(self, x: FloatArray, with_gradient: bool) -> tuple[float, FloatArray | None]:
        cache = self._cache
        if cache is not None and np.array_equal(cache[0], x):
            if not with_gradient or cache[2] is not None:
                return cache[1], cache[2]
        q, qd, qdd = self.states(x)
        value, local, parts = self.integrand(q, qd, qdd, with_gradient, self.bq_of(x))
        total = float(self.quadrature @ value)
        gradient: FloatArray | None = None
        if with_gradient:
            self.n_gradient += 1
            weighted = local * self.quadrature[:, None, None]
            per_point = np.zeros((self.n_free, self.n_dof))
            for order, (g, _) in enumerate(self.maps):
                per_point += g.T @ weighted[:, order]
            lag = (self.quadrature @ parts)[: self.n_s]
            gradient = np.concatenate([per_point.ravel(), lag])
        else:
            self.n_value += 1
        self._cache = (x.copy(), total, gradient)
        return total, gradient

    def objective(self, x: FloatArray) -> float:
        """OBJ (eq. 3.30) on the grid, divided by :attr:`scale`."""
        return self._evaluate(x, False)[0] / self.scale

    def gradient(self, x: FloatArray) -> FloatArray:
        """Gradient of :meth:`objective`."""
        gradient = self._evaluate(x, True)[1]
        assert gradient is not None  # computed with_gradient
        return np.asarray(gradient / self.scale)

    def raw_objective(self, x: FloatArray) -> float:
        """OBJ (eq. 3.30) on the grid [N m s]."""
        return self._evaluate(x, False)[0]


def trapezoid_weights(t: FloatArray) -> FloatArray:
    """Weights w with Σ w_s f(t_s) = the trapezoid rule of f on ``t`` [s]."""
    steps = np.diff(t)
    weights = np.zeros_like(t)
    weights[:-1] += 0.5 * steps
    weights[1:] += 0.5 * steps
    return weights
