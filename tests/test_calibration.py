"""Tuning that tells the truth: cross-validated false alarms, a stated rate, warnings, files.

Synthetic residuals with a known distribution stand in for collision-free
runs: :class:`ObserverSignals` built directly from seeded noise, so the tests
are fast and the truth is known.
"""

from __future__ import annotations

import copy
import doctest
import inspect

import numpy as np
import pytest
import yaml
from scipy.signal import lfilter
from typer.testing import CliRunner

from sensorless.cli import app
from sensorless.detection import Detector
from sensorless.exceptions import FileFormatError, InputTypeError, InputValueError
from sensorless.monitor import (
    Calibration,
    CollisionMonitor,
    ObserverSettings,
    _heldout,
    calibration_of,
    cross_validate,
    hours_needed,
    load_tuned,
    margin_for_rate,
    poisson_interval,
    save_tuned,
    tune,
)
from sensorless.monitor.calibration import (
    DEFAULT_HOLD,
    DEFAULT_MIN_DURATION,
    attach_calibration,
    with_stated,
)
from sensorless.monitor.rate_margin import alarm_level, cluster_peaks
from sensorless.signals import ObserverSignals
from sensorless.simulation.scenario import load_scenario
from sensorless.thresholds import ConstantThreshold, TimeVariantThreshold, VelocityThreshold

SCALE = 0.1  # residual scale [N m]


def student_run(rng, seconds, *, dt=0.05, n_dof=2, nu=5.0):
    """iid Student-t residuals (scale SCALE) with every joint moving."""
    n = round(seconds / dt)
    t = np.arange(n) * dt
    residual = SCALE * rng.standard_t(nu, size=(n, n_dof))
    zeros = np.zeros_like(residual)
    velocity = np.column_stack([np.sin(t + j) for j in range(n_dof)])
    return ObserverSignals(t, residual, zeros, zeros, zeros, velocity, gain=20.0, robot="synth")


def filtered_run(rng, seconds, *, dt=0.01, n_dof=3, velocity=None):
    """Gaussian residuals through K_I/(s+K_I), K_I = 20 1/s, as an observer leaves them."""
    n = round(seconds / dt)
    t = np.arange(n) * dt
    a = np.exp(-20.0 * dt)
    noise = rng.standard_normal((n, n_dof))
    residual = SCALE * lfilter([np.sqrt(1 - a * a)], [1.0, -a], noise, axis=0)
    zeros = np.zeros_like(residual)
    if velocity is None:
        velocity = np.column_stack([np.sin(0.5 * t + j) for j in range(n_dof)])
    return ObserverSignals(t, residual, zeros, zeros, zeros, velocity, gain=20.0, robot="synth")


def stated_rate_trial(seed, rate=4.0, runs=6, seconds=60.0, test_hours=10.0):
    """Tune to ``rate`` on a few minutes, then count false alarms over ``test_hours``.

    Returns the empirical rate [1/h] and the interval the tuning stated.
    """
    rng = np.random.default_rng(seed)
    train = [student_run(rng, seconds) for _ in range(runs)]
    stated = margin_for_rate(train, ConstantThreshold(), rate, min_duration=0, hold=0, seed=seed)
    detector = Detector(ConstantThreshold(margin=list(stated.margin)).fit(train))
    pieces = int(test_hours)
    events = sum(len(detector.detect(student_run(rng, 3600.0))) for _ in range(pieces))
    return events / pieces, stated


def cross_validation_trial(seed, runs=8, seconds=60.0):
    """Cross-validate on ``runs`` runs, then count on ten times as many new runs."""
    rng = np.random.default_rng(seed)
    train = [filtered_run(rng, seconds) for _ in range(runs)]
    calibration = cross_validate(train, ConstantThreshold())
    detector = Detector(
        ConstantThreshold().fit(train), min_duration=DEFAULT_MIN_DURATION, hold=DEFAULT_HOLD
    )
    test = [filtered_run(rng, seconds) for _ in range(10 * runs)]
    events = sum(len(detector.detect(run)) for run in test)
    return events / (10 * runs * seconds / 3600.0), calibration


# ----------------------------------------------------------------------------- statistics


def test_poisson_interval_is_the_exact_chi_square_interval() -> None:
    assert poisson_interval(0, 1.0) == pytest.approx((0.0, 3.6889), abs=1e-4)
    assert poisson_interval(10, 2.0) == pytest.approx((4.7954 / 2, 18.3904 / 2), abs=1e-4)
    assert poisson_interval(3, 0.0) == (0.0, np.inf)
    assert hours_needed(1.0) == pytest.approx(2.9957, abs=1e-4)
    assert hours_needed(0.5, confidence=0.99) == pytest.approx(9.2103, abs=1e-4)
    with pytest.raises(InputValueError, match="confidence must be in"):
        poisson_interval(1, 1.0, confidence=1.0)
    with pytest.raises(InputValueError, match="events must be an integer"):
        poisson_interval(-1, 1.0)
    with pytest.raises(InputValueError, match="false-alarm rate"):
        hours_needed(0.0)


def test_the_doctests_run() -> None:
    result = doctest.testmod(_heldout)
    assert result.failed == 0 and result.attempted == 2


@pytest.mark.parametrize(
    ("min_duration", "hold"), [(0.0, 0.0), (0.0, 0.0505), (0.0055, 0.0505), (0.0205, 0.0105)]
)
def test_the_alarm_level_counts_what_the_detector_counts(min_duration, hold) -> None:
    """Clusters of the alarm level above m = the detector's events at margin m, for every m.

    Durations off the sample grid: on it, whether the detector's float
    subtraction of times reaches ``min_duration`` or ``hold`` is a matter of
    rounding, and the alarm level counts such ties as alarms.
    """
    rng = np.random.default_rng(0)
    train, test = (filtered_run(rng, seconds, dt=1e-3, n_dof=1) for seconds in (20.0, 100.0))
    zero = ConstantThreshold().fit(train)
    lower, upper = zero.bounds(test)
    excursion = np.maximum(test.residual - upper, lower - test.residual)
    level = alarm_level(excursion, test.dt, min_duration, hold)
    counted = []
    for margin in (-0.1, -0.05, 0.0, 0.02):
        shifted = copy.deepcopy(zero)
        shifted.beta_ = zero.beta_ + margin  # a margin below the fit, to see many events
        events = Detector(shifted, min_duration=min_duration, hold=hold).detect(test)
        counted.append(len(events))
        assert cluster_peaks(level[:, 0], margin, test.dt, hold).size == len(events)
    assert counted[0] > 10 and counted[-1] < counted[0]


# ----------------------------------------------------------------------------- (a) stated rate


def test_a_stated_rate_is_met_within_its_interval_in_most_trials() -> None:
    """20 seeded trials (15 asserted); 200 seeded trials gave a coverage of 179/200 = 0.895."""
    inside = 0
    for seed in range(20):
        empirical, stated = stated_rate_trial(seed)
        assert stated.predicted == pytest.approx(4.0) or stated.predicted < 4.0
        lower, upper = stated.interval
        inside += lower <= empirical <= upper
    assert inside >= 15


def test_margin_for_rate_reports_its_tail_and_the_data_needed() -> None:
    rng = np.random.default_rng(1)
    train = [student_run(rng, 60.0, n_dof=3) for _ in range(4)]
    stated = margin_for_rate(
        train, ConstantThreshold(joints=[1, 3]), 2.0, min_duration=0, hold=0, peaks=20
    )
    assert stated.margin[1] == 0.0 and stated.margin[0] > 0 and stated.margin[2] > 0
    assert stated.joints == (1, 3) and min(stated.peaks) >= 20
    assert stated.hours == pytest.approx(4 * 60 / 3600)
    assert stated.hours_needed == pytest.approx(hours_needed(2.0))
    assert stated.interval[0] <= stated.predicted <= stated.interval[1]
    again = margin_for_rate(
        train, ConstantThreshold(joints=[1, 3]), 2.0, min_duration=0, hold=0, peaks=20
    )
    assert again == stated  # seeded
    assert "stated rate 2 /h" in stated.describe()
    bigger = margin_for_rate(
        train, ConstantThreshold(joints=[1, 3]), 0.2, min_duration=0, hold=0, peaks=20
    )
    assert all(b > s for b, s in zip(bigger.margin[::2], stated.margin[::2], strict=True))


def test_margin_for_rate_refuses_what_it_cannot_do() -> None:
    rng = np.random.default_rng(2)
    train = [student_run(rng, 30.0) for _ in range(2)]
    with pytest.raises(InputValueError, match="false_alarm_rate must be"):
        margin_for_rate(train, ConstantThreshold(), 0.0)
    with pytest.raises(InputValueError, match="peaks must be an integer >= 10"):
        margin_for_rate(train, ConstantThreshold(), 1.0, peaks=5)
    with pytest.raises(InputValueError, match="no fold outlasts the transient"):
        margin_for_rate(train, ConstantThreshold(transient=40.0), 1.0)
    flat = [ObserverSignals(r.t, np.zeros_like(r.residual), *(r.residual * 0,) * 3, r.velocity,
                            gain=20.0, robot="synth") for r in train]  # fmt: skip
    with pytest.raises(InputValueError, match="too few or too alike"):
        margin_for_rate(flat, ConstantThreshold(), 1.0)
    with pytest.raises(InputTypeError, match="threshold must be a Threshold"):
        margin_for_rate(train, "constant", 1.0)  # type: ignore[arg-type]


# ----------------------------------------------------------------------------- (b) cross-validation


def test_the_cross_validated_interval_covers_ten_times_more_held_out_data() -> None:
    """20 seeded trials (16 asserted); 200 seeded trials gave a coverage of 185/200 = 0.925."""
    inside = 0
    for seed in range(20):
        measured, calibration = cross_validation_trial(seed)
        lower, upper = calibration.interval
        inside += lower <= measured <= upper
    assert inside >= 16


def test_cross_validation_by_run_and_by_time_block() -> None:
    rng = np.random.default_rng(3)
    train = [filtered_run(rng, 30.0) for _ in range(4)]
    by_run = cross_validate(train, ConstantThreshold(margin=0.01))
    assert by_run.scheme == "runs" and by_run.fold_labels == ("run 1", "run 2", "run 3", "run 4")
    assert by_run.hours == pytest.approx(4 * 30 / 3600)
    assert by_run.rate == pytest.approx(by_run.events / by_run.hours)
    assert by_run.interval == poisson_interval(by_run.events, by_run.hours)
    paired = cross_validate(train, ConstantThreshold(margin=0.01), folds=2)
    assert paired.fold_labels == ("runs 1-2", "runs 3-4")
    blocks = cross_validate([train[0]], ConstantThreshold(transient=1.0), folds=3)
    assert blocks.scheme == "blocks" and len(blocks.fold_events) == 3
    assert blocks.hours == pytest.approx((30 - 3 * 1.0) / 3600, rel=0.01)
    assert cross_validate([train[0]], ConstantThreshold()).fold_labels == (
        "block 1 of 2",
        "block 2 of 2",
    )
    table = by_run.to_pandas()
    assert list(table.columns) == ["held_out", "hours", "events", "rate"]
    assert table["events"].sum() == by_run.events
    with pytest.raises(InputValueError, match="needs at least 5 runs"):
        cross_validate(train, ConstantThreshold(), folds=5)
    with pytest.raises(InputValueError, match="folds must be 'runs' or an integer"):
        cross_validate(train, ConstantThreshold(), folds="blocks")
    with pytest.raises(InputValueError, match="folds must be an integer >= 2"):
        cross_validate(train, ConstantThreshold(), folds=1)
    short = filtered_run(rng, 0.4)  # 40 samples: one run cuts into blocks of >= 2 samples
    twenty = cross_validate([short], ConstantThreshold(transient=0.0), folds=20)
    assert len(twenty.fold_events) == 20
    for many in (21, 10**20):  # 10**20 was an array too large to allocate
        with pytest.raises(InputValueError, match=f"into {many} time blocks.*at most 20"):
            cross_validate([short], ConstantThreshold(transient=0.0), folds=many)


def test_cross_validation_leaves_the_threshold_alone() -> None:
    rng = np.random.default_rng(4)
    train = [filtered_run(rng, 20.0) for _ in range(3)]
    fitted = TimeVariantThreshold(margin=0.02).fit(train)
    before = fitted.to_dict()
    calibration = cross_validate(train, fitted)
    assert fitted.to_dict() == before and calibration.method == "time-variant"


# ----------------------------------------------------------------------------- (c) warnings


def test_warnings_for_a_short_run_a_still_joint_and_sparse_velocity_bins() -> None:
    rng = np.random.default_rng(5)
    n = 3000
    t = np.arange(n) * 0.01
    velocity = np.column_stack([0.4 * np.sin(t), np.zeros(n), 2.0 * np.sin(3 * t)])
    short = filtered_run(rng, 30.0, velocity=velocity)
    (warning_short, warning_still) = cross_validate([short], ConstantThreshold()).warnings
    assert warning_short == (
        "only 30 s of collision-free data: even without a false alarm they would bound the "
        "rate only below 443 /h; confirming 1 /h needs 3 h"
    )
    assert warning_still.startswith("joint(s) 2 never moved")
    calibration = cross_validate([short], VelocityThreshold(bin_width=0.05))
    sparse = calibration.warnings[-1]
    assert sparse.startswith("velocity bins with less than 0.5 s of fit data")
    assert "joint 3:" in sparse  # fast, so few samples per bin
    fitted = VelocityThreshold(bin_width=0.05).fit(short)
    assert cross_validate([short], fitted).warnings[-1] == sparse  # the fitted table agrees
    quiet = cross_validate([short], ConstantThreshold(joints=[1, 3])).warnings
    assert len(quiet) == 1  # joint 2 is not monitored; nothing sparse for the constant band
    stated = cross_validate([short], ConstantThreshold(joints=[1]), target_rate=10.0).warnings
    assert stated == (
        "30 s of collision-free data cannot confirm 10 false alarms/h: that needs 18 min "
        "without a false alarm (95 % confidence); until then the stated rate is extrapolated",
    )
    long_runs = [filtered_run(rng, 400.0) for _ in range(2)]
    assert cross_validate(long_runs, ConstantThreshold()).warnings == ()
    empty = cross_validate([short], ConstantThreshold(transient=20.0))
    assert empty.hours == 0 and "no fold outlasts the transient" in empty.warnings[0]
    assert np.isnan(empty.rate) and empty.interval == (0.0, np.inf)


# ----------------------------------------------------------------------------- (d) files


def test_save_and_load_round_trip_the_calibration(tmp_path) -> None:
    rng = np.random.default_rng(6)
    train = [student_run(rng, 60.0) for _ in range(3)]
    stated = margin_for_rate(train, ConstantThreshold(), 5.0, peaks=20, min_duration=0, hold=0)
    threshold = ConstantThreshold(margin=list(stated.margin)).fit(train)
    calibration = with_stated(cross_validate(train, threshold, target_rate=5.0), stated)
    attach_calibration(threshold, calibration)
    path = save_tuned(tmp_path / "th.yaml", threshold, ObserverSettings())
    content = yaml.safe_load(path.read_text())
    assert content["calibration"]["false_alarms_per_hour"] == pytest.approx(calibration.rate)
    loaded, _ = load_tuned(path)
    restored = calibration_of(loaded)
    assert restored == calibration and restored.to_dict() == calibration.to_dict()
    assert calibration_of(ConstantThreshold().fit(train)) is None
    content["calibration"]["fold_hours"] = [1.0]
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(content))
    with pytest.raises(FileFormatError, match="one label, count and duration per fold"):
        load_tuned(bad)
    del content["calibration"]["fold_events"]
    bad.write_text(yaml.safe_dump(content))
    with pytest.raises(FileFormatError, match="not a calibration description"):
        load_tuned(bad)
    with pytest.raises(InputTypeError, match="calibration must be a Calibration"):
        attach_calibration(threshold, {"rate": 1.0})  # type: ignore[arg-type]
    assert Calibration.from_dict(calibration.to_dict()) == calibration


# ----------------------------------------------------------------------------- tune and the CLI


def test_detector_defaults_match_the_monitor() -> None:
    parameters = inspect.signature(CollisionMonitor.__init__).parameters
    assert parameters["min_duration"].default == DEFAULT_MIN_DURATION
    assert parameters["hold"].default == DEFAULT_HOLD


@pytest.fixture(scope="module")
def tiny_scenario(tmp_path_factory):
    """Two short collision-free panda-gaz logs and one with a contact."""
    folder = tmp_path_factory.mktemp("tiny")
    spec = copy.deepcopy(load_scenario("panda-gaz").spec)
    spec["duration"] = 3.0
    spec["random_collisions"] = {**spec["random_collisions"], "count": 1}
    scenario = folder / "panda-gaz.yaml"
    scenario.write_text(yaml.safe_dump(spec))
    runner = CliRunner()
    paths = []
    for name, flag, seed in (("a", "--no-collisions", "1"), ("b", "--no-collisions", "2"),
                             ("hit", "--collisions", "3")):  # fmt: skip
        path = folder / f"{name}.parquet"
        result = runner.invoke(
            app, ["simulate", str(scenario), "-o", str(path), flag, "--seed", seed]
        )
        assert result.exit_code == 0, result.output
        paths.append(path)
    return paths


def test_tune_attaches_the_calibration_and_sets_a_stated_rate(tiny_scenario) -> None:
    from sensorless.io import read_log

    logs = [read_log(path) for path in tiny_scenario[:2]]
    scenario = load_scenario("panda-gaz")
    robot = scenario.robots()[1]
    threshold, _ = tune(logs, robot, "time-variant", margin=0.05)
    calibration = calibration_of(threshold)
    assert calibration is not None and calibration.fold_labels == ("run 1", "run 2")
    assert calibration.stated is None and calibration.method == "time-variant"
    quick, _ = tune(logs, robot, "time-variant", margin=0.05, folds=None)
    assert calibration_of(quick) is None and np.allclose(quick.alpha_, threshold.alpha_)
    with pytest.raises(InputValueError, match="record more collision-free motion"):
        tune(logs, robot, "time-variant", false_alarm_rate=50.0)
    longer = [scenario.with_duration(8.0).run(seed=s, collisions=False).log for s in (1, 2)]
    stated, _ = tune(longer, robot, "time-variant", false_alarm_rate=50.0, hold=0.01)
    chosen = calibration_of(stated).stated
    assert chosen is not None and chosen.rate == 50.0 and chosen.predicted == pytest.approx(50.0)
    assert stated.margin == list(chosen.margin) and min(chosen.margin) > 0
    assert calibration_of(stated).target_rate == 50.0
    with pytest.raises(InputValueError, match="give no margin"):
        tune(logs, robot, "time-variant", false_alarm_rate=1.0, margin=0.1)
    with pytest.raises(InputValueError, match="give no margin"):
        tune(logs, robot, "time-variant", false_alarm_rate=1.0, folds=None)


def test_cli_tune_prints_the_rate_and_detect_shows_it(tiny_scenario, tmp_path) -> None:
    runner = CliRunner()
    first, second, hit = (str(path) for path in tiny_scenario)
    out = tmp_path / "tv.yaml"
    arguments = ["tune", "--method", "time-variant", first, second, "-o", str(out), "--folds", "2"]
    result = runner.invoke(app, [*arguments, "--margin", "0.05"])
    assert result.exit_code == 0, result.output
    assert "false alarms:" in result.output and "% interval" in result.output
    assert "2 folds by run" in result.output and "warning: only" in result.output
    assert "false_alarms_per_hour" in out.read_text()
    result = runner.invoke(app, ["detect", hit, "--thresholds", str(out)])
    assert result.exit_code == 0, result.output
    assert "expected at tuning:" in result.output and "false alarms:" in result.output
    result = runner.invoke(app, [*arguments, "--false-alarm-rate", "50"])
    assert result.exit_code == 2 and "too few or too alike to fit a tail" in result.output
    result = runner.invoke(app, [*arguments, "--false-alarm-rate", "5", "--margin", "0.1"])
    assert result.exit_code == 2 and "give no margin" in result.output
    result = runner.invoke(app, [*arguments[:-1], "three"])
    assert result.exit_code == 2 and "folds must be 'runs' or an integer >= 2" in result.output
