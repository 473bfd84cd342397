"""Tests of :mod:`sensorless.isolation`: link, point and force from the residual.

Closed form first: r = J_c(q)ᵀ F built with :meth:`RobotModel.point_jacobian`
(an independent path from the isolator's own Jacobian) for a known point and
force on a built-in robot must give back the link, the point and the force
to 1e-6. Then a simulated push with the true model, where the tolerance
comes from the observer's bandwidth (see :func:`test_true_model_push_is_isolated`).
"""

from __future__ import annotations

import doctest
import math

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import (
    DimensionError,
    InputTypeError,
    InputValueError,
    ModelError,
    UnknownNameError,
)
from sensorless.isolation import (
    QUASI_STATIC_LIMITS,
    TRANSIENT_FACTOR,
    CapsuleSurface,
    Isolator,
    MeshSurface,
    capsule_surfaces,
    urdf_surfaces,
)
from sensorless.isolation._triangles import box_mesh, closest_points, face_normals
from sensorless.observers import observe
from sensorless.robots.builtin import panda_urdf_path
from sensorless.signals import Event
from sensorless.simulation.collisions import Contact, ContactSet, Push
from sensorless.simulation.controllers import ComputedTorque
from sensorless.simulation.plants import RigidPlant
from sensorless.simulation.simulator import simulate
from sensorless.trajectories.quintic import QuinticViaPoints

TIGHT = 1e-3  # band half-width of the closed-form cases [N m]: every joint that feels F is outside


def _pushing_force(robot, q, link, point, normal, size, tilt, rng):
    """A force of ``size`` [N] into the surface at ``point``, ``tilt`` [rad] off the normal."""
    rotation = robot.link_pose(q, link)[:3, :3]
    side = np.cross(normal, rng.standard_normal(3))
    side /= np.linalg.norm(side)
    return size * rotation @ (-math.cos(tilt) * normal + math.sin(tilt) * side)


def _closed_form_case(robot, isolator, link, rng):
    """Random q, a point on link's surface between candidates, a pushing force, r = J_cᵀ F."""
    low, high = robot.position_limits
    low = np.where(np.isfinite(low), low, -np.pi)
    high = np.where(np.isfinite(high), high, np.pi)
    surface = isolator.surfaces[link]
    while True:
        q = rng.uniform(low, high)
        start = surface.points[rng.integers(surface.points.shape[0])]
        point, normal = surface.project((start + rng.normal(0.0, 0.004, 3))[None])
        force = _pushing_force(robot, q, link, point[0], normal[0], 30.0, 0.5, rng)
        r = robot.point_jacobian(q, link, point[0])[:3].T @ force
        if abs(r[link - 1]) > 10 * TIGHT:  # the contact link's own joint feels it
            return q, point[0], force, r


@pytest.mark.parametrize(
    ("name", "link"),
    [("panda", 7), ("panda", 6), ("panda", 5), ("puma560", 6), ("ur5", 6), ("ur5", 5)],
)
def test_closed_form_recovers_link_point_and_force(name: str, link: int) -> None:
    robot = sl.robots.load(name)
    isolator = Isolator(robot)
    rng = np.random.default_rng(12 + link)
    n = robot.n_dof
    for _ in range(4):
        q, point, force, r = _closed_form_case(robot, isolator, link, rng)
        estimate = isolator.step(q, r, -TIGHT * np.ones(n), TIGHT * np.ones(n), t=0.5)
        assert estimate is not None
        assert estimate.link == link
        assert estimate.point_identifiable and estimate.pushing
        np.testing.assert_allclose(estimate.point_link, point, atol=1e-6)
        np.testing.assert_allclose(estimate.force, force, atol=1e-6 * 30.0)
        world = robot.forward_kinematics(q, link, point)
        np.testing.assert_allclose(estimate.point_world, world, atol=1e-6)
        assert estimate.t == 0.5 and estimate.last_significant_joint == link


@pytest.mark.parametrize("link", [1, 2, 3, 4])
def test_links_near_the_base_fit_the_residual_but_not_a_unique_point(link: int) -> None:
    """With fewer than 5 joints the point is not identifiable; the fit still explains r."""
    robot = sl.robots.load("panda")
    isolator = Isolator(robot)
    q, _, _, r = _closed_form_case(robot, isolator, link, np.random.default_rng(link))
    estimate = isolator.step(q, r, -TIGHT * np.ones(7), TIGHT * np.ones(7))
    assert estimate is not None and estimate.link == link
    assert not estimate.point_identifiable
    # A second method: J_cᵀ F̂ at the estimated point reproduces the residual.
    again = robot.point_jacobian(q, link, estimate.point_link)[:3].T @ estimate.force
    np.testing.assert_allclose(again, r, atol=1e-6 * np.abs(r).max())
    assert estimate.force_rank <= min(link, 3)
    assert np.isfinite(estimate.force_bound).all() == (estimate.force_rank == 3)


@pytest.mark.parametrize(
    ("direction", "consistent"), [((0.6, 0.0, -0.8), (6,)), ((0.3, 0.3, -0.9), (5, 6))]
)
def test_a_force_through_the_wrist_axes(direction, consistent) -> None:
    """On the PUMA's flange axis a force whose line meets joint 6's axis leaves τ_6 = 0,
    so joint 6 does not bound the link: link 5 is a candidate. Its surface (a sphere at
    the wrist centre) has, for some directions, a pushing point that explains τ_1..5
    exactly too: both links are then reported and the lower one, with as many numbers
    fitted, is chosen; it reproduces the residual. For others only link 6 fits."""
    robot = sl.robots.load("puma560")
    isolator = Isolator(robot)
    q = np.array([0.3, -0.5, 0.4, 0.2, 0.8, -0.3])
    tip = isolator.surfaces[6]
    point = tip.end + np.array([0.0, 0.0, tip.radius])  # the pole of the capsule's far cap
    unit = np.array(direction) / np.linalg.norm(direction)
    force = 30.0 * robot.link_pose(q, 6)[:3, :3] @ unit  # into the cap, through the axis
    r = robot.point_jacobian(q, 6, point)[:3].T @ force
    assert abs(r[5]) < 1e-12
    estimate = isolator.step(q, r, -TIGHT * np.ones(6), TIGHT * np.ones(6))
    assert estimate.last_significant_joint == 5
    assert estimate.consistent_links == consistent and estimate.link == consistent[0]
    again = robot.point_jacobian(q, estimate.link, estimate.point_link)[:3].T @ estimate.force
    np.testing.assert_allclose(again, r, atol=1e-6 * np.abs(r).max())
    if estimate.link == 6:
        np.testing.assert_allclose(estimate.force, force, atol=1e-6 * 30.0)


def test_urdf_collision_meshes_recover_a_point_inside_a_face() -> None:
    robot = sl.robots.load("panda")
    surfaces = urdf_surfaces(robot, panda_urdf_path())
    assert all(isinstance(surfaces[k], MeshSurface) for k in range(1, 8))
    isolator = Isolator(robot, surfaces)
    rng = np.random.default_rng(5)
    for link in (5, 6, 7):
        mesh = surfaces[link]
        normals = face_normals(mesh.vertices, mesh.triangles)
        face = int(rng.integers(mesh.triangles.shape[0]))
        a, b, c = mesh.vertices[mesh.triangles[face]]
        point = a + 0.3 * (b - a) + 0.25 * (c - a)  # inside the face, not a candidate
        q = np.array([0.2, -0.3, 0.1, -1.9, 0.3, 1.5, 0.4])
        force = _pushing_force(robot, q, link, point, normals[face], 30.0, 0.4, rng)
        r = robot.point_jacobian(q, link, point)[:3].T @ force
        estimate = isolator.step(q, r, -TIGHT * np.ones(7), TIGHT * np.ones(7))
        assert estimate is not None and estimate.link == link
        np.testing.assert_allclose(estimate.point_link, point, atol=1e-6)
        np.testing.assert_allclose(estimate.force, force, atol=3e-5)


def test_worst_case_bound_holds_for_errors_inside_the_band() -> None:
    """|F̂ − F| <= force_bound for any residual error within ±δ, the corners included."""
    robot = sl.robots.load("panda")
    isolator = Isolator(robot)
    rng = np.random.default_rng(3)
    q, point, force, r = _closed_form_case(robot, isolator, 7, rng)
    half = rng.uniform(0.05, 0.3, 7)
    exact = isolator.step(q, r, -TIGHT * np.ones(7), TIGHT * np.ones(7))
    n = 200
    errors = rng.uniform(-1.0, 1.0, (n, 7)) * half
    errors[:8] = np.sign(rng.standard_normal((8, 7))) * half  # corners: the worst cases
    qs = np.tile(q, (n, 1))
    series = isolator.force_series(
        exact, np.arange(n), qs, r + errors, (-half + 0 * qs, half + 0 * qs)
    )
    assert np.all(np.abs(series.force - force) <= series.force_bound * (1 + 1e-9))
    # The bound is attained: the worst corner of the band reaches it component by component.
    b = robot.point_jacobian(q, 7, point)[:3].T / half[:, None]
    worst = np.sign(np.linalg.pinv(b))[0] * half
    reach = isolator.force_series(
        exact, [0.0], q[None], (r + worst)[None], (-half[None], half[None])
    )
    assert abs(reach.force[0, 0] - force[0]) == pytest.approx(reach.force_bound[0, 0], rel=1e-9)


def test_iso_flags_follow_the_magnitude() -> None:
    robot = sl.robots.load("puma560")
    isolator = Isolator(robot)
    q, point, force, _ = _closed_form_case(robot, isolator, 6, np.random.default_rng(4))
    unit = force / np.linalg.norm(force)
    low, high = QUASI_STATIC_LIMITS
    for size in (0.5 * low, 0.5 * (low + TRANSIENT_FACTOR * low), 1.1 * high):
        r = robot.point_jacobian(q, 6, point)[:3].T @ (size * unit)
        estimate = isolator.step(q, r, -TIGHT * np.ones(6), TIGHT * np.ones(6))
        assert estimate.magnitude == pytest.approx(size, rel=1e-9)
        assert estimate.exceeds_quasi_static_min == (size > low)
        assert estimate.exceeds_transient_min == (size > TRANSIENT_FACTOR * low)
        assert estimate.exceeds_quasi_static_max == (size > high)


def test_doctests() -> None:
    assert doctest.testmod(sl.isolation).failed == 0


def test_pruned_search_finds_the_same_contact() -> None:
    """``search="pruned"`` stops where no link further out can win: the same estimate."""
    robot = sl.robots.load("panda")
    full, fast = Isolator(robot), Isolator(robot, search="pruned")
    rng = np.random.default_rng(8)
    for link in (2, 5, 7):
        q, _, _, r = _closed_form_case(robot, full, link, rng)
        bounds = (-TIGHT * np.ones(7), TIGHT * np.ones(7))
        a, b = full.step(q, r, *bounds), fast.step(q, r, *bounds)
        assert a.link == b.link == link
        assert link in a.consistent_links and set(b.consistent_links) <= set(a.consistent_links)
        np.testing.assert_allclose(b.force, a.force, atol=1e-6 * 30.0)


def test_nothing_outside_the_bands_gives_no_estimate() -> None:
    robot = sl.robots.load("planar2")
    isolator = Isolator(robot, radius=0.1)
    assert isolator.step([0.1, 0.2], [0.5, -0.5], [-1.0, -1.0], [1.0, 1.0]) is None
    # An infinite band: never significant, no weight.
    estimate = isolator.step([0.1, 0.2], [3.0, 9.0], [-1.0, -np.inf], [1.0, np.inf])
    assert estimate.last_significant_joint == 1


# ------------------------------------------------------------------ simulated push

K_I = 50.0  # observer gain [1/s]
RAMP_START, RAMP, HOLD, RELEASE, PEAK = 0.5, 0.2, 0.6, 0.2, 40.0
PLATEAU = RAMP_START + RAMP
EPSILON = 0.01  # what is not lag: the sample-and-hold of τ_c (see the test's docstring)
POINT_TOLERANCE = 2 * EPSILON * 0.15  # [m], see the test's docstring


@pytest.fixture(scope="module")
def pushed():
    """A Panda held by a stiff computed-torque loop, pushed on link 7 at a capsule point."""
    robot = sl.robots.load("panda")
    isolator = Isolator(robot)
    q0 = np.array([0.2, -0.4, 0.3, -1.8, 0.4, 1.6, 0.5])
    index = 60
    point, normal = isolator.surfaces[7].points[index], isolator.surfaces[7].normals[index]
    side = np.cross([0.0, 0.0, 1.0], normal)  # tilted about the link axis: joint 7 feels it
    rotation = robot.link_pose(q0, 7)[:3, :3]
    direction = rotation @ (-math.cos(0.5) * normal + math.sin(0.5) * side)
    contact = Contact(1, 7, point, direction, Push(RAMP_START, RAMP, HOLD, RELEASE, PEAK))
    controller = ComputedTorque(
        kp=80.0**2, ki=0.0, kd=160.0, model=robot, friction_compensation=False
    )
    log = simulate(
        RigidPlant(robot, friction=None),
        controller,
        QuinticViaPoints([0.0, 1.6], [q0, q0]),
        1.6,
        contacts=ContactSet([contact]),
    ).log
    signals = observe(log, robot, gain=K_I, velocity="true", friction=None)
    half = np.full(7, 0.3)  # a constant band [N m]; the free residual is ~1e-14 N m
    bounds = (np.tile(-half, (log.n_samples, 1)), np.tile(half, (log.n_samples, 1)))
    return robot, isolator, contact, log, signals, bounds


def _event(t, r, bounds) -> Event:
    outside = (r > bounds[1]) | (r < bounds[0])
    rows = np.flatnonzero(outside.any(axis=1))
    excursion = np.maximum(r - bounds[1], bounds[0] - r)
    peak = float(excursion[rows].max())
    joints = tuple(int(j) + 1 for j in np.flatnonzero(outside.any(axis=0)))
    return Event(float(t[rows[0]]), float(t[rows[-1]]), joints, peak, 0.0)


def test_true_model_push_is_isolated(pushed) -> None:
    """With the true model r̂ = K_I/(s+K_I) τ_c (eq. 3.6): the tolerance follows from K_I.

    The arm is held by a stiff loop, so τ_c = J_cᵀ F has every joint's
    component proportional to the force f(t), and the lag e = τ_c − r̂ obeys
    ė = τ̇_c − K_I e. For a force that rises monotonically to its plateau F0
    at t_p and holds, |e(t)| <= F0 exp(−K_I (t − t_p)) for t >= t_p (a step
    is the worst case). F̂ = pinv(J_cᵀ) r̂ is linear in r̂, so on the plateau

        |F̂(t) − F| / F0 <= exp(−K_I (t − t_p)) + ε

    with ε for what is not lag: the simulator holds τ_c over each sample
    period (a delay of up to dt, worth max|ḟ| dt / F0 = π dt / (2 T_ramp) =
    0.8 % for the raised-cosine ramp), the arm's small deflection under the
    push, rounding: ε = 1 %. (Measured: the plateau error never exceeds the
    lag term; 6e-5 F0 at the peak.) A relative error ρ of force and moment
    moves the line of action by at most about 2 ρ ℓ, ℓ <= 0.15 m from joint
    7's origin to the point: the point is within 2 · 1 % · 0.15 m = 3 mm.
    """
    _, isolator, contact, log, signals, bounds = pushed
    event = _event(log.t, signals.residual, bounds)
    (estimate,) = isolator.isolate_events([event], log.t, log.q, signals.residual, bounds)
    assert estimate.event == event
    assert estimate.link == contact.link == 7
    # The residual still converges during the hold: its peak is at the hold's end, at most
    # a few samples into the release (whose force has then fallen by < 1e-4 F0: within ε).
    assert PLATEAU + 0.5 * HOLD <= estimate.t <= PLATEAU + HOLD + 0.005
    lag = math.exp(-K_I * (estimate.t - PLATEAU))
    true = contact.force(estimate.t)
    assert np.linalg.norm(estimate.force - true) / PEAK <= lag + EPSILON
    assert np.linalg.norm(estimate.point_link - contact.point) <= POINT_TOLERANCE
    assert estimate.magnitude_bound < PEAK  # the band of ±0.3 N m bounds F̂ usefully
    # Averaged over ±10 ms around the peak: the same contact, the lag bound of the window's start.
    (averaged,) = isolator.isolate_events(
        [event], log.t, log.q, signals.residual, bounds, window=0.02
    )
    assert averaged.link == 7 and averaged.t == estimate.t
    lag = math.exp(-K_I * (averaged.t - 0.01 - PLATEAU))
    assert np.linalg.norm(averaged.force - contact.force(averaged.t)) / PEAK <= lag + EPSILON
    # Every sample of the plateau, at the estimated point: the lag bound holds throughout.
    series = isolator.force_series(
        estimate, log.t, log.q, signals.residual, bounds, start=PLATEAU, end=PLATEAU + HOLD
    )
    error = np.linalg.norm(series.force - contact.force(series.t), axis=1) / PEAK
    assert np.all(error <= np.exp(-K_I * (series.t - PLATEAU)) + EPSILON)


def test_batch_equals_stream_and_chunks(pushed) -> None:
    _, isolator, _, log, signals, bounds = pushed
    rows = slice(526, 550)  # before and after the residual leaves its band (0.533 s)
    t, q, r = log.t[rows], log.q[rows], signals.residual[rows]
    lower, upper = bounds[0][rows], bounds[1][rows]
    batch = isolator.run(q, r, (lower, upper), t=t)
    stream = [isolator.step(q[k], r[k], lower[k], upper[k], t=t[k]) for k in range(len(t))]
    first = isolator.run(q[:9], r[:9], (lower[:9], upper[:9]), t=t[:9])
    second = isolator.run(q[9:], r[9:], (lower[9:], upper[9:]), t=t[9:])
    assert any(e is None for e in stream) and any(e is not None for e in stream)
    for a, b, c in zip(batch.estimates, stream, first.estimates + second.estimates, strict=True):
        assert (a is None) == (b is None) == (c is None)
        if a is not None:
            assert a.to_dict() == b.to_dict() == c.to_dict()
    table = batch.to_pandas()
    assert len(table) == sum(e is not None for e in stream)
    np.testing.assert_array_equal(batch.link, [0 if e is None else e.link for e in stream])


def test_skip_nonfinite_leaves_bad_samples_out(pushed) -> None:
    _, isolator, _, log, signals, bounds = pushed
    rows = slice(900, 905)
    r = signals.residual[rows].copy()
    r[2, 3] = np.nan
    with pytest.raises(InputValueError, match="r must be finite"):
        isolator.run(log.q[rows], r, (bounds[0][rows], bounds[1][rows]))
    result = isolator.run(log.q[rows], r, (bounds[0][rows], bounds[1][rows]), skip_nonfinite=True)
    assert result.estimates[2] is None and result.estimates[1] is not None


# ------------------------------------------------------------------ surfaces


def test_capsule_points_lie_on_the_capsule_with_outward_normals() -> None:
    capsule = CapsuleSurface([0.0, 0.0, 0.0], [0.0, 0.3, 0.1], 0.04, 0.01)
    axis = np.array([0.0, 0.3, 0.1])
    s = np.clip(capsule.points @ axis / (axis @ axis), 0.0, 1.0)
    distance = np.linalg.norm(capsule.points - s[:, None] * axis, axis=1)
    np.testing.assert_allclose(distance, 0.04, atol=1e-12)
    projected, normals = capsule.project(capsule.points + 0.01 * capsule.normals)
    np.testing.assert_allclose(projected, capsule.points, atol=1e-12)
    np.testing.assert_allclose(normals, capsule.normals, atol=1e-12)


def test_capsules_follow_the_joint_origins() -> None:
    robot = sl.robots.load("puma560")
    surfaces = capsule_surfaces(robot, radius=0.06)
    model = robot.pinocchio_model
    for link in range(1, robot.n_dof):
        np.testing.assert_allclose(surfaces[link].end, model.jointPlacements[link + 1].translation)
    np.testing.assert_allclose(surfaces[6].end, 2 * model.inertias[6].lever)  # no frame: 2 × CoM


def test_closest_points_on_a_box_match_clipping() -> None:
    """Closest point on a box's surface from outside = the point clipped to the box."""
    vertices, triangles = box_mesh(np.array([0.1, 0.2, 0.3]))
    points = np.random.default_rng(0).uniform(-1.0, 1.0, (50, 3))
    points = points[np.any(np.abs(points) > [0.1, 0.2, 0.3], axis=1)]
    closest, _ = closest_points(points, vertices, triangles)
    np.testing.assert_allclose(
        closest, np.clip(points, [-0.1, -0.2, -0.3], [0.1, 0.2, 0.3]), atol=1e-12
    )
    mesh = MeshSurface(vertices, triangles[:, ::-1], spacing=0.05)  # inward winding is flipped
    assert np.all(np.einsum("ij,ij->i", mesh.points, mesh.normals) > 0.0)


# ------------------------------------------------------------------ bad input


def test_bad_input_gives_clear_errors() -> None:
    robot = sl.robots.load("planar2")
    isolator = Isolator(robot, radius=0.1)
    ones = np.ones(2)
    with pytest.raises(DimensionError, match=r"one sample of shape \(2,\)"):
        isolator.step(np.ones((3, 2)), ones, -ones, ones)
    with pytest.raises(DimensionError, match="must have shape"):
        isolator.step(np.ones(3), ones, -ones, ones)
    with pytest.raises(InputValueError, match="r must be finite"):
        isolator.step(ones, [np.nan, 1.0], -ones, ones)
    with pytest.raises(InputValueError, match="must not be NaN"):
        isolator.step(ones, ones, [np.nan, -1.0], ones)
    with pytest.raises(InputValueError, match="lower bound must be <= upper"):
        isolator.step(ones, ones, ones, -ones)
    with pytest.raises(InputTypeError, match="bounds must be a pair"):
        isolator.run(np.ones((4, 2)), np.ones((4, 2)), np.ones((4, 2)))
    with pytest.raises(DimensionError, match="same number of samples"):
        isolator.run(np.ones((4, 2)), np.ones((3, 2)), (-np.ones((4, 2)), np.ones((4, 2))))
    with pytest.raises(InputValueError, match="has no sample in t"):
        isolator.isolate_events(
            [Event(5.0, 6.0, (1,), 1.0, 1.0)],
            np.arange(4.0),
            np.ones((4, 2)),
            np.ones((4, 2)),
            (-np.ones((4, 2)), np.ones((4, 2))),
        )
    with pytest.raises(InputValueError, match="strictly increasing"):
        isolator.isolate_events(
            [],
            [0.0, 0.0, 1.0, 2.0],
            np.ones((4, 2)),
            np.ones((4, 2)),
            (-np.ones((4, 2)), np.ones((4, 2))),
        )
    with pytest.raises(InputTypeError, match="robot must be a RobotModel"):
        Isolator("planar2")
    with pytest.raises(InputValueError, match="link 3 is not a link"):
        Isolator(robot, {3: CapsuleSurface([0, 0, 0], [1, 0, 0], 0.1)})
    with pytest.raises(InputTypeError, match=r"surfaces\[1\] must be a Surface"):
        Isolator(robot, {1: "capsule"})
    with pytest.raises(InputValueError, match="t must be a time"):
        isolator.step(ones, ones, -ones, ones, t="now")
    with pytest.raises(UnknownNameError, match="unknown search 'fast'"):
        Isolator(robot, search="fast")
    with pytest.raises(InputValueError, match="force_limits"):
        Isolator(robot, force_limits=(210.0, 65.0))
    with pytest.raises(InputValueError, match="radius"):
        capsule_surfaces(robot, radius=-0.1)
    with pytest.raises(ModelError, match="capsule start"):
        CapsuleSurface([0.0, np.nan, 0.0], [1.0, 0.0, 0.0], 0.1)
    with pytest.raises(ModelError, match="triangles must be indices"):
        MeshSurface(np.zeros((3, 3)), [[0, 1, 5]])
    with pytest.raises(ModelError, match="none of the collision geometry"):
        urdf_surfaces(robot, panda_urdf_path())
