"""Franka Emika robots: CSV files of libfranka ``RobotState`` fields.

The file has a header naming the fields as they are commonly logged, one
column per joint numbered from 0:

============================  ===========  =========================================
columns                       log group    libfranka ``RobotState`` field
============================  ===========  =========================================
``time``                      ``t``        ``time`` (unit: ``time_unit``)
``q0`` .. ``q6``              ``q``        ``q``, measured joint position [rad]
``dq0`` .. ``dq6``            ``qd``       ``dq``, measured joint velocity [rad/s]
``tau_J0`` .. ``tau_J6``      ``tau_j``    ``tau_J``, measured link-side joint torque [N m]
``tau_J_d0`` .. ``tau_J_d6``  ``tau_m``    ``tau_J_d``, desired torque *without gravity* [N m],
                                           only with ``gravity_model`` (see below)
``tau_ext0`` .. ``tau_ext6``  ``tau_ext``  ``tau_ext_hat_filtered``, Franka's own external
                                           torque estimate [N m], kept as a baseline
``label``                     ``collision_id``  optional collision label
============================  ===========  =========================================

Only ``time`` and the positions are required; every other group is read
when all its columns are present. Franka's torque sensors make ``tau_J`` the
input of the observer with joint torque sensors (``kind="joint"``). The
robot exposes no motor current: the commanded torque is ``tau_J_d`` plus the
gravity torque its controller adds, so ``tau_m`` is built only when a model
is given for that gravity (``tau_m = tau_J_d + g(q)``, recorded in the
metadata), e.g. ``sensorless.robots.load("panda")``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from ...exceptions import DimensionError, InputTypeError, InputValueError, LogFormatError
from ..log import Log
from ._csv import (
    TIME_SCALES,
    CsvLayout,
    joint_columns,
    prefixed_groups,
    read_header,
    read_recording,
)
from ._pipeline import Provenance, Timebase, regularize, timebase_doc

if TYPE_CHECKING:
    from typing import Unpack

    from ...robots import RobotModel

__all__ = ["FRANKA_COLUMNS", "import_franka"]

IMPORTER_VERSION = 1
"""Version of the conversion rules of this importer, recorded in the metadata."""

FRANKA_COLUMNS: dict[str, str] = {
    "q": "q",
    "qd": "dq",
    "tau_j": "tau_J",
    "tau_ext": "tau_ext",
}
"""Log group to the column prefix of the ``RobotState`` field that fills it (positions first)."""

_COMMANDED = "tau_J_d"


def _time_scale(unit: Any) -> float:
    """Factor from ``unit`` (``"s"``, ``"ms"``, ``"us"``, ``"ns"``) to seconds."""
    if unit not in TIME_SCALES:
        raise InputValueError(f"time_unit must be one of {list(TIME_SCALES)}; got {unit!r}")
    return TIME_SCALES[unit]


def _groups(
    source: Path, names: list[str], gravity_model: RobotModel | None
) -> tuple[dict[str, tuple[str, ...]], dict[str, Any]]:
    """The header's columns of each log group, and the conversions applied to them."""
    groups = prefixed_groups(source, names, "time", FRANKA_COLUMNS)
    n_dof = len(groups["q"])
    conversions: dict[str, Any] = {}
    if gravity_model is not None:
        if gravity_model.n_dof != n_dof:
            raise DimensionError(
                f"gravity_model {gravity_model.name!r} has {gravity_model.n_dof} joints, the "
                f"file {source} has {n_dof}"
            )
        commanded = joint_columns(source, names, _COMMANDED, n_dof)
        if not commanded:
            raise LogFormatError(
                f"{source}: gravity_model needs the columns {_COMMANDED}0..{_COMMANDED}"
                f"{n_dof - 1}; the header has none"
            )
        groups["tau_m"] = tuple(commanded)
        conversions["tau_m"] = f"tau_J_d + g(q) of the model {gravity_model.name!r}"
    return groups, conversions


@timebase_doc
def import_franka(
    path: str | Path,
    *,
    time_unit: str = "s",
    gravity_model: RobotModel | None = None,
    delimiter: str | None = None,
    **timebase: Unpack[Timebase],
) -> list[Log]:
    """Import a CSV file of libfranka ``RobotState`` fields (see the module docstring).

    Parameters
    ----------
    path : str or Path
        The CSV file, with a header.
    time_unit : {"s", "ms", "us", "ns"}
        Unit of the ``time`` column (libfranka's own ``time`` counts ms).
    gravity_model : RobotModel, optional
        Model whose gravity torque g(q) [N m] is added to ``tau_J_d`` to make
        the commanded torque ``tau_m``; without it the log has no ``tau_m``.
    delimiter : str, optional
        Field separator; guessed from the header by default.
    {timebase}

    Raises
    ------
    LogFormatError
        A required or partial column group, an unparsable file or a bad
        value (the message names the file, the column and the row).
    DimensionError
        ``gravity_model`` has another number of joints.
    InputValueError
        An invalid option.
    FileNotFoundError
        ``path`` is not a file.
    """
    source = Path(path)
    scale = _time_scale(time_unit)
    # Imported here: reading a file needs no robot model (nor Pinocchio).
    from ...robots import RobotModel

    if gravity_model is not None and not isinstance(gravity_model, RobotModel):
        raise InputTypeError(
            f"gravity_model must be a RobotModel or None; got {type(gravity_model).__name__}"
        )
    names, sep = read_header(source, delimiter)
    groups, conversions = _groups(source, names, gravity_model)
    layout = CsvLayout(
        header=True,
        delimiter=sep,
        time="time",
        time_scale=scale,
        groups=groups,
        label="label" if "label" in names else None,
    )
    recording = read_recording(source, layout, {"q": "angle"})
    if gravity_model is not None:
        recording.groups["tau_m"] += gravity_model.gravity(recording.groups["q"])
    units = {"t": time_unit} | {group: "rad" if group == "q" else "N m" for group in groups}
    if "qd" in groups:
        units["qd"] = "rad/s"
    columns: dict[str, Any] = {"t": "time"} | {group: list(keys) for group, keys in groups.items()}
    if layout.label is not None:
        columns["collision_id"] = "label"
    provenance = Provenance(
        format="franka",
        source=source.resolve(),
        importer=__name__,
        importer_version=IMPORTER_VERSION,
        source_units=units,
        columns=columns,
        conversions=conversions,
    )
    return regularize(recording, provenance, **timebase)
