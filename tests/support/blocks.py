"""Blocks of the several-zone tests (tests/test_zones.py, tests/test_parallel.py), written as a DOLFINx user would:
plane-strain elasticity, tagged faces, rollers; two unit squares in one mesh."""

import numpy as np
from mpi4py import MPI

import ufl  # noqa: E402
from dolfinx import fem, mesh  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import compat  # noqa: E402

E, NU = 200000.0, 0.3
LMBDA, MU_LAME = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
E_PLANE = E / (1 - NU ** 2)   # plane strain, sigma_xx = 0: sigma_yy = E / (1 - nu^2) eps_yy
TIGHT = dfr.LocalSolver(tol=1e-12)


def elasticity(V):
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    sigma = LMBDA * ufl.tr(eps(u)) * ufl.Identity(2) + 2 * MU_LAME * eps(u)
    return ufl.inner(sigma, eps(v)) * ufl.dx


def tagged(msh, where: dict[int, object]):
    fdim = 1
    found = [(marker, mesh.locate_entities_boundary(msh, fdim, f)) for marker, f in where.items()]
    facets = np.concatenate([f for _, f in found])
    values = np.concatenate([np.full(f.size, m, dtype=np.int32) for m, f in found])
    order = np.argsort(facets)
    return mesh.meshtags(msh, fdim, facets[order], values[order])


def component(V, i, where):
    Vi, _ = V.sub(i).collapse()
    dofs = fem.locate_dofs_geometrical((V.sub(i), Vi), where)
    return fem.dirichletbc(fem.Function(Vi), dofs, V.sub(i))


LEFT_X, RIGHT_X = 0.0, 1.5   # the blocks' left edges (unit squares, 0.5 apart)


def unit_squares(origins, n: int, comm: MPI.Comm = MPI.COMM_WORLD):
    """One mesh of unit squares (n x n quadrilaterals each) with their lower-left corners at ``origins``, each with
    its own nodes (squares that touch share positions, not nodes: separate bodies)."""
    points, cells = [], []
    for x0, y0 in origins:
        first = len(points) and sum(len(p) for p in points)
        xs, ys = np.meshgrid(np.linspace(x0, x0 + 1, n + 1), np.linspace(y0, y0 + 1, n + 1), indexing="ij")
        points.append(np.column_stack([xs.ravel(), ys.ravel()]))
        index = lambda i, j, first=first: first + i * (n + 1) + j  # noqa: E731
        cells += [[index(i, j), index(i + 1, j), index(i, j + 1), index(i + 1, j + 1)]
                  for i in range(n) for j in range(n)]
    points = np.vstack(points) if comm.rank == 0 else np.zeros((0, 2))
    cells = np.array(cells) if comm.rank == 0 else np.zeros((0, 4), dtype=np.int64)
    return compat.create_mesh(comm, cells, points, "quadrilateral")


def two_blocks(n: int = 6, comm: MPI.Comm = MPI.COMM_WORLD):
    """Two unit squares (n x n quadrilaterals each) side by side in one mesh, not touching; markers 1 and 2 their
    tops; rollers on their bottoms (u_y = 0) and u_x = 0 at each bottom-left corner (no rigid motion)."""
    msh = unit_squares([(LEFT_X, 0.0), (RIGHT_X, 0.0)], n, comm)
    V = compat.vector_space(msh, 1)
    tags = tagged(msh, {1: lambda x: np.isclose(x[1], 1.0) & (x[0] < 1.2),
                        2: lambda x: np.isclose(x[1], 1.0) & (x[0] > 1.2)})
    bcs = [component(V, 1, lambda x: np.isclose(x[1], 0.0)),
           component(V, 0, lambda x: np.isclose(x[1], 0.0) & (np.isclose(x[0], LEFT_X) | np.isclose(x[0], RIGHT_X)))]
    return V, tags, bcs


def plane_above():
    return dfr.RigidPlane([0.0, 1.0], [0.0, -1.0])
