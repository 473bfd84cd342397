"""Figures of friction identification: the steady-state map and fitted curves (Fig. 2.2)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..exceptions import InputValueError
from ..friction import FrictionModel, LuGre
from ._friction_models import FrictionFit

if TYPE_CHECKING:
    from ._friction_result import FrictionIdentification

__all__ = ["plot_friction_map"]


def plot_friction_map(
    map_df: pd.DataFrame, model: FrictionModel | LuGre | FrictionFit | None = None
) -> Figure:
    """Plot a steady-state friction map with error bars and a fitted curve (Fig. 2.2).

    Parameters
    ----------
    map_df : DataFrame
        Output of :func:`~sensorless.identification.friction.steady_state_map`
        (columns ``velocity`` [rad/s], ``torque`` [N m], optionally
        ``torque_std`` [N m]).
    model : FrictionModel, LuGre or FrictionFit, optional
        One-joint model drawn as a curve over the velocity range; for
        :class:`~sensorless.friction.LuGre` its steady state.

    Returns
    -------
    figure : matplotlib.figure.Figure
    """
    missing = {"velocity", "torque"} - set(map_df.columns)
    if missing:
        raise InputValueError(
            f"map_df must have columns 'velocity' and 'torque'; missing {sorted(missing)}"
        )
    if isinstance(model, FrictionFit):
        model = model.model
    figure = Figure(figsize=(6.0, 4.0))
    curves = {} if model is None else {type(model).__name__: model}
    draw_friction_map(figure.add_subplot(), map_df, curves)
    figure.tight_layout()
    return figure


def plot_friction_identification(result: FrictionIdentification) -> Figure:
    """Friction map and fitted curves of every identified joint, one panel each.

    The figure of :meth:`FrictionIdentification.plot
    <sensorless.identification.friction.FrictionIdentification.plot>`.
    """
    n = len(result.joints)
    ncols = min(n, 4)
    nrows = -(-n // ncols)
    figure = Figure(figsize=(4.0 * ncols, 3.2 * nrows))
    for k, joint in enumerate(result.joints):
        axes = figure.add_subplot(nrows, ncols, k + 1)
        curves = {name: fit.model for name, fit in result.fits[joint].items()}
        draw_friction_map(axes, result.joint_map(joint), curves)
        axes.set_title(f"joint {joint} ({result.torque} torque)")
    figure.tight_layout()
    return figure


def draw_friction_map(
    axes: Axes, map_df: pd.DataFrame, models: Mapping[str, FrictionModel | LuGre]
) -> None:
    """Measured map (with error bars if ``torque_std`` is given) and one curve per model."""
    v = map_df["velocity"].to_numpy()
    std = map_df["torque_std"].to_numpy() if "torque_std" in map_df.columns else None
    axes.errorbar(
        v,
        map_df["torque"].to_numpy(),
        yerr=std,
        fmt="o",
        markersize=3,
        capsize=2,
        color="0.2",
        label="measured",
    )
    grid = np.linspace(v.min(), v.max(), 801)
    grid = grid[grid != 0.0][:, None]
    for name, model in models.items():
        curve = model.steady_state(grid) if isinstance(model, LuGre) else model.torque(grid)
        axes.plot(grid[:, 0], curve[:, 0], "-", label=name)
    axes.axhline(0.0, color="0.7", linewidth=0.5)
    axes.axvline(0.0, color="0.7", linewidth=0.5)
    axes.set_xlabel("joint velocity [rad/s]")
    axes.set_ylabel("friction torque [N m]")
    axes.legend(fontsize="small")
