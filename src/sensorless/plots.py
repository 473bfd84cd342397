"""Figures of residuals, thresholds, collision windows and evaluations.

Every function returns a :class:`matplotlib.figure.Figure` built without
:mod:`matplotlib.pyplot`, so no GUI backend is needed or selected and nothing
is shown: save it with ``fig.savefig(path)`` or embed it in a report
(:func:`sensorless.report.write_report`). Time is in seconds, joint torques
in N m, joints are numbered from 1.

* :func:`plot_residuals` — residual of each joint against the lower/upper
  bounds of one or more threshold methods, with the ground-truth collision
  windows shaded and the detections marked (thesis Figs. 4.6, 5.6, 5.13).
* :func:`plot_tau_c` — ground-truth external torque τ_c against the residual.
* :func:`plot_evaluation` — timeline of windows, detections and false alarms
  of one or more :class:`~sensorless.evaluation.Evaluation` objects.
* :func:`plot_held_out` — a held-out real recording of
  :func:`sensorless.realarm.evaluate_folds`: its residual against every
  family's bounds, apparent contacts shaded.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from ._validation import FloatArray, check_type
from .evaluation import Evaluation, Window, collision_windows
from .evaluation.scoring import check_evaluations
from .exceptions import DimensionError, InputTypeError, InputValueError
from .io import Log
from .realarm import HeldOutRun
from .signals import Event, ObserverSignals

__all__ = ["plot_evaluation", "plot_held_out", "plot_residuals", "plot_tau_c"]

WINDOW_COLOR = "tab:red"
WINDOW_ALPHA = 0.15
RESIDUAL_COLOR = "0.15"
TAU_C_COLOR = "tab:orange"
_METHOD_COLORS = ("tab:blue", "tab:green", "tab:purple", "tab:brown", "tab:cyan", "tab:olive")
_RESIDUAL_SYMBOLS = {
    "motor": r"$\hat{r}$",
    "joint": r"$\hat{r}_s$",
    "acceleration": r"$\hat{\tau}_c$",
}


def _check_joints(joints: Sequence[int] | None, n_dof: int) -> list[int]:
    """1-based joint numbers to plot; all joints by default."""
    if joints is None:
        return list(range(1, n_dof + 1))
    chosen = list(joints)
    valid = all(
        isinstance(j, int | np.integer) and not isinstance(j, bool) and 1 <= j <= n_dof
        for j in chosen
    )
    if not chosen or not valid:
        raise InputValueError(
            f"joints must be a non-empty sequence of joint numbers 1..{n_dof}; got {joints!r}"
        )
    return [int(j) for j in chosen]


def _joint_axes(figure: Figure, n_rows: int) -> list[Axes]:
    axes = figure.subplots(n_rows, 1, sharex=True, squeeze=False)
    return [row[0] for row in axes]


def _figure(n_rows: int, figsize: tuple[float, float] | None) -> Figure:
    size = figsize if figsize is not None else (8.0, 1.0 + 2.2 * n_rows)
    return Figure(figsize=size, layout="constrained")


def _shade_windows(ax: Axes, windows: Sequence[Window], label: str | None) -> None:
    for k, window in enumerate(windows):
        ax.axvspan(
            window.start,
            window.end,
            color=WINDOW_COLOR,
            alpha=WINDOW_ALPHA,
            linewidth=0,
            label=label if k == 0 else None,
        )


def _broadcast_bound(values: ArrayLike, shape: tuple[int, int], name: str) -> FloatArray:
    try:
        arr = np.asarray(values, dtype=float)
        return np.broadcast_to(arr, shape)
    except (TypeError, ValueError):
        raise DimensionError(
            f"{name} must be a number or an array of shape ({shape[1]},) or {shape} "
            f"(n_samples, n_dof) [N m]; got shape {np.shape(values)}"
        ) from None


def _check_bounds(
    bounds: Mapping[str, tuple[ArrayLike, ArrayLike]], shape: tuple[int, int]
) -> dict[str, tuple[FloatArray, FloatArray]]:
    if not isinstance(bounds, Mapping):
        raise InputTypeError(
            f"bounds must be a mapping {{method name: (lower, upper)}}; got {type(bounds).__name__}"
        )
    checked = {}
    for name, pair in bounds.items():
        if not isinstance(pair, tuple | list) or len(pair) != 2:
            raise InputValueError(
                f"bounds[{name!r}] must be a pair (lower, upper) of arrays [N m]; got "
                f"{type(pair).__name__}"
            )
        lower = _broadcast_bound(pair[0], shape, f"lower bound of {name!r}")
        upper = _broadcast_bound(pair[1], shape, f"upper bound of {name!r}")
        checked[str(name)] = (lower, upper)
    return checked


def _method_colors(names: Sequence[str]) -> dict[str, str]:
    colors: dict[str, str] = {}
    for name in names:
        if name not in colors:
            colors[name] = _METHOD_COLORS[len(colors) % len(_METHOD_COLORS)]
    return colors


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
    """Residuals against threshold bounds with collision windows and detections.

    One subplot per joint (sharing the time axis) with, in this order of
    ``ax.lines``: the residual, then for each method of ``bounds`` its upper
    (solid) and lower (dashed) bound in the method's colour. Ground-truth
    collision windows of ``log`` are shaded (``ax.patches``) and the start of
    each event of ``events`` that involves the joint is marked with a
    triangle on the residual (one scatter in ``ax.collections`` per method).
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
        are shaded.
    events : mapping of str to list of Event, optional
        Detections per method name; methods also in ``bounds`` share its colour.
    joints : sequence of int, optional
        1-based joints to plot; default all.
    title : str, optional
        Figure title.
    figsize : (float, float), optional
        Figure size [in]; default 8 wide and 2.2 per joint.

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
    chosen = _check_joints(joints, signals.n_dof)
    checked = _check_bounds(bounds if bounds is not None else {}, signals.residual.shape)
    if events is not None and not isinstance(events, Mapping):
        raise InputTypeError(
            f"events must be a mapping {{method name: list of Event}}; got {type(events).__name__}"
        )
    detections = {str(name): list(found) for name, found in (events or {}).items()}
    colors = _method_colors([*checked, *detections])
    windows = collision_windows(log) if log is not None else []
    symbol = _RESIDUAL_SYMBOLS.get(signals.kind, _RESIDUAL_SYMBOLS["motor"])
    t = signals.t

    figure = _figure(len(chosen), figsize)
    axes = _joint_axes(figure, len(chosen))
    for ax, joint in zip(axes, chosen, strict=True):
        column = joint - 1
        residual = signals.residual[:, column]
        ax.plot(t, residual, color=RESIDUAL_COLOR, linewidth=0.8, label=symbol)
        for name, (lower, upper) in checked.items():
            ax.plot(t, upper[:, column], color=colors[name], linewidth=1.0, label=name)
            ax.plot(t, lower[:, column], color=colors[name], linewidth=1.0, linestyle="--")
        _shade_windows(ax, windows, "collision")
        for name, found in detections.items():
            starts = [e.start for e in found if not e.joints or joint in e.joints]
            if starts:
                ax.scatter(
                    starts,
                    np.interp(starts, t, residual),
                    marker="v",
                    s=36,
                    color=colors[name],
                    edgecolors="black",
                    linewidths=0.5,
                    zorder=3,
                    label=f"{name} detection",
                )
        ax.set_ylabel(f"{symbol} joint {joint} [N m]")
        ax.set_xlim(float(t[0]), float(t[-1]))
        ax.grid(True, linewidth=0.3)
    axes[-1].set_xlabel("time [s]")
    _legend(axes)
    if title is not None:
        figure.suptitle(title)
    return figure


def _legend(axes: Sequence[Axes]) -> None:
    """One legend on the first axes with the entries of all axes (first occurrence)."""
    entries: dict[str, Any] = {}
    for ax in axes:
        handles, labels = ax.get_legend_handles_labels()
        for handle, label in zip(handles, labels, strict=True):
            entries.setdefault(label, handle)
    if entries:
        axes[0].legend(
            list(entries.values()), list(entries), loc="upper right", fontsize="small", ncol=2
        )


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
        figure title, figure size [in] (default 8 wide and 2.2 per joint).

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
    chosen = _check_joints(joints, log.n_dof)
    windows = collision_windows(log)
    symbol = (
        _RESIDUAL_SYMBOLS.get(signals.kind, _RESIDUAL_SYMBOLS["motor"])
        if signals is not None
        else ""
    )

    figure = _figure(len(chosen), figsize)
    axes = _joint_axes(figure, len(chosen))
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
        _shade_windows(ax, windows, "collision")
        ax.set_ylabel(f"joint {joint} [N m]")
        ax.grid(True, linewidth=0.3)
    axes[-1].set_xlabel("time [s]")
    axes[-1].set_xlim(float(log.t[0]), float(log.t[-1]))
    _legend(axes)
    if title is not None:
        figure.suptitle(title)
    return figure


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
    excused events in grey as bars (``ax.collections``), and marks each
    missed window with a red cross. Bars are drawn at least 0.2 % of the
    time span wide so that single-sample events stay visible.

    Parameters
    ----------
    evaluations : Evaluation or mapping of str to Evaluation
        Results of :func:`~sensorless.evaluation.evaluate`; a single one is
        labelled by its ``method``.
    title : str, optional
        Figure title.
    figsize : (float, float), optional
        Figure size [in]; default 8 wide and 1.2 + 0.6 per method.

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
    if isinstance(evaluations, Evaluation):
        items = [(evaluations.method or "events", evaluations)]
    elif isinstance(evaluations, Mapping):
        items = [(str(name), evaluation) for name, evaluation in check_evaluations(evaluations)]
    else:
        raise InputTypeError(
            "evaluations must be an Evaluation or a mapping {method name: Evaluation}; got "
            f"{type(evaluations).__name__}"
        )
    t_start = min(evaluation.t_start for _, evaluation in items)
    t_end = max(evaluation.t_start + evaluation.duration for _, evaluation in items)
    min_width = 0.002 * (t_end - t_start)

    size = figsize if figsize is not None else (8.0, 1.2 + 0.6 * len(items))
    figure = Figure(figsize=size, layout="constrained")
    ax = figure.subplots()
    _shade_windows(ax, items[0][1].windows, "collision")
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
        missed = evaluation.per_collision.loc[~evaluation.per_collision["detected"]]
        if len(missed):
            ax.plot(
                0.5 * (missed["start"] + missed["end"]).to_numpy(dtype=float),
                np.full(len(missed), float(y)),
                linestyle="none",
                marker="x",
                markersize=8,
                color="tab:red",
                label=None if "missed" in labelled else "missed",
            )
            labelled.add("missed")
    ax.set_yticks(range(len(items)), [name for name, _ in reversed(items)])
    ax.set_ylim(-0.6, len(items) - 0.4)
    ax.set_xlim(t_start, t_end)
    ax.set_xlabel("time [s]")
    ax.grid(True, axis="x", linewidth=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper right", fontsize="small", ncol=5)
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
