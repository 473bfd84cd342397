"""The learned family's compiled step: equal to the numpy step and to the batch, fail-safe."""

from __future__ import annotations

import numpy as np
import pytest

from sensorless.detection import Detector
from sensorless.exceptions import DimensionError, InputValueError
from sensorless.learning.training import random_network
from sensorless.signals import ObserverSignals
from sensorless.thresholds import LearnedThreshold, LearnedWeights, _cnn, _cnn_kernel, save_weights

N_DOF = 3
needs_numba = pytest.mark.skipif(not _cnn_kernel.available, reason="numba not installed")


def _network(channels: int, seed: int = 0) -> _cnn.Network:
    rng = np.random.default_rng(seed)
    norm = {
        "input_mean": rng.normal(size=(4, N_DOF)),
        "input_scale": rng.uniform(0.5, 2.0, (4, N_DOF)),
        "output_mean": rng.normal(size=N_DOF),
        "output_scale": rng.uniform(0.5, 2.0, N_DOF),
    }
    net = random_network(rng, norm, channels=channels)
    # large weights: many units saturate, where tanh's approximation is least exact
    return net.with_parameters([p + 0.8 * rng.normal(size=p.shape) for p in net.parameters()])


def _run(seed: int, n: int = 300) -> ObserverSignals:
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 1e-3
    h = 3.0 * np.sin(np.outer(t, [3.0, 5.0, 7.0]) + seed)
    f = np.cos(np.outer(t, [2.0, 4.0, 1.0]))
    r = 0.1 * h + 0.05 * rng.normal(size=h.shape)
    return ObserverSignals(t, r, h, f, np.tanh(f), 0.5 * f, gain=20.0, robot="demo")


@pytest.fixture
def threshold(tmp_path):
    weights = LearnedWeights(_network(8), robot="demo", kind="motor", gain=20.0, dt=1e-3)
    path = save_weights(weights, tmp_path / "demo")
    return LearnedThreshold(path, margin=[0.0, 0.05, 0.1], joints=[1, 3]).fit(_run(0))


def test_tanh_is_numpys_to_rounding():
    x = np.concatenate(
        [
            np.linspace(-30.0, 30.0, 6001),
            [0.0, -0.0, 5e-324, 1e-300, -1e-12, 1e-8, 19.99, 20.0, 20.01, 1e300, -1e300],
        ]
    )
    mine = np.array([_cnn_kernel._tanh(float(v)) for v in x])
    reference = np.tanh(x)
    np.testing.assert_allclose(mine, reference, rtol=5e-15, atol=1e-300)
    assert np.signbit(mine[x == 0.0]).tolist() == np.signbit(reference[x == 0.0]).tolist()


@needs_numba
@pytest.mark.parametrize("channels", [8, 5])  # 5: the odd channel of the paired products
def test_compiled_step_equals_numpy_step_and_run(channels):
    net = _network(channels, seed=channels)
    x = 2.0 * np.random.default_rng(1).normal(size=(200, 4, N_DOF))
    start = _cnn.initial_state(net, x[0])
    centre, width, _ = _cnn.run(net, start, x)
    compiled, numpy_only, mixed = start.copy(), start.copy(), start.copy()
    rows = []
    for k, row in enumerate(x):
        c1, w1, compiled = _cnn.step(net, compiled, row)
        c2, w2, numpy_only = _cnn.step_numpy(net, numpy_only, row)
        # one stream, the two steps in turn: they read and write the same rings
        step = _cnn.step if k % 2 else _cnn.step_numpy
        c3, w3, mixed = step(net, mixed, row)
        rows.append(np.concatenate([c1, w1, c2, w2, c3, w3]))
    got = np.array(rows).reshape(len(x), 3, 2, N_DOF)
    expected = np.stack([centre, width], axis=1)
    for k in range(3):
        np.testing.assert_allclose(got[:, k], expected, rtol=0.0, atol=1e-12)
    # the state of a network of another shape is refused, never read past its rings
    other = _cnn.initial_state(_network(channels + 2), x[0])
    with pytest.raises(InputValueError, match="network of another shape"):
        _cnn.step(net, other, x[0])
    # the batch continues from either stream's state
    more = np.random.default_rng(2).normal(size=(30, 4, N_DOF))
    after, _, _ = _cnn.run(net, compiled, more)
    np.testing.assert_allclose(after, _cnn.run(net, numpy_only, more)[0], atol=1e-12)


def _stream(threshold, run, convert=np.asarray):
    inputs = [run.model_torque, run.friction, run.sign, run.velocity]
    state = threshold.initial_state(*(a[0] for a in inputs))
    rows = []
    for k in range(run.n_samples):
        lower, upper, state = threshold.step(state, *(convert(a[k]) for a in inputs))
        rows.append(np.concatenate([lower, upper]))
    return np.array(rows)


def test_every_step_path_gives_the_batch_bounds(threshold, monkeypatch):
    run = _run(5)
    lower, upper = threshold.bounds(run)
    assert np.isinf(lower[:, 1]).all() and np.isinf(upper[:, 1]).all()  # joint 2 not monitored
    batch = np.hstack([lower, upper])
    np.testing.assert_allclose(_stream(threshold, run), batch, rtol=0.0, atol=1e-9)
    # lists are not float arrays: the checked path converts them
    np.testing.assert_allclose(_stream(threshold, run, list), batch, rtol=0.0, atol=1e-9)
    # without numba: the numpy step (a fresh threshold, nothing packed yet)
    monkeypatch.setattr(_cnn_kernel, "available", False)
    plain = LearnedThreshold.from_dict(threshold.to_dict())
    np.testing.assert_allclose(_stream(plain, run), batch, rtol=0.0, atol=1e-9)
    assert plain._compiled is None


def test_bad_sample_changes_nothing(threshold):
    run = _run(6, n=40)
    inputs = [run.model_torque, run.friction, run.sign, run.velocity]
    state = threshold.initial_state(*(a[0] for a in inputs))
    for k in range(1, 20):
        _, _, state = threshold.step(state, *(a[k] for a in inputs))
    ring = state.network.ring.copy()
    bad = [a[20].copy() for a in inputs]
    bad[2][1] = np.nan
    with pytest.raises(InputValueError, match="sign must be finite; found nan"):
        threshold.step(state, *bad)
    with pytest.raises(DimensionError, match=r"velocity must have shape \(3,\)"):
        threshold.step(state, *(a[20] for a in inputs[:3]), np.zeros(4))
    np.testing.assert_array_equal(state.network.ring, ring)
    assert not state.network.spent
    # the detector reports a fault and keeps its state; the stream goes on as if it never came
    detector = Detector(threshold)
    d_state = detector.initial_state()
    for k in range(20):
        _, d_state = detector.step(d_state, run.residual[k], *(a[k] for a in inputs), t=run.t[k])
    before = d_state.threshold.network.ring.copy()
    verdict, same = detector.step(d_state, run.residual[20], *bad, t=run.t[20])
    assert verdict.status == "fault" and same is d_state
    np.testing.assert_array_equal(same.threshold.network.ring, before)
    lowers = []
    for k in range(20, 40):
        verdict, d_state = detector.step(
            d_state, run.residual[k], *(a[k] for a in inputs), t=run.t[k]
        )
        lowers.append(verdict.lower)
    np.testing.assert_allclose(np.array(lowers), threshold.bounds(run)[0][20:], atol=1e-9)
