"""A planned trajectory against the quintic it replaces, and the bounds B_c(t) along both.

:func:`plot_planned_trajectory` draws a
:class:`~sensorless.metric.PlannedTrajectory` (thesis § 3.4): per joint, the
positions of both trajectories (left) and the model-based bound B_c(t) of
eq. 3.36 along each (right); the title states EM[q] (eq. 3.32) of both.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from .._validation import check_type
from ..metric import PlannedTrajectory
from ._common import METHOD_COLORS, check_joints

__all__ = ["plot_planned_trajectory"]

_PLANNED, _QUINTIC = METHOD_COLORS[0], "0.45"


def plot_planned_trajectory(
    result: PlannedTrajectory,
    *,
    joints: Sequence[int] | None = None,
    title: str | None = None,
    figsize: tuple[float, float] | None = None,
) -> Figure:
    """Positions [rad] and bounds B_c(t) [N m] of the planned trajectory and the quintic.

    One row per joint: ``axes[2 r]`` shows q_j(t) of the planned trajectory
    (solid) and the quintic (dashed), ``axes[2 r + 1]`` the bound B_c,j(t)
    along each, in the same styles (``ax.lines`` = [planned, quintic]).

    Parameters
    ----------
    result : PlannedTrajectory
        From :func:`sensorless.metric.optimize_trajectory`.
    joints : sequence of int, optional
        1-based joints to plot; default all.
    title : str, optional
        Figure title; default the robot and EM of both trajectories.
    figsize : (float, float), optional
        Size [in]; default 11 wide and 1.9 per joint.

    Returns
    -------
    Figure
    """
    check_type(result, PlannedTrajectory, "result", " (from optimize_trajectory)")
    chosen = check_joints(joints, len(result.joint_names))
    size = figsize if figsize is not None else (11.0, 1.2 + 1.9 * len(chosen))
    figure = Figure(figsize=size, layout="constrained")
    grid = figure.subplots(len(chosen), 2, sharex=True, squeeze=False)
    q_planned = result.trajectory.evaluate(result.t)[0]
    q_initial = result.initial.evaluate(result.t)[0]
    for row, joint in zip(grid, chosen, strict=True):
        j = joint - 1
        left, right = row
        left.plot(result.t, np.rad2deg(q_planned[:, j]), color=_PLANNED, label="planned")
        left.plot(result.t, np.rad2deg(q_initial[:, j]), "--", color=_QUINTIC, label="quintic")
        left.set_ylabel(f"q{joint} [deg]")
        right.plot(result.t, result.bound[:, j], color=_PLANNED, label="planned")
        right.plot(result.t, result.initial_bound[:, j], "--", color=_QUINTIC, label="quintic")
        right.set_ylabel(f"$B_{{c,{joint}}}$ [N m]")
        for ax in row:
            ax.grid(True, alpha=0.3)
    grid[0][0].legend(loc="best", fontsize="small")
    grid[0][0].set_title("joint positions")
    grid[0][1].set_title("model-based bound $B_c(t)$ (eq. 3.36)")
    for ax in grid[-1]:
        ax.set_xlabel("t [s]")
    if title is None:
        title = (
            f"{result.robot}: EM = {result.metric:.4g} N m s planned vs "
            f"{result.initial_metric:.4g} N m s quintic ({100 * result.improvement:.1f} % lower)"
        )
    figure.suptitle(title)
    return figure
