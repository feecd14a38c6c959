"""Finite sliding of two deformable bodies: pairings formed anew from one surface compliance (pure NumPy).

With small sliding (:class:`~dolfinx_fretting.contact.ElasticBody`'s default) each slave node keeps the master
point it faced in the reference configuration. When the bodies slide by more than a fraction of an element
(the paper's gross-slip stroke is two elements) the master's displacement is then read at a point that no longer
faces the node. Here the slave nodes are paired again, in the current configuration, without refactorising K:

- :class:`SurfaceCompliance` holds ``C = S K^-1 S^T`` on the dofs ``S`` of both contact surfaces (the slave
  candidates and the master nodes within reach) and each load's response ``S K^-1 f_l``, computed once. A
  pairing's H touches surface dofs only, ``H = L S``, so its Delassus matrix and load responses are
  ``W = L C L^T`` and ``L S K^-1 f_l``; the surface displacement of a state is ``C L^T r + sum_l s_l S K^-1 f_l``.
- :func:`offsets` measures, from that displacement, how far each paired master point has moved from the point
  facing its slave node; :func:`repair` searches the closest master points again in the current configuration
  (the master moved by its rigid translation D as well) and builds the new contact set
  (:func:`~dolfinx_fretting.contact.paired_contact_set`); :func:`carry_state` expresses a state in it.
- The master's share of the wear lives on the master's nodes (:func:`master_node_areas`, :func:`spread_wear`)
  and is interpolated at each pairing, so the scar on the master stays where it was worn.
- Mortar (``ElasticBody(formulation="mortar")``): a re-pairing integrates D and M anew
  (:func:`~dolfinx_fretting.mortar.mortar_matrices`) between the slave segments (faces) holding a contact's node and
  the master facets within reach, placed where they are now (their motion in the contact plane) and measured in the
  reference configuration, and forms the contacts' rows from them
  (:func:`~dolfinx_fretting.contact.mortar_paired_set`); a contact's "paired point" is its weighted master point
  ``sum_l w_jl X_l``. The slave's share of the wear is kept by each slave node's own measure
  (:attr:`~dolfinx_fretting.contact.ContactSet.slave_areas`), since ``D_jj`` changes with the pairing.

Nothing here touches DOLFINx or MPI: every rank holds the same arrays and computes the same pairing.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np
import scipy.sparse as sp

from .contact import ContactSet, MasterSurface, mortar_paired_set, paired_contact_set
from .mortar import mortar_matrices

__all__ = ["SurfaceCompliance", "surface_nodes", "master_node_areas", "offsets", "repair", "carry_state",
           "interpolate_master", "spread_wear"]


def surface_nodes(pairing: ContactSet, reach: float | None) -> tuple[np.ndarray, np.ndarray]:
    """The master facets a slave node may slide onto, and the surface nodes of the compliance.

    Args:
        pairing: The reference pairing (:func:`~dolfinx_fretting.contact.find_pairs`).
        reach: Sliding reach (length), or None for the whole master surface.

    Returns:
        (the facets of ``pairing.master_surface`` within ``reach`` of a slave node, sorted; the global block nodes of
        the slave candidates and of those facets, sorted).
    """
    surface = pairing.master_surface
    nf = surface.nodes.shape[0]
    if reach is None:
        faces = np.arange(nf)
    else:
        centre = np.array([x[:k].mean(axis=0) for x, k in zip(surface.x, surface.nv)]).reshape(-1, surface.dim)
        radius = np.array([np.linalg.norm(x[:k] - c, axis=1).max() for x, k, c in zip(surface.x, surface.nv, centre)])
        # distance from each facet's centre to the nearest slave node, in chunks of facets (slaves x facets)
        nearest = np.empty(nf)
        for start in range(0, nf, 512):
            d = np.linalg.norm(centre[start:start + 512, None, :] - pairing.coords[None], axis=2)
            nearest[start:start + 512] = d.min(axis=1)
        faces = np.flatnonzero(nearest - radius <= reach)
    masters = surface.nodes[faces].ravel()
    nodes = np.union1d(pairing.global_nodes, masters[masters >= 0])
    if pairing.slave_surface is not None:   # mortar: the nodes of the slave segments the contacts' rows integrate
        slaves = pairing.slave_surface.nodes[_contact_segments(pairing)].ravel()
        nodes = np.union1d(nodes, slaves[slaves >= 0])
    return faces, nodes


def master_node_areas(surface: MasterSurface, nodes: np.ndarray) -> np.ndarray:
    """Tributary measure (length in 2D, area in 3D) of each of ``nodes`` on the whole master surface
    (:meth:`~dolfinx_fretting.contact.MasterSurface.node_measures`): a share of each facet's measure per vertex.
    0 for a node of no master facet."""
    return surface.node_measures(nodes)


@dataclass(frozen=True)
class SurfaceCompliance:
    """K⁻¹ on the dofs of both contact surfaces, from which every pairing's operators are formed.

    Attributes:
        nodes: Global block nodes of the surfaces (sorted); the dofs are ``dim * node + k``.
        dim: Components per node.
        C: ``S K^-1 S^T`` on the free dofs (rows and columns of fixed dofs are zero), shape (m, m),
            ``m = dim * nodes.size``.
        responses: ``S K^-1 f_l`` per load (prescribed values at the fixed dofs), shape (n_loads, m).
        faces: The master facets within reach (:func:`surface_nodes`).
        master_areas: Tributary measure of each node on the master surface (0 at slave nodes).
    """

    nodes: np.ndarray
    dim: int
    C: np.ndarray
    responses: np.ndarray
    faces: np.ndarray
    master_areas: np.ndarray
    #: id(pairing) -> (pairing, what :meth:`_held` gives) of the last pairings read; a cache, not data.
    _restricted: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def dofs(self) -> np.ndarray:
        return (self.dim * self.nodes[:, None] + np.arange(self.dim)).ravel()

    def restrict(self, pairing: ContactSet) -> sp.csr_matrix:
        """L: H's columns at the surface dofs (``H = L S``).

        H's columns are renumbered, not sliced out of its full width: the surface dofs are in the order of the
        global dofs (``nodes`` sorted), so L's entries are H's, in the same order.

        Raises:
            ValueError: H touches a dof outside the surfaces (a pairing beyond the reach).
        """
        return self._held(pairing)[0]

    def pairing_rows(self, pairing: ContactSet) -> tuple[np.ndarray, np.ndarray]:
        """(the row in :attr:`nodes` of each slave node, of each master node (-1 for padding)) of ``pairing``
        (:meth:`rows`)."""
        return self._held(pairing)[1:3]

    def _held(self, pairing: ContactSet) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray, sp.csc_matrix]:
        """(L, the slave nodes' rows, the master nodes' rows, L^T) of ``pairing``, kept for the last few pairings: a
        re-paired increment reads them a dozen times (the operators, the outside rows, the displacement, the carry,
        the offsets, the master's wear)."""
        held = self._restricted.get(id(pairing))
        if held is not None and held[0] is pairing:
            return held[1:]
        H = pairing.H
        dofs = H.indices
        where = np.minimum(np.searchsorted(self.nodes, dofs // self.dim), self.nodes.size - 1)
        if np.any(self.nodes[where] != dofs // self.dim):
            raise ValueError("finite sliding: the pairing touches nodes outside the surface compliance: "
                             "ElasticBody.reach is shorter than the pairing needs")
        L = sp.csr_matrix((H.data.copy(), self.dim * where + dofs % self.dim, H.indptr.copy()),
                          shape=(H.shape[0], self.dim * self.nodes.size))
        entry = (L, self.rows(pairing.global_nodes), self.rows(pairing.master_nodes), L.T)
        if len(self._restricted) >= 4:   # the pairings of the last increments only (their states hold them)
            self._restricted.pop(next(iter(self._restricted)))
        self._restricted[id(pairing)] = (pairing, *entry)
        return entry

    def operators(self, pairing: ContactSet) -> tuple[np.ndarray, np.ndarray]:
        """(W, the load responses) of ``pairing``: ``L C L^T`` and ``L S K^-1 f_l``."""
        L = self.restrict(pairing)
        W = _congruence(L.indptr, L.indices, L.data, self.C)
        W = 0.5 * (W + W.T)  # exactly symmetric, as the factorisation's W
        responses = np.zeros((self.responses.shape[0], L.shape[0]))
        if responses.size:
            responses[:] = np.asarray(L @ self.responses.T).T
        return W, responses

    def displacement(self, pairing: ContactSet, forces: np.ndarray, factors: np.ndarray) -> np.ndarray:
        """The surface nodes' displacement (nodes, dim) under the contact forces of ``pairing`` and the loads
        at ``factors``: ``C L^T r + sum_l s_l S K^-1 f_l`` (without the master's rigid translation)."""
        u = self.C @ (self._held(pairing)[3] @ forces)
        if self.responses.shape[0]:
            u = u + factors @ self.responses
        return u.reshape(-1, self.dim)

    def rows(self, global_nodes: np.ndarray) -> np.ndarray:
        """Row of each global node in :attr:`nodes` (-1 for padding).

        Raises:
            ValueError: a node is not on the surfaces (a pairing with a master facet outside the reach).
        """
        where = np.minimum(np.searchsorted(self.nodes, np.maximum(global_nodes, 0)), self.nodes.size - 1)
        missing = (global_nodes >= 0) & (self.nodes[where] != global_nodes)
        if missing.any():
            raise ValueError(f"finite sliding: node {int(global_nodes[missing].flat[0])} is paired but lies outside "
                             "the surface compliance: ElasticBody.reach is shorter than the pairing needs")
        return np.where(global_nodes >= 0, where, -1)


@numba.njit(cache=True)
def _congruence(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, C: np.ndarray) -> np.ndarray:
    """``L C L^T`` for a CSR ``L`` (its arrays) and a dense ``C``: the rows of ``L C`` first, then their products
    with L's rows, each sum in the order of L's entries (scipy's CSR products' order, without their per-call
    cost: finite sliding forms a W at almost every increment)."""
    rows, m = indptr.size - 1, C.shape[1]
    LC = np.zeros((rows, m))
    for i in range(rows):
        for k in range(indptr[i], indptr[i + 1]):
            a, col = data[k], indices[k]
            for j in range(m):
                LC[i, j] += a * C[col, j]
    W = np.zeros((rows, rows))
    for i in range(rows):
        for k in range(indptr[i], indptr[i + 1]):
            a, col = data[k], indices[k]
            for j in range(rows):
                W[i, j] += a * LC[j, col]
    return W


def _master_motion(compliance: SurfaceCompliance, u: np.ndarray, D: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Displacement of master nodes at ``rows`` (any shape; -1 padding takes the previous column's) plus D."""
    rows = rows.copy()
    if rows.ndim == 2 and rows.shape[1] > 1:
        for j in range(1, rows.shape[1]):
            pad = rows[:, j] < 0
            rows[pad, j] = rows[pad, j - 1]
    return u[rows] + D


def offsets(pairing: ContactSet, compliance: SurfaceCompliance, u: np.ndarray, D: np.ndarray) -> np.ndarray:
    """How far each contact's paired master point has moved from its slave node, in the contact plane, in
    master elements: ``|t . ((X_s + u_s) - sum_i w_i (X_i + u_i + D))| / size``.

    Args:
        pairing: The pairing.
        compliance: The surface compliance (its node rows).
        u: (nodes, dim) displacement of the surface nodes (:meth:`SurfaceCompliance.displacement`).
        D: The master's rigid translation.

    Returns:
        (nc,) the offsets, in master facet sizes.
    """
    slave_rows, master_rows = compliance.pairing_rows(pairing)
    slave = pairing.coords + u[slave_rows]
    moved = _master_motion(compliance, u, D, master_rows)
    if pairing.master_faces is None:   # mortar: the weighted master point sum_l w_jl X_l (the weights sum to one)
        master = pairing.master_points + np.einsum("ci,cij->cj", pairing.master_weights, moved)
    else:
        master = np.einsum("ci,cij->cj", pairing.master_weights,
                           pairing.master_surface.x[pairing.master_faces] + moved)
    tangential = np.einsum("ckj,cj->ck", pairing.frames[:, 1:], slave - master)
    return np.linalg.norm(tangential, axis=1) / pairing.master_sizes


def repair(pairing: ContactSet, compliance: SurfaceCompliance, u: np.ndarray, D: np.ndarray) -> ContactSet:
    """Pair the slave nodes of ``pairing`` anew with the closest points of the master facets within reach, both moved
    by their displacement in the contact plane (surface displacement ``u``, the master translated by ``D``;
    their components along the obstacle's normal are left out). A node that has
    slid beyond the reach pairs with the nearest facet within it; its :func:`offsets` then stay large (the
    problem reports it). A mortar pairing (``pairing.slave_surface`` set) is made anew by integrating D and M
    between the surfaces so placed (see the module).

    Args:
        pairing: The current pairing (its slave nodes are kept, in order).
        compliance: The surface compliance (the facets within reach, the node rows).
        u: (nodes, dim) displacement of the surface nodes.
        D: The master's rigid translation.

    Returns:
        The new pairing's contact set (:func:`~dolfinx_fretting.contact.paired_contact_set`, or for mortar
        :func:`~dolfinx_fretting.contact.mortar_paired_set`).

    Raises:
        ValueError: mortar: a contact's slave node no longer faces the master (slid off its end or beyond reach).
    """
    surface = pairing.master_surface
    # The motion in the contact plane only (the obstacle frame's tangents): the approach along n is micrometres
    # and does not change which points face each other, and leaving it out keeps a flat master's facets flat,
    # so that a node on a symmetry plane pairs with a point on it exactly (the closest point of a facet warped by
    # the indentation would lie a rounding-sized step off it, and the roller would no longer hold the pair).
    n = surface.reference_frame[0]
    u = u - np.outer(u @ n, n)
    D = D - (D @ n) * n
    faces = compliance.faces
    rows = compliance.rows(surface.nodes[faces])
    current = surface.x[faces] + _master_motion(compliance, u, D, rows)
    if pairing.slave_surface is not None:
        return _repair_mortar(pairing, compliance, u, D, current)
    slave = pairing.coords + u[compliance.pairing_rows(pairing)[0]]
    pairs = MasterSurface(surface.nodes[faces], current, surface.nv[faces], surface.inside[faces] + D,
                          surface.reference_frame).pair(slave)
    chosen = faces[pairs["face"]]
    return paired_contact_set(surface, pairing.global_nodes, pairing.coords, pairing.tributary, pairing.abscissa,
                              chosen, pairs["weights"], pairing.H.shape[1], pairing.surface_mass)


def _contact_segments(pairing: ContactSet) -> np.ndarray:
    """Mortar: which slave segments (faces) hold a contact's node, the only ones its rows of D and M integrate."""
    nodes = pairing.slave_surface.nodes
    return np.isin(nodes, pairing.global_nodes).any(axis=1)


def _repair_mortar(pairing: ContactSet, compliance: SurfaceCompliance, u: np.ndarray, D: np.ndarray,
                   master_x: np.ndarray) -> ContactSet:
    """:func:`repair` of a mortar pairing: D and M integrated anew between the slave segments (faces) and the master
    facets within reach (``master_x``), both at their current positions in the contact plane (``u``, ``D`` without
    their normal components), then :func:`~dolfinx_fretting.contact.mortar_paired_set`. Only the surface
    compliance's arrays are read: no solve, no factorisation."""
    surface = pairing.master_surface
    segments = _contact_segments(pairing)
    slave = MasterSurface(*(getattr(pairing.slave_surface, name)[segments] for name in ("nodes", "x", "nv", "inside")),
                          pairing.slave_surface.reference_frame)
    faces = compliance.faces
    moved = _master_motion(compliance, u, np.zeros(compliance.dim), compliance.rows(slave.nodes))
    valid = (slave.nodes >= 0)[:, :, None]
    mean_motion = (moved * valid).sum(axis=1) / valid.sum(axis=1)   # a triangle's padding not counted
    matrices = mortar_matrices(slave.nodes, slave.x + moved,
                               slave.inside + mean_motion, surface.nodes[faces], master_x, surface.inside[faces] + D,
                               reference_tangent=surface.reference_frame[1] if surface.dim == 3 else None,
                               slave_reference_x=slave.x, symmetry_axes=pairing.symmetry_axes)
    # mortar_paired_set keeps the reference pairing's frames and drops the H columns along a symmetry axis as the
    # first pairing did (pairing.symmetry_axes): the matrices' own normals are given the same axes only so that
    # they are the same as the frames kept.
    return mortar_paired_set(pairing, matrices)


def interpolate_master(pairing: ContactSet, compliance: SurfaceCompliance, master_wear: np.ndarray) -> np.ndarray:
    """The master's wear depth at each contact's paired point (weights of the pairing).

    Args:
        pairing: The pairing.
        compliance: The surface compliance (the node rows of ``master_wear``).
        master_wear: The master's depth at the compliance's nodes.

    Returns:
        (nc,) the depth at each paired point.
    """
    rows = compliance.pairing_rows(pairing)[1]
    return np.einsum("ci,ci->c", pairing.master_weights, np.where(rows >= 0, master_wear[np.maximum(rows, 0)], 0.0))


def spread_wear(pairing: ContactSet, compliance: SurfaceCompliance, depth: np.ndarray) -> np.ndarray:
    """The master's wear depth added at its nodes when each contact's paired point wears by ``depth``: the
    worn measure ``depth_c A_c`` (A_c the slave node's tributary measure) shared among the facet's nodes by the
    pairing's weights and divided by each node's own measure, so the worn volume is kept exactly.

    Args:
        pairing: The pairing.
        compliance: The surface compliance (node rows, the master's node measures).
        depth: (nc,) the master's wear depth added at each paired point.

    Returns:
        The depth added at the compliance's nodes.

    Raises:
        RuntimeError: wear at a node of no master facet.
    """
    rows = compliance.pairing_rows(pairing)[1]
    volume = np.zeros(compliance.nodes.size)
    share = pairing.master_weights * (depth * pairing.tributary)[:, None]
    valid = rows >= 0
    np.add.at(volume, rows[valid], share[valid])
    areas = compliance.master_areas
    if np.any((volume != 0) & (areas <= 0)):
        raise RuntimeError("finite sliding: wear reached a node of no master facet")
    return np.divide(volume, areas, out=np.zeros_like(volume), where=areas > 0)


def carry_state(old: ContactSet, new: ContactSet, compliance: SurfaceCompliance, u: np.ndarray, D: np.ndarray,
                forces: np.ndarray, slip: np.ndarray, wear_gap: np.ndarray,
                master_wear: np.ndarray) -> dict[str, np.ndarray]:
    """A committed state's contact arrays expressed in the pairing ``new``: the forces and the last slip turned
    into the new frames (the same vectors), the wear gap with the master's share read at the new points, and the relative
    positions of the committed configuration as the new pairing measures them, ``L u - frames D + g0 + w``
    (their tangential rows are where the next increment's slip is measured from)."""
    dim = new.dim

    def turned(values: np.ndarray) -> np.ndarray:   # the same vectors in the new frames
        v = values.reshape(-1, dim)
        return np.einsum("ckj,cj->ck", new.frames, np.einsum("ckj,ck->cj", old.frames, v)).ravel()

    wear = wear_gap - interpolate_master(old, compliance, master_wear) + interpolate_master(new, compliance,
                                                                                          master_wear)
    positions = np.asarray(compliance.restrict(new) @ u.ravel()) - new.rigid_modes @ D
    positions[0::dim] += new.gap0 + wear
    return {"forces": turned(forces), "slip": turned(slip), "wear_gap": wear, "positions": positions}
