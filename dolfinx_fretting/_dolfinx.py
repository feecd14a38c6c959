"""The DOLFINx-version differences, in one place (the rest of the package does not test versions)."""

from __future__ import annotations

__all__ = ["element_degree", "element_family", "value_size", "petsc_vec", "vector_space", "scalar_space"]


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
