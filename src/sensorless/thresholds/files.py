"""The file format of fitted thresholds and the registry of families that reads it.

A fitted threshold is a plain mapping (:func:`threshold_to_dict`) written as
readable YAML (:func:`save_threshold`): the method name, the library
version, the robot name, the signal kind, n_dof, the observer gain K_I
[1/s], the sample period [s], the hyper-parameters and the fitted
attributes as (nested) lists. :func:`load_threshold` reads it back and
dispatches on the method name through :data:`METHODS`, which every family
joins by defining the class attribute ``name``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import yaml

from .._version import __version__
from ..exceptions import DimensionError, InputValueError, UnknownNameError

if TYPE_CHECKING:
    from .base import Threshold

__all__ = [
    "METHODS",
    "load_threshold",
    "save_threshold",
    "threshold_from_dict",
    "threshold_to_dict",
]

METHODS: dict[str, type[Threshold]] = {}
"""Threshold families by name (``"constant"``, ``"time_variant"``, ``"velocity"``, ...)."""

_FILE_KEYS = ("method", "robot", "kind", "n_dof", "gain", "dt", "params", "attributes")
_FILE_HEADER = (
    "# sensorless fitted threshold; read it with sensorless.thresholds.load_threshold(path)\n"
)


def _to_builtin(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple | list):
        return [_to_builtin(v) for v in value]
    return value


def threshold_to_dict(threshold: Threshold) -> dict[str, Any]:
    """A fitted threshold as plain Python values (what :func:`save_threshold` writes)."""
    threshold._check_fitted()
    return {
        "method": threshold.name,
        "library_version": __version__,
        "robot": threshold.robot_,
        "kind": threshold.kind_,
        "n_dof": int(threshold.n_dof_),
        "gain": threshold.gain_.tolist(),
        "dt": float(threshold.dt_),
        "params": {k: _to_builtin(v) for k, v in threshold.get_params().items()},
        "attributes": {
            name: np.asarray(getattr(threshold, name)).tolist()
            for name in threshold._attribute_names()
        },
    }


def threshold_from_dict(data: Mapping[str, Any], expected: type[Threshold] | None) -> Threshold:
    """Rebuild a fitted threshold from :func:`threshold_to_dict` output.

    Parameters
    ----------
    data : mapping
        The description; its ``method`` selects the family in :data:`METHODS`.
    expected : type, optional
        Family (or base class) the description must hold; None for any.
    """
    if not isinstance(data, Mapping):
        raise InputValueError(
            f"a threshold description must be a mapping; got {type(data).__name__}"
        )
    missing = [key for key in _FILE_KEYS if key not in data]
    if missing:
        raise InputValueError(
            f"threshold description lacks {missing}; expected keys {list(_FILE_KEYS)}"
        )
    method = data["method"]
    target = METHODS.get(method)
    if target is None:
        raise UnknownNameError(
            f"unknown threshold method {method!r}; valid methods: {sorted(METHODS)}"
        )
    if expected is not None and not issubclass(target, expected):
        raise InputValueError(
            f"the description holds a {method!r} threshold, not {expected.name!r}"
        )
    threshold = target(**dict(data["params"]))
    threshold.robot_ = str(data["robot"])
    threshold.kind_ = str(data["kind"])
    threshold.n_dof_ = int(data["n_dof"])
    threshold.gain_ = np.asarray(data["gain"], dtype=np.float64)
    threshold.dt_ = float(data["dt"])
    if threshold.gain_.shape != (threshold.n_dof_,):
        raise DimensionError(
            f"gain must have {threshold.n_dof_} values; got shape {threshold.gain_.shape}"
        )
    attributes = dict(data["attributes"])
    names = threshold._attribute_names()
    if sorted(attributes) != sorted(names):
        raise InputValueError(
            f"a {method!r} threshold has attributes {list(names)}; "
            f"the description has {sorted(attributes)}"
        )
    for name in names:
        dtype = np.int64 if name in threshold._integer_attributes else np.float64
        try:
            value = np.asarray(attributes[name], dtype=dtype)
        except (TypeError, ValueError):
            raise InputValueError(
                f"attribute {name} must be a (nested) list of numbers; got {attributes[name]!r}"
            ) from None
        setattr(threshold, name, value)
    threshold._check_attributes()
    return threshold


def save_threshold(threshold: Threshold, path: str | Path) -> Path:
    """Write ``threshold.to_dict()`` to a readable YAML file and return its path."""
    text = yaml.safe_dump(threshold.to_dict(), sort_keys=False, default_flow_style=None, width=100)
    out = Path(path)
    out.write_text(_FILE_HEADER + text, encoding="utf-8")
    return out


def load_threshold(path: str | Path) -> Threshold:
    """Read a threshold written by ``Threshold.save``.

    Raises
    ------
    FileNotFoundError
        No such file.
    InputValueError
        Not a threshold file.
    UnknownNameError
        A method that is not in :data:`METHODS`.
    """
    text = Path(path).read_text(encoding="utf-8")
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise InputValueError(f"{path} is not a YAML threshold file: {exc}") from None
    return threshold_from_dict(data, None)
