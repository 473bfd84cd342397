"""Figures of evaluations: the timeline of every method, and detection rate against force."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from .._validation import FloatArray
from ..evaluation import Evaluation
from ..evaluation.scoring import check_evaluations
from ..exceptions import InputTypeError, InputValueError
from ..signals import Event
from ._common import add_legend, method_colors, shade_windows

__all__ = ["force_bins", "plot_detection_vs_force", "plot_evaluation"]


def _event_bars(events: Sequence[Event], min_width: float) -> list[tuple[float, float]]:
    return [(e.start, max(e.duration, min_width)) for e in events]


def plot_evaluation(
    evaluations: Evaluation | Mapping[str, Evaluation],
    *,
    title: str | None = None,
    figsize: tuple[float, float] | None = None,
) -> Figure:
    """Timeline of collision windows, detections and false alarms.

    One axes; one row per method (top to bottom in the mapping's order).
    Collision windows are shaded across all rows (``ax.patches``); each row
    draws the detecting events in green, the false alarms in red and the
    excused events in grey as bars (``ax.collections``), marks each missed
    window with a red cross and each masked one (an alarm already on when it
    started) with a grey square. Bars are drawn at least 0.2 % of the
    time span wide so that single-sample events stay visible.

    Parameters
    ----------
    evaluations : Evaluation or mapping of str to Evaluation
        Results of :func:`~sensorless.evaluation.evaluate`; a single one is
        labelled by its ``method``.
    title : str, optional
        Figure title.
    figsize : (float, float), optional
        Figure size [in]; default 11 wide and 1.4 + 0.5 per method.

    Returns
    -------
    Figure
        One axes with time along x and the methods along y.

    Raises
    ------
    InputValueError
        The mapping is empty.
    TypeError
        An entry is not an :class:`~sensorless.evaluation.Evaluation`.
    """
    items = _items(evaluations)
    t_start = min(evaluation.t_start for _, evaluation in items)
    t_end = max(evaluation.t_start + evaluation.duration for _, evaluation in items)
    min_width = 0.002 * (t_end - t_start)

    size = figsize if figsize is not None else (11.0, 1.4 + 0.5 * len(items))
    figure = Figure(figsize=size, layout="constrained")
    ax = figure.subplots()
    shade_windows(ax, items[0][1].windows, "collision")
    styles = (
        ("detections", "tab:green", "detection"),
        ("false_alarms", "tab:red", "false alarm"),
        ("excused", "0.6", "excused"),
    )
    labelled: set[str] = set()
    for row, (_, evaluation) in enumerate(items):
        y = len(items) - 1 - row
        for attribute, color, label in styles:
            found = getattr(evaluation, attribute)
            if found:
                ax.broken_barh(
                    _event_bars(found, min_width),
                    (y - 0.3, 0.6),
                    facecolors=color,
                    label=None if label in labelled else label,
                )
                labelled.add(label)
        table = evaluation.per_collision
        for which, marker, color in (("missed", "x", "tab:red"), ("masked", "s", "0.45")):
            if which == "missed":
                chosen = table.loc[~table["detected"] & ~table["masked"]]
            else:
                chosen = table.loc[table["masked"]]
            if len(chosen):
                ax.plot(
                    0.5 * (chosen["start"] + chosen["end"]).to_numpy(dtype=float),
                    np.full(len(chosen), float(y)),
                    linestyle="none",
                    marker=marker,
                    markersize=8,
                    color=color,
                    markerfacecolor="none" if which == "masked" else color,
                    label=None if which in labelled else which,
                )
                labelled.add(which)
    ax.set_yticks(range(len(items)), [name for name, _ in reversed(items)])
    ax.set_ylim(-0.6, len(items) - 0.4)
    ax.set_xlim(t_start, t_end)
    ax.set_xlabel("time [s]")
    ax.grid(True, axis="x", linewidth=0.3)
    add_legend([ax])
    if title is not None:
        figure.suptitle(title)
    return figure


def _items(evaluations: Evaluation | Mapping[str, Evaluation]) -> list[tuple[str, Evaluation]]:
    if isinstance(evaluations, Evaluation):
        return [(evaluations.method or "events", evaluations)]
    if isinstance(evaluations, Mapping):
        return [(str(name), evaluation) for name, evaluation in check_evaluations(evaluations)]
    raise InputTypeError(
        "evaluations must be an Evaluation or a mapping {method name: Evaluation}; got "
        f"{type(evaluations).__name__}"
    )


_NICE_STEPS = (5.0, 10.0, 20.0, 25.0, 50.0, 100.0, 200.0, 500.0)


def force_bins(forces: Sequence[float], max_bins: int = 5) -> list[float]:
    """Edges [N] on a round step that cover ``forces`` with at most ``max_bins`` bins.

    >>> force_bins([12.0, 35.0, 60.0])
    [0.0, 20.0, 40.0, 60.0, 80.0]
    """
    values = [float(f) for f in forces if math.isfinite(float(f))]
    if not values:
        raise InputValueError("force_bins needs at least one finite peak force [N]; got none")
    for step in _NICE_STEPS:
        low = math.floor(min(values) / step) * step
        high = (math.floor(max(values) / step) + 1) * step
        if (high - low) / step <= max_bins:
            break
    return [low + k * step for k in range(round((high - low) / step) + 1)]


def plot_detection_vs_force(
    evaluations: Evaluation | Mapping[str, Evaluation],
    *,
    title: str | None = None,
    figsize: tuple[float, float] | None = None,
) -> Figure:
    """Detection rate against the peak contact force, and every collision by force.

    Two axes. The first: per method, detected / collisions in each force
    bin (:func:`force_bins`), one line with markers (``ax.lines``); the
    number of collisions per bin is written under the bin; lines of equal
    rates are shifted a little apart. The second: one
    row per method and one marker per collision at its peak force: filled
    circle detected, open circle missed, grey square masked. Collisions of
    unknown peak force are left out.

    Parameters
    ----------
    evaluations : Evaluation or mapping of str to Evaluation
        Results of :func:`~sensorless.evaluation.evaluate` on the same run.
    title : str, optional
        Figure title.
    figsize : (float, float), optional
        Figure size [in]; default 11 wide and 2.8 + 0.35 per method.

    Returns
    -------
    Figure

    Raises
    ------
    InputValueError
        The mapping is empty, or no collision has a known peak force.
    TypeError
        An entry is not an :class:`~sensorless.evaluation.Evaluation`.
    """
    items = _items(evaluations)
    forces = items[0][1].per_collision["peak_force"].to_numpy(dtype=float)
    n_known = int(np.isfinite(forces).sum())
    edges: FloatArray = np.asarray(
        force_bins(forces.tolist(), max_bins=min(5, max(2, math.ceil(n_known / 2)))), dtype=float
    )
    known = np.isfinite(forces)
    which = np.clip(np.searchsorted(edges, forces[known], side="right") - 1, 0, len(edges) - 2)
    counts = np.bincount(which, minlength=len(edges) - 1)
    centres = 0.5 * (edges[:-1] + edges[1:])
    colors = method_colors([name for name, _ in items])

    size = figsize if figsize is not None else (11.0, 2.8 + 0.35 * len(items))
    figure = Figure(figsize=size, layout="constrained")
    rate_ax, strip_ax = figure.subplots(
        2, 1, sharex=True, height_ratios=[2.0, 0.4 + 0.35 * len(items)]
    )
    occupied = counts > 0
    # Methods with equal rates would hide each other: each is shifted a little along x.
    shift = 0.04 * (edges[1] - edges[0])
    for k, (name, evaluation) in enumerate(items):
        detected = evaluation.per_collision["detected"].to_numpy(dtype=bool)[known]
        hits = np.bincount(which, weights=detected.astype(float), minlength=len(edges) - 1)
        rate_ax.plot(
            centres[occupied] + shift * (k - 0.5 * (len(items) - 1)),
            100.0 * hits[occupied] / counts[occupied],
            marker="o",
            color=colors[name],
            label=name,
        )
    for centre, count in zip(centres, counts, strict=True):
        rate_ax.annotate(
            f"n = {count}", (centre, 0.0), xytext=(0, -14), textcoords="offset points",
            ha="center", va="top", fontsize="small", annotation_clip=False,
        )  # fmt: skip
    rate_ax.set_ylim(-5.0, 105.0)
    rate_ax.set_ylabel("detected [%]")
    rate_ax.grid(True, linewidth=0.3)
    for edge in edges:
        for ax in (rate_ax, strip_ax):
            ax.axvline(edge, color="0.85", linewidth=0.8, zorder=0)

    labelled: set[str] = set()
    for row, (name, evaluation) in enumerate(items):
        y = len(items) - 1 - row
        table = evaluation.per_collision.loc[known]
        for status, marker, face in (
            ("detected", "o", colors[name]),
            ("missed", "o", "white"),
            ("masked", "s", "0.6"),
        ):
            if status == "missed":
                chosen = table.loc[~table["detected"] & ~table["masked"]]
            else:
                chosen = table.loc[table[status]]
            if len(chosen):
                strip_ax.scatter(
                    chosen["peak_force"].to_numpy(dtype=float),
                    np.full(len(chosen), float(y)),
                    marker=marker,
                    s=50,
                    facecolors=face,
                    edgecolors=colors[name] if status != "masked" else "0.3",
                    linewidths=1.2,
                    zorder=3,
                )
                if status not in labelled:  # a neutral legend entry, not one method's colour
                    strip_ax.scatter([], [], marker=marker, s=50, label=status,
                                     facecolors="0.3" if status == "detected" else face,
                                     edgecolors="0.3")  # fmt: skip
                labelled.add(status)
    strip_ax.set_yticks(range(len(items)), [name for name, _ in reversed(items)])
    strip_ax.set_ylim(-0.6, len(items) - 0.4)
    strip_ax.set_xlim(float(edges[0]), float(edges[-1]))
    strip_ax.set_xlabel("peak contact force [N]")
    add_legend([rate_ax, strip_ax])
    if title is not None:
        figure.suptitle(title)
    return figure
