"""``sensorless plan``: the trajectory along which external torques are estimated best (§ 3.4)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer

from ..exceptions import DimensionError, InputValueError
from ..metric import optimize_trajectory
from ..plots import plot_planned_trajectory
from ._common import console, nominal_robot, output_path, print_table, run_with_spinner

__all__ = ["plan_command"]

_PLOT_SUFFIXES = (".png", ".pdf", ".svg")


def _numbers(text: str, option: str, unit: str) -> list[float]:
    """Comma-separated finite numbers, or one clear error naming the option."""
    parts = [part.strip() for part in text.split(",")]
    try:
        values = [float(part) for part in parts]
    except ValueError:
        values = []
    if not values or not all(math.isfinite(v) for v in values):
        raise InputValueError(
            f"{option} must be comma-separated finite numbers [{unit}], e.g. 0,0.5,-1; got {text!r}"
        )
    return values


def _positions(text: str, option: str, n_dof: int, robot: str, degrees: bool) -> list[float]:
    values = _numbers(text, option, "deg" if degrees else "rad")
    if len(values) != n_dof:
        raise DimensionError(
            f"{option} has {len(values)} value(s); robot {robot} has {n_dof} joints"
        )
    return [math.radians(v) for v in values] if degrees else values


def _via_points(
    via: list[str], n_dof: int, robot: str, degrees: bool
) -> tuple[list[float], list[list[float]]] | tuple[None, None]:
    if not via:
        return None, None
    times, positions = [], []
    for item in via:
        time, sep, rest = item.partition(":")
        if not sep:
            raise InputValueError(
                f"--via must be TIME:q1,q2,... (seconds, then one position per joint); got {item!r}"
            )
        times.append(_numbers(time, "--via time", "s")[0])
        positions.append(_positions(rest, "--via positions", n_dof, robot, degrees))
    return times, positions


def plan_command(
    robot: Annotated[
        str, typer.Option("--robot", help="Built-in name, URDF file or scenario:NAME.")
    ],
    start: Annotated[
        str, typer.Option("--from", help="Start positions q1,q2,... in rad (deg with --degrees).")
    ],
    end: Annotated[str, typer.Option("--to", help="End positions q1,q2,... (as --from).")],
    duration: Annotated[str, typer.Option("--duration", help="Duration T in s, > 0.")],
    output: Annotated[
        Path, typer.Option("-o", "--output", help="Planned trajectory (YAML).")
    ] = Path("traj.yaml"),
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot", help="Figure of both trajectories and their bounds (.png/.pdf/.svg)."
        ),
    ] = None,
    via: Annotated[
        list[str] | None,
        typer.Option("--via", help="Via point TIME:q1,q2,... (repeat for more)."),
    ] = None,
    degrees: Annotated[
        bool, typer.Option("--degrees", help="Positions in degrees instead of radians.")
    ] = False,
    seed: Annotated[
        int, typer.Option("--seed", min=0, help="Seed of the noise draws behind B_Q (Table 3.1).")
    ] = 0,
    iterations: Annotated[
        int, typer.Option("--max-iterations", min=1, max=10_000, help="SLSQP iterations per round.")
    ] = 200,
) -> None:
    """Plan the trajectory from --from to --to that minimises EM (thesis eq. 3.28-3.32).

    The file's ``trajectory`` entry is a ``type: bspline`` trajectory that
    ``sensorless.metric.load_plan`` reads back.
    """
    output_path(output, suffixes=(".yaml", ".yml"))
    if plot is not None:
        output_path(plot, suffixes=_PLOT_SUFFIXES)
    model = nominal_robot(robot, None)
    n, name = model.n_dof, model.name
    q_start = _positions(start, "--from", n, name, degrees)
    q_end = _positions(end, "--to", n, name, degrees)
    total = _numbers(duration, "--duration", "s")
    if len(total) != 1 or total[0] <= 0.0:
        raise InputValueError(f"--duration must be one number of seconds > 0; got {duration!r}")
    via_times, via_positions = _via_points(via or [], n, name, degrees)
    result = run_with_spinner(
        f"planning {name} over {total[0]:g} s",
        lambda: optimize_trajectory(
            model, q_start, q_end, total[0], via_times=via_times, via_positions=via_positions,
            seed=seed, max_iterations=iterations,
        ),
    )  # fmt: skip
    path = result.to_yaml(output)
    written = [str(path)]
    if plot is not None:
        plot_planned_trajectory(result).savefig(plot, dpi=100)
        written.append(str(plot))
    print_table(result.to_pandas())
    status = "" if result.success else f" (warning: {result.message})"
    console.print(
        f"EM {result.initial_metric:.5g} -> {result.metric:.5g} N m s "
        f"({100 * result.improvement:.1f} % lower){status}; wrote {' and '.join(written)}",
        markup=False,
    )
