"""Areas and lengths of a 2D mesh's cells and tagged facets, computed with numpy from the vertices (no form
compilation) and summed over owned entities only, so that the same code gives global values under MPI. Used by
tests/test_meshes.py, in its own process and in the child it starts under mpiexec."""

import numpy as np
from mpi4py import MPI

from dolfinx_fretting import _dolfinx as dfx


def cell_polygons(msh) -> np.ndarray:
    """(owned cells, k, 2) vertex coordinates of first-order cells in boundary order."""
    tdim = msh.topology.dim
    n = msh.topology.index_map(tdim).size_local
    dofmap = dfx.geometry_dofmap(msh)[:n]
    if dofmap.shape[1] == 4:  # DOLFINx quadrilaterals are tensor-ordered: 0 1 / 2 3
        dofmap = dofmap[:, [0, 1, 3, 2]]
    return msh.geometry.x[dofmap][:, :, :2]


def signed_areas(p: np.ndarray) -> np.ndarray:
    """Shoelace areas of polygons (n, k, 2); positive when counter-clockwise."""
    q = np.roll(p, -1, axis=1)
    return 0.5 * np.sum(p[:, :, 0] * q[:, :, 1] - q[:, :, 0] * p[:, :, 1], axis=1)


def area(msh) -> float:
    """The mesh's area (collective)."""
    return msh.comm.allreduce(float(np.abs(signed_areas(cell_polygons(msh))).sum()), op=MPI.SUM)


def facet_segments(body, name, owned_only=True) -> np.ndarray:
    """(n, 2, 2) end points of the facets of a tag or zone (owned facets only by default)."""
    msh = body.mesh
    fdim = msh.topology.dim - 1
    facets = body.facets(name)
    if owned_only:
        facets = facets[facets < msh.topology.index_map(fdim).size_local]
    if facets.size == 0:
        return np.zeros((0, 2, 2))
    nodes = dfx.entities_to_geometry(msh, fdim, facets)
    return msh.geometry.x[nodes][:, :, :2]


def length(body, name) -> float:
    """The length of the facets of a tag or zone (collective)."""
    seg = facet_segments(body, name)
    return body.mesh.comm.allreduce(float(np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1).sum()), op=MPI.SUM)


def max_chord(body, name) -> float:
    """The longest facet of a tag or zone (collective)."""
    seg = facet_segments(body, name)
    local = float(np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1).max()) if len(seg) else 0.0
    return body.mesh.comm.allreduce(local, op=MPI.MAX)
