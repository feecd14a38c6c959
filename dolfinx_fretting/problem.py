"""The public problem: frictional contact and fretting wear on the user's own DOLFINx model.

The user owns mesh, space, forms, boundary conditions and loop; this module adds one object that plugs in,
in the idiom of dolfinx_mpc's ``LinearProblem(a, L, mpc, bcs)``::

    contact = Contact(V, (facet_tags, marker), RigidPlane([0, 0], [0, 1]), mu=0.5, bcs=bcs)
    problem = FrettingProblem(a, contact, bcs, wear=Archard(1e-5), loads={"push": L})
    state = problem.initial_state()
    for approach in np.linspace(0, 1e-3, 5)[1:]:
        result = problem.solve(state, normal=approach)          # or normal=Force(100.0)
        state = problem.commit(state, result)                   # rollback = not committing
    result = problem.run_cycle(state, CyclePath.waveform(80, normal=1e-3, tangential=5e-3))
    state = problem.commit(state, result)
    u = problem.displacement(state)                             # a fem.Function

K is assembled from the user's bilinear form with the Dirichlet conditions and factorised once by MUMPS;
W = H K^-1 H^T is formed from that factor by the routes of :mod:`dolfinx_fretting.compliance`. Each
increment is then a local problem ``x = W r + q`` (paper eq. 28) with

    q_n = g_0 + g_w - n.D + sum_l s_l (H K^-1 f_l)_n,    q_t = -t.D + sum_l s_l (H K^-1 f_l)_t - y_t(previous),

D the obstacle's rigid translation (given in the obstacle frame, see :class:`~dolfinx_fretting.contact.Contact`),
f_l the user's named load vectors and Dirichlet data, s_l their factors, y the total relative position of the
committed state and g_w the wear gap. Elastic–plastic bodies run Newton with this contact solve inside every
iteration (paper Fig. 4) on the same object (``plasticity=...``).

Frame of the obstacle motion: ``normal`` is the approach of the obstacle along n (n points from the obstacle
into the body: a positive value closes the gap), ``tangential`` the motion along t1 (and t2 in 3D); a
:class:`~dolfinx_fretting.loading.Force` instead prescribes the matching component of the total contact force on the
body, the
obstacle position becoming an unknown.

Collective: every method is called on every rank with the same arguments; the local problem is solved on
rank 0 and its result broadcast, so every rank holds the same contact state whatever the partition, and an
error on rank 0 is raised on every rank.

:class:`FrettingProblem` is a façade over parts with one job each: the operators (K, its factorisation, W and the
load responses: :mod:`~dolfinx_fretting.operators`), one increment (:mod:`~dolfinx_fretting.increments`), its
commit (:mod:`~dolfinx_fretting.commit`), cycles (:mod:`~dolfinx_fretting.cycles`), the readers of a state
(:mod:`~dolfinx_fretting.readers`) and checkpoints (:mod:`~dolfinx_fretting.checkpoint`); the value objects live in
:mod:`~dolfinx_fretting.state`, :mod:`~dolfinx_fretting.settings`, :mod:`~dolfinx_fretting.laws` and
:mod:`~dolfinx_fretting.loading`, and are re-exported here.
"""

from __future__ import annotations

import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np
from mpi4py import MPI

from . import checkpoint, friction, readers
from .commit import SlidingMonitor, commit, relative_slip_ratio, wear_coefficients
from .delassus_routes import METHODS
from .contact import Contact, ContactSet
from .cycles import compiled_cycle, cycle_targets, sliding_cycle, stepwise_cycle
from .increments import advance, increment_targets, load_plastic, on_rank0, solve_contact, solve_plastic
from .laws import Archard, WearLaw
from .loading import CyclePath, Displacement, Force
from .materials import J2Plasticity
from .operators import ContactOperators
from .zones import ContactZones, as_zones, zone_wear_laws
from .plasticity import ElastoplasticBody
from .settings import LocalSolver, Plasticity
from .state import (INCREMENT_COLUMNS, STATUS_NAMES, ContactState, ConvergenceError, CycleResult, IncrementResult,
                    PlasticHistory, WindowError)

__all__ = ["Archard", "Displacement", "Force", "LocalSolver", "Plasticity", "ContactState", "IncrementResult",
           "CyclePath", "CycleResult", "FrettingProblem", "ConvergenceError", "WindowError", "STATUS_NAMES",
           "INCREMENT_COLUMNS"]


class FrettingProblem:
    """Frictional contact and wear of a linear elastic (or elastic–plastic) body. Collective.

    Args:
        a: The bilinear form of K (UFL or ``fem.Form``), or an assembled PETSc matrix (Dirichlet rows already
            applied; then ``prescribed`` and a non-zero Dirichlet value are not available).
        contact: The :class:`~dolfinx_fretting.contact.Contact`, or a list of them: several contact zones, each
            with its own surface, obstacle, friction law and window, coupled through the body (one W, one
            factorisation; :class:`~dolfinx_fretting.zones.ContactZones`). With several zones the targets of
            :meth:`solve` and :class:`~dolfinx_fretting.loading.CyclePath` map each zone's Contact to its item, and
            :meth:`total_force` and :meth:`contact_fields` take the zone.
        bcs: Dirichlet conditions. Their values are part of the model (applied in full at every increment);
            to scale a Dirichlet value along a load path, give it in ``prescribed`` instead.
        wear: A wear law (the :class:`~dolfinx_fretting.laws.WearLaw` protocol, e.g.
            :class:`~dolfinx_fretting.laws.Archard`), or None (no wear); with several zones, one law for all or a
            mapping from each zone's Contact to its law (a zone not named does not wear; the laws share one
            ``acceleration``).
        loads: Named linear forms (UFL or ``fem.Form``) or assembled PETSc vectors; each is applied times its
            factor (``loads={"face": 2.0}`` in :meth:`solve`).
        prescribed: Named lists of Dirichlet conditions with non-zero values (``fem.Function`` or
            ``fem.Constant`` data): each set is applied times its factor.
        petsc_options: Options of the factorisation (MUMPS Cholesky by default; keys without prefix).
        delassus_method: Route for W: ``"auto"`` (by W's size: :func:`~dolfinx_fretting.delassus_routes.auto_route`),
            ``"selected_inverse"``, ``"owned"``, ``"block"``, ``"columns"``, ``"schur"`` (serial only).
        solver: :class:`~dolfinx_fretting.settings.LocalSolver` settings.
        plasticity: :class:`~dolfinx_fretting.settings.Plasticity` for an elastic–plastic body, else None.
        options_prefix: PETSc options prefix of the factorisation (unique per problem by default).

    Attributes:
        operators: K, its factorisation, W and the load responses
            (:class:`~dolfinx_fretting.operators.ContactOperators`).
        body: The elastic–plastic body (:class:`~dolfinx_fretting.plasticity.ElastoplasticBody`), else None.
        sliding: What the run learned about sliding (:class:`~dolfinx_fretting.commit.SlidingMonitor`).
    """

    _count = 0

    def __init__(self, a, contact: Contact | Sequence[Contact], bcs: Sequence = (), *,
                 wear: WearLaw | Mapping[Contact, WearLaw | None] | None = None,
                 loads: Mapping[str, Any] | None = None, prescribed: Mapping[str, Sequence] | None = None,
                 petsc_options: Mapping[str, Any] | None = None, delassus_method: str = "auto",
                 solver: LocalSolver | None = None, plasticity: Plasticity | None = None,
                 options_prefix: str | None = None):
        # Bad input is refused before anything is assembled.
        contact = as_zones(contact)
        if delassus_method not in METHODS:
            raise ValueError(f"FrettingProblem: delassus_method = {delassus_method!r}: allowed {', '.join(METHODS)}")
        wear_laws = zone_wear_laws(contact.zones, wear)
        names = list(loads or {}) + list(prescribed or {})
        for name in names:
            if not isinstance(name, str) or not name:
                raise ValueError(f"FrettingProblem: load names must be non-empty strings, got {name!r}")
        if len(set(names)) < len(names):
            raise ValueError(f"FrettingProblem: names used twice: {sorted(set(loads or {}) & set(prescribed or {}))}")
        if plasticity is not None:
            if prescribed:
                raise ValueError("FrettingProblem: prescribed Dirichlet data are not supported with plasticity "
                                 "(the Newton loop holds Dirichlet dofs at zero)")
            if any(zone.obstacle.finite_sliding for zone in contact.zones):
                raise ValueError("FrettingProblem: finite sliding (ElasticBody(sliding='finite')) is for elastic "
                                 "bodies; an elastic-plastic problem keeps the pairing fixed (sliding='small')")
            law = plasticity.law
            if not (hasattr(law, "E") and hasattr(law, "nu")
                    and (hasattr(law, "update") or isinstance(law, J2Plasticity))):
                raise TypeError("Plasticity.law must have E, nu and update(strain, eps_p, p) (see Plasticity)")
        self.wear = wear
        #: Each zone's wear law (None: the zone does not wear).
        self.wear_laws = wear_laws
        self.solver = solver or LocalSolver()
        self.plasticity = plasticity
        self.bcs = list(bcs)
        FrettingProblem._count += 1
        self.operators = ContactOperators(
            a, contact, bcs, loads=loads, prescribed=prescribed, petsc_options=petsc_options,
            delassus_method=delassus_method, plastic=plasticity is not None,
            options_prefix=options_prefix or f"dolfinx_fretting_{FrettingProblem._count}_")
        self.sliding = SlidingMonitor()
        self.body: ElastoplasticBody | None = None
        if plasticity is not None:
            operators = self.operators
            self.body = ElastoplasticBody(
                operators, plasticity.law, operators.contact.H_free, operators.W,
                operators.vectors[0] if operators.vectors else None,
                tangent=plasticity.tangent, max_iter=plasticity.max_iter, delta_1=plasticity.residual_tol,
                delta_2=plasticity.displacement_tol, quadrature_degree=plasticity.quadrature_degree,
                elastic_cells=plasticity.elastic_cells)

    # What the problem holds ------------------------------------------------------------------------------
    @property
    def contact(self) -> Contact | ContactZones:
        """The contact (under finite sliding: holding the pairing of the state last solved or committed); with
        several zones, all of them stacked (:class:`~dolfinx_fretting.zones.ContactZones`)."""
        return self.operators.contact

    @property
    def contacts(self) -> tuple[Contact, ...]:
        """The contact zones, in the order given (one: ``(contact,)``)."""
        return self.operators.contact.zones

    @property
    def V(self):
        """The displacement space."""
        return self.operators.V

    @property
    def comm(self) -> MPI.Comm:
        """The mesh's communicator."""
        return self.operators.comm

    @property
    def dim(self) -> int:
        """The contact's dimension (2 or 3)."""
        return self.operators.dim

    @property
    def n_dofs(self) -> int:
        """Global number of displacement dofs."""
        return self.operators.n_dofs

    @property
    def load_names(self) -> list[str]:
        """Names of the loads, in the order of :attr:`~dolfinx_fretting.state.ContactState.load_factors`."""
        return self.operators.load_names

    def wear_coefficient(self, in_cycle: bool) -> float:
        """The wear gap's rate ``c`` of ``dg = c p |dx_t|`` applied to an increment (Archard's k, or Fouvry's
        alpha times mu, times the acceleration in cycles; 0 without wear), when every contact shares it.

        Raises:
            ValueError: the contacts' coefficients differ (zones with different laws, or an energy law with
                friction varying over the contacts): :meth:`wear_coefficients` has them.
        """
        values = np.unique(self.wear_coefficients(in_cycle))
        if values.size > 1:
            raise ValueError(f"wear_coefficient: the contacts' wear coefficients differ ({values.min():g} to "
                             f"{values.max():g}): read wear_coefficients(in_cycle), one per contact")
        return float(values[0]) if values.size else 0.0

    def wear_coefficients(self, in_cycle: bool, state: ContactState | None = None) -> np.ndarray:
        """Each contact's wear coefficient of an increment (its zone's law's; 0 where a zone does not wear), solved
        from ``state`` (an energy law's alpha mu with an evolving friction law's mu there; None: at the start)."""
        mu = None if state is None else friction.coefficients(self.operators.contact, state)
        return wear_coefficients(self.operators, self.wear_laws, in_cycle, mu)

    # States and increments --------------------------------------------------------------------------------
    def initial_state(self) -> ContactState:
        """The unloaded, unworn state (obstacle at its initial position, every load factor 0; finite sliding:
        the reference configuration's pairing)."""
        operators = self.operators
        finite = operators.surface_compliance is not None
        contact_set = operators.reference_pairing if finite else operators.contact.contact_set
        m = contact_set.nc * contact_set.dim
        y = np.zeros(m)
        y[0::contact_set.dim] = contact_set.gap0
        factors = np.zeros(len(operators.load_names))
        factors[operators.fixed_factor] = 1.0
        plastic = None
        if self.body is not None:
            points = self.body.state
            plastic = PlasticHistory(np.zeros_like(self.body.u.x.array), np.zeros_like(points.sigma),
                                     np.zeros_like(points.eps_p), np.zeros_like(points.p))
        size = operators.contact.obstacle_size
        return ContactState(np.zeros(m), y, np.zeros(m), np.zeros(contact_set.nc), np.zeros(size), factors,
                            targets=np.zeros(size), force_controlled=np.zeros(size, dtype=bool), plastic=plastic,
                            pairing=contact_set if finite else None,
                            master_wear=np.zeros(operators.surface_compliance.nodes.size) if finite else None,
                            friction_energy=np.zeros(contact_set.nc) if friction.tracks_energy(operators.contact)
                            else None)

    def solve(self, state: ContactState, normal: float | Displacement | Force | None = None,
              tangential: float | Sequence[float] | Displacement | Force | None = None,
              loads: Mapping[str, float] | None = None, *, in_cycle: bool = False) -> IncrementResult:
        """Solve one increment from ``state`` (nothing is committed). Collective.

        Args:
            state: The committed state to start from.
            normal: Obstacle approach along n (a float or :class:`~dolfinx_fretting.loading.Displacement`), or
                (several zones: a mapping from each zone's Contact to such an item; zones not named keep theirs)
                :class:`~dolfinx_fretting.loading.Force` on the body
                along n; None keeps the state's prescribed value (the approach, or the force if the last
                increment prescribed one).
            tangential: Obstacle motion along t1 (2D) or (t1, t2) (3D), or :class:`~dolfinx_fretting.loading.Force`
                components (several zones: per zone, as ``normal``); None keeps the state's prescribed values
                likewise.
            loads: Factors of named loads and prescribed Dirichlet data; names not given keep their factors.
            in_cycle: The increment belongs to a load cycle (the wear law's acceleration applies at commit).

        Returns:
            The converged increment.

        Raises:
            ConvergenceError: the local solver, a force control or (elastic–plastic) Newton failed.
            WindowError: a node of the contact surface outside the candidate window penetrates the obstacle (the
                answer is truncated; the message names the window needed). Raised here whatever
                ``grow_window``: the result must belong to ``state``'s window; :meth:`advance` and
                :meth:`run_cycle` grow it.
        """
        operators = self.operators
        operators.activate(state)
        targets, controlled = increment_targets(operators, state, normal, tangential)
        factors = operators.factors(state, loads)
        source = state.token   # the one state the result may be committed to (commit checks it)
        if self.body is not None:
            result = solve_plastic(operators, self.solver, self.body, state, targets, controlled, factors, in_cycle)
            result = replace(result, solved_from=source)
        else:
            result = replace(solve_contact(operators, self.solver, state, targets, controlled, factors),
                             in_cycle=in_cycle, solved_from=source)
        self._check_window(result)
        return result

    def _check_window(self, result: IncrementResult) -> None:
        """Raise WindowError on every rank if a node outside the window penetrates in ``result`` (the decision is
        rank 0's, broadcast). Collective; nothing to do (no communication) without a window."""
        operators = self.operators
        if operators.outside is None:
            return
        gaps, newton_tol = None, 0.0
        if result.plastic is not None:  # the displacement holds the plastic strains: gaps from it (a reduction)
            gaps = operators.outside_gaps_of(result.plastic.u, result.obstacle)
            newton_tol = self.plasticity.displacement_tol
        on_rank0(operators.comm, lambda: operators.check_window(result.forces, result.obstacle, result.load_factors,
                                                    self.solver.tol, displacement_gaps=gaps,
                                                    displacement_tol=newton_tol))

    def commit(self, state: ContactState, result: IncrementResult | CycleResult) -> ContactState:
        """The new state after a converged increment or cycle (:func:`dolfinx_fretting.commit.commit`: the wear
        law, the plastic history, the totals of :attr:`~dolfinx_fretting.state.ContactState.record`, finite sliding's
        re-pairing).
        ``state`` itself is not changed; rollback is not committing.

        Raises:
            ValueError: ``result`` was not solved from ``state`` (a result already committed, or one of another
                state: its :attr:`~dolfinx_fretting.state.IncrementResult.solved_from` is not ``state``'s
                :attr:`~dolfinx_fretting.state.ContactState.token`); its wear would count twice.
        """
        return commit(self.operators, self.wear_laws, self.sliding, state, result)

    def advance(self, state: ContactState, normal=None, tangential=None, loads=None, *, in_cycle: bool = False,
                max_cutbacks: int | None = None,
                check: Callable[[ContactState], None] | None = None) -> tuple[ContactState, dict[str, Any]]:
        """Solve and commit one increment, halving it on failure up to ``max_cutbacks`` times (default:
        ``Plasticity.max_cutbacks``, 0 for elastic bodies); see :func:`dolfinx_fretting.increments.advance`.

        Returns:
            (the new state, the increment's solver columns :data:`~dolfinx_fretting.state.SOLVER_COLUMNS`).

        Raises:
            ConvergenceError: no convergence after the cut-backs (``state`` itself is unchanged).
            WindowError: a node outside the candidate window penetrated (no cut-back). With
                ``Contact(..., grow_window=True)`` (elastic bodies) the window is widened to the one needed
                instead and the increment solved again from ``state`` (a RuntimeWarning says so); the new state
                then belongs to the wider window, as after :meth:`set_window`.
        """
        if max_cutbacks is None:
            max_cutbacks = self.plasticity.max_cutbacks if self.plasticity is not None else 0
        return self._growing(state, lambda start: advance(
            self.operators, self.solve, self.commit, start, normal, tangential, loads, in_cycle=in_cycle,
            max_cutbacks=max_cutbacks, check=check))

    def _growing(self, state: ContactState, attempt: Callable[[ContactState], Any]) -> Any:
        """``attempt(state)``; with ``Contact(grow_window=True)``, on a WindowError widen the window to the one
        needed (the committed ``state`` carried over: nothing of the failed try is kept) and try again. Each
        growth takes in the penetrating nodes, so it ends, at the latest with the whole surface. Collective."""
        while True:
            try:
                return attempt(state)
            except WindowError as exc:
                # (an elastic-plastic or finite-sliding problem cannot change its window: the error stands)
                fixed = self.body is not None or self.operators.surface_compliance is not None
                zone = self.contacts[exc.zone]
                if not zone.grow_window or fixed:
                    raise
                before = zone.window
                state = self.set_window(state, exc.window_needed, zone=exc.zone)
                who = f"contact[{exc.zone}]: " if len(self.contacts) > 1 else ""
                if self.comm.rank == 0:
                    warnings.warn(f"{who}candidate window grown from {before:.6g} to {exc.window_needed:.6g} "
                                  f"({self.contact.nc} contacts): {exc.positions.shape[0]} node(s) outside it "
                                  f"penetrated by up to {exc.penetration:.3g}; the increment is solved again",
                                  RuntimeWarning, stacklevel=3)

    def run_cycle(self, state: ContactState, path: CyclePath, keep: bool = False,
                  check: Callable[[ContactState], None] | None = None) -> CycleResult:
        """Solve the increments of one cycle from ``state`` (nothing committed: :meth:`commit` the result).

        Elastic bodies run in the compiled loop (:mod:`dolfinx_fretting.cycling`, the path the scenes use; the
        local method must be Uzawa), prescribed forces found inside it by the stepwise load control; finite sliding
        (2D node-to-segment) in its own compiled loop that pairs anew between increments
        (:func:`~dolfinx_fretting.cycles.sliding_cycle`); other local methods, plasticity and the rest of finite
        sliding run increment by increment. Either way a failure raises before anything is committed.

        Args:
            state: The committed state.
            path: The targets of the cycle's increments.
            keep: Also return every increment's forces, slip, positions, wear gap and status.
            check: Increment by increment only: called with each committed increment's state (see
                :meth:`advance`); the compiled loop's increments are checked by the caller on the records.

        Raises:
            ConvergenceError: an increment failed (its cycle step in the message).
            WindowError: a node outside the candidate window penetrated at some increment of the cycle (every
                increment is checked; ``step`` is the first); with ``Contact(..., grow_window=True)`` the window
                is widened instead and the whole cycle solved again from ``state``.
        """
        operators = self.operators
        obstacle, forced, factors = cycle_targets(operators, state, path)
        operators.activate(state)
        operators.check_held(obstacle, forced)

        def attempt(start: ContactState) -> CycleResult:
            if self.solver.compiled_cycles and self.solver.method == "uzawa" and self.body is None:
                if operators.surface_compliance is None:
                    return compiled_cycle(operators, self.solver, self.wear_laws, start, obstacle, factors, keep,
                                          forced)
                # Finite sliding pairs anew between increments, in its own compiled loop (what the loop does not
                # cover: increment by increment).
                result = sliding_cycle(operators, self.solver, self.wear_laws, self.sliding, start, obstacle, forced,
                                       factors, keep)
                if result is not None:
                    return result
            return stepwise_cycle(operators, self._advance_once, start, obstacle, forced, factors, keep, check)
        # A growth solves the whole cycle again from ``state`` in the wider window (its increments then all refer
        # to one contact set); the result is still ``state``'s to commit (its final state is in the wider window).
        source = state.token
        return replace(self._growing(state, attempt), solved_from=source)

    def _advance_once(self, state, normal=None, tangential=None, loads=None, *, in_cycle=False, check=None):
        """:meth:`advance` without growing the window (a cycle grows it once for all its increments)."""
        max_cutbacks = self.plasticity.max_cutbacks if self.plasticity is not None else 0
        return advance(self.operators, self.solve, self.commit, state, normal, tangential, loads, in_cycle=in_cycle,
                       max_cutbacks=max_cutbacks, check=check)

    def set_window(self, state: ContactState, window: float | None, zone: int = 0) -> ContactState:
        """Rebuild the contact set, W and the load responses for another candidate window of zone ``zone`` (its
        index in the list given; elastic bodies) and carry ``state`` over: forces and wear by node; new candidates
        start open and unworn; the relative positions are recomputed (y = W r + q_abs exactly). All or nothing.
        Collective."""
        if self.body is not None:
            raise ValueError("the candidate window of an elastic-plastic problem cannot change")
        if not (isinstance(zone, (int, np.integer)) and 0 <= zone < len(self.contacts)):
            raise ValueError(f"set_window: zone = {zone!r}: allowed 0 .. {len(self.contacts) - 1} (the zones' order)")
        return self.operators.set_window(state, window, int(zone))

    # Readers ----------------------------------------------------------------------------------------------
    def displacement(self, state: ContactState, out=None):
        """The displacement of ``state`` as a ``fem.Function`` (``out`` if given); see
        :func:`dolfinx_fretting.readers.displacement`. Collective."""
        plastic_u = state.plastic.u if self.body is not None else None
        return readers.displacement(self.operators, state, out, plastic_u)

    def displacements(self, states: Sequence[ContactState], outs: Sequence | None = None) -> list:
        """The displacements of several states (``outs``: a ``fem.Function`` for each, or None: new ones).
        Elastic bodies: the back-solves of :meth:`displacement` as one multiple right-hand-side solve per
        :func:`~dolfinx_fretting.readers.batch_size` states (:func:`dolfinx_fretting.readers.displacements`: the
        same answers, rounding apart); elastic–plastic bodies: each state's committed displacement. Collective."""
        states = list(states)
        outs = list(outs) if outs is not None else [None] * len(states)
        if len(outs) != len(states):
            raise ValueError(f"displacements: {len(states)} states, {len(outs)} functions in outs")
        if self.body is not None:
            return [self.displacement(state, out=u) for state, u in zip(states, outs)]
        step = readers.batch_size(self.operators)
        for first in range(0, len(states), step):
            outs[first:first + step] = readers.displacements(self.operators, states[first:first + step],
                                                             outs[first:first + step])
        return outs

    def contact_fields(self, state: ContactState, contact: Contact | None = None) -> dict[str, np.ndarray]:
        """Per contact node (replicated): :func:`dolfinx_fretting.readers.contact_fields`; ``contact``: one zone's
        nodes (default every zone's, in turn)."""
        return readers.contact_fields(self.operators, state, contact)

    def total_force(self, state: ContactState, contact: Contact | None = None) -> np.ndarray:
        """Total contact force on the body in the obstacle frame (n, t1[, t2]); with several zones, zone
        ``contact``'s in its obstacle's frame."""
        return readers.total_force(self.operators, state, contact)

    def body_wear(self, state: ContactState) -> dict[str, np.ndarray]:
        """Two bodies: each body's worn depth (:func:`dolfinx_fretting.readers.body_wear`)."""
        return readers.body_wear(self.operators, self.wear_laws, state)

    def worn_measure(self, state: ContactState) -> float:
        """The worn area (2D, per unit thickness) or volume (3D) of ``state``, both bodies'."""
        return readers.worn_measure(self.operators, state)

    def contact_set_of(self, state: ContactState) -> ContactSet:
        """The contact set ``state``'s per-contact arrays refer to (its pairing under finite sliding)."""
        return self.operators.contact_set_of(state)

    def obstacle_translation(self, obstacle: np.ndarray) -> np.ndarray:
        """The obstacle's rigid translation D (global frame) from its components in the obstacle frame
        (:attr:`~dolfinx_fretting.state.ContactState.obstacle`)."""
        return self.operators.obstacle_translation(obstacle)

    def relative_slip_ratio(self, state: ContactState) -> float:
        """Two bodies: the largest relative slip in master elements
        (:func:`dolfinx_fretting.commit.relative_slip_ratio`)."""
        return relative_slip_ratio(self.operators, state)

    def plastic_state(self, state: ContactState):
        """The body's :class:`~dolfinx_fretting.plasticity.PlasticState` holding ``state``'s committed history
        (von Mises stress, equivalent plastic strain, cell averages for output)."""
        load_plastic(self.body, state.plastic)
        return self.body.state

    # Checkpoints ------------------------------------------------------------------------------------------
    def save_state(self, state: ContactState, path: str | Path, meta: Mapping[str, Any] | None = None) -> None:
        """Write ``state`` (and JSON-able ``meta``) to an ``.npz`` file atomically (rank 0 writes). Collective."""
        checkpoint.save_state(self.operators, self.sliding, state, path, meta, self.wear_laws,
                              self._plastic_points())

    def load_state(self, path: str | Path) -> tuple[ContactState, dict[str, Any]]:
        """Read a state written by :meth:`save_state` (same problem, same contact set). Collective.

        Checked: the contact nodes, the load names, a plastic state's dofs and quadrature points (by their
        coordinates: a state moves between rank counts), finite sliding's pairing and master wear (by the input
        mesh's node indices: they move between rank counts too), and each
        zone's contact parameters: ``mu``, the wear law (its class, coefficients and acceleration) and the obstacle
        (its class, normal and a plane's position). Not checked: the material (bilinear form), the Dirichlet
        conditions, the load vectors' values, the solver settings, the plastic law; nor the contact parameters of
        a checkpoint written before they were saved (it loads as before).

        Raises:
            ValueError: the file does not match this problem (the message names what differs, with both values).
        """
        return checkpoint.load_state(self.operators, self.sliding, path, self.wear_laws, self._plastic_points())

    def _plastic_points(self) -> np.ndarray | None:
        """This rank's quadrature points' coordinates (an elastic-plastic body; what a checkpoint keys its history
        by). Collective."""
        return self.body.state.point_coordinates() if self.body is not None else None

    def destroy(self) -> None:
        """Free the PETSc objects (factorisation, K if assembled here, load vectors, the plastic body's)."""
        if self.body is not None:
            self.body.destroy()
        self.operators.destroy()
