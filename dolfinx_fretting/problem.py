"""The public problem: frictional contact and fretting wear on the user's own DOLFINx model.

The user owns mesh, space, forms, boundary conditions and loop; this module adds one object that plugs in,
in the idiom of dolfinx_mpc's ``LinearProblem(a, L, mpc, bcs)``::

    contact = Contact(V, (facet_tags, marker), RigidPlane([0, 0], [0, 1]), mu=0.5, bcs=bcs)
    problem = FrettingProblem(a, contact, bcs, wear=Archard(1e-5), loads={"push": L})
    state = problem.initial_state()
    for approach in np.linspace(0, 1e-3, 5)[1:]:
        result = problem.solve(state, normal=approach)          # or normal=Force(100.0)
        state = problem.commit(state, result)                   # rollback = not committing
    result = problem.run_cycle(state, CyclePath.triangular(80, normal=1e-3, tangential=5e-3))
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
:class:`Force` instead prescribes the matching component of the total contact force on the body, the
obstacle position becoming an unknown.

Collective: every method is called on every rank with the same arguments; the local problem is solved on
rank 0 and its result broadcast, so every rank holds the same contact state whatever the partition, and an
error on rank 0 is raised on every rank.
"""

from __future__ import annotations

import json
import os
import time
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np
from mpi4py import MPI

from . import local_solvers
from . import sliding
from .contact import Contact, ContactSet, ElasticBody, constrained_global_dofs
from .loading import LoadControlError, find_displacement, waveform
from .wear import ROW, ROW_FIELDS, commit_increment

__all__ = ["Archard", "Displacement", "Force", "LocalSolver", "Plasticity", "ContactState", "IncrementResult",
           "CyclePath", "CycleResult", "FrettingProblem", "ConvergenceError", "STATUS_NAMES", "INCREMENT_COLUMNS"]

#: Contact status codes of :attr:`ContactState.status` (the wear module's classification).
STATUS_NAMES = {0: "open", 1: "stick", 2: "slip"}
#: Per-increment columns of a cycle's records (:attr:`CycleResult.records`) and of the info of
#: :meth:`FrettingProblem.advance`: the totals of :data:`~dolfinx_fretting.wear.ROW_FIELDS`, then the solver's
#: counters (one declaration: the scene runner's history table reads its columns from here).
SOLVER_COLUMNS = ("local_iterations", "local_error", "load_solves", "newton_iterations", "newton_delta_1",
                  "newton_delta_2", "cutbacks", "yielded_points")
#: Per-increment columns: the :data:`~dolfinx_fretting.wear.ROW_FIELDS`, then the :data:`SOLVER_COLUMNS`.
INCREMENT_COLUMNS = ROW_FIELDS + SOLVER_COLUMNS


class ConvergenceError(RuntimeError):
    """An increment or cycle could not be solved; nothing of it was committed. The message says why.

    Attributes:
        step: In a cycle, the 1-based increment of the cycle that failed (None otherwise).
    """

    def __init__(self, message: str, step: int | None = None):
        super().__init__(message)
        self.step = step


# Settings -------------------------------------------------------------------------------------------------
def _finite(name: str, value: float, low: float | None = None, strict: bool = False) -> float:
    v = float(value)
    if not np.isfinite(v) or (low is not None and (v <= low if strict else v < low)):
        rel = ">" if strict else ">="
        raise ValueError(f"{name} = {value!r}: expected a finite number" + (f" {rel} {low}" if low is not None else ""))
    return v


@dataclass(frozen=True)
class Archard:
    """Archard's wear law, the paper's equation 5: the wear gap grows by ``k p |dx_t|`` where contacts slide.

    Give ``k`` (1/MPa with N, mm), or for two deformable bodies ``k_slave`` and ``k_master``: both see the
    same pressure and slip, the wear gap grows with their sum and each body wears its share.
    ``acceleration`` multiplies k in cycles (each simulated cycle stands for that many physical ones).
    """

    k: float | None = None
    k_slave: float | None = None
    k_master: float | None = None
    acceleration: float = 1.0

    def __post_init__(self) -> None:
        per_body = (self.k_slave is not None, self.k_master is not None)
        if any(per_body) and not all(per_body):
            raise ValueError("Archard: give both k_slave and k_master, or k alone")
        if any(per_body) and self.k is not None:
            raise ValueError("Archard: give either k or (k_slave, k_master), not both")
        if not any(per_body) and self.k is None:
            raise ValueError("Archard: k (1/MPa, finite, >= 0) is required")
        for name in ("k", "k_slave", "k_master"):
            if getattr(self, name) is not None:
                _finite(f"Archard.{name}", getattr(self, name), 0.0)
        _finite("Archard.acceleration", self.acceleration, 1.0)

    @property
    def k_total(self) -> float:
        """The wear gap's coefficient, ``k`` or ``k_slave + k_master``."""
        return float(self.k) if self.k is not None else float(self.k_slave + self.k_master)

    @property
    def slave_share(self) -> float:
        """Fraction of the wear gap worn from the slave body (1 with a single ``k``)."""
        if self.k is not None or self.k_total == 0:
            return 1.0
        return float(self.k_slave) / self.k_total


@dataclass(frozen=True)
class Displacement:
    """A prescribed obstacle displacement component (or per-increment array of them, in a :class:`CyclePath`)."""

    value: Any


@dataclass(frozen=True)
class Force:
    """A prescribed total contact force component on the body (the obstacle position becomes unknown)."""

    value: Any


@dataclass(frozen=True)
class LocalSolver:
    """Settings of the local contact solve (see :func:`dolfinx_fretting.local_solvers.solve`).

    Attributes:
        method: ``"uzawa"`` (the paper's), ``"nsgs"``, ``"newton"`` or ``"auto"``; the compiled cycle loop is
            Uzawa-based, so another method runs cycles increment by increment.
        tol: Natural-map tolerance (unit-free).
        max_iter: Sweeps per local solve.
        force_tol: Relative tolerance of a prescribed force.
        compiled_cycles: Run displacement- and load-controlled elastic cycles in the compiled loop.
        warm_start: ``"cycle"``: an increment of a compiled cycle starts from the same increment of the previous
            cycle; ``"increment"``: from the previous increment.
        pattern_reuse: 2D compiled cycles first try the previous cycle's contact pattern (an exact linear solve
            accepted only if it meets ``tol``).
    """

    method: str = "uzawa"
    tol: float = 1e-10
    max_iter: int = 20000
    force_tol: float = 1e-8
    compiled_cycles: bool = True
    warm_start: str = "cycle"
    pattern_reuse: bool = True

    def __post_init__(self) -> None:
        if self.method not in ("uzawa", "nsgs", "newton", "auto"):
            raise ValueError(f"LocalSolver.method = {self.method!r}: allowed 'uzawa', 'nsgs', 'newton', 'auto'")
        if self.warm_start not in ("cycle", "increment"):
            raise ValueError(f"LocalSolver.warm_start = {self.warm_start!r}: allowed 'cycle', 'increment'")
        if not (0 < _finite("LocalSolver.tol", self.tol) < 1):
            raise ValueError(f"LocalSolver.tol = {self.tol!r}: expected 0 < tol < 1")
        if not (0 < _finite("LocalSolver.force_tol", self.force_tol) < 1):
            raise ValueError(f"LocalSolver.force_tol = {self.force_tol!r}: expected 0 < force_tol < 1")
        if int(self.max_iter) != self.max_iter or self.max_iter < 1:
            raise ValueError(f"LocalSolver.max_iter = {self.max_iter!r}: expected an integer >= 1")


@dataclass(frozen=True)
class Plasticity:
    """An elastic–plastic body: Newton with the contact solve inside every iteration (the paper's Figure 4).

    The constitutive update is the hook: ``law`` is any object with the elastic constants ``E`` and ``nu``
    (they make K, W and the elastic predictor) and a method
    ``update(strain, eps_p, p) -> (stress, eps_p_new, p_new, tangent, yielded)`` on arrays of quadrature
    points: Mandel strain and stress ``(n, 6)`` (``[xx, yy, zz, √2 yz, √2 xz, √2 xy]``; in 2D plane strain the
    out-of-plane strains are zero), plastic strain ``(n, 6)``, a scalar internal variable ``p`` ``(n,)``,
    the consistent tangent ``(n, 6, 6)`` and a boolean ``yielded`` ``(n,)``. It must start from the committed
    ``(eps_p, p)`` it is given and not modify them (the committed history is kept by the state).
    :class:`dolfinx_fretting.materials.J2Plasticity` (von Mises, linear isotropic hardening) is one instance.

    Attributes:
        law: The constitutive update (see above).
        quadrature_degree: Degree of the quadrature rule that carries the plastic state (and of K).
        tangent: Newton iteration matrix: ``"adaptive"`` (default), ``"consistent"`` or ``"elastic"``.
        max_iter, residual_tol, displacement_tol: Newton settings.
        max_cutbacks: Halvings of an increment whose Newton loop fails, in :meth:`FrettingProblem.advance`.
        elastic_cells: Local cells that stay elastic whatever the stress (e.g. the other body of a pair).
    """

    law: Any
    quadrature_degree: int = 2
    tangent: str = "adaptive"
    max_iter: int = 60
    residual_tol: float = 1e-8
    displacement_tol: float = 1e-6
    max_cutbacks: int = 4
    elastic_cells: np.ndarray | None = None


# State and results ----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PlasticHistory:
    """This rank's committed displacement and plastic state (owned quadrature points)."""

    u: np.ndarray
    sigma: np.ndarray
    eps_p: np.ndarray
    p: np.ndarray


@dataclass(frozen=True)
class ContactState:
    """Everything a run needs to go on, after a committed increment (immutable; a checkpoint holds it).

    Per-contact arrays follow the contact set's order, ``dim`` components per contact in the contact's frame
    ``(n, t1[, t2])``.

    Attributes:
        forces: Contact forces r (N; N/mm in 2D plane strain).
        positions: Total relative positions y = W r + q_abs: normal rows the gaps, tangential rows the
            accumulated relative tangential displacement.
        slip: The last increment's local solution x: gaps (normal rows) and slip increments (tangential rows).
        wear_gap: Wear gap per contact (length).
        obstacle: Obstacle displacement in the obstacle frame (approach along n, then t1[, t2]).
        targets: The last increment's prescribed values per obstacle component (the displacement, or the force
            where it was force controlled): what a component not given to :meth:`FrettingProblem.solve` keeps,
            and where a cut increment's sub-steps start from.
        force_controlled: Which components of ``targets`` are forces.
        load_factors: Factor of each named load and Dirichlet data set (:attr:`FrettingProblem.load_names`).
        increment: Increments committed.
        dissipated_energy: Frictional energy dissipated so far.
        local_iterations: Local solver sweeps so far.
        record: The last increment's row (:data:`INCREMENT_COLUMNS`: forces, peak pressure, energy and wear
            added, widths, state counts ..., then the solver's iterations and errors), or None before any
            increment.
        status: Contact status codes of the last increment (0 open, 1 stick, 2 slip).
        warm: Compiled cycles: the forces of every increment of the last cycle (rank 0 only; None elsewhere).
        plastic: This rank's committed plastic history (elastic–plastic problems), else None.
        pairing: Finite sliding (:class:`~dolfinx_fretting.contact.ElasticBody`): the contact set of the
            pairing the per-contact arrays refer to (same slave nodes, frames and H of the paired master points),
            else None.
        master_wear: Finite sliding: the master's worn depth at the surface compliance's nodes
            (:attr:`FrettingProblem.surface_compliance`; 0 at slave nodes); the master's share of ``wear_gap`` is this,
            interpolated at each contact's paired point. None otherwise (the share is carried per contact).
    """

    forces: np.ndarray
    positions: np.ndarray
    slip: np.ndarray
    wear_gap: np.ndarray
    obstacle: np.ndarray
    load_factors: np.ndarray
    targets: np.ndarray | None = None
    force_controlled: np.ndarray | None = None
    increment: int = 0
    dissipated_energy: float = 0.0
    local_iterations: int = 0
    record: dict[str, float] | None = None
    status: np.ndarray | None = None
    warm: np.ndarray | None = None
    plastic: PlasticHistory | None = None
    pairing: ContactSet | None = None
    master_wear: np.ndarray | None = None


@dataclass(frozen=True)
class IncrementResult:
    """A converged increment, not yet committed (see :meth:`FrettingProblem.commit`)."""

    forces: np.ndarray
    slip: np.ndarray
    positions: np.ndarray
    obstacle: np.ndarray
    load_factors: np.ndarray
    in_cycle: bool
    iterations: int
    targets: np.ndarray
    force_controlled: np.ndarray
    error: float
    local_solves: int
    newton: dict[str, Any] | None = None
    plastic: PlasticHistory | None = None


@dataclass(frozen=True)
class CyclePath:
    """The targets of the increments of one load cycle (``n`` increments).

    ``normal`` and ``tangential`` are :class:`Displacement` or :class:`Force` of arrays: ``normal`` of shape
    (n,), ``tangential`` (n,) in 2D or (n, 2) in 3D (components along t1, t2; (n,) in 3D: along t1, t2 at 0);
    in 3D ``tangential`` may also be a pair of items of shape (n,) with their own controls, e.g.
    ``(Force(Q), Displacement(zeros))`` in a half model. ``loads`` maps load names to (n,) factors. Names and
    components not given keep the state's values.
    """

    normal: Displacement | Force | None = None
    tangential: Displacement | Force | tuple | None = None
    loads: Mapping[str, Any] = field(default_factory=dict)

    @property
    def increments(self) -> int:
        for item in (self.normal, self.tangential):
            if isinstance(item, tuple):
                item = item[0]
            if item is not None:
                return int(np.shape(item.value)[0])
        for v in self.loads.values():
            return int(np.shape(v)[0])
        raise ValueError("CyclePath: no target given")

    @classmethod
    def waveform(cls, increments: int, shape: str = "triangular", *, normal: Displacement | Force | float | None = None,
                 tangential: Displacement | Force | float | None = None,
                 loads: Mapping[str, float] | None = None) -> CyclePath:
        """A periodic path: ``normal`` held, ``tangential`` and ``loads`` amplitudes times the waveform
        (:func:`dolfinx_fretting.loading.waveform`: ``"triangular"`` 0 → A → 0 → −A → 0, or ``"sinusoidal"``)."""
        wave = waveform(shape, increments)

        def held(item):
            if item is None:
                return None
            kind = type(item) if isinstance(item, (Displacement, Force)) else Displacement
            value = item.value if isinstance(item, (Displacement, Force)) else item
            return kind(np.full(increments, float(value)))

        def waved(item):
            if item is None:
                return None
            if isinstance(item, tuple):
                return tuple(waved(i) for i in item)
            kind = type(item) if isinstance(item, (Displacement, Force)) else Displacement
            amp = np.asarray(item.value if isinstance(item, (Displacement, Force)) else item, dtype=float)
            return kind(np.multiply.outer(wave, amp) if amp.ndim else amp * wave)

        return cls(held(normal), waved(tangential), {k: a * wave for k, a in (loads or {}).items()})


@dataclass(frozen=True)
class CycleResult:
    """A converged cycle, not yet committed.

    Attributes:
        records: Per-increment columns: every :data:`~dolfinx_fretting.wear.ROW_FIELDS` entry, plus
            ``local_iterations``, ``local_error`` and ``local_solves`` (arrays of length n).
        obstacle: (n, dim) obstacle displacement of each increment (obstacle frame).
        load_factors: (n, L) load factors of each increment.
        final: The state the cycle ends in (committed by :meth:`FrettingProblem.commit`).
        kept: With ``keep=True``: per increment (forces, slip, positions, wear gap, status), arrays (n, ...).
        compiled: True when the compiled loop ran it.
        kept_pairings: Finite sliding with ``keep=True``: the pairing each kept increment's arrays refer to
            (:attr:`ContactState.pairing`), else None.
    """

    records: dict[str, np.ndarray]
    obstacle: np.ndarray
    load_factors: np.ndarray
    final: ContactState
    kept: tuple[np.ndarray, ...] | None
    compiled: bool
    kept_pairings: tuple[ContactSet, ...] | None = None


def _solver_columns(result: IncrementResult, newton_iterations: int | None = None,
                    local_iterations: int | None = None, cutbacks: int = 0) -> dict[str, Any]:
    """The :data:`SOLVER_COLUMNS` of an increment (and ``full_newton_fallbacks``); ``advance`` gives the totals
    over its sub-increments."""
    newton = result.newton or {}
    return {"local_iterations": result.iterations if local_iterations is None else local_iterations,
            "local_error": result.error, "load_solves": result.local_solves,
            "newton_iterations": (newton_iterations if newton_iterations is not None
                                  else newton.get("newton_iterations", 1)) if result.newton is not None else 1,
            "newton_delta_1": newton.get("delta_1", 0.0), "newton_delta_2": newton.get("delta_2", 0.0),
            "cutbacks": cutbacks, "yielded_points": newton.get("yielded_points", 0),
            "full_newton_fallbacks": newton.get("full_newton_fallback", 0)}


# The problem ----------------------------------------------------------------------------------------------
class FrettingProblem:
    """Frictional contact and wear of a linear elastic (or elastic–plastic) body. Collective.

    Args:
        a: The bilinear form of K (UFL or ``fem.Form``), or an assembled PETSc matrix (Dirichlet rows already
            applied; then ``prescribed`` and a non-zero Dirichlet value are not available).
        contact: The :class:`~dolfinx_fretting.contact.Contact`.
        bcs: Dirichlet conditions. Their values are part of the model (applied in full at every increment);
            to scale a Dirichlet value along a load path, give it in ``prescribed`` instead.
        wear: :class:`Archard`, or None (no wear).
        loads: Named linear forms (UFL or ``fem.Form``) or assembled PETSc vectors; each is applied times its
            factor (``loads={"face": 2.0}`` in :meth:`solve`).
        prescribed: Named lists of Dirichlet conditions with non-zero values (``fem.Function`` or
            ``fem.Constant`` data): each set is applied times its factor.
        petsc_options: Options of the factorisation (MUMPS Cholesky by default; keys without prefix).
        delassus_method: Route for W: ``"auto"``, ``"selected_inverse"``, ``"owned"``, ``"block"``, ``"columns"``,
            ``"schur"`` (serial only).
        solver: :class:`LocalSolver` settings.
        plasticity: :class:`Plasticity` for an elastic–plastic body, else None.
        options_prefix: PETSc options prefix of the factorisation (unique per problem by default).
    """

    _count = 0

    def __init__(self, a, contact: Contact, bcs: Sequence = (), *, wear: Archard | None = None,
                 loads: Mapping[str, Any] | None = None, prescribed: Mapping[str, Sequence] | None = None,
                 petsc_options: Mapping[str, Any] | None = None, delassus_method: str = "auto",
                 solver: LocalSolver | None = None, plasticity: Plasticity | None = None,
                 options_prefix: str | None = None):
        from . import _dolfinx as dfx
        from ._dolfinx import fem
        from petsc4py import PETSc

        from .compliance import METHODS, DelassusOperator

        if not isinstance(contact, Contact):
            raise TypeError(f"FrettingProblem: contact must be a Contact, got {type(contact).__name__}")
        if delassus_method not in METHODS:
            raise ValueError(f"FrettingProblem: delassus_method = {delassus_method!r}: allowed {', '.join(METHODS)}")
        if wear is not None and not isinstance(wear, Archard):
            raise TypeError("FrettingProblem: wear must be an Archard law or None")
        self.contact = contact
        self.V = contact.V
        self.comm: MPI.Comm = self.V.mesh.comm
        self.wear = wear
        self.solver = solver or LocalSolver()
        self.plasticity = plasticity
        prescribed = dict(prescribed or {})
        loads = dict(loads or {})
        for name in list(loads) + list(prescribed):
            if not isinstance(name, str) or not name:
                raise ValueError(f"FrettingProblem: load names must be non-empty strings, got {name!r}")
        if set(loads) & set(prescribed):
            raise ValueError(f"FrettingProblem: names used twice: {sorted(set(loads) & set(prescribed))}")
        self.bcs = list(bcs)
        self.prescribed = {k: list(v) for k, v in prescribed.items()}
        all_bcs = self.bcs + [bc for v in self.prescribed.values() for bc in v]
        # The contact and K must fix the same dofs: W is built on the contact's free dofs, and K has identity
        # rows exactly at the dofs of these conditions.
        fixed = constrained_global_dofs(self.V, all_bcs)
        if not np.array_equal(fixed, contact.fixed_global):
            raise ValueError("FrettingProblem: the Dirichlet conditions (bcs and prescribed) differ from those given "
                             f"to the Contact ({fixed.size} fixed dofs here, {contact.fixed_global.size} there): pass "
                             "the same conditions to Contact(..., bcs=...), or W would be wrong")
        if plasticity is not None and self.prescribed:
            raise ValueError("FrettingProblem: prescribed Dirichlet data are not supported with plasticity "
                             "(the Newton loop holds Dirichlet dofs at zero)")

        t0 = time.perf_counter()
        #: Wall times (s) of the assembly, the factorisation and W (with the load responses).
        self.timings: dict[str, float] = {}
        FrettingProblem._count += 1
        prefix = options_prefix or f"dolfinx_fretting_{FrettingProblem._count}_"
        self._form = None
        if isinstance(a, PETSc.Mat):
            if self.prescribed:
                raise ValueError("FrettingProblem: prescribed Dirichlet data need the bilinear form, not a matrix")
            self.K = a
            self._own_K = False
        else:
            self._form = dfx.compiled_form(a)
            self.K = fem.petsc.assemble_matrix(self._form, bcs=all_bcs)
            self.K.assemble()
            self._own_K = True
        self.all_bcs = all_bcs
        base = self._dirichlet_vector(self.bcs) if self._form is not None else None
        if base is not None and plasticity is not None:
            base.destroy()
            raise ValueError("FrettingProblem: non-zero Dirichlet values in bcs are not supported with plasticity "
                             "(the Newton loop holds the Dirichlet dofs at zero); give the motion to the obstacle "
                             "(normal=, tangential=) or apply a load instead")
        self.timings["assemble_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        self.delassus = DelassusOperator(self.K, self.comm, method=delassus_method,
                                         petsc_options=dict(petsc_options or {}), options_prefix=prefix)
        self.delassus.factorize()
        self.timings["factorize_s"] = time.perf_counter() - t0
        self._vectors: list = []   # PETSc vectors of the loads (owned by this problem)
        #: Names of the load vectors, in the order of :attr:`ContactState.load_factors`: ``"dirichlet
        #: values"`` first if ``bcs`` prescribe non-zero values, then the keys of ``loads``, ``prescribed``.
        self.load_names: list[str] = []
        if base is not None:
            self._add_vector("dirichlet values", base)
        for name, form in loads.items():
            self._add_vector(name, self._load_vector(form))
        for name, conditions in self.prescribed.items():
            vec = self._dirichlet_vector(conditions)
            if vec is None:
                raise ValueError(f"FrettingProblem: prescribed[{name!r}] has zero values everywhere")
            self._add_vector(name, vec)
        #: Loads always applied at factor 1 (the values of ``bcs``), by index in :attr:`load_names`.
        self._fixed_factor = [i for i, n in enumerate(self.load_names) if n == "dirichlet values"]
        self.body = None
        t0 = time.perf_counter()
        #: Finite sliding: K^-1 on both contact surfaces' dofs
        #: (:class:`~dolfinx_fretting.sliding.SurfaceCompliance`), from which each pairing's W and load responses
        #: are formed; None with small sliding or a rigid plane. ``self.contact`` is then a copy of the given
        #: Contact holding the pairing of the state last solved or committed
        #: (:meth:`~dolfinx_fretting.contact.Contact.with_pairing`).
        self.surface_compliance: sliding.SurfaceCompliance | None = None
        if isinstance(contact.obstacle, ElasticBody) and contact.obstacle.sliding == "finite":
            if plasticity is not None:
                raise ValueError("FrettingProblem: finite sliding (ElasticBody(sliding='finite')) is for elastic "
                                 "bodies; an elastic-plastic problem keeps the pairing fixed (sliding='small')")
            self.surface_compliance = self._surface_compliance()
        self._build_contact_operators()
        self.timings["delassus_s"] = time.perf_counter() - t0
        self._kernel = None
        self._reference_pairing = self.contact.contact_set
        self._repairs = 0
        #: Two bodies: warn (once) when the relative slip exceeds half a master element (see
        #: :meth:`relative_slip_ratio`); set False when the caller reports it itself.
        self.sliding_warning = True
        if plasticity is not None:
            self._make_plastic_body()

    # Construction helpers -----------------------------------------------------------------------------
    def _add_vector(self, name: str, vec) -> None:
        self.load_names.append(name)
        self._vectors.append(vec)

    def _load_vector(self, form):
        from . import _dolfinx as dfx
        from ._dolfinx import fem
        from petsc4py import PETSc

        if isinstance(form, PETSc.Vec):
            f = form.copy()
        else:
            L = dfx.compiled_form(form)
            f = fem.petsc.assemble_vector(L)
            if self._form is not None:
                fem.petsc.apply_lifting(f, [self._form], bcs=[self.all_bcs])
            f.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dfx.set_bc(f, self.all_bcs, scale=0.0)  # a load alone: zero displacement at every fixed dof
        return _plain_vector(f, self.K)

    def _dirichlet_vector(self, conditions):
        """The right-hand side of the Dirichlet values of ``conditions`` alone (lifting, other fixed dofs 0)."""
        from . import _dolfinx as dfx
        from ._dolfinx import fem
        from petsc4py import PETSc

        if not conditions:
            return None
        f = dfx.vector_for_form(fem.form(_zero_linear_form(self.V)))
        with f.localForm() as loc:
            loc.set(0.0)
        fem.petsc.apply_lifting(f, [self._form], bcs=[list(conditions)])
        f.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dfx.set_bc(f, self.all_bcs, scale=0.0)
        dfx.set_bc(f, list(conditions))
        if f.norm() == 0.0:
            f.destroy()
            return None
        return _plain_vector(f, self.K)

    def _build_contact_operators(self, keep_slope: bool = False) -> None:
        """W on the free dofs (one copy broadcast from rank 0) and each load's contact response (finite sliding:
        formed from the surface compliance, no communication)."""
        cs = self.contact.contact_set
        if self.surface_compliance is not None:
            self.W, self.responses = self.surface_compliance.operators(cs)
        else:
            W = self.delassus.build(self.contact.H_free)
            self.W = self.comm.bcast(W if self.comm.rank == 0 else None, root=0)
            self.responses = np.zeros((len(self._vectors), cs.nc * cs.dim))
            for i, f in enumerate(self._vectors):
                self.responses[i] = self._local_response(f)
        self._hold_directions()
        if not (keep_slope and hasattr(self, "_stiffness")):
            # Point stiffness of the closest node: a safe first guess of the load-displacement slope (kept when
            # only the pairing changes, so that a force-controlled run does not depend on which state was read)
            k = int(np.argmin(cs.gap0))
            blk = self.W[k * cs.dim:(k + 1) * cs.dim, k * cs.dim:(k + 1) * cs.dim]
            self._stiffness = np.array([1.0 / blk[c, c] for c in range(cs.dim)])
        self._kernel = None

    def _hold_directions(self) -> None:
        """Tangential directions held by the conditions (:attr:`Contact.held_rows`, e.g. a symmetry plane's
        roller): W is zero on their rows and columns; they get the contact's normal compliance on the diagonal,
        which keeps the local problem well posed and leaves their force at zero as long as nothing moves along
        them (then ``x = c r`` there: sticking gives r = 0, sliding ``r = -mu r_n x_t/|x_t|`` gives r = 0 too).
        Obstacle components along them are refused (:meth:`_check_held`), as are loads that move them.
        Then every contact's diagonal block must be positive definite."""
        cs = self.contact.contact_set
        dim = cs.dim
        held = self.contact.held_rows
        if held.size:
            normal_rows = held - held % dim
            self.W[held, held] = self.W[normal_rows, normal_rows]
            scale = np.abs(self.responses).max(initial=0.0)
            moved = np.abs(self.responses[:, held]).max(initial=0.0)
            if moved > 1e-12 * scale:
                c, k = divmod(int(held[np.argmax(np.abs(self.responses[:, held]).max(axis=0))]), dim)
                raise ValueError(
                    f"FrettingProblem: a load or Dirichlet value moves contact {c} (node at {cs.coords[c].tolist()}) "
                    f"along its direction t{k}, which the conditions hold (a roller): a half model's loads must be "
                    "symmetric about its symmetry plane")
        # Obstacle components (rows of the obstacle frame) with a component along a held direction.
        held_dirs = cs.frames.reshape(-1, dim)[held]
        self._held_components = np.abs(held_dirs @ self.contact.frame.T).max(axis=0, initial=0.0) > 1e-9
        blocks = np.array([self.W[c * dim:(c + 1) * dim, c * dim:(c + 1) * dim] for c in range(cs.nc)])
        eig = np.linalg.eigvalsh(0.5 * (blocks + blocks.transpose(0, 2, 1))) if cs.nc else np.zeros((0, dim))
        bad = np.flatnonzero(eig[:, 0] <= 1e-10 * eig[:, -1])
        if bad.size:
            c = int(bad[0])
            raise ValueError(
                f"FrettingProblem: the compliance of contact {c} (node at {cs.coords[c].tolist()}) is singular "
                f"(eigenvalues {eig[c].tolist()}): the conditions fix a combination of its directions n, t1"
                f"{', t2' if dim == 3 else ''} that is not one of them (a roller must fix the component along one "
                "of the contact frame's directions, e.g. u_y on a symmetry plane y = 0 with the obstacle normal in "
                "that plane)")

    def _check_held(self, obstacle: np.ndarray, force_controlled: np.ndarray) -> None:
        """Refuse obstacle motions and forces along a held contact direction (see :meth:`_hold_directions`)."""
        held = self._held_components
        if not held.any():
            return
        obstacle = np.atleast_2d(obstacle)
        names = ["normal"] + [f"tangential t{k}" for k in range(1, self.dim)]
        for k in np.flatnonzero(held):
            if force_controlled[k] or np.any(obstacle[:, k] != 0.0):
                what = "a force" if force_controlled[k] else f"a motion ({np.abs(obstacle[:, k]).max():.3g})"
                raise ValueError(
                    f"{names[k]} = {what}: the conditions hold some contacts along this direction (a roller, e.g. "
                    "on a symmetry plane): a half model moves only in its symmetry plane. Prescribe "
                    f"Displacement(0) along {names[k]} (in 3D, tangential=(Force(Q), Displacement(0.0)) for a "
                    "force along t1 alone)")

    def _local_response(self, f, H=None) -> np.ndarray:
        """``H K^-1 f`` with the full H (prescribed values at fixed dofs count; default the contact set's),
        replicated. Collective."""
        H = self.contact.contact_set.H if H is None else H
        u = f.duplicate()
        self.delassus.solve(f, u)
        rstart, rend = u.getOwnershipRange()
        part = H[:, rstart:rend] @ u.getArray(readonly=True)
        u.destroy()
        return self.comm.allreduce(part, op=MPI.SUM)

    def _surface_compliance(self) -> sliding.SurfaceCompliance:
        """K^-1 on the dofs of both contact surfaces and the loads' responses there (finite sliding). Collective."""
        import scipy.sparse as sp

        cs = self.contact.contact_set
        faces, nodes = sliding.surface_nodes(cs, self.contact.obstacle.reach)
        paired = cs.master_nodes[cs.master_nodes >= 0]
        if not np.isin(paired, nodes).all():  # before the build: the reference pairing must lie within reach
            raise ValueError(f"ElasticBody.reach = {self.contact.obstacle.reach!r}: too short for the reference "
                             "pairing itself (a slave candidate's closest master facet lies beyond it); allowed a "
                             "reach at least the candidates' largest initial gap, or None")
        dim = cs.dim
        dofs = (dim * nodes[:, None] + np.arange(dim)).ravel()
        S = sp.csr_matrix((np.ones(dofs.size), (np.arange(dofs.size), dofs)), shape=(dofs.size, self.n_dofs))
        free = np.ones(self.n_dofs)
        free[self.contact.fixed_global] = 0.0
        S_free = sp.csr_matrix(S @ sp.diags(free))
        S_free.eliminate_zeros()
        C = self.delassus.build(S_free)
        C = self.comm.bcast(C if self.comm.rank == 0 else None, root=0)
        responses = np.array([self._local_response(f, S) for f in self._vectors]).reshape(len(self._vectors),
                                                                                          dofs.size)
        # rank 0's sums on every rank: each rank decides the re-pairings from these, so they must be the same bits
        responses = self.comm.bcast(responses if self.comm.rank == 0 else None, root=0)
        return sliding.SurfaceCompliance(nodes, dim, C, responses, faces,
                                         sliding.master_node_areas(cs.master_surface, nodes))

    def contact_set_of(self, state: ContactState) -> ContactSet:
        """The contact set ``state``'s per-contact arrays refer to (its pairing under finite sliding), without
        switching the problem to it (reading a state changes nothing)."""
        return state.pairing if state.pairing is not None else self.contact.contact_set

    def obstacle_translation(self, obstacle: np.ndarray) -> np.ndarray:
        """The obstacle's rigid translation D (global frame) from its components ``obstacle`` in the obstacle
        frame (:attr:`ContactState.obstacle`: approach along n, then t1[, t2])."""
        frame = self.contact.frame
        return sum(obstacle[k] * frame[k] for k in range(frame.shape[0]))

    def _activate(self, state: ContactState) -> None:
        """Finite sliding: hold ``state``'s pairing (its contact set, W and load responses) if another is held."""
        if state.pairing is None or state.pairing is self.contact.contact_set:
            return
        self.contact = self.contact.with_pairing(state.pairing)
        self._build_contact_operators(keep_slope=True)

    def _make_plastic_body(self) -> None:
        from .materials import J2Plasticity
        from .plasticity import ElastoplasticBody

        pl = self.plasticity
        law = pl.law
        if not (hasattr(law, "E") and hasattr(law, "nu") and (hasattr(law, "update") or isinstance(law, J2Plasticity))):
            raise TypeError("Plasticity.law must have E, nu and update(strain, eps_p, p) (see Plasticity)")
        single = self._single_load_vector()
        self.body = ElastoplasticBody(self, law, self.contact.H_free, self.W, single, tangent=pl.tangent,
                                      max_iter=pl.max_iter, delta_1=pl.residual_tol, delta_2=pl.displacement_tol,
                                      quadrature_degree=pl.quadrature_degree, elastic_cells=pl.elastic_cells)

    def _single_load_vector(self):
        return self._vectors[0] if self._vectors else None

    # Properties -----------------------------------------------------------------------------------------
    @property
    def n_dofs(self) -> int:
        """Global number of displacement dofs."""
        return self.V.dofmap.index_map.size_global * self.V.dofmap.index_map_bs

    @property
    def dim(self) -> int:
        return self.contact.dim

    def _factors(self, state: ContactState, loads: Mapping[str, float] | None) -> np.ndarray:
        s = state.load_factors.copy()
        for name, value in (loads or {}).items():
            if name not in self.load_names or name == "dirichlet values":
                raise KeyError(f"unknown load {name!r}; this problem's loads: "
                               f"{', '.join(n for n in self.load_names if n != 'dirichlet values') or 'none'}")
            s[self.load_names.index(name)] = _finite(f"loads[{name!r}]", value)
        return s

    # States -------------------------------------------------------------------------------------------------
    def initial_state(self) -> ContactState:
        """The unloaded, unworn state (obstacle at its initial position, every load factor 0; finite sliding:
        the reference configuration's pairing)."""
        finite = self.surface_compliance is not None
        cs = self._reference_pairing if finite else self.contact.contact_set
        m = cs.nc * cs.dim
        y = np.zeros(m)
        y[0::cs.dim] = cs.gap0
        factors = np.zeros(len(self.load_names))
        factors[self._fixed_factor] = 1.0
        plastic = None
        if self.body is not None:
            st = self.body.state
            plastic = PlasticHistory(np.zeros_like(self.body.u.x.array), np.zeros_like(st.sigma),
                                     np.zeros_like(st.eps_p), np.zeros_like(st.p))
        return ContactState(np.zeros(m), y, np.zeros(m), np.zeros(cs.nc), np.zeros(cs.dim), factors,
                            targets=np.zeros(cs.dim), force_controlled=np.zeros(cs.dim, dtype=bool), plastic=plastic,
                            pairing=cs if finite else None,
                            master_wear=np.zeros(self.surface_compliance.nodes.size) if finite else None)

    def _q(self, d: np.ndarray, factors: np.ndarray, y_prev: np.ndarray, gw: np.ndarray,
           q_body: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(q for the local problem, q_abs) of an increment; ``q_body`` replaces the loads' response."""
        cs = self.contact.contact_set
        D = self.obstacle_translation(d)
        if q_body is None:  # sum_l s_l q_l, in load order (one load: s q, as the compiled loop adds it)
            q_body = np.zeros(cs.nc * cs.dim) if not len(self.load_names) else factors[0] * self.responses[0]
            for i in range(1, len(self.load_names)):
                q_body = q_body + factors[i] * self.responses[i]
        q_abs = -cs.rigid_modes @ D + q_body
        q_abs[0::cs.dim] += cs.gap0 + gw
        q = q_abs.copy()
        normal = np.arange(q.size) % cs.dim == 0
        q[~normal] -= y_prev[~normal]
        return q, q_abs

    # Increments ---------------------------------------------------------------------------------------------
    def solve(self, state: ContactState, normal: float | Displacement | Force | None = None,
              tangential: float | Sequence[float] | Displacement | Force | None = None,
              loads: Mapping[str, float] | None = None, *, in_cycle: bool = False) -> IncrementResult:
        """Solve one increment from ``state`` (nothing is committed). Collective.

        Args:
            state: The committed state to start from.
            normal: Obstacle approach along n (a float or :class:`Displacement`), or :class:`Force` on the body
                along n; None keeps the state's prescribed value (the approach, or the force if the last
                increment prescribed one).
            tangential: Obstacle motion along t1 (2D) or (t1, t2) (3D), or :class:`Force` components; None
                keeps the state's prescribed values likewise.
            loads: Factors of named loads and prescribed Dirichlet data; names not given keep their factors.
            in_cycle: The increment belongs to a load cycle (the wear law's acceleration applies at commit).

        Returns:
            The converged increment.

        Raises:
            ConvergenceError: the local solver, a force control or (elastic–plastic) Newton failed.
        """
        self._activate(state)
        targets, controlled = self._targets(state, normal, tangential)
        factors = self._factors(state, loads)
        if self.body is not None:
            return self._plastic_solve(state, targets, controlled, factors, in_cycle)
        solved = self._contact_solve(state, targets, controlled, factors, None, None)
        return replace(solved, in_cycle=in_cycle)

    def _targets(self, state: ContactState, normal, tangential) -> tuple[np.ndarray, np.ndarray]:
        dim = self.dim
        targets = (state.targets if state.targets is not None else state.obstacle).astype(float).copy()
        controlled = (state.force_controlled.copy() if state.force_controlled is not None
                      else np.zeros(dim, dtype=bool))

        def parse(item, comps: list[int], name: str):
            if item is None:
                return
            if isinstance(item, (tuple, list)) and any(isinstance(i, (Displacement, Force)) for i in item):
                # One item per component, e.g. (Force(Q), Displacement(0.0)): a force along t1, t2 held.
                if len(item) != len(comps):
                    raise ValueError(f"{name} = {item!r}: expected {len(comps)} component(s)")
                for c, sub in zip(comps, item):
                    parse(sub, [c], name)
                return
            kind_force = isinstance(item, Force)
            value = item.value if isinstance(item, (Displacement, Force)) else item
            values = np.atleast_1d(np.asarray(value, dtype=float))
            if values.size == 1 and len(comps) > 1 and name == "tangential":
                values = np.concatenate([values, np.zeros(len(comps) - 1)])
            if values.size != len(comps):
                raise ValueError(f"{name} = {value!r}: expected {len(comps)} component(s)")
            for c, v in zip(comps, values):
                targets[c] = _finite(f"{name}", v)
                controlled[c] = kind_force

        parse(normal, [0], "normal")
        parse(tangential, list(range(1, dim)), "tangential")
        self._check_held(targets, controlled)
        return targets, controlled

    def _contact_solve(self, state: ContactState, targets: np.ndarray, controlled: np.ndarray,
                       factors: np.ndarray, q_body: np.ndarray | None, W: np.ndarray | None,
                       r_warm: np.ndarray | None = None) -> IncrementResult:
        """The local problem with its load control, on rank 0, broadcast; raises ConvergenceError on all ranks."""
        return self._on_rank0(lambda: self._local_with_control(state, targets, controlled, factors, q_body, W,
                                                               r_warm))

    def _on_rank0(self, work: Callable[[], Any]) -> Any:
        """Run ``work`` on rank 0 and broadcast its value; an exception there is raised on every rank (the
        others would otherwise wait in the broadcast forever)."""
        value = failure = None
        if self.comm.rank == 0:
            try:
                value = work()
            except ConvergenceError as exc:
                failure = ("ConvergenceError", str(exc), exc.step)
            except Exception as exc:  # noqa: BLE001 - re-raised on every rank below
                failure = (type(exc).__name__, str(exc), None)
        if self.comm.size > 1:
            value, failure = self.comm.bcast((value, failure), root=0)
        if failure is not None:
            kind, message, step = failure
            if kind == "ConvergenceError":
                raise ConvergenceError(message, step=step)
            raise RuntimeError(f"{kind} on rank 0: {message}")
        return value

    def _local_with_control(self, state: ContactState, targets: np.ndarray, controlled: np.ndarray,
                            factors: np.ndarray, q_body: np.ndarray | None, W: np.ndarray | None,
                            r_warm: np.ndarray | None) -> IncrementResult:
        cs = self.contact.contact_set
        frame = self.contact.frame
        dim = cs.dim
        Wm = self.W if W is None else W
        sv = self.solver
        d = state.obstacle.astype(float).copy()
        warm = [state.forces.copy() if r_warm is None else r_warm.copy()]
        count = {"solves": 0, "iterations": 0}
        last: dict[str, Any] = {}

        def local(dd: np.ndarray) -> np.ndarray:
            q, q_abs = self._q(dd, factors, state.positions, state.wear_gap, q_body)
            res = local_solvers.solve(Wm, q, self.contact.mu, dim, method=sv.method, tol=sv.tol,
                                      max_iter=sv.max_iter, r0=warm[0])
            count["solves"] += 1
            count["iterations"] += res.iterations
            if not res.converged:
                raise ConvergenceError(f"local solver did not converge: {res.message}")
            warm[0] = res.r
            F = cs.total_force(res.r)
            last.update(res=res, d=dd.copy(), q_abs=q_abs, F=np.array([F @ frame[k] for k in range(dim)]))
            return last["F"]

        d[~controlled] = targets[~controlled]
        names = ["normal force"] + [f"tangential force (t{k})" for k in range(1, dim)]
        try:
            F = local(d)
            # Tolerance relative to the loads in play (a zero tangential target is held to the normal force).
            scale = max(np.abs(targets[controlled]).max(initial=0.0), np.abs(F).max(), 1e-300)
            ftol = sv.force_tol * scale
            for _sweep in range(100):
                if np.all(np.abs(F - targets)[controlled] <= ftol):
                    break
                for k in np.flatnonzero(controlled):
                    def force_k(v: float, k: int = k) -> float:
                        dd = d.copy()
                        dd[k] = v
                        return local(dd)[k]
                    d_old, F_old = d[k], F[k]
                    d[k], _, _ = find_displacement(force_k, targets[k], d[k], self._stiffness[k], ftol, name=names[k])
                    F = last["F"]  # the root finder's last evaluation is at the returned d[k]
                    if d[k] != d_old and F[k] != F_old:
                        self._stiffness[k] = abs((F[k] - F_old) / (d[k] - d_old))
            else:
                raise ConvergenceError(f"prescribed forces not reached after 100 sweeps (residual "
                                       f"{np.abs(F - targets)[controlled]}, tolerance {ftol:.3g})")
        except LoadControlError as exc:
            raise ConvergenceError(str(exc)) from None
        res = last["res"]
        y = Wm @ res.r + last["q_abs"]
        return IncrementResult(res.r.copy(), res.x.copy(), y, last["d"].copy(), factors.copy(), False,
                               count["iterations"], targets.copy(), controlled.copy(), res.error, count["solves"])

    def _plastic_solve(self, state: ContactState, targets: np.ndarray, controlled: np.ndarray,
                       factors: np.ndarray, in_cycle: bool) -> IncrementResult:
        from .plasticity import NewtonError

        body = self.body
        self._load_plastic(state.plastic)
        scale = body.set_loads([(self._vectors[i], factors[i]) for i in range(len(self.load_names))])
        warm = [state.forces]
        total = {"iterations": 0, "solves": 0}

        def local_solve(q_body, W):
            solved = self._contact_solve(state, targets, controlled, factors, q_body, W, warm[0])
            warm[0] = solved.forces
            total["iterations"] += solved.iterations
            total["solves"] += solved.local_solves
            return solved

        try:
            try:
                solved, info = body.increment(local_solve, scale)
            except NewtonError:
                if body.tangent != "adaptive":
                    raise
                # The adaptive matrix failed: full Newton on the same increment before giving up.
                body.tangent = "consistent"
                try:
                    solved, info = body.increment(local_solve, scale)
                finally:
                    body.tangent = "adaptive"
                info = dict(info, full_newton_fallback=1)
        except (NewtonError, ConvergenceError) as exc:
            raise ConvergenceError(str(exc)) from None
        st = body.state
        history = PlasticHistory(body._trial.x.array.copy(), st.trial_sigma.copy(), st.trial_eps_p.copy(),
                                 st.trial_p.copy())
        return replace(solved, in_cycle=in_cycle, newton=info, plastic=history,
                       iterations=total["iterations"], local_solves=total["solves"])

    def _load_plastic(self, history: PlasticHistory | None) -> None:
        """Make ``history`` the body's committed state (a state may be solved from more than once)."""
        body = self.body
        if history is None:
            raise ValueError("this elastic-plastic problem needs a state with its plastic history "
                             "(from initial_state() or commit())")
        body.u.x.array[:] = history.u
        st = body.state
        st.sigma, st.eps_p, st.p = history.sigma.copy(), history.eps_p.copy(), history.p.copy()

    def plastic_state(self, state: ContactState):
        """The body's :class:`~dolfinx_fretting.plasticity.PlasticState` holding ``state``'s committed history
        (von Mises stress, equivalent plastic strain, cell averages for output)."""
        self._load_plastic(state.plastic)
        return self.body.state

    def commit(self, state: ContactState, result: IncrementResult | CycleResult) -> ContactState:
        """The new state after a converged increment or cycle: Archard's law (increments), the plastic history,
        the totals of :attr:`ContactState.record`. ``state`` itself is not changed. Collective only in name
        (no communication: every rank holds the same contact data)."""
        if isinstance(result, CycleResult):
            self._check_sliding(result.final)
            return result.final
        self._activate(state)
        cs = self.contact.contact_set
        states = np.empty(cs.nc, dtype=np.int8)
        row = np.empty(len(ROW_FIELDS))
        gw = state.wear_gap.copy()
        commit_increment(result.forces, result.slip, result.positions, self.contact.mu, cs.dim, cs.tributary,
                         cs.abscissa, self._k(result.in_cycle), gw, states, row)
        master_wear = state.master_wear
        if self.surface_compliance is not None and self.wear is not None:
            # The master's share of the wear stays on the master's nodes (it follows its material points).
            master_share = (1.0 - self.wear.slave_share) * (gw - state.wear_gap)
            added = sliding.spread_wear(cs, self.surface_compliance, master_share)
            master_wear = state.master_wear + added
            gw = gw - master_share + sliding.interpolate_master(cs, self.surface_compliance, added)
            # the worn area of both bodies: the flat's wear left behind by the slide is no longer under a contact
            row[ROW["wear_area"]] = self.worn_measure(replace(state, wear_gap=gw, master_wear=master_wear))
        record = {**dict(zip(ROW_FIELDS, row.tolist())), **_solver_columns(result)}
        new = replace(state, forces=result.forces, positions=result.positions, slip=result.slip, wear_gap=gw,
                      obstacle=result.obstacle, load_factors=result.load_factors, increment=state.increment + 1,
                      dissipated_energy=state.dissipated_energy + row[ROW["dissipated_energy"]],
                      local_iterations=state.local_iterations + result.iterations, record=record, status=states,
                      targets=result.targets, force_controlled=result.force_controlled,
                      plastic=result.plastic if result.plastic is not None else state.plastic, master_wear=master_wear)
        if self.surface_compliance is not None:
            return self._repair(new)
        self._check_sliding(new)
        return new

    def _surface_state(self, state: ContactState) -> tuple[np.ndarray, np.ndarray]:
        """Finite sliding: (the surface nodes' displacement, the master's translation D) of ``state``."""
        u = self.surface_compliance.displacement(state.pairing, state.forces, state.load_factors)
        return u, self.obstacle_translation(state.obstacle)

    def _repair(self, state: ContactState) -> ContactState:
        """Finite sliding: pair the slave nodes anew once a paired point has moved more than
        ``ElasticBody.repair_slip`` master elements from its slave node, and carry ``state`` into the new
        pairing (:func:`~dolfinx_fretting.sliding.carry_state`). Not collective (replicated data)."""
        cs = state.pairing
        u, D = self._surface_state(state)
        moved = sliding.offsets(cs, self.surface_compliance, u, D).max(initial=0.0)
        if moved <= self.contact.obstacle.repair_slip:
            return state
        if moved > 1.0 and self.sliding_warning and not getattr(self, "_stride_warned", False):
            self._stride_warned = True
            if self.comm.rank == 0:
                warnings.warn(f"finite sliding: an increment moved a paired point {moved:.3g} master elements (more than "
                              "one): it was solved on a pairing that no longer faced its nodes; take smaller "
                              "increments", RuntimeWarning, stacklevel=3)
        new = sliding.repair(cs, self.surface_compliance, u, D)
        if np.array_equal(new.master_faces, cs.master_faces) and np.allclose(new.master_weights, cs.master_weights,
                                                                             rtol=0.0, atol=1e-12):
            return state   # e.g. a node facing past the master's end: its closest point does not move
        carried = sliding.carry_state(cs, new, self.surface_compliance, u, D, state.forces, state.slip,
                                      state.wear_gap, state.master_wear)
        self._repairs += 1
        loaded = state.forces[0::cs.dim] > 0
        beyond = sliding.offsets(new, self.surface_compliance, u, D)[loaded]
        if beyond.size and beyond.max() > self.contact.obstacle.repair_slip and self.sliding_warning \
                and not getattr(self, "_reach_warned", False):
            self._reach_warned = True
            if self.comm.rank == 0:
                warnings.warn(f"finite sliding: a loaded contact is {beyond.max():.3g} master elements from the "
                              "closest master point within reach: it has slid beyond ElasticBody.reach (or off the "
                              "master surface)", RuntimeWarning, stacklevel=3)
        return replace(state, pairing=new, **carried)

    @property
    def repairs(self) -> int:
        """Finite sliding: how many times the slave nodes were paired anew (by this problem, all states)."""
        return self._repairs

    def relative_slip_ratio(self, state: ContactState) -> float:
        """Two deformable bodies: the largest accumulated relative tangential displacement of a contact over its
        master facet's size (:attr:`~dolfinx_fretting.contact.ContactSet.master_sizes`); 0 against a rigid
        plane. The pairing is fixed (small sliding): past 0.5 the master point of a node is no longer the one
        facing it."""
        cs = self.contact.contact_set
        if cs.master_sizes is None:
            return 0.0
        if self.surface_compliance is not None:  # how far the paired points have moved since the pairing
            offsets = sliding.offsets(state.pairing, self.surface_compliance, *self._surface_state(state))
            return float(offsets.max(initial=0.0))
        y_t = state.positions.reshape(cs.nc, cs.dim)[:, 1:]
        return float((np.linalg.norm(y_t, axis=1) / cs.master_sizes).max(initial=0.0))

    def _check_sliding(self, state: ContactState) -> None:
        """Warn once (RuntimeWarning, rank 0) when the relative slip of two bodies exceeds half a master facet,
        unless :attr:`sliding_warning` is False (a driver that reports it itself)."""
        if not self.sliding_warning or getattr(self, "_sliding_warned", False) or self.surface_compliance is not None:
            return
        ratio = self.relative_slip_ratio(state)
        if ratio > 0.5:
            self._sliding_warned = True
            if self.comm.rank == 0:
                warnings.warn(
                    f"relative slip of {ratio:.3g} master elements exceeds half an element: the contact pairs are fixed "
                    "in the reference configuration (small sliding), so the master's displacement is taken up to "
                    f"{ratio:.2g} elements away from the point facing each slave node", RuntimeWarning, stacklevel=3)

    def _k(self, in_cycle: bool) -> float:
        if self.wear is None:
            return 0.0
        return self.wear.k_total * (self.wear.acceleration if in_cycle else 1.0)

    def advance(self, state: ContactState, normal=None, tangential=None, loads=None, *, in_cycle: bool = False,
                max_cutbacks: int | None = None,
                check: Callable[[ContactState], None] | None = None) -> tuple[ContactState, dict[str, Any]]:
        """Solve and commit one increment, halving it on failure (elastic–plastic bodies).

        A failed try is halved up to ``max_cutbacks`` times (default: ``Plasticity.max_cutbacks``, 0 for
        elastic bodies); each converged sub-increment is committed (wear and plastic history) and the last
        one's record carries the energy and wear added by the earlier ones. Sub-steps interpolate the
        prescribed values (displacements, forces, load factors) between ``state.targets`` and the new ones.

        Args:
            state, normal, tangential, loads, in_cycle: As :meth:`solve`.
            max_cutbacks: Halvings allowed.
            check: Called with every committed (sub-)increment's state; an exception it raises aborts the
                increment (the caller keeps ``state``).

        Returns:
            (the new state, the increment's solver columns :data:`SOLVER_COLUMNS`).

        Raises:
            ConvergenceError: no convergence after the cut-backs (``state`` itself is unchanged).
        """
        if max_cutbacks is None:
            max_cutbacks = self.plasticity.max_cutbacks if self.plasticity is not None else 0
        end_targets, end_controlled = self._targets(state, normal, tangential)
        end_factors = self._factors(state, loads)
        start_targets = (state.targets if state.targets is not None else state.obstacle).astype(float)
        start_factors = state.load_factors.copy()
        names = [n for n in self.load_names if n != "dirichlet values"]
        done, size = 0.0, 1.0
        cuts = newton = local_its = 0
        sums = np.zeros(2)
        current = state
        while True:
            f = min(1.0, done + size)
            if f == 1.0:
                targets, factors = end_targets, end_factors
            else:
                targets = start_targets + f * (end_targets - start_targets)
                factors = start_factors + f * (end_factors - start_factors)
            sub_normal = (Force if end_controlled[0] else Displacement)(targets[0])
            sub_tangential = _tangential_item(targets[1:], end_controlled[1:])
            sub_loads = {n: factors[self.load_names.index(n)] for n in names}
            try:
                result = self.solve(current, sub_normal, sub_tangential, sub_loads, in_cycle=in_cycle)
            except ConvergenceError as exc:
                if cuts >= max_cutbacks:
                    raise ConvergenceError(
                        (f"no convergence after {cuts} cut-backs (last try: {done:.4g} -> {f:.4g} of the "
                         "increment): " if max_cutbacks else "") + str(exc)) from None
                cuts += 1
                size *= 0.5
                continue
            newton += result.newton["newton_iterations"] if result.newton is not None else 1
            local_its += result.iterations
            done = f
            committed = self.commit(current, result)
            if check is not None:
                check(committed)
            if done < 1.0:
                current = committed
                sums += (current.record["dissipated_energy"], current.record["wear_area_increment"])
                continue
            info = _solver_columns(result, newton_iterations=newton, local_iterations=local_its, cutbacks=cuts)
            record = {**committed.record, **info}
            record["dissipated_energy"] += sums[0]
            record["wear_area_increment"] += sums[1]
            # The sub-increments count as one increment of the caller's path.
            new = replace(committed, record=record, increment=state.increment + 1,
                          local_iterations=state.local_iterations + local_its)
            return new, info

    # Cycles ------------------------------------------------------------------------------------------------
    def run_cycle(self, state: ContactState, path: CyclePath, keep: bool = False,
                  check: Callable[[ContactState], None] | None = None) -> CycleResult:
        """Solve the increments of one cycle from ``state`` (nothing committed: :meth:`commit` the result).

        Elastic bodies with displacement-controlled obstacle and load factors run in the compiled loop
        (:mod:`dolfinx_fretting.cycling`, the path the scenes use; the local method must be Uzawa); forces,
        other local methods or plasticity run increment by increment. Either way a failure raises before
        anything is committed.

        Args:
            state: The committed state.
            path: The targets of the cycle's increments.
            keep: Also return every increment's forces, slip, positions, wear gap and status.
            check: Increment by increment only: called with each committed increment's state (see
                :meth:`advance`); the compiled loop's increments are checked by the caller on the records.

        Raises:
            ConvergenceError: an increment failed (its cycle step in the message).
        """
        n = path.increments
        dim = self.dim
        # Components the path does not give keep the state's prescribed values (displacements or forces).
        held = state.targets if state.targets is not None else state.obstacle
        obstacle = np.tile(held.astype(float), (n, 1))
        forced = (state.force_controlled.copy() if state.force_controlled is not None
                  else np.zeros(dim, dtype=bool))
        for item, comps in ((path.normal, [0]), (path.tangential, list(range(1, dim)))):
            if item is None:
                continue
            if isinstance(item, tuple):  # one item per component
                if len(item) != len(comps) or not all(isinstance(i, (Displacement, Force)) for i in item):
                    raise ValueError(f"CyclePath: expected {len(comps)} Displacement or Force items per component")
                parts = [(np.asarray(i.value, dtype=float), isinstance(i, Force)) for i in item]
                if any(v.shape != (n,) or not np.all(np.isfinite(v)) for v, _ in parts):
                    raise ValueError(f"CyclePath: expected {n} finite values per component")
                for c, (v, f) in zip(comps, parts):
                    obstacle[:, c] = v
                    forced[c] = f
                continue
            values = np.asarray(item.value, dtype=float).reshape(n, -1)
            if values.shape[1] == 1 and len(comps) > 1:
                values = np.column_stack([values, np.zeros((n, len(comps) - 1))])
            if values.shape[1] != len(comps) or not np.all(np.isfinite(values)):
                raise ValueError(f"CyclePath: expected finite values with {len(comps)} component(s) per increment")
            obstacle[:, comps] = values
            forced[comps] = isinstance(item, Force)
        factors = np.tile(state.load_factors, (n, 1))
        for name, values in path.loads.items():
            if name not in self.load_names or name == "dirichlet values":
                raise KeyError(f"unknown load {name!r}; this problem's loads: {', '.join(self.load_names) or 'none'}")
            values = np.asarray(values, dtype=float)
            if values.shape != (n,) or not np.all(np.isfinite(values)):
                raise ValueError(f"CyclePath.loads[{name!r}]: expected {n} finite factors")
            factors[:, self.load_names.index(name)] = values
        self._activate(state)
        self._check_held(obstacle, forced)
        # Finite sliding pairs anew between increments: increment by increment.
        compiled = (self.solver.compiled_cycles and self.solver.method == "uzawa" and self.body is None
                    and not forced.any() and self.surface_compliance is None)
        if compiled:
            return self._compiled_cycle(state, obstacle, factors, keep)
        return self._stepwise_cycle(state, obstacle, forced, factors, keep, check)

    def _stepwise_cycle(self, state, obstacle, forced, factors, keep, check) -> CycleResult:
        n = obstacle.shape[0]
        rows, kept, pairings = [], [], []
        current = state
        names = [nm for nm in self.load_names if nm != "dirichlet values"]
        obstacle = obstacle.copy()
        for j in range(n):
            normal = (Force if forced[0] else Displacement)(obstacle[j, 0])
            tangential = _tangential_item(obstacle[j, 1:], forced[1:])
            loads = {nm: factors[j, self.load_names.index(nm)] for nm in names}
            try:
                current, info = self.advance(current, normal, tangential, loads, in_cycle=True, check=check)
            except ConvergenceError as exc:
                raise ConvergenceError(str(exc), step=j + 1) from None
            rows.append(current.record)
            obstacle[j] = current.obstacle
            if keep:
                kept.append((current.forces, current.slip, current.positions, current.wear_gap, current.status))
                pairings.append(current.pairing)
        records = {k: np.array([r[k] for r in rows]) for k in INCREMENT_COLUMNS}
        records["full_newton_fallbacks"] = np.array([r["full_newton_fallbacks"] for r in rows])
        kept_arrays = tuple(np.array([k[i] for k in kept]) for i in range(5)) if keep else None
        return CycleResult(records, obstacle, factors, current, kept_arrays, False,
                           tuple(pairings) if keep and current.pairing is not None else None)

    def _kernel_data(self, n: int):
        """W transposed, the Uzawa steps and the contact-pattern cache of cycles of ``n`` increments (rank 0)."""
        from .cycling import ActivePatternCache

        if self._kernel is None or self._kernel[2].pattern.shape[0] not in (n, 1):
            cs = self.contact.contact_set
            self._kernel = (np.ascontiguousarray(self.W.T), local_solvers.block_rho(self.W, cs.dim),
                            ActivePatternCache(n, cs.nc, cs.dim))
        return self._kernel

    @property
    def pattern_counts(self) -> np.ndarray | None:
        """Counts of the compiled cycles' exact pattern solves accepted and rejected, and of their LU
        factorisations (rank 0)."""
        return None if self._kernel is None else self._kernel[2].counts

    def _compiled_cycle(self, state: ContactState, obstacle: np.ndarray, factors: np.ndarray,
                        keep: bool) -> CycleResult:
        from .cycling import N_ROW, run_increments

        cs = self.contact.contact_set
        frame = self.contact.frame
        n, m, dim = obstacle.shape[0], cs.nc * cs.dim, cs.dim
        sv = self.solver
        D = obstacle[:, :1] * frame[0]
        for k in range(1, dim):
            D = D + obstacle[:, k:k + 1] * frame[k]
        D = np.ascontiguousarray(D)
        warm_new = None

        def work():  # rank 0: the compiled loop; its result is broadcast, the warm start stays on rank 0
            nonlocal warm_new
            Wc, rho, cache = self._kernel_data(n)
            active = cache.enabled and sv.pattern_reuse
            warm = 1 if state.warm is not None and state.warm.shape == (n, m) and sv.warm_start == "cycle" else 0
            r_warm = state.warm.copy() if warm else np.zeros((n, m))
            gw, y, r_last = state.wear_gap.copy(), state.positions.copy(), state.forces.copy()
            # Every increment is stored (cheap): the last one's slip and status belong to the final state.
            out_r, out_x, out_y = np.zeros((n, m)), np.zeros((n, m)), np.zeros((n, m))
            out_gw, out_states = np.zeros((n, cs.nc)), np.zeros((n, cs.nc), dtype=np.int8)
            hist = np.zeros((n, N_ROW))
            G = np.ascontiguousarray(cs.rigid_modes)
            Q = np.ascontiguousarray(self.responses)
            S = np.ascontiguousarray(factors)
            done, status, err = run_increments(
                Wc, rho, self.contact.mu, dim, cs.gap0, gw, G, D, Q, S, cs.tributary, cs.abscissa, y, r_last,
                r_warm, warm, self._k(True), sv.tol, sv.max_iter, local_solvers._REFRESH, True, out_r, out_x,
                out_y, out_gw, out_states, hist, active, cache.pattern, cache.lu, cache.piv, cache.lu_ok,
                cache.counts)
            if done < n:
                why = "non-finite values" if status == 2 else "max_iter reached"
                raise ConvergenceError(f"local solver did not converge ({why}, error {err:.3e} >= tol {sv.tol:.1e} "
                                       f"after {sv.max_iter} sweeps)", step=done + 1)
            warm_new = r_warm  # the cycle's forces: the next cycle's warm start
            outs = (out_r, out_x, out_y, out_gw, out_states) if keep else (out_x[-1:], out_states[-1:])
            return hist, gw, y, r_last, outs

        result = self._on_rank0(work)
        hist, gw, y, r_last, outs = result
        nf = len(ROW_FIELDS)
        records = {name: hist[:, i] for i, name in enumerate(ROW_FIELDS)}
        records.update(local_iterations=hist[:, nf].astype(int), local_error=hist[:, nf + 1],
                       load_solves=np.ones(n, dtype=int), newton_iterations=np.ones(n, dtype=int),
                       newton_delta_1=np.zeros(n), newton_delta_2=np.zeros(n), cutbacks=np.zeros(n, dtype=int),
                       yielded_points=np.zeros(n, dtype=int))
        slip, status = (outs[1][-1].copy(), outs[4][-1].copy()) if keep else (outs[0][-1].copy(), outs[1][-1].copy())
        final = replace(state, forces=r_last, positions=y, slip=slip, wear_gap=gw, obstacle=obstacle[-1].copy(),
                        targets=obstacle[-1].copy(), force_controlled=np.zeros(dim, dtype=bool),
                        load_factors=factors[-1].copy(), increment=state.increment + n,
                        dissipated_energy=state.dissipated_energy + float(hist[:, ROW["dissipated_energy"]].sum()),
                        local_iterations=state.local_iterations + int(hist[:, nf].sum()),
                        record={k: records[k][-1].item() for k in INCREMENT_COLUMNS},
                        status=status, warm=warm_new if self.comm.rank == 0 else None)
        return CycleResult(records, obstacle, factors, final, outs if keep else None, True)

    # Window ---------------------------------------------------------------------------------------------------
    def set_window(self, state: ContactState, window: float | None) -> ContactState:
        """Rebuild the contact set, W and the load responses for another candidate window (elastic bodies) and
        carry ``state`` over: forces and wear by node; new candidates start open and unworn; the relative
        positions are recomputed (y = W r + q_abs exactly). All or nothing. Collective."""
        if self.body is not None:
            raise ValueError("the candidate window of an elastic-plastic problem cannot change")
        if self.surface_compliance is not None:
            raise ValueError("the candidate window of a finite-sliding problem cannot change (its surface compliance "
                             "is built for the contact's window): give Contact a window wide enough for the run")
        old_contact, old_W, old_resp = self.contact, self.W, self.responses
        try:
            self.contact = old_contact.with_window(window)
            self._build_contact_operators()
        except Exception:
            self.contact, self.W, self.responses = old_contact, old_W, old_resp
            self._kernel = None
            raise
        old, new = old_contact.contact_set, self.contact.contact_set
        where_old = {int(g): i for i, g in enumerate(old.global_nodes)}
        src = np.array([where_old.get(int(g), -1) for g in new.global_nodes])
        had = src >= 0
        dim = new.dim

        def carry(values: np.ndarray | None, per_contact: int) -> np.ndarray | None:
            if values is None:
                return None
            lead = values.shape[:-1]
            out = np.zeros(lead + (new.nc, per_contact))
            out[..., had, :] = values.reshape(lead + (old.nc, per_contact))[..., src[had], :]
            return out.reshape(lead + (new.nc * per_contact,))

        gw = carry(state.wear_gap, 1)
        r = carry(state.forces, dim)
        _, q_abs = self._q(state.obstacle, state.load_factors, np.zeros(new.nc * dim), gw)
        status = None if state.status is None else carry(state.status.astype(float), 1).astype(np.int8)
        return replace(state, forces=r, wear_gap=gw, positions=self.W @ r + q_abs, slip=carry(state.slip, dim),
                       warm=carry(state.warm, dim), status=status)

    # Output -----------------------------------------------------------------------------------------------
    def displacement(self, state: ContactState, out=None):
        """The displacement of ``state`` as a ``fem.Function`` (``out`` if given). Collective.

        Elastic: solves K u = H^T r + sum_l s_l f_l with the one factorisation; with an
        :class:`~dolfinx_fretting.contact.ElasticBody` obstacle that has ``cells``, its nodes also move by
        the obstacle's translation D. Elastic–plastic: the committed displacement of the state.
        """
        from . import _dolfinx as dfx
        from ._dolfinx import fem
        from petsc4py import PETSc

        u = out if out is not None else fem.Function(self.V, name="displacement")
        self._activate(state)
        if self.body is not None:
            u.x.array[:] = state.plastic.u
            u.x.scatter_forward()
            return self._add_obstacle_motion(u, state)
        rhs = self.K.createVecRight()
        rstart, rend = rhs.getOwnershipRange()
        R = self.contact.H_free.T.tocsr() @ state.forces
        rhs.setValues(np.arange(rstart, rend, dtype=PETSc.IntType), R[rstart:rend])
        rhs.assemble()
        dfx.set_bc(rhs, self.all_bcs, scale=0.0)
        for i, f in enumerate(self._vectors):
            if state.load_factors[i] != 0.0:
                rhs.axpy(state.load_factors[i], f)
        self.delassus.solve(rhs, dfx.petsc_vec(u))
        rhs.destroy()
        u.x.scatter_forward()
        return self._add_obstacle_motion(u, state)

    def _add_obstacle_motion(self, u, state: ContactState):
        obstacle = self.contact.obstacle
        if not isinstance(obstacle, ElasticBody) or obstacle.cells is None:
            return u
        from ._dolfinx import cell_dofmap

        D = self.obstacle_translation(state.obstacle)
        # The cells' nodes from the dofmap (DOLFINx 0.11 wants a cell-to-cell connectivity for
        # locate_dofs_topological on cells of a 3D mesh).
        nodes = np.unique(cell_dofmap(self.V)[np.asarray(obstacle.cells, dtype=np.int32)])
        values = u.x.array.reshape(-1, self.V.dofmap.index_map_bs)
        values[nodes, :D.size] += D
        return u

    def contact_fields(self, state: ContactState) -> dict[str, np.ndarray]:
        """Per contact node (replicated): ``coordinates``, ``global_node``, ``pressure`` and ``shear``
        (force / tributary measure; shear has dim-1 components), ``gap``, ``slip`` (last increment's slip
        increments), ``relative_tangential`` (accumulated), ``wear`` and ``status`` (0 open, 1 stick, 2 slip)."""
        cs = self.contact_set_of(state)
        dim = cs.dim
        r = state.forces.reshape(cs.nc, dim)
        y = state.positions.reshape(cs.nc, dim)
        x = state.slip.reshape(cs.nc, dim)
        status = state.status if state.status is not None else np.zeros(cs.nc, dtype=np.int8)
        return {"coordinates": cs.coords.copy(), "global_node": cs.global_nodes.copy(),
                "pressure": r[:, 0] / cs.tributary, "shear": r[:, 1:] / cs.tributary[:, None],
                "gap": y[:, 0].copy(), "slip": x[:, 1:].copy(), "relative_tangential": y[:, 1:].copy(),
                "wear": state.wear_gap.copy(), "status": status.copy()}

    def body_wear(self, state: ContactState) -> dict[str, np.ndarray]:
        """Two bodies: each body's worn depth. ``slave`` per contact node; ``master`` and
        ``master_coordinates`` (reference) at the master's points: with finite sliding the master's nodes
        (:attr:`surface_compliance`), with small sliding each contact's paired point (the pairing is fixed, so
        the master's share is carried per contact). Reads ``state`` only (the problem's pairing is not changed)."""
        cs = self.contact_set_of(state)
        if not cs.two_body:
            raise ValueError("body_wear: the obstacle is rigid (the wear gap is the body's: contact_fields)")
        if self.surface_compliance is None:
            share = self.wear.slave_share if self.wear is not None else 1.0
            return {"slave": share * state.wear_gap, "master": (1 - share) * state.wear_gap,
                    "master_coordinates": cs.master_points.copy()}
        on_master = self.surface_compliance.master_areas > 0
        surface = cs.master_surface
        flat_nodes, first = np.unique(surface.nodes.ravel(), return_index=True)
        x = surface.x.reshape(-1, surface.dim)[first[np.searchsorted(flat_nodes, self.surface_compliance.nodes[on_master])]]
        return {"slave": state.wear_gap - sliding.interpolate_master(cs, self.surface_compliance, state.master_wear),
                "master": state.master_wear[on_master].copy(), "master_coordinates": x}

    def worn_measure(self, state: ContactState) -> float:
        """The worn area (2D, mm^2 per mm) or volume (3D) of ``state``: the wear gap times the tributary measures;
        with finite sliding the slave's part per contact plus the master's on its own nodes (the master's wear
        left behind by the slide is under no contact)."""
        cs = self.contact_set_of(state)
        if self.surface_compliance is None:
            return float(state.wear_gap @ cs.tributary)
        slave = state.wear_gap - sliding.interpolate_master(cs, self.surface_compliance, state.master_wear)
        return float(slave @ cs.tributary + state.master_wear @ self.surface_compliance.master_areas)

    def total_force(self, state: ContactState) -> np.ndarray:
        """Total contact force on the body in the obstacle frame (n, t1[, t2])."""
        cs = self.contact_set_of(state)
        F = cs.total_force(state.forces)
        return np.array([F @ self.contact.frame[k] for k in range(self.dim)])

    # Checkpoints --------------------------------------------------------------------------------------------
    _ARRAYS = ("forces", "positions", "slip", "wear_gap", "obstacle", "load_factors")

    def save_state(self, state: ContactState, path: str | Path, meta: Mapping[str, Any] | None = None) -> None:
        """Write ``state`` (and JSON-able ``meta``) to an ``.npz`` file atomically (rank 0 writes). Collective."""
        from .io import _jsonable

        plastic = None
        if state.plastic is not None:
            p = state.plastic
            plastic = self.comm.gather((p.u, p.sigma, p.eps_p, p.p), root=0)

        def write() -> None:  # rank 0; a failure (disk full, a folder gone) is raised on every rank
            target = Path(path)
            arrays = {k: getattr(state, k) for k in self._ARRAYS}
            arrays["status"] = state.status if state.status is not None else np.zeros(0, np.int8)
            arrays["warm"] = state.warm if state.warm is not None else np.zeros(0)
            arrays["targets"] = state.targets if state.targets is not None else state.obstacle
            arrays["force_controlled"] = (state.force_controlled if state.force_controlled is not None
                                          else np.zeros(self.dim, dtype=bool))
            if state.pairing is not None:  # finite sliding: the pairing and the master's wear
                arrays["pairing_faces"] = state.pairing.master_faces
                arrays["pairing_nodes"] = state.pairing.master_nodes
                arrays["pairing_weights"] = state.pairing.master_weights
                arrays["master_wear"] = state.master_wear
                arrays["repairs"] = np.array(self._repairs)
            for i, parts in enumerate(plastic or []):
                for name, a in zip(("u", "sigma", "eps_p", "p"), parts):
                    arrays[f"plastic_{name}_{i}"] = a
            info = {"increment": state.increment, "dissipated_energy": state.dissipated_energy,
                    "local_iterations": state.local_iterations, "record": state.record, "ranks": self.comm.size,
                    "load_names": self.load_names, "global_nodes": self.contact.contact_set.global_nodes.tolist(),
                    "plastic": plastic is not None, "meta": dict(meta or {})}
            tmp = target.with_name(target.name + ".tmp.npz")
            np.savez(tmp, state=json.dumps(info, default=_jsonable), **arrays)
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
            os.replace(tmp, target)
        self._on_rank0(write)

    def load_state(self, path: str | Path) -> tuple[ContactState, dict[str, Any]]:
        """Read a state written by :meth:`save_state` (same problem, same contact set). Collective.

        Raises:
            ValueError: the file does not match this problem (contact nodes, loads, ranks of a plastic state).
        """
        def read() -> dict[str, np.ndarray]:
            with np.load(path, allow_pickle=False) as npz:
                return {k: npz[k] for k in npz.files}

        data = self._on_rank0(read)
        info = json.loads(str(data["state"]))
        if info["global_nodes"] != self.contact.contact_set.global_nodes.tolist():
            raise ValueError(f"{path}: the saved contact set differs from this problem's")
        if info["load_names"] != self.load_names:
            raise ValueError(f"{path}: saved loads {info['load_names']} differ from this problem's {self.load_names}")
        plastic = None
        if info["plastic"]:
            if info["ranks"] != self.comm.size:
                raise ValueError(f"{path}: an elastic-plastic state saved on {info['ranks']} rank(s) loads on the same "
                                 f"number (here {self.comm.size})")
            i = self.comm.rank
            plastic = PlasticHistory(*(data[f"plastic_{k}_{i}"].copy() for k in ("u", "sigma", "eps_p", "p")))
        warm = data["warm"] if data["warm"].size and self.comm.rank == 0 else None
        pairing = master_wear = None
        if ("pairing_faces" in data) != (self.surface_compliance is not None):
            raise ValueError(f"{path}: a state saved with{'' if 'pairing_faces' in data else 'out'} finite sliding "
                             f"loads into a problem with{'' if self.surface_compliance is not None else 'out'} it")
        if self.surface_compliance is not None:
            from .contact import paired_contact_set

            ref = self._reference_pairing
            pairing = paired_contact_set(ref.master_surface, ref.global_nodes, ref.coords, ref.tributary,
                                         ref.abscissa, data["pairing_faces"], data["pairing_weights"], ref.H.shape[1])
            master_wear = data["master_wear"].copy()
            if (not np.array_equal(pairing.master_nodes, data["pairing_nodes"])
                    or master_wear.shape != (self.surface_compliance.nodes.size,)):
                raise ValueError(f"{path}: the saved pairing or master wear does not fit this problem's master surface")
            self.surface_compliance.rows(pairing.master_nodes)   # within reach, or a message
            self._repairs = int(data["repairs"])
        state = ContactState(*(data[k].copy() for k in self._ARRAYS), increment=int(info["increment"]),
                             dissipated_energy=float(info["dissipated_energy"]),
                             local_iterations=int(info["local_iterations"]), record=info["record"],
                             status=data["status"].copy() if data["status"].size else None, warm=warm,
                             targets=data["targets"].copy(), force_controlled=data["force_controlled"].copy(),
                             plastic=plastic, pairing=pairing, master_wear=master_wear)
        return state, info["meta"]

    def destroy(self) -> None:
        """Free the PETSc objects (factorisation, K if assembled here, load vectors)."""
        if self.body is not None:
            self.body.destroy()
        self.delassus.destroy()
        for f in self._vectors:
            f.destroy()
        if self._own_K:
            self.K.destroy()


def _tangential_item(values: np.ndarray, forced: np.ndarray):
    """The ``tangential`` argument of :meth:`FrettingProblem.solve` for these values and controls: one
    Displacement or Force of all components, or one item per component when the controls differ."""
    if forced.all() or not forced.any():
        return (Force if forced.all() else Displacement)(values)
    return tuple((Force if f else Displacement)(float(v)) for v, f in zip(values, forced))


def _zero_linear_form(V):
    import ufl
    from ._dolfinx import fem
    from petsc4py import PETSc

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
