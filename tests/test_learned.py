"""The learned threshold family: network stream = batch, fit level, weights files, training."""

from __future__ import annotations

import json

import numpy as np
import pytest

from sensorless.detection import Detector
from sensorless.evaluation import collision_windows
from sensorless.exceptions import (
    FileFormatError,
    InputTypeError,
    InputValueError,
    ModelMismatchError,
    UnknownNameError,
)
from sensorless.learning import (
    SCENARIOS,
    TrainingRecipe,
    run_draws,
    train_detector,
    training_runs,
)
from sensorless.learning._backward import forward_crops, gradients
from sensorless.learning.training import _randomised, random_network
from sensorless.observers import observe
from sensorless.signals import ObserverSignals
from sensorless.simulation.scenario import Scenario, load_scenario
from sensorless.thresholds import (
    LearnedThreshold,
    LearnedWeights,
    _cnn,
    builtin_weights,
    load_threshold,
    load_weights,
    save_weights,
)

N_DOF = 3


def _network(seed: int = 0, channels: int = 8) -> _cnn.Network:
    rng = np.random.default_rng(seed)
    norm = {
        "input_mean": rng.normal(size=(4, N_DOF)),
        "input_scale": rng.uniform(0.5, 2.0, (4, N_DOF)),
        "output_mean": rng.normal(size=N_DOF),
        "output_scale": rng.uniform(0.5, 2.0, N_DOF),
    }
    net = random_network(rng, norm, channels=channels)
    return net.with_parameters([p + 0.2 * rng.normal(size=p.shape) for p in net.parameters()])


@pytest.fixture
def weights_path(tmp_path):
    weights = LearnedWeights(_network(), robot="demo", kind="motor", gain=20.0, dt=1e-3)
    return save_weights(weights, tmp_path / "demo")


def _run(seed: int, n: int = 600, offset: float = 0.0) -> ObserverSignals:
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 1e-3
    h = np.sin(np.outer(t, [3.0, 5.0, 7.0]) + seed)
    f = np.cos(np.outer(t, [2.0, 4.0, 1.0]))
    r = 0.1 * h + 0.05 * rng.normal(size=h.shape) + offset
    return ObserverSignals(t, r, h, f, np.tanh(f), 0.5 * f, gain=20.0, robot="demo")


def test_gradients_match_finite_differences():
    net = _network(1, channels=5)
    rng = np.random.default_rng(2)
    x = rng.normal(size=(2, 70, 4, N_DOF))
    n_out = 70 - net.receptive_field + 1
    target = rng.normal(size=(2, n_out, N_DOF))
    weight = rng.uniform(0.0, 1.0, (2, n_out, N_DOF))
    _, grads = gradients(net, x, target, weight)
    params = net.parameters()
    for i, p in enumerate(params):
        index = tuple(int(rng.integers(s)) for s in p.shape)

        def loss(step: float, i: int = i, index: tuple[int, ...] = index) -> float:
            shifted = [a.copy() for a in params]
            shifted[i][index] += step
            return gradients(net.with_parameters(shifted), x, target, weight)[0]

        numeric = (loss(1e-6) - loss(-1e-6)) / 2e-6
        assert grads[i][index] == pytest.approx(numeric, rel=1e-5, abs=1e-9)


def test_stream_equals_batch_and_chunks_equal_whole():
    net = _network()
    x = np.random.default_rng(3).normal(size=(400, 4, N_DOF))
    start = _cnn.initial_state(net, x[0])
    centre, width, _ = _cnn.run(net, start, x)
    first = _cnn.run(net, start, x[:123])
    second = _cnn.run(net, first[2], x[123:])
    np.testing.assert_array_equal(np.vstack([first[0], second[0]]), centre)
    # one sample at a time, also across a chunk boundary: run's state continues by step
    state, stream = start.copy(), []
    for row in x:
        c, w, state = _cnn.step(net, state, row)
        stream.append(np.concatenate([c, w]))
    np.testing.assert_allclose(np.array(stream), np.hstack([centre, width]), rtol=0, atol=1e-9)
    state = first[2]
    for row in x[123:]:
        c, _, state = _cnn.step(net, state, row)
    np.testing.assert_allclose(c, centre[-1], rtol=0, atol=1e-9)
    # step advances the rings in place: the state it was given is spent, run's is not
    assert not start.spent and first[2].spent
    with pytest.raises(InputValueError, match="advanced by a later step"):
        _cnn.run(net, first[2], x[:5])
    # the crops of training compute the same outputs (no state: from sample receptive_field - 1)
    out, _ = forward_crops(net, x[None])
    crop_centre = out[0, :, 0] * net.output_scale + net.output_mean
    np.testing.assert_allclose(crop_centre, centre[net.receptive_field - 1 :], atol=1e-12)


def test_nonfinite_sample_is_skipped():
    net = _network()
    x = np.random.default_rng(4).normal(size=(50, 4, N_DOF))
    start = _cnn.initial_state(net, x[0])
    bad = x.copy()
    bad[20, 1, 2] = np.nan
    c, w, state = _cnn.step(net, start, bad[20])
    assert np.isnan(c).all() and np.isnan(w).all() and state is start
    centre, _, _ = _cnn.run(net, start, bad)
    clean, _, _ = _cnn.run(net, start, np.delete(x, 20, axis=0))
    assert np.isnan(centre[20]).all()
    np.testing.assert_allclose(np.delete(centre, 20, axis=0), clean, atol=1e-12)
    huge = np.full((4, N_DOF), 1e300)
    assert np.isfinite(_cnn.step(net, start, huge)[0]).all()


def _score(weights_path, run: ObserverSignals) -> np.ndarray:
    """|r - c|/w by the network's one-sample step (a second path to the score)."""
    net = load_weights(weights_path).network
    x = np.stack([run.model_torque, run.friction, run.sign, run.velocity], axis=1)
    state, scores = _cnn.initial_state(net, x[0]), []
    for row, r in zip(x, run.residual, strict=True):
        c, w, state = _cnn.step(net, state, row)
        scores.append(np.abs(r - c) / w)
    return np.array(scores)


def test_level_is_the_largest_score_of_the_fit_runs(weights_path):
    runs = [_run(0), _run(1, offset=0.2)]
    margin = np.array([0.0, 0.1, 0.3])
    threshold = LearnedThreshold(weights_path, margin=margin, transient=0.05).fit(runs)
    kept = [run.t >= 0.05 for run in runs]
    expected = np.max(
        [_score(weights_path, r)[k].max(axis=0) for r, k in zip(runs, kept, strict=True)], axis=0
    )
    np.testing.assert_allclose(threshold.level_, expected, rtol=1e-9)
    # only the runs given count: order does not matter, a third run changes it
    swapped = LearnedThreshold(weights_path, margin=margin, transient=0.05).fit(runs[::-1])
    np.testing.assert_array_equal(swapped.level_, threshold.level_)
    more = LearnedThreshold(weights_path, margin=margin, transient=0.05).fit([*runs, _run(2)])
    assert (more.level_ >= threshold.level_).all()
    # bounds: centre ∓ (level · width + margin); the fit runs stay inside them
    centre, width = threshold.predict(runs[0])
    lower, upper = threshold.bounds(runs[0])
    np.testing.assert_allclose(upper - centre, threshold.level_ * width + margin, atol=1e-12)
    np.testing.assert_allclose(centre - lower, threshold.level_ * width + margin, atol=1e-12)
    inside = (lower <= runs[0].residual) & (runs[0].residual <= upper)
    assert inside[kept[0]].all()


def test_threshold_stream_equals_bounds_and_file_round_trip(weights_path, tmp_path):
    run = _run(5)
    threshold = LearnedThreshold(weights_path, margin=0.05).fit(_run(0))
    lower, upper = threshold.bounds(run)
    inputs = (run.model_torque, run.friction, run.sign, run.velocity)
    first = state = threshold.initial_state(*(a[0] for a in inputs))
    rows = []
    for k in range(run.n_samples):
        lo, up, state = threshold.step(state, *(a[k] for a in inputs))
        rows.append(np.concatenate([lo, up]))
    np.testing.assert_allclose(np.array(rows), np.hstack([lower, upper]), rtol=0, atol=1e-9)
    with pytest.raises(InputValueError, match="advanced by a later step"):
        threshold.step(first, *(a[0] for a in inputs))  # spent: the rings moved on
    loaded = load_threshold(threshold.save(tmp_path / "th.yaml"))
    assert isinstance(loaded, LearnedThreshold)
    np.testing.assert_array_equal(loaded.bounds(run)[1], upper)


def test_bad_inputs_are_clear_errors(weights_path, tmp_path):
    run = _run(0)
    with pytest.raises(UnknownNameError, match="no shipped weights named 'nosuch'"):
        LearnedThreshold("nosuch").fit(run)
    with pytest.raises(InputTypeError, match="weights must be a robot name"):
        LearnedThreshold(3.0).fit(run)  # type: ignore[arg-type]
    slow = ObserverSignals(run.t * 2, *(getattr(run, n) for n in _FIELDS), gain=20.0, robot="demo")
    with pytest.raises(InputValueError, match=r"sample period of 0\.001 s"):
        LearnedThreshold(weights_path).fit(slow)
    other_gain = ObserverSignals(run.t, *(getattr(run, n) for n in _FIELDS), gain=5.0, robot="demo")
    with pytest.raises(InputValueError, match=r"observer gain K_I = 20\.0"):
        LearnedThreshold(weights_path).fit(other_gain)
    other = ObserverSignals(run.t, *(getattr(run, n) for n in _FIELDS), gain=20.0, robot="ur10")
    with pytest.raises(ModelMismatchError, match="weights trained for demo"):
        LearnedThreshold(weights_path).fit(other)
    meta = json.loads(weights_path.read_text())
    weights_path.with_suffix(".npz").write_bytes(b"not the arrays")
    with pytest.raises(FileFormatError, match="does not match arrays_sha256"):
        load_weights(weights_path)
    meta["format_version"] = 99
    newer = tmp_path / "newer.json"
    newer.write_text(json.dumps(meta))
    with pytest.raises(FileFormatError, match=r"format_version must be 1\.\.2; got 99"):
        load_weights(newer)


_FIELDS = ("residual", "model_torque", "friction", "sign", "velocity")


def test_seeded_training_gives_the_same_weights():
    recipe = TrainingRecipe(minutes=2 / 60, run_seconds=2.0, steps=4, batch=3, crop=80, seed=5)
    first = train_detector(recipe).network.parameters()
    second = train_detector(recipe).network.parameters()
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(a, b)


_SECONDS = {"puma560": 7.0}


@pytest.mark.parametrize("robot", sorted(SCENARIOS))
def test_shipped_weights_detect_a_clear_impact(robot):
    if robot not in builtin_weights():
        pytest.skip(f"no shipped {robot} weights")
    # long enough for a contact: puma560-thesis has its first at 6.26 s (40 N)
    scenario = load_scenario(SCENARIOS[robot]).with_duration(_SECONDS.get(robot, 5.0))
    nominal = scenario.nominal("motor")
    free = observe(scenario.run(seed=11, collisions=False).log, nominal, gain=20.0)
    threshold = LearnedThreshold(margin=0.05, transient=0.3).fit(free)
    assert threshold.weights_.robot == robot  # the shipped file of the fit runs' robot
    log = scenario.run(seed=12).log
    events = Detector(threshold, min_duration=0.005).detect(observe(log, nominal, gain=20.0))
    windows = collision_windows(log)
    assert windows
    hit = [w for w in windows if any(e.start <= w.end + 0.3 and e.end >= w.start for e in events)]
    assert len(hit) == len(windows)


def _recomputed_draws(recipe: TrainingRecipe) -> list[dict]:
    """The draws of every run, replayed from the recipe's SeedSequence in training's order."""
    scenario = load_scenario(recipe.scenario)
    n_runs = int(np.ceil(recipe.minutes * 60.0 / recipe.run_seconds))
    draws = []
    for child in np.random.SeedSequence(recipe.seed).spawn(n_runs):
        rng = np.random.default_rng(child)
        rng.uniform(size=2)  # inertial and friction bands of the model error
        rng.integers(2**31)  # its seed
        rng.uniform(size=2)  # noise and speed factors (a random point-to-point trajectory)
        seed = int(rng.integers(2**31))
        carries = rng.random() < recipe.payload_share
        mass = rng.uniform(*recipe.payload_mass)
        com = rng.uniform(recipe.payload_com_low, recipe.payload_com_high)
        factor = rng.uniform(*recipe.rate_factor)
        draws.append(
            {
                "seed": seed,
                "factor": factor,
                "rate": factor / scenario.dt,
                "payload": {"mass": mass, "com": com.tolist()} if carries else None,
            }
        )
    return draws


def test_payload_and_rate_are_drawn_from_the_recipe_and_recorded(tmp_path):
    recipe = TrainingRecipe(
        minutes=8 / 60,
        run_seconds=2.0,
        steps=2,
        batch=2,
        crop=60,
        seed=3,
        rate_factor=(0.8, 1.25),
        payload_share=0.5,
    )
    assert recipe.payload_mass == (0.0, 3.0)
    expected = _recomputed_draws(recipe)
    assert {d["payload"] is None for d in expected} == {True, False}  # both kinds of run
    runs = training_runs(recipe)
    path = save_weights(train_detector(recipe), tmp_path / "drawn")
    weights = load_weights(path)
    recorded = weights.recipe["drawn"]
    assert len(recorded) == len(runs) == len(expected) == 4
    dt = load_scenario(recipe.scenario).dt
    for run, drawn, wanted in zip(runs, recorded, expected, strict=True):
        assert drawn["seed"] == wanted["seed"] == run.drawn["seed"]
        assert drawn["sample_rate"] == pytest.approx(wanted["rate"], rel=1e-12)
        assert 0.8 <= wanted["factor"] <= 1.25
        assert run.signals.dt == pytest.approx(1.0 / wanted["rate"], rel=1e-9)  # the run's rate
        assert drawn["payload"] == wanted["payload"]
        if wanted["payload"] is not None:
            assert 0.0 <= wanted["payload"]["mass"] <= 3.0
            com = np.array(wanted["payload"]["com"])
            assert (np.array([-0.03, -0.03, 0.0]) <= com).all()
            assert (com <= np.array([0.03, 0.03, 0.15])).all()
    # the ranges are in the file; the band of periods spans the rate factors
    for name in ("payload_share", "payload_mass", "payload_com_low", "payload_com_high"):
        assert np.array_equal(weights.recipe[name], getattr(recipe, name))
    assert tuple(weights.recipe["rate_factor"]) == (0.8, 1.25)
    assert weights.period_range == pytest.approx((dt / 1.25, dt / 0.8), rel=1e-9)
    assert weights.dt == dt
    assert run_draws(recipe) == recorded  # the draws recomputed without simulating


def test_training_puts_the_payload_on_the_true_robot_only():
    recipe = TrainingRecipe(minutes=2 / 60, run_seconds=2.0, payload_share=1.0, seed=2)
    (drawn,) = _recomputed_draws(recipe)
    scenario = load_scenario(recipe.scenario)
    rng = np.random.default_rng(np.random.SeedSequence(recipe.seed).spawn(1)[0])
    randomised, _ = _randomised(scenario, recipe, rng)
    assert randomised.spec["payload"] == drawn["payload"]
    true, nominal = randomised.robots()
    grown = true.parameter_vector() - scenario.robots()[0].parameter_vector()
    # the end link's standard parameters (last 11: inertia, m c, m, Ia) grew by the
    # payload's m c and m; no other link's did
    mass, com = drawn["payload"]["mass"], np.array(drawn["payload"]["com"])
    np.testing.assert_allclose(grown[-5:-2], mass * com, rtol=1e-9, atol=1e-12)
    assert grown[-2] == pytest.approx(mass, rel=1e-12)
    assert grown[-1] == 0.0 and np.count_nonzero(grown[:-11]) == 0
    # the model the user has is the same without the payload
    spec = {k: v for k, v in randomised.spec.items() if k != "payload"}
    without = Scenario(randomised.name, spec).robots()[1]
    np.testing.assert_array_equal(nominal.parameter_vector(), without.parameter_vector())


def _banded(tmp_path, low: float = 0.8e-3, high: float = 1.25e-3):
    weights = LearnedWeights(
        _network(), robot="demo", kind="motor", gain=20.0, dt=1e-3, period_range=(low, high)
    )
    return save_weights(weights, tmp_path / "banded")


def _at_period(dt: float) -> ObserverSignals:
    """``_run(0)`` with its samples ``dt`` [s] apart."""
    run = _run(0)
    t = np.arange(run.n_samples) * dt
    return ObserverSignals(t, *(getattr(run, f) for f in _FIELDS), gain=20.0, robot="demo")


def test_a_period_inside_the_trained_band_is_accepted_one_outside_refused(tmp_path):
    path = _banded(tmp_path)
    assert load_weights(path).period_range == (0.8e-3, 1.25e-3)
    for dt in (0.8e-3, 0.9e-3, 1.1e-3, 1.25e-3):  # inside, edges included, none exactly 1 ms
        run = _at_period(dt)
        threshold = LearnedThreshold(path, transient=0.05).fit(run)
        kept = run.t >= 0.05
        np.testing.assert_allclose(threshold.level_, _score(path, run)[kept].max(axis=0), rtol=1e-9)
    for dt, hz in ((0.7e-3, "1428.57"), (1.3e-3, "769.231")):
        message = (
            r"sample periods of 0\.0008 to 0\.00125 s \(800 to 1250 Hz; the network counts "
            rf"samples\); got {dt} s \({hz} Hz\), outside that band"
        )
        with pytest.raises(InputValueError, match=message):
            LearnedThreshold(path).fit(_at_period(dt))
        with pytest.raises(InputValueError, match=message):  # a stream at that period too
            threshold.initial_state(*(np.zeros(N_DOF) for _ in range(4)), dt=dt)


def test_a_format_1_file_still_loads_and_keeps_its_exact_period(weights_path, tmp_path):
    meta = json.loads(weights_path.read_text())
    assert meta["format_version"] == 2 and meta["period_range"] is None
    meta["format_version"] = 1  # as version 1 wrote it: no period_range key
    del meta["period_range"]
    old = tmp_path / "old.json"
    old.write_text(json.dumps(meta))
    (tmp_path / "old.npz").write_bytes(weights_path.with_suffix(".npz").read_bytes())
    meta["arrays"] = "old.npz"
    old.write_text(json.dumps(meta))
    loaded, saved = load_weights(old), load_weights(weights_path)
    assert loaded.period_range is None and loaded.dt == 1e-3
    for a, b in zip(loaded.network.parameters(), saved.network.parameters(), strict=True):
        np.testing.assert_array_equal(a, b)
    LearnedThreshold(old).fit(_at_period(1.005e-3))  # within 1 % of the period
    with pytest.raises(InputValueError, match=r"sample period of 0\.001 s .* more than 1% apart"):
        LearnedThreshold(old).fit(_at_period(0.9e-3))


def test_bad_training_ranges_and_bands_are_clear_errors(tmp_path):
    bad = [
        ({"payload_share": 1.5}, r"payload_share must be in \[0, 1\]"),
        (
            {"payload_mass": (2.0, 1.0)},
            r"payload_mass must be a range \(low, high\) with low <= high",
        ),
        ({"payload_mass": (-1.0, 1.0)}, r"payload_mass must be a finite number >= 0"),
        ({"rate_factor": (0.0, 1.2)}, r"rate_factor must be a finite number > 0"),
        ({"rate_factor": (1.2,)}, r"rate_factor must be a range \(low, high\) \[-\]"),
        ({"payload_com_low": (0.0, 0.0)}, r"must be 3 coordinates \[m\]"),
        (
            {"payload_com_low": (0.0, 0.0, 0.2)},
            r"payload_com_low \.\. payload_com_high must be a range",
        ),
    ]
    for change, message in bad:
        with pytest.raises(InputValueError, match=message):
            run_draws(TrainingRecipe(minutes=1 / 60, run_seconds=1.0, **change))
    with pytest.raises(InputValueError, match=r"period_range must be \(low, high\) \[s\]"):
        _banded(tmp_path, 2e-3, 1e-3)
    path = _banded(tmp_path)  # a file whose band was edited by hand is refused on reading
    meta = json.loads(path.read_text())
    meta["period_range"] = [2e-3, 1e-3]
    path.write_text(json.dumps(meta))
    with pytest.raises(
        FileFormatError, match=r"period_range must be \[low, high\] \[s\] with 0 < low <= high"
    ):
        load_weights(path)
