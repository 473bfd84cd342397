"""One name per threshold family, margins as a fraction of the band, Fourier scenarios."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

from sensorless.exceptions import FileFormatError, InputValueError, UnknownNameError
from sensorless.monitor import ObserverSettings, load_tuned, save_tuned, tune
from sensorless.simulation.scenario import load_scenario
from sensorless.simulation.schema import validate_scenario
from sensorless.thresholds import TimeVariantThreshold, load_threshold
from sensorless.thresholds.files import FAMILY_NAMES, family_class, family_name


@pytest.fixture(scope="module")
def free_run() -> tuple:
    scenario = load_scenario("panda-gaz").with_duration(1.5)
    return scenario.run(seed=1, collisions=False).log, scenario.robots()[1]


@pytest.fixture(scope="module")
def hysteretic(free_run: tuple) -> tuple:
    log, nominal = free_run
    return tune([log], nominal, "hysteretic", folds=None)


def test_every_family_name_names_a_class() -> None:
    assert all(family_class(name) is not None for name in FAMILY_NAMES)
    assert family_class("time_variant") is family_class("time-variant") is TimeVariantThreshold
    assert family_class("nonsense") is None


def test_hysteretic_is_saved_under_its_own_name_and_old_files_read(
    hysteretic: tuple, free_run: tuple, tmp_path: Path
) -> None:
    threshold, settings = hysteretic
    assert family_name(threshold) == "hysteretic"
    path = save_tuned(tmp_path / "h.yaml", threshold, settings)
    data = yaml.safe_load(path.read_text())
    assert data["method"] == "hysteretic" and data["params"]["form"] == "hysteretic"
    # A file of the earlier format: the family's class name, the form in params only.
    old = tmp_path / "old.yaml"
    old.write_text(yaml.safe_dump({**data, "method": "time_variant"}))
    loaded, _ = load_tuned(old)
    assert family_name(loaded) == "hysteretic"
    signals = settings.observe(free_run[0], free_run[1])
    for a, b in zip(loaded.bounds(signals), threshold.bounds(signals), strict=True):
        np.testing.assert_array_equal(a, b)
    # The method names the form; a file whose params say otherwise is refused.
    wrong = tmp_path / "wrong.yaml"
    params = {**data["params"], "form": "friction"}
    wrong.write_text(yaml.safe_dump({**data, "params": params}))
    with pytest.raises(FileFormatError, match=r"params.form: method 'hysteretic' is the form"):
        load_threshold(wrong)


def test_unknown_and_old_method_names_in_tune(free_run: tuple) -> None:
    log, nominal = free_run
    with pytest.raises(UnknownNameError, match=r"'time_variant' \(the family is called 'time-var"):
        tune([log], nominal, "time_variant", folds=None)
    with pytest.raises(UnknownNameError, match="unknown threshold method 'magic'"):
        tune([log], nominal, "magic", folds=None)


def test_default_margin_is_a_tenth_of_the_constant_band(free_run: tuple) -> None:
    log, nominal = free_run
    settings = ObserverSettings()
    threshold, _ = tune([log], nominal, "velocity", settings, folds=None)
    # The band recomputed by hand: max |r| after the observer's settling time.
    signals = settings.observe(log, nominal)
    keep = signals.t >= signals.t[0] + settings.settle_time(log.dt)
    beta = np.max(np.abs(signals.residual[keep]), axis=0)
    np.testing.assert_allclose(threshold.margin, 0.1 * beta, rtol=1e-12)
    wider, _ = tune([log], nominal, "velocity", settings, folds=None, margin_fraction=0.25)
    np.testing.assert_allclose(wider.margin, 0.25 * beta, rtol=1e-12)
    absolute, _ = tune([log], nominal, "velocity", settings, folds=None, margin=0.5)
    assert absolute.margin == 0.5


def test_margin_forms_exclude_each_other(free_run: tuple) -> None:
    log, nominal = free_run
    with pytest.raises(InputValueError, match="not both"):
        tune([log], nominal, "constant", folds=None, margin=0.5, margin_fraction=0.1)
    with pytest.raises(InputValueError, match="margin_fraction"):
        tune([log], nominal, "constant", folds=None, margin_fraction=-0.1)
    with pytest.raises(InputValueError, match="false_alarm_rate sets the margin"):
        tune([log], nominal, "constant", false_alarm_rate=1.0, margin_fraction=0.1)


def _fourier(n_dof: int, harmonics: int = 2) -> dict:
    rng = np.random.default_rng(0)
    return {
        "type": "fourier",
        "base_frequency": 0.2,
        "duration": 5.0,
        "offset": [0.0] * n_dof,
        "a": rng.uniform(-0.2, 0.2, (harmonics, n_dof)).tolist(),
        "b": rng.uniform(-0.2, 0.2, (harmonics, n_dof)).tolist(),
    }


def test_scenario_schema_accepts_a_fourier_trajectory() -> None:
    spec = copy.deepcopy(load_scenario("panda-gaz").spec)
    spec["trajectory"] = _fourier(7)
    assert validate_scenario(spec).trajectory.type == "fourier"
    spec["trajectory"]["b"] = spec["trajectory"]["b"][:1]
    with pytest.raises(FileFormatError, match=r"trajectory.b: expected a and b of the same shape"):
        validate_scenario(spec)
    spec["trajectory"] = _fourier(6)
    with pytest.raises(FileFormatError, match=r"trajectory.a: expected one row of 7 numbers"):
        validate_scenario(spec)
