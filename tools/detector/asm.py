"""The Active Shape Model of seed 000 (Eq. 1) for the Python side (docs/asm.md).

Contract
--------
``load_asm(path)`` reads a ``format_version: 1`` ASM YAML file (the file
``vp_asm_learn`` writes, default ``models/asm/default_asm.yaml``) with PyYAML
(Debian's ``python3-yaml``) and returns an ``Asm``:

* ``mean``        [36, 3] float64, metres, vehicle frame (x forward, y left, z up);
* ``sigma``       [n_s];
* ``eigenvectors`` [n_s, 36, 3] (orthonormal as 108-vectors);
* ``type_priors`` {type: (mean [n_s], covariance [n_s, n_s])};
* ``n_s``, ``keypoint_names``, ``EVAL_KEYPOINTS`` (indices 0..23).

``Asm.shape(gamma)`` is Eq. 1, M(gamma) = m + sum_s gamma_s sigma_s e_s, for numpy arrays
[..., n_s] -> [..., 36, 3]. ``Asm.torch_basis()`` gives (mean, basis) as float32 tensors for
the V_L2 loss (basis[s] = sigma_s e_s). Errors name the file and the field, as the C++ loader.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Dict, List, Tuple

import numpy as np

KEYPOINT_COUNT = 36
EVAL_KEYPOINTS = tuple(range(24))
CAR_TYPES = ("estate", "compact", "sports", "sedan", "suv", "van")
TYPES = CAR_TYPES + ("large",)  # network class order; index 6 = bus/truck (no ASM shape)

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEFAULT_ASM_PATH = os.path.join(REPO_ROOT, "models", "asm", "default_asm.yaml")


class AsmError(ValueError):
    pass


@dataclass
class Asm:
    path: str
    keypoint_names: List[str]
    mean: np.ndarray
    sigma: np.ndarray
    eigenvectors: np.ndarray
    type_priors: Dict[str, Tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)

    @property
    def n_s(self) -> int:
        return int(self.sigma.shape[0])

    def shape(self, gamma) -> np.ndarray:
        g = np.asarray(gamma, np.float64)
        basis = self.sigma[:, None, None] * self.eigenvectors  # [n_s, 36, 3]
        return self.mean + np.tensordot(g, basis, axes=([-1], [0]))

    def torch_basis(self):
        import torch

        basis = self.sigma[:, None, None] * self.eigenvectors
        return (torch.tensor(self.mean, dtype=torch.float32),
                torch.tensor(basis, dtype=torch.float32))


def _fail(path: str, fld: str, msg: str):
    raise AsmError(f"{path}: field '{fld}': {msg}")


def _matrix(path: str, fld: str, value, rows: int, cols: int) -> np.ndarray:
    if not isinstance(value, list) or len(value) != rows:
        _fail(path, fld, f"expected {rows} entries, got "
              f"{len(value) if isinstance(value, list) else type(value).__name__}")
    out = np.zeros((rows, cols))
    for i, row in enumerate(value):
        if not isinstance(row, list) or len(row) != cols:
            _fail(path, f"{fld}[{i}]", f"expected {cols} entries, got "
                  f"{len(row) if isinstance(row, list) else type(row).__name__}")
        for j, v in enumerate(row):
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                _fail(path, f"{fld}[{i}][{j}]", f"not a number: {v!r}")
            out[i, j] = float(v)
    if not np.all(np.isfinite(out)):
        _fail(path, fld, "non-finite value")
    return out


def load_asm(path: str = DEFAULT_ASM_PATH) -> Asm:
    """Reads and checks an ASM file (see the module docstring)."""
    try:
        import yaml
    except ImportError as exc:  # pragma: no cover - python3-yaml is a Debian dependency
        raise AsmError("PyYAML is needed (Debian package python3-yaml)") from exc
    try:
        with open(path, "r", encoding="utf-8") as f:
            doc = yaml.safe_load(f)
    except OSError as exc:
        raise AsmError(f"{path}: cannot read ({exc.strerror})") from exc
    except yaml.YAMLError as exc:
        raise AsmError(f"{path}: not valid YAML ({exc})") from exc
    if not isinstance(doc, dict):
        raise AsmError(f"{path}: not a YAML map")
    if doc.get("format_version") != 1:
        _fail(path, "format_version", f"unsupported version {doc.get('format_version')!r} "
              "(this reader reads 1)")
    names = doc.get("keypoint_names")
    if not isinstance(names, list) or len(names) != KEYPOINT_COUNT:
        _fail(path, "keypoint_names", f"expected {KEYPOINT_COUNT} names")
    n_s = doc.get("component_count")
    if not isinstance(n_s, int) or not 1 <= n_s <= 8:
        _fail(path, "component_count", f"expected an integer 1..8, got {n_s!r}")
    mean = _matrix(path, "mean", doc.get("mean"), KEYPOINT_COUNT, 3)
    sigma = _matrix(path, "sigma", [doc.get("sigma")], 1, n_s)[0]
    if np.any(sigma < 0):
        _fail(path, "sigma", "negative value")
    ev_raw = doc.get("eigenvectors")
    if not isinstance(ev_raw, list) or len(ev_raw) != n_s:
        _fail(path, "eigenvectors", f"expected {n_s} entries")
    ev = np.stack([_matrix(path, f"eigenvectors[{s}]", e, KEYPOINT_COUNT, 3)
                   for s, e in enumerate(ev_raw)])
    gram = ev.reshape(n_s, -1) @ ev.reshape(n_s, -1).T
    if np.abs(gram - np.eye(n_s)).max() > 1e-6:
        _fail(path, "eigenvectors", "not orthonormal (tolerance 1e-6)")
    priors = {}
    for t, p in (doc.get("type_priors") or {}).items():
        if t not in CAR_TYPES:
            _fail(path, "type_priors", f"unknown type '{t}'")
        m = _matrix(path, f"type_priors.{t}.mean", [p.get("mean")], 1, n_s)[0]
        c = _matrix(path, f"type_priors.{t}.covariance", p.get("covariance"), n_s, n_s)
        priors[t] = (m, c)
    return Asm(path=path, keypoint_names=[str(n) for n in names], mean=mean, sigma=sigma,
               eigenvectors=ev, type_priors=priors)
