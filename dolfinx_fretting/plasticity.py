"""DOLFINx glue of J2 plasticity: quadrature-point state, residual, consistent tangent, commit and rollback.

The constitutive update itself is :func:`dolfinx_fretting.materials.return_mapping` (numba, on arrays)
and the plastic zone's algebra is :mod:`dolfinx_fretting.plastic_zone`; this module moves data between
DOLFINx and them, and runs the Newton loop (:class:`ElastoplasticBody`, condensed on the plastic zone by
:class:`PlasticZone`). The state:

1. the total strain of the current displacement is evaluated at the quadrature points with a
   ``fem.Expression`` (DOLFINx 0.5.2 cannot interpolate into quadrature spaces; 0.11 uses the same path);
2. the return mapping runs from the *committed* state (plastic strain, cumulative plastic strain) and
   writes the trial stress and consistent tangent into quadrature functions;
3. the residual ``F(u) = int sigma : eps(v) dx - f_ext`` and the tangent ``int eps(du) : C : eps(v) dx``
   are assembled with the same quadrature rule (forms compiled once);
4. :meth:`PlasticState.commit` copies the trial state into history only after an increment converged;
   nothing needs undoing after a failed or cut increment.

Tensors are Mandel vectors ``[xx, yy, zz, sqrt2 yz, sqrt2 xz, sqrt2 xy]``; in 2D (plane strain) the
strain has ``eps_zz = eps_yz = eps_xz = 0`` and the forms use the in-plane part ``[xx, yy, sqrt2 xy]``,
while the out-of-plane stress ``sigma_zz`` is kept in the state (it enters von Mises).
"""

from __future__ import annotations

import math
import time

import basix
import numpy as np
import scipy.sparse as sp
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from . import _dolfinx as dfx
from ._dolfinx import fem
from .compliance import DelassusOperator
from .contact import constrained_global_dofs
from .materials import J2Plasticity, return_mapping, von_mises
from .plastic_zone import (MAX_ZONE_DOFS, ZONE_MARGIN, LowRankTangent, point_strains, rows_axpy,
                           zone_tangent_matrix, zone_update)

__all__ = ["ElastoplasticBody", "NewtonError", "PlasticState", "PlasticZone", "condensation_unavailable",
           "is_radial_return", "mandel_strain"]

_SQ2 = math.sqrt(2.0)


def _in_plane(gdim: int) -> list[int]:
    """Mandel components used by the forms: in 2D (xx, yy, sqrt2 xy); in 3D all six."""
    return [0, 1, 5] if gdim == 2 else [0, 1, 2, 3, 4, 5]


def _strain_pairs(gdim: int) -> list[tuple[int, int]]:
    """(i, j) of each form component of :func:`mandel_strain`."""
    return [(0, 0), (1, 1), (0, 1)] if gdim == 2 else [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]


def mandel_strain(u, gdim: int):
    """UFL Mandel vector of the small strain of ``u`` restricted to the form components."""
    e = ufl.sym(ufl.grad(u))
    if gdim == 2:
        return ufl.as_vector([e[0, 0], e[1, 1], _SQ2 * e[0, 1]])
    return ufl.as_vector([e[0, 0], e[1, 1], e[2, 2], _SQ2 * e[1, 2], _SQ2 * e[0, 2], _SQ2 * e[0, 1]])


def is_radial_return(law) -> bool:
    """Whether ``law`` updates by :class:`~dolfinx_fretting.materials.J2Plasticity`'s own radial return (a
    subclass that overrides ``update`` does not: its update is the hook)."""
    return isinstance(law, J2Plasticity) and type(law).update is J2Plasticity.update


def _not_lagrange(V) -> str | None:
    """Why the point matrices of :meth:`PlasticState.point_matrices` cannot be built on ``V`` (None: they can)."""
    family, degree = dfx.element_family(V), dfx.element_degree(V)
    if family not in ("P", "Q", "Lagrange", "CG"):
        return (f"the displacement space's element is {family!r} degree {degree}; the strains at the points are "
                "built from the gradients of a continuous Lagrange basis (families P, Q, Lagrange)")
    return None


def condensation_unavailable(law, V) -> str | None:
    """Why the condensed Newton iteration (:class:`PlasticZone`) cannot run for ``law`` on ``V``, or None.

    The zone's kernel (:func:`~dolfinx_fretting.plastic_zone.zone_update`) *is* J2's radial return and its
    tangent difference C_T - C_e, so another constitutive update (the ``Plasticity.law`` hook) cannot be
    condensed; and the points' strain-displacement matrices need a continuous Lagrange space. Such bodies
    run Newton by refactorising the tangent (the same iterates, slower).
    """
    if not is_radial_return(law):
        return (f"the law {type(law).__name__} has its own update (the condensed kernel is J2Plasticity's "
                "radial return)")
    return _not_lagrange(V)


class PlasticState:
    """Quadrature-point state of a J2 body and the forms that use it. Collective to build.

    Args:
        V: Displacement space (vector Lagrange).
        law: The material.
        quadrature_degree: Degree of the quadrature rule (2: 2 x 2 Gauss on quadrilaterals).

    Attributes:
        sigma, eps_p, p: Committed state per quadrature point (numpy, (n, 6), (n, 6), (n,)), owned cells.
        trial_*: State of the last :meth:`update` (becomes the committed one at :meth:`commit`).
        yielded: Points that yielded in the last update.
    """

    def __init__(self, V: fem.FunctionSpace, law: J2Plasticity, quadrature_degree: int = 2,
                 elastic_cells: np.ndarray | None = None):
        self.V = V
        self.law = law
        msh = V.mesh
        self.mesh = msh
        self.gdim = gdim = msh.geometry.dim
        self.comps = _in_plane(gdim)
        k = len(self.comps)
        points, _ = basix.make_quadrature(dfx.basix_cell(msh), quadrature_degree)
        self.nq = points.shape[0]
        self._degree = quadrature_degree
        tdim = msh.topology.dim
        self.cells = np.arange(msh.topology.index_map(tdim).size_local, dtype=np.int32)
        n = self.cells.size * self.nq
        self.n_points = n
        # Cells of a body that stays elastic (two bodies, one of them plastic): their points use the same
        # elastic constants and a yield stress that is never reached.
        self.elastic_points = np.zeros(n, dtype=bool)
        if elastic_cells is not None and len(elastic_cells):
            in_elastic = np.isin(self.cells, elastic_cells)
            self.elastic_points = np.repeat(in_elastic, self.nq)
        self._elastic_law = J2Plasticity(law.E, law.nu, np.inf, 0.0)

        md = {"quadrature_degree": quadrature_degree, "quadrature_scheme": "default"}
        self.dx = ufl.dx(domain=msh, metadata=md)
        S = dfx.quadrature_space(msh, quadrature_degree, (k,))
        T = dfx.quadrature_space(msh, quadrature_degree, (k, k))
        self._stress = fem.Function(S)      # trial stress, form components
        self._tangent = fem.Function(T)     # consistent tangent, form components
        # Quadrature dofs of the owned cells, in (cell, point) order: where point j of cell c lives.
        self._blocks = dfx.cell_dofmap(S)[self.cells].ravel()

        u_, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        self._u = fem.Function(V)
        self._strain_expr = dfx.expression(mandel_strain(self._u, gdim), points)
        self.residual_form = fem.form(ufl.inner(self._stress, mandel_strain(v, gdim)) * self.dx)
        self.tangent_form = fem.form(ufl.inner(ufl.dot(self._tangent, mandel_strain(u_, gdim)),
                                               mandel_strain(v, gdim)) * self.dx)

        self.sigma = np.zeros((n, 6))
        self.eps_p = np.zeros((n, 6))
        self.p = np.zeros(n)
        self.trial_sigma = self.sigma.copy()
        self.trial_eps_p = self.eps_p.copy()
        self.trial_p = self.p.copy()
        self.yielded = np.zeros(n, dtype=bool)
        self.update_count = 0
        self._point_coordinates: np.ndarray | None = None  # point_coordinates(), computed once

    # ------------------------------------------------------------------------------------------------
    def point_coordinates(self) -> np.ndarray:
        """(n, 3) coordinates of the quadrature points of the owned cells, in the order of ``sigma``'s rows (what a
        checkpoint keys the plastic state by: they do not depend on the partition). Collective the first time (a
        JIT compile); the cells never change, so every checkpoint after the first reuses them."""
        if self._point_coordinates is None:
            points, _ = basix.make_quadrature(dfx.basix_cell(self.mesh), self._degree)
            expression = dfx.expression(ufl.SpatialCoordinate(self.mesh), points)
            coordinates = dfx.eval_expression(expression, self.mesh, self.cells).reshape(-1, self.gdim)
            self._point_coordinates = np.column_stack([coordinates, np.zeros((coordinates.shape[0], 3 - self.gdim))])
        return self._point_coordinates

    def strain(self, u: fem.Function) -> np.ndarray:
        """Total strain (n, 6) Mandel at the quadrature points of the owned cells."""
        self._u.x.array[:] = u.x.array
        vals = dfx.eval_expression(self._strain_expr, self.mesh, self.cells).reshape(-1, len(self.comps))
        eps = np.zeros((vals.shape[0], 6))
        eps[:, self.comps] = vals
        return eps

    def update(self, u: fem.Function, tangent: bool = True, eps: np.ndarray | None = None) -> None:
        """Return mapping from the committed state at the strain of ``u``; fills the stress function used by
        the residual form and, if ``tangent``, the consistent tangent used by the tangent form (collective
        only through the ghost update). ``eps``: the strain of ``u`` at the points if already known."""
        eps = self.strain(u) if eps is None else eps
        # The law's own update (the constitutive hook of problem.Plasticity; for J2Plasticity's own update the
        # radial return, called directly so that the tangent is computed only when asked for).
        if is_radial_return(self.law):
            sigma, eps_p, p, C, yielded = return_mapping(self.law, eps, self.eps_p, self.p, tangent=tangent)
        else:
            sigma, eps_p, p, C, yielded = self.law.update(eps, self.eps_p, self.p)
        if self.elastic_points.any():
            e = self.elastic_points
            out = return_mapping(self._elastic_law, eps[e], self.eps_p[e], self.p[e], tangent=tangent)
            sigma[e], eps_p[e], p[e], yielded[e] = out[0], out[1], out[2], out[4]
            if tangent:
                C[e] = out[3]
        self.trial_sigma, self.trial_eps_p, self.trial_p, self.yielded = sigma, eps_p, p, yielded
        k = len(self.comps)
        comps = np.asarray(self.comps)
        stress = self._stress.x.array.reshape(-1, k)
        stress[self._blocks] = sigma[:, comps]
        self._stress.x.scatter_forward()
        if tangent:
            Ck = self._tangent.x.array.reshape(-1, k, k)
            Ck[self._blocks] = C[:, comps[:, None], comps[None, :]]
            self._tangent.x.scatter_forward()
        self.update_count += 1

    def point_matrices(self, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Strain-displacement matrices and weights of the quadrature points of ``cells`` (owned, local).

        Returns:
            ``B`` (len(cells) * nq, k, nd): the form components of the strain at each point, ``B @ u_cell``,
            with ``u_cell`` the cell's dofs node-major (``[u_0x, u_0y, u_1x, ...]``, the dofmap's order);
            ``w`` (len(cells) * nq,): quadrature weight x ``|det J|``, so that ``sum w B^T C B`` is the
            element stiffness of the forms.

        Raises:
            ValueError: the displacement space is not continuous Lagrange (any degree; tested 1 to 3).
        """
        if not hasattr(self, "_grad_expr"):
            # The gradients of the scalar basis of the same element give B (DOLFINx 0.5.2 tabulates an
            # Expression with a *scalar* argument correctly; a blocked one comes back wrong).
            # Collective (a function space and two JIT-compiled expressions): the first call must come
            # from every rank, with or without cells.
            reason = _not_lagrange(self.V)
            if reason is not None:
                raise ValueError(f"PlasticState.point_matrices: {reason}")
            points, weights = basix.make_quadrature(dfx.basix_cell(self.mesh), self._degree)
            self._grad_expr = dfx.basis_gradient_expression(self.V, points)
            self._detj_expr = dfx.expression(abs(ufl.JacobianDeterminant(self.mesh)), points)
            self._qweights = weights
        cells = np.asarray(cells, dtype=np.int32)
        gdim, nq = self.gdim, self.nq
        grads = dfx.eval_basis_gradients(self._grad_expr, self.mesh, cells)  # (point, d/dx_i, node)
        nn = grads.shape[2]
        B = np.zeros((cells.size * nq, len(self.comps), gdim * nn))
        for a, (i, j) in enumerate(_strain_pairs(gdim)):
            if i == j:  # eps_ii = du_i/dx_i
                B[:, a, i::gdim] = grads[:, i]
            else:  # sqrt2 eps_ij = (du_i/dx_j + du_j/dx_i) / sqrt2
                B[:, a, i::gdim] = grads[:, j] / _SQ2
                B[:, a, j::gdim] = grads[:, i] / _SQ2
        w = (dfx.eval_expression(self._detj_expr, self.mesh, cells).reshape(cells.size, nq) * self._qweights).ravel()
        return B, w

    def commit(self) -> None:
        """Make the last update the history (call only after a converged increment)."""
        self.sigma, self.eps_p, self.p = self.trial_sigma.copy(), self.trial_eps_p.copy(), self.trial_p.copy()

    def assemble_residual(self, b: PETSc.Vec, bcs: list) -> None:
        """b <- internal forces of the last update (Dirichlet rows zeroed). Collective."""
        with b.localForm() as loc:
            loc.set(0.0)
        fem.petsc.assemble_vector(b, self.residual_form)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dfx.set_bc(b, bcs, scale=0.0)

    def assemble_tangent(self, A: PETSc.Mat, bcs: list) -> None:
        """A <- consistent tangent of the last update (identity on Dirichlet rows). Collective."""
        A.zeroEntries()
        fem.petsc.assemble_matrix(A, self.tangent_form, bcs=bcs)
        A.assemble()

    def create_tangent(self, bcs: list) -> PETSc.Mat:
        A = fem.petsc.assemble_matrix(self.tangent_form, bcs=bcs)
        A.assemble()
        return A

    # Output -------------------------------------------------------------------------------------------
    def cell_average(self, values: np.ndarray) -> np.ndarray:
        """Average of per-point values over each owned cell."""
        return values.reshape(self.cells.size, self.nq).mean(axis=1)

    def von_mises(self, sigma: np.ndarray | None = None) -> np.ndarray:
        return von_mises(self.sigma if sigma is None else sigma)


class NewtonError(RuntimeError):
    """A Newton loop did not converge; the message gives the iteration norms."""


class _ZoneGrew(Exception):
    """Points outside the plastic zone yielded: the zone grew and the increment starts again."""


class _ZoneTooLarge(Exception):
    """The plastic zone outgrew ``max_zone_dofs``: the refactorising path takes over."""


class _CondensedMismatch(Exception):
    """The converged condensed iterate failed its check on the whole body (see ``_verify``)."""


def _replicated(comm, a: np.ndarray, op) -> None:
    """In-place reduction of ``a`` over ``comm``, bitwise identical on every rank (reduced on rank 0, then
    broadcast): the replicated algebra of the condensed iteration takes decisions (converged or not) on
    it, and every rank must take the same ones."""
    comm.Reduce(MPI.IN_PLACE if comm.rank == 0 else a, a if comm.rank == 0 else None, op=op, root=0)
    comm.Bcast(a, root=0)


class PlasticZone:
    """The cells where plastic strain may appear, their points, and the elastic inverse on their dofs.
    Collective to build and to grow; the algebra on it is replicated (identical on every rank).

    X is the set of (global, unconstrained) dofs of the zone's cells and of the contact; ``Z = (K^-1)_XX``
    (one MUMPS selected inverse of the elastic factor per growth), ``HZ = H[:, X] Z = (H K^-1)[:, X]``,
    ``aX = (K^-1 f)_X`` for the unit load f of :meth:`set_load`. The zone's points (owned cells only) carry their B matrices,
    weights and the positions in X of their cell's dofs (see :mod:`dolfinx_fretting.plastic_zone`).
    """

    #: Calls of :meth:`inverse_of` between two full products Z g.
    refresh_every = 200

    def __init__(self, body: ElastoplasticBody):
        self.body = body
        state, operators = body.state, body.operators
        self.comm = body.comm
        V = state.V
        bs = V.dofmap.index_map_bs
        ncells = state.cells.size
        nodes = dfx.cell_dofmap(V)[:ncells]
        gnodes = V.dofmap.index_map.local_to_global(nodes.ravel()).reshape(nodes.shape).astype(np.int64)
        comp = np.arange(bs)
        #: (ncells, nd) global / local dofs of the owned cells, node-major (the order of B's columns).
        self.cell_gdofs = (bs * gnodes[:, :, None] + comp).reshape(ncells, -1)
        cell_ldofs = (bs * nodes[:, :, None].astype(np.int64) + comp).reshape(ncells, -1)
        # Constrained dofs (value 0, not in X).
        self.cell_fixed = np.isin(self.cell_gdofs, constrained_global_dofs(V, operators.bcs))
        self.S = np.unique(body.H.indices).astype(np.int64)  # the contact's dofs
        self.comps = np.asarray(state.comps, dtype=np.int64)
        self.rstart, self.rend = body.rstart, body.rend
        self.cell_mask = np.zeros(ncells, dtype=bool)
        #: K^-1 f (this rank's owned entries) of each load vector met, by id: one solve per load, ever (the
        #: vector is kept beside it, so that its id cannot be reused by another vector).
        self._responses: dict[int, tuple[PETSc.Vec, np.ndarray]] = {}
        self._load_terms: tuple = ()
        # Every owned point's B (the check of a converged iterate needs the strain everywhere; B @ u is
        # cheaper than the fem.Expression and the same to rounding).
        self.B_all, self.w_all = state.point_matrices(state.cells)
        self.ldofs_all = np.repeat(cell_ldofs, state.nq, axis=0)
        self.builds = 0
        self.build_time = 0.0
        self._build()

    # ------------------------------------------------------------------------------------------------
    def _union(self, local: np.ndarray) -> np.ndarray:
        if self.comm.size == 1:
            return np.unique(local)
        return np.unique(np.concatenate(self.comm.allgather(np.asarray(local, dtype=np.int64))))

    def grow(self, seed: np.ndarray) -> None:
        """Add the owned cells ``seed`` (bool mask or indices) and ``margin`` layers of neighbours (through
        shared dofs, across ranks), then rebuild. Collective."""
        new = self.cell_mask.copy()
        new[seed] = True
        for _ in range(self.body.zone_margin):
            dofs = self._union(self.cell_gdofs[new].ravel())
            new |= np.isin(self.cell_gdofs, dofs).any(axis=1)
        self.cell_mask = new
        self._build()

    def _build(self) -> None:
        """X, Z, HZ, aX and the zone's points for the current cells. Collective."""
        t0 = time.perf_counter()
        body, state = self.body, self.body.state
        cells = np.flatnonzero(self.cell_mask)
        gd, fixed = self.cell_gdofs[cells], self.cell_fixed[cells]
        X = np.union1d(self._union(gd[~fixed]), self.S)
        if X.size > body.max_zone_dofs:
            raise _ZoneTooLarge(f"the plastic zone needs {X.size} dofs, more than max_zone_dofs = "
                                f"{body.max_zone_dofs}")
        N = body.operators.K.getSize()[0]
        EX = sp.csr_matrix((np.ones(X.size), (np.arange(X.size), X)), shape=(X.size, N))
        self.Z = np.ascontiguousarray(body.operators.delassus.build(EX))  # (K^-1)_XX, replicated
        self.X = X
        self.HX = body.H[:, X].tocsr()
        self.HZ = np.ascontiguousarray((self.HX @ self.Z))
        self.ZH = np.ascontiguousarray(self.HZ.T)
        self.own = np.flatnonzero((X >= self.rstart) & (X < self.rend))
        self.own_local = (X[self.own] - self.rstart).astype(np.int64)
        self.aX = self._load_response_on_X()
        # The zone's points: every point of its cells that may yield (an elastic body's points never do).
        nq = state.nq
        pts = (cells[:, None] * nq + np.arange(nq)).ravel()
        keep = ~state.elastic_points[pts]
        dofpos = np.searchsorted(X, gd)
        dofpos[fixed] = -1
        self.points = pts[keep]
        self.B = np.ascontiguousarray(self.B_all[self.points])
        self.w = np.ascontiguousarray(self.w_all[self.points])
        self.dofpos = np.ascontiguousarray(np.repeat(dofpos, nq, axis=0)[keep]).astype(np.int64)
        self.point_mask = np.zeros(state.n_points, dtype=bool)
        self.point_mask[self.points] = True
        self._Zg = None  # see inverse_of
        n = self.points.size
        self.out = {"eps": np.zeros((n, 6)), "sigma": np.zeros((n, 6)), "eps_p": np.zeros((n, 6)),
                    "p": np.zeros(n), "dC": np.zeros((n, 6, 6)), "yielded": np.zeros(n, dtype=np.bool_),
                    "g": np.zeros(X.size)}
        self.builds += 1
        self.build_time += time.perf_counter() - t0

    def set_load(self, terms: tuple) -> None:
        """The applied unit load is ``sum c_i f_i`` over ``terms = ((f_i, c_i), ...)``: ``aX`` becomes its
        K^-1 response on X, combined from one cached response per load vector (a face pressure and a
        traction, say, applied with changing factors). Collective."""
        terms = tuple((vec, float(c)) for vec, c in terms)
        if len(terms) == len(self._load_terms) and all(
                a is b and c == d for (a, c), (b, d) in zip(terms, self._load_terms)):
            return
        self._load_terms = terms
        self.aX = self._load_response_on_X()

    def _load_response_on_X(self) -> np.ndarray:
        owned = np.zeros(self.body.rend - self.body.rstart)
        for vec, c in self._load_terms:
            if id(vec) not in self._responses:
                a = vec.duplicate()
                self.body.operators.delassus.solve(vec, a)
                self._responses[id(vec)] = (vec, a.getArray(readonly=True).copy())
                a.destroy()
            owned += c * self._responses[id(vec)][1]
        return self.gather(owned)

    # ------------------------------------------------------------------------------------------------
    def gather(self, owned: np.ndarray) -> np.ndarray:
        """Values on X of a vector given by this rank's owned entries (replicated result). Collective."""
        v = np.zeros(self.X.size)
        v[self.own] = owned[self.own_local]
        if self.comm.size > 1:
            _replicated(self.comm, v, MPI.SUM)
        return v

    def strain_all(self, u: fem.Function) -> np.ndarray:
        """Strain (n, 6) at every owned point of ``u`` (ghosts up to date)."""
        eps = np.empty((self.ldofs_all.shape[0], 6))
        point_strains(self.B_all, self.ldofs_all, u.x.array, self.comps, eps)
        return eps

    def load_committed(self) -> None:
        """The committed plastic state at the zone's points (the return mapping starts from it)."""
        state = self.body.state
        self.eps_p_old = np.ascontiguousarray(state.eps_p[self.points])
        self.p_old = np.ascontiguousarray(state.p[self.points])

    def evaluate(self, uX: np.ndarray) -> tuple[np.ndarray, int]:
        """Return mapping at the zone's points for ``uX``: (plastic forces on X, yielded points). Collective."""
        zone_update(self.body.state.law, self.B, self.w, self.dofpos, self.comps, uX, self.eps_p_old,
                    self.p_old, self.out)
        g, yielded = self.out["g"], int(self.out["yielded"].sum())
        if self.comm.size > 1:
            g = g.copy()
            _replicated(self.comm, g, MPI.SUM)
            yielded = self.comm.allreduce(yielded, op=MPI.SUM)
        return g.copy(), yielded

    def inverse_of(self, g: np.ndarray) -> np.ndarray:
        """(K^-1 E_X g)_X = Z g, from the last one by the entries of g that changed (g changes only at the
        dofs of the points whose plastic strain changed: a few dozen rows of Z instead of all of them).
        Recomputed in full every ``refresh_every`` calls, so that rounding cannot accumulate."""
        if self._Zg is None or self._Zg_calls >= self.refresh_every:
            self._g, self._Zg, self._Zg_calls = g.copy(), self.Z @ g, 0
        else:
            changed = np.flatnonzero(g != self._g)
            if changed.size:
                rows_axpy(self._Zg, self.Z, changed, g[changed] - self._g[changed])
                self._g = g.copy()
            self._Zg_calls += 1
        return self._Zg.copy()

    def tangent(self, W: np.ndarray):
        """The consistent tangent of the last :meth:`evaluate` as a low-rank correction of K (None when
        nothing yields: K itself). Collective."""
        out = self.out
        pos = self.dofpos[out["yielded"]].ravel()
        touched = np.zeros(self.X.size, dtype=np.int8)
        touched[pos[pos >= 0]] = 1
        if self.comm.size > 1:
            _replicated(self.comm, touched, MPI.MAX)
        P = np.flatnonzero(touched)
        if P.size == 0:
            return None
        D = zone_tangent_matrix(self.B, self.w, self.dofpos, self.comps, out["dC"], out["yielded"], P, self.X.size)
        if self.comm.size > 1:
            _replicated(self.comm, D, MPI.SUM)
        return LowRankTangent(P, D, self.Z, self.HZ, W, self.ZH)


class ElastoplasticBody:
    """Newton-Raphson on the equilibrium of a J2 body with the contact solve inside each iteration
    (paper Fig. 4). Collective.

    Iteration i from the displacement u_i (residual R_i = F_int(u_i) - s f, f the unit face load):

        u_pred = u_i - K^-1 R_i,   local problem on W = H K^-1 H^T with q_body = H u_pred -> r,
        u_{i+1} = u_pred + K^-1 H^T r,

    converged when the out-of-balance force ||F_int - s f - H^T r|| <= delta_1 * (force scale) and the
    last correction ||u_{i+1} - u_i|| <= delta_2 * ||u_{i+1} - u_start|| (a first iteration with the
    elastic K is exact where the increment stays elastic: only delta_1 is asked of it). ``K`` is the
    elastic stiffness throughout with ``tangent = "elastic"`` (the initial-stiffness method); the
    consistent tangent at the current iterate from the second iteration on with ``"consistent"`` (full
    Newton: the elastic K in the first) and ``"adaptive"`` (the first iteration with the tangent the
    previous increment converged with: where the plastic flow of one increment repeats in the next, as in
    the sliding phases of fretting, two iterations instead of five; its first iteration is never accepted
    alone). The wear gap is held fixed during the loop (the caller updates it after convergence), and the
    plastic state is committed by the caller only after convergence.

    **How the tangent is applied** (``condensed``, the default): K_T differs from K only on the dofs of the
    cells that yield, so K_T^-1 and its W are the elastic ones corrected by a low-rank (Woodbury) term on
    those dofs, from the entries of K^-1 on the plastic zone's dofs X (:class:`PlasticZone`,
    :mod:`dolfinx_fretting.plastic_zone`); the plastic forces F_int - K u live on X too. So an iteration runs
    on X alone: no refactorisation, no W rebuild, no solve with the whole body. These are the same
    iterates as with a refactorised K_T (to rounding) as long as nothing yields outside the zone: the
    converged iterate is then checked on the whole body (one solve, the return mapping at every point, the
    residual assembled by DOLFINx); if a point outside the zone yielded, the zone grows (its cells plus
    ``zone_margin`` layers) and the increment starts again; if the check's out-of-balance force misses
    delta_1, the increment is redone by refactorisation (``condensed_fallbacks``). A zone larger than
    ``max_zone_dofs`` dofs switches the body to refactorisation for good (``condensed = False``): K_T
    assembled and refactorised (numeric only) and W rebuilt by selected inverse at each tangent.

    Args:
        operators: The elastic problem's operators (space, K, Dirichlet conditions, its factorisation).
        law: The J2 material.
        H: Contact operator (replicated, global dofs).
        W: Delassus matrix of the elastic K.
        face_load: Load vector of a unit face pressure, or None (several loads: :meth:`set_loads`).
        tangent: ``"elastic"``, ``"consistent"`` or ``"adaptive"``.
        max_iter, delta_1, delta_2: Newton settings.
        quadrature_degree: Of the plastic state.
        elastic_cells: Cells that stay elastic (the other body).

    Attributes:
        u: Committed displacement.
        state: The :class:`PlasticState` (committed and last trial state).
        refactorizations: MUMPS refactorisations of K_T (refactorising path).
        tangent_updates: Low-rank tangents formed (condensed path).
        zone_growths: Increments started again because the plastic zone grew.
        condensed_fallbacks: Increments the condensed path handed to refactorisation.
    """

    #: Condense the iterations on the plastic zone (see the class docstring); False: refactorise.
    condensed = True
    #: Largest plastic zone (dofs of X) kept condensed (:data:`~dolfinx_fretting.plastic_zone.MAX_ZONE_DOFS`).
    max_zone_dofs = MAX_ZONE_DOFS
    #: Layers of neighbour cells added around the yielding cells (:data:`~dolfinx_fretting.plastic_zone.ZONE_MARGIN`).
    zone_margin = ZONE_MARGIN

    def __init__(self, operators, law: J2Plasticity, H, W: np.ndarray, face_load: PETSc.Vec | None,
                 tangent: str = "elastic", max_iter: int = 50, delta_1: float = 1e-8, delta_2: float = 1e-8,
                 quadrature_degree: int = 2, elastic_cells: np.ndarray | None = None):
        self.MPI = MPI
        #: The problem's :class:`~dolfinx_fretting.operators.ContactOperators` (K, its factorisation, the bcs).
        self.operators = operators
        self.comm = operators.comm
        self.H = H.tocsr()
        self.HT = self.H.T.tocsr()
        self.W_elastic = W
        self.face_load = face_load
        self.tangent = tangent
        self.max_iter = max_iter
        self.delta_1 = delta_1
        self.delta_2 = delta_2
        self.state = PlasticState(operators.V, law, quadrature_degree, elastic_cells)
        V = operators.V
        self.u = fem.Function(V, name="displacement")        # committed
        self._trial = fem.Function(V)
        self._work = (fem.Function(V), fem.Function(V))  # u_pred and the contact correction, reused
        self._rhs = operators.K.createVecRight()
        self._z = operators.K.createVecRight()
        self._fint = dfx.vector_for_form(self.state.residual_form)
        self.rstart, self.rend = self._rhs.getOwnershipRange()
        self._HS = self.H[:, self.rstart:self.rend].tocsr()
        self._tangent_op = None
        self._KT = None
        self._W_tangent = None
        self.refactorizations = 0
        self.tangent_updates = 0
        self.zone_growths = 0
        self.condensed_fallbacks = 0
        self.zone: PlasticZone | None = None
        self._serial_ksp = None
        self._kept = None  # the adaptive tangent of the condensed path (a LowRankTangent), or None: K
        self.last_info: dict = {}
        #: The applied unit load as ``((vector, coefficient), ...)`` (see :meth:`set_loads`); ``face_load``
        #: is their sum (the vector itself for one load).
        self._load_terms: tuple = ((face_load, 1.0),) if face_load is not None else ()
        self._combined: PETSc.Vec | None = None  # face_load when it sums several loads (this body's own)
        #: Why this body cannot run the condensed iteration (None: it can); it then refactorises.
        self.condensed_unavailable = condensation_unavailable(law, V)
        if self.condensed_unavailable is not None:
            self.condensed = False

    def set_loads(self, terms) -> float:
        """Apply the loads ``terms = ((vector, factor), ...)`` in the next increments (each vector a load of
        the whole body, zero at the Dirichlet dofs; any number of them, e.g. a face pressure and a traction
        with their own factors). Returns the scale to pass to :meth:`increment`: one load is applied as its
        vector times its factor, several as their sum at scale 1 (a vector of this body's, made again only
        when the factors change). The condensed iteration combines one cached K^-1 response per vector.
        Collective."""
        terms = tuple((vec, float(c)) for vec, c in terms if c != 0.0)
        if len(terms) <= 1:
            unit, scale = (((terms[0][0], 1.0),), terms[0][1]) if terms else ((), 0.0)
        else:
            unit, scale = terms, 1.0
        same = len(unit) == len(self._load_terms) and all(
            a is b and c == d for (a, c), (b, d) in zip(unit, self._load_terms))
        if not same:
            if self._combined is not None:
                self._combined.destroy()
                self._combined = None
            if len(unit) > 1:
                self._combined = unit[0][0].copy()
                self._combined.scale(unit[0][1])
                for vec, c in unit[1:]:
                    self._combined.axpy(c, vec)
            self.face_load = self._combined if len(unit) > 1 else (unit[0][0] if unit else None)
            self.__dict__.pop("_fnorm", None)  # the cached norm is the force scale of the Newton test
            self._load_terms = unit
        return scale

    def describe(self) -> dict[str, str]:
        """What the Newton loop did so far, in words (a run's ``modelled`` text): ``"iteration"`` (how the
        tangent was applied, with its counts) and ``"delassus"`` (how the tangent's W was made)."""
        z = self.zone
        refactorised = (f"{self.refactorizations} tangent refactorisation(s) (K_T assembled and factorised, "
                        "W rebuilt by selected inverse)")
        if self.condensed or z is not None:
            zone = (f"plastic zone of {z.X.size} dofs ({z.builds} build(s) of K^-1 on its dofs by selected inverse, "
                    f"{self.zone_growths} increment(s) restarted because it grew)" if z is not None
                    else "no plastic zone yet")
            iteration = (f"condensed on the plastic zone: {self.tangent_updates} tangent update(s) as low-rank "
                         f"(Woodbury) corrections of K^-1 and W, each converged increment checked on the whole "
                         f"body; {zone}")
            if self.condensed_fallbacks or self.refactorizations:
                iteration += (f"; {self.condensed_fallbacks} increment(s) redone by refactorisation, "
                              + refactorised)
            if not self.condensed:
                iteration += "; the zone outgrew max_zone_dofs, refactorising since"
            delassus = "W of the tangent = the elastic W minus a low-rank term on the yielded cells' dofs"
        else:
            why = self.condensed_unavailable or "ElastoplasticBody.condensed = False"
            iteration = f"not condensed ({why}): {refactorised}"
            delassus = "W of the tangent rebuilt at each refactorisation"
        return {"iteration": iteration, "delassus": delassus}

    # Linear algebra helpers ---------------------------------------------------------------------------
    def _H_dot(self, u: fem.Function) -> np.ndarray:
        n = self.rend - self.rstart
        return self.comm.allreduce(self._HS @ u.x.array[:n], op=self.MPI.SUM)

    def _solve_into(self, op, b: PETSc.Vec, out: fem.Function) -> None:
        op.solve(b, dfx.petsc_vec(out))
        out.x.scatter_forward()

    def _residual(self, u: fem.Function, pressure: float) -> PETSc.Vec:
        """R = F_int(u) - s f into self._rhs (non-ghosted, Dirichlet rows 0); updates the trial state."""
        self.state.update(u)
        return self._assembled_residual(pressure)

    def _assembled_residual(self, pressure: float) -> PETSc.Vec:
        """R = F_int - s f of the last state update into self._rhs."""
        self.state.assemble_residual(self._fint, self.operators.bcs)
        n = self.rend - self.rstart
        self._rhs.getArray()[:] = self._fint.getArray(readonly=True)[:n]
        if self.face_load is not None and pressure != 0.0:
            self._rhs.axpy(-pressure, self.face_load)
        return self._rhs

    def _contact_force(self, r: np.ndarray) -> np.ndarray:
        return (self.HT @ r)[self.rstart:self.rend]

    @property
    def tangent(self) -> str:
        return self._tangent_mode

    @tangent.setter
    def tangent(self, mode: str) -> None:
        if mode not in ("elastic", "consistent", "adaptive"):
            raise ValueError(f"solver.newton_tangent = {mode!r}: allowed 'elastic', 'consistent', 'adaptive'")
        self._tangent_mode = mode

    def _operator(self, refresh: bool):
        """(factorised operator, W) of the iteration matrix; ``refresh``: refactorise the current tangent."""
        if self.tangent == "elastic" or ((self._KT is None or self._W_tangent is None) and not refresh):
            return self.operators.delassus, self.W_elastic
        if self.tangent == "consistent" and not refresh:
            return self.operators.delassus, self.W_elastic
        if not refresh:
            return self._tangent_op, self._W_tangent
        if self._KT is None:
            self._KT = self.state.create_tangent(self.operators.bcs)
            self._tangent_op = DelassusOperator(self._KT, self.comm, method="auto",
                                                options_prefix="dolfinx_fretting_tangent_")
            self._tangent_op.factorize()
        else:
            self.state.assemble_tangent(self._KT, self.operators.bcs)
            self._tangent_op.refactorize()
        self._W_tangent = self._tangent_op.build(self.H)   # the same bits on every rank (build's Bcast)
        self.refactorizations += 1
        return self._tangent_op, self._W_tangent

    # The increment ------------------------------------------------------------------------------------
    def increment(self, local_solve, pressure: float) -> tuple:
        """Newton loop of one increment from the committed state.

        Args:
            local_solve: ``local_solve(q_body, W) -> IncrementResult`` (the contact solve with its load control;
                its ``forces`` enter the equilibrium; called on every rank with identical input; must raise on
                failure).
            pressure: Face pressure of the increment.

        Returns:
            (the contact solution of the last iteration, info with iterations and norms).

        Raises:
            NewtonError: no convergence within ``max_iter`` or non-finite norms (nothing committed).
        """
        if self.condensed:
            try:
                return self._increment_condensed(local_solve, pressure)
            except _ZoneTooLarge:
                self.condensed = False  # for good: this body's plastic zone is too large to condense
                self.zone = None
                self._kept = None
            except _CondensedMismatch:
                self.condensed_fallbacks += 1
        return self._increment_refactorizing(local_solve, pressure)

    def _increment_refactorizing(self, local_solve, pressure: float) -> tuple:
        """The Newton loop with K_T assembled, refactorised and its W rebuilt (see the class docstring)."""
        u_i = self._trial
        u_i.x.array[:] = self.u.x.array
        history = []
        solved = None
        R = self._residual(u_i, pressure)
        n = self.rend - self.rstart
        # The first iteration's matrix is K (the exact tangent of an increment that stays elastic: one
        # iteration, no refactorisation) or, "adaptive", the last tangent; the tangent from the second on.
        refresh = False
        for it in range(self.max_iter):
            op, W = self._operator(refresh)
            if it == 0:
                first_is_K = op is self.operators.delassus
            # u_pred = u_i - K^-1 R
            z = self._work[0]
            self._solve_into(op, R, z)
            u_pred = z
            u_pred.x.array[:] = u_i.x.array - z.x.array
            solved = local_solve(self._H_dot(u_pred), W)
            # u_new = u_pred + K^-1 H^T r
            self._z.getArray()[:] = self._contact_force(solved.forces)
            dfx.set_bc(self._z, self.operators.bcs, scale=0.0)
            c = self._work[1]
            self._solve_into(op, self._z, c)
            u_new = c
            u_new.x.array[:] = u_pred.x.array + c.x.array
            du = u_new.x.array[:n] - u_i.x.array[:n]
            R = self._residual(u_new, pressure)
            out_of_balance = R.getArray(readonly=True) - self._contact_force(solved.forces)
            sums = np.array([out_of_balance @ out_of_balance, du @ du,
                             np.sum((u_new.x.array[:n] - self.u.x.array[:n]) ** 2),
                             self._z.getArray(readonly=True) @ self._z.getArray(readonly=True),
                             float(self.state.yielded.sum()),
                             R.getArray(readonly=True) @ R.getArray(readonly=True)])
            sums = self.comm.allreduce(sums, op=self.MPI.SUM)
            res, dun, incn, fc = np.sqrt(sums[:4])
            # Force scale: contact forces, face load, or the internal forces (R ~ F_int when both vanish).
            fscale = max(fc, abs(pressure) * self._face_norm(), math.sqrt(sums[5]), 1e-300)
            d1 = res / fscale
            d2 = dun / max(incn, 1e-300)
            history.append((it + 1, d1, d2, int(sums[4])))
            u_i.x.array[:] = u_new.x.array
            if not (np.isfinite(d1) and np.isfinite(d2)):
                break
            if d1 <= self.delta_1 and ((it == 0 and first_is_K) or d2 <= self.delta_2):
                self.last_info = {"newton_iterations": it + 1, "delta_1": d1, "delta_2": d2,
                                  "yielded_points": int(sums[4])}
                return solved, self.last_info
            refresh = self.tangent != "elastic"
        self._W_tangent = None  # a failed try's tangent is no start for the next one: back to elastic K
        raise NewtonError(self._failure(history))

    def _failure(self, history: list) -> str:
        def fmt(x: float) -> str:
            return "n/a" if np.isnan(x) else f"{x:.2e}"

        table = "; ".join(f"it {i}: delta_1 = {fmt(a)}, delta_2 = {fmt(b)}, {y} yielded points"
                          for i, a, b, y in history[-5:])
        return (f"Newton did not converge in {len(history)} iterations (tolerances delta_1 = {self.delta_1:g}, "
                f"delta_2 = {self.delta_2:g}); last: {table}")

    # The condensed iteration --------------------------------------------------------------------------
    def _increment_condensed(self, local_solve, pressure: float) -> tuple:
        if self.zone is None:
            self.zone = PlasticZone(self)
        self.zone.set_load(self._load_terms)
        while True:  # the zone only grows, and stops at max_zone_dofs: this ends
            # Plastic strain outside the zone (e.g. a state restored from a checkpoint): grow first.
            outside = (self.state.p > 0.0) & ~self.zone.point_mask
            if self.comm.allreduce(int(outside.any()), op=self.MPI.MAX):
                self._grow(outside)
            try:
                return self._newton_condensed(local_solve, pressure)
            except _ZoneGrew:
                continue

    def _grow(self, points: np.ndarray) -> None:
        """Grow the zone by the cells of ``points`` (a mask over this rank's points). Collective."""
        cells = np.unique(np.flatnonzero(points) // self.state.nq)
        self._kept = None  # its positions in X change
        self.zone.grow(cells)

    def _solve_condensed(self, s: float, r: np.ndarray, c: np.ndarray, out: fem.Function) -> None:
        """out <- K^-1 (s f + H^T r + E_X c): the displacement of the whole body. Collective."""
        z = self.zone
        b = self._z
        arr = b.getArray()
        arr[:] = self._contact_force(r)
        arr[z.own_local] += c[z.own]
        if self.face_load is not None and s != 0.0:
            b.axpy(s, self.face_load)
        dfx.set_bc(b, self.operators.bcs, scale=0.0)
        self._solve_into(self._whole_body_solver(), b, out)

    def _whole_body_solver(self):
        """The factorised elastic K for the condensed path's solves with the whole body. Serially a second
        factorisation of K by PETSc's own sparse Cholesky (quotient minimum degree ordering): its solve costs
        a third of a MUMPS solve on these meshes (no per-call set-up; measured 0.7 vs 1.8 ms at 9918 dofs),
        and K never changes. Under MPI the problem's (distributed MUMPS) factor."""
        if self.comm.size > 1:
            return self.operators.delassus
        if self._serial_ksp is None:
            ksp = PETSc.KSP().create(PETSc.COMM_SELF)
            ksp.setOperators(self.operators.K)
            ksp.setType("preonly")
            pc = ksp.getPC()
            pc.setType("cholesky")
            pc.setFactorSolverType("petsc")
            pc.setFactorOrdering("qmd")
            ksp.setErrorIfNotConverged(True)
            ksp.setUp()
            self._serial_ksp = ksp
        return self._serial_ksp

    def _newton_condensed(self, local_solve, pressure: float) -> tuple:
        """The Newton loop on the zone's dofs X (see the class docstring).

        With u = K^-1 phi and g(u) = F_int(u) - K u (on X), an iteration from u_i with the tangent
        K_T = K + E_P D E_P^T (M = (I + D Z_PP)^-1 D) is, on X::

            y   = (K^-1 R_i)_X = u_i + Z g_i - s a,           q_body = H u_i - H y + G M y_P,
            r   = local solve on W_T,                         w = M (G^T r - y_P),
            u_{i+1} = K^-1 (s f + H^T r + E_X c),             c = -g_i - E_P w,

        the out-of-balance force of u_{i+1} is E_X (c + g_{i+1}), and only the candidate that meets delta_1
        needs the whole body's displacement (for delta_2 and the check).
        """
        z = self.zone
        s = pressure
        z.load_committed()
        u0 = self.u.x.array[: self.rend - self.rstart]
        uX = z.gather(u0)
        g, _ = z.evaluate(uX)
        Zg = z.inverse_of(g)  # K^-1 of the plastic forces, on X, updated where g changed (few dofs)
        fnorm = abs(s) * self._face_norm()
        history = []
        solved = None
        refresh = False
        # The first iteration's matrix: K, or ("adaptive") the tangent the last increment converged with.
        T = first = self._kept if self.tangent == "adaptive" else None
        r_prev = c_prev = None
        prev_candidate, last_full = False, None
        for it in range(self.max_iter):
            if refresh:
                T = z.tangent(self.W_elastic)
                self.tangent_updates += 1
            y = uX + Zg - s * z.aX
            q_body = z.HX @ (uX - y)
            if T is not None:
                w1 = T.apply(y[T.P])
                q_body += T.G @ w1
            solved = local_solve(q_body, self.W_elastic if T is None else T.W)
            r = solved.forces
            c = -g
            uX = s * z.aX + z.ZH @ r - Zg  # + Z c, c = -g - E_P w
            if T is not None:
                w = T.apply(T.G.T @ r) - w1
                c[T.P] -= w
                uX -= w @ T.Z_P
            g, yielded = z.evaluate(uX)
            Zg = z.inverse_of(g)
            HTr = z.HX.T @ r
            out_of_balance = c + g
            res = float(np.linalg.norm(out_of_balance))
            fscale = max(float(np.linalg.norm(HTr)), fnorm, float(np.linalg.norm(HTr + out_of_balance)), 1e-300)
            d1 = res / fscale
            d2 = float("nan")
            candidate = np.isfinite(d1) and d1 <= self.delta_1
            if candidate:
                # The whole body's displacement, its last correction (from the previous candidate's
                # displacement if the previous iteration was one, else by one more solve) and the check.
                n = self.rend - self.rstart
                u_prev = last_full if prev_candidate else None
                u_new = self._work[0] if u_prev is self._trial else self._trial
                self._solve_condensed(s, r, c, u_new)
                last_full = u_new
                inc = u_new.x.array[:n] - u0
                incn2 = inc @ inc
                if it == 0:
                    dun2 = incn2
                elif u_prev is not None:
                    du = u_new.x.array[:n] - u_prev.x.array[:n]
                    dun2 = du @ du
                else:
                    du = self._work[1]
                    self._solve_condensed(0.0, r - r_prev, c - c_prev, du)
                    dun2 = du.x.array[:n] @ du.x.array[:n]
                dun, incn = np.sqrt(self.comm.allreduce(np.array([dun2, incn2]), op=self.MPI.SUM))
                d2 = dun / max(incn, 1e-300)
                if (it == 0 and first is None) or d2 <= self.delta_2:
                    if u_new is not self._trial:
                        self._trial.x.array[:] = u_new.x.array
                    self.last_info = self._verify(s, r, it + 1, d2)
                    self._kept = T  # the adaptive tangent's start for the next increment
                    return solved, self.last_info
            history.append((it + 1, d1, d2, yielded))
            if not np.isfinite(d1):
                break
            r_prev, c_prev, prev_candidate = r, c, candidate
            refresh = self.tangent != "elastic"
        self._kept = None  # a failed try's tangent is no start for the next one: back to elastic K
        raise NewtonError(self._failure(history))

    def _verify(self, s: float, r: np.ndarray, iterations: int, d2: float) -> dict:
        """Check the converged condensed iterate (in ``self._trial``) on the whole body and make it the trial
        state. Collective.

        Raises:
            _ZoneGrew: a point outside the zone yielded (the zone has grown: start the increment again).
            _CondensedMismatch: the whole body's out-of-balance force misses delta_1, or the zone's stresses
                differ from the whole body's (refactorise this increment instead).
        """
        state, zone = self.state, self.zone
        state.update(self._trial, tangent=False, eps=zone.strain_all(self._trial))
        outside = state.yielded & ~zone.point_mask
        if self.comm.allreduce(int(outside.any()), op=self.MPI.MAX):
            self._grow(outside)
            self.zone_growths += 1
            raise _ZoneGrew
        # The zone's stresses from its own strains against DOLFINx's at the same displacement (rounding).
        gap = np.abs(state.trial_sigma[zone.points] - zone.out["sigma"]).max(initial=0.0)
        R = self._assembled_residual(s)
        out_of_balance = R.getArray(readonly=True) - self._contact_force(r)
        fc = self._contact_force(r)
        sums = np.array([out_of_balance @ out_of_balance, fc @ fc, float(state.yielded.sum()),
                         R.getArray(readonly=True) @ R.getArray(readonly=True)])
        sums = self.comm.allreduce(sums, op=self.MPI.SUM)
        gap = self.comm.allreduce(gap, op=self.MPI.MAX)
        fscale = max(math.sqrt(sums[1]), abs(s) * self._face_norm(), math.sqrt(sums[3]), 1e-300)
        d1 = math.sqrt(sums[0]) / fscale
        if not d1 <= self.delta_1 or gap > 1e-6 * state.law.sigma_y0:
            raise _CondensedMismatch(f"delta_1 = {d1:.3g} on the whole body, zone stress gap {gap:.3g} MPa")
        return {"newton_iterations": iterations, "delta_1": d1, "delta_2": d2, "yielded_points": int(sums[2])}

    def _face_norm(self) -> float:
        if self.face_load is None:
            return 0.0
        if not hasattr(self, "_fnorm"):
            self._fnorm = self.face_load.norm()
        return self._fnorm

    def commit(self) -> None:
        """The last increment converged: its displacement and plastic state become history."""
        self.u.x.array[:] = self._trial.x.array
        self.state.commit()

    def destroy(self) -> None:
        for obj in (self._rhs, self._z, self._fint):
            obj.destroy()
        if self._combined is not None:
            self._combined.destroy()
        if self._tangent_op is not None:
            self._tangent_op.destroy()
        if self._KT is not None:
            self._KT.destroy()
        if self._serial_ksp is not None:
            self._serial_ksp.destroy()
