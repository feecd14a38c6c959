"""Mortar integrals of two 2D contact surfaces of linear segments (pure NumPy; no mesh).

For a slave surface and a master surface, each a set of straight two-node segments, this module computes the
mortar matrices of the segment-to-segment method (Puso & Laursen, CMAME 193, 2004; with dual Lagrange multipliers:
Wohlmuth, SIAM J. Numer. Anal. 38, 2000; Popp, Gee & Wall, IJNME 79, 2009):

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
        normals: (s, 2) each slave node's unit contact normal, pointing from the master into the slave (minus the
            average of the unit outward normals of the slave segments meeting at the node).
        tangents: (s, 2) ``t = (n_y, -n_x)`` (the package's 2D frame,
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
                    multipliers: str = "dual") -> MortarMatrices:
    """The mortar matrices D and M of two 2D surfaces of linear segments (see the module).

    Args:
        slave_segment_nodes, master_segment_nodes: (f, 2) each segment's node labels (integers; a label shared by two
            segments is one node).
        slave_x, master_x: (f, 2, 2) the segments' end points, in the order of their labels.
        slave_inside, master_inside: (f, 2) a point inside each body behind each segment (its cell's centroid).
        multipliers: ``"dual"`` (D diagonal) or ``"standard"``.

    Returns:
        The matrices, rows the slave nodes of every segment given (a node facing no master has an empty row and
        ``D_jj = 0``).

    Raises:
        ValueError: ``multipliers`` not one of :data:`MULTIPLIERS`, arrays of the wrong shapes, or a segment of zero
            length.
    """
    if multipliers not in MULTIPLIERS:
        raise ValueError(f"mortar: multipliers = {multipliers!r}: allowed {', '.join(map(repr, MULTIPLIERS))}")
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
    slave_nodes = np.unique(slave_segment_nodes)
    master_nodes = np.unique(master_segment_nodes)
    slave_out = _segment_normals(slave_x, np.asarray(slave_inside, dtype=float))
    master_out = _segment_normals(master_x, np.asarray(master_inside, dtype=float))
    seg, mseg, low, high = _overlaps(slave_x, slave_out, master_x, master_out)

    slave_length = np.linalg.norm(slave_x[:, 1] - slave_x[:, 0], axis=1)
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
    normals = slave_normals(slave_segment_nodes, slave_x, np.asarray(slave_inside, dtype=float), slave_nodes)
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
