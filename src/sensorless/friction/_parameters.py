"""Per-joint friction parameters: broadcasting, range checks and immutable storage.

Shared by the static models (:mod:`sensorless.friction.static`) and
:class:`~sensorless.friction.LuGre`. Every parameter accepts a scalar or an
array of shape ``(n_dof,)``; scalars are broadcast to the common length.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_float_array, check_finite
from ..exceptions import DimensionError, InputValueError

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
        label = f"{model}: {name}"
        arr = as_float_array(value, label, "(n_dof,) or a scalar")
        if arr.ndim > 1 or arr.size == 0:
            raise DimensionError(
                f"{label} must be a scalar or a non-empty array of shape (n_dof,); "
                f"got shape {arr.shape}"
            )
        arrays[name] = np.atleast_1d(arr)
        check_finite(arrays[name], label)
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


class JointParameters:
    """Per-joint constants stored once, immutable after construction."""

    _n_dof: int

    @property
    def n_dof(self) -> int:
        """Number of joints the model describes."""
        return self._n_dof

    def _assign(self, names: tuple[str, ...], arrays: list[FloatArray]) -> None:
        # The subclasses are frozen dataclasses: attributes are set once, here.
        for name, arr in zip(names, arrays, strict=True):
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "_n_dof", int(arrays[0].shape[0]))
