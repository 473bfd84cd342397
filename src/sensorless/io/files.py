"""Log files: a Parquet or CSV table plus a JSON metadata sidecar.

:func:`write_log` writes a :class:`~sensorless.io.Log`; :func:`read_log`
reads one back (or a table written by hand) and validates it with
:func:`~sensorless.io.validate_table`. The format comes from the suffix
(``.parquet``/``.pq``, ``.csv``), else from the sidecar ``<path>.meta.json``
(:func:`sidecar_path`), which holds ``n_dof``, the column list, the units,
the sample rate [Hz] and the user metadata.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from .._version import __version__
from ..exceptions import DimensionError, InputValueError, LogFormatError, MissingFileError, one_line
from .columns import UNITS, abbreviate
from .log import Log
from .validate import TableChecks

if TYPE_CHECKING:
    from typing import Unpack

__all__ = ["FORMATS", "read_log", "sidecar_path", "write_log"]

FORMATS: tuple[str, ...] = ("parquet", "csv")
"""File formats understood by :func:`write_log` and :func:`read_log`."""

_SUFFIXES = {".parquet": "parquet", ".pq": "parquet", ".csv": "csv"}
_SIDECAR_SUFFIX = ".meta.json"
_FORMAT_VERSION = 1
# pandas before 3.1 parses CSV floats with a fast converter that is not guaranteed to be
# correctly rounded; its "round_trip" converter is. From 3.1 on every mode uses the exact
# converter and passing the option only warns.
_CSV_READ_OPTIONS: dict[str, Any] = (
    {"float_precision": "round_trip"}
    if tuple(map(int, re.findall(r"\d+", pd.__version__)[:2])) < (3, 1)
    else {}
)


def sidecar_path(path: str | Path) -> Path:
    """Path of the metadata sidecar of the log file ``path``: ``<path>.meta.json``."""
    path = Path(path)
    return path.with_name(path.name + _SIDECAR_SUFFIX)


def _check_format(format: Any) -> str:
    if format not in FORMATS:
        raise InputValueError(f"format must be one of {list(FORMATS)} or None; got {format!r}")
    return str(format)


def write_log(log: Log, path: str | Path, format: str | None = None) -> Path:
    """Write a log table and its metadata sidecar ``<path>.meta.json``.

    Parameters
    ----------
    log : Log
        The log to write.
    path : str or Path
        Destination of the table.
    format : {'parquet', 'csv'}, optional
        File format; by default taken from the suffix (``.csv`` -> CSV,
        ``.parquet``/``.pq`` -> Parquet) and Parquet for any other suffix.

    Returns
    -------
    Path
        ``path``.

    Notes
    -----
    Parquet stores float64 exactly; CSV writes every float with 17
    significant digits (``%.17g``), which also reads back exactly. The same
    log written twice gives the same bytes for CSV and the same table for
    Parquet. The sidecar is pretty-printed JSON with ``format``, ``n_dof``,
    ``n_samples``, ``columns``, ``units``, ``sample_rate`` [Hz] (from the
    median step), ``sensorless_version`` and the user ``metadata``.

    Raises
    ------
    InputValueError
        ``format`` is not one of ``'parquet'``, ``'csv'`` or None.
    """
    path = Path(path)
    if format is None:
        fmt = _SUFFIXES.get(path.suffix.lower(), "parquet")
    else:
        fmt = _check_format(format)
    table = log.to_pandas()
    if fmt == "parquet":
        table.to_parquet(path, engine="pyarrow", index=False)
    else:
        table.to_csv(path, index=False, float_format="%.17g", lineterminator="\n")
    present = ["t", *log.groups] + (["collision_id"] if log.collision_id is not None else [])
    sidecar = {
        "format": fmt,
        "format_version": _FORMAT_VERSION,
        "sensorless_version": __version__,
        "n_dof": log.n_dof,
        "n_samples": log.n_samples,
        "columns": list(table.columns),
        "units": {name: UNITS[name] for name in present},
        "sample_rate": 1.0 / log.dt,
        "metadata": log.metadata,
    }
    sidecar_path(path).write_text(
        json.dumps(sidecar, indent=2, allow_nan=False) + "\n", encoding="utf-8"
    )
    return path


def _read_sidecar(path: Path) -> dict[str, Any] | None:
    meta_path = sidecar_path(path)
    if not meta_path.exists():
        return None
    try:
        sidecar = json.loads(meta_path.read_text(encoding="utf-8"))
    except ValueError as exc:
        raise LogFormatError(f"metadata sidecar {meta_path} is not valid JSON: {exc}") from None
    if not isinstance(sidecar, dict):
        raise LogFormatError(
            f"metadata sidecar {meta_path} must hold a JSON object; got {type(sidecar).__name__}"
        )
    if not isinstance(sidecar.get("metadata", {}), dict):
        raise LogFormatError(f"'metadata' in {meta_path} must be a JSON object")
    return sidecar


def _listed(columns: Any) -> str:
    return abbreviate(columns) if isinstance(columns, list) else repr(columns)


def read_log(
    path: str | Path,
    n_dof: int | None = None,
    *,
    format: str | None = None,
    **checks: Unpack[TableChecks],
) -> Log:
    """Read and validate a log written by :func:`write_log` (or by hand).

    Parameters
    ----------
    path : str or Path
        The table file.
    n_dof : int, optional
        Number of joints of the robot the log is for; checked against the log.
    format : {'parquet', 'csv'}, optional
        File format; by default from the suffix, else from the sidecar.
    check_regular, rtol, allow_missing : keyword-only
        As in :func:`~sensorless.io.validate_table`; pass
        ``check_regular=False`` to read a jittery log and then
        :func:`~sensorless.io.resample` it, ``allow_missing=True`` to read a
        log with lost samples for the monitor.

    Returns
    -------
    Log
        With the sidecar's user metadata, or empty metadata when the file
        has no sidecar.

    Raises
    ------
    LogFormatError
        The format cannot be determined, the file cannot be parsed, the table
        fails :func:`~sensorless.io.validate_table`, or the sidecar is invalid or disagrees
        with the table (``n_dof``, ``columns``).
    DimensionError
        ``n_dof`` differs from the joint count of the log.
    MissingFileError
        ``path`` does not exist (a ``FileNotFoundError``).
    """
    path = Path(path)
    sidecar = _read_sidecar(path)
    if format is not None:
        fmt = _check_format(format)
    elif path.suffix.lower() in _SUFFIXES:
        fmt = _SUFFIXES[path.suffix.lower()]
    elif sidecar is not None and sidecar.get("format") in FORMATS:
        fmt = str(sidecar["format"])
    else:
        raise LogFormatError(
            f"cannot tell the format of {path} from its suffix {path.suffix!r}; known "
            f"suffixes are {sorted(_SUFFIXES)}, or pass format= one of {list(FORMATS)}"
        )
    if not path.exists():
        raise MissingFileError(f"log file {path} does not exist")
    try:
        if fmt == "parquet":
            table = pd.read_parquet(path, engine="pyarrow")
        else:
            table = pd.read_csv(path, **_CSV_READ_OPTIONS)
    except (ValueError, OSError) as exc:
        if isinstance(exc, OSError) and exc.errno is not None:
            raise  # the system's error (permissions, a folder, ...), not the content's
        # pyarrow reports a corrupt Parquet file as an OSError without errno.
        raise LogFormatError(f"cannot read {path} as {fmt}: {one_line(exc)}") from None
    metadata = sidecar.get("metadata", {}) if sidecar is not None else {}
    try:
        log = Log.from_pandas(table, metadata, n_dof, **checks)
    except (LogFormatError, DimensionError) as exc:
        raise type(exc)(f"{path}: {exc}") from None
    if sidecar is not None:
        meta_path = sidecar_path(path)
        if "n_dof" in sidecar and sidecar["n_dof"] != log.n_dof:
            raise LogFormatError(
                f"sidecar {meta_path} says n_dof = {sidecar['n_dof']!r}, but the table "
                f"{path} has {log.n_dof} joints"
            )
        if "columns" in sidecar and sidecar["columns"] != list(table.columns):
            raise LogFormatError(
                f"sidecar {meta_path} lists columns {_listed(sidecar['columns'])}, "
                f"but the table {path} has {abbreviate(list(table.columns))}"
            )
    return log
