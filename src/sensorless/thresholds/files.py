"""The file format of fitted thresholds and the registry of families that reads it.

A fitted threshold is a plain mapping (:func:`threshold_to_dict`) written as
readable YAML (:func:`save_threshold`): the format version, the method name,
the library version, the robot name, the signal kind, n_dof, the observer
gain K_I [1/s], the sample period [s], the hyper-parameters and the fitted
attributes as (nested) lists. :func:`load_threshold` reads it back and
dispatches on the method name through :data:`METHODS`, which every family
joins by defining the class attribute ``name``.

Every family has one name, the same in files, on the command line, in
:func:`sensorless.tune` and in reports (:data:`FAMILY_NAMES`): ``constant``,
``time-variant``, ``hysteretic`` (the time-variant family's form of eq. 5.39),
``velocity``, ``velocity-combined`` and ``model`` (model-based). Files written
before these names (``time_variant``, ``model_based``, ``velocity_combined``,
and a hysteretic threshold saved as ``time_variant`` with ``params.form:
hysteretic``) are still read (:data:`OLD_NAMES`).

Reading checks the file against its declared format
(:mod:`sensorless.thresholds.file_schema`) before anything is built: the
envelope, the hyper-parameters of the family (those of its constructor) and
the shape and sign of every fitted attribute. A mistake is one
:class:`~sensorless.exceptions.FileFormatError` that lists every problem
with the path of its field (``params.margni: unknown key; did you mean
'margin'?``, ``attributes.alpha_: expected finite numbers >= 0; got -5.0 at
[0]``); a file written in a newer ``format_version`` is refused.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import yaml
from pydantic import ValidationError

from .._version import __version__
from ..exceptions import DimensionError, FileFormatError, InputValueError
from ..io.file_schema import (
    Problem,
    check_format_version,
    did_you_mean,
    file_error,
    problems_of,
    read_yaml_mapping,
    shown,
)
from .file_schema import (
    ATTRIBUTE_SELECTORS,
    THRESHOLD_FORMAT_VERSION,
    ThresholdFile,
    attribute_problems,
    params_model,
)

if TYPE_CHECKING:
    from ..robots.model import RobotModel
    from .base import Threshold

__all__ = [
    "FAMILY_NAMES",
    "METHODS",
    "OLD_NAMES",
    "THRESHOLD_FORMAT_VERSION",
    "envelope",
    "family_class",
    "family_name",
    "load_threshold",
    "save_threshold",
    "threshold_from_dict",
    "threshold_to_dict",
]

METHODS: dict[str, type[Threshold]] = {}
"""Threshold classes by their class attribute ``name`` (filled as each family is defined)."""

READERS: dict[str, Callable[[Mapping[str, Any], str, RobotModel | None], Threshold]] = {}
"""Readers of the ``method`` of thresholds that hold other thresholds (``phased``,
``payload``): each takes the description, its source and the nominal model given
to the loader (or None), and checks it itself; filled by their modules."""

FAMILY_NAMES = (
    "constant", "time-variant", "hysteretic", "velocity", "velocity-combined", "model", "learned",
)  # fmt: skip
"""The one name of each family: in files, on the command line, in the API and in reports."""

OLD_NAMES: dict[str, str] = {
    "time_variant": "time-variant",
    "model_based": "model",
    "velocity_combined": "velocity-combined",
}
"""Spellings of earlier files (and of the classes' ``name``), read as the family they meant."""

_FORMS = {"hysteretic": ("time-variant", "hysteretic")}
"""A family that is another family's form: (that family, its ``form``)."""

_FILE_HEADER = (
    "# sensorless fitted threshold; read it with sensorless.thresholds.load_threshold(path)\n"
)


def _canonical(name: str) -> str:
    return OLD_NAMES.get(name, name)


def family_name(threshold: Threshold) -> str:
    """The family's one name (:data:`FAMILY_NAMES`): ``"hysteretic"`` for that form, ...

    Examples
    --------
    >>> from sensorless.thresholds import TimeVariantThreshold
    >>> family_name(TimeVariantThreshold(form="hysteretic"))
    'hysteretic'
    """
    name = _canonical(threshold.name)
    for family, (parent, form) in _FORMS.items():
        if name == parent and getattr(threshold, "form", None) == form:
            return family
    return name


def family_class(method: str) -> type[Threshold] | None:
    """The class of a family name (:data:`FAMILY_NAMES` or :data:`OLD_NAMES`); None if unknown."""
    name = _canonical(method)
    name = _FORMS.get(name, (name, ""))[0]
    for cls in METHODS.values():
        if _canonical(cls.name) == name:
            return cls
    return None


def _method_problem(method: Any, params: Any) -> Problem | None:
    if not isinstance(method, str):
        return None  # a missing or non-text method is the envelope's to report
    if family_class(method) is not None:
        form = _FORMS.get(method, (None, None))[1]
        if form is not None and isinstance(params, dict) and params.get("form", form) != form:
            return Problem(
                ("params", "form"),
                f"method {method!r} is the form {form!r}; got {params.get('form')!r}",
            )
        return None
    valid = [name for name in FAMILY_NAMES if family_class(name) is not None]
    hint = did_you_mean(method, valid)
    hint = hint if hint.startswith("; did you mean") else ""
    return Problem(
        ("method",),
        f"unknown threshold method {method!r}{hint}; valid methods: {', '.join(valid)}",
    )


# ----------------------------------------------------------------------------- read, write


def _to_builtin(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple | list):
        return [_to_builtin(v) for v in value]
    return value


def envelope(threshold: Threshold, method: str) -> dict[str, Any]:
    """The keys every threshold file starts with (:class:`ThresholdFile` without params and
    attributes), for a fitted ``threshold`` written with ``method``."""
    return {
        "format_version": THRESHOLD_FORMAT_VERSION,
        "method": method,
        "library_version": __version__,
        "robot": threshold.robot_,
        "kind": threshold.kind_,
        "n_dof": int(threshold.n_dof_),
        "gain": threshold.gain_.tolist(),
        "dt": float(threshold.dt_),
        **_fingerprints(threshold),
    }


def threshold_to_dict(threshold: Threshold) -> dict[str, Any]:
    """A fitted threshold as plain Python values (what :func:`save_threshold` writes)."""
    threshold._check_fitted()
    return {
        **envelope(threshold, family_name(threshold)),
        "params": {k: _to_builtin(v) for k, v in threshold.get_params().items()},
        "attributes": {
            name: np.asarray(getattr(threshold, name)).tolist()
            for name in threshold._attribute_names()
        },
    }


def _fingerprints(threshold: Threshold) -> dict[str, str]:
    """The model fingerprints a fitted threshold knows (none for hand-made signals)."""
    found = {"fingerprint": threshold.fingerprint_}
    found["joint_fingerprint"] = getattr(threshold, "joint_fingerprint_", "")
    return {key: value for key, value in found.items() if value}


def _checked(data: Any, source: str) -> tuple[ThresholdFile, type[Threshold]]:
    """The envelope and the family of a description, params checked; else one error."""
    if not isinstance(data, Mapping):
        raise file_error(source, [Problem((), f"expected a mapping; got {shown(data)}")])
    check_format_version(data, THRESHOLD_FORMAT_VERSION, source, "threshold")
    n_dof = data.get("n_dof")
    valid_n = isinstance(n_dof, int) and not isinstance(n_dof, bool) and n_dof >= 1
    context = {"n_dof": n_dof} if valid_n else None
    problems: list[Problem] = []
    envelope = None
    try:
        envelope = ThresholdFile.model_validate(dict(data), context=context)
    except ValidationError as exc:
        problems += problems_of(exc, ThresholdFile)
    method, params = data.get("method"), data.get("params")
    unknown = _method_problem(method, params)
    if unknown is not None:
        problems.insert(0, unknown)
    family = family_class(method) if isinstance(method, str) else None
    if family is not None and isinstance(params, dict):
        form = _FORMS.get(str(method), (None, None))[1]
        if form is not None:  # a form named by the method may leave params.form out
            params = {**params, "form": params.get("form", form)}
        model = params_model(family)
        try:
            model.model_validate(params, context=context)
        except ValidationError as exc:
            problems += problems_of(exc, model, ("params",))
    if problems or envelope is None or family is None:
        raise file_error(source, problems)
    return envelope, family


def threshold_from_dict(
    data: Mapping[str, Any],
    expected: type[Threshold] | None,
    *,
    source: str = "threshold description",
    robot: RobotModel | None = None,
) -> Threshold:
    """Rebuild a fitted threshold from :func:`threshold_to_dict` output.

    Parameters
    ----------
    data : mapping
        The description; its ``method`` selects the family in :data:`METHODS`.
    expected : type, optional
        Family (or base class) the description must hold; None for any.
    source : str
        What ``data`` is, for messages (e.g. ``"threshold file th.yaml"``).
    robot : RobotModel, optional
        The nominal model, for a family that needs it to compute its bounds
        (``payload``); the other families ignore it.

    Raises
    ------
    FileFormatError
        The description does not follow the format: every problem with the
        path of its field (keys, types, shapes, non-finite or wrongly signed
        fitted values, a newer ``format_version``).
    InputValueError
        A valid description of another family than ``expected``.
    """
    method = data.get("method") if isinstance(data, Mapping) else None
    reader = READERS.get(method) if isinstance(method, str) else None
    if reader is not None:
        read = reader(data, source, robot)
        if expected is not None and not isinstance(read, expected):
            raise InputValueError(
                f"the description holds a {method!r} threshold, not {_canonical(expected.name)!r}"
            )
        return read
    envelope, family = _checked(data, source)
    if expected is not None and not issubclass(family, expected):
        raise InputValueError(
            f"the description holds a {_canonical(family.name)!r} threshold, "
            f"not {_canonical(expected.name)!r}"
        )
    params = dict(data["params"])
    form = _FORMS.get(str(data["method"]), (None, None))[1]
    if form is not None:
        params.setdefault("form", form)
    threshold = family(**params)
    threshold.robot_ = envelope.robot
    threshold.fingerprint_ = envelope.fingerprint or ""
    if envelope.joint_fingerprint is not None:
        threshold.joint_fingerprint_ = envelope.joint_fingerprint  # type: ignore[attr-defined]
    threshold.kind_ = envelope.kind
    threshold.n_dof_ = envelope.n_dof
    threshold.gain_ = np.asarray(envelope.gain, dtype=np.float64)
    threshold.dt_ = float(envelope.dt)
    params = threshold.get_params()
    selected = ", ".join(f"params.{k}: {params[k]!r}" for k in ATTRIBUTE_SELECTORS if k in params)
    problems, arrays = attribute_problems(
        threshold._attribute_names(),
        envelope.attributes,
        envelope.n_dof,
        f" for {selected}" if selected else "",
    )
    if problems:
        raise file_error(source, problems)
    for name, value in arrays.items():
        setattr(threshold, name, value)
    try:
        threshold._check_attributes()
    except (DimensionError, InputValueError) as exc:
        raise FileFormatError(f"{source}: {exc}") from None
    return threshold


def save_threshold(threshold: Threshold, path: str | Path) -> Path:
    """Write ``threshold.to_dict()`` to a readable YAML file and return its path."""
    text = yaml.safe_dump(threshold.to_dict(), sort_keys=False, default_flow_style=None, width=100)
    out = Path(path)
    out.write_text(_FILE_HEADER + text, encoding="utf-8")
    return out


def load_threshold(path: str | Path, robot: RobotModel | None = None) -> Threshold:
    """Read a threshold written by ``Threshold.save``.

    ``robot`` is the nominal model, for a family that needs it (``payload``).

    Raises
    ------
    FileNotFoundError
        No such file.
    FileFormatError
        Not a threshold file: binary, not UTF-8, not YAML, not a mapping, a
        newer format, or a description that does not follow the format (every
        problem with the path of its field).
    ModelMismatchError
        A ``payload`` threshold whose nominal model is neither ``robot`` nor
        the built-in robot of its name.
    """
    data = read_yaml_mapping(path, "threshold")
    return threshold_from_dict(data, None, source=f"threshold file {path}", robot=robot)
