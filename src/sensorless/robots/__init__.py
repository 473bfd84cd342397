"""Robot models: the :class:`RobotModel` class and the built-in robots.

>>> import sensorless as sl
>>> sl.robots.available()
['lwr4', 'panda', 'panda_gaz', 'planar2', 'puma560', 'ur10', 'ur5']
>>> sl.robots.load("planar2").n_dof
2
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..exceptions import InputTypeError, UnknownNameError
from .builtin import BUILTIN
from .model import PARAMETER_NAMES, LinkInertia, MotorData, RobotModel

__all__ = ["PARAMETER_NAMES", "LinkInertia", "MotorData", "RobotModel", "available", "load"]


def available() -> list[str]:
    """Names of the built-in robots, sorted."""
    return sorted(BUILTIN)


def load(name: str, **options: Any) -> RobotModel:
    """Build a built-in robot by name (see :func:`available`).

    Parameters
    ----------
    name : str
        One of :func:`available`.
    **options
        Passed to the robot's builder (e.g. ``planar2`` accepts link lengths).
    """
    if not isinstance(name, str):
        raise InputTypeError(f"robot name must be a string, one of {available()}; got {name!r}")
    builder: Callable[..., RobotModel] | None = BUILTIN.get(name)
    if builder is None:
        raise UnknownNameError(f"unknown robot {name!r}; available robots: {available()}")
    return builder(**options)
