"""Reading the columns of a CSV file in chunks into a :class:`Recording`.

The CSV importers (the column-mapping one, Franka, UR RTDE) describe which
file columns make which log group with a :class:`CsvLayout`;
:func:`read_recording` streams the file in chunks of rows (so that an hour at
1 kHz never sits in memory as text or as a full table), keeps only the
columns it needs, converts them to SI units and checks every value, naming
the file, the column and the row (data rows counted from 0, header not
counted) of the first bad one. A row with more fields than the first line
is refused; a row with fewer has empty trailing fields, refused as such.
"""

from __future__ import annotations

import csv
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..._validation import FloatArray
from ...exceptions import InputValueError, LogFormatError, MissingFileError, one_line
from ..columns import abbreviate, show_value
from ._checks import ColumnKind, checked_column
from ._pipeline import Recording, RowBuffer

__all__ = [
    "CHUNK_ROWS",
    "TIME_SCALES",
    "ColumnKey",
    "CsvLayout",
    "column_label",
    "joint_columns",
    "prefixed_groups",
    "read_header",
    "read_recording",
]

ColumnKey = str | int
"""A column by header name, or by 0-based position in a file without header."""

CHUNK_ROWS = 1 << 17
"""Rows per chunk read from a CSV file."""

TIME_SCALES = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
"""Factor from each accepted time unit to seconds."""

_DELIMITERS = (",", ";", "\t", " ")


def column_label(key: ColumnKey) -> str:
    """How error messages name a column: ``column 'dq3'``, or ``column 14`` (from 1)."""
    return f"column {key!r}" if isinstance(key, str) else f"column {key + 1}"


@dataclass(frozen=True)
class CsvLayout:
    """Which columns of a CSV file make which log group, and their conversion to SI.

    Attributes
    ----------
    header : bool
        The first line names the columns (keys are names), else keys are
        0-based positions.
    delimiter : str or None
        Field separator; ``" "`` means any run of whitespace; None: guessed
        from the first line among ``,`` ``;`` tab and space.
    time : ColumnKey
        The time column.
    time_scale : float
        Factor from the file's time unit to seconds.
    groups : dict of str to tuple of ColumnKey
        Log group (``q``, ``qd``, ``tau_m``, ...) to its columns, joint order.
    scales : dict of str to ndarray of shape (n_dof,)
        Per-joint factors from the file's unit to SI (missing: 1).
    label : ColumnKey, optional
        Collision label column.
    """

    header: bool
    delimiter: str | None
    time: ColumnKey
    time_scale: float
    groups: Mapping[str, Sequence[ColumnKey]]
    scales: Mapping[str, FloatArray] = field(default_factory=dict)
    label: ColumnKey | None = None

    def keys(self) -> list[ColumnKey]:
        """Every column the layout reads, without repeats, time first."""
        keys: list[ColumnKey] = [self.time]
        for columns in self.groups.values():
            keys.extend(columns)
        if self.label is not None:
            keys.append(self.label)
        return list(dict.fromkeys(keys))


def _first_line(path: Path) -> str:
    if not path.is_file():
        raise MissingFileError(f"{path} does not exist or is not a file")
    # utf-8-sig: a byte-order mark (spreadsheets write one) is not part of the first name
    with path.open(encoding="utf-8-sig", errors="replace", newline="") as handle:
        line = handle.readline().rstrip("\r\n")
    if not line.strip():
        raise LogFormatError(f"{path}: the first line is empty; expected a header or data")
    return line


def _delimiter(line: str, delimiter: Any) -> str:
    if delimiter is None:
        return next((d for d in _DELIMITERS if d in line.strip()), ",")
    if not isinstance(delimiter, str) or len(delimiter) != 1:
        raise InputValueError(
            f"delimiter must be one character (' ': any run of whitespace) or None to guess "
            f"it; got {delimiter!r}"
        )
    return delimiter


def _split(line: str, delimiter: str) -> list[str]:
    if delimiter == " ":
        return line.split()
    return [name.strip() for name in next(csv.reader([line], delimiter=delimiter))]


def read_header(path: Path, delimiter: str | None = None) -> tuple[list[str], str]:
    """The column names of the first line of ``path`` and the delimiter used.

    Raises
    ------
    FileNotFoundError
        ``path`` is not a file.
    LogFormatError
        The first line is empty or names a column twice.
    """
    line = _first_line(path)
    sep = _delimiter(line, delimiter)
    names = _split(line, sep)
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise LogFormatError(f"{path}: the header names column(s) {repeated} more than once")
    return names, sep


def joint_columns(path: Path, names: list[str], prefix: str, n_dof: int | None) -> list[str]:
    """The columns ``<prefix><j>`` of a header (j = 0, 1, ...), all ``n_dof`` of them or none.

    With ``n_dof`` None, the count is that of the consecutive columns found.

    Raises
    ------
    LogFormatError
        Some but not all of the ``n_dof`` columns are present.
    """
    present = set(names)
    count = 0
    while f"{prefix}{count}" in present:
        count += 1
    if n_dof is None or count == n_dof:
        return [f"{prefix}{j}" for j in range(count)]
    found = [f"{prefix}{j}" for j in range(n_dof) if f"{prefix}{j}" in present]
    if not found:
        return []
    missing = [f"{prefix}{j}" for j in range(n_dof) if f"{prefix}{j}" not in present]
    raise LogFormatError(
        f"{path}: has {len(found)} of the {n_dof} columns {prefix}0..{prefix}{n_dof - 1}; "
        f"missing column(s) {missing}"
    )


def prefixed_groups(
    path: Path, names: list[str], time: str, prefixes: Mapping[str, str]
) -> dict[str, tuple[str, ...]]:
    """The columns ``<prefix><j>`` of each log group named in a header.

    The time column and the first group (the joint positions, which set the
    number of joints) are required; every other group is kept when all its
    columns are present.

    Raises
    ------
    LogFormatError
        The time column or the positions are missing, or a group is partial.
    """
    if time not in names:
        raise LogFormatError(f"{path}: missing column {time!r}; the header has {names[:40]}")
    (first, prefix), *others = prefixes.items()
    positions = joint_columns(path, names, prefix, None)
    if not positions:
        raise LogFormatError(
            f"{path}: missing the joint positions {prefix}0, {prefix}1, ...; the header has "
            f"{names[:40]}"
        )
    groups = {first: tuple(positions)}
    for group, other in others:
        if found := joint_columns(path, names, other, len(positions)):
            groups[group] = tuple(found)
    return groups


def _check_columns(path: Path, layout: CsvLayout) -> str:
    """Check that the file has every column of the layout; return the delimiter."""
    line = _first_line(path)
    sep = _delimiter(line, layout.delimiter)
    if layout.header:
        names, _ = read_header(path, sep)
        missing = [key for key in layout.keys() if key not in names]
        if missing:
            raise LogFormatError(
                f"{path}: missing column(s) {missing}; the header has {names[:40]}"
                + (f" ... ({len(names)} columns)" if len(names) > 40 else "")
            )
    else:
        n_fields = len(_split(line, sep))
        beyond = [key for key in layout.keys() if isinstance(key, int) and key >= n_fields]
        if beyond:
            raise LogFormatError(
                f"{path}: row 0 has {n_fields} columns (delimiter {sep!r}), but "
                f"{column_label(beyond[0])} is needed"
            )
    return sep


def _chunks(path: Path, layout: CsvLayout, sep: str) -> Iterator[pd.DataFrame]:
    # Every column is parsed, not only those of the layout: the parser then refuses a row
    # with more fields than the first (a stray delimiter shifting the values after it),
    # which it lets through when told to keep some columns only.
    options: dict[str, Any] = {
        "header": 0 if layout.header else None,
        "chunksize": CHUNK_ROWS,
        "skipinitialspace": True,
    }
    if sep == " ":
        options["sep"] = r"\s+"
    else:
        options["sep"] = sep
    try:
        with pd.read_csv(path, **options) as reader:
            for chunk in reader:
                if layout.header:
                    # As read_header names them: the parser keeps the spaces after a name.
                    chunk.columns = [str(name).strip() for name in chunk.columns]
                yield chunk
    except (ValueError, pd.errors.ParserError) as exc:
        raise LogFormatError(f"{path}: cannot be parsed as CSV: {one_line(exc)}") from None


def _column(
    chunk: pd.DataFrame,
    key: ColumnKey,
    path: Path,
    first_row: int,
    kind: ColumnKind,
    scale: float = 1.0,
) -> FloatArray:
    """One column of a chunk, checked, times ``scale`` (checked again if an angle)."""
    label = column_label(key)
    if key not in chunk.columns:
        # The first line split one way, the parser another (quotes, stray spaces).
        raise LogFormatError(
            f"{path}: the CSV parser finds no {label} (delimiter and quotes as read: columns "
            f"{abbreviate(list(chunk.columns))}); check the first line"
        )
    values = checked_column(
        chunk[key].to_numpy(),
        source=path,
        column=label,
        first_row=first_row,
        kind=kind if scale == 1.0 else "value",
    )
    if scale == 1.0:
        return values
    with np.errstate(over="ignore"):  # refused, naming the row, below
        scaled = values * scale
    beyond = np.flatnonzero(~np.isfinite(scaled))
    if beyond.size:
        row = int(beyond[0])
        raise LogFormatError(
            f"{path}: {label}, row {first_row + row}: holds {show_value(values[row])}, which "
            f"times its factor {scale:g} (unit or gain) is beyond the range of a float"
        )
    values = scaled
    if kind == "angle":
        checked_column(values, source=path, column=label, first_row=first_row, kind="angle")
    return values


def _check_span(path: Path, key: ColumnKey, t: FloatArray, first_row: int) -> None:
    """Time from the first row must be finite: 1e308 after -1e308 is not."""
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        row = int(bad[0])
        raise LogFormatError(
            f"{path}: {column_label(key)}, row {first_row + row}: is {show_value(t[row])} s from "
            "row 0, beyond the range of a float; time stamps must be finite and comparable"
        )


def _row_estimate(path: Path) -> int:
    """An upper estimate of the lines of a file: its size over the mean length of the first.

    Lines of a log have nearly the same length; the margin of 10 % covers the
    rest, and :class:`RowBuffer` grows if it does not.
    """
    size = path.stat().st_size
    with path.open("rb") as handle:
        head = handle.read(1 << 20)
    lines = max(head.count(b"\n"), 1)
    return int(1.1 * size * lines / max(len(head), 1)) + 16


def read_recording(path: Path, layout: CsvLayout, kinds: dict[str, ColumnKind]) -> Recording:
    """Read the columns of ``layout`` from a CSV file, checked and in SI units.

    Parameters
    ----------
    path : Path
        The CSV file.
    layout : CsvLayout
        Columns and conversions.
    kinds : dict of str to {"angle", "value"}
        Check applied to each group's values (after conversion).

    Returns
    -------
    Recording
        Rows in file order.

    Raises
    ------
    FileNotFoundError
        ``path`` is not a file.
    LogFormatError
        A column is missing, the file cannot be parsed, or a value fails its
        check (the message names the file, the column and the row).
    """
    sep = _check_columns(path, layout)
    widths = {"t": 0} | {group: len(keys) for group, keys in layout.groups.items()}
    if layout.label is not None:
        widths["label"] = 0
    buffer = RowBuffer(_row_estimate(path), widths)
    origin: float | None = None
    for chunk in _chunks(path, layout, sep):
        first_row = buffer.size
        raw = _column(chunk, layout.time, path, first_row, "time")
        if origin is None:
            origin = float(raw[0]) if raw.size else 0.0
        rows = buffer.take(len(chunk))
        # Measured from the first row before scaling: exact for integer stamps (ms or ns
        # since 1970), which seconds since 1970 in float64 are not.
        with np.errstate(over="ignore"):  # an overflow is refused, naming the row, below
            rows["t"][:] = (raw - origin) * layout.time_scale
        _check_span(path, layout.time, rows["t"], first_row)
        for group, keys in layout.groups.items():
            scales = layout.scales.get(group, np.ones(len(keys)))
            kind = kinds.get(group, "value")
            for joint, key in enumerate(keys):
                rows[group][:, joint] = _column(
                    chunk, key, path, first_row, kind, float(scales[joint])
                )
        if layout.label is not None:
            rows["label"][:] = _column(chunk, layout.label, path, first_row, "label")
    if buffer.size == 0:
        raise LogFormatError(f"{path}: holds no data rows")
    columns = buffer.arrays()
    return Recording(
        t=columns.pop("t"),
        groups={group: columns[group] for group in layout.groups},
        collision_id=columns.get("label"),
        time_origin=float(origin or 0.0) * layout.time_scale,
    )
