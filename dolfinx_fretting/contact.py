"""Contact: candidate nodes, local frames, the operator H and the initial gap, against a rigid plane
(:func:`find_candidates`) or a deformable master body (:func:`find_pairs`).

For each candidate node alpha the local relative position is (paper eqs 1, 3)

    x^alpha = H_alpha u + g^alpha,    H_alpha = [n; t1; (t2)]  acting on the node's displacement,

ordered (n, t1[, t2]) per contact like FCLIB/Siconos, so ``r^alpha = (r_n, r_t...)`` and the nodal force
on the body is ``R^alpha = H_alpha^T r^alpha``. Nothing here assumes two dimensions: the frames, the
window and the tributary measures work for gdim = 2 or 3.

The contact set is replicated on every MPI rank (it is small: tens to a few thousand nodes) and ordered
by position along the surface, so the local problem is the same whatever the partition.
"""

from __future__ import annotations

import copy
import functools
from abc import ABCMeta, abstractmethod
from dataclasses import dataclass, replace
from typing import Any

import numba
import numpy as np
import scipy.sparse as sp
from mpi4py import MPI

from .laws import Coulomb, FrictionLaw
from .mortar import MortarMatrices, mortar_matrices, weighted_relative_displacement
from .pressure import RECOVERIES, check_surface_cells, smoothed_tractions, surface_mass

# DOLFINx, UFL and petsc4py are imported inside the functions that read the mesh: this module's value types
# (ContactSet, MasterSurface, RigidPlane, ElasticBody and the pure pairing functions) are imported by modules that
# must load without DOLFINx (state, sliding, the scene models behind the schema), and the pure modules stay usable
# without it (docs/architecture.md).

__all__ = ["Obstacle", "RigidPlane", "ElasticBody", "Contact", "ContactSet", "MasterSurface", "find_candidates",
           "find_pairs",
           "tangent_frame", "constrained_dofs", "constrained_global_dofs", "pair_with_faces", "pair_with_segments",
           "paired_contact_set", "find_mortar_pairs", "mortar_contact_set", "mortar_paired_set",
           "mortar_rows_set"]


def tangent_frame(normal: np.ndarray) -> np.ndarray:
    """Orthonormal frame with rows (n, t1[, t2]) for a normal in 2D or 3D (divided by its length first).

    - 2D: ``t1 = (n_y, -n_x)``, n turned clockwise by 90 degrees: ``n = (0, 1)`` gives ``t1 = (1, 0)``.
    - 3D: ``e`` is the coordinate axis least aligned with n (the smallest ``|n_i|``; on a tie the first of
      x, y, z), ``t1 = (e - (e.n) n) / |e - (e.n) n|`` (e made orthogonal to n) and ``t2 = n x t1``, so that
      (n, t1, t2) is right-handed:

      ============== =================== =================
      n              t1                  t2
      ============== =================== =================
      (0, 0, 1)      (1, 0, 0)           (0, 1, 0)
      (0, 1, 0)      (1, 0, 0)           (0, 0, -1)
      (1, 0, 0)      (0, 1, 0)           (0, 0, 1)
      (1, 1, 1)/√3   (2, -1, -1)/√6      (0, 1, -1)/√2
      ============== =================== =================

    Args:
        normal: The normal, 2 or 3 components, not zero.

    Returns:
        (dim, dim) array, rows n, t1[, t2].

    Raises:
        ValueError: if the normal does not have 2 or 3 components.
    """
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    if n.size == 2:
        return np.array([n, [n[1], -n[0]]])
    if n.size == 3:
        e = np.zeros(3)
        e[np.argmin(np.abs(n))] = 1.0
        t1 = e - (e @ n) * n
        t1 /= np.linalg.norm(t1)
        return np.array([n, t1, np.cross(n, t1)])
    raise ValueError(f"normal must have 2 or 3 components, got {n.size}")


class Obstacle(metaclass=ABCMeta):
    """What a :class:`Contact` needs of an obstacle: its frame, its candidate search, what moves with it.

    An obstacle shape is one class implementing :meth:`candidates` (and, where it has them, :meth:`check`, the
    cells moved with it and finite sliding), registered by name in
    :data:`dolfinx_fretting.obstacles.OBSTACLES`; the operators, increments, cycles and readers reach it only
    through these members. :class:`RigidPlane` and :class:`ElasticBody` are the two shapes.

    Attributes:
        normal: The unit normal of the obstacle motion's frame, pointing from the obstacle into the body.
    """

    normal: np.ndarray
    #: Finite sliding: the candidates are paired anew as the bodies slide (:class:`ElasticBody` only).
    finite_sliding: bool = False
    #: Cells of the mesh that move with the obstacle's translation D in the displacement read back, or None.
    moved_cells: np.ndarray | None = None

    @property
    def frame(self) -> np.ndarray:
        """Rows (n, t1[, t2]) of the obstacle frame (see :func:`tangent_frame`): the directions of the obstacle
        motion and of the total forces."""
        return tangent_frame(self.normal)

    def check(self, V) -> None:
        """Cheap checks of the obstacle against the space (on every rank alike), before any candidate search."""

    @abstractmethod
    def candidates(self, V, facets: np.ndarray, half_width: float | None,
                   exclude_nodes: np.ndarray | None) -> ContactSet:
        """The candidate contacts of the body's ``facets`` (within ``half_width`` of the window's centre, all if
        None; ``exclude_nodes`` never: their every dof is fixed), with frames, gaps and H. Collective."""

    def candidates_held(self, V, facets: np.ndarray, half_width: float | None, exclude_nodes: np.ndarray | None,
                        held_dofs: np.ndarray) -> ContactSet:
        """:meth:`candidates`, told the global dofs the conditions fix (``bs * global node + component``, the same on
        every rank): what :class:`Contact` calls. A shape whose rows reach the body's own surface (mortar: a node on a
        symmetry plane has its H columns along the roller's axis dropped, as the whole model's mirrored faces would
        cancel them) reads them; by default they are not needed. Collective."""
        return self.candidates(V, facets, half_width, exclude_nodes)


@dataclass(frozen=True)
class RigidPlane(Obstacle):
    """A rigid plane (a line in 2D) through ``point``, its ``normal`` pointing from the plane into the body.

    The normal may have any length: it is stored divided by its length (``RigidPlane([0, 0], [0, 2]).normal`` is
    ``[0, 1]``), so gaps are distances and the frame (:func:`tangent_frame`) is orthonormal whatever is given.

    Attributes:
        point: A point of the plane (2 or 3 coordinates, finite).
        normal: The unit normal (given as any finite non-zero vector of the same dimension).
    """

    point: np.ndarray
    normal: np.ndarray

    def __post_init__(self) -> None:
        n = np.asarray(self.normal, dtype=float)
        if n.ndim != 1 or n.size not in (2, 3) or not np.all(np.isfinite(n)) or np.linalg.norm(n) == 0:
            raise ValueError(f"RigidPlane.normal = {self.normal!r}: expected a finite non-zero 2- or 3-vector")
        point = np.asarray(self.point, dtype=float)
        if point.shape != n.shape or not np.all(np.isfinite(point)):
            raise ValueError(f"RigidPlane.point = {self.point!r}: expected {n.size} finite coordinates, as the normal")
        object.__setattr__(self, "normal", n / np.linalg.norm(n))
        object.__setattr__(self, "point", point)

    def gap(self, coords: np.ndarray) -> np.ndarray:
        """Signed normal distance of points (rows of ``coords``) from the plane."""
        return (np.asarray(coords) - self.point) @ self.normal

    def candidates(self, V, facets: np.ndarray, half_width: float | None,
                   exclude_nodes: np.ndarray | None) -> ContactSet:
        """:func:`find_candidates` against this plane. Collective."""
        return find_candidates(V, facets, self, half_width, exclude_nodes=exclude_nodes)


@dataclass
class ContactSet:
    """Candidate contact nodes with their frames, gaps and the operator H (identical on all ranks).

    Attributes:
        dim: Spatial dimension (2 or 3); each contact has ``dim`` local components.
        global_nodes: Global (block) node index of each contact in the displacement space.
        coords: Reference coordinates, shape (nc, dim).
        frames: Local frames, shape (nc, dim, dim), rows (n, t1[, t2]).
        gap0: Initial normal gap g_0 (mm) of each contact.
        tributary: Tributary length (2D) or area (3D) of each contact on the contact surface.
        abscissa: Position along the surface (t1-coordinate), used for ordering and profiles.
        H: Sparse (nc*dim, N_global) map from global dofs to local relative displacements.
    """

    dim: int
    global_nodes: np.ndarray
    coords: np.ndarray
    frames: np.ndarray
    gap0: np.ndarray
    tributary: np.ndarray
    abscissa: np.ndarray
    H: sp.csr_matrix
    #: Two deformable bodies (:func:`find_pairs`): the master facet's global nodes per contact (2D: a segment's
    #: two; 3D: four, a triangle's third padded with -1), their interpolation weights (0 on padding) and the
    #: paired master point; None against a rigid obstacle.
    master_nodes: np.ndarray | None = None
    master_weights: np.ndarray | None = None
    master_points: np.ndarray | None = None
    #: Two deformable bodies: the size of each contact's master facet (2D: the segment's length; 3D: the mean
    #: edge length), the scale of the small-sliding limit (relative slip below half of it).
    master_sizes: np.ndarray | None = None
    #: Two deformable bodies: each contact's facet in ``master_surface`` (the pairing, with
    #: ``master_weights``), and the master surface the pairing was searched on.
    master_faces: np.ndarray | None = None
    master_surface: MasterSurface | None = None
    #: The candidate window's centre: the body point closest to the obstacle (the first point of contact), from
    #: which the window's half-width is measured in the tangent plane.
    window_centre: np.ndarray | None = None
    #: The P1 mass matrix (nc, nc) of the contact surface's facets whose every node is a contact, when the
    #: tractions read are the ``"smoothed"`` ones (:mod:`dolfinx_fretting.pressure`); None: ``"nodal"``.
    surface_mass: sp.csr_matrix | None = None
    #: Mortar (:func:`mortar_contact_set`): the slave surface's segments (3D: faces) in the reference configuration,
    #: from which a finite-sliding re-pairing recomputes the mortar matrices; None for node pairing.
    slave_surface: MasterSurface | None = None
    #: Mortar: each contact's slave node's own measure (its hat's integral over the whole slave surface,
    #: :meth:`MasterSurface.node_measures`), where finite sliding keeps the slave's share of the wear, whatever part
    #: of the hat faces the master (``tributary``, ``D_jj``); None for node pairing (the tributary is that measure).
    slave_areas: np.ndarray | None = None
    #: Mortar: (k, 2) integer pairs (slave node label, coordinate axis) of the slave nodes on a symmetry plane normal
    #: to that axis (:func:`find_mortar_pairs`' ``held_dofs``), whose H columns along the axis every pairing drops
    #: (the same function at every pairing); None for node pairing.
    symmetry_axes: np.ndarray | None = None
    #: Mortar: (nc, dim) each slave node's position less its weighted master point's when it was paired (in that
    #: moment's configuration), which finite sliding's offsets subtract: the dual weights' master point is not the
    #: node's closest point (on a curved slave the two differ by about the gap times the slope), and that geometric
    #: offset is not slip; None: zero (node pairing pairs with the closest point).
    paired_separation: np.ndarray | None = None

    @property
    def two_body(self) -> bool:
        """True when the obstacle is a deformable master body."""
        return self.master_nodes is not None

    @property
    def nc(self) -> int:
        return int(self.global_nodes.size)

    @property
    def rigid_modes(self) -> np.ndarray:
        """Local relative displacement per unit rigid translation of the body, shape (nc*dim, dim).

        Its transpose sums local contact forces into the total global force on the body,
        ``F = rigid_modes.T @ r``.
        """
        return self.frames.reshape(self.nc * self.dim, self.dim)

    def total_force(self, r: np.ndarray) -> np.ndarray:
        """Total contact force on the body in global coordinates."""
        return self.rigid_modes.T @ r

    def tractions(self, forces: np.ndarray) -> np.ndarray:
        """The traction read at each contact, (..., nc, dim) rows (pressure, shear t1[, t2]), of contact forces
        ``forces`` (..., nc * dim): ``r / A`` (``"nodal"``), or the ``"smoothed"`` values of
        :func:`~dolfinx_fretting.pressure.smoothed_tractions` when :attr:`surface_mass` is held."""
        r = np.asarray(forces, dtype=float)
        r = r.reshape(*r.shape[:-1], self.nc, self.dim)
        if self.surface_mass is None:
            return r / self.tributary[:, None]
        return smoothed_tractions(r, self.tributary, self.surface_mass)

    def subset(self, contacts: np.ndarray) -> ContactSet:
        """The contacts ``contacts`` (indices, in that order) of this set: their rows of every array and of H."""
        contacts = np.asarray(contacts, dtype=np.int64)
        rows = (self.dim * contacts[:, None] + np.arange(self.dim)).ravel()
        pick = lambda a: None if a is None else a[contacts]  # noqa: E731
        return ContactSet(self.dim, self.global_nodes[contacts], self.coords[contacts], self.frames[contacts],
                          self.gap0[contacts], self.tributary[contacts], self.abscissa[contacts], self.H[rows],
                          pick(self.master_nodes), pick(self.master_weights), pick(self.master_points),
                          pick(self.master_sizes), pick(self.master_faces), self.master_surface, self.window_centre,
                          None if self.surface_mass is None else self.surface_mass[contacts][:, contacts].tocsr(),
                          self.slave_surface, pick(self.slave_areas), self.symmetry_axes,
                          pick(self.paired_separation))


def _tributary_measure(V, facets: np.ndarray, fdim: int) -> np.ndarray:
    """Lumped boundary measure per node: assemble the integral of each P1 hat function over ``facets``."""
    import ufl  # lazy: DOLFINx (see the note at the imports)
    from dolfinx import mesh as dmesh
    from petsc4py import PETSc

    from ._dolfinx import fem, scalar_space  # lazy: DOLFINx (see the note at the imports)

    msh = V.mesh
    Q = scalar_space(msh, "Lagrange", 1)
    tags = dmesh.meshtags(msh, fdim, facets, np.ones(facets.size, dtype=np.int32))
    ds = ufl.Measure("ds", domain=msh, subdomain_data=tags)
    b = fem.petsc.assemble_vector(fem.form(ufl.TestFunction(Q) * ds(1)))
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    b.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    with b.localForm() as loc:
        values = loc.array.copy()
    b.destroy()
    return values


def _node_coordinates(V) -> np.ndarray:
    """(nodes, gdim) coordinates of the P1 nodes of ``V`` (owned and ghost), copied from the mesh geometry.

    ``V.tabulate_dof_coordinates()`` recomputes them by the cells' maps, with rounding that depends on which
    cell does it (~1e-18 on a coordinate that is 0), hence on the partition; the geometry holds the mesh's
    input coordinates, the same bits on every partition. A P1 space and a first-order geometry number a
    cell's nodes alike.
    """
    from ._dolfinx import cell_dofmap, geometry_dofmap  # lazy: DOLFINx (see the note at the imports)

    msh = V.mesh
    gdim = msh.geometry.dim
    dofs, xdofs = cell_dofmap(V), geometry_dofmap(msh)
    n = V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts
    out = np.zeros((n, gdim))
    out[dofs.ravel()] = msh.geometry.x[xdofs.ravel(), :gdim]
    return out


def _in_plane_order(in_plane: np.ndarray, extent: float) -> np.ndarray:
    """Order of points by their first in-plane coordinate, then the second (3D): values within 1e-9 of the
    extent count as equal, so that the rounding of a coordinate cannot reorder a column of nodes."""
    if in_plane.shape[1] == 1:
        return np.argsort(in_plane[:, 0], kind="stable")
    first = np.argsort(in_plane[:, 0], kind="stable")
    column = np.concatenate([[0], np.cumsum(np.diff(in_plane[first, 0]) > 1e-9 * extent)])
    groups = np.empty(first.size, dtype=np.int64)
    groups[first] = column
    return np.lexsort((in_plane[:, 1], groups))


def find_candidates(V, facets: np.ndarray, obstacle: RigidPlane, half_width: float | None = None,
                    exclude_nodes: np.ndarray | None = None) -> ContactSet:
    """Choose candidate nodes on a boundary and build their frames, gaps and H. Collective.

    Candidates are the nodes of ``facets`` within ``half_width`` (measured in the plane) of the body
    point closest to the obstacle; with ``half_width=None`` every node of ``facets``.

    Args:
        V: Vector P1 displacement space (:func:`~dolfinx_fretting._dolfinx.vector_space`).
        facets: Local indices of the boundary facets that may touch the obstacle (sorted, unique).
        obstacle: The rigid plane.
        half_width: Window half-width (mm) around the closest point, or None.
        exclude_nodes: Local block indices of nodes with prescribed displacement (never candidates:
            K has identity rows there).

    Returns:
        The contact set, identical on every rank.

    Raises:
        ValueError: if ``facets`` hold no node outside ``exclude_nodes`` on any rank, no candidate is found within
            the window, or the dimensions disagree.
    """
    from dolfinx import fem  # lazy: DOLFINx (see the note at the imports)

    msh = V.mesh
    comm = msh.comm
    gdim = msh.geometry.dim
    fdim = msh.topology.dim - 1
    if obstacle.normal.size != gdim:
        raise ValueError(f"obstacle normal has {obstacle.normal.size} components, mesh is {gdim}D")
    bs = V.dofmap.index_map_bs
    imap = V.dofmap.index_map
    n_owned = imap.size_local

    facets = np.asarray(facets, dtype=np.int32)
    nodes = fem.locate_dofs_topological(V, fdim, facets)
    nodes = nodes[nodes < n_owned]  # owned only: each node listed once across ranks
    if exclude_nodes is not None and len(exclude_nodes):
        nodes = np.setdiff1d(nodes, exclude_nodes)
    # Decided on the sum over ranks (a rank may own no node of the surface while others do), so that every rank
    # raises or none does; without it the extent below fails on an empty array with numpy's own message.
    if comm.allreduce(nodes.size, op=MPI.SUM) == 0:
        raise ValueError("find_candidates: the facets given hold no free node on any rank (no facet, or every node "
                         "in exclude_nodes); check the surface's marker and the Dirichlet conditions on it")
    # 3D: the geometry's coordinates (partition-free bits, see _node_coordinates); 2D keeps the tabulated ones.
    coords = (_node_coordinates(V) if gdim == 3 else V.tabulate_dof_coordinates())[nodes, :gdim]
    gaps = obstacle.gap(coords)

    # Point of the surface closest to the obstacle (the first point of contact), on every rank. Ties go to
    # the node nearest the plane point's foot along the plane, then the smallest coordinates, so that the
    # window does not depend on the partition. Gaps within rounding of the smallest (1e-9 of the surface's
    # extent: a flat face meshed by a generator is flat to ~1e-16 only) are ties.
    frame = obstacle.frame
    extent = np.ptp(np.concatenate(comm.allgather(coords)), axis=0).max(initial=0.0)
    g_min = comm.allreduce(gaps.min(initial=np.inf), op=MPI.MIN)
    keys = [(g if g > g_min + 1e-9 * extent else g_min, float(np.linalg.norm((c - obstacle.point) @ frame[1:].T)),
             *c) for g, c in zip(gaps, coords)]
    local_min = min(keys) if keys else (np.inf, np.inf) + (0.0,) * gdim
    closest = np.array(min(comm.allgather(local_min))[2:])
    if half_width is not None:
        in_plane = (coords - closest) @ frame[1:].T
        keep = np.linalg.norm(in_plane, axis=1) <= half_width * (1 + 1e-12)
        nodes, coords, gaps = nodes[keep], coords[keep], gaps[keep]

    measure = _tributary_measure(V, facets, fdim)
    trib = measure[nodes]
    gnodes = imap.local_to_global(nodes.astype(np.int32)).astype(np.int64)

    gathered = comm.allgather((gnodes, coords, gaps, trib))
    gnodes = np.concatenate([g[0] for g in gathered])
    coords = np.concatenate([g[1] for g in gathered]).reshape(-1, gdim)
    gaps = np.concatenate([g[2] for g in gathered])
    trib = np.concatenate([g[3] for g in gathered])
    if gnodes.size == 0:
        raise ValueError("contact: no contact candidate found on the contact surface within the window "
                         f"(contact.candidate_half_width = {half_width}); widen the window or check "
                         "contact.surface and the obstacle position")

    # Order along the surface (t1, then t2): independent of the partition.
    in_plane = coords @ frame[1:].T
    order = (_in_plane_order(in_plane, np.ptp(coords, axis=0).max()) if gdim == 3
             else np.lexsort(tuple(in_plane[:, k] for k in reversed(range(gdim - 1)))))
    gnodes, coords, gaps, trib, in_plane = (a[order] for a in (gnodes, coords, gaps, trib, in_plane))

    nc = gnodes.size
    frames = np.broadcast_to(frame, (nc, gdim, gdim)).copy()
    rows = np.repeat(np.arange(nc * gdim), gdim)
    cols = (bs * np.repeat(gnodes, gdim * gdim).reshape(nc, gdim, gdim)
            + np.arange(gdim)[None, None, :]).ravel()
    n_global = imap.size_global * bs
    H = sp.csr_matrix((frames.ravel(), (rows, cols)), shape=(nc * gdim, n_global))
    return ContactSet(dim=gdim, global_nodes=gnodes, coords=coords, frames=frames, gap0=gaps,
                      tributary=trib, abscissa=in_plane[:, 0].copy(), H=H, window_centre=closest)



# Two deformable bodies -------------------------------------------------------------------------------------
def _owned_facet_topology(msh, facets: np.ndarray) -> tuple[np.ndarray, Any, Any, Any]:
    """The owned ones of ``facets`` (each facet once across ranks) and the facet-to-cell, facet-to-vertex and
    cell-to-vertex connectivities of ``msh`` (created if missing)."""
    tdim = msh.topology.dim
    fdim = tdim - 1
    msh.topology.create_connectivity(fdim, tdim)
    msh.topology.create_connectivity(fdim, 0)
    facets = np.asarray(facets, dtype=np.int32)
    owned = facets[facets < msh.topology.index_map(fdim).size_local]
    return (owned, msh.topology.connectivity(fdim, tdim), msh.topology.connectivity(fdim, 0),
            msh.topology.connectivity(tdim, 0))


def _boundary_segments(V, facets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The owned facets of a 2D boundary as segments of P1 nodes, gathered on every rank. Collective.

    Returns:
        (global node pairs (n, 2), end coordinates (n, 2, gdim), the centroid of each facet's cell (n, gdim));
        the cell centroid tells on which side of the segment the body lies.
    """
    msh, comm, gdim = V.mesh, V.mesh.comm, V.mesh.geometry.dim
    facets, f_to_c, f_to_v, c_to_v = _owned_facet_topology(msh, facets)
    dof_x = V.tabulate_dof_coordinates()[:, :gdim]
    imap = V.dofmap.index_map
    pairs, ends, centroids = [], [], []
    for f in facets:
        cell = f_to_c.links(f)[0]
        dofs = V.dofmap.cell_dofs(cell)
        # P1: a facet's nodes are the cell's dofs sitting at the facet's vertices (matched by position
        # inside one cell, where positions are distinct; coincident nodes of the other body are elsewhere).
        vx = msh.geometry.x[_vertex_geometry(msh, f_to_v.links(f)), :gdim]
        local = [int(dofs[np.argmin(np.linalg.norm(dof_x[dofs] - p, axis=1))]) for p in vx]
        pairs.append(local)
        ends.append(dof_x[local])
        cverts = _vertex_geometry(msh, c_to_v.links(cell))
        centroids.append(msh.geometry.x[cverts, :gdim].mean(axis=0))
    pairs = np.asarray(pairs, dtype=np.int32).reshape(-1, 2)
    gpairs = imap.local_to_global(pairs.ravel()).reshape(-1, 2).astype(np.int64) if pairs.size else \
        np.zeros((0, 2), dtype=np.int64)
    gathered = comm.allgather((gpairs, np.asarray(ends).reshape(-1, 2, gdim),
                               np.asarray(centroids).reshape(-1, gdim)))
    nodes, xs, centroids = (np.concatenate([g[k] for g in gathered]) for k in range(3))
    # A partition-free order (by the segment's midpoint), so that ties between segments, and the segment
    # indices a checkpoint stores, are the same on any number of ranks.
    mid = xs.mean(axis=1)
    order = np.lexsort(mid.T[::-1]) if mid.size else np.zeros(0, dtype=np.int64)
    return nodes[order], xs[order], centroids[order]


def _vertex_geometry(msh, vertices: np.ndarray) -> np.ndarray:
    """Geometry node index of each topological vertex (first-order mesh)."""
    from ._dolfinx import geometry_dofmap  # lazy: DOLFINx (see the note at the imports)

    # Cached per mesh: the vertex -> geometry node map through the cell -> geometry dofmap.
    cache = getattr(msh, "_vertex_to_node", None)
    if cache is None:
        tdim = msh.topology.dim
        c_to_v = msh.topology.connectivity(tdim, 0)
        imap = msh.topology.index_map(0)
        cache = np.full(imap.size_local + imap.num_ghosts, -1, dtype=np.int64)
        x_dofmap = geometry_dofmap(msh)
        for c in range(msh.topology.index_map(tdim).size_local + msh.topology.index_map(tdim).num_ghosts):
            cache[c_to_v.links(c)] = x_dofmap[c]
        msh._vertex_to_node = cache
    return cache[vertices]



def _tied_gaps(gaps: np.ndarray, coords: np.ndarray) -> np.ndarray:
    """``gaps`` with those within rounding of the smallest (1e-9 of the surface's extent) set to the smallest, so
    that the first point of contact of a conforming surface (flat or concentric: equal gaps by construction) is
    decided by the partition-free tie-breaks, not by the last bit of a gap (as :func:`find_candidates` does)."""
    if gaps.size == 0:
        return gaps
    extent = np.ptp(coords, axis=0).max(initial=0.0)
    smallest = gaps.min()
    return np.where(gaps > smallest + 1e-9 * extent, gaps, smallest)

def _slave_nodes(V, slave_facets: np.ndarray, exclude_nodes: np.ndarray | None,
                 coordinates: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The slave surface's owned nodes (less ``exclude_nodes``), gathered on every rank: (global node numbers,
    coordinates from ``coordinates``, tributary measures). Collective."""
    from dolfinx import fem  # lazy: DOLFINx (see the note at the imports)

    fdim = V.mesh.topology.dim - 1
    imap = V.dofmap.index_map
    slave_facets = np.asarray(slave_facets, dtype=np.int32)
    nodes = fem.locate_dofs_topological(V, fdim, slave_facets)
    nodes = nodes[nodes < imap.size_local]
    if exclude_nodes is not None and len(exclude_nodes):
        nodes = np.setdiff1d(nodes, exclude_nodes)
    measure = _tributary_measure(V, slave_facets, fdim)
    gathered = V.mesh.comm.allgather((imap.local_to_global(nodes.astype(np.int32)).astype(np.int64),
                                      coordinates[nodes], measure[nodes]))
    return (np.concatenate([g[0] for g in gathered]),
            np.concatenate([g[1] for g in gathered]).reshape(-1, coordinates.shape[1]),
            np.concatenate([g[2] for g in gathered]))


def find_pairs(V, slave_facets: np.ndarray, master_facets: np.ndarray, half_width: float | None = None,
               exclude_nodes: np.ndarray | None = None, reference_frame: np.ndarray | None = None) -> ContactSet:
    """Pair each slave node with a point of the master surface, in the reference configuration. Collective.

    2D here (node-to-segment); 3D in :func:`_find_pairs_3d` (node-to-face).

    Small sliding: the pairing is made once and kept for the whole run. In fretting the relative slip is
    micrometres, a fraction of the contact width, so the master point of a slave node moves little; the
    run warns when the accumulated relative slip exceeds half a master element (then the master's
    displacement is taken at a point that is no longer the one facing the slave node).

    For slave node s, the master point is the closest point P of the master segments, with weights
    ``(1 - xi, xi)`` on the segment's end nodes (A, B) and the frame (n, t) of that segment, n the master's
    outward normal (pointing towards the slave). The local relative displacement is

        x^s = [n; t] (u_s - (1 - xi) u_A - xi u_B) + g0,    g0 = (s - P) . n,

    so H has ``3 dim`` non-zeros per row and ``W = H K^-1 H^T`` and the local solvers are unchanged. A rigid
    translation D of the master body changes x by ``-[n; t] D``, as for a rigid plane moved by D
    (:attr:`ContactSet.rigid_modes`). Slave candidates: the owned nodes of ``slave_facets`` within
    ``half_width`` (along t) of the slave node closest to the master.

    In 3D (node-to-face, :func:`_find_pairs_3d`) the master point is the closest point of the master's
    triangles and quadrilaterals, with linear (triangle) or bilinear (quadrilateral) weights on their nodes.

    Args:
        V: Vector P1 displacement space on the mesh holding both bodies.
        slave_facets, master_facets: Local facet indices of the two contact surfaces.
        half_width: Candidate window half-width (mm), or None for every slave node.
        exclude_nodes: Local block indices with prescribed displacement (never candidates).
        reference_frame: 3D: the obstacle frame (n, t1, t2) whose t1, projected on each master facet, gives the
            contact's t1 (so the contacts' frames follow the obstacle's); 2D: unused.

    Returns:
        The contact set (identical on every rank) with ``master_nodes``, ``master_weights`` and
        ``master_points`` set.

    Raises:
        ValueError: if no slave node or master facet is found.
    """
    gdim = V.mesh.geometry.dim
    if gdim == 3:
        return _find_pairs_3d(V, slave_facets, master_facets, half_width, exclude_nodes, reference_frame)
    if gdim != 2:
        raise ValueError(f"two-body contact needs a 2D or 3D mesh; the mesh is {gdim}D")
    imap = V.dofmap.index_map
    seg_nodes, seg_x, seg_inside = _boundary_segments(V, master_facets)
    if seg_nodes.shape[0] == 0:
        raise ValueError("contact: the master surface has no facet")
    ref = tangent_frame([0.0, 1.0]) if reference_frame is None else np.asarray(reference_frame, dtype=float)
    surface = MasterSurface(seg_nodes, seg_x, np.full(seg_nodes.shape[0], 2), seg_inside, ref)

    gnodes, coords, trib = _slave_nodes(V, slave_facets, exclude_nodes, V.tabulate_dof_coordinates()[:, :gdim])
    if gnodes.size == 0:
        raise ValueError("contact: no slave node on the contact surface")

    pairs = surface.pair(coords)
    frames = surface.frames(pairs["normal"])
    gaps = np.einsum("ij,ij->i", coords - pairs["point"], pairs["normal"])
    abscissa = np.einsum("ij,ij->i", coords, frames[:, 1])  # position along the master's tangent
    closest = coords[np.lexsort((coords[:, 0], np.abs(abscissa), _tied_gaps(gaps, coords)))[0]]  # ties: nearest x = 0
    keep = np.ones(gnodes.size, dtype=bool)
    if half_width is not None:
        keep = np.abs(np.einsum("ij,ij->i", coords - closest, frames[:, 1])) <= half_width * (1 + 1e-12)
    order = np.flatnonzero(keep)[np.argsort(abscissa[keep], kind="stable")]
    contact_set = paired_contact_set(surface, gnodes[order], coords[order], trib[order], abscissa[order],
                                     pairs["face"][order], pairs["weights"][order], imap.size_global * gdim)
    contact_set.window_centre = closest
    return contact_set


def paired_contact_set(surface: MasterSurface, global_nodes: np.ndarray, coords: np.ndarray, tributary: np.ndarray,
                       abscissa: np.ndarray, faces: np.ndarray, weights: np.ndarray, n_dofs: int,
                       surface_mass: sp.csr_matrix | None = None) -> ContactSet:
    """The contact set of slave nodes paired with points of ``surface`` (pure NumPy; the same on every rank).

    The pairing (each contact's facet and its weights on the facet's nodes) may have been searched in any
    configuration (:meth:`MasterSurface.pair`); the master point, its normal, the frame and the gap are those of
    the reference configuration at the same facet and weights, so that ``x = H u + g0`` is the linearised
    relative position of the slave node and that material point of the master:

        x^s = frame . (u_s - sum_i w_i u_i) + g0,    g0 = (X_s - sum_i w_i X_i) . n.

    Args:
        surface: The master surface.
        global_nodes, coords, tributary, abscissa: The slave nodes (global block index, reference coordinates,
            tributary measure, position along the surface), in the contacts' order.
        faces, weights: Each contact's facet of ``surface`` and its weights on the facet's nodes (0 on padding).
        n_dofs: Global number of displacement dofs (the columns of H).
        surface_mass: The slave nodes' :attr:`ContactSet.surface_mass` (a pairing anew keeps the slave's).
    """
    dim = surface.dim
    faces = np.asarray(faces, dtype=np.int64)
    point, normal = surface.reference_geometry(faces, weights)
    frames = surface.frames(normal)
    gaps = np.einsum("ij,ij->i", coords - point, normal)
    masters = surface.nodes[faces]
    nc = global_nodes.size
    # Rows (n, t1[, t2]) of contact c: frame . (e_slave - sum_i w_i e_master_i); (1 + nodes per facet) x dim
    # columns each; a triangle's padding (-1) points at the slave node with weight 0.
    node_cols = np.column_stack([global_nodes, np.where(masters >= 0, masters, global_nodes[:, None])])
    node_coef = np.column_stack([np.ones(nc), -np.where(masters >= 0, weights, 0.0)])
    vals = frames[:, :, None, :] * node_coef[:, None, :, None]           # (nc, dim, nodes, dim)
    cols = dim * node_cols[:, None, :, None] + np.arange(dim)[None, None, None, :]
    # CSR directly (finite sliding pairs anew at almost every increment): each row's columns sorted; a padding
    # column repeats the slave node's with a zero value, which goes with the zero weights (a node facing a master
    # node or edge touches no column)
    per_row = node_cols.shape[1] * dim
    cols = np.broadcast_to(cols, vals.shape).reshape(nc * dim, per_row)
    order = np.argsort(cols, axis=1, kind="stable")
    H = sp.csr_matrix((np.take_along_axis(vals.reshape(nc * dim, per_row), order, axis=1).ravel(),
                       np.take_along_axis(cols, order, axis=1).ravel(), np.arange(nc * dim + 1) * per_row),
                      shape=(nc * dim, n_dofs))
    H.eliminate_zeros()
    return ContactSet(dim=dim, global_nodes=global_nodes, coords=coords, frames=frames, gap0=gaps,
                      tributary=tributary, abscissa=abscissa, H=H, master_nodes=masters,
                      master_weights=np.asarray(weights, dtype=float), master_points=point,
                      master_sizes=surface.sizes[faces], master_faces=faces, master_surface=surface,
                      surface_mass=surface_mass)


def find_mortar_pairs(V, slave_facets: np.ndarray, master_facets: np.ndarray, half_width: float | None = None,
                      exclude_nodes: np.ndarray | None = None, reference_frame: np.ndarray | None = None,
                      held_dofs: np.ndarray | None = None) -> ContactSet:
    """Mortar contact of the slave surface with the master surface, in the reference configuration (2D segments,
    3D triangles and quadrilaterals). Collective.

    The mortar matrices D and M of the two surfaces (dual multipliers, :mod:`dolfinx_fretting.mortar`) give each
    slave node j with some of its hat function facing the master (``D_jj > 0``) one contact, whose rows of H are
    the weighted gap and weighted relative tangential displacement divided by ``D_jj`` (see
    :func:`mortar_contact_set`). Slave candidates: the free owned nodes of ``slave_facets`` within ``half_width``
    of the slave node with the smallest gap, as :func:`find_pairs` (2D along t; 3D in the reference frame's tangent
    plane, ordered as node-to-face orders them).

    Args:
        V: Vector P1 displacement space on the mesh holding both bodies (2D or 3D).
        slave_facets, master_facets: Local facet indices of the two contact surfaces.
        half_width: Candidate window half-width (length units), or None for every slave node.
        exclude_nodes: Local block indices with prescribed displacement (never candidates).
        reference_frame: The obstacle frame (n, t1[, t2]); held by the master surface; in 3D its t1 projected on
            the master facet at each slave node's closest point is the contact's t1 (as node-to-face's).
        held_dofs: Global dofs (``gdim * global node + component``) the conditions fix. A slave node with some but
            not all of its components held is taken to lie on a symmetry plane normal to each held axis (a roller):
            its averaged normal (the mortar module's ``symmetry_axes``: the facing check) drops those components, as
            the whole model's mirrored faces would cancel them, and its H columns along the held axis are dropped, so
            its frame holds the roller's direction (as node-to-face's flat master frame does).

    Raises:
        ValueError: if the mesh is neither 2D nor 3D, or no slave node faces the master.
    """
    gdim = V.mesh.geometry.dim
    if gdim not in (2, 3):
        raise ValueError(f"mortar contact needs a 2D or 3D mesh; the mesh is {gdim}D")
    imap = V.dofmap.index_map
    if gdim == 2:
        slave_nodes_of, slave_x, slave_inside = _boundary_segments(V, slave_facets)
        master_nodes_of, master_x, master_inside = _boundary_segments(V, master_facets)
        master_nv = np.full(master_nodes_of.shape[0], 2)
        slave_nv = np.full(slave_nodes_of.shape[0], 2)
        coordinates = V.tabulate_dof_coordinates()[:, :gdim]
    else:
        slave_nodes_of, slave_x, slave_nv, slave_inside = _boundary_faces(V, slave_facets)
        master_nodes_of, master_x, master_nv, master_inside = _boundary_faces(V, master_facets)
        coordinates = _node_coordinates(V)
    if master_nodes_of.shape[0] == 0 or slave_nodes_of.shape[0] == 0:
        raise ValueError("contact: the master or the slave surface has no facet")
    ref = tangent_frame(np.eye(gdim)[-1 if gdim == 3 else 1]) if reference_frame is None \
        else np.asarray(reference_frame, dtype=float)
    surface = MasterSurface(master_nodes_of, master_x, master_nv, master_inside, ref)
    symmetry_axes = np.zeros((0, 2), dtype=np.int64)
    if held_dofs is not None:
        labels = np.unique(slave_nodes_of[slave_nodes_of >= 0])
        held = np.isin(gdim * labels[:, None] + np.arange(gdim), np.asarray(held_dofs, dtype=np.int64))
        partly = np.flatnonzero(held.any(axis=1) & ~held.all(axis=1))
        node_of, axis = np.nonzero(held[partly])
        symmetry_axes = np.column_stack([labels[partly[node_of]], axis])
    mortar = mortar_matrices(slave_nodes_of, slave_x, slave_inside, master_nodes_of, master_x, master_inside,
                             reference_tangent=ref[1] if gdim == 3 else None, symmetry_axes=symmetry_axes)
    free, _, _ = _slave_nodes(V, slave_facets, exclude_nodes, coordinates)
    contacts = np.flatnonzero(np.isin(mortar.slave_nodes, free) & (mortar.D.diagonal() > 0))
    if contacts.size == 0:
        raise ValueError("contact: no free slave node faces the master surface (mortar: every D_jj = 0)")
    contact_set = mortar_contact_set(mortar, slave_nodes_of, slave_x, surface, imap.size_global * gdim,
                                     slave_surface=MasterSurface(slave_nodes_of, slave_x, slave_nv, slave_inside, ref))
    contact_set.symmetry_axes = symmetry_axes
    contact_set.H = _drop_symmetry_columns(contact_set.H, contact_set.global_nodes, gdim, symmetry_axes)
    gaps, coords = contact_set.gap0[contacts], contact_set.coords[contacts]
    if gdim == 2:
        abscissa = contact_set.abscissa[contacts]
        closest = coords[np.lexsort((coords[:, 0], np.abs(abscissa), _tied_gaps(gaps, coords)))[0]]
        keep = np.ones(contacts.size, dtype=bool)
        if half_width is not None:
            keep = np.abs(np.einsum("ij,ij->i", coords - closest, contact_set.frames[contacts, 1])) \
                <= half_width * (1 + 1e-12)
        order = contacts[np.flatnonzero(keep)[np.argsort(abscissa[keep], kind="stable")]]
    else:   # as node-to-face (_find_pairs_3d): in the reference frame's tangent plane
        in_plane = coords @ ref[1:].T
        distance = np.linalg.norm(in_plane, axis=1)
        closest = coords[np.lexsort((coords[:, 1], coords[:, 0], distance, _tied_gaps(gaps, coords)))[0]]
        keep = np.ones(contacts.size, dtype=bool)
        if half_width is not None:
            keep = np.linalg.norm((coords - closest) @ ref[1:].T, axis=1) <= half_width * (1 + 1e-12)
        if not keep.any():
            raise ValueError("contact: no slave node within the candidate window")
        kept = np.flatnonzero(keep)
        order = contacts[kept[_in_plane_order(in_plane[kept], np.ptp(coords, axis=0).max())]]
    contact_set = contact_set.subset(order)
    contact_set.window_centre = closest
    return contact_set


def _drop_symmetry_columns(H: sp.csr_matrix, global_nodes: np.ndarray, dim: int,
                           symmetry_axes: np.ndarray | None) -> sp.csr_matrix:
    """H of mortar contacts (rows ``dim c + k`` of contact c's slave node ``global_nodes[c]``) without, in the rows of
    a slave node on a symmetry plane (a pair (node, axis) of ``symmetry_axes``), the columns of the dofs along that
    axis: the first pairing's (:func:`find_mortar_pairs`) and every re-pairing's (:func:`mortar_rows_set`) alike.
    Pure NumPy.

    The whole model's mirrored master faces would cancel those components (the master's antisymmetric displacement
    on the plane), so they are dropped; the node's row along the axis (a frame direction: its averaged normal lies
    in the plane) then touches held dofs only, a held row as node-to-face's (:attr:`Contact.held_rows`).
    """
    if symmetry_axes is None or symmetry_axes.size == 0:
        return H
    entries = H.tocoo()
    along = np.isin(global_nodes[entries.row // dim] * dim + entries.col % dim,
                    symmetry_axes[:, 0] * dim + symmetry_axes[:, 1])
    return sp.csr_matrix((entries.data[~along], (entries.row[~along], entries.col[~along])), shape=H.shape)


def mortar_contact_set(mortar: MortarMatrices, slave_segment_nodes: np.ndarray, slave_x: np.ndarray,
                       surface: MasterSurface, n_dofs: int, slave_surface: MasterSurface | None = None) -> ContactSet:
    """The contact set of every slave node of ``mortar`` (pure NumPy; the same on every rank), rows in
    ``mortar.slave_nodes``' order (a node with ``D_jj = 0`` gets an empty row: select the others with
    :meth:`ContactSet.subset`). Dual multipliers only (D diagonal).

    Contact j's relative position is the weighted gap and the weighted relative tangential displacement divided by
    ``D_jj``, in the master's frame at the slave node (n_j, t_j) (3D: (n_j, t1_j, t2_j); the abscissa is then the
    position along the reference frame's t1, as node-to-face's): n_j the master's unit outward normal at the node's
    closest master point and t_j as :meth:`MasterSurface.frames` makes it, the frame node-to-segment/face pairing
    gives the node (:func:`find_pairs`). Not the slave's averaged normal (``MortarMatrices.normals``): on a curved
    slave it tilts by x/R from the contact plane, and the Coulomb law applied about it is off by O(a/R) (row 58 of
    the validation page). The gap is weighted along the same n_j:

        x^j = [n_j; t_j] (u_j - sum_l w_jl u_l) + g0_j,    w_jl = M_jl / D_jj,    g0_j = (x_j - sum_l w_jl x_l) . n_j,

    with ``sum_l w_jl = 1`` (so a rigid translation of both bodies leaves x^j unchanged whatever n_j: the patch
    test). The contact force r_j is then ``D_jj`` times the multiplier (a nodal force, as with
    node-to-segment pairing), the slave node gets ``r_j`` and master node l ``-w_jl r_j``: the nodal forces of the
    traction ``sum_j lambda_j psi_j``. The tributary measure is ``D_jj`` (the slave hat's measure over the part facing
    the master), so the pressure read, force over tributary, is the multiplier ``lambda_j`` itself.

    Args:
        mortar: The mortar matrices (``multipliers="dual"``) of the slave segments and the master surface.
        slave_segment_nodes, slave_x: (f, 2) the slave segments' global nodes and (f, 2, 2) their end points; 3D
            (f, 4) the slave faces' (a triangle's fourth -1) and (f, 4, 3) their vertices.
        surface: The master surface (its nodes the columns of ``mortar.M``).
        n_dofs: Global number of displacement dofs (the columns of H).
        slave_surface: The slave segments (faces) as a surface (their nodes, reference points, vertex counts and
            inside points): held by the set (:attr:`ContactSet.slave_surface`, with each node's own measure) for
            finite sliding's re-pairing; None: not held.

    Raises:
        ValueError: if ``mortar`` is not dual, or a facing slave node's closest master point has a normal opposed to
            the slave's (the master folds back over it).
    """
    if mortar.multipliers != "dual":
        raise ValueError(f"mortar_contact_set: multipliers = {mortar.multipliers!r}: the nodal contact solvers need "
                         "the dual ones (D diagonal)")
    dim = mortar.normals.shape[1]
    nodes = mortar.slave_nodes
    coords = np.zeros((nodes.size, dim))
    real = slave_segment_nodes.ravel() >= 0   # 3D: a triangle's fourth label is -1
    coords[np.searchsorted(nodes, slave_segment_nodes.ravel()[real])] = slave_x.reshape(-1, dim)[real]
    master_coords = np.zeros((mortar.master_nodes.size, dim))
    real = surface.nodes.ravel() >= 0
    master_coords[np.searchsorted(mortar.master_nodes, surface.nodes.ravel()[real])] = surface.x.reshape(-1, dim)[real]
    measure = mortar.D.diagonal()
    scale = np.divide(1.0, measure, out=np.zeros_like(measure), where=measure > 0)
    weights = sp.csr_matrix(sp.diags(scale) @ mortar.M)
    weights.sort_indices()
    # The frames are the master's, as node-to-segment/face pairing's (find_pairs): n the master's outward normal at
    # the slave node's closest point. The slave's averaged reference normals would tilt every frame of a curved slave
    # by x/R from the contact plane (an O(a/R) error of the Coulomb law that meshes do not reduce); the gap is
    # weighted along the same n, so that x = H u + g0 is one relative position.
    normals = surface.pair(coords)["normal"]
    facing = np.einsum("ij,ij->i", normals, mortar.normals)
    if np.any((measure > 0) & (facing <= 0)):
        node = int(nodes[np.flatnonzero((measure > 0) & (facing <= 0))[0]])
        raise ValueError(f"mortar_contact_set: slave node {node}'s closest master point has a normal that does not "
                         "face the slave's (the master surface folds back there)")
    frames = surface.frames(normals)                                                # (s, dim, dim) rows n, t1[, t2]
    gaps = weighted_relative_displacement(mortar, coords, master_coords, normals) * scale
    master_nodes, master_weights = _padded_rows(weights, mortar.master_nodes)
    master_points = np.asarray(weights @ master_coords)
    return ContactSet(dim=dim, global_nodes=nodes, coords=coords, frames=frames, gap0=gaps, tributary=measure,
                      abscissa=coords @ surface.reference_frame[1] if dim == 3 else np.einsum("ij,ij->i", coords,
                                                                                              frames[:, 1]),
                      H=_mortar_rows(nodes, frames, master_nodes, master_weights, measure, n_dofs),
                      master_nodes=master_nodes,
                      master_weights=master_weights, master_points=master_points,
                      master_sizes=mortar.master_sizes, master_faces=None, master_surface=surface,
                      slave_surface=slave_surface,
                      slave_areas=None if slave_surface is None else slave_surface.node_measures(nodes),
                      paired_separation=coords - master_points)


def _padded_rows(weights: sp.csr_matrix, master_nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each row's master nodes (``master_nodes`` at the columns of ``weights``, sorted rows) and weights, padded with
    -1 and 0 to the widest row."""
    rows = weights.shape[0]
    counts = np.diff(weights.indptr)
    width = max(int(counts.max(initial=0)), 1)
    nodes = np.full((rows, width), -1, dtype=np.int64)
    values = np.zeros((rows, width))
    slot = np.arange(weights.indices.size) - np.repeat(weights.indptr[:-1], counts)
    row = np.repeat(np.arange(rows), counts)
    nodes[row, slot] = master_nodes[weights.indices]
    values[row, slot] = weights.data
    return nodes, values


def _mortar_rows(nodes: np.ndarray, frames: np.ndarray, master_nodes: np.ndarray, master_weights: np.ndarray,
                 measure: np.ndarray, n_dofs: int) -> sp.csr_matrix:
    """H of mortar contacts: rows (n, t1[, t2]) of contact j; the slave node's columns, then each master node's with
    -w_jl (a row of a node with ``measure`` 0 is empty)."""
    dim = frames.shape[1]
    node_cols = np.column_stack([nodes, np.where(master_nodes >= 0, master_nodes, nodes[:, None])])
    node_coef = np.column_stack([np.where(measure > 0, 1.0, 0.0), -master_weights])
    vals = frames[:, :, None, :] * node_coef[:, None, :, None]                       # (s, dim, nodes, dim)
    cols = np.broadcast_to(dim * node_cols[:, None, :, None] + np.arange(dim)[None, None, None, :], vals.shape)
    rws = np.broadcast_to(np.arange(nodes.size * dim).reshape(nodes.size, dim, 1, 1), vals.shape)
    H = sp.csr_matrix((vals.ravel(), (rws.ravel(), cols.ravel())), shape=(nodes.size * dim, n_dofs))
    H.eliminate_zeros()
    return H


def mortar_paired_set(pairing: ContactSet, mortar: MortarMatrices) -> ContactSet:
    """The contacts of the mortar contact set ``pairing`` paired anew by the mortar matrices ``mortar`` (finite
    sliding: D and M integrated in the current configuration, :func:`dolfinx_fretting.sliding.repair`). Pure NumPy.

    As :func:`paired_contact_set` does for node pairing, the pairing (each contact's weights ``M_jl / D_jj``, its
    measure ``D_jj`` and master size) is the current configuration's, and everything else is the reference
    configuration's: the slave nodes, their frames (the first pairing's: the master's normals at the nodes' closest
    points in the reference configuration, so a re-pairing does not turn the forces) and the gap ``g0_j = n_j . (X_j -
    sum_l w_jl X_l)``, so that ``x = H u + g0`` is the linearised weighted gap and weighted relative displacement over
    ``D_jj``.

    Args:
        pairing: A mortar contact set (:func:`find_mortar_pairs`): its slave nodes are kept, in order.
        mortar: The mortar matrices of ``pairing.slave_surface`` and (part of) ``pairing.master_surface``
            (dual multipliers), rows every slave node of the segments.

    Raises:
        ValueError: a contact's slave node no longer faces the master (``D_jj = 0``: it has slid off the master's end
            or beyond the sliding reach).
    """
    position = np.searchsorted(mortar.slave_nodes, pairing.global_nodes)
    position = np.minimum(position, mortar.slave_nodes.size - 1)
    measure = np.zeros(pairing.nc)
    found = mortar.slave_nodes[position] == pairing.global_nodes
    measure[found] = mortar.D.diagonal()[position[found]]
    if np.any(measure <= 0):
        c = int(np.flatnonzero(measure <= 0)[0])
        raise ValueError(f"finite sliding (mortar): the slave node of contact {c} (at {pairing.coords[c].tolist()} "
                         "in the reference configuration) no longer faces the master: it has slid off the master "
                         "surface's end or beyond ElasticBody.reach; allowed: a master surface (and reach) that "
                         "covers the whole stroke")
    weights = sp.csr_matrix(sp.diags(1.0 / measure) @ mortar.M[position])
    weights.sort_indices()
    master_nodes, master_weights = _padded_rows(weights, mortar.master_nodes)
    return mortar_rows_set(pairing, master_nodes, master_weights, measure, mortar.master_sizes[position])


def mortar_rows_set(pairing: ContactSet, master_nodes: np.ndarray, master_weights: np.ndarray, measure: np.ndarray,
                    master_sizes: np.ndarray) -> ContactSet:
    """The contacts of the mortar contact set ``pairing`` with the master rows given (each contact's master nodes,
    padded with -1, their weights ``M_jl / D_jj``, ``D_jj`` and the master size): :func:`mortar_paired_set`'s set,
    also what a checkpoint's saved pairing is read back into. Pure NumPy."""
    surface = pairing.master_surface
    labels, first = np.unique(surface.nodes.ravel(), return_index=True)
    first, labels = first[labels >= 0], labels[labels >= 0]
    master_x = surface.x.reshape(-1, surface.dim)[first]
    where = np.searchsorted(labels, np.maximum(master_nodes, 0))
    points = np.einsum("cl,clj->cj", master_weights, master_x[np.minimum(where, labels.size - 1)])
    gaps = np.einsum("cj,cj->c", pairing.coords - points, pairing.frames[:, 0])
    H = _mortar_rows(pairing.global_nodes, pairing.frames, master_nodes, master_weights, measure, pairing.H.shape[1])
    return replace(pairing, gap0=gaps, tributary=measure,
                   H=_drop_symmetry_columns(H, pairing.global_nodes, pairing.dim, pairing.symmetry_axes),
                   master_nodes=master_nodes, master_weights=master_weights, master_points=points,
                   master_sizes=master_sizes)


def pair_with_segments(points: np.ndarray, segments_x: np.ndarray,
                       inside: np.ndarray) -> dict[str, np.ndarray]:
    """Pair each point with the closest point of a set of 2D segments (pure NumPy; :func:`pair_with_faces` in 2D).

    Args:
        points: (n, 2) the slave nodes.
        segments_x: (f, 2, 2) the segments' end points.
        inside: (f, 2) a point inside the body behind each segment (its cell's centroid), to orient the normals.

    Returns:
        ``face`` (n,) the closest segment (the first among equally close ones), ``weights`` (n, 2) on its ends,
        ``point`` (n, 2), ``normal`` (n, 2) the segment's unit normal, pointing out of the body, ``distance`` (n,).
    """
    if segments_x.shape[0] == 0:
        raise ValueError("pair_with_segments: no master segment to pair with")
    A, B = segments_x[:, 0], segments_x[:, 1]
    d = B - A
    L2 = np.einsum("ij,ij->i", d, d)
    points = np.ascontiguousarray(points, dtype=float)
    n = points.shape[0]
    best, xi, distance = np.empty(n, dtype=np.int64), np.empty(n), np.empty(n)
    _closest_segments(points, np.ascontiguousarray(A), np.ascontiguousarray(d), L2, best, xi, distance)
    P = A[best] + xi[:, None] * d[best]
    tang = d[best] / np.sqrt(L2[best])[:, None]
    normal = np.stack([-tang[:, 1], tang[:, 0]], axis=1)
    flip = np.einsum("ij,ij->i", inside[best] - A[best], normal) > 0
    normal[flip] *= -1
    return {"face": best, "weights": np.column_stack([1.0 - xi, xi]), "point": P, "normal": normal,
            "distance": distance}


@numba.njit(cache=True)
def _closest_segments(points: np.ndarray, A: np.ndarray, d: np.ndarray, L2: np.ndarray, best: np.ndarray,
                      xi: np.ndarray, distance: np.ndarray) -> None:
    """For each point, the closest segment ``A + t d`` (the first among equally close ones), its ``t`` and the
    distance: every segment tried (a contact surface's, a few hundred), no search structure. Finite sliding
    pairs anew at almost every increment, where the dense NumPy search cost more than the increment's solve."""
    for p in range(points.shape[0]):
        best[p] = -1
        distance[p] = np.inf
        for s in range(A.shape[0]):
            rx = points[p, 0] - A[s, 0]
            ry = points[p, 1] - A[s, 1]
            t = min(max((rx * d[s, 0] + ry * d[s, 1]) / L2[s], 0.0), 1.0)
            ex = points[p, 0] - (A[s, 0] + t * d[s, 0])
            ey = points[p, 1] - (A[s, 1] + t * d[s, 1])
            dist = np.sqrt(ex * ex + ey * ey)
            if dist < distance[p]:
                best[p], xi[p], distance[p] = s, t, dist


@dataclass(frozen=True)
class MasterSurface:
    """The master body's contact facets, replicated on every rank (pure data): what pairings are searched on.

    Attributes:
        nodes: (f, k) global nodes of each facet (2D: a segment's two; 3D: four, a triangle's fourth -1),
            in the order of the facet's interpolation (:func:`_canonical_face` in 3D).
        x: (f, k, dim) the nodes' reference coordinates (a triangle's fourth repeats its third).
        nv: (f,) nodes per facet (2, 3 or 4).
        inside: (f, dim) a point inside the master behind each facet (its cell's centroid).
        reference_frame: (dim, dim) the obstacle frame; in 3D its t1 projected on a facet is the contact's t1.
    """

    nodes: np.ndarray
    x: np.ndarray
    nv: np.ndarray
    inside: np.ndarray
    reference_frame: np.ndarray

    @property
    def dim(self) -> int:
        return int(self.x.shape[2])

    @functools.cached_property
    def sizes(self) -> np.ndarray:
        """Each facet's size: a segment's length, a face's mean edge length (the scale of re-pairing; computed once:
        finite sliding reads it at every re-pairing)."""
        edges = np.linalg.norm(np.roll(self.x, -1, axis=1) - self.x, axis=2)
        if self.dim == 2:
            return edges[:, 0]
        # Round the facet: a triangle's fourth vertex repeats its third, so its edges 2-3 (length 0) and 3-0
        # (the edge 2-0) add up to its perimeter too.
        return edges.sum(axis=1) / self.nv

    def pair(self, points: np.ndarray, x: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Pair points with the closest point of the facets placed at ``x`` (default: the reference
        configuration): see :func:`pair_with_segments` and :func:`pair_with_faces` (``weights`` has ``k``
        columns)."""
        x = self.x if x is None else x
        if self.dim == 2:
            return pair_with_segments(points, x, self.inside)
        return pair_with_faces(points, x, self.nv, self.inside)

    def reference_geometry(self, faces: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(point, unit outward normal) at the given facets and weights, in the reference configuration."""
        X = self.x[faces]
        point = np.einsum("mi,mij->mj", weights, X)
        if self.dim == 2:
            tang = X[:, 1] - X[:, 0]
            normal = np.stack([-tang[:, 1], tang[:, 0]], axis=1)
        else:
            normal = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
            quad = self.nv[faces] == 4
            if quad.any():
                w = weights[quad]   # bilinear weights (1-xi)(1-eta), xi(1-eta), xi eta, (1-xi) eta
                _, _, dxi, deta = _bilinear(X[quad], w[:, 1] + w[:, 2], w[:, 2] + w[:, 3])
                normal[quad] = np.cross(dxi, deta)
        normal = normal / np.linalg.norm(normal, axis=1)[:, None]
        flip = np.einsum("ij,ij->i", self.inside[faces] - point, normal) > 0
        normal[flip] *= -1
        return point, normal

    def node_measures(self, nodes: np.ndarray) -> np.ndarray:
        """Tributary measure (length in 2D, area in 3D) of each of ``nodes`` on the whole surface: a share of each
        facet's measure per vertex (half a segment; a third of a triangle; a quadrilateral's area by its two
        triangles, a quarter each). 0 for a node of no facet. ``nodes`` sorted."""
        X = self.x
        if self.dim == 2:
            measure = np.linalg.norm(X[:, 1] - X[:, 0], axis=1)
        else:
            tri = 0.5 * np.linalg.norm(np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]), axis=1)
            quad = tri + 0.5 * np.linalg.norm(np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 0]), axis=1)
            measure = np.where(self.nv == 4, quad, tri)
        share = measure / self.nv
        valid = self.nodes >= 0
        owners = self.nodes[valid]
        where = np.searchsorted(nodes, owners)
        inside = (where < nodes.size) & (nodes[np.minimum(where, nodes.size - 1)] == owners)
        areas = np.zeros(nodes.size)
        np.add.at(areas, where[inside], np.broadcast_to(share[:, None], self.nodes.shape)[valid][inside])
        return areas

    def frames(self, normal: np.ndarray) -> np.ndarray:
        """The contacts' frames (n, t1[, t2]) for unit normals: 2D ``t1 = (n_y, -n_x)``; 3D the reference
        frame's t1 projected on the facet, ``t2 = n x t1`` (on a flat master: the reference frame)."""
        if self.dim == 2:
            return np.stack([normal, np.column_stack([normal[:, 1], -normal[:, 0]])], axis=1)
        t1 = self.reference_frame[1] - (normal @ self.reference_frame[1])[:, None] * normal
        t1 /= np.linalg.norm(t1, axis=1)[:, None]
        return np.stack([normal, t1, np.cross(normal, t1)], axis=1)


# Node-to-face (3D) ------------------------------------------------------------------------------------------
def _canonical_face(points: np.ndarray) -> np.ndarray:
    """Order of a facet's 3 or 4 vertices that depends on their coordinates only (so on no partition): the
    lexicographically smallest first; a quadrilateral's then go round the facet (cyclic order, as the bilinear
    map needs), towards the smaller of the first vertex's two neighbours."""
    start = np.lexsort(points.T[::-1])
    if len(points) == 3:
        return start
    v0 = start[0]
    c = points.mean(axis=0)
    n = np.cross(points[start[1]] - points[v0], points[start[2]] - points[v0])
    u = points[v0] - c
    u /= np.linalg.norm(u)
    w = np.cross(n / np.linalg.norm(n), u)
    d = points - c
    angle = np.mod(np.arctan2(d @ w, d @ u), 2 * np.pi)
    angle[v0] = 0.0
    cyc = np.argsort(angle)
    nb1, nb3 = cyc[1], cyc[3]
    if tuple(points[nb3]) < tuple(points[nb1]):  # go round towards the smaller neighbour
        cyc = np.array([cyc[0], cyc[3], cyc[2], cyc[1]])
    return cyc


def _boundary_faces(V, facets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The owned facets of a 3D boundary, gathered on every rank and sorted by position. Collective.

    Returns:
        (global nodes (n, 4) in :func:`_canonical_face` order, -1 as a triangle's fourth; coordinates (n, 4, 3),
        a triangle's fourth repeating its third; number of vertices (n,); the centroid of each facet's cell
        (n, 3), which tells on which side the body lies).
    """
    msh, comm, gdim = V.mesh, V.mesh.comm, V.mesh.geometry.dim
    facets, f_to_c, f_to_v, c_to_v = _owned_facet_topology(msh, facets)
    dof_x = _node_coordinates(V)
    imap = V.dofmap.index_map
    nodes = np.full((facets.size, 4), -1, dtype=np.int64)
    xs = np.zeros((facets.size, 4, gdim))
    nv = np.zeros(facets.size, dtype=np.int64)
    centroids = np.zeros((facets.size, gdim))
    for i, f in enumerate(facets):
        cell = f_to_c.links(f)[0]
        dofs = V.dofmap.cell_dofs(cell)
        vx = msh.geometry.x[_vertex_geometry(msh, f_to_v.links(f)), :gdim]
        local = np.array([int(dofs[np.argmin(np.linalg.norm(dof_x[dofs] - p, axis=1))]) for p in vx])
        order = _canonical_face(dof_x[local])
        local = local[order]
        k = local.size
        nv[i] = k
        nodes[i, :k] = imap.local_to_global(local.astype(np.int32))
        xs[i, :k] = dof_x[local]
        xs[i, k:] = dof_x[local[-1]]
        centroids[i] = msh.geometry.x[_vertex_geometry(msh, c_to_v.links(cell)), :gdim].mean(axis=0)
    gathered = comm.allgather((nodes, xs, nv, centroids))
    nodes, xs, nv, centroids = (np.concatenate([g[k] for g in gathered]) for k in range(4))
    # A partition-free order (by the facet's centroid), so that ties between facets go the same way anywhere.
    mid = np.array([x[:k].mean(axis=0) for x, k in zip(xs, nv)]).reshape(-1, gdim)
    order = np.lexsort(mid.T[::-1]) if mid.size else np.zeros(0, dtype=np.int64)
    return nodes[order], xs[order], nv[order], centroids[order]


def _closest_on_segments(p: np.ndarray, A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closest points of segments AB to points p (rows): (parameter t in [0, 1], point)."""
    d = B - A
    t = np.clip(np.einsum("ij,ij->i", p - A, d) / np.einsum("ij,ij->i", d, d), 0.0, 1.0)
    return t, A + t[:, None] * d


def _closest_on_triangles(p: np.ndarray, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closest points of triangles X (m, 3, 3) to points p (m, 3): (barycentric weights (m, 3), point (m, 3)).

    The projection on the triangle's plane if it falls inside, else the closest of the three edges' points.
    """
    A, B, C = X[:, 0], X[:, 1], X[:, 2]
    e1, e2, r = B - A, C - A, p - A
    g11, g12, g22 = (np.einsum("ij,ij->i", u, v) for u, v in ((e1, e1), (e1, e2), (e2, e2)))
    b1, b2 = np.einsum("ij,ij->i", r, e1), np.einsum("ij,ij->i", r, e2)
    det = g11 * g22 - g12 * g12
    s = (g22 * b1 - g12 * b2) / det
    t = (g11 * b2 - g12 * b1) / det
    weights = np.column_stack([1 - s - t, s, t])
    point = A + s[:, None] * e1 + t[:, None] * e2
    outside = (s < 0) | (t < 0) | (s + t > 1)
    if outside.any():
        o = np.flatnonzero(outside)
        best = np.full(o.size, np.inf)
        for i, j in ((0, 1), (1, 2), (2, 0)):
            tt, pt = _closest_on_segments(p[o], X[o, i], X[o, j])
            dist = np.linalg.norm(p[o] - pt, axis=1)
            better = dist < best
            best[better] = dist[better]
            w = np.zeros((o.size, 3))
            w[:, i], w[:, j] = 1 - tt, tt
            weights[o[better]] = w[better]
            point[o[better]] = pt[better]
    return weights, point


def _bilinear(X: np.ndarray, xi: np.ndarray, eta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Bilinear map of quadrilaterals X (m, 4, 3) (cyclic vertex order: (0,0) (1,0) (1,1) (0,1)) at (xi, eta):
    (weights (m, 4), point, d/dxi, d/deta)."""
    N = np.column_stack([(1 - xi) * (1 - eta), xi * (1 - eta), xi * eta, (1 - xi) * eta])
    x = np.einsum("mi,mij->mj", N, X)
    dxi = (1 - eta)[:, None] * (X[:, 1] - X[:, 0]) + eta[:, None] * (X[:, 2] - X[:, 3])
    deta = (1 - xi)[:, None] * (X[:, 3] - X[:, 0]) + xi[:, None] * (X[:, 2] - X[:, 1])
    return N, x, dxi, deta


def _closest_on_quadrilaterals(p: np.ndarray, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest points of bilinear quadrilaterals X (m, 4, 3) to points p (m, 3): (bilinear weights (m, 4),
    point (m, 3), (xi, eta) (m, 2)).

    Projected Gauss-Newton on ``|x(xi, eta) - p|^2`` over the unit square from its centre: a parameter on a
    bound where the descent direction points outwards stays there and the other one takes its one-dimensional
    step (exact in one or two steps for a flat parallelogram; a few for a warped facet).
    """
    m = p.shape[0]
    xi, eta = np.full(m, 0.5), np.full(m, 0.5)
    for _ in range(60):
        _, x, dxi, deta = _bilinear(X, xi, eta)
        r = p - x
        a11, a12, a22 = (np.einsum("ij,ij->i", u, v) for u, v in ((dxi, dxi), (dxi, deta), (deta, deta)))
        b1, b2 = np.einsum("ij,ij->i", dxi, r), np.einsum("ij,ij->i", deta, r)
        det = a11 * a22 - a12 * a12
        s1 = (a22 * b1 - a12 * b2) / det
        s2 = (a11 * b2 - a12 * b1) / det
        # A parameter on a bound stays there while the descent direction of |x - p|^2 along it points out.
        out1 = ((xi <= 0) & (b1 < 0)) | ((xi >= 1) & (b1 > 0))
        out2 = ((eta <= 0) & (b2 < 0)) | ((eta >= 1) & (b2 > 0))
        s1 = np.where(out1, 0.0, np.where(out2, b1 / a11, s1))
        s2 = np.where(out2, 0.0, np.where(out1, b2 / a22, s2))
        new_xi, new_eta = np.clip(xi + s1, 0.0, 1.0), np.clip(eta + s2, 0.0, 1.0)
        change = max(np.abs(new_xi - xi).max(initial=0.0), np.abs(new_eta - eta).max(initial=0.0))
        xi, eta = new_xi, new_eta
        if change < 1e-15:
            break
    # A parameter within 1e-10 of a bound is on it: a node facing a master node or edge gets exact zeros there
    # (then H does not touch the other nodes, as when the node lies on a symmetry plane).
    xi = np.where(xi < 1e-10, 0.0, np.where(xi > 1 - 1e-10, 1.0, xi))
    eta = np.where(eta < 1e-10, 0.0, np.where(eta > 1 - 1e-10, 1.0, eta))
    N, x, _, _ = _bilinear(X, xi, eta)
    return N, x, np.column_stack([xi, eta])


def pair_with_faces(points: np.ndarray, faces_x: np.ndarray, faces_nv: np.ndarray,
                    inside: np.ndarray) -> dict[str, np.ndarray]:
    """Pair each point with the closest point of a set of triangles and quadrilaterals (pure NumPy).

    Args:
        points: (n, 3) the slave nodes.
        faces_x: (f, 4, 3) facet vertices (triangles: 3 and a repeat; quadrilaterals in cyclic order).
        faces_nv: (f,) 3 or 4.
        inside: (f, 3) a point inside the body behind each facet (its cell's centroid), to orient the normals.

    Returns:
        ``face`` (n,) the closest facet (the first in the given order among equally close ones), ``weights``
        (n, 4) on its vertices (0 on a triangle's fourth), ``point`` (n, 3), ``normal`` (n, 3) the facet's unit
        normal at the point, pointing out of the body, ``distance`` (n,).
    """
    n = points.shape[0]
    centre = np.array([x[:k].mean(axis=0) for x, k in zip(faces_x, faces_nv)]).reshape(-1, 3)
    diam = np.array([np.linalg.norm(x[:k, None] - x[None, :k], axis=2).max() for x, k in zip(faces_x, faces_nv)])
    face = np.zeros(n, dtype=np.int64)
    weights = np.zeros((n, 4))
    point = np.zeros((n, 3))
    distance = np.full(n, np.inf)
    params = np.zeros((n, 2))
    for start in range(0, n, 256):  # chunks: (chunk x facets) distance tables stay small
        stop = min(n, start + 256)
        d_c = np.linalg.norm(points[start:stop, None, :] - centre[None], axis=2)
        # A facet can hold a closer point than the nearest centre's facet only if |p - c_f| - diam_f <= that.
        cand = d_c - diam[None] <= d_c.min(axis=1, keepdims=True) + 1e-12 * diam.max()
        rows, cols = np.nonzero(cand)
        p = points[start + rows]
        w = np.zeros((rows.size, 4))
        x = np.zeros((rows.size, 3))
        tri = faces_nv[cols] == 3
        if tri.any():
            w[tri, :3], x[tri] = _closest_on_triangles(p[tri], faces_x[cols[tri], :3])
        quad = ~tri
        par = np.zeros((rows.size, 2))
        if quad.any():
            w[quad], x[quad], par[quad] = _closest_on_quadrilaterals(p[quad], faces_x[cols[quad]])
        dist = np.linalg.norm(p - x, axis=1)
        # Smallest distance per row; ties (a node facing a shared node or edge) to the first facet.
        order = np.lexsort((cols, dist, rows))
        first = order[np.r_[True, rows[order][1:] != rows[order][:-1]]]
        r = start + rows[first]
        face[r], weights[r], point[r], distance[r], params[r] = cols[first], w[first], x[first], dist[first], par[first]
    # The facet's normal at the point (bilinear: d/dxi x d/deta there), out of the body.
    X = faces_x[face]
    tri = faces_nv[face] == 3
    normal = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    if (~tri).any():
        _, _, dxi, deta = _bilinear(X[~tri], params[~tri, 0], params[~tri, 1])
        normal[~tri] = np.cross(dxi, deta)
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    flip = np.einsum("ij,ij->i", inside[face] - point, normal) > 0
    normal[flip] *= -1
    return {"face": face, "weights": weights, "point": point, "normal": normal, "distance": distance}


def _find_pairs_3d(V, slave_facets: np.ndarray, master_facets: np.ndarray, half_width: float | None,
                   exclude_nodes: np.ndarray | None, reference_frame: np.ndarray | None) -> ContactSet:
    """:func:`find_pairs` in 3D: node-to-face (triangles and quadrilaterals). Collective.

    Each contact's frame is (n, t1, t2): n the master facet's outward normal at the paired point, t1 the
    reference frame's t1 projected on the facet's plane, t2 = n x t1; on a flat master the contacts' frames are
    the reference frame. The window and the order of the contacts are measured in the reference frame's
    tangent plane, as for a rigid plane.
    """
    gdim = 3
    imap = V.dofmap.index_map
    ref = tangent_frame([0.0, 0.0, 1.0]) if reference_frame is None else np.asarray(reference_frame, dtype=float)
    face_nodes, face_x, face_nv, face_inside = _boundary_faces(V, master_facets)
    if face_nodes.shape[0] == 0:
        raise ValueError("contact: the master surface has no facet")
    surface = MasterSurface(face_nodes, face_x, face_nv, face_inside, ref)

    gnodes, coords, trib = _slave_nodes(V, slave_facets, exclude_nodes, _node_coordinates(V))
    if gnodes.size == 0:
        raise ValueError("contact: no slave node on the contact surface")
    # The slave nodes in a partition-free order (by position) before anything depends on their order.
    order = np.lexsort(coords.T[::-1])
    gnodes, coords, trib = gnodes[order], coords[order], trib[order]

    pairs = surface.pair(coords)
    gaps = np.einsum("ij,ij->i", coords - pairs["point"], pairs["normal"])
    in_plane = coords @ ref[1:].T
    distance = np.linalg.norm(in_plane, axis=1)
    closest = coords[np.lexsort((coords[:, 1], coords[:, 0], distance, _tied_gaps(gaps, coords)))[0]]  # ties: the axis
    keep = np.ones(gnodes.size, dtype=bool)
    if half_width is not None:
        keep = np.linalg.norm((coords - closest) @ ref[1:].T, axis=1) <= half_width * (1 + 1e-12)
    if not keep.any():
        raise ValueError("contact: no slave node within the candidate window")
    sel = np.flatnonzero(keep)
    sel = sel[_in_plane_order(in_plane[sel], np.ptp(coords, axis=0).max())]  # along t1, then t2 (as find_candidates)
    contact_set = paired_contact_set(surface, gnodes[sel], coords[sel], trib[sel], in_plane[sel, 0].copy(),
                                     pairs["face"][sel], pairs["weights"][sel], imap.size_global * gdim)
    contact_set.window_centre = closest
    return contact_set


# The public contact object ---------------------------------------------------------------------------------
#: Sliding models of two deformable bodies (:class:`ElasticBody`).
SLIDING = ("small", "finite")
#: :class:`ElasticBody`'s contact formulations: node-to-segment/face pairing, or mortar (2D and 3D).
FORMULATIONS = ("node", "mortar")

@dataclass(frozen=True)
class ElasticBody(Obstacle):
    """A deformable counter-body (the *master*) meshed in the same mesh as the body (the *slave*). 2D or 3D.

    Each slave node of the contact surface is paired with the closest point of the master surface:
    node-to-segment in 2D, node-to-face in 3D (triangles and quadrilaterals, linear and bilinear weights). The
    contacts' frames are the master's: n its outward normal at the paired point, in 3D t1 the obstacle frame's
    t1 projected on the facet.

    Sliding (``sliding``):

    - ``"small"`` (default): the pairing is made once, in the reference configuration, and kept (see
      :func:`find_pairs`); right while the relative slip stays below half a master element (the problem warns
      past it).
    - ``"finite"``: the slave nodes are paired anew, in the current configuration, whenever a node's paired
      master point has moved more than ``repair_slip`` master elements away from the point facing it (checked
      after every committed increment). K is not refactorised: the problem computes K⁻¹ once on the dofs of
      both contact surfaces (the slave nodes and the master facets within ``reach`` of them) and forms W and the
      load responses of each pairing from it (:mod:`dolfinx_fretting.sliding`); the master's share of the wear
      is then kept on the master's nodes, so the scar on the master follows its material points. Elastic
      bodies only; cycles run increment by increment (not in the compiled loop).

    The obstacle's rigid motion ``D`` of :class:`~dolfinx_fretting.problem.FrettingProblem` translates the
    master body as a whole (as if the supports that hold it moved with it; a rigid translation of a body
    held on one face only is stress-free), in the frame of ``normal``: ``D = d_n n + d_t t1``.

    Attributes:
        surface: ``(facet_tags, marker)`` of the master's contact surface.
        normal: Unit normal of the master surface, pointing from the master into the slave body; it fixes
            the frame (n, t1[, t2]) of the obstacle motion and of the total forces (:func:`tangent_frame`). Given as
            any finite non-zero vector, stored divided by its length.
        cells: Local cells of the master body (optional): the displacement recovered by
            :meth:`~dolfinx_fretting.problem.FrettingProblem.displacement` then includes the master's rigid
            motion ``D`` on its nodes.
        sliding: ``"small"`` or ``"finite"`` (above).
        repair_slip: Finite sliding: re-pair when a paired point is this many master elements (facet sizes) away
            from the point facing its slave node, in the contact plane; > 0 and <= 1.
        reach: Finite sliding: how far (length units, in the reference configuration) a slave node may slide
            over the master: the master facets within ``reach`` of a slave candidate enter the surface
            compliance. None: every facet of the master surface. A pairing that would need a facet beyond it
            raises an error.
        formulation: ``"node"`` (default): each slave node paired with the closest master point (above);
            ``"mortar"`` (2D and 3D, small or finite sliding): the segment-to-segment (2D) or face-to-face (3D:
            triangles and quadrilaterals, clipped in each slave face's plane) mortar integrals with dual Lagrange
            multipliers (:mod:`dolfinx_fretting.mortar`, :func:`find_mortar_pairs`): each slave node facing the master
            is a contact whose gap and relative tangential displacement are the weighted ones divided by ``D_jj``, its
            frame the master's at the node's closest point (as node-to-segment/face pairing's, above; not the slave's
            normals, which on a curved slave tilt by x/R from the contact plane), its tributary measure ``D_jj``; the
            pressure read is the multiplier. It passes the contact patch test on non-matching meshes, which
            node-to-segment and node-to-face pairing do not. With friction make the flatter surface the master, in both
            formulations. Without friction make the coarser surface the slave: a finer slave's nodes follow the
            coarser master's chords and their pressures alternate at its node spacing (validation rows 58, 59). With ``sliding = "finite"`` a re-pairing recomputes D and M in the current configuration
            (:func:`dolfinx_fretting.sliding.repair`, no refactorisation), the frames kept; the slave's share of the
            wear is kept on its nodes by their own measure, the master's on the master's nodes.
    """

    surface: tuple
    normal: np.ndarray
    cells: np.ndarray | None = None
    sliding: str = "small"
    repair_slip: float = 0.25
    reach: float | None = None
    formulation: str = "node"

    def __post_init__(self) -> None:
        n = np.asarray(self.normal, dtype=float)
        if n.ndim != 1 or n.size not in (2, 3) or not np.all(np.isfinite(n)) or np.linalg.norm(n) == 0:
            raise ValueError(f"ElasticBody.normal = {self.normal!r}: expected a finite non-zero 2- or 3-vector")
        object.__setattr__(self, "normal", n / np.linalg.norm(n))
        if self.sliding not in SLIDING:
            raise ValueError(f"ElasticBody.sliding = {self.sliding!r}: allowed {', '.join(map(repr, SLIDING))}")
        if not (isinstance(self.repair_slip, (int, float)) and np.isfinite(self.repair_slip)
                and 0 < self.repair_slip <= 1):
            raise ValueError(f"ElasticBody.repair_slip = {self.repair_slip!r}: allowed a finite number > 0 and <= 1 "
                             "(master elements)")
        if self.reach is not None and not (isinstance(self.reach, (int, float)) and np.isfinite(self.reach)
                                           and self.reach > 0):
            raise ValueError(f"ElasticBody.reach = {self.reach!r}: allowed None or a finite length > 0")
        if self.formulation not in FORMULATIONS:
            raise ValueError(f"ElasticBody.formulation = {self.formulation!r}: allowed "
                             f"{', '.join(map(repr, FORMULATIONS))}")

    @property
    def finite_sliding(self) -> bool:
        """``sliding == "finite"``."""
        return self.sliding == "finite"

    @property
    def moved_cells(self) -> np.ndarray | None:
        """:attr:`cells`: the master body's cells, moved by D in the displacement read back."""
        return self.cells

    def check(self, V) -> None:
        """The master surface's marker tags facets (a message naming the markers the tags hold otherwise)."""
        _tagged_facets(self.surface, V.mesh, "ElasticBody.surface")

    def candidates(self, V, facets: np.ndarray, half_width: float | None,
                   exclude_nodes: np.ndarray | None) -> ContactSet:
        """:func:`find_pairs` (or :func:`find_mortar_pairs`): each slave node of ``facets`` paired with the master
        surface. Collective."""
        return self.candidates_held(V, facets, half_width, exclude_nodes, None)

    def candidates_held(self, V, facets: np.ndarray, half_width: float | None, exclude_nodes: np.ndarray | None,
                        held_dofs: np.ndarray | None) -> ContactSet:
        """:meth:`candidates`; mortar's frames keep the rollers' directions (:func:`find_mortar_pairs`'s
        ``held_dofs``). Collective."""
        master_facets = _tagged_facets(self.surface, V.mesh, "ElasticBody.surface")
        if self.formulation == "mortar":
            return find_mortar_pairs(V, facets, master_facets, half_width, exclude_nodes=exclude_nodes,
                                     reference_frame=self.frame, held_dofs=held_dofs)
        return find_pairs(V, facets, master_facets, half_width, exclude_nodes=exclude_nodes,
                          reference_frame=self.frame)


def _resolved_recovery(given: str, V, obstacle: Obstacle) -> str:
    """``pressure_recovery`` with ``"auto"`` resolved: ``"smoothed"`` on tetrahedra against a rigid plane or an elastic
    body (node-to-face or mortar: the cases measured, ``benchmarks/results/tet_pressure.md``), ``"nodal"``
    otherwise."""
    from dolfinx import mesh as dmesh  # lazy: DOLFINx (see the note at the imports)

    if given != "auto":
        return given
    tetrahedra = V.mesh.topology.cell_type == dmesh.CellType.tetrahedron
    return "smoothed" if tetrahedra and isinstance(obstacle, (RigidPlane, ElasticBody)) else "nodal"


def _candidate_surface_mass(V, facets: np.ndarray, contact_set: ContactSet) -> sp.csr_matrix:
    """The P1 mass matrix of the facets of ``facets`` whose every node is a contact of ``contact_set``, in its
    contacts' order (the ``"smoothed"`` recovery's; :func:`~dolfinx_fretting.pressure.surface_mass`). Collective."""
    nodes = _facet_nodes(V, facets)
    order = np.argsort(contact_set.global_nodes)
    sorted_nodes = contact_set.global_nodes[order]
    where = np.clip(np.searchsorted(sorted_nodes, nodes), 0, max(sorted_nodes.size - 1, 0))
    found = (nodes >= 0) & (sorted_nodes[where] == nodes)
    keep = np.all(found | (nodes < 0), axis=1)
    faces = np.where(nodes >= 0, order[where], -1)[keep]
    return surface_mass(faces, contact_set.coords, contact_set.nc)


def _facet_nodes(V, facets: np.ndarray) -> np.ndarray:
    """The global P1 nodes of the owned ones of ``facets``, gathered on every rank: (f, 2) segments in 2D, (f, 4)
    faces in 3D, a quadrilateral's in cyclic order (a triangle's fourth -1). Collective. Vectorised (what the
    smoothed recovery needs of :func:`_boundary_faces`, without its per-facet loop: 1 ms a facet)."""
    from dolfinx import mesh as dmesh  # lazy: DOLFINx (see the note at the imports)

    from ._dolfinx import cell_dofmap, entities_to_geometry, geometry_dofmap  # lazy: DOLFINx (see the imports)

    msh, comm = V.mesh, V.mesh.comm
    fdim = msh.topology.dim - 1
    owned, f_to_c, _, _ = _owned_facet_topology(msh, facets)
    cells = np.array([f_to_c.links(f)[0] for f in owned], dtype=np.int64)
    vertices = 2 if fdim == 1 else (3 if msh.topology.cell_type == dmesh.CellType.tetrahedron else 4)
    # (a rank may own none of the facets: the reshape keeps the width then)
    facet_geometry = np.asarray(entities_to_geometry(msh, fdim, owned)).reshape(owned.size, vertices)
    cell_geometry, cell_dofs = geometry_dofmap(msh)[cells], cell_dofmap(V)[cells]
    # A P1 space and a first-order geometry number a cell's nodes alike (see _node_coordinates).
    slot = np.argmax(cell_geometry[:, None, :] == facet_geometry[:, :, None], axis=2)
    local = np.take_along_axis(cell_dofs, slot, axis=1)
    nodes = V.dofmap.index_map.local_to_global(local.ravel().astype(np.int32)).astype(np.int64).reshape(local.shape)
    width = 2 if fdim == 1 else 4
    if fdim == 2 and nodes.shape[1] == 4:   # DOLFINx's quadrilateral (tensor-product order) to the cyclic one
        nodes = nodes[:, [0, 1, 3, 2]]
    elif fdim == 2:                         # triangles: the fourth -1
        nodes = np.column_stack([nodes, np.full(owned.size, -1, dtype=np.int64)])
    return np.concatenate([g.reshape(-1, width) for g in comm.allgather(nodes.reshape(-1, width))])


def _check_vector_p1(V) -> None:
    """Refuse a space that is not a vector P1 (Lagrange degree 1, one component per space dimension)."""
    from . import _dolfinx as dfx  # lazy: DOLFINx (see the note at the imports)

    gdim = V.mesh.geometry.dim
    degree, family, value_size = dfx.element_degree(V), dfx.element_family(V), dfx.value_size(V)
    if value_size != gdim or V.dofmap.index_map_bs != gdim or family not in ("P", "Q", "Lagrange", "CG") \
            or degree != 1:
        raise ValueError(
            f"Contact: the displacement space must be vector P1 (Lagrange, degree 1, {gdim} components, one "
            f"node per mesh vertex); got family {family!r}, degree {degree}, {value_size} component(s), block size "
            f"{V.dofmap.index_map_bs}. Contact nodes, frames and tributary measures are defined on P1 vertices: "
            "solve on a vector P1 space (a mixed or higher-order space is not supported)")


def _tagged_facets(surface: tuple, msh, name: str) -> np.ndarray:
    """Local facets (owned and ghost) of ``surface = (facet_tags, marker)``. Collective.

    Refuses, before any expensive work, tags that are not facet tags of ``msh``'s dimension, a marker that is not
    an integer, and a marker that tags no facet on any rank; that last message names the markers the tags hold.
    The emptiness is decided on the sum over ranks (a rank may own none of a surface's facets while others do),
    so every rank raises or none does.

    Args:
        surface: ``(facet_tags, marker)``.
        msh: The mesh of the displacement space.
        name: How the message calls the surface (``"surface"``, ``"ElasticBody.surface"``).
    """
    if not (isinstance(surface, tuple) and len(surface) == 2):
        raise TypeError(f"Contact: {name} must be (facet_tags, marker), got {surface!r}")
    facet_tags, marker = surface
    if not all(hasattr(facet_tags, attribute) for attribute in ("find", "dim", "values")):
        raise TypeError(f"Contact: {name}[0] must be DOLFINx facet tags (dolfinx.mesh.MeshTags), got "
                        f"{type(facet_tags).__name__}")
    if isinstance(marker, (bool, np.bool_)) or not isinstance(marker, (int, np.integer)):
        raise TypeError(f"Contact: {name} marker = {marker!r}: expected an integer facet tag")
    fdim = msh.topology.dim - 1
    if facet_tags.dim != fdim:
        raise ValueError(f"Contact: {name}: the tags are of entities of dimension {facet_tags.dim}; the facets of this "
                         f"{msh.topology.dim}D mesh have dimension {fdim} (cell tags given for facet tags?)")
    facets = np.asarray(facet_tags.find(int(marker)), dtype=np.int32)
    comm = msh.comm
    if comm.allreduce(facets.size, op=MPI.SUM) == 0:
        held = sorted(set().union(*comm.allgather({int(v) for v in np.unique(facet_tags.values)})))
        raise ValueError(f"Contact: {name} marker {int(marker)} tags no facet; "
                         + (f"the facet tags hold markers {held}" if held else "the facet tags hold no marker"))
    return facets


def _refuse_fixed_surface(V, facets: np.ndarray, fixed_nodes: np.ndarray, marker: int) -> None:
    """Refuse a contact surface whose every node has all its components fixed (no free vertex). Collective.

    Such a surface cannot move towards the obstacle; without this check the candidate search would find no node
    and fail further on. Decided on the sums over ranks, so every rank raises or none does.
    """
    from dolfinx import fem  # lazy: DOLFINx (see the note at the imports)

    fdim = V.mesh.topology.dim - 1
    nodes = fem.locate_dofs_topological(V, fdim, facets)
    owned = nodes[nodes < V.dofmap.index_map.size_local]  # each node counted once across ranks
    counts = np.array([owned.size, np.setdiff1d(owned, fixed_nodes).size], dtype=np.int64)
    n_nodes, n_free = V.mesh.comm.allreduce(counts, op=MPI.SUM)
    if n_free == 0:
        raise ValueError(f"Contact: surface marker {marker} has no free vertex: bcs fix every component of all its "
                         f"{n_nodes} nodes, so none can move towards the obstacle. Remove the condition from the "
                         "contact surface (or fix fewer components there) or give another marker")


def constrained_dofs(V, bcs) -> np.ndarray:
    """Local unrolled dofs (``bs * node + component``) of ``V`` fixed by ``bcs`` (owned and ghost).

    Args:
        V: The blocked vector space the conditions act on (conditions on ``V.sub(i)`` included).
        bcs: DOLFINx Dirichlet conditions.
    """
    bs = V.dofmap.index_map_bs
    size = (V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts) * bs
    dofs = [np.asarray(bc.dof_indices()[0], dtype=np.int64) for bc in bcs]
    out = np.unique(np.concatenate(dofs)) if dofs else np.zeros(0, dtype=np.int64)
    if out.size and out.max() >= size:
        raise ValueError("Contact: a Dirichlet condition in bcs is not on the displacement space V")
    return out


def constrained_global_dofs(V, bcs) -> np.ndarray:
    """Global PETSc dofs (``bs * global_node + component``) fixed by ``bcs``, the union over ranks. Collective."""
    bs = V.dofmap.index_map_bs
    fixed = constrained_dofs(V, bcs)
    local_nodes = (fixed // bs).astype(np.int32)
    glob = bs * V.dofmap.index_map.local_to_global(local_nodes).astype(np.int64) + fixed % bs
    return np.unique(np.concatenate(V.mesh.comm.allgather(glob)))


class Contact:
    """Frictional contact of the body discretised by ``V`` with an obstacle. Collective to build.

    The DOLFINx idiom of dolfinx_mpc: the user owns mesh, space, forms and boundary conditions; this object
    holds the contact nodes of one tagged boundary, their frames, gaps and tributary measures and the operator
    H (``x = H u + g``, see :mod:`dolfinx_fretting.contact`), identical on every rank.

    Dofs fixed by ``bcs`` are handled exactly: a node whose every component is fixed is never a contact
    candidate (it cannot move); at a node with some components fixed (a roller), those components enter the
    relative positions (their prescribed values) but not the compliance W (``H_free``, H without the fixed
    columns: K has identity rows there, which would add a meaningless unit compliance). A normal direction
    left with no free dof is refused with a message; a tangential one is *held* (:attr:`held_rows`: a node on a
    symmetry plane with its roller, whose normal is one of the frame's tangents): its force stays zero and the
    problem refuses obstacle motions along it (see :class:`~dolfinx_fretting.problem.FrettingProblem`).

    Frames and units: the obstacle frame is ``obstacle.frame``, rows ``(n, t1[, t2])`` with n the obstacle's
    normal divided by its length, pointing from the obstacle into the body, ``t1 = (n_y, -n_x)`` in 2D; in 3D
    t1 the coordinate axis least aligned with n made orthogonal to it, and ``t2 = n x t1`` (see
    :func:`tangent_frame`: ``n = (0, 0, 1)`` gives ``t1 = (1, 0, 0)``, ``t2 = (0, 1, 0)``). Per-contact forces
    ``r`` and relative positions are in each contact's own frame (``contact_set.frames``: the obstacle frame for a
    rigid plane, the master facet's for an elastic body, whose 3D t1 is the obstacle frame's t1 projected on the
    facet).

    Against a rigid plane the normal and tangential problems are coupled (Dundurs' β ≠ 0): the stick zone of
    a partial-slip contact is not Cattaneo–Mindlin's; see "Frames and units" in ``docs/api.md``.

    Args:
        V: Vector P1 displacement space (anything else is refused).
        surface: ``(facet_tags, marker)``: the body's boundary that may touch the obstacle.
        obstacle: An :class:`Obstacle`: :class:`RigidPlane` (2D or 3D, any orientation) or :class:`ElasticBody` (2D
            or 3D).
        mu: The friction law (:class:`~dolfinx_fretting.laws.FrictionLaw`, e.g.
            :class:`~dolfinx_fretting.laws.Coulomb`, or :class:`~dolfinx_fretting.laws.EvolvingFriction`: a
            coefficient of the cycles or of the dissipated energy), or Coulomb's coefficient (finite, >= 0): one
            value or one per contact.
        bcs: The Dirichlet conditions of the problem (their dofs are excluded as above).
        window: Candidate half-width (length units): only nodes within this distance, measured in the
            obstacle's tangent plane, of the body point closest to the obstacle; ``None``: every node of
            ``surface``. The nodes of ``surface`` outside the window are not left unwatched: after every
            increment the problem checks that none of them penetrates the obstacle, and raises
            :class:`~dolfinx_fretting.state.WindowError` (naming the window needed) if one does.
        grow_window: Instead of raising, let :meth:`~dolfinx_fretting.problem.FrettingProblem.advance` and
            :meth:`~dolfinx_fretting.problem.FrettingProblem.run_cycle` widen the window to the one needed and
            solve the increment (or cycle) again (a RuntimeWarning says so). Elastic bodies with a fixed pairing:
            an elastic-plastic or finite-sliding problem cannot change its window and raises.
        pressure_recovery: How the pressure and shear a user reads (``contact_fields``, ``max_pressure``, the
            profiles and maps) are recovered from the nodal contact forces (:mod:`dolfinx_fretting.pressure`):
            ``"nodal"``, force over tributary measure; ``"smoothed"``, those nodal values of the loaded nodes
            smoothed by two sweeps of the lumped L2 projection over the loaded facets; ``"auto"`` (default):
            ``"smoothed"`` on tetrahedra against a :class:`RigidPlane` or an :class:`ElasticBody` (node-to-face or
            mortar), where the nodal values scatter node to node (measured against Hertz, the pressure and
            Cattaneo-Mindlin's shear, ``benchmarks/results/tet_pressure.md``), ``"nodal"`` otherwise (hexahedra:
            within 0.1 % of Hertz; 2D as validated). The contact problem, the wear
            and the total forces do not depend on it.

    Attributes:
        contact_set: The :class:`ContactSet` (nodes, frames, gaps, tributary measures, H).
        outside: The free nodes of ``surface`` outside the window (a :class:`ContactSet`, paired with the master
            like the candidates for an :class:`ElasticBody`), or None (no window, or none outside it).
        H_free: H without the columns of fixed dofs (what W is built from).
        held_rows: Rows of H (``dim c + k``, k >= 1) whose every dof is fixed (their free entries, if any, rounding:
            below 1e-12 of the row's largest): held tangential directions.
        friction: The friction law (``Coulomb(mu)`` when ``mu`` was a number).
        mu: Friction coefficient per contact (the law's; an evolving law's at the start: a state's are
            :func:`dolfinx_fretting.friction.coefficients`).
        pressure_recovery: The recovery in use, ``"nodal"`` or ``"smoothed"`` (``"auto"`` resolved).

    Raises:
        TypeError: ``surface`` (or ``ElasticBody.surface``) is not ``(facet tags, integer marker)``, or the
            obstacle is of another type.
        ValueError: before any candidate search, on every rank alike: tags that are not of facets; a marker
            (the body's, or the master's of an :class:`ElasticBody`) that tags no facet on any rank, the message
            naming the markers the tags hold; a surface with no free vertex (every component of every node fixed
            by ``bcs``); a non-P1 space, a normal of the wrong dimension, a bad ``mu`` or ``window``, a bad
            ``pressure_recovery`` or a mesh whose facets are not of one type (prisms, pyramids). After it: no
            candidate within ``window``, or a contact whose normal direction ``bcs`` fix entirely.
    """

    def __init__(self, V, surface: tuple, obstacle: Obstacle, mu: float | np.ndarray | FrictionLaw,
                 bcs=(), window: float | None = None, grow_window: bool = False, pressure_recovery: str = "auto"):
        if not isinstance(pressure_recovery, str) or pressure_recovery not in RECOVERIES:
            raise ValueError(f"Contact: pressure_recovery = {pressure_recovery!r}: allowed "
                             f"{', '.join(map(repr, RECOVERIES))}")
        # Facets of one type the surface mass and the tributary measures integrate (a prism mesh would fail later in
        # a reshape or in DOLFINx's facet integrals)
        check_surface_cells(V.mesh.topology.cell_type.name, pressure_recovery)
        _check_vector_p1(V)
        if not isinstance(obstacle, Obstacle):
            raise TypeError(f"Contact: obstacle must be an Obstacle (a RigidPlane, an ElasticBody, or a shape of "
                            f"dolfinx_fretting.obstacles.OBSTACLES), got {type(obstacle).__name__}")
        gdim = V.mesh.geometry.dim
        if obstacle.normal.size != gdim:
            raise ValueError(f"Contact: the obstacle normal has {obstacle.normal.size} components, the mesh is {gdim}D")
        if window is not None and not (np.isfinite(window) and window > 0):
            raise ValueError(f"Contact: window = {window!r}: expected a finite half-width > 0 or None")
        # A friction law, or the values of Coulomb's (numbers: a string or None is not read as one), checked now;
        # their number, one per contact, once the contacts are known.
        if isinstance(mu, FrictionLaw):
            friction = mu
        else:
            try:
                mu_values = np.asarray(mu)
            except ValueError:  # a ragged list
                mu_values = np.array(np.nan)
            if mu_values.dtype.kind not in "iuf" or mu_values.ndim > 1 or not np.all(np.isfinite(mu_values)) \
                    or np.any(mu_values < 0):
                raise ValueError(f"Contact: mu = {mu!r}: expected a finite value >= 0 (or one per contact), or a "
                                 "friction law (dolfinx_fretting.laws.Coulomb)")
            friction = Coulomb(mu)
        if not isinstance(grow_window, (bool, np.bool_)):
            raise TypeError(f"Contact: grow_window = {grow_window!r}: expected True or False")
        self.V, self.surface, self.obstacle, self.window = V, surface, obstacle, window
        self.grow_window = bool(grow_window)
        self._recovery_given = pressure_recovery
        self.pressure_recovery = _resolved_recovery(pressure_recovery, V, obstacle)
        self.bcs = list(bcs)
        self._mu_given = mu
        # The surfaces and their free vertices are checked (a few reductions) before any candidate search.
        self.facets = _tagged_facets(surface, V.mesh, "surface")
        obstacle.check(V)
        bs = V.dofmap.index_map_bs
        fixed = constrained_dofs(V, self.bcs)
        counts = np.bincount(fixed // bs, minlength=0)
        self.fixed_nodes = np.flatnonzero(counts == bs).astype(np.int32)  # local blocks with every component fixed
        _refuse_fixed_surface(V, self.facets, self.fixed_nodes, int(surface[1]))
        self.fixed_global = constrained_global_dofs(V, self.bcs)
        def search(half_width: float | None) -> ContactSet:
            return obstacle.candidates_held(V, self.facets, half_width, self.fixed_nodes, self.fixed_global)

        contact_set = search(window)
        if self.pressure_recovery == "smoothed":
            contact_set.surface_mass = _candidate_surface_mass(V, self.facets, contact_set)
        self._use(contact_set)
        #: The window's centre (kept here: a pairing made anew under finite sliding does not carry it).
        self.window_centre = contact_set.window_centre
        # The surface's other free nodes: a second search of the whole surface (the candidates' own search is left
        # as it was, so a window's contact set keeps its bits), less the candidates.
        self.outside: ContactSet | None = None
        if window is not None:
            whole = search(None)
            rest = np.flatnonzero(~np.isin(whole.global_nodes, contact_set.global_nodes))
            if rest.size:
                self.outside = whole.subset(rest)
        self.friction: FrictionLaw = friction
        try:
            mu_arr = np.asarray(friction.coefficients(contact_set.nc), dtype=float)
        except ValueError:
            mu_arr = np.array(np.nan)
        if mu_arr.shape != (contact_set.nc,) or not np.all(np.isfinite(mu_arr)) or np.any(mu_arr < 0):
            raise ValueError(f"Contact: mu = {mu!r}: expected a finite value >= 0 (or one per contact, "
                             f"{contact_set.nc})")
        self.mu = mu_arr

    def _use(self, contact_set: ContactSet) -> None:
        """Hold ``contact_set``: its H without the fixed columns and its held rows (see the class's docstring)."""
        self.contact_set: ContactSet = contact_set
        H = contact_set.H.tocsr()
        free = np.ones(H.shape[1])
        free[self.fixed_global] = 0.0
        # H's entries at the free columns (the product H diag(free) without forming it: finite sliding holds a new
        # pairing at almost every increment)
        self.H_free = sp.csr_matrix((H.data * free[H.indices], H.indices.copy(), H.indptr.copy()), shape=H.shape)
        # A row whose every free entry is rounding (below 1e-12 of the row's largest entry, fixed columns included)
        # touches held dofs only: a slave node on a symmetry plane paired with a master vertex there gets
        # interpolation weights of ~1e-14 on the vertex's neighbours off the plane (measured 6.6e-15 on gmsh
        # tetrahedra), which would leave its compliance along the plane's normal at ~1e-29 instead of held.
        row_of = np.repeat(np.arange(H.shape[0]), np.diff(H.indptr))
        row_scale = np.zeros(H.shape[0])
        np.maximum.at(row_scale, row_of, np.abs(H.data))
        free_row = np.repeat(np.arange(H.shape[0]), np.diff(self.H_free.indptr))
        significant = np.abs(self.H_free.data) > 1e-12 * row_scale[free_row]
        rounding_only = np.bincount(free_row[significant], minlength=H.shape[0]) == 0
        self.H_free.data[rounding_only[free_row]] = 0.0
        self.H_free.eliminate_zeros()
        empty = np.diff(self.H_free.indptr) == 0
        normal_rows = np.arange(empty.size) % contact_set.dim == 0
        if (empty & normal_rows).any():
            row = int(np.flatnonzero(empty & normal_rows)[0])
            c = row // contact_set.dim
            raise ValueError(
                f"Contact: direction n of contact {c} (node at {contact_set.coords[c].tolist()}) has every dof fixed "
                "by bcs: "
                "the contact cannot move that way. Remove the node from the contact surface or the condition from bcs")
        # Rows (dim c + k) of the tangential directions held by bcs: every dof of the row is fixed, as at a node on a
        # symmetry plane with its roller (the plane's normal is then one of the contact's tangents). Their contact
        # force is zero (by symmetry, in a half model); FrettingProblem gives them a positive compliance so that
        # the local problem stays well posed, and refuses an obstacle motion along them.
        self.held_rows = np.flatnonzero(empty & ~normal_rows)

    def with_pairing(self, contact_set: ContactSet) -> Contact:
        """The same contact with the same slave nodes paired anew (finite sliding: :class:`ElasticBody`'s
        ``sliding = "finite"``): a shallow copy holding ``contact_set``. Not collective."""
        if not (contact_set.two_body and np.array_equal(contact_set.global_nodes, self.contact_set.global_nodes)):
            raise ValueError("Contact.with_pairing: the pairing must be of the same slave nodes, in the same order")
        other = copy.copy(self)
        other._use(contact_set)
        return other

    @property
    def frame(self) -> np.ndarray:
        """Rows (n, t1[, t2]) of the obstacle frame (the directions of the obstacle motion and total forces)."""
        return self.obstacle.frame

    @property
    def nc(self) -> int:
        """Number of contact nodes."""
        return self.contact_set.nc

    @property
    def dim(self) -> int:
        """Components per contact (the space dimension)."""
        return self.contact_set.dim

    # The obstacle's motion and forces (the protocol :class:`~dolfinx_fretting.zones.ContactZones` shares) -----
    @property
    def zones(self) -> tuple[Contact, ...]:
        """The contact zones of the problem: this contact alone."""
        return (self,)

    @property
    def obstacle_size(self) -> int:
        """Components of the obstacle's motion (:attr:`~dolfinx_fretting.state.ContactState.obstacle`): n, t1[, t2]."""
        return self.dim

    def translations(self, obstacle: np.ndarray) -> np.ndarray:
        """The obstacle's rigid translation D (global frame) from its components ``obstacle`` in the obstacle frame
        (the last axis: approach along n, then t1[, t2]); leading axes kept (e.g. a cycle's increments)."""
        obstacle = np.asarray(obstacle, dtype=float)
        frame = self.frame
        D = obstacle[..., :1] * frame[0]
        for k in range(1, frame.shape[0]):
            D = D + obstacle[..., k:k + 1] * frame[k]
        return D

    def rigid_motion(self, obstacle: np.ndarray) -> np.ndarray:
        """Each contact's local relative displacement (m,) when the obstacle moves by ``obstacle`` (its frame):
        ``G D``, G = :attr:`ContactSet.rigid_modes`, D = :meth:`translations` (the local problem's ``q`` has
        minus this)."""
        return self.contact_set.rigid_modes @ self.translations(obstacle)

    @property
    def rigid_modes(self) -> np.ndarray:
        """G of the compiled cycles: (m, dim) local relative displacement per unit global translation of the
        obstacle (:meth:`translations` gives the translations it multiplies)."""
        return self.contact_set.rigid_modes

    def obstacle_forces(self, forces: np.ndarray, contact_set: ContactSet | None = None) -> np.ndarray:
        """The total contact force on the body along each obstacle component (n, t1[, t2]) from the contact forces
        ``forces`` (of ``contact_set``, default the one held)."""
        contact_set = self.contact_set if contact_set is None else contact_set
        F = contact_set.total_force(forces)
        return np.array([F @ self.frame[k] for k in range(self.dim)])

    def held_components(self, contact_set: ContactSet | None = None) -> np.ndarray:
        """Which obstacle components (bool, (dim,)) have a component along a direction the conditions hold
        (:attr:`held_rows`)."""
        contact_set = self.contact_set if contact_set is None else contact_set
        held_dirs = contact_set.frames.reshape(-1, self.dim)[self.held_rows]
        return np.abs(held_dirs @ self.frame.T).max(axis=0, initial=0.0) > 1e-9

    def component_names(self) -> list[str]:
        """The obstacle components' names in messages: ``normal``, ``tangential t1`` ..."""
        return ["normal"] + [f"tangential t{k}" for k in range(1, self.dim)]

    def zone_slice(self, zone: int) -> slice:
        """The contacts of zone ``zone`` (0: every contact)."""
        return slice(0, self.nc)

    def zone_set(self, zone: int) -> ContactSet:
        """Zone ``zone``'s contact set (0: the one held)."""
        return self.contact_set

    @property
    def windows(self) -> tuple[float | None, ...]:
        """The candidate window of each zone (one)."""
        return (self.window,)

    @property
    def outside_zone(self) -> np.ndarray:
        """The zone of each node of :attr:`outside` (all 0)."""
        return np.zeros(0 if self.outside is None else self.outside.nc, dtype=int)

    def outside_distance(self) -> np.ndarray:
        """Each node of :attr:`outside`'s in-plane distance from the window's centre."""
        return self.window_distance(self.outside)

    def outside_motion(self) -> np.ndarray:
        """(k, dim): each node of :attr:`outside`'s normal displacement per unit obstacle component."""
        return self.outside.frames[:, 0, :] @ self.frame.T

    def with_window(self, window: float | None, zone: int = 0) -> Contact:
        """The same contact with another candidate window (collective; ``zone`` must be 0, the only one)."""
        if zone != 0:
            raise ValueError(f"zone = {zone}: a single Contact is zone 0")
        return Contact(self.V, self.surface, self.obstacle, self._mu_given, self.bcs, window, self.grow_window,
                       self._recovery_given)

    def window_distance(self, contact_set: ContactSet) -> np.ndarray:
        """In-plane distance of ``contact_set``'s nodes from the window's centre, measured as the candidate search
        measures
        it: in the obstacle's tangent plane (a node-to-segment pairing in 2D: along each node's own tangent)."""
        offset = contact_set.coords - self.window_centre
        if contact_set.two_body and contact_set.dim == 2:
            return np.abs(np.einsum("ij,ij->i", offset, contact_set.frames[:, 1]))
        return np.linalg.norm(offset @ self.frame[1:].T, axis=1)
