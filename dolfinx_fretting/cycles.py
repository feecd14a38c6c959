"""One load cycle of the public problem: its path as per-increment targets, then either the compiled loop
(:mod:`dolfinx_fretting.cycling`: elastic bodies, displacement, load and force control, Uzawa) or increment by
increment through :func:`~dolfinx_fretting.increments.advance`. Either way a failure raises before anything is
committed.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Callable

import numpy as np

from . import friction, local_solvers
from .commit import SlidingMonitor, acceleration, wear_coefficients
from .contact import ContactSet, paired_contact_set
from .cycling import (HELD_BLOCK_ARGUMENTS, N_ROW, NOT_BRACKETED, SATURATED, SWEEPS_EXHAUSTED, TRIAL_NOT_FINITE,
                      FrictionEvolution, run_force_increments, run_increments)
from .laws import Archard, EnergyWear
from .increments import (force_names, load_control_message, on_rank0, per_zone, sweeps_message, target_items,
                         trial_not_finite_message)
from .loading import (MAX_EVAL, CyclePath, Displacement, Force, not_bracketed_message, not_reached_message,
                      saturated_message)
from .operators import ContactOperators
from .settings import LocalSolver
from .sliding import run_sliding_increments
from .state import INCREMENT_COLUMNS, ContactState, ConvergenceError, CycleResult, WindowError
from .wear import ROW, ROW_FIELDS

__all__ = ["cycle_targets", "stepwise_cycle", "compiled_cycle", "sliding_cycle"]


def cycle_targets(operators: ContactOperators, state: ContactState, path: CyclePath
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(obstacle targets (n, components), which components are forces (components,), load factors (n, L)) of
    ``path`` (with several zones, ``normal`` and ``tangential`` map each zone's Contact to its item) from
    ``state``: components and loads the path does not give keep the state's values; bad shapes and unknown
    names are refused."""
    n = path.increments
    dim = operators.dim
    # Components the path does not give keep the state's prescribed values (displacements or forces).
    held = state.targets if state.targets is not None else state.obstacle
    obstacle = np.tile(held.astype(float), (n, 1))
    forced = (state.force_controlled.copy() if state.force_controlled is not None
              else np.zeros(held.size, dtype=bool))
    items = [(item, [dim * zone]) for zone, item in per_zone(operators, path.normal, "CyclePath.normal")]
    items += [(item, list(range(dim * zone + 1, dim * (zone + 1))))
              for zone, item in per_zone(operators, path.tangential, "CyclePath.tangential")]
    for item, comps in items:
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
        if name not in operators.load_names or name == "dirichlet values":
            raise KeyError(f"unknown load {name!r}; this problem's loads: {', '.join(operators.load_names) or 'none'}")
        values = np.asarray(values, dtype=float)
        if values.shape != (n,) or not np.all(np.isfinite(values)):
            raise ValueError(f"CyclePath.loads[{name!r}]: expected {n} finite factors")
        factors[:, operators.load_names.index(name)] = values
    return obstacle, forced, factors


def stepwise_cycle(operators: ContactOperators, advance: Callable[..., tuple[ContactState, dict[str, Any]]],
                   state: ContactState, obstacle: np.ndarray, forced: np.ndarray, factors: np.ndarray, keep: bool,
                   check: Callable[[ContactState], None] | None) -> CycleResult:
    """The cycle increment by increment, each through ``advance`` (the problem's, with its cut-backs)."""
    n = obstacle.shape[0]
    rows, kept, pairings = [], [], []
    current = state
    names = [nm for nm in operators.load_names if nm != "dirichlet values"]
    obstacle = obstacle.copy()
    for j in range(n):
        normal, tangential = target_items(operators, obstacle[j], forced)
        loads = {nm: factors[j, operators.load_names.index(nm)] for nm in names}
        try:
            current, info = advance(current, normal, tangential, loads, in_cycle=True, check=check)
        except WindowError as exc:
            raise WindowError(str(exc), step=j + 1, **exc.details) from None
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


def compiled_cycle(operators: ContactOperators, solver: LocalSolver, laws: tuple, state: ContactState,
                   obstacle: np.ndarray, factors: np.ndarray, keep: bool, forced: np.ndarray | None = None
                   ) -> CycleResult:
    """The cycle in the compiled loop (rank 0, broadcast; the warm start of the next cycle stays on rank 0), with
    ``laws`` each zone's wear law. Collective.

    ``forced`` (components,): which columns of ``obstacle`` are prescribed forces. With any, each increment finds
    its obstacle displacement by the stepwise path's load control inside the loop
    (:func:`~dolfinx_fretting.cycling.run_force_increments`: the same iteration, tolerance and warm starts, and its
    failures raised with the stepwise path's messages); the increments' displacements are the result's
    ``obstacle``.

    The friction coefficients are the state's (:func:`~dolfinx_fretting.friction.coefficients`): a friction law of
    the cycles holds them over the cycle (one compiled call); one of the dissipated energy changes them after every
    increment. A table of the energy runs inside the compiled loop too (one call for the cycle:
    :class:`~dolfinx_fretting.cycling.FrictionEvolution`, with the wear rates of the shipped laws, Archard's and
    Fouvry's ``alpha mu``); the user's function of the energy, or a wear law of the user's, runs one increment per
    call, with each contact's energy and mu (and the wear rate) updated in Python in between: the same arithmetic
    (``benchmarks/results/evolving_friction.md`` measures both)."""
    contact_set = operators.contact.contact_set
    n, m, dim = obstacle.shape[0], contact_set.nc * contact_set.dim, contact_set.dim
    forced = np.zeros(obstacle.shape[1], dtype=bool) if forced is None else np.asarray(forced, dtype=bool)
    by_force = bool(forced.any())
    # Each zone's translation against G's block of its contacts (one zone: G = its rigid modes).
    D = None if by_force else np.ascontiguousarray(operators.contact.translations(obstacle))
    targets = np.ascontiguousarray(obstacle, dtype=float)
    found = targets.copy()   # the increments' obstacle displacements (found where forced)
    failure, last_force = np.zeros(4), np.zeros(obstacle.shape[1])
    scale = acceleration(laws)
    evolution = _friction_evolution(operators, laws, state, scale)
    per_increment = friction.tracks_energy(operators.contact) and evolution is None
    if evolution is None:
        evolution = FrictionEvolution.held()
    warm_new = None

    def work():  # rank 0: the compiled loop; its result is broadcast, the warm start stays on rank 0
        nonlocal warm_new
        Wc, rho, cache = operators.kernel_data(None if by_force else n)
        # Force control tries no cached contact pattern: an exact pattern solve instead of the Uzawa sweeps' answer
        # (to the local tolerance) moves the root finder's answers by up to ~4e-8 relative on the frozen 2D cases
        # (tests/test_reference_summaries.py, measured); without it the loop repeats the stepwise path's iteration.
        active = cache.enabled and solver.pattern_reuse and not by_force
        if by_force:
            T, A = operators.force_maps()
            # The load control's state, as the stepwise path's: the last increment's obstacle and the slopes
            # (updated in place, on rank 0 as there).
            d = state.obstacle.astype(float).copy()
            stiffness = operators.stiffness
        warm = 1 if state.warm is not None and state.warm.shape == (n, m) and solver.warm_start == "cycle" else 0
        r_warm = state.warm.copy() if warm else np.zeros((n, m))
        wear_gap, y, r_last = state.wear_gap.copy(), state.positions.copy(), state.forces.copy()
        # Every increment is stored (cheap): the last one's slip and status belong to the final state.
        out_r, out_x, out_y = np.zeros((n, m)), np.zeros((n, m)), np.zeros((n, m))
        out_wear, out_states = np.zeros((n, contact_set.nc)), np.zeros((n, contact_set.nc), dtype=np.int8)
        rows = np.zeros((n, N_ROW))
        solves = np.ones(n, dtype=np.int64)
        G = np.ascontiguousarray(operators.contact.rigid_modes)
        Q = np.ascontiguousarray(operators.responses)
        S = np.ascontiguousarray(factors)
        current = state
        # One call for the cycle, or (mu changing with the energy) one per increment: the slices of the per-increment
        # arrays are C-contiguous views, so the kernel writes its results in place either way.
        calls = [slice(j, j + 1) for j in range(n)] if per_increment else [slice(0, n)]
        for part in calls:
            # (an evolving law's coefficients are a new array: the loop may change them in place)
            mu = friction.coefficients(operators.contact, current)
            if active and not evolution.evolve:   # factors made with another mu are stale (an evolving law changed it)
                stale = np.any(cache.factor_mu[part] != mu, axis=1)
                cache.lu_ok[part][stale] = False
                cache.factor_mu[part] = mu
            k = wear_coefficients(operators, laws, True, mu)
            if by_force:
                done, status, err = run_force_increments(
                    Wc, rho, mu, dim, contact_set.gap0, wear_gap, G, T, A, targets[part], forced, d, stiffness,
                    solver.force_tol, MAX_EVAL, Q, S[part], contact_set.tributary, contact_set.abscissa, y, r_last,
                    r_warm[part], k, solver.tol, solver.max_iter, local_solvers._REFRESH, True, out_r[part],
                    out_x[part], out_y[part], out_wear[part], out_states[part], rows[part], found[part],
                    solves[part], active, cache.pattern[part], cache.lu[part], cache.piv[part], cache.lu_ok[part],
                    cache.counts, failure, last_force, cache.factor_mu[part], *evolution.arguments(),
                    *HELD_BLOCK_ARGUMENTS, False)
            else:
                done, status, err = run_increments(
                    Wc, rho, mu, dim, contact_set.gap0, wear_gap, G, D[part], Q, S[part], contact_set.tributary,
                    contact_set.abscissa, y, r_last, r_warm[part], warm, k, solver.tol, solver.max_iter,
                    local_solvers._REFRESH, True, out_r[part], out_x[part], out_y[part], out_wear[part],
                    out_states[part], rows[part], active, cache.pattern[part], cache.lu[part], cache.piv[part],
                    cache.lu_ok[part], cache.counts, cache.factor_mu[part], *evolution.arguments(),
                    *HELD_BLOCK_ARGUMENTS, False)
            if done < part.stop - part.start:
                step = part.start + done + 1
                if status > 2:
                    raise ConvergenceError(_load_control_failure(operators, status, failure, targets[step - 1],
                                                                 forced, last_force, mu), step=step)
                why = "non-finite values" if status == 2 else "max_iter reached"
                raise ConvergenceError(f"local solver did not converge ({why}, error {err:.3e} >= tol "
                                       f"{solver.tol:.1e} after {solver.max_iter} sweeps)", step=step)
            if per_increment:
                current = replace(current, friction_energy=friction.accumulated_energy(
                    operators.contact, current, out_r[part.start], out_x[part.start], scale))
        if evolution.evolve:   # the energy the loop accumulated (a copy of the state's: it stays unchanged)
            current = replace(current, friction_energy=evolution.energy)
        # Every increment of the cycle, not only the last: one product of the outside rows with the cycle's forces.
        operators.check_window(out_r, found, factors, solver.tol, cycle=True)
        if contact_set.surface_mass is not None:   # the peak of the pressure read (pressure_recovery "smoothed")
            pressure = contact_set.tractions(out_r)[..., 0]
            rows[:, ROW["max_pressure"]] = np.maximum(pressure.max(axis=1, initial=0.0), 0.0)
        warm_new = r_warm  # the cycle's forces: the next cycle's warm start
        outs = (out_r, out_x, out_y, out_wear, out_states) if keep else (out_x[-1:], out_states[-1:])
        return rows, wear_gap, y, r_last, outs, current.friction_energy, found, solves

    result = on_rank0(operators.comm, work)
    rows, wear_gap, y, r_last, outs, energy_new, found, solves = result
    nf = len(ROW_FIELDS)
    records = _records(rows, solves)
    slip, status = (outs[1][-1].copy(), outs[4][-1].copy()) if keep else (outs[0][-1].copy(), outs[1][-1].copy())
    final = replace(state, forces=r_last, positions=y, slip=slip, wear_gap=wear_gap, obstacle=found[-1].copy(),
                    targets=obstacle[-1].copy(), force_controlled=forced.copy(),
                    load_factors=factors[-1].copy(), increment=state.increment + n,
                    dissipated_energy=state.dissipated_energy + float(rows[:, ROW["dissipated_energy"]].sum()),
                    local_iterations=state.local_iterations + int(rows[:, nf].sum()),
                    record={k: records[k][-1].item() for k in INCREMENT_COLUMNS},
                    status=status, warm=warm_new if operators.comm.rank == 0 else None, friction_energy=energy_new)
    return CycleResult(records, found, factors, final, outs if keep else None, True)


def _friction_evolution(operators: ContactOperators, laws: tuple, state: ContactState,
                        scale: float) -> FrictionEvolution | None:
    """The compiled loop's friction of the energy (a copy of the state's energy), or None when no zone's friction
    follows the energy, or one follows the user's function, or a wear law is not one whose rate is affine in mu
    (Archard's, Fouvry's): then the cycle runs one increment per call."""
    contact = operators.contact
    if not friction.tracks_energy(contact):
        return None
    tables = friction.energy_tables(contact)
    # the shipped laws themselves, not a subclass: a user's subclass may make the rate other than affine in mu
    if tables is None or not all(law is None or type(law) in (Archard, EnergyWear) for law in laws):
        return None
    # k = k0 + k1 mu exactly as the laws compute it (Archard: k0 = k acceleration, k1 = 0; Fouvry: k0 = 0,
    # k1 = alpha acceleration, so k0 + k1 mu is alpha acceleration mu to the bit)
    base = wear_coefficients(operators, laws, True, np.zeros(contact.nc))
    per_mu = wear_coefficients(operators, laws, True, np.ones(contact.nc)) - base
    energy = np.zeros(contact.nc) if state.friction_energy is None else state.friction_energy.copy()
    return FrictionEvolution(energy, scale, *tables, base, per_mu)


def _records(rows: np.ndarray, solves: np.ndarray) -> dict[str, np.ndarray]:
    """The per-increment columns of a compiled cycle from the loop's rows and each increment's local solves."""
    n, nf = rows.shape[0], len(ROW_FIELDS)
    records = {name: rows[:, i] for i, name in enumerate(ROW_FIELDS)}
    records.update(local_iterations=rows[:, nf].astype(int), local_error=rows[:, nf + 1],
                   load_solves=solves.astype(int), newton_iterations=np.ones(n, dtype=int),
                   newton_delta_1=np.zeros(n), newton_delta_2=np.zeros(n), cutbacks=np.zeros(n, dtype=int),
                   yielded_points=np.zeros(n, dtype=int))
    return records


def sliding_cycle(operators: ContactOperators, solver: LocalSolver, laws: tuple, monitor: SlidingMonitor,
                  state: ContactState, obstacle: np.ndarray, forced: np.ndarray, factors: np.ndarray,
                  keep: bool = False) -> CycleResult | None:
    """A finite-sliding cycle in the compiled loop (:func:`~dolfinx_fretting.sliding.run_sliding_increments`: the
    increments solved, committed and re-paired as :func:`stepwise_cycle` does them, with the same decisions), on
    rank 0, broadcast. Collective. ``keep``: also every increment's committed arrays and the pairing they refer to
    (:attr:`~dolfinx_fretting.state.CycleResult.kept_pairings`), as :func:`stepwise_cycle` keeps them.

    None, with nothing changed, when the loop does not apply (3D or mortar pairings, a friction law of the dissipated
    energy, directions held by the conditions, a smoothed pressure read) or stops before the cycle's end: a failed
    increment, a node outside the window that may penetrate, a warning due (a stride over one master element, a
    contact beyond the reach), a singular contact compliance; the caller then solves the cycle increment by
    increment, which raises or warns with its own messages."""
    pairing = state.pairing
    contact = operators.contact
    # (a smoothed pressure read: the loop's rows hold the nodal peak pressure, the stepwise path's the smoothed one)
    if (pairing.dim != 2 or pairing.master_faces is None or friction.tracks_energy(contact)
            or contact.held_rows.size or len(contact.zones) != 1 or pairing.surface_mass is not None):
        return None
    data = operators.sliding_kernel_data()
    faces = data.local_faces(pairing)
    if faces is None:
        return None
    compliance = operators.surface_compliance
    n = obstacle.shape[0]
    by_force = bool(forced.any())
    mu = friction.coefficients(contact, state)
    k = wear_coefficients(operators, laws, True, mu)
    wear = laws[0]
    master_share = 1.0 - wear.slave_share if wear is not None else -1.0
    translations = np.ascontiguousarray(contact.translations(obstacle))
    # The obstacle's translation per unit component, and the total force along each component per contact force (the
    # pairing's frames): force_maps' T and A, without its loop over the contacts (a new pairing at every cycle)
    T = np.ascontiguousarray(contact.translations(np.eye(contact.obstacle_size)).T)
    A = contact.rigid_modes @ contact.frame.T
    warn_stride = monitor.warn and not monitor.stride_warned
    warn_reach = monitor.warn and not monitor.reach_warned
    copy = np.array   # every array the loop writes in place is a copy (the states and the operators keep theirs)

    def work():
        weights, frames, gap0 = copy(pairing.master_weights, dtype=float), copy(pairing.frames), copy(pairing.gap0)
        W, Q = copy(operators.W), copy(operators.responses)
        G, A_now, rho = copy(contact.rigid_modes), copy(A.T), copy(operators.block_steps)
        d, wear_gap, master_wear = state.obstacle.astype(float), copy(state.wear_gap), copy(state.master_wear)
        y, r_last = copy(state.positions), copy(state.forces)
        rows, found, solves = np.zeros((n, N_ROW)), copy(obstacle, dtype=float), np.ones(n, dtype=np.int64)
        slip, status = np.zeros(pairing.nc * 2), np.zeros(pairing.nc, dtype=np.int8)
        fl, stiffness = copy(faces), copy(operators.stiffness)
        kept_rows = n if keep else 0
        kept = (np.zeros((kept_rows, 2 * pairing.nc)), np.zeros((kept_rows, 2 * pairing.nc)),
                np.zeros((kept_rows, 2 * pairing.nc)), np.zeros((kept_rows, pairing.nc)))
        kept_status = np.zeros((kept_rows, pairing.nc), dtype=np.int8)
        kept_fl, kept_weights = np.zeros((kept_rows, pairing.nc), dtype=np.int64), np.zeros((kept_rows, pairing.nc, 2))
        _done, code, repairs = run_sliding_increments(
            fl, weights, frames, gap0, W, Q, G, A_now, rho, data.face_rows, data.face_x, data.face_inside,
            data.face_sizes, data.slave_rows, pairing.coords, pairing.tributary, pairing.abscissa, compliance.C,
            data.compliance_columns, compliance.responses, compliance.master_areas, contact.frame, T,
            data.on_surfaces, data.out_responses, data.out_motion, data.out_gap0, by_force,
            np.ascontiguousarray(obstacle, dtype=float), forced, translations, np.ascontiguousarray(factors),
            solver.force_tol, MAX_EVAL, stiffness, d, wear_gap, master_wear, y, r_last, mu, k, master_share,
            solver.tol, solver.max_iter, local_solvers._REFRESH, float(contact.obstacle.repair_slip), warn_stride,
            warn_reach, rows, found, solves, slip, status, ROW["wear_area"], kept, kept_status, kept_fl, kept_weights)
        if code:
            return None
        operators.stiffness[:] = stiffness   # the slopes learnt, as the stepwise load control keeps them (rank 0)
        return (rows, found, solves, fl, weights, wear_gap, master_wear, y, r_last, slip, status, repairs,
                (*kept, kept_status) if keep else None, (kept_fl, kept_weights) if keep else None)

    result = on_rank0(operators.comm, work)
    if result is None:
        return None
    rows, found, solves, fl, weights, wear_gap, master_wear, y, r_last, slip, status, repairs, kept, kept_faces = result
    monitor.repairs += repairs

    def paired(faces_now: np.ndarray, weights_now: np.ndarray) -> ContactSet:
        return paired_contact_set(pairing.master_surface, pairing.global_nodes, pairing.coords, pairing.tributary,
                                  pairing.abscissa, data.faces[faces_now], weights_now, pairing.H.shape[1],
                                  pairing.surface_mass)

    final_pairing = pairing if not repairs else paired(fl, weights)
    kept_pairings = None
    if keep:   # one ContactSet per pairing held, as the stepwise path's states share theirs until a re-pairing
        kept_pairings, held, held_arrays = [], pairing, (faces, pairing.master_weights)
        for faces_now, weights_now in zip(*kept_faces):
            if not (np.array_equal(faces_now, held_arrays[0]) and np.array_equal(weights_now, held_arrays[1])):
                same_as_final = np.array_equal(faces_now, fl) and np.array_equal(weights_now, weights)
                held = final_pairing if same_as_final else paired(faces_now, weights_now)
                held_arrays = (faces_now, weights_now)
            kept_pairings.append(held)
        kept_pairings = tuple(kept_pairings)
    records = _records(rows, solves)
    nf = len(ROW_FIELDS)
    final = replace(state, forces=r_last, positions=y, slip=slip, wear_gap=wear_gap, obstacle=found[-1].copy(),
                    targets=obstacle[-1].copy(), force_controlled=forced.copy(), load_factors=factors[-1].copy(),
                    increment=state.increment + n,
                    dissipated_energy=state.dissipated_energy + float(rows[:, ROW["dissipated_energy"]].sum()),
                    local_iterations=state.local_iterations + int(rows[:, nf].sum()),
                    record={k: records[k][-1].item() for k in INCREMENT_COLUMNS}, status=status,
                    master_wear=master_wear, pairing=final_pairing)
    return CycleResult(records, found, factors, final, kept, True, kept_pairings)


def _load_control_failure(operators: ContactOperators, status: int, failure: np.ndarray, targets: np.ndarray,
                          forced: np.ndarray, forces: np.ndarray, mu: np.ndarray) -> str:
    """The stepwise path's message for a load control failure of the compiled loop (``status``: one of
    :mod:`~dolfinx_fretting.cycling`'s codes, ``failure`` its numbers; ``targets`` the increment's, ``forces`` the
    total force of its last trial)."""
    names = force_names(operators)
    k = int(failure[0])
    if status == TRIAL_NOT_FINITE:
        return trial_not_finite_message(names[k], targets[k])
    if status == SWEEPS_EXHAUSTED:
        return sweeps_message(np.abs(forces - targets)[forced], failure[1])
    if status == SATURATED:
        message = saturated_message(names[k], failure[1], failure[2])
    elif status == NOT_BRACKETED:
        message = not_bracketed_message(names[k], failure[1], MAX_EVAL, failure[2], failure[3])
    else:
        message = not_reached_message(names[k], failure[1], MAX_EVAL, failure[2], failure[3])
    return load_control_message(operators, k, targets, forced, forces, mu, message)
