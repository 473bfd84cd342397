"""The report's summary: one short table per scenario, the best per column, one sentence.

:func:`summarize` turns the :class:`~sensorless.evaluation.Evaluation` of
every method on one run into a :class:`ScenarioSummary`: a table in plain
words and units (its counts are those of the evaluations), the best cell of
each column, and a sentence generated from the table's numbers
(:func:`summary_sentence`). :data:`GLOSSARY` explains every column of the
report's tables once.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from ..evaluation import Evaluation
from ..evaluation.scoring import check_evaluations
from .html import Table

__all__ = [
    "GLOSSARY",
    "STRONG_FORCE",
    "ScenarioSummary",
    "band_widths",
    "best_cells",
    "collision_table",
    "summarize",
    "summary_sentence",
]

STRONG_FORCE = 20.0
"""Peak contact force [N] from which a collision counts as strong in the summary."""

DETECTED = "detected"
STRONG = f"≥ {STRONG_FORCE:g} N detected"
MASKED = "masked"
FALSE_ALARMS = "false alarms"
RATE = "false alarms [1/h]"
DELAY = "median delay [ms]"
EFF = "band vs constant (eff)"
BAND = "mean band [N m]"

# Which way is better, per column of the summary table (the numeric value behind each cell).
_BETTER = {DETECTED: "max", STRONG: "max", MASKED: "min", FALSE_ALARMS: "min", RATE: "min",
           DELAY: "min", EFF: "min", BAND: "min"}  # fmt: skip

GLOSSARY: dict[str, str] = {
    DETECTED: "collisions detected / collisions in the run. A collision is detected by an "
    "alarm that starts during the contact or at most max_delay (0.5 s) after its end.",
    STRONG: f"the same, counting only collisions whose peak force is at least {STRONG_FORCE:g} N.",
    MASKED: "collisions during which an alarm that began before the contact was still on when "
    "it started: that alarm tells nothing about the contact. It counts as a false alarm, and "
    "the collision neither as detected nor as missed.",
    "missed": "a collision that no alarm detects and none masks.",
    FALSE_ALARMS: "alarms that detect no collision (including those that mask one).",
    RATE: "false alarms per hour of motion: false alarms / duration of the run [h].",
    DELAY: "median over detected collisions of (start of the first detecting alarm − start of "
    "the contact), in milliseconds; never negative.",
    EFF: "mean width of the method's band (upper − lower bound, over time and monitored joints) "
    "divided by that of the constant threshold on the same residual; below 1 is tighter.",
    BAND: "mean width of the band (upper − lower bound) over time and monitored joints [N m].",
    "start delay [ms]": "per collision and method: start of the first detecting alarm − start "
    "of the contact [ms], or 'missed' / 'masked'.",
    "peak force [N]": "largest contact force of the collision, from the simulator.",
    "α, β [N m]": "time-variant threshold's constant part α and the constant threshold β = "
    "max|r̂| + margin (eq. 5.32, 5.33); eff = α/β per joint (thesis Table 5.7).",
    "γ, ε_fr [-]": "coefficients of h (the model-error term) and of the filtered friction in "
    "the time-variant threshold.",
}


@dataclass(frozen=True)
class ScenarioSummary:
    """The summary of one scenario (returned by :func:`summarize`).

    Attributes
    ----------
    name : str
        Scenario or log name.
    table : DataFrame
        One row per method (index ``"method"``); columns ``detected``
        (text "k/n"), ``≥ 20 N detected`` ("k/n", "–" without known
        forces), ``masked``, ``false alarms``, ``false alarms [1/h]``,
        ``median delay [ms]`` and, given band widths, ``band vs constant
        (eff)`` or ``mean band [N m]``.
    values : DataFrame
        The numbers behind ``table`` (counts as numbers, not text), which
        :func:`best_cells` and :func:`summary_sentence` read.
    best : frozenset of (method, column)
        Cells holding the best value of their column (none when all tie).
    missed_by_all : list of (int, float)
        Id and peak force [N] of the collisions that every method misses.
    sentence : str
        :func:`summary_sentence` of ``values``.
    """

    name: str
    table: pd.DataFrame
    values: pd.DataFrame
    best: frozenset[tuple[str, str]]
    missed_by_all: list[tuple[int, float]]
    sentence: str

    def to_table(self) -> Table:
        """The table for :func:`~sensorless.report.write_report`, titled, best cells in bold."""
        return Table(
            self.table,
            f"{self.name}: summary",
            note="Bold: the best value of its column. Columns are explained in the glossary.",
            best=self.best,
        )


def band_widths(
    bounds: Mapping[str, tuple[ArrayLike, ArrayLike]], joints: Sequence[int] | None = None
) -> dict[str, float]:
    """Mean band width (upper − lower) of every method over time and joints [N m].

    Parameters
    ----------
    bounds : mapping of str to (lower, upper)
        Arrays of shape (n_samples, n_dof) [N m] per method; NaN samples
        (refused, settling) are left out.
    joints : sequence of int, optional
        1-based joints to average over; default all.
    """
    widths = {}
    for name, (lower, upper) in bounds.items():
        width = np.asarray(upper, dtype=float) - np.asarray(lower, dtype=float)
        width = np.atleast_2d(width)
        if joints is not None:
            width = width[:, [j - 1 for j in joints]]
        finite = width[np.isfinite(width)]
        widths[str(name)] = float(finite.mean()) if finite.size else math.nan
    return widths


def _reference(method: str, widths: Mapping[str, float]) -> str | None:
    """The constant threshold on the residual ``method`` watches ("constant (joint)" for r̂_s)."""
    suffix = method[method.index(" (") :] if " (" in method else ""
    for candidate in (f"constant{suffix}", "constant"):
        if candidate in widths and math.isfinite(widths[candidate]) and widths[candidate] > 0:
            return candidate
    return None


def _fraction(k: float, n: float) -> str:
    return f"{int(k)}/{int(n)}" if n > 0 else "–"


def best_cells(values: pd.DataFrame) -> frozenset[tuple[str, str]]:
    """(method, column) of the best value of every column of ``values``; none when all tie."""
    best = set()
    for column in values.columns:
        if column not in _BETTER or column.endswith(" of"):
            continue
        numbers = values[column].to_numpy(dtype=float)
        finite = numbers[np.isfinite(numbers)]
        if finite.size == 0 or (np.all(finite == finite[0]) and finite.size == len(numbers)):
            continue
        target = finite.max() if _BETTER[column] == "max" else finite.min()
        best |= {
            (str(m), column) for m, v in zip(values.index, numbers, strict=True) if v == target
        }
    return frozenset(best)


def summarize(
    name: str,
    evaluations: Mapping[str, Evaluation],
    widths: Mapping[str, float] | None = None,
) -> ScenarioSummary:
    """The summary of one run: every method's counts, rates, delays and band width.

    Parameters
    ----------
    name : str
        Scenario or log name (the table's title).
    evaluations : mapping of str to Evaluation
        Evaluation of every method on the same run, by method name.
    widths : mapping of str to float, optional
        Mean band width of every method [N m] (:func:`band_widths`). With a
        constant threshold among them, the column ``band vs constant (eff)``;
        without, ``mean band [N m]``.

    Returns
    -------
    ScenarioSummary

    Raises
    ------
    InputValueError
        ``evaluations`` is empty.
    TypeError
        ``evaluations`` is not a mapping of Evaluation.
    """
    items = check_evaluations(evaluations)
    rows = {}
    for method, evaluation in items:
        table = evaluation.per_collision
        strong = table["peak_force"].to_numpy(dtype=float) >= STRONG_FORCE
        row: dict[str, float] = {
            DETECTED: evaluation.n_detected,
            f"{DETECTED} of": evaluation.n_collisions,
            STRONG: int(table["detected"].to_numpy(dtype=bool)[strong].sum()),
            f"{STRONG} of": int(strong.sum()),
            MASKED: evaluation.n_masked,
            FALSE_ALARMS: evaluation.n_false_alarms,
            RATE: evaluation.false_alarm_rate,
            DELAY: 1e3 * evaluation.median_start_delay,
        }
        if widths is not None:
            reference = _reference(method, widths)
            has_constant = any(_reference(m, widths) for m, _ in items)
            if has_constant:
                ratio = widths.get(method, math.nan) / widths[reference] if reference else math.nan
                row[EFF] = ratio
            else:
                row[BAND] = widths.get(method, math.nan)
        rows[str(method)] = row
    values = pd.DataFrame.from_dict(rows, orient="index")
    values.index.name = "method"
    shown = pd.DataFrame(index=values.index)
    for column in values.columns:
        if column.endswith(" of"):
            continue
        if column in (DETECTED, STRONG):
            shown[column] = [
                _fraction(k, n) for k, n in zip(values[column], values[f"{column} of"], strict=True)
            ]
        elif column in (MASKED, FALSE_ALARMS):
            shown[column] = values[column].astype(int)
        elif column == DELAY:
            shown[column] = values[column].round(0)
        else:
            shown[column] = values[column].round(1 if column == RATE else 2)
    first = items[0][1].per_collision
    detected_by_any = np.any(
        [e.per_collision["detected"].to_numpy(dtype=bool) for _, e in items], axis=0
    )
    missed_by_all = [
        (int(ident), float(force))
        for ident, force, hit in zip(
            first.index, first["peak_force"].to_numpy(dtype=float), detected_by_any, strict=True
        )
        if not hit
    ]
    return ScenarioSummary(
        str(name),
        shown,
        values,
        best_cells(values),
        missed_by_all,
        summary_sentence(values, missed_by_all),
    )


def _count(n: float, word: str) -> str:
    return f"{int(n)} {word}{'' if int(n) == 1 else 's'}"


def _rate(value: float) -> str:
    return f"{value:.0f}" if value >= 10 else f"{value:.1f}"


def _describe(method: str, row: pd.Series) -> str:
    text = f"{method} detects {_fraction(row[DETECTED], row[f'{DETECTED} of'])}"
    if row[f"{STRONG} of"] > 0 and row[f"{STRONG} of"] != row[f"{DETECTED} of"]:
        text += f" ({_fraction(row[STRONG], row[f'{STRONG} of'])} of ≥ {STRONG_FORCE:g} N)"
    text += f" with {_count(row[FALSE_ALARMS], 'false alarm')}"
    if row[FALSE_ALARMS] > 0:
        text += f" ({_rate(row[RATE])}/h)"
    if math.isfinite(row[DELAY]):
        text += f", median delay {row[DELAY]:.0f} ms"
    return text


def summary_sentence(values: pd.DataFrame, missed_by_all: Sequence[tuple[int, float]] = ()) -> str:
    """One sentence, from the numbers, that says which method wins and by how much.

    The methods are ranked by detected collisions (more is better), then
    false alarms, masked collisions and median delay (fewer, shorter). The
    sentence describes the first; compares it with the constant threshold's
    band (or, if the first is the constant threshold, with the runner-up);
    names masked collisions and the collisions every method misses.

    Parameters
    ----------
    values : DataFrame
        :attr:`ScenarioSummary.values`.
    missed_by_all : sequence of (int, float)
        Id and peak force [N] of the collisions no method detects.

    Returns
    -------
    str
    """
    ranked = values.assign(_delay=values[DELAY].fillna(math.inf)).sort_values(
        [DETECTED, FALSE_ALARMS, MASKED, "_delay"], ascending=[False, True, True, True]
    )
    winner = str(ranked.index[0])
    parts = [_describe(winner, ranked.iloc[0])]
    constant = next((str(m) for m in ranked.index if str(m).startswith("constant")), None)
    eff = float(ranked[EFF].to_numpy(dtype=float)[0]) if EFF in values.columns else math.nan
    if constant is not None and constant != winner and math.isfinite(eff) and eff > 0:
        wider = 1.0 / eff
        if wider >= 1.05:
            band = f"needs a {wider:.1f}× wider band"
        elif wider <= 0.95:
            band = f"has a {eff:.1f}× narrower band"
        else:
            band = "has a band as wide"
        parts.append(
            f"{_describe(constant, ranked.iloc[list(ranked.index).index(constant)])} and {band}"
        )
    elif len(ranked) > 1:
        parts.append(_describe(str(ranked.index[1]), ranked.iloc[1]))
    sentence = "; ".join(parts) + "."
    masked = [(str(m), int(n)) for m, n in values[MASKED].items() if n > 0]
    if masked:
        names = ", ".join(f"{m} {n}" for m, n in masked)
        sentence += f" Alarms already on masked contacts ({names})."
    if missed_by_all:
        listed = ", ".join(
            f"{ident} ({force:.0f} N)" if math.isfinite(force) else str(ident)
            for ident, force in missed_by_all
        )
        word = "collision" if len(missed_by_all) == 1 else "collisions"
        sentence += f" Every method misses {word} {listed}."
    return sentence


def collision_table(name: str, evaluations: Mapping[str, Evaluation]) -> Table:
    """Start delay [ms] of every method on every collision, or "missed" / "masked".

    One row per collision, labelled "id · peak force · start"; one column per
    method. Wide (many methods) it is shown transposed by the report.
    """
    items = check_evaluations(evaluations)
    reference = items[0][1].per_collision
    labels = []
    for ident, row in reference.iterrows():
        force = f"{row['peak_force']:.0f} N · " if math.isfinite(row["peak_force"]) else ""
        labels.append(f"{ident} · {force}{row['start']:.2f} s")
    columns: dict[str, list[str]] = {}
    for method, evaluation in items:
        cells = []
        for _, row in evaluation.per_collision.iterrows():
            if bool(row["detected"]):
                cells.append(f"{1e3 * row['start_delay']:.0f}")
            else:
                cells.append("masked" if bool(row["masked"]) else "missed")
        columns[str(method)] = cells
    frame = pd.DataFrame(columns, index=pd.Index(labels, name="collision · peak · start"))
    return Table(
        frame,
        f"{name}: start delay per collision [ms]",
        note="A number is the detection delay in milliseconds; 'missed' and 'masked' are "
        "explained in the glossary.",
    )
