"""The contact pressure (and shear) a user reads, recovered from the nodal contact forces (pure NumPy/SciPy).

The contact problem is solved for nodal forces ``r`` (one per contact node, in its frame (n, t1[, t2])); the
traction a user reads (``contact_fields()["pressure"]``, ``max_pressure``, the profiles and maps) is recovered from
them in one of two ways, :attr:`~dolfinx_fretting.contact.Contact.pressure_recovery`:

- ``"nodal"``: the force over the node's tributary measure A (the lumped integral of its P1 hat function over the
  contact surface), ``p_j = r_n,j / A_j``.
- ``"smoothed"``: the nodal values ``q = r / A`` of the loaded nodes (``r_n > 0``) smoothed by two sweeps of the
  lumped L2 projection of their P1 field onto P1 over the loaded part of the surface:

      p_L = (D_L^-1 M_LL)^2 q_L,    p = 0 at open nodes,

  with M the P1 mass matrix (``int phi_i phi_j``) of the contact's surface facets, M_LL its rows and columns of the
  loaded nodes and D_L the row sums of M_LL. Each sweep is a weighted average with positive weights (half on the
  node itself on a regular patch), so a uniform traction stays uniform to rounding (the patch tests), the pressure
  stays >= 0 and, with a uniform mu, Coulomb's ``|shear| <= mu p`` holds for the smoothed values as it does for the
  nodal ones; and ``sum_L D_L p_L = sum_L D_L q_L`` (the M-weighted integral is kept).

Why: on unstructured tetrahedra the nodal forces of node-to-rigid contact scatter from node to node, and so does
``r / A`` (a sphere's cap on a rigid plane, a/h = 12-16: +4.0 ... +5.7 % at the peak, 7-10 % at single nodes, RMS
2.6-4.0 % within 0.8a); the L2 projection with the consistent mass matrix, ``M^-1 r``, amplifies that scatter
(+11 ... +25 % at the peak), while the smoothing above gives the peak within 0.4 % and the RMS within 1 % of Hertz at
a/h >= 12 (``benchmarks/results/tet_pressure.md``). Against an elastic body on tetrahedra (node-to-face or mortar,
non-matching faces) the nodal values scatter more (RMS 2.5-8.7 % of Hertz's p0 within 0.8a) and the smoothed ones
are 3-5 times closer (0.5-2.3 %), the shear likewise (Cattaneo-Mindlin's: 7-11 % against 3-4 % of mu p0). The
wear law and the cycle jumps keep using the nodal ``r / A`` (Archard's worn volume is the sum of the nodal ``A dg``,
whatever is read).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["RECOVERIES", "CELL_FACETS", "SURFACE_FACETS", "check_surface_cells", "surface_mass", "smoothed_tractions"]

#: The values of :class:`~dolfinx_fretting.contact.Contact`'s ``pressure_recovery``: ``"auto"`` is
#: ``"smoothed"`` on a tetrahedral mesh against a rigid plane or an elastic body (node-to-face or mortar; measured
#: there) and ``"nodal"`` otherwise.
RECOVERIES = ("auto", "nodal", "smoothed")

#: The facet types of each cell type (DOLFINx's names): a prism's and a pyramid's are of two types.
CELL_FACETS = {"interval": ("point",), "triangle": ("segment",), "quadrilateral": ("segment",),
               "tetrahedron": ("triangle",), "hexahedron": ("quadrilateral",),
               "prism": ("triangle", "quadrilateral"), "pyramid": ("triangle", "quadrilateral")}

#: The facets :func:`surface_mass` integrates (and the tributary measures are computed on): of one type each mesh.
SURFACE_FACETS = ("segment", "triangle", "quadrilateral")


def check_surface_cells(cell_type: str, recovery: str) -> None:
    """Refuse a mesh whose contact facets are not of one type :func:`surface_mass` integrates, before any work.

    Args:
        cell_type: The mesh's cell type (DOLFINx's name: ``"tetrahedron"``, ``"prism"`` ...).
        recovery: ``pressure_recovery`` as given (named in the message).

    Raises:
        ValueError: cells of mixed facet types (prisms, pyramids) or of facets that are not segments, triangles or
            quadrilaterals; the message names ``pressure_recovery``, its value, the facet types found and those
            allowed.
    """
    facets = CELL_FACETS.get(cell_type)
    if facets is not None and len(facets) == 1 and facets[0] in SURFACE_FACETS:
        return
    found = " and ".join(f"{name}s" for name in facets) if facets else "facets of an unknown type"
    raise ValueError(
        f"Contact: pressure_recovery = {recovery!r} on a mesh of {cell_type} cells, whose facets are {found}: the "
        f"contact surface must be of one facet type, {', '.join(SURFACE_FACETS)} (2D meshes of triangles or "
        "quadrilaterals: segments; tetrahedra: triangles; hexahedra: quadrilaterals). No recovery is supported on "
        "it ('smoothed' integrates the surface mass over those facets, 'nodal' the tributary measures): mesh the "
        "contact body with tetrahedra or hexahedra")


# Gauss points (2 x 2) of the reference square [0, 1]^2: exact for the bilinear shapes' products times the
# Jacobian of a bilinear (warped) quadrilateral, of degree 3 in each direction.
_GAUSS = 0.5 + np.array([-1.0, 1.0]) / (2 * np.sqrt(3.0))


def surface_mass(faces: np.ndarray, coords: np.ndarray, size: int) -> sp.csr_matrix:
    """The P1 mass matrix ``M_ij = int phi_i phi_j`` over a surface of segments (2D), triangles or bilinear
    quadrilaterals (3D).

    Args:
        faces: (f, 2) segments, or (f, 4) faces whose vertices are indices into ``coords`` (a quadrilateral's in
            cyclic order; a triangle's fourth -1).
        coords: (n, dim) the vertices' coordinates.
        size: The matrix's size (>= the largest index + 1).

    Returns:
        (size, size) symmetric, its row sums the lumped measures of the vertices.
    """
    faces = np.asarray(faces, dtype=np.int64)
    coords = np.asarray(coords, dtype=float)
    blocks: list[tuple[np.ndarray, np.ndarray]] = []   # (vertices (k, m), local matrices (k, m, m))
    if faces.shape[1] == 2:
        length = np.linalg.norm(coords[faces[:, 1]] - coords[faces[:, 0]], axis=1)
        blocks.append((faces, length[:, None, None] * (np.ones((2, 2)) + np.eye(2)) / 6))
    else:
        triangles = faces[faces[:, 3] < 0, :3]
        x = coords[triangles]
        area = 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)
        blocks.append((triangles, area[:, None, None] * (np.ones((3, 3)) + np.eye(3)) / 12))
        quads = faces[faces[:, 3] >= 0]
        x = coords[quads]
        local = np.zeros((quads.shape[0], 4, 4))
        for xi in _GAUSS:
            for eta in _GAUSS:
                shapes = np.array([(1 - xi) * (1 - eta), xi * (1 - eta), xi * eta, (1 - xi) * eta])
                d_xi = np.array([-(1 - eta), 1 - eta, eta, -eta])
                d_eta = np.array([-(1 - xi), -xi, xi, 1 - xi])
                jacobian = np.linalg.norm(np.cross(d_xi @ x, d_eta @ x), axis=1)   # (q,) the area element
                local += 0.25 * jacobian[:, None, None] * np.outer(shapes, shapes)[None]
        blocks.append((quads, local))
    rows = np.concatenate([np.repeat(v, v.shape[1], axis=1).ravel() for v, _ in blocks])
    cols = np.concatenate([np.tile(v, (1, v.shape[1])).ravel() for v, _ in blocks])
    values = np.concatenate([m.ravel() for _, m in blocks])
    return sp.csr_matrix((values, (rows, cols)), shape=(size, size))


def smoothed_tractions(forces: np.ndarray, tributary: np.ndarray, mass: sp.csr_matrix,
                       sweeps: int = 2) -> np.ndarray:
    """The ``"smoothed"`` tractions of nodal contact forces (see the module).

    Args:
        forces: (..., nc, dim) contact forces per contact, (n, t1[, t2]); leading axes: increments.
        tributary: (nc,) the tributary measures A (the nodal values are ``forces / A``).
        mass: (nc, nc) the P1 mass matrix of the contact's surface facets (:func:`surface_mass`).
        sweeps: The number of smoothing sweeps (2: measured, ``benchmarks/results/tet_pressure.md``).

    Returns:
        (..., nc, dim) tractions: 0 at the open contacts (``r_n <= 0``), the smoothed values at the loaded ones.
    """
    forces = np.asarray(forces, dtype=float)
    out = np.zeros_like(forces)
    flat_forces, flat_out = forces.reshape(-1, *forces.shape[-2:]), out.reshape(-1, *forces.shape[-2:])
    for r, t in zip(flat_forces, flat_out):
        loaded = np.flatnonzero(r[:, 0] > 0)
        if loaded.size == 0:
            continue
        block = mass[loaded][:, loaded]
        measure = np.asarray(block.sum(axis=1)).ravel()
        # a loaded node none of whose facets has only loaded nodes keeps its nodal value
        measure_safe = np.where(measure > 0, measure, 1.0)
        values = r[loaded] / tributary[loaded, None]
        for _ in range(sweeps):
            values = np.where(measure[:, None] > 0, (block @ values) / measure_safe[:, None], values)
        t[loaded] = values
    return out
