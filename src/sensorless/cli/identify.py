"""Identification commands: friction and inertial parameters from logs, excitation trajectories."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import numpy as np
import pandas as pd
import typer

from ..identification.excitation import optimize_excitation
from ..identification.friction import identify_friction
from ..identification.logs import identify_from_logs
from ..io import read_log
from ..report import write_report
from ._common import (
    console,
    nominal_robot,
    output_path,
    print_table,
    run_with_spinner,
    write_yaml,
)

__all__ = ["excite_command", "identify_friction_command", "identify_inertial_command"]


def identify_friction_command(
    logs: Annotated[list[Path], typer.Argument(help="Constant-velocity sweep logs.")],
    robot: Annotated[
        str | None, typer.Option("--robot", help="Nominal model for g(q) (default: the log's).")
    ] = None,
    output: Annotated[
        Path, typer.Option("-o", "--output", help="Result file (YAML); a .html report beside it.")
    ] = Path("friction.yaml"),
    torque: Annotated[
        str, typer.Option("--torque", help="motor (eq. 2.6) or joint (eq. 2.10) torques.")
    ] = "motor",
) -> None:
    """Friction maps and Coulomb, Coulomb + viscous and Stribeck fits from sweeps (§2.4.1)."""
    output_path(output, suffixes=(".yaml", ".yml"))
    results = []
    for path in logs:
        log = read_log(path)
        model = nominal_robot(robot, log, "joint" if torque == "joint" else "motor")
        results.append((path, identify_friction(log, model, torque=torque)))
    write_yaml(output, {str(path): result.to_dict() for path, result in results})
    sections: list[tuple[str, Any]] = [
        (str(path), [result.to_pandas(), result.plot()]) for path, result in results
    ]
    report = write_report(
        output.with_suffix(".html"), title="sensorless: friction identification", sections=sections
    )
    for path, result in results:
        console.print(f"[bold]{path}[/]")
        print_table(result.to_pandas())
    console.print(f"wrote {output} and {report}")


def identify_inertial_command(
    logs: Annotated[list[Path], typer.Argument(help="Logs of the moving robot.")],
    robot: Annotated[str, typer.Option("--robot", help="Built-in name, URDF or scenario:NAME.")],
    output: Annotated[
        Path, typer.Option("-o", "--output", help="Result file (YAML); a .html report beside it.")
    ] = Path("inertial.yaml"),
    torque: Annotated[str, typer.Option("--torque", help="motor or joint torques.")] = "motor",
    zero: Annotated[
        list[str] | None, typer.Option("--zero", help="Standard parameter known to be zero.")
    ] = None,
) -> None:
    """Base inertial and friction parameters by least squares (eq. 2.12-2.13)."""
    output_path(output, suffixes=(".yaml", ".yml"))
    runs = [read_log(path) for path in logs]
    model = nominal_robot(robot, runs[0], "joint" if torque == "joint" else "motor")
    base, result = identify_from_logs(runs, model, torque=torque, zero=zero or ())
    table = result.to_pandas()
    nominal = dict(zip(base.names, base.values, strict=True))
    table.insert(0, "nominal", [nominal.get(name, np.nan) for name in table.index])
    table.insert(0, "formula", [base.formula(n) if n in nominal else "" for n in table.index])
    stats = {
        "r_squared": result.r_squared,
        "residual_std [N m]": result.residual_std,
        "condition_number": result.condition_number,
        "n_rows": result.n_samples,
    }
    write_yaml(
        output,
        {
            "robot": model.name,
            "torque": torque,
            "logs": [str(path) for path in logs],
            "statistics": stats,
            "units": "kg m² (XX..ZZ, Ia), kg m (mX..mZ), kg (m), N m (c_pos, c_neg), "
            "N m s/rad (fv)",
            "parameters": {
                name: {
                    key: float(value) if key != "formula" else value for key, value in row.items()
                }
                for name, row in table.to_dict(orient="index").items()
            },
        },
    )
    report = write_report(
        output.with_suffix(".html"),
        title=f"sensorless: inertial identification of {model.name}",
        sections=[("Statistics", pd.Series(stats)), ("Parameters", table)],
    )
    print_table(table)
    console.print(f"R² = {result.r_squared:.6f}; wrote {output} and {report}")


def excite_command(
    robot: Annotated[str, typer.Option("--robot", help="Built-in name or URDF.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Trajectory (YAML).")] = Path(
        "excitation.yaml"
    ),
    harmonics: Annotated[
        int, typer.Option("--harmonics", min=1, max=20, help="Fourier harmonics.")
    ] = 5,
    frequency: Annotated[
        float, typer.Option("--frequency", help="Fundamental frequency [Hz].")
    ] = 0.1,
    seed: Annotated[int, typer.Option("--seed", min=0, help="Seed of the random starts.")] = 0,
    iterations: Annotated[
        int, typer.Option("--iterations", min=1, max=10_000, help="SLSQP iterations per start.")
    ] = 100,
    restarts: Annotated[
        int, typer.Option("--restarts", min=1, max=100, help="Random starts; the best is kept.")
    ] = 3,
) -> None:
    """Optimise a Fourier excitation trajectory (Swevers 1997) for the base regressor.

    The file's ``trajectory`` entry is a ``type: fourier`` trajectory that a
    scenario file takes as its ``trajectory`` as it is.
    """
    output_path(output, suffixes=(".yaml", ".yml"))
    model = nominal_robot(robot, None)
    result = run_with_spinner(
        f"excitation of {model.name}: {restarts} start(s) x {iterations} iterations",
        lambda: optimize_excitation(
            model,
            n_harmonics=harmonics,
            base_frequency=frequency,
            seed=seed,
            n_restarts=restarts,
            max_iterations=iterations,
        ),
    )
    path = result.to_yaml(output)
    print_table(result.to_pandas())
    console.print(
        f"condition number {result.initial_condition_number:.4g} -> "
        f"{result.condition_number:.4g}; wrote {path}"
    )
