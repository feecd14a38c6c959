"""The watch over the contact surface outside a candidate window: no node there may penetrate the obstacle
unnoticed (:class:`~dolfinx_fretting.contact.Contact`'s ``window``); and a state carried into a new window.

:func:`watch_outside` forms :class:`OutsideRows` from the operators' factor
(:class:`~dolfinx_fretting.operators.ContactOperators`); every increment's answer is checked by
:func:`check_window`, a product with C and no solve; :func:`carry_state` carries a state's per-contact arrays
into the contact set of another window. No DOLFINx here: the operators' factor and communicator do the work.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI

from .contact import ContactSet
from .state import ContactState, WindowError

__all__ = ["OutsideRows", "check_window", "watch_outside", "outside_on_surfaces", "outside_gaps_of", "carry_state"]


@dataclass(frozen=True)
class OutsideRows:
    """The nodes of the contact surface outside the candidate window, watched for penetration.

    Their normal gap is affine in what an increment solves for, with the contacts' own ingredients (paper
    eq. 28's q, one row per node)::

        g_out = g0_out + C r - M d + sum_l s_l (H_out K^-1 f_l),     C = H_out K^-1 H^T  (free dofs),

    r the contact forces, d the obstacle's components (M: each node's normal displacement per unit component, its
    zone's obstacle only), s_l the load factors; H_out holds the nodes' normal rows (against an
    :class:`~dolfinx_fretting.contact.ElasticBody`: the node minus its paired master point, as
    :func:`~dolfinx_fretting.contact.find_pairs` pairs the candidates). The wear gap is zero there (a node outside
    the window has never been a contact). So checking an increment is a product with C (a cycle's: one matrix
    product over its increments), no solve.

    Attributes:
        nodes: The outside nodes (a :class:`~dolfinx_fretting.contact.ContactSet`: coordinates, frames, gaps, H).
        coupling: C, shape (k, m) (k nodes, m = dim x contacts).
        responses: (L, k) each load's normal displacement at the nodes (prescribed values count).
        motion: M, (k, obstacle components).
        distance: (k,) in-plane distance from the window's centre (what the window's half-width measures).
        compliance: The largest contact compliance ``max_a ||W_aa||_2`` (the tolerance's length scale).
        zone: (k,) each node's contact zone (0 with one :class:`~dolfinx_fretting.contact.Contact`).
        windows: Each zone's window; centres: each zone's window centre (None for a zone without outside nodes).
    """

    nodes: ContactSet
    coupling: np.ndarray
    responses: np.ndarray
    motion: np.ndarray
    distance: np.ndarray
    compliance: float
    zone: np.ndarray
    windows: tuple
    centres: tuple

    def gaps(self, forces: np.ndarray, obstacle: np.ndarray, factors: np.ndarray) -> np.ndarray:
        """Normal gaps (n, k) of n increments: ``forces`` (n, m), ``obstacle`` (n, components), ``factors``
        (n, L)."""
        g = np.atleast_2d(forces) @ self.coupling.T - np.atleast_2d(obstacle) @ self.motion.T
        if self.responses.shape[0]:
            g += np.atleast_2d(factors) @ self.responses
        return g + self.nodes.gap0

    def tolerance(self, forces: np.ndarray, local_tol: float, terms: np.ndarray) -> np.ndarray:
        """How far below zero a gap of each increment (rows of ``forces``) may be and not count as penetration.

        The local solver accepts a solution whose natural-map error
        (:func:`~dolfinx_fretting.local_solvers.natural_map_error`) is below ``local_tol``: a force residual of
        ``local_tol ||r||``, which at an open contact leaves a
        penetration up to ``local_tol ||r||_2 / rho_a = local_tol ||r||_2 ||W_aa||_2``. An outside node is held
        to that same bound with the largest contact compliance (it would have been accepted as a candidate), plus
        the rounding of the sum that forms its gap: 1e-12 of the largest term (``terms``, per increment), far above
        the few ulps of a handful of additions and far below any penetration that matters."""
        forces = np.atleast_2d(forces)
        return local_tol * np.linalg.norm(forces, axis=1) * self.compliance + 1e-12 * terms

    def check(self, gaps: np.ndarray, tolerance: np.ndarray, cycle: bool = False) -> None:
        """Raise :class:`~dolfinx_fretting.state.WindowError` if a gap (rows: increments) is below minus its
        row's tolerance; in a cycle (``cycle``) the error's step is the first such increment. With several zones
        the error is the zone of the deepest penetration's (its window is the one to widen first)."""
        bad = gaps < -np.asarray(tolerance)[:, None]
        if not bad.any():
            return
        depth_all = -np.where(bad, gaps, np.inf).min(axis=0)
        zone = int(self.zone[np.argmax(np.where(bad.any(axis=0), depth_all, -np.inf))])
        bad = bad & (self.zone == zone)[None, :]
        rows = np.flatnonzero(bad.any(axis=1))
        nodes = np.flatnonzero(bad.any(axis=0))   # penetrating in any increment of the batch
        depth = -gaps[:, nodes].min(axis=0)
        far = self.distance[nodes].max()
        # The margin: a tenth of the farthest distance, at least two of the nodes' spacings (their tributary
        # measure), so that the solve with the window needed has open candidates at its ends, as the scene
        # runner's edge check wants, and room for the contact to settle.
        dim = self.nodes.dim
        spacing = float((self.nodes.tributary[nodes] ** (1.0 / (dim - 1))).max())
        needed = far + max(0.1 * far, 2.0 * spacing)
        order = np.argsort(-depth, kind="stable")
        shown = "; ".join(str((np.round(self.nodes.coords[nodes[i]], 6) + 0.0).tolist()) for i in order[:3])
        where = f" at increment {rows[0] + 1} of the cycle" if cycle else ""
        window = self.windows[zone]
        several = len(self.windows) > 1
        who = f"contact[{zone}]: " if several else ""
        widen = (f"problem.set_window(state, {needed:.6g}, zone={zone})" if several
                 else f"problem.set_window(state, {needed:.6g})")
        raise WindowError(
            f"{who}window = {window:.6g}: {nodes.size} node(s) of the contact surface outside the candidate window "
            f"penetrate the obstacle{where} (by up to {depth.max():.3g}; deepest at {shown}"
            f"{' ...' if nodes.size > 3 else ''}): the answer would be truncated. The window needed is at least "
            f"{needed:.6g} (the farthest penetrating node lies {far:.6g} from the window's centre "
            f"{(np.round(self.centres[zone], 6) + 0.0).tolist()}, plus a margin): widen it "
            f"({widen} and solve again), or let advance and run_cycle grow it (Contact(..., grow_window=True))",
            step=int(rows[0]) + 1 if cycle else None, window=window, window_needed=needed,
            positions=self.nodes.coords[nodes[order]], penetration=float(depth.max()), zone=zone)


def check_window(outside: OutsideRows | None, forces: np.ndarray, obstacle: np.ndarray, factors: np.ndarray,
                 translations: np.ndarray, local_tol: float, cycle: bool = False,
                 displacement_gaps: np.ndarray | None = None, displacement_tol: float = 0.0) -> None:
    """Raise :class:`~dolfinx_fretting.state.WindowError` if a node outside the window penetrates the obstacle in
    an increment (rows of ``forces`` (n, m), ``obstacle`` (n, components), ``factors`` (n, L); ``translations``
    the obstacles' global translations of each row, for the rounding scale); ``cycle``: the rows are a cycle's
    increments. Elastic-plastic increments give their gaps from the displacement instead (``displacement_gaps``),
    converged by Newton to ``displacement_tol`` of itself, which adds to the tolerance. Nothing to do without
    outside nodes."""
    if outside is None:
        return
    forces, obstacle, factors = np.atleast_2d(forces), np.atleast_2d(obstacle), np.atleast_2d(factors)
    gaps = (outside.gaps(forces, obstacle, factors) if displacement_gaps is None
            else np.atleast_2d(displacement_gaps))
    moved = np.abs(gaps - outside.nodes.gap0).max(axis=1)
    # The largest term of each row's sum, for its rounding (see OutsideRows.tolerance): the gap, what moved it, the
    # translation and the loads' share.
    terms = np.maximum(moved, np.abs(outside.nodes.gap0).max())
    terms = np.maximum(terms, np.linalg.norm(np.atleast_2d(translations), axis=1))
    if outside.responses.shape[0]:
        terms = np.maximum(terms, np.abs(factors) @ np.abs(outside.responses).max(axis=1))
    tolerance = outside.tolerance(forces, local_tol, terms) + displacement_tol * moved
    outside.check(gaps, tolerance, cycle)


def _normal_rows(outside: ContactSet, fixed_global: np.ndarray) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The outside nodes' normal rows of H: (full, without the fixed dofs' columns)."""
    H = sp.csr_matrix(outside.H[0::outside.dim])
    free = np.ones(H.shape[1])
    free[fixed_global] = 0.0
    H_free = sp.csr_matrix(H @ sp.diags(free))
    H_free.eliminate_zeros()
    return H, H_free


def outside_on_surfaces(operators) -> tuple[np.ndarray, np.ndarray] | None:
    """Finite sliding: ``H_out K^-1 S^T`` on the surface compliance's dofs S and the loads' responses at the outside
    nodes, once (a pairing's coupling is then ``(H_out K^-1 S^T) L^T``, no solve: see :func:`watch_outside`); None
    without outside nodes. The outside nodes keep their reference pairing. Collective."""
    contact = operators.contact
    if contact.outside is None:
        return None
    H, H_free = _normal_rows(contact.outside, contact.fixed_global)
    dofs = operators.surface_compliance.dofs
    S = sp.csr_matrix((np.ones(dofs.size), (np.arange(dofs.size), dofs)), shape=(dofs.size, operators.n_dofs))
    free = np.ones(operators.n_dofs)
    free[contact.fixed_global] = 0.0
    S_free = sp.csr_matrix(S @ sp.diags(free))
    S_free.eliminate_zeros()
    responses = np.array([operators.local_response(f, H) for f in operators.vectors]).reshape(
        len(operators.vectors), H.shape[0])
    return operators.delassus.coupling(H_free, S_free), responses


def watch_outside(operators, responses: np.ndarray | None) -> OutsideRows | None:
    """The :class:`OutsideRows` of the contact the operators hold, or None (no window, or no node outside it).
    C is formed from entries of K^-1 (:meth:`~dolfinx_fretting.compliance.DelassusOperator.coupling`; its cost is
    measured in ``benchmarks/results/window_check.md``); under finite sliding from ``H_out K^-1 S^T`` on the
    surface compliance's dofs, made once (:func:`outside_on_surfaces`), and each pairing's columns L: no solve.
    ``responses``: the loads' normal responses at the outside nodes (finite sliding: made with the surfaces').
    Collective."""
    contact = operators.contact
    outside = contact.outside
    if outside is None:
        return None
    if operators.surface_compliance is not None:
        on_surfaces, responses = operators._surface_outside
        L = operators.surface_compliance.restrict(contact.contact_set)
        coupling = np.asarray((L @ on_surfaces.T).T)
    else:
        coupling = operators.delassus.coupling(_normal_rows(outside, contact.fixed_global)[1], contact.H_free)
    rho = operators.block_steps if contact.contact_set.nc else np.ones(1)
    centres = tuple(zone.window_centre for zone in contact.zones)
    return OutsideRows(outside, coupling, responses, contact.outside_motion(), contact.outside_distance(),
                       float(1.0 / rho.min()), contact.outside_zone, contact.windows, centres)


def outside_gaps_of(operators, u: np.ndarray, obstacle: np.ndarray) -> np.ndarray | None:
    """The outside nodes' normal gaps for this rank's displacement ``u`` (a ``fem.Function``'s array: owned then
    ghost values) and the obstacle position ``obstacle`` (obstacle frames); None without outside nodes. Collective
    (the same sum on every rank)."""
    out = operators.outside
    if out is None:
        return None
    rstart, rend = operators.K.getOwnershipRange()
    part = out.nodes.H[0::out.nodes.dim][:, rstart:rend] @ u[:rend - rstart]
    moved = operators.comm.allreduce(part, op=MPI.SUM)
    moved = operators.comm.bcast(moved if operators.comm.rank == 0 else None, root=0)
    return out.nodes.gap0 + moved - out.motion @ obstacle


def carry_state(old_contact, new_contact, state: ContactState) -> dict[str, Any]:
    """``state``'s per-contact arrays (forces, slip, wear gap, warm starts, status, the friction's accumulated
    energy) carried from ``old_contact``'s contact set into ``new_contact``'s (another window): by (zone, global
    node), a corner's node being in two zones; new candidates start open and unworn, having dissipated nothing."""
    old, new = old_contact.contact_set, new_contact.contact_set

    def keys(contact) -> list[tuple[int, int]]:
        zone_of = np.repeat(np.arange(len(contact.zones)), [contact.zone_slice(i).stop - contact.zone_slice(i).start
                                                            for i in range(len(contact.zones))])
        return list(zip(zone_of.tolist(), contact.contact_set.global_nodes.tolist()))
    where_old = {key: i for i, key in enumerate(keys(old_contact))}
    src = np.array([where_old.get(key, -1) for key in keys(new_contact)])
    had = src >= 0
    dim = new.dim

    def carry(values: np.ndarray | None, per_contact: int) -> np.ndarray | None:
        if values is None:
            return None
        lead = values.shape[:-1]
        out = np.zeros(lead + (new.nc, per_contact))
        out[..., had, :] = values.reshape(lead + (old.nc, per_contact))[..., src[had], :]
        return out.reshape(lead + (new.nc * per_contact,))

    status = None if state.status is None else carry(state.status.astype(float), 1).astype(np.int8)
    return {"forces": carry(state.forces, dim), "wear_gap": carry(state.wear_gap, 1), "slip": carry(state.slip, dim),
            "warm": carry(state.warm, dim), "status": status, "friction_energy": carry(state.friction_energy, 1)}
