"""One sample of the residual → the contact link, point and force (the isolator's core).

The model (eq. 5.34): a force F [N] on link k at a point c of its surface
produces the external joint torque

    τ_c = J_c(q)ᵀ F,    J_c = J_lin − [c − o_k]ₓ J_ang              (1)

with J_lin, J_ang the translational and rotational rows of joint k's
Jacobian at its origin o_k in base-frame axes (Pinocchio's
``LOCAL_WORLD_ALIGNED``); columns beyond k are zero, so τ_c has zeros beyond
joint k. The residual r̂ follows τ_c through K_I/(s+K_I) (eq. 3.6) plus the
model error, which the threshold's bounds [lower, upper] contain in free
motion. Per sample:

1. joints whose residual is outside its band are *significant*; the last
   one, j*, bounds the link from below (k >= j*);
2. the corrected residual y = W (r̂ − m), with m the band's midpoint (the
   model error the threshold expects) and W = diag(1/δ), δ the band's
   half-width, is fitted on every candidate point of every link k >= j*:
   F̂ = argmin ‖W (J_cᵀ F) − y‖ (3-D force; the minimum-norm one where
   fewer than 3 joints are in front of the point); joints beyond k count
   with their whole residual, which is how the residual's direction
   narrows the link;
3. on each link the candidate with the smallest residual norm wins among
   those whose force pushes into the surface (F̂·n <= 0, n outward) — a
   line of action crosses a closed surface twice, and only the entry point
   pushes; Gauss–Newton then moves it on the surface (tangent-plane steps,
   projected back), which makes the point exact when it is identifiable: at
   least 5 joints in front of it (3 force components and 2 surface
   coordinates) and a Jacobian of full rank there. The misfit is not convex
   over a surface, so up to three separated candidates are refined on the
   links up to the one that wins;
4. the link has the least score, its misfit plus ``link_tolerance`` (in
   squared band half-widths) for every number its fit adjusts, min(k, 5)
   (3 force components and 2 surface coordinates, at most one per joint in
   front of the point) — Akaike's criterion for errors of variance
   tolerance/2. A link with fewer joints wins unless the joints beyond it
   leave their bands; among links with 5 joints or more in front, all of
   whose fits adjust 5 numbers, the misfit decides. Every link within the
   tolerance of the least score is reported (``consistent_links``): a force
   through the axes of the joints between two links gives both nearly the
   same residual, and their forces can differ a lot.

Uncertainty of F̂ (worst case, not statistics): with P = pinv(W J_cᵀ) W and
the free-motion error of joint j within ±δ_j of the midpoint,
|ΔF_i| <= Σ_j |P_ij| δ_j, and ‖ΔF‖ <= ‖(Σ_j |P_ij| δ_j)_i‖; the point is
taken as exact there, and the observer's lag (the residual is the filtered
τ_c) is not included. A force direction the joints do not see (rank of
W J_cᵀ below 3, e.g. a link with fewer than 3 joints before it) has an
infinite bound.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .._validation import FloatArray
from ..robots.model import RobotModel
from ._linalg import Link, force_bound, least_squares, lsq, pushes, skew, tangents
from .results import ContactEstimate
from .surfaces import Surface

__all__ = ["Settings", "Solver"]

_MAX_ITER = 30
_STARTS = 3
_EXACT = 1e-20  # misfit² / ‖y‖² below which a fit is exact (rounding)
_STEP_TOL = 1e-12  # [m]


@dataclass(frozen=True)
class Settings:
    """Options of the fit (see :class:`~sensorless.isolation.Isolator`)."""

    require_push: bool
    center: bool
    refine: bool
    band_floor: float
    limits: tuple[float, float]
    transient_factor: float
    link_tolerance: float
    search: str = "all"


@dataclass
class _Fit:
    """Best point of one link."""

    link: int
    point: FloatArray  # link frame [m]
    normal: FloatArray  # link frame
    force: FloatArray
    cost: float
    pushing: bool
    identifiable: bool = False


class Solver:
    """The per-sample fit on checked arrays; owns its Pinocchio scratch data."""

    def __init__(self, robot: RobotModel, surfaces: dict[int, Surface], settings: Settings) -> None:
        self.robot = robot
        self.surfaces = surfaces
        self.settings = settings
        self._model = robot.pinocchio_model
        self._data = self._model.createData()
        # [c]ₓ of every candidate, once: B[p] = W (J_linᵀ + J_angᵀ R [c_p]ₓ Rᵀ), eq. (1)
        self._skews = {k: skew(s.points) for k, s in surfaces.items()}

    def weights(
        self, lower: FloatArray, upper: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Band midpoint [N m], half-width δ [N m], weight 1/max(δ, floor) [1/(N m)] (0 for inf)."""
        finite = np.isfinite(lower) & np.isfinite(upper)
        half = np.where(finite, 0.5 * (upper - lower), np.inf)
        both = np.where(finite, lower, 0.0) + np.where(finite, upper, 0.0)
        mid = np.where(finite & self.settings.center, 0.5 * both, 0.0)
        floored = np.maximum(np.where(finite, half, 1.0), self.settings.band_floor)
        return mid, half, np.where(finite, 1.0 / floored, 0.0)

    def estimate(
        self,
        q: FloatArray,
        r: FloatArray,
        lower: FloatArray,
        upper: FloatArray,
        t: float,
        least_link: int = 0,
    ) -> ContactEstimate | None:
        """Estimate of one checked sample; None if no joint is significant and no ``least_link``."""
        significant = np.flatnonzero((r > upper) | (r < lower))
        last = int(significant[-1]) + 1 if significant.size else 0
        floor = last or least_link
        if floor == 0:
            return None
        mid, half, weight = self.weights(lower, upper)
        y = weight * (r - mid)
        pin.computeJointJacobians(self._model, self._data, q)
        fits = self._fits(floor, y, weight)
        consistent = tuple(f.link for f in self._consistent(fits))
        return self._estimate_of(self._choose(fits), y, weight, half, t, last, consistent)

    def _fits(self, floor: int, y: FloatArray, weight: FloatArray) -> list[_Fit]:
        """Best fit of each link from ``floor`` on, each refined from one start, and from
        every start for the links up to the winner (one refinement can stop in a local
        minimum of the misfit).

        With ``search="pruned"`` the links stop where none further out can win: link
        j's score is at least its tail Σ_{i>j} y_i² (the joints it cannot move) plus
        its penalty.
        """
        n = self.robot.n_dof
        tails = np.append(np.cumsum((y**2)[::-1])[::-1][1:], 0.0)  # tails[j - 1]: link j
        least = [float(tails[j - 1]) + self._penalty(j) for j in range(1, n + 1)]
        starts: dict[int, list[_Fit]] = {}
        fits: dict[int, _Fit] = {}
        for k in range(floor, n + 1):
            starts[k] = self._candidates(k, y, weight)
            fits[k] = self._refined(starts[k], k, y, weight, 1)
            if self.settings.search == "pruned" and k < n:
                best = self._choose(list(fits.values()))
                pushing = best.pushing or not self.settings.require_push
                if pushing and self._score(best) <= min(least[k:]):
                    break
        if self.settings.refine and _STARTS > 1:
            for k in range(floor, self._choose(list(fits.values())).link + 1):
                fits[k] = self._refined(starts[k], k, y, weight, _STARTS, fits[k])
        return list(fits.values())

    def _penalty(self, link: int) -> float:
        """``link_tolerance`` per number a fit on ``link`` adjusts: min(k, 5) (F, 2 coordinates)."""
        return self.settings.link_tolerance * min(link, 5)

    def _score(self, fit: _Fit) -> float:
        return fit.cost + self._penalty(fit.link)

    def _pool(self, fits: list[_Fit]) -> list[_Fit]:
        """The fits that push into the surface when the settings require it (all if none does)."""
        pushing = [f for f in fits if f.pushing] if self.settings.require_push else fits
        return pushing or fits

    def _choose(self, fits: list[_Fit]) -> _Fit:
        """The fit of least score (misfit + penalty); the lower link on a tie."""
        return min(self._pool(fits), key=lambda f: (self._score(f), f.link))

    def _consistent(self, fits: list[_Fit]) -> list[_Fit]:
        """The fits whose score is within ``link_tolerance`` of the least, by link."""
        pool = self._pool(fits)
        best = min(self._score(f) for f in pool)
        return [f for f in pool if self._score(f) <= best + self.settings.link_tolerance]

    # ------------------------------------------------------------------ one link

    def _link(self, k: int) -> Link:
        """Kinematics of link k at the sample of the last computeJointJacobians."""
        jac = pin.getJointJacobian(
            self._model, self._data, k, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        pose = self._data.oMi[k]
        return Link(
            np.asarray(pose.rotation), np.asarray(pose.translation), jac[:3, :k].T, jac[3:, :k].T
        )

    def _candidates(self, k: int, y: FloatArray, weight: FloatArray) -> list[_Fit]:
        """Fits at up to :data:`_STARTS` separated candidates of link k, best first."""
        link = self._link(k)
        surface = self.surfaces[k]
        w = weight[:k]
        yk = y[:k]
        tail = float(y[k:] @ y[k:])
        # J_angᵀ [R c]ₓ = (J_angᵀ R) [c]ₓ Rᵀ: the candidates' skews are computed once.
        arm = (link.ang @ link.rotation) @ self._skews[k] @ link.rotation.T
        b = w[:, None] * (link.lin + arm)
        force = least_squares(b, yk)
        misfit = np.einsum("pij,pj->pi", b, force) - yk
        cost = np.einsum("pi,pi->p", misfit, misfit) + tail
        push = np.einsum("pi,pi->p", force, surface.normals @ link.rotation.T)
        pushing = push <= 1e-9 * np.linalg.norm(force, axis=1)
        choice = cost
        if self.settings.require_push and pushing.any():
            choice = np.where(pushing, cost, np.inf)
        return [
            _Fit(
                k, surface.points[p], surface.normals[p], force[p], float(cost[p]), bool(pushing[p])
            )
            for p in _starts(choice, surface.points, 3.0 * surface.spacing)
        ]

    def _refined(
        self,
        starts: list[_Fit],
        k: int,
        y: FloatArray,
        weight: FloatArray,
        count: int,
        done: _Fit | None = None,
    ) -> _Fit:
        """Best of the first ``count`` starts of link k, refined; ``done`` is the first, refined."""
        if not self.settings.refine:
            return starts[0]
        link = self._link(k)
        surface = self.surfaces[k]
        w, yk = weight[:k], y[:k]
        tail = float(y[k:] @ y[k:])
        fits = [done] if done is not None else []
        for start in starts[len(fits) : count]:
            if fits and fits[-1].cost - tail <= _EXACT * (yk @ yk):
                break  # an exact fit: no other start can do better
            fits.append(self._refine(start, surface, link, w, yk, tail))
        return min(fits, key=lambda f: (self.settings.require_push and not f.pushing, f.cost))

    def _refine(
        self, fit: _Fit, surface: Surface, link: Link, w: FloatArray, yk: FloatArray, tail: float
    ) -> _Fit:
        """Gauss–Newton on the surface from the best candidate (see the module docstring)."""
        keep_push = self.settings.require_push and fit.pushing
        c, normal = fit.point, fit.normal
        b, force, misfit = link.solve(c, w, yk)
        jac = link.jacobian(b, force, normal, w)
        for _ in range(_MAX_ITER):
            # With fewer than 5 joints the step is the least-norm one: the point slides
            # along the set of exact fits, from the candidate, no further than it must.
            step = lsq(jac, yk - b @ force)
            move = step[3:] @ tangents(normal)
            for alpha in (1.0, 0.5, 0.25, 0.125):
                point, nrm = surface.project((c + alpha * move)[None])
                trial = link.solve(point[0], w, yk)
                inward = pushes(trial[1], link.rotation @ nrm[0])
                if trial[2] <= misfit and (inward or not keep_push):
                    break
            else:
                break
            moved = float(np.linalg.norm(point[0] - c))
            gain = misfit - trial[2]
            c, normal = point[0], nrm[0]
            b, force, misfit = trial
            jac = link.jacobian(b, force, normal, w)
            if moved < _STEP_TOL or gain <= 1e-12 * misfit or misfit <= _EXACT * (yk @ yk):
                break
        singular = np.linalg.svd(jac, compute_uv=False)
        identifiable = jac.shape[0] >= 5 and bool(singular[-1] > 1e-8 * singular[0])
        pushing = pushes(force, link.rotation @ normal)
        return _Fit(fit.link, c, normal, force, misfit + tail, pushing, identifiable)

    # ------------------------------------------------------------------ result

    def _estimate_of(
        self,
        fit: _Fit,
        y: FloatArray,
        weight: FloatArray,
        half: FloatArray,
        t: float,
        last: int,
        consistent: tuple[int, ...],
    ) -> ContactEstimate:
        k = fit.link
        link = self._link(k)
        b, force, _ = link.solve(fit.point, weight[:k], y[:k])
        bound, rank = force_bound(b, weight[:k], half[:k])
        magnitude = float(np.linalg.norm(force))
        low, high = self.settings.limits
        return ContactEstimate(
            t=t,
            link=k,
            point_world=link.origin + link.rotation @ fit.point,
            point_link=fit.point.copy(),
            normal_world=link.rotation @ fit.normal,
            force=force,
            force_bound=bound,
            magnitude=magnitude,
            magnitude_bound=float(np.linalg.norm(bound)),
            cost=fit.cost,
            force_rank=rank,
            point_identifiable=fit.identifiable,
            pushing=fit.pushing,
            last_significant_joint=last,
            consistent_links=consistent,
            exceeds_quasi_static_min=magnitude > low,
            exceeds_quasi_static_max=magnitude > high,
            exceeds_transient_min=magnitude > self.settings.transient_factor * low,
        )


def _starts(cost: FloatArray, points: FloatArray, apart: float) -> list[int]:
    """Up to :data:`_STARTS` candidates of least cost, each ``apart`` [m] from those before.

    The misfit is not convex over a surface: refining a few separated good
    candidates finds the best fit where refining the best one alone may stop
    in a local minimum.
    """
    order = np.argsort(cost, kind="stable")
    order = order[np.isfinite(cost[order])]
    chosen: list[int] = []
    while order.size and len(chosen) < _STARTS:
        p = int(order[0])
        chosen.append(p)
        order = order[np.sum((points[order] - points[p]) ** 2, axis=1) >= apart**2]
    return chosen or [int(np.argmin(cost))]
