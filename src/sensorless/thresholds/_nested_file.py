"""Reading the file of a threshold that holds fitted thresholds (``phased``, ``payload``).

Such a file is the common envelope (:class:`~sensorless.thresholds.file_schema.ThresholdFile`),
params of its own model, and its fitted parts nested under ``attributes``, each a
complete threshold description. :func:`read_nested` checks all of it, reports
every problem with the path of its field in one error, and checks that each part
is for the envelope's robot, signal kind and joint count.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, TypeVar

from pydantic import ValidationError

from ..exceptions import FileFormatError, InputValueError
from ..io.file_schema import (
    FileModel,
    Problem,
    check_format_version,
    file_error,
    problems_of,
    shown,
)
from .file_schema import THRESHOLD_FORMAT_VERSION, ThresholdFile
from .files import threshold_from_dict

if TYPE_CHECKING:
    from .base import Threshold

__all__ = ["read_nested"]

P = TypeVar("P", bound=FileModel)


def read_nested(
    data: Mapping[str, Any],
    source: str,
    params_model: type[P],
    names: Sequence[str],
    part: tuple[str, str],
) -> tuple[ThresholdFile, P, dict[str, Threshold]]:
    """The envelope, the params and the parts ``names`` of a description, checked.

    ``part`` names a part in messages: what it is (``"the part"``) and how a
    mismatch starts (``"a part"``).

    Raises
    ------
    FileFormatError
        Every problem of the description with the path of its field, or a part
        for another robot, signal kind or joint count than the envelope.
    """
    label, noun = part
    if not isinstance(data, Mapping):
        raise file_error(source, [Problem((), f"expected a mapping; got {shown(data)}")])
    check_format_version(data, THRESHOLD_FORMAT_VERSION, source, "threshold")
    n_dof = data.get("n_dof")
    context = {"n_dof": n_dof} if isinstance(n_dof, int) and n_dof >= 1 else None
    problems: list[Problem] = []
    envelope = params = None
    try:
        envelope = ThresholdFile.model_validate(dict(data), context=context)
    except ValidationError as exc:
        problems += problems_of(exc, ThresholdFile)
    try:
        params = params_model.model_validate(data.get("params"), context=context)
    except ValidationError as exc:
        problems += problems_of(exc, params_model, ("params",))
    attributes = data.get("attributes")
    parts: dict[str, Threshold] = {}
    if isinstance(attributes, Mapping):
        problems += [
            Problem(("attributes", key), f"unknown key; expected {', '.join(names)}")
            for key in attributes
            if key not in names
        ]
        for name in names:
            if name not in attributes:
                problems.append(Problem(("attributes", name), "required key is missing"))
                continue
            try:
                parts[name] = threshold_from_dict(attributes[name], None, source=label)
            except (FileFormatError, InputValueError) as exc:
                problems.append(Problem(("attributes", name), str(exc).removeprefix(label + ": ")))
    if problems or envelope is None or params is None or len(parts) < len(names):
        raise file_error(source, problems)
    for name, fitted in parts.items():
        if (fitted.robot_, fitted.kind_, fitted.n_dof_) != (envelope.robot, envelope.kind, n_dof):
            raise file_error(
                source,
                [
                    Problem(
                        ("attributes", name),
                        f"{noun} for robot {fitted.robot_!r}, {fitted.kind_!r} signals and "
                        f"{fitted.n_dof_} joints; the file is for {envelope.robot!r}, "
                        f"{envelope.kind!r} and {n_dof}",
                    )
                ],
            )
    return envelope, params, parts
