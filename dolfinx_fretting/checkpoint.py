"""Checkpoints: a state (and the caller's JSON-able metadata) written to one ``.npz`` file atomically by rank 0,
and read back into the same problem, with the checks that it fits.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .contact import paired_contact_set
from .increments import on_rank0
from .io import _jsonable
from .operators import ContactOperators
from .commit import SlidingMonitor
from .state import ContactState, PlasticHistory

__all__ = ["save_state", "load_state"]

#: The per-contact and per-component arrays of a :class:`~dolfinx_fretting.state.ContactState`, stored as they are.
ARRAYS = ("forces", "positions", "slip", "wear_gap", "obstacle", "load_factors")


def save_state(operators: ContactOperators, monitor: SlidingMonitor, state: ContactState, path: str | Path,
               meta: Mapping[str, Any] | None = None) -> None:
    """Write ``state`` (and JSON-able ``meta``) to an ``.npz`` file atomically (rank 0 writes). Collective."""
    plastic = None
    if state.plastic is not None:
        p = state.plastic
        plastic = operators.comm.gather((p.u, p.sigma, p.eps_p, p.p), root=0)

    def write() -> None:  # rank 0; a failure (disk full, a folder gone) is raised on every rank
        target = Path(path)
        arrays = {k: getattr(state, k) for k in ARRAYS}
        arrays["status"] = state.status if state.status is not None else np.zeros(0, np.int8)
        arrays["warm"] = state.warm if state.warm is not None else np.zeros(0)
        arrays["targets"] = state.targets if state.targets is not None else state.obstacle
        arrays["force_controlled"] = (state.force_controlled if state.force_controlled is not None
                                      else np.zeros(state.obstacle.size, dtype=bool))
        if state.pairing is not None:  # finite sliding: the pairing and the master's wear
            arrays["pairing_faces"] = state.pairing.master_faces
            arrays["pairing_nodes"] = state.pairing.master_nodes
            arrays["pairing_weights"] = state.pairing.master_weights
            arrays["master_wear"] = state.master_wear
            arrays["repairs"] = np.array(monitor.repairs)
        for i, parts in enumerate(plastic or []):
            for name, a in zip(("u", "sigma", "eps_p", "p"), parts):
                arrays[f"plastic_{name}_{i}"] = a
        info = {"increment": state.increment, "dissipated_energy": state.dissipated_energy,
                "local_iterations": state.local_iterations, "record": state.record, "ranks": operators.comm.size,
                "load_names": operators.load_names, "global_nodes": operators.contact.contact_set.global_nodes.tolist(),
                "plastic": plastic is not None, "meta": dict(meta or {})}
        tmp = target.with_name(target.name + ".tmp.npz")
        np.savez(tmp, state=json.dumps(info, default=_jsonable), **arrays)
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.replace(tmp, target)
    on_rank0(operators.comm, write)


def load_state(operators: ContactOperators, monitor: SlidingMonitor, path: str | Path
               ) -> tuple[ContactState, dict[str, Any]]:
    """Read a state written by :func:`save_state` (same problem, same contact set). Collective.

    Raises:
        ValueError: the file does not match this problem (contact nodes, loads, ranks of a plastic state).
    """
    def read() -> dict[str, np.ndarray]:
        with np.load(path, allow_pickle=False) as npz:
            return {k: npz[k] for k in npz.files}

    data = on_rank0(operators.comm, read)
    info = json.loads(str(data["state"]))
    if info["global_nodes"] != operators.contact.contact_set.global_nodes.tolist():
        raise ValueError(f"{path}: the saved contact set differs from this problem's")
    if info["load_names"] != operators.load_names:
        raise ValueError(f"{path}: saved loads {info['load_names']} differ from this problem's {operators.load_names}")
    plastic = None
    if info["plastic"]:
        if info["ranks"] != operators.comm.size:
            raise ValueError(f"{path}: an elastic-plastic state saved on {info['ranks']} rank(s) loads on the same "
                             f"number (here {operators.comm.size})")
        i = operators.comm.rank
        plastic = PlasticHistory(*(data[f"plastic_{k}_{i}"].copy() for k in ("u", "sigma", "eps_p", "p")))
    warm = data["warm"] if data["warm"].size and operators.comm.rank == 0 else None
    pairing = master_wear = None
    if ("pairing_faces" in data) != (operators.surface_compliance is not None):
        raise ValueError(f"{path}: a state saved with{'' if 'pairing_faces' in data else 'out'} finite sliding "
                         f"loads into a problem with{'' if operators.surface_compliance is not None else 'out'} it")
    if operators.surface_compliance is not None:
        ref = operators.reference_pairing
        pairing = paired_contact_set(ref.master_surface, ref.global_nodes, ref.coords, ref.tributary,
                                     ref.abscissa, data["pairing_faces"], data["pairing_weights"], ref.H.shape[1])
        master_wear = data["master_wear"].copy()
        if (not np.array_equal(pairing.master_nodes, data["pairing_nodes"])
                or master_wear.shape != (operators.surface_compliance.nodes.size,)):
            raise ValueError(f"{path}: the saved pairing or master wear does not fit this problem's master surface")
        operators.surface_compliance.rows(pairing.master_nodes)   # within reach, or a message
        monitor.repairs = int(data["repairs"])
    state = ContactState(*(data[k].copy() for k in ARRAYS), increment=int(info["increment"]),
                         dissipated_energy=float(info["dissipated_energy"]),
                         local_iterations=int(info["local_iterations"]), record=info["record"],
                         status=data["status"].copy() if data["status"].size else None, warm=warm,
                         targets=data["targets"].copy(), force_controlled=data["force_controlled"].copy(),
                         plastic=plastic, pairing=pairing, master_wear=master_wear)
    return state, info["meta"]
