"""The real-arm recipe on the UR10 recordings of ext_observer.

Four recordings of a Universal Robots UR10 (MIT-licensed project
ext_observer, kept in ``../shared/data/ur10-ext_observer``; see its README):
100 Hz with jittery time stamps, joint positions, the velocities the
controller measures, and motor currents that become torques through UR's
current-to-torque gains. They carry no collision labels; six spans that look
like a hand on the arm are :data:`APPARENT_CONTACTS`.

:func:`load_ur10` imports them with the column-mapping CSV importer and its
shipped spec (the 1.1 s gap of ``3times.csv`` splits it into two segments);
:func:`ur10_folds` makes the two folds (identify on one half of
``link4.csv``, tune on it plus the first quarter of ``ur-static.csv``, hold
out the rest); :func:`evaluate_ur10` runs both on a folder;
:func:`standing_residual` shows how far the residual of the standing arm
strays. ``examples/ur10_real_arm.py`` explains the recipe and what the
recordings show. Units SI and radians; time along axis 0.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .._validation import check_type
from ..exceptions import InputValueError
from ..identification import NominalCorrection
from ..io import import_log
from ..monitor import ObserverSettings
from ..robots import RobotModel, load
from .heldout import Fold, RealArmEvaluation, evaluate_folds
from .recordings import Recording, Windows

__all__ = [
    "APPARENT_CONTACTS",
    "FILES",
    "SPEC",
    "STATIC_TUNING",
    "UR10_FOLDER",
    "evaluate_ur10",
    "load_ur10",
    "missing_files",
    "standing_residual",
    "ur10_folds",
]

UR10_FOLDER = Path("..", "shared", "data", "ur10-ext_observer")
"""Default folder of the recordings, relative to the current directory (a checkout's root)."""
FILES = ("link4.csv", "ur-static.csv", "no_torque.csv", "3times.csv")
SPEC = "ur10_ext_observer"
"""Import spec shipped with the library for these files."""
STATIC_TUNING = 0.25
"""Fraction of ``ur-static.csv`` (from its start) used for tuning; the rest is held out."""
APPARENT_CONTACTS: dict[str, Windows] = {
    "link4.csv": ((3.4, 4.3), (9.4, 10.2)),
    "ur-static.csv": ((3.0, 6.6), (11.5, 16.6), (25.2, 31.6), (37.8, 44.0)),
}
"""Spans [s] (time from the file's first sample) that look like a hand on the arm.

Read off the residuals by eye, and generously; not ground truth.
"""


def missing_files(folder: str | Path) -> list[str]:
    """The files of :data:`FILES` that ``folder`` lacks (all of them if it is not a folder)."""
    path = Path(folder)
    return [name for name in FILES if not (path / name).is_file()]


def load_ur10(
    folder: str | Path = UR10_FOLDER, contacts: Mapping[str, Windows] = APPARENT_CONTACTS
) -> dict[str, Recording]:
    """Import the four files: one :class:`Recording` per segment, by name.

    Parameters
    ----------
    folder : str or Path
        Folder holding :data:`FILES`.
    contacts : mapping of str to sequence of (float, float)
        Apparent contacts [s] per file name; ``{}`` treats the recordings as
        collision-free.

    Returns
    -------
    dict of str to Recording
        Keyed by file name, ``"<file>#k"`` for the k-th segment of a file cut
        at a gap; time [s] from each file's first sample.

    Raises
    ------
    FileNotFoundError
        A file of :data:`FILES` is missing.
    """
    missing = missing_files(folder)
    if missing:
        raise FileNotFoundError(f"{folder} lacks the UR10 recordings {missing}; expected {FILES}")
    recordings: dict[str, Recording] = {}
    for name in FILES:
        segments = import_log("csv", Path(folder) / name, spec=SPEC)
        for k, log in enumerate(segments):
            label = name if len(segments) == 1 else f"{name}#{k + 1}"
            recordings[label] = Recording(label, log, tuple(contacts.get(name, ())))
    return recordings


def ur10_folds(
    recordings: Mapping[str, Recording], static_tuning: float = STATIC_TUNING
) -> list[Fold]:
    """The two folds of the recipe.

    ``link4.csv`` is cut into two halves in time. Fold k identifies the
    correction on half k, tunes on half k plus the first ``static_tuning``
    of ``ur-static.csv``, and holds out the other half, the rest of
    ``ur-static.csv`` and every other recording.

    Raises
    ------
    InputValueError
        ``link4.csv`` or ``ur-static.csv`` is missing, or ``static_tuning``
        is not in (0, 1).
    """
    absent = [name for name in ("link4.csv", "ur-static.csv") if name not in recordings]
    if absent:
        raise InputValueError(f"the folds need the recordings {absent}; got {list(recordings)}")
    if not 0.0 < static_tuning < 1.0:
        raise InputValueError(f"static_tuning must be in (0, 1); got {static_tuning!r}")
    link4 = recordings["link4.csv"]
    middle = float(link4.log.t[0]) + link4.log.duration / 2.0
    halves = [link4.part(None, middle, "first half"), link4.part(middle, None, "second half")]
    static = recordings["ur-static.csv"]
    cut = float(static.log.t[0]) + static_tuning * static.log.duration
    start, rest = static.part(None, cut, "start"), static.part(cut, None, "rest")
    others = [r for name, r in recordings.items() if name not in ("link4.csv", "ur-static.csv")]
    return [
        Fold((halves[0],), (halves[0], start), (halves[1], rest, *others)),
        Fold((halves[1],), (halves[1], start), (halves[0], rest, *others)),
    ]


def evaluate_ur10(
    folder: str | Path = UR10_FOLDER,
    *,
    contacts: Mapping[str, Windows] = APPARENT_CONTACTS,
    robot: RobotModel | None = None,
    **options: Any,
) -> RealArmEvaluation:
    """The whole recipe on ``folder``: :func:`load_ur10`, :func:`ur10_folds`, then
    :func:`~sensorless.realarm.evaluate_folds`.

    Parameters
    ----------
    folder : str or Path
        Folder of the recordings.
    contacts : mapping of str to sequence of (float, float)
        Apparent contacts [s] per file (``{}``: every alarm is false).
    robot : RobotModel, optional
        Nominal rigid-body model; by default the built-in ``ur10`` (URDF).
    **options
        ``families``, ``margin_fraction``, ``min_piece`` of :func:`evaluate_folds`.
    """
    model = load("ur10") if robot is None else check_type(robot, RobotModel, "robot")
    return evaluate_folds(ur10_folds(load_ur10(folder, contacts)), model, **options)


def standing_residual(
    recordings: Mapping[str, Recording], robot: RobotModel, correction: NominalCorrection
) -> pd.DataFrame:
    """Largest |r̂| [N m] per joint on the standing arm, bare model vs corrected model.

    Over all of ``ur-static.csv`` and over its stretches between apparent
    contacts; the observer (K_I = 20/s, measured velocity) starts on the
    first sample of each.

    Returns
    -------
    DataFrame
        Rows ``"<URDF|corrected>, <whole file|between contacts>"``, columns
        ``joint 1 ...`` [N m], rounded to 0.1.
    """
    static = recordings["ur-static.csv"]
    settings = ObserverSettings()
    corrected = correction.model(robot)
    rows = {}
    parts: Sequence[tuple[str, list[Any]]] = (
        ("whole file", [static.log]),
        ("between contacts", static.clean_pieces()),
    )
    for label, logs in parts:
        for name, model, apply in (("URDF", robot, False), ("corrected", corrected, True)):
            peak = np.zeros(robot.n_dof)
            for log in logs:
                used = correction.apply(log) if apply else log
                residual = settings.observe(used, model).residual
                peak = np.maximum(peak, np.abs(residual).max(axis=0))
            rows[f"{name}, {label}"] = peak.round(1)
    columns = [f"joint {j}" for j in range(1, robot.n_dof + 1)]
    return pd.DataFrame.from_dict(rows, orient="index", columns=columns)
