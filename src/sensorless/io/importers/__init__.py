"""Importers of robot recordings in foreign formats, one module per format.

================  ===========================================  =============================
format            files                                        function
================  ===========================================  =============================
``"csv"``         any CSV, described by a YAML spec            :func:`import_csv`
``"franka"``      CSV of libfranka ``RobotState`` fields        :func:`import_franka`
``"ur-rtde"``     CSV recorded through UR's RTDE interface     :func:`import_ur_rtde`
``"ros2"``        ROS 2 bag or MCAP of ``JointState``          :func:`import_ros2`
================  ===========================================  =============================

:func:`import_log` dispatches by format name over several files. Every
importer returns a list of :class:`~sensorless.io.Log`: the *segments* of
the recording. Rows out of time order are sorted, rows repeating a time
stamp are dropped, a step longer than the gap tolerance (3 periods unless
given) cuts the recording rather than being interpolated across, and a
segment whose time stamps jitter is resampled by linear interpolation onto
a regular grid of the nominal period (the median step unless given; with
strong jitter, give it as ``dt``). Time starts at 0 at the earliest sample
of the file; its time in the file's own clock is kept as ``time_origin``. A
malformed file raises :class:`~sensorless.exceptions.LogFormatError` naming
the file, the column and the row (data rows from 0, header not counted; in
a bag, the field, the joint and the message number on the topic).

Each log's metadata records:

- ``robot`` (if known) and ``sample_rate`` [Hz];
- ``import``: ``format``, ``source`` (the file), ``importer`` (module) and
  ``importer_version``, ``sensorless_version``, ``source_units`` (unit of each
  group in the file, e.g. ``"A"`` for currents), ``columns`` (the file's
  columns or fields behind each group), ``conversions`` (gains [N m/A] and
  the like), ``report`` (``rows_read``, ``out_of_order_rows``,
  ``duplicate_rows_dropped``, ``duplicates_with_other_values``,
  ``time_origin`` [s], ``nominal_dt`` [s], ``max_jitter`` [s],
  ``gap_tolerance`` [s], ``gaps`` [s], ``rows_dropped_between_gaps``,
  ``segments``; ROS 2 also ``messages_skipped``) and ``segment``
  (``index``, ``count``, ``first_sample`` in the sorted recording,
  ``n_samples_before`` resampling, its own ``max_jitter`` [s]);
- ``resampled`` (as :func:`~sensorless.io.resample` writes it) when the
  segment was resampled.

The rows of a long file are read in chunks into arrays allocated once, and
the logs share them instead of copying: an hour of a 7-joint arm at 1 kHz
(a 1.2 GB CSV, a 1.5 GB MCAP bag) imports in about 9 and 15 s of CPU time
with a peak of 1.3 and 1.2 GB (``benchmarks/bench_import.py``).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from ...exceptions import InputTypeError, UnknownNameError
from ..log import Log
from ._pipeline import Timebase
from .franka import FRANKA_COLUMNS, import_franka
from .mapping import CsvSpec, available_csv_specs, import_csv, load_csv_spec
from .ros2 import import_ros2
from .ur_rtde import UR_CURRENT_GAINS, import_ur_rtde

__all__ = [
    "FRANKA_COLUMNS",
    "IMPORT_FORMATS",
    "UR_CURRENT_GAINS",
    "CsvSpec",
    "available_csv_specs",
    "import_csv",
    "import_franka",
    "import_log",
    "import_ros2",
    "import_ur_rtde",
    "load_csv_spec",
]

IMPORTERS: dict[str, Callable[..., list[Log]]] = {
    "csv": import_csv,
    "franka": import_franka,
    "ur-rtde": import_ur_rtde,
    "ros2": import_ros2,
}
"""Importer of each format name."""

IMPORT_FORMATS: tuple[str, ...] = tuple(IMPORTERS)
"""Format names understood by :func:`import_log`."""


def import_log(format: str, paths: str | Path | Sequence[str | Path], **options: Any) -> list[Log]:
    """Import recordings in a foreign format.

    Parameters
    ----------
    format : {"csv", "franka", "ur-rtde", "ros2"}
        The files' format (see the module docstring).
    paths : str, Path or sequence of them
        One or more files (or rosbag2 folders), each imported on its own.
    **options
        Keyword options of the format's importer, e.g. ``spec=`` for
        ``"csv"``, ``robot=`` and ``gains=`` for ``"ur-rtde"``, ``topic=`` for
        ``"ros2"``; ``dt=`` [s] and ``gap_tolerance=`` [s] for all.

    Returns
    -------
    list of Log
        The segments of every file, file by file in the order given.

    Raises
    ------
    UnknownNameError
        ``format`` is not one of :data:`IMPORT_FORMATS`.
    InputTypeError
        An option the format's importer does not take, or no path.
    LogFormatError, InputValueError, FileNotFoundError
        As the format's importer.

    Examples
    --------
    >>> import sensorless.io as sio
    >>> sio.import_log("parquet", "run.parquet")
    Traceback (most recent call last):
    ...
    sensorless.exceptions.UnknownNameError: unknown import format 'parquet'; ...
    """
    importer = IMPORTERS.get(format)
    if importer is None:
        raise UnknownNameError(
            f"unknown import format {format!r}; formats: {list(IMPORT_FORMATS)} (a log "
            "already in the sensorless format is read with sensorless.io.read_log)"
        )
    valid = []
    for name, parameter in inspect.signature(importer).parameters.items():
        if parameter.kind is inspect.Parameter.VAR_KEYWORD:
            valid.extend(sorted(Timebase.__optional_keys__))  # **timebase: dt, gap_tolerance
        elif name != "path":
            valid.append(name)
    unknown = sorted(set(options) - set(valid))
    if unknown:
        raise InputTypeError(
            f"unknown option(s) {unknown} for format {format!r}; its options: {valid}"
        )
    files = [paths] if isinstance(paths, str | Path) else list(paths)
    if not files:
        raise InputTypeError("paths must name at least one file")
    logs: list[Log] = []
    for path in files:
        logs.extend(importer(path, **options))
    return logs
