"""Any CSV file, through a small YAML spec that maps its columns onto the log format.

The spec says which columns hold the time, the joint positions and,
optionally, the measured velocities, the motor torques or currents (with
per-joint gains), the joint-torque-sensor torques, the vendor's external
torque estimate and a collision label; their units; the delimiter; and
whether the first line is a header. Each key of the spec is named after the
log group it fills (``q``, ``qd``, ``tau_m``, ``tau_j``, ``tau_ext``, see
:mod:`sensorless.io`), plus ``time`` and ``label``. With a header, columns
are named; without one, they are numbered from 1 as in a spreadsheet (the
first column is 1). Columns the spec does not name are ignored.

The spec is validated (pydantic) before the file is opened; a mistake is an
:class:`~sensorless.exceptions.InputValueError` that names the field, e.g.
``tau_m.gains``. The spec of the real UR10 recordings of ext_observer ships
with the package as ``ur10_ext_observer`` (:func:`available_csv_specs`):

.. code-block:: yaml

    description: UR10 recordings of ext_observer (Mikhel 2020, MIT), 100 Hz, no header
    robot: ur10
    header: false
    delimiter: ","
    time: {column: 1, unit: s}
    q: {columns: [2, 3, 4, 5, 6, 7], unit: rad}
    qd: {columns: [8, 9, 10, 11, 12, 13], unit: rad/s}
    tau_m:
      columns: [14, 15, 16, 17, 18, 19]
      unit: A
      gains: [10.0, 10.6956, 8.4566, 9.0029, 9.48, 10.1232]   # N m/A

>>> spec = load_csv_spec("ur10_ext_observer")
>>> spec.robot, spec.header, spec.tau_m.unit, spec.tau_m.gains[1]
('ur10', False, 'A', 10.6956)
>>> load_csv_spec({"time": {"column": "t"}, "q": {"columns": ["a"], "unit": "degrees"}})
Traceback (most recent call last):
...
sensorless.exceptions.InputValueError: invalid CSV import spec (a mapping): q.unit: ...
"""

from __future__ import annotations

import importlib.resources
import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

import numpy as np
import yaml
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError, model_validator

from ...exceptions import InputValueError, UnknownNameError, one_line
from ..log import Log
from ._checks import ColumnKind
from ._csv import TIME_SCALES, ColumnKey, CsvLayout, read_recording
from ._pipeline import Provenance, Timebase, regularize, timebase_doc

if TYPE_CHECKING:
    from typing import Unpack

__all__ = ["CsvSpec", "available_csv_specs", "import_csv", "load_csv_spec"]

IMPORTER_VERSION = 1
"""Version of the conversion rules of this importer, recorded in the metadata."""

_ANGLE_SCALES = {"rad": 1.0, "deg": math.pi / 180.0, "rad/s": 1.0, "deg/s": math.pi / 180.0}


def _column_ref(value: Any) -> Any:
    if isinstance(value, bool) or not isinstance(value, int | str):
        raise ValueError(
            "a column is a header name (text) or, without header, a column number from 1; "
            f"got {value!r}"
        )
    return value


def _gain_list(value: Any) -> Any:
    return [value] if isinstance(value, int | float) and not isinstance(value, bool) else value


ColumnRef = Annotated[int | str, BeforeValidator(_column_ref)]
Gain = Annotated[float, Field(gt=0.0, allow_inf_nan=False)]


class _Part(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class TimeColumn(_Part):
    """The time column and its unit."""

    column: ColumnRef
    unit: Literal["s", "ms", "us", "ns"] = "s"


class _JointColumns(_Part):
    columns: list[ColumnRef] = Field(min_length=1)
    unit: str


class PositionColumns(_JointColumns):
    """Joint positions, one column per joint in joint order."""

    unit: Literal["rad", "deg"] = "rad"


class VelocityColumns(_JointColumns):
    """Measured joint velocities."""

    unit: Literal["rad/s", "deg/s"] = "rad/s"


class TorqueColumns(_JointColumns):
    """Torques [N m] (joint-torque sensors, vendor's external-torque estimate)."""

    unit: Literal["N m"] = "N m"


class MotorTorqueColumns(_JointColumns):
    """Motor torques [N m], or motor currents [A] with gains [N m/A] (torque = gain · current)."""

    unit: Literal["N m", "A"] = "N m"
    gains: Annotated[list[Gain], BeforeValidator(_gain_list)] | None = None

    @model_validator(mode="after")
    def _gains_match_unit(self) -> MotorTorqueColumns:
        if self.unit == "A" and self.gains is None:
            raise ValueError(
                "currents (unit 'A') need gains [N m/A]: one per column, or one for all"
            )
        if self.unit == "N m" and self.gains is not None:
            raise ValueError("gains convert currents to torques; they need unit 'A'")
        if self.gains is not None and len(self.gains) not in (1, len(self.columns)):
            raise ValueError(
                f"gains has {len(self.gains)} values for {len(self.columns)} columns; give one "
                "per column or one for all"
            )
        return self


class LabelColumn(_Part):
    """Collision labels: non-negative integers, 0 = no collision."""

    column: ColumnRef


class CsvSpec(_Part):
    """How the columns of a CSV file map onto the log format (see the module docstring).

    Attributes
    ----------
    description : str
        Free text: where the files come from.
    robot : str, optional
        Robot name, stored as the logs' ``metadata["robot"]``.
    header : bool
        The first line names the columns.
    delimiter : {",", ";", "\\t", " "}, optional
        Field separator (``" "``: any run of whitespace); guessed by default.
    time, q, qd, tau_m, tau_j, tau_ext, label
        Columns and units of each log group.
    """

    description: str = ""
    robot: str | None = None
    header: bool = True
    delimiter: Literal[",", ";", "\t", " "] | None = None
    time: TimeColumn
    q: PositionColumns
    qd: VelocityColumns | None = None
    tau_m: MotorTorqueColumns | None = None
    tau_j: TorqueColumns | None = None
    tau_ext: TorqueColumns | None = None
    label: LabelColumn | None = None

    def joint_groups(self) -> dict[str, _JointColumns]:
        """The per-joint groups present in the spec, by log group name."""
        parts: dict[str, _JointColumns | None] = {"q": self.q, "qd": self.qd}
        parts |= {"tau_m": self.tau_m, "tau_j": self.tau_j, "tau_ext": self.tau_ext}
        return {name: part for name, part in parts.items() if part is not None}

    @model_validator(mode="after")
    def _consistent(self) -> CsvSpec:
        groups = self.joint_groups()
        n_dof = len(self.q.columns)
        for name, part in groups.items():
            if len(part.columns) != n_dof:
                raise ValueError(
                    f"{name}.columns has {len(part.columns)} columns but q.columns has {n_dof}; "
                    "every joint group needs one column per joint"
                )
        refs: list[tuple[str, ColumnRef]] = [("time.column", self.time.column)]
        refs += [(f"{name}.columns", ref) for name, part in groups.items() for ref in part.columns]
        if self.label is not None:
            refs.append(("label.column", self.label.column))
        for where, ref in refs:
            if self.header and not isinstance(ref, str):
                raise ValueError(f"{where}: with header: true, columns are named; got {ref!r}")
            if not self.header and not (isinstance(ref, int) and ref >= 1):
                raise ValueError(
                    f"{where}: with header: false, columns are numbers from 1; got {ref!r}"
                )
        seen: dict[ColumnRef, str] = {}
        for where, ref in refs:
            if ref in seen and seen[ref] != where:
                raise ValueError(f"column {ref!r} is used by both {seen[ref]} and {where}")
            seen[ref] = where
        return self

    def layout(self) -> CsvLayout:
        """The file layout of this spec (0-based positions without header)."""

        def key(ref: ColumnRef) -> ColumnKey:
            return ref - 1 if isinstance(ref, int) else ref

        groups = {
            name: tuple(key(r) for r in part.columns) for name, part in self.joint_groups().items()
        }
        scales = {
            name: np.full(len(part.columns), _ANGLE_SCALES[part.unit])
            for name, part in self.joint_groups().items()
            if part.unit in _ANGLE_SCALES
        }
        if self.tau_m is not None and self.tau_m.gains is not None:
            scales["tau_m"] = np.broadcast_to(self.tau_m.gains, len(self.tau_m.columns)).copy()
        return CsvLayout(
            header=self.header,
            delimiter=self.delimiter,
            time=key(self.time.column),
            time_scale=TIME_SCALES[self.time.unit],
            groups=groups,
            scales=scales,
            label=None if self.label is None else key(self.label.column),
        )


def _spec_dir() -> Path:
    return Path(str(importlib.resources.files("sensorless") / "data" / "importers"))


def available_csv_specs() -> list[str]:
    """Names of the CSV import specs shipped with the package."""
    return sorted(p.stem for p in _spec_dir().glob("*.yaml"))


def _describe(exc: ValidationError) -> str:
    problems = []
    for error in exc.errors():
        where = ".".join(str(part) for part in error["loc"])
        message = str(error["msg"]).removeprefix("Value error, ")
        if error["type"] not in ("value_error", "missing"):
            message += f"; got {error['input']!r}"
        # Checks across fields name their fields themselves.
        problems.append(f"{where}: {message}" if where else message)
    return "; ".join(problems)


def load_csv_spec(spec: CsvSpec | Mapping[str, Any] | str | Path) -> CsvSpec:
    """Load and validate a CSV import spec.

    Parameters
    ----------
    spec : CsvSpec, mapping, str or Path
        A spec, its content as a mapping, the name of a shipped spec
        (:func:`available_csv_specs`) or the path of a YAML file.

    Returns
    -------
    CsvSpec

    Raises
    ------
    InputValueError
        The spec is invalid; the message names each wrong field.
    UnknownNameError
        ``spec`` is neither a shipped spec's name nor an existing file.
    """
    if isinstance(spec, CsvSpec):
        return spec
    if isinstance(spec, Mapping):
        origin, content = "a mapping", spec
    else:
        path = Path(spec)
        if not path.suffix and not path.exists():
            path = _spec_dir() / f"{spec}.yaml"
        if not path.is_file():
            raise UnknownNameError(
                f"unknown CSV import spec {str(spec)!r}: not a file, and not one of the shipped "
                f"specs {available_csv_specs()}"
            )
        origin = str(path)
        try:
            with path.open(encoding="utf-8") as handle:
                content = yaml.safe_load(handle)
        except (yaml.YAMLError, UnicodeDecodeError) as exc:
            raise InputValueError(
                f"invalid CSV import spec ({origin}): not a readable YAML file: {one_line(exc)}"
            ) from None
        if not isinstance(content, Mapping):
            raise InputValueError(
                f"invalid CSV import spec ({origin}): a YAML mapping is needed; got "
                f"{type(content).__name__}"
            )
    try:
        return CsvSpec.model_validate(dict(content))
    except ValidationError as exc:
        raise InputValueError(f"invalid CSV import spec ({origin}): {_describe(exc)}") from None


@timebase_doc
def import_csv(
    path: str | Path,
    spec: CsvSpec | Mapping[str, Any] | str | Path,
    **timebase: Unpack[Timebase],
) -> list[Log]:
    """Import a CSV file whose columns a spec describes.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    spec : CsvSpec, mapping, str or Path
        As :func:`load_csv_spec`, e.g. ``"ur10_ext_observer"``.
    {timebase}

    Raises
    ------
    InputValueError, UnknownNameError
        The spec is invalid or unknown.
    LogFormatError
        The file lacks a column, cannot be parsed, or holds a bad value (the
        message names the file, the column and the row).
    FileNotFoundError
        ``path`` is not a file.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> folder = Path(tempfile.mkdtemp())
    >>> _ = (folder / "run.csv").write_text("0,0.0,1.0\\n10,0.1,1.5\\n20,0.2,2.0\\n")
    >>> spec = {
    ...     "header": False,
    ...     "time": {"column": 1, "unit": "ms"},
    ...     "q": {"columns": [2]},
    ...     "tau_m": {"columns": [3], "unit": "A", "gains": 2.0},
    ... }
    >>> [log] = import_csv(folder / "run.csv", spec)
    >>> log.t.tolist(), log.tau_m[:, 0].tolist(), log.metadata["import"]["source_units"]["tau_m"]
    ([0.0, 0.01, 0.02], [2.0, 3.0, 4.0], 'A')
    """
    checked = load_csv_spec(spec)
    source = Path(path)
    layout = checked.layout()
    kinds: dict[str, ColumnKind] = {"q": "angle"}
    recording = read_recording(source, layout, kinds)
    units: dict[str, str] = {"t": checked.time.unit}
    units |= {name: part.unit for name, part in checked.joint_groups().items()}
    conversions: dict[str, Any] = {}
    if checked.tau_m is not None and checked.tau_m.gains is not None:
        conversions["tau_m"] = {"gains": layout.scales["tau_m"].tolist(), "unit": "N m/A"}
    columns: dict[str, Any] = {"t": checked.time.column}
    columns |= {name: list(part.columns) for name, part in checked.joint_groups().items()}
    if checked.label is not None:
        columns["collision_id"] = checked.label.column
    provenance = Provenance(
        format="csv",
        source=source.resolve(),
        importer=__name__,
        importer_version=IMPORTER_VERSION,
        source_units=units,
        columns=columns,
        conversions=conversions,
        robot=checked.robot,
    )
    return regularize(recording, provenance, **timebase)
