"""Tests of :mod:`sensorless.simulation.collisions`.

Profiles are checked against closed forms (the impulse of a half sine by
numerical quadrature); joint torques against the principle of virtual work,
τ_c·δq = F·δx, with δx from finite differences of forward kinematics, which
does not use the point Jacobian.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import quad

import sensorless as sl
from sensorless.exceptions import (
    DimensionError,
    InputValueError,
    LogFormatError,
    UnknownNameError,
)
from sensorless.simulation.collisions import (
    Contact,
    ContactSet,
    HalfSine,
    Push,
    Recorded,
)


@pytest.fixture(scope="module")
def puma() -> sl.robots.RobotModel:
    return sl.robots.load("puma560")


def _contact(id_: int = 1, link: int = 3, start: float = 1.0) -> Contact:
    return Contact(id_, link, [0.1, 0.02, -0.03], [0.3, -1.0, 0.5], HalfSine(start, 0.2, 40.0))


# ---------------------------------------------------------------------- profiles
def test_half_sine_impulse_and_shape() -> None:
    profile = HalfSine(start=0.5, duration=0.3, peak=60.0)
    impulse, _ = quad(profile, profile.start, profile.end)
    assert impulse == pytest.approx(2 * 60.0 * 0.3 / math.pi, rel=1e-10)
    assert profile(0.65) == pytest.approx(60.0)
    assert profile.peak == 60.0
    assert (profile.start, profile.end) == (0.5, pytest.approx(0.8))
    assert profile(0.4) == 0.0 and profile(0.9) == 0.0
    t = np.linspace(0.0, 1.0, 11).reshape(11, 1)
    assert profile(t).shape == (11, 1)
    assert isinstance(profile(0.6), float)


def test_push_is_continuous_and_holds_peak() -> None:
    profile = Push(start=1.0, ramp=0.1, hold=0.3, release=0.2, peak=35.0)
    assert profile.end == pytest.approx(1.6)
    t = np.linspace(0.9, 1.7, 80001)  # 10 µs steps
    f = profile(t)
    # Continuity: steps no larger than the steepest slope (π peak / (2 ramp)) times dt.
    assert np.max(np.abs(np.diff(f))) <= math.pi * 35.0 / (2 * 0.1) * 1e-5 * 1.01
    hold = (t >= 1.1) & (t <= 1.4)
    np.testing.assert_allclose(f[hold], 35.0, rtol=0, atol=1e-12)
    assert profile(1.05) == pytest.approx(35.0 * (1 - math.cos(math.pi * 0.5)) / 2)
    assert profile(1.5) == pytest.approx(35.0 / 2)
    assert f.max() == pytest.approx(35.0)
    assert profile(1.0) == 0.0 and profile(1.6) == pytest.approx(0.0, abs=1e-12)


def test_recorded_from_csv_interpolates(tmp_path) -> None:
    path = tmp_path / "hand.csv"
    path.write_text("time,force\n10.0,0.0\n10.1,4.0\n10.3,-2.0\n10.4,0.0\n")
    profile = Recorded.from_csv(
        path, start=2.0, scale=2.0, time_column="time", force_column="force"
    )
    assert profile.start == 2.0 and profile.end == pytest.approx(2.4)
    assert profile.peak == pytest.approx(8.0)
    assert profile(2.05) == pytest.approx(2.0 * 2.0)
    assert profile(2.2) == pytest.approx(2.0 * 1.0)
    assert profile(2.3) == pytest.approx(-4.0)
    assert profile(1.99) == 0.0 and profile(2.41) == 0.0
    assert profile == Recorded([10.0, 10.1, 10.3, 10.4], [0, 4, -2, 0], start=2.0, scale=2.0)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("t,g\n0,1\n1,2\n", r"missing column\(s\) \['f'\]; columns found: \['t', 'g'\]"),
        ("t,f\n0,1\n0.2,2\n0.1,3\n", r"strictly increasing; sample 2 is 0.1 s after 0.2 s"),
        ("t,f\n0,1\n0.1,\n0.2,3\n", r"column 'f' must hold finite numbers; data row 2"),
        ("t,f\n0,1\n", r"one length n >= 2"),
    ],
)
def test_recorded_from_csv_errors(tmp_path, text: str, match: str) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(LogFormatError, match=match):
        Recorded.from_csv(path)


@pytest.mark.parametrize(
    ("build", "error", "match"),
    [
        (lambda: HalfSine(0.0, -0.1, 10.0), InputValueError, r"duration must be > 0"),
        (lambda: HalfSine(0.0, 0.1, float("nan")), InputValueError, r"peak must be finite"),
        (lambda: HalfSine(0.0, 0.1, -5.0), InputValueError, r"peak must be >= 0"),
        (lambda: Push(0.0, 0.0, 0.1, 0.1, 5.0), InputValueError, r"ramp must be > 0"),
        (lambda: Push(0.0, 0.1, -0.1, 0.1, 5.0), InputValueError, r"hold must be >= 0"),
        (lambda: Recorded([0, 1], [0, np.nan]), LogFormatError, r"force must be finite"),
        (lambda: Recorded([0, 1], [0, 1], scale=np.inf), InputValueError, r"scale must be"),
    ],
)
def test_profile_validation(build, error, match) -> None:
    with pytest.raises(error, match=match):
        build()


def test_profile_rejects_nan_time() -> None:
    with pytest.raises(InputValueError, match=r"t must be finite"):
        HalfSine(0.0, 1.0, 1.0)(np.nan)


# ---------------------------------------------------------------------- contacts
def test_contact_normalises_direction_and_wrench() -> None:
    contact = Contact(2, 4, [0, 0, 0.05], [0, 3.0, 4.0], HalfSine(0.0, 1.0, 10.0))
    np.testing.assert_allclose(contact.direction, [0, 0.6, 0.8])
    np.testing.assert_allclose(contact.wrench(0.5), [0, 6.0, 8.0, 0, 0, 0])
    assert contact.wrench(np.array([0.5, 2.0])).shape == (2, 6)
    assert contact.summary() == {
        "id": 2,
        "link": 4,
        "point": [0.0, 0.0, 0.05],
        "direction": [0.0, 0.6, 0.8],
        "start": 0.0,
        "end": 1.0,
        "peak": 10.0,
        "profile": "HalfSine",
        "kind": "collision",
    }


@pytest.mark.parametrize("link", [1, 3, 6])
def test_joint_torque_is_virtual_work_of_the_force(puma, link: int) -> None:
    rng = np.random.default_rng(7)
    q = rng.uniform(-1.5, 1.5, puma.n_dof)
    point = np.array([0.12, -0.04, 0.07])
    contact = Contact(1, link, point, [0.2, -0.7, 0.4], Push(0.0, 0.1, 1.0, 0.1, 55.0))
    force = contact.force(0.5)
    h = 1e-6
    expected = np.empty(puma.n_dof)
    for j in range(puma.n_dof):
        dq = np.zeros(puma.n_dof)
        dq[j] = h
        dx = puma.forward_kinematics(q + dq, link, point) - puma.forward_kinematics(
            q - dq, link, point
        )
        expected[j] = force @ dx / (2 * h)  # τ_j δq_j = F·δx
    tau = contact.joint_torque(puma, q, 0.5)
    np.testing.assert_allclose(tau, expected, atol=1e-6)
    assert np.all(tau[link:] == 0.0)  # joints beyond the link cannot feel the force
    assert np.any(tau[:link] != 0.0)


def test_joint_torque_batch_and_outside_window(puma) -> None:
    rng = np.random.default_rng(3)
    qs = rng.uniform(-1, 1, (5, puma.n_dof))
    times = np.array([0.5, 1.05, 1.1, 1.15, 2.0])
    contact = _contact(start=1.0)
    batch = contact.joint_torque(puma, qs, times)
    steps = np.array([contact.joint_torque(puma, q, t) for q, t in zip(qs, times, strict=True)])
    np.testing.assert_array_equal(batch, steps)
    assert np.all(batch[[0, 4]] == 0.0)
    contacts = ContactSet([contact, _contact(2, 5, start=1.1)])
    np.testing.assert_allclose(
        contacts.joint_torque(puma, qs, times),
        batch + contacts[1].joint_torque(puma, qs, times),
    )


def test_joint_torque_shape_errors(puma) -> None:
    with pytest.raises(DimensionError, match=r"t must be a scalar or have shape \(2,\)"):
        _contact().joint_torque(puma, np.zeros((2, 6)), [0.0, 1.0, 2.0])
    with pytest.raises(DimensionError, match=r"q must have shape \(6,\)"):
        _contact().joint_torque(puma, np.zeros(5), 1.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"id": 0}, r"contact id must be an integer >= 1; got 0"),
        ({"link": 0}, r"contact 1: link must be an integer >= 1; got 0"),
        ({"direction": [0, 0, 0]}, r"contact 1: direction must be a non-zero vector"),
        ({"direction": [0, np.nan, 1]}, r"direction must be finite"),
        ({"point": [0, 1]}, r"point \[m\] must be a 3-vector; got shape \(2,\)"),
    ],
)
def test_contact_validation(kwargs, match) -> None:
    args = {"id": 1, "link": 2, "point": [0, 0, 0], "direction": [1, 0, 0]}
    args.update(kwargs)
    with pytest.raises((InputValueError, DimensionError), match=match):
        Contact(**args, profile=HalfSine(0.0, 0.1, 1.0))


def test_contact_needs_a_profile() -> None:
    with pytest.raises(TypeError, match=r"profile must be a ForceProfile"):
        Contact(1, 2, [0, 0, 0], [1, 0, 0], lambda t: 1.0)  # type: ignore[arg-type]


def test_link_beyond_robot_is_named(puma) -> None:
    contacts = ContactSet([_contact(1, 2), _contact(4, 7, start=3.0)])
    with pytest.raises(InputValueError, match=r"contact 4: link 7 does not exist.*1\.\.6"):
        contacts.check(puma)
    with pytest.raises(InputValueError, match=r"contact 4: link 7"):
        contacts.joint_torque(puma, np.zeros(6), 0.0)


def test_contact_set_rejects_duplicate_ids() -> None:
    with pytest.raises(InputValueError, match=r"id 3 is used by items 0 and 1"):
        ContactSet([_contact(3, start=1.0), _contact(3, start=1.05)])
    with pytest.raises(TypeError, match=r"item 0 is str"):
        ContactSet(["contact"])  # type: ignore[list-item]


def test_active_id_at_window_edges() -> None:
    a = Contact(1, 2, [0, 0, 0], [1, 0, 0], HalfSine(1.0, 0.5, 10.0))
    b = Contact(2, 3, [0, 0, 0], [1, 0, 0], Push(1.5, 0.1, 0.2, 0.1, 30.0))
    c = Contact(5, 3, [0, 0, 0], [1, 0, 0], HalfSine(3.0, 1.0, 10.0))
    contacts = ContactSet([a, b, c])
    eps = 1e-9
    assert contacts.active_id(1.0 - eps) == 0
    assert contacts.active_id(1.0) == 1  # window is closed: the start belongs to it
    assert contacts.active_id(1.5) == 1  # a ends where b starts, both at zero force: first listed
    assert contacts.active_id(1.5 + 1e-3) == 2  # b's force is larger
    assert contacts.active_id(1.9) == 2
    assert contacts.active_id(1.9 + eps) == 0
    # overlapping windows: the larger force wins
    assert contacts.active_id(3.5) == 5
    labels = contacts.active_id(np.array([[0.0, 1.25], [1.7, 3.5]]))
    np.testing.assert_array_equal(labels, [[0, 1], [2, 5]])
    assert ContactSet([]).active_id(1.0) == 0
    assert contacts.windows() == [(1, 1.0, 1.5), (2, 1.5, pytest.approx(1.9)), (5, 3.0, 4.0)]
    assert len(contacts) == 3 and [c.id for c in contacts] == [1, 2, 5]
    assert [s["id"] for s in contacts.summaries()] == [1, 2, 5]


# ---------------------------------------------------------------------- random sets
def test_random_set_is_reproducible_and_separated(puma) -> None:
    first = ContactSet.random(puma, 8, 30.0, np.random.default_rng(42), min_gap=1.5)
    again = ContactSet.random(puma, 8, 30.0, np.random.default_rng(42), min_gap=1.5)
    other = ContactSet.random(puma, 8, 30.0, np.random.default_rng(43), min_gap=1.5)
    assert first == again
    assert first.summaries() == again.summaries()
    assert first != other
    windows = first.windows()
    assert [w[0] for w in windows] == list(range(1, 9))
    for (_, _, end), (_, start, _) in itertools.pairwise(windows):
        assert start - end >= 1.5 - 1e-12
    assert windows[0][1] >= 0.5 and windows[-1][2] <= 30.0 - 0.5
    for contact in first:
        assert 2 <= contact.link <= 6
        assert np.all(np.abs(contact.point) <= 0.05)
        assert np.linalg.norm(contact.direction) == pytest.approx(1.0)
        assert 20.0 <= contact.profile.peak <= 80.0
        assert 0.1 <= contact.end - contact.start <= 0.5 + 1e-12
    assert {type(c.profile) for c in first} == {HalfSine, Push}


def test_random_set_options(puma) -> None:
    rng = np.random.default_rng(0)
    contacts = ContactSet.random(puma, 4, 10.0, rng, links=[6], kinds=("push",), margin=2.0)
    assert all(c.link == 6 and isinstance(c.profile, Push) for c in contacts)
    assert contacts.windows()[0][1] >= 2.0
    assert len(ContactSet.random(puma, 0, 1.0, rng)) == 0


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"n": 20}, InputValueError, r"cannot fit 20 contacts"),
        ({"n": -1}, InputValueError, r"n must be an integer >= 0"),
        ({"links": [0]}, InputValueError, r"links entry must be an integer >= 1"),
        ({"links": [7]}, InputValueError, r"link numbers in 1\.\.6"),
        ({"kinds": ("slap",)}, UnknownNameError, r"unknown profile kind\(s\) \['slap'\]"),
        ({"duration_range": (0.5, 0.1)}, InputValueError, r"low <= high"),
        ({"peak_range": (np.nan, 10)}, InputValueError, r"peak_range\[0\] must be finite"),
        ({"min_gap": -1.0}, InputValueError, r"min_gap must be >= 0"),
        ({"rng": 42}, TypeError, r"rng must be a numpy.random.Generator"),
    ],
)
def test_random_set_validation(puma, kwargs, error, match) -> None:
    args = {"n": 3, "duration": 10.0, "rng": np.random.default_rng(0)}
    args.update(kwargs)
    with pytest.raises(error, match=match):
        ContactSet.random(puma, **args)
