"""The least-squares retrieval of consistent standard parameters: residuals and passes.

:class:`Problem` holds the scaled residuals (a)–(c) of
:mod:`sensorless.identification.consistent` in the variables of
:class:`~sensorless.identification._log_cholesky.Layout`, and runs the passes
of decreasing prior weight with the final least-norm correction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.optimize
from numpy.typing import NDArray

from .._validation import FloatArray
from ..robots.base_parameters import BaseParameters
from ..robots.model import N_LINK_PARAMETERS
from ..simulation.model_error import physically_consistent_links, pseudo_inertia
from ._log_cholesky import ARMATURE, TINY, Layout

__all__ = ["Problem"]

_ZERO_WEIGHT = 1e3
_SCALE_FLOOR = 1e-6  # of max|θ|, for base parameters near zero
# In residual (a), base parameters near zero are weighted as this fraction of
# their size with the prior's magnitudes: weighting a zero target by the floor
# above would make the problem too stiff for Levenberg–Marquardt.
_TYPICAL_FRACTION = 1e-2
_KIND_FLOOR = 1e-3  # of the robot's largest prior scale of the same kind
# Per pass: stop when the cost falls by less than this fraction (the next pass,
# with a smaller prior weight, refines), or the step or gradient is negligible.
_FTOL, _XTOL, _GTOL = 1e-8, 1e-10, 1e-10
# The final correction may take this fraction of the margin.
_POLISH_MARGIN = 1e-2


@dataclass(frozen=True)
class Problem:
    """Scaled residuals of one retrieval (module docstring, (a)–(c))."""

    layout: Layout
    combinations: FloatArray
    target: FloatArray
    scale: FloatArray  # of each base parameter, for the test of success
    weight: FloatArray  # of each base parameter, in residual (a)
    prior_scale: FloatArray  # of each standard parameter
    x_prior: FloatArray
    x_scale: FloatArray

    @classmethod
    def build(
        cls, base: BaseParameters, target: FloatArray, prior: FloatArray, margin: float
    ) -> Problem:
        layout = Layout.build(base.robot.n_dof, set(base.zero), margin)
        floor = max(_SCALE_FLOOR * float(np.abs(target).max()), TINY)
        prior_scale = _prior_scale(prior)
        x_prior, x_scale = layout.start(prior, prior_scale[ARMATURE::N_LINK_PARAMETERS])
        combinations = base.combinations.to_numpy()
        typical = np.abs(combinations) @ prior_scale
        return cls(
            layout,
            combinations,
            target,
            np.maximum(np.abs(target), floor),
            np.maximum(np.abs(target), np.maximum(_TYPICAL_FRACTION * typical, floor)),
            prior_scale,
            x_prior,
            x_scale,
        )

    def residual(self, x: FloatArray, root: float) -> FloatArray:
        pi = self.layout.parameters(x)
        penalised = list(self.layout.penalised)
        return np.concatenate(
            [
                (self.combinations @ pi - self.target) / self.weight,
                root * (x - self.x_prior) / self.x_scale,
                _ZERO_WEIGHT * pi[penalised] / self.prior_scale[penalised],
            ]
        )

    def jacobian(self, x: FloatArray, root: float) -> FloatArray:
        d_pi = self.layout.jacobian(x)
        penalised = list(self.layout.penalised)
        return np.vstack(
            [
                self.combinations @ d_pi / self.weight[:, None],
                np.diag(root / self.x_scale),
                _ZERO_WEIGHT * d_pi[penalised] / self.prior_scale[penalised, None],
            ]
        )

    def solve(
        self, weights: list[float], budget: int, tolerance: float, zero_index: NDArray[np.intp]
    ) -> tuple[FloatArray, int, int]:
        """Passes of decreasing prior weight; returns (π, evaluations, passes)."""
        x, evaluations, passes = self.x_prior, 0, 0
        pi = self.layout.parameters(x)
        for weight in weights:
            solution = scipy.optimize.least_squares(
                self.residual,
                x,
                jac=self.jacobian,
                method="lm",
                x_scale=self.x_scale,
                ftol=_FTOL,
                xtol=_XTOL,
                gtol=_GTOL,
                max_nfev=budget - evaluations,
                args=(math.sqrt(weight),),
            )
            x, evaluations, passes = solution.x, evaluations + int(solution.nfev), passes + 1
            pi = self.layout.parameters(x)
            pi[zero_index] = 0.0
            pi = self._polish(pi, x, zero_index)
            if self._within(pi, tolerance) or evaluations >= budget:
                break
        return pi, evaluations, passes

    def _within(self, pi: FloatArray, tolerance: float) -> bool:
        return bool(np.all(np.abs(self.combinations @ pi - self.target) <= tolerance * self.scale))

    def _polish(self, pi: FloatArray, x: FloatArray, zero_index: NDArray[np.intp]) -> FloatArray:
        """Remove the last residual by the smallest scaled change of the free parameters.

        Kept only if it helps and costs at most 1 % of the margin on every
        link's smallest pseudo-inertia eigenvalue (and the links stay rigid
        bodies), i.e. when the fit is already close: it turns, e.g., an
        armature b² approaching 0 into an exact 0.
        """
        free = np.flatnonzero(np.any(self.layout.jacobian(x) != 0, axis=1))
        free = np.setdiff1d(free, zero_index)
        error = self.target - self.combinations @ pi
        weighted = self.combinations[:, free] * self.prior_scale[free]
        step, *_ = np.linalg.lstsq(weighted, error, rcond=None)
        polished = pi.copy()
        polished[free] += self.prior_scale[free] * step
        armature = polished[ARMATURE::N_LINK_PARAMETERS]
        polished[ARMATURE::N_LINK_PARAMETERS] = np.maximum(armature, 0.0)
        before = np.abs(error) / self.scale
        after = np.abs(self.target - self.combinations @ polished) / self.scale
        margin = self.layout.margin
        old = np.linalg.eigvalsh(pseudo_inertia(pi))[:, 0]
        new = np.linalg.eigvalsh(pseudo_inertia(polished))[:, 0]
        keep = (
            after.max() < before.max()
            and bool(np.all(new >= np.minimum(old, margin) - _POLISH_MARGIN * margin))
            and bool(physically_consistent_links(polished).all())
        )
        return polished if keep else pi


def _prior_scale(prior: FloatArray) -> FloatArray:
    """Per link and kind the prior's magnitude: inertia, first moment, mass, armature."""
    links = np.abs(prior.reshape(-1, N_LINK_PARAMETERS))
    inertia = links[:, :6].max(axis=1)
    mass = links[:, 9]
    kinds = np.stack(
        [
            inertia,
            np.maximum(links[:, 6:9].max(axis=1), np.sqrt(mass * inertia)),
            mass,
            np.maximum(links[:, ARMATURE], inertia),
        ],
        axis=1,
    )
    kinds = np.maximum(kinds, np.maximum(_KIND_FLOOR * kinds.max(axis=0), TINY))
    columns = [0] * 6 + [1] * 3 + [2, 3]
    return kinds[:, columns].ravel()
