"""sensorless: collision detection and external-torque estimation without force sensors.

Units are SI and radians; joint time series have shape ``(n_samples, n_dof)``
with time along axis 0.
"""

from __future__ import annotations

from . import exceptions, friction, robots
from .exceptions import SensorlessError
from .robots import LinkInertia, MotorData, RobotModel
from .robots.base_parameters import BaseParameters, base_parameters

__version__ = "0.1.0"

__all__ = [
    "BaseParameters",
    "LinkInertia",
    "MotorData",
    "RobotModel",
    "SensorlessError",
    "__version__",
    "base_parameters",
    "exceptions",
    "friction",
    "robots",
]
