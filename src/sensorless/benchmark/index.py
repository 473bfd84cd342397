"""A small standalone HTML page of a benchmark's outputs (``index.html`` next to them).

Relative links only, so the folder can be moved or served as is; the HTML
report can link to this page.
"""

from __future__ import annotations

import html
from collections.abc import Mapping
from pathlib import Path

import pandas as pd

from .config import BenchmarkConfig

__all__ = ["write_index"]

_STYLE = (
    "body{font-family:sans-serif;margin:2em;max-width:110em}"
    "table{border-collapse:collapse;font-size:85%}"
    "td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}"
    "img{max-width:100%}"
)
_SHOWN = [
    "scenario", "method", "n_collisions", "n_detected", "detection_rate", "detection_low",
    "detection_high", "strong_rate", "strong_low", "strong_high", "free_hours",
    "n_false_alarms", "false_alarms_per_hour", "false_alarms_low", "false_alarms_high",
    "delay_median", "delay_p95", "delay_ratio", "delay_excess", "eff",
]  # fmt: skip


def _describe(config: BenchmarkConfig) -> str:
    scenarios = ", ".join(
        f"{getattr(c.scenario, 'name', c.scenario)}"
        + (f" ({c.duration:g} s runs)" if c.duration else "")
        + (
            f" (collision runs: {c.interactions} random interactions each: guiding, clamp, impact)"
            if c.interactions
            else ""
        )
        for c in config.scenarios
    )
    tuning = (
        f"stated false-alarm rate {config.false_alarm_rate:g} /h"
        if config.false_alarm_rate is not None
        else f"margin {config.margin_fraction:g} × the constant β of the same residual"
    )
    return (
        f"Scenarios: {scenarios}. Per scenario {config.n_tuning} tuning, {config.n_collision} "
        f"collision and {config.n_free} collision-free test runs from master seed "
        f"{config.master_seed}. Tuning: {tuning}. Oracle: {config.oracle_method} on the "
        f"residual of the exact model, same runs. Intervals at {100 * config.confidence:g} % "
        f"(Wilson for rates, exact Poisson for false alarms per hour); strong contacts: peak "
        f"≥ {config.strong_force:g} N."
    )


_CONTACTS_TEXT = (
    "Every event of the collision runs is isolated at one sample, its largest excursion "
    "beyond a bound (Isolator.isolate_events; capsules around the links of the model the "
    "residual was computed with; only the monitored joints, those with a band, count), "
    "classified by the stated rules (classify_events), and "
    "scored against the simulator's ground truth; an event is scored when it starts inside "
    "a contact's window [start, end + max_delay]. Link rate with its Wilson interval; point "
    "errors on the right link [m]; force errors ||F̂| − |F|| [N] against the true force at "
    "that sample, and against it through the observer's filter K_I/(s+K_I) (the lag no "
    "isolation can undo); direction error [deg]; |F̂| above the lowest ISO/TS 15066 "
    "quasi-static limit (65 N)."
)


def _table(frame: pd.DataFrame) -> str:
    return frame.to_html(index=False, float_format=lambda v: f"{v:.4g}")


def _contacts_section(contacts: pd.DataFrame | None, confusion: pd.DataFrame | None) -> str:
    if contacts is None or confusion is None:
        return ""
    return (
        f"<h2>isolation and classification</h2><p>{html.escape(_CONTACTS_TEXT)}</p>"
        f"{_table(contacts)}<h2>confusion table (rows: true class; columns: assigned class)"
        f"</h2>{_table(confusion)}"
    )


def write_index(
    out: Path,
    summary: pd.DataFrame,
    by_force: pd.DataFrame,
    written: Mapping[str, Path],
    config: BenchmarkConfig,
    contacts: pd.DataFrame | None = None,
    confusion: pd.DataFrame | None = None,
) -> Path:
    """Write ``out/index.html``: description, tables, figures, links to every file."""
    shown = summary[[c for c in _SHOWN if c in summary.columns]]
    names = ("detection_vs_force", "delays", "false_alarms", "force_estimates")
    figures = [name for name in names if name in written]
    links = "".join(
        f'<li><a href="{html.escape(path.name)}">{html.escape(path.name)}</a></li>'
        for name, path in written.items()
        if name not in figures
    )
    images = "".join(
        f"<h2>{html.escape(name.replace('_', ' '))}</h2>"
        f'<img src="{html.escape(written[name].name)}" alt="{html.escape(name)}">'
        for name in figures
    )
    page = (
        "<!DOCTYPE html><html><head><meta charset='utf-8'>"
        f"<title>sensorless benchmark</title><style>{_STYLE}</style></head><body>"
        f"<h1>sensorless detection benchmark</h1><p>{html.escape(_describe(config))}</p>"
        f"<h2>summary</h2>{_table(shown)}{_contacts_section(contacts, confusion)}"
        f"{images}<h2>detection rate by peak force</h2>{_table(by_force)}"
        f"<h2>files</h2><ul>{links}</ul></body></html>"
    )
    path = out / "index.html"
    path.write_text(page, encoding="utf-8")
    return path
