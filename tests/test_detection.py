"""Tests of :mod:`sensorless.detection`.

Planted steps ("collisions") added to a residual must give events with the
planted start, end and joints; the streaming detector must give the events
of the batch detector, and skip faulty samples without changing anything
that follows.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from sensorless.detection import (
    DetectionResult,
    Detector,
    DetectorState,
    Verdict,
    events_to_pandas,
)
from sensorless.exceptions import DimensionError, InputValueError, NotFittedError
from sensorless.signals import Event, ObserverSignals
from sensorless.thresholds import (
    ConstantThreshold,
    Threshold,
    TimeVariantThreshold,
    VelocityThreshold,
)

DT = 1e-3
GAIN = np.array([20.0, 25.0])
N_DOF = 2
GAMMA = np.array([-0.05, 0.03])
EPS_FR = np.array([0.4, -0.6])
SERIES = ("model_torque", "friction", "sign", "velocity")


def lowpass(x: np.ndarray) -> np.ndarray:
    a = np.exp(-GAIN * DT)
    y = np.empty_like(x)
    y[0] = x[0]
    for k in range(x.shape[0] - 1):
        y[k + 1] = a * y[k] + (1.0 - a) * x[k]
    return y


def run(seed: int, n: int, bumps: list[tuple[int, int, int, float]] = ()) -> ObserverSignals:
    """Collision-free run plus planted steps (first sample, last sample, joint 1-based, size)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * DT
    freq = rng.uniform(0.5, 2.0, size=(3, N_DOF))
    phase = rng.uniform(0, 2 * np.pi, size=(3, N_DOF))
    wave = np.sin(2 * np.pi * freq * t[:, None, None] + phase)
    velocity = 0.6 * wave.sum(axis=1) / 3
    h = 20.0 * np.cos(2 * np.pi * freq[0] * t[:, None] + phase[1])
    friction = lowpass(0.5 * np.sign(velocity) + 0.3 * velocity)
    r = GAMMA * h + EPS_FR * friction + rng.uniform(-0.05, 0.05, size=(n, N_DOF))
    for first, last, joint, size in bumps:
        r[first : last + 1, joint - 1] += size
    return ObserverSignals(
        t=t,
        residual=r,
        model_torque=h,
        friction=friction,
        sign=lowpass(np.sign(velocity)),
        velocity=velocity,
        gain=GAIN,
        robot="synthetic",
    )


FIT = run(0, 3000)
# Velocity bins need several runs to be visited often enough for their L/U.
FIT_RUNS = [FIT, run(100, 3000), run(101, 3000)]
FAMILIES = {
    "constant": ConstantThreshold(margin=0.02).fit(FIT_RUNS),
    "time-variant": TimeVariantThreshold(margin=0.02).fit(FIT_RUNS),
    "velocity": VelocityThreshold(margin=0.03).fit(FIT_RUNS),
}


def stream(
    detector: Detector, signals: ObserverSignals, order: np.ndarray | None = None, dt: float = DT
) -> tuple[list[Verdict], list[Event], DetectorState]:
    """Feed samples (in ``order``, default all) through the streaming detector."""
    state = detector.initial_state(dt=dt)
    verdicts, events = [], []
    for k in range(signals.n_samples) if order is None else order:
        verdict, state = detector.step(
            state, signals.residual[k], *(getattr(signals, s)[k] for s in SERIES), signals.t[k]
        )
        verdicts.append(verdict)
        if verdict.event is not None:
            events.append(verdict.event)
    last, state = detector.finish(state)
    if last is not None:
        events.append(last)
    return verdicts, events, state


@pytest.mark.parametrize("method", list(FAMILIES))
def test_fit_data_raises_no_alarm(method: str) -> None:
    assert Detector(FAMILIES[method]).detect(FIT) == []


@pytest.mark.parametrize("method", list(FAMILIES))
def test_planted_step_is_detected_with_its_start_and_end(method: str) -> None:
    signals = run(1, 1500, [(400, 519, 2, 5.0), (900, 904, 1, -4.0)])
    events = Detector(FAMILIES[method]).detect(signals)
    assert [(e.start, e.end, e.joints) for e in events] == [
        (400 * DT, 519 * DT, (2,)),
        (900 * DT, 904 * DT, (1,)),
    ]
    _, upper = FAMILIES[method].bounds(signals)
    first = signals.residual[400:520, 1] - upper[400:520, 1]
    assert events[0].peak == pytest.approx(first.max())
    assert events[0].peak_residual == signals.residual[400 + np.argmax(first), 1]
    assert events[1].peak_residual < -3.0
    assert all(e.method == method for e in events)


def test_thresholds_give_bounds_and_the_detector_gives_events() -> None:
    signals = run(12, 600, [(100, 130, 1, 5.0), (140, 150, 2, 5.0)])
    for threshold in FAMILIES.values():
        assert not hasattr(threshold, "detect")  # events are the detector's business
        events = Detector(threshold, hold=0.02).detect(signals)
        assert [(e.start, e.end, e.joints) for e in events] == [(100 * DT, 150 * DT, (1, 2))]
    assert len(Detector(FAMILIES["constant"], hold=0.02).detect(signals)) == 1


def test_hold_merges_and_min_duration_drops() -> None:
    bumps = [(100, 109, 1, 5.0), (115, 120, 2, 5.0), (300, 300, 1, 5.0), (500, 560, 2, -5.0)]
    signals = run(2, 800, bumps)
    threshold = FAMILIES["constant"]
    plain = Detector(threshold).detect(signals)
    assert [(e.start, e.end) for e in plain] == [
        (100 * DT, 109 * DT),
        (115 * DT, 120 * DT),
        (300 * DT, 300 * DT),
        (500 * DT, 560 * DT),
    ]
    merged = Detector(threshold, hold=0.01).detect(signals)
    assert (merged[0].start, merged[0].end, merged[0].joints) == (100 * DT, 120 * DT, (1, 2))
    assert len(merged) == 3
    assert Detector(threshold, hold=0.006).detect(signals)[0].end == 109 * DT  # gap is 6 ms
    long = Detector(threshold, min_duration=0.02).detect(signals)
    assert [(e.start, e.end) for e in long] == [(500 * DT, 560 * DT)]
    assert Detector(threshold, hold=0.01, min_duration=0.015).detect(signals)[0].start == 100 * DT


def test_monitored_joints_of_detector() -> None:
    signals = run(3, 600, [(100, 150, 2, 5.0), (300, 320, 1, 5.0)])
    events = Detector(FAMILIES["constant"], joints=[1]).detect(signals)
    assert [(e.start, e.joints) for e in events] == [(300 * DT, (1,))]
    result = Detector(FAMILIES["constant"], joints=[1]).run(signals)
    assert not result.outside[:, 1].any() and result.joints == (1,)


@pytest.mark.parametrize("method", list(FAMILIES))
@pytest.mark.parametrize(("hold", "min_duration"), [(0.0, 0.0), (0.012, 0.004)])
def test_streaming_gives_the_batch_events(method: str, hold: float, min_duration: float) -> None:
    bumps = [(100, 109, 1, 5.0), (115, 120, 2, 5.0), (200, 202, 1, -5.0), (380, 399, 2, 4.0)]
    signals = run(4, 400, bumps)
    detector = Detector(FAMILIES[method], hold=hold, min_duration=min_duration)
    batch = detector.run(signals)
    verdicts, events, _ = stream(detector, signals, dt=batch.dt)
    assert events == batch.events and len(events) >= 2
    for k, verdict in enumerate(verdicts):
        np.testing.assert_allclose(verdict.lower, batch.lower[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(verdict.upper, batch.upper[k], rtol=0, atol=1e-12)
        outside = tuple(int(j) + 1 for j in np.flatnonzero(batch.outside[k]))
        assert verdict.joints == outside
        assert verdict.status in ("ok", "collision")


def test_collision_status_waits_for_min_duration() -> None:
    signals = run(5, 200, [(50, 59, 1, 5.0)])
    # 9 sample periods: a round number of periods in floating point is not exact
    verdicts, events, _ = stream(Detector(FAMILIES["constant"], min_duration=0.0045), signals)
    status = [v.status for v in verdicts]
    assert status[50:55] == ["ok"] * 5 and status[55:60] == ["collision"] * 5
    assert verdicts[50].joints == (1,)
    assert status[60] == "ok" and verdicts[60].event == events[0]
    assert (events[0].start, events[0].end) == (50 * DT, 59 * DT)


def test_finish_closes_an_open_event() -> None:
    signals = run(6, 100, [(90, 99, 2, 5.0)])
    verdicts, events, state = stream(Detector(FAMILIES["constant"]), signals)
    assert all(v.event is None for v in verdicts)
    assert [(e.start, e.end) for e in events] == [(90 * DT, 99 * DT)]
    assert state.open_event is None


@pytest.mark.parametrize("method", ["constant", "velocity"])
def test_nonfinite_sample_is_a_fault_and_is_skipped(method: str) -> None:
    signals = run(7, 300, [(120, 140, 1, 5.0)])
    bad = 60
    residual = signals.residual.copy()
    residual[bad, 1] = np.nan
    velocity = signals.velocity.copy()
    velocity[bad + 100, 0] = np.inf
    faulty = ObserverSignals(
        t=signals.t,
        residual=residual,
        model_torque=signals.model_torque,
        friction=signals.friction,
        sign=signals.sign,
        velocity=velocity,
        gain=GAIN,
        robot="synthetic",
    )
    detector = Detector(FAMILIES[method])
    dt = detector.run(faulty, skip_nonfinite=True).dt
    verdicts, events, _ = stream(detector, faulty, dt=dt)
    keep = np.setdiff1d(np.arange(300), [bad, bad + 100])
    clean_verdicts, clean_events, _ = stream(detector, signals, order=keep, dt=dt)
    assert verdicts[bad].status == "fault" and "residual is nan at joint 2" in verdicts[bad].message
    assert (
        verdicts[bad + 100].status == "fault" and "velocity is inf" in verdicts[bad + 100].message
    )
    assert np.isnan(verdicts[bad].lower).all() and verdicts[bad].event is None
    others = [v for k, v in enumerate(verdicts) if k not in (bad, bad + 100)]
    for mine, clean in zip(others, clean_verdicts, strict=True):
        assert (mine.status, mine.t, mine.joints, mine.event) == (
            clean.status,
            clean.t,
            clean.joints,
            clean.event,
        )
        np.testing.assert_array_equal(mine.lower, clean.lower)
    assert events == clean_events
    # the batch detector skips the same samples on request, and refuses them otherwise
    with pytest.raises(InputValueError, match="residual is nan at sample 60, joint 2"):
        detector.detect(faulty)
    result = detector.run(faulty, skip_nonfinite=True)
    assert result.events == events and not result.valid[[bad, bad + 100]].any()
    assert np.isnan(result.lower[bad]).all()


def test_fault_leaves_state_unchanged_and_time_must_increase() -> None:
    detector = Detector(FAMILIES["velocity"])
    signals = run(8, 20)
    state = detector.initial_state(dt=DT)
    rows = [getattr(signals, s)[0] for s in SERIES]
    verdict, state = detector.step(state, signals.residual[0], *rows, 0.0)
    assert verdict.status == "ok"
    for t in (0.0, -1.0, np.nan, "noon"):
        again, same = detector.step(state, signals.residual[1], *rows, t)
        assert again.status == "fault" and same is state
    assert "does not increase" in detector.step(state, signals.residual[1], *rows, 0.0)[0].message
    nan_rows = [np.full(N_DOF, np.nan)] * 4
    verdict, same = detector.step(state, signals.residual[1], *nan_rows, 0.001)
    assert verdict.status == "fault" and same is state


def test_first_samples_faulty_start_the_filters_later() -> None:
    signals = run(9, 200, [(150, 160, 2, 5.0)])
    residual = signals.residual.copy()
    residual[:3] = np.nan
    faulty = ObserverSignals(
        t=signals.t,
        residual=residual,
        model_torque=signals.model_torque,
        friction=signals.friction,
        sign=signals.sign,
        velocity=signals.velocity,
        gain=GAIN,
        robot="synthetic",
    )
    detector = Detector(FAMILIES["velocity"])
    result = detector.run(faulty, skip_nonfinite=True)
    verdicts, events, _ = stream(detector, faulty, dt=result.dt)
    assert [v.status for v in verdicts[:3]] == ["fault"] * 3
    assert events == result.events
    assert [(e.start, e.end) for e in events] == [(150 * DT, 160 * DT)]


def test_batch_rejects_time_that_does_not_increase() -> None:
    signals = run(10, 50)
    t = signals.t.copy()
    t[20] = t[19]
    repeated = ObserverSignals(
        t=t,
        residual=signals.residual,
        model_torque=signals.model_torque,
        friction=signals.friction,
        sign=signals.sign,
        velocity=signals.velocity,
        gain=GAIN,
        robot="synthetic",
    )
    detector = Detector(FAMILIES["constant"])
    with pytest.raises(InputValueError, match=r"strictly increasing; t\[20\]"):
        detector.detect(repeated)
    result = detector.run(repeated, skip_nonfinite=True)
    assert result.valid.sum() == 49 and not result.valid[20]


def test_result_tables() -> None:
    signals = run(11, 300, [(100, 120, 1, 5.0)])
    result = Detector(FAMILIES["time-variant"]).run(signals)
    assert isinstance(result, DetectionResult)
    table = result.to_pandas()
    assert list(table.columns[:4]) == ["t", "valid", "residual_1", "residual_2"]
    assert table["outside_1"].sum() == 21 and table.shape == (300, 2 + 4 * N_DOF)
    events = result.events_to_pandas()
    assert list(events.columns) == [
        "start",
        "end",
        "duration",
        "joints",
        "peak",
        "peak_residual",
        "method",
        "level",
    ]
    assert events.loc[0, "duration"] == pytest.approx(0.02)
    assert events.loc[0, "method"] == "time-variant"
    assert events.loc[0, "level"] == ""  # a one-level detector
    empty = events_to_pandas([])
    assert isinstance(empty, pd.DataFrame) and empty.empty and "peak" in empty.columns


def test_detector_errors() -> None:
    with pytest.raises(TypeError, match="threshold must be a Threshold"):
        Detector("constant")  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="hold must be a finite number of seconds >= 0"):
        Detector(FAMILIES["constant"], hold=-0.1)
    with pytest.raises(InputValueError, match="min_duration must be"):
        Detector(FAMILIES["constant"], min_duration=np.nan)
    with pytest.raises(InputValueError, match="joints must be distinct joint numbers"):
        Detector(FAMILIES["constant"], joints=[3]).detect(FIT)
    unfitted: Threshold = ConstantThreshold()
    with pytest.raises(NotFittedError, match="call fit"):
        Detector(unfitted).initial_state()
    with pytest.raises(NotFittedError, match="call fit"):
        Detector(unfitted).detect(FIT)
    detector = Detector(FAMILIES["constant"])
    state = detector.initial_state()
    assert state.dt == pytest.approx(DT)
    with pytest.raises(InputValueError, match="dt must be a positive"):
        detector.initial_state(dt=-1.0)
    with pytest.raises(DimensionError, match="step takes one sample"):
        detector.step(state, np.zeros((2, N_DOF)), *np.zeros((4, N_DOF)), 0.0)
    with pytest.raises(DimensionError, match=r"shape \(2,\)"):
        detector.step(state, np.zeros(3), *np.zeros((4, N_DOF)), 0.0)
    with pytest.raises(TypeError, match="DetectorState"):
        detector.step(None, np.zeros(N_DOF), *np.zeros((4, N_DOF)), 0.0)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="DetectorState"):
        detector.finish(None)  # type: ignore[arg-type]
    other = ObserverSignals(
        t=FIT.t,
        residual=FIT.residual,
        model_torque=FIT.model_torque,
        friction=FIT.friction,
        sign=FIT.sign,
        velocity=FIT.velocity,
        gain=GAIN,
        robot="synthetic",
        kind="joint",
    )
    with pytest.raises(InputValueError, match="'joint'"):
        detector.detect(other)
