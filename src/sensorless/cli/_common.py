"""What every command shares: the console, user-error handling, paths, the nominal model.

A user's mistake never ends in a traceback: :func:`user_errors` turns it into
one line on stderr and an exit code that says what kind of mistake it was
(``--debug`` before the command shows the traceback instead):

====  ==========================================================================
code  meaning
====  ==========================================================================
2     a bad argument or option (unknown name, value out of range, wrong shape)
3     a file that cannot be found, read or written
4     a file whose content is not what the command expects (log, YAML, model)
1     an internal error (a bug: please report it with the ``--debug`` output)
====  ==========================================================================
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import Any, ParamSpec, TypeVar

import pandas as pd
import typer
import yaml
from rich.console import Console
from rich.progress import (
    BarColumn,
    Progress,
    SpinnerColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from .. import robots as robot_registry
from ..exceptions import FileFormatError, InputValueError, ModelError, SensorlessError, one_line
from ..io import Log
from ..robots.model import RobotModel
from ..simulation.scenario import load_scenario
from ..simulation.simulator import SimulationResult

__all__ = [
    "EXIT_BAD_ARGUMENT",
    "EXIT_BAD_CONTENT",
    "EXIT_FILE",
    "EXIT_INTERNAL",
    "console",
    "nominal_robot",
    "output_path",
    "print_table",
    "run_with_progress",
    "run_with_spinner",
    "user_errors",
    "write_yaml",
]

EXIT_INTERNAL = 1
EXIT_BAD_ARGUMENT = 2
EXIT_FILE = 3
EXIT_BAD_CONTENT = 4

console = Console(log_path=False)
errors = Console(stderr=True, log_path=False, highlight=False, soft_wrap=True)
settings = {"debug": False}

P = ParamSpec("P")
R = TypeVar("R")


def _exit_code(exc: BaseException) -> int:
    if isinstance(exc, (FileFormatError, ModelError, yaml.YAMLError, UnicodeDecodeError)):
        return EXIT_BAD_CONTENT
    if isinstance(exc, OSError):
        return EXIT_FILE
    if isinstance(exc, SensorlessError):
        return EXIT_BAD_ARGUMENT
    return EXIT_INTERNAL


def _describe(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.filename is not None:
        reason = exc.strerror or type(exc).__name__
        return f"{exc.filename}: {reason}"
    if isinstance(exc, yaml.YAMLError):
        return f"not a valid YAML file: {one_line(exc)}"
    if _exit_code(exc) == EXIT_INTERNAL:
        return f"internal error {type(exc).__name__}: {exc} (rerun with --debug for the traceback)"
    return str(exc)


def user_errors(command: Callable[P, R]) -> Callable[P, R]:
    """Run ``command``; a user's mistake becomes one line on stderr and its exit code."""

    @functools.wraps(command)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        try:
            return command(*args, **kwargs)
        except (typer.Exit, typer.Abort, KeyboardInterrupt):
            raise
        except Exception as exc:
            if settings["debug"]:
                raise
            errors.print(f"error: {_describe(exc)}", markup=False)
            raise typer.Exit(code=_exit_code(exc)) from None

    return wrapper


def print_table(table: pd.DataFrame) -> None:
    """A table on stdout, as text."""
    console.print(table.to_string(), soft_wrap=True, highlight=False)


def output_path(path: Path, *, suffixes: tuple[str, ...] = ()) -> Path:
    """Check, before any long work, that ``path`` can be written; create its folder.

    Raises
    ------
    InputValueError
        ``path`` is a folder or has a suffix other than ``suffixes``.
    OSError
        Its folder cannot be created or written.
    """
    if path.is_dir():
        raise InputValueError(f"{path} is a folder; give a file name")
    if suffixes and path.suffix.lower() not in suffixes:
        raise InputValueError(f"{path}: the file name must end in one of {list(suffixes)}")
    path.parent.mkdir(parents=True, exist_ok=True)
    probe = path.parent / f".{path.name}.sensorless-write-check"
    probe.touch()
    probe.unlink()
    return path


def write_yaml(path: Path, content: dict[str, Any]) -> Path:
    """Write ``content`` as YAML (folders created)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(yaml.safe_dump(content, sort_keys=False, allow_unicode=True), encoding="utf-8")
    return path


def run_with_progress(
    label: str, run: Callable[[Callable[[int, int], None]], SimulationResult]
) -> SimulationResult:
    """Run a simulation with a progress bar on the console."""
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeRemainingColumn(),
    )
    with Progress(*columns, console=console, transient=False) as progress:
        task = progress.add_task(label, total=1.0)

        def report(done: int, total: int) -> None:
            progress.update(task, completed=done / total)

        return run(report)


def run_with_spinner(label: str, run: Callable[[], R]) -> R:
    """Run work of unknown length with a spinner and the elapsed time on the console."""
    columns = (SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn())
    with Progress(*columns, console=console, transient=False) as progress:
        task = progress.add_task(label, total=None)
        result = run()
        progress.update(task, total=1.0, completed=1.0, description=f"{label}: done")
        return result


def nominal_robot(robot: str | None, log: Log | None, kind: str = "motor") -> RobotModel:
    """The nominal model: a built-in name, a URDF path, ``scenario:NAME``, or the log's scenario.

    A scenario gives the model the observer ``kind`` needs (:meth:`Scenario.nominal`).
    """
    if robot is None:
        scenario = None if log is None else log.metadata.get("scenario")
        if not scenario:
            raise InputValueError(
                "give --robot (a built-in name, a URDF file or scenario:NAME); "
                "the log names no scenario"
            )
        robot = f"scenario:{scenario}"
    if robot.startswith("scenario:"):
        return load_scenario(robot.split(":", 1)[1]).nominal(kind)
    if robot.endswith(".urdf"):
        return RobotModel.from_urdf(robot)
    return robot_registry.load(robot)
