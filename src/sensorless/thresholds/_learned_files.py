"""The weights file of the learned family: ``<stem>.npz`` (arrays) beside ``<stem>.json``.

The JSON file is what a person reads: the format name and version, the
library version, the robot the network was trained for (name, joints,
fingerprint of the nominal model), the signals it reads (kind, observer gain
K_I [1/s], sample period [s] and, from format version 2, the band of periods
it was trained on, ``period_range`` [s], or null), the architecture, the
input and output normalisation, the training recipe with its seeds, and the
SHA-256 of the ``.npz`` file, which holds only the trained arrays (``kernel_<k>``,
``bias_<k>``, ``head``, ``head_bias``). Both are written and read without
pickle. Weights shipped with the package live in ``sensorless/data/learned``
and are named by their robot (:func:`builtin_weights`).

Versions: 1 has no ``period_range`` (the network was trained at ``dt`` only);
2 adds it. Both are read; version 2 is written.
"""

from __future__ import annotations

import hashlib
import importlib.resources
import io
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._validation import FloatArray
from .._version import __version__
from ..exceptions import (
    FileFormatError,
    InputTypeError,
    InputValueError,
    MissingFileError,
    UnknownNameError,
)
from ._cnn import CHANNELS, Network

__all__ = [
    "WEIGHTS_FORMAT",
    "WEIGHTS_FORMAT_VERSION",
    "LearnedWeights",
    "builtin_weights",
    "load_weights",
    "save_weights",
]

WEIGHTS_FORMAT = "sensorless-learned-weights"
WEIGHTS_FORMAT_VERSION = 2
"""Version of the weights format this library writes (it reads 1 and 2)."""
_NORMALISATION = ("input_mean", "input_scale", "output_mean", "output_scale")


@dataclass(frozen=True, eq=False)
class LearnedWeights:
    """A trained network and what it was trained for.

    Attributes
    ----------
    network : Network
        The arrays (:mod:`sensorless.thresholds._cnn`).
    robot : str
        Name of the nominal robot model of the training runs.
    kind : str
        Signal kind the network reads (``"motor"``).
    gain : float
        Observer gain K_I of the training runs [1/s].
    dt : float
        Sample period of the training scenario [s]; the dilations count samples.
    fingerprint : str
        Fingerprint of the nominal model of the training runs (empty: unknown).
    recipe : dict
        How it was trained: scenario, minutes, seeds, randomisation, optimiser.
    library_version : str
        Version of sensorless that trained it.
    period_range : (float, float) or None
        Shortest and longest sample period of the training runs' band [s]
        (the recipe's ``rate_factor``); None: trained at ``dt`` only.
    """

    network: Network
    robot: str
    kind: str
    gain: float
    dt: float
    fingerprint: str = ""
    recipe: dict[str, Any] = field(default_factory=dict)
    library_version: str = __version__
    period_range: tuple[float, float] | None = None

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return self.network.n_dof


def _data_dir() -> Path:
    return Path(str(importlib.resources.files("sensorless") / "data" / "learned"))


def builtin_weights() -> list[str]:
    """Robots for which trained weights ship with the package."""
    return sorted(p.stem for p in _data_dir().glob("*.json"))


def _stem(path: str | Path) -> Path:
    out = Path(path)
    return out.with_suffix("") if out.suffix in (".npz", ".json") else out


def _arrays(network: Network) -> dict[str, FloatArray]:
    found = {f"kernel_{k}": a for k, a in enumerate(network.kernels)}
    found |= {f"bias_{k}": a for k, a in enumerate(network.biases)}
    return found | {"head": network.head, "head_bias": network.head_bias}


def save_weights(weights: LearnedWeights, path: str | Path) -> Path:
    """Write ``<stem>.npz`` and ``<stem>.json`` (a ``.npz``/``.json`` suffix is dropped).

    Returns
    -------
    Path
        The JSON file (what :func:`load_weights` takes).
    """
    if not isinstance(weights, LearnedWeights):
        raise InputTypeError(f"weights must be LearnedWeights; got {type(weights).__name__}")
    band = weights.period_range
    if band is not None and not 0.0 < band[0] <= band[1] < np.inf:
        raise InputValueError(
            f"period_range must be (low, high) [s] with 0 < low <= high; got {band}"
        )
    stem = _stem(path)
    buffer = io.BytesIO()
    np.savez(buffer, allow_pickle=False, **_arrays(weights.network))
    data = buffer.getvalue()
    net = weights.network
    meta = {
        "format": WEIGHTS_FORMAT,
        "format_version": WEIGHTS_FORMAT_VERSION,
        "library_version": weights.library_version,
        "robot": weights.robot,
        "n_dof": net.n_dof,
        "fingerprint": weights.fingerprint,
        "kind": weights.kind,
        "gain": weights.gain,
        "dt": weights.dt,
        "period_range": None if weights.period_range is None else list(weights.period_range),
        "architecture": {
            "inputs": list(CHANNELS),
            "channels": int(net.kernels[-1].shape[0]),
            "kernel": 3,
            "dilations": list(net.dilations),
            "delays": list(net.delays),
            "receptive_field": net.receptive_field,
            "activation": "tanh",
            "outputs": "centre = output_mean + output_scale * o1; "
            "width = output_scale * (softplus(o2) + floor)",
            "floor": net.floor,
            "n_parameters": net.n_parameters,
        },
        "normalisation": {name: getattr(net, name).tolist() for name in _NORMALISATION},
        "training": weights.recipe,
        "arrays": stem.with_suffix(".npz").name,
        "arrays_sha256": hashlib.sha256(data).hexdigest(),
    }
    stem.parent.mkdir(parents=True, exist_ok=True)
    stem.with_suffix(".npz").write_bytes(data)
    out = stem.with_suffix(".json")
    out.write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")
    return out


def _resolve(name_or_path: str | Path) -> Path:
    if isinstance(name_or_path, str) and name_or_path in builtin_weights():
        return _data_dir() / f"{name_or_path}.json"
    path = _stem(name_or_path).with_suffix(".json")
    if path.is_file():
        return path
    if isinstance(name_or_path, str) and not Path(name_or_path).suffix and "/" not in name_or_path:
        raise UnknownNameError(
            f"no shipped weights named {name_or_path!r}; shipped: {builtin_weights()} "
            "(or give the path of a weights file)"
        )
    raise MissingFileError(f"weights file not found: {path}")


def _problem(source: Path, message: str) -> FileFormatError:
    return FileFormatError(f"weights file {source}: {message}")


def load_weights(name_or_path: str | Path) -> LearnedWeights:
    """Read weights by robot name (shipped) or by path (``<stem>``, ``.json`` or ``.npz``).

    Raises
    ------
    UnknownNameError
        A bare name that is not shipped and not a file.
    MissingFileError
        No such file.
    FileFormatError
        Not a weights file, a newer format, arrays that do not match the
        JSON (checksum, shapes).
    """
    if not isinstance(name_or_path, str | Path):
        raise InputTypeError(
            f"weights must be a robot name or a path; got {type(name_or_path).__name__}"
        )
    source = _resolve(name_or_path)
    try:
        meta = json.loads(source.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise _problem(source, f"not JSON text ({exc})") from None
    if not isinstance(meta, dict) or meta.get("format") != WEIGHTS_FORMAT:
        raise _problem(source, f"expected 'format': {WEIGHTS_FORMAT!r}")
    version = meta.get("format_version")
    if not isinstance(version, int) or not 1 <= version <= WEIGHTS_FORMAT_VERSION:
        raise _problem(
            source, f"format_version must be 1..{WEIGHTS_FORMAT_VERSION}; got {version!r}"
        )
    try:
        return _from_meta(meta, source)
    except (KeyError, TypeError, ValueError) as exc:
        raise _problem(source, f"{type(exc).__name__}: {exc}") from None


def _from_meta(meta: dict[str, Any], source: Path) -> LearnedWeights:
    arrays_path = source.parent / str(meta["arrays"])
    if not arrays_path.is_file():
        raise MissingFileError(f"weights arrays not found: {arrays_path} (named by {source})")
    data = arrays_path.read_bytes()
    if hashlib.sha256(data).hexdigest() != meta["arrays_sha256"]:
        raise _problem(source, f"{arrays_path.name} does not match arrays_sha256")
    with np.load(io.BytesIO(data), allow_pickle=False) as npz:
        arrays = {k: np.asarray(npz[k], dtype=np.float64) for k in npz.files}
    arch = meta["architecture"]
    dilations = tuple(int(d) for d in arch["dilations"])
    n = len(dilations)
    norm = {k: np.asarray(meta["normalisation"][k], dtype=np.float64) for k in _NORMALISATION}
    network = Network(
        tuple(arrays[f"kernel_{k}"] for k in range(n)),
        tuple(arrays[f"bias_{k}"] for k in range(n)),
        arrays["head"],
        arrays["head_bias"],
        dilations,
        norm["input_mean"],
        norm["input_scale"],
        norm["output_mean"],
        norm["output_scale"],
        float(arch["floor"]),
    )
    _check_shapes(network, int(meta["n_dof"]), source)
    band = meta.get("period_range") if meta["format_version"] >= 2 else None
    period_range = None if band is None else _period_range(band, source)
    return LearnedWeights(
        network,
        str(meta["robot"]),
        str(meta["kind"]),
        float(meta["gain"]),
        float(meta["dt"]),
        str(meta.get("fingerprint", "")),
        dict(meta.get("training", {})),
        str(meta.get("library_version", "")),
        period_range,
    )


def _period_range(band: Any, source: Path) -> tuple[float, float]:
    low, high = (float(v) for v in band)
    if not 0.0 < low <= high < np.inf:
        raise _problem(
            source, f"period_range must be [low, high] [s] with 0 < low <= high; got {band}"
        )
    return low, high


def _check_shapes(net: Network, n_dof: int, source: Path) -> None:
    channels = net.head.shape[1]
    expected: dict[str, tuple[int, ...]] = {"head": (2, channels), "head_bias": (2, 1)}
    c_in = len(CHANNELS)
    for k in range(len(net.dilations)):
        expected[f"kernel_{k}"] = (channels, 3 * c_in)
        expected[f"bias_{k}"] = (channels, n_dof if k == 0 else 1)
        c_in = channels
    for name in _NORMALISATION:
        expected[name] = (len(CHANNELS), n_dof) if name.startswith("input") else (n_dof,)
    found = _arrays(net) | {name: getattr(net, name) for name in _NORMALISATION}
    for name, shape in expected.items():
        value = found[name]
        if value.shape != shape:
            raise _problem(source, f"{name} must have shape {shape}; got {value.shape}")
        if not np.isfinite(value).all():
            raise _problem(source, f"{name} must be finite")
    if (net.input_scale <= 0).any() or (net.output_scale <= 0).any() or not net.floor > 0:
        raise _problem(source, "input_scale, output_scale and floor must be > 0")
