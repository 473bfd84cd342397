"""The compiled step in the user's own numba loop: the stream of ``CollisionMonitor.step``."""

from __future__ import annotations

import gc
import sys

import numpy as np
import pytest

from sensorless.exceptions import InputValueError
from sensorless.monitor import CollisionMonitor, CompiledStep, tune
from sensorless.robots.recursion import numba_available
from sensorless.simulation.scenario import load_scenario

pytestmark = pytest.mark.skipif(not numba_available(), reason="numba is not installed")

EVENT, EVENT_AT = CompiledStep.EVENT, CompiledStep.EVENT_AT


def _user_loop():
    """What a user writes: an njit loop that calls the step on each sample of its arrays."""
    from numba import njit

    @njit
    def loop(function, model, buffers, t, q, tau, codes, rows, events):
        out = np.empty((3, q.shape[1]))
        for k in range(t.shape[0]):
            code = function(t[k], q[k], tau[k], tau[k], model, buffers, out)
            codes[k] = code
            rows[k] = out
            if code & EVENT:
                events[k] = buffers[EVENT_AT : EVENT_AT + 5]

    return loop


@pytest.fixture(scope="module")
def panda():
    """A collision log with a NaN stretch and a torque breach; the Panda; velocity bins."""
    scenario = load_scenario("panda-gaz").with_duration(4.0)
    free = [scenario.run(seed=s, collisions=False).log for s in (1, 2)]
    log = scenario.run(seed=3).log
    q, tau = log.q.copy(), log.tau_m.copy()
    q[1500:1520, 2] = np.nan
    tau[1800, 1] = 1e6
    robot = scenario.robots()[1]
    tuned = tune(free, robot, "velocity", margin=0.05, folds=None)
    return (np.ascontiguousarray(log.t), q, tau), robot, tuned


def test_a_compiled_loop_is_the_stream(panda) -> None:
    (t, q, tau), robot, tuned = panda
    looped = CollisionMonitor(robot, *tuned, backend="numba")
    stepped = CollisionMonitor(robot, *tuned, backend="numba")
    half = t.shape[0] // 2
    n_samples, n = q.shape
    codes = np.zeros(half, dtype=np.int64)
    rows = np.full((half, 3, n), np.nan)
    events = np.full((half, 5), np.nan)
    kernel = looped.compiled_step()
    _user_loop()(*kernel, t[:half], q[:half], tau[:half], codes, rows, events)

    seen = set()
    for k in range(half):
        verdict = stepped.step(t[k], q[k], tau[k])
        status = CompiledStep.reason(int(codes[k]))
        judged = verdict.status != "fault"
        assert (status if judged else "fault") == verdict.status, k
        seen.add(status)
        if not judged:
            continue
        joints = tuple(j + 1 for j in range(n) if codes[k] >> CompiledStep.JOINTS_SHIFT >> j & 1)
        assert joints == verdict.joints
        expected = np.stack([verdict.residual, verdict.lower, verdict.upper])
        np.testing.assert_array_equal(rows[k], expected, err_msg=str(k))
        event = verdict.event
        assert bool(codes[k] & EVENT) == (event is not None)
        if event is not None:
            start, end, mask, peak, residual = events[k]
            assert (start, end, peak, residual) == (
                event.start,
                event.end,
                event.peak,
                event.peak_residual,
            )
            assert tuple(j + 1 for j in range(n) if int(mask) >> j & 1) == event.joints
    # The loop met every case the stream has: its faults name what they refused.
    assert {"settling", "ok", "collision", "q", "tau_m"} <= seen
    assert np.count_nonzero(codes & EVENT) >= 1
    assert looped.latched == stepped.latched

    # The monitor's own step goes on from where the loop stopped.
    for k in range(half, n_samples):
        got, expected = looped.step(t[k], q[k], tau[k]), stepped.step(t[k], q[k], tau[k])
        assert (got.status, got.joints, got.event) == (
            expected.status,
            expected.joints,
            expected.event,
        )
        np.testing.assert_array_equal(got.residual, expected.residual)
    assert looped.finish() == stepped.finish()


def test_a_sample_of_the_wrong_length_is_unjudged(panda) -> None:
    (t, q, tau), robot, tuned = panda
    monitor = CollisionMonitor(robot, *tuned, backend="numba")
    function, model, buffers = monitor.compiled_step()
    out = np.zeros((3, q.shape[1]))
    assert function(t[0], q[0], tau[0], tau[0], model, buffers, out) == CompiledStep.SETTLING
    before = buffers.copy()
    for sample in ((q[1, :-1], tau[1]), (q[1], tau[1, :-1])):
        code = function(t[1], sample[0], sample[1], sample[1], model, buffers, out)
        assert CompiledStep.reason(code) == "unjudged"
    assert function(np.nan, q[1], tau[1], tau[1], model, buffers, out) == CompiledStep.UNJUDGED
    np.testing.assert_array_equal(buffers, before)
    with pytest.raises(TypeError):  # numba's dispatcher: float32 is not a signature
        function(t[1], q[1].astype(np.float32), tau[1], tau[1], model, buffers, out)


@pytest.mark.parametrize("backend", ["numpy", "python"])
def test_only_the_numba_backend_has_a_compiled_step(panda, backend) -> None:
    _, robot, tuned = panda
    monitor = CollisionMonitor(robot, *tuned, backend=backend)
    with pytest.raises(InputValueError, match=f"needs the 'numba' backend.*'{backend}'"):
        monitor.compiled_step()


def test_the_kernels_keep_no_reference_to_their_arrays(panda) -> None:
    """The stream step, a user's loop and the batch leave every array's reference count as it
    was: none kept (a leak), none released (an early free); the kernels' views
    (``robots._numba_views.view``) count their owner as numpy's reshape does."""
    # Own copies, and no collection between the counts: a cycle of another test that the
    # collector frees would change the count of a shared array.
    t, q, tau = (array.copy() for array in panda[0])
    monitor = CollisionMonitor(panda[1], *panda[2], backend="numba")
    function, model, buffers = monitor.compiled_step()
    fused = monitor._fused
    loop = _user_loop()
    arrays = (t, q, tau, model, buffers)
    gc.collect()
    gc.disable()
    try:
        before = [sys.getrefcount(array) for array in arrays]
        for k in range(300):
            monitor.step(t[k], q[k], tau[k])
        codes = np.zeros(300, dtype=np.int64)
        rows, events = np.zeros((300, 3, q.shape[1])), np.zeros((300, 5))
        loop(function, model, buffers, t[:300], q[:300], tau[:300], codes, rows, events)
        for chunk in (0, 128):
            fused.block(t, (q, np.empty((t.size, 0)), tau, tau), "batch", chunk)
        after = [sys.getrefcount(array) for array in arrays]
    finally:
        gc.enable()
    assert after == before
