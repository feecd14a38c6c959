"""The friction coefficients a state holds: where the local solvers, the compiled cycles and the commit read mu.

A constant law's coefficients are the contact's own (:attr:`~dolfinx_fretting.contact.Contact.mu`, the same array:
nothing is recomputed). An :class:`~dolfinx_fretting.laws.EvolvingFriction` zone's coefficients are a function of
the state: its law at the state's :attr:`~dolfinx_fretting.state.ContactState.cycles` (``"cycles"``) or at each
contact's :attr:`~dolfinx_fretting.state.ContactState.friction_energy` (``"energy"``). So mu is part of the state
without being stored twice: a checkpoint holds the variables, a window growth carries the energy by node (a new
candidate starts at 0, as it has dissipated nothing), and W does not change (it does not depend on mu).
"""

from __future__ import annotations

import numpy as np

from .laws import EvolvingFriction

__all__ = ["evolving_laws", "tracks_energy", "energy_tables", "coefficients", "energy_density", "accumulated_energy",
           "jump_limit"]


def evolving_laws(contact) -> list[tuple[int, EvolvingFriction]]:
    """(zone index, law) of each zone of ``contact`` (a Contact or ContactZones) whose friction evolves."""
    return [(zone, part.friction) for zone, part in enumerate(contact.zones)
            if isinstance(part.friction, EvolvingFriction)]


def tracks_energy(contact) -> bool:
    """Whether a zone's friction follows the dissipated energy (then the state carries it per contact)."""
    return any(law.variable == "energy" for _, law in evolving_laws(contact))


def energy_tables(contact) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """The energy laws' tables as the compiled loop reads them (:class:`~dolfinx_fretting.cycling.FrictionEvolution`):
    (each contact's table or -1 where mu is held over a cycle, the tables' abscissae and coefficients padded to
    the longest, each one's rows). None when a zone's law of the energy is the user's function: a Python call per
    increment, which the compiled loop cannot make (that cycle then runs one increment per call)."""
    laws = [(zone, law) for zone, law in evolving_laws(contact) if law.variable == "energy"]
    if any(law.table is None for _, law in laws):
        return None
    table_of = np.full(contact.nc, -1, dtype=np.int64)
    longest = max((law.table.shape[0] for _, law in laws), default=1)
    abscissae, values = np.zeros((max(len(laws), 1), longest)), np.zeros((max(len(laws), 1), longest))
    lengths = np.ones(max(len(laws), 1), dtype=np.int64)
    for index, (zone, law) in enumerate(laws):
        rows = contact.zone_slice(zone)
        table_of[rows] = index
        size = law.table.shape[0]
        abscissae[index, :size], values[index, :size] = law.table[:, 0], law.table[:, 1]
        lengths[index] = size
    return table_of, abscissae, values, lengths


def coefficients(contact, state) -> np.ndarray:
    """Each contact's friction coefficient for an increment solved from ``state`` (held over the increment).

    Without an evolving law: ``contact.mu`` itself. Raises ValueError (from the user's function) if it gives a
    coefficient that is not finite or below 0."""
    laws = evolving_laws(contact)
    if not laws:
        return contact.mu
    mu = np.array(contact.mu, dtype=float)
    for zone, law in laws:
        rows = contact.zone_slice(zone)
        if law.variable == "cycles":
            values = np.full(rows.stop - rows.start, float(state.cycles))
        else:
            values = (np.zeros(rows.stop - rows.start) if state.friction_energy is None
                      else state.friction_energy[rows])
        mu[rows] = law.at(values)
    return mu


def energy_density(dim: int, tributary: np.ndarray, forces: np.ndarray, slip: np.ndarray) -> np.ndarray:
    """Each contact's frictional energy dissipated in an increment per unit area, ``-r_t . dx_t / A`` (the
    terms of the increment's ``dissipated_energy``, :func:`~dolfinx_fretting.wear.commit_increment`), with A its
    tributary length (2D) or area; 0 where A is 0. ``forces`` and ``slip`` may carry leading axes (increments)."""
    r = np.asarray(forces, dtype=float)
    x = np.asarray(slip, dtype=float)
    r = r.reshape(r.shape[:-1] + (-1, dim))[..., 1:]
    x = x.reshape(x.shape[:-1] + (-1, dim))[..., 1:]
    work = -(r * x).sum(axis=-1)
    return np.divide(work, tributary, out=np.zeros_like(work), where=tributary > 0)


def accumulated_energy(contact, state, forces: np.ndarray, slip: np.ndarray, scale: float) -> np.ndarray | None:
    """``state``'s :attr:`~dolfinx_fretting.state.ContactState.friction_energy` plus an increment's
    (:func:`energy_density` times ``scale``, the wear law's acceleration in a cycle: each simulated cycle stands for
    that many), or None when no zone's friction follows the energy."""
    if not tracks_energy(contact):
        return None
    contact_set = contact.contact_set
    before = np.zeros(contact_set.nc) if state.friction_energy is None else state.friction_energy
    return before + scale * energy_density(contact_set.dim, contact_set.tributary, forces, slip)


def jump_limit(contact, start, end, acceleration: float) -> float:
    """The largest cycle jump dN (the simulated cycle from ``start`` to ``end`` and the dN - 1 cycles extrapolated
    from it) over which no zone's friction changes: the jump extrapolates the simulated cycle's wear rate, which
    holds only for that cycle's mu. ``inf`` when no law evolves (or each has reached its last value), 1 while mu
    changes at once (a sloped part of a table, or a function: its course is not known).

    A law of the cycles allows ``1 + (limit - N) / acceleration`` (N the simulated cycle's count, limit
    :meth:`~dolfinx_fretting.laws.EvolvingFriction.constant_until`); one of the energy, with each contact's energy
    per cycle e and the energy E at the simulated cycle's start, ``(limit - E) / e`` over the contacts that
    dissipate (every increment of the extrapolated cycles below the limit)."""
    bound = np.inf
    for zone, law in evolving_laws(contact):
        rows = contact.zone_slice(zone)
        if law.variable == "cycles":
            limit = float(law.constant_until(np.array([float(start.cycles)]))[0])
            bound = min(bound, 1.0 + np.floor((limit - float(start.cycles)) / acceleration))
            continue
        before, after = start.friction_energy[rows], end.friction_energy[rows]
        per_cycle = after - before
        dissipating = per_cycle > 0
        if not dissipating.any():
            continue
        limit = law.constant_until(before[dissipating])
        bound = min(bound, float(np.floor(((limit - before[dissipating]) / per_cycle[dissipating]).min())))
    return max(bound, 1.0)
