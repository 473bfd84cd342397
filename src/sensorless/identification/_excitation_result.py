"""The result of :func:`~sensorless.identification.excitation.optimize_excitation` and its file."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd
import yaml

from .._validation import FloatArray
from .._version import __version__
from ..exceptions import InputValueError
from ..trajectories import FourierSeries

__all__ = ["ExcitationResult", "load_excitation"]


@dataclass(frozen=True)
class ExcitationResult:
    """An optimised excitation trajectory and how well it does.

    Extremes are measured on the check grid (``10 × n_samples`` instants over
    one period), after the final amplitude scaling.

    Attributes
    ----------
    trajectory : FourierSeries
        The optimised trajectory (one period).
    initial_trajectory : FourierSeries
        The best of the seeded random starts, before optimisation.
    condition_number : float
        cond(W) of :attr:`trajectory` on the optimisation grid [-].
    initial_condition_number : float
        cond(W) of :attr:`initial_trajectory` on the same grid [-].
    robot : str
        Name of the robot model.
    joint_names : list of str
        Joint names of the robot, in the order of the arrays below.
    base_names : list of str
        The base parameters whose regressor W is made of.
    n_samples : int
        Instants of the optimisation grid over one period.
    lower_limit, upper_limit : ndarray of shape (n_dof,)
        Position limits used [rad].
    velocity_limit : ndarray of shape (n_dof,)
        Velocity limits used [rad/s].
    acceleration_limit : ndarray of shape (n_dof,)
        Acceleration limits used [rad/s²]; inf where unconstrained.
    min_position, max_position : ndarray of shape (n_dof,)
        Extreme joint positions of :attr:`trajectory` [rad].
    max_velocity : ndarray of shape (n_dof,)
        Largest |q̇| [rad/s].
    max_acceleration : ndarray of shape (n_dof,)
        Largest |q̈| [rad/s²].
    amplitude_scale : float
        Factor (<= 1) applied to the optimised a, b so that the check grid
        respects the limits; 1 when nothing had to be shrunk.
    success : bool
        Whether SLSQP reported convergence for the kept run.
    message : str
        SLSQP's message for the kept run.
    n_iterations : int
        SLSQP iterations of the kept run.
    """

    trajectory: FourierSeries
    initial_trajectory: FourierSeries
    condition_number: float
    initial_condition_number: float
    robot: str
    joint_names: list[str]
    base_names: list[str]
    n_samples: int
    lower_limit: FloatArray
    upper_limit: FloatArray
    velocity_limit: FloatArray
    acceleration_limit: FloatArray
    min_position: FloatArray
    max_position: FloatArray
    max_velocity: FloatArray
    max_acceleration: FloatArray
    amplitude_scale: float
    success: bool
    message: str
    n_iterations: int

    @property
    def within_limits(self) -> bool:
        """True when every extreme lies within its limit (checked on the check grid)."""
        return bool(
            (self.min_position >= self.lower_limit).all()
            and (self.max_position <= self.upper_limit).all()
            and (self.max_velocity <= self.velocity_limit).all()
            and (self.max_acceleration <= self.acceleration_limit).all()
        )

    def to_pandas(self) -> pd.DataFrame:
        """One row per joint: offset, extremes and limits (SI units, radians)."""
        return pd.DataFrame(
            {
                "offset": self.trajectory.q0,
                "min_position": self.min_position,
                "max_position": self.max_position,
                "lower_limit": self.lower_limit,
                "upper_limit": self.upper_limit,
                "max_velocity": self.max_velocity,
                "velocity_limit": self.velocity_limit,
                "max_acceleration": self.max_acceleration,
                "acceleration_limit": self.acceleration_limit,
            },
            index=pd.Index(self.joint_names, name="joint"),
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain Python values: the trajectory specification and the figures of merit."""

        def as_list(arr: FloatArray) -> list[float]:
            return [float(v) for v in arr]

        return {
            "robot": self.robot,
            "trajectory": self.trajectory.to_dict(),
            "condition_number": float(self.condition_number),
            "initial_condition_number": float(self.initial_condition_number),
            "n_samples": int(self.n_samples),
            "amplitude_scale": float(self.amplitude_scale),
            "success": bool(self.success),
            "message": str(self.message),
            "n_iterations": int(self.n_iterations),
            "base_parameters": list(self.base_names),
            "joints": {
                "names": list(self.joint_names),
                "min_position": as_list(self.min_position),
                "max_position": as_list(self.max_position),
                "lower_limit": as_list(self.lower_limit),
                "upper_limit": as_list(self.upper_limit),
                "max_velocity": as_list(self.max_velocity),
                "velocity_limit": as_list(self.velocity_limit),
                "max_acceleration": as_list(self.max_acceleration),
                "acceleration_limit": as_list(self.acceleration_limit),
            },
        }

    def to_yaml(self, path: str | Path) -> Path:
        """Write :meth:`to_dict` to a YAML file a person can read; return its path.

        The ``trajectory`` entry is a ``{type: fourier, ...}`` specification
        that :func:`load_excitation` (or :meth:`FourierSeries.from_dict`) reads
        back into the identical series.
        """
        header = (
            f"# Excitation trajectory (finite Fourier series, Swevers et al. 1997) written by "
            f"sensorless {__version__}.\n"
            "# SI units: base_frequency [Hz], duration [s], offset and positions [rad], "
            "a, b and velocities [rad/s],\n# accelerations [rad/s^2]. "
            "q_j(t) = offset_j + sum_k a[k-1][j]/(w k) sin(w k t) - b[k-1][j]/(w k) cos(w k t), "
            "w = 2 pi base_frequency.\n"
        )
        text = yaml.safe_dump(self.to_dict(), sort_keys=False, default_flow_style=None, width=100)
        out = Path(path)
        out.write_text(header + text, encoding="utf-8")
        return out


def load_excitation(path: str | Path) -> FourierSeries:
    """Read the trajectory of a file written by :meth:`ExcitationResult.to_yaml`.

    A file that holds a bare ``{type: fourier, ...}`` specification is read too.

    Raises
    ------
    FileNotFoundError
        No such file.
    InputValueError
        Not YAML, or no Fourier specification in it.
    """
    text = Path(path).read_text(encoding="utf-8")
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise InputValueError(f"{path} is not a YAML file: {exc}") from None
    if isinstance(data, dict) and "trajectory" in data:
        data = data["trajectory"]
    if not isinstance(data, dict):
        raise InputValueError(
            f"{path} holds no trajectory specification: expected a mapping with a "
            f"'trajectory' entry or the keys of FourierSeries.to_dict; got {type(data).__name__}"
        )
    return FourierSeries.from_dict(data)
