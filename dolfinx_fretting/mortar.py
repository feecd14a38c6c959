"""Mortar integrals of two contact surfaces: 2D of linear segments, 3D of triangles and quadrilaterals (pure NumPy;
no mesh).

For a slave surface and a master surface, each a set of straight two-node segments (3D: faces, below), this module
computes the mortar matrices of the segment-to-segment method (Puso & Laursen, CMAME 193, 2004; with dual Lagrange
multipliers: Wohlmuth, SIAM J. Numer. Anal. 38, 2000; Popp, Gee & Wall, IJNME 79, 2009):

    D_jk = integral over the slave surface of  phi_j N_k,       M_jl = integral over the slave surface of  phi_j N^m_l,

``N_k`` the slave's hat functions, ``N^m_l`` the master's (taken at the master point facing each slave point), and
``phi_j`` the multiplier's shape function of slave node j: the dual (biorthogonal) ``psi_j`` or the standard
``N_j``. The weighted gap and the weighted relative displacement of slave node j are then

    g_j = sum_k D_jk (x_k . n_j) - sum_l M_jl (x_l . n_j),     s_j = sum_k D_jk (u_k . t_j) - sum_l M_jl (u_l . t_j).

Projection and clipping. Each slave segment is integrated over the part of it that faces the master: the master
segments' end points are projected orthogonally onto the slave segment's line (along the slave segment's own
normal; on a flat interface this is exact), their parameter interval is clipped to [0, 1], and on each non-empty
overlap sub-segment the integrands are integrated by Gauss–Legendre quadrature. A slave point at parameter xi faces
the master point at parameter eta, affine in xi on one overlap, so every integrand is a quadratic polynomial and
two Gauss points integrate it exactly. Only master segments facing the slave segment (normals opposed) count; the
master must not fold over itself as seen from a slave segment (no double cover).

Dual multipliers and the partial segments. On a slave segment wholly facing the master, ``psi_1 = 2 N_1 - N_2``
and ``psi_2 = 2 N_2 - N_1`` (biorthogonal: ``integral psi_i N_k = delta_ik integral N_k``). A slave segment only
partly facing the master (at the master's end, or where the slave surface overhangs it) gets the dual functions of
its facing part (the consistent treatment of partial segments: Cichosz & Bischoff, CMAME 200, 2011; Popp, Seitz,
Gee & Wall, CMAME 264, 2013): ``psi_i = sum_k A_ik N_k`` with ``A = diag(d) Me^-1``, ``Me_ik`` and ``d_k`` the
integrals of ``N_i N_k`` and ``N_k`` over the facing part only, so that biorthogonality holds where the constraint
is integrated; the ratios ``M_jl / D_jj`` stay bounded as the facing part shrinks (they tend to the weights that
extrapolate the master's segment to the slave node: 13/3 and -10/3 for a master segment 0.3 long). D stays diagonal, ``D_jj`` is the measure of
slave node j's hat function over the facing part, and every row of M sums to ``D_jj`` (the master's hats sum to one):
the weighted gap does not change under a rigid translation of both bodies, and a uniform multiplier gives the
master the nodal forces of a uniform traction (the patch test). The slave surface's end nodes need no boundary
modification here: they keep their own multiplier (a node whose hat faces no master at all, ``D_jj = 0``, has no
constraint). Segments facing the master over less than :data:`MIN_FACING` of their length are left out
(their facing part is a point, its mass matrix singular).

Standard multipliers (``multipliers="standard"``) give the consistent D (not diagonal) of the same facing parts,
for comparison; the package's nodal contact solvers need the dual ones.

3D: faces. Surfaces of triangles (linear shape functions) and quadrilaterals (bilinear, vertices in cyclic order)
are integrated face against face in an auxiliary plane (Puso & Laursen, CMAME 193, 2004; Popp, Gee & Wall, IJNME
83, 2010): the plane of each slave face (through its vertices' centroid, normal to the face at its centre), onto
which the slave face and every nearby master face facing it (normals opposed) are projected along that normal; the
master polygon is clipped by the slave polygon (Sutherland–Hodgman; both convex) and the overlap triangulated from
its vertices' centroid. On each triangle a slave and a master point face each other along the normal: the face
parameters of a plane point are found by inverting each face's map in the plane (affine for a triangle, Newton for
a quadrilateral). Quadrature: Radon's seven-point rule of degree 5 on each triangle, exact for the degree-4 products
of two bilinear shape functions where those are polynomials of the plane's coordinates (triangles and
parallelograms; on a general quadrilateral, whose inverse map is not polynomial, it approximates, as in the
references). The plane's area element is corrected to the slave surface's (a warped quadrilateral). Dual functions
as in 2D, ``psi_i = sum_k A_ik N_k``, ``A = diag(d) Me^-1`` from the face's own mass matrix over its facing part
(on a whole face: ``psi_i = 4 N_i - 1`` on a triangle, ``4 N_1 - 2 N_2 + N_3 - 2 N_4`` on a parallelogram); a face
facing the master over less than :data:`MIN_FACING` of its area is left out. Nodal normals: minus the normalised
sum of the unit outward normals (at the face centres) of the slave faces meeting at the node; tangents: ``t1`` a
reference direction projected on the node's tangent plane, ``t2 = n x t1`` (the node-to-face rule,
:meth:`~dolfinx_fretting.contact.MasterSurface.frames`). The master must not fold over itself as seen from a slave
face.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

__all__ = ["MortarMatrices", "MULTIPLIERS", "MIN_FACING", "mortar_matrices", "slave_normals", "weighted_gaps",
           "weighted_relative_displacement"]

#: The multipliers' shape functions: biorthogonal (``"dual"``, D diagonal) or the slave's hats (``"standard"``).
MULTIPLIERS = ("dual", "standard")
#: A slave segment facing the master over less than this fraction of its length is left out of the integrals.
MIN_FACING = 1e-9
#: Two-point Gauss–Legendre rule on [0, 1]: exact for the quadratic integrands (see the module's docstring).
GAUSS_POINTS = 0.5 + np.array([-0.5, 0.5]) / np.sqrt(3.0)
GAUSS_WEIGHTS = np.array([0.5, 0.5])


@dataclass(frozen=True)
class MortarMatrices:
    """The mortar matrices of a slave and a master surface (see the module).

    Attributes:
        slave_nodes: (s,) the slave nodes (their labels as given, sorted): the rows of D and M.
        master_nodes: (m,) the master nodes (sorted): the columns of M.
        D: (s, s) sparse; diagonal for dual multipliers.
        M: (s, m) sparse.
        normals: (s, dim) each slave node's unit normal, pointing from the master into the slave (minus the
            average of the unit outward normals of the slave segments or faces meeting at the node). The package's
            contact frames are the master's instead (:func:`~dolfinx_fretting.contact.mortar_contact_set`).
        tangents: 2D (s, 2) ``t = (n_y, -n_x)``; 3D (s, 2, 3) ``t1`` the reference tangent projected on the node's
            tangent plane, ``t2 = n x t1`` (the package's frames,
            :meth:`~dolfinx_fretting.contact.MasterSurface.frames`).
        master_sizes: (s,) the mean length of the master segments facing each slave node's segments, weighted by the
            facing length (0 where none faces it): the scale of the small-sliding limit.
        multipliers: ``"dual"`` or ``"standard"``.
    """

    slave_nodes: np.ndarray
    master_nodes: np.ndarray
    D: sp.csr_matrix
    M: sp.csr_matrix
    normals: np.ndarray
    tangents: np.ndarray
    master_sizes: np.ndarray
    multipliers: str

    @property
    def frames(self) -> np.ndarray:
        """(s, dim, dim) each slave node's frame, rows (n, t1[, t2])."""
        tangents = self.tangents if self.tangents.ndim == 3 else self.tangents[:, None, :]
        return np.concatenate([self.normals[:, None, :], tangents], axis=1)


def _segment_normals(x: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """(f, 2) unit normals of segments with ends ``x`` (f, 2, 2), pointing out of the body (away from ``inside``)."""
    tangent = x[:, 1] - x[:, 0]
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]]) / np.linalg.norm(tangent, axis=1)[:, None]
    flip = np.einsum("ij,ij->i", inside - x[:, 0], normal) > 0
    normal[flip] *= -1
    return normal


def slave_normals(segment_nodes: np.ndarray, segment_x: np.ndarray, inside: np.ndarray,
                  nodes: np.ndarray) -> np.ndarray:
    """Each of ``nodes``' averaged contact normal (2D): minus the normalised sum of the unit outward normals of the
    slave segments that meet at the node, so pointing from the master into the slave.

    Args:
        segment_nodes: (f, 2) the slave segments' node labels.
        segment_x: (f, 2, 2) their end points.
        inside: (f, 2) a point inside the slave behind each segment (orients the outward normals).
        nodes: (s,) the node labels wanted (each must belong to a segment).
    """
    outward = _segment_normals(segment_x, inside)
    position = np.searchsorted(nodes, segment_nodes)
    total = np.zeros((nodes.size, 2))
    for end in (0, 1):
        np.add.at(total, position[:, end], outward)
    length = np.linalg.norm(total, axis=1)
    if np.any(length == 0):
        raise ValueError("mortar: a slave node joins two segments whose outward normals cancel (the slave surface "
                         "folds back on itself there)")
    return -total / length[:, None]


def _on_symmetry_planes(normals: np.ndarray, nodes: np.ndarray, symmetry: np.ndarray) -> np.ndarray:
    """``normals`` (rows: ``nodes``, sorted) with each (node, axis) pair of ``symmetry``'s component along the axis
    dropped and the row normalised again: the unit normal of the sum of the faces' normals and their mirror images'
    (the whole model's averaged normal)."""
    if symmetry.size == 0:
        return normals
    rows = np.minimum(np.searchsorted(nodes, symmetry[:, 0]), nodes.size - 1)
    found = nodes[rows] == symmetry[:, 0]
    out = normals.copy()
    out[rows[found], symmetry[found, 1]] = 0.0
    changed = np.unique(rows[found])
    length = np.linalg.norm(out[changed], axis=1)
    if np.any(length < 1e-8):
        node = int(nodes[changed[np.flatnonzero(length < 1e-8)[0]]])
        raise ValueError(f"mortar: slave node {node}'s normal lies along its symmetry axis (the surface meets its "
                         "symmetry plane at a right angle there, not along it): a roller there cannot be a symmetry "
                         "condition of the contact")
    out[changed] /= length[:, None]
    return out


def _overlaps(slave_x: np.ndarray, slave_out: np.ndarray, master_x: np.ndarray,
              master_out: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The facing (slave segment, master segment) pairs and their overlap on the slave segment: ``(slave, master,
    xi_start, xi_end)``, the master's ends projected orthogonally on the slave segment's line, clipped to [0, 1]."""
    start, direction = slave_x[:, 0], slave_x[:, 1] - slave_x[:, 0]
    length2 = np.einsum("ij,ij->i", direction, direction)
    # dense (slave x master segments): both are one contact surface's, small
    xi = np.einsum("smij,sj->smi", master_x[None, :, :, :] - start[:, None, None, :], direction) / length2[:, None,
                                                                                                         None]
    low = np.clip(xi.min(axis=2), 0.0, 1.0)
    high = np.clip(xi.max(axis=2), 0.0, 1.0)
    facing = slave_out @ master_out.T < 0.0
    slave, master = np.nonzero(facing & (high > low))
    return slave, master, low[slave, master], high[slave, master]


def mortar_matrices(slave_segment_nodes: np.ndarray, slave_x: np.ndarray, slave_inside: np.ndarray,
                    master_segment_nodes: np.ndarray, master_x: np.ndarray, master_inside: np.ndarray,
                    multipliers: str = "dual", reference_tangent: np.ndarray | None = None,
                    slave_reference_x: np.ndarray | None = None,
                    symmetry_axes: np.ndarray | None = None) -> MortarMatrices:
    """The mortar matrices D and M of two surfaces: 2D of linear segments, 3D of triangles and bilinear
    quadrilaterals (see the module; 3D when the points have three coordinates).

    Args:
        slave_segment_nodes, master_segment_nodes: (f, 2) each segment's node labels (integers; a label shared by two
            segments is one node); 3D: (f, 4) each face's, a triangle's fourth -1, a quadrilateral's in cyclic order.
        slave_x, master_x: (f, 2, 2) the segments' end points, in the order of their labels; 3D (f, 4, 3) the faces'
            vertices (a triangle's fourth any point, unused).
        slave_inside, master_inside: (f, dim) a point inside each body behind each facet (its cell's centroid).
        multipliers: ``"dual"`` (D diagonal) or ``"standard"``.
        reference_tangent: 3D: the direction whose projection on each slave node's tangent plane is its first
            tangent (the second ``n x t1``), as the node-to-face frames
            (:meth:`~dolfinx_fretting.contact.MasterSurface.frames`); default x. 2D: unused.
        slave_reference_x: The slave segments' (faces') points in the reference configuration, shaped as
            ``slave_x``, or None (``slave_x``). Finite sliding places the surfaces where they are now (``slave_x``,
            ``master_x``: which parts face each other) and measures the integrals with each slave segment's length
            (face's area) here, so that D and M are of the reference configuration's measure, as the stiffness is.
        symmetry_axes: (k, 2) integer pairs (slave node label, coordinate axis): the node lies on a symmetry plane
            normal to that axis (a roller holds its displacement along it); its averaged normal drops its component
            along the axis, as the mirrored faces of the whole model would cancel it, so that its frame holds the
            axis (a half model's nodes on the plane). Pairs naming no slave node are ignored.

    Returns:
        The matrices, rows the slave nodes of every segment given (a node facing no master has an empty row and
        ``D_jj = 0``).

    Raises:
        ValueError: ``multipliers`` not one of :data:`MULTIPLIERS`, arrays of the wrong shapes, a segment of zero
            length or a face of zero area, a slave node's normal along its symmetry axis, or (3D) a reference
            tangent along a slave node's normal.
    """
    if multipliers not in MULTIPLIERS:
        raise ValueError(f"mortar: multipliers = {multipliers!r}: allowed {', '.join(map(repr, MULTIPLIERS))}")
    symmetry = np.zeros((0, 2), dtype=np.int64) if symmetry_axes is None else np.asarray(symmetry_axes)
    dim = np.shape(slave_x)[-1]
    if symmetry.ndim != 2 or symmetry.shape[1] != 2 or (symmetry.size and (
            symmetry.dtype.kind not in "iu" or symmetry[:, 1].min() < 0 or symmetry[:, 1].max() >= dim)):
        raise ValueError(f"mortar: symmetry_axes of shape {symmetry.shape}: expected (k, 2) integer pairs (slave node, "
                         f"axis 0 .. {dim - 1})")
    if np.shape(slave_x)[-1:] == (3,):
        tangent = np.asarray(reference_tangent if reference_tangent is not None else [1.0, 0.0, 0.0], dtype=float)
        if tangent.shape != (3,) or not np.all(np.isfinite(tangent)):
            raise ValueError(f"mortar: reference_tangent = {reference_tangent!r}: expected a finite 3-vector")
        return _mortar_matrices_3d(np.asarray(slave_segment_nodes, dtype=np.int64), np.asarray(slave_x, dtype=float),
                                   np.asarray(slave_inside, dtype=float),
                                   np.asarray(master_segment_nodes, dtype=np.int64), np.asarray(master_x, dtype=float),
                                   np.asarray(master_inside, dtype=float), multipliers, tangent, symmetry,
                                   None if slave_reference_x is None else np.asarray(slave_reference_x, dtype=float))
    slave_segment_nodes = np.asarray(slave_segment_nodes, dtype=np.int64)
    master_segment_nodes = np.asarray(master_segment_nodes, dtype=np.int64)
    slave_x, master_x = np.asarray(slave_x, dtype=float), np.asarray(master_x, dtype=float)
    for name, labels, x, inside in (("slave", slave_segment_nodes, slave_x, slave_inside),
                                    ("master", master_segment_nodes, master_x, master_inside)):
        f = labels.shape[0]
        if labels.shape != (f, 2) or x.shape != (f, 2, 2) or np.shape(inside) != (f, 2) or f == 0:
            raise ValueError(f"mortar: the {name} segments: expected (f, 2) labels, (f, 2, 2) end points and (f, 2) "
                             f"inside points, f > 0; got {labels.shape}, {x.shape}, {np.shape(inside)}")
        if np.any(np.linalg.norm(x[:, 1] - x[:, 0], axis=1) == 0):
            raise ValueError(f"mortar: a {name} segment has zero length")
    if slave_reference_x is not None and np.shape(slave_reference_x) != slave_x.shape:
        raise ValueError(f"mortar: slave_reference_x has the shape {np.shape(slave_reference_x)}, slave_x "
                         f"{slave_x.shape}: expected the same")
    slave_nodes = np.unique(slave_segment_nodes)
    master_nodes = np.unique(master_segment_nodes)
    slave_out = _segment_normals(slave_x, np.asarray(slave_inside, dtype=float))
    master_out = _segment_normals(master_x, np.asarray(master_inside, dtype=float))
    seg, mseg, low, high = _overlaps(slave_x, slave_out, master_x, master_out)

    reference = slave_x if slave_reference_x is None else np.asarray(slave_reference_x, dtype=float)
    slave_length = np.linalg.norm(reference[:, 1] - reference[:, 0], axis=1)   # the measure integrated with
    master_length = np.linalg.norm(master_x[:, 1] - master_x[:, 0], axis=1)
    # Gauss points of every overlap: slave parameter xi, weight (length units), the slave and master hats there.
    xi = low[:, None] + (high - low)[:, None] * GAUSS_POINTS[None, :]                      # (p, g)
    weight = (slave_length[seg] * (high - low))[:, None] * GAUSS_WEIGHTS[None, :]          # (p, g)
    slave_hats = np.stack([1.0 - xi, xi], axis=2)                                          # (p, g, 2)
    # The master point facing slave point xi projects orthogonally on the slave line at xi:
    # (P + eta d_m - A) . d_s = xi |d_s|^2.
    d_slave = slave_x[seg, 1] - slave_x[seg, 0]
    d_master = master_x[mseg, 1] - master_x[mseg, 0]
    offset = np.einsum("ij,ij->i", master_x[mseg, 0] - slave_x[seg, 0], d_slave)
    eta = (xi * np.einsum("ij,ij->i", d_slave, d_slave)[:, None] - offset[:, None]) \
        / np.einsum("ij,ij->i", d_master, d_slave)[:, None]
    master_hats = np.stack([1.0 - eta, eta], axis=2)                                       # (p, g, 2)

    # Each slave segment's facing part: its mass matrix there; segments facing too little are dropped.
    n_seg = slave_x.shape[0]
    mass = np.zeros((n_seg, 2, 2))
    np.add.at(mass, seg, np.einsum("pg,pgi,pgk->pik", weight, slave_hats, slave_hats))
    facing = np.zeros(n_seg)
    np.add.at(facing, seg, high - low)
    used = facing >= MIN_FACING
    if multipliers == "dual":   # psi_i = sum_k A_ik N_k, A = diag(d) Me^-1, d_k = integral N_k = Me's row sums
        coefficients = np.zeros((n_seg, 2, 2))
        coefficients[used] = mass[used].sum(axis=2)[:, :, None] * np.linalg.inv(mass[used])
    else:
        coefficients = np.broadcast_to(np.eye(2), (n_seg, 2, 2)).copy()
        coefficients[~used] = 0.0
    shape = np.einsum("pik,pgk->pgi", coefficients[seg], slave_hats)                        # phi_i at the points

    row_of = np.searchsorted(slave_nodes, slave_segment_nodes)                              # (f, 2)
    col_of = np.searchsorted(master_nodes, master_segment_nodes)
    keep = used[seg]
    local = np.einsum("pg,pgi,pgl->pil", weight, shape, master_hats)[keep]                   # (p, 2, 2)
    rows = np.broadcast_to(row_of[seg[keep]][:, :, None], local.shape).ravel()
    cols = np.broadcast_to(col_of[mseg[keep]][:, None, :], local.shape).ravel()
    n_slave = slave_nodes.size
    M = sp.csr_matrix((local.ravel(), (rows, cols)), shape=(n_slave, master_nodes.size))
    # D: phi_i N_k over the facing parts. Dual: diagonal, D_jj = integral psi_j = integral psi_j sum_l N^m_l, M's row
    # sum (equal to the integral of N_j by biorthogonality), so that the weights M_jl / D_jj sum to one to rounding
    # even where Me is ill-conditioned (a sliver facing the master: Me^-1 loses digits as 1/facing^2).
    if multipliers == "dual":
        D = sp.csr_matrix(sp.diags(np.asarray(M.sum(axis=1)).ravel()))
        D.eliminate_zeros()
    else:
        rows = np.repeat(row_of[used], 2, axis=1).ravel()
        cols = np.tile(row_of[used], (1, 2)).ravel()
        D = sp.csr_matrix((mass[used].ravel(), (rows, cols)), shape=(n_slave, n_slave))

    # The master segments' mean size seen by each slave node, weighted by the facing length.
    size_sum, size_weight = np.zeros(n_slave), np.zeros(n_slave)
    facing_length = (slave_length[seg] * (high - low))[keep]
    for end in (0, 1):
        np.add.at(size_sum, row_of[seg[keep], end], facing_length * master_length[mseg[keep]])
        np.add.at(size_weight, row_of[seg[keep], end], facing_length)
    sizes = np.divide(size_sum, size_weight, out=np.zeros(n_slave), where=size_weight > 0)
    normals = _on_symmetry_planes(slave_normals(slave_segment_nodes, slave_x, np.asarray(slave_inside, dtype=float),
                                                slave_nodes), slave_nodes, symmetry)
    tangents = np.column_stack([normals[:, 1], -normals[:, 0]])
    return MortarMatrices(slave_nodes, master_nodes, D, M, normals, tangents, sizes, multipliers)


def weighted_relative_displacement(mortar: MortarMatrices, slave_values: np.ndarray, master_values: np.ndarray,
                                   direction: np.ndarray) -> np.ndarray:
    """``sum_k D_jk (a_k . e_j) - sum_l M_jl (b_l . e_j)`` for each slave node j.

    Args:
        mortar: The matrices.
        slave_values: (s, 2) a vector per slave node (:attr:`MortarMatrices.slave_nodes`' order).
        master_values: (m, 2) a vector per master node.
        direction: (s, 2) the direction e_j of each slave node (its normal, its tangent).
    """
    def product(matrix: sp.csr_matrix, values: np.ndarray) -> np.ndarray:
        entries = matrix.tocoo()
        projected = np.einsum("ei,ei->e", values[entries.col], direction[entries.row])
        return np.bincount(entries.row, weights=entries.data * projected, minlength=matrix.shape[0])

    direction = np.asarray(direction, dtype=float)
    return product(mortar.D, np.asarray(slave_values, dtype=float)) \
        - product(mortar.M, np.asarray(master_values, dtype=float))


def weighted_gaps(mortar: MortarMatrices, slave_points: np.ndarray, master_points: np.ndarray) -> np.ndarray:
    """The weighted gap ``g_j = sum_k D_jk (x_k . n_j) - sum_l M_jl (x_l . n_j)`` of each slave node (length x
    measure: divided by ``D_jj`` it is a distance for dual multipliers), positive open.

    Args:
        mortar: The matrices.
        slave_points: (s, 2) the slave nodes' positions (:attr:`MortarMatrices.slave_nodes`' order).
        master_points: (m, 2) the master nodes' positions.
    """
    return weighted_relative_displacement(mortar, slave_points, master_points, mortar.normals)


# 3D: faces (triangles and bilinear quadrilaterals) -------------------------------------------------------------------
#: A degree-5 rule on the triangle (Radon's seven points; Stroud T2:5-1), barycentric points and weights summing to
#: one: exact for the degree-4 products of two bilinear (or linear) shape functions over a triangle of the overlap
#: polygon wherever the faces' shape functions are polynomials of the auxiliary plane's coordinates (triangles,
#: parallelograms: exact; a general quadrilateral's inverse map is not polynomial and the rule then approximates).
_RADON_A, _RADON_B = (6.0 - np.sqrt(15.0)) / 21.0, (6.0 + np.sqrt(15.0)) / 21.0
TRIANGLE_POINTS = np.array([[1 / 3, 1 / 3, 1 / 3],
                            [_RADON_A, _RADON_A, 1 - 2 * _RADON_A], [_RADON_A, 1 - 2 * _RADON_A, _RADON_A],
                            [1 - 2 * _RADON_A, _RADON_A, _RADON_A],
                            [_RADON_B, _RADON_B, 1 - 2 * _RADON_B], [_RADON_B, 1 - 2 * _RADON_B, _RADON_B],
                            [1 - 2 * _RADON_B, _RADON_B, _RADON_B]])
TRIANGLE_WEIGHTS = np.array([9 / 40] + [(155 - np.sqrt(15.0)) / 1200] * 3 + [(155 + np.sqrt(15.0)) / 1200] * 3)


def _face_shapes(params: np.ndarray, quad: np.ndarray) -> np.ndarray:
    """(p, 4) shape functions at face parameters ``params`` (p, 2): a triangle's ``(1 - s - t, s, t, 0)``, a
    quadrilateral's bilinear ones in cyclic vertex order (0,0) (1,0) (1,1) (0,1)."""
    s, t = params[:, 0], params[:, 1]
    triangle = np.column_stack([1 - s - t, s, t, np.zeros_like(s)])
    bilinear = np.column_stack([(1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t])
    return np.where(quad[:, None], bilinear, triangle)


def _face_tangents(x: np.ndarray, params: np.ndarray, quad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """d x / d s and d x / d t of faces ``x`` (p, 4, k) at ``params`` (p, 2) (k = 2 for faces projected on a plane,
    3 in space)."""
    s, t = params[:, 0:1], params[:, 1:2]
    d_s = np.where(quad[:, None], (1 - t) * (x[:, 1] - x[:, 0]) + t * (x[:, 2] - x[:, 3]), x[:, 1] - x[:, 0])
    d_t = np.where(quad[:, None], (1 - s) * (x[:, 3] - x[:, 0]) + s * (x[:, 2] - x[:, 1]), x[:, 2] - x[:, 0])
    return d_s, d_t


def _inverse_map(plane_x: np.ndarray, quad: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The face parameters (p, 2) of ``points`` (p, 2) in the plane, for faces with plane vertices ``plane_x``
    (p, 4, 2): affine for triangles, Newton's method for quadrilaterals (one step on a parallelogram)."""
    params = np.where(quad[:, None], 0.5, 1.0 / 3.0) * np.ones((points.shape[0], 2))
    for _ in range(30):
        shapes = _face_shapes(params, quad)
        residual = points - np.einsum("pi,pij->pj", shapes, plane_x)
        d_s, d_t = _face_tangents(plane_x, params, quad)
        det = d_s[:, 0] * d_t[:, 1] - d_s[:, 1] * d_t[:, 0]
        step = np.column_stack([d_t[:, 1] * residual[:, 0] - d_t[:, 0] * residual[:, 1],
                                d_s[:, 0] * residual[:, 1] - d_s[:, 1] * residual[:, 0]]) / det[:, None]
        params = params + step
        if np.abs(step).max(initial=0.0) < 1e-15:
            break
    return params


def _clip(subject: np.ndarray, clip: np.ndarray) -> np.ndarray:
    """Sutherland–Hodgman: the polygon ``subject`` (k, 2) clipped by the convex polygon ``clip`` (m, 2),
    counter-clockwise; an empty (0, 2) array when they do not overlap. Python floats inside: a few vertices each,
    where NumPy's per-element overhead would dominate."""
    output = [tuple(point) for point in subject.tolist()]
    corners = [tuple(point) for point in clip.tolist()]
    for i, (ax, ay) in enumerate(corners):
        if not output:
            break
        bx, by = corners[(i + 1) % len(corners)]
        ex, ey = bx - ax, by - ay
        side = [ex * (y - ay) - ey * (x - ax) for x, y in output]   # >= 0: inside (left of a->b)
        points = []
        for k, (x, y) in enumerate(output):
            following = (k + 1) % len(output)
            side_current, side_following = side[k], side[following]
            if side_current >= 0:
                points.append((x, y))
            if (side_current >= 0) != (side_following >= 0):
                fraction = side_current / (side_current - side_following)
                fx, fy = output[following]
                points.append((x + fraction * (fx - x), y + fraction * (fy - y)))
        output = points
    return np.array(output, dtype=float).reshape(-1, 2)


def _face_normals(x: np.ndarray, quad: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """(f, 3) unit normals of faces ``x`` (f, 4, 3) at their centres, pointing out of the body (away from
    ``inside``): a triangle's plane normal; a quadrilateral's ``d x/d s x d x/d t`` at its centre (the cross product
    of its diagonals)."""
    normal = np.where(quad[:, None], np.cross(x[:, 2] - x[:, 0], x[:, 3] - x[:, 1]),
                      np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    centre = np.where(quad[:, None], x.mean(axis=1), x[:, :3].mean(axis=1))
    flip = np.einsum("ij,ij->i", inside - centre, normal) > 0
    normal[flip] *= -1
    return normal


def _check_faces(name: str, labels: np.ndarray, x: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """Refuse faces of the wrong shapes or of zero area; return which are quadrilaterals."""
    f = labels.shape[0]
    if labels.shape != (f, 4) or x.shape != (f, 4, 3) or np.shape(inside) != (f, 3) or f == 0:
        raise ValueError(f"mortar: the {name} faces: expected (f, 4) labels (a triangle's fourth -1), (f, 4, 3) "
                         f"vertices and (f, 3) inside points, f > 0; got {labels.shape}, {x.shape}, {np.shape(inside)}")
    quad = labels[:, 3] >= 0
    area = np.where(quad, np.linalg.norm(np.cross(x[:, 2] - x[:, 0], x[:, 3] - x[:, 1]), axis=1),
                    np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1))
    if np.any(area == 0):
        raise ValueError(f"mortar: a {name} face has zero area")
    return quad


def _mortar_matrices_3d(slave_labels: np.ndarray, slave_x: np.ndarray, slave_inside: np.ndarray,
                        master_labels: np.ndarray, master_x: np.ndarray, master_inside: np.ndarray,
                        multipliers: str, reference_tangent: np.ndarray, symmetry: np.ndarray,
                        slave_reference_x: np.ndarray | None = None) -> MortarMatrices:
    """:func:`mortar_matrices` for faces (see the module's 3D section)."""
    slave_quad = _check_faces("slave", slave_labels, slave_x, slave_inside)
    if slave_reference_x is not None and slave_reference_x.shape != slave_x.shape:
        raise ValueError(f"mortar: slave_reference_x has the shape {slave_reference_x.shape}, slave_x "
                         f"{slave_x.shape}: expected the same")
    master_quad = _check_faces("master", master_labels, master_x, master_inside)
    slave_nodes = np.unique(slave_labels[slave_labels >= 0])
    master_nodes = np.unique(master_labels[master_labels >= 0])
    slave_out = _face_normals(slave_x, slave_quad, slave_inside)
    master_out = _face_normals(master_x, master_quad, master_inside)
    n_slave_faces = slave_x.shape[0]
    corners = np.where(slave_quad, 4, 3)
    master_corners = np.where(master_quad, 4, 3)

    # The auxiliary plane of each slave face: its vertices' centroid and its centre normal; in-plane axes e1, e2.
    origin = np.array([x[:k].mean(axis=0) for x, k in zip(slave_x, corners)])
    first_axis = slave_x[:, 1] - slave_x[:, 0]
    first_axis -= np.einsum("ij,ij->i", first_axis, slave_out)[:, None] * slave_out
    first_axis /= np.linalg.norm(first_axis, axis=1)[:, None]
    axes = np.stack([first_axis, np.cross(slave_out, first_axis)], axis=1)                     # (f, 2, 3)
    slave_plane = np.einsum("fvj,faj->fva", slave_x - origin[:, None], axes)                   # (f, 4, 2)
    slave_radius = np.linalg.norm(slave_plane, axis=2).max(axis=1)
    master_centre = np.array([x[:k].mean(axis=0) for x, k in zip(master_x, master_corners)])
    master_radius = np.array([np.linalg.norm(x[:k] - c, axis=1).max()
                              for x, k, c in zip(master_x, master_corners, master_centre)])

    # Clip every facing master face near each slave face (in-plane distance of the centres below the sum of their
    # radii) against it in the slave's plane; triangulate each overlap polygon from its vertex centroid.
    triangles, triangle_pair, pair_slave, pair_master = [], [], [], []
    for face in range(n_slave_faces):
        offset = (master_centre - origin[face]) @ axes[face].T
        near = np.flatnonzero((np.linalg.norm(offset, axis=1) <= (slave_radius[face] + master_radius) * (1 + 1e-9))
                              & (master_out @ slave_out[face] < 0.0))
        clip = slave_plane[face, :corners[face]]
        first_edge, second_edge = clip[1] - clip[0], clip[2] - clip[0]
        if first_edge[0] * second_edge[1] - first_edge[1] * second_edge[0] < 0:   # counter-clockwise for _clip
            clip = clip[::-1]
        for master in near:
            subject = (master_x[master, :master_corners[master]] - origin[face]) @ axes[face].T
            polygon = _clip(subject, clip)
            if polygon.shape[0] < 3:
                continue
            centre = polygon.mean(axis=0)
            pair = len(pair_slave)
            pair_slave.append(face)
            pair_master.append(master)
            for k in range(polygon.shape[0]):
                triangles.append([centre, polygon[k], polygon[(k + 1) % polygon.shape[0]]])
                triangle_pair.append(pair)
    triangles = np.array(triangles).reshape(-1, 3, 2)
    triangle_pair = np.asarray(triangle_pair, dtype=np.int64)
    pair_slave, pair_master = np.asarray(pair_slave, dtype=np.int64), np.asarray(pair_master, dtype=np.int64)
    edge_1, edge_2 = triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]
    triangle_area = np.abs(edge_1[:, 0] * edge_2[:, 1] - edge_1[:, 1] * edge_2[:, 0]) / 2

    # Gauss points: their pair, plane position, weight (area in the plane), the slave and master parameters.
    n_gauss = TRIANGLE_WEIGHTS.size
    point_pair = np.repeat(triangle_pair, n_gauss)
    point_slave, point_master = pair_slave[point_pair], pair_master[point_pair]
    plane_point = np.einsum("ga,tav->tgv", TRIANGLE_POINTS, triangles).reshape(-1, 2)
    weight = (triangle_area[:, None] * TRIANGLE_WEIGHTS[None, :]).ravel()
    quad_s, quad_m = slave_quad[point_slave], master_quad[point_master]
    slave_params = _inverse_map(slave_plane[point_slave], quad_s, plane_point)
    master_plane = np.einsum("pvj,paj->pva", master_x[point_master] - origin[point_slave][:, None],
                             axes[point_slave])
    master_params = _inverse_map(master_plane, quad_m, plane_point)
    slave_shapes = _face_shapes(slave_params, quad_s)                                          # (p, 4)
    master_shapes = _face_shapes(master_params, quad_m)
    # The slave surface's area element over the plane's (1 on a flat face; a warped quadrilateral's ratio).
    d_s, d_t = _face_tangents(slave_x[point_slave], slave_params, quad_s)
    p_s, p_t = _face_tangents(slave_plane[point_slave], slave_params, quad_s)
    weight = weight * np.linalg.norm(np.cross(d_s, d_t), axis=1) \
        / np.abs(p_s[:, 0] * p_t[:, 1] - p_s[:, 1] * p_t[:, 0])
    if slave_reference_x is not None:   # measured with the faces' reference areas (finite sliding)
        weight = weight * (_face_areas(slave_reference_x, slave_quad) / _face_areas(slave_x, slave_quad))[point_slave]
        slave_x = slave_reference_x

    # Each slave face's facing part: its mass matrix there; faces facing too little are dropped.
    mass = np.zeros((n_slave_faces, 4, 4))
    # Sums over each pair's points first (a pair's points are consecutive), then over the pairs of a face.
    pair_start = np.flatnonzero(np.r_[True, point_pair[1:] != point_pair[:-1]]) if point_pair.size else \
        np.zeros(0, dtype=np.int64)
    pair_of_sum = point_pair[pair_start]
    per_pair = lambda values: np.add.reduceat(values, pair_start, axis=0) if pair_start.size \
        else np.zeros((0,) + values.shape[1:])  # noqa: E731
    np.add.at(mass, pair_slave[pair_of_sum], per_pair(np.einsum("p,pi,pk->pik", weight, slave_shapes, slave_shapes)))
    facing = np.zeros(n_slave_faces)
    np.add.at(facing, point_slave, weight)
    used = facing >= MIN_FACING * _face_areas(slave_x, slave_quad)
    padded = mass + np.where(slave_quad, 0.0, 1.0)[:, None, None] * np.diag([0.0, 0.0, 0.0, 1.0])  # triangles
    if multipliers == "dual":   # psi_i = sum_k A_ik N_k, A = diag(d) Me^-1 (d = Me's row sums) on the facing part
        coefficients = np.zeros((n_slave_faces, 4, 4))
        coefficients[used] = mass[used].sum(axis=2)[:, :, None] * np.linalg.inv(padded[used])
    else:
        coefficients = np.broadcast_to(np.eye(4), (n_slave_faces, 4, 4)).copy()
        coefficients[~used] = 0.0
    coefficients[~slave_quad, 3, :] = 0.0
    shape = np.einsum("pik,pk->pi", coefficients[point_slave], slave_shapes)                  # phi_i at the points

    row_of = np.searchsorted(slave_nodes, np.where(slave_labels >= 0, slave_labels, slave_nodes[0]))
    col_of = np.searchsorted(master_nodes, np.where(master_labels >= 0, master_labels, master_nodes[0]))
    kept_pairs = used[pair_slave[pair_of_sum]]
    local = per_pair(np.einsum("p,pi,pl->pil", weight, shape, master_shapes))[kept_pairs]       # (pairs, 4, 4)
    rows = np.broadcast_to(row_of[pair_slave[pair_of_sum[kept_pairs]]][:, :, None], local.shape).ravel()
    cols = np.broadcast_to(col_of[pair_master[pair_of_sum[kept_pairs]]][:, None, :], local.shape).ravel()
    n_slave = slave_nodes.size
    M = sp.csr_matrix((local.ravel(), (rows, cols)), shape=(n_slave, master_nodes.size))
    M.eliminate_zeros()
    if multipliers == "dual":   # D_jj as M's row sum (see the 2D code: the weights sum to one to rounding)
        D = sp.csr_matrix(sp.diags(np.asarray(M.sum(axis=1)).ravel()))
        D.eliminate_zeros()
    else:
        rows = np.repeat(row_of[used], 4, axis=1).ravel()
        cols = np.tile(row_of[used], (1, 4)).ravel()
        D = sp.csr_matrix((mass[used].ravel(), (rows, cols)), shape=(n_slave, n_slave))
        D.eliminate_zeros()

    # The master faces' mean size (mean edge length) seen by each slave node, weighted by the facing area.
    edges = np.linalg.norm(np.roll(master_x, -1, axis=1) - master_x, axis=2)
    master_size = edges.sum(axis=1) / master_corners   # a triangle's fourth repeats its third: edges 2-3, 3-0
    pair_area = np.where(kept_pairs, per_pair(weight), 0.0)
    pair_faces, pair_masters = pair_slave[pair_of_sum], pair_master[pair_of_sum]
    size_sum, size_weight = np.zeros(n_slave), np.zeros(n_slave)
    for corner in range(4):
        real = slave_labels[pair_faces, corner] >= 0
        np.add.at(size_sum, row_of[pair_faces[real], corner], (pair_area * master_size[pair_masters])[real])
        np.add.at(size_weight, row_of[pair_faces[real], corner], pair_area[real])
    sizes = np.divide(size_sum, size_weight, out=np.zeros(n_slave), where=size_weight > 0)

    # Averaged nodal normals (from the master into the slave) and the tangents of the reference tangent.
    total = np.zeros((n_slave, 3))
    for corner in range(4):
        real = slave_labels[:, corner] >= 0
        np.add.at(total, row_of[real, corner], slave_out[real])
    length = np.linalg.norm(total, axis=1)
    if np.any(length == 0):
        raise ValueError("mortar: a slave node joins faces whose outward normals cancel (the slave surface folds "
                         "back on itself there)")
    normals = _on_symmetry_planes(-total / length[:, None], slave_nodes, symmetry)
    first = reference_tangent[None, :] - (normals @ reference_tangent)[:, None] * normals
    first_length = np.linalg.norm(first, axis=1)
    if np.any(first_length < 1e-8):
        raise ValueError(f"mortar: reference_tangent = {reference_tangent.tolist()} is along a slave node's normal: "
                         "allowed a direction in the contact plane")
    first /= first_length[:, None]
    tangents = np.stack([first, np.cross(normals, first)], axis=1)
    return MortarMatrices(slave_nodes, master_nodes, D, M, normals, tangents, sizes, multipliers)


def _face_areas(x: np.ndarray, quad: np.ndarray) -> np.ndarray:
    """(f,) the faces' areas: a triangle's; a (possibly warped) quadrilateral's by the 2 x 2 Gauss rule."""
    area = np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1) / 2
    if quad.any():
        gauss = 0.5 + np.array([-0.5, 0.5]) / np.sqrt(3.0)
        quad_area = np.zeros(int(quad.sum()))
        for s in gauss:
            for t in gauss:
                params = np.tile([s, t], (quad_area.size, 1))
                d_s, d_t = _face_tangents(x[quad], params, np.ones(quad_area.size, dtype=bool))
                quad_area += np.linalg.norm(np.cross(d_s, d_t), axis=1) / 4
        area[quad] = quad_area
    return area
