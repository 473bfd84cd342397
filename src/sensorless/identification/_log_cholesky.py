"""Log-Cholesky parametrisation of a robot's pseudo-inertias (Rucker & Wensing 2022).

The map x ↦ π from unconstrained variables to standard parameters whose
links are rigid bodies, with the declared zeros built in, and its Jacobian:
:class:`Layout` (one per robot and set of declared zeros) made of blocks of
the links' 4x4 pseudo-inertias J. The method is described in
:mod:`sensorless.identification.consistent`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validation import FloatArray
from ..robots.model import N_LINK_PARAMETERS, PARAMETER_NAMES
from ..simulation.model_error import pseudo_inertia

__all__ = ["ARMATURE", "TINY", "Layout"]

# J coordinates (x, y, z, homogeneous) that a declared zero removes from a
# positive semidefinite J, and the J entry an off-diagonal parameter is (up to sign).
_DEAD_COORDINATES = {"XX": (1, 2), "YY": (0, 2), "ZZ": (0, 1), "m": (3,)}
_OFF_DIAGONAL = {"XY": (0, 1), "XZ": (0, 2), "YZ": (1, 2), "mX": (0, 3), "mY": (1, 3), "mZ": (2, 3)}
#: Column of the armature Ia among the 11 standard parameters of a link.
ARMATURE = PARAMETER_NAMES.index("Ia")
#: Floor of positive scales and eigenvalues, against divisions by zero.
TINY = 1e-12
# Logarithms are capped here (e^200 ~ 1e87) so that a wild trial step gives a
# huge, finite residual that the solver rejects instead of an overflow.
_LOG_CAP = 100.0


def _standard_from_pseudo(pseudo: FloatArray) -> FloatArray:
    """The 10 inertial parameters (XX ... m) of pseudo-inertias of shape (..., 4, 4).

    Inverse of :func:`pseudo_inertia`: Ī = tr(Σ)·1 − Σ. Linear, so it also maps
    derivatives of J to derivatives of π.
    """
    s = pseudo[..., :3, :3]
    return np.stack(
        [
            s[..., 1, 1] + s[..., 2, 2],
            -s[..., 0, 1],
            -s[..., 0, 2],
            s[..., 0, 0] + s[..., 2, 2],
            -s[..., 1, 2],
            s[..., 0, 0] + s[..., 1, 1],
            pseudo[..., 0, 3],
            pseudo[..., 1, 3],
            pseudo[..., 2, 3],
            pseudo[..., 3, 3],
        ],
        axis=-1,
    )


@dataclass(frozen=True)
class _Block:
    """One diagonal block of a link's J: ``J_b = margin·1 + e^{2α} V Vᵀ``.

    V is upper triangular with diagonal ``exp(δ)`` (Rucker & Wensing's U = e^α V).
    With the homogeneous coordinate in the block (it is last), V's last diagonal
    entry is 1, e^{2α} = m − margin and V's last column is h / e^{2α} (the
    centre of mass for a negligible margin) [m]; without it there is no α.
    """

    link: int
    coordinates: tuple[int, ...]
    offset: int

    @property
    def size(self) -> int:
        return len(self.coordinates)

    @property
    def has_mass(self) -> bool:
        return self.coordinates[-1] == 3

    @property
    def n_variables(self) -> int:
        return self.size * (self.size + 1) // 2

    @property
    def variables(self) -> list[tuple[int, int]]:
        """Entry of V for each variable: (a, a) log-diagonal, (a, b) a < b free, (-1, -1) α."""
        k = self.size
        logs = [(a, a) for a in range(k - 1 if self.has_mass else k)]
        alpha = [(-1, -1)] if self.has_mass else []
        rows, cols = np.triu_indices(k, 1)
        return logs + alpha + list(zip(rows.tolist(), cols.tolist(), strict=True))

    def factor(self, x: FloatArray) -> tuple[float, FloatArray]:
        """(e^{2α} or 1, V)."""
        factor, scale = np.zeros((self.size, self.size)), 1.0
        if self.has_mass:
            factor[-1, -1] = 1.0
        for k, (a, b) in enumerate(self.variables):
            value = x[self.offset + k]
            if a < 0:
                scale = math.exp(2.0 * min(value, _LOG_CAP))
            elif a == b:
                factor[a, a] = math.exp(min(value, _LOG_CAP))
            else:
                factor[a, b] = value
        return scale, factor

    def derivatives(self, x: FloatArray) -> FloatArray:
        """d J_b / d x of shape (n_variables, size, size)."""
        scale, factor = self.factor(x)
        out = np.zeros((self.n_variables, self.size, self.size))
        for k, (a, b) in enumerate(self.variables):
            if a < 0:
                out[k] = 2.0 * scale * factor @ factor.T
                continue
            # d(V Vᵀ)/dV_ab = e_a V[:, b]ᵀ + V[:, b] e_aᵀ; d V_aa / d δ_a = V_aa.
            out[k, a, :] += factor[:, b]
            out[k, :, a] += factor[:, b]
            out[k] *= scale * (factor[a, a] if a == b else 1.0)
        return out

    def start(self, shifted: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Variables and their prior scales for ``J_b − margin·1 = shifted`` (positive definite).

        The scale is 1 for the logarithms (relative changes of mass and lengths)
        and the block's largest radius of gyration for the free entries
        (centre of mass and shear [m], or [sqrt(kg) m] without the mass).
        """
        scale = shifted[-1, -1] if self.has_mass else 1.0
        normalised = shifted / scale
        flip = normalised[::-1, ::-1]
        factor = np.linalg.cholesky(0.5 * (flip + flip.T))[::-1, ::-1]
        diagonal = np.diag(normalised)[:-1] if self.has_mass else np.diag(normalised)
        length = math.sqrt(float(diagonal.max())) if diagonal.size else 1.0
        values, scales = np.zeros(self.n_variables), np.ones(self.n_variables)
        for k, (a, b) in enumerate(self.variables):
            if a < 0:
                values[k] = 0.5 * math.log(scale)
            elif a == b:
                values[k] = math.log(factor[a, a])
            else:
                values[k], scales[k] = factor[a, b], max(length, TINY)
        return values, scales


@dataclass(frozen=True)
class Layout:
    """Map from the unconstrained variables x to the standard parameters π."""

    n_dof: int
    margin: float
    blocks: tuple[_Block, ...]
    armature: tuple[tuple[int, int], ...]  # (link, variable index)
    n_variables: int
    penalised: tuple[int, ...]  # flat indices of declared zeros not built in

    @classmethod
    def build(cls, n_dof: int, zero: set[str], margin: float) -> Layout:
        blocks: list[_Block] = []
        armature: list[tuple[int, int]] = []
        penalised: list[int] = []
        offset = 0
        for link in range(n_dof):
            declared = {p for p in PARAMETER_NAMES if f"{p}{link + 1}" in zero}
            dead = {c for p, cs in _DEAD_COORDINATES.items() if p in declared for c in cs}
            live = [c for c in range(4) if c not in dead]
            cut = {_OFF_DIAGONAL[p] for p in declared if p in _OFF_DIAGONAL}
            for component in _components(live, cut):
                blocks.append(_Block(link, component, offset))
                offset += blocks[-1].n_variables
                penalised += [
                    link * N_LINK_PARAMETERS + PARAMETER_NAMES.index(p)
                    for p, (a, b) in _OFF_DIAGONAL.items()
                    if p in declared and a in component and b in component
                ]
            if "Ia" not in declared:
                armature.append((link, offset))
                offset += 1
        return cls(n_dof, margin, tuple(blocks), tuple(armature), offset, tuple(sorted(penalised)))

    def parameters(self, x: FloatArray) -> FloatArray:
        """Standard parameters π of shape (11·n_dof,)."""
        pseudo = np.zeros((self.n_dof, 4, 4))
        for block in self.blocks:
            scale, factor = block.factor(x)
            index = np.ix_(block.coordinates, block.coordinates)
            pseudo[block.link][index] = self.margin * np.eye(block.size) + scale * factor @ factor.T
        out = np.zeros((self.n_dof, N_LINK_PARAMETERS))
        out[:, :10] = _standard_from_pseudo(pseudo)
        for link, k in self.armature:
            out[link, ARMATURE] = x[k] ** 2
        return out.ravel()

    def jacobian(self, x: FloatArray) -> FloatArray:
        """dπ/dx of shape (11·n_dof, n_variables)."""
        out = np.zeros((self.n_dof * N_LINK_PARAMETERS, self.n_variables))
        for block in self.blocks:
            d_pseudo = np.zeros((block.n_variables, 4, 4))
            coords = np.asarray(block.coordinates)
            d_pseudo[:, coords[:, None], coords[None, :]] = block.derivatives(x)
            rows = slice(block.link * N_LINK_PARAMETERS, block.link * N_LINK_PARAMETERS + 10)
            columns = slice(block.offset, block.offset + block.n_variables)
            out[rows, columns] = _standard_from_pseudo(d_pseudo).T
        for link, k in self.armature:
            out[link * N_LINK_PARAMETERS + ARMATURE, k] = 2.0 * x[k]
        return out

    def start(self, prior: FloatArray, armature_scale: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Variables of the prior's consistent projection, and the scale of each variable.

        Each block of J − margin·1 is projected by clipping its eigenvalues at
        ``max(margin, 1e-12)``. The armature is held off 0 by 1e-12 of its scale
        (at b = 0 its gradient vanishes and it could never grow).
        """
        per_link = prior.reshape(self.n_dof, N_LINK_PARAMETERS)
        pseudo = pseudo_inertia(per_link)
        x, scales = np.zeros(self.n_variables), np.ones(self.n_variables)
        for block in self.blocks:
            index = np.ix_(block.coordinates, block.coordinates)
            shifted = pseudo[block.link][index] - self.margin * np.eye(block.size)
            eigenvalues, vectors = np.linalg.eigh(shifted)
            floor = max(self.margin, TINY)
            clipped = (vectors * np.maximum(eigenvalues, floor)) @ vectors.T
            span = slice(block.offset, block.offset + block.n_variables)
            x[span], scales[span] = block.start(clipped)
        for link, k in self.armature:
            ia = max(float(per_link[link, ARMATURE]), TINY * armature_scale[link])
            x[k], scales[k] = math.sqrt(ia), math.sqrt(armature_scale[link])
        return x, scales


def _components(live: list[int], cut: set[tuple[int, int]]) -> list[tuple[int, ...]]:
    """Connected components of the live J coordinates; an edge is a non-zero entry."""
    remaining = list(live)
    components = []
    while remaining:
        stack, component = [remaining.pop(0)], []
        while stack:
            node = stack.pop()
            component.append(node)
            linked = [c for c in remaining if (min(node, c), max(node, c)) not in cut]
            remaining = [c for c in remaining if c not in linked]
            stack += linked
        components.append(tuple(sorted(component)))
    return components
