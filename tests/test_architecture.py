"""The house rules of ARCHITECTURE.md: one-way layers, validation once, a map that resolves."""

from __future__ import annotations

import cProfile
import importlib
import pstats
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sensorless import _validation
from sensorless.monitor import CollisionMonitor, tune
from sensorless.monitor import stream as stream_module
from sensorless.robots.recursion import numba_available
from sensorless.simulation.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[1]
LINT_IMPORTS = Path(sys.executable).with_name("lint-imports")


def _calls(function: object, run: object) -> int:
    """How many times ``function`` was called while ``run()`` ran (by its code object)."""
    code = function.__code__  # type: ignore[attr-defined]
    profile = cProfile.Profile()
    profile.runcall(run)  # type: ignore[arg-type]
    stats = pstats.Stats(profile).stats  # type: ignore[attr-defined]
    key = (code.co_filename, code.co_firstlineno, code.co_name)
    return int(stats[key][1]) if key in stats else 0


@pytest.fixture(scope="module")
def monitor_and_log():
    scenario = load_scenario("panda-gaz").with_duration(2.0)
    free = [scenario.run(seed=1, collisions=False).log]
    log = scenario.run(seed=2).log
    nominal = scenario.robots()[1]
    threshold, settings = tune(free, nominal, "time-variant", margin=0.05, folds=None)
    return CollisionMonitor(nominal, threshold, settings), log


@pytest.mark.parametrize("backend", ["python", "auto"])
def test_the_log_path_converts_once(monitor_and_log, backend) -> None:
    monitor, log = monitor_and_log
    monitor = CollisionMonitor(monitor.robot, monitor.threshold, monitor.settings, backend=backend)
    # The Python path converts the log's arrays once; the compiled one reads them as they are.
    expected = 1 if monitor.backend == "python" else 0
    assert _calls(_validation.as_joint_array, lambda: monitor.run(log)) == expected


@pytest.mark.parametrize("backend", ["python", "numpy", "numba"])
def test_a_stream_step_converts_each_input_once(monitor_and_log, backend, monkeypatch) -> None:
    monitor, log = monitor_and_log
    if backend == "numba" and not numba_available():
        pytest.skip("numba is not installed")
    monitor = CollisionMonitor(monitor.robot, monitor.threshold, monitor.settings, backend=backend)
    assert monitor.backend == backend
    for k in range(400):  # past the settling window: the whole pipeline runs
        monitor.step(log.t[k], log.q[k], log.tau_m[k])

    def one_step() -> None:
        monitor.step(log.t[400], log.q[400], log.tau_m[400])

    def one_step_of_lists() -> None:
        monitor.step(log.t[401], log.q[401].tolist(), log.tau_m[401].tolist())

    # The Python path converts with as_sample; the others hand float64 arrays to their
    # entry as they are (numba's signatures check them) and convert anything else once.
    conversions: list[object] = []

    def counted(x: object, dtype: object) -> np.ndarray:
        conversions.append(x)
        return np.ascontiguousarray(x, dtype=dtype)

    monkeypatch.setattr(stream_module, "_contiguous", counted)
    as_sample_calls = _calls(_validation.as_sample, one_step)
    if backend == "python":
        assert (as_sample_calls, len(conversions)) == (2, 0)  # q and tau_m
    else:
        assert (as_sample_calls, len(conversions)) == (0, 0)
        assert _calls(_validation.as_sample, one_step_of_lists) + len(conversions) == 2
    assert _calls(_validation.as_joint_array, one_step) == 0


def test_layers_hold_and_an_upward_import_breaks_them(tmp_path) -> None:
    config = ROOT / "pyproject.toml"
    kept = subprocess.run([LINT_IMPORTS, "--config", config], capture_output=True, text=True)
    assert kept.returncode == 0, kept.stdout + kept.stderr
    # A scratch copy with one upward import (the robots layer reaching for the monitor).
    scratch = tmp_path / "src"
    shutil.copytree(ROOT / "src" / "sensorless", scratch / "sensorless")
    model = scratch / "sensorless" / "robots" / "model.py"
    model.write_text(model.read_text() + "\nfrom ..monitor import tune  # noqa\n")
    broken = subprocess.run(
        [LINT_IMPORTS, "--config", config],
        capture_output=True,
        text=True,
        env={"PYTHONPATH": str(scratch), "PATH": str(LINT_IMPORTS.parent)},
        cwd=tmp_path,
    )
    assert broken.returncode != 0
    assert "sensorless.robots.model -> sensorless.monitor" in broken.stdout


def test_every_name_the_map_gives_exists() -> None:
    text = (ROOT / "ARCHITECTURE.md").read_text(encoding="utf-8")
    names = set(re.findall(r"`(sensorless(?:\.\w+)+)`", text))
    assert len(names) > 15
    for name in sorted(names):
        parts = name.split(".")
        for split in range(len(parts), 0, -1):
            try:
                obj: object = importlib.import_module(".".join(parts[:split]))
            except ModuleNotFoundError:
                continue
            for attribute in parts[split:]:
                obj = getattr(obj, attribute)
            break
        else:  # pragma: no cover - the loop always imports "sensorless"
            pytest.fail(name)
    for path in set(re.findall(r"`(\w+/\w+\.py)`", text)):
        assert (ROOT / path).exists() or (ROOT / "src" / "sensorless" / path).exists(), path


def test_no_module_is_a_two_room_house() -> None:
    sizes = {
        path.relative_to(ROOT / "src").as_posix(): len(path.read_text().splitlines())
        for path in (ROOT / "src" / "sensorless").rglob("*.py")
    }
    assert max(sizes.values()) <= 600, sorted(sizes.items(), key=lambda kv: -kv[1])[:3]
    assert np.median(list(sizes.values())) < 300
