"""A payload gripped by the true robot and unknown to the nominal model.

An arm that picks up an object carries, rigidly attached to its end link, a
body the user's model does not hold. To the collision observer its weight and
inertia are an external torque that lasts as long as the grip: what
:mod:`sensorless.identification.payload` estimates and what
:class:`sensorless.thresholds.PayloadThreshold` allows for. Here it is put on
the *true* plant only: :func:`with_payload` adds its spatial inertia to the
inertia of the end link (Pinocchio's ``model.inertias[n] += Inertia(m, c, I)``),
so the simulated robot moves it while the nominal model stays as it was.

The payload is given in the end-link frame (the frame of the last joint, as
every link frame of :class:`~sensorless.robots.RobotModel`): mass m [kg],
centre of mass c [m] and inertia about the centre of mass I_c [kg m²] (zero:
a point mass). Its standard parameters about the link origin, in the order of
:data:`sensorless.robots.PARAMETER_NAMES` without the armature, are

    (I_c + m(|c|² E − c cᵀ),  m c,  m),

what :meth:`Payload.parameters` returns.

Examples
--------
>>> import numpy as np
>>> import sensorless as sl
>>> robot = sl.robots.load("planar2")
>>> payload = Payload(2.0, (0.1, 0.0, 0.0))
>>> loaded = with_payload(robot, payload)
>>> grown = loaded.parameter_vector()[-11:-1] - robot.parameter_vector()[-11:-1]
>>> bool(np.allclose(grown, payload.parameters()))
True
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_float_array, check_finite, check_scalar, check_type
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..robots.inertia import check_inertia_tensor, parameters_from_inertia
from ..robots.model import RobotModel

__all__ = ["Payload", "with_payload"]

_KEYS = ("mass", "com", "inertia")


def _vector3(value: ArrayLike, name: str, unit: str) -> FloatArray:
    arr = as_float_array(value, name, "(3,)")
    if arr.shape != (3,):
        raise DimensionError(f"{name} must have shape (3,) [{unit}]; got shape {arr.shape}")
    check_finite(arr, name)
    return arr


def _tensor(value: ArrayLike) -> FloatArray:
    arr = as_float_array(value, "inertia", "(3, 3) or (6,)")
    if arr.shape == (6,):  # xx, xy, xz, yy, yz, zz, the order of a URDF <inertia>
        xx, xy, xz, yy, yz, zz = arr
        arr = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    if arr.shape != (3, 3):
        raise DimensionError(
            "inertia must be a 3x3 tensor or its 6 entries (xx, xy, xz, yy, yz, zz) [kg m²]; "
            f"got shape {arr.shape}"
        )
    check_finite(arr, "inertia")
    return check_inertia_tensor(arr, "payload")


@dataclass(frozen=True, eq=False)
class Payload:
    """A rigid body attached to the end link: mass, centre of mass and inertia.

    Parameters
    ----------
    mass : float
        Mass m [kg], > 0.
    com : array-like of shape (3,), default (0, 0, 0)
        Centre of mass c in the end-link frame [m].
    inertia : array-like of shape (3, 3) or (6,), optional
        Inertia about the centre of mass in end-link axes [kg m²] (a tensor,
        or its entries xx, xy, xz, yy, yz, zz); symmetric, positive
        semi-definite and a rigid body's (triangle inequality). Zero, a
        point mass, by default.

    Raises
    ------
    InputValueError
        A mass that is not a finite positive number, non-finite entries.
    DimensionError
        ``com`` or ``inertia`` of another shape.
    ModelError
        An inertia no rigid body has.
    """

    mass: float
    com: FloatArray = field(default_factory=lambda: np.zeros(3))
    inertia: FloatArray = field(default_factory=lambda: np.zeros((3, 3)))

    def __post_init__(self) -> None:
        object.__setattr__(self, "mass", check_scalar(self.mass, "payload mass", "kg"))
        object.__setattr__(self, "com", _vector3(self.com, "payload com", "m"))
        object.__setattr__(self, "inertia", _tensor(self.inertia))
        for name in ("com", "inertia"):
            getattr(self, name).setflags(write=False)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Payload:
        """A payload from a mapping with ``mass``, ``com``, ``inertia`` (a scenario's ``payload``).

        Unknown keys are an :class:`~sensorless.exceptions.InputValueError`
        naming the valid ones.
        """
        if not isinstance(data, Mapping):
            raise InputTypeError(
                f"payload must be a mapping with keys {list(_KEYS)}; got {type(data).__name__}"
            )
        unknown = sorted(set(data) - set(_KEYS))
        if unknown:
            raise InputValueError(f"payload: unknown keys {unknown}; valid: {list(_KEYS)}")
        if "mass" not in data:
            raise InputValueError("payload: the key 'mass' [kg] is required")
        return cls(**{key: data[key] for key in _KEYS if data.get(key) is not None})

    def to_pinocchio(self) -> pin.Inertia:
        """The spatial inertia in the end-link frame (Pinocchio's ``Inertia(m, c, I_c)``)."""
        return pin.Inertia(self.mass, np.array(self.com), np.array(self.inertia))

    def parameters(self) -> FloatArray:
        """Standard parameters about the end-link origin, shape (10,).

        ``XX, XY, XZ, YY, YZ, ZZ`` [kg m²], ``mX, mY, mZ`` [kg m], ``m`` [kg]:
        the order of :data:`sensorless.robots.PARAMETER_NAMES` without ``Ia``.
        """
        return parameters_from_inertia(self.to_pinocchio())

    def __repr__(self) -> str:
        return f"Payload(mass={self.mass!r}, com={self.com.tolist()!r})"


def with_payload(robot: RobotModel, payload: Payload, *, name: str | None = None) -> RobotModel:
    """Copy of ``robot`` whose end link carries ``payload`` rigidly.

    The payload's spatial inertia is added to that of the last link; the
    kinematics, armature, limits, gravity and friction are kept. Simulate the
    result as the *true* robot and observe with the model without the
    payload to reproduce an arm that grips an object its model does not know.

    Parameters
    ----------
    robot : RobotModel
        The robot without the payload.
    payload : Payload
        What the end link carries, in the end-link frame.
    name : str, optional
        Name of the new model; by default that of ``robot``.

    Returns
    -------
    RobotModel
    """
    check_type(robot, RobotModel, "robot")
    check_type(payload, Payload, "payload", " (sensorless.simulation.payload.Payload)")
    model = robot.pinocchio_model.copy()
    last = robot.n_dof
    model.inertias[last] = model.inertias[last] + payload.to_pinocchio()
    return RobotModel(model, name or robot.name, robot.friction, robot.description)
