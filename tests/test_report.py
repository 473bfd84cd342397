"""The report's summary, sentences and the `sensorless report` command.

The summary's counts are checked against the Evaluation objects and a recount
of their per-collision tables; the sentence against numbers that are changed.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from typer.testing import CliRunner

from sensorless.cli import app
from sensorless.comparison import compare
from sensorless.evaluation import evaluate
from sensorless.io import Log, write_log
from sensorless.report import (
    GLOSSARY,
    STRONG_FORCE,
    band_widths,
    collision_table,
    summarize,
    summary_sentence,
)
from sensorless.signals import Event
from sensorless.simulation.scenario import load_scenario

DT = 0.01
WINDOWS = {1: (2.0, 2.5, 40.0), 2: (5.0, 5.3, 12.0), 3: (8.0, 8.2, 60.0)}


def make_log() -> Log:
    t = np.arange(1001) * DT
    labels = np.zeros(t.size, dtype=np.int64)
    for ident, (start, end, _) in WINDOWS.items():
        labels[round(start / DT) : round(end / DT) + 1] = ident
    collisions = [{"id": i, "start": s, "end": e, "peak": f} for i, (s, e, f) in WINDOWS.items()]
    return Log(
        t=t, q=np.zeros((t.size, 2)), collision_id=labels, metadata={"collisions": collisions}
    )


def event(start: float, end: float) -> Event:
    return Event(start, end, (1,), 1.0, 2.0)


def evaluations(time_variant_events, constant_events):
    log = make_log()
    return {
        "constant": evaluate(constant_events, log, method="constant"),
        "time-variant": evaluate(time_variant_events, log, method="time-variant"),
    }


def test_summary_counts_equal_those_of_the_evaluations() -> None:
    found = evaluations(
        [event(2.05, 2.6), event(5.02, 5.1), event(8.01, 8.3)],
        [event(1.5, 2.2), event(8.1, 8.3), event(9.0, 9.1)],  # masks 1, misses 2
    )
    summary = summarize("run", found, {"constant": 4.0, "time-variant": 2.0})
    for method, evaluation in found.items():
        row = summary.table.loc[method]
        assert row["detected"] == f"{evaluation.n_detected}/{evaluation.n_collisions}"
        assert row["masked"] == evaluation.n_masked
        assert row["false alarms"] == evaluation.n_false_alarms
        assert row["false alarms [1/h]"] == pytest.approx(evaluation.false_alarm_rate, abs=0.05)
        # Recount of the strong collisions from the per-collision table.
        table = evaluation.per_collision
        strong = table["peak_force"] >= STRONG_FORCE
        assert row[f"≥ {STRONG_FORCE:g} N detected"] == (
            f"{int(table.loc[strong, 'detected'].sum())}/{int(strong.sum())}"
        )
        delays = table.loc[table["detected"], "start_delay"]
        assert row["median delay [ms]"] == pytest.approx(round(1e3 * float(np.median(delays))))
    assert summary.values.loc["constant", "masked"] == 1
    assert summary.table.loc["time-variant", "band vs constant (eff)"] == pytest.approx(0.5)
    # Best per column: more detected, fewer false alarms, narrower band.
    assert ("time-variant", "detected") in summary.best
    assert ("time-variant", "false alarms") in summary.best
    assert ("time-variant", "band vs constant (eff)") in summary.best
    assert ("constant", "detected") not in summary.best
    # Every column of the summary is explained in the glossary.
    assert set(summary.table.columns) <= set(GLOSSARY)


def test_sentence_is_derived_from_the_numbers() -> None:
    found = evaluations([event(2.05, 2.6), event(5.02, 5.1)], [event(2.2, 2.3), event(9.0, 9.1)])
    summary = summarize("run", found, {"constant": 5.0, "time-variant": 2.0})
    assert summary.sentence.startswith("time-variant detects 2/3 (1/2 of ≥ 20 N) with 0 false")
    assert "constant detects 1/3" in summary.sentence
    assert "needs a 2.5× wider band" in summary.sentence
    assert "Every method misses collision 3 (60 N)." in summary.sentence
    # Change the numbers: the sentence follows.
    values = summary.values.copy()
    values.loc["constant", ["detected", "false alarms"]] = [3, 0]
    changed = summary_sentence(values, [])
    assert changed.startswith("constant detects 3/3")
    assert "misses" not in changed
    values.loc["time-variant", "band vs constant (eff)"] = 0.25
    values.loc["constant", "detected"] = 0
    assert "needs a 4.0× wider band" in summary_sentence(values, [])
    # Other events, other sentence.
    other = summarize("run", evaluations([], [event(1.0, 2.1)]), None)
    assert "Alarms already on masked contacts (constant 1)." in other.sentence
    assert "Every method misses collisions 1 (40 N), 2 (12 N), 3 (60 N)." in other.sentence


def test_collision_table_and_band_widths() -> None:
    found = evaluations([event(2.05, 2.6)], [event(4.9, 5.1)])
    table = collision_table("run", found)
    assert list(table.frame["time-variant"]) == ["50", "missed", "missed"]
    assert list(table.frame["constant"]) == ["missed", "masked", "missed"]
    assert table.title == "run: start delay per collision [ms]"
    lower = np.full((4, 3), -1.0)
    upper = np.array([[1.0, 2.0, 3.0]] * 4)
    upper[0, 0] = np.nan
    widths = band_widths({"c": (lower, upper)}, joints=[1, 3])
    assert widths["c"] == pytest.approx((3 * 2.0 + 4 * 4.0) / 7)


@pytest.fixture(scope="module")
def run_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("report")
    comparison = compare(
        load_scenario("panda-gaz").with_duration(6.0), methods=("constant",), n_tuning=1,
        master_seed=2,
    )  # fmt: skip
    runner = CliRunner()
    collision = folder / "collision.parquet"
    write_log(comparison.test_log, collision)
    result = runner.invoke(
        app, ["tune", "--method", "constant", str(collision), "-o", str(folder / "c.yaml")]
    )
    assert result.exit_code == 0, result.output
    result = runner.invoke(
        app, ["tune", "--method", "time-variant", str(collision), "-o", str(folder / "tv.yaml")]
    )
    assert result.exit_code == 0, result.output
    return {"folder": folder, "log": collision}


def test_report_command_writes_the_report_and_how_to_reproduce_it(run_files) -> None:
    folder, log = run_files["folder"], run_files["log"]
    out = folder / "out" / "report.html"
    args = ["report", str(log), "--thresholds", str(folder / "c.yaml"),
            "--thresholds", str(folder / "tv.yaml"), "-o", str(out)]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "masked" in result.output  # the scoring rule is stated
    html = out.read_text(encoding="utf-8")
    assert "<h2>Summary</h2>" in html and "<h2>Glossary</h2>" in html
    assert "sensorless version" in html and "seeds of collision.parquet" in html
    command = re.search(r"<dt>command</dt><dd><code>([^<]*)</code>", html)
    assert command is not None and "--thresholds" in command.group(1)
    assert str(folder / "tv.yaml") in command.group(1)
    assert html.count("<img") >= 2


@pytest.mark.parametrize(
    ("extra", "code", "message"),
    [
        (["--thresholds", "{folder}/missing.yaml"], 3, "No such file"),
        (["--thresholds", "{folder}/c.yaml", "-o", "{folder}/report.txt"], 2, "must end in one of"),
        (["--thresholds", "{folder}/c.yaml", "--thresholds", "{folder}/c.yaml"], 2, "given twice"),
    ],
)
def test_report_command_user_errors_are_one_line(run_files, extra, code, message) -> None:
    folder = run_files["folder"]
    args = ["report", str(run_files["log"]), *[a.format(folder=folder) for a in extra]]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == code, result.output
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and message in lines[0]
