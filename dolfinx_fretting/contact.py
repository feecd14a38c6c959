"""Node-to-rigid contact: candidate nodes, local frames, the operator H and the initial gap.

For each candidate node alpha the local relative position is (paper eqs 1, 3)

    x^alpha = H_alpha u + g^alpha,    H_alpha = [n; t1; (t2)]  acting on the node's displacement,

ordered (n, t1[, t2]) per contact like FCLIB/Siconos, so ``r^alpha = (r_n, r_t...)`` and the nodal force
on the body is ``R^alpha = H_alpha^T r^alpha``. Nothing here assumes two dimensions: the frames, the
window and the tributary measures work for gdim = 2 or 3.

The contact set is replicated on every MPI rank (it is small: tens to a few thousand nodes) and ordered
by position along the surface, so the local problem is the same whatever the partition.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

__all__ = ["RigidPlane", "ContactSet", "find_candidates", "tangent_frame"]


def tangent_frame(normal: np.ndarray) -> np.ndarray:
    """Orthonormal frame with rows (n, t1[, t2]) for a unit normal in 2D or 3D.

    In 2D ``t1 = (n_y, -n_x)`` (so ``n = (0, 1)`` gives ``t1 = (1, 0)``); in 3D ``t1`` is the coordinate
    axis least aligned with ``n``, orthogonalised, and ``t2 = n x t1``.
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


@dataclass(frozen=True)
class RigidPlane:
    """A rigid plane through ``point`` whose unit ``normal`` points from the plane into the body."""

    point: np.ndarray
    normal: np.ndarray

    def __post_init__(self) -> None:
        n = np.asarray(self.normal, dtype=float)
        if n.ndim != 1 or n.size not in (2, 3) or np.linalg.norm(n) == 0:
            raise ValueError(f"plane normal must be a non-zero 2- or 3-vector, got {self.normal!r}")
        if np.asarray(self.point).shape != n.shape:
            raise ValueError("plane point and normal must have the same dimension")
        object.__setattr__(self, "normal", n / np.linalg.norm(n))
        object.__setattr__(self, "point", np.asarray(self.point, dtype=float))

    @property
    def frame(self) -> np.ndarray:
        return tangent_frame(self.normal)

    def gap(self, coords: np.ndarray) -> np.ndarray:
        """Signed normal distance of points (rows of ``coords``) from the plane."""
        return (np.asarray(coords) - self.point) @ self.normal


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

    @property
    def nc(self) -> int:
        return int(self.global_nodes.size)

    @property
    def rigid_modes(self) -> np.ndarray:
        """(nc*dim, dim) matrix: local relative displacement per unit rigid translation of the body.

        Its transpose sums local contact forces into the total global force on the body,
        ``F = rigid_modes.T @ r``.
        """
        return self.frames.reshape(self.nc * self.dim, self.dim)

    def total_force(self, r: np.ndarray) -> np.ndarray:
        """Total contact force on the body in global coordinates."""
        return self.rigid_modes.T @ r


def _tributary_measure(V, facets: np.ndarray, fdim: int) -> np.ndarray:
    """Lumped boundary measure per node: assemble the integral of each P1 hat function over ``facets``."""
    import ufl
    from dolfinx import fem, mesh as dmesh
    from petsc4py import PETSc

    msh = V.mesh
    Q = fem.FunctionSpace(msh, ("Lagrange", 1))
    tags = dmesh.meshtags(msh, fdim, facets, np.ones(facets.size, dtype=np.int32))
    ds = ufl.Measure("ds", domain=msh, subdomain_data=tags)
    b = fem.petsc.assemble_vector(fem.form(ufl.TestFunction(Q) * ds(1)))
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    b.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    with b.localForm() as loc:
        values = loc.array.copy()
    b.destroy()
    return values


def find_candidates(V, facets: np.ndarray, obstacle: RigidPlane, half_width: float | None = None,
                    exclude_nodes: np.ndarray | None = None) -> ContactSet:
    """Choose candidate nodes on a boundary and build their frames, gaps and H. Collective.

    Candidates are the nodes of ``facets`` within ``half_width`` (measured in the plane) of the body
    point closest to the obstacle; with ``half_width=None`` every node of ``facets``.

    Args:
        V: Vector P1 displacement space (DOLFINx 0.5 ``VectorFunctionSpace``).
        facets: Local indices of the boundary facets that may touch the obstacle (sorted, unique).
        obstacle: The rigid plane.
        half_width: Window half-width (mm) around the closest point, or None.
        exclude_nodes: Local block indices of nodes with prescribed displacement (never candidates:
            K has identity rows there).

    Returns:
        The contact set, identical on every rank.

    Raises:
        ValueError: if no candidate is found, or the dimensions disagree.
    """
    from dolfinx import fem

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
    coords = V.tabulate_dof_coordinates()[nodes, :gdim]
    gaps = obstacle.gap(coords)

    # Point of the surface closest to the obstacle (the first point of contact), on every rank.
    local_min = (gaps.min(), *coords[np.argmin(gaps)]) if nodes.size else (np.inf,) + (0.0,) * gdim
    all_min = comm.allgather(local_min)
    closest = np.array(min(all_min, key=lambda t: t[0])[1:])
    frame = obstacle.frame
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
    order = np.lexsort(tuple(in_plane[:, k] for k in reversed(range(gdim - 1))))
    gnodes, coords, gaps, trib, in_plane = (a[order] for a in (gnodes, coords, gaps, trib, in_plane))

    nc = gnodes.size
    frames = np.broadcast_to(frame, (nc, gdim, gdim)).copy()
    rows = np.repeat(np.arange(nc * gdim), gdim)
    cols = (bs * np.repeat(gnodes, gdim * gdim).reshape(nc, gdim, gdim)
            + np.arange(gdim)[None, None, :]).ravel()
    n_global = imap.size_global * bs
    H = sp.csr_matrix((frames.ravel(), (rows, cols)), shape=(nc * gdim, n_global))
    return ContactSet(dim=gdim, global_nodes=gnodes, coords=coords, frames=frames, gap0=gaps,
                      tributary=trib, abscissa=in_plane[:, 0].copy(), H=H)

