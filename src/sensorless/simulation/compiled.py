"""The compiled plant: one numba call per control period, and when it applies.

:func:`compile_plant` packs a :class:`~sensorless.simulation.plants.RigidPlant`
or a :class:`~sensorless.simulation.plants.FlexiblePlant` (Rosenbrock
integrator) into flat arrays once: the robot's constants as
:class:`~sensorless.robots.recursion.MomentumTerms` reads them, the friction
models (:func:`pack_friction`), the spring loop. :class:`CompiledPlant` then
integrates one period, all substeps, in :mod:`sensorless.simulation._plant_kernels`,
with the arithmetic of the plant's own ``advance``, the reference, which stays
the path without numba and the one ``backend="numpy"`` forces.

Supported: trees of one-DoF revolute or prismatic joints, friction that is
none, :class:`~sensorless.friction.Coulomb`, :class:`~sensorless.friction.Viscous`,
:class:`~sensorless.friction.CoulombViscous`, :class:`~sensorless.friction.Stribeck`,
:class:`~sensorless.friction.Sigmoid`, :class:`~sensorless.friction.HystereticError`,
:class:`~sensorless.friction.LuGre`, or a :class:`~sensorless.friction.DriftingFriction`
around a stateless one of these. Anything else gives ``None``: the caller
keeps the reference path.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..exceptions import InputValueError, ModelError, UnknownNameError
from ..friction import DriftingFriction, LuGre
from ..friction._kinds import STATIC_KINDS
from ..robots.recursion import MomentumTerms
from .plants import FlexiblePlant, Friction, PlantState, RigidPlant

_kernels: ModuleType | None
try:
    from . import _plant_kernels as _kernels
except ImportError:  # numba is an optional extra
    _kernels = None

__all__ = [
    "BACKENDS",
    "CompiledPlant",
    "compile_plant",
    "model_constants",
    "numba_available",
    "pack_friction",
]

#: Backend names accepted by :func:`~sensorless.simulation.simulator.simulate`.
BACKENDS = ("auto", "numba", "numpy")

_STATIC: dict[type, tuple[float, tuple[str, ...]]] = {
    **{model: (float(kind), names) for model, (kind, names) in STATIC_KINDS.items()},
    LuGre: (7.0, ("sigma0", "sigma1", "sigma2", "fc", "fs", "vs", "delta")),
}


def numba_available() -> bool:
    """True when the compiled plant can be used (numba is importable)."""
    return _kernels is not None


def check_backend(backend: str) -> bool:
    """Whether ``backend`` asks for the compiled path; errors on an unknown or impossible one."""
    if backend not in BACKENDS:
        raise UnknownNameError(f"unknown backend {backend!r}; options: {list(BACKENDS)}")
    if backend == "numba" and _kernels is None:
        raise InputValueError(
            "backend 'numba' needs numba (pip install sensorless[fast]); use 'auto' or 'numpy'"
        )
    return backend != "numpy" and _kernels is not None


def pack_friction(friction: Friction, n_dof: int) -> FloatArray | None:
    """The friction as the (n_dof, 24) array of :mod:`sensorless.simulation._friction_kernels`.

    ``None`` when the model is not one the kernels know (exact types only: a
    subclass may change the law).
    """
    packed = np.zeros((n_dof, 24))
    if friction is None:
        return packed
    base: Any = friction
    if type(friction) is DriftingFriction:
        base = friction.base
        # The drift's time laws, in the order DriftingFriction evaluates them.
        packed[:, 1] = 1.0
        packed[:, 9] = friction.warmup
        packed[:, 10] = friction.warmup_viscous
        packed[:, 11] = friction.time_constant
        packed[:, 12] = friction.base_viscous
        packed[:, 13:16], packed[:, 16:19], packed[:, 19:22] = friction.offset_components
        if type(base) is LuGre:
            return None
    entry = _STATIC.get(type(base))
    if entry is None:
        return None
    kind, names = entry
    packed[:, 0] = kind
    for i, name in enumerate(names):
        packed[:, 2 + i] = np.broadcast_to(getattr(base, name), (n_dof,))
    if type(base) is LuGre:
        packed[:, 22] = float(np.all(np.asarray(base.delta) == 2.0))  # LuGre's Gaussian curve
    return packed


def model_constants(model: Any) -> FloatArray | None:
    """The recursion's per-joint constants of a Pinocchio model; None if it has other joints."""
    try:
        terms = MomentumTerms(model, backend="numpy")
    except ModelError:
        return None
    return np.ascontiguousarray(terms.kernel_constants)


class CompiledPlant:
    """A plant whose :meth:`advance` is one compiled call per period.

    Build it with :func:`compile_plant`, which says whether the plant is
    supported. The arrays are public to the simulator's compiled loop:
    ``consts`` (the true robot; the link side of a flexible one), ``frictions``
    (joint or link side, motor side), ``loop`` (K, D, B_m, D_m, B per joint;
    zeros for a rigid plant), ``held`` and ``scratch``.
    """

    def __init__(
        self, plant: RigidPlant | FlexiblePlant, consts: FloatArray, frictions: list[FloatArray]
    ) -> None:
        assert _kernels is not None  # compile_plant checked it
        n = plant.n_dof
        self.plant = plant
        self.flexible = isinstance(plant, FlexiblePlant)
        self.consts = consts
        self.frictions = frictions
        self.loop = np.zeros((n, 5))
        if isinstance(plant, FlexiblePlant):
            spring = plant._loop
            columns = (spring.stiffness, spring.damping, spring.loop_inertia,
                       spring.loop_damping, spring.motor_inertia)  # fmt: skip
            self.loop = np.ascontiguousarray(np.column_stack(columns), dtype=float)
        self.held = [np.zeros((n, 5)), np.zeros((n, 5))]
        self.scratch = _kernels.scratch(n)

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return self.plant.n_dof

    def advance(
        self, state: PlantState, tau_m: FloatArray, tau_c: FloatArray, dt: float, substeps: int
    ) -> PlantState:
        """One period ``dt`` [s] with τ_m (or u) and τ_c [N m] held, as the plant's ``advance``."""
        assert _kernels is not None
        n = self.n_dof
        z = np.zeros(n) if state.z is None else state.z.copy()
        if not self.flexible:
            x = np.concatenate((state.q, state.qd))
            drive = np.ascontiguousarray(tau_m + tau_c, dtype=float)
            _kernels.rigid_period(x, z, state.t, drive, dt, substeps, self.consts,
                                  self.frictions[0], self.held[0], *self.scratch[:4])  # fmt: skip
            return PlantState(x[:n], x[n:], None if state.z is None else z, t=state.t + dt)
        assert state.theta is not None and state.thetad is not None
        z_motor = np.zeros(n) if state.z_motor is None else state.z_motor.copy()
        y = np.concatenate((state.q, state.qd, state.theta, state.thetad))
        _kernels.flexible_period(
            y, z, z_motor, state.t,
            np.ascontiguousarray(tau_m, dtype=float), np.ascontiguousarray(tau_c, dtype=float),
            dt, substeps, self.consts, self.loop, self.frictions[0], self.held[0],
            self.frictions[1], self.held[1], *self.scratch,
        )  # fmt: skip
        return PlantState(
            y[:n], y[n : 2 * n], None if state.z is None else z, y[2 * n : 3 * n], y[3 * n :],
            None if state.z_motor is None else z_motor, state.t + dt,
        )  # fmt: skip


def compile_plant(plant: RigidPlant | FlexiblePlant) -> CompiledPlant | None:
    """The compiled form of ``plant``, or ``None`` when numba or a part of the plant is missing.

    Parameters
    ----------
    plant : RigidPlant or FlexiblePlant
        A flexible plant is supported with its Rosenbrock integrator only
        (``integrator="rk4"`` is the reference of that one).

    Returns
    -------
    CompiledPlant or None
    """
    if _kernels is None:
        return None
    n = plant.n_dof
    if isinstance(plant, FlexiblePlant):
        if plant.integrator != "rosenbrock":
            return None
        consts = model_constants(plant._link_model)
        frictions = [pack_friction(plant.link_friction, n), pack_friction(plant.motor_friction, n)]
    else:
        consts = model_constants(plant.robot.pinocchio_model)
        frictions = [pack_friction(plant.friction, n), pack_friction(None, n)]
    if consts is None or any(f is None for f in frictions):
        return None
    return CompiledPlant(plant, consts, [f for f in frictions if f is not None])
