"""What every figure shares: colours, joint choice, shaded windows, bounds, legends, envelopes."""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from .._validation import FloatArray
from ..evaluation import Window
from ..exceptions import DimensionError, InputTypeError, InputValueError

WINDOW_COLOR = "tab:red"
WINDOW_ALPHA = 0.15
RESIDUAL_COLOR = "0.15"
TAU_C_COLOR = "tab:orange"
METHOD_COLORS = ("tab:blue", "tab:green", "tab:purple", "tab:brown", "tab:cyan", "tab:olive")
RESIDUAL_SYMBOLS = {
    "motor": r"$\hat{r}$",
    "joint": r"$\hat{r}_s$",
    "acceleration": r"$\hat{\tau}_c$",
}


def check_joints(joints: Sequence[int] | None, n_dof: int) -> list[int]:
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


def joint_axes(figure: Figure, n_rows: int) -> list[Axes]:
    axes = figure.subplots(n_rows, 1, sharex=True, squeeze=False)
    return [row[0] for row in axes]


def new_figure(n_rows: int, figsize: tuple[float, float] | None) -> Figure:
    size = figsize if figsize is not None else (11.0, 1.2 + 2.0 * n_rows)
    return Figure(figsize=size, layout="constrained")


def shade_windows(ax: Axes, windows: Sequence[Window], label: str | None) -> None:
    for k, window in enumerate(windows):
        ax.axvspan(
            window.start,
            window.end,
            color=WINDOW_COLOR,
            alpha=WINDOW_ALPHA,
            linewidth=0,
            label=label if k == 0 else None,
        )


def broadcast_bound(values: ArrayLike, shape: tuple[int, int], name: str) -> FloatArray:
    try:
        arr = np.asarray(values, dtype=float)
        return np.broadcast_to(arr, shape)
    except (TypeError, ValueError):
        raise DimensionError(
            f"{name} must be a number or an array of shape ({shape[1]},) or {shape} "
            f"(n_samples, n_dof) [N m]; got shape {np.shape(values)}"
        ) from None


def check_bounds(
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
        lower = broadcast_bound(pair[0], shape, f"lower bound of {name!r}")
        upper = broadcast_bound(pair[1], shape, f"upper bound of {name!r}")
        checked[str(name)] = (lower, upper)
    return checked


def method_colors(names: Sequence[str]) -> dict[str, str]:
    colors: dict[str, str] = {}
    for name in names:
        if name not in colors:
            colors[name] = METHOD_COLORS[len(colors) % len(METHOD_COLORS)]
    return colors


def add_legend(axes: Sequence[Axes]) -> None:
    """One legend below the axes (never over the data) with the entries of all axes."""
    entries: dict[str, Any] = {}
    for ax in axes:
        handles, labels = ax.get_legend_handles_labels()
        for handle, label in zip(handles, labels, strict=True):
            entries.setdefault(label, handle)
    if entries:
        axes[0].figure.legend(
            list(entries.values()),
            list(entries),
            loc="outside lower center",
            fontsize="small",
            ncol=min(len(entries), 5),
            frameon=False,
        )


MAX_BUCKETS = 1500
"""A series longer than twice this is drawn as min/max envelopes over this many buckets."""


def buckets(n_samples: int, max_buckets: int = MAX_BUCKETS) -> int:
    """Samples per bucket of a decimated series (1: draw every sample)."""
    return 1 if n_samples <= 2 * max_buckets else math.ceil(n_samples / max_buckets)


def envelope(values: FloatArray, size: int, reduce: str) -> FloatArray:
    """Min or max of ``values`` (n_samples, ...) over consecutive buckets of ``size`` samples.

    All-NaN buckets give NaN (a gap in the plot).
    """
    if size == 1:
        return values
    n_buckets = math.ceil(values.shape[0] / size)
    padded = np.full((n_buckets * size, *values.shape[1:]), np.nan)
    padded[: values.shape[0]] = values
    shaped = padded.reshape(n_buckets, size, *values.shape[1:])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN bucket: NaN is the answer
        return np.nanmax(shaped, axis=1) if reduce == "max" else np.nanmin(shaped, axis=1)


def check_mapping(value: Any, name: str, what: str) -> Mapping[Any, Any]:
    """``value`` if it is a mapping, else a TypeError that says what was expected."""
    if not isinstance(value, Mapping):
        raise InputTypeError(f"{name} must be a mapping {{{what}}}; got {type(value).__name__}")
    return value
