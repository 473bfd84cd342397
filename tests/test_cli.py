"""The command-line interface is a thin layer: check its wiring and its errors."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from sensorless.cli import app
from sensorless.io import Log, read_log, write_log
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
    assert "method: time-variant" in thresholds.read_text()
    result = runner.invoke(app, ["detect", str(hit), "--thresholds", str(thresholds)])
    assert result.exit_code == 0, result.output
    assert "event(s) detected by time-variant" in result.output
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


# --------------------------------------------------------------------- a user's mistakes
@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cli")
    spec = copy.deepcopy(load_scenario("panda-gaz").spec)
    spec["duration"] = 1.0
    spec.pop("random_collisions")
    scenario = folder / "tiny.yaml"
    scenario.write_text(yaml.safe_dump(spec))
    log = folder / "free.parquet"
    assert runner.invoke(app, ["simulate", str(scenario), "-o", str(log)]).exit_code == 0
    thresholds = folder / "th.yaml"
    result = runner.invoke(app, ["tune", "--method", "constant", str(log), "-o", str(thresholds)])
    assert result.exit_code == 0, result.output
    corrupt = folder / "corrupt.yaml"
    corrupt.write_text("method: [constant\n  robot: {")
    return {"scenario": scenario, "log": log, "thresholds": thresholds, "corrupt": corrupt}


CASES = [
    # (arguments, exit code, what stderr must say)
    (["detect", "{missing}", "--thresholds", "{thresholds}"], 3, "does not exist"),
    (["detect", "{log}", "--thresholds", "{missing}"], 3, "No such file"),
    (["tune", "--method", "constant", "{missing}"], 3, "does not exist"),
    (["simulate", "{missing}.yaml", "-o", "{folder}/run.parquet"], 3, "scenario file not found"),
    (["detect", "{log}", "--thresholds", "{corrupt}"], 4, "is not valid YAML"),
    (["detect", "{log}", "--thresholds", "{log}"], 4, "not a YAML threshold file"),
    (["simulate", "{scenario}", "-o", "{folder}"], 2, "is a folder"),
    (["simulate", "{scenario}", "-o", "/dev/null/run.parquet"], 3, "/dev/null"),
    (["simulate", "{scenario}", "-o", "{folder}/run.txt"], 2, "must end in one of"),
    (["simulate", "{scenario}", "--seed", "-1"], 2, "--seed"),
    (["excite", "--robot", "panda", "--harmonics", "200"], 2, "--harmonics"),
    (["tune", "--method", "magic", "{log}"], 2, "unknown threshold method 'magic'"),
]


@pytest.mark.parametrize(("arguments", "code", "says"), CASES)
def test_a_mistake_is_one_line_on_stderr(files, tmp_path, arguments, code, says) -> None:
    paths = {**{k: str(v) for k, v in files.items()}, "missing": str(tmp_path / "nope.parquet")}
    paths["folder"] = str(tmp_path)
    result = runner.invoke(app, [a.format(**paths) for a in arguments])
    assert result.exit_code == code, (result.exit_code, result.output)
    assert "Traceback" not in result.output
    assert says in result.stderr
    if says not in ("--seed", "--harmonics"):  # click's own usage errors print a short box
        assert len(result.stderr.strip().splitlines()) == 1, result.stderr


def test_debug_shows_the_traceback(files, tmp_path) -> None:
    missing = str(tmp_path / "nope.parquet")
    result = runner.invoke(app, ["--debug", "detect", missing, "--thresholds", missing])
    assert isinstance(result.exception, FileNotFoundError)


def test_detect_reports_the_spans_it_refused(files, tmp_path) -> None:
    frame = read_log(files["log"]).to_pandas()
    frame.loc[(frame["t"] > 0.5) & (frame["t"] < 0.6), "tau_m_2"] = 1e6
    broken = tmp_path / "broken.parquet"
    write_log(Log.from_pandas(frame, metadata=read_log(files["log"]).metadata), broken)
    result = runner.invoke(app, ["detect", str(broken), "--thresholds", str(files["thresholds"])])
    assert result.exit_code == 0, result.output
    assert "1 span(s) refused as faults" in result.output
    assert "tau_m of joint 2 is 1e+06 N m" in result.output


UR10 = Path(__file__).resolve().parents[2] / "shared" / "data" / "ur10-ext_observer"


@pytest.mark.skipif(not UR10.is_dir(), reason="../shared/data/ur10-ext_observer is absent")
def test_import_splits_a_real_recording_at_its_gap(tmp_path) -> None:
    out = tmp_path / "three.parquet"
    args = ["import", "csv", str(UR10 / "3times.csv"), "--spec", "ur10_ext_observer"]
    result = runner.invoke(app, [*args, "-o", str(out)])
    assert result.exit_code == 0, result.output
    first, second = read_log(tmp_path / "three-1.parquet"), read_log(tmp_path / "three-2.parquet")
    assert (first.n_samples, second.n_samples) == (32, 36)
    assert first.groups == ["q", "qd", "tau_m"] and first.dt == pytest.approx(0.01)
    result = runner.invoke(app, ["import", "matlab", str(UR10 / "3times.csv")])
    assert result.exit_code == 2 and "unknown import format 'matlab'" in result.stderr


def test_warm_up_runs_every_compiled_path_once() -> None:
    """``make`` runs it after installing: each scenario's simulator and monitor on numba."""
    from sensorless.robots.recursion import numba_available

    result = runner.invoke(app, ["warm-up"])
    assert result.exit_code == 0, result.output
    lines = result.output.strip().splitlines()
    if not numba_available():
        assert "nothing to compile" in lines[0]
        return
    assert [line.split(":")[0] for line in lines] == ["puma560-thesis", "panda-gaz", "lwr4-thesis"]
    assert all("simulator numba, monitor numba" in line for line in lines), lines
