"""Tests of :class:`sensorless.robots.LinkInertia` and of the model-mismatch error.

The orders of the six inertia entries are checked against a tensor built
independently (a rotated solid box, closed form) and against Pinocchio's own
dynamic-parameter vector; the refusals against tensors whose defect is known
by construction (eigenvalues, triangle inequality); a declared payload against
the same arm assembled by the parallel-axis theorem.
"""

from __future__ import annotations

import doctest

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import sensorless as sl
from sensorless.exceptions import (
    DimensionError,
    InputTypeError,
    ModelError,
    ModelMismatchError,
    UnknownNameError,
)
from sensorless.io import Log
from sensorless.monitor import CollisionMonitor, ObserverSettings
from sensorless.observers import observe
from sensorless.robots import inertia as inertia_module
from sensorless.robots.inertia import INERTIA_ORDERS, INERTIA_RTOL
from sensorless.signals import ObserverSignals
from sensorless.thresholds import ConstantThreshold

MASS = 3.0
COM = (0.01, -0.02, 0.15)
ROW = {"alpha": 0.0, "a": 0.0, "theta": 0.0, "d": 0.0}


def box_inertia(mass: float, sides: tuple[float, float, float], seed: int) -> np.ndarray:
    """Inertia about the centre of a solid box [kg m²], its edges turned by a random rotation."""
    a, b, c = sides
    principal = mass / 12 * np.array([b**2 + c**2, a**2 + c**2, a**2 + b**2])
    rotation = Rotation.random(random_state=seed).as_matrix()
    tensor = rotation @ np.diag(principal) @ rotation.T
    return 0.5 * (tensor + tensor.T)  # exactly symmetric, as published tensors are


def turned(principal: tuple[float, float, float], seed: int) -> np.ndarray:
    rotation = Rotation.random(random_state=seed).as_matrix()
    return rotation @ np.diag(principal) @ rotation.T


def refusal(error: type[Exception], match: str, *args: object, **kwargs: object) -> None:
    """LinkInertia(*args, **kwargs) raises exactly ``error`` with ``match`` in its message."""
    with pytest.raises(error, match=match) as caught:
        sl.LinkInertia(*args, **kwargs)  # type: ignore[arg-type]
    assert type(caught.value) is error


# --------------------------------------------------------------------------- orders
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_every_order_gives_the_same_tensor(seed: int) -> None:
    tensor = box_inertia(MASS, (0.3, 0.1, 0.05), seed)
    (xx, xy, xz), (_, yy, yz), (_, _, zz) = tensor
    vectors = {
        "urdf": [xx, xy, xz, yy, yz, zz],
        # Pinocchio's own vector [m, mx, my, mz, Ixx, ...] about the frame of the centre of mass.
        "pinocchio": pin.Inertia(MASS, np.zeros(3), tensor).toDynamicParameters()[4:],
        "rtb": [xx, yy, zz, xy, yz, xz],
        "mujoco": [xx, yy, zz, xy, xz, yz],
    }
    assert sorted(vectors) == sorted(INERTIA_ORDERS)
    for order, vector in vectors.items():
        link = sl.LinkInertia(MASS, COM, vector, order=order)
        np.testing.assert_allclose(link.inertia, tensor, rtol=0, atol=1e-15, err_msg=order)
    # The default is the URDF order, and reading a vector in the wrong order changes the tensor.
    np.testing.assert_array_equal(sl.LinkInertia(MASS, COM, vectors["urdf"]).inertia, tensor)
    try:
        misread = sl.LinkInertia(MASS, COM, vectors["rtb"]).inertia
    except ModelError:
        return
    assert np.abs(misread - tensor).max() > 1e-3


def test_the_doctests_run() -> None:
    result = doctest.testmod(inertia_module)
    assert result.attempted >= 4 and result.failed == 0


def test_a_3x3_tensor_ignores_the_order() -> None:
    tensor = box_inertia(MASS, (0.2, 0.2, 0.4), 5)
    for order in INERTIA_ORDERS:
        np.testing.assert_array_equal(
            sl.LinkInertia(MASS, COM, tensor, order=order).inertia, tensor
        )


def test_an_unknown_order_lists_the_choices() -> None:
    message = r"link 'wrist': unknown order 'corke'.*urdf.*pinocchio.*rtb.*mujoco"
    refusal(UnknownNameError, message, MASS, COM, np.eye(3), "wrist", order="corke")
    with pytest.raises(KeyError):
        sl.LinkInertia(MASS, COM, np.eye(3), order="RTB")


def test_orders_reach_the_model_through_a_mapping() -> None:
    tensor = box_inertia(MASS, (0.3, 0.2, 0.1), 7)
    (xx, xy, xz), (_, yy, yz), (_, _, zz) = tensor
    link = {"mass": MASS, "com": COM, "inertia": [xx, yy, zz, xy, yz, xz], "order": "rtb"}
    robot = sl.RobotModel.from_mdh([ROW], [link])
    np.testing.assert_allclose(robot.pinocchio_model.inertias[1].inertia, tensor, atol=1e-15)


# --------------------------------------------------------------------------- refusals
def test_a_tensor_that_is_not_symmetric_is_refused() -> None:
    tensor = np.eye(3)
    tensor[0, 1] = 0.1
    refusal(
        ModelError, r"link 'link3': the inertia tensor is not symmetric", 1.0, COM, tensor, "link3"
    )
    # Round-off of a rotation is not asymmetry.
    tensor = box_inertia(MASS, (0.3, 0.1, 0.05), 3)
    tensor[0, 1] *= 1 + 1e-13
    link = sl.LinkInertia(MASS, COM, tensor)
    np.testing.assert_array_equal(link.inertia, link.inertia.T)


def test_a_tensor_that_is_not_positive_semi_definite_is_refused() -> None:
    refusal(
        ModelError,
        r"link 'link3': the inertia tensor is not positive semi-definite \(principal moments "
        r"\(-1, 1, 1\)\) \[kg m²\]",
        1.0, COM, np.diag([1.0, 1.0, -1.0]), "link3",
    )  # fmt: skip
    # Positive diagonal, one negative eigenvalue: Pinocchio takes it, LinkInertia does not.
    indefinite = np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    pin.Inertia(1.0, np.zeros(3), indefinite)
    refusal(ModelError, r"principal moments \(-1, 1, 3\)", 1.0, COM, indefinite, "link3")
    # Neither is accepted when the triangle inequality is waived.
    refusal(ModelError, "not positive semi-definite", 1.0, COM, indefinite, rigid_body=False)


def test_semi_definite_idealisations_are_accepted() -> None:
    """A point mass and a thin rod have singular inertia tensors; both are links."""
    point = sl.LinkInertia(2.0, COM, np.zeros((3, 3)), "point")
    assert not point.inertia.any()
    rod = sl.LinkInertia(2.0, COM, turned((0.0, 0.5, 0.5), 4), "rod")
    assert np.linalg.eigvalsh(rod.inertia)[0] == pytest.approx(0.0, abs=1e-15)
    # A moment below zero by round-off is zero; Pinocchio, which refuses it, gets zero.
    tiny = sl.LinkInertia(2.0, COM, np.diag([-0.1 * INERTIA_RTOL, 1.0, 1.0]), "rod")
    assert tiny.inertia[0, 0] == 0.0
    sl.RobotModel.from_mdh([ROW], [tiny])
    refusal(ModelError, "not positive semi-definite", 2.0, COM, np.diag([-1e-6, 1.0, 1.0]))


@pytest.mark.parametrize("seed", [0, 1])
def test_triangle_inequality_boundary(seed: int) -> None:
    length, a, b = 0.8, 0.4, 0.3
    rod = (0.0, length**2 / 12, length**2 / 12)  # per kg: thin rod along x
    plate = (b**2 / 12, a**2 / 12, (a**2 + b**2) / 12)  # per kg: flat a x b plate in x-y
    for principal in (rod, plate):
        sl.LinkInertia(MASS, COM, MASS * turned(principal, seed), "edge")
        inside = (principal[0], principal[1], principal[2] * (1 + 0.1 * INERTIA_RTOL))
        sl.LinkInertia(MASS, COM, MASS * turned(inside, seed), "edge")
        beyond = (principal[0], principal[1], principal[2] * (1 + 1e-6))
        refusal(
            ModelError,
            r"link 'edge': the principal moments .* break the triangle inequality",
            MASS, COM, MASS * turned(beyond, seed), "edge",
        )  # fmt: skip
        link = sl.LinkInertia(MASS, COM, MASS * turned(beyond, seed), "edge", rigid_body=False)
        assert link.rigid_body is False


def test_mass_and_finiteness_are_checked_with_the_link_name() -> None:
    cases = [
        (-1.0, COM, np.eye(3), "mass must be >= 0 kg; got -1.0"),
        (np.nan, COM, np.eye(3), "mass must be finite"),
        ("heavy", COM, np.eye(3), "mass must be a number"),
        (True, COM, np.eye(3), "mass must be a number"),
        (1.0, (0.0, np.inf, 0.0), np.eye(3), "centre of mass and inertia must be finite"),
        (1.0, COM, np.diag([1.0, np.nan, 1.0]), "centre of mass and inertia must be finite"),
        (1.0, (0.0, 0.0), np.eye(3), r"centre of mass must have 3 entries \[m\]"),
        (1.0, COM, np.ones(5), r"inertia must be a 3x3 tensor or 6 entries in the order 'urdf'"),
    ]
    for mass, com, inertia, match in cases:
        refusal(ModelError, f"link 'elbow': {match}", mass, com, inertia, "elbow")
    refusal(InputTypeError, "rigid_body must be True or False", 1.0, COM, np.eye(3), rigid_body=1)
    refusal(InputTypeError, "a link name must be a str; got int", 1.0, COM, np.eye(3), 3)


def test_the_builders_name_the_links_of_mappings() -> None:
    good = {"mass": 1.0, "com": (0.0, 0.0, 0.0), "inertia": np.eye(3)}
    bad = {**good, "inertia": np.diag([1.0, 1.0, 3.0])}
    with pytest.raises(ModelError, match=r"link 'link2': the principal moments \(1, 1, 3\)"):
        sl.RobotModel.from_mdh([ROW, ROW], [good, bad])
    with pytest.raises(ModelError, match=r"link 'forearm': the principal"):
        sl.RobotModel.from_mdh([ROW, ROW], [good, {**bad, "name": "forearm"}])
    with pytest.raises(InputTypeError, match=r"link 'link1': unknown keys \['odrer'\].*'order'"):
        sl.RobotModel.from_mdh([ROW], [{**good, "odrer": "rtb"}])


@settings(max_examples=200, deadline=None)
@given(
    entries=st.lists(st.floats(-2.0, 2.0, allow_nan=False), min_size=6, max_size=6),
    order=st.sampled_from(sorted(INERTIA_ORDERS)),
    rigid_body=st.booleans(),
)
def test_pinocchio_never_refuses_an_accepted_link(
    entries: list[float], order: str, rigid_body: bool
) -> None:
    """Either LinkInertia refuses the data with a ModelError, or Pinocchio builds the model."""
    try:
        link = sl.LinkInertia(1.0, COM, entries, "link1", rigid_body=rigid_body, order=order)
    except ModelError as exc:
        assert str(exc).startswith("link 'link1': ")
        return
    moments = np.linalg.eigvalsh(link.inertia)
    assert moments[0] >= -INERTIA_RTOL * np.abs(moments).max()
    robot = sl.RobotModel.from_mdh([ROW], [link])
    assert robot.mass_matrix(np.zeros(1))[0, 0] >= 0.0


def test_a_link_changed_in_place_is_refused_by_name() -> None:
    link = sl.LinkInertia(1.0, COM, np.eye(3), "link4")
    link.inertia[2, 2] = -1.0  # type: ignore[index]
    with pytest.raises(ModelError, match="link 'link4': Pinocchio refuses its inertia"):
        sl.RobotModel.from_mdh([ROW], [link])


# --------------------------------------------------------------------------- payload
PAYLOAD = 2.0  # [kg], a point mass at the tip of link 2 (x = l2 = 1 m in its frame)


def payload_parameters(robot: sl.RobotModel, inertia_too: bool) -> np.ndarray:
    params = robot.standard_parameters()
    added = {"m": PAYLOAD, "mX": PAYLOAD * 1.0}
    if inertia_too:  # m d² about the link origin, d = 1 m along x
        added |= {"YY": PAYLOAD * 1.0, "ZZ": PAYLOAD * 1.0}
    for name, value in added.items():
        params.loc["link2", name] += value
    return params.to_numpy()


def test_a_payload_declared_without_its_inertia_is_refused_by_link() -> None:
    planar = sl.robots.load("planar2")
    with pytest.raises(
        ModelError, match=r"link 2: .*negative moment.*\(0, -1.75, -1.75\).*XX, YY, ZZ"
    ):
        planar.with_standard_parameters(payload_parameters(planar, inertia_too=False))


def test_a_declared_payload_equals_the_composite_link() -> None:
    planar = sl.robots.load("planar2")
    payload = planar.with_standard_parameters(payload_parameters(planar, True), name="p")
    # Link 2 rebuilt as rod + point mass by the parallel-axis theorem, about their joint centre.
    mass = 1.0 + PAYLOAD
    com = (1.0 * 0.5 + PAYLOAD * 1.0) / mass
    across = 1.0 / 12 + 1.0 * (0.5 - com) ** 2 + PAYLOAD * (1.0 - com) ** 2
    rod = sl.LinkInertia(1.0, (0.5, 0.0, 0.0), np.diag([0.0, 1.0, 1.0]) / 12)
    tip = sl.LinkInertia(mass, (com, 0.0, 0.0), np.diag([0.0, across, across]))
    table = [ROW, {**ROW, "a": 1.0}]
    composite = sl.RobotModel.from_mdh(table, [rod, tip], gravity=(0.0, -9.81, 0.0))
    rng = np.random.default_rng(3)
    q, qd, qdd = rng.normal(size=(3, 10, 2))
    np.testing.assert_allclose(
        payload.inverse_dynamics(q, qd, qdd), composite.inverse_dynamics(q, qd, qdd), atol=1e-12
    )


@pytest.fixture(scope="module")
def two_models() -> tuple[sl.RobotModel, sl.RobotModel, dict[str, ObserverSignals]]:
    """planar2, the same arm with a declared payload, and the signals of each observing its run."""
    planar = sl.robots.load("planar2")
    payload = planar.with_standard_parameters(
        payload_parameters(planar, True), name="planar2 + 2 kg payload"
    )
    t = np.arange(0.0, 0.5, 1e-3)
    q = np.stack([0.5 * np.sin(2 * t), 0.8 * np.sin(3 * t)], 1)
    qd = np.stack([np.cos(2 * t), 2.4 * np.cos(3 * t)], 1)
    qdd = np.stack([-2 * np.sin(2 * t), -7.2 * np.sin(3 * t)], 1)
    signals = {
        robot.name: observe(Log(t, q, qd=qd, tau_m=robot.inverse_dynamics(q, qd, qdd)), robot)
        for robot in (planar, payload)
    }
    return planar, payload, signals


def test_a_payload_is_a_model_mismatch_not_a_dimension_error(two_models) -> None:
    planar, payload, signals = two_models
    plain, loaded = signals["planar2"], signals["planar2 + 2 kg payload"]
    assert plain.n_dof == loaded.n_dof == 2
    both = r"'planar2' \(2 joints\).*'planar2 \+ 2 kg payload' \(2 joints\).*models differ"
    with pytest.raises(ModelMismatchError, match=both):
        ConstantThreshold().fit([plain, loaded])
    threshold = ConstantThreshold().fit(plain)
    with pytest.raises(
        ModelMismatchError, match=r"fitted for planar2 .*come from planar2 \+ 2 kg payload"
    ):
        threshold.bounds(loaded)
    settings = ObserverSettings(kind="motor", gain=20.0)
    with pytest.raises(
        ModelMismatchError, match=r"threshold is for robot 'planar2'.*'planar2 \+ 2 kg payload'"
    ) as caught:
        CollisionMonitor(payload, threshold, settings)
    assert isinstance(caught.value, ModelError) and isinstance(caught.value, ValueError)
    assert not isinstance(caught.value, DimensionError)
    CollisionMonitor(planar, threshold, settings)  # the model it was fitted for


def test_a_joint_count_mismatch_stays_a_dimension_error(two_models) -> None:
    _, _, signals = two_models
    threshold = ConstantThreshold().fit(signals["planar2"])
    settings = ObserverSettings(kind="motor", gain=20.0)
    with pytest.raises(DimensionError, match="threshold is for 2 joints") as caught:
        CollisionMonitor(sl.robots.load("puma560"), threshold, settings)
    assert not isinstance(caught.value, ModelMismatchError)
