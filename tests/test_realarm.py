"""The real-arm recipe (sensorless.realarm) on synthetic recordings with a known push.

The recordings are made up, so that the recipe is checked without the real
UR10 files: a planar two-link arm swings with a known Coulomb + viscous
friction, a known torque offset and seeded noise; the held-out recording
carries a known external torque pulse inside its "apparent contact".
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import (
    DimensionError,
    InputTypeError,
    InputValueError,
    UnknownNameError,
)
from sensorless.friction import CoulombViscous
from sensorless.io import Log
from sensorless.monitor import poisson_interval
from sensorless.realarm import Fold, Recording, evaluate_folds

FRICTION = CoulombViscous([1.5, 0.8], [-1.2, -0.6], [2.0, 1.0])
OFFSET = np.array([0.7, -0.4])
PUSH = (6.0, 6.5)
"""Span [s] of the external torque pulse of the held-out recording."""


@pytest.fixture(scope="module")
def robot() -> sl.RobotModel:
    return sl.robots.load("planar2")


def swinging(robot: sl.RobotModel, seed: int, push: float = 0.0, seconds: float = 10.0) -> Log:
    """q = a sin(w t) per joint; τ_m = model + friction + offset + noise (+ push in PUSH)."""
    t = np.arange(0.0, seconds, 0.01)
    phase = np.random.default_rng(seed).uniform(0.0, np.pi, 2)
    amplitude, omega = np.array([0.8, 0.6]), np.array([1.1, 1.7])
    angle = omega * t[:, None] + phase
    q = amplitude * np.sin(angle)
    qd = amplitude * omega * np.cos(angle)
    qdd = -amplitude * omega**2 * np.sin(angle)
    tau = robot.inverse_dynamics(q, qd, qdd) + FRICTION.torque(qd) + OFFSET
    tau += 0.02 * np.random.default_rng(seed + 100).standard_normal(tau.shape)
    # An external torque the motor answers: the observer sees it in τ_m.
    tau[(t >= PUSH[0]) & (t < PUSH[1])] += push
    return Log(t, q, qd=qd, tau_m=tau)


def test_recording_parts_pieces_and_labels() -> None:
    t = np.arange(0.0, 10.0, 0.01)
    log = Log(t, np.zeros((t.size, 1)), qd=np.zeros((t.size, 1)), tau_m=np.zeros((t.size, 1)))
    recording = Recording("r.csv", log, [(6.0, 6.5), (2.0, 3.0)])
    assert recording.contacts == ((2.0, 3.0), (6.0, 6.5))  # sorted
    pieces = recording.clean_pieces(min_piece=1.0)
    assert [(p.t[0], round(p.t[-1], 2)) for p in pieces] == [(0.0, 1.99), (3.0, 5.99), (6.5, 9.99)]
    # [6.5, 10) lasts 3.5 s (to the end of its last sample), [3, 6) 3 s.
    assert [p.t[0] for p in recording.clean_pieces(min_piece=3.2)] == [6.5]
    second = recording.part(5.0, None, "end")
    assert second.name == "r.csv end" and second.contacts == ((6.0, 6.5),)
    windows = recording.labelled().metadata["collisions"]
    assert windows == [{"id": 1, "start": 2.0, "end": 3.0}, {"id": 2, "start": 6.0, "end": 6.5}]
    with pytest.raises(InputValueError, match=r"contacts\[1\] must have start < stop \[s\]"):
        Recording("r", log, [(1.0, 2.0), (3.0, 2.0)])
    with pytest.raises(DimensionError, match=r"contacts must be \(start, stop\) pairs"):
        Recording("r", log, [(1.0, 2.0, 3.0)])
    with pytest.raises(InputValueError, match="contacts must be finite"):
        Recording("r", log, [(1.0, math.nan)])
    with pytest.raises(InputTypeError, match="log must be a Log"):
        Recording("r", t, ())  # type: ignore[arg-type]


def test_held_out_evaluation_finds_the_push_and_counts_the_rest(robot: sl.RobotModel) -> None:
    train = Recording("train", swinging(robot, seed=1, seconds=20.0))
    test = Recording("test", swinging(robot, seed=2, push=8.0), [PUSH])
    evaluation = evaluate_folds([Fold((train,), (train,), (test,))], robot)
    (fold,) = evaluation.folds
    # The correction is that of the generating model (the swing never rests: o sits in C±).
    friction = fold.correction.friction
    np.testing.assert_allclose(friction.c_pos, FRICTION.c_pos + OFFSET, atol=0.05)
    np.testing.assert_allclose(friction.c_neg, FRICTION.c_neg + OFFSET, atol=0.05)
    np.testing.assert_allclose(friction.fv, FRICTION.fv, rtol=0.05)
    (run,) = fold.held_out
    table = evaluation.summary()
    assert list(table.index) == ["constant", "time-variant", "velocity"]
    for family, row in table.iterrows():
        # Every family sees the 8 N m push, 400 times the noise.
        assert row["at contacts"] >= 1, family
        assert any(e.start >= PUSH[0] for e in run.events[family])
        # Judged: 10 s less the 0.25 s settling, the push and the scoring's delay after it.
        assert 8.5 < row["held-out [s]"] < 10.0 - 0.25 - (PUSH[1] - PUSH[0])
        alarms, hours = int(row["false alarms"]), row["held-out [s]"] / 3600.0
        assert row["per hour"] == pytest.approx(alarms / hours)
        assert (row["95 % low"], row["95 % high"]) == pytest.approx(poisson_interval(alarms, hours))
        assert math.isfinite(row["tune expects, fold 1 [1/h]"])
    lower, upper = run.bounds["constant"]
    assert (lower < 0).all() and (upper > 0).all()


def test_evaluate_folds_refuses_what_it_cannot_run(robot: sl.RobotModel) -> None:
    recording = Recording("r", swinging(robot, seed=3, seconds=3.0))
    fold = Fold((recording,), (recording,), (recording,))
    with pytest.raises(InputValueError, match="needs at least one fold"):
        evaluate_folds([], robot)
    with pytest.raises(UnknownNameError, match="'model' watches the acceleration residual"):
        evaluate_folds([fold], robot, families=("constant", "model"))
    with pytest.raises(UnknownNameError, match="'foo' is no threshold family"):
        evaluate_folds([fold], robot, families=("foo",))
    with pytest.raises(InputValueError, match=r"folds\[0\] needs identification, tuning and held"):
        evaluate_folds([Fold((recording,), (recording,), ())], robot)
    with pytest.raises(InputTypeError, match=r"folds\[0\] must be a Fold"):
        evaluate_folds([(recording,)], robot)  # type: ignore[list-item]
    with pytest.raises(InputValueError, match="margin_fraction must be a finite number >= 0"):
        evaluate_folds([fold], robot, margin_fraction=-0.1)
