"""Read and write local frictional contact problems in the FCLIB-like ``.npz`` format of ``shared/fclib``.

A file holds one problem ``x = W r + q`` with Coulomb friction ``mu`` per contact:

- ``dim`` (2 or 3), ``nc``, ``q`` (``dim*nc``), ``mu`` (``nc``), ``order = "nt"`` (each contact's block is
  ``(n, t1[, t2])``);
- ``W`` dense ``(dim nc, dim nc)``, or its CSR pieces ``W_data``, ``W_indices``, ``W_indptr``, ``W_shape``;
- ``name``, ``source``, ``kind`` (strings); optionally ``x_ref`` and ``r_ref``, a reference solution;
- anything else (``title``, ``description``, ``x_nodes``, ``trib`` ...) is kept in :attr:`FCProblem.extra`.

Files are read with ``allow_pickle=False``: only plain arrays and strings are accepted.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

__all__ = ["FCProblem", "list_problems", "load", "save"]

_CSR_KEYS = ("W_data", "W_indices", "W_indptr", "W_shape")
_CORE_KEYS = {"dim", "nc", "q", "mu", "order", "name", "source", "kind", "W", "x_ref", "r_ref", *_CSR_KEYS}


@dataclass
class FCProblem:
    """One local problem ``x = W r + q`` with Coulomb friction.

    Attributes:
        W: Delassus matrix: dense array, or ``scipy.sparse.csr_matrix`` when stored as CSR.
        q: Free relative displacement, length ``dim * nc``.
        mu: Friction coefficient per contact.
        dim: 2 or 3.
        nc: Number of contacts.
        name: Problem name.
        source: Where it comes from.
        kind: ``"local"``, ``"global->local"``, ``"FE-condensed"``, ...
        x_ref: Reference ``W r_ref + q`` if a reference solver converged, else None.
        r_ref: Reference forces, else None.
        extra: Every other field of the file.
    """

    W: np.ndarray | sp.csr_matrix
    q: np.ndarray
    mu: np.ndarray
    dim: int
    nc: int
    name: str = ""
    source: str = ""
    kind: str = "local"
    x_ref: np.ndarray | None = None
    r_ref: np.ndarray | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def m(self) -> int:
        """Number of unknowns ``dim * nc``."""
        return self.dim * self.nc

    @property
    def is_sparse(self) -> bool:
        """True when ``W`` was stored as CSR."""
        return sp.issparse(self.W)

    def dense_W(self) -> np.ndarray:
        """``W`` as a dense array."""
        return self.W.toarray() if sp.issparse(self.W) else np.asarray(self.W)


def _value(a: np.ndarray) -> Any:
    """0-d string arrays to str, other 0-d arrays to Python scalars (exact), larger arrays unchanged."""
    if a.ndim == 0:
        return str(a) if a.dtype.kind == "U" else a.item()
    return a


def load(path: str | Path) -> FCProblem:
    """Read a problem.

    Args:
        path: ``.npz`` file.

    Returns:
        The problem; ``W`` dense or CSR as stored.

    Raises:
        ValueError: missing field, inconsistent sizes, or a block order other than ``"nt"``.
    """
    path = Path(path)
    with np.load(path, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    missing = [k for k in ("dim", "q", "mu") if k not in data]
    if "W" not in data and not all(k in data for k in _CSR_KEYS):
        missing.append("W (dense) or " + "/".join(_CSR_KEYS))
    if missing:
        raise ValueError(f"{path}: missing field(s) {', '.join(missing)}")
    order = str(data.get("order", "nt"))
    if order != "nt":
        raise ValueError(f"{path}: order {order!r} not supported (expected 'nt': (n, t1[, t2]) per contact)")
    dim = int(data["dim"])
    q = np.asarray(data["q"], dtype=float)
    if dim not in (2, 3) or q.ndim != 1 or q.size % dim:
        raise ValueError(f"{path}: dim = {dim} and len(q) = {q.size} are inconsistent")
    nc = q.size // dim
    if "nc" in data and int(data["nc"]) != nc:
        raise ValueError(f"{path}: nc = {int(data['nc'])} but len(q) / dim = {nc}")
    mu = np.asarray(data["mu"], dtype=float)
    mu = np.full(nc, float(mu)) if mu.ndim == 0 else mu
    if mu.shape != (nc,):
        raise ValueError(f"{path}: mu has shape {mu.shape}, expected ({nc},)")
    if "W" in data:
        W = data["W"]
    else:
        W = sp.csr_matrix((data["W_data"], data["W_indices"], data["W_indptr"]),
                          shape=tuple(int(s) for s in data["W_shape"]))
    if W.shape != (q.size, q.size):
        raise ValueError(f"{path}: W has shape {W.shape}, expected ({q.size}, {q.size})")
    refs = {}
    for k in ("x_ref", "r_ref"):
        refs[k] = data[k] if k in data else None
        if refs[k] is not None and refs[k].shape != q.shape:
            raise ValueError(f"{path}: {k} has shape {refs[k].shape}, expected {q.shape}")
    extra = {k: _value(v) for k, v in data.items() if k not in _CORE_KEYS}
    return FCProblem(W=W, q=q, mu=mu, dim=dim, nc=nc, name=str(data.get("name", path.stem)),
                     source=str(data.get("source", "")), kind=str(data.get("kind", "local")),
                     x_ref=refs["x_ref"], r_ref=refs["r_ref"], extra=extra)


def save(path: str | Path, W: np.ndarray | sp.spmatrix, q: np.ndarray, mu: float | np.ndarray, dim: int,
         name: str = "", source: str = "", kind: str = "local", **extra: Any) -> Path:
    """Write a problem in the format read by :func:`load`.

    A scipy sparse ``W`` is stored as CSR pieces, a dense one as is; values are written unchanged, so
    ``load(save(...))`` gives back identical arrays.

    Args:
        path: Output file (``.npz`` is appended by NumPy if missing).
        W: Delassus matrix ``(dim nc, dim nc)``.
        q: Free relative displacement.
        mu: Friction coefficient, scalar or one per contact.
        dim: 2 or 3.
        name: Problem name (defaults to the file stem).
        source: Origin of the problem.
        kind: Problem kind.
        **extra: Further fields: ``x_ref``, ``r_ref``, arrays, numbers or strings (no objects).

    Returns:
        The path written.

    Raises:
        ValueError: inconsistent sizes, or an extra field that is not a plain array, number or string.
    """
    path = Path(path)
    if path.suffix != ".npz":
        path = path.with_name(path.name + ".npz")
    if dim not in (2, 3):
        raise ValueError(f"dim: expected 2 or 3, got {dim!r}")
    q = np.asarray(q, dtype=float)
    if q.ndim != 1 or q.size % dim:
        raise ValueError(f"q: expected a 1-D array of length multiple of dim = {dim}, got shape {q.shape}")
    nc = q.size // dim
    mu = np.asarray(mu, dtype=float)
    mu = np.full(nc, float(mu)) if mu.ndim == 0 else mu
    if mu.shape != (nc,):
        raise ValueError(f"mu: expected a scalar or shape ({nc},), got {mu.shape}")
    if W.shape != (q.size, q.size):
        raise ValueError(f"W: expected shape ({q.size}, {q.size}), got {W.shape}")
    out: dict[str, Any] = {"dim": np.int64(dim), "nc": np.int64(nc), "q": q, "mu": mu, "order": np.str_("nt"),
                           "name": np.str_(name or path.stem), "source": np.str_(source),
                           "kind": np.str_(kind)}
    if sp.issparse(W):
        csr = sp.csr_matrix(W)
        out.update(W_data=csr.data, W_indices=csr.indices, W_indptr=csr.indptr,
                   W_shape=np.asarray(csr.shape, dtype=np.int64))
    else:
        out["W"] = np.asarray(W)
    for k, v in extra.items():
        if k in out or k in _CSR_KEYS or k == "W":
            raise ValueError(f"{k}: reserved field name")
        if v is None:
            continue
        a = np.str_(v) if isinstance(v, str) else np.asarray(v)
        if isinstance(a, np.ndarray) and a.dtype.kind not in "biufcU":
            raise ValueError(f"{k}: only numeric arrays, numbers and strings can be saved, "
                             f"got dtype {a.dtype}")
        out[k] = a
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **out)
    return path


def list_problems(directory: str | Path) -> list[Path]:
    """The ``.npz`` problem files of a directory, sorted by name.

    Args:
        directory: Folder to scan (not recursive).

    Returns:
        Sorted paths; empty if the folder has none.

    Raises:
        FileNotFoundError: the folder does not exist.
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise FileNotFoundError(f"{directory}: no such directory")
    return sorted(directory.glob("*.npz"))
