"""The benchmark's tables: every run, result, collision and event; the summary with intervals.

Record tables (one row per ...):

* ``runs``: simulated run (all roles): scenario, role, run, seed, duration [s],
  n_samples, n_contacts;
* ``results``: test run and detector: judged time [s] (after the settling
  window), collisions, detections, events, false alarms, excused events;
* ``collisions``: ground-truth collision window and detector (collision
  runs): start, end [s], peak force [N], detected, start and end delays [s];
* ``events``: detected event: start, end [s], joints, peak excursion [N m],
  outcome (``detection``, ``false_alarm``, ``excused``) and the collision
  ids it detects; on collision runs also its isolation and class against the
  ground truth (:data:`~sensorless.benchmark.contacts.CONTACT_COLUMNS`).

:func:`summary_table`, :func:`detection_by_force` and :func:`contact_summary` reduce them with
Wilson intervals for detection rates (``scipy.stats.binomtest(...).
proportion_ci(method="wilson")``) and exact Poisson intervals for false alarms
per hour (:func:`sensorless.monitor.poisson_interval`); :func:`confusion_table`
counts the classes.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from ..classification import KINDS
from ..monitor import poisson_interval
from .config import ORACLE, BenchmarkConfig
from .contacts import CONTACT_COLUMNS
from .tasks import RunRecords, Tuned, efficiency

__all__ = [
    "COLUMNS",
    "confusion_table",
    "contact_summary",
    "detection_by_force",
    "oracle_label",
    "record_tables",
    "summary_table",
    "wilson_interval",
]

_KEYS = {"scenario": "string", "role": "string", "run": "int64"}
COLUMNS: dict[str, dict[str, str]] = {
    "runs": {
        **_KEYS, "seed": "int64", "duration": "float64", "n_samples": "int64",
        "n_contacts": "int64",
    },
    "results": {
        **_KEYS, "method": "string", "family": "string", "kind": "string", "oracle": "bool",
        "judged_seconds": "float64", "n_collisions": "int64", "n_detected": "int64",
        "n_events": "int64", "n_false_alarms": "int64", "n_excused": "int64",
    },
    "collisions": {
        **_KEYS, "collision": "int64", "method": "string", "oracle": "bool", "start": "float64",
        "end": "float64", "peak_force": "float64", "detected": "bool", "start_delay": "float64",
        "end_delay": "float64", "n_events": "int64",
    },
    "events": {
        **_KEYS, "method": "string", "start": "float64", "end": "float64", "joints": "string",
        "peak": "float64", "peak_residual": "float64", "outcome": "string",
        "collisions": "string", **CONTACT_COLUMNS,
    },
}  # fmt: skip
"""Columns and dtypes of the record tables."""


def _frame(rows: Sequence[Mapping[str, Any]], name: str) -> pd.DataFrame:
    columns = COLUMNS[name]
    return pd.DataFrame(list(rows), columns=list(columns)).astype(columns)


def record_tables(
    tuning: Sequence[tuple[Any, dict[str, Any]]], records: Sequence[RunRecords]
) -> dict[str, pd.DataFrame]:
    """The four record tables from the tuning runs' rows and the test runs' records."""
    runs = [row for _, row in tuning] + [record.run for record in records]
    return {
        "runs": _frame(runs, "runs"),
        "results": _frame([r for record in records for r in record.results], "results"),
        "collisions": _frame([r for record in records for r in record.collisions], "collisions"),
        "events": _frame([r for record in records for r in record.events], "events"),
    }


def wilson_interval(successes: int, trials: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of a proportion; (NaN, NaN) without trials.

    Examples
    --------
    >>> [round(v, 4) for v in wilson_interval(8, 10)]
    [0.4902, 0.9433]
    """
    if trials == 0:
        return math.nan, math.nan
    result = stats.binomtest(int(successes), int(trials))
    interval = result.proportion_ci(confidence_level=confidence, method="wilson")
    return float(interval.low), float(interval.high)


def _rate(successes: int, trials: int, confidence: float) -> tuple[float, float, float]:
    low, high = wilson_interval(successes, trials, confidence)
    return (successes / trials if trials else math.nan), low, high


def oracle_label(kind: str, labels: Sequence[str]) -> str | None:
    """The oracle a detector of observer ``kind`` is compared with, if there is one."""
    own = f"{ORACLE} (joint)" if kind == "joint" else ORACLE
    for label in (own, ORACLE):
        if label in labels:
            return label
    return None


def _delays(table: pd.DataFrame) -> np.ndarray:
    return table.loc[table["detected"], "start_delay"].to_numpy(dtype=float)


def _quantile(values: np.ndarray, q: float) -> float:
    return float(np.quantile(values, q)) if values.size else math.nan


def summary_table(
    tables: Mapping[str, pd.DataFrame],
    tuned: Mapping[tuple[str, str], Tuned],
    config: BenchmarkConfig,
) -> pd.DataFrame:
    """One row per scenario and detector (columns: module docstring of :mod:`.result`)."""
    results, collisions = tables["results"], tables["collisions"]
    rows = []
    for (scenario, label), item in tuned.items():
        labels = [name for (s, name) in tuned if s == scenario]
        mine = collisions[(collisions["scenario"] == scenario) & (collisions["method"] == label)]
        n, k = len(mine), int(mine["detected"].sum())
        strong = mine[mine["peak_force"] >= config.strong_force]
        n_s, k_s = len(strong), int(strong["detected"].sum())
        runs = results[(results["scenario"] == scenario) & (results["method"] == label)]
        free = runs[runs["role"] == "free"]
        alarms, hours = (
            int(free["n_false_alarms"].sum()),
            float(free["judged_seconds"].sum()) / 3600,
        )
        hit = runs[runs["role"] == "collision"]
        delays = _delays(mine)
        row: dict[str, Any] = {
            "scenario": scenario, "method": label, "family": item.detection.method,
            "kind": item.detection.kind, "oracle": item.detection.oracle,
            "n_collisions": n, "n_detected": k,
        }  # fmt: skip
        row["detection_rate"], row["detection_low"], row["detection_high"] = _rate(
            k, n, config.confidence
        )
        row["n_strong"], row["n_strong_detected"] = n_s, k_s
        row["strong_rate"], row["strong_low"], row["strong_high"] = _rate(
            k_s, n_s, config.confidence
        )
        row["free_hours"], row["n_false_alarms"] = hours, alarms
        row["false_alarms_per_hour"] = alarms / hours if hours > 0 else math.nan
        row["false_alarms_low"], row["false_alarms_high"] = poisson_interval(
            alarms, hours, config.confidence
        )
        row["n_false_alarms_collision_runs"] = int(hit["n_false_alarms"].sum())
        row["delay_median"] = _quantile(delays, 0.5)
        row["delay_p95"] = _quantile(delays, 0.95)
        row.update(_against_oracle(collisions, scenario, label, item, labels))
        row["eff"], row["eff_joints"] = efficiency(item.threshold)
        rows.append(row)
    return pd.DataFrame(rows)


def _against_oracle(
    collisions: pd.DataFrame, scenario: str, label: str, item: Tuned, labels: Sequence[str]
) -> dict[str, Any]:
    """Oracle's median delay, the ratio of the medians, the paired median excess delay [s]."""
    reference = oracle_label(item.detection.kind, labels)
    if reference is None:
        return {"oracle_delay_median": math.nan, "delay_ratio": math.nan, "delay_excess": math.nan}
    here = collisions[collisions["scenario"] == scenario]
    mine = here[here["method"] == label].set_index(["run", "collision"])
    theirs = here[here["method"] == reference].set_index(["run", "collision"])
    oracle_median = _quantile(_delays(theirs), 0.5)
    median = _quantile(_delays(mine), 0.5)
    both = mine["detected"] & theirs["detected"].reindex(mine.index, fill_value=False)
    excess = (mine["start_delay"] - theirs["start_delay"].reindex(mine.index))[both]
    ratio = median / oracle_median if oracle_median > 0 else math.nan
    return {
        "oracle_delay_median": oracle_median,
        "delay_ratio": ratio,
        "delay_excess": _quantile(excess.to_numpy(dtype=float), 0.5),
    }


def _bin_labels(edges: Sequence[float]) -> list[str]:
    return [f"[{lo:g}, {hi:g}) N" for lo, hi in itertools.pairwise(edges)]


def detection_by_force(tables: Mapping[str, pd.DataFrame], config: BenchmarkConfig) -> pd.DataFrame:
    """Detection rate per scenario, detector and peak-force bin, with Wilson intervals.

    Columns: scenario, method, bin (label), force_low, force_high [N], n,
    n_detected, rate, low, high. Contacts of unknown peak force are left out.
    """
    collisions = tables["collisions"]
    edges = np.asarray(config.force_bins, dtype=float)
    names = _bin_labels(list(config.force_bins))
    rows = []
    for (scenario, label), group in collisions.groupby(["scenario", "method"], sort=False):
        force = group["peak_force"].to_numpy(dtype=float)
        index = np.searchsorted(edges, force, side="right") - 1
        for b, name in enumerate(names):
            inside = (index == b) & np.isfinite(force)
            n = int(inside.sum())
            k = int(group["detected"].to_numpy()[inside].sum())
            rate, low, high = _rate(k, n, config.confidence)
            rows.append(
                {
                    "scenario": scenario, "method": label, "bin": name,
                    "force_low": edges[b], "force_high": edges[b + 1], "n": n,
                    "n_detected": k, "rate": rate, "low": low, "high": high,
                }
            )  # fmt: skip
    columns = ["scenario", "method", "bin", "force_low", "force_high", "n", "n_detected", "rate",
               "low", "high"]  # fmt: skip
    return pd.DataFrame(rows, columns=columns)


def _scored(tables: Mapping[str, pd.DataFrame]) -> pd.DataFrame:
    """Events of collision runs matched to a contact (``contact`` > 0)."""
    events = tables["events"]
    keep = (events["role"] == "collision") & (events["contact"].fillna(0) > 0)
    return events[keep.to_numpy(dtype=bool)]


def _abs_quantile(values: pd.Series, q: float) -> float:
    data = np.abs(values.to_numpy(dtype=float, na_value=np.nan))
    return _quantile(data[np.isfinite(data)], q)


def contact_summary(
    tables: Mapping[str, pd.DataFrame],
    tuned: Mapping[tuple[str, str], Tuned],
    config: BenchmarkConfig,
) -> pd.DataFrame:
    """Isolation and classification per scenario and detector, over its scored events.

    A *scored* event is an event of a collision run matched to a contact
    (:mod:`.contacts`). Columns: scenario, method, oracle; ``n_events``
    (events of the collision runs), ``n_scored``; ``n_link_ok``,
    ``link_rate`` and its Wilson interval ``link_low``/``link_high``;
    ``n_link_unseen``, scored events on a link beyond the last monitored
    joint (the isolator weighs only joints with a band, so it cannot reach
    that link);
    ``point_error_median``/``_p95`` [m] (right link), ``line_distance_median``
    [m]; ``force_error_median``/``_p95`` of ||F̂| − |F|| [N],
    ``force_error_rel_median`` [-], ``force_error_filtered_median``/``_p95``
    [N] (against the force through the observer's filter),
    ``direction_error_median`` [deg]; ``n_above_quasi_static_min`` (|F̂| >
    65 N); ``n_intended`` (scored events of intended contacts), ``n_correct``,
    ``accuracy`` with ``accuracy_low``/``accuracy_high`` (Wilson).
    """
    events = tables["events"]
    scored = _scored(tables)
    rows = []
    for (scenario, label), item in tuned.items():
        here = events[
            (events["scenario"] == scenario) & (events["method"] == label)
            & (events["role"] == "collision")
        ]  # fmt: skip
        mine = scored[(scored["scenario"] == scenario) & (scored["method"] == label)]
        n = len(mine)
        links = int(mine["link_ok"].fillna(False).astype(bool).sum())
        right = mine[mine["link_ok"].fillna(False).to_numpy(dtype=bool)]
        correct = int(mine["kind_correct"].fillna(False).astype(bool).sum())
        row: dict[str, Any] = {
            "scenario": scenario, "method": label, "oracle": item.detection.oracle,
            "n_events": len(here), "n_scored": n, "n_link_ok": links,
        }  # fmt: skip
        row["link_rate"], row["link_low"], row["link_high"] = _rate(links, n, config.confidence)
        # A link beyond the last monitored joint moves joints without a band: unseen.
        last = max(item.threshold.monitored_joints_)
        row["n_link_unseen"] = int((mine["link_true"].fillna(0) > last).sum())
        row["point_error_median"] = _abs_quantile(right["point_error"], 0.5)
        row["point_error_p95"] = _abs_quantile(right["point_error"], 0.95)
        row["line_distance_median"] = _abs_quantile(mine["line_distance"], 0.5)
        row["force_error_median"] = _abs_quantile(mine["force_error"], 0.5)
        row["force_error_p95"] = _abs_quantile(mine["force_error"], 0.95)
        row["force_error_rel_median"] = _abs_quantile(mine["force_error_rel"], 0.5)
        row["force_error_filtered_median"] = _abs_quantile(mine["force_error_filtered"], 0.5)
        row["force_error_filtered_p95"] = _abs_quantile(mine["force_error_filtered"], 0.95)
        row["direction_error_median"] = _abs_quantile(mine["direction_error"], 0.5)
        row["n_above_quasi_static_min"] = int(
            mine["above_quasi_static_min"].fillna(False).astype(bool).sum()
        )
        row["n_intended"] = int((mine["true_kind"] == "intended").sum())
        row["n_correct"] = correct
        row["accuracy"], row["accuracy_low"], row["accuracy_high"] = _rate(
            correct, n, config.confidence
        )
        rows.append(row)
    return pd.DataFrame(rows)


def confusion_table(
    tables: Mapping[str, pd.DataFrame], tuned: Mapping[tuple[str, str], Tuned]
) -> pd.DataFrame:
    """Classes of the scored events: one row per scenario, detector and true class.

    Columns: scenario, method, ``true`` (``"intended"``, ``"collision"``) and
    the counts of the class assigned, ``intended`` and ``collision``; every
    row is there, zeros included, so a detector's counts add up to its
    ``n_scored`` of :func:`contact_summary`.
    """
    scored = _scored(tables)
    rows = []
    for scenario, label in tuned:
        mine = scored[(scored["scenario"] == scenario) & (scored["method"] == label)]
        for true in KINDS:
            assigned = mine.loc[mine["true_kind"] == true, "assigned_kind"]
            rows.append(
                {"scenario": scenario, "method": label, "true": true}
                | {kind: int((assigned == kind).sum()) for kind in KINDS}
            )
    return pd.DataFrame(rows, columns=["scenario", "method", "true", *KINDS])
