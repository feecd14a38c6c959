"""The operators of a fretting problem: K, its one factorisation, the loads, and W = H K^-1 H^T.

:class:`ContactOperators` assembles K from the user's bilinear form with the Dirichlet conditions, factorises it
once (MUMPS, :class:`~dolfinx_fretting.compliance.DelassusOperator`), assembles the named loads and Dirichlet
data, and forms, for the contact set it holds, the Delassus operator W on the free dofs and each load's contact
response ``H K^-1 f``. Under finite sliding it holds K^-1 on both contact surfaces
(:class:`~dolfinx_fretting.sliding.SurfaceCompliance`) and forms each pairing's W from it; a new candidate window
rebuilds W from the same factor (:meth:`ContactOperators.set_window`). Collective where it says so.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any, Mapping, Sequence

import numpy as np
import scipy.sparse as sp
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from . import _dolfinx as dfx
from . import local_solvers, sliding
from ._dolfinx import fem
from .compliance import DelassusOperator
from .contact import Contact, ContactSet, constrained_global_dofs
from .cycling import ActivePatternCache
from .settings import finite
from .state import ContactState
from .window_check import OutsideRows, carry_state, check_window, outside_gaps_of, outside_on_surfaces, watch_outside
from .zones import ContactZones

__all__ = ["ContactOperators"]


class ContactOperators:
    """K, its factorisation, the load vectors, and W and the load responses of the contact set held. Collective.

    Args:
        a: The bilinear form of K (UFL or ``fem.Form``), or an assembled PETSc matrix (Dirichlet rows applied).
        contact: The :class:`~dolfinx_fretting.contact.Contact`, or several zones
            (:class:`~dolfinx_fretting.zones.ContactZones`).
        bcs: Dirichlet conditions (applied in full).
        loads: Named linear forms or assembled PETSc vectors.
        prescribed: Named lists of Dirichlet conditions scaled by their factors.
        petsc_options: Options of the factorisation (keys without prefix).
        delassus_method: Route for W (:data:`~dolfinx_fretting.delassus_routes.METHODS`).
        options_prefix: PETSc options prefix of the factorisation.
        plastic: The body is elastic–plastic (non-zero Dirichlet values in ``bcs`` are then refused).

    Attributes:
        contact: The contact held (under finite sliding a copy holding the pairing last activated).
        W: The Delassus operator of the contact set held (replicated, dense).
        responses: ``H K^-1 f`` of each load (rows in :attr:`load_names` order).
        load_names: Names of the load vectors, in the order of
            :attr:`~dolfinx_fretting.state.ContactState.load_factors`: ``"dirichlet values"`` first if ``bcs``
            prescribe non-zero values, then the keys of ``loads``, ``prescribed``.
        surface_compliance: Finite sliding: K^-1 on both contact surfaces' dofs, else None.
        timings: Wall times (s) of the assembly, the factorisation and W (with the load responses).
        delassus_route: The route that built W (``delassus_method`` "auto" resolved for its size), under finite
            sliding the surface compliance's.
    """

    def __init__(self, a, contact: Contact | ContactZones, bcs: Sequence = (), *,
                 loads: Mapping[str, Any] | None = None,
                 prescribed: Mapping[str, Sequence] | None = None, petsc_options: Mapping[str, Any] | None = None,
                 delassus_method: str = "auto", options_prefix: str = "dolfinx_fretting_", plastic: bool = False):
        self.contact = contact
        self.V = contact.V
        self.comm: MPI.Comm = self.V.mesh.comm
        self.bcs = list(bcs)
        self.prescribed = {k: list(v) for k, v in (prescribed or {}).items()}
        loads = dict(loads or {})
        all_bcs = self.bcs + [bc for v in self.prescribed.values() for bc in v]
        # The contact and K must fix the same dofs: W is built on the contact's free dofs, and K has identity
        # rows exactly at the dofs of these conditions.
        fixed = constrained_global_dofs(self.V, all_bcs)
        if not np.array_equal(fixed, contact.fixed_global):
            raise ValueError("FrettingProblem: the Dirichlet conditions (bcs and prescribed) differ from those given "
                             f"to the Contact ({fixed.size} fixed dofs here, {contact.fixed_global.size} there): pass "
                             "the same conditions to Contact(..., bcs=...), or W would be wrong")
        t0 = time.perf_counter()
        self.timings: dict[str, float] = {}
        self.form = None
        if isinstance(a, PETSc.Mat):
            if self.prescribed:
                raise ValueError("FrettingProblem: prescribed Dirichlet data need the bilinear form, not a matrix")
            self.K = a
            self._own_K = False
        else:
            self.form = dfx.compiled_form(a)
            self.K = fem.petsc.assemble_matrix(self.form, bcs=all_bcs)
            self.K.assemble()
            self._own_K = True
        self.all_bcs = all_bcs
        base = self._dirichlet_vector(self.bcs) if self.form is not None else None
        if base is not None and plastic:
            base.destroy()
            raise ValueError("FrettingProblem: non-zero Dirichlet values in bcs are not supported with plasticity "
                             "(the Newton loop holds the Dirichlet dofs at zero); give the motion to the obstacle "
                             "(normal=, tangential=) or apply a load instead")
        # The loads before the factorisation: a non-finite one is refused before the expensive work.
        self.vectors: list = []   # PETSc vectors of the loads (owned here)
        self.load_names: list[str] = []
        if base is not None:
            self._add_vector("dirichlet values", base, "bcs (their Dirichlet values)")
        for name, form in loads.items():
            self._add_vector(name, self._load_vector(form), f"loads[{name!r}]")
        for name, conditions in self.prescribed.items():
            vec = self._dirichlet_vector(conditions)
            if vec is None:
                raise ValueError(f"FrettingProblem: prescribed[{name!r}] has zero values everywhere")
            self._add_vector(name, vec, f"prescribed[{name!r}]")
        self.timings["assemble_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        self.delassus = DelassusOperator(self.K, self.comm, method=delassus_method,
                                         petsc_options=dict(petsc_options or {}), options_prefix=options_prefix)
        self.delassus.factorize()
        self.timings["factorize_s"] = time.perf_counter() - t0
        #: Loads always applied at factor 1 (the values of ``bcs``), by index in :attr:`load_names`.
        self.fixed_factor = [i for i, n in enumerate(self.load_names) if n == "dirichlet values"]
        t0 = time.perf_counter()
        self.surface_compliance: sliding.SurfaceCompliance | None = None
        if isinstance(contact, Contact) and contact.obstacle.finite_sliding:
            self.surface_compliance = self._build_surface_compliance()
            self._surface_outside = outside_on_surfaces(self)
        #: The first guess of each obstacle component's load-displacement slope (force control).
        self.stiffness: np.ndarray | None = None
        self.build()
        self.timings["delassus_s"] = time.perf_counter() - t0
        self._kernel = None
        self._force_maps = None
        self._sliding_data: sliding.SlidingKernelData | None = None
        #: Finite sliding: the pairing of the reference configuration (the initial state's).
        self.reference_pairing = self.contact.contact_set
        #: The Contact of each zone as given (a zone rebuilt for a new window stays known by it).
        self.zone_keys = self.contact.zones

    def _add_vector(self, name: str, vec, given_as: str) -> None:
        """Hold the load vector ``vec`` as ``name``, refused unless finite (``given_as``: the argument it came from,
        for the message). Collective (a norm)."""
        norm = vec.norm()
        if not np.isfinite(norm):
            vec.destroy()
            raise ValueError(f"FrettingProblem: {given_as} is not finite (its assembled vector's norm is {norm}): a "
                             "NaN or infinite value in the form's coefficients, the vector or the Dirichlet data")
        self.load_names.append(name)
        self.vectors.append(vec)

    def _load_vector(self, form):
        if isinstance(form, PETSc.Vec):
            f = form.copy()
        else:
            L = dfx.compiled_form(form)
            f = fem.petsc.assemble_vector(L)
            # No lifting: a load alone holds every fixed dof at zero. Lifting by the conditions' values would add
            # the Dirichlet data's response (the "dirichlet values" or prescribed loads' own) times this load's factor.
            f.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dfx.set_bc(f, self.all_bcs, scale=0.0)  # a load alone: zero displacement at every fixed dof
        return _plain_vector(f, self.K)

    def _dirichlet_vector(self, conditions):
        """The right-hand side of the Dirichlet values of ``conditions`` alone (lifting, other fixed dofs 0)."""
        if not conditions:
            return None
        f = dfx.vector_for_form(fem.form(_zero_linear_form(self.V)))
        with f.localForm() as loc:
            loc.set(0.0)
        fem.petsc.apply_lifting(f, [self.form], bcs=[list(conditions)])
        f.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dfx.set_bc(f, self.all_bcs, scale=0.0)
        dfx.set_bc(f, list(conditions))
        if f.norm() == 0.0:
            f.destroy()
            return None
        return _plain_vector(f, self.K)

    def build(self, keep_slope: bool = False) -> None:
        """W on the free dofs (rank 0's copy on every rank) and each load's contact response (finite sliding:
        formed from the surface compliance, no communication)."""
        contact_set = self.contact.contact_set
        out_responses = None   # the loads' responses at the nodes outside the window (finite sliding: made once)
        if self.surface_compliance is not None:
            self.W, self.responses = self.surface_compliance.operators(contact_set)
        else:
            # DelassusOperator.build broadcasts rank 0's W (a buffer Bcast): the same bits on every rank already; a
            # second, pickled broadcast would fail past 2 GiB (about 5,500 3D contacts) on rank 0 alone
            self.W = self.delassus.build(self.contact.H_free)
            self.delassus_route = self.delassus.stats["last_build_route"]
            self.responses = np.zeros((len(self.vectors), contact_set.nc * contact_set.dim))
            outside = self.contact.outside
            H_out = outside.H[0::outside.dim] if outside is not None else None
            out_responses = np.zeros((len(self.vectors), 0 if outside is None else outside.nc))
            for i, f in enumerate(self.vectors):
                self.responses[i], out_responses[i] = self._responses(f, contact_set.H, H_out)
        self._hold_directions()
        #: The per-contact Uzawa steps ``local_solvers.block_rho(W, dim)`` of the W just built, once per W (every
        #: local solve on this W and the outside rows read them; W changes only here and in set_window).
        self.block_steps = local_solvers.block_rho(self.W, contact_set.dim)
        self._watch_outside(out_responses)
        if not (keep_slope and self.stiffness is not None):
            # Point stiffness of the closest node: a safe first guess of the load-displacement slope (kept when
            # only the pairing changes, so that a force-controlled run does not depend on which state was read)
            # (each zone's closest node)
            stiffness = []
            for zone in range(len(self.contact.zones)):
                rows = self.contact.zone_slice(zone)
                k = rows.start + int(np.argmin(contact_set.gap0[rows]))
                rows = slice(k * contact_set.dim, (k + 1) * contact_set.dim)
                block = self.W[rows, rows]
                stiffness += [1.0 / block[c, c] for c in range(contact_set.dim)]
            self.stiffness = np.array(stiffness)
        self._kernel = None

    def _hold_directions(self) -> None:
        """Tangential directions held by the conditions (:attr:`Contact.held_rows`, e.g. a symmetry plane's
        roller): W is zero on their rows and columns; they get the contact's normal compliance on the diagonal,
        which keeps the local problem well posed and leaves their force at zero as long as nothing moves along
        them (then ``x = c r`` there: sticking gives r = 0, sliding ``r = -mu r_n x_t/|x_t|`` gives r = 0 too).
        Obstacle components along them are refused (:meth:`_check_held`), as are loads that move them.
        Then every contact's diagonal block must be positive definite."""
        contact_set = self.contact.contact_set
        dim = contact_set.dim
        held = self.contact.held_rows
        if held.size:
            normal_rows = held - held % dim
            self.W[held, held] = self.W[normal_rows, normal_rows]
            scale = np.abs(self.responses).max(initial=0.0)
            moved = np.abs(self.responses[:, held]).max(initial=0.0)
            if moved > 1e-12 * scale:
                c, k = divmod(int(held[np.argmax(np.abs(self.responses[:, held]).max(axis=0))]), dim)
                raise ValueError(
                    f"FrettingProblem: a load or Dirichlet value moves contact {c} (node at "
                    f"{contact_set.coords[c].tolist()}) "
                    f"along its direction t{k}, which the conditions hold (a roller): a half model's loads must be "
                    "symmetric about its symmetry plane")
        # Obstacle components (rows of each zone's obstacle frame) with a component along a held direction.
        self.held_components = self.contact.held_components()
        blocks = np.array([self.W[c * dim:(c + 1) * dim, c * dim:(c + 1) * dim] for c in range(contact_set.nc)])
        eig = np.linalg.eigvalsh(0.5 * (blocks + blocks.transpose(0, 2, 1))) if contact_set.nc else np.zeros((0, dim))
        bad = np.flatnonzero(eig[:, 0] <= 1e-10 * eig[:, -1])
        if bad.size:
            c = int(bad[0])
            raise ValueError(
                f"FrettingProblem: the compliance of contact {c} (node at {contact_set.coords[c].tolist()}) is "
                "singular "
                f"(eigenvalues {eig[c].tolist()}): the conditions fix a combination of its directions n, t1"
                f"{', t2' if dim == 3 else ''} that is not one of them (a roller must fix the component along one "
                "of the contact frame's directions, e.g. u_y on a symmetry plane y = 0 with the obstacle normal in "
                "that plane)")

    def _watch_outside(self, responses: np.ndarray | None) -> None:
        """The outside rows of the window held (:func:`~dolfinx_fretting.window_check.watch_outside`)."""
        t0 = time.perf_counter()
        self.outside: OutsideRows | None = watch_outside(self, responses)
        if self.outside is not None:
            self.timings["outside_s"] = time.perf_counter() - t0

    def check_window(self, forces: np.ndarray, obstacle: np.ndarray, factors: np.ndarray, local_tol: float,
                     cycle: bool = False, displacement_gaps: np.ndarray | None = None,
                     displacement_tol: float = 0.0) -> None:
        """:func:`~dolfinx_fretting.window_check.check_window` on the outside rows held (``obstacle``: (n,
        components) in the obstacles' frames). Not collective (replicated data): call it on rank 0 through
        :func:`~dolfinx_fretting.increments.on_rank0`."""
        if self.outside is None:
            return
        check_window(self.outside, forces, obstacle, factors, self.contact.translations(np.atleast_2d(obstacle)),
                     local_tol, cycle, displacement_gaps, displacement_tol)

    def outside_gaps_of(self, u: np.ndarray, obstacle: np.ndarray) -> np.ndarray | None:
        """:func:`~dolfinx_fretting.window_check.outside_gaps_of` with the outside rows held. Collective."""
        return outside_gaps_of(self, u, obstacle)

    def check_held(self, obstacle: np.ndarray, force_controlled: np.ndarray) -> None:
        """Refuse obstacle motions and forces along a held contact direction (see :meth:`_hold_directions`)."""
        held = self.held_components
        if not held.any():
            return
        obstacle = np.atleast_2d(obstacle)
        names = self.contact.component_names()
        for k in np.flatnonzero(held):
            if force_controlled[k] or np.any(obstacle[:, k] != 0.0):
                what = "a force" if force_controlled[k] else f"a motion ({np.abs(obstacle[:, k]).max():.3g})"
                raise ValueError(
                    f"{names[k]} = {what}: the conditions hold some contacts along this direction (a roller, e.g. "
                    "on a symmetry plane): a half model moves only in its symmetry plane. Prescribe "
                    f"Displacement(0) along {names[k]} (in 3D, tangential=(Force(Q), Displacement(0.0)) for a "
                    "force along t1 alone)")

    def local_response(self, f, H=None) -> np.ndarray:
        """``H K^-1 f`` with the full H (prescribed values at fixed dofs count; default the contact set's),
        replicated. Collective."""
        H = self.contact.contact_set.H if H is None else H
        return self._responses(f, H)[0]

    def _responses(self, f, *Hs) -> list[np.ndarray]:
        """``H K^-1 f`` for each H of ``Hs`` (None: an empty array) from one solve, each reduced on its own (so
        that each has the bits it would have alone). Collective."""
        u = f.duplicate()
        self.delassus.solve(f, u)
        rstart, rend = u.getOwnershipRange()
        values = u.getArray(readonly=True)
        out = [np.zeros(0) if H is None else self.comm.allreduce(H[:, rstart:rend] @ values, op=MPI.SUM) for H in Hs]
        u.destroy()
        return out

    def _build_surface_compliance(self) -> sliding.SurfaceCompliance:
        """K^-1 on the dofs of both contact surfaces and the loads' responses there (finite sliding). Collective."""
        contact_set = self.contact.contact_set
        faces, nodes = sliding.surface_nodes(contact_set, self.contact.obstacle.reach)
        paired = contact_set.master_nodes[contact_set.master_nodes >= 0]
        if not np.isin(paired, nodes).all():  # before the build: the reference pairing must lie within reach
            raise ValueError(f"ElasticBody.reach = {self.contact.obstacle.reach!r}: too short for the reference "
                             "pairing itself (a slave candidate's closest master facet lies beyond it); allowed a "
                             "reach at least the candidates' largest initial gap, or None")
        dim = contact_set.dim
        dofs = (dim * nodes[:, None] + np.arange(dim)).ravel()
        S = sp.csr_matrix((np.ones(dofs.size), (np.arange(dofs.size), dofs)), shape=(dofs.size, self.n_dofs))
        free = np.ones(self.n_dofs)
        free[self.contact.fixed_global] = 0.0
        S_free = sp.csr_matrix(S @ sp.diags(free))
        S_free.eliminate_zeros()
        C = self.delassus.build(S_free)   # the same bits on every rank (build's Bcast)
        self.delassus_route = self.delassus.stats["last_build_route"]
        responses = np.array([self.local_response(f, S) for f in self.vectors]).reshape(len(self.vectors),
                                                                                          dofs.size)
        # rank 0's sums on every rank: each rank decides the re-pairings from these, so they must be the same bits
        responses = self.comm.bcast(responses if self.comm.rank == 0 else None, root=0)
        return sliding.SurfaceCompliance(nodes, dim, C, responses, faces,
                                         sliding.master_node_areas(contact_set.master_surface, nodes))

    def contact_set_of(self, state: ContactState) -> ContactSet:
        """The contact set ``state``'s per-contact arrays refer to (its pairing under finite sliding), without
        switching the problem to it (reading a state changes nothing)."""
        return state.pairing if state.pairing is not None else self.contact.contact_set

    def obstacle_translation(self, obstacle: np.ndarray) -> np.ndarray:
        """The obstacle's rigid translation D (global frame) from its components ``obstacle`` in the obstacle
        frame (:attr:`~dolfinx_fretting.state.ContactState.obstacle`: approach along n, then t1[, t2]); with
        several zones each zone's in turn."""
        return self.contact.translations(obstacle)

    def activate(self, state: ContactState) -> None:
        """Finite sliding: hold ``state``'s pairing (its contact set, W and load responses) if another is held."""
        if state.pairing is None or state.pairing is self.contact.contact_set:
            return
        self.contact = self.contact.with_pairing(state.pairing)
        self.build(keep_slope=True)


    def zone_of(self, contact) -> int | None:
        """The index of zone ``contact`` (the Contact given to the problem, or the one held now), else None."""
        for i, (given, held) in enumerate(zip(self.zone_keys, self.contact.zones)):
            if contact is given or contact is held:
                return i
        return None

    # Properties -----------------------------------------------------------------------------------------
    @property
    def n_dofs(self) -> int:
        """Global number of displacement dofs."""
        return self.V.dofmap.index_map.size_global * self.V.dofmap.index_map_bs

    @property
    def dim(self) -> int:
        """The contact's dimension (2 or 3)."""
        return self.contact.dim

    def factors(self, state: ContactState, loads: Mapping[str, float] | None) -> np.ndarray:
        """``state``'s load factors with those named in ``loads`` replaced (unknown names refused)."""
        s = state.load_factors.copy()
        for name, value in (loads or {}).items():
            if name not in self.load_names or name == "dirichlet values":
                raise KeyError(f"unknown load {name!r}; this problem's loads: "
                               f"{', '.join(n for n in self.load_names if n != 'dirichlet values') or 'none'}")
            s[self.load_names.index(name)] = finite(f"loads[{name!r}]", value)
        return s


    def q(self, d: np.ndarray, factors: np.ndarray, y_prev: np.ndarray, wear_gap: np.ndarray,
           q_body: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(q for the local problem, q_abs) of an increment; ``q_body`` replaces the loads' response."""
        contact_set = self.contact.contact_set
        if q_body is None:  # sum_l s_l q_l, in load order (one load: s q, as the compiled loop adds it)
            q_body = (np.zeros(contact_set.nc * contact_set.dim) if not len(self.load_names)
                      else factors[0] * self.responses[0])
            for i in range(1, len(self.load_names)):
                q_body = q_body + factors[i] * self.responses[i]
        q_abs = -self.contact.rigid_motion(d) + q_body
        q_abs[0::contact_set.dim] += contact_set.gap0 + wear_gap
        q = q_abs.copy()
        normal = np.arange(q.size) % contact_set.dim == 0
        q[~normal] -= y_prev[~normal]
        return q, q_abs


    # Compiled cycles, window --------------------------------------------------------------------------------
    def kernel_data(self, n: int | None):
        """W transposed, the Uzawa steps and the contact-pattern cache of cycles of ``n`` increments (rank 0); ``n``
        None: a loop that tries no pattern (force control), served by the cache held, or a one-row one (no
        per-increment LU factors made for it)."""
        cache = None if self._kernel is None else self._kernel[2]
        # A 2D cache holds one row per increment (the compiled loop indexes it unchecked): only for cycles of its n.
        # The 3D one is an empty stand-in of one row, for any n.
        if cache is None or (n is not None and cache.enabled and cache.pattern.shape[0] != n):
            contact_set = self.contact.contact_set
            self._kernel = (np.ascontiguousarray(self.W.T), self.block_steps,
                            ActivePatternCache(1 if n is None else n, contact_set.nc, contact_set.dim))
        return self._kernel

    def force_maps(self) -> tuple[np.ndarray, np.ndarray]:
        """(T, A) of force-controlled compiled cycles: T (translation components, obstacle components) the obstacle
        translation per unit obstacle component, A (obstacle components, m) the total force along each component per
        contact force (both linear: the contact's ``translations`` and ``obstacle_forces`` of unit vectors), made
        once per contact set."""
        contact_set = self.contact.contact_set
        if self._force_maps is None or self._force_maps[0] is not contact_set:
            components = self.dim * len(self.contact.zones)
            T = np.ascontiguousarray(self.contact.translations(np.eye(components)).T)
            unit = np.eye(contact_set.nc * contact_set.dim)
            A = np.ascontiguousarray(np.column_stack([self.contact.obstacle_forces(e) for e in unit]))
            self._force_maps = (contact_set, T, A)
        return self._force_maps[1], self._force_maps[2]

    def sliding_kernel_data(self) -> sliding.SlidingKernelData:
        """Finite sliding: what its compiled loop reads of the surfaces and the window's outside rows, made once."""
        if self._sliding_data is None:
            outside = self.contact.outside
            self._sliding_data = sliding.SlidingKernelData.of(
                self.reference_pairing, self.surface_compliance, outside, self._surface_outside,
                None if outside is None else self.contact.outside_motion(), len(self.load_names))
        return self._sliding_data

    @property
    def pattern_counts(self) -> np.ndarray | None:
        """Counts of the compiled cycles' exact pattern solves accepted and rejected, of their LU factorisations,
        and of the local solves that swept the held block W_AA and that gathered one
        (:class:`~dolfinx_fretting.cycling.ActivePatternCache`'s ``counts``; rank 0)."""
        return None if self._kernel is None else self._kernel[2].counts


    def set_window(self, state: ContactState, window: float | None, zone: int = 0) -> ContactState:
        """Rebuild the contact set, W and the load responses for another candidate window of zone ``zone``
        (elastic bodies) and carry ``state`` over: forces and wear by node (of the same zone); new candidates start
        open and unworn; the relative positions are recomputed (y = W r + q_abs exactly). All or nothing.
        Collective."""
        if self.surface_compliance is not None:
            raise ValueError("the candidate window of a finite-sliding problem cannot change (its surface compliance "
                             "is built for the contact's window): give Contact a window wide enough for the run")
        old_contact, old_W, old_resp, old_steps = self.contact, self.W, self.responses, self.block_steps
        try:
            self.contact = old_contact.with_window(window, zone)
            self.build()
        except Exception:
            self.contact, self.W, self.responses, self.block_steps = old_contact, old_W, old_resp, old_steps
            self._kernel = None
            raise
        carried = carry_state(old_contact, self.contact, state)
        _, q_abs = self.q(state.obstacle, state.load_factors, np.zeros(carried["forces"].size), carried["wear_gap"])
        return replace(state, positions=self.W @ carried["forces"] + q_abs, **carried)

    def destroy(self) -> None:
        """Free the PETSc objects (factorisation, K if assembled here, load vectors)."""
        self.delassus.destroy()
        for f in self.vectors:
            f.destroy()
        if self._own_K:
            self.K.destroy()


def _zero_linear_form(V):
    v = ufl.TestFunction(V)
    zero = fem.Constant(V.mesh, PETSc.ScalarType((0.0,) * V.mesh.geometry.dim))
    return ufl.inner(zero, v) * ufl.dx


def _plain_vector(f, K):
    """An unghosted copy of ``f`` with K's layout (K's solves and axpy need the same layout)."""
    out = K.createVecRight()
    n = out.getLocalSize()
    out.getArray()[:] = f.getArray(readonly=True)[:n]
    f.destroy()
    return out
