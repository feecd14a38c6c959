"""Two identical boxes of structured tetrahedra (Kuhn's 6 per cube), the upper (slave) pressed onto the lower
(master) by the lower's rigid approach, frictionless, tops and bottoms on rollers: uniaxial stress sigma = E delta /
(H1 + H2), linear in every element, the contact patch test of Taylor & Papadopoulos (IJNME 31, 1991) in 3D
(tests/test_api.py, tests/test_pressure_recovery.py). Plain DOLFINx, as a user would write it."""

import numpy as np
from mpi4py import MPI

import ufl  # noqa: E402
from dolfinx import fem, mesh  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import _dolfinx as dfx  # noqa: E402

E, NU = 200000.0, 0.3
#: The lower box's cells along each side; the approach (mm).
LOWER_CELLS, DELTA = 4, 1e-4


def elasticity(V):
    lmbda, shear_modulus = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    return ufl.inner(lmbda * ufl.tr(eps(u)) * ufl.Identity(3) + 2 * shear_modulus * eps(u), eps(v)) * ufl.dx


def tetrahedral_box(n, z0, z1, first):
    """Points and cells of [-1/2, 1/2]^2 x [z0, z1] on an n x n x n grid, each cube cut into 6 tetrahedra
    around its main diagonal (Kuhn); vertex numbers start at ``first``."""
    g = np.linspace(-0.5, 0.5, n + 1)
    z = np.linspace(z0, z1, n + 1)
    X, Y, Z = np.meshgrid(g, g, z, indexing="ij")
    points = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    index = np.arange(points.shape[0]).reshape(n + 1, n + 1, n + 1) + first
    cells = []
    paths = ([0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7])
    for i in range(n):
        for j in range(n):
            for k in range(n):
                corner = [index[i + a, j + b, k + c] for a in (0, 1) for b in (0, 1) for c in (0, 1)]
                cells += [[corner[v] for v in path] for path in paths]
    return points, np.array(cells)


def stacked_boxes(upper_cells, formulation="node", comm=MPI.COMM_WORLD, **contact_options):
    """The upper box (``upper_cells`` along each side: even, so that the rollers' centre line x = 0 is a grid
    line; :data:`LOWER_CELLS` matches the faces) on the lower, ``ElasticBody(..., formulation=)``, pressed by
    :data:`DELTA`. Returns (problem, state, sigma); ``contact_options`` go to
    :class:`~dolfinx_fretting.contact.Contact`."""
    lower = tetrahedral_box(LOWER_CELLS, 0.0, 1.0, 0)
    upper = tetrahedral_box(upper_cells, 1.0, 2.0, (LOWER_CELLS + 1) ** 3)
    root = comm.rank == 0
    points = np.vstack([lower[0], upper[0]]) if root else np.zeros((0, 3))
    cells = np.vstack([lower[1], upper[1]]) if root else np.zeros((0, 4), dtype=np.int64)
    msh = dfx.create_mesh(comm, cells, points, "tetrahedron")
    V = dfx.vector_space(msh, 1)
    fdim = 2
    msh.topology.create_connectivity(fdim, 3)
    interface = mesh.locate_entities_boundary(msh, fdim, lambda x: np.isclose(x[2], 1.0))
    f_to_c = msh.topology.connectivity(fdim, 3)
    centre_z = np.array([mesh.compute_midpoints(msh, 3, f_to_c.links(f))[0, 2] for f in interface])
    marker = np.where(centre_z > 1.0, 1, 2).astype(np.int32)     # 1 the upper's bottom (slave), 2 the lower's top
    order = np.argsort(interface)
    tags = mesh.meshtags(msh, fdim, interface[order], marker[order])

    def component(i, where):
        Vi, _ = V.sub(i).collapse()
        dofs = fem.locate_dofs_geometrical((V.sub(i), Vi), where)
        return fem.dirichletbc(fem.Function(Vi), dofs, V.sub(i))

    bcs = []
    for z in (0.0, 2.0):   # rollers on the top and the bottom, the in-plane rigid motions removed on them
        bcs += [component(2, lambda x, z=z: np.isclose(x[2], z)),
                component(0, lambda x, z=z: np.isclose(x[2], z) & np.isclose(x[0], 0.0) & np.isclose(x[1], 0.0)),
                component(1, lambda x, z=z: np.isclose(x[2], z) & np.isclose(x[1], 0.0))]
    contact = dfr.Contact(V, (tags, 1), dfr.ElasticBody((tags, 2), [0.0, 0.0, 1.0], formulation=formulation),
                          mu=0.0, bcs=bcs, **contact_options)
    problem = dfr.FrettingProblem(elasticity(V), contact, bcs)
    state = problem.initial_state()
    state = problem.commit(state, problem.solve(state, normal=DELTA))
    return problem, state, E * DELTA / 2.0
