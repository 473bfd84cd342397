"""The simulation loop: plant, controller, sensors and contacts at a fixed control rate.

At each control instant t_k = k·dt the loop reads the sensors, computes the
command from the nominal model, logs the sample, and integrates the true
plant over [t_k, t_k + dt) with the command and the contact torque held
(zero-order hold, as a digital controller applies them). Every random draw
comes from one ``numpy.random.Generator`` seeded by ``seed``: the same inputs
and seed give the same bytes.

Two paths run this loop. The reference is the Python loop below with the
plant's own ``advance``. When numba is installed and every part is supported
(:func:`~sensorless.simulation.compiled.compile_plant`), the plant period is
one compiled call, and with a plain
:class:`~sensorless.simulation.controllers.JointPID` or
:class:`~sensorless.simulation.controllers.ComputedTorque` the samples run
compiled as well (:mod:`sensorless.simulation._compiled_loop`).
``backend="numpy"`` forces the reference.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from .._validation import FloatArray, check_dt
from ..exceptions import DimensionError, InputValueError
from ..io import Log
from ..trajectories import Trajectory
from ._compiled_loop import LoopInputs, run_compiled, supports_loop
from .collisions import ContactSet
from .compiled import check_backend, compile_plant
from .controllers import ControllerState, JointPID
from .plants import FlexiblePlant, PlantState, RigidPlant
from .sensors import SensorModel

__all__ = ["SimulationResult", "simulate"]

Plant = RigidPlant | FlexiblePlant


@dataclass(frozen=True)
class SimulationResult:
    """A simulated run.

    Attributes
    ----------
    log : Log
        What a user would record (measured q, τ_m, τ_J) plus the ground truth
        (true q, q̇, τ_c, collision id).
    friction : ndarray of shape (n_samples, n_dof)
        True friction torque at each sample [N m] (link side for flexible arms).
    command : ndarray of shape (n_samples, n_dof)
        Command u actually applied over each period [N m] (before measurement errors).
    desired : ndarray of shape (n_samples, n_dof)
        Desired joint positions of the trajectory [rad].
    substeps : int
        Integrator substeps per control period.
    backend : str
        The path that ran: ``"numpy"`` (the reference), ``"numba-plant"``
        (compiled plant period, Python loop) or ``"numba"`` (compiled samples).
    """

    log: Log
    friction: FloatArray
    command: FloatArray
    desired: FloatArray
    substeps: int
    metadata: dict[str, Any] = field(default_factory=dict)
    backend: str = "numpy"

    def to_pandas(self) -> pd.DataFrame:
        """The log as a table (see :meth:`sensorless.io.Log.to_pandas`)."""
        return self.log.to_pandas()


def simulate(
    plant: Plant,
    controller: JointPID,
    trajectory: Trajectory,
    duration: float,
    *,
    dt: float = 1e-3,
    sensors: SensorModel | None = None,
    contacts: ContactSet | None = None,
    seed: int = 0,
    substeps: int | None = None,
    metadata: dict[str, Any] | None = None,
    progress: Callable[[int, int], None] | None = None,
    backend: str = "auto",
) -> SimulationResult:
    """Simulate a controlled arm following ``trajectory``.

    Parameters
    ----------
    plant : RigidPlant or FlexiblePlant
        The true arm.
    controller : JointPID
        Controller built on the nominal model.
    trajectory : Trajectory
        Desired motion; the run starts at rest at its initial position.
    duration : float
        Simulated time [s].
    dt : float
        Control and logging period [s] (1 kHz by default).
    sensors : SensorModel, optional
        Measurement errors; perfect by default.
    contacts : ContactSet, optional
        External contacts; none by default.
    seed : int
        Seed of the sensor noise (three independent streams are spawned
        from it: positions, motor torques, joint torques).
    substeps : int, optional
        Integrator substeps per period; by default chosen for stability
        (:meth:`RigidPlant.substeps`, :meth:`FlexiblePlant.substeps`).
    metadata : dict, optional
        Stored in the log's metadata.
    progress : callable(done, total), optional
        Called every 1000 samples and at the end.
    backend : {"auto", "numba", "numpy"}
        ``"numpy"``: the reference path. ``"auto"`` and ``"numba"``: the
        compiled path where numba is installed and the plant supported (the
        same results to integration round-off), else the reference;
        ``"numba"`` without numba is an error.

    Returns
    -------
    SimulationResult
    """
    period = check_dt(dt)
    if not np.isfinite(duration) or duration <= 0:
        raise InputValueError(f"duration must be a positive number of seconds; got {duration}")
    n = plant.n_dof
    if controller.n_dof != n or trajectory.n_dof != n:
        raise DimensionError(
            f"plant has {n} joints, controller {controller.n_dof}, trajectory {trajectory.n_dof}"
        )
    compiled = compile_plant(plant) if check_backend(backend) else None
    sensors = sensors or SensorModel()
    contacts = contacts or ContactSet([])
    contacts.check(plant.robot)
    # Independent noise streams: the position noise (inside the loop) does not
    # depend on whether the torque sensors are simulated, and vice versa.
    position_rng, motor_rng, joint_rng = (
        np.random.default_rng(child) for child in np.random.SeedSequence(seed).spawn(3)
    )
    n_samples = round(duration / period) + 1
    t = np.arange(n_samples, dtype=np.float64) * np.float64(period)
    q_des, qd_des, qdd_des = trajectory.evaluate(t)

    state = plant.initial_state(q_des[0])
    n_sub = plant.substeps(period, q_des[0]) if substeps is None else int(substeps)
    if n_sub < 1:
        raise InputValueError(f"substeps must be >= 1; got {substeps}")
    ctrl = controller.initial_state(q_des[0])
    flexible = isinstance(plant, FlexiblePlant)

    logged = np.zeros((6, n_samples, n))
    q_meas, command, q_true, qd_true, friction = logged[:5]
    elastic = logged[5] if flexible else None
    tau_c = np.zeros((n_samples, n))
    collision_id = np.zeros(n_samples, dtype=np.int64)
    if compiled is not None and supports_loop(controller):
        inputs = LoopInputs(t, q_des, qd_des, qdd_des, logged, tau_c, collision_id)
        run_compiled(compiled, state, controller, sensors, contacts, inputs, period, n_sub,
                     position_rng, progress)  # fmt: skip
        path = "numba"
    else:
        advance = plant.advance if compiled is None else compiled.advance
        path = "numpy" if compiled is None else "numba-plant"
        _run_python(plant, advance, controller, sensors, contacts, state, ctrl, t, q_des,
                    qd_des, qdd_des, logged, tau_c, collision_id, period, n_sub,
                    position_rng, progress)  # fmt: skip

    # Torque readings are not fed back, so they are measured after the loop.
    tau_m = sensors.measure_motor_torque(command, motor_rng)
    tau_j = None
    if elastic is not None:
        tau_j, _ = sensors.measure_joint_torque(
            elastic, sensors.initial_state(n, elastic[0]), joint_rng
        )
    meta = dict(metadata or {})
    meta.setdefault("sample_rate", 1.0 / period)
    meta.setdefault("collisions", contacts.summaries())
    meta.setdefault("seed", seed)
    meta["substeps"] = n_sub
    log = Log(
        t=t,
        q=q_meas,
        tau_m=tau_m,
        tau_j=tau_j,
        q_true=q_true,
        qd_true=qd_true,
        tau_c=tau_c,
        collision_id=collision_id,
        metadata=meta,
    )
    return SimulationResult(log, friction, command, q_des, n_sub, meta, path)


def _run_python(
    plant: Plant,
    advance: Callable[[PlantState, FloatArray, FloatArray, float, int], PlantState],
    controller: JointPID,
    sensors: SensorModel,
    contacts: ContactSet,
    state: PlantState,
    ctrl: ControllerState,
    t: FloatArray,
    q_des: FloatArray,
    qd_des: FloatArray,
    qdd_des: FloatArray,
    logged: FloatArray,
    tau_c: FloatArray,
    collision_id: NDArray[np.int64],
    period: float,
    n_sub: int,
    position_rng: np.random.Generator,
    progress: Callable[[int, int], None] | None,
) -> None:
    """The reference loop, one sample at a time in Python (``advance``: the plant period)."""
    n, n_samples = plant.n_dof, t.shape[0]
    q_meas, command, q_true, qd_true, friction = logged[:5]
    elastic = logged[5] if isinstance(plant, FlexiblePlant) else None
    # Everything below is checked once, here: the loop calls unchecked paths.
    read_position = sensors.position_reader(n, position_rng)
    step = controller._step_unchecked
    windows = [(c.profile.start, c.profile.end, c) for c in contacts]
    inside = [(start <= t) & (t <= end) for start, end, _ in windows]
    touched = np.logical_or.reduce(inside) if inside else np.zeros(n_samples, dtype=bool)
    no_contact = np.zeros(n)
    for k in range(n_samples):
        q_meas[k] = read_position(state.q)
        command[k], ctrl = step(ctrl, q_meas[k], q_des[k], qd_des[k], period, qdd_des[k])
        contact = no_contact
        if touched[k]:
            active = [c for (_, _, c), mask in zip(windows, inside, strict=True) if mask[k]]
            contact = np.sum([c.joint_torque(plant.robot, state.q, t[k]) for c in active], axis=0)
            tau_c[k] = contact
            collision_id[k] = active[0].id if len(active) == 1 else contacts.active_id(t[k])
        q_true[k] = state.q
        qd_true[k] = state.qd
        if elastic is not None:
            elastic[k] = plant.elastic_torque(state)
        friction[k] = plant.joint_friction(state)
        state = advance(state, command[k], contact, period, n_sub)
        if progress is not None and (k % 1000 == 999 or k == n_samples - 1):
            progress(k + 1, n_samples)
