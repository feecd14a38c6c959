"""Version-independent DOLFINx for your own scripts: the few calls whose spelling changed between DOLFINx 0.5
and 0.11 that a model needs.

``dolfinx_fretting`` is tested on DOLFINx 0.5.2 and 0.11; so are its demos, which build their meshes and spaces
with these functions. A script for one DOLFINx can write the call directly instead (each function's docstring
gives both spellings). Everything else in the demos is plain DOLFINx, the same on both versions.

Example:
    .. code-block:: python

        from mpi4py import MPI  # first: the DOLFINx 0.11 wheel needs the MPI library that mpi4py loads
        from dolfinx_fretting.compat import model_to_mesh, vector_space

        msh, cell_tags, facet_tags = model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=2)
        V = vector_space(msh, 1)   # vector P1, what Contact takes

These are re-exported from the package's one module of version differences (``_dolfinx``), which is the only
place that tests versions.
"""

from __future__ import annotations

from . import _dolfinx
from ._dolfinx import create_mesh, model_to_mesh, scalar_space, vector_space

__all__ = ["DOLFINX_VERSION", "create_mesh", "model_to_mesh", "scalar_space", "vector_space"]

#: ``(major, minor)`` of the DOLFINx in use, e.g. ``(0, 11)``.
DOLFINX_VERSION: tuple[int, int] = _dolfinx.DOLFINX_VERSION
