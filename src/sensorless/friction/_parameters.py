"""Per-joint friction parameters: broadcasting, range checks and immutable storage.

Shared by the static models (:mod:`sensorless.friction.static`) and
:class:`~sensorless.friction.LuGre`. Every parameter accepts a scalar or an
array of shape ``(n_dof,)``; scalars are broadcast to the common length.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, joint_parameter
from ..exceptions import DimensionError, InputValueError

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

_BOUNDS = {
    ">= 0": lambda x: x >= 0.0,
    "> 0": lambda x: x > 0.0,
    "<= 0": lambda x: x <= 0.0,
}


def broadcast_parameters(model: str, **values: ArrayLike) -> list[FloatArray]:
    """Return the parameters as read-only float arrays of one common shape ``(n_dof,)``.

    Parameters
    ----------
    model : str
        Class name used in error messages.
    **values : float or array-like of shape (n_dof,)
        The parameters by name, in their own units.

    Returns
    -------
    list of ndarray of shape (n_dof,)
        In the order of ``values``.
    """
    arrays: dict[str, FloatArray] = {}
    for name, value in values.items():
        arrays[name] = np.atleast_1d(joint_parameter(value, f"{model}: {name}"))
    try:
        shape = np.broadcast_shapes(*(arr.shape for arr in arrays.values()))
    except ValueError:
        shapes = ", ".join(f"{name}: {arr.shape}" for name, arr in arrays.items())
        raise DimensionError(
            f"{model}: per-joint parameters must be scalars or arrays of one common length "
            f"n_dof; got shapes {shapes}"
        ) from None
    result = []
    for arr in arrays.values():
        full = np.array(np.broadcast_to(arr, shape), dtype=np.float64)
        full.setflags(write=False)
        result.append(full)
    return result


def require(model: str, name: str, value: FloatArray, bound: str, meaning: str) -> None:
    """Raise :class:`InputValueError` unless every joint's ``value`` satisfies ``bound``.

    ``bound`` is one of ``">= 0"``, ``"> 0"``, ``"<= 0"``; ``meaning`` says
    what the parameter is, with its unit, for the message.
    """
    ok = _BOUNDS[bound](value)
    if not ok.all():
        joint = int(np.argmin(ok))
        raise InputValueError(
            f"{model}: {name} must be {bound} ({meaning}); got {value[joint]} at joint {joint}"
        )


def bound(relation: str, meaning: str) -> dict[str, Any]:
    """Metadata of a parameter field: its range (a relation of :func:`require`) and meaning.

    ``meaning`` says what the parameter is, with its unit, for the error message.
    """
    return {"range": (relation, meaning)}


class JointParameters:
    """Per-joint constants stored once, immutable after construction."""

    _n_dof: int

    @property
    def n_dof(self) -> int:
        """Number of joints the model describes."""
        return self._n_dof

    def _set_parameters(self, **values: ArrayLike) -> None:
        """Broadcast the parameters, check the ranges of their fields (:func:`bound`), store."""
        model = type(self).__name__
        arrays = broadcast_parameters(model, **values)
        fields = {item.name: item for item in dataclasses.fields(cast("DataclassInstance", self))}
        # The subclasses are frozen dataclasses: attributes are set once, here.
        for name, arr in zip(values, arrays, strict=True):
            if "range" in fields[name].metadata:
                require(model, name, arr, *fields[name].metadata["range"])
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "_n_dof", int(arrays[0].shape[0]))
