"""The method comparison behind the demo, on a short scenario."""

from __future__ import annotations

import numpy as np
import pytest

from sensorless.comparison import compare, write_comparison_report
from sensorless.exceptions import InputValueError
from sensorless.simulation.scenario import load_scenario


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
