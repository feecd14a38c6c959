"""The watch over the contact surface outside a candidate window: no node there may penetrate the obstacle
unnoticed (:class:`~dolfinx_fretting.contact.Contact`'s ``window``).

The operators (:class:`~dolfinx_fretting.operators.ContactOperators`) form :class:`OutsideRows` from their factor;
every increment's answer is checked by :func:`check_window`, a product with C and no solve. Pure NumPy: no mesh.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .contact import ContactSet
from .state import WindowError

__all__ = ["OutsideRows", "check_window"]


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
