"""The command-line interface is a thin layer: check its wiring and its errors."""

from __future__ import annotations

import copy

import yaml
from typer.testing import CliRunner

from sensorless.cli import app
from sensorless.io import read_log
from sensorless.simulation.scenario import load_scenario

runner = CliRunner()


def test_robots_and_scenarios_listings() -> None:
    result = runner.invoke(app, ["robots"])
    assert result.exit_code == 0, result.output
    for name in ("puma560", "panda_gaz", "planar2"):
        assert name in result.output
    result = runner.invoke(app, ["scenarios"])
    assert result.exit_code == 0, result.output
    assert "puma560-thesis" in result.output and "panda-gaz" in result.output


def test_simulate_writes_a_log(tmp_path) -> None:
    spec = copy.deepcopy(load_scenario("panda-gaz").spec)
    spec["duration"] = 1.0
    spec.pop("random_collisions")
    scenario = tmp_path / "tiny.yaml"
    scenario.write_text(yaml.safe_dump(spec))
    out = tmp_path / "run.csv"
    result = runner.invoke(app, ["simulate", str(scenario), "-o", str(out), "--seed", "4"])
    assert result.exit_code == 0, result.output
    log = read_log(out)
    assert log.n_samples == 1001 and log.n_dof == 7
    assert log.metadata["seed"] == 4


def test_simulate_reports_errors_without_a_traceback() -> None:
    result = runner.invoke(app, ["simulate", "no-such-scenario"])
    assert result.exit_code == 2
    assert "unknown scenario" in result.output
