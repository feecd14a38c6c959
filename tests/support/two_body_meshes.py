"""Two bodies in one mesh for the 2D mortar validations (tests/test_mortar.py, tests/test_mortar_validation.py): a
slave body (the package's half-cylinder, or a structured flat punch with rounded edges) on a structured flat of its
own whose element size in the contact zone is chosen apart from the slave's, so the two contact faces match only
when the sizes are equal. Plain DOLFINx, as a user would write it; quadrilaterals."""

import numpy as np
from mpi4py import MPI

import ufl  # noqa: E402
from dolfinx import mesh  # noqa: E402
from support.blocks import component  # noqa: E402

from dolfinx_fretting import _dolfinx as dfx  # noqa: E402
from dolfinx_fretting import compat, meshes  # noqa: E402

#: The paper's material for both bodies (MPa, -): E* = E / (2 (1 - nu^2)) for the pair.
E, NU = 115000.0, 0.342
E_STAR = E / (2 * (1 - NU ** 2))
#: Half-width of the refined zone of both contact faces (mm).
FINE = 0.4
#: The slave face and the master face are tagged within |x| < TAGGED (mm).
TAGGED = 1.0


def graded_lines(h, fine, total, growth=1.2):
    """Grid lines 0, h, 2h ... up to ``fine``, then steps growing by ``growth`` up to ``total``."""
    lines = list(np.arange(0.0, fine + h / 2, h))
    step = h
    while lines[-1] < total:
        step *= growth
        lines.append(min(lines[-1] + step, total))
    if total - lines[-2] < 0.3 * (lines[-2] - lines[-3]):   # no sliver at the end
        del lines[-2]
    return np.array(lines)


def symmetric_lines(h, fine, half):
    """Grid lines over [-half, half]: h within ``fine`` of 0 (0 a line), graded beyond."""
    lines = graded_lines(h, fine, half)
    return np.concatenate([-lines[:0:-1], lines])


def structured_cells(first, nx, ny):
    """Quadrilaterals of an nx x ny grid of points numbered ``first + i ny + j`` (DOLFINx's tensor-product order)."""
    index = lambda i, j: first + i * ny + j  # noqa: E731
    return np.array([[index(i, j), index(i + 1, j), index(i, j + 1), index(i + 1, j + 1)]
                     for i in range(nx - 1) for j in range(ny - 1)], dtype=np.int64)


def elasticity(V):
    """Plane-strain elasticity of :data:`E`, :data:`NU` (the support.blocks form has other constants)."""
    lmbda, mu_lame = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    sigma = lmbda * ufl.tr(eps(u)) * ufl.Identity(2) + 2 * mu_lame * eps(u)
    return ufl.inner(sigma, eps(v)) * ufl.dx


def on_graded_flat(slave_points, slave_cells, slave_top, flat_h, width=20.0, height=10.0, comm=MPI.COMM_WORLD):
    """The slave body (points above y = 0 touching it at the origin, quadrilaterals, its top at y = ``slave_top``) on
    a structured flat [-W/2, W/2] x [-H, 0], ``flat_h`` within :data:`FINE` of the origin and graded away from it.
    Tags: 1 the slave's lower boundary within |x| < TAGGED, 2 the flat's top there. The slave's top and the flat's
    bottom clamped. Returns (V, facet tags, bcs)."""
    xs = symmetric_lines(flat_h, FINE, width / 2)
    ys = -graded_lines(flat_h, FINE, height)[::-1]
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    points = np.vstack([slave_points, np.column_stack([X.ravel(), Y.ravel()])])
    cells = np.vstack([slave_cells, structured_cells(slave_points.shape[0], xs.size, ys.size)])
    root = comm.rank == 0
    msh = compat.create_mesh(comm, cells if root else np.zeros((0, 4), dtype=np.int64),
                             points if root else np.zeros((0, 2)), "quadrilateral")
    fdim = 1
    msh.topology.create_connectivity(fdim, 2)
    boundary = mesh.exterior_facet_indices(msh.topology)
    middle = mesh.compute_midpoints(msh, fdim, boundary).reshape(-1, 3)
    f_to_c = msh.topology.connectivity(fdim, 2)
    cell_y = np.array([mesh.compute_midpoints(msh, 2, f_to_c.links(f))[0, 1] for f in boundary])
    near = np.abs(middle[:, 0]) < TAGGED
    slave_face = (cell_y > 0) & (middle[:, 1] < slave_top - 1e-9) & near
    flat_top = (cell_y < 0) & np.isclose(middle[:, 1], 0.0) & near
    markers = np.select([slave_face, flat_top], [1, 2], 0).astype(np.int32)
    keep = np.flatnonzero(markers > 0)
    keep = keep[np.argsort(boundary[keep])]
    tags = mesh.meshtags(msh, fdim, boundary[keep], markers[keep])
    V = compat.vector_space(msh, 1)
    clamped = lambda x: np.isclose(x[1], slave_top) | np.isclose(x[1], -height)  # noqa: E731
    return V, tags, [component(V, 0, clamped), component(V, 1, clamped)]


def cylinder_on_graded_flat(h, flat_h, radius=6.0, comm=MPI.COMM_WORLD):
    """The package's half-cylinder (quadrilaterals, h on the arc within :data:`FINE` of its lowest point, the
    origin) on :func:`on_graded_flat` (20 x 10): the two contact faces match (to the arc's O((x/R)^2) sag of the
    node abscissae) only if flat_h = h."""
    cylinder = meshes.half_cylinder(MPI.COMM_SELF, radius, contact_mesh_size=h, contact_half_width=FINE,
                                    coarse_mesh_size=0.6)
    return on_graded_flat(cylinder.mesh.geometry.x[:, :2], dfx.geometry_dofmap(cylinder.mesh), radius, flat_h,
                          comm=comm)


def punch_on_graded_flat(h, flat_h, flat_half_width, radius, half_width=4.0, height=4.0, comm=MPI.COMM_WORLD):
    """A flat punch with rounded edges, its face y = g(x) = max(|x| - b, 0)^2 / (2R) (b = ``flat_half_width``, R =
    ``radius``: the parabolic profile of the closed form, not an arc), [-half_width, half_width] wide and ``height``
    tall: a structured grid, h within :data:`FINE` of the origin and graded away from it, each vertical line lifted
    onto the face (y -> g(x) + y (1 - g(x)/height)); on :func:`on_graded_flat` (20 x 10). The slave nodes' abscissae
    are the grid's, so the faces match exactly if flat_h = h. b should be a grid line (the profile's kink a node)."""
    xs = symmetric_lines(h, FINE, half_width)
    ys = graded_lines(h, FINE, height)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    lift = np.clip(np.abs(X) - flat_half_width, 0.0, None) ** 2 / (2 * radius)
    if lift.max() >= 0.5 * height:
        raise ValueError(f"punch_on_graded_flat: the face rises {lift.max():.3g} over the half-width {half_width}, "
                         f"above half the height {height}: the lifted grid would fold")
    points = np.column_stack([X.ravel(), (lift + Y * (1 - lift / height)).ravel()])
    return on_graded_flat(points, structured_cells(0, xs.size, ys.size), height, flat_h, comm=comm)
