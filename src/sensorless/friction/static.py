"""Static friction models: the torque depends on the current joint velocity only.

:class:`Coulomb`, :class:`Viscous`, :class:`CoulombViscous`, :class:`Stribeck`,
:class:`Sigmoid` and :class:`HystereticError`, all derived from
:class:`FrictionModel`. Sign convention and shapes: :mod:`sensorless.friction`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import expit

from .._validation import FloatArray, as_joint_array
from ._parameters import JointParameters, bound

__all__ = [
    "Coulomb",
    "CoulombViscous",
    "FrictionModel",
    "HystereticError",
    "Sigmoid",
    "Stribeck",
    "Viscous",
]


def stribeck_level(
    speed: FloatArray, fc: FloatArray, fs: FloatArray, vs: FloatArray, delta: FloatArray
) -> FloatArray:
    """Stribeck curve ``s(|qd|) = fc + (fs - fc) exp(-(|qd|/vs)**delta)`` [N m], eq. (4.22c)."""
    return fc + (fs - fc) * np.exp(-((speed / vs) ** delta))


class FrictionModel(JointParameters, ABC):
    """Stateless friction model: the torque depends on the current velocity only.

    Subclasses implement :meth:`evaluate` on an already checked array;
    :meth:`torque` handles shapes and checks.
    """

    def torque(self, qd: ArrayLike) -> FloatArray:
        """Friction torque for the given joint velocities.

        Parameters
        ----------
        qd : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint velocities [rad/s].

        Returns
        -------
        tau : ndarray of the shape of ``qd``
            Friction torque [N m], sign convention of :mod:`sensorless.friction`.

        Raises
        ------
        DimensionError
            If ``qd`` does not have ``n_dof`` columns.
        InputValueError
            If ``qd`` contains NaN or inf.
        """
        arr, single = as_joint_array(qd, self.n_dof, "qd")
        tau = self.evaluate(arr)
        return tau[0] if single else tau

    @abstractmethod
    def evaluate(self, qd: FloatArray) -> FloatArray:
        """Torque [N m] without input checks: the fast path for inner loops.

        ``qd`` must already be a finite float array of shape (..., n_dof) [rad/s].
        """


def _coulomb(qd: FloatArray, c_pos: FloatArray, c_neg: FloatArray) -> FloatArray:
    return np.where(qd > 0.0, c_pos, np.where(qd < 0.0, c_neg, 0.0))


@dataclass(frozen=True, eq=False, init=False)
class Coulomb(FrictionModel):
    """Asymmetric Coulomb friction, eq. (2.7) with the constants of Table 2.2.

    ``tau = c_pos`` where ``qd > 0``, ``tau = c_neg`` where ``qd < 0`` and
    ``tau = 0`` where ``qd == 0``.

    Parameters
    ----------
    c_pos : float or array-like of shape (n_dof,)
        Friction torque at positive velocity, C+ [N m], ``>= 0``.
    c_neg : float or array-like of shape (n_dof,)
        Friction torque at negative velocity, C- [N m], ``<= 0`` (it is the
        signed torque, e.g. -0.2591 N m for joint 1 of the KUKA LWR).

    Examples
    --------
    >>> model = Coulomb(c_pos=0.2508, c_neg=-0.2591)
    >>> model.torque([[-1.0], [0.0], [0.5]]).ravel().tolist()
    [-0.2591, 0.0, 0.2508]
    """

    c_pos: FloatArray = field(metadata=bound(">= 0", "torque at positive velocity [N m]"))
    c_neg: FloatArray = field(
        metadata=bound("<= 0", "signed torque at negative velocity [N m], e.g. -0.2591")
    )

    def __init__(self, c_pos: ArrayLike, c_neg: ArrayLike) -> None:
        self._set_parameters(c_pos=c_pos, c_neg=c_neg)

    def evaluate(self, qd: FloatArray) -> FloatArray:
        return _coulomb(qd, self.c_pos, self.c_neg)


@dataclass(frozen=True, eq=False, init=False)
class Viscous(FrictionModel):
    """Viscous friction ``tau = fv * qd``.

    Parameters
    ----------
    fv : float or array-like of shape (n_dof,)
        Viscous coefficient [N m s/rad], ``>= 0``.

    Examples
    --------
    >>> Viscous(fv=[0.5, 2.0]).torque([1.0, -3.0]).tolist()
    [0.5, -6.0]
    """

    fv: FloatArray = field(metadata=bound(">= 0", "viscous coefficient [N m s/rad]"))

    def __init__(self, fv: ArrayLike) -> None:
        self._set_parameters(fv=fv)

    def evaluate(self, qd: FloatArray) -> FloatArray:
        return self.fv * qd


@dataclass(frozen=True, eq=False, init=False)
class CoulombViscous(FrictionModel):
    """Asymmetric Coulomb plus viscous friction: ``tau = Coulomb(qd) + fv * qd``.

    Parameters
    ----------
    c_pos : float or array-like of shape (n_dof,)
        Coulomb torque at positive velocity, C+ [N m], ``>= 0``.
    c_neg : float or array-like of shape (n_dof,)
        Signed Coulomb torque at negative velocity, C- [N m], ``<= 0``.
    fv : float or array-like of shape (n_dof,)
        Viscous coefficient [N m s/rad], ``>= 0``.

    Examples
    --------
    >>> model = CoulombViscous(c_pos=0.3, c_neg=-0.2, fv=0.5)
    >>> model.torque([[-2.0], [2.0]]).ravel().tolist()
    [-1.2, 1.3]
    """

    c_pos: FloatArray = field(metadata=bound(">= 0", "torque at positive velocity [N m]"))
    c_neg: FloatArray = field(metadata=bound("<= 0", "signed torque at negative velocity [N m]"))
    fv: FloatArray = field(metadata=bound(">= 0", "viscous coefficient [N m s/rad]"))

    def __init__(self, c_pos: ArrayLike, c_neg: ArrayLike, fv: ArrayLike) -> None:
        self._set_parameters(c_pos=c_pos, c_neg=c_neg, fv=fv)

    def evaluate(self, qd: FloatArray) -> FloatArray:
        return _coulomb(qd, self.c_pos, self.c_neg) + self.fv * qd


@dataclass(frozen=True, eq=False, init=False)
class Stribeck(FrictionModel):
    """Coulomb-Stribeck-viscous curve, the steady state of the LuGre model.

    ``tau = sign(qd) * (fc + (fs - fc) * exp(-|qd / vs|**delta)) + fv * qd``.
    ``delta = 2`` is the Gaussian of Canudas de Wit et al. (1995);
    ``delta = 1`` with ``vs = 1 / alpha`` is the thesis's eq. (4.22c).

    Parameters
    ----------
    fc : float or array-like of shape (n_dof,)
        Coulomb torque F_c [N m], ``>= 0``.
    fs : float or array-like of shape (n_dof,)
        Stiction (breakaway) torque F_s [N m], ``>= 0``.
    vs : float or array-like of shape (n_dof,)
        Stribeck velocity [rad/s], ``> 0``.
    fv : float or array-like of shape (n_dof,), default 0.0
        Viscous coefficient [N m s/rad], ``>= 0``.
    delta : float or array-like of shape (n_dof,), default 2.0
        Stribeck exponent [-], ``> 0``.

    Examples
    --------
    >>> model = Stribeck(fc=1.0, fs=1.5, vs=0.001, fv=0.4)
    >>> round(float(model.torque([0.001])[0]), 6)  # 1 + 0.5 / e + 0.0004
    1.18434
    """

    fc: FloatArray = field(metadata=bound(">= 0", "Coulomb torque [N m]"))
    fs: FloatArray = field(metadata=bound(">= 0", "stiction torque [N m]"))
    vs: FloatArray = field(metadata=bound("> 0", "Stribeck velocity [rad/s]"))
    fv: FloatArray = field(metadata=bound(">= 0", "viscous coefficient [N m s/rad]"))
    delta: FloatArray = field(metadata=bound("> 0", "Stribeck exponent [-]"))

    def __init__(
        self,
        fc: ArrayLike,
        fs: ArrayLike,
        vs: ArrayLike,
        fv: ArrayLike = 0.0,
        delta: ArrayLike = 2.0,
    ) -> None:
        self._set_parameters(fc=fc, fs=fs, vs=vs, fv=fv, delta=delta)

    def evaluate(self, qd: FloatArray) -> FloatArray:
        level = stribeck_level(np.abs(qd), self.fc, self.fs, self.vs, self.delta)
        return np.sign(qd) * level + self.fv * qd


@dataclass(frozen=True, eq=False, init=False)
class Sigmoid(FrictionModel):
    """Sigmoidal friction of the Franka Panda (Gaz et al., RA-L 2019).

    ``tau = phi1 / (1 + exp(-phi2 (qd + phi3))) - phi1 / (1 + exp(-phi2 phi3))``.
    The offset term makes ``tau(0) = 0``; for ``qd -> +inf`` the torque tends
    to ``phi1 - phi1 / (1 + exp(-phi2 phi3))`` and for ``qd -> -inf`` to
    ``-phi1 / (1 + exp(-phi2 phi3))``. The logistic function is evaluated with
    :func:`scipy.special.expit`, which does not overflow for large arguments.

    Parameters
    ----------
    phi1 : float or array-like of shape (n_dof,)
        Torque span of the sigmoid [N m], ``>= 0``.
    phi2 : float or array-like of shape (n_dof,)
        Slope of the sigmoid [s/rad], ``>= 0``. With ``phi1, phi2 >= 0`` the
        curve increases through the origin, so ``tau`` has the sign of ``qd``.
    phi3 : float or array-like of shape (n_dof,)
        Velocity offset of the sigmoid [rad/s], any sign.

    Examples
    --------
    >>> model = Sigmoid(phi1=0.54615, phi2=5.1181, phi3=0.039533)  # Panda joint 1
    >>> float(model.torque([0.0])[0])
    0.0
    """

    phi1: FloatArray = field(metadata=bound(">= 0", "torque span [N m]"))
    phi2: FloatArray = field(metadata=bound(">= 0", "slope [s/rad]"))
    phi3: FloatArray

    def __init__(self, phi1: ArrayLike, phi2: ArrayLike, phi3: ArrayLike) -> None:
        self._set_parameters(phi1=phi1, phi2=phi2, phi3=phi3)

    def evaluate(self, qd: FloatArray) -> FloatArray:
        offset = self.phi1 * expit(self.phi2 * self.phi3)
        return self.phi1 * expit(self.phi2 * (qd + self.phi3)) - offset


@dataclass(frozen=True, eq=False, init=False)
class HystereticError(FrictionModel):
    """Hysteretic friction-compensation error of the KUKA LWR, eq. (5.38).

    ``tau_fre = -c * sign(qd)`` (0 at ``qd == 0``, where ``|qd| / qd`` is
    undefined). Unlike the other models this is not a friction torque but the
    error of a friction estimate, ``tau_fre = tau_fr_hat - tau_fr`` in
    eq. (5.37): with ``c > 0`` the compensation falls short of the true
    friction by ``c`` in the direction of motion. It is used to build the
    time-variant thresholds of eq. (5.39); the values identified in Table 5.7
    are c = 0.2678, 0.5654, 0.4367 N m for joints 1-3. The sign of ``c`` is
    not restricted, because an error can have either sign.

    Parameters
    ----------
    c : float or array-like of shape (n_dof,)
        Magnitude of the friction error C_j [N m].

    Examples
    --------
    >>> HystereticError(c=0.2678).torque([[2.0], [-2.0]]).ravel().tolist()
    [-0.2678, 0.2678]
    """

    c: FloatArray

    def __init__(self, c: ArrayLike) -> None:
        self._set_parameters(c=c)

    def evaluate(self, qd: FloatArray) -> FloatArray:
        return -self.c * np.sign(qd)
