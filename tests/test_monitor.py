"""The pipeline: tune → save/load → detect, batch and streaming, with faults."""

from __future__ import annotations

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import DimensionError, InputValueError, UnknownNameError
from sensorless.monitor import CollisionMonitor, ObserverSettings, load_tuned, save_tuned, tune
from sensorless.simulation.scenario import load_scenario


@pytest.fixture(scope="module")
def runs():
    scenario = load_scenario("panda-gaz").with_duration(6.0)
    free = [scenario.run(seed=s, collisions=False).log for s in (1, 2)]
    test = scenario.run(seed=3).log
    return free, test, scenario.robots()[1]


@pytest.mark.parametrize("method", ["constant", "time-variant", "velocity", "model"])
def test_streaming_equals_batch_and_files_round_trip(runs, method, tmp_path) -> None:
    free, test, nominal = runs
    threshold, settings = tune(free, nominal, method, margin=0.05)
    path = save_tuned(tmp_path / "th.yaml", threshold, settings)
    loaded, loaded_settings = load_tuned(path)
    assert loaded_settings == settings
    monitor = CollisionMonitor(nominal, loaded, loaded_settings)
    signals, batch_events = monitor.run(test)
    np.testing.assert_array_equal(loaded.bounds(signals)[0], threshold.bounds(signals)[0])
    assert batch_events, "the test run has contacts: something must be detected"
    stream_events = []
    n = 4000  # the first 4 s hold the first contact
    for k in range(n):
        verdict = monitor.step(test.t[k], test.q[k], test.tau_m[k])
        assert verdict.status in ("ok", "collision")
        if verdict.event is not None:
            stream_events.append(verdict.event)
    last = monitor.finish()
    if last is not None:
        stream_events.append(last)
    expected = CollisionMonitor(nominal, loaded, loaded_settings).detector.detect(_head(signals, n))
    assert [(e.start, e.end, e.joints) for e in stream_events] == [
        (e.start, e.end, e.joints) for e in expected
    ]
    for a, b in zip(stream_events, expected, strict=True):
        assert a.peak == pytest.approx(b.peak, rel=1e-9, abs=1e-9)


def _head(signals: sl.observers.ObserverSignals, n: int) -> sl.observers.ObserverSignals:
    fields = (
        "residual",
        "model_torque",
        "friction",
        "sign",
        "velocity",
        "position",
        "acceleration",
    )
    values = {f: None if getattr(signals, f) is None else getattr(signals, f)[:n] for f in fields}
    return type(signals)(
        t=signals.t[:n], gain=signals.gain, kind=signals.kind, robot=signals.robot, **values
    )


def test_a_bad_sample_gives_a_fault_and_loses_nothing(runs) -> None:
    free, test, nominal = runs
    threshold, settings = tune(free, nominal, "constant", margin=0.05)
    clean = CollisionMonitor(nominal, threshold, settings)
    faulty = CollisionMonitor(nominal, threshold, settings)
    bad_inputs = [
        (test.t[5], np.full(7, np.nan), test.tau_m[5]),
        (test.t[5], test.q[5][:6], test.tau_m[5]),
        (test.t[5], test.q[5], "torque"),
        (float("nan"), test.q[5], test.tau_m[5]),
    ]
    for k in range(300):
        expected = clean.step(test.t[k], test.q[k], test.tau_m[k])
        if k == 5:
            for t, q, tau in bad_inputs:
                verdict = faulty.step(t, q, tau)
                assert verdict.status == "fault" and verdict.message
        if k == 6:
            assert faulty.step(test.t[2], test.q[2], test.tau_m[2]).status == "fault"  # time back
        got = faulty.step(test.t[k], test.q[k], test.tau_m[k])
        assert got.status == expected.status
        np.testing.assert_array_equal(got.residual, expected.residual)


def test_pipeline_errors_are_clear(runs) -> None:
    free, _, nominal = runs
    with pytest.raises(UnknownNameError, match="unknown threshold method 'magic'"):
        tune(free, nominal, "magic")
    with pytest.raises(InputValueError, match="at least one collision-free log"):
        tune([], nominal, "constant")
    with pytest.raises(InputValueError, match="watches the 'acceleration' residual"):
        tune(free, nominal, "model", ObserverSettings(kind="motor"))
    threshold, settings = tune(free, nominal, "constant")
    with pytest.raises(DimensionError, match="threshold is for 7 joints"):
        CollisionMonitor(sl.robots.load("puma560"), threshold, settings)
    with pytest.raises(InputValueError, match="observer kind must be"):
        ObserverSettings(kind="magic")
    with pytest.raises(TypeError, match="unknown observer settings"):
        ObserverSettings.from_dict({"kind": "motor", "colour": "red"})


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")
@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")
@pytest.mark.parametrize("method", ["constant", "time-variant"])
def test_stream_equals_the_public_components_step_by_step(runs, method) -> None:
    # The monitor skips re-validation internally; it must give exactly what the
    # validated public steps give, including on a finite sample whose huge value
    # makes the observer outputs non-finite (a detector fault).
    free, test, nominal = runs
    threshold, settings = tune(free, nominal, method, margin=0.05)
    monitor = CollisionMonitor(nominal, threshold, settings)
    dt = monitor.dt
    estimator = settings.estimator(dt)
    observer = sl.observers.MomentumObserver(nominal, dt, settings.gain, torque=settings.kind)
    detector = sl.detection.Detector(threshold)
    q_huge = test.q[250] + 1e200
    samples = [(test.t[k], test.q[k], test.tau_m[k]) for k in range(300)]
    samples[250] = (test.t[250], q_huge, test.tau_m[250])
    states = None
    for t, q, tau in samples:
        got = monitor.step(t, q, tau)
        if states is None:
            states = (
                estimator.initial_state(q),
                observer.initial_state(q, np.zeros_like(q)),
                detector.initial_state(dt),
            )
        y, est_state = estimator.step(q, states[0])
        sample, obs_state = observer.step(states[1], q, y.velocity, tau)
        expected, det_state = detector.step(
            states[2], *sample, y.velocity, t, position=q, acceleration=y.acceleration
        )
        states = (est_state, obs_state, det_state)
        assert (got.status, got.t, got.joints, got.message) == (
            expected.status,
            expected.t,
            expected.joints,
            expected.message,
        )
        assert got.event == expected.event
        for name in ("residual", "lower", "upper"):
            np.testing.assert_array_equal(getattr(got, name), getattr(expected, name))
    assert monitor.step(*samples[-1]).status == "fault"  # time does not increase
