"""Figures of one collision: a zoom on the joints that matter, and why a method missed it."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from .._validation import FloatArray
from ..evaluation import Evaluation, Window
from ..exceptions import InputValueError
from ..io import Log
from ..signals import ObserverSignals
from ._common import (
    RESIDUAL_COLOR,
    RESIDUAL_SYMBOLS,
    TAU_C_COLOR,
    WINDOW_ALPHA,
    WINDOW_COLOR,
    add_legend,
    check_bounds,
    check_joints,
    check_mapping,
    method_colors,
    shade_windows,
)

__all__ = [
    "Headroom",
    "describe",
    "headroom",
    "joints_that_matter",
    "plot_collision",
    "plot_missed",
]

ZOOM = 0.5
"""Time [s] shown before the start and after the end of a collision."""


def joints_that_matter(
    log: Log, window: Window, monitored: Sequence[int] | None = None, limit: int = 3
) -> list[int]:
    """The monitored joints (1-based) that feel a collision most, at most ``limit``.

    With ground-truth external torques: the joints whose peak |τ_c| during
    the window is at least 30 % of the largest, by decreasing peak. Without
    them (or when no monitored joint feels the contact): the first
    ``limit`` monitored joints.
    """
    chosen = check_joints(monitored, log.n_dof)
    if log.tau_c is None:
        return chosen[:limit]
    inside = (log.t >= window.start) & (log.t <= window.end)
    if not inside.any():
        return chosen[:limit]
    peaks = np.abs(np.asarray(log.tau_c)[inside][:, [j - 1 for j in chosen]]).max(axis=0)
    if not peaks.max() > 0:
        return chosen[:limit]
    order = np.argsort(-peaks, kind="stable")
    return [chosen[k] for k in order if peaks[k] >= 0.3 * peaks.max()][:limit]


def _kinds(
    signals: Mapping[str, ObserverSignals], methods: Sequence[str], kinds: Mapping[str, str] | None
) -> dict[str, str]:
    """Observer kind of every method: given, or the only one there is."""
    found = {}
    for method in methods:
        if kinds is not None and method in kinds:
            found[method] = kinds[method]
        elif len(signals) == 1:
            found[method] = next(iter(signals))
        else:
            raise InputValueError(
                f"kinds must name the observer kind of {method!r}: signals has several "
                f"({sorted(signals)})"
            )
        if found[method] not in signals:
            raise InputValueError(
                f"{method!r} watches the {found[method]!r} residual; signals has {sorted(signals)}"
            )
    return found


def _row(table: pd.DataFrame, window: Window) -> int:
    return list(table.index).index(window.id)


def _status(evaluation: Evaluation, window: Window) -> tuple[str, float]:
    """("detected", delay [s]), ("masked", nan) or ("missed", nan) of a window."""
    table = evaluation.per_collision
    if bool(table.at[window.id, "detected"]):
        return "detected", float(table["start_delay"].to_numpy(dtype=float)[_row(table, window)])
    return ("masked" if bool(table.at[window.id, "masked"]) else "missed"), math.nan


def describe(evaluations: Mapping[str, Evaluation], window: Window) -> str:
    """What every method made of a window: "a +12 ms; b missed; c masked"."""
    parts = []
    for method, evaluation in evaluations.items():
        status, delay = _status(evaluation, window)
        parts.append(
            f"{method} +{1e3 * delay:.0f} ms" if status == "detected" else f"{method} {status}"
        )
    return "; ".join(parts)


def _window_name(window: Window) -> str:
    force = f"{window.peak_force:.0f} N, " if math.isfinite(window.peak_force) else ""
    return f"Collision {window.id} ({force}{window.start:.2f}–{window.end:.2f} s)"


def plot_collision(
    window: Window,
    log: Log,
    signals: Mapping[str, ObserverSignals],
    bounds: Mapping[str, tuple[ArrayLike, ArrayLike]],
    evaluations: Mapping[str, Evaluation],
    *,
    kinds: Mapping[str, str] | None = None,
    joints: Sequence[int] | None = None,
    zoom: float = ZOOM,
) -> Figure:
    """A zoom of ±``zoom`` s around one collision: residual, bounds, τ_c, detection instants.

    One row per observer kind (residual) that a method watches and one column
    per joint that matters (:func:`joints_that_matter`). Each axes shows the
    residual [N m], the upper (solid) and lower (dashed) bound of every
    method on that residual, the true external torque τ_c (orange) when the
    log has it, the collision window shaded and, for every method that
    detects it, a dotted vertical line at the detection instant. The title
    says what each method made of the collision.

    Parameters
    ----------
    window : Window
        The collision (from the evaluations' ``windows``).
    log : Log
        The run; its ``tau_c`` [N m] is overlaid when present.
    signals : mapping of str to ObserverSignals
        Observer signals of the run per kind ("motor", "joint", "acceleration").
    bounds : mapping of str to (lower, upper)
        Bounds per method [N m], arrays of shape (n_samples, n_dof) on the
        time base of the method's signals.
    evaluations : mapping of str to Evaluation
        Evaluation per method of ``bounds``.
    kinds : mapping of str to str, optional
        Observer kind per method; needed when ``signals`` has several.
    joints : sequence of int, optional
        Monitored 1-based joints; the panel shows those that matter.
    zoom : float
        Time [s] shown before and after the window.

    Returns
    -------
    Figure
    """
    check_mapping(signals, "signals", "observer kind: ObserverSignals")
    check_mapping(evaluations, "evaluations", "method name: Evaluation")
    kind_of = _kinds(signals, list(bounds), kinds)
    rows = [kind for kind in signals if kind in kind_of.values()]
    shown = joints_that_matter(log, window, joints)
    colors = method_colors(list(bounds))
    lo, hi = window.start - zoom, window.end + zoom

    figure = Figure(figsize=(11.0, 1.2 + 2.4 * len(rows)), layout="constrained")
    grid = figure.subplots(len(rows), len(shown), squeeze=False, sharex=True)
    for r, kind in enumerate(rows):
        run = signals[kind]
        checked = check_bounds(
            {m: b for m, b in bounds.items() if kind_of[m] == kind}, run.residual.shape
        )
        near = (run.t >= lo) & (run.t <= hi)
        symbol = RESIDUAL_SYMBOLS.get(kind, RESIDUAL_SYMBOLS["motor"])
        for c, joint in enumerate(shown):
            ax = grid[r][c]
            ax.plot(run.t[near], run.residual[near, joint - 1], color=RESIDUAL_COLOR,
                    linewidth=1.0, label=symbol)  # fmt: skip
            if log.tau_c is not None:
                in_log = (log.t >= lo) & (log.t <= hi)
                ax.plot(log.t[in_log], np.asarray(log.tau_c)[in_log, joint - 1], color=TAU_C_COLOR,
                        linewidth=1.4, label=r"true $\tau_c$")  # fmt: skip
            for method, (lower, upper) in checked.items():
                ax.plot(run.t[near], upper[near, joint - 1], color=colors[method], linewidth=1.0,
                        label=method)  # fmt: skip
                ax.plot(run.t[near], lower[near, joint - 1], color=colors[method], linewidth=1.0,
                        linestyle="--")  # fmt: skip
                status, delay = _status(evaluations[method], window)
                if status == "detected":
                    ax.axvline(window.start + delay, color=colors[method], linestyle=":",
                               linewidth=1.8, label=f"{method} detects")  # fmt: skip
            shade_windows(ax, [window], "contact")
            ax.set_xlim(lo, hi)
            ax.grid(True, linewidth=0.3)
            ax.set_title(f"joint {joint}", fontsize="medium")
            if c == 0:
                ax.set_ylabel(f"{symbol} [N m]")
            if r == len(rows) - 1:
                ax.set_xlabel("time [s]")
    add_legend([ax for row in grid for ax in row])
    figure.suptitle(f"{_window_name(window)}: {describe(evaluations, window)}", fontsize="medium")
    return figure


@dataclass(frozen=True)
class Headroom:
    """How close a residual came to leaving its band during a collision.

    Attributes
    ----------
    margin : float
        Smallest distance [N m] from the residual to the nearer bound over
        the window and the monitored joints (positive: it stayed inside).
    joint : int
        1-based joint of that closest approach.
    time : float
        Time [s] of that closest approach.
    """

    margin: float
    joint: int
    time: float


def _headroom_series(
    run: ObserverSignals, lower: FloatArray, upper: FloatArray, joints: Sequence[int]
) -> FloatArray:
    columns = [j - 1 for j in joints]
    residual = run.residual[:, columns]
    return np.minimum(upper[:, columns] - residual, residual - lower[:, columns])


def headroom(
    window: Window,
    signals: ObserverSignals,
    bounds: tuple[ArrayLike, ArrayLike],
    *,
    joints: Sequence[int] | None = None,
    max_delay: float = 0.0,
) -> Headroom:
    """The closest approach of the residual to its bounds during ``[start, end + max_delay]``.

    Raises
    ------
    InputValueError
        No finite sample of the residual lies in the window.
    """
    chosen = check_joints(joints, signals.n_dof)
    lower, upper = check_bounds({"bounds": bounds}, signals.residual.shape)["bounds"]
    inside = (signals.t >= window.start) & (signals.t <= window.end + max_delay)
    room = _headroom_series(signals, lower, upper, chosen)[inside]
    if not np.isfinite(room).any():
        raise InputValueError(
            f"no finite residual sample lies in collision {window.id} "
            f"[{window.start:g}, {window.end + max_delay:g}] s"
        )
    k, j = np.unravel_index(np.nanargmin(room), room.shape)
    return Headroom(float(room[k, j]), chosen[j], float(signals.t[inside][k]))


def plot_missed(
    window: Window,
    signals: Mapping[str, ObserverSignals],
    bounds: Mapping[str, tuple[ArrayLike, ArrayLike]],
    evaluations: Mapping[str, Evaluation],
    *,
    kinds: Mapping[str, str] | None = None,
    joints: Sequence[int] | None = None,
    zoom: float = ZOOM,
) -> Figure | None:
    """Why methods missed a collision: the residual's distance to the nearer bound.

    One row per method that missed the window (neither detected nor masked):
    per monitored joint, min(upper − r̂, r̂ − lower) [N m] over ±``zoom`` s,
    the joint of the closest approach drawn bold; the red line at 0 is the
    bound (an alarm needs a value below it). The closest approach during the
    window and the ``max_delay`` after it is marked and written out.

    Parameters
    ----------
    window, signals, bounds, evaluations, kinds, joints, zoom
        As in :func:`plot_collision`.

    Returns
    -------
    Figure or None
        None when no method missed the window.
    """
    check_mapping(evaluations, "evaluations", "method name: Evaluation")
    missed = [m for m in bounds if _status(evaluations[m], window)[0] == "missed"]
    if not missed:
        return None
    kind_of = _kinds(signals, missed, kinds)
    figure = Figure(figsize=(11.0, 1.0 + 1.9 * len(missed)), layout="constrained")
    axes = figure.subplots(len(missed), 1, squeeze=False, sharex=True)[:, 0]
    lo, hi = window.start - zoom, window.end + zoom
    shades = ("0.55", "0.7", "0.4", "0.8", "0.3", "0.65", "0.5")
    inside = True
    for ax, method in zip(axes, missed, strict=True):
        run = signals[kind_of[method]]
        chosen = check_joints(joints, run.n_dof)
        lower, upper = check_bounds({method: bounds[method]}, run.residual.shape)[method]
        delay = evaluations[method].max_delay
        closest = headroom(window, run, (lower, upper), joints=chosen, max_delay=delay)
        inside = inside and closest.margin >= 0
        near = (run.t >= lo) & (run.t <= hi)
        room = _headroom_series(run, lower, upper, chosen)
        for k, joint in enumerate(chosen):
            bold = joint == closest.joint
            ax.plot(run.t[near], room[near, k], color="tab:blue" if bold else shades[k % 7],
                    linewidth=1.6 if bold else 0.8, label=f"joint {joint}")  # fmt: skip
        ax.axhline(0.0, color="tab:red", linewidth=1.2, label="bound (alarm below 0)")
        ax.axvspan(window.start, window.end, color=WINDOW_COLOR, alpha=WINDOW_ALPHA, linewidth=0)
        ax.axvspan(window.end, window.end + delay, color=WINDOW_COLOR, alpha=WINDOW_ALPHA / 3,
                   linewidth=0)  # fmt: skip
        ax.plot([closest.time], [closest.margin], marker="o", color="tab:red", linestyle="none")
        where = f"(joint {closest.joint}, {closest.time:.2f} s)"
        ax.annotate(
            f"closest: {closest.margin:.2f} N m inside {where}"
            if closest.margin >= 0
            else f"out by {-closest.margin:.2f} N m {where}, too briefly to make an event",
            (closest.time, closest.margin), xytext=(8, 8), textcoords="offset points",
            fontsize="small",
            bbox={"boxstyle": "round", "facecolor": "white", "edgecolor": "0.7"},
        )  # fmt: skip
        ax.set_ylim(bottom=min(-0.1 * np.nanmax(room[near]), closest.margin - 0.5))
        ax.set_ylabel("distance to\nbound [N m]")
        ax.set_title(f"{method} missed it", fontsize="medium", loc="left")
        ax.grid(True, linewidth=0.3)
        ax.set_xlim(lo, hi)
    axes[-1].set_xlabel("time [s]  (shaded: contact, then the max_delay an alarm may still start)")
    add_legend(list(axes))
    why = "the residual never left the band" if inside else "why the residual made no event"
    figure.suptitle(f"{_window_name(window)}: {why}", fontsize="medium")
    return figure
