"""The monitor with drift adaptation: the stream rules hold, and batch equals stream."""

from __future__ import annotations

import numpy as np
import pytest

from sensorless.exceptions import InputTypeError, InputValueError
from sensorless.monitor import Adaptation, CollisionMonitor, ObserverSettings, tune
from sensorless.simulation.scenario import load_scenario


@pytest.fixture(scope="module")
def panda():
    """A collision-free tuning run, a test log with contacts, the robot and a constant threshold."""
    scenario = load_scenario("panda-gaz").with_duration(6.0)
    free = scenario.run(seed=1, collisions=False).log
    test = scenario.run(seed=3).log
    nominal = scenario.robots()[1]
    return free, test, nominal, tune([free], nominal, "constant", margin=0.05, folds=None)


def _drifted(log, rate, joint=2):
    """``log`` with a torque offset growing at ``rate`` [N m/s] on ``joint`` (1-based)."""
    frame = log.to_pandas()
    frame[f"tau_m_{joint}"] += rate * (log.t - log.t[0])
    return type(log).from_pandas(frame)


def test_batch_equals_stream_and_a_fault_changes_nothing(panda) -> None:
    _, test, nominal, (threshold, settings) = panda
    log = _drifted(test, 0.2)
    adaptation = Adaptation(rate_limit=0.5, max_correction=10.0, guard=0.5)
    # The Python path, whose state this test reads (the compiled one: test_monitor_compiled).
    monitor = CollisionMonitor(
        nominal, threshold, settings, adaptation=adaptation, backend="python"
    )
    batch = monitor.process(log)
    clean = CollisionMonitor(nominal, threshold, settings, adaptation=adaptation, backend="python")
    residual, events = np.full(log.q.shape, np.nan), []
    k_bad = int(np.searchsorted(log.t, 2.0))
    for k in range(log.n_samples):
        if k == k_bad:  # faults between good samples: refused, nothing learned from them
            before = monitor._stream.adapter
            for q_bad in (np.full(7, np.nan), log.q[k] * 1e6, log.q[k][:3]):
                assert monitor.step(log.t[k], q_bad, log.tau_m[k]).status == "fault"
            assert monitor._stream.adapter is before
        verdict = monitor.step(log.t[k], log.q[k], log.tau_m[k])
        reference = clean.step(log.t[k], log.q[k], log.tau_m[k])
        assert verdict.status == reference.status
        np.testing.assert_array_equal(verdict.residual, reference.residual)
        residual[k] = verdict.residual
        events += [verdict.event] if verdict.event is not None else []
    last = monitor.finish()
    events += [last] if last is not None else []
    np.testing.assert_array_equal(residual, batch.signals.residual)
    assert [(e.start, e.end, e.joints) for e in events] == [
        (e.start, e.end, e.joints) for e in batch.events
    ]
    # Learning happened on joint 2, and only while nothing was outside the bounds.
    assert monitor._stream.adapter.updates[1] > 0


def test_adaptation_settings_are_checked(panda) -> None:
    _, _, nominal, (threshold, settings) = panda
    with pytest.raises(InputTypeError, match="adaptation must be an Adaptation"):
        CollisionMonitor(nominal, threshold, settings, adaptation={"rate_limit": 1.0})
    with pytest.raises(InputValueError, match="guard"):
        Adaptation(guard=-1.0)
    accel = ObserverSettings(kind="acceleration")
    with pytest.raises(InputValueError, match="acceleration observer"):
        CollisionMonitor(nominal, threshold, accel, adaptation=Adaptation())
