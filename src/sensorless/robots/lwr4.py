"""The KUKA LWR IV+ of the thesis: kinematics, friction and base parameters of chapter 2.

Everything the thesis gives about its robot is here, each with its table:

- Table 2.4: modified DH parameters (Craig), :data:`MDH`.
- Table 2.2: effective motor-side Coulomb friction B B_θ⁻¹ τ_fr (C₊, C₋),
  :data:`MOTOR_COULOMB_POS`, :data:`MOTOR_COULOMB_NEG`.
- Table 2.3: link-side Coulomb friction C_L, :data:`LINK_COULOMB`.
- Table 2.5: classical parameters that are zero by symmetry, :data:`ZERO`.
- Table 2.7, right-hand "Final Estimation" column (the minimal parameters the
  KUKA controller uses for M(q) and g(q), identified from them by eq.
  2.14–2.15): :data:`TABLE_2_7_FINAL`, keyed by our base-parameter names
  (the thesis's θ1 … θ25 in the order of Table 2.6).

The thesis publishes base parameters only; a simulator needs one classical
parameter set per link. :data:`LINK_PARAMETERS` is such a set: the physically
consistent one closest to the prior of :func:`lwr4_prior` whose base
parameters reproduce :data:`TABLE_2_7_FINAL` (found by
:func:`sensorless.identification.consistent_parameters`;
``tests/test_lwr4.py`` reruns that retrieval and checks both properties).

The prior is a documented assumption, not a measurement: KUKA's catalogue
mass of the arm (16 kg) split over the links, centres of mass half-way along
each segment, uniform cylinders of radius 0.06 m. Only combinations of it that
the base parameters do not fix survive in :data:`LINK_PARAMETERS`.
"""

from __future__ import annotations

import numpy as np

from ..friction import Coulomb
from .model import LinkInertia, RobotModel

__all__ = [
    "LINK_COULOMB",
    "LINK_PARAMETERS",
    "MDH",
    "MOTOR_COULOMB_NEG",
    "MOTOR_COULOMB_POS",
    "TABLE_2_7_FINAL",
    "ZERO",
    "lwr4",
    "lwr4_link_friction",
    "lwr4_prior",
]

_L3, _L5 = 0.4, 0.39
_DEG = np.pi / 180

MDH = [
    {"alpha": a * _DEG, "a": 0.0, "theta": 0.0, "d": d}
    for a, d in zip((0, 90, -90, -90, 90, 90, -90), (0, 0, _L3, 0, _L5, 0, 0), strict=True)
]
"""Thesis Table 2.4: (α_{i-1} [rad], a_{i-1} [m], θ offset [rad], d_i [m]) per joint."""

MOTOR_COULOMB_POS = np.array([0.2508, 0.4902, 0.3609, 0.3491, 0.2945, 1.1474, 0.2954])
"""Thesis Table 2.2, C₊ of the effective motor-side friction [N m]."""
MOTOR_COULOMB_NEG = np.array([-0.2591, -0.4939, -0.3717, -0.3581, -0.3034, -1.1174, -0.2961])
"""Thesis Table 2.2, C₋ of the effective motor-side friction [N m]."""
LINK_COULOMB = np.array([0.9661, 0.4561, 0.9952, 0.8136, 0.2805, 0.1313, 0.1865])
"""Thesis Table 2.3, link-side Coulomb friction C_L [N m]."""

ZERO: tuple[str, ...] = tuple(
    [f"{p}{i}" for i in range(1, 8) for p in ("XY", "XZ", "mX")]
    + ["YZ1", "mY1"]
    + [f"Ia{i}" for i in range(1, 8)]
)
"""Classical parameters zero by the symmetry of Table 2.5 (no rotor inertia on the link side).

Table 2.5 also zeroes XX1, YY1, mZ1 and m1; they do not act on a fixed base
with a vertical first axis, and a link with ZZ1 > 0 but XX1 = YY1 = 0 is not
a rigid body, so they are left free here (the prior sets them).
"""

TABLE_2_7_FINAL: dict[str, float] = {
    "mY2R": 3.4968,  # θ1
    "mY3R": 0.0,  # θ2
    "mY4R": -1.343,  # θ3
    "mY5R": 0.02398,  # θ4
    "mY6R": 0.02628,  # θ5
    "mY7": 0.0,  # θ6
    "XX2R": 1.2634,  # θ7
    "XX3R": 0.0,  # θ8
    "XX4R": 0.42847,  # θ9
    "XX5R": 0.0,  # θ10
    "XX6R": 0.0,  # θ11
    "XX7R": 0.0,  # θ12
    "YZ2": 0.0,  # θ13
    "YZ3": 0.0,  # θ14
    "YZ4": 0.0,  # θ15
    "YZ5": 4.241e-4,  # θ16
    "YZ6": 0.0,  # θ17
    "YZ7": 0.0,  # θ18
    "ZZ1R": 0.0116,  # θ19
    "ZZ2R": 1.2686,  # θ20
    "ZZ3R": 0.0108,  # θ21
    "ZZ4R": 0.4328,  # θ22
    "ZZ5R": 6.33e-3,  # θ23
    "ZZ6R": 4.421e-3,  # θ24
    "ZZ7": 1.201e-4,  # θ25
}
"""Thesis Table 2.7, right-hand "Final Estimation" [kg m, kg m²], by base-parameter name."""

# KUKA LWR 4+ catalogue limits (as in the CentroEPiaggio/kuka-lwr description).
_LOWER = np.array([-170, -120, -170, -120, -170, -120, -170]) * _DEG
_VELOCITY = np.array([110, 110, 128, 128, 204, 184, 184]) * _DEG
_EFFORT = np.array([176, 176, 100, 100, 100, 38, 38], dtype=float)

# Prior (assumption, see the module docstring): mass [kg], centre of mass in
# the link frame [m], axis of the cylinder, its length [m].
_PRIOR = (
    (2.7, (0.0, 0.0, -0.10), 2, 0.20),
    (2.7, (0.0, 0.10, 0.0), 1, 0.20),
    (2.7, (0.0, 0.0, -0.12), 2, 0.20),
    (2.7, (0.0, -0.10, 0.0), 1, 0.20),
    (1.7, (0.0, 0.0, -0.14), 2, 0.19),
    (1.6, (0.0, 0.01, 0.0), 1, 0.08),
    (0.3, (0.0, 0.0, -0.01), 2, 0.02),
)
_RADIUS = 0.06


def _cylinder(mass: float, axis: int, length: float) -> np.ndarray:
    """Inertia of a solid cylinder about its centre [kg m²], its axis along ``axis``."""
    across = mass * (3 * _RADIUS**2 + length**2) / 12
    moments = np.full(3, across)
    moments[axis] = mass * _RADIUS**2 / 2
    return np.diag(moments)


def lwr4_link_friction() -> Coulomb:
    """Link-side friction τ_frL of thesis Table 2.3 (symmetric Coulomb, eq. 2.8)."""
    return Coulomb(LINK_COULOMB, -LINK_COULOMB)


def _build(links: list[LinkInertia], name: str, description: str) -> RobotModel:
    friction = Coulomb(MOTOR_COULOMB_POS + LINK_COULOMB, MOTOR_COULOMB_NEG - LINK_COULOMB)
    return RobotModel.from_mdh(
        MDH,
        links,
        friction=friction,
        name=name,
        description=description,
        position_limits=(_LOWER, -_LOWER),
        velocity_limits=_VELOCITY,
        effort_limits=_EFFORT,
    )


def lwr4_prior() -> RobotModel:
    """The assumed geometric model the LWR parameters are retrieved near (module docstring)."""
    links = [LinkInertia(m, com, _cylinder(m, axis, length)) for m, com, axis, length in _PRIOR]
    return _build(links, "lwr4_prior", "KUKA LWR IV+: geometric prior (assumption)")


# Retrieved by consistent_parameters from TABLE_2_7_FINAL and lwr4_prior()
# (relative residual 5.3e-17; tests/test_lwr4.py reruns it).
LINK_PARAMETERS = np.array(
    [
        (0.03889189864, 0, 0, 0.03889189864, 0, 0.005863962123, 0, 0, -0.27, 2.7, 0),
        (
            0.03975192326,
            0,
            0,
            0.005736037877,
            6.677116964e-20,
            0.03921588538,
            0,
            0.2735603485,
            -7.855023487e-16,
            2.797041298,
            0,
        ),
        (
            0.03500344135,
            0,
            0,
            0.03893972867,
            -6.796698124e-20,
            0.006863712678,
            0,
            -1.598234721e-17,
            -0.2471286867,
            2.44918576,
            0,
        ),
        (
            0.0359386699,
            0,
            0,
            0.003936287322,
            -1.126054401e-22,
            0.03633238258,
            0,
            -0.2737998084,
            1.682847808e-17,
            3.22461192,
            0,
        ),
        (
            0.01625732087,
            0,
            0,
            0.01911440147,
            0.0004241,
            0.0034729194,
            0,
            0.004266591507,
            -0.101627843,
            0.7622729454,
            0,
        ),
        (
            0.002778356441,
            0,
            0,
            0.0028570806,
            -8.392328926e-23,
            0.004342275841,
            0,
            0.02764905561,
            -0.01971340849,
            2.100801166,
            0,
        ),
        (
            7.872415909e-05,
            0,
            0,
            7.872415909e-05,
            -2.295887404e-41,
            0.0001201,
            0,
            0,
            -0.001369055615,
            0.1390490543,
            0,
        ),
    ]
)
"""Classical parameters per link (rows), columns as :meth:`RobotModel.standard_parameters`."""


def lwr4() -> RobotModel:
    """KUKA LWR IV+ as the thesis identified it (chapter 2).

    Kinematics of Table 2.4; classical link parameters :data:`LINK_PARAMETERS`,
    physically consistent and reproducing the base parameters of Table 2.7
    ("Final Estimation" from the controller's M and g); joint friction seen
    from the command torque of the KUKA torque loop: effective motor-side
    Coulomb friction of Table 2.2 plus link-side Coulomb friction of Table 2.3.
    No armature: the links alone (the motors are in the flexible-joint plant
    of the ``lwr4-thesis`` scenario). Limits from KUKA's LWR 4+ catalogue.
    """
    prior = lwr4_prior()
    robot = prior.with_standard_parameters(LINK_PARAMETERS, name="lwr4")
    return RobotModel(
        robot.pinocchio_model,
        "lwr4",
        robot.friction,
        "KUKA LWR IV+, thesis Tables 2.2-2.4 and 2.7",
    )
