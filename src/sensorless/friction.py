"""Joint friction models: Coulomb, viscous, Stribeck, sigmoid (Panda) and LuGre.

Sign convention
---------------
The friction torque ``tau_fr`` [N m] returned by every model in this module
is the torque that friction *dissipates*: it has the sign of the joint
velocity ``qd`` and enters the rigid-body dynamics with a minus sign,

    M(q) qdd + C(q, qd) qd + g(q) = tau_m + tau_c - tau_fr        eq. (5.1)

so ``tau_fr * qd >= 0`` for every dissipative model here. The one exception
is :class:`HystereticError`, which models the *error* of a friction
compensation, eq. (5.37), and has the sign that the thesis gives it.

Units are SI and angles are radians. Joint quantities have shape
``(n_dof,)`` for one sample or ``(n_samples, n_dof)`` for a time series (time
along axis 0); results have the shape of the input. Model parameters are per
joint: each accepts a scalar or an array of shape ``(n_dof,)``; scalars are
broadcast, and ``n_dof`` is the common length (1 when all are scalars).

Stateless models (:class:`Coulomb`, :class:`Viscous`, :class:`CoulombViscous`,
:class:`Stribeck`, :class:`Sigmoid`, :class:`HystereticError`) derive from
:class:`FrictionModel` and map a velocity to a torque with ``torque(qd)``.
The dynamic :class:`LuGre` model keeps its bristle deflection ``z`` [rad] in
an explicit state array, as ``zi``/``zf`` in :func:`scipy.signal.lfilter`:
``step`` advances one sample and ``torque`` a whole series, and a series cut
into chunks with the state carried over gives the same result as in one go.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import expit

from ._validation import FloatArray, as_joint_array, check_dt
from .exceptions import DimensionError, InputValueError

__all__ = [
    "Coulomb",
    "CoulombViscous",
    "FrictionModel",
    "HystereticError",
    "LuGre",
    "Sigmoid",
    "Stribeck",
    "Viscous",
]

_BOUNDS = {
    ">= 0": lambda x: x >= 0.0,
    "> 0": lambda x: x > 0.0,
    "<= 0": lambda x: x <= 0.0,
}


def _broadcast_parameters(model: str, **values: ArrayLike) -> list[FloatArray]:
    """Return the parameters as read-only float arrays of one common shape ``(n_dof,)``."""
    arrays: dict[str, FloatArray] = {}
    for name, value in values.items():
        try:
            arr = np.array(value, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InputValueError(
                f"{model}: {name} must be a number or an array of shape (n_dof,); "
                f"could not convert {value!r}: {exc}"
            ) from None
        if arr.ndim > 1 or arr.size == 0:
            raise DimensionError(
                f"{model}: {name} must be a scalar or a non-empty array of shape (n_dof,); "
                f"got shape {arr.shape}"
            )
        if not np.isfinite(arr).all():
            raise InputValueError(f"{model}: {name} must be finite; got {arr}")
        arrays[name] = np.atleast_1d(arr)
    try:
        shape = np.broadcast_shapes(*(arr.shape for arr in arrays.values()))
    except ValueError:
        shapes = ", ".join(f"{name}: {arr.shape}" for name, arr in arrays.items())
        raise DimensionError(
            f"{model}: per-joint parameters must be scalars or arrays of one common length "
            f"n_dof; got shapes {shapes}"
        ) from None
    result = []
    for arr in arrays.values():
        full = np.array(np.broadcast_to(arr, shape), dtype=np.float64)
        full.setflags(write=False)
        result.append(full)
    return result


def _require(model: str, name: str, value: FloatArray, bound: str, meaning: str) -> None:
    """Raise :class:`InputValueError` unless every joint's ``value`` satisfies ``bound``."""
    ok = _BOUNDS[bound](value)
    if not ok.all():
        joint = int(np.argmin(ok))
        raise InputValueError(
            f"{model}: {name} must be {bound} ({meaning}); got {value[joint]} at joint {joint}"
        )


def _stribeck_level(
    speed: FloatArray, fc: FloatArray, fs: FloatArray, vs: FloatArray, delta: FloatArray
) -> FloatArray:
    """Stribeck curve ``s(|qd|) = fc + (fs - fc) exp(-(|qd|/vs)**delta)`` [N m], eq. (4.22c)."""
    return fc + (fs - fc) * np.exp(-((speed / vs) ** delta))


class _JointParameters:
    """Per-joint constants stored once, immutable after construction."""

    _n_dof: int

    @property
    def n_dof(self) -> int:
        """Number of joints the model describes."""
        return self._n_dof

    def _assign(self, names: tuple[str, ...], arrays: list[FloatArray]) -> None:
        # The subclasses are frozen dataclasses: attributes are set once, here.
        for name, arr in zip(names, arrays, strict=True):
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "_n_dof", int(arrays[0].shape[0]))


class FrictionModel(_JointParameters, ABC):
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
            Friction torque [N m], sign convention of the module docstring.

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

    c_pos: FloatArray
    c_neg: FloatArray

    def __init__(self, c_pos: ArrayLike, c_neg: ArrayLike) -> None:
        arrays = _broadcast_parameters("Coulomb", c_pos=c_pos, c_neg=c_neg)
        _require("Coulomb", "c_pos", arrays[0], ">= 0", "torque at positive velocity [N m]")
        _require(
            "Coulomb",
            "c_neg",
            arrays[1],
            "<= 0",
            "signed torque at negative velocity [N m], e.g. -0.2591",
        )
        self._assign(("c_pos", "c_neg"), arrays)

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

    fv: FloatArray

    def __init__(self, fv: ArrayLike) -> None:
        arrays = _broadcast_parameters("Viscous", fv=fv)
        _require("Viscous", "fv", arrays[0], ">= 0", "viscous coefficient [N m s/rad]")
        self._assign(("fv",), arrays)

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

    c_pos: FloatArray
    c_neg: FloatArray
    fv: FloatArray

    def __init__(self, c_pos: ArrayLike, c_neg: ArrayLike, fv: ArrayLike) -> None:
        arrays = _broadcast_parameters("CoulombViscous", c_pos=c_pos, c_neg=c_neg, fv=fv)
        _require("CoulombViscous", "c_pos", arrays[0], ">= 0", "torque at positive velocity")
        _require("CoulombViscous", "c_neg", arrays[1], "<= 0", "signed torque at negative velocity")
        _require("CoulombViscous", "fv", arrays[2], ">= 0", "viscous coefficient [N m s/rad]")
        self._assign(("c_pos", "c_neg", "fv"), arrays)

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

    fc: FloatArray
    fs: FloatArray
    vs: FloatArray
    fv: FloatArray
    delta: FloatArray

    def __init__(
        self,
        fc: ArrayLike,
        fs: ArrayLike,
        vs: ArrayLike,
        fv: ArrayLike = 0.0,
        delta: ArrayLike = 2.0,
    ) -> None:
        arrays = _broadcast_parameters("Stribeck", fc=fc, fs=fs, vs=vs, fv=fv, delta=delta)
        _require("Stribeck", "fc", arrays[0], ">= 0", "Coulomb torque [N m]")
        _require("Stribeck", "fs", arrays[1], ">= 0", "stiction torque [N m]")
        _require("Stribeck", "vs", arrays[2], "> 0", "Stribeck velocity [rad/s]")
        _require("Stribeck", "fv", arrays[3], ">= 0", "viscous coefficient [N m s/rad]")
        _require("Stribeck", "delta", arrays[4], "> 0", "Stribeck exponent")
        self._assign(("fc", "fs", "vs", "fv", "delta"), arrays)

    def evaluate(self, qd: FloatArray) -> FloatArray:
        level = _stribeck_level(np.abs(qd), self.fc, self.fs, self.vs, self.delta)
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

    phi1: FloatArray
    phi2: FloatArray
    phi3: FloatArray

    def __init__(self, phi1: ArrayLike, phi2: ArrayLike, phi3: ArrayLike) -> None:
        arrays = _broadcast_parameters("Sigmoid", phi1=phi1, phi2=phi2, phi3=phi3)
        _require("Sigmoid", "phi1", arrays[0], ">= 0", "torque span [N m]")
        _require("Sigmoid", "phi2", arrays[1], ">= 0", "slope [s/rad]")
        self._assign(("phi1", "phi2", "phi3"), arrays)

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
        self._assign(("c",), _broadcast_parameters("HystereticError", c=c))

    def evaluate(self, qd: FloatArray) -> FloatArray:
        return -self.c * np.sign(qd)


@dataclass(frozen=True, eq=False, init=False)
class LuGre(_JointParameters):
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

    sigma0: FloatArray
    sigma1: FloatArray
    sigma2: FloatArray
    fc: FloatArray
    fs: FloatArray
    vs: FloatArray
    delta: FloatArray
    _drop: FloatArray = field(init=False, repr=False, compare=False)
    _gaussian: bool = field(init=False, repr=False, compare=False)

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
        arrays = _broadcast_parameters(
            "LuGre",
            sigma0=sigma0,
            sigma1=sigma1,
            sigma2=sigma2,
            fc=fc,
            fs=fs,
            vs=vs,
            delta=delta,
        )
        _require("LuGre", "sigma0", arrays[0], "> 0", "bristle stiffness [N m/rad]")
        _require("LuGre", "sigma1", arrays[1], ">= 0", "bristle damping [N m s/rad]")
        _require("LuGre", "sigma2", arrays[2], ">= 0", "viscous coefficient [N m s/rad]")
        _require("LuGre", "fc", arrays[3], "> 0", "Coulomb torque [N m]")
        _require("LuGre", "fs", arrays[4], "> 0", "stiction torque [N m]")
        _require("LuGre", "vs", arrays[5], "> 0", "Stribeck velocity [rad/s]")
        _require("LuGre", "delta", arrays[6], "> 0", "Stribeck exponent")
        self._assign(("sigma0", "sigma1", "sigma2", "fc", "fs", "vs", "delta"), arrays)
        # Constants of the inner loop, computed once: a simulator evaluates
        # s(qd) several times per sample.
        object.__setattr__(self, "_drop", self.fs - self.fc)
        object.__setattr__(self, "_gaussian", bool(np.all(self.delta == 2.0)))

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
        return _stribeck_level(np.abs(qd), self.fc, self.fs, self.vs, self.delta)

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
        rate_dt = self._rate(qd) * dt
        z_ss = np.sign(qd) * self._level(qd) / self.sigma0
        # expm1 keeps z_ss * (1 - exp(-a dt)) -> qd dt accurate for small a dt.
        z_new = z * np.exp(-rate_dt) - z_ss * np.expm1(-rate_dt)
        return self.output(qd, z_new), z_new

    def _sample(self, x: ArrayLike, name: str) -> FloatArray:
        arr, single = as_joint_array(x, self.n_dof, name)
        if not single:
            raise DimensionError(
                f"{name} must be one sample of shape ({self.n_dof},); got shape {np.shape(x)}"
            )
        return arr[0]

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
        qd_arr, single = as_joint_array(qd, self.n_dof, "qd")
        z_arr, _ = as_joint_array(z, self.n_dof, "z")
        if z_arr.shape != qd_arr.shape:
            raise DimensionError(
                f"z must have the shape of qd, {np.shape(qd)}; got shape {np.shape(z)}"
            )
        zdot = qd_arr - self._rate(qd_arr) * z_arr
        return zdot[0] if single else zdot

    def torque_from_state(self, qd: ArrayLike, z: ArrayLike) -> FloatArray:
        """Friction torque for given velocities and bristle deflections, eq. (4.22b).

        The output equation for continuous-time simulators that integrate
        :meth:`bristle_dynamics` themselves; :meth:`step` uses the same one.

        Parameters
        ----------
        qd : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint velocities [rad/s].
        z : array-like of the shape of ``qd``
            Bristle deflections [rad].

        Returns
        -------
        tau : ndarray of the shape of ``qd``
            Friction torque [N m].
        """
        qd_arr, single = as_joint_array(qd, self.n_dof, "qd")
        z_arr, _ = as_joint_array(z, self.n_dof, "z")
        if z_arr.shape != qd_arr.shape:
            raise DimensionError(
                f"z must have the shape of qd, {np.shape(qd)}; got shape {np.shape(z)}"
            )
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
            Joint velocities [rad/s].

        Returns
        -------
        tau : ndarray of the shape of ``qd``
            Steady-state friction torque [N m].
        """
        arr, single = as_joint_array(qd, self.n_dof, "qd")
        tau = np.sign(arr) * self._level(arr) + self.sigma2 * arr
        return tau[0] if single else tau
