"""Exception hierarchy of :mod:`sensorless`.

Every error raised on purpose by the library derives from
:class:`SensorlessError`. Each subclass also derives from the built-in
exception a Python user would expect (``ValueError``, ``TypeError``,
``KeyError``, ``FileNotFoundError``), so ``except ValueError`` keeps working.
Messages state what was expected, what was received and, where there is a
closed set, the valid options; :func:`one_line` puts a third-party error's
message on one line inside one of ours.
"""

from __future__ import annotations

__all__ = [
    "DimensionError",
    "FileFormatError",
    "InputTypeError",
    "InputValueError",
    "LogFormatError",
    "MissingFileError",
    "ModelError",
    "ModelMismatchError",
    "NotFittedError",
    "SensorlessError",
    "UnknownNameError",
    "one_line",
]


class SensorlessError(Exception):
    """Root of every error raised by :mod:`sensorless`."""


class DimensionError(SensorlessError, ValueError):
    """An array has the wrong shape or a joint count does not match the robot."""


class InputTypeError(SensorlessError, TypeError):
    """An argument of the wrong type, or an unknown keyword / option name."""


class InputValueError(SensorlessError, ValueError):
    """A value is out of its domain: NaN/inf, negative period, degrees for radians..."""


class ModelError(SensorlessError, ValueError):
    """A robot description is incomplete, inconsistent or cannot be read."""


class ModelMismatchError(ModelError):
    """Data made with one robot model meet another model with the same joint count.

    A threshold fitted on the signals of one model, applied to (or fitted
    together with) signals of another: another robot, the same arm with a
    payload, other parameters. The shapes agree, the numbers do not. Joint
    counts that differ are a :class:`DimensionError` instead.
    """


class UnknownNameError(SensorlessError, KeyError):
    """A name (robot, scenario, method, parameter) is not one of the known ones."""

    def __str__(self) -> str:  # KeyError quotes its message; keep it readable
        return str(self.args[0]) if self.args else ""


class NotFittedError(SensorlessError, ValueError):
    """An estimator (threshold, identification) is used before ``fit``."""


class FileFormatError(SensorlessError, ValueError):
    """A file (log, thresholds, scenario) cannot be read as what it should be."""


class MissingFileError(SensorlessError, FileNotFoundError):
    """A file the library was asked to read does not exist."""


class LogFormatError(FileFormatError):
    """A log file or table does not have the expected columns, time base or values."""


def one_line(reason: object) -> str:
    """``str(reason)`` on one line: runs of whitespace and line breaks become one space.

    For the message of a third-party error (YAML, CSV and Parquet readers,
    rosbags) quoted inside one of ours, which the CLI prints as one line.
    """
    return " ".join(str(reason).split())
