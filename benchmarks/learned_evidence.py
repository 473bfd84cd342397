"""Learned vs time-variant vs oracle on held-out ``panda-gaz`` runs (issue 20, deliverable 4).

Runs of the ``panda-gaz`` scenario whose seeds the shipped Panda weights never
saw (checked: the training runs' seeds are recomputed from the weights'
recipe): ``N_FIT`` collision-free runs to fit on, and, to test on,
``N_COLLISION`` runs with contacts and ``N_FREE`` more collision-free runs,
``SECONDS`` s each. Three detectors, each the way a user builds it:

- ``learned``: :class:`~sensorless.thresholds.LearnedThreshold` with the
  shipped ``panda`` weights, level fitted on the fit runs;
- ``time-variant``: :func:`~sensorless.monitor.tune` on the same runs;
- ``oracle``: the time-variant threshold on the same logs observed with the
  exact model (:meth:`Scenario.with_exact_model`).

All use the default observer (motor torques, K_I = 20 1/s), the settling
time of :class:`~sensorless.monitor.ObserverSettings` as transient, and the
margin :func:`tune` gives by default (10 % of the constant band β_j of the
fit runs, in N m, the same for both model-error detectors). Events come from
:class:`~sensorless.monitor.CollisionMonitor` (its default min_duration and
hold), and are scored by :func:`sensorless.evaluation.evaluate`. Printed:
contacts detected / total, false alarms per hour over all test runs with a
Poisson 95 % interval (chi-square), and the median start delay.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/learned_evidence.py`` (~1 min);
``--weights`` takes another weights file than the shipped ``panda`` (e.g. a
copy of older weights, to compare in the same conditions); ``--case`` picks
the section (heldout, unseen, rate and cross each took under 2 min on one core):

- ``heldout`` (default): the comparison above;
- ``unseen``: a payload on the true Panda's end link, ``--payload-mass`` kg
  (default 2) at ``PAYLOAD_COM``, fit and test runs both carrying it (a user
  fits on the arm as it is). Weights trained with payloads (a recipe with
  ``payload_share`` > 0, e.g. ``train-detector --payload-max 3``; the shipped
  weights have none) have seen such payloads in kind; the table's title says
  whether the mass lies inside the training range;
- ``rate``: the held-out comparison at ``--rate`` Hz (default 900), a rate
  inside the weights' trained band of periods but not one a training run
  had (the nearest is printed), and the refusal of a log outside the band
  (``OUTSIDE_RATES``): the message :class:`LearnedThreshold` gives. Weights
  trained at one period only refuse ``--rate`` itself: the table then has no
  learned rows;
- ``cross``: the ``puma560-thesis`` scenario judged with the Panda's weights.
  The network's convolutions and head are shared by all joints; what is per
  joint is the first layer's bias and the input and output normalisation
  ((4, n_dof) and (n_dof,)). So the Panda's weights apply to the 6-joint
  PUMA once each PUMA joint j takes the Panda joint j's bias (joint 7's is
  dropped), and the normalisation is either the Panda's own or re-estimated
  on the PUMA's fit runs (mean and spread of the four inputs and of r̂, as
  training does); the puma560 weights (``--puma-weights``, default the
  shipped ones) and the time-variant threshold on the same runs are the
  references;
- ``lwr4``: the ``lwr4-thesis`` scenario (flexible joints, joints 1–3
  monitored) with the shipped ``lwr4`` weights (``--lwr4-weights``);
- ``oracle``: why the time-variant threshold on the exact model raises more
  false alarms than on the nominal one: its band, where its alarms fall,
  and how far the test runs' residual exceeds the fit runs'.

Every table has a row ``either (learned or time-variant)``: one alarm when
either detector's monitor raises one (overlapping events merged), each
tuned as above.
"""

from __future__ import annotations

import argparse
import copy
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import chi2

from sensorless.evaluation import evaluate
from sensorless.exceptions import InputValueError
from sensorless.io import Log
from sensorless.learning import TrainingRecipe, run_draws
from sensorless.monitor import CollisionMonitor, ObserverSettings, tune
from sensorless.monitor.tuning import DEFAULT_MARGIN_FRACTION
from sensorless.robots.model import RobotModel
from sensorless.signals import Event, ObserverSignals
from sensorless.simulation.scenario import Scenario, load_scenario
from sensorless.thresholds import (
    ConstantThreshold,
    LearnedThreshold,
    LearnedWeights,
    Threshold,
    load_weights,
    save_weights,
)
from sensorless.thresholds._cnn import CHANNELS, Network

SCENARIO, SECONDS = "panda-gaz", 30.0
N_FIT, N_COLLISION, N_FREE = 2, 6, 4
FIRST_SEED = 9001
PAYLOAD_COM = [0.0, 0.0, 0.1]
"""Centre of mass of the ``unseen`` case's payload: 10 cm out along the flange axis [m]."""
OUTSIDE_RATES = (700.0, 1400.0)
"""Rates [Hz] outside the shipped Panda weights' band (800 to 1250 Hz): refused."""


def training_recipe(weights: str) -> TrainingRecipe:
    """The recipe of the weights' training (fields of later recipes take their defaults)."""
    recipe_info = load_weights(weights).recipe
    fields = TrainingRecipe.__dataclass_fields__
    return TrainingRecipe(**{k: v for k, v in recipe_info.items() if k in fields})


def training_seeds(weights: str) -> set[int]:
    """The scenario seeds of the weights' training runs (recomputed, nothing simulated).

    The scenario seed is drawn before the payload and the rate, so weights
    trained before those were randomised recompute theirs the same way.
    """
    return {int(drawn["seed"]) for drawn in run_draws(training_recipe(weights))}


def poisson_interval(count: int, hours: float) -> tuple[float, float]:
    """Exact (Garwood) 95 % interval of a Poisson rate [1/h]."""
    low = 0.0 if count == 0 else chi2.ppf(0.025, 2 * count) / 2.0
    high = chi2.ppf(0.975, 2 * count + 2) / 2.0
    return low / hours, high / hours


def _merged(first: list[Event], second: list[Event]) -> list[Event]:
    """One alarm per overlap of the two detectors' events (either fires)."""
    merged: list[Event] = []
    for event in sorted([*first, *second], key=lambda e: e.start):
        if merged and event.start <= merged[-1].end:
            last = merged[-1]
            merged[-1] = replace(
                last,
                end=max(last.end, event.end),
                joints=tuple(sorted(set(last.joints) | set(event.joints))),
                peak=max(last.peak, event.peak),
            )
        else:
            merged.append(event)
    return merged


def _row(name: str, results: list[Any]) -> dict[str, Any]:
    detected = sum(r.n_detected for r in results)
    total = sum(len(r.windows) for r in results)
    alarms = sum(len(r.false_alarms) for r in results)
    hours = sum(r.duration for r in results) / 3600.0
    delays = []
    for r in results:
        rows = r.per_collision
        delays.extend(rows.loc[rows["detected"], "start_delay"].tolist())
    low, high = poisson_interval(alarms, hours)
    return {
        "detector": name,
        "detected": f"{detected}/{total}",
        "false alarms": alarms,
        "per hour": alarms / hours,
        "95 % interval": f"[{low:.0f}, {high:.0f}]",
        "median delay [ms]": 1e3 * float(np.median(delays)) if delays else float("nan"),
        "hours": hours,
    }


def events_of(
    robot: RobotModel, threshold: Threshold, settings: ObserverSettings, tests: list[Log]
) -> list[list[Event]]:
    """The monitor's events on every test log."""
    monitor = CollisionMonitor(robot, threshold, settings)
    return [monitor.run(log)[1] for log in tests]


def score(name: str, events: list[list[Event]], tests: list[Log]) -> dict[str, Any]:
    """Pooled detection, false alarms and delays of one detector's events on the test logs."""
    return _row(name, [evaluate(e, log, method=name) for e, log in zip(events, tests, strict=True)])


def print_table(rows: list[dict[str, Any]]) -> None:
    header = (
        f"{'detector':52s} {'detected':>9s} {'false alarms':>12s} {'per hour':>9s} "
        f"{'95 % interval':>14s} {'median delay [ms]':>18s}"
    )
    print(header)
    for row in rows:
        print(
            f"{row['detector']:52s} {row['detected']:>9s} {row['false alarms']:>12d} "
            f"{row['per hour']:>9.0f} {row['95 % interval']:>14s} "
            f"{row['median delay [ms]']:>18.1f}"
        )


def simulate(scenario: Scenario, weights: str) -> tuple[list[int], list[Log], list[Log], list[Log]]:
    """Seeds and logs to fit on, with contacts and without, none of them a training seed."""
    n_runs = N_FIT + N_COLLISION + N_FREE
    seeds = list(range(FIRST_SEED, FIRST_SEED + n_runs))
    overlap = set(seeds) & training_seeds(weights)
    if overlap:
        raise SystemExit(f"seeds {sorted(overlap)} were used in training: pick others")
    fit_logs = [scenario.run(seed=s, collisions=False).log for s in seeds[:N_FIT]]
    collision_logs = [scenario.run(seed=s).log for s in seeds[N_FIT : N_FIT + N_COLLISION]]
    free_logs = [scenario.run(seed=s, collisions=False).log for s in seeds[N_FIT + N_COLLISION :]]
    return seeds, fit_logs, collision_logs, free_logs


def transferred(
    source: str, fit: list[ObserverSignals], renormalise: bool, *, rate_of_fit: bool = False
) -> Path:
    """Weights file of ``source``'s network for the robot of ``fit`` (see ``--case cross``).

    ``rate_of_fit``: declare the fit runs' sample period and observer gain
    (the network then spans 51 of their samples, ``--case ur10``).
    """
    weights = load_weights(source)
    net, n_dof = weights.network, fit[0].n_dof
    pick = np.minimum(np.arange(n_dof), net.n_dof - 1)  # joint j takes joint j's (the last's)
    biases = (net.biases[0][:, pick], *net.biases[1:])
    normalisation = {
        "input_mean": net.input_mean[:, pick],
        "input_scale": net.input_scale[:, pick],
        "output_mean": net.output_mean[pick],
        "output_scale": net.output_scale[pick],
    }
    if renormalise:  # as training does, on the target's collision-free runs
        x = np.concatenate([np.stack([getattr(r, c) for c in CHANNELS], axis=1) for r in fit])
        residual = np.concatenate([r.residual for r in fit])
        normalisation = {
            "input_mean": x.mean(axis=0),
            "input_scale": np.maximum(x.std(axis=0), 1e-3),
            "output_mean": residual.mean(axis=0),
            "output_scale": np.maximum(residual.std(axis=0), 1e-3),
        }
    network = Network(
        net.kernels,
        biases,
        net.head,
        net.head_bias,
        net.dilations,
        input_mean=np.asarray(normalisation["input_mean"]),
        input_scale=np.asarray(normalisation["input_scale"]),
        output_mean=np.asarray(normalisation["output_mean"]),
        output_scale=np.asarray(normalisation["output_scale"]),
        floor=net.floor,
    )
    robot = fit[0].robot.split(" (")[0]
    folder = Path(tempfile.mkdtemp())
    recipe = {"transferred_from": source, "renormalised": renormalise}
    dt, gain, band = weights.dt, weights.gain, weights.period_range
    if rate_of_fit:
        dt, gain, band = fit[0].dt, float(fit[0].gain[0]), None
    return save_weights(
        LearnedWeights(network, robot, weights.kind, gain, dt, recipe=recipe, period_range=band),
        folder / f"{Path(source).stem}-to-{robot}",
    )


def ur10_case() -> None:
    """Held-out false alarms on the real UR10 recordings, both folds pooled (``--case ur10``)."""
    from sensorless.identification import identify_correction
    from sensorless.realarm import APPARENT_CONTACTS, load_ur10, ur10_folds
    from sensorless.realarm.heldout import (
        DEFAULT_FAMILIES,
        DEFAULT_MIN_PIECE,
        Tuned,
        judge,
        tune_families,
    )
    from sensorless.robots import load

    data = Path(__file__).resolve().parents[2] / "shared" / "data" / "ur10-ext_observer"
    recordings = load_ur10(data, APPARENT_CONTACTS)
    robot = load("ur10")
    names = [*DEFAULT_FAMILIES, "learned (puma560 net, re-normalised, 100 Hz)", "either"]
    totals = {name: [0.0, 0, 0] for name in names}  # judged seconds, false alarms, at contacts
    for fold in ur10_folds(recordings):
        clean = [log for r in fold.identification for log in r.clean_pieces(DEFAULT_MIN_PIECE)]
        correction = identify_correction(clean, robot)
        model = correction.model(robot)
        pieces = [
            correction.apply(log) for r in fold.tuning for log in r.clean_pieces(DEFAULT_MIN_PIECE)
        ]
        tuned = tune_families(pieces, model, DEFAULT_FAMILIES, DEFAULT_MARGIN_FRACTION)
        base, settings = tune(pieces, model, "constant", folds=None, margin=0.0)
        signals = [settings.observe(log, model) for log in pieces]
        path = transferred("puma560", signals, renormalise=True, rate_of_fit=True)
        margin = DEFAULT_MARGIN_FRACTION * base.beta_  # type: ignore[attr-defined]
        learned, learned_settings = tune(pieces, model, "learned", margin=margin, weights=str(path))
        tuned.append(Tuned(names[-2], learned, learned_settings, float("nan")))
        for recording in fold.held_out:
            held = replace(recording, log=correction.apply(recording.log))
            found = {t.family: judge(t, model, held) for t in tuned}
            for family, (verdict, _, _) in found.items():
                totals[family][0] += verdict.seconds
                totals[family][1] += len(verdict.false_alarms)
                totals[family][2] += verdict.at_contacts
            either = _merged(found[names[-2]][1].events, found["time-variant"][1].events)
            result = evaluate(either, held.labelled(), method="either")
            totals["either"][0] += found["time-variant"][0].seconds
            totals["either"][1] += len(result.false_alarms)
            totals["either"][2] += len(either) - len(result.false_alarms)
    print(
        "UR10 recordings (ext_observer, 100 Hz), two folds pooled as in "
        "examples/ur10_real_arm.py; learned: the puma560 network (6 joints) with its "
        "normalisation re-estimated on each fold's tuning data, declared at 100 Hz"
    )
    print(
        f"{'family':48s} {'held-out s':>10s} {'false alarms':>12s} {'per hour':>9s} "
        f"{'95 % interval':>14s} {'at contacts':>11s}"
    )
    for family, (seconds, alarms, at_contacts) in totals.items():
        low, high = poisson_interval(alarms, seconds / 3600.0)
        print(
            f"{family:48s} {seconds:10.1f} {alarms:12d} {alarms / seconds * 3600:9.0f} "
            f"{f'[{low:.0f}, {high:.0f}]':>14s} {at_contacts:11d}"
        )


def compare(
    scenario: Scenario,
    fit_logs: list[Log],
    tests: list[Log],
    learned: dict[str, Any],
    oracle: bool = True,
) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """Rows of every learned variant, the time-variant threshold, the oracle and ``either``.

    ``learned`` maps a row name to the ``weights`` of a LearnedThreshold, or to a
    function of the fit signals that gives them.
    """
    nominal = scenario.nominal("motor")
    settings = ObserverSettings(kind="motor")
    fit_signals = [settings.observe(log, nominal) for log in fit_logs]
    transient = settings.settle_time(fit_signals[0].dt)
    band = ConstantThreshold(transient=transient).fit(fit_signals)
    margin = DEFAULT_MARGIN_FRACTION * band.beta_  # what tune gives by default
    time_variant, _ = tune(fit_logs, nominal, "time-variant", settings, folds=None)
    np.testing.assert_allclose(time_variant.margin, margin)  # the same margin rule
    tv_events = events_of(nominal, time_variant, settings, tests)
    rows, fitted = [], {"margin": margin, "time-variant": time_variant}
    first_learned: list[list[Event]] | None = None
    for name, weights in learned.items():
        source = weights(fit_signals) if callable(weights) else weights
        threshold = LearnedThreshold(source, margin=margin, transient=transient).fit(fit_signals)
        fitted[name] = threshold
        events = events_of(nominal, threshold, settings, tests)
        first_learned = events if first_learned is None else first_learned
        rows.append(score(name, events, tests))
    rows.append(score("time-variant", tv_events, tests))
    if oracle:
        exact = scenario.with_exact_model().nominal("motor")
        tuned, _ = tune(fit_logs, exact, "time-variant", settings, folds=None)
        fitted["oracle"] = tuned
        events = events_of(exact, tuned, settings, tests)
        fitted["oracle events"] = events
        rows.append(score("oracle (time-variant, exact model)", events, tests))
    if first_learned is not None:
        either = [_merged(a, b) for a, b in zip(first_learned, tv_events, strict=True)]
        rows.append(score(f"either ({next(iter(learned))} or time-variant)", either, tests))
    return rows, fitted


def oracle_diagnosis(scenario: Scenario, fit_logs: list[Log], free: list[Log], fitted: Any) -> None:
    """Band, alarms and residual extremes of the oracle against the nominal time-variant."""
    settings = ObserverSettings(kind="motor")
    for label, model, key in (
        ("exact", scenario.with_exact_model().nominal("motor"), "oracle"),
        ("nominal", scenario.nominal("motor"), "time-variant"),
    ):
        threshold = fitted[key]
        fit = [settings.observe(log, model) for log in fit_logs]
        test = [settings.observe(log, model) for log in free]
        skip = settings.settle_time(fit[0].dt)

        def peak(runs: list[ObserverSignals], skip: float = skip) -> Any:
            return np.max([np.abs(r.residual[r.t - r.t[0] >= skip]).max(axis=0) for r in runs], 0)

        fit_peak, test_peak = peak(fit), peak(test)
        params = {
            k: np.round(np.atleast_1d(v), 3).tolist()
            for k, v in threshold.to_dict().get("attributes", {}).items()
        }
        print(f"\n{label} model: {type(threshold).__name__} {params}")
        print(f"  max |r| on the fit runs  [N m]: {np.round(fit_peak, 3).tolist()}")
        print(f"  max |r| on the free tests [N m]: {np.round(test_peak, 3).tolist()}")
        print(f"  ratio test / fit           [-]: {np.round(test_peak / fit_peak, 2).tolist()}")
        outside = []
        for run in test:
            lower, upper = threshold.bounds(run)
            late = run.t - run.t[0] >= skip
            out = ((run.residual < lower) | (run.residual > upper)) & late[:, None]
            outside.append(out.sum(axis=0))
        print(f"  samples outside the band, free tests, per joint: {np.sum(outside, 0).tolist()}")
        events = events_of(model, threshold, settings, free)
        joints = [j for run in events for e in run for j in e.joints]
        print(
            f"  alarms on the free tests: {sum(len(e) for e in events)}, joints involved "
            f"{np.bincount(joints, minlength=threshold.n_dof_ + 1)[1:].tolist()}"
        )
        # where the alarms fall: time since the alarm joint's velocity estimate changed sign
        since, share = [], []
        for run, found in zip(test, events, strict=True):
            flips = np.diff(np.signbit(run.velocity), axis=0).astype(bool)
            for event in found:
                k = int(np.searchsorted(run.t, event.start))
                for j in event.joints:
                    before = np.flatnonzero(flips[:k, j - 1])
                    since.append(run.t[k] - run.t[before[-1] + 1] if before.size else np.inf)
            near = np.zeros(run.velocity.shape, dtype=bool)
            for j in range(run.n_dof):
                for k in np.flatnonzero(flips[:, j]):
                    near[(run.t >= run.t[k + 1]) & (run.t < run.t[k + 1] + 0.1), j] = True
            share.append(near.mean())
        if since:
            print(
                f"  alarm starts within 0.1 s after a velocity reversal of their joint: "
                f"{np.mean(np.array(since) < 0.1):.0%} (of all time and joints: "
                f"{np.mean(share):.0%}); seconds since the reversal: "
                f"{np.round(np.sort(since), 3).tolist()}"
            )


def payload_scenario(scenario: Scenario, weights: str, mass: float) -> tuple[Scenario, str]:
    """``scenario`` with a payload of ``mass`` kg on the true robot, and its title."""
    spec = copy.deepcopy(scenario.spec)
    spec["payload"] = {"mass": mass, "com": PAYLOAD_COM}
    info = load_weights(weights).recipe
    if "payload_mass" not in info or not info["payload_share"] > 0.0:
        seen = "never seen in training (weights trained without payloads)"
    else:
        low, high = info["payload_mass"]
        inside = "inside" if low <= mass <= high else "outside (never seen in training)"
        seen = f"{inside} the training range {low:g}..{high:g} kg"
    return Scenario(scenario.name, spec), f"{SCENARIO} with a payload {spec['payload']}, {seen}"


def refusals(scenario: Scenario, weights: str, rates: tuple[float, ...]) -> list[str]:
    """What fitting the learned threshold on a short collision-free run at each rate gives."""
    settings = ObserverSettings(kind="motor")
    nominal = scenario.nominal("motor")
    found = []
    for rate in rates:
        log = scenario.with_sample_rate(rate).with_duration(2.0).run(seed=FIRST_SEED).log
        try:
            LearnedThreshold(weights).fit(settings.observe(log, nominal))
            found.append(f"{rate:g} Hz: accepted")
        except InputValueError as exc:
            found.append(f"{rate:g} Hz: refused: {exc}")
    return found


def rate_title(weights: str, rate: float) -> str:
    """Where ``rate`` lies against the weights' band and the nearest rate of a training run."""
    loaded = load_weights(weights)
    band = loaded.period_range
    if band is None:
        return f"{SCENARIO} at {rate:g} Hz; weights trained at {1.0 / loaded.dt:g} Hz only"
    trained = [float(d["sample_rate"]) for d in loaded.recipe.get("drawn", [])]
    nearest = min(trained, key=lambda r: abs(r - rate)) if trained else float("nan")
    return (
        f"{SCENARIO} at {rate:g} Hz; weights trained at {1.0 / band[1]:g}..{1.0 / band[0]:g} Hz "
        f"(nearest training run: {nearest:.1f} Hz)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument(
        "--case",
        choices=["heldout", "unseen", "rate", "cross", "lwr4", "oracle", "ur10"],
        default="heldout",
    )
    parser.add_argument("--weights", default="panda", help="Panda weights: name or file")
    parser.add_argument("--puma-weights", default="puma560", help="cross: PUMA 560 weights")
    parser.add_argument("--lwr4-weights", default="lwr4", help="lwr4: LWR IV weights")
    parser.add_argument("--payload-mass", type=float, default=2.0, help="unseen: payload [kg]")
    parser.add_argument("--rate", type=float, default=900.0, help="rate: sample rate [Hz]")
    args = parser.parse_args()
    started = time.perf_counter()
    if args.case == "ur10":
        ur10_case()
        print(f"total {time.perf_counter() - started:.0f} s")
        return
    weights, name = args.weights, SCENARIO
    scenario = load_scenario(SCENARIO).with_duration(SECONDS)
    learned: dict[str, Any] = {"learned": weights}
    notes: list[str] = []
    if args.case == "unseen":
        scenario, name = payload_scenario(scenario, weights, args.payload_mass)
    if args.case == "rate":
        name = rate_title(weights, args.rate)
        notes = refusals(scenario, weights, (args.rate, *OUTSIDE_RATES))
        scenario = scenario.with_sample_rate(args.rate)
        if not notes[0].endswith("accepted"):
            learned = {}
    if args.case == "cross":
        panda, weights, name = weights, args.puma_weights, "puma560-thesis"
        scenario = load_scenario(name).with_duration(SECONDS)
        learned = {
            "learned (puma560 weights)": weights,
            "learned (panda weights, re-normalised on fit runs)": (
                lambda fit: transferred(panda, fit, renormalise=True)
            ),
            "learned (panda weights, panda normalisation)": (
                lambda fit: transferred(panda, fit, renormalise=False)
            ),
        }
    if args.case == "lwr4":
        weights, name = args.lwr4_weights, "lwr4-thesis"
        scenario = load_scenario(name).with_duration(SECONDS)
        learned = {"learned (lwr4 weights)": weights}
    seeds, fit_logs, collision_logs, free_logs = simulate(scenario, weights)
    tests = collision_logs + free_logs
    simulated = time.perf_counter() - started
    rows, fitted = compare(scenario, fit_logs, tests, learned)
    print(
        f"{name}, held-out seeds {seeds[0]}..{seeds[-1]} (none used in training): "
        f"fit on {N_FIT} collision-free runs, tested on {N_COLLISION} collision runs + "
        f"{N_FREE} collision-free runs of {SECONDS:g} s ({rows[0]['hours'] * 3600:.0f} s)"
    )
    print(f"weights: {weights}")
    for note in notes:
        print(f"learned threshold fitted at {note}")
    print(f"margin (10 % of β) [N m]: {np.round(fitted['margin'], 3).tolist()}")
    for key, threshold in fitted.items():
        if isinstance(threshold, LearnedThreshold):
            print(f"{key}: level λ [-] {np.round(threshold.level_, 2).tolist()}")
    print_table(rows)
    if args.case == "oracle":
        oracle_diagnosis(scenario, fit_logs, free_logs, fitted)
    total = time.perf_counter() - started
    print(f"simulation {simulated:.0f} s, total {total:.0f} s")


if __name__ == "__main__":
    main()
