"""The result of :func:`~sensorless.metric.optimize_trajectory` and its YAML file."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd
import yaml

from .._validation import FloatArray
from .._version import __version__
from ..exceptions import InputValueError, one_line
from ..trajectories import SplineTrajectory, Trajectory

__all__ = ["PlannedTrajectory", "load_plan"]


@dataclass(frozen=True)
class PlannedTrajectory:
    """A trajectory planned for precise external-torque estimation, and what it gains.

    Figures compare the planned trajectory with the starting quintic, both
    sampled every :attr:`dt`, each with its own B_Q̃ (:attr:`bq`,
    :attr:`initial_bq`) and the same B_Θ̃: the EM of
    :func:`~sensorless.metric.rank_trajectories`.

    Attributes
    ----------
    trajectory : SplineTrajectory
        The optimised trajectory; a :class:`~sensorless.trajectories.Trajectory`
        that :func:`sensorless.simulation.simulate` and the controllers take.
    initial : Trajectory
        The starting trajectory (the quintic through the same points).
    metric : float
        EM[q] of :attr:`trajectory` (eq. 3.32, with |·|, trapezoid rule) [N m s].
    initial_metric : float
        EM[q] of :attr:`initial` [N m s].
    t : ndarray of shape (n_samples,)
        Sample times [s], every :attr:`dt`.
    bound : ndarray of shape (n_samples, n_dof)
        Model-based part of B_c(t) (eq. 3.36: q-error, cross and parameter
        terms, without B_fr and B_d) along :attr:`trajectory` [N m].
    initial_bound : ndarray of shape (n_samples, n_dof)
        The same along :attr:`initial` [N m].
    bq : ndarray of shape (l,)
        B_Q̃ of :attr:`trajectory` (eq. 3.26): by the method of thesis Table
        3.1 on it, or the ``bq`` given to the planner.
    initial_bq : ndarray of shape (l,)
        B_Q̃ of :attr:`initial`, likewise.
    dt : float
        Sample period [s] of :attr:`t` and of the estimator behind :attr:`bq`.
    robot : str
        Name of the robot model.
    joint_names : list of str
    objective, initial_objective : float
        OBJ[q] with the smooth |·| of eq. 3.30 on the collocation grid [N m s].
    epsilon : float
        ε of eq. 3.30.
    max_violation : float
        Largest excess over a limit on the check grid (10 times denser than
        the collocation grid), relative to the limit; <= 0 when every limit holds.
    success : bool
        Whether SLSQP converged and the limits hold on the check grid.
    message : str
        SLSQP's message, and what the checks found.
    n_iterations : int
        SLSQP iterations over all refinement rounds.
    n_values, n_gradients : int
        Evaluations of OBJ and of its gradient.
    """

    trajectory: SplineTrajectory
    initial: Trajectory
    metric: float
    initial_metric: float
    t: FloatArray
    bound: FloatArray
    initial_bound: FloatArray
    bq: FloatArray
    initial_bq: FloatArray
    dt: float
    robot: str
    joint_names: list[str]
    objective: float
    initial_objective: float
    epsilon: float
    max_violation: float
    success: bool
    message: str
    n_iterations: int
    n_values: int
    n_gradients: int

    @property
    def improvement(self) -> float:
        """Relative decrease of EM from :attr:`initial` to :attr:`trajectory` [-]."""
        return 1.0 - self.metric / self.initial_metric if self.initial_metric > 0 else 0.0

    def to_pandas(self) -> pd.DataFrame:
        """One row per joint: mean and peak bound along both trajectories [N m]."""
        return pd.DataFrame(
            {
                "mean_bound": self.bound.mean(axis=0),
                "initial_mean_bound": self.initial_bound.mean(axis=0),
                "max_bound": self.bound.max(axis=0),
                "initial_max_bound": self.initial_bound.max(axis=0),
            },
            index=pd.Index(self.joint_names, name="joint"),
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain Python values: the trajectory specification and the figures of merit."""
        return {
            "robot": self.robot,
            "joints": list(self.joint_names),
            "trajectory": self.trajectory.to_dict(),
            "metric": float(self.metric),
            "initial_metric": float(self.initial_metric),
            "mean_bound": [float(v) for v in self.bound.mean(axis=0)],
            "initial_mean_bound": [float(v) for v in self.initial_bound.mean(axis=0)],
            "objective": float(self.objective),
            "initial_objective": float(self.initial_objective),
            "epsilon": float(self.epsilon),
            "bq": [float(v) for v in self.bq],
            "initial_bq": [float(v) for v in self.initial_bq],
            "dt": float(self.dt),
            "max_violation": float(self.max_violation),
            "success": bool(self.success),
            "message": str(self.message),
            "n_iterations": int(self.n_iterations),
        }

    def to_yaml(self, path: str | Path) -> Path:
        """Write :meth:`to_dict` to a YAML file a person can read; return its path.

        :func:`load_plan` reads the ``trajectory`` entry back into the
        identical :class:`~sensorless.trajectories.SplineTrajectory`.
        """
        header = (
            f"# Trajectory planned for external-torque estimation (thesis eq. 3.28-3.32), "
            f"written by sensorless {__version__}.\n"
            "# q(t) = sum_i control_points[i] N_i,degree(t) on the clamped knots [s]; "
            "control points [rad].\n"
            "# metric: EM[q] [N m s]; mean_bound: mean model-based B_c(t) per joint [N m].\n"
        )
        text = yaml.safe_dump(self.to_dict(), sort_keys=False, default_flow_style=None, width=100)
        out = Path(path)
        out.write_text(header + text, encoding="utf-8")
        return out


def load_plan(path: str | Path) -> SplineTrajectory:
    """Read the trajectory of a file written by :meth:`PlannedTrajectory.to_yaml`.

    A file holding a bare ``{type: bspline, ...}`` specification is read too.

    Raises
    ------
    FileNotFoundError
        No such file.
    InputValueError
        Not YAML, or no B-spline specification in it.
    """
    text = Path(path).read_text(encoding="utf-8")
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise InputValueError(f"{path} is not a YAML file: {one_line(exc)}") from None
    if isinstance(data, dict) and "trajectory" in data:
        data = data["trajectory"]
    if not isinstance(data, dict):
        raise InputValueError(
            f"{path} holds no trajectory specification: expected a mapping with a 'trajectory' "
            f"entry or the keys of SplineTrajectory.to_dict; got {type(data).__name__}"
        )
    return SplineTrajectory.from_dict(data)
