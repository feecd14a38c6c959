"""Mesh files a test writes with gmsh, as a user would, for the scenes that read them (``geometry.kind = "file"``):
the model built on rank 0 inside one gmsh session, written, and every rank waiting for the file."""

from pathlib import Path
from typing import Callable

import gmsh
from mpi4py import MPI


def write_msh(path: Path, build: Callable[[], None], comm: MPI.Comm = MPI.COMM_WORLD, dim: int = 2) -> Path:
    """Run ``build()`` (the gmsh model: geometry, physical groups, size fields) on rank 0, mesh it in ``dim``
    dimensions (2 by default) and write ``path``; every rank returns once the file is written."""
    if comm.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        build()
        gmsh.model.mesh.generate(dim)
        gmsh.write(str(path))
        gmsh.finalize()
    comm.barrier()
    return path


def shared_folder(tmp_path_factory, name: str, comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """A temporary folder named on rank 0, the same on every rank."""
    return Path(comm.bcast(str(tmp_path_factory.mktemp(name)) if comm.rank == 0 else None, root=0))
