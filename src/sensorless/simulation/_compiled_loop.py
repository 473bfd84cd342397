"""The simulation loop with its samples compiled: runs of samples in one numba call each.

:func:`sensorless.simulation.simulator.simulate` uses :func:`run_compiled`
when the plant compiles (:func:`~sensorless.simulation.compiled.compile_plant`)
and the controller is a plain :class:`~sensorless.simulation.controllers.JointPID`
or :class:`~sensorless.simulation.controllers.ComputedTorque`.
Every sample runs in :func:`sensorless.simulation._loop_kernel.run_samples`,
in runs of 1000 between calls of ``progress``. What does not depend on the
state is computed here beforehand, for all samples at once: the contact
forces of each contact over its window (the kernel turns them into joint
torques with the Jacobian at the state it reaches), the labels of the active
contact, the friction compensation at the desired velocity, and the encoder
noise, drawn in one call, which gives the numbers that one draw per sample
gives (a :class:`numpy.random.Generator` fills an array from its stream in order).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .._validation import FloatArray
from ..robots.recursion import frame_with_z, joint_axis
from .collisions import ContactSet
from .compiled import CompiledPlant, model_constants
from .controllers import ComputedTorque, JointPID, friction_torque
from .plants import PlantState
from .sensors import SensorModel

__all__ = ["LoopInputs", "run_compiled", "supports_loop"]

_CHUNK = 1000  # samples between calls of ``progress``, as in the reference loop


@dataclass(frozen=True)
class LoopInputs:
    """What the loop reads: trajectory, contacts, and where it writes its log.

    Attributes
    ----------
    t : ndarray of shape (n_samples,)
        Sample times [s].
    q_des, qd_des, qdd_des : ndarray of shape (n_samples, n_dof)
        Desired positions [rad], velocities [rad/s] and accelerations [rad/s²].
    logged : ndarray of shape (6, n_samples, n_dof)
        Output: measured q, command, true q, true q̇, friction, elastic torque.
    tau_c : ndarray of shape (n_samples, n_dof)
        Output: contact torque [N m].
    collision_id : ndarray of shape (n_samples,)
        Output: id of the active contact, 0 outside contacts.
    """

    t: FloatArray
    q_des: FloatArray
    qd_des: FloatArray
    qdd_des: FloatArray
    logged: FloatArray
    tau_c: FloatArray
    collision_id: np.ndarray


def _nominal_constants(controller: JointPID) -> FloatArray | None:
    return model_constants(controller.model.pinocchio_model)


def _pack_contacts(
    contacts: ContactSet, plant: CompiledPlant, t: FloatArray
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Table (n_contacts, 7), forces (n_rows, 3) [N] of :func:`run_samples`, touched samples."""
    model = plant.plant.robot.pinocchio_model
    table = np.zeros((len(contacts), 7))
    forces = [np.zeros((0, 3))]
    row = 0
    touched = np.zeros(t.shape[0], dtype=bool)
    for c, contact in enumerate(contacts):
        inside = np.flatnonzero((contact.profile.start <= t) & (t <= contact.profile.end))
        first, stop = (int(inside[0]), int(inside[-1]) + 1) if inside.size else (0, 0)
        touched[first:stop] = True
        # The point in the joint's canonical frame (z along its axis), as the kernel's poses.
        frame = frame_with_z(joint_axis(model, contact.link)[1])
        table[c] = (contact.link - 1, *(frame.T @ contact.point), first, stop, row)
        forces.append(contact.force(t[first:stop]).reshape(-1, 3))
        row += stop - first
    return table, np.ascontiguousarray(np.concatenate(forces)), np.flatnonzero(touched)


def supports_loop(controller: object) -> bool:
    """Whether the compiled loop runs this controller: a plain JointPID or ComputedTorque."""
    if type(controller) is ComputedTorque:
        return _nominal_constants(controller) is not None
    if type(controller) is not JointPID:
        return False
    return not controller.gravity_compensation or _nominal_constants(controller) is not None


def run_compiled(
    plant: CompiledPlant,
    state: PlantState,
    controller: JointPID,
    sensors: SensorModel,
    contacts: ContactSet,
    inputs: LoopInputs,
    period: float,
    substeps: int,
    position_rng: np.random.Generator,
    progress: Callable[[int, int], None] | None,
) -> None:
    """Run every sample of the loop into ``inputs``' output arrays."""
    from . import _loop_kernel

    n = plant.n_dof
    n_samples = inputs.t.shape[0]
    step, std = sensors.position_parameters(n)
    quantised, noisy = bool(np.any(step)), bool(np.any(std))
    gains = np.column_stack(  # C-contiguous, the layout the kernel was compiled for
        [controller.kp, controller.ki, controller.kd, np.asarray(controller.torque_limit),
         np.where(step > 0.0, step, 1.0), (step > 0.0).astype(float), std]
    )  # fmt: skip
    noise = position_rng.standard_normal((n_samples, n)) if noisy else np.zeros((1, n))
    desired = np.zeros((4, n_samples, n))
    desired[0], desired[1], desired[3] = inputs.q_des, inputs.qd_des, inputs.qdd_des
    nominal_friction = controller.model.friction
    if controller.friction_compensation and nominal_friction is not None:
        desired[2] = friction_torque(nominal_friction, inputs.qd_des)
    computed = type(controller) is ComputedTorque
    compensated = computed or controller.gravity_compensation
    nominal = _nominal_constants(controller) if compensated else None
    flags = np.array(
        [plant.flexible, nominal is not None and not computed, quantised, noisy, computed],
        dtype=np.int64,
    )
    values = np.zeros(4 * n + 1)
    parts = [state.q, state.qd] + ([state.theta, state.thetad] if plant.flexible else [])
    values[: len(parts) * n] = np.concatenate(parts)  # type: ignore[arg-type]
    values[4 * n] = state.t
    bristles = np.zeros((2, n))
    for row, z in enumerate((state.z, state.z_motor)):
        if z is not None:
            bristles[row] = z
    table, forces, touched = _pack_contacts(contacts, plant, inputs.t)
    if touched.size:
        inputs.collision_id[touched] = contacts.active_id(inputs.t[touched])
    # The controller's initial state: zero integral, previous position q(0) (``initial_state``).
    arrays = (
        flags, values, bristles, np.stack([np.zeros(n), state.q.copy()]), gains,
        plant.consts, plant.loop, np.stack(plant.frictions), np.zeros((2, n, 5)),
        plant.consts if nominal is None else nominal, desired, noise, inputs.tau_c, table,
        forces, np.zeros((n, 12)), inputs.logged, *plant.scratch,
    )  # fmt: skip
    for start in range(0, n_samples, _CHUNK):
        stop = min(start + _CHUNK, n_samples)
        _loop_kernel.run_samples(start, stop, period, substeps, *arrays)
        if progress is not None:
            progress(stop, n_samples)
