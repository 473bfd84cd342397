"""The method comparison behind the demo, on a short scenario."""

from __future__ import annotations

import numpy as np

from sensorless.comparison import compare, write_comparison_report
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
