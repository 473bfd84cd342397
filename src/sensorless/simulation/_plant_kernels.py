"""Compiled (numba) control periods of the simulated plants.

Importing this module requires numba. Each function integrates one control
period, all its substeps, in place, with the arithmetic of the reference
methods in :mod:`sensorless.simulation.plants` (rigid: classical RK4 with the
friction held per substep and the exact bristle update after it) and
:mod:`sensorless.simulation._stiff` (flexible: the ROS2 step); forward
dynamics and M(q) come from :mod:`sensorless.robots._dynamics_numba`, friction
from :mod:`sensorless.simulation._friction_kernels`.

Arrays: ``x`` = (q, q̇) of shape (2 n_dof,) or ``y`` = (q, q̇, θ, θ̇) of shape
(4 n_dof,); ``z``, ``z_motor`` the bristles (n_dof,); ``t`` the period's start
[s]; ``consts`` the robot's recursion constants; ``fr``/``held`` the packed
friction and its held terms; ``loop`` (n_dof, 5) the columns K, D, B_m, D_m, B
of :class:`~sensorless.simulation._stiff.SpringLoop`; ``scratch`` the tuple of
:func:`scratch`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._validation import FloatArray
from ..robots import _dynamics_numba as dyn
from . import _friction_kernels as fk

__all__ = ["flexible_period", "rigid_period", "scratch"]

#: γ of ROS2, as in :mod:`sensorless.simulation._stiff`.
GAMMA = 1.0 - 1.0 / math.sqrt(2.0)


@njit(cache=True)
def scratch(n_dof: int) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Scratch of the period kernels: the dynamics' three arrays, ``vectors`` (12, 4 n_dof)
    and ``matrices`` (2, n_dof, n_dof)."""
    work, inertia, acc = dyn.scratch(n_dof)
    return work, inertia, acc, np.zeros((12, 4 * n_dof)), np.zeros((2, n_dof, n_dof))


@njit(cache=True)
def rigid_period(
    x: FloatArray,
    z: FloatArray,
    t: float,
    drive: FloatArray,
    dt: float,
    substeps: int,
    consts: FloatArray,
    fr: FloatArray,
    held: FloatArray,
    work: FloatArray,
    inertia: FloatArray,
    acc: FloatArray,
    vectors: FloatArray,
) -> None:
    """One period of the rigid plant (``RigidPlant.advance``), x and z in place.

    ``drive`` = τ_m + τ_c [N m], held; drifting friction held at ``t``.
    """
    n = z.shape[0]
    h = dt / substeps
    fk.hold_drift(fr, t, held)
    slope = vectors[0:4, : 2 * n]
    stage = vectors[4, : 2 * n]
    force = vectors[5, :n]
    qdd = vectors[6, :n]
    weights = (0.5 * h, 0.5 * h, h, 0.0)
    for _ in range(substeps):
        fk.hold_bristles(fr, z, held)
        for j in range(2 * n):
            stage[j] = x[j]
        for i in range(4):
            for j in range(n):
                force[j] = drive[j] - fk.stage(fr, held, j, stage[n + j])
            dyn.aba(stage[:n], stage[n:], force, consts, work, inertia, acc, qdd)
            for j in range(n):
                slope[i, j] = stage[n + j]
                slope[i, n + j] = qdd[j]
            weight = weights[i]
            if weight != 0.0:
                for j in range(2 * n):
                    stage[j] = slope[i, j] * weight + x[j]
        sixth = h / 6.0
        for j in range(2 * n):
            new = x[j] + sixth * (slope[0, j] + 2.0 * (slope[1, j] + slope[2, j]) + slope[3, j])
            if j >= n:
                fk.advance_bristles(fr, z, j - n, 0.5 * (x[j] + new), h)
            x[j] = new


@njit(cache=True)
def _cholesky(a: FloatArray) -> None:
    """Lower Cholesky factor of the SPD matrix ``a``, in place (upper triangle left alone)."""
    n = a.shape[0]
    for j in range(n):
        total = a[j, j]
        for m in range(j):
            total -= a[j, m] * a[j, m]
        a[j, j] = math.sqrt(total)
        for i in range(j + 1, n):
            total = a[i, j]
            for m in range(j):
                total -= a[i, m] * a[j, m]
            a[i, j] = total / a[j, j]


@njit(cache=True)
def _solve(factor: FloatArray, b: FloatArray) -> None:
    """b ← A⁻¹ b with the lower Cholesky factor of A, in place."""
    n = b.shape[0]
    for i in range(n):
        total = b[i]
        for m in range(i):
            total -= factor[i, m] * b[m]
        b[i] = total / factor[i, i]
    for i in range(n - 1, -1, -1):
        total = b[i]
        for m in range(i + 1, n):
            total -= factor[m, i] * b[m]
        b[i] = total / factor[i, i]


@njit(cache=True)
def _derivative(
    y: FloatArray,
    command: FloatArray,
    tau_c: FloatArray,
    loop: FloatArray,
    consts: FloatArray,
    frl: FloatArray,
    heldl: FloatArray,
    frm: FloatArray,
    heldm: FloatArray,
    work: FloatArray,
    inertia: FloatArray,
    acc: FloatArray,
    link: FloatArray,
    f: FloatArray,
) -> None:
    """f(y) of the flexible plant (SpringLoop.advance's ``derivative``) into f (4 n_dof,)."""
    n = link.shape[0]
    for j in range(n):
        qd, thetad = y[n + j], y[3 * n + j]
        deflection_rate = thetad - qd
        spring = loop[j, 0] * (y[2 * n + j] - y[j])
        link[j] = spring + loop[j, 1] * deflection_rate + tau_c[j] - fk.stage(frl, heldl, j, qd)
        motor = (command[j] - spring - loop[j, 3] * deflection_rate) * (1.0 / loop[j, 2])
        f[3 * n + j] = motor - fk.stage(frm, heldm, j, thetad) * (1.0 / loop[j, 4])
        f[j] = qd
        f[2 * n + j] = thetad
    dyn.aba(y[:n], y[n : 2 * n], link, consts, work, inertia, acc, f[n : 2 * n])


@njit(cache=True)
def _stage_solve(
    r: FloatArray,
    link_force: FloatArray,
    loop: FloatArray,
    c: float,
    factor: FloatArray,
    out: FloatArray,
) -> None:
    """k with (I − γ h J) k = r into out (SpringLoop.advance's ``solve``)."""
    n = link_force.shape[0]
    kv = out[n : 2 * n]
    for j in range(n):
        k, d, bm, dm = loop[j, 0], loop[j, 1], loop[j, 2], loop[j, 3]
        ck = c * k
        alpha_l = c * (ck + d)
        beta = bm + c * (ck + dm)
        spring = ck * (r[2 * n + j] - r[j])
        motor = bm * r[3 * n + j] - spring
        kv[j] = link_force[j] + spring + alpha_l / beta * motor
    _solve(factor, kv)
    for j in range(n):
        k, d, bm, dm = loop[j, 0], loop[j, 1], loop[j, 2], loop[j, 3]
        ck = c * k
        alpha_m = c * (ck + dm)
        beta = bm + alpha_m
        motor = bm * r[3 * n + j] - ck * (r[2 * n + j] - r[j])
        kw = (motor + alpha_m * kv[j]) / beta
        out[j] = r[j] + c * kv[j]
        out[2 * n + j] = r[2 * n + j] + c * kw
        out[3 * n + j] = kw


@njit(cache=True)
def flexible_period(
    y: FloatArray,
    z: FloatArray,
    z_motor: FloatArray,
    t: float,
    command: FloatArray,
    tau_c: FloatArray,
    dt: float,
    substeps: int,
    consts: FloatArray,
    loop: FloatArray,
    frl: FloatArray,
    heldl: FloatArray,
    frm: FloatArray,
    heldm: FloatArray,
    work: FloatArray,
    inertia: FloatArray,
    acc: FloatArray,
    vectors: FloatArray,
    matrices: FloatArray,
) -> None:
    """One period of the flexible plant by ROS2 substeps (``FlexiblePlant.advance``), in place.

    ``command`` is τ_m, or u with the torque loop (``loop`` holds B_θ, D_s then).
    """
    n = z.shape[0]
    h = dt / substeps
    c = GAMMA * h
    fk.hold_drift(frl, t, heldl)
    fk.hold_drift(frm, t, heldm)
    f, k1, k2, stage = vectors[0], vectors[1], vectors[2], vectors[3]
    link, force = vectors[4, :n], vectors[5, :n]
    mass, factor = matrices[0], matrices[1]
    for _ in range(substeps):
        fk.hold_bristles(frl, z, heldl)
        fk.hold_bristles(frm, z_motor, heldm)
        dyn.crba(y[:n], consts, work, inertia, mass)
        for i in range(n):
            for j in range(n):
                factor[i, j] = mass[i, j]
            factor[i, i] += (
                c
                * (c * loop[i, 0] + loop[i, 1])
                / (loop[i, 2] + c * (c * loop[i, 0] + loop[i, 3]))
                * loop[i, 2]
            )
        _cholesky(factor)
        _derivative(y, command, tau_c, loop, consts, frl, heldl, frm, heldm,
                    work, inertia, acc, link, f)  # fmt: skip
        for i in range(n):
            total = 0.0
            for j in range(n):
                total += mass[i, j] * f[n + j]
            force[i] = total
        _stage_solve(f, force, loop, c, factor, k1)
        for j in range(4 * n):
            stage[j] = y[j] + h * k1[j]
        _derivative(stage, command, tau_c, loop, consts, frl, heldl, frm, heldm,
                    work, inertia, acc, link, f)  # fmt: skip
        for i in range(n):
            total = 0.0
            for j in range(n):
                total += mass[i, j] * (f[n + j] - 2.0 * k1[n + j])
            force[i] = total
        for j in range(4 * n):
            f[j] -= 2.0 * k1[j]
        _stage_solve(f, force, loop, c, factor, k2)
        for j in range(4 * n):
            new = y[j] + (1.5 * h) * k1[j] + (0.5 * h) * k2[j]
            if n <= j < 2 * n:
                fk.advance_bristles(frl, z, j - n, 0.5 * (y[j] + new), h)
            elif j >= 3 * n:
                fk.advance_bristles(frm, z_motor, j - 3 * n, 0.5 * (y[j] + new), h)
            y[j] = new
