"""Tests of :mod:`sensorless.evaluation.isolation` and :func:`sensorless.plots.plot_isolation`.

The true force recovered from a simulated log's τ_c must be the contact's
own profile (a second computation of the same ground truth); with the true
model, the evaluation of the isolator's estimates must show the right link,
a point within millimetres and a force within the observer's lag.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from matplotlib.figure import Figure

import sensorless as sl
from sensorless.evaluation import evaluate_isolation
from sensorless.evaluation.isolation import COLUMNS, true_contacts, true_force
from sensorless.exceptions import InputValueError, LogFormatError
from sensorless.io import Log
from sensorless.isolation import Isolator
from sensorless.observers import observe
from sensorless.plots import plot_isolation
from sensorless.signals import Event
from sensorless.simulation.collisions import Contact, ContactSet, HalfSine, Push
from sensorless.simulation.controllers import ComputedTorque
from sensorless.simulation.plants import RigidPlant
from sensorless.simulation.simulator import simulate
from sensorless.trajectories.quintic import QuinticViaPoints

K_I = 50.0


def _contact(robot, isolator, ident, link, index, profile, q0) -> Contact:
    """A force into link's capsule at candidate ``index``, tilted: joint ``link`` feels it."""
    point = isolator.surfaces[link].points[index]
    normal = isolator.surfaces[link].normals[index]
    side = np.cross([0.0, 0.0, 1.0], normal)
    side /= np.linalg.norm(side)
    direction = robot.link_pose(q0, link)[:3, :3] @ (-math.cos(0.5) * normal + math.sin(0.5) * side)
    return Contact(ident, link, point, direction, profile)


@pytest.fixture(scope="module")
def run():
    robot = sl.robots.load("panda")
    isolator = Isolator(robot)
    q0 = np.array([0.2, -0.4, 0.3, -1.8, 0.4, 1.6, 0.5])
    contacts = ContactSet(
        [
            _contact(robot, isolator, 1, 7, 60, Push(0.4, 0.15, 0.4, 0.15, 40.0), q0),
            _contact(robot, isolator, 2, 6, 150, HalfSine(1.6, 0.3, 30.0), q0),
        ]
    )
    log = simulate(
        RigidPlant(robot, friction=None),
        ComputedTorque(kp=80.0**2, ki=0.0, kd=160.0, model=robot, friction_compensation=False),
        QuinticViaPoints([0.0, 2.3], [q0, q0]),
        2.3,
        contacts=contacts,
    ).log
    signals = observe(log, robot, gain=K_I, velocity="true", friction=None)
    half = np.full(7, 0.3)
    bounds = (np.tile(-half, (log.n_samples, 1)), np.tile(half, (log.n_samples, 1)))
    events = []
    for contact in contacts:  # one event per contact, as a detector with a hold would give
        rows = (log.t >= contact.start) & (log.t <= contact.end + 0.2)
        outside = rows[:, None] & ((signals.residual > half) | (signals.residual < -half))
        k = np.flatnonzero(outside.any(axis=1))
        events.append(Event(float(log.t[k[0]]), float(log.t[k[-1]]), (7,), 1.0, 1.0))
    events.append(Event(2.2, 2.25, (1,), 0.1, 0.1))  # a false alarm, on the free arm
    r = signals.residual.copy()
    r[(log.t >= 2.2) & (log.t <= 2.25), 0] += 1.0  # ... that crosses joint 1's band
    estimates = isolator.isolate_events(events, log.t, log.q, r, bounds)
    series = [isolator.force_series(e, log.t, log.q, r, bounds) for e in estimates]
    return robot, contacts, log, estimates, series


def test_true_force_is_the_contact_profile(run) -> None:
    robot, contacts, log, _, _ = run
    found = true_contacts(log)
    assert sorted(found) == [1, 2]
    for contact in contacts:
        force = true_force(log, robot, found[contact.id])
        rows = log.collision_id == contact.id
        np.testing.assert_allclose(force[rows], contact.force(log.t[rows]), atol=1e-9 * 40.0)
        assert not force[~rows].any()


def test_true_model_evaluation(run) -> None:
    """Right link, a point within 3 mm, the force within the lag (1 % against the filtered force).

    The tolerances are those of ``tests/test_isolation.py::test_true_model_push_is_isolated``:
    at the peak of the residual, what is left of |F̂| − |K_I/(s+K_I) F| is the
    sample-and-hold of τ_c (< 1 %).
    """
    robot, _, log, estimates, series = run
    evaluation = evaluate_isolation(estimates, log, robot, series=series, gain=K_I, max_delay=0.2)
    table = evaluation.to_pandas()
    assert list(table.columns) == list(COLUMNS)
    assert table["id"].tolist() == [1, 2, 0]
    matched = table[table["id"] > 0]
    assert matched["link_ok"].all()
    assert (matched["point_error"] <= 0.003).all()
    assert (matched["line_distance"] <= matched["point_error"] + 1e-12).all()
    assert (matched["magnitude_error_filtered"].abs() <= 0.01).all()
    assert (matched["direction_error"] <= 0.02).all()
    assert matched["within_bound"].all()  # a ±0.3 N m band bounds F̂ − K_I/(s+K_I) F
    # A first-order lag peaks where it meets its input (ṙ = K_I (τ − r) = 0): at the
    # residual's peak the estimate is the force of that instant, below the impact's peak.
    assert abs(table.loc[1, "magnitude_error"]) <= 0.01
    assert table.loc[1, "force_estimated"] < 30.0 * (1.0 - 0.01)
    false_alarm = table.iloc[2]
    assert false_alarm["link_true"] == 0 and math.isnan(false_alarm["magnitude_error"])
    summary = evaluation.summary()
    assert summary["n_events"] == 3 and summary["n_matched"] == 2 and summary["link_rate"] == 1.0
    assert summary["bound_coverage"] == 1.0
    assert len(evaluation.forces) == 3 and evaluation.forces[2].id == 0
    first = evaluation.forces[0]
    assert first.filtered is not None and first.t.shape == (first.estimated.shape[0],)


def test_plot_isolation(run) -> None:
    robot, _, log, estimates, series = run
    evaluation = evaluate_isolation(estimates, log, robot, series=series, gain=K_I, max_delay=0.2)
    figure = plot_isolation(evaluation)
    assert isinstance(figure, Figure)
    titles = [ax.get_title(loc="left") for ax in figure.axes]
    assert titles[0].startswith("collision 1: link 7 (true 7)")
    assert titles[2].startswith("false alarm")
    assert len(plot_isolation(evaluation, max_events=1).axes) == 1
    with pytest.raises(InputValueError, match="no force series"):
        plot_isolation(evaluate_isolation(estimates, log, robot))
    with pytest.raises(InputValueError, match="max_events"):
        plot_isolation(evaluation, max_events=0)


def test_logs_without_the_ground_truth_are_refused(run) -> None:
    robot, _, log, _, _ = run
    entry = dict(log.metadata["collisions"][0])
    del entry["direction"]
    bare = Log(t=log.t, q=log.q, metadata={"collisions": [entry]})
    with pytest.raises(LogFormatError, match="lacks"):
        true_contacts(bare)
    with pytest.raises(LogFormatError, match="tau_c, q_true and collision_id"):
        true_force(Log(t=log.t, q=log.q), robot, true_contacts(log)[1])
