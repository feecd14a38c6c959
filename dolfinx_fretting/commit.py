"""Committing a converged increment: Archard's law, the master's share of the wear, the totals of the record,
and under finite sliding the re-pairing of the slave nodes once the bodies have slid.

:class:`SlidingMonitor` holds what a run learns about sliding as it goes (re-pairings counted, warnings given
once); everything else is in the states.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np

from . import friction, sliding
from .operators import ContactOperators
from .readers import worn_measure
from .state import ContactState, CycleResult, IncrementResult, solver_columns
from .wear import ROW, ROW_FIELDS, commit_increment

__all__ = ["SlidingMonitor", "commit", "check_solved_from", "relative_slip_ratio", "wear_coefficients", "acceleration"]


@dataclass
class SlidingMonitor:
    """What a run learns about sliding as it goes.

    Attributes:
        warn: Warn (once each, rank 0) when two bodies slide past half a master element, or finite sliding
            re-pairs after a long stride or past its reach; False when the caller reports it itself.
        repairs: Finite sliding: how many times the slave nodes were paired anew.
    """

    warn: bool = True
    repairs: int = 0
    sliding_warned: bool = False
    stride_warned: bool = False
    reach_warned: bool = False


def wear_coefficients(operators: ContactOperators, laws: tuple, in_cycle: bool,
                      mu: np.ndarray | None = None) -> np.ndarray:
    """Each contact's wear rate ``c`` of an increment (``dg = c p |dx_t|``): its zone's law's (``laws``, one per
    zone; 0 where None), given each contact's friction coefficient ``mu`` (default: the contact's own, the
    coefficients at the start of an evolving law)."""
    contacts = operators.contact
    mu = contacts.mu if mu is None else mu
    coefficients = np.zeros(contacts.nc)
    for zone, law in enumerate(laws):
        if law is not None:
            rows = contacts.zone_slice(zone)
            coefficients[rows] = law.coefficients(in_cycle, mu[rows])
    return coefficients


def acceleration(laws: tuple) -> float:
    """The physical cycles each simulated cycle stands for: the wear laws' acceleration (one value per run), 1
    without wear."""
    return next((float(law.acceleration) for law in laws if law is not None), 1.0)


def check_solved_from(state: ContactState, result: IncrementResult | CycleResult) -> None:
    """Refuse ``result`` unless it was solved from ``state`` (its
    :attr:`~dolfinx_fretting.state.IncrementResult.solved_from` is ``state``'s token): committed twice, or to another
    state, its wear and increments would be added again. Not collective: the token is of data every rank holds
    alike, so every rank decides the same."""
    what = "cycle" if isinstance(result, CycleResult) else "increment"
    if result.solved_from is None:
        raise ValueError(f"commit: this {what} result carries no token of the state it was solved from "
                         "(solved_from = None): commit only results of FrettingProblem.solve or run_cycle")
    if result.solved_from != state.token:
        raise ValueError(
            f"commit: this {what} result was solved from another state than the one given (the given state has "
            f"{state.increment} increment(s)): a result is committed once, to the state it was solved from; "
            "committed again, or to another state, its wear and increments would count twice. Solve again from "
            "this state instead")


def commit(operators: ContactOperators, laws: tuple, monitor: SlidingMonitor, state: ContactState,
           result: IncrementResult | CycleResult) -> ContactState:
    """The new state after a converged increment or cycle: each zone's wear law (``laws``, one per zone;
    increments), the plastic history, the totals of :attr:`~dolfinx_fretting.state.ContactState.record`. ``state``
    itself is not changed. Collective only in name (no communication: every rank holds the same contact data).

    Raises:
        ValueError: ``result`` was not solved from ``state`` (:func:`check_solved_from`).
    """
    check_solved_from(state, result)
    if isinstance(result, CycleResult):
        check_sliding(operators, monitor, result.final)
        # the cycle counts the physical cycles it stands for (what a friction law of the cycles reads next)
        return replace(result.final, cycles=state.cycles + acceleration(laws))
    operators.activate(state)
    contact_set = operators.contact.contact_set
    states = np.empty(contact_set.nc, dtype=np.int8)
    row = np.empty(len(ROW_FIELDS))
    wear_gap = state.wear_gap.copy()
    # The coefficients the increment was solved with: those of the state it started from (explicit update).
    mu = friction.coefficients(operators.contact, state)
    coefficients = wear_coefficients(operators, laws, result.in_cycle, mu)
    commit_increment(result.forces, result.slip, result.positions, mu, contact_set.dim,
                     contact_set.tributary, contact_set.abscissa, coefficients, wear_gap, states, row)
    if contact_set.surface_mass is not None:   # the peak of the pressure read (pressure_recovery "smoothed")
        row[ROW["max_pressure"]] = max(float(contact_set.tractions(result.forces)[:, 0].max(initial=0.0)), 0.0)
    friction_energy = friction.accumulated_energy(operators.contact, state, result.forces, result.slip,
                                                  acceleration(laws) if result.in_cycle else 1.0)
    master_wear = state.master_wear
    wear = laws[0]   # finite sliding: one zone
    if operators.surface_compliance is not None and wear is not None:
        # The master's share of the wear stays on the master's nodes (it follows its material points).
        master_share = (1.0 - wear.slave_share) * (wear_gap - state.wear_gap)
        added = sliding.spread_wear(contact_set, operators.surface_compliance, master_share)
        master_wear = state.master_wear + added
        if contact_set.slave_areas is not None:
            # Mortar: the slave's worn measure (Archard's on the weighted slip, depth x D_jj) over the node's own
            # measure, which stays the node's whatever part of its hat faces the master after a re-pairing.
            slave_share = (wear_gap - state.wear_gap - master_share) * contact_set.tributary / contact_set.slave_areas
            wear_gap = state.wear_gap + slave_share
        else:
            wear_gap = wear_gap - master_share
        wear_gap = wear_gap + sliding.interpolate_master(contact_set, operators.surface_compliance, added)
        # the worn area of both bodies: the flat's wear left behind by the slide is no longer under a contact
        row[ROW["wear_area"]] = worn_measure(operators, replace(state, wear_gap=wear_gap, master_wear=master_wear))
    record = {**dict(zip(ROW_FIELDS, row.tolist())), **solver_columns(result)}
    new = replace(state, forces=result.forces, positions=result.positions, slip=result.slip, wear_gap=wear_gap,
                  obstacle=result.obstacle, load_factors=result.load_factors, increment=state.increment + 1,
                  dissipated_energy=state.dissipated_energy + row[ROW["dissipated_energy"]],
                  local_iterations=state.local_iterations + result.iterations, record=record, status=states,
                  targets=result.targets, force_controlled=result.force_controlled,
                  plastic=result.plastic if result.plastic is not None else state.plastic, master_wear=master_wear,
                  friction_energy=friction_energy)
    if operators.surface_compliance is not None:
        return _repair(operators, monitor, new)
    check_sliding(operators, monitor, new)
    return new


def _surface_state(operators: ContactOperators, state: ContactState) -> tuple[np.ndarray, np.ndarray]:
    """Finite sliding: (the surface nodes' displacement, the master's translation D) of ``state``."""
    u = operators.surface_compliance.displacement(state.pairing, state.forces, state.load_factors)
    return u, operators.obstacle_translation(state.obstacle)

def _repair(operators: ContactOperators, monitor: SlidingMonitor, state: ContactState) -> ContactState:
    """Finite sliding: pair the slave nodes anew once a paired point has moved more than
    ``ElasticBody.repair_slip`` master elements from its slave node, and carry ``state`` into the new
    pairing (:func:`~dolfinx_fretting.sliding.carry_state`). Not collective (replicated data)."""
    contact_set = state.pairing
    u, D = _surface_state(operators, state)
    moved = sliding.offsets(contact_set, operators.surface_compliance, u, D).max(initial=0.0)
    if moved <= operators.contact.obstacle.repair_slip:
        return state
    if moved > 1.0 and monitor.warn and not monitor.stride_warned:
        monitor.stride_warned = True
        if operators.comm.rank == 0:
            warnings.warn(f"finite sliding: an increment moved a paired point {moved:.3g} master elements (more than "
                          "one): it was solved on a pairing that no longer faced its nodes; take smaller "
                          "increments", RuntimeWarning, stacklevel=4)
    new = sliding.repair(contact_set, operators.surface_compliance, u, D)
    if _same_pairing(contact_set, new):
        return state   # e.g. a node facing past the master's end: its closest point does not move
    carried = sliding.carry_state(contact_set, new, operators.surface_compliance, u, D, state.forces, state.slip,
                                  state.wear_gap, state.master_wear)
    monitor.repairs += 1
    if not monitor.warn or monitor.reach_warned:   # (the check below only warns, once)
        return replace(state, pairing=new, **carried)
    loaded = state.forces[0::contact_set.dim] > 0
    beyond = sliding.offsets(new, operators.surface_compliance, u, D)[loaded]
    if beyond.size and beyond.max() > operators.contact.obstacle.repair_slip:
        monitor.reach_warned = True
        if operators.comm.rank == 0:
            warnings.warn(f"finite sliding: a loaded contact is {beyond.max():.3g} master elements from the "
                          "closest master point within reach: it has slid beyond ElasticBody.reach (or off the "
                          "master surface)", RuntimeWarning, stacklevel=4)
    return replace(state, pairing=new, **carried)


def _same_pairing(old, new) -> bool:
    """The same master facets (mortar: master nodes) and weights to 1e-12."""
    if new.master_faces is None:   # mortar
        return (new.master_nodes.shape == old.master_nodes.shape and np.array_equal(new.master_nodes, old.master_nodes)
                and np.allclose(new.master_weights, old.master_weights, rtol=0.0, atol=1e-12))
    return np.array_equal(new.master_faces, old.master_faces) and np.allclose(new.master_weights,
                                                                              old.master_weights, rtol=0.0, atol=1e-12)


def relative_slip_ratio(operators: ContactOperators, state: ContactState) -> float:
    """Two deformable bodies: the largest accumulated relative tangential displacement of a contact over its
    master facet's size (:attr:`~dolfinx_fretting.contact.ContactSet.master_sizes`); 0 against a rigid
    plane. The pairing is fixed (small sliding): past 0.5 the master point of a node is no longer the one
    facing it."""
    if operators.surface_compliance is not None:  # how far the paired points have moved since the pairing
        offsets = sliding.offsets(state.pairing, operators.surface_compliance, *_surface_state(operators, state))
        return float(offsets.max(initial=0.0))
    contacts = operators.contact
    dim = contacts.dim
    ratio = 0.0
    for zone in range(len(contacts.zones)):   # the zones against an elastic body
        sizes = contacts.zone_set(zone).master_sizes
        if sizes is None:
            continue
        y_t = state.positions.reshape(-1, dim)[contacts.zone_slice(zone), 1:]
        ratio = max(ratio, float((np.linalg.norm(y_t, axis=1) / sizes).max(initial=0.0)))
    return ratio

def check_sliding(operators: ContactOperators, monitor: SlidingMonitor, state: ContactState) -> None:
    """Warn once (RuntimeWarning, rank 0) when the relative slip of two bodies exceeds half a master facet,
    unless ``monitor.warn`` is False (a driver that reports it itself)."""
    if not monitor.warn or monitor.sliding_warned or operators.surface_compliance is not None:
        return
    ratio = relative_slip_ratio(operators, state)
    if ratio > 0.5:
        monitor.sliding_warned = True
        if operators.comm.rank == 0:
            warnings.warn(
                f"relative slip of {ratio:.3g} master elements exceeds half an element: the contact pairs are fixed "
                "in the reference configuration (small sliding), so the master's displacement is taken up to "
                f"{ratio:.2g} elements away from the point facing each slave node", RuntimeWarning, stacklevel=4)
