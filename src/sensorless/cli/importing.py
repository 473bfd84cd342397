"""``sensorless import``: recordings of real arms into the sensorless log format."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from .. import robots as robot_registry
from ..exceptions import InputValueError
from ..io import IMPORT_FORMATS, import_log, write_log
from ._common import console, output_path

__all__ = ["import_command"]


def _numbers(text: str, name: str) -> list[float]:
    try:
        return [float(part) for part in text.split(",")]
    except ValueError:
        raise InputValueError(f"{name} must be comma-separated numbers; got {text!r}") from None


def import_command(
    format: Annotated[str, typer.Argument(help=f"One of {', '.join(IMPORT_FORMATS)}.")],
    files: Annotated[list[Path], typer.Argument(help="Files (or rosbag2 folders) to import.")],
    output: Annotated[
        Path, typer.Option("-o", "--output", help="Log file (.parquet or .csv).")
    ] = Path("log.parquet"),
    spec: Annotated[
        str | None,
        typer.Option("--spec", help="csv: a YAML column spec, or a shipped one by name."),
    ] = None,
    robot: Annotated[
        str | None, typer.Option("--robot", help="ur-rtde, ros2: robot for the gains.")
    ] = None,
    gains: Annotated[
        str | None, typer.Option("--gains", help="Current-to-torque gains [N m/A], a,b,...")
    ] = None,
    topic: Annotated[str | None, typer.Option("--topic", help="ros2: JointState topic.")] = None,
    joints: Annotated[
        str | None, typer.Option("--joints", help="ros2: joint names in order, a,b,...")
    ] = None,
    time_unit: Annotated[
        str | None, typer.Option("--time-unit", help="franka: s, ms, us or ns.")
    ] = None,
    dt: Annotated[
        float | None, typer.Option("--dt", min=0.0, help="Sample period to resample to [s].")
    ] = None,
    gap_tolerance: Annotated[
        float | None,
        typer.Option("--gap-tolerance", min=0.0, help="A longer step splits the log [s]."),
    ] = None,
) -> None:
    """Import recordings (column-mapped CSV, Franka, UR RTDE, ROS 2 bags) as sensorless logs.

    Each gap in time splits a recording into segments; one segment is written
    to OUTPUT, several to OUTPUT-1, OUTPUT-2, ... beside it.
    """
    output_path(output, suffixes=(".parquet", ".pq", ".csv"))
    options: dict[str, Any] = {
        "spec": spec,
        "robot": robot,
        "topic": topic,
        "time_unit": time_unit,
        "dt": dt,
        "gap_tolerance": gap_tolerance,
        "gains": None if gains is None else _numbers(gains, "--gains"),
        "joints": None if joints is None else [name.strip() for name in joints.split(",")],
    }
    if format == "franka" and robot is not None:
        options["gravity_model"] = robot_registry.load(options.pop("robot"))
    if format == "ros2" and gains is not None:
        options["effort_gains"] = options.pop("gains")
    logs = import_log(format, files, **{k: v for k, v in options.items() if v is not None})
    if len(logs) == 1:
        targets = [output]
    else:
        targets = [
            output.with_name(f"{output.stem}-{k}{output.suffix}") for k in range(1, 1 + len(logs))
        ]
    for log, target in zip(logs, targets, strict=True):
        path = write_log(log, target)
        console.print(
            f"wrote {path}: {log.n_samples} samples of {log.n_dof} joints, "
            f"{log.duration:.3f} s at dt = {log.dt:g} s, groups {log.groups}"
        )
