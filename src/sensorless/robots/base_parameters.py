"""Base (minimal) inertial parameters, found numerically (Gautier–Khalil).

The regressor Y of the standard parameters π has dependent columns: some
parameters never act (zero columns) and others only act in fixed linear
combinations. The base parameters are those combinations,
θ = π_b + β π_d, so that Y π = Y_b θ with Y_b the independent columns.

Route (Gautier 1991, "Numerical calculation of the base inertial parameters
of robots"): stack Y at random states; the rank comes from a QR
decomposition with column pivoting; the independent columns are then picked
in a preferred order (Khalil's choice: XX, XY, XZ, YZ, ZZ, mX, mY, Ia are
kept, YY, mZ, m are regrouped into them — the form of thesis Table 2.6), and
β solves Y_b β = Y_d by least squares.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.linalg
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_int, check_scalar
from ..exceptions import InputTypeError, UnknownNameError
from .model import N_LINK_PARAMETERS, PARAMETER_NAMES, RobotModel

__all__ = ["BaseParameters", "base_parameters"]

_KEPT_FIRST = ("XX", "XY", "XZ", "YZ", "ZZ", "mX", "mY", "Ia")
_COEFFICIENT_ZERO = 1e-9


@dataclass(frozen=True)
class BaseParameters:
    """Base parameters of a robot: their grouping and their values.

    Attributes
    ----------
    robot : RobotModel
        The model whose regressor was analysed.
    names : list of str
        One name per base parameter: the standard parameter it is built on,
        with a trailing ``R`` when others are regrouped into it (Khalil's
        notation, e.g. ``ZZ1R``).
    combinations : DataFrame of shape (count, 11·n_dof)
        θ = combinations @ π; rows are base parameters, columns standard ones.
    independent : ndarray of int
        Indices (into the standard parameters) of the columns kept.
    rank_tolerance : float
        Tolerance on |R_ii| used to decide the rank.
    singular_gap : tuple of float
        Smallest |R_ii| kept and largest |R_ii| dropped by the pivoted QR (a
        large ratio means a clear-cut rank).
    zero : tuple of str
        Standard parameters declared zero (their columns were removed).
    """

    robot: RobotModel
    names: list[str]
    combinations: pd.DataFrame
    independent: np.ndarray
    rank_tolerance: float
    singular_gap: tuple[float, float]
    zero: tuple[str, ...]

    @property
    def count(self) -> int:
        """Number of base parameters."""
        return len(self.names)

    @property
    def values(self) -> FloatArray:
        """Base-parameter values of :attr:`robot`, shape (count,)."""
        return self.values_of(self.robot)

    def values_of(self, robot: RobotModel | ArrayLike) -> FloatArray:
        """Base-parameter values of another model with the same kinematics, or of a π vector."""
        pi = robot.parameter_vector() if isinstance(robot, RobotModel) else np.asarray(robot, float)
        return np.asarray(self.combinations.to_numpy() @ pi)

    def regressor(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
        """Base regressor Y_b(q, q̇, q̈) with Y_b θ = inverse dynamics.

        The columns :attr:`independent` of :meth:`RobotModel.regressor`, which
        takes the same joint positions [rad], velocities [rad/s] and
        accelerations [rad/s²]; shape (n_dof, count) or (n_samples, n_dof, count).
        """
        return np.asarray(self.robot.regressor(q, qd, qdd)[..., self.independent])

    def formula(self, name: str, digits: int = 6) -> str:
        """Readable combination, e.g. ``'mY2 + mZ3 + 0.4 m3 + ...'``."""
        if name not in self.names:
            raise UnknownNameError(f"unknown base parameter {name!r}; options: {self.names}")
        row = self.combinations.loc[name]
        terms = []
        for label, coef in zip(row.index, row.to_numpy(), strict=True):
            if coef == 0:
                continue
            coef_text = "" if np.isclose(abs(coef), 1.0) else f"{abs(coef):.{digits}g} "
            sign = "-" if coef < 0 else "+"
            terms.append(f"{sign} {coef_text}{label}")
        text = " ".join(terms)
        return text[2:] if text.startswith("+ ") else text

    def to_pandas(self) -> pd.DataFrame:
        """Table of base parameters: name, formula and value of :attr:`robot`."""
        return pd.DataFrame(
            {"formula": [self.formula(n) for n in self.names], "value": self.values},
            index=pd.Index(self.names, name="base parameter"),
        )


def base_parameters(
    robot: RobotModel,
    zero: Iterable[str] = (),
    *,
    n_samples: int | None = None,
    seed: int = 0,
    tolerance: float | None = None,
) -> BaseParameters:
    """Find the base parameters of ``robot`` numerically.

    Parameters
    ----------
    robot : RobotModel
        Robot whose kinematics define the regressor (its parameter values do not
        matter for the grouping).
    zero : iterable of str
        Standard parameters known to be zero, e.g. the blanks of thesis Table
        2.5 (``"XY2"``, ``"mX3"``...); names as :meth:`RobotModel.parameter_names`.
    n_samples : int, optional
        Random states stacked into the observation matrix (each gives n_dof
        rows for 11·n_dof columns); default 100.
    seed : int
        Seed of the random states (q uniform in [−π, π] rad, q̇ and q̈ standard
        normal [rad/s], [rad/s²]).
    tolerance : float, optional
        Rank tolerance on |R_ii|; default ``1e-8 · max|R_ii|``.

    Returns
    -------
    BaseParameters
    """
    names = robot.parameter_names()
    if isinstance(zero, str) or not isinstance(zero, Iterable):
        raise InputTypeError(f"zero must be a sequence of parameter names; got {zero!r}")
    zero = tuple(zero)
    unknown = [z for z in zero if z not in names]
    if unknown:
        raise UnknownNameError(
            f"unknown standard parameters {unknown}; names are {list(PARAMETER_NAMES)} "
            f"followed by the link number 1..{robot.n_dof}"
        )
    n = robot.n_dof
    # Every column needs rows: n_samples·n_dof >= 11·n_dof, so at least 11 random states.
    n_samples = 100 if n_samples is None else check_int(n_samples, "n_samples", N_LINK_PARAMETERS)
    seed = check_int(seed, "seed", 0)
    if tolerance is not None:
        tolerance = check_scalar(tolerance, "tolerance", "-")
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (n_samples, n))
    observation = robot.regressor(
        q, rng.standard_normal((n_samples, n)), rng.standard_normal((n_samples, n))
    )
    observation = observation.reshape(n_samples * n, -1)
    active = np.array([name not in zero for name in names])
    active_idx = np.flatnonzero(active)
    _, r_pivoted, pivots = scipy.linalg.qr(
        observation[:, active_idx], mode="economic", pivoting=True
    )
    diag = np.abs(np.diag(r_pivoted))
    tol = float(1e-8 * diag.max() if tolerance is None else tolerance)
    rank = int((diag > tol).sum())
    gap = (float(diag[rank - 1]) if rank else 0.0, float(diag[rank]) if rank < diag.size else 0.0)

    preferred = [PARAMETER_NAMES[k % N_LINK_PARAMETERS] in _KEPT_FIRST for k in range(len(names))]
    order = sorted(active_idx, key=lambda k: (not preferred[k], k))
    _, r_ordered = scipy.linalg.qr(observation[:, order], mode="economic")
    kept = np.abs(np.diag(r_ordered)) > tol
    independent = np.sort(np.asarray(order)[kept])
    if independent.size != rank:
        # The ordered, unpivoted QR disagrees with the pivoted rank: fall back to
        # the pivoted choice, which is always consistent.
        independent = np.sort(active_idx[pivots[:rank]])
    dependent = np.setdiff1d(active_idx, independent)
    beta, *_ = scipy.linalg.lstsq(observation[:, independent], observation[:, dependent])
    beta[np.abs(beta) < _COEFFICIENT_ZERO] = 0.0

    combinations = np.zeros((rank, len(names)))
    combinations[np.arange(rank), independent] = 1.0
    combinations[:, dependent] = beta
    base_names = [
        names[k] + ("R" if np.count_nonzero(row) > 1 else "")
        for k, row in zip(independent, combinations, strict=True)
    ]
    frame = pd.DataFrame(combinations, index=base_names, columns=names)
    return BaseParameters(robot, base_names, frame, independent, tol, gap, zero)
