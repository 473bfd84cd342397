"""Universal Robots: CSV files recorded through the RTDE interface.

The file has a header with RTDE's output names, joints numbered from 0
(as written by UR's ``rtde`` client ``record.py``, space-separated, or by
``ur_rtde``'s file recording, comma-separated; the delimiter is guessed):

==============================  =========  ===========================================
columns                         log group  RTDE output
==============================  =========  ===========================================
``timestamp``                   ``t``      controller time [s]
``actual_q_0`` .. ``_5``        ``q``      actual joint positions [rad]
``actual_qd_0`` .. ``_5``       ``qd``     actual joint velocities [rad/s]
``actual_current_0`` .. ``_5``  ``tau_m``  actual motor currents [A] × gains [N m/A]
``target_moment_0`` .. ``_5``   ``tau_m``  target joint torques [N m] (``torque=
                                           "target_moment"``)
``label``                       ``collision_id``  optional collision label
==============================  =========  ===========================================

**Current-to-torque convention.** A UR joint reports the current of its
motor, not a torque. The joint torque is taken as ``gain · current``, one
gain [N m/A] per joint that lumps the motor's torque constant and the gear
ratio (friction and the motor inertia are left to the model).
:data:`UR_CURRENT_GAINS` holds the published tables; pass ``gains=`` for
another arm or your own identification. No published table is known for the
UR5, so its gains must be given.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from numpy.typing import ArrayLike

from ..._validation import FloatArray, per_joint
from ...exceptions import InputValueError, LogFormatError
from ..log import Log
from ._csv import CsvLayout, joint_columns, prefixed_groups, read_header, read_recording
from ._pipeline import Provenance, Timebase, regularize, timebase_doc

if TYPE_CHECKING:
    from typing import Unpack

__all__ = ["TORQUE_SOURCES", "UR_CURRENT_GAINS", "import_ur_rtde"]

IMPORTER_VERSION = 1
"""Version of the conversion rules of this importer, recorded in the metadata."""

UR_CURRENT_GAINS: dict[str, tuple[float, ...]] = {
    "ur10": (10.0, 10.6956, 8.4566, 9.0029, 9.48, 10.1232),
}
"""Joint torque per motor current [N m/A], base to wrist 3, by robot.

``ur10``: the gains K of the MIT-licensed project ext_observer (S. Mikhel,
2020, ``ur/test.cpp``), used with its real UR10 recordings.
"""

TORQUE_SOURCES: tuple[str, ...] = ("current", "target_moment")
"""Where ``tau_m`` comes from: the currents times the gains, or RTDE's target torque."""

_TORQUE_PREFIXES = {"current": "actual_current_", "target_moment": "target_moment_"}


def _current_gains(robot: str | None, gains: ArrayLike | None, n_dof: int) -> FloatArray:
    """The current-to-torque gains [N m/A]: ``gains`` if given, else the robot's table entry.

    Raises
    ------
    InputValueError
        Neither is given, the robot has no published table, or a gain is not
        positive and finite.
    """
    if gains is not None:
        return per_joint(gains, n_dof, "gains", "N m/A", "positive")
    if robot is None:
        raise InputValueError(
            "torque='current' needs the current-to-torque gains [N m/A]: pass robot= one of "
            f"{sorted(UR_CURRENT_GAINS)} for a published table, or gains= one per joint"
        )
    if robot not in UR_CURRENT_GAINS:
        raise InputValueError(
            f"no published current-to-torque gains are known for robot {robot!r} (tables: "
            f"{sorted(UR_CURRENT_GAINS)}); pass gains= one per joint [N m/A]"
        )
    return per_joint(UR_CURRENT_GAINS[robot], n_dof, f"UR_CURRENT_GAINS[{robot!r}]", "N m/A")


@timebase_doc
def import_ur_rtde(
    path: str | Path,
    *,
    robot: str | None = None,
    gains: ArrayLike | None = None,
    torque: str | None = "current",
    delimiter: str | None = None,
    **timebase: Unpack[Timebase],
) -> list[Log]:
    """Import a CSV file recorded through UR's RTDE interface (see the module docstring).

    Parameters
    ----------
    path : str or Path
        The CSV file, with a header.
    robot : str, optional
        Robot name (e.g. ``"ur10"``): stored as ``metadata["robot"]`` and used
        to look the gains up in :data:`UR_CURRENT_GAINS`.
    gains : float or array-like of shape (n_dof,), optional
        Current-to-torque gains [N m/A]; override the table.
    torque : {"current", "target_moment"} or None
        Source of ``tau_m``: ``actual_current_*`` times the gains, RTDE's
        ``target_moment_*``, or none.
    delimiter : str, optional
        Field separator; guessed from the header by default.
    {timebase}

    Raises
    ------
    LogFormatError
        A missing or partial column group, an unparsable file or a bad value
        (the message names the file, the column and the row).
    InputValueError
        An invalid option, or currents without gains.
    FileNotFoundError
        ``path`` is not a file.
    """
    source = Path(path)
    if torque is not None and torque not in TORQUE_SOURCES:
        raise InputValueError(
            f"torque must be one of {list(TORQUE_SOURCES)} or None; got {torque!r}"
        )
    names, sep = read_header(source, delimiter)
    groups = prefixed_groups(source, names, "timestamp", {"q": "actual_q_", "qd": "actual_qd_"})
    n_dof = len(groups["q"])
    units = {"t": "s", "q": "rad", "qd": "rad/s"}
    scales: dict[str, FloatArray] = {}
    conversions: dict[str, Any] = {}
    if torque is not None:
        prefix = _TORQUE_PREFIXES[torque]
        torques = joint_columns(source, names, prefix, n_dof)
        if not torques:
            raise LogFormatError(
                f"{source}: torque={torque!r} needs the columns {prefix}0..{prefix}{n_dof - 1}; "
                f"the header has none (pass torque=None or the other source of "
                f"{list(TORQUE_SOURCES)})"
            )
        groups["tau_m"] = tuple(torques)
        if torque == "current":
            scales["tau_m"] = _current_gains(robot, gains, n_dof)
            units["tau_m"] = "A"
            conversions["tau_m"] = {"gains": scales["tau_m"].tolist(), "unit": "N m/A"}
        else:
            units["tau_m"] = "N m"
    layout = CsvLayout(
        header=True,
        delimiter=sep,
        time="timestamp",
        time_scale=1.0,
        groups=groups,
        scales=scales,
        label="label" if "label" in names else None,
    )
    recording = read_recording(source, layout, {"q": "angle"})
    columns: dict[str, Any] = {"t": "timestamp"}
    columns |= {group: list(keys) for group, keys in groups.items()}
    if layout.label is not None:
        columns["collision_id"] = "label"
    provenance = Provenance(
        format="ur-rtde",
        source=source.resolve(),
        importer=__name__,
        importer_version=IMPORTER_VERSION,
        source_units={group: units[group] for group in ["t", *groups]},
        columns=columns,
        conversions=conversions,
        robot=robot,
    )
    return regularize(recording, provenance, **timebase)
