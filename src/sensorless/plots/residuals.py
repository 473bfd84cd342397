"""Whole-run figures: residuals against bounds, τ_c against the residual, a held-out recording."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_type
from ..evaluation import collision_windows, evaluate
from ..exceptions import DimensionError, InputValueError
from ..io import Log
from ..realarm import HeldOutRun
from ..signals import Event, ObserverSignals
from ._common import (
    RESIDUAL_COLOR,
    RESIDUAL_SYMBOLS,
    TAU_C_COLOR,
    add_legend,
    buckets,
    check_bounds,
    check_joints,
    check_mapping,
    envelope,
    joint_axes,
    method_colors,
    new_figure,
    shade_windows,
)

__all__ = ["plot_held_out", "plot_residuals", "plot_tau_c"]


def _draw_series(
    ax: Axes, t: FloatArray, values: FloatArray, size: int, *, envelope_of: str, **style: object
) -> None:
    """A line, or over buckets of ``size`` samples its max (upper), min (lower) or both (band)."""
    if size == 1:
        ax.plot(t, values, **style)  # type: ignore[arg-type]
        return
    t_bucket = t[::size]
    if envelope_of == "both":
        ax.fill_between(
            t_bucket,
            envelope(values, size, "min"),
            envelope(values, size, "max"),
            step="post",
            linewidth=0,
            color=style.get("color"),
            alpha=0.55,
            label=style.get("label"),
        )
        return
    ax.plot(t_bucket, envelope(values, size, envelope_of), drawstyle="steps-post", **style)  # type: ignore[arg-type]


def _mark_events(
    ax: Axes,
    t: FloatArray,
    residual: FloatArray,
    joint: int,
    name: str,
    color: str,
    groups: tuple[list[Event], list[Event]],
) -> None:
    """Detections as filled triangles, false alarms as crosses, on the residual."""
    for found, marker, size, what in (
        (groups[0], "v", 40, "detection"),
        (groups[1], "X", 60, "false alarm"),
    ):
        starts = [e.start for e in found if not e.joints or joint in e.joints]
        if not starts:
            continue
        ax.scatter(
            starts,
            np.interp(starts, t, np.nan_to_num(residual)),
            marker=marker,
            s=size,
            color=color if what == "detection" else "white",
            edgecolors=color if what == "false alarm" else "black",
            linewidths=1.5 if what == "false alarm" else 0.5,
            zorder=3,
            label=f"{name} {what}",
        )


def plot_residuals(
    signals: ObserverSignals,
    bounds: Mapping[str, tuple[ArrayLike, ArrayLike]] | None = None,
    log: Log | None = None,
    events: Mapping[str, Sequence[Event]] | None = None,
    *,
    joints: Sequence[int] | None = None,
    title: str | None = None,
    figsize: tuple[float, float] | None = None,
) -> Figure:
    """Residuals against threshold bounds with collision windows, detections and false alarms.

    One subplot per joint (sharing the time axis) with, in this order of
    ``ax.lines``: the residual, then for each method of ``bounds`` its upper
    (solid) and lower (dashed) bound in the method's colour. A run longer
    than 3000 samples is drawn decimated to 1500 buckets: the residual as
    its min/max envelope (a band, in ``ax.collections``), the upper bound as
    its maximum and the lower bound as its minimum per bucket, so no
    excursion disappears and the data is not a solid band. Ground-truth
    collision windows of ``log`` are shaded (``ax.patches``). The start of
    each event of ``events`` that involves the joint is marked on the
    residual, one scatter per method and kind: a filled triangle for a
    detection and a white cross for a false alarm (by the rules of
    :func:`~sensorless.evaluation.evaluate`; without ``log`` every event is
    drawn as a detection). The legend sits below the axes, off the data.
    This is the layout of the thesis' Figs. 4.6, 5.6 and 5.13.

    Parameters
    ----------
    signals : ObserverSignals
        Observer output; its ``residual`` [N m] is plotted against ``t`` [s].
    bounds : mapping of str to (lower, upper), optional
        Bounds per method name, each a number, an array of shape (n_dof,) or
        of shape (n_samples, n_dof) [N m] on the time base of ``signals``.
    log : Log, optional
        Labelled run whose collision windows (:func:`~sensorless.evaluation.collision_windows`)
        are shaded and against which events are judged.
    events : mapping of str to list of Event, optional
        Events per method name; methods also in ``bounds`` share its colour.
    joints : sequence of int, optional
        1-based joints to plot; default all.
    title : str, optional
        Figure title.
    figsize : (float, float), optional
        Figure size [in]; default 11 wide and 2 per joint.

    Returns
    -------
    Figure
        One axes per joint, the last one labelled with the time axis.

    Raises
    ------
    InputValueError
        A joint number is out of range or a bounds entry is not a pair.
    DimensionError
        A bound cannot be broadcast to ``(n_samples, n_dof)``.
    TypeError
        ``bounds`` or ``events`` is not a mapping.
    """
    chosen = check_joints(joints, signals.n_dof)
    checked = check_bounds(bounds if bounds is not None else {}, signals.residual.shape)
    found = check_mapping(
        events if events is not None else {}, "events", "method name: list of Event"
    )
    groups: dict[str, tuple[list[Event], list[Event]]] = {}
    for name, listed in found.items():
        if log is None:
            groups[str(name)] = (list(listed), [])
        else:
            judged = evaluate(listed, log)
            groups[str(name)] = (
                [e for e in judged.events if e not in judged.false_alarms],
                list(judged.false_alarms),
            )
    colors = method_colors([*checked, *groups])
    windows = collision_windows(log) if log is not None else []
    symbol = RESIDUAL_SYMBOLS.get(signals.kind, RESIDUAL_SYMBOLS["motor"])
    t = signals.t
    size = buckets(t.size)

    figure = new_figure(len(chosen), figsize)
    axes = joint_axes(figure, len(chosen))
    for ax, joint in zip(axes, chosen, strict=True):
        column = joint - 1
        residual = signals.residual[:, column]
        label = symbol if size == 1 else f"{symbol} (min–max per {size} samples)"
        _draw_series(
            ax, t, residual, size, envelope_of="both", color=RESIDUAL_COLOR, linewidth=0.8,
            label=label,
        )  # fmt: skip
        for name, (lower, upper) in checked.items():
            _draw_series(
                ax, t, upper[:, column], size, envelope_of="max", color=colors[name],
                linewidth=1.0, label=name,
            )  # fmt: skip
            _draw_series(
                ax, t, lower[:, column], size, envelope_of="min", color=colors[name],
                linewidth=1.0, linestyle="--",
            )  # fmt: skip
        shade_windows(ax, windows, "collision")
        for name, pair in groups.items():
            _mark_events(ax, t, residual, joint, name, colors[name], pair)
        ax.set_ylabel(f"{symbol} joint {joint} [N m]")
        ax.set_xlim(float(t[0]), float(t[-1]))
        ax.grid(True, linewidth=0.3)
    axes[-1].set_xlabel("time [s]")
    add_legend(axes)
    if title is not None:
        figure.suptitle(title)
    return figure


def plot_tau_c(
    log: Log,
    signals: ObserverSignals | None = None,
    *,
    joints: Sequence[int] | None = None,
    title: str | None = None,
    figsize: tuple[float, float] | None = None,
) -> Figure:
    """Ground-truth external torque τ_c against the residual, per joint.

    One subplot per joint with ``ax.lines`` = [τ_c] or [τ_c, residual], and
    the collision windows of ``log`` shaded (``ax.patches``).

    Parameters
    ----------
    log : Log
        Run with the ground-truth external joint torques ``tau_c`` [N m].
    signals : ObserverSignals, optional
        Observer output whose residual [N m] is overlaid (on its own time base).
    joints, title, figsize : optional
        As in :func:`plot_residuals`: 1-based joints to plot (default all),
        figure title, figure size [in] (default 11 wide and 2 per joint).

    Returns
    -------
    Figure
        One axes per joint, as :func:`plot_residuals`.

    Raises
    ------
    InputValueError
        The log has no ``tau_c``, or a joint number is out of range.
    DimensionError
        ``signals`` has a different number of joints than the log.
    """
    if log.tau_c is None:
        raise InputValueError(
            "plot_tau_c needs a log with ground-truth external torques (columns tau_c_<j>); "
            f"this log has the groups {log.groups}"
        )
    if signals is not None and signals.n_dof != log.n_dof:
        raise DimensionError(
            f"signals must have the joint count of the log ({log.n_dof}); got {signals.n_dof}"
        )
    chosen = check_joints(joints, log.n_dof)
    windows = collision_windows(log)
    symbol = (
        RESIDUAL_SYMBOLS.get(signals.kind, RESIDUAL_SYMBOLS["motor"]) if signals is not None else ""
    )

    figure = new_figure(len(chosen), figsize)
    axes = joint_axes(figure, len(chosen))
    for ax, joint in zip(axes, chosen, strict=True):
        ax.plot(log.t, log.tau_c[:, joint - 1], color=TAU_C_COLOR, linewidth=1.2, label=r"$\tau_c$")
        if signals is not None:
            ax.plot(
                signals.t,
                signals.residual[:, joint - 1],
                color=RESIDUAL_COLOR,
                linewidth=0.8,
                label=symbol,
            )
        shade_windows(ax, windows, "collision")
        ax.set_ylabel(f"joint {joint} [N m]")
        ax.grid(True, linewidth=0.3)
    axes[-1].set_xlabel("time [s]")
    axes[-1].set_xlim(float(log.t[0]), float(log.t[-1]))
    add_legend(axes)
    if title is not None:
        figure.suptitle(title)
    return figure


def plot_held_out(
    run: HeldOutRun,
    *,
    joints: Sequence[int] | None = None,
    title: str | None = None,
    figsize: tuple[float, float] | None = None,
) -> Figure:
    """The residual of a held-out real recording against every family's bounds.

    :func:`plot_residuals` of the run's residual r̂ [N m], the bounds and
    events of every family, and its apparent contacts shaded as collision
    windows.

    Parameters
    ----------
    run : HeldOutRun
        A held-out recording of :func:`sensorless.realarm.evaluate_folds`.
    joints : sequence of int, optional
        1-based joints to plot; default all.
    title : str, optional
        Figure title; default names the fold and the recording.
    figsize : (float, float), optional
        Figure size [in].

    Returns
    -------
    Figure
    """
    checked = check_type(run, HeldOutRun, "run")
    return plot_residuals(
        checked.signals,
        checked.bounds,
        checked.log,
        checked.events,
        joints=joints,
        title=f"fold {checked.fold}: {checked.name} (shaded: apparent contacts)"
        if title is None
        else title,
        figsize=figsize,
    )
