"""The result of :func:`~sensorless.identification.consistent.consistent_parameters`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from .._validation import FloatArray
from ..robots.base_parameters import BaseParameters
from ..robots.model import N_LINK_PARAMETERS, PARAMETER_NAMES, RobotModel
from ..simulation.model_error import physically_consistent_links, pseudo_inertia

if TYPE_CHECKING:
    from ._consistent_problem import Problem

__all__ = ["ConsistentFit"]

#: Base parameters named in the message of a failed fit.
_N_WORST = 5


@dataclass(frozen=True)
class ConsistentFit:
    """Physically consistent standard parameters fitted to base parameters.

    Attributes
    ----------
    robot : RobotModel
        ``base.robot`` with the retrieved standard parameters (kinematics,
        gravity and friction of ``base.robot``).
    parameters : DataFrame of shape (n_dof, 11)
        The retrieved standard parameters π, laid out as
        :meth:`RobotModel.standard_parameters` (taken from π itself, so declared
        zeros are exact zeros; ``robot`` holds them up to Pinocchio round-off):
        ``XX ... ZZ`` [kg m²] about the link frame origin, ``mX, mY, mZ`` [kg m],
        ``m`` [kg], ``Ia`` [kg m²].
    names : list of str
        Base-parameter names, as ``base.names``.
    target : ndarray of shape (count,)
        The requested base parameters θ [units of each parameter].
    reproduced : ndarray of shape (count,)
        ``combinations @ π`` of the retrieved parameters.
    scale : ndarray of shape (count,)
        Scale s_j = max(|θ_j|, 1e-6 max|θ|) of each base parameter; ``success``
        needs |reproduced − target| ≤ tolerance · s everywhere.
    tolerance : float
        Relative tolerance of that test [-].
    min_eigenvalue : ndarray of shape (n_dof,)
        Smallest eigenvalue of each link's 4x4 pseudo-inertia J [mixed: kg m²,
        kg m, kg]: ≥ margin (less at most 1 % of it, the final correction), or
        0 on links whose declared zeros remove a coordinate of J.
    success : bool
        Every base parameter reproduced within tolerance and every link a
        rigid body with non-negative armature.
    message : str
        What was reached, or which base parameters / links failed.
    n_evaluations : int
        Residual evaluations over all passes (Jacobian evaluations not counted).
    """

    robot: RobotModel
    parameters: pd.DataFrame
    names: list[str]
    target: FloatArray
    reproduced: FloatArray
    scale: FloatArray
    tolerance: float
    min_eigenvalue: FloatArray
    success: bool
    message: str
    n_evaluations: int

    @property
    def residual(self) -> FloatArray:
        """``reproduced − target``, shape (count,) [units of each base parameter]."""
        return np.asarray(self.reproduced - self.target)

    @property
    def relative_residual(self) -> float:
        """‖reproduced − target‖ / ‖target‖ [-] (the plain norm if θ = 0)."""
        norm = float(np.linalg.norm(self.target))
        residual = float(np.linalg.norm(self.residual))
        return residual / norm if norm > 0 else residual

    def to_pandas(self) -> pd.DataFrame:
        """One row per base parameter: target, reproduced, residual, scaled_residual."""
        return pd.DataFrame(
            {
                "target": self.target,
                "reproduced": self.reproduced,
                "residual": self.residual,
                "scaled_residual": self.residual / self.scale,
            },
            index=pd.Index(self.names, name="base parameter"),
        )


def consistent_fit(
    base: BaseParameters,
    pi: FloatArray,
    problem: Problem,
    tolerance: float,
    evaluations: int,
    budget: int,
    how: str,
) -> ConsistentFit:
    """The :class:`ConsistentFit` of the retrieved standard parameters ``pi``.

    Parameters
    ----------
    base : BaseParameters
        The grouping the fit was made for.
    pi : ndarray of shape (11·n_dof,)
        Retrieved standard parameters [kg m², kg m, kg per parameter].
    problem : Problem
        The problem that was solved (targets, scales, combinations).
    tolerance : float
        Relative tolerance of the success test [-].
    evaluations, budget : int
        Residual evaluations used and allowed.
    how : str
        How the fit went (passes, weights, evaluations), ending the message.
    """
    target, scale = problem.target, problem.scale
    reproduced = problem.combinations @ pi
    scaled = np.abs(reproduced - target) / scale
    min_eigenvalue = np.asarray(np.linalg.eigvalsh(pseudo_inertia(pi))[:, 0], dtype=float)
    rigid = physically_consistent_links(pi)
    missed = np.flatnonzero(scaled > tolerance)
    success = missed.size == 0 and bool(rigid.all())
    if success:
        message = (
            f"reproduced all {target.size} base parameters within {tolerance:.3g} of their "
            f"scale; every link is a rigid body (smallest pseudo-inertia eigenvalue "
            f"{min_eigenvalue.min():.3g}); {how}"
        )
    else:
        parts = []
        if missed.size:
            why = (
                f"the budget of {budget} evaluations ran out"
                if evaluations >= budget
                else "no rigid bodies with the declared zeros give them"
            )
            parts.append(_missed_message(base, reproduced, problem, tolerance, missed, why))
        if not rigid.all():
            bad = [f"link{i + 1}" for i in np.flatnonzero(~rigid)]
            parts.append(
                f"links {bad} are not rigid bodies after setting the declared zeros "
                f"(smallest pseudo-inertia eigenvalues {min_eigenvalue[~rigid]})"
            )
        message = "; ".join(parts) + f"; {how}"
    n_dof = base.robot.n_dof
    index = pd.Index([f"link{i}" for i in range(1, n_dof + 1)], name="link")
    return ConsistentFit(
        robot=base.robot.with_standard_parameters(pi),
        parameters=pd.DataFrame(
            pi.reshape(n_dof, N_LINK_PARAMETERS), index=index, columns=list(PARAMETER_NAMES)
        ),
        names=list(base.names),
        target=target,
        reproduced=reproduced,
        scale=scale,
        tolerance=tolerance,
        min_eigenvalue=min_eigenvalue,
        success=success,
        message=message,
        n_evaluations=evaluations,
    )


def _missed_message(
    base: BaseParameters,
    reproduced: FloatArray,
    problem: Problem,
    tolerance: float,
    missed: NDArray[np.intp],
    why: str,
) -> str:
    """What a fit missed: the count and the worst base parameters, worst first."""
    target = problem.target
    scaled = np.abs(reproduced - target) / problem.scale
    worst = missed[np.argsort(scaled[missed])[::-1][:_N_WORST]]
    listed = ", ".join(
        f"{base.names[j]} (target {target[j]:.6g}, reproduced {reproduced[j]:.6g}, "
        f"scaled residual {scaled[j]:.3g})"
        for j in worst
    )
    return (
        f"could not reproduce {missed.size} of {target.size} base parameters within "
        f"{tolerance:.3g} of their scale ({why}); worst: {listed}"
    )
