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

import math
from dataclasses import dataclass, field, replace

import numba
import numpy as np
import scipy.sparse as sp

from .contact import ContactSet, MasterSurface, mortar_paired_set, paired_contact_set
from .cycling import HELD_BLOCK_ARGUMENTS, run_force_increments, run_increments
from .mortar import mortar_matrices

__all__ = ["SurfaceCompliance", "surface_nodes", "master_node_areas", "offsets", "repair", "carry_state",
           "interpolate_master", "spread_wear", "SlidingKernelData", "run_sliding_increments"]


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


def _separations(pairing: ContactSet, compliance: SurfaceCompliance, u: np.ndarray, D: np.ndarray) -> np.ndarray:
    """(nc, dim) each contact's slave node less its paired master point, both displaced (``u``, the master also by
    ``D``): ``(X_s + u_s) - sum_i w_i (X_i + u_i + D)``."""
    slave_rows, master_rows = compliance.pairing_rows(pairing)
    slave = pairing.coords + u[slave_rows]
    moved = _master_motion(compliance, u, D, master_rows)
    if pairing.master_faces is None:   # mortar: the weighted master point sum_l w_jl X_l (the weights sum to one)
        master = pairing.master_points + np.einsum("ci,cij->cj", pairing.master_weights, moved)
    else:
        master = np.einsum("ci,cij->cj", pairing.master_weights,
                           pairing.master_surface.x[pairing.master_faces] + moved)
    return slave - master


def offsets(pairing: ContactSet, compliance: SurfaceCompliance, u: np.ndarray, D: np.ndarray) -> np.ndarray:
    """How far each contact's paired master point has moved from its slave node, in the contact plane, in
    master elements: ``|t . ((X_s + u_s) - sum_i w_i (X_i + u_i + D) - s_0)| / size``, ``s_0`` the separation when
    it was paired (:attr:`~dolfinx_fretting.contact.ContactSet.paired_separation`: mortar's weighted point is not the
    closest point; 0 for node pairing).

    Args:
        pairing: The pairing.
        compliance: The surface compliance (its node rows).
        u: (nodes, dim) displacement of the surface nodes (:meth:`SurfaceCompliance.displacement`).
        D: The master's rigid translation.

    Returns:
        (nc,) the offsets, in master facet sizes.
    """
    separation = _separations(pairing, compliance, u, D)
    if pairing.paired_separation is not None:
        separation = separation - pairing.paired_separation
    tangential = np.einsum("ckj,cj->ck", pairing.frames[:, 1:], separation)
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
    paired = mortar_paired_set(pairing, matrices)
    return replace(paired, paired_separation=_separations(paired, compliance, u, D))


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
    """A committed state's contact arrays expressed in the pairing ``new``: the forces and the last slip turned into
    the new frames (the same vectors), the wear gap with the master's share read at the new points, and the relative
    positions of the committed configuration as the new pairing measures them, ``L u - frames D + g0 + w`` (their
    tangential rows are where the next increment's slip is measured from)."""
    dim = new.dim

    def turned(values: np.ndarray) -> np.ndarray:   # the same vectors in the new frames
        v = values.reshape(-1, dim)
        return np.einsum("ckj,cj->ck", new.frames, np.einsum("ckj,ck->cj", old.frames, v)).ravel()

    wear = wear_gap - interpolate_master(old, compliance, master_wear) + interpolate_master(new, compliance,
                                                                                          master_wear)
    positions = np.asarray(compliance.restrict(new) @ u.ravel()) - new.rigid_modes @ D
    positions[0::dim] += new.gap0 + wear
    return {"forces": turned(forces), "slip": turned(slip), "wear_gap": wear, "positions": positions}


# The compiled loop of finite sliding (2D node-to-segment) ------------------------------------------------------
#: Why :func:`run_sliding_increments` stopped before the cycle's end (0: it did not): a local solve or the load
#: control failed, a node outside the window may penetrate, an increment moved a paired point more than one master
#: element (a warning), a loaded contact slid beyond the reach (a warning), a re-paired contact's compliance is
#: singular, the master's wear reached a node of no master facet. The caller then solves the cycle increment by
#: increment, which raises or warns with its own messages.
SOLVE_FAILED, WINDOW_SUSPECT, LONG_STRIDE, BEYOND_REACH, SINGULAR_BLOCK, WEAR_OFF_MASTER = 1, 2, 3, 4, 5, 6


@dataclass(frozen=True)
class SlidingKernelData:
    """What the compiled loop of finite sliding reads of a problem, array only (2D node-to-segment pairings).

    Attributes:
        faces: The master facets within reach (:attr:`SurfaceCompliance.faces`); a pairing's facets are indices into
            them in the loop.
        face_rows: (F, 2) each facet's nodes' rows in :attr:`SurfaceCompliance.nodes`.
        face_x, face_inside, face_sizes: (F, 2, 2), (F, 2), (F,) the facets' reference end points, a point inside the
            master behind each, their lengths.
        slave_rows: (nc,) the slave nodes' rows in :attr:`SurfaceCompliance.nodes`.
        compliance_columns: ``C^T`` contiguous (C's columns: a surface displacement adds those of the loaded dofs).
        on_surfaces, out_responses, out_motion, out_gap0: the window's outside rows: ``H_out K^-1 S^T`` (k, M), the
            loads' normal responses (L, k), the normal displacement per obstacle component (k, components) and the
            gaps (k,) at the k nodes outside the window (k = 0 without).
    """

    faces: np.ndarray
    face_rows: np.ndarray
    face_x: np.ndarray
    face_inside: np.ndarray
    face_sizes: np.ndarray
    slave_rows: np.ndarray
    compliance_columns: np.ndarray
    on_surfaces: np.ndarray
    out_responses: np.ndarray
    out_motion: np.ndarray
    out_gap0: np.ndarray

    @classmethod
    def of(cls, pairing: ContactSet, compliance: SurfaceCompliance, outside: ContactSet | None,
           surface_outside: tuple[np.ndarray, np.ndarray] | None, out_motion: np.ndarray | None,
           n_loads: int) -> SlidingKernelData:
        """The data of ``pairing``'s master surface and slave nodes (any pairing of them), ``outside`` the nodes
        outside the window (None: none), ``surface_outside`` their ``(H_out K^-1 S^T, the loads' responses)``
        (:func:`~dolfinx_fretting.window_check.outside_on_surfaces`) and ``out_motion`` their normal displacement per
        obstacle component."""
        surface, faces = pairing.master_surface, compliance.faces
        contiguous = np.ascontiguousarray
        if outside is None:
            on_surfaces, out_responses = np.zeros((0, compliance.C.shape[0])), np.zeros((n_loads, 0))
            out_motion, out_gap0 = np.zeros((0, surface.dim)), np.zeros(0)
        else:
            on_surfaces, out_responses = surface_outside
            out_gap0 = outside.gap0
        out_responses = np.reshape(out_responses, (n_loads, on_surfaces.shape[0]))
        return cls(faces, contiguous(compliance.rows(surface.nodes[faces])), contiguous(surface.x[faces]),
                   contiguous(surface.inside[faces]), contiguous(surface.sizes[faces]),
                   contiguous(compliance.rows(pairing.global_nodes)), contiguous(compliance.C.T),
                   contiguous(on_surfaces, dtype=float),
                   contiguous(out_responses, dtype=float), contiguous(out_motion, dtype=float),
                   contiguous(out_gap0, dtype=float))

    def local_faces(self, pairing: ContactSet) -> np.ndarray | None:
        """``pairing``'s facets as indices into :attr:`faces` (None if one is not within reach)."""
        where = np.minimum(np.searchsorted(self.faces, pairing.master_faces), self.faces.size - 1)
        return where if np.array_equal(self.faces[where], pairing.master_faces) else None


@numba.njit(cache=True)
def _pairing_arrays(fl: np.ndarray, weights: np.ndarray, face_x: np.ndarray, face_inside: np.ndarray,
                    coords: np.ndarray, frames: np.ndarray, gap0: np.ndarray) -> None:
    """A 2D pairing's frames (nc, 2, 2) and gaps (nc,) (out), as :func:`~dolfinx_fretting.contact.paired_contact_set`
    forms them: the reference master point at the facet ``fl`` and weights, the facet's outward unit normal n and
    ``t = (n_y, -n_x)``, ``g0 = (X_s - point) . n``."""
    for c in range(fl.size):
        f = fl[c]
        px = weights[c, 0] * face_x[f, 0, 0] + weights[c, 1] * face_x[f, 1, 0]
        py = weights[c, 0] * face_x[f, 0, 1] + weights[c, 1] * face_x[f, 1, 1]
        tx = face_x[f, 1, 0] - face_x[f, 0, 0]
        ty = face_x[f, 1, 1] - face_x[f, 0, 1]
        length = math.sqrt(tx * tx + ty * ty)
        nx, ny = -ty / length, tx / length
        if (face_inside[f, 0] - px) * nx + (face_inside[f, 1] - py) * ny > 0:
            nx, ny = -nx, -ny
        frames[c, 0, 0], frames[c, 0, 1], frames[c, 1, 0], frames[c, 1, 1] = nx, ny, ny, -nx
        gap0[c] = (coords[c, 0] - px) * nx + (coords[c, 1] - py) * ny


@numba.njit(cache=True)
def _pairing_operators(fl: np.ndarray, weights: np.ndarray, frames: np.ndarray, face_rows: np.ndarray,
                       slave_rows: np.ndarray, C: np.ndarray, surface_responses: np.ndarray, obstacle_frame: np.ndarray,
                       W: np.ndarray, Q: np.ndarray, G: np.ndarray, A: np.ndarray, rho: np.ndarray) -> bool:
    """A 2D pairing's operators (out): ``W = L C L^T``, the load responses ``Q = L S K^-1 f_l``, the rigid modes G
    (the frames' rows), the total force along each obstacle component per contact force A, and the Uzawa steps
    ``rho = 1 / ||W_aa||_2`` (:func:`~dolfinx_fretting.local_solvers.block_rho`). False if a contact's block of W
    is singular (as ``ContactOperators._hold_directions`` refuses it).

    L's rows of contact c are its frame times ``e_s - w_0 e_m0 - w_1 e_m1`` (slave node s, the facet's nodes): each
    2 x 2 block of W is ``F_c (sum_ab coef_ca coef_eb C[node_ca, node_eb]) F_e^T``, ``C[p, q]`` the 2 x 2 block of C
    at nodes p, q: the nine blocks of C the two contacts' nodes meet, read in place (not L times C's whole rows: C has
    ~4 surface dofs per contact dof), the upper triangle mirrored (W exactly symmetric, as the factorised W)."""
    nc = fl.size
    n_loads = Q.shape[0]
    nodes, coefs = np.empty((nc, 3), dtype=np.int64), np.empty((nc, 3))
    for c in range(nc):
        f = fl[c]
        nodes[c, 0], nodes[c, 1], nodes[c, 2] = slave_rows[c], face_rows[f, 0], face_rows[f, 1]
        coefs[c, 0], coefs[c, 1], coefs[c, 2] = 1.0, -weights[c, 0], -weights[c, 1]
    for c in range(nc):
        for e in range(c, nc):
            b00 = b01 = b10 = b11 = 0.0
            for a in range(3):
                ca = coefs[c, a]
                if ca == 0.0:
                    continue
                row0, row1 = 2 * nodes[c, a], 2 * nodes[c, a] + 1
                s00 = s01 = s10 = s11 = 0.0
                for b in range(3):
                    eb = coefs[e, b]
                    if eb == 0.0:
                        continue
                    col = 2 * nodes[e, b]
                    s00 += eb * C[row0, col]
                    s01 += eb * C[row0, col + 1]
                    s10 += eb * C[row1, col]
                    s11 += eb * C[row1, col + 1]
                b00 += ca * s00
                b01 += ca * s01
                b10 += ca * s10
                b11 += ca * s11
            for k in range(2):
                f0, f1 = frames[c, k, 0], frames[c, k, 1]
                for kk in range(2):
                    v = (f0 * (b00 * frames[e, kk, 0] + b01 * frames[e, kk, 1])
                         + f1 * (b10 * frames[e, kk, 0] + b11 * frames[e, kk, 1]))
                    W[2 * c + k, 2 * e + kk] = v
                    W[2 * e + kk, 2 * c + k] = v
        off = 0.5 * (W[2 * c, 2 * c + 1] + W[2 * c + 1, 2 * c])
        W[2 * c, 2 * c + 1] = off
        W[2 * c + 1, 2 * c] = off
        for k in range(2):
            for load in range(n_loads):
                v = 0.0
                for a in range(3):
                    for j in range(2):
                        v += coefs[c, a] * frames[c, k, j] * surface_responses[load, 2 * nodes[c, a] + j]
                Q[load, 2 * c + k] = v
            for g in range(2):
                G[2 * c + k, g] = frames[c, k, g]
    for comp in range(A.shape[0]):
        for i in range(2 * nc):
            A[comp, i] = G[i, 0] * obstacle_frame[comp, 0] + G[i, 1] * obstacle_frame[comp, 1]
    top = 0.0
    regular = True
    for c in range(nc):
        a, b, d = W[2 * c, 2 * c], W[2 * c, 2 * c + 1], W[2 * c + 1, 2 * c + 1]
        mean, half = 0.5 * (a + d), math.sqrt((0.5 * (a - d)) ** 2 + b * b)
        high, low = mean + half, mean - half
        if not low > 1e-10 * high:
            regular = False
        rho[c] = max(abs(high), abs(low))
        top = max(top, rho[c])
    for c in range(nc):
        if top == 0.0:
            rho[c] = 1.0
        else:
            rho[c] = 1.0 / (rho[c] if rho[c] > 1e-14 * top else top)
    return regular


@numba.njit(cache=True)
def _surface_motion(fl: np.ndarray, weights: np.ndarray, frames: np.ndarray, face_rows: np.ndarray,
                    slave_rows: np.ndarray, C_columns: np.ndarray, surface_responses: np.ndarray, r: np.ndarray,
                    factors: np.ndarray, s: np.ndarray, u: np.ndarray) -> None:
    """``s = L^T r`` and the surface displacement ``u = C s + sum_l s_l S K^-1 f_l`` (flat, (M,)) of contact forces
    ``r`` of a 2D pairing (:meth:`SurfaceCompliance.displacement`); ``C_columns`` is ``C^T`` (C's columns, contiguous):
    only the columns of the loaded contacts' dofs are added (the open contacts' forces are zero)."""
    M = C_columns.shape[0]
    for i in range(M):
        s[i] = 0.0
        u[i] = 0.0
    for load in range(factors.size):
        for i in range(M):
            u[i] += factors[load] * surface_responses[load, i]
    for c in range(fl.size):
        if r[2 * c] == 0.0 and r[2 * c + 1] == 0.0:
            continue
        f = fl[c]
        nodes = (slave_rows[c], face_rows[f, 0], face_rows[f, 1])
        coefs = (1.0, -weights[c, 0], -weights[c, 1])
        for a in range(3):
            for j in range(2):
                v = coefs[a] * frames[c, 0, j] * r[2 * c] + coefs[a] * frames[c, 1, j] * r[2 * c + 1]
                col = 2 * nodes[a] + j
                s[col] += v
                if v != 0.0:
                    for i in range(M):
                        u[i] += v * C_columns[col, i]


@numba.njit(cache=True)
def _offsets_2d(fl: np.ndarray, weights: np.ndarray, frames: np.ndarray, face_rows: np.ndarray, face_x: np.ndarray,
                face_sizes: np.ndarray, slave_rows: np.ndarray, coords: np.ndarray, u: np.ndarray, D: np.ndarray,
                out: np.ndarray) -> None:
    """:func:`offsets` of a 2D pairing (out, (nc,)); ``u`` flat (M,)."""
    for c in range(fl.size):
        f = fl[c]
        sr = slave_rows[c]
        t = 0.0
        for j in range(2):
            master = 0.0
            for i in range(2):
                master += weights[c, i] * (face_x[f, i, j] + u[2 * face_rows[f, i] + j] + D[j])
            t += frames[c, 1, j] * (coords[c, j] + u[2 * sr + j] - master)
        out[c] = abs(t) / face_sizes[f]


@numba.njit(cache=True)
def _interpolate_2d(fl: np.ndarray, weights: np.ndarray, face_rows: np.ndarray, values: np.ndarray,
                    out: np.ndarray) -> None:
    """:func:`interpolate_master` of a 2D pairing (out)."""
    for c in range(fl.size):
        out[c] = weights[c, 0] * values[face_rows[fl[c], 0]] + weights[c, 1] * values[face_rows[fl[c], 1]]


@numba.njit(cache=True)
def _closest_segments_near(points: np.ndarray, A: np.ndarray, d: np.ndarray, L2: np.ndarray, previous: np.ndarray,
                           best: np.ndarray, xi: np.ndarray, distance: np.ndarray) -> None:
    """:func:`~dolfinx_fretting.contact._closest_segments` (each point's closest segment ``A + t d``, the first among
    equally close ones, its ``t`` and the distance), pruned from a guess: a point's distance to its ``previous``
    segment bounds its least distance, so a segment whose bounding box lies farther than that (with a margin of
    1e-9 of the coordinates' size, far above the rounding of either distance) cannot be the closest, nor tie with
    it, and is skipped. The others are tried in index order with the same formula and comparison, so the answer is
    the full search's to the bit (tests/test_finite_sliding.py checks it on random and tied cases); a non-finite
    bound skips nothing. Finite sliding re-pairs at almost every increment, each node a fraction of a facet from
    its last one."""
    for p in range(points.shape[0]):
        px, py = points[p, 0], points[p, 1]
        s0 = previous[p]
        rx, ry = px - A[s0, 0], py - A[s0, 1]
        t = min(max((rx * d[s0, 0] + ry * d[s0, 1]) / L2[s0], 0.0), 1.0)
        ex, ey = px - (A[s0, 0] + t * d[s0, 0]), py - (A[s0, 1] + t * d[s0, 1])
        size = abs(px) + abs(py) + abs(A[s0, 0]) + abs(A[s0, 1]) + abs(d[s0, 0]) + abs(d[s0, 1])
        bound = np.sqrt(ex * ex + ey * ey) * (1.0 + 1e-9) + 1e-9 * size
        bound2 = bound * bound
        best[p] = -1
        distance[p] = np.inf
        for s in range(A.shape[0]):
            x0, x1 = A[s, 0], A[s, 0] + d[s, 0]
            y0, y1 = A[s, 1], A[s, 1] + d[s, 1]
            bx = max(min(x0, x1) - px, 0.0, px - max(x0, x1))
            by = max(min(y0, y1) - py, 0.0, py - max(y0, y1))
            if bx * bx + by * by > bound2:
                continue
            rx = px - A[s, 0]
            ry = py - A[s, 1]
            t = min(max((rx * d[s, 0] + ry * d[s, 1]) / L2[s], 0.0), 1.0)
            ex = px - (A[s, 0] + t * d[s, 0])
            ey = py - (A[s, 1] + t * d[s, 1])
            dist = np.sqrt(ex * ex + ey * ey)
            if dist < distance[p]:
                best[p], xi[p], distance[p] = s, t, dist


@numba.njit(cache=True)
def _repair_2d(fl: np.ndarray, weights: np.ndarray, face_rows: np.ndarray, face_x: np.ndarray,
               slave_rows: np.ndarray, coords: np.ndarray, u: np.ndarray, D: np.ndarray, normal: np.ndarray,
               new_fl: np.ndarray, new_weights: np.ndarray) -> bool:
    """:func:`repair`'s search for a 2D pairing: each slave node's closest point of the facets within reach, both
    moved in the contact plane (``normal``: the obstacle's; ``u`` flat (M,)). Writes the new facets and weights;
    False when they are the pairing's own (the same facets, weights within 1e-12)."""
    F, nc = face_x.shape[0], fl.size
    un = np.empty(u.size)
    for node in range(u.size // 2):
        along = u[2 * node] * normal[0] + u[2 * node + 1] * normal[1]
        un[2 * node] = u[2 * node] - along * normal[0]
        un[2 * node + 1] = u[2 * node + 1] - along * normal[1]
    Dn = D[0] * normal[0] + D[1] * normal[1]
    Dt = np.array([D[0] - Dn * normal[0], D[1] - Dn * normal[1]])
    start, direction, length2 = np.empty((F, 2)), np.empty((F, 2)), np.empty(F)
    for f in range(F):
        for j in range(2):
            start[f, j] = face_x[f, 0, j] + un[2 * face_rows[f, 0] + j] + Dt[j]
            direction[f, j] = face_x[f, 1, j] + un[2 * face_rows[f, 1] + j] + Dt[j] - start[f, j]
        length2[f] = direction[f, 0] ** 2 + direction[f, 1] ** 2
    slave = np.empty((nc, 2))
    for c in range(nc):
        for j in range(2):
            slave[c, j] = coords[c, j] + un[2 * slave_rows[c] + j]
    xi, distance = np.empty(nc), np.empty(nc)
    _closest_segments_near(slave, start, direction, length2, fl, new_fl, xi, distance)
    changed = False
    for c in range(nc):
        new_weights[c, 0] = 1.0 - xi[c]
        new_weights[c, 1] = xi[c]
        if new_fl[c] != fl[c] or abs(new_weights[c, 0] - weights[c, 0]) > 1e-12 \
                or abs(new_weights[c, 1] - weights[c, 1]) > 1e-12:
            changed = True
    return changed


@numba.njit(cache=True)
def run_sliding_increments(fl: np.ndarray, weights: np.ndarray, frames: np.ndarray, gap0: np.ndarray,
                           W: np.ndarray, Q: np.ndarray, G: np.ndarray, A: np.ndarray, rho: np.ndarray,
                           face_rows: np.ndarray, face_x: np.ndarray, face_inside: np.ndarray,
                           face_sizes: np.ndarray, slave_rows: np.ndarray, coords: np.ndarray,
                           tributary: np.ndarray, abscissa: np.ndarray, C: np.ndarray, C_columns: np.ndarray,
                           surface_responses: np.ndarray, master_areas: np.ndarray, obstacle_frame: np.ndarray,
                           T: np.ndarray, on_surfaces: np.ndarray, out_responses: np.ndarray,
                           out_motion: np.ndarray, out_gap0: np.ndarray, by_force: bool, targets: np.ndarray,
                           controlled: np.ndarray, translations: np.ndarray, factors: np.ndarray, force_tol: float,
                           max_eval: int, stiffness: np.ndarray, d: np.ndarray, wear_gap: np.ndarray,
                           master_wear: np.ndarray, y: np.ndarray, r_last: np.ndarray, mu: np.ndarray,
                           k: np.ndarray, master_share: float, tol: float, max_iter: int, refresh: int,
                           repair_slip: float, warn_stride: bool, warn_reach: bool, rows: np.ndarray,
                           found: np.ndarray, solves: np.ndarray, slip: np.ndarray, status: np.ndarray,
                           wear_area_column: int, kept: tuple, kept_status: np.ndarray, kept_fl: np.ndarray,
                           kept_weights: np.ndarray) -> tuple[int, int, int]:
    """The increments of a cycle under finite sliding (2D node-to-segment), each solved on the pairing of the state
    it starts from and committed as :func:`~dolfinx_fretting.commit.commit` commits it: the compiled loop's local
    solve and load control (:func:`~dolfinx_fretting.cycling.run_force_increments` or
    :func:`~dolfinx_fretting.cycling.run_increments`, one increment per call; every local solve first tries its warm
    start's contact pattern exactly, :func:`~dolfinx_fretting.cycling.warm_pattern_solve`, as the stepwise path's
    ``increments._local_with_control`` does: no pattern can be cached per increment when W changes with the
    pairing), Archard's law, the master's share
    of the wear spread on its nodes (:func:`spread_wear`, ``master_share`` its fraction, < 0 without wear), the
    window's outside rows watched, then the re-pairing when a paired point has moved more than ``repair_slip``
    master elements (:func:`offsets`, :func:`repair`, :func:`carry_state`) with the new pairing's W, load responses,
    rigid modes, force map and Uzawa steps (``_pairing_operators``).

    The pairing (``fl`` indices into the facets within reach, ``weights``, ``frames``, ``gap0``, ``W``, ``Q``,
    ``G``, ``A``, ``rho``) and the state (``d``, ``stiffness``, ``wear_gap``, ``master_wear``, ``y``, ``r_last``)
    are in/out; ``rows``, ``found`` (each increment's obstacle), ``solves``, the last increment's ``slip`` and
    ``status`` out. ``translations``: (n, 2) each increment's obstacle translation (displacement control).
    ``kept`` (forces, slip, positions, wear gap: (n, m), (n, m), (n, m), (n, nc)), ``kept_status`` (n, nc),
    ``kept_fl`` (n, nc), ``kept_weights`` (n, nc, 2): out, each increment's committed state as the stepwise path keeps
    it (after its re-pairing: in the frames of the pairing ``kept_fl``, ``kept_weights``); n = 0 rows: not kept.

    Returns:
        (increments done, 0 or the code of what stopped the loop (``SOLVE_FAILED`` ...), re-pairings).
    """
    n, nc = targets.shape[0], fl.size
    m, M = 2 * nc, C.shape[0]
    n_out = out_gap0.size
    out_r, out_x, out_y = np.zeros((1, m)), np.zeros((1, m)), np.zeros((1, m))
    out_wear, out_states = np.zeros((1, nc)), np.zeros((1, nc), dtype=np.int8)
    r_warm = np.zeros((1, m))
    pattern, lu, piv = np.full((1, 1), -1, dtype=np.int8), np.zeros((1, 1, 1)), np.zeros((1, 1), dtype=np.int64)
    lu_ok, counts = np.zeros(1, dtype=np.bool_), np.zeros(3, dtype=np.int64)
    failure, force = np.zeros(4), np.zeros(d.size)
    before, moved = np.empty(nc), np.empty(nc)
    s, u = np.empty(M), np.empty(M)
    D = np.empty(2)
    volume, added, interpolated = np.empty(master_areas.size), np.empty(master_areas.size), np.empty(nc)
    new_fl, new_weights = np.empty(nc, dtype=np.int64), np.empty((nc, 2))
    new_frames, new_gap0 = np.empty((nc, 2, 2)), np.empty(nc)
    old_interp, new_interp = np.empty(nc), np.empty(nc)
    # mu held over the cycle (a friction law of the energy never runs here): the loop's unused evolution arguments
    factor_mu, held_energy, held_tables = np.zeros((1, 1)), np.zeros(1), np.full(1, -1, dtype=np.int64)
    held_rows, held_lengths, held_rates = np.zeros((1, 1)), np.ones(1, dtype=np.int64), np.zeros(1)
    normal = obstacle_frame[0]
    repairs = 0
    keep = kept_fl.shape[0] > 0
    for j in range(n):
        if keep and j > 0:   # the state increment j - 1 committed (re-paired or not: its step ends here)
            _keep_increment(j - 1, r_last, slip, y, wear_gap, status, fl, weights, kept, kept_status, kept_fl,
                            kept_weights)
        for c in range(nc):
            before[c] = wear_gap[c]
        if by_force:
            done, code, err = run_force_increments(
                W, rho, mu, 2, gap0, wear_gap, G, T, A, targets[j:j + 1], controlled, d, stiffness, force_tol,
                max_eval, Q, factors[j:j + 1], tributary, abscissa, y, r_last, r_warm, k, tol, max_iter, refresh,
                True, out_r, out_x, out_y, out_wear, out_states, rows[j:j + 1], found[j:j + 1], solves[j:j + 1],
                False, pattern, lu, piv, lu_ok, counts, failure, force, factor_mu, False, held_energy, 0.0,
                held_tables, held_rows, held_rows, held_lengths, held_rates, held_rates, *HELD_BLOCK_ARGUMENTS,
                True)
        else:
            done, code, err = run_increments(
                W, rho, mu, 2, gap0, wear_gap, G, translations[j:j + 1], Q, factors[j:j + 1], tributary, abscissa,
                y, r_last, r_warm, 0, k, tol, max_iter, refresh, True, out_r, out_x, out_y, out_wear, out_states,
                rows[j:j + 1], False, pattern, lu, piv, lu_ok, counts, factor_mu, False, held_energy, 0.0,
                held_tables, held_rows, held_rows, held_lengths, held_rates, held_rates, *HELD_BLOCK_ARGUMENTS,
                True)
        if done < 1:
            return j, SOLVE_FAILED, repairs
        for c in range(nc):
            status[c] = out_states[0, c]
        for i in range(m):
            slip[i] = out_x[0, i]
        # the master's share of the wear on the master's nodes (commit.commit)
        if master_share >= 0.0:
            for node in range(volume.size):
                volume[node] = 0.0
            for c in range(nc):
                depth = master_share * (wear_gap[c] - before[c])
                before[c] = depth
                for i in range(2):
                    volume[face_rows[fl[c], i]] += weights[c, i] * (depth * tributary[c])
            for node in range(volume.size):
                if volume[node] != 0.0 and not master_areas[node] > 0.0:
                    return j, WEAR_OFF_MASTER, repairs
                added[node] = volume[node] / master_areas[node] if master_areas[node] > 0.0 else 0.0
                master_wear[node] += added[node]
            _interpolate_2d(fl, weights, face_rows, added, interpolated)
            for c in range(nc):
                wear_gap[c] = wear_gap[c] - before[c] + interpolated[c]
            _interpolate_2d(fl, weights, face_rows, master_wear, interpolated)
            worn = 0.0
            for c in range(nc):
                worn += (wear_gap[c] - interpolated[c]) * tributary[c]
            on_master = 0.0
            for node in range(master_areas.size):
                on_master += master_wear[node] * master_areas[node]
            rows[j, wear_area_column] = worn + on_master
        obstacle = found[j]
        for g in range(2):
            D[g] = obstacle[0] * T[g, 0]
            for comp in range(1, obstacle.size):
                D[g] += obstacle[comp] * T[g, comp]
        _surface_motion(fl, weights, frames, face_rows, slave_rows, C_columns, surface_responses, r_last, factors[j], s,
                        u)
        if n_out:   # the nodes outside the window (window_check.check_window), with half its tolerance: a doubt
            norm_r, largest_gap, moved_out = 0.0, 0.0, 0.0
            for i in range(m):
                norm_r += r_last[i] * r_last[i]
            low = np.inf
            for c in range(nc):
                low = min(low, rho[c])
            gaps = np.empty(n_out)
            for i in range(n_out):
                g = 0.0
                for col in range(M):
                    g += on_surfaces[i, col] * s[col]
                for comp in range(obstacle.size):
                    g -= out_motion[i, comp] * obstacle[comp]
                for load in range(factors.shape[1]):
                    g += factors[j, load] * out_responses[load, i]
                gaps[i] = g + out_gap0[i]
                moved_out = max(moved_out, abs(gaps[i] - out_gap0[i]))
                largest_gap = max(largest_gap, abs(out_gap0[i]))
            terms = max(max(moved_out, largest_gap), math.sqrt(D[0] * D[0] + D[1] * D[1]))
            load_terms = 0.0
            for load in range(factors.shape[1]):
                largest = 0.0
                for i in range(n_out):
                    largest = max(largest, abs(out_responses[load, i]))
                load_terms += abs(factors[j, load]) * largest
            terms = max(terms, load_terms)
            bound = tol * math.sqrt(norm_r) / low + 1e-12 * terms
            for i in range(n_out):
                if gaps[i] < -0.5 * bound:
                    return j, WINDOW_SUSPECT, repairs
        _offsets_2d(fl, weights, frames, face_rows, face_x, face_sizes, slave_rows, coords, u, D, moved)
        largest_move = 0.0
        for c in range(nc):
            largest_move = max(largest_move, moved[c])
        if largest_move <= repair_slip:
            continue
        if largest_move > 1.0 and warn_stride:
            return j, LONG_STRIDE, repairs
        if not _repair_2d(fl, weights, face_rows, face_x, slave_rows, coords, u, D, normal, new_fl, new_weights):
            continue
        _pairing_arrays(new_fl, new_weights, face_x, face_inside, coords, new_frames, new_gap0)
        if warn_reach:
            _offsets_2d(new_fl, new_weights, new_frames, face_rows, face_x, face_sizes, slave_rows, coords, u, D,
                        moved)
            for c in range(nc):
                if r_last[2 * c] > 0.0 and moved[c] > repair_slip:
                    return j, BEYOND_REACH, repairs
        # carry_state: the forces and the slip turned into the new frames, the wear gap with the master's share read
        # at the new points, the positions of the committed configuration as the new pairing measures them
        _interpolate_2d(fl, weights, face_rows, master_wear, old_interp)
        _interpolate_2d(new_fl, new_weights, face_rows, master_wear, new_interp)
        for c in range(nc):
            for vector in (r_last, slip):
                gx = frames[c, 0, 0] * vector[2 * c] + frames[c, 1, 0] * vector[2 * c + 1]
                gy = frames[c, 0, 1] * vector[2 * c] + frames[c, 1, 1] * vector[2 * c + 1]
                vector[2 * c] = new_frames[c, 0, 0] * gx + new_frames[c, 0, 1] * gy
                vector[2 * c + 1] = new_frames[c, 1, 0] * gx + new_frames[c, 1, 1] * gy
            wear_gap[c] = wear_gap[c] - old_interp[c] + new_interp[c]
            f = new_fl[c]
            nodes = (slave_rows[c], face_rows[f, 0], face_rows[f, 1])
            coefs = (1.0, -new_weights[c, 0], -new_weights[c, 1])
            for kk in range(2):
                v = 0.0
                for a in range(3):
                    for jj in range(2):
                        v += coefs[a] * new_frames[c, kk, jj] * u[2 * nodes[a] + jj]
                y[2 * c + kk] = v - (new_frames[c, kk, 0] * D[0] + new_frames[c, kk, 1] * D[1])
            y[2 * c] += new_gap0[c] + wear_gap[c]
        for c in range(nc):
            fl[c] = new_fl[c]
            gap0[c] = new_gap0[c]
            for i in range(2):
                weights[c, i] = new_weights[c, i]
                for jj in range(2):
                    frames[c, i, jj] = new_frames[c, i, jj]
        repairs += 1
        if not _pairing_operators(fl, weights, frames, face_rows, slave_rows, C, surface_responses, obstacle_frame,
                                  W, Q, G, A, rho):
            return j, SINGULAR_BLOCK, repairs
    if keep and n > 0:
        _keep_increment(n - 1, r_last, slip, y, wear_gap, status, fl, weights, kept, kept_status, kept_fl,
                        kept_weights)
    return n, 0, repairs


@numba.njit(cache=True)
def _keep_increment(j: int, r: np.ndarray, slip: np.ndarray, y: np.ndarray, wear_gap: np.ndarray, status: np.ndarray,
                    fl: np.ndarray, weights: np.ndarray, kept: tuple, kept_status: np.ndarray, kept_fl: np.ndarray,
                    kept_weights: np.ndarray) -> None:
    """Row ``j`` of :func:`run_sliding_increments`' kept arrays: the committed state and its pairing."""
    kept_r, kept_x, kept_y, kept_wear = kept
    for i in range(r.size):
        kept_r[j, i] = r[i]
        kept_x[j, i] = slip[i]
        kept_y[j, i] = y[i]
    for c in range(fl.size):
        kept_wear[j, c] = wear_gap[c]
        kept_status[j, c] = status[c]
        kept_fl[j, c] = fl[c]
        kept_weights[j, c, 0] = weights[c, 0]
        kept_weights[j, c, 1] = weights[c, 1]
