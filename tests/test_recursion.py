"""The O(n) recursion for p = M q̇, Cᵀq̇ and g against Pinocchio, and ṗ = τ + Cᵀq̇ − g."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import sensorless as sl
from sensorless.exceptions import DimensionError, InputValueError, ModelError, UnknownNameError
from sensorless.robots import recursion
from sensorless.robots.recursion import MomentumTerms, numba_available

BACKENDS = [
    "numpy",
    pytest.param(
        "numba", marks=pytest.mark.skipif(not numba_available(), reason="numba not installed")
    ),
]


def _link(name: str, mass: float, com: str, ixx: float) -> str:
    return (
        f'<link name="{name}"><inertial><origin xyz="{com}" rpy="0.1 -0.2 0.3"/>'
        f'<mass value="{mass}"/><inertia ixx="{ixx}" ixy="0.001" ixz="-0.002" '
        f'iyy="{1.3 * ixx}" iyz="0.003" izz="{0.7 * ixx}"/></inertial></link>'
    )


def _joint(name: str, kind: str, parent: str, child: str, origin: str, axis: str) -> str:
    xyz, rpy = origin.split("|")
    extra = "" if kind == "fixed" else f'<axis xyz="{axis}"/>'
    if kind in ("revolute", "prismatic"):
        extra += '<limit lower="-3" upper="3" effort="100" velocity="5"/>'
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="{rpy}"/>{extra}</joint>'
    )


#: A tree (j7 and j8 branch off l2) with joint axes along x, y, z, −z and two
#: unaligned axes, three prismatic joints and a fixed joint between movable ones.
TREE_URDF = (
    '<robot name="tree"><link name="base"/>'
    + _link("l1", 2.0, "0.01 0.02 0.1", 0.02)
    + _link("l2", 1.5, "0.1 0 0.02", 0.015)
    + _link("l3", 1.0, "0 0.05 0", 0.01)
    + _link("l4", 0.5, "0.02 0 0.03", 0.004)
    + _link("l5", 0.7, "0 0 0.05", 0.006)
    + _link("l6", 0.4, "0.03 0.01 0", 0.003)
    + _link("l7", 0.6, "0.01 -0.02 0.04", 0.005)
    + _link("l8", 0.3, "0 0.02 0.01", 0.002)
    + _link("l9", 0.2, "0.01 0 0", 0.001)
    + _joint("j1", "revolute", "base", "l1", "0 0 0.3|0 0 0", "0 0 1")
    + _joint("j2", "revolute", "l1", "l2", "0 0.05 0.2|0.3 0.2 0.1", "1 0 0")
    + _joint("j3", "prismatic", "l2", "l3", "0.2 0 0|0 0.4 0", "0 1 0")
    + _joint("fixed", "fixed", "l3", "l4", "0.1 0.05 0|0.2 0 0.5", "")
    + _joint("j5", "revolute", "l4", "l5", "0 0 0.1|0 0 0", "0 0.6 0.8")
    + _joint("j6", "prismatic", "l5", "l6", "0.05 0 0.1|0.1 0.1 0.1", "0.6 0 -0.8")
    + _joint("j7", "revolute", "l2", "l7", "0.1 0.1 0|-0.5 0 0.2", "0 1 0")
    + _joint("j8", "revolute", "l7", "l8", "0 0.1 0.1|0 0 0", "0 0 -1")
    + _joint("j9", "prismatic", "l2", "l9", "0 0 0.1|0 0.3 0", "0 0 1")
    + "</robot>"
)


def tree_model() -> pin.Model:
    """The URDF tree with armature and a tilted gravity."""
    model = pin.buildModelFromXML(TREE_URDF)
    model.armature = np.linspace(0.05, 0.4, model.nv)
    model.gravity = pin.Motion(np.array([0.8, -1.5, -9.6]), np.zeros(3))
    return model


def models() -> list[tuple[str, pin.Model]]:
    built_in = [(name, sl.robots.load(name).pinocchio_model) for name in sl.robots.available()]
    return [*built_in, ("tree_urdf", tree_model())]


MODELS = models()


def pinocchio_terms(model: pin.Model, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """(3, n_samples, n_dof): crba·q̇ (symmetrised), computeCoriolisMatrixᵀ·q̇, gravity."""
    data = model.createData()
    out = np.empty((3, *q.shape))
    for i in range(q.shape[0]):
        upper = np.triu(pin.crba(model, data, q[i]))
        out[0, i] = (upper + np.triu(upper, 1).T) @ qd[i]
        out[1, i] = pin.computeCoriolisMatrix(model, data, q[i], qd[i]).T @ qd[i]
        out[2, i] = pin.computeGeneralizedGravity(model, data, q[i])
    return out


def random_states(n_dof: int, n_samples: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.uniform(-3, 3, (n_samples, n_dof)), rng.uniform(-3, 3, (n_samples, n_dof))


def assert_relative(actual: np.ndarray, expected: np.ndarray, rtol: float = 1e-10) -> None:
    """|actual − expected| ≤ rtol · max|expected|, entrywise."""
    scale = float(np.abs(expected).max())
    np.testing.assert_allclose(actual, expected, rtol=0.0, atol=rtol * scale)


def test_the_tree_has_every_joint_kind() -> None:
    kinds = {joint.shortname() for joint in tree_model().joints[1:]}
    assert kinds == {
        "JointModelRZ",
        "JointModelRX",
        "JointModelRY",
        "JointModelPY",
        "JointModelPZ",
        "JointModelRevoluteUnaligned",
        "JointModelPrismaticUnaligned",
    }
    assert list(tree_model().parents) == [0, 0, 1, 2, 3, 4, 2, 6, 2]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(("name", "model"), MODELS, ids=[name for name, _ in MODELS])
def test_terms_equal_pinocchio(name: str, model: pin.Model, backend: str) -> None:
    q, qd = random_states(model.nv, 40, seed=len(name))
    expected = pinocchio_terms(model, q, qd)
    actual = MomentumTerms(model, backend=backend).terms(q, qd)
    for got, want in zip(actual, expected, strict=True):
        assert_relative(got, want)


def test_armature_enters_p_only() -> None:
    model = tree_model()
    bare = model.copy()
    bare.armature = np.zeros(model.nv)
    q, qd = random_states(model.nv, 5, seed=1)
    with_armature = MomentumTerms(model).terms(q, qd)
    without = MomentumTerms(bare).terms(q, qd)
    assert_relative(with_armature[0] - without[0], model.armature * qd)
    assert_relative(with_armature[1], without[1], rtol=1e-14)
    assert_relative(with_armature[2], without[2], rtol=1e-14)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(("name", "model"), MODELS, ids=[name for name, _ in MODELS])
def test_one_sample_equals_batch(name: str, model: pin.Model, backend: str) -> None:
    terms = MomentumTerms(model, backend=backend)
    q, qd = random_states(model.nv, 6, seed=3)
    batch = np.stack(terms.terms(q, qd))
    out = np.empty((3, model.nv))
    for i in range(q.shape[0]):
        one = terms.terms_one(np.ascontiguousarray(q[i]), np.ascontiguousarray(qd[i]))
        assert one.shape == (3, model.nv)
        assert_relative(one, batch[:, i])
        assert terms.terms_one(q[i].copy(), qd[i].copy(), out) is out
        assert_relative(out, batch[:, i])
        single = np.stack(terms.terms(q[i], qd[i]))
        assert single.shape == (3, model.nv)
        assert_relative(single, batch[:, i], rtol=1e-14)


@pytest.mark.parametrize("chunk_size", [1, 7, 64])
def test_numpy_chunks_equal_whole(chunk_size: int) -> None:
    model = tree_model()
    q, qd = random_states(model.nv, 100, seed=4)
    whole = np.stack(MomentumTerms(model, backend="numpy", chunk_size=4096).terms(q, qd))
    chunked = np.stack(MomentumTerms(model, backend="numpy", chunk_size=chunk_size).terms(q, qd))
    assert_relative(chunked, whole, rtol=1e-14)


@pytest.mark.skipif(not numba_available(), reason="numba not installed")
@pytest.mark.parametrize(("name", "model"), MODELS, ids=[name for name, _ in MODELS])
def test_numba_equals_numpy(name: str, model: pin.Model) -> None:
    q, qd = random_states(model.nv, 300, seed=5)
    compiled = np.stack(MomentumTerms(model, backend="numba").terms(q, qd))
    plain = np.stack(MomentumTerms(model, backend="numpy", chunk_size=128).terms(q, qd))
    np.testing.assert_allclose(compiled, plain, rtol=0.0, atol=1e-9)
    assert_relative(compiled, plain, rtol=1e-13)


def test_from_robot_and_properties() -> None:
    robot = sl.robots.load("puma560")
    terms = MomentumTerms.from_robot(robot, backend="numpy", chunk_size=16)
    assert (terms.n_dof, terms.backend, terms.chunk_size) == (6, "numpy", 16)
    constants = terms.kernel_constants
    assert constants.shape == (6, 28)
    assert not constants.flags.writeable
    np.testing.assert_array_equal(constants[:, 22], robot.armature)
    expected = "numba" if numba_available() else "numpy"
    assert MomentumTerms.from_robot(robot).backend == expected


def test_auto_falls_back_to_numpy_without_numba(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(recursion, "_numba_kernels", None)
    model = tree_model()
    assert not recursion.numba_available()
    assert MomentumTerms(model).backend == "numpy"
    with pytest.raises(InputValueError, match="backend 'numba' needs numba"):
        MomentumTerms(model, backend="numba")


def _simulate(model: pin.Model, dt: float, n_steps: int) -> tuple[np.ndarray, ...]:
    """RK4 of pin.aba under a smooth torque; returns t, q, qd, τ at every step."""
    data = model.createData()
    n_dof = model.nv
    amplitude = 2.0 + np.arange(n_dof)
    frequency = 0.7 + 0.3 * np.arange(n_dof)

    def torque(t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        hold = pin.computeGeneralizedGravity(model, data, q)
        return hold + amplitude * np.sin(frequency * t) - 2.0 * qd

    def rate(t: float, x: np.ndarray) -> np.ndarray:
        q, qd = x[:n_dof], x[n_dof:]
        return np.concatenate([qd, pin.aba(model, data, q, qd, torque(t, q, qd))])

    t = np.arange(n_steps) * dt
    x = np.zeros((n_steps, 2 * n_dof))
    x[0, :n_dof] = 0.3
    for i in range(n_steps - 1):
        k1 = rate(t[i], x[i])
        k2 = rate(t[i] + dt / 2, x[i] + dt / 2 * k1)
        k3 = rate(t[i] + dt / 2, x[i] + dt / 2 * k2)
        k4 = rate(t[i] + dt, x[i] + dt * k3)
        x[i + 1] = x[i] + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    q, qd = x[:, :n_dof], x[:, n_dof:]
    tau = np.array([torque(t[i], q[i], qd[i]) for i in range(n_steps)])
    return t, q, qd, tau


@pytest.mark.parametrize("name", ["puma560", "tree_urdf"])
def test_momentum_rate_along_a_simulated_trajectory(name: str) -> None:
    """ṗ = τ + Cᵀq̇ − g along 1.5 s of RK4 (dt = 1 ms) of ``pin.aba``.

    ṗ is the fourth-order central difference of p, whose error, dt⁴/30·|p⁽⁵⁾|,
    and the RK4 error are both below 1e-9 of max|ṗ| here (measured 4e-10 and
    3e-11; 16 times more at dt = 2 ms, as fourth order predicts): tolerance
    1e-8 of max|ṗ|. With C q̇ in place of Cᵀq̇ the identity must fail by far.
    """
    model = dict(MODELS)[name]
    dt = 1e-3
    _, q, qd, tau = _simulate(model, dt, 1500)
    p, coriolis_t_qd, gravity = MomentumTerms(model).terms(q, qd)
    p_rate = (p[:-4] - 8 * p[1:-3] + 8 * p[3:-1] - p[4:]) / (12 * dt)
    inner = slice(2, -2)
    predicted = tau[inner] + coriolis_t_qd[inner] - gravity[inner]
    scale = float(np.abs(p_rate).max())
    assert np.abs(p_rate - predicted).max() <= 1e-8 * scale
    data = model.createData()
    weightless = model.copy()
    weightless.gravity = pin.Motion.Zero()
    coriolis_qd = np.array(
        [pin.rnea(weightless, data, q[i], qd[i], np.zeros(model.nv)) for i in range(len(q))]
    )
    wrong = tau[inner] + coriolis_qd[inner] - gravity[inner]
    assert np.abs(p_rate - wrong).max() > 1e-3 * scale


def test_refuses_other_joints() -> None:
    model = pin.Model()
    model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "shoulder")
    model.addJoint(1, pin.JointModelSpherical(), pin.SE3.Identity(), "wrist")
    with pytest.raises(ModelError, match=r"joint 'wrist' is a JointModelSpherical.*JointModelRX"):
        MomentumTerms(model)
    continuous = pin.buildModelFromXML(TREE_URDF.replace('type="revolute"', 'type="continuous"'))
    with pytest.raises(ModelError, match="joint 'j1' is a JointModelRUBZ"):
        MomentumTerms(continuous)


def test_refuses_empty_model_and_rotating_gravity() -> None:
    with pytest.raises(ModelError, match="no joint"):
        MomentumTerms(pin.Model())
    model = tree_model()
    model.gravity = pin.Motion(np.array([0.0, 0.0, -9.81]), np.array([0.0, 0.1, 0.0]))
    with pytest.raises(ModelError, match="pure linear field"):
        MomentumTerms(model)


def test_option_checks() -> None:
    model = tree_model()
    with pytest.raises(UnknownNameError, match=r"unknown backend 'fast'.*'numba'"):
        MomentumTerms(model, backend="fast")
    with pytest.raises(InputValueError, match="chunk_size must be an integer >= 1"):
        MomentumTerms(model, chunk_size=0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_input_checks(backend: str) -> None:
    terms = MomentumTerms(tree_model(), backend=backend)
    q, qd = random_states(8, 3, seed=6)
    with pytest.raises(DimensionError, match="q and qd must have the same shape"):
        terms.terms(q, qd[:2])
    with pytest.raises(DimensionError, match="q must have shape"):
        terms.terms(q[:, :5], qd[:, :5])
    qd[1, 2] = np.nan
    with pytest.raises(InputValueError, match="qd must be finite"):
        terms.terms(q, qd)
