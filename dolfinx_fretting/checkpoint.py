"""Checkpoints: a state (and the caller's JSON-able metadata) written to one ``.npz`` file atomically by rank 0,
and read back into the same problem, with the checks that it fits.

A state's per-contact arrays are in the contact set's order, which is by position along the surface whatever the
partition; the contact set is recognised by its nodes' coordinates, not by DOLFINx's global node numbers (those
differ between launches under MPI and between rank counts), so a state written on N ranks loads on any number. An
elastic-plastic state's displacement and quadrature-point history are saved with keys that do not depend on the
partition (each dof block's node in the input mesh, each point's coordinates) and matched by them on loading
(checkpoints of earlier releases hold each rank's arrays: they load on the partition they were written on, checked
by a fingerprint of its dof coordinates). A finite-sliding state's pairing is saved as each contact's master facet
by its nodes' input mesh indices, with the weights in that order, and the master's wear by the same indices; on
loading each facet is found in this problem's master surface by its node set (the weights permuted to its node
order) and the wear reordered to its surface compliance (checkpoints of earlier releases hold facet indices and
DOLFINx's node numbers: they load where those are the same, and are refused elsewhere).

A checkpoint also holds the contact parameters of the problem that wrote it (:func:`contact_parameters`: each
zone's friction coefficients, wear law and obstacle), and a problem with other values refuses it, naming them.
What it does not check: the bilinear form (material), the Dirichlet conditions, the load vectors' values (their
names are checked), the local solver's settings and the plastic law.
"""

from __future__ import annotations

import hashlib
import json
import os
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
from mpi4py import MPI
from scipy.spatial import cKDTree

from . import _dolfinx as dfx
from . import friction
from .contact import ContactSet, mortar_rows_set, paired_contact_set
from .increments import on_rank0
from .io import _jsonable
from .laws import EvolvingFriction, WearLaw
from .operators import ContactOperators
from .commit import SlidingMonitor
from .state import ContactState, PlasticHistory

__all__ = ["save_state", "load_state", "contact_parameters", "friction_parameters", "parameter_differences"]

#: The per-contact and per-component arrays of a :class:`~dolfinx_fretting.state.ContactState`, stored as they are.
ARRAYS = ("forces", "positions", "slip", "wear_gap", "obstacle", "load_factors")


def _partition_fingerprint(operators: ContactOperators) -> str:
    """This rank's owned and ghost dof coordinates, hashed (rounded to 1e-9: the same mesh read again gives the same
    bits): what an elastic-plastic state's per-rank arrays are laid out on."""
    coords = operators.V.tabulate_dof_coordinates()
    return hashlib.sha1(np.round(coords, 9).tobytes()).hexdigest()


def friction_parameters(law) -> dict[str, Any] | None:
    """A friction law's parameters beyond its starting coefficients, as plain data: an
    :class:`~dolfinx_fretting.laws.EvolvingFriction`'s variable and table (a function: its description, which names
    it), None for a constant law."""
    if not isinstance(law, EvolvingFriction):
        return None
    table = law.table
    return {"law": type(law).__name__, "variable": law.variable,
            "table": None if table is None else table.tolist(), "describe": law.describe()}


def contact_parameters(operators: ContactOperators, wear_laws: Sequence[WearLaw | None]) -> list[dict[str, Any]]:
    """Each zone's contact parameters as plain data (what a checkpoint saves and checks): its friction coefficient
    per contact at the start (``mu``) and an evolving law's variable and table (``friction``,
    :func:`friction_parameters`), its wear law (class name, each body's coefficient, acceleration; None without
    wear) and its obstacle (class name, normal, a rigid plane's point, an elastic body's contact formulation)."""
    contacts = operators.contact
    zones = []
    for zone, (obstacle, law) in enumerate(zip((c.obstacle for c in contacts.zones), wear_laws)):
        point = getattr(obstacle, "point", None)
        wear = None if law is None else {"law": type(law).__name__, "body_coefficients": list(law.body_coefficients),
                                         "acceleration": float(law.acceleration), "describe": law.describe()}
        zones.append({"mu": contacts.mu[contacts.zone_slice(zone)].tolist(),
                      "friction": friction_parameters(contacts.zones[zone].friction), "wear": wear,
                      "obstacle": {"kind": type(obstacle).__name__, "normal": np.asarray(obstacle.normal).tolist(),
                                   "point": None if point is None else np.asarray(point).tolist(),
                                   "formulation": getattr(obstacle, "formulation", None)}})
    return zones


def _values(values: list[float]) -> str:
    """A zone's friction coefficients in a message: one value, or their range."""
    array = np.asarray(values, dtype=float)
    if array.size and np.all(array == array[0]):
        return f"{array[0]:g}"
    return f"{array.min(initial=np.inf):g} to {array.max(initial=-np.inf):g} per contact"


def _same_friction(old: Mapping[str, Any] | None, new: Mapping[str, Any] | None) -> bool:
    """Whether two zones' :func:`friction_parameters` are the same law: both constant, or the same variable and table
    (1e-12: the user's values through JSON's exact float repr, as mu), or functions of the same name."""
    if old is None or new is None:
        return old is None and new is None
    if old["variable"] != new["variable"] or (old["table"] is None) != (new["table"] is None):
        return False
    if old["table"] is None:
        return old["describe"] == new["describe"]
    return (np.shape(old["table"]) == np.shape(new["table"])
            and np.allclose(old["table"], new["table"], rtol=1e-12, atol=0.0))


def _obstacle(obstacle: Mapping[str, Any]) -> str:
    point = "" if obstacle["point"] is None else f" point {np.asarray(obstacle['point']).tolist()}"
    formulation = _formulation(obstacle)
    formulation = "" if formulation is None else f" formulation {formulation!r}"
    return f"{obstacle['kind']}{point} normal {np.round(obstacle['normal'], 12).tolist()}{formulation}"


def _formulation(obstacle: Mapping[str, Any]) -> str | None:
    """An elastic body's contact formulation; a checkpoint saved before mortar existed (no key) was "node"."""
    if "formulation" not in obstacle and obstacle["kind"] == "ElasticBody":
        return "node"
    return obstacle.get("formulation")


def parameter_differences(saved: list[dict[str, Any]], current: list[dict[str, Any]], extent: float) -> list[str]:
    """The contact parameters that differ between a checkpoint's (``saved``) and this problem's (``current``), one
    phrase each naming both values (empty: the same). ``extent``: the contact surface's size, the scale of a plane's
    position."""
    if len(saved) != len(current):
        return [f"{len(saved)} contact zone(s) saved, {len(current)} here"]
    out = []
    for zone, (old, new) in enumerate(zip(saved, current)):
        who = f"contact[{zone}] " if len(saved) > 1 else ""
        mu_old, mu_new = np.asarray(old["mu"], dtype=float), np.asarray(new["mu"], dtype=float)
        # The user's values through JSON's exact float repr: equal bits when unchanged; 1e-12 only absorbs a
        # coefficient recomputed by another NumPy.
        if mu_old.shape != mu_new.shape or not np.allclose(mu_old, mu_new, rtol=1e-12, atol=1e-15):
            out.append(f"{who}mu: saved {_values(old['mu'])}, this problem's {_values(new['mu'])}")
        # (a checkpoint of an earlier release has no "friction": its laws were constant)
        friction_old, friction_new = old.get("friction"), new.get("friction")
        if not _same_friction(friction_old, friction_new):
            describe = lambda law: "constant mu" if law is None else law["describe"]  # noqa: E731
            out.append(f"{who}friction law: saved {describe(friction_old)}, this problem's {describe(friction_new)}")
        wear_old, wear_new = old["wear"], new["wear"]
        same_wear = (wear_old is None) == (wear_new is None) and (wear_old is None or (
            wear_old["law"] == wear_new["law"]
            and np.allclose(wear_old["body_coefficients"], wear_new["body_coefficients"], rtol=1e-12, atol=0.0)
            and np.isclose(wear_old["acceleration"], wear_new["acceleration"], rtol=1e-12, atol=0.0)))
        if not same_wear:
            describe = lambda wear: "no wear" if wear is None else wear["describe"]  # noqa: E731
            out.append(f"{who}wear law: saved {describe(wear_old)}, this problem's {describe(wear_new)}")
        obstacle_old, obstacle_new = old["obstacle"], new["obstacle"]
        normal_new = np.asarray(obstacle_new["normal"], dtype=float)
        # Unit normals: 1e-12 absorbs a normalisation by another NumPy. A rigid plane is the same plane when the
        # saved point lies on this one (within 1e-9 of the surface's extent, as the contact nodes' coordinates):
        # a point moved along the plane changes no gap.
        same = (obstacle_old["kind"] == obstacle_new["kind"]
                and np.shape(obstacle_old["normal"]) == normal_new.shape
                and np.allclose(obstacle_old["normal"], normal_new, rtol=0.0, atol=1e-12)
                and (obstacle_old["point"] is None) == (obstacle_new["point"] is None)
                and _formulation(obstacle_old) == _formulation(obstacle_new))
        if same and obstacle_new["point"] is not None:
            offset = (np.asarray(obstacle_old["point"], dtype=float) - np.asarray(obstacle_new["point"])) @ normal_new
            same = abs(float(offset)) <= 1e-9 * extent
        if not same:
            out.append(f"{who}obstacle: saved {_obstacle(obstacle_old)}, this problem's {_obstacle(obstacle_new)}")
    return out


#: The arrays of an elastic-plastic state's history (:class:`~dolfinx_fretting.state.PlasticHistory`): the
#: displacement (saved by owned dof block with its node's coordinates) and the quadrature points' history (saved
#: with the points' coordinates).
PLASTIC_ARRAYS = ("u", "sigma", "eps_p", "p")


def _dof_block_keys(operators: ContactOperators) -> np.ndarray:
    """The input mesh's node index of each of this rank's dof blocks (owned, then ghosts): what an elastic-plastic
    state's displacement is saved by. Unlike DOLFINx's numbering it does not depend on the partition, and unlike
    the coordinates it tells apart two bodies' nodes at one place (where they touch). P1 on the mesh's own
    (affine) geometry: a cell's dofs are its geometry nodes in the same order."""
    V = operators.V
    msh = V.mesh
    index_map = V.dofmap.index_map
    keys = np.full(index_map.size_local + index_map.num_ghosts, -1, dtype=np.int64)
    keys[dfx.cell_dofmap(V).ravel()] = np.asarray(msh.geometry.input_global_indices,
                                                  dtype=np.int64)[dfx.geometry_dofmap(msh).ravel()]
    return keys


def _input_indices(operators: ContactOperators, global_nodes: np.ndarray) -> np.ndarray:
    """The input mesh's node index (:func:`_dof_block_keys`) of each of ``global_nodes`` (DOLFINx global block
    numbers, any shape, the same on every rank; -1 padding stays -1), on every rank: what a finite-sliding state's
    master facets and master wear are saved by. Collective."""
    global_nodes = np.asarray(global_nodes, dtype=np.int64)
    index_map = operators.V.dofmap.index_map
    start = int(index_map.local_range[0])
    owned = _dof_block_keys(operators)[: index_map.size_local]
    local = global_nodes - start
    mine = (global_nodes >= 0) & (local >= 0) & (local < owned.size)
    keys = np.full(global_nodes.shape, -1, dtype=np.int64)
    keys[mine] = owned[local[mine]]
    # Each node has one owner, which writes its index; every other rank holds -1 there.
    operators.comm.Allreduce(MPI.IN_PLACE, keys, op=MPI.MAX)
    return keys


def _find_facets(saved: np.ndarray, weights: np.ndarray, here: np.ndarray,
                 path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Each saved facet (its nodes' input indices, in its saved node order) found among this problem's master
    facets ``here`` (the same, in this problem's order): (the facet's index here, ``weights`` permuted into its
    node order here). A facet is its node set (in a conforming mesh no two facets share one); its node order may
    differ between partitions (a 2D segment's ends follow the local vertex numbers).

    Raises:
        ValueError: a saved facet is not a facet of this problem's master surface.
    """
    canonical = lambda rows: np.sort(rows, axis=1)  # noqa: E731 - a facet's node set (-1 padding sorts first)
    lookup = {tuple(row): index for index, row in enumerate(canonical(here))}
    faces = np.empty(saved.shape[0], dtype=np.int64)
    permuted = np.zeros_like(weights)
    for contact, (row, key) in enumerate(zip(saved, canonical(saved))):
        face = lookup.get(tuple(key))
        if face is None:
            raise ValueError(f"{path}: the saved pairing of contact {contact} is on a master facet (input mesh "
                             f"nodes {row[row >= 0].tolist()}) that is not on this problem's master surface: load "
                             "it into the mesh it was written with")
        faces[contact] = face
        for j, node in enumerate(here[face]):
            if node >= 0:
                permuted[contact, j] = weights[contact, int(np.flatnonzero(row == node)[0])]
    return faces, permuted


def _gather_plastic(operators: ContactOperators, history: PlasticHistory, points: np.ndarray) -> dict | None:
    """Every rank's owned part of ``history`` with its keys (dof blocks: the input node index; quadrature points:
    their coordinates), stacked on rank 0 (None elsewhere). Collective."""
    bs = operators.V.dofmap.index_map_bs
    owned = operators.V.dofmap.index_map.size_local
    mine = (_dof_block_keys(operators)[:owned], history.u[: owned * bs].reshape(-1, bs), points, history.sigma,
            history.eps_p, history.p)
    parts = operators.comm.gather(mine, root=0)
    if parts is None:
        return None
    stacked = [np.concatenate([part[i] for part in parts]) for i in range(len(mine))]
    return dict(zip(("u_nodes", "u", "points", "sigma", "eps_p", "p"), stacked))


def _match_points(saved: np.ndarray, mine: np.ndarray) -> np.ndarray | None:
    """For each of ``mine`` (n, 3) the index of the saved quadrature point at the same place (within 1e-9 of the
    points' extent: the mesh's input bits on every partition, far below any element; quadrature points are inside
    cells, so no two bodies share one), None if one has none."""
    if mine.shape[0] == 0:
        return np.zeros(0, dtype=np.int64)
    if saved.shape[0] == 0:
        return None
    extent = max(float(np.ptp(saved, axis=0).max(initial=0.0)), 1e-300)
    distance, index = cKDTree(saved).query(mine)
    return index if distance.max() <= 1e-9 * extent else None


def _match_keys(saved: np.ndarray, mine: np.ndarray) -> np.ndarray | None:
    """For each of ``mine`` the index of the same key in ``saved``, None if one is not there."""
    if mine.size == 0:
        return np.zeros(0, dtype=np.int64)
    if saved.size == 0:
        return None
    order = np.argsort(saved)
    found = np.minimum(np.searchsorted(saved[order], mine), saved.size - 1)
    return order[found] if np.array_equal(saved[order][found], mine) else None


def _plastic_from(operators: ContactOperators, data: dict[str, np.ndarray], points: np.ndarray,
                  path: str | Path) -> PlasticHistory:
    """This rank's part of a saved plastic history, matched by its keys (any partition). Collective."""
    node_index = _match_keys(data["plastic_u_nodes"], _dof_block_keys(operators))  # owned and ghost blocks alike
    point_index = _match_points(data["plastic_points"], points)
    missing = node_index is None or point_index is None
    if operators.comm.allreduce(missing, op=MPI.LOR):   # every rank raises, or none
        raise ValueError(f"{path}: the saved elastic-plastic state does not fit this mesh (a node or quadrature "
                         "point of this problem has no saved one): load it into the mesh it was written with, and "
                         "the same quadrature degree")
    u = data["plastic_u"][node_index].reshape(-1)
    return PlasticHistory(u.copy(), data["plastic_sigma"][point_index].copy(),
                          data["plastic_eps_p"][point_index].copy(), data["plastic_p"][point_index].copy())


def _pairing_from(operators: ContactOperators, data: dict[str, np.ndarray],
                  path: str | Path) -> tuple[ContactSet, np.ndarray]:
    """A saved finite-sliding pairing and master wear in this problem's master surface and surface compliance
    (any partition: facets and nodes found by their input mesh node indices). Collective.

    Raises:
        ValueError: a saved facet or master wear node is not this problem's (the same on every rank: every rank
            holds the same saved and replicated arrays).
    """
    ref = operators.reference_pairing
    surface, compliance = ref.master_surface, operators.surface_compliance
    weights = data["pairing_weights"]
    if "pairing_facet_nodes" in data or "pairing_master_nodes" in data:
        here = _input_indices(operators, surface.nodes)
        wear_nodes = _input_indices(operators, compliance.nodes)
        if "pairing_master_nodes" in data:   # mortar
            pairing = _mortar_pairing_from(ref, data, surface.nodes, here, path)
        else:
            faces, weights = _find_facets(data["pairing_facet_nodes"], weights, here, path)
        order = _match_keys(data["master_wear_nodes"], wear_nodes)
        if order is None or data["master_wear_nodes"].size != wear_nodes.size:
            raise ValueError(f"{path}: the saved master wear is on {data['master_wear_nodes'].size} surface nodes, "
                             f"this problem's surface compliance has {wear_nodes.size} and they are not the same "
                             "input mesh nodes: load it into the mesh it was written with and the same "
                             "ElasticBody.reach")
        master_wear = data["master_wear"][order].copy()
        if "pairing_master_nodes" in data:
            return pairing, master_wear
    else:   # a checkpoint of an earlier release: facet indices and DOLFINx's node numbers, as they were saved
        faces, master_wear = data["pairing_faces"], data["master_wear"].copy()
    pairing = paired_contact_set(surface, ref.global_nodes, ref.coords, ref.tributary, ref.abscissa, faces, weights,
                                 ref.H.shape[1], ref.surface_mass)
    if "pairing_nodes" in data and (not np.array_equal(pairing.master_nodes, data["pairing_nodes"])
                                    or master_wear.shape != (compliance.nodes.size,)):
        raise ValueError(f"{path}: the saved pairing or master wear does not fit this problem's master surface (a "
                         "finite-sliding checkpoint of an earlier release holds DOLFINx's node numbers: resume it "
                         "on the number of ranks it was written on)")
    return pairing, master_wear


def _mortar_pairing_from(ref: ContactSet, data: dict[str, np.ndarray], surface_nodes: np.ndarray,
                         surface_keys: np.ndarray, path: str | Path) -> ContactSet:
    """A saved mortar pairing (each contact's master nodes by input mesh index, weights, ``D_jj``, master sizes) as
    a contact set of this problem (:func:`~dolfinx_fretting.contact.mortar_rows_set`).

    Raises:
        ValueError: a saved master node is not on this problem's master surface, or the saved rows are not of this
            problem's contacts.
    """
    saved = data["pairing_master_nodes"]
    if saved.shape[0] != ref.nc or data["pairing_weights"].shape != saved.shape:
        raise ValueError(f"{path}: the saved mortar pairing has {saved.shape[0]} contacts, this problem {ref.nc}: "
                         "load it into the problem it was written with")
    real = surface_nodes >= 0
    keys, nodes = surface_keys[real], surface_nodes[real]
    order = np.argsort(keys)
    keys, nodes = keys[order], nodes[order]
    where = np.minimum(np.searchsorted(keys, np.maximum(saved, 0)), keys.size - 1)
    missing = (saved >= 0) & (keys[where] != saved)
    if missing.any():
        raise ValueError(f"{path}: the saved mortar pairing holds master node {int(saved[missing][0])} (input mesh "
                         "index), which is not on this problem's master surface: load it into the mesh it was "
                         "written with")
    master_nodes = np.where(saved >= 0, nodes[where], -1)
    pairing = mortar_rows_set(ref, master_nodes, data["pairing_weights"].copy(), data["pairing_measures"].copy(),
                              data["pairing_master_sizes"].copy())
    if "pairing_separations" not in data:   # written before the separation was kept: the first pairing's
        return pairing
    return replace(pairing, paired_separation=data["pairing_separations"].copy())


def save_state(operators: ContactOperators, monitor: SlidingMonitor, state: ContactState, path: str | Path,
               meta: Mapping[str, Any] | None = None, wear_laws: Sequence[WearLaw | None] | None = None,
               plastic_points: np.ndarray | None = None) -> None:
    """Write ``state`` (and JSON-able ``meta``) to an ``.npz`` file atomically (rank 0 writes), with the problem's
    contact parameters (:func:`contact_parameters`; ``wear_laws``: each zone's, None: no zone wears). An
    elastic-plastic state needs ``plastic_points``, the coordinates of this rank's quadrature points
    (:meth:`~dolfinx_fretting.plasticity.PlasticState.point_coordinates`). Collective."""
    parameters = contact_parameters(operators, wear_laws or (None,) * len(operators.contact.zones))
    plastic = None
    pairing_keys = wear_keys = None
    if state.pairing is not None and state.pairing.master_faces is None:   # mortar: each contact's master nodes
        pairing_keys = _input_indices(operators, state.pairing.master_nodes)
        wear_keys = _input_indices(operators, operators.surface_compliance.nodes)
    elif state.pairing is not None:   # (collective: every rank holds the same pairing)
        pairing_keys = _input_indices(operators, state.pairing.master_surface.nodes[state.pairing.master_faces])
        wear_keys = _input_indices(operators, operators.surface_compliance.nodes)
    if state.plastic is not None:
        if plastic_points is None:
            raise ValueError("save_state: an elastic-plastic state needs its quadrature points' coordinates")
        plastic = _gather_plastic(operators, state.plastic, plastic_points)

    def write() -> None:  # rank 0; a failure (disk full, a folder gone) is raised on every rank
        target = Path(path)
        arrays = {k: getattr(state, k) for k in ARRAYS}
        arrays["contact_coordinates"] = operators.contact_set_of(state).coords
        arrays["status"] = state.status if state.status is not None else np.zeros(0, np.int8)
        arrays["warm"] = state.warm if state.warm is not None else np.zeros(0)
        arrays["friction_energy"] = state.friction_energy if state.friction_energy is not None else np.zeros(0)
        arrays["targets"] = state.targets if state.targets is not None else state.obstacle
        arrays["force_controlled"] = (state.force_controlled if state.force_controlled is not None
                                      else np.zeros(state.obstacle.size, dtype=bool))
        if state.pairing is not None:  # finite sliding: the pairing and the master's wear, by input node indices
            if state.pairing.master_faces is None:   # mortar: the rows of D^-1 M, D_jj and the master sizes
                arrays["pairing_master_nodes"] = pairing_keys
                arrays["pairing_measures"] = state.pairing.tributary
                arrays["pairing_master_sizes"] = state.pairing.master_sizes
                arrays["pairing_separations"] = state.pairing.paired_separation
            else:
                arrays["pairing_facet_nodes"] = pairing_keys
            arrays["pairing_weights"] = state.pairing.master_weights
            arrays["master_wear"] = state.master_wear
            arrays["master_wear_nodes"] = wear_keys
            arrays["repairs"] = np.array(monitor.repairs)
        for name, values in (plastic or {}).items():
            arrays[f"plastic_{name}"] = values
        info = {"increment": state.increment, "dissipated_energy": state.dissipated_energy, "cycles": state.cycles,
                "local_iterations": state.local_iterations, "record": state.record, "ranks": operators.comm.size,
                "load_names": operators.load_names, "global_nodes": operators.contact.contact_set.global_nodes.tolist(),
                "plastic": state.plastic is not None, "contact_parameters": parameters,
                "meta": dict(meta or {})}
        tmp = target.with_name(target.name + ".tmp.npz")
        np.savez(tmp, state=json.dumps(info, default=_jsonable), **arrays)
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.replace(tmp, target)
    on_rank0(operators.comm, write)


def load_state(operators: ContactOperators, monitor: SlidingMonitor, path: str | Path,
               wear_laws: Sequence[WearLaw | None] | None = None,
               plastic_points: np.ndarray | None = None) -> tuple[ContactState, dict[str, Any]]:
    """Read a state written by :func:`save_state` (same problem, same contact set). Collective.

    Checked against this problem: the contact nodes (by their coordinates), the load names, a plastic state's
    dofs and quadrature points (by their coordinates; ``plastic_points``: this rank's, as for :func:`save_state`),
    finite sliding's pairing and master wear (their master facets and nodes by the input mesh's node indices),
    and the contact parameters (:func:`contact_parameters`: each zone's
    ``mu``, wear law with its coefficients and acceleration (``wear_laws``, one per zone), obstacle kind, normal and
    a plane's position). Not checked: the material (bilinear form), the Dirichlet conditions, the load vectors'
    values, the solver settings and the plastic law; nor, in a checkpoint written before the contact parameters
    were saved (it still loads, with a warning on rank 0), the contact parameters.

    Raises:
        ValueError: the file does not match this problem; the message names what differs, with both values.
    """
    def read() -> dict[str, np.ndarray]:
        with np.load(path, allow_pickle=False) as npz:
            return {k: npz[k] for k in npz.files}

    data = on_rank0(operators.comm, read)
    info = json.loads(str(data["state"]))
    contact_set = operators.contact.contact_set
    if "contact_coordinates" in data:   # the same nodes in the same order, whatever their global numbers
        saved = data["contact_coordinates"]
        extent = max(float(np.ptp(contact_set.coords, axis=0).max(initial=0.0)), 1.0) if contact_set.nc else 1.0
        # 1e-9 of the surface's extent: the coordinates are the mesh's input bits on every partition; far below
        # any node spacing
        same = saved.shape == contact_set.coords.shape and np.abs(saved - contact_set.coords).max(initial=0.0) \
            <= 1e-9 * extent
    else:   # a checkpoint of an earlier release: its global node numbers
        same = info["global_nodes"] == contact_set.global_nodes.tolist()
    if not same:
        raise ValueError(f"{path}: the saved contact set differs from this problem's (its nodes' coordinates)")
    if info["load_names"] != operators.load_names:
        raise ValueError(f"{path}: saved loads {info['load_names']} differ from this problem's {operators.load_names}")
    if "contact_parameters" in info:   # (a checkpoint of an earlier release has none: unchecked)
        extent = max(float(np.ptp(contact_set.coords, axis=0).max(initial=0.0)), 1.0) if contact_set.nc else 1.0
        differences = parameter_differences(
            info["contact_parameters"],
            contact_parameters(operators, wear_laws or (None,) * len(operators.contact.zones)), extent)
        if differences:
            raise ValueError(f"{path}: the checkpoint was written with other contact parameters than this "
                             f"problem's: {'; '.join(differences)}; load it into a problem with the saved values")
    elif operators.comm.rank == 0:  # loads as before, but the user must know what was not checked
        warnings.warn(f"{path}: written by an earlier release, the checkpoint does not record its contact "
                      "parameters (mu, wear law, obstacle): they were not checked against this problem's",
                      stacklevel=3)
    plastic = None
    if info["plastic"] and "plastic_points" in data:   # keyed by coordinates: any partition
        if plastic_points is None:
            raise ValueError(f"{path}: an elastic-plastic state loads into an elastic-plastic problem")
        plastic = _plastic_from(operators, data, plastic_points, path)
    elif info["plastic"]:   # a checkpoint of an earlier release: each rank's arrays, on the same partition only
        if info["ranks"] != operators.comm.size:
            raise ValueError(f"{path}: an elastic-plastic state saved on {info['ranks']} rank(s) loads on the same "
                             f"number (here {operators.comm.size})")
        i = operators.comm.rank
        saved = info.get("partition")
        moved = saved is not None and saved[i] != _partition_fingerprint(operators)
        if operators.comm.allreduce(moved, op=MPI.LOR):   # every rank raises, or none
            raise ValueError(f"{path}: an elastic-plastic state holds each rank's quadrature points, and this launch "
                             "partitioned the mesh differently: resume it on the partition it was written on")
        plastic = PlasticHistory(*(data[f"plastic_{k}_{i}"].copy() for k in PLASTIC_ARRAYS))
    warm = data["warm"] if data["warm"].size and operators.comm.rank == 0 else None
    pairing = master_wear = None
    sliding = "pairing_facet_nodes" in data or "pairing_faces" in data or "pairing_master_nodes" in data
    if sliding != (operators.surface_compliance is not None):
        raise ValueError(f"{path}: a state saved with{'' if sliding else 'out'} finite sliding "
                         f"loads into a problem with{'' if operators.surface_compliance is not None else 'out'} it")
    if operators.surface_compliance is not None:
        pairing, master_wear = _pairing_from(operators, data, path)
        operators.surface_compliance.rows(pairing.master_nodes)   # within reach, or a message
        monitor.repairs = int(data["repairs"])
    # (a checkpoint of an earlier release holds neither: no cycles counted, no energy tracked)
    energy = data["friction_energy"] if "friction_energy" in data and data["friction_energy"].size else None
    if energy is None and friction.tracks_energy(operators.contact):
        energy = np.zeros(contact_set.nc)
    state = ContactState(*(data[k].copy() for k in ARRAYS), increment=int(info["increment"]),
                         dissipated_energy=float(info["dissipated_energy"]),
                         local_iterations=int(info["local_iterations"]), record=info["record"],
                         status=data["status"].copy() if data["status"].size else None, warm=warm,
                         targets=data["targets"].copy(), force_controlled=data["force_controlled"].copy(),
                         plastic=plastic, pairing=pairing, master_wear=master_wear,
                         cycles=float(info.get("cycles", 0.0)),
                         friction_energy=None if energy is None else energy.copy())
    return state, info["meta"]
