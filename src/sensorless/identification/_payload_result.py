"""The results and the state of :mod:`sensorless.identification.payload`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .._validation import FloatArray
from ._payload_regressor import PAYLOAD_PARAMETER_NAMES, RegressorState

__all__ = ["EstimatorState", "PayloadEstimate"]


@dataclass(frozen=True, eq=False)
class PayloadEstimate:
    """A payload's estimated mass and centre of mass, with what the fit rests on.

    Attributes
    ----------
    mass : float
        m̂ [kg], >= 0.
    com : ndarray of shape (3,)
        ĉ in the end-link frame [m]; NaN when m̂ = 0.
    mass_std : float
        Standard error of m̂ [kg], cluster-robust over blocks (see
        :mod:`sensorless.identification.payload`); NaN with fewer than two blocks.
    com_std : ndarray of shape (3,)
        Standard errors of ĉ [m] (delta method).
    parameters : ndarray of shape (10,)
        π̂_L in the order of :data:`PAYLOAD_PARAMETER_NAMES`.
    covariance : ndarray of shape (10, 10)
        Covariance of π̂_L.
    duration : float
        Seconds of samples in the fit [s].
    n_samples : int
        Samples in the fit (each gives one row per used joint).
    n_blocks : int
        Blocks behind the standard errors.
    rank : int
        Numerical rank of the regressor (10 when every parameter is excited).
    condition : float
        Condition number of the regressor (largest over smallest singular value).
    rms : float
        Root mean square of r̂ − Ψ π̂_L over the fitted rows [N m].
    mass_clipped : bool
        The unconstrained fit gave m̂ < 0 and the mass was fixed at 0.
    """

    mass: float
    com: FloatArray
    mass_std: float
    com_std: FloatArray
    parameters: FloatArray
    covariance: FloatArray
    duration: float
    n_samples: int
    n_blocks: int
    rank: int
    condition: float
    rms: float
    mass_clipped: bool

    def to_pandas(self) -> pd.DataFrame:
        """One row per quantity: ``mass``, ``com_x``, ``com_y``, ``com_z``, the ten parameters.

        Columns ``value`` and ``std`` in SI units (``unit`` says which).
        """
        names = ["mass", "com_x", "com_y", "com_z", *PAYLOAD_PARAMETER_NAMES]
        units = ["kg", "m", "m", "m", *(["kg m²"] * 6), *(["kg m"] * 3), "kg"]
        values = [self.mass, *self.com, *self.parameters]
        stds = [self.mass_std, *self.com_std, *np.sqrt(np.diag(self.covariance))]
        index = pd.Index(names, name="quantity")
        return pd.DataFrame({"value": values, "std": stds, "unit": units}, index=index)


@dataclass(frozen=True, eq=False)
class EstimatorState:
    """State of a :class:`PayloadEstimator`; immutable, from :meth:`PayloadEstimator.initial_state`.

    Attributes
    ----------
    regressor : RegressorState
        The filter of Ψ after the last sample.
    seen : int
        Samples of the current run so far (the transient counts them).
    factor : ndarray of shape (11, 11)
        Upper-triangular R of the rows [Ψ | r̂] used so far.
    block : ndarray of shape (10, 11)
        X_bᵀ[y_b | X_b] of the block being filled.
    in_block : int
        Samples in that block.
    meat : ndarray of shape (10, 11, 10, 11)
        Σ over closed blocks of M_b ⊗ M_b, M_b = X_bᵀ[y_b | X_b].
    n_blocks : int
        Closed blocks.
    n_samples : int
        Samples used in the fit.
    """

    regressor: RegressorState
    seen: int
    factor: FloatArray
    block: FloatArray
    in_block: int
    meat: FloatArray
    n_blocks: int
    n_samples: int
