"""The pipeline: tune → save/load → detect, batch and streaming, with faults."""

from __future__ import annotations

import math

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import DimensionError, InputValueError, UnknownNameError
from sensorless.monitor import (
    CollisionMonitor,
    ObserverSettings,
    StreamPolicy,
    load_tuned,
    save_tuned,
    tune,
)
from sensorless.simulation.scenario import load_scenario

FAMILIES = ("constant", "time-variant", "hysteretic", "velocity", "model")


@pytest.fixture(scope="module")
def runs():
    scenario = load_scenario("panda-gaz").with_duration(6.0)
    free = [scenario.run(seed=s, collisions=False).log for s in (1, 2)]
    test = scenario.run(seed=3).log
    return free, test, scenario.robots()[1]


@pytest.fixture(scope="module")
def tuned(runs):
    free, _, nominal = runs
    return {method: tune(free, nominal, method, margin=0.05, folds=None) for method in FAMILIES}


def _stream(monitor: CollisionMonitor, log: sl.Log, n: int | None = None):
    verdicts, events = [], []
    for k in range(log.n_samples if n is None else n):
        verdict = monitor.step(log.t[k], log.q[k], log.tau_m[k])
        verdicts.append(verdict)
        if verdict.event is not None:
            events.append(verdict.event)
    last = monitor.finish()
    if last is not None:
        events.append(last)
    return verdicts, events


def _key(events):
    return [(e.start, e.end, e.joints) for e in events]


@pytest.mark.parametrize("method", FAMILIES)
def test_streaming_equals_batch_and_files_round_trip(runs, tuned, method, tmp_path) -> None:
    _, test, nominal = runs
    threshold, settings = tuned[method]
    path = save_tuned(tmp_path / "th.yaml", threshold, settings)
    loaded, loaded_settings = load_tuned(path)
    assert loaded_settings == settings
    monitor = CollisionMonitor(nominal, loaded, loaded_settings)
    signals, batch_events = monitor.run(test)
    assert batch_events, "the test run has contacts: something must be detected"
    verdicts, stream_events = _stream(monitor, test)
    assert _key(stream_events) == _key(batch_events)
    for a, b in zip(stream_events, batch_events, strict=True):
        assert a.peak == pytest.approx(b.peak, rel=1e-9, abs=1e-9)
    residual = np.array([v.residual for v in verdicts])
    np.testing.assert_allclose(residual, signals.residual, rtol=1e-9, atol=1e-9)
    # The start is judged by nothing: settling for 5/K_I (K_I = 20 → 0.25 s), then judged.
    settle = settings.settle_time(monitor.dt)
    statuses = [v.status for v in verdicts]
    n_settle = int(np.searchsorted(test.t - test.t[0], settle))
    assert set(statuses[:n_settle]) == {"settling"}
    assert "settling" not in statuses[n_settle:] and "fault" not in statuses


def test_tune_leaves_out_the_start_and_says_so(runs) -> None:
    free, _, nominal = runs
    threshold, settings = tune(free, nominal, "constant", folds=None)
    assert threshold.transient == pytest.approx(settings.settle_time(free[0].dt)) == 0.25
    explicit, _ = tune(free, nominal, "constant", transient=0.0, folds=None)
    assert explicit.transient == 0.0


def test_stream_chunked_equals_whole(runs, tuned) -> None:
    _, test, nominal = runs
    threshold, settings = tuned["time-variant"]
    whole = CollisionMonitor(nominal, threshold, settings).run(test)[1]
    # Two logs cut at 3 s, run as one stream: same events as the whole log.
    monitor = CollisionMonitor(nominal, threshold, settings)
    events = []
    for part in (test.slice(stop=3.0), test.slice(start=3.0)):
        for k in range(part.n_samples):
            verdict = monitor.step(part.t[k], part.q[k], part.tau_m[k])
            if verdict.event is not None:
                events.append(verdict.event)
    last = monitor.finish()
    events += [last] if last is not None else []
    assert _key(events) == _key(whole)


# ------------------------------------------------------------------ faults, exact sequences
@pytest.fixture
def constant_monitor(runs, tuned):
    def make(**policy):
        threshold, settings = tuned["constant"]
        return CollisionMonitor(runs[2], threshold, settings, policy=StreamPolicy(**policy))

    return make


def _feed(monitor, log, times, replace=None):
    """Feed samples k at the given times; ``replace`` maps k to (q, tau) substitutes."""
    replace = replace or {}
    out = []
    for k, t in times:
        q, tau = replace.get(k, (log.q[k], log.tau_m[k]))
        out.append(monitor.step(t, q, tau))
    return out


def test_bad_samples_give_faults_and_lose_nothing(runs, constant_monitor) -> None:
    _, test, _ = runs
    clean, faulty = constant_monitor(), constant_monitor()
    bad_inputs = [
        (test.t[400], np.full(7, np.nan), test.tau_m[400]),
        (test.t[400], test.q[400][:6], test.tau_m[400]),
        (test.t[400], test.q[400], "torque"),
        (float("nan"), test.q[400], test.tau_m[400]),
        (test.t[400], test.q[400] + 1e308, test.tau_m[400]),
        (test.t[400], test.q[400] + 1e200, test.tau_m[400]),
        (test.t[400], test.q[400], test.tau_m[400] + 1e308),
        (test.t[399] + 1000.0, test.q[400], test.tau_m[400]),
        (test.t[399] + 1e-12, test.q[400], test.tau_m[400]),
        (test.t[399], test.q[400], test.tau_m[400]),  # repeated time stamp
        (test.t[100], test.q[100], test.tau_m[100]),  # back in time
        (test.t[400], np.rad2deg(test.q[400]), test.tau_m[400]),  # degrees
    ]
    for k in range(600):
        expected = clean.step(test.t[k], test.q[k], test.tau_m[k])
        if k == 400:
            for t, q, tau in bad_inputs:
                verdict = faulty.step(t, q, tau)
                assert verdict.status == "fault" and verdict.message, (t, verdict)
        got = faulty.step(test.t[k], test.q[k], test.tau_m[k])
        assert got.status == expected.status
        np.testing.assert_array_equal(got.residual, expected.residual)


def test_a_gap_faults_then_restarts_with_settling(runs, constant_monitor) -> None:
    _, test, _ = runs
    monitor = constant_monitor(settle=0.0035)
    # Samples 0..9 regular, then the stream resumes at sample 510 (0.5 s later).
    times = [(k, test.t[k]) for k in range(10)] + [(k, test.t[k]) for k in range(510, 520)]
    verdicts = _feed(monitor, test, times)
    settle = ["settling"] * 4
    assert [v.status for v in verdicts] == [*settle, *["ok"] * 6, "fault", *settle, *["ok"] * 5]
    assert "gap: 0.501 s" in verdicts[10].message
    # After the restart the stream is a fresh stream started at sample 511.
    fresh = _feed(constant_monitor(settle=0.0035), test, [(k, test.t[k]) for k in range(511, 520)])
    for a, b in zip(verdicts[11:], fresh, strict=True):
        assert a.status == b.status
        np.testing.assert_array_equal(a.residual, b.residual)


def test_time_in_ms_and_every_second_sample_are_faults(runs, constant_monitor) -> None:
    _, test, _ = runs
    in_ms = constant_monitor()
    statuses = [v.status for v in _feed(in_ms, test, [(k, 1e3 * test.t[k]) for k in range(50)])]
    assert statuses == ["settling"] + ["fault"] * 49
    assert "gap" in in_ms.step(1e3 * test.t[50], test.q[50], test.tau_m[50]).message
    halved = constant_monitor()
    statuses = [v.status for v in _feed(halved, test, [(k, test.t[k]) for k in range(0, 100, 2)])]
    assert statuses == ["settling"] + ["fault"] * 49


def test_a_log_at_another_rate_is_refused(runs, tuned) -> None:
    _, test, nominal = runs
    threshold, settings = tuned["constant"]
    monitor = CollisionMonitor(nominal, threshold, settings)
    every_second = sl.Log.from_pandas(test.to_pandas().iloc[::2], metadata=test.metadata)
    with pytest.raises(InputValueError, match=r"tuned at 0\.001 s"):
        monitor.run(every_second)
    with pytest.raises(InputValueError, match=r"tuned at dt = 0\.001 s"):
        CollisionMonitor(nominal, threshold, settings, dt=0.002)


def test_limits_are_faults(runs, constant_monitor) -> None:
    _, test, _ = runs
    monitor = constant_monitor(settle=0.0)
    q_far = test.q[3].copy()
    q_far[1] = 3.0  # joint 2 of the Panda stops at 1.7628 rad (+0.1 margin)
    tau_big = test.tau_m[3].copy()
    tau_big[4] = 25.0  # joint 5 is rated 12 N m (×2)
    jump = test.q[3] + 0.01  # 10 rad/s in one millisecond
    verdicts = _feed(
        monitor,
        test,
        [(0, test.t[0]), (1, test.t[1]), (3, test.t[2]), (4, test.t[2]), (5, test.t[2])],
        {3: (q_far, test.tau_m[3]), 4: (test.q[3], tau_big), 5: (jump, test.tau_m[3])},
    )
    assert [v.status for v in verdicts] == ["ok", "ok", "fault", "fault", "fault"]
    assert "q of joint 2 is 3 rad" in verdicts[2].message
    assert "tau_m of joint 5 is 25 N m" in verdicts[3].message
    assert "qd of joint" in verdicts[4].message


def test_a_collision_latches_until_reset_or_release(runs, tuned) -> None:
    _, test, nominal = runs
    threshold, settings = tuned["constant"]
    events = CollisionMonitor(nominal, threshold, settings).run(test)[1]
    first = events[0]
    stop = int(np.searchsorted(test.t, first.end + 0.2))
    latched = CollisionMonitor(nominal, threshold, settings)
    statuses = [v.status for v in _stream(latched, test, stop)[0]]
    onset = statuses.index("collision")
    assert set(statuses[onset:]) == {"collision"} and latched.latched
    latched.reset()
    assert not latched.latched
    assert latched.step(test.t[stop], test.q[stop], test.tau_m[stop]).status == "settling"
    released = CollisionMonitor(nominal, threshold, settings, policy=StreamPolicy(release=0.1))
    statuses = [v.status for v in _stream(released, test, stop)[0]]
    t_ok = test.t[len(statuses) - 1 - statuses[::-1].index("collision") + 1]
    # Released exactly 0.1 s after the last sample outside the bounds.
    assert t_ok == pytest.approx(first.end + 0.1 + test.dt, abs=1.5 * test.dt)


def test_a_log_with_a_bad_stretch_is_processed_around_it(runs, tuned) -> None:
    _, test, nominal = runs
    threshold, settings = tuned["time-variant"]
    monitor = CollisionMonitor(nominal, threshold, settings)
    clean = monitor.process(test)
    frame = test.to_pandas()
    bad = (frame["t"] >= 4.5) & (frame["t"] < 5.0)
    frame.loc[bad, "tau_m_3"] = 1e7
    broken = sl.Log.from_pandas(frame, metadata=test.metadata)
    result = monitor.process(broken)
    assert len(result.faults) == 1
    span = result.faults[0]
    assert (span.start, span.end, span.n_samples) == (4.5, pytest.approx(4.999), 500)
    assert "tau_m of joint 3" in span.reason
    assert np.isnan(result.signals.residual[bad.to_numpy()]).all()
    # Outside the bad span and the settling after it, the events are those of the clean log
    # (an event still open at 4.5 s ends there).
    resume = 5.0 + monitor.settle
    before = [(e.start, e.joints) for e in clean.events if e.start < 4.5]
    assert [(e.start, e.joints) for e in result.events if e.start < 4.5] == before
    after = [e for e in clean.events if e.start >= resume]
    assert _key([e for e in result.events if e.start >= resume]) == _key(after)
    with pytest.raises(InputValueError, match=r"sample 4500 .* is a fault: tau_m of joint 3"):
        monitor.process(broken, strict=True)
    # The stream gives the same events on the same samples.
    _, stream_events = _stream(CollisionMonitor(nominal, threshold, settings), broken)
    assert _key(stream_events) == _key(result.events)


def test_a_log_with_nan_in_the_middle_is_processed_around_it(runs, tuned, tmp_path) -> None:
    _, test, nominal = runs
    threshold, settings = tuned["time-variant"]
    # Settling 10/K_I. With the default 5/K_I the residual after 3.25 s is the clean log's
    # within 0.0025 N m, yet one 11 ms event (0.013 N m beyond the band, joint 5) starts at
    # 3.251 s: the time-variant threshold's own filters start when the settling ends.
    monitor = CollisionMonitor(nominal, threshold, settings, policy=StreamPolicy(settle=0.5))
    frame = test.to_pandas()
    lost = (frame["t"] >= 2.0) & (frame["t"] < 3.0)  # one second of NaN, as a logger writes it
    frame.loc[lost, [c for c in frame.columns if c.startswith(("q_", "tau_m_"))]] = np.nan
    with pytest.raises(sl.exceptions.LogFormatError, match="must be finite"):
        sl.Log.from_pandas(frame, metadata=test.metadata)
    sl.io.write_log(sl.Log.from_pandas(frame, allow_missing=True), tmp_path / "lost.parquet")
    broken = sl.read_log(tmp_path / "lost.parquet", allow_missing=True)
    result = monitor.process(broken)
    assert [(f.start, f.end, f.n_samples) for f in result.faults] == [(2.0, 2.999, 1000)]
    assert "non-finite" in result.faults[0].reason
    clean = monitor.process(test).events
    resume = 3.0 + monitor.settle
    before = [(e.start, e.joints) for e in clean if e.start < 2.0]
    assert [(e.start, e.joints) for e in result.events if e.start < 2.0] == before
    after = [e for e in clean if e.start >= resume]
    assert _key([e for e in result.events if e.start >= resume]) == _key(after)


@pytest.mark.parametrize("backend", ["python", "auto"])
def test_a_log_cut_in_mid_motion_starts_clean(runs, tuned, backend) -> None:
    free, _, nominal = runs
    whole = free[1]
    threshold, settings = tuned["time-variant"]
    monitor = CollisionMonitor(nominal, threshold, settings, backend=backend)
    fastest = int(np.argmax(np.abs(whole.qd_true[500:-1000]).max(axis=1))) + 500
    cut = whole.slice(start=whole.t[fastest])
    assert np.abs(cut.qd_true[0]).max() > 1.0  # [rad/s]: the arm is moving fast
    full = monitor.process(whole).signals.residual
    part = monitor.process(cut).signals.residual
    settle = round(monitor.settle / whole.dt)
    # After 5/K_I the residual is the whole log's (measured: <= 0.0044 N m apart) ...
    np.testing.assert_allclose(part[settle:], full[-cut.n_samples :][settle:], atol=0.01)
    # ... and before it, no start-up excursion leaves the steady band of the whole log.
    assert (np.abs(part[:settle]).max(axis=0) <= np.abs(full[settle:]).max(axis=0)).all()
    verdicts, _ = _stream(monitor, cut)
    np.testing.assert_allclose([v.residual for v in verdicts], part, rtol=1e-9, atol=1e-9)


def test_pipeline_errors_are_clear(runs, tuned) -> None:
    free, _, nominal = runs
    with pytest.raises(UnknownNameError, match="unknown threshold method 'magic'"):
        tune(free, nominal, "magic")
    with pytest.raises(InputValueError, match="at least one collision-free log"):
        tune([], nominal, "constant")
    with pytest.raises(InputValueError, match="watches the 'acceleration' residual"):
        tune(free, nominal, "model", ObserverSettings(kind="motor"))
    threshold, settings = tuned["constant"]
    with pytest.raises(DimensionError, match="threshold is for 7 joints"):
        CollisionMonitor(sl.robots.load("puma560"), threshold, settings)
    with pytest.raises(InputValueError, match="observer kind must be"):
        ObserverSettings(kind="magic")
    with pytest.raises(TypeError, match="unknown observer settings"):
        ObserverSettings.from_dict({"kind": "motor", "colour": "red"})
    with pytest.raises(sl.exceptions.NotFittedError):
        CollisionMonitor(nominal, sl.thresholds.ConstantThreshold(), settings)
    with pytest.raises(InputValueError, match="early < 1 < gap"):
        StreamPolicy(gap=0.9)
    assert math.isclose(StreamPolicy().gap, 1.5)
