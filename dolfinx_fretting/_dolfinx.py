"""The one module that knows which DOLFINx it runs on.

Two stacks are tested (``./tasks.sh test``):

* DOLFINx 0.5.2 from Debian bookworm (``python3-dolfinx``: petsc4py 3.18, ufl 2022.2, basix 0.5, Open MPI,
  numpy 1.24) — the *legacy* API;
* the current release, DOLFINx 0.11 (the ``dolfinx-solver-real`` wheel, conda-forge ``fenics-dolfinx``, the
  DOLFINx Docker images: petsc4py 3.25, ufl 2026.1, basix 0.11, numpy 2) — the *current* API (used from 0.10
  on; other versions than these two are not tested and get a warning).

Every call whose spelling differs between the two goes through a function here, so the rest of the package
never tests versions. Import order: on the wheel, ``dolfinx`` finds its MPI library only once mpi4py has
loaded it, so this module (and the package's ``__init__``) imports ``mpi4py.MPI`` first.
"""

from __future__ import annotations

import os
import shutil
import sys
import warnings
from typing import TYPE_CHECKING, Sequence

import numpy as np
from mpi4py import MPI  # first: loads libmpi for DOLFINx and PETSc (the wheel's libmpi.so.12)

import basix  # noqa: E402
import dolfinx  # noqa: E402
import dolfinx.fem.petsc  # noqa: E402,F401  (0.11 does not import it with dolfinx.fem)
import ufl  # noqa: E402
from dolfinx import fem  # noqa: E402
from dolfinx import mesh as dmesh  # noqa: E402
from dolfinx import plot  # noqa: E402
from petsc4py import PETSc  # noqa: E402

if TYPE_CHECKING:  # for the annotations only: gmsh is imported by whoever builds a model
    import gmsh

__all__ = ["MPI", "PETSc", "fem", "dmesh", "ufl", "DOLFINX_VERSION", "LEGACY_API", "TESTED_VERSIONS", "versions",
           "basis_gradient_expression", "eval_basis_gradients",
           "element_degree", "element_family", "value_size", "vector_space", "scalar_space", "quadrature_space", "basix_cell", "petsc_vec", "vector_for_form",
           "set_bc", "interpolation_points", "expression", "eval_expression", "model_to_mesh", "create_mesh",
           "entities_to_geometry", "geometry_dofmap", "cell_dofmap", "vtk_mesh", "mpiexec", "write_meshtags",
           "cell_submesh"]

#: (major, minor) of the DOLFINx in use.
DOLFINX_VERSION: tuple[int, int] = tuple(int(p) for p in dolfinx.__version__.split(".")[:2])  # type: ignore[assignment]
#: True on the 0.5 API (Debian bookworm), False on 0.10 and later.
LEGACY_API: bool = DOLFINX_VERSION < (0, 10)
#: The (major, minor) versions ./tasks.sh test runs on.
TESTED_VERSIONS = ((0, 5), (0, 11))
if DOLFINX_VERSION not in TESTED_VERSIONS:
    warnings.warn(f"DOLFINx {dolfinx.__version__} is not tested by dolfinx_fretting (tested: 0.5.2 and 0.11; "
                  f"this one gets the {'0.5' if LEGACY_API else '0.11'} calls)", RuntimeWarning, stacklevel=2)


def versions() -> dict[str, str]:
    """Versions of the numerical stack in use (for run summaries and benchmark records)."""
    return {
        "dolfinx": dolfinx.__version__,
        "basix": basix.__version__,
        "ufl": ufl.__version__,
        "petsc": ".".join(str(v) for v in PETSc.Sys.getVersion()),
        "numpy": np.__version__,
        "mpi": MPI.Get_library_version().strip("\x00 \n").splitlines()[0].strip(),
        "python": sys.version.split()[0],
    }


# Spaces ------------------------------------------------------------------------------------------------------
def element_degree(V) -> int:
    """Polynomial degree of the element of ``V``."""
    element = V.ufl_element()
    return int(element.degree()) if LEGACY_API else int(element.embedded_superdegree)


def element_family(V) -> str:
    """Family name of the element of ``V``: ``"Q"``, ``"P"``, ``"Lagrange"`` ... for continuous Lagrange; a
    discontinuous family is named as such (0.5: ``"DQ"``, ``"Discontinuous Lagrange"``; 0.11: ``"DG"``)."""
    element = V.ufl_element()
    if LEGACY_API:
        return str(element.family())
    return "DG" if element.discontinuous else str(element.family_name)


def value_size(V) -> int:
    """Number of components of a function of ``V``."""
    return int(V.dofmap.index_map_bs) if V.num_sub_spaces == 0 else int(V.num_sub_spaces)


def vector_space(msh: dolfinx.mesh.Mesh, degree: int = 1, family: str = "Lagrange") -> fem.FunctionSpace:
    """Vector-valued space with ``gdim`` components (the displacement space), on any tested DOLFINx.

    0.11: ``fem.functionspace(msh, (family, degree, (gdim,)))``; 0.5: ``fem.VectorFunctionSpace(msh, (family,
    degree))``. Its dofmap is blocked (block size gdim): dof ``bs * node + component``.

    Args:
        msh: The mesh; the space has ``msh.geometry.dim`` components.
        degree: Polynomial degree (:class:`~dolfinx_fretting.contact.Contact` needs 1).
        family: Element family, e.g. ``"Lagrange"``.

    Returns:
        The function space.
    """
    if LEGACY_API:
        return fem.VectorFunctionSpace(msh, (family, degree))
    return fem.functionspace(msh, (family, degree, (msh.geometry.dim,)))


def scalar_space(msh: dolfinx.mesh.Mesh, family: str = "Lagrange", degree: int = 1) -> fem.FunctionSpace:
    """Scalar space, e.g. ``("Lagrange", 1)`` or ``("DG", 0)``, on any tested DOLFINx.

    0.11: ``fem.functionspace(msh, (family, degree))``; 0.5: ``fem.FunctionSpace(msh, (family, degree))``.

    Args:
        msh: The mesh.
        family: Element family, e.g. ``"Lagrange"`` or ``"DG"``.
        degree: Polynomial degree.

    Returns:
        The function space.
    """
    if LEGACY_API:
        return fem.FunctionSpace(msh, (family, degree))
    return fem.functionspace(msh, (family, degree))


def basix_cell(msh) -> "basix.CellType":
    """The basix cell type of a (single cell type) mesh."""
    if LEGACY_API:
        return basix.cell.string_to_type(dolfinx.cpp.mesh.to_string(msh.topology.cell_type))
    return msh.basix_cell()


def quadrature_space(msh, degree: int, shape: Sequence[int]) -> fem.FunctionSpace:
    """Quadrature space of values of ``shape`` (``(k,)`` or ``(k, k)``) at the points of the default
    rule of ``degree`` (those of ``basix.make_quadrature(basix_cell(msh), degree)``, in that order per cell).

    Forms that use its functions must integrate with ``metadata={"quadrature_degree": degree,
    "quadrature_scheme": "default"}``. Its dofmap is blocked: block ``cell_dofmap(S)[c, j]`` holds the
    ``prod(shape)`` values (row-major) at point j of cell c.
    """
    shape = tuple(int(s) for s in shape)
    if LEGACY_API:
        cell = msh.ufl_cell()
        if len(shape) == 1:
            element = ufl.VectorElement("Quadrature", cell, degree=degree, dim=shape[0], quad_scheme="default")
        else:
            element = ufl.TensorElement("Quadrature", cell, degree=degree, shape=shape, quad_scheme="default")
        return fem.FunctionSpace(msh, element)
    import basix.ufl  # lazy: 0.10+ only (basix 0.5 has no basix.ufl)

    element = basix.ufl.quadrature_element(msh.basix_cell(), value_shape=shape, scheme="default",
                                           degree=degree)
    return fem.functionspace(msh, element)


def cell_dofmap(V) -> np.ndarray:
    """(num_cells, dofs per cell) block indices of a space's dofmap, ghost cells included."""
    dm = V.dofmap.list
    if LEGACY_API:  # an AdjacencyList with a constant number of links
        n = dm.num_nodes
        # a rank holding no cell (a submesh's empty part) still gets the row width, as the current API gives it
        return dm.array.reshape(n, -1) if n else np.zeros((0, V.dofmap.dof_layout.num_dofs), dtype=np.int32)
    return dm


def geometry_dofmap(msh) -> np.ndarray:
    """(num_cells, nodes per cell) rows of ``msh.geometry.x`` of each cell, ghost cells included."""
    dm = msh.geometry.dofmap
    if LEGACY_API:
        n = dm.num_nodes
        # a rank holding no cell (a submesh's empty part) still gets the row width, as the current API gives it
        width = msh.geometry.cmap.create_dof_layout().num_dofs
        return dm.array.reshape(n, -1) if n else np.zeros((0, width), dtype=np.int32)
    return dm


def entities_to_geometry(msh, dim: int, entities: np.ndarray) -> np.ndarray:
    """(n, nodes per entity) geometry nodes (rows of ``msh.geometry.x``) of local mesh entities."""
    entities = np.asarray(entities, dtype=np.int32)
    msh.topology.create_connectivity(dim, msh.topology.dim)  # 0.11 needs it (a local operation)
    if LEGACY_API:
        return dolfinx.cpp.mesh.entities_to_geometry(msh._mesh, dim, entities, False)
    return dmesh.entities_to_geometry(msh, dim, entities, False)


# Forms, vectors and boundary conditions --------------------------------------------------------------------
def compiled_form(form):
    """``form`` compiled by ``fem.form`` unless it already is (0.5: ``fem.FormMetaClass``, 0.11: ``fem.Form``)."""
    compiled = fem.FormMetaClass if LEGACY_API else fem.Form
    return form if isinstance(form, compiled) else fem.form(form)


def petsc_vec(u: fem.Function) -> PETSc.Vec:
    """The PETSc vector that shares ``u``'s values (ghosted)."""
    return u.vector if LEGACY_API else u.x.petsc_vec


def vector_for_form(L) -> PETSc.Vec:
    """A new (ghosted) PETSc vector laid out for the compiled linear form ``L``."""
    if LEGACY_API:
        return fem.petsc.create_vector(L)
    return fem.petsc.create_vector(L.function_spaces[0])


def set_bc(b: PETSc.Vec, bcs: list, scale: float = 1.0) -> None:
    """Owned constrained entries of ``b`` <- ``scale`` x the boundary values."""
    if LEGACY_API:
        fem.petsc.set_bc(b, bcs, scale=scale)
    else:
        fem.petsc.set_bc(b, bcs, alpha=scale)


def solve_linear(a, L, bcs: list, petsc_options: dict, prefix: str = "dolfinx_fretting_linear_") -> fem.Function:
    """Plain DOLFINx solve of the linear problem a(u, v) = L(v) with ``bcs`` (``fem.petsc.LinearProblem``;
    0.11 requires an options prefix)."""
    if LEGACY_API:
        problem = fem.petsc.LinearProblem(a, L, bcs=bcs, petsc_options=petsc_options)
    else:
        problem = fem.petsc.LinearProblem(a, L, bcs=bcs, petsc_options=petsc_options, petsc_options_prefix=prefix)
    return problem.solve()


# Expressions -------------------------------------------------------------------------------------------------
def interpolation_points(V) -> np.ndarray:
    """Reference points at which an expression is evaluated to interpolate it into ``V``."""
    points = V.element.interpolation_points
    return points() if callable(points) else points


def expression(expr, points: np.ndarray) -> fem.Expression:
    """A compiled UFL expression to evaluate at reference ``points`` (num_points, tdim)."""
    return fem.Expression(expr, np.asarray(points))


def eval_expression(compiled: fem.Expression, msh, cells: np.ndarray) -> np.ndarray:
    """Values of a compiled expression in ``cells``: shape (num_cells, num_points * value_size), each row
    point by point, value components row-major."""
    cells = np.asarray(cells, dtype=np.int32)
    values = compiled.eval(cells) if LEGACY_API else compiled.eval(msh, cells)
    return values.reshape(cells.size, -1)


def basis_gradient_expression(V, points: np.ndarray) -> fem.Expression:
    """A compiled expression of the physical gradients of the *scalar* basis of ``V``'s element (the
    scalar space of the same family and degree) at reference ``points``; evaluate it with
    :func:`eval_basis_gradients`. Collective (a function space and a JIT compilation)."""
    scalar = scalar_space(V.mesh, element_family(V), element_degree(V))
    return expression(ufl.grad(ufl.TrialFunction(scalar)), points)


def eval_basis_gradients(compiled: fem.Expression, msh, cells: np.ndarray) -> np.ndarray:
    """Values of :func:`basis_gradient_expression` in ``cells``: shape (num_cells * num_points, gdim, num_basis),
    ``[c * num_points + j, i, a]`` = d phi_a / d x_i at point j of cell c (phi_a in the cell dofmap's order)."""
    cells = np.asarray(cells, dtype=np.int32)
    gdim = msh.geometry.dim
    if LEGACY_API:
        values = compiled.eval(cells)  # (cell, point x component x basis function)
        num_basis = compiled.argument_function_space.element.space_dimension
    else:
        values = compiled.eval(msh, cells)  # (cell, point, component, basis function)
        num_basis = values.shape[-1]
    return values.reshape(-1, gdim, num_basis)


# Meshes --------------------------------------------------------------------------------------------------------
def model_to_mesh(model: gmsh.model, comm: MPI.Comm, rank: int,
                  gdim: int) -> tuple[dolfinx.mesh.Mesh, dolfinx.mesh.MeshTags, dolfinx.mesh.MeshTags]:
    """``(mesh, cell_tags, facet_tags)`` from the gmsh model that lives on ``rank``, on any tested DOLFINx.
    Collective.

    0.11: ``dolfinx.io.gmsh.model_to_mesh(model, comm, rank, gdim=gdim)`` (a named tuple: its ``mesh``,
    ``cell_tags``, ``facet_tags``); 0.5: ``dolfinx.io.gmshio.model_to_mesh`` (a tuple).

    Args:
        model: ``gmsh.model`` with its mesh generated and physical groups defined (on ``rank``; other ranks'
            models are not read).
        comm: The communicator the mesh is distributed over.
        rank: The rank that holds the model.
        gdim: Geometric dimension of the mesh (2 or 3).

    Returns:
        The mesh, its cell tags (the physical groups of dimension ``tdim``) and facet tags (those of dimension
        ``tdim - 1``), whose values are the physical groups' tags.
    """
    if LEGACY_API:
        from dolfinx.io import gmshio  # lazy: exists on 0.5-0.9 only (0.10+: dolfinx.io.gmsh); loads gmsh

        msh, cell_tags, facet_tags = gmshio.model_to_mesh(model, comm, rank, gdim=gdim)
        return msh, cell_tags, facet_tags
    from dolfinx.io import gmsh as dgmsh  # lazy: 0.10+ only, as above

    data = dgmsh.model_to_mesh(model, comm, rank, gdim=gdim)
    return data.mesh, data.cell_tags, data.facet_tags


def create_mesh(comm: MPI.Comm, cells: np.ndarray, points: np.ndarray, cell_type: str):
    """A first-order mesh from ``cells`` (vertex indices in DOLFINx's order for ``cell_type``, e.g.
    ``"hexahedron"``) and ``points`` (N, gdim) given on any ranks (typically all on rank 0, none elsewhere);
    DOLFINx distributes them with its default partitioner, as ``model_to_mesh`` does. Collective."""
    points = np.asarray(points, dtype=np.float64)
    gdim = points.shape[1]
    cells = np.asarray(cells, dtype=np.int64)
    if LEGACY_API:
        domain = ufl.Mesh(ufl.VectorElement("Lagrange", cell_type, 1))
        return dmesh.create_mesh(comm, cells, points, domain)
    import basix.ufl  # lazy: 0.10+ only (basix 0.5 has no basix.ufl)

    element = basix.ufl.element("Lagrange", cell_type, 1, shape=(gdim,))
    return dmesh.create_mesh(comm, cells, element, points)


def write_meshtags(xdmf, tags, msh) -> None:
    """Write mesh tags to an open ``XDMFFile`` after its mesh (0.10+ also take the mesh geometry). Collective."""
    if LEGACY_API:
        xdmf.write_meshtags(tags)
    else:
        xdmf.write_meshtags(tags, msh.geometry)


def cell_submesh(msh, cells: np.ndarray):
    """The submesh of some of ``msh``'s cells and, for each of its local cells (ghosts included), the local index
    of its cell in ``msh``. Collective.

    0.11: ``create_submesh`` returns an ``EntityMap`` (``sub_topology_to_topology``); 0.5: an array.

    Args:
        msh: The mesh.
        cells: Local indices of this rank's cells to keep (every rank calls, with its own).

    Returns:
        ``(submesh, parent_cells)``.
    """
    cells = np.asarray(cells, dtype=np.int32)
    submesh, entity_map, _, _ = dmesh.create_submesh(msh, msh.topology.dim, cells)
    count = submesh.topology.index_map(submesh.topology.dim)
    local = count.size_local + count.num_ghosts
    if LEGACY_API:
        return submesh, np.asarray(entity_map, dtype=np.int32)[:local]
    return submesh, np.asarray(entity_map.sub_topology_to_topology(np.arange(local, dtype=np.int32), False),
                               dtype=np.int32)


def vtk_mesh(msh, dim: int | None = None, entities: np.ndarray | None = None):
    """(topology, cell types, points) of mesh entities for VTK/pyvista.

    The cell types are VTK's linear ones on 0.5 (5 triangle, 9 quadrilateral) and its Lagrange cells on 0.11
    (69, 70); pyvista draws both, with the same first-order node order.
    """
    if LEGACY_API:
        return plot.create_vtk_mesh(msh, dim, entities)
    return plot.vtk_mesh(msh, dim, entities)


# MPI launcher ------------------------------------------------------------------------------------------------
def mpiexec(n: int) -> list[str]:
    """The command that starts ``n`` ranks of this Python's MPI, e.g. ``mpiexec(2) + [sys.executable, ...]``.

    Open MPI (Debian's): ``mpirun -n N --oversubscribe`` (run as root it also needs
    ``OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1`` in the environment). MPICH (the wheel's,
    conda-forge's): the ``mpiexec`` next to this Python if there is one, else the first on ``PATH``.
    ``DOLFINX_FRETTING_MPIEXEC`` overrides the program.

    Raises:
        FileNotFoundError: if the launcher is not found.
    """
    library = MPI.Get_library_version()
    program = os.environ.get("DOLFINX_FRETTING_MPIEXEC")
    if program is None:
        beside = os.path.join(os.path.dirname(sys.executable), "mpiexec")
        if "Open MPI" not in library and os.access(beside, os.X_OK):
            program = beside
        else:
            program = shutil.which("mpirun" if "Open MPI" in library else "mpiexec")
    if program is None:
        raise FileNotFoundError(f"no MPI launcher found for {library.splitlines()[0]!r}; "
                                "set DOLFINX_FRETTING_MPIEXEC")
    extra = ["--oversubscribe"] if "Open MPI" in library else []
    return [program, "-n", str(int(n)), *extra]
