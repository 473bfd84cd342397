"""Compiled (numba) samples of the simulation loop: contacts, encoder, controller, log, plant.

Importing this module requires numba. :func:`run_samples` does, for each
sample k, what the reference loop of
:func:`sensorless.simulation.simulator.simulate` does: read the encoder
(quantise, then add the noise drawn beforehand); compute the command of a
:class:`~sensorless.simulation.controllers.JointPID` (nominal gravity g(q) by
``rnea(q, 0, 0)``) or of a
:class:`~sensorless.simulation.controllers.ComputedTorque` (nominal inverse
dynamics by ``rnea``), with the friction compensation at the desired velocity
computed beforehand; evaluate the contact torque τ_c = J_c(q)ᵀ f of every
contact whose window holds the sample (its force f computed beforehand); log
the true state, its friction and the elastic torque; integrate one period of
the plant (:mod:`sensorless.simulation._plant_kernels`) with τ_c held.

Arrays: ``state`` (4 n_dof + 1,) = the plant's x or y, then the clock t [s]
at index 4 n_dof; ``bristles`` (2, n_dof) link- and motor-side z;
``controller`` (2, n_dof) the integral of the error and the previous
measured position; ``gains`` (n_dof, 7) the columns k_p, k_i, k_d, torque
limit, encoder step, encoder on (1/0), position noise σ; ``flags`` the
integers (flexible, gravity compensation, quantised, noisy, computed
torque); ``nominal`` the nominal robot's recursion constants; ``contacts``
(n_contacts, 7) per contact its link (0-based joint index), the point in the
link's canonical frame [m], its first and last-plus-one sample and the row
of its first force in ``forces`` (n_rows, 3) [N, base frame]; ``poses``
(n_dof, 12) scratch: each joint frame's rotation in the base frame
(row-major) and origin [m].
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from .._validation import FloatArray
from ..robots import _dynamics_numba as dyn
from . import _friction_kernels as fk
from . import _plant_kernels as pk

__all__ = ["run_samples"]

IntArray = NDArray[np.int64]


@njit(cache=True)
def _round_half_even(x: float) -> float:
    """``numpy.round`` of one value: to the nearest integer, ties to even."""
    low = math.floor(x)
    rest = x - low
    if rest > 0.5 or (rest == 0.5 and low % 2.0 != 0.0):
        return low + 1.0
    return low


@njit(cache=True)
def _contact_torque(
    k: int,
    q: FloatArray,
    consts: FloatArray,
    contacts: FloatArray,
    forces: FloatArray,
    work: FloatArray,
    poses: FloatArray,
    out: FloatArray,
) -> bool:
    """Σ J_c(q)ᵀ f_c over the contacts whose window holds sample k into out; False if none."""
    n = q.shape[0]
    found = False
    for c in range(contacts.shape[0]):
        if not contacts[c, 4] <= k < contacts[c, 5]:
            continue
        if not found:
            found = True
            for j in range(n):
                out[j] = 0.0
            dyn.transforms(q, consts, work)
            for j in range(n):
                parent = int(consts[j, 23])
                for a in range(3):
                    for b in range(3):
                        total = 0.0
                        for m in range(3):
                            w = (1.0 if a == m else 0.0) if parent < 0 else poses[parent, 3 * a + m]
                            total += w * work[j, 3 * b + m]
                        poses[j, 3 * a + b] = total
                    origin = 0.0 if parent < 0 else poses[parent, 9 + a]
                    for m in range(3):
                        w = (1.0 if a == m else 0.0) if parent < 0 else poses[parent, 3 * a + m]
                        origin += w * work[j, 9 + m]
                    poses[j, 9 + a] = origin
        link = int(contacts[c, 0])
        row = int(contacts[c, 6]) + k - int(contacts[c, 4])
        fx, fy, fz = forces[row, 0], forces[row, 1], forces[row, 2]
        point = np.empty(3)
        for a in range(3):
            point[a] = poses[link, 9 + a]
            for m in range(3):
                point[a] += poses[link, 3 * a + m] * contacts[c, 1 + m]
        j = link
        while j >= 0:
            ax, ay, az = poses[j, 2], poses[j, 5], poses[j, 8]
            if consts[j, 24] == 0.0:
                dx = point[0] - poses[j, 9]
                dy = point[1] - poses[j, 10]
                dz = point[2] - poses[j, 11]
                ax, ay, az = ay * dz - az * dy, az * dx - ax * dz, ax * dy - ay * dx
            out[j] += ax * fx + ay * fy + az * fz
            j = int(consts[j, 23])
    return found


@njit(cache=True)
def run_samples(
    k0: int,
    k1: int,
    period: float,
    substeps: int,
    flags: IntArray,
    state: FloatArray,
    bristles: FloatArray,
    controller: FloatArray,
    gains: FloatArray,
    consts: FloatArray,
    loop: FloatArray,
    frictions: FloatArray,
    held: FloatArray,
    nominal: FloatArray,
    desired: FloatArray,
    noise: FloatArray,
    tau_c: FloatArray,
    contacts: FloatArray,
    forces: FloatArray,
    poses: FloatArray,
    logged: FloatArray,
    work: FloatArray,
    inertia: FloatArray,
    acc: FloatArray,
    vectors: FloatArray,
    matrices: FloatArray,
) -> None:
    """Samples k0 ≤ k < k1 of the loop, state in place.

    ``frictions`` (2, n_dof, 24) and ``held`` (2, n_dof, 5): joint or link
    side, motor side. ``desired`` (4, n_samples, n_dof): q_d [rad], q̇_d
    [rad/s], the friction compensation [N m] and q̈_d [rad/s²]. ``logged``
    (6, n_samples, n_dof): measured q [rad], command [N m], true q [rad], true q̇ [rad/s],
    friction [N m], elastic torque [N m] (flexible plants).
    """
    n = bristles.shape[1]
    flexible, gravity, quantised, noisy = flags[0], flags[1], flags[2], flags[3]
    computed = flags[4]
    speed, accel, inverse = vectors[7, :n], vectors[8, :n], vectors[9, :n]
    integral, previous = controller[0], controller[1]
    y = state[: 4 * n] if flexible else state[: 2 * n]
    z, z_motor = bristles[0], bristles[1]
    for k in range(k0, k1):
        row = logged[0, k]
        for j in range(n):
            value = y[j]
            if quantised and gains[j, 5] != 0.0:
                value = _round_half_even(value / gains[j, 4]) * gains[j, 4]
            if noisy:
                value = value + gains[j, 6] * noise[k, j]
            row[j] = value
        q_meas = row
        if gravity:  # g(q) = rnea(q, 0, 0); row 10 of ``vectors`` stays zero
            dyn.rnea(q_meas, vectors[10, :n], vectors[10, :n], nominal, work, inertia, acc, inverse)
        command = logged[1, k]
        for j in range(n):
            error = desired[0, k, j] - q_meas[j]
            integral[j] = integral[j] + error * period
            velocity = (q_meas[j] - previous[j]) / period
            u = (
                gains[j, 0] * error
                + gains[j, 1] * integral[j]
                + gains[j, 2] * (desired[1, k, j] - velocity)
            )
            previous[j] = q_meas[j]
            if computed:
                speed[j] = velocity
                accel[j] = desired[3, k, j] + u
                continue
            if gravity:
                u = u + inverse[j]
            u = u + desired[2, k, j]
            limit = gains[j, 3]
            command[j] = min(max(u, -limit), limit)
        if computed:
            dyn.rnea(q_meas, speed, accel, nominal, work, inertia, acc, inverse)
            for j in range(n):
                u = inverse[j] + desired[2, k, j]
                limit = gains[j, 3]
                command[j] = min(max(u, -limit), limit)
        _contact_torque(k, y[:n], consts, contacts, forces, work, poses, tau_c[k])
        t = state[4 * n]
        fk.hold_drift(frictions[0], t, held[0])
        for j in range(n):
            logged[2, k, j] = y[j]
            logged[3, k, j] = y[n + j]
            logged[4, k, j] = fk.recorded(frictions[0], held[0], z, j, y[n + j])
            if flexible:
                logged[5, k, j] = loop[j, 0] * (y[2 * n + j] - y[j])
        if flexible:
            pk.flexible_period(y, z, z_motor, t, command, tau_c[k], period, substeps, consts,
                               loop, frictions[0], held[0], frictions[1], held[1],
                               work, inertia, acc, vectors, matrices)  # fmt: skip
        else:
            drive = vectors[11, :n]
            for j in range(n):
                drive[j] = command[j] + tau_c[k, j]
            pk.rigid_period(y, z, t, drive, period, substeps, consts, frictions[0], held[0],
                            work, inertia, acc, vectors[:11])  # fmt: skip
        state[4 * n] = t + period
