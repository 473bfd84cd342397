"""sensorless: collision detection and external-torque estimation without force sensors.

Units are SI and radians; joint time series have shape ``(n_samples, n_dof)``
with time along axis 0.
"""

from __future__ import annotations

from . import (
    classification,
    detection,
    evaluation,
    exceptions,
    filters,
    friction,
    identification,
    io,
    isolation,
    observers,
    robots,
    thresholds,
    trajectories,
)
from ._version import __version__
from .exceptions import SensorlessError
from .io import Log, read_log, write_log
from .monitor import CollisionMonitor, ObserverSettings, load_tuned, save_tuned, tune
from .robots import LinkInertia, MotorData, RobotModel
from .robots.base_parameters import BaseParameters, base_parameters

__all__ = [
    "BaseParameters",
    "CollisionMonitor",
    "LinkInertia",
    "Log",
    "MotorData",
    "ObserverSettings",
    "RobotModel",
    "SensorlessError",
    "__version__",
    "base_parameters",
    "classification",
    "detection",
    "evaluation",
    "exceptions",
    "filters",
    "friction",
    "identification",
    "io",
    "isolation",
    "load_tuned",
    "observers",
    "read_log",
    "robots",
    "save_tuned",
    "thresholds",
    "trajectories",
    "tune",
    "write_log",
]
