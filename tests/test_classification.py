"""Intended contact vs collision: profiles, draws, ground truth, classifier, scoring.

Profiles are checked against their closed forms (rise time, plateau, and the
integral by numerical quadrature). The classifier is checked on features built
by hand (each rule, and :meth:`fit` on a set whose true rule is known), on a
simulated Franka Panda with the true model (``Scenario.with_exact_model``):
a 2 s guiding push and a 50 ms impact get the right class, the stream's
classes equal the batch ones, and on a small seeded set of mixed guiding,
clamp and impact contacts the accuracy beats a coin by a one-sided binomial
margin.
"""

from __future__ import annotations

import doctest
import inspect
import itertools
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.integrate import quad

from sensorless.classification import (
    Classification,
    Cutoffs,
    EventFeatures,
    InteractionClassifier,
    classifications_to_pandas,
    classify_events,
)
from sensorless.classification import classifier as classifier_module
from sensorless.classification import features as features_module
from sensorless.detection import Detector
from sensorless.evaluation.classification import (
    ClassificationEvaluation,
    classification_table,
    evaluate_classification,
    ground_truth_kinds,
)
from sensorless.exceptions import (
    DimensionError,
    FileFormatError,
    InputTypeError,
    InputValueError,
    LogFormatError,
    NotFittedError,
    UnknownNameError,
)
from sensorless.io import Log, read_log, write_log
from sensorless.monitor import CollisionMonitor, tune
from sensorless.signals import Event, ObserverSignals
from sensorless.simulation import interaction_profiles, interactions
from sensorless.simulation.collisions import Contact, ContactSet, HalfSine, Push
from sensorless.simulation.interaction_profiles import (
    Clamp,
    GuidingHand,
    Impact,
    interaction_profile,
    kind_of_profile,
)
from sensorless.simulation.interactions import (
    RANGES,
    draw_interactions,
    random_interactions,
    simulate_interactions,
)
from sensorless.simulation.scenario import load_scenario
from sensorless.simulation.schema import validate_scenario
from sensorless.simulation.schema_interactions import RandomInteractionsSpec
from sensorless.simulation.simulator import simulate

# ----------------------------------------------------------------------------- profiles


def _integral(profile) -> float:
    return quad(profile, profile.start, profile.end, limit=200, points=[profile.start])[0]


def test_guiding_hand_rises_in_its_ramp_holds_and_integrates_to_its_closed_form() -> None:
    hand = GuidingHand(start=1.0, ramp=0.6, hold=1.5, release=0.4, peak=25.0)
    t = np.linspace(1.0, 1.6, 601)
    force = hand(t)
    assert np.all(np.diff(force) > 0) and force[-1] == pytest.approx(25.0)  # rise time = ramp
    assert np.all(hand(np.linspace(1.6, 3.1, 50)) == pytest.approx(25.0))  # plateau
    slope = np.max(np.diff(force) / np.diff(t))
    assert slope == pytest.approx(math.pi * 25.0 / (2 * 0.6), rel=1e-4)
    assert _integral(hand) == pytest.approx(25.0 * (0.6 / 2 + 1.5 + 0.4 / 2), rel=1e-9)
    assert hand.end == pytest.approx(3.5) and hand.kind == "intended"


def test_clamp_builds_linearly_holds_and_integrates_to_its_closed_form() -> None:
    clamp = Clamp.from_approach(
        start=2.0, stiffness=8000.0, speed=0.05, peak=120.0, hold=1.0, release=0.2
    )
    assert clamp.build == pytest.approx(120.0 / (8000.0 * 0.05)) and clamp.rate == pytest.approx(
        400.0
    )
    t = np.linspace(2.0, 2.0 + clamp.build, 101)
    np.testing.assert_allclose(np.diff(clamp(t)) / np.diff(t), 400.0, rtol=1e-9)
    assert clamp(2.0 + clamp.build + 0.5) == pytest.approx(120.0)
    expected = 120.0 * (clamp.build / 2 + 1.0 + 0.2 / 2)
    assert _integral(clamp) == pytest.approx(expected, rel=1e-9)
    assert clamp(clamp.end) == pytest.approx(0.0, abs=1e-12) and clamp.kind == "collision"


def test_impact_peaks_at_its_rise_time_and_has_half_its_peak_times_duration() -> None:
    hit = Impact(start=0.5, rise=0.008, duration=0.06, peak=90.0)
    t = np.linspace(0.5, 0.56, 6001)
    force = hit(t)
    assert t[np.argmax(force)] == pytest.approx(0.508, abs=1e-5) and force.max() == pytest.approx(
        90
    )
    assert _integral(hit) == pytest.approx(90.0 * 0.06 / 2, rel=1e-9)
    assert hit(0.5) == 0.0 and hit(0.56) == pytest.approx(0.0, abs=1e-12)
    assert hit(0.4) == 0.0 and hit(0.7) == 0.0 and hit.kind == "collision"


def test_every_profile_has_its_label_and_the_names_map_back() -> None:
    assert HalfSine.kind == Push.kind == "collision"
    for cls in (GuidingHand, Clamp, Impact, HalfSine, Push):
        assert kind_of_profile(cls.__name__) == cls.kind
    assert kind_of_profile("SomethingElse") == "collision"


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: GuidingHand(0.0, -0.1, 1.0, 0.5, 20.0), "GuidingHand ramp"),
        (lambda: GuidingHand(0.0, 0.5, 1.0, 0.5, -1.0), "GuidingHand peak"),
        (lambda: Clamp(0.0, 0.0, 1.0, 0.1, 50.0), "Clamp build"),
        (lambda: Clamp.from_approach(0.0, 1e4, 0.0, 50.0, 1.0, 0.1), "Clamp speed"),
        (lambda: Impact(0.0, 0.05, 0.05, 50.0), "rise must be shorter than its duration"),
        (lambda: Impact(0.0, 0.01, math.nan, 50.0), "Impact duration"),
    ],
)
def test_profile_arguments_are_checked(build, match) -> None:
    with pytest.raises(InputValueError, match=match):
        build()


def test_scenario_entries_build_the_profiles_they_name() -> None:
    entries = [
        (
            {"profile": "guiding", "start": 1, "ramp": 0.5, "hold": 1, "release": 0.5, "peak": 20},
            GuidingHand(1, 0.5, 1, 0.5, 20),
        ),
        (
            {"profile": "clamp", "start": 1, "build": 0.2, "hold": 1, "release": 0.1, "peak": 90},
            Clamp(1, 0.2, 1, 0.1, 90),
        ),
        (
            {"profile": "impact", "start": 1, "rise": 0.01, "duration": 0.05, "peak": 60},
            Impact(1, 0.01, 0.05, 60),
        ),
    ]
    for entry, profile in entries:
        assert interaction_profile(entry) == profile
    with pytest.raises(UnknownNameError, match="unknown interaction profile 'push'"):
        interaction_profile({"profile": "push"})


# ----------------------------------------------------------------------------- schema


def _spec(**contacts) -> dict:
    return {
        "duration": 10.0,
        "robot": "panda",
        "controller": {"type": "computed_torque"},
        "trajectory": {"type": "random_point_to_point", "max_velocity": 1.0},
        **contacts,
    }


def test_the_scenario_format_accepts_the_new_contacts_and_random_interactions() -> None:
    contact = {"id": 1, "link": 3, "direction": [1, 0, 0]}
    validated = validate_scenario(
        _spec(
            collisions=[
                {
                    **contact,
                    "profile": "guiding",
                    "start": 1,
                    "ramp": 0.5,
                    "hold": 1,
                    "release": 0.5,
                    "peak": 20,
                },
                {
                    **contact,
                    "id": 2,
                    "profile": "clamp",
                    "start": 4,
                    "build": 0.2,
                    "hold": 1,
                    "release": 0.1,
                    "peak": 90,
                },
                {
                    **contact,
                    "id": 3,
                    "profile": "impact",
                    "start": 7,
                    "rise": 0.01,
                    "duration": 0.05,
                    "peak": 60,
                },
            ]
        )
    )
    assert [c.profile for c in validated.collisions] == ["guiding", "clamp", "impact"]
    drawn = validate_scenario(_spec(random_interactions={"count": 3, "kinds": ["guiding"]}))
    assert drawn.random_interactions is not None and drawn.random_interactions.count == 3
    with pytest.raises(FileFormatError, match="rise"):
        validate_scenario(
            _spec(
                collisions=[
                    {
                        **contact,
                        "profile": "impact",
                        "start": 7,
                        "rise": 0.1,
                        "duration": 0.05,
                        "peak": 60,
                    }
                ]
            )
        )
    with pytest.raises(FileFormatError, match="random_interactions alone"):
        validate_scenario(_spec(random_interactions={"count": 1}, random_collisions={"count": 1}))
    with pytest.raises(FileFormatError, match=r"random_interactions\.kinds"):
        validate_scenario(_spec(random_interactions={"count": 1, "kinds": ["push"]}))


def test_random_interactions_section_mirrors_draw_interactions() -> None:
    signature = inspect.signature(draw_interactions).parameters
    for key, field in RandomInteractionsSpec.model_fields.items():
        if key != "count":
            default = signature[key].default
            assert field.default == (list(default) if isinstance(default, tuple) else default), key


# ----------------------------------------------------------------------------- draws


@pytest.fixture(scope="module")
def panda_run():
    """Robot and desired motion of a Panda run (nothing simulated)."""
    scenario = load_scenario("panda-gaz").with_exact_model().with_duration(20.0)
    kwargs = scenario.build(seed=5, collisions=False)
    return kwargs["plant"].robot, kwargs["trajectory"]


def test_draws_are_reproducible_separated_and_within_the_ranges(panda_run) -> None:
    robot, trajectory = panda_run
    first = draw_interactions(robot, 6, 20.0, np.random.default_rng(3), trajectory=trajectory)
    again = draw_interactions(robot, 6, 20.0, np.random.default_rng(3), trajectory=trajectory)
    assert first == again and [c.id for c in first] == list(range(1, 7))
    windows = sorted((c.start, c.end) for c in first)
    assert windows[0][0] >= 0.5 and windows[-1][1] <= 19.5
    assert all(b[0] - a[1] >= 1.0 - 1e-12 for a, b in itertools.pairwise(windows))
    for contact in first:
        profile, kind = contact.profile, type(contact.profile).__name__
        ranges = RANGES[{"GuidingHand": "guiding", "Clamp": "clamp", "Impact": "impact"}[kind]]
        assert ranges["peak"][0] <= profile.peak <= ranges["peak"][1]
        if isinstance(profile, Impact):
            assert profile.rise < 0.02 and 0.03 <= profile.duration <= 0.1
        if isinstance(profile, GuidingHand):
            assert 1.6 <= profile.duration <= 5.0


def test_directions_follow_the_motion_of_the_point(panda_run) -> None:
    robot, trajectory = panda_run
    for kind, sense in (("guiding", 1.0), ("impact", -1.0), ("clamp", -1.0)):
        drawn = draw_interactions(
            robot,
            4,
            20.0,
            np.random.default_rng(8),
            trajectory=trajectory,
            kinds=[kind],
            spread=0.0,
        )
        for contact in drawn:
            # The point's velocity by finite differences of its position (no Jacobian).
            h = 1e-6
            q0 = trajectory.evaluate(np.array([contact.start - h, contact.start + h]))[0]
            positions = [robot.forward_kinematics(q, contact.link, contact.point) for q in q0]
            velocity = (positions[1] - positions[0]) / (2 * h)
            speed = np.linalg.norm(velocity)
            if speed >= 1e-2:
                np.testing.assert_allclose(contact.direction, sense * velocity / speed, atol=1e-5)
            assert type(contact.profile).kind == ("intended" if kind == "guiding" else "collision")


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"kinds": ["push"]}, UnknownNameError, "kinds must name"),
        ({"kinds": []}, UnknownNameError, "kinds must name"),
        ({"n": 30}, InputValueError, "need .* but duration - 2\\*margin"),
        ({"spread": -1.0}, InputValueError, "spread"),
        ({"links": [9]}, InputValueError, "links"),
        ({"trajectory": "fast"}, InputTypeError, "trajectory must be a Trajectory"),
        ({"rng": 3}, InputTypeError, "numpy.random.Generator"),
    ],
)
def test_draw_arguments_are_checked(panda_run, kwargs, error, match) -> None:
    robot, _ = panda_run
    arguments = {"n": 3, "rng": np.random.default_rng(0), **kwargs}
    with pytest.raises(error, match=match):
        draw_interactions(robot, arguments.pop("n"), 20.0, arguments.pop("rng"), **arguments)


def test_a_scenario_section_draws_what_draw_interactions_draws(panda_run) -> None:
    robot, trajectory = panda_run
    spec = {"count": 3, "kinds": ["guiding", "impact"], "links": [4, 6], "spread": 0.1}
    built = random_interactions(spec, robot, trajectory, 20.0, np.random.default_rng(4))
    direct = draw_interactions(
        robot,
        3,
        20.0,
        np.random.default_rng(4),
        trajectory=trajectory,
        kinds=("guiding", "impact"),
        links=(4, 6),
        spread=0.1,
    )
    assert built == direct


# ----------------------------------------------------------------------------- ground truth


def test_labels_survive_a_log_round_trip(tmp_path: Path) -> None:
    scenario = load_scenario("panda-gaz").with_duration(5.0).with_sample_rate(250.0)
    log = simulate_interactions(scenario, 2, seed=2, kinds=["guiding", "impact"]).log
    entries = log.metadata["collisions"]
    expected = {e["id"]: kind_of_profile(e["profile"]) for e in entries}
    assert ground_truth_kinds(log) == expected == {e["id"]: e["kind"] for e in entries}
    for suffix in ("parquet", "csv"):
        back = read_log(write_log(log, tmp_path / f"run.{suffix}"))
        assert ground_truth_kinds(back) == expected
        assert [e["kind"] for e in back.metadata["collisions"]] == [e["kind"] for e in entries]
    # Without "kind", the profile's name gives the label.
    bare = [{k: v for k, v in e.items() if k != "kind"} for e in entries]
    assert ground_truth_kinds(Log(t=log.t, q=log.q, metadata={"collisions": bare})) == expected


def test_a_bad_label_is_named() -> None:
    entry = {"id": 1, "start": 0.0, "end": 0.1, "kind": "friendly"}
    log = Log(t=np.arange(5) * 0.1, q=np.zeros((5, 1)), metadata={"collisions": [entry]})
    with pytest.raises(LogFormatError, match=r"\['kind'\] must be one of"):
        ground_truth_kinds(log)


# ----------------------------------------------------------------------------- rules, fit


def _features(rise=50.0, duration=2.0, hf=0.05, power=1.0) -> EventFeatures:
    return EventFeatures(0.0, duration, rise, duration, hf, power, 10.0, 100)


def test_each_rule_alone_makes_a_collision() -> None:
    classifier = InteractionClassifier()
    assert classifier.decide(_features()).kind == "intended"
    cases = {
        "rise_rate": {"rise": 250.0},
        "duration": {"duration": 0.1},
        "hf_fraction": {"hf": 0.5},
        "mean_power": {"power": -20.0},
    }
    for rule, change in cases.items():
        result = classifier.decide(_features(**change))
        assert result.kind == "collision" and result.failed == (rule,)
    # At the cut-offs themselves, every rule still says intended.
    cut = Cutoffs()
    edge = _features(cut.rise_rate, cut.duration - 1e-12, cut.hf_fraction, cut.mean_power)
    assert classifier.decide(edge).kind == "intended"


def test_fit_recovers_a_known_rule_and_states_its_probability() -> None:
    rng = np.random.default_rng(1)
    n = 80
    intended = [
        _features(rng.uniform(5, 30), rng.uniform(1, 4), rng.uniform(0, 0.5), rng.uniform(-2, 2))
        for _ in range(n)
    ]
    # Collisions differ from intended events in the rise rate only (hundreds of N m/s).
    collisions = [
        _features(
            rng.uniform(300, 3000), rng.uniform(1, 4), rng.uniform(0, 0.5), rng.uniform(-2, 2)
        )
        for _ in range(n)
    ]
    features = intended + collisions
    labels = ["intended"] * n + ["collision"] * n
    fitted = InteractionClassifier().fit(features, labels)
    assert 30.0 <= fitted.cutoffs_.rise_rate <= 300.0 and fitted.converged_
    assert [fitted.decide(f).kind for f in features] == labels
    p = fitted.probability(features)
    assert np.all((p >= 0) & (p <= 1)) and p[:n].min() > 0.5 > p[n:].max()
    # The stated hf cut-off (0.3) would call many of these intended events collisions; the fit
    # moves it beyond the data.
    assert fitted.cutoffs_.hf_fraction > 0.5
    assert (
        fitted.active_cutoffs is fitted.cutoffs_
        and InteractionClassifier().active_cutoffs == Cutoffs()
    )


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda c: c.fit([_features()], ["intended"]), InputValueError, "both intended and"),
        (lambda c: c.fit([_features()], ["intended", "collision"]), DimensionError, "labels"),
        (
            lambda c: c.fit([_features(), _features()], ["intended", "bump"]),
            UnknownNameError,
            "unknown labels",
        ),
        (lambda c: c.probability([_features()]), NotFittedError, "fit first"),
        (lambda c: c.decide("features"), InputTypeError, "EventFeatures"),
        (lambda c: c.initial_state(0.2), InputValueError, "Nyquist"),
        (lambda c: InteractionClassifier(window=0.0), InputValueError, "window"),
        (lambda c: InteractionClassifier(cutoffs=3), InputTypeError, "Cutoffs"),
        (lambda c: Cutoffs(rise_rate=-1.0), InputValueError, "rise_rate"),
        (lambda c: Cutoffs(mean_power=math.inf), InputValueError, "mean_power"),
    ],
)
def test_classifier_arguments_are_checked(call, error, match) -> None:
    with pytest.raises(error, match=match):
        call(InteractionClassifier())


def test_features_of_chunks_equal_features_of_the_whole() -> None:
    rng = np.random.default_rng(0)
    n, dt = 700, 1e-3
    t = np.arange(n) * dt
    residual = np.cumsum(rng.standard_normal((n, 3)), axis=0) * 0.05
    velocity = rng.standard_normal((n, 3))
    design = features_module._design(3.0, 0.02, dt)
    whole = features_module._open(design, 0.0, residual[0])
    whole = features_module._update(design, whole, t, residual, velocity)
    parts = features_module._open(design, 0.0, residual[0])
    for chunk in np.array_split(np.arange(n), [1, 2, 13, 20, 21, 400]):
        parts = features_module._update(design, parts, t[chunk], residual[chunk], velocity[chunk])
    a, b = features_module._features(whole, design.lag), features_module._features(parts, 20)
    for name in ("rise_rate", "hf_fraction", "mean_power", "peak_change", "duration"):
        assert getattr(a, name) == pytest.approx(getattr(b, name), rel=1e-12), name
    # Against a second computation: the power by a plain mean, the HF share by scipy's sosfilt
    # of the whole change, the rise rate by differences 20 samples apart.
    from scipy import signal as sps

    change = residual - residual[0]
    high = sps.sosfilt(sps.butter(2, 3.0, "highpass", fs=1 / dt, output="sos"), change, axis=0)
    assert a.mean_power == pytest.approx(np.mean(np.sum(residual * velocity, axis=1)))
    assert a.hf_fraction == pytest.approx(np.sum(high**2) / np.sum(change**2))
    e = np.linalg.norm(change, axis=1)
    assert a.rise_rate == pytest.approx(np.max((e[20:] - e[:-20]) / (t[20:] - t[:-20])))


# ----------------------------------------------------------------------------- simulated


@pytest.fixture(scope="module")
def exact():
    """Panda with the true model at 500 Hz, tuned on one collision-free run."""
    # 500 Hz: a contact costs the simulator a point Jacobian per sample, and the guiding
    # hands last seconds.
    scenario = load_scenario("panda-gaz").with_exact_model().with_duration(7.0)
    scenario = scenario.with_sample_rate(500.0)
    free = scenario.run(seed=11, collisions=False).log
    nominal = scenario.nominal()
    threshold, settings = tune([free], nominal, "time-variant", folds=None)
    return scenario, nominal, threshold, settings


def _along(robot, trajectory, link, point, t, sense):
    q, qd, _ = trajectory.evaluate(np.array([t]))
    velocity = robot.point_jacobian(q, link, point)[0, :3] @ qd[0]
    return sense * velocity / np.linalg.norm(velocity)


@pytest.fixture(scope="module")
def clear_cut(exact):
    """A 2 s guiding push along the motion at 1 s and a 50 ms impact against it at 5.5 s."""
    scenario, nominal, threshold, settings = exact
    kwargs = scenario.build(seed=16, collisions=False)
    robot, trajectory = kwargs["plant"].robot, kwargs["trajectory"]
    point = np.array([0.0, 0.0, 0.05])
    contacts = ContactSet(
        [
            Contact(
                1,
                6,
                point,
                _along(robot, trajectory, 6, point, 1.0, 1.0),
                GuidingHand(1.0, 0.6, 0.8, 0.6, 25.0),
            ),
            Contact(
                2,
                6,
                point,
                _along(robot, trajectory, 6, point, 5.5, -1.0),
                Impact(5.5, 0.01, 0.05, 80.0),
            ),
        ]
    )
    kwargs["contacts"] = contacts
    kwargs["metadata"]["collisions"] = contacts.summaries()
    log = simulate(**kwargs).log
    run = CollisionMonitor(nominal, threshold, settings).process(log)
    return log, run


def test_a_guiding_push_is_intended_and_an_impact_a_collision(clear_cut) -> None:
    log, run = clear_cut
    classes = classify_events(run.events, run.signals)
    evaluation = evaluate_classification(classes, log)
    by_window = dict(zip(evaluation.records["window"], evaluation.records["assigned"], strict=True))
    assert by_window == {1: "intended", 2: "collision"}, classifications_to_pandas(classes)
    assert evaluation.accuracy == 1.0 and evaluation.n_false_alarms == 0


def _stream(classifier, threshold, signals):
    detector = Detector(threshold, min_duration=0.005, hold=0.05)
    state, mine = detector.initial_state(signals.dt), classifier.initial_state(signals.dt)
    events, out = [], []
    for k in range(signals.n_samples):
        verdict, state = detector.step(
            state,
            signals.residual[k],
            signals.model_torque[k],
            signals.friction[k],
            signals.sign[k],
            signals.velocity[k],
            signals.t[k],
        )
        found, mine = classifier.step(mine, verdict, state, signals.velocity[k])
        if verdict.event is not None:
            events.append(verdict.event)
        if found is not None:
            out.append(found)
    last, state = detector.finish(state)
    found = classifier.finish(mine, last)
    if last is not None:
        events.append(last)
    if found is not None:
        out.append(found)
    return events, out


def test_the_stream_gives_the_batch_classes(exact, clear_cut) -> None:
    _, nominal, threshold, settings = exact
    log, _ = clear_cut
    signals = settings.observe(log, nominal)
    classifier = InteractionClassifier()
    events, out = _stream(classifier, threshold, signals)
    assert events == Detector(threshold, min_duration=0.005, hold=0.05).detect(signals)
    final = [c for c in out if not c.provisional]
    batch = classify_events(events, signals, classifier)
    assert [c.event for c in final] == events and len(events) >= 2
    for streamed, recorded in zip(final, batch, strict=True):
        assert streamed.kind == recorded.kind and streamed.failed == recorded.failed
        for name, value in recorded.features.as_dict().items():
            assert getattr(streamed.features, name) == pytest.approx(value, rel=1e-12), name
    provisional = {c.features.start: c for c in out if c.provisional}
    early = classify_events(events, signals, classifier, provisional=True)
    long_events = [e for e in events if e.duration >= classifier.window]
    assert {e.start for e in long_events} <= set(provisional) and long_events
    # A shorter event gets one only while the detector's hold (0.05 s) still keeps it open.
    for event in events:
        if event.start in provisional and event.duration < classifier.window:
            assert event.end + 0.05 >= event.start + classifier.window
    for event, recorded in zip(events, early, strict=True):
        if event.duration >= classifier.window:
            streamed = provisional[event.start]
            assert streamed.kind == recorded.kind
            assert streamed.features.end == recorded.features.end
            elapsed = streamed.features.end - event.start
            assert classifier.window - 1e-9 <= elapsed < classifier.window + signals.dt


def test_on_a_seeded_mixed_set_the_classes_beat_a_coin(exact) -> None:
    scenario, nominal, threshold, settings = exact
    monitor = CollisionMonitor(nominal, threshold, settings)
    evaluations = []
    for seed in (1, 2):
        log = simulate_interactions(scenario.with_duration(20.0), 6, seed=seed).log
        run = monitor.process(log)
        evaluations.append(evaluate_classification(classify_events(run.events, run.signals), log))
    pooled = ClassificationEvaluation.pooled(evaluations)
    n = len(pooled.matched)
    # A coin is right with probability 1/2; the one-sided 5 % binomial margin over n events.
    margin = 1.645 * math.sqrt(0.25 / n)
    print(
        f"\nmixed set, exact model: {n} classified events, accuracy {pooled.accuracy:.3f} "
        f"(coin + margin {0.5 + margin:.3f})\n{pooled.confusion}"
    )
    assert n >= 10
    assert pooled.accuracy > 0.5 + margin
    # The confusion table recounts the records.
    matched = pooled.matched
    for true in ("intended", "collision"):
        for assigned in ("intended", "collision"):
            count = int(((matched["true"] == true) & (matched["assigned"] == assigned)).sum())
            assert pooled.confusion.loc[true, assigned] == count
    assert pooled.accuracy == pytest.approx(np.trace(pooled.confusion.to_numpy()) / n)
    table = classification_table({"exact": pooled})
    assert table.loc["exact", "n_classified"] == n
    assert table.loc["exact", "accuracy"] == pytest.approx(pooled.accuracy)


# ----------------------------------------------------------------------------- scoring


def test_false_alarms_stay_out_of_the_confusion_table() -> None:
    t = np.arange(0, 10, 0.01)
    entries = [
        {"id": 1, "start": 1.0, "end": 3.0, "kind": "intended"},
        {"id": 2, "start": 5.0, "end": 5.05, "kind": "collision"},
    ]
    log = Log(t=t, q=np.zeros((t.size, 1)), metadata={"collisions": entries})
    f = _features()

    def item(start, end, kind):
        return Classification(
            kind,
            f,
            () if kind == "intended" else ("duration",),
            False,
            Event(start, end, (1,), 1.0, 1.0),
        )

    classes = [item(1.1, 2.9, "intended"), item(5.01, 5.2, "intended"), item(8.0, 8.1, "collision")]
    evaluation = evaluate_classification(classes, log)
    assert evaluation.n_false_alarms == 1 and len(evaluation.matched) == 2
    assert evaluation.confusion.to_dict() == {
        "intended": {"intended": 1, "collision": 1},
        "collision": {"intended": 0, "collision": 0},
    }
    assert evaluation.accuracy == 0.5 and evaluation.n_windows == 2
    assert list(evaluation.to_pandas()["true"]) == ["intended", "collision", "none"]
    with pytest.raises(InputTypeError, match="classifications\\[0\\]"):
        evaluate_classification(["x"], log)
    with pytest.raises(InputValueError, match="at least one"):
        ClassificationEvaluation.pooled([])
    empty = evaluate_classification([], log)
    assert math.isnan(empty.accuracy) and isinstance(
        classification_table({"m": empty}), pd.DataFrame
    )


def test_an_event_outside_the_signals_is_named() -> None:
    t = np.arange(10) * 1e-3
    zeros = np.zeros((10, 2))
    signals = ObserverSignals(t, zeros, zeros, zeros, zeros, zeros, 20.0)
    with pytest.raises(InputValueError, match="no finite sample"):
        classify_events([Event(5.0, 6.0, (1,), 1.0, 1.0)], signals)


def test_a_velocity_of_the_wrong_shape_is_an_error(exact) -> None:
    _, _, threshold, _ = exact
    detector = Detector(threshold)
    state = detector.initial_state(1e-3)
    n = threshold.n_dof_
    verdict, state = detector.step(
        state, np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), 0.0
    )
    classifier = InteractionClassifier()
    with pytest.raises(DimensionError, match="velocity"):
        classifier.step(classifier.initial_state(1e-3), verdict, state, np.zeros(n + 1))


@pytest.mark.parametrize("module", [interaction_profiles, interactions, classifier_module])
def test_doctests(module) -> None:
    assert doctest.testmod(module).failed == 0
