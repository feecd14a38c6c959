"""Reading a state: the displacement field, the contact fields per node, each body's wear, the worn measure
and the total contact force. Reading a state changes nothing (not even the pairing the operators hold, except
:func:`displacement`, which solves with the state's own).
"""

from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from . import _dolfinx as dfx
from . import sliding
from ._dolfinx import cell_dofmap, fem
from .operators import ContactOperators
from .state import ContactState

__all__ = ["displacement", "displacements", "batch_size", "contact_fields", "body_wear", "worn_measure", "total_force",
           "zone_index"]


def displacement(operators: ContactOperators, state: ContactState, out=None, plastic_u: np.ndarray | None = None):
    """The displacement of ``state`` as a ``fem.Function`` (``out`` if given). Collective.

    Elastic: solves K u = H^T r + sum_l s_l f_l with the one factorisation; with an
    :class:`~dolfinx_fretting.contact.ElasticBody` obstacle that has ``cells``, its nodes also move by
    the obstacle's translation D. Elastic–plastic: ``plastic_u``, the state's committed displacement.
    """
    u = out if out is not None else fem.Function(operators.V, name="displacement")
    operators.activate(state)
    if plastic_u is not None:
        u.x.array[:] = plastic_u
        u.x.scatter_forward()
        return _add_obstacle_motion(operators, u, state)
    rhs = _right_hand_side(operators, state)
    operators.delassus.solve(rhs, dfx.petsc_vec(u))
    rhs.destroy()
    u.x.scatter_forward()
    return _add_obstacle_motion(operators, u, state)


def _right_hand_side(operators: ContactOperators, state: ContactState) -> PETSc.Vec:
    """K u = H^T r + sum_l s_l f_l of an elastic ``state`` (its pairing active), zero on the constrained dofs."""
    rhs = operators.K.createVecRight()
    rstart, rend = rhs.getOwnershipRange()
    R = operators.contact.H_free.T.tocsr() @ state.forces
    rhs.setValues(np.arange(rstart, rend, dtype=PETSc.IntType), R[rstart:rend])
    rhs.assemble()
    dfx.set_bc(rhs, operators.all_bcs, scale=0.0)
    for i, f in enumerate(operators.vectors):
        if state.load_factors[i] != 0.0:
            rhs.axpy(state.load_factors[i], f)
    return rhs


def batch_size(operators: ContactOperators) -> int:
    """How many states :func:`displacements` solves in one call: the dense blocks (right-hand sides, solutions
    and their copies, ~4 of N values a state) within the factorisation's ``block_memory_mb``."""
    dofs = max(operators.K.getSize()[0], 1)
    return int(max(1, operators.delassus.block_memory_mb * 2**20 // (4 * 8 * dofs)))


def displacements(operators: ContactOperators, states: list[ContactState], outs: list) -> list:
    """The displacements of several elastic states into ``outs`` (a ``fem.Function`` or None: a new one, for each
    state): the same
    right-hand sides as :func:`displacement`, solved in one multiple right-hand-side call
    (:meth:`~dolfinx_fretting.compliance.DelassusOperator.solve_many`) instead of one back-solve each; the
    caller bounds ``len(states)`` (a dense block of that many columns). Collective."""
    if len(states) != len(outs):
        raise ValueError(f"displacements: {len(states)} states, {len(outs)} functions")
    if not states:
        return []
    outs = [u if u is not None else fem.Function(operators.V, name="displacement") for u in outs]
    columns = []
    for state in states:
        operators.activate(state)   # finite sliding: each state's own pairing (its H)
        rhs = _right_hand_side(operators, state)
        columns.append(rhs.getArray(readonly=True).copy())
        rhs.destroy()
    solution = operators.delassus.solve_many(np.column_stack(columns))
    for j, (state, u) in enumerate(zip(states, outs)):
        u.x.array[:solution.shape[0]] = solution[:, j]   # the owned dofs come first (then the ghosts)
        u.x.scatter_forward()
        operators.activate(state)
        _add_obstacle_motion(operators, u, state)
    return outs


def _add_obstacle_motion(operators: ContactOperators, u, state: ContactState):
    """Each obstacle with cells that move with it (an :class:`~dolfinx_fretting.contact.ElasticBody`'s ``cells``)
    moves their nodes by its zone's translation D."""
    dim = operators.dim
    for zone, contact in enumerate(operators.contact.zones):
        cells = contact.obstacle.moved_cells
        if cells is None:
            continue
        D = contact.translations(state.obstacle[dim * zone:dim * (zone + 1)])
        # The cells' nodes from the dofmap (DOLFINx 0.11 wants a cell-to-cell connectivity for
        # locate_dofs_topological on cells of a 3D mesh).
        nodes = np.unique(cell_dofmap(operators.V)[np.asarray(cells, dtype=np.int32)])
        values = u.x.array.reshape(-1, operators.V.dofmap.index_map_bs)
        values[nodes, :D.size] += D
    return u


def zone_index(operators: ContactOperators, contact, reader: str) -> int | None:
    """The index of zone ``contact`` (a :class:`~dolfinx_fretting.contact.Contact` of the problem), None for the
    whole problem; with several zones a reader of one zone's quantity needs its zone."""
    if contact is None:
        return None
    zone = operators.zone_of(contact)
    if zone is None:
        raise ValueError(f"{reader}: contact = {contact!r} is not one of this problem's "
                         f"{len(operators.contact.zones)} contact zone(s)")
    return zone


def contact_fields(operators: ContactOperators, state: ContactState, contact=None) -> dict[str, np.ndarray]:
    """Per contact node (replicated): ``coordinates``, ``global_node``, ``pressure`` and ``shear`` (the tractions
    recovered from the contact forces as the contact's ``pressure_recovery`` says: force / tributary measure, or
    the smoothed values, :meth:`~dolfinx_fretting.contact.ContactSet.tractions`; shear has dim-1 components),
    ``gap``, ``slip`` (last increment's slip increments), ``relative_tangential`` (accumulated), ``wear`` and ``status`` (0 open, 1 stick, 2 slip).
    ``contact``: one zone's nodes only (default every zone's, in turn)."""
    contact_set = operators.contact_set_of(state)
    dim = contact_set.dim
    y = state.positions.reshape(contact_set.nc, dim)
    x = state.slip.reshape(contact_set.nc, dim)
    status = state.status if state.status is not None else np.zeros(contact_set.nc, dtype=np.int8)
    zone = zone_index(operators, contact, "contact_fields")
    if zone is not None:
        rows = operators.contact.zone_slice(zone)
        fields = contact_fields(operators, state)
        return {name: values[rows].copy() for name, values in fields.items()}
    traction = contact_set.tractions(state.forces)
    return {"coordinates": contact_set.coords.copy(), "global_node": contact_set.global_nodes.copy(),
            "pressure": traction[:, 0].copy(), "shear": traction[:, 1:].copy(),
            "gap": y[:, 0].copy(), "slip": x[:, 1:].copy(), "relative_tangential": y[:, 1:].copy(),
            "wear": state.wear_gap.copy(), "status": status.copy()}

def body_wear(operators: ContactOperators, laws: tuple, state: ContactState) -> dict[str, np.ndarray]:
    """Two bodies: each body's worn depth. ``slave`` per contact node; ``master`` and
    ``master_coordinates`` (reference) at the master's points: with finite sliding the master's nodes
    (:attr:`~dolfinx_fretting.operators.ContactOperators.surface_compliance`), with small sliding each contact's
    paired point (the pairing is fixed, so
    the master's share is carried per contact). Reads ``state`` only (the problem's pairing is not changed)."""
    contact_set = operators.contact_set_of(state)
    if not contact_set.two_body:
        raise ValueError("body_wear: the obstacle is rigid (the wear gap is the body's: contact_fields)")
    if operators.surface_compliance is None:
        # each contact's slave share, its zone's law's (``laws``, one per zone)
        share = np.empty(contact_set.nc)
        for zone, law in enumerate(laws):
            share[operators.contact.zone_slice(zone)] = law.slave_share if law is not None else 1.0
        return {"slave": share * state.wear_gap, "master": (1 - share) * state.wear_gap,
                "master_coordinates": contact_set.master_points.copy()}
    on_master = operators.surface_compliance.master_areas > 0
    surface = contact_set.master_surface
    flat_nodes, first = np.unique(surface.nodes.ravel(), return_index=True)
    master_nodes = operators.surface_compliance.nodes[on_master]
    x = surface.x.reshape(-1, surface.dim)[first[np.searchsorted(flat_nodes, master_nodes)]]
    slave = state.wear_gap - sliding.interpolate_master(contact_set, operators.surface_compliance, state.master_wear)
    return {"slave": slave,
            "master": state.master_wear[on_master].copy(), "master_coordinates": x}

def worn_measure(operators: ContactOperators, state: ContactState) -> float:
    """The worn area (2D, mm^2 per mm) or volume (3D) of ``state``: the wear gap times the tributary measures;
    with finite sliding the slave's part per contact plus the master's on its own nodes (the master's wear
    left behind by the slide is under no contact)."""
    contact_set = operators.contact_set_of(state)
    if operators.surface_compliance is None:
        return float(state.wear_gap @ contact_set.tributary)
    slave = state.wear_gap - sliding.interpolate_master(contact_set, operators.surface_compliance, state.master_wear)
    # mortar: the slave's depth over its nodes' own measures (the tributary D_jj changes with the pairing)
    slave_areas = contact_set.tributary if contact_set.slave_areas is None else contact_set.slave_areas
    return float(slave @ slave_areas + state.master_wear @ operators.surface_compliance.master_areas)

def total_force(operators: ContactOperators, state: ContactState, contact=None) -> np.ndarray:
    """Total contact force on the body in the obstacle frame (n, t1[, t2]); with several zones the force of zone
    ``contact`` in its obstacle's frame (required: the zones' frames differ)."""
    zones = operators.contact.zones
    zone = zone_index(operators, contact, "total_force")
    if zone is None and len(zones) > 1:
        raise ValueError(f"total_force: this problem has {len(zones)} contact zones, each with its own frame: name "
                         "one, total_force(state, contact)")
    forces = operators.contact.obstacle_forces(state.forces, operators.contact_set_of(state))
    zone = zone or 0
    return forces[operators.dim * zone:operators.dim * (zone + 1)]
