"""Estimated against true contact force over time, one panel per event.

:func:`plot_isolation` draws the :attr:`~sensorless.evaluation.IsolationEvaluation.forces`
of an isolation evaluation: |F̂|(t) at the event's link and point with its
worst-case band, the true |F|(t) of the simulator and, when the observer
gain was given, the true force through the observer's filter
K_I/(s+K_I) — the most a residual can show. Forces in N, time in s.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from ..evaluation.isolation import IsolationEvaluation
from ..exceptions import InputTypeError, InputValueError
from ._common import TAU_C_COLOR, add_legend

__all__ = ["plot_isolation"]

ESTIMATE_COLOR = "tab:blue"


def plot_isolation(
    evaluation: IsolationEvaluation,
    *,
    max_events: int | None = None,
    figsize: tuple[float, float] | None = None,
) -> Figure:
    """Estimated and true force magnitude over the time of each event.

    Parameters
    ----------
    evaluation : IsolationEvaluation
        From :func:`~sensorless.evaluation.evaluate_isolation` with ``series``.
    max_events : int, optional
        Draw the first ``max_events`` events only (>= 1).
    figsize : (float, float), optional
        Figure size [in]; by default 11 in wide, 2 in per event.

    Returns
    -------
    matplotlib.figure.Figure
        One row per event: |F̂| (blue) with the band |F̂| ± ‖bound‖ shaded,
        the true |F| (orange), the filtered true force (orange, dashed); the
        title gives the collision id, the estimated and the true link and
        the errors at the estimate's time.

    Raises
    ------
    InputValueError
        The evaluation has no force series (pass ``series`` to
        :func:`~sensorless.evaluation.evaluate_isolation`).
    """
    if not isinstance(evaluation, IsolationEvaluation):
        raise InputTypeError(
            f"evaluation must be an IsolationEvaluation; got {type(evaluation).__name__}"
        )
    forces = list(evaluation.forces)
    if max_events is not None:
        if isinstance(max_events, bool) or not isinstance(max_events, int) or max_events < 1:
            raise InputValueError(f"max_events must be an integer >= 1; got {max_events!r}")
        forces = forces[:max_events]
    if not forces:
        raise InputValueError(
            "the evaluation has no force series: pass series= (Isolator.force_series per "
            "estimate) to evaluate_isolation"
        )
    size = figsize if figsize is not None else (11.0, 1.2 + 2.0 * len(forces))
    figure = Figure(figsize=size, layout="constrained")
    # Events have their own time spans: no shared x axis.
    axes = [row[0] for row in figure.subplots(len(forces), 1, squeeze=False)]
    table = evaluation.per_event
    for index, (ax, one) in enumerate(zip(axes, forces, strict=True)):
        magnitude = np.linalg.norm(one.estimated, axis=1)
        spread = np.linalg.norm(one.bound, axis=1)
        spread = np.where(np.isfinite(spread), spread, np.nan)
        ax.fill_between(
            one.t,
            magnitude - spread,
            magnitude + spread,
            color=ESTIMATE_COLOR,
            alpha=0.15,
            linewidth=0,
            label="worst-case band",
        )
        ax.plot(one.t, magnitude, color=ESTIMATE_COLOR, label=r"$|\hat F|$ estimated")
        ax.plot(one.t, np.linalg.norm(one.true, axis=1), color=TAU_C_COLOR, label="|F| true")
        if one.filtered is not None:
            ax.plot(
                one.t,
                np.linalg.norm(one.filtered, axis=1),
                color=TAU_C_COLOR,
                linestyle="--",
                label=r"$K_I/(s+K_I)\,|F|$ true",
            )
        ax.set_ylabel("force [N]")
        ax.set_title(_title(table, index, one.id), fontsize="small", loc="left")
        ax.set_xlabel("time [s]")
    add_legend(axes)
    return figure


def _title(table: pd.DataFrame, index: int, ident: int) -> str:
    """``collision k: link a (true b), point error, |F| error`` for row ``index``."""
    if index >= len(table):
        return f"collision {ident}" if ident else "false alarm"
    row = table.iloc[index]
    head = f"collision {ident}" if ident else "false alarm"
    parts = [f"{head}: link {int(row['link'])}"]
    if ident:
        parts[0] += f" (true {int(row['link_true'])})"
    for name, label, scale, unit in (
        ("point_error", "point error", 1000.0, "mm"),
        ("magnitude_error", "|F| error", 100.0, "%"),
        ("direction_error", "direction error", 180.0 / math.pi, "°"),
    ):
        value = float(row[name])
        if math.isfinite(value):
            parts.append(f"{label} {value * scale:.0f} {unit}")
    return ", ".join(parts)
