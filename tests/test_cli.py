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


def test_tune_detect_evaluate_round_trip(tmp_path) -> None:
    spec = copy.deepcopy(load_scenario("panda-gaz").spec)
    spec["duration"] = 4.0
    spec["random_collisions"] = {**spec["random_collisions"], "count": 1}
    scenario = tmp_path / "panda-gaz.yaml"
    scenario.write_text(yaml.safe_dump(spec))
    free, hit = tmp_path / "free.parquet", tmp_path / "hit.parquet"
    for path, flag, seed in ((free, "--no-collisions", "1"), (hit, "--collisions", "2")):
        result = runner.invoke(
            app, ["simulate", str(scenario), "-o", str(path), flag, "--seed", seed]
        )
        assert result.exit_code == 0, result.output
    thresholds = tmp_path / "tv.yaml"
    result = runner.invoke(
        app,
        ["tune", "--method", "time-variant", str(free), "-o", str(thresholds), "--margin", "0.1"],
    )
    assert result.exit_code == 0, result.output
    assert "method: time_variant" in thresholds.read_text()
    result = runner.invoke(app, ["detect", str(hit), "--thresholds", str(thresholds)])
    assert result.exit_code == 0, result.output
    assert "event(s) detected by time_variant" in result.output
    result = runner.invoke(app, ["evaluate", str(hit), "--thresholds", str(thresholds)])
    assert result.exit_code == 0, result.output
    assert "n_detected" in result.output
    result = runner.invoke(app, ["tune", "--method", "magic", str(free)])
    assert result.exit_code == 2 and "unknown threshold method" in result.output


def test_identify_friction_from_a_simulated_sweep(tmp_path) -> None:
    """`simulate` a sweep of planar2 with planted Coulomb friction, then `identify friction`."""
    spec = {
        "name": "planar2-sweep",
        "duration": 15.0,
        "robot": "planar2",
        "true_friction": {"type": "coulomb", "c_pos": [0.8, 0.5], "c_neg": [-0.6, -0.4]},
        "controller": {
            "kp": [4000.0, 2000.0],
            "kd": [200.0, 100.0],
            "ki": 0.0,
            "gravity_compensation": True,
            "friction_compensation": False,
        },
        "trajectory": {
            "type": "velocity_sweep",
            "joints": [1, 2],
            "velocities": [-0.5, 0.5, -1.0, 1.0],
            "hold": 1.2,
            "ramp": 0.3,
        },
    }
    scenario = tmp_path / "sweep.yaml"
    scenario.write_text(yaml.safe_dump(spec))
    log = tmp_path / "sweep.parquet"
    result = runner.invoke(app, ["simulate", str(scenario), "-o", str(log)])
    assert result.exit_code == 0, result.output
    out = tmp_path / "friction.yaml"
    result = runner.invoke(
        app, ["identify", "friction", str(log), "--robot", "planar2", "-o", str(out)]
    )
    assert result.exit_code == 0, result.output
    content = yaml.safe_load(out.read_text())
    assert out.with_suffix(".html").is_file()
    joints = content[str(log)]["joints"]
    coulomb = {j["joint"]: j["models"]["coulomb"] for j in joints}
    planted = {1: (0.8, -0.6), 2: (0.5, -0.4)}
    for joint, (c_pos, c_neg) in planted.items():
        assert abs(coulomb[joint]["c_pos"] - c_pos) < 0.02, coulomb
        assert abs(coulomb[joint]["c_neg"] - c_neg) < 0.02, coulomb
    result = runner.invoke(
        app, ["identify", "friction", str(log), "--robot", "panda", "-o", str(out)]
    )
    assert result.exit_code == 2 and "joints" in result.output


def test_identify_inertial_and_excite(tmp_path) -> None:
    log = tmp_path / "run.parquet"
    spec = copy.deepcopy(load_scenario("panda-gaz").spec)
    spec["duration"] = 15.0
    spec.pop("random_collisions")
    scenario = tmp_path / "short.yaml"
    scenario.write_text(yaml.safe_dump(spec))
    assert runner.invoke(app, ["simulate", str(scenario), "-o", str(log)]).exit_code == 0
    out = tmp_path / "inertial.yaml"
    result = runner.invoke(
        app, ["identify", "inertial", str(log), "--robot", "panda_gaz", "-o", str(out)]
    )
    assert result.exit_code == 0, result.output
    content = yaml.safe_load(out.read_text())
    assert content["statistics"]["r_squared"] > 0.99
    assert "mY2R" in content["parameters"] or len(content["parameters"]) > 40
    result = runner.invoke(app, ["identify", "inertial", str(log), "--robot", "puma560"])
    assert result.exit_code == 2 and "joints" in result.output
    trajectory = tmp_path / "excite.yaml"
    result = runner.invoke(
        app,
        [
            "excite",
            "--robot",
            "panda",
            "-o",
            str(trajectory),
            "--harmonics",
            "1",
            "--iterations",
            "3",
        ],
    )
    assert result.exit_code == 0, result.output
    assert yaml.safe_load(trajectory.read_text())["trajectory"]["type"] == "fourier"
