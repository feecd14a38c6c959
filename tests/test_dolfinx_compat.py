"""dolfinx_fretting._dolfinx: each version-dependent helper against an independent reference, on whichever
stack runs the suite (./tasks.sh test runs it on DOLFINx 0.5.2 and 0.11).

References are closed forms on small structured meshes: counts of dofs and quadrature points, the affine map
of a triangle, the centroid of a cell, a boundary condition's value.
"""

import os

import basix
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from dolfinx_fretting import _dolfinx as dfx

COMM = MPI.COMM_WORLD


@pytest.fixture(scope="module", params=["triangle", "quadrilateral"])
def msh(request):
    cell = getattr(dfx.dmesh.CellType, request.param)
    return dfx.dmesh.create_rectangle(COMM, [np.array([0.0, 0.0]), np.array([2.0, 1.0])], [4, 3], cell_type=cell)


def _n_cells(msh) -> int:
    return msh.topology.index_map(2).size_local + msh.topology.index_map(2).num_ghosts


def test_vector_and_scalar_spaces(msh):
    V = dfx.vector_space(msh, 1)
    Q = dfx.scalar_space(msh, "Lagrange", 1)
    D = dfx.scalar_space(msh, "DG", 0)
    # P1 on a 4 x 3 grid: 5 * 4 nodes; vector: block size 2; DG0: one dof per cell.
    assert V.dofmap.index_map_bs == 2 and V.dofmap.index_map.size_global == 20
    assert Q.dofmap.index_map_bs == 1 and Q.dofmap.index_map.size_global == 20
    assert D.dofmap.index_map.size_global == msh.topology.index_map(2).size_global
    V2 = dfx.vector_space(msh, 2)
    # P2 nodes: (2*4+1) * (2*3+1) on quadrilaterals (edge and cell midpoints), vertices + edges on triangles.
    quad = msh.topology.cell_type == dfx.dmesh.CellType.quadrilateral
    assert V2.dofmap.index_map.size_global == (63 if quad else 20 + (4 * 4 + 5 * 3 + 12))


def test_element_description(msh):
    quad = msh.topology.cell_type == dfx.dmesh.CellType.quadrilateral
    for space, degree, size, continuous in ((dfx.vector_space(msh, 1), 1, 2, True), (dfx.vector_space(msh, 2), 2, 2, True),
                                            (dfx.scalar_space(msh, "Lagrange", 1), 1, 1, True),
                                            (dfx.scalar_space(msh, "DG", 0), 0, 1, False)):
        assert dfx.element_degree(space) == degree and dfx.value_size(space) == size
        family = dfx.element_family(space)
        # contact._check_vector_p1 accepts these continuous Lagrange names only.
        assert (family in ("P", "Q", "Lagrange", "CG")) == continuous, (family, quad)


def test_quadrature_space_layout(msh):
    degree = 2
    points, _ = basix.make_quadrature(dfx.basix_cell(msh), degree)
    for shape in ((3,), (3, 3)):
        S = dfx.quadrature_space(msh, degree, shape)
        blocks = dfx.cell_dofmap(S)
        assert blocks.shape == (_n_cells(msh), points.shape[0])
        assert S.dofmap.index_map_bs == int(np.prod(shape))
        # Every (cell, point) has its own block: the owned and ghost blocks are numbered once each.
        assert np.unique(blocks).size == blocks.size


def test_expression_at_points_is_the_affine_map(msh):
    """x evaluated at reference points X of each cell equals the map from the cell's vertices."""
    X = np.array([[0.2, 0.3], [0.6, 0.1], [0.25, 0.25]])
    compiled = dfx.expression(ufl.SpatialCoordinate(msh), X)
    cells = np.arange(_n_cells(msh), dtype=np.int32)
    values = dfx.eval_expression(compiled, msh, cells).reshape(cells.size, X.shape[0], 2)
    nodes = msh.geometry.x[dfx.geometry_dofmap(msh)][:, :, :2]  # (cells, vertices, 2)
    if nodes.shape[1] == 3:  # P1 triangle: x = v0 (1 - X - Y) + v1 X + v2 Y
        w = np.column_stack([1 - X[:, 0] - X[:, 1], X[:, 0], X[:, 1]])
    else:  # Q1 quadrilateral, DOLFINx's tensor ordering 0 1 / 2 3
        w = np.column_stack([(1 - X[:, 0]) * (1 - X[:, 1]), X[:, 0] * (1 - X[:, 1]), (1 - X[:, 0]) * X[:, 1],
                             X[:, 0] * X[:, 1]])
    expected = np.einsum("pv,cvd->cpd", w, nodes)
    assert np.allclose(values, expected, rtol=0, atol=1e-14)


def test_solve_linear_is_the_mass_projection(msh):
    """Projecting the constant 3 by the L2 mass matrix gives 3 everywhere (to solver precision)."""
    Q = dfx.scalar_space(msh, "Lagrange", 1)
    u, v = ufl.TrialFunction(Q), ufl.TestFunction(Q)
    uh = dfx.solve_linear(u * v * ufl.dx, 3.0 * v * ufl.dx, [], {"ksp_type": "preonly", "pc_type": "lu"})
    assert np.allclose(uh.x.array, 3.0, rtol=1e-12)


def test_interpolation_points_of_dg0_are_the_centroid(msh):
    points = dfx.interpolation_points(dfx.scalar_space(msh, "DG", 0))
    centroid = [1 / 3, 1 / 3] if msh.topology.cell_type == dfx.dmesh.CellType.triangle else [0.5, 0.5]
    assert np.allclose(points, [centroid], atol=1e-15)


def test_petsc_vec_shares_the_function_values(msh):
    u = dfx.fem.Function(dfx.vector_space(msh, 1))
    u.x.array[:] = np.arange(u.x.array.size)
    vec = dfx.petsc_vec(u)
    n = vec.getLocalSize()
    assert np.array_equal(vec.getArray(readonly=True), u.x.array[:n])
    vec.getArray()[0] = -7.0
    assert u.x.array[0] == -7.0


def test_vector_for_form_and_set_bc(msh):
    V = dfx.vector_space(msh, 1)
    L = dfx.fem.form(ufl.inner(ufl.as_vector([1.0, 0.0]), ufl.TestFunction(V)) * ufl.dx)
    b = dfx.vector_for_form(L)
    bs = V.dofmap.index_map_bs
    assert b.getSize() == V.dofmap.index_map.size_global * bs and b.getLocalSize() == V.dofmap.index_map.size_local * bs
    facets = dfx.dmesh.locate_entities_boundary(msh, 1, lambda x: np.isclose(x[0], 0.0))
    dofs = dfx.fem.locate_dofs_topological(V, 1, facets)
    bc = dfx.fem.dirichletbc(np.array([3.0, -5.0]), dofs, V)
    b.set(1.0)
    dfx.set_bc(b, [bc], scale=0.5)
    owned = dofs[dofs < V.dofmap.index_map.size_local]
    arr = b.getArray(readonly=True).reshape(-1, bs)
    assert np.allclose(arr[owned], [1.5, -2.5])  # scale x the boundary value
    free = np.setdiff1d(np.arange(arr.shape[0]), owned)
    assert np.all(arr[free] == 1.0)
    b.destroy()


def test_vtk_mesh_topology(msh):
    topology, types, points = dfx.vtk_mesh(msh)
    nv = 3 if msh.topology.cell_type == dfx.dmesh.CellType.triangle else 4
    n_owned = msh.topology.index_map(2).size_local
    cells = topology.reshape(n_owned, nv + 1)
    assert np.all(cells[:, 0] == nv)
    # 0.5: VTK_TRIANGLE (5) / VTK_QUAD (9); 0.11: the Lagrange cells VTK_LAGRANGE_TRIANGLE (69) /
    # VTK_LAGRANGE_QUADRILATERAL (70), whose first-order node order is the same.
    assert np.unique(types).size == 1 and int(types[0]) in ((5, 69) if nv == 3 else (9, 70))
    assert points is msh.geometry.x or np.array_equal(points, msh.geometry.x)
    # VTK orders a quadrilateral's vertices around it: the polygon's shoelace area is the cell's (0.5 x 1/3 mm).
    p = points[cells[:, 1:], :2]
    q = np.roll(p, -1, axis=1)
    area = 0.5 * np.abs(np.sum(p[:, :, 0] * q[:, :, 1] - q[:, :, 0] * p[:, :, 1], axis=1))
    assert np.allclose(area, (2.0 / 4) * (1.0 / 3) / (2 if nv == 3 else 1))


def test_mpiexec_names_a_launcher_of_this_mpi():
    cmd = dfx.mpiexec(3)
    assert os.access(cmd[0], os.X_OK) and cmd[1:3] == ["-n", "3"]
    assert ("--oversubscribe" in cmd) == ("Open MPI" in MPI.Get_library_version())


def test_versions_name_this_stack():
    v = dfx.versions()
    assert v["dolfinx"].startswith(f"{dfx.DOLFINX_VERSION[0]}.{dfx.DOLFINX_VERSION[1]}.")
    assert v["numpy"] == np.__version__ and dfx.DOLFINX_VERSION in dfx.TESTED_VERSIONS


def test_cell_submesh_maps_its_cells_to_the_parents(msh):
    """The submesh of the owned cells left of x = 1 (half the 2 x 1 mm rectangle: 2 x 3 cells of 4 x 3, times 2 for
    triangles): that many cells over the ranks, and each submesh cell's vertices are those of the parent cell its
    map names (the same coordinates: 1e-14, the nodes are copied)."""
    owned = msh.topology.index_map(2).size_local
    geometry = dfx.geometry_dofmap(msh)
    midpoints = msh.geometry.x[geometry[:owned]].mean(axis=1)
    left = np.flatnonzero(midpoints[:, 0] < 1.0).astype(np.int32)
    submesh, parent_cells = dfx.cell_submesh(msh, left)
    sub_owned = submesh.topology.index_map(2).size_local
    per_square = 2 if msh.topology.cell_type == dfx.dmesh.CellType.triangle else 1
    assert COMM.allreduce(sub_owned) == 2 * 3 * per_square
    assert parent_cells.size == sub_owned + submesh.topology.index_map(2).num_ghosts
    assert np.array_equal(np.sort(parent_cells[:sub_owned]), np.sort(left))
    sub_vertices = np.sort(submesh.geometry.x[dfx.geometry_dofmap(submesh)], axis=1)
    parent_vertices = np.sort(msh.geometry.x[geometry[parent_cells]], axis=1)
    assert sub_vertices == pytest.approx(parent_vertices, abs=1e-14)


def test_cell_dofmap_of_a_rank_without_cells_has_its_row_width(msh):
    """A submesh with no cell on this rank (here on every rank): ``cell_dofmap`` is (0, dofs per cell) and
    ``geometry_dofmap`` (0, nodes per cell), as the current API gives them, so ``[:, 0]`` works there (the fatigue
    region's XDMF on a rank holding none of it)."""
    submesh, _ = dfx.cell_submesh(msh, np.zeros(0, dtype=np.int32))
    per_cell = 3 if msh.topology.cell_type == dfx.dmesh.CellType.triangle else 4
    assert dfx.cell_dofmap(dfx.scalar_space(submesh, "DG", 0)).shape == (0, 1)
    assert dfx.cell_dofmap(dfx.vector_space(submesh, 1)).shape == (0, per_cell)
    assert dfx.geometry_dofmap(submesh).shape == (0, per_cell)
