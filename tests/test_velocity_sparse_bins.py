"""Sparse velocity bins: L and U pooled with neighbouring bins (issue 13, item 5).

The synthetic runs move one joint the way a via-point trajectory does: long
rests and cruises in a few bins, ramps that cross every other bin in a few
milliseconds. The residual is the filtered friction of the bin plus white
Gaussian noise, so every bin has the same error distribution and held-out
runs come from the same distribution as the fit runs.

The nominal rate is the rank argument for exchangeable errors: a new sample
exceeds the largest of n fit errors with probability 1/(n + 1), so a bound
backed by at least ``least`` samples is exceeded on either side by at most
2/(least + 1) of the held-out samples.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from sensorless.exceptions import InputValueError
from sensorless.monitor.calibration import data_warnings
from sensorless.signals import ObserverSignals
from sensorless.thresholds import (
    CombinedVelocityThreshold,
    ThresholdState,
    VelocityThreshold,
    load_threshold,
)
from sensorless.thresholds.velocity_bins import MIN_BIN_TIME, pooled_windows

DT = 1e-3
GAIN = 20.0
WIDTH = 0.06
NOISE = 0.05  # N m, std
LEAST = MIN_BIN_TIME / DT  # fit samples a bin needs for its own L and U


def lowpass(x: np.ndarray, gain: float = GAIN) -> np.ndarray:
    """K/(s+K) with zero-order hold, written as the recursion (y[0] = x[0])."""
    a = np.exp(-gain * DT)
    y = np.empty_like(x)
    y[0] = x[0]
    for k in range(x.shape[0] - 1):
        y[k + 1] = a * y[k] + (1.0 - a) * x[k]
    return y


def via_point_velocity(ramp: float = 0.08, cruise: float = 1.5, rest: float = 0.5) -> np.ndarray:
    """Six moves of alternating sign at 1 rad/s: rest, ramp up, cruise, ramp down [rad/s]."""
    pieces = []
    for sign in (1, -1, 1, -1, 1, -1):
        up = np.linspace(0.0, 1.0, round(ramp / DT))
        pieces += [np.zeros(round(rest / DT)), sign * up, np.full(round(cruise / DT), sign * 1.0)]
        pieces.append(sign * up[::-1])
    return np.concatenate(pieces)


def friction(velocity: np.ndarray) -> np.ndarray:
    """Per-bin friction [N m]: Coulomb-like and viscous, constant over each bin."""
    centre = (np.floor(velocity / WIDTH) + 0.5) * WIDTH
    return 0.5 * np.tanh(centre / 0.05) + 0.3 * centre


def run(seed: int, kind: str = "motor", velocity: np.ndarray | None = None) -> ObserverSignals:
    """One run of two joints (the second slower), residual = filtered friction + noise."""
    v = via_point_velocity() if velocity is None else velocity
    v = np.column_stack([v, 0.5 * v])
    rng = np.random.default_rng(seed)
    h = np.column_stack([np.sin(np.arange(v.shape[0]) * DT * 3.0)] * 2)
    residual = 0.02 * h + lowpass(friction(v)) + rng.normal(0.0, NOISE, v.shape)
    t = np.arange(v.shape[0]) * DT
    zeros = np.zeros_like(v)
    return ObserverSignals(t, residual, h, zeros, zeros, v, gain=GAIN, robot="syn", kind=kind)


FIT = (1, 2)
HELD_OUT = tuple(range(10, 18))


def sparse_of(fits: list[ObserverSignals], velocity: np.ndarray) -> np.ndarray:
    """Recount: do the samples of ``velocity`` fall in bins with < LEAST fit samples?"""
    fit_bins = np.floor(np.concatenate([f.velocity for f in fits]) / WIDTH).astype(int)
    bins = np.floor(velocity / WIDTH).astype(int)
    out = np.empty(bins.shape, dtype=bool)
    for j in range(bins.shape[1]):
        held = np.unique(fit_bins[:, j], return_counts=True)
        counts = dict(zip(held[0].tolist(), held[1].tolist(), strict=True))
        out[:, j] = [counts.get(b, 0) < LEAST for b in bins[:, j].tolist()]
    return out


def exceedances(threshold: VelocityThreshold, fits: list[ObserverSignals]) -> tuple[int, int]:
    """Held-out samples in sparse bins, and how many of them leave the bounds."""
    samples = exceeding = 0
    for seed in HELD_OUT:
        test = run(seed)
        lower, upper = threshold.bounds(test)
        out = (test.residual < lower) | (test.residual > upper)
        sparse = sparse_of(fits, test.velocity)
        samples += int(sparse.sum())
        exceeding += int(out[sparse].sum())
    return samples, exceeding


def test_sparse_bins_too_tight_before_and_at_the_nominal_rate_after() -> None:
    fits = [run(seed) for seed in FIT]
    old = VelocityThreshold(min_bin_time=0.0).fit(fits)
    new = VelocityThreshold().fit(fits)
    samples, old_out = exceedances(old, fits)
    same_samples, new_out = exceedances(new, fits)
    assert samples == same_samples and samples > 5000
    nominal = samples * 2.0 / (LEAST + 1.0)  # expected exceedances at the nominal rate
    upper_limit = stats.poisson.ppf(0.999, nominal)
    assert new_out <= upper_limit
    # The old rule: a bound from a handful of samples, exceeded far beyond the nominal rate.
    assert old_out > 3 * upper_limit


def test_pooled_bounds_are_the_extremes_of_the_smallest_sufficient_window() -> None:
    fits = [run(seed) for seed in FIT]
    th = VelocityThreshold().fit(fits)
    edges = th.bin_edges_
    n_bins = edges.size - 1
    # Recount from scratch: bin of every fit sample and its error about the fitted centre.
    bins = np.concatenate([np.searchsorted(edges, f.velocity, side="right") - 1 for f in fits])
    bins = np.clip(bins, 0, n_bins - 1)
    errors = []
    for f in fits:
        index = np.clip(np.searchsorted(edges, f.velocity, side="right") - 1, 0, n_bins - 1)
        tau = th.tau_fme_[index, np.arange(2)]
        errors.append(f.residual - th.gamma_ * f.model_torque - lowpass(tau))
    error = np.concatenate(errors)
    pooled_count = 0
    for j in range(2):
        counts = np.bincount(bins[:, j], minlength=n_bins)
        for k in range(n_bins):
            w = 0
            while counts[max(k - w, 0) : k + w + 1].sum() < LEAST and w < n_bins:
                w += 1
            inside = (bins[:, j] >= k - w) & (bins[:, j] <= k + w)
            np.testing.assert_allclose(th.lower_[k, j], error[inside, j].min(), atol=1e-9)
            np.testing.assert_allclose(th.upper_[k, j], error[inside, j].max(), atol=1e-9)
            pooled_count += w > 0
        np.testing.assert_array_equal(th.counts_[:, j], counts)
    assert th.pooled_bins_.sum() == pooled_count > 0


def test_well_filled_bins_are_those_of_the_old_rule() -> None:
    fits = [run(seed) for seed in FIT]
    old = VelocityThreshold(margin=0.01, min_bin_time=0.0).fit(fits)
    new = VelocityThreshold(margin=0.01).fit(fits)
    filled = new.counts_ * DT >= MIN_BIN_TIME
    assert filled.any() and (~filled).any()
    np.testing.assert_array_equal(new.pooled_bins_, ~filled)
    np.testing.assert_array_equal(new.tau_fme_, old.tau_fme_)
    np.testing.assert_array_equal(new.gamma_, old.gamma_)
    np.testing.assert_array_equal(new.lower_[filled], old.lower_[filled])
    np.testing.assert_array_equal(new.upper_[filled], old.upper_[filled])
    # Pooling only ever adds samples: no pooled band is narrower than the old one.
    assert np.all(new.lower_ <= old.lower_) and np.all(new.upper_ >= old.upper_)
    assert not old.pooled_bins_.any()


def test_a_joint_with_too_little_data_takes_its_overall_extremes() -> None:
    short = run(3, velocity=via_point_velocity()[:400])  # 0.4 s < MIN_BIN_TIME
    th = VelocityThreshold().fit(short)
    assert th.pooled_bins_.all()
    error_range = th.upper_ - th.lower_
    np.testing.assert_allclose(error_range, error_range[:1], rtol=0, atol=1e-12)


def test_pooled_windows_closed_form() -> None:
    counts = np.array([[0, 9], [3, 0], [10, 0], [1, 0], [0, 1]])
    np.testing.assert_array_equal(
        pooled_windows(counts, 5.0), [[2, 0], [1, 1], [0, 2], [1, 3], [2, 4]]
    )
    np.testing.assert_array_equal(pooled_windows(counts, 100.0), np.full((5, 2), 5))


def test_streaming_equals_batch_with_pooled_bins() -> None:
    th = VelocityThreshold(margin=0.01).fit([run(seed) for seed in FIT])
    assert th.pooled_bins_.any()
    test = run(30)
    lower, upper = th.bounds(test)
    rows = [test.model_torque, test.friction, test.sign, test.velocity]
    state = th.initial_state(*(x[0] for x in rows), dt=DT)
    chunks = []
    for cut in np.array_split(np.arange(test.n_samples), [1, 7, 3000, 3001]):
        lo, up, state = th.process(state, *(x[cut] for x in rows))
        chunks.append((lo, up))
    np.testing.assert_allclose(np.vstack([c[0] for c in chunks]), lower, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.vstack([c[1] for c in chunks]), upper, rtol=0, atol=1e-12)
    assert isinstance(state, ThresholdState)


def test_save_load_round_trip_keeps_min_bin_time(tmp_path: Path) -> None:
    fits = [run(seed) for seed in FIT]
    th = VelocityThreshold(min_bin_time=0.3).fit(fits)
    loaded = load_threshold(th.save(tmp_path / "velocity.yaml"))
    assert isinstance(loaded, VelocityThreshold)
    assert loaded.get_params() == th.get_params()
    np.testing.assert_array_equal(loaded.pooled_bins_, th.pooled_bins_)
    test = run(31)
    for a, b in zip(loaded.bounds(test), th.bounds(test), strict=True):
        np.testing.assert_array_equal(a, b)


def combined_fit(min_bin_time: float) -> CombinedVelocityThreshold:
    pairs = [(run(seed, "motor"), run(seed + 50, "joint")) for seed in FIT]
    return CombinedVelocityThreshold(min_bin_time=min_bin_time).fit(pairs)


def test_combined_threshold_pools_both_residuals(tmp_path: Path) -> None:
    old, new = combined_fit(0.0), combined_fit(MIN_BIN_TIME)
    filled = ~new.pooled_bins_
    assert filled.any() and new.pooled_bins_.any()
    for name in ("lower_motor_", "upper_motor_", "lower_joint_", "upper_joint_"):
        np.testing.assert_array_equal(getattr(new, name)[filled], getattr(old, name)[filled])
    assert np.all(new.lower_joint_ <= old.lower_joint_)
    assert np.all(new.upper_joint_ >= old.upper_joint_)
    assert np.any(new.upper_joint_ > old.upper_joint_)
    single = new.for_kind("joint")
    assert single.min_bin_time == MIN_BIN_TIME
    np.testing.assert_array_equal(single.pooled_bins_, new.pooled_bins_)
    loaded = load_threshold(new.save(tmp_path / "combined.yaml"))
    assert isinstance(loaded, CombinedVelocityThreshold)
    assert loaded.min_bin_time == MIN_BIN_TIME


@pytest.mark.parametrize("min_bin_time", [MIN_BIN_TIME, 2.0])
def test_calibration_flags_the_pooled_bins(min_bin_time: float) -> None:
    fits = [run(seed) for seed in FIT]
    th = VelocityThreshold(min_bin_time=min_bin_time).fit(fits)
    warnings = data_warnings(fits, th, 1.0, 0.95, None, 0.0)
    text = next(w for w in warnings if "velocity bins" in w)
    for j in range(2):
        visited = np.flatnonzero(th.counts_[:, j] > 0)
        span = slice(visited[0], visited[-1] + 1)
        found = re.search(rf"joint {j + 1}: (\d+) of (\d+)", text)
        assert found is not None
        assert int(found.group(1)) == int(th.pooled_bins_[span, j].sum())
        assert int(found.group(2)) == visited[-1] - visited[0] + 1


@pytest.mark.parametrize("value", [-0.1, float("nan"), "long"])
def test_bad_min_bin_time_is_rejected(value: object) -> None:
    with pytest.raises(InputValueError, match="min_bin_time"):
        VelocityThreshold(min_bin_time=value).fit(run(1))  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="min_bin_time"):
        combined_fit(value)  # type: ignore[arg-type]
