"""Tests of :mod:`sensorless.plots` and :mod:`sensorless.report`.

Figures are checked by their artists (axes, lines, shaded spans, scatter
collections, line data), not by pixels; saving to PNG checks that they can be
rendered without pyplot or a GUI backend. The report is checked for its
table values, the embedded image and the escaping of text.
"""

from __future__ import annotations

import base64
import math

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import PathCollection
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from sensorless.evaluation import evaluate
from sensorless.exceptions import DimensionError, InputValueError
from sensorless.io import Log
from sensorless.plots import plot_evaluation, plot_residuals, plot_tau_c
from sensorless.report import write_report
from sensorless.signals import Event, ObserverSignals

DT = 0.01
N_SAMPLES = 601  # 0 .. 6 s
N_DOF = 3
WINDOWS = ((1.0, 1.5), (4.0, 4.2))
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def time_base() -> np.ndarray:
    return np.arange(N_SAMPLES) * DT


def make_log(with_tau_c: bool = True) -> Log:
    t = time_base()
    labels = np.zeros(N_SAMPLES, dtype=np.int64)
    tau_c = np.zeros((N_SAMPLES, N_DOF))
    for ident, (start, end) in enumerate(WINDOWS, start=1):
        inside = slice(round(start / DT), round(end / DT) + 1)
        labels[inside] = ident
        tau_c[inside, 1] = 10.0 * np.sin(np.pi * (t[inside] - start) / (end - start))
    return Log(
        t=t,
        q=np.zeros((N_SAMPLES, N_DOF)),
        tau_c=tau_c if with_tau_c else None,
        collision_id=labels,
        metadata={"collisions": [{"id": 1, "start": 1.0, "end": 1.5, "peak": 20.0}]},
    )


def make_signals(kind: str = "motor") -> ObserverSignals:
    t = time_base()
    residual = np.column_stack([np.sin(t * (j + 1)) for j in range(N_DOF)])
    zeros = np.zeros_like(residual)
    return ObserverSignals(t, residual, zeros, zeros, zeros, zeros, 20.0, kind=kind)


def make_bounds() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    t = time_base()
    varying = 1.5 + 0.2 * np.sin(t)[:, None] * np.ones((1, N_DOF))
    return {
        "constant": (np.full(N_DOF, -2.0), np.full(N_DOF, 2.0)),
        "time-variant": (-varying, varying),
    }


def make_events() -> dict[str, list[Event]]:
    return {
        "constant": [Event(1.2, 1.4, (2,), 0.5, 2.5, "constant")],
        "time-variant": [
            Event(1.05, 1.6, (1, 2), 0.5, 2.5, "time-variant"),
            Event(4.02, 4.3, (2,), 0.5, 2.5, "time-variant"),
        ],
    }


def window_spans(ax) -> list[Rectangle]:
    return [patch for patch in ax.patches if isinstance(patch, Rectangle)]


def test_plot_residuals_artists():
    figure = plot_residuals(
        make_signals(), make_bounds(), log=make_log(), events=make_events(), title="PUMA 560"
    )
    assert isinstance(figure, Figure)
    axes = figure.axes
    assert len(axes) == N_DOF
    for ax in axes:
        # Residual, then upper and lower bound of each of the two methods.
        assert len(ax.lines) == 1 + 2 * 2
        assert len(window_spans(ax)) == len(WINDOWS)
    # Spans cover the ground-truth windows.
    extents = sorted(
        (round(p.get_x(), 9), round(p.get_x() + p.get_width(), 9)) for p in window_spans(axes[0])
    )
    assert extents == [WINDOWS[0], WINDOWS[1]]
    # Detection marks: joint 1 only has the time-variant event, joint 2 both methods,
    # joint 3 none.
    scatters = [[c for c in ax.collections if isinstance(c, PathCollection)] for ax in axes]
    assert [len(s) for s in scatters] == [1, 2, 0]
    marks = scatters[1][1].get_offsets()
    residual = make_signals().residual[:, 1]
    assert np.asarray(marks[:, 0]).tolist() == [1.05, 4.02]
    assert np.asarray(marks[:, 1]) == pytest.approx(np.interp([1.05, 4.02], time_base(), residual))
    # The lines carry the data: residual of joint 3, constant upper bound 2.0.
    assert np.array_equal(axes[2].lines[0].get_ydata(), make_signals().residual[:, 2])
    assert np.all(axes[0].lines[1].get_ydata() == 2.0)
    assert np.all(axes[0].lines[2].get_ydata() == -2.0)
    assert axes[-1].get_xlabel() == "time [s]"
    assert axes[1].get_ylabel() == r"$\hat{r}$ joint 2 [N m]"
    assert figure.get_suptitle() == "PUMA 560"
    # The legend sits below the axes (a figure legend), never on the data.
    assert all(ax.get_legend() is None for ax in axes)
    labels = [text.get_text() for text in figure.legends[0].get_texts()]
    assert labels[:3] == [r"$\hat{r}$", "constant", "time-variant"]
    assert "collision" in labels


def test_plot_residuals_selected_joints_without_log_or_events():
    figure = plot_residuals(make_signals("joint"), make_bounds(), joints=[2, 3])
    assert len(figure.axes) == 2
    assert figure.axes[0].get_ylabel() == r"$\hat{r}_s$ joint 2 [N m]"
    assert all(not window_spans(ax) for ax in figure.axes)
    assert all(not ax.collections for ax in figure.axes)


def test_plot_residuals_without_bounds_has_only_the_residual():
    figure = plot_residuals(make_signals())
    assert [len(ax.lines) for ax in figure.axes] == [1, 1, 1]


def test_figures_save_to_png(tmp_path):
    log = make_log()
    evaluations = {name: evaluate(found, log, method=name) for name, found in make_events().items()}
    figures = {
        "residuals": plot_residuals(make_signals(), make_bounds(), log=log, events=make_events()),
        "tau_c": plot_tau_c(log, make_signals()),
        "evaluation": plot_evaluation(evaluations),
    }
    for name, figure in figures.items():
        path = tmp_path / f"{name}.png"
        figure.savefig(path)
        assert path.read_bytes()[:8] == PNG_MAGIC


def test_plot_residuals_rejects_bad_input():
    signals = make_signals()
    with pytest.raises(InputValueError, match=r"joints must be .* joint numbers 1..3; got \[0\]"):
        plot_residuals(signals, joints=[0])
    with pytest.raises(InputValueError, match=r"got \[\]"):
        plot_residuals(signals, joints=[])
    with pytest.raises(InputValueError, match=r"got \[True\]"):
        plot_residuals(signals, joints=[True])
    with pytest.raises(DimensionError, match=r"lower bound of 'c' must be .* got shape \(2,\)"):
        plot_residuals(signals, {"c": (np.zeros(2), np.ones(3))})
    with pytest.raises(InputValueError, match=r"bounds\['c'\] must be a pair"):
        plot_residuals(signals, {"c": np.ones(3)})  # type: ignore[dict-item]
    with pytest.raises(TypeError, match="bounds must be a mapping"):
        plot_residuals(signals, [(0.0, 1.0)])  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="events must be a mapping"):
        plot_residuals(signals, events=[])  # type: ignore[arg-type]


def test_plot_tau_c_artists():
    log = make_log()
    figure = plot_tau_c(log, make_signals(), joints=[2])
    (ax,) = figure.axes
    assert len(ax.lines) == 2
    assert np.array_equal(ax.lines[0].get_ydata(), log.tau_c[:, 1])
    assert np.array_equal(ax.lines[1].get_ydata(), make_signals().residual[:, 1])
    assert len(window_spans(ax)) == len(WINDOWS)
    assert [len(ax.lines) for ax in plot_tau_c(log).axes] == [1, 1, 1]


def test_plot_tau_c_rejects_bad_input():
    with pytest.raises(InputValueError, match="needs a log with ground-truth external torques"):
        plot_tau_c(make_log(with_tau_c=False))
    two_joints = ObserverSignals(
        time_base(), np.zeros((N_SAMPLES, 2)), *[np.zeros((N_SAMPLES, 2))] * 4, 20.0
    )
    with pytest.raises(DimensionError, match=r"joint count of the log \(3\); got 2"):
        plot_tau_c(make_log(), two_joints)


def test_plot_evaluation_artists():
    log = make_log()
    events = [Event(1.05, 1.6, (2,), 0.5, 2.5), Event(2.5, 2.6, (1,), 0.5, 2.5)]
    evaluations = {
        "time-variant": evaluate(events, log),
        "none": evaluate([], log),
    }
    figure = plot_evaluation(evaluations, title="timeline")
    (ax,) = figure.axes
    assert len(window_spans(ax)) == len(WINDOWS)
    # time-variant: one detection bar set, one false-alarm bar set; none: no bars.
    assert len(ax.collections) == 2
    # Missed windows: window 2 for time-variant, both windows for "none".
    crosses = [line for line in ax.lines if line.get_marker() == "x"]
    assert [len(line.get_xdata()) for line in crosses] == [1, 2]
    assert [tick.get_text() for tick in ax.get_yticklabels()] == ["none", "time-variant"]
    single = plot_evaluation(evaluate(events, log, method="tv"))
    assert [tick.get_text() for tick in single.axes[0].get_yticklabels()] == ["tv"]


def test_plot_evaluation_rejects_bad_input():
    with pytest.raises(InputValueError, match="at least one"):
        plot_evaluation({})
    with pytest.raises(TypeError, match=r"evaluations\['a'\] must be an Evaluation; got int"):
        plot_evaluation({"a": 1})  # type: ignore[dict-item]
    with pytest.raises(TypeError, match="an Evaluation or a mapping"):
        plot_evaluation([])  # type: ignore[arg-type]


# --------------------------------------------------------------------------- report


def test_write_report_is_self_contained(tmp_path):
    table = pd.DataFrame(
        {"start_delay": [0.27, math.nan], "detected": [True, False]},
        index=pd.Index([1, 2], name="id"),
    )
    figure = plot_residuals(make_signals(), make_bounds(), log=make_log())
    path = write_report(
        tmp_path / "report.html",
        title="Detection <PUMA 560>",
        sections=[
            ("Tables", [table, pd.Series([0.7847], name="eff")]),
            ("Figures", figure),
            ("Notes", "First paragraph.\n\n<script>alert('x')</script> & more"),
        ],
    )
    assert path == tmp_path / "report.html"
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>")
    assert "<title>Detection &lt;PUMA 560&gt;</title>" in text
    assert "<h2>Tables</h2>" in text and "<h2>Notes</h2>" in text
    assert "<td>0.27</td>" in text
    assert "<td>0.7847</td>" in text
    assert "<td>–</td>" in text  # NaN
    assert "start_delay" in text
    assert "<p>First paragraph.</p>" in text
    assert "<script>" not in text
    assert "&lt;script&gt;alert(&#x27;x&#x27;)&lt;/script&gt; &amp; more" in text
    # No external assets: the only image is inline, there are no links or scripts.
    assert text.count('<img src="data:image/png;base64,') == 1
    assert "<link" not in text and "http" not in text and "<style>" in text
    start = text.index("base64,") + len("base64,")
    encoded = text[start : text.index('"', start)]
    assert base64.b64decode(encoded)[:8] == PNG_MAGIC


def test_write_report_rejects_bad_input(tmp_path):
    path = tmp_path / "report.html"
    with pytest.raises(TypeError, match=r"sections\[0\] item 1 must be a pandas DataFrame"):
        write_report(path, title="t", sections=[("a", ["ok", 3])])  # type: ignore[list-item]
    with pytest.raises(InputValueError, match=r"sections\[0\] must be a pair"):
        write_report(path, title="t", sections=["heading only"])  # type: ignore[list-item]
    with pytest.raises(InputValueError, match="dpi must be a positive number; got 0"):
        write_report(path, title="t", sections=[], dpi=0)
    with pytest.raises(TypeError, match="unexpected keyword"):
        write_report(path, title="t", sections=[], style="dark")  # type: ignore[call-arg]
    assert not path.exists()
