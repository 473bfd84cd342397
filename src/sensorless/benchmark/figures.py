"""The benchmark's figures (PNG, matplotlib): detection vs peak force, delays, false alarms.

One panel per scenario in each figure; the oracle is drawn dashed / hatched.
Rates carry their Wilson (detection) or exact Poisson (false alarms) interval.
With isolation, a fourth: estimated vs true force magnitude per scored event.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..isolation import QUASI_STATIC_LIMITS

__all__ = ["write_figures"]


def _panels(n: int, height: float = 3.4) -> tuple[Any, list[Any]]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, n, figsize=(5.2 * n, height), squeeze=False)
    return figure, list(axes[0])


def _save(figure: Any, path: Path) -> Path:
    import matplotlib.pyplot as plt

    figure.tight_layout()
    figure.savefig(path, dpi=110, metadata={"Software": None})
    plt.close(figure)
    return path


def _is_oracle(summary: pd.DataFrame, scenario: str, method: str) -> bool:
    rows = summary[(summary["scenario"] == scenario) & (summary["method"] == method)]
    return bool(rows["oracle"].any())


def detection_figure(summary: pd.DataFrame, by_force: pd.DataFrame, path: Path) -> Path:
    """Detection rate per peak-force bin and method, Wilson interval bars."""
    scenarios = list(dict.fromkeys(summary["scenario"]))
    figure, axes = _panels(len(scenarios))
    for axis, scenario in zip(axes, scenarios, strict=True):
        rows = by_force[(by_force["scenario"] == scenario) & (by_force["n"] > 0)]
        methods = list(dict.fromkeys(rows["method"]))
        for k, method in enumerate(methods):
            part = rows[rows["method"] == method]
            high = part["force_high"].to_numpy(dtype=float)
            low = part["force_low"].to_numpy(dtype=float)
            centre = np.where(np.isfinite(high), 0.5 * (low + high), low + 10.0)
            shift = (k - 0.5 * (len(methods) - 1)) * 0.8  # methods side by side
            rate = part["rate"].to_numpy(dtype=float)
            error = np.vstack([rate - part["low"].to_numpy(), part["high"].to_numpy() - rate])
            axis.errorbar(
                centre + shift, rate, yerr=error, marker="o", capsize=3, label=method,
                linestyle="--" if _is_oracle(summary, scenario, method) else "-",
            )  # fmt: skip
        axis.set(title=scenario, xlabel="peak contact force [N]", ylabel="detection rate",
                 ylim=(-0.05, 1.05))  # fmt: skip
        axis.grid(alpha=0.3)
        axis.legend(fontsize="small")
    return _save(figure, path)


def delay_figure(summary: pd.DataFrame, collisions: pd.DataFrame, path: Path) -> Path:
    """Start-delay distribution per method (box plots), oracle included."""
    scenarios = list(dict.fromkeys(summary["scenario"]))
    figure, axes = _panels(len(scenarios))
    for axis, scenario in zip(axes, scenarios, strict=True):
        methods = list(summary.loc[summary["scenario"] == scenario, "method"])
        here = collisions[(collisions["scenario"] == scenario) & collisions["detected"]]
        data = [
            1e3 * here.loc[here["method"] == m, "start_delay"].to_numpy(dtype=float)
            for m in methods
        ]
        if any(d.size for d in data):
            axis.boxplot([d if d.size else [np.nan] for d in data], tick_labels=methods)
        axis.set(title=scenario, ylabel="start delay [ms]")
        axis.tick_params(axis="x", labelrotation=30)
        axis.grid(alpha=0.3)
    return _save(figure, path)


def false_alarm_figure(summary: pd.DataFrame, path: Path) -> Path:
    """False alarms per hour on the collision-free test runs, exact Poisson interval bars."""
    scenarios = list(dict.fromkeys(summary["scenario"]))
    figure, axes = _panels(len(scenarios))
    for axis, scenario in zip(axes, scenarios, strict=True):
        rows = summary[summary["scenario"] == scenario]
        rate = rows["false_alarms_per_hour"].to_numpy(dtype=float)
        high = rows["false_alarms_high"].to_numpy(dtype=float)
        low = rows["false_alarms_low"].to_numpy(dtype=float)
        position = np.arange(len(rows))
        bars = axis.bar(position, rate, yerr=np.vstack([rate - low, high - rate]), capsize=4)
        for bar, oracle in zip(bars, rows["oracle"], strict=True):
            if oracle:
                bar.set_hatch("//")
        axis.set_xticks(position, list(rows["method"]), rotation=30)
        axis.set(title=scenario, ylabel="false alarms per hour")
        axis.grid(alpha=0.3, axis="y")
    return _save(figure, path)


def force_figure(summary: pd.DataFrame, events: pd.DataFrame, path: Path) -> Path:
    """|F̂| vs the true |F| at the isolated sample, per scored event and method; y = x dotted.

    Symmetric log axes (linear below 1 N).
    """
    scenarios = list(dict.fromkeys(summary["scenario"]))
    figure, axes = _panels(len(scenarios), height=4.2)
    scored = events[(events["role"] == "collision") & (events["contact"].fillna(0) > 0)]
    for axis, scenario in zip(axes, scenarios, strict=True):
        here = scored[scored["scenario"] == scenario]
        top = 1.0
        for method in summary.loc[summary["scenario"] == scenario, "method"]:
            part = here[here["method"] == method]
            true = part["force_true"].to_numpy(dtype=float, na_value=np.nan)
            estimate = part["force_estimated"].to_numpy(dtype=float, na_value=np.nan)
            oracle = _is_oracle(summary, scenario, method)
            axis.scatter(
                true, estimate, s=18, label=method, marker="x" if oracle else "o",
                alpha=0.7,
            )  # fmt: skip
            finite = np.concatenate([true, estimate])
            finite = finite[np.isfinite(finite)]
            top = max(top, float(finite.max()) if finite.size else 0.0)
        axis.plot([0.0, top], [0.0, top], ":", color="grey", label="|F̂| = |F|")
        axis.axhline(QUASI_STATIC_LIMITS[0], color="red", linewidth=0.8, linestyle="--",
                     label=f"ISO/TS 15066 {QUASI_STATIC_LIMITS[0]:g} N")  # fmt: skip
        # Outliers (a contact beyond the monitored joints) span decades: symmetric log axes.
        axis.set_xscale("symlog", linthresh=1.0)
        axis.set_yscale("symlog", linthresh=1.0)
        axis.set_xlim(left=0.0)
        axis.set_ylim(bottom=0.0)
        axis.set(title=scenario, xlabel="true |F| at the isolated sample [N]",
                 ylabel="estimated |F̂| [N]")  # fmt: skip
        axis.grid(alpha=0.3)
        axis.legend(fontsize="small")
    return _save(figure, path)


def write_figures(
    summary: pd.DataFrame,
    by_force: pd.DataFrame,
    tables: Mapping[str, pd.DataFrame],
    out: Path,
    isolation: bool = False,
) -> dict[str, Path]:
    """The PNG figures in ``out``, by name (the force figure with ``isolation``)."""
    written = {
        "detection_vs_force": detection_figure(summary, by_force, out / "detection_vs_force.png"),
        "delays": delay_figure(summary, tables["collisions"], out / "delays.png"),
        "false_alarms": false_alarm_figure(summary, out / "false_alarms.png"),
    }
    if isolation:
        written["force_estimates"] = force_figure(
            summary, tables["events"], out / "force_estimates.png"
        )
    return written
