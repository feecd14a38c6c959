"""The explicit state of a fretting run and the results that advance it.

:class:`ContactState` is everything a run needs to go on after a committed increment (immutable; a checkpoint
holds it); :class:`IncrementResult` and :class:`CycleResult` are converged, not yet committed
(:meth:`~dolfinx_fretting.problem.FrettingProblem.commit`: rollback is simply not committing). The per-increment
columns are declared once here (:data:`INCREMENT_COLUMNS`).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from .contact import ContactSet
from .wear import ROW_FIELDS

__all__ = ["ConvergenceError", "WindowError", "STATUS_NAMES", "SOLVER_COLUMNS", "INCREMENT_COLUMNS", "PlasticHistory",
           "ContactState", "IncrementResult", "CycleResult", "solver_columns", "STATE_TOKEN_FIELDS"]

#: Contact status codes of :attr:`ContactState.status` (the wear module's classification).
STATUS_NAMES = {0: "open", 1: "stick", 2: "slip"}
#: Per-increment columns of a cycle's records (:attr:`CycleResult.records`) and of the info of
#: :meth:`~dolfinx_fretting.problem.FrettingProblem.advance`: the totals of :data:`~dolfinx_fretting.wear.ROW_FIELDS`,
#: then the solver's
#: counters (one declaration: the scene runner's history table reads its columns from here).
SOLVER_COLUMNS = ("local_iterations", "local_error", "load_solves", "newton_iterations", "newton_delta_1",
                  "newton_delta_2", "cutbacks", "yielded_points")
#: Per-increment columns: the :data:`~dolfinx_fretting.wear.ROW_FIELDS`, then the :data:`SOLVER_COLUMNS`.
INCREMENT_COLUMNS = ROW_FIELDS + SOLVER_COLUMNS
#: The fields of a :class:`ContactState` its :attr:`~ContactState.token` is a digest of: the contact data every rank
#: holds alike (not ``warm``, rank 0's only, nor ``plastic``, each rank's own) and the counters, so a commit
#: (which adds at least one increment) always changes it.
STATE_TOKEN_FIELDS = ("forces", "positions", "slip", "wear_gap", "obstacle", "load_factors", "targets",
                      "force_controlled", "master_wear", "increment", "dissipated_energy", "local_iterations",
                      "cycles", "friction_energy")


class ConvergenceError(RuntimeError):
    """An increment or cycle could not be solved; nothing of it was committed. The message says why.

    Attributes:
        step: In a cycle, the 1-based increment of the cycle that failed (None otherwise).
    """

    def __init__(self, message: str, step: int | None = None):
        super().__init__(message)
        self.step = step


class WindowError(ConvergenceError):
    """Nodes of the contact surface outside the candidate window (:class:`~dolfinx_fretting.contact.Contact`'s
    ``window``) penetrate the obstacle: the increment's answer is truncated, and nothing of it was committed.

    A :class:`ConvergenceError`: like a failed solve, the increment (or cycle) was not accepted and the caller's
    state is unchanged, so code that already stops on a failed increment stops here too; it is caught first by
    what can act on it (a wider window: :meth:`~dolfinx_fretting.problem.FrettingProblem.set_window`, what
    ``Contact(..., grow_window=True)`` and the scene runner do). It is not a ValueError: the window is valid input,
    only the load reached past it. The message names ``window``, the penetrating nodes and the window needed.

    Attributes:
        step: In a cycle, the 1-based increment of the cycle where the first penetration was found.
        window: The candidate half-width in use.
        window_needed: A half-width that holds every penetrating node (the in-plane distance from the window's
            centre to the farthest one, plus a margin).
        positions: (k, dim) reference coordinates of the penetrating nodes (all of them).
        penetration: The largest penetration (length units, > 0).
        zone: The index of the contact zone whose window is too narrow (0 with one
            :class:`~dolfinx_fretting.contact.Contact`; with several, their order in the problem's list).
    """

    def __init__(self, message: str, step: int | None = None, *, window: float | None = None,
                 window_needed: float = 0.0, positions: np.ndarray | None = None, penetration: float = 0.0,
                 zone: int = 0):
        super().__init__(message, step=step)
        self.zone = int(zone)
        self.window = window
        self.window_needed = float(window_needed)
        self.positions = np.zeros((0, 0)) if positions is None else np.asarray(positions, dtype=float)
        self.penetration = float(penetration)

    @property
    def details(self) -> dict[str, Any]:
        """The attributes above as plain data (what :func:`~dolfinx_fretting.increments.on_rank0` sends)."""
        return {"window": self.window, "window_needed": self.window_needed, "positions": self.positions,
                "penetration": self.penetration, "zone": self.zone}



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
        obstacle: Obstacle displacement in the obstacle frame (approach along n, then t1[, t2]); with several
            contact zones (:class:`~dolfinx_fretting.zones.ContactZones`) each zone's obstacle in turn, in its own
            frame (``dim`` components per zone).
        targets: The last increment's prescribed values per obstacle component (the displacement, or the force
            where it was force controlled): what a component not given to
            :meth:`~dolfinx_fretting.problem.FrettingProblem.solve` keeps,
            and where a cut increment's sub-steps start from.
        force_controlled: Which components of ``targets`` are forces.
        load_factors: Factor of each named load and Dirichlet data set
            (:attr:`~dolfinx_fretting.problem.FrettingProblem.load_names`).
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
            (:attr:`~dolfinx_fretting.operators.ContactOperators.surface_compliance`; 0 at slave nodes); the master's
            share of ``wear_gap`` is this,
            interpolated at each contact's paired point. None otherwise (the share is carried per contact).
        cycles: Load cycles committed (:meth:`~dolfinx_fretting.problem.FrettingProblem.run_cycle` results), each
            counting the wear law's acceleration (the physical cycles it stands for), a cycle jump's cycles added
            by the runner: what an :class:`~dolfinx_fretting.laws.EvolvingFriction` with ``variable="cycles"``
            reads.
        friction_energy: Each contact's accumulated dissipated frictional energy per unit area (acceleration
            counted in cycles) when a zone's friction follows it (``variable="energy"``), else None.
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
    cycles: float = 0.0
    friction_energy: np.ndarray | None = None

    @property
    def token(self) -> str:
        """A digest of this state's contents (:data:`STATE_TOKEN_FIELDS` and the pairing): what a result records
        of the state it was solved from (:attr:`IncrementResult.solved_from`), so that
        :meth:`~dolfinx_fretting.problem.FrettingProblem.commit` refuses it on any other state. Two states hold the
        same token when they hold the same contact data (a state and its checkpoint read back); every commit
        changes it (the increment counter). Recomputed on each call (a state's arrays could be changed in place);
        the same on every rank."""
        digest = hashlib.blake2b(digest_size=16)
        for name in STATE_TOKEN_FIELDS:
            value = getattr(self, name)
            if value is None:
                digest.update(f"{name}:None;".encode())
                continue
            array = np.ascontiguousarray(value)
            digest.update(f"{name}:{array.dtype.str}{array.shape};".encode())
            digest.update(array.tobytes())
        if self.pairing is not None:   # finite sliding: the pairing the per-contact arrays refer to
            for array in (self.pairing.master_faces, self.pairing.master_weights):
                digest.update(np.ascontiguousarray(array).tobytes())
        return digest.hexdigest()


@dataclass(frozen=True)
class IncrementResult:
    """A converged increment, not yet committed (see :meth:`~dolfinx_fretting.problem.FrettingProblem.commit`).

    Attributes:
        solved_from: The :attr:`~ContactState.token` of the state it was solved from (set by
            :meth:`~dolfinx_fretting.problem.FrettingProblem.solve`): the one state it may be committed to, once.
    """

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
    solved_from: str | None = None


@dataclass(frozen=True)
class CycleResult:
    """A converged cycle, not yet committed.

    Attributes:
        records: Per-increment columns: every :data:`~dolfinx_fretting.wear.ROW_FIELDS` entry, plus
            ``local_iterations``, ``local_error`` and ``local_solves`` (arrays of length n).
        obstacle: (n, dim) obstacle displacement of each increment (obstacle frame).
        load_factors: (n, L) load factors of each increment.
        final: The state the cycle ends in (committed by :meth:`~dolfinx_fretting.problem.FrettingProblem.commit`).
        kept: With ``keep=True``: per increment (forces, slip, positions, wear gap, status), arrays (n, ...).
        compiled: True when the compiled loop ran it.
        kept_pairings: Finite sliding with ``keep=True``: the pairing each kept increment's arrays refer to
            (:attr:`ContactState.pairing`), else None.
        solved_from: The :attr:`~ContactState.token` of the state given to
            :meth:`~dolfinx_fretting.problem.FrettingProblem.run_cycle` (also when the window grew during the cycle):
            the one state it may be committed to, once.
    """

    records: dict[str, np.ndarray]
    obstacle: np.ndarray
    load_factors: np.ndarray
    final: ContactState
    kept: tuple[np.ndarray, ...] | None
    compiled: bool
    kept_pairings: tuple[ContactSet, ...] | None = None
    solved_from: str | None = None


def solver_columns(result: IncrementResult, newton_iterations: int | None = None,
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
