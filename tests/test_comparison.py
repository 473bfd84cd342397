"""The method comparison behind the demo, on a short scenario, and its real-arm section."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from sensorless.cli import app, demo
from sensorless.comparison import REAL_ARM_HEADING, compare, real_arm, write_comparison_report
from sensorless.comparison.runs import _jobs, _submit_runs
from sensorless.exceptions import InputValueError
from sensorless.monitor import poisson_interval
from sensorless.realarm import DEFAULT_FAMILIES
from sensorless.simulation.scenario import load_scenario

UR10_DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "ur10-ext_observer"


def test_compare_tunes_detects_and_reports(tmp_path) -> None:
    scenario = load_scenario("panda-gaz").with_duration(8.0)
    result = compare(scenario, methods=("constant", "time-variant"), n_tuning=1, master_seed=3)
    summary = result.summary()
    assert list(summary.index) == ["constant", "time-variant"]
    n_windows = len(result.evaluations["constant"].windows)
    assert n_windows >= 1
    assert (summary["n_collisions"] == n_windows).all()
    # Tuning and test seeds come from one master seed and never coincide.
    assert result.seeds["test"] not in result.seeds["tuning"]
    # Same absolute margin for both; the minimax band is never wider than β on its fit data.
    tv = result.thresholds["time-variant"]
    assert np.all(tv.alpha_ <= tv.beta_ + 1e-9)
    lower, upper = result.bounds["constant"]
    assert lower.shape == upper.shape == (result.test_log.n_samples, 7)
    table = result.per_collision()
    assert len(table) == n_windows
    assert result.efficiency() is not None
    path = write_comparison_report([result], tmp_path / "report.html")
    html = path.read_text()
    assert "panda-gaz" in html and "data:image/png;base64," in html


def test_compare_both_residuals_of_a_flexible_arm(tmp_path) -> None:
    """LWR with torque sensors: every momentum method on r̂ and r̂_s, plus the combined fit."""
    scenario = load_scenario("lwr4-thesis").with_duration(5.0)
    parallel = compare(
        scenario,
        methods=("constant", "velocity"),
        n_tuning=1,
        master_seed=5,
        joints=(1, 2, 3),
        residuals=("motor", "joint"),
        workers=2,
    )
    labels = [
        "constant",
        "constant (joint)",
        "velocity",
        "velocity (joint)",
        "velocity-combined",
        "velocity-combined (joint)",
    ]
    assert sorted(parallel.evaluations) == sorted(labels)
    assert parallel.kinds["velocity (joint)"] == "joint"
    assert parallel.kinds["velocity-combined"] == "motor"
    # r̂_s and r̂ differ (torque sensor vs command), each with its own constant β.
    motor, joint = parallel.signals["motor"], parallel.signals["joint"]
    assert not np.allclose(motor.residual, joint.residual)
    # One γ for both residuals (eq. 4.47).
    assert (
        parallel.thresholds["velocity-combined"] is parallel.thresholds["velocity-combined (joint)"]
    )
    # Simulating in worker processes gives the same logs, hence the same results.
    serial = compare(
        scenario,
        methods=("constant",),
        n_tuning=1,
        master_seed=5,
        joints=(1, 2, 3),
        residuals=("motor", "joint"),
    )
    np.testing.assert_array_equal(serial.test_log.tau_j, parallel.test_log.tau_j)
    np.testing.assert_array_equal(
        serial.bounds["constant (joint)"][1], parallel.bounds["constant (joint)"][1]
    )
    html = write_comparison_report([parallel], tmp_path / "report.html").read_text()
    assert "joint residual and bounds" in html


def test_compare_rejects_bad_options() -> None:
    scenario = load_scenario("lwr4-thesis").with_duration(1.0)
    with pytest.raises(InputValueError, match="residuals must be a non-empty subset"):
        compare(scenario, residuals=("torque",))
    with pytest.raises(InputValueError, match="workers must be a positive integer"):
        compare(scenario, workers=0)


@pytest.mark.skipif(
    not UR10_DATA.is_dir(), reason=f"the real UR10 recordings are absent (expected in {UR10_DATA})"
)
def test_real_arm_section_reports_held_out_false_alarms_of_three_families(tmp_path) -> None:
    section = real_arm(UR10_DATA)
    assert section.evaluation is not None and section.skipped == ""
    assert section.seconds > 0
    table = section.summary()
    assert table is not None and list(table.index) == list(DEFAULT_FAMILIES)
    for family, row in table.iterrows():
        seconds, alarms = float(row["held-out [s]"]), int(row["false alarms"])
        assert seconds > 50.0, family  # both folds' held-out recordings
        rate = float(row["per hour"])
        assert math.isfinite(rate) and rate == pytest.approx(alarms * 3600.0 / seconds)
        low, high = poisson_interval(alarms, seconds / 3600.0)
        assert (row["95 % low"], row["95 % high"]) == pytest.approx((low, high))
        assert low <= rate <= high
    html = write_comparison_report([], tmp_path / "report.html", real_arm=section).read_text()
    body = html[html.index(f"<h2>{REAL_ARM_HEADING}</h2>") :]
    rows = re.findall(r"<th>([a-z-]+)</th>\s*<td>", body)
    assert rows == list(DEFAULT_FAMILIES)
    assert "data:image/png;base64," in body and "link4.csv second half" in body


def test_real_arm_section_is_skipped_with_the_reason_without_recordings(tmp_path) -> None:
    absent = real_arm(tmp_path / "nowhere")
    assert absent.evaluation is None and absent.summary() is None
    assert "is not a folder" in absent.skipped and "--real-data" in absent.skipped
    empty = real_arm(tmp_path)  # a folder, but without the four files
    assert "lacks ['link4.csv', 'ur-static.csv', 'no_torque.csv', '3times.csv']" in empty.skipped
    html = write_comparison_report([], tmp_path / "report.html", real_arm=absent).read_text()
    body = html[html.index(f"<h2>{REAL_ARM_HEADING}</h2>") :]
    assert "<p>Skipped: " in body and "nowhere is not a folder" in body
    assert "<table" not in body and "<img" not in body


@pytest.mark.parametrize("present", [True, False])
def test_demo_ends_with_the_real_arm_section(tmp_path, monkeypatch, present) -> None:
    if present and not UR10_DATA.is_dir():
        pytest.skip(f"the real UR10 recordings are absent (expected in {UR10_DATA})")
    # The simulated scenarios take minutes: left out, the demo is its real-arm part alone.
    monkeypatch.setattr(demo, "DEMO_SCENARIOS", {})
    folder = UR10_DATA if present else tmp_path / "absent"
    out = tmp_path / "demo"
    result = CliRunner().invoke(app, ["demo", "-o", str(out), "--real-data", str(folder)])
    assert result.exit_code == 0, result.output
    html = (out / "report.html").read_text()
    body = html[html.index(f"<h2>{REAL_ARM_HEADING}</h2>") :]
    if present:
        assert "held-out false alarms, both folds pooled" in result.output
        assert "held-out [s]" in result.output  # the unit is no markup tag
        for family in DEFAULT_FAMILIES:
            assert re.search(rf"\n{family} +\d", result.output), family
        assert "<table" in body and "<img" in body
    else:
        assert "Real arm (UR10): skipped." in " ".join(result.output.split())
        assert "<p>Skipped: " in body and "<table" not in body


def test_compare_on_dask_equals_serial_and_reuses_runs_submitted_ahead() -> None:
    """The runs as Dask tasks give the serial run's logs, hence its bounds and tables.

    Runs submitted before :func:`compare` (as the demo does) are found by their keys: the
    client holds no key beyond them afterwards.
    """
    distributed = pytest.importorskip("distributed")
    scenario = load_scenario("panda-gaz").with_duration(3.0)
    options: dict[str, Any] = {
        "methods": ("constant", "velocity"),
        "n_tuning": 1,
        "master_seed": 11,
        "joints": (1, 2),
    }
    serial = compare(scenario, **options)
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        ahead = _submit_runs(client, _jobs(scenario, 1, 11)[1])
        parallel = compare(scenario, scheduler=client, **options)
        assert set(client.futures) == {future.key for future in ahead}
        assert len(ahead) == 2 and all(future.status == "finished" for future in ahead)
    for name in ("q", "tau_m", "tau_ext"):
        np.testing.assert_array_equal(
            getattr(serial.test_log, name), getattr(parallel.test_log, name)
        )
    for label in serial.bounds:
        np.testing.assert_array_equal(serial.bounds[label][0], parallel.bounds[label][0])
        np.testing.assert_array_equal(serial.bounds[label][1], parallel.bounds[label][1])
    pd.testing.assert_frame_equal(serial.summary(), parallel.summary())
    assert serial.seeds == parallel.seeds


def test_compare_rejects_an_unknown_scheduler() -> None:
    scenario = load_scenario("panda-gaz").with_duration(1.0)
    with pytest.raises(InputValueError, match="scheduler must be None, 'local'"):
        compare(scenario, scheduler="nowhere")
