"""The DOLFINx-version differences, in one place (the rest of the package does not test versions)."""

from __future__ import annotations

__all__ = ["element_degree", "element_family", "value_size", "petsc_vec", "vector_space", "scalar_space",
           "model_to_mesh", "entities_to_geometry"]


def element_degree(V) -> int:
    """Polynomial degree of the element of ``V``."""
    return int(V.ufl_element().degree())


def element_family(V) -> str:
    """Family name of the element of ``V`` (``"Q"``, ``"P"``, ``"Lagrange"`` ...)."""
    return str(V.ufl_element().family())


def value_size(V) -> int:
    """Number of components of a function of ``V``."""
    return int(V.dofmap.index_map_bs) if V.num_sub_spaces == 0 else int(V.num_sub_spaces)


def petsc_vec(u):
    """The PETSc vector of a ``fem.Function``."""
    return u.vector


def vector_space(msh, degree: int = 1):
    """The vector Lagrange space of ``msh`` (one component per geometric dimension)."""
    from dolfinx import fem

    return fem.VectorFunctionSpace(msh, ("Lagrange", degree))


def scalar_space(msh, family: str = "Lagrange", degree: int = 1):
    """A scalar space of ``msh`` (``("DG", 0)`` for cell values)."""
    from dolfinx import fem

    return fem.FunctionSpace(msh, (family, degree))


def model_to_mesh(model, comm, rank: int, gdim: int):
    """A gmsh model (on ``rank``) as ``(mesh, cell_tags, facet_tags)``. Collective."""
    from dolfinx.io import gmshio

    return gmshio.model_to_mesh(model, comm, rank, gdim=gdim)


def entities_to_geometry(msh, dim: int, entities):
    """Geometry node indices of each entity (rows), first-order meshes."""
    import numpy as np
    from dolfinx import cpp

    return cpp.mesh.entities_to_geometry(msh._mesh, dim, np.asarray(entities, dtype=np.int32), False)
