"""The LuGre dynamic friction model with its bristle state, eq. (4.22).

Sign convention and shapes: :mod:`sensorless.friction`. The state is a plain
array passed in and returned, as ``zi``/``zf`` in :func:`scipy.signal.lfilter`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_joint_array, check_dt
from ..exceptions import DimensionError, InputValueError
from ._parameters import JointParameters, bound
from .static import stribeck_level

__all__ = ["LuGre"]


@dataclass(frozen=True, eq=False, init=False)
class LuGre(JointParameters):
    """LuGre dynamic friction model, eq. (4.22) and Canudas de Wit et al. (1995).

    With the bristle deflection ``z`` [rad] as state::

        zdot = qd - sigma0 |qd| / s(qd) * z                      (4.22a)
        tau  = sigma0 z + sigma1 zdot + sigma2 qd                (4.22b)
        s(qd) = fc + (fs - fc) exp(-|qd / vs|**delta)            (4.22c)

    The thesis writes ``exp(-alpha |qd|)``: use ``delta=1`` and
    ``vs=1/alpha``. ``delta=2`` is the Gaussian of the 1995 paper.

    The model (this object) holds constants only; the state is a plain array
    of shape ``(n_dof,)`` passed in and returned, as ``zi``/``zf`` in
    :func:`scipy.signal.lfilter`. :meth:`initial_state` gives the rest state.

    Discretisation: the velocity is held constant over each sample period,
    as a controller sampling at ``dt`` sees it. For a constant ``qd`` the
    bristle equation is linear in ``z``, ``zdot = qd - a z`` with
    ``a = sigma0 |qd| / s(qd) >= 0``, and :meth:`step` uses its exact
    solution ``z(t + dt) = z_ss + (z - z_ss) exp(-a dt)``,
    ``z_ss = sign(qd) s(qd) / sigma0``. This is unconditionally stable (no
    step-size limit even with the stiff Canudas parameters, where explicit
    Euler needs about 1e-6 s), keeps the invariant ``|z| <= max(fc, fs) /
    sigma0``, and tends to ``z + qd dt`` as ``a -> 0``. The torque is
    returned at the end of the step, with ``zdot`` evaluated from eq. (4.22a)
    at the new state; this makes the constant-velocity steady state exactly
    the Stribeck curve ``sign(qd) s(qd) + sigma2 qd``, and at zero velocity
    gives the pure spring torque ``sigma0 z``.

    Parameters
    ----------
    sigma0 : float or array-like of shape (n_dof,)
        Bristle stiffness [N m/rad], ``> 0``.
    sigma1 : float or array-like of shape (n_dof,)
        Bristle damping [N m s/rad], ``>= 0``.
    sigma2 : float or array-like of shape (n_dof,)
        Viscous coefficient [N m s/rad], ``>= 0``.
    fc : float or array-like of shape (n_dof,)
        Coulomb torque F_c [N m], ``> 0``.
    fs : float or array-like of shape (n_dof,)
        Stiction torque F_s [N m], ``> 0``.
    vs : float or array-like of shape (n_dof,)
        Stribeck velocity [rad/s], ``> 0``.
    delta : float or array-like of shape (n_dof,), default 2.0
        Stribeck exponent [-], ``> 0``.

    Examples
    --------
    >>> model = LuGre.canudas1995()
    >>> z = model.initial_state()
    >>> for _ in range(1000):  # 1 s at 0.01 rad/s sampled at 1 kHz
    ...     tau, z = model.step([0.01], 1e-3, z)
    >>> bool(np.allclose(tau, model.steady_state([0.01]), rtol=1e-12))
    True
    """

    sigma0: FloatArray = field(metadata=bound("> 0", "bristle stiffness [N m/rad]"))
    sigma1: FloatArray = field(metadata=bound(">= 0", "bristle damping [N m s/rad]"))
    sigma2: FloatArray = field(metadata=bound(">= 0", "viscous coefficient [N m s/rad]"))
    fc: FloatArray = field(metadata=bound("> 0", "Coulomb torque [N m]"))
    fs: FloatArray = field(metadata=bound("> 0", "stiction torque [N m]"))
    vs: FloatArray = field(metadata=bound("> 0", "Stribeck velocity [rad/s]"))
    delta: FloatArray = field(metadata=bound("> 0", "Stribeck exponent [-]"))
    _drop: FloatArray = field(init=False, repr=False, compare=False)
    _gaussian: bool = field(init=False, repr=False, compare=False)
    _damping: FloatArray = field(init=False, repr=False, compare=False)

    def __init__(
        self,
        sigma0: ArrayLike,
        sigma1: ArrayLike,
        sigma2: ArrayLike,
        fc: ArrayLike,
        fs: ArrayLike,
        vs: ArrayLike,
        delta: ArrayLike = 2.0,
    ) -> None:
        self._set_parameters(
            sigma0=sigma0, sigma1=sigma1, sigma2=sigma2, fc=fc, fs=fs, vs=vs, delta=delta
        )
        # Constants of the inner loop, computed once: a simulator evaluates
        # s(qd) several times per sample.
        object.__setattr__(self, "_drop", self.fs - self.fc)
        object.__setattr__(self, "_gaussian", bool(np.all(self.delta == 2.0)))
        object.__setattr__(self, "_damping", self.sigma1 + self.sigma2)

    @classmethod
    def canudas1995(cls, n_dof: int = 1) -> LuGre:
        """Parameters of Canudas de Wit et al. (1995), Table I, on every joint.

        sigma0 = 1e5 N m/rad, sigma1 = sqrt(1e5) N m s/rad, sigma2 = 0.4
        N m s/rad, fc = 1 N m, fs = 1.5 N m, vs = 0.001 rad/s, Gaussian
        Stribeck curve (delta = 2). The paper gives them for a translational
        mass (N, m); they are read here as rotational values. Reference:
        C. Canudas de Wit, H. Olsson, K. J. Astrom, P. Lischinsky, "A new
        model for control of systems with friction", IEEE Trans. Automatic
        Control 40(3), 419-425, 1995.

        Parameters
        ----------
        n_dof : int, default 1
            Number of joints that get the same parameters.

        Returns
        -------
        model : LuGre
        """
        if isinstance(n_dof, bool) or not isinstance(n_dof, int | np.integer) or n_dof < 1:
            raise InputValueError(f"n_dof must be a positive integer; got {n_dof!r}")
        ones = np.ones(int(n_dof))
        return cls(
            sigma0=1e5 * ones,
            sigma1=np.sqrt(1e5) * ones,
            sigma2=0.4 * ones,
            fc=1.0 * ones,
            fs=1.5 * ones,
            vs=0.001 * ones,
            delta=2.0 * ones,
        )

    def initial_state(self) -> FloatArray:
        """Rest state: zero bristle deflection.

        Returns
        -------
        z : ndarray of shape (n_dof,)
            Bristle deflection [rad], all zeros.
        """
        return np.zeros(self.n_dof)

    def _level(self, qd: FloatArray) -> FloatArray:
        if self._gaussian:
            ratio = qd / self.vs
            return np.asarray(self.fc + self._drop * np.exp(-(ratio * ratio)))
        return stribeck_level(np.abs(qd), self.fc, self.fs, self.vs, self.delta)

    def _rate(self, qd: FloatArray) -> FloatArray:
        """Decay rate ``a = sigma0 |qd| / s(qd)`` [1/s] of eq. (4.22a)."""
        return self.sigma0 * np.abs(qd) / self._level(qd)

    def output(self, qd: FloatArray, z: FloatArray) -> FloatArray:
        """Eq. (4.22b) without input checks (inner-loop fast path of :meth:`torque_from_state`)."""
        zdot = qd - self._rate(qd) * z
        return self.sigma0 * z + self.sigma1 * zdot + self.sigma2 * qd

    def advance(self, qd: FloatArray, dt: float, z: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Exact bristle update over one period with ``qd`` held; torque at its end.

        No input checks: the inner-loop fast path of :meth:`step`.
        """
        z_new = self.advance_state(qd, dt, z)
        return self.output(qd, z_new), z_new

    def advance_state(self, qd: FloatArray, dt: float, z: FloatArray) -> FloatArray:
        """The bristle deflection [rad] of :meth:`advance` alone (no torque); no input checks."""
        level = self._level(qd)
        rate_dt = (self.sigma0 * dt) * np.abs(qd) / level
        z_ss = np.sign(qd) * level / self.sigma0
        # expm1 keeps z_ss * (1 - exp(-a dt)) -> qd dt accurate for small a dt.
        return np.asarray(z * np.exp(-rate_dt) - z_ss * np.expm1(-rate_dt))

    def held(self, z: FloatArray) -> Callable[[FloatArray], FloatArray]:
        """Torque [N m] as a function of the velocity [rad/s] with ``z`` [rad] held.

        Eq. (4.22b) rearranged as ``sigma0 z + (sigma1 + sigma2) qd − sigma1
        sigma0 z |qd| / s(qd)`` with the ``z`` terms computed once: a
        simulator evaluates it at every stage of a step where the bristles
        are held. No input checks.
        """
        spring = self.sigma0 * z
        coupling = self.sigma1 * spring
        damping = self._damping

        def torque(qd: FloatArray) -> FloatArray:
            return np.asarray(damping * qd + spring - coupling * np.abs(qd) / self._level(qd))

        return torque

    def _sample(self, x: ArrayLike, name: str) -> FloatArray:
        arr, single = as_joint_array(x, self.n_dof, name)
        if not single:
            raise DimensionError(
                f"{name} must be one sample of shape ({self.n_dof},); got shape {np.shape(x)}"
            )
        return arr[0]

    def _velocity_and_state(
        self, qd: ArrayLike, z: ArrayLike
    ) -> tuple[FloatArray, FloatArray, bool]:
        """Checked ``qd`` [rad/s] and ``z`` [rad] of one shape, and whether they are one sample."""
        qd_arr, single = as_joint_array(qd, self.n_dof, "qd")
        z_arr, _ = as_joint_array(z, self.n_dof, "z")
        if z_arr.shape != qd_arr.shape:
            raise DimensionError(
                f"z must have the shape of qd, {np.shape(qd)}; got shape {np.shape(z)}"
            )
        return qd_arr, z_arr, single

    def bristle_dynamics(self, qd: ArrayLike, z: ArrayLike) -> FloatArray:
        """Right-hand side of the bristle equation, eq. (4.22a).

        For simulators that integrate ``z`` with their own ODE solver.

        Parameters
        ----------
        qd : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint velocities [rad/s].
        z : array-like of the shape of ``qd``
            Bristle deflections [rad].

        Returns
        -------
        zdot : ndarray of the shape of ``qd``
            Bristle deflection rate [rad/s].
        """
        qd_arr, z_arr, single = self._velocity_and_state(qd, z)
        zdot = qd_arr - self._rate(qd_arr) * z_arr
        return zdot[0] if single else zdot

    def torque_from_state(self, qd: ArrayLike, z: ArrayLike) -> FloatArray:
        """Friction torque for given velocities and bristle deflections, eq. (4.22b).

        The output equation for continuous-time simulators that integrate
        :meth:`bristle_dynamics` themselves; :meth:`step` uses the same one.

        Parameters
        ----------
        qd, z : array-like of shape (n_dof,) or (n_samples, n_dof), both the same
            Joint velocities [rad/s] and bristle deflections [rad].

        Returns
        -------
        tau : ndarray of the shape of ``qd``
            Friction torque [N m].
        """
        qd_arr, z_arr, single = self._velocity_and_state(qd, z)
        tau = self.output(qd_arr, z_arr)
        return tau[0] if single else tau

    def step(self, qd: ArrayLike, dt: float, z: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Advance the model by one sample period with the velocity held constant.

        Parameters
        ----------
        qd : array-like of shape (n_dof,)
            Joint velocity over the period [rad/s].
        dt : float
            Sample period [s], positive and finite.
        z : array-like of shape (n_dof,)
            Bristle deflection at the start of the period [rad].

        Returns
        -------
        tau : ndarray of shape (n_dof,)
            Friction torque at the end of the period [N m].
        z_new : ndarray of shape (n_dof,)
            Bristle deflection at the end of the period [rad].
        """
        period = check_dt(dt)
        return self.advance(self._sample(qd, "qd"), period, self._sample(z, "z"))

    def torque(
        self, qd: ArrayLike, dt: float, z0: ArrayLike | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """Friction torque over a velocity series sampled every ``dt``.

        Sample ``k`` is :meth:`step` applied to ``qd[k]``: ``tau[k]`` is the
        torque at the end of the period in which ``qd[k]`` was held.

        Parameters
        ----------
        qd : array-like of shape (n_samples, n_dof) or (n_dof,)
            Joint velocities [rad/s].
        dt : float
            Sample period [s], positive and finite.
        z0 : array-like of shape (n_dof,), optional
            Bristle deflection before the first sample [rad]; default
            :meth:`initial_state`. Pass the returned ``z_final`` to continue
            a series in chunks.

        Returns
        -------
        tau : ndarray of the shape of ``qd``
            Friction torque [N m].
        z_final : ndarray of shape (n_dof,)
            Bristle deflection after the last sample [rad].
        """
        period = check_dt(dt)
        qd_arr, single = as_joint_array(qd, self.n_dof, "qd")
        z = self.initial_state() if z0 is None else self._sample(z0, "z0").copy()
        tau = np.empty_like(qd_arr)
        for k in range(qd_arr.shape[0]):
            tau[k], z = self.advance(qd_arr[k], period, z)
        return (tau[0] if single else tau), z

    def steady_state(self, qd: ArrayLike) -> FloatArray:
        """Friction torque after a long run at constant velocity.

        ``sign(qd) s(qd) + sigma2 qd``: the Stribeck curve with ``fv = sigma2``
        (:class:`Stribeck`).

        Parameters
        ----------
        qd : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint velocities [rad/s], each held for a long time.

        Returns
        -------
        tau : ndarray of the shape of ``qd``
            Steady-state friction torque [N m].
        """
        arr, single = as_joint_array(qd, self.n_dof, "qd")
        tau = np.sign(arr) * self._level(arr) + self.sigma2 * arr
        return tau[0] if single else tau
