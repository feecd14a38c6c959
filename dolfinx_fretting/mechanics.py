"""The DOLFINx side: displacement space, stiffness K, boundary conditions and stress output.

:class:`ElasticProblem` owns its PETSc objects (the assembled K and, through
:class:`~dolfinx_fretting.compliance.DelassusOperator`, the MUMPS factorisation reused for every
solve and for W = H K^-1 H^T). Loads on the contact are applied through the obstacle's rigid motion and
the contact forces, so K carries only homogeneous Dirichlet conditions (the fixed faces).
"""

from __future__ import annotations

import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from . import _dolfinx as dfx
from ._dolfinx import fem
from .compliance import DelassusOperator
from .materials import LinearElastic
from .meshes import BodyMesh

__all__ = ["ElasticProblem"]


class ElasticProblem:
    """Small-strain linear elasticity (plane strain in 2D) with fixed faces.

    K is assembled on construction; call ``self.delassus.factorize()`` once before solving (kept
    separate so that cheap input checks can run before the factorisation).

    Args:
        body: The meshed body with its facet tags.
        material: Elastic constants.
        fixed: Names of facet tags whose displacement is zero.
        delassus_method: Route for W (see :class:`DelassusOperator`).
        petsc_options: Extra PETSc options for the factorisation.
        quadrature_degree: Quadrature degree of K (default: estimated by UFL).
    """

    def __init__(self, body: BodyMesh, material: LinearElastic, fixed: list[str],
                 delassus_method: str = "auto", petsc_options: dict | None = None,
                 quadrature_degree: int | None = None):
        self.body = body
        self.material = material
        msh = body.mesh
        self.mesh = msh
        self.comm = msh.comm
        self.gdim = msh.geometry.dim
        self.V = dfx.vector_space(msh, 1)
        fdim = msh.topology.dim - 1

        zero = np.zeros(self.gdim, dtype=PETSc.ScalarType)
        self.bcs = []
        fixed_nodes = []
        for name in fixed:
            facets = body.facets(name)
            dofs = fem.locate_dofs_topological(self.V, fdim, facets)
            fixed_nodes.append(dofs)
            self.bcs.append(fem.dirichletbc(zero, dofs, self.V))
        #: Local block indices of constrained nodes (never contact candidates).
        self.fixed_nodes = np.unique(np.concatenate(fixed_nodes)) if fixed_nodes else np.zeros(0, np.int32)

        u, v = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
        # An elastic-plastic body integrates its stresses with a fixed rule (plasticity.PlasticState): K
        # then uses the same one, so that W and the elastic iteration matrix are exact where nothing yields.
        dx = ufl.dx if quadrature_degree is None else ufl.dx(metadata={"quadrature_degree": quadrature_degree,
                                                                      "quadrature_scheme": "default"})
        self._a = fem.form(ufl.inner(self.sigma(u), self.epsilon(v)) * dx)
        self.K = fem.petsc.assemble_matrix(self._a, bcs=self.bcs)
        self.K.assemble()
        self.delassus = DelassusOperator(self.K, self.comm, method=delassus_method,
                                         petsc_options=petsc_options)
        self.u = fem.Function(self.V, name="displacement")
        self._rhs = self.K.createVecRight()
        self._loads: list[PETSc.Vec] = []

    # Constitutive relations -------------------------------------------------------------------------
    def epsilon(self, u):
        return ufl.sym(ufl.grad(u))

    def sigma(self, u):
        lmbda, mu = self.material.lame
        eps = self.epsilon(u)
        return lmbda * ufl.tr(eps) * ufl.Identity(self.gdim) + 2.0 * mu * eps

    def von_mises_expression(self, u):
        """Von Mises stress; in 2D plane strain it includes sigma_zz = lambda tr(eps)."""
        s = self.sigma(u)
        if self.gdim == 2:
            lmbda, _ = self.material.lame
            szz = lmbda * ufl.tr(self.epsilon(u))
            dev = s - (ufl.tr(s) + szz) / 3.0 * ufl.Identity(2)
            szz_dev = szz - (ufl.tr(s) + szz) / 3.0
            return ufl.sqrt(1.5 * (ufl.inner(dev, dev) + szz_dev**2))
        dev = ufl.dev(s)
        return ufl.sqrt(1.5 * ufl.inner(dev, dev))

    # Solves -----------------------------------------------------------------------------------------
    def face_pressure_load(self, face: str) -> PETSc.Vec:
        """Load vector of a unit pressure on a named face, pushing into the body (traction -n). Collective.

        Returns:
            A vector owned by this problem (freed by :meth:`destroy`); zero at the fixed dofs.
        """
        msh = self.mesh
        ds = ufl.Measure("ds", domain=msh, subdomain_data=self.body.facet_tags)
        v = ufl.TestFunction(self.V)
        n = ufl.FacetNormal(msh)
        form = fem.form(-ufl.dot(n, v) * ds(self.body.tags[face]))
        f = fem.petsc.assemble_vector(form)
        fem.petsc.apply_lifting(f, [self._a], bcs=[self.bcs])
        f.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dfx.set_bc(f, self.bcs)
        self._loads.append(f)
        return f

    def local_response(self, H, f: PETSc.Vec) -> np.ndarray:
        """``H K^-1 f``: the local relative displacements due to a load vector (replicated). Collective."""
        u = f.duplicate()
        self.delassus.solve(f, u)
        rstart, rend = u.getOwnershipRange()
        part = H[:, rstart:rend] @ u.getArray(readonly=True)
        u.destroy()
        return self.comm.allreduce(part, op=MPI.SUM)

    def solve_contact_response(self, H, r: np.ndarray, load: PETSc.Vec | None = None,
                               load_factor: float = 0.0) -> fem.Function:
        """Displacement due to contact forces R = H^T r (replicated H, r) plus ``load_factor * load``.
        Collective.

        Returns:
            ``self.u`` updated (ghosts included).
        """
        rstart, rend = self._rhs.getOwnershipRange()
        R = H.T.tocsr() @ r
        owned = np.arange(rstart, rend, dtype=PETSc.IntType)
        # K's vectors are not ghosted: localForm() would hand back a null Vec in parallel.
        self._rhs.set(0.0)
        self._rhs.setValues(owned, R[rstart:rend])
        self._rhs.assemble()
        dfx.set_bc(self._rhs, self.bcs)
        if load is not None and load_factor != 0.0:
            self._rhs.axpy(load_factor, load)
        self.delassus.solve(self._rhs, dfx.petsc_vec(self.u))
        self.u.x.scatter_forward()
        return self.u

    def von_mises(self) -> fem.Function:
        """Cell-wise (DG0) von Mises stress of the current displacement."""
        if not hasattr(self, "_vm"):
            W0 = dfx.scalar_space(self.mesh, "DG", 0)
            self._vm = fem.Function(W0, name="von_mises")
            self._vm_expr = dfx.expression(self.von_mises_expression(self.u), dfx.interpolation_points(W0))
        self._vm.interpolate(self._vm_expr)
        return self._vm

    def destroy(self) -> None:
        self.delassus.destroy()
        self.K.destroy()
        self._rhs.destroy()
        for f in self._loads:
            f.destroy()
