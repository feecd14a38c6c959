"""One increment of the public problem: its targets, the local contact solve under load control, the
elastic–plastic Newton loop around it, and the cut-backs of :func:`advance`.

The local problem ``x = W r + q`` is solved on rank 0 (:func:`on_rank0`: its result is broadcast and its
error raised on every rank); a prescribed force makes its obstacle component an unknown found by
:func:`~dolfinx_fretting.loading.find_displacement`, each trial one warm-started local solve.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Callable, Mapping

import numpy as np
from mpi4py import MPI

from . import friction, local_solvers
from .cycling import warm_pattern_solve
from .loading import FORCE_SWEEPS, Displacement, Force, LoadControlError, find_displacement, tangential_item
from .operators import ContactOperators
from .plasticity import ElastoplasticBody, NewtonError
from .settings import LocalSolver, finite
from .state import ContactState, ConvergenceError, IncrementResult, PlasticHistory, WindowError, solver_columns

__all__ = ["on_rank0", "increment_targets", "target_items", "per_zone", "solve_contact", "solve_plastic",
           "load_plastic", "advance"]


def on_rank0(comm: MPI.Comm, work: Callable[[], Any]) -> Any:
    """Run ``work`` on rank 0 and broadcast its value; an exception there is raised on every rank (the others
    would otherwise wait in the broadcast forever). Collective."""
    value = failure = None
    if comm.rank == 0:
        try:
            value = work()
        except WindowError as exc:
            failure = ("WindowError", str(exc), exc.step, exc.details)
        except ConvergenceError as exc:
            failure = ("ConvergenceError", str(exc), exc.step, None)
        except Exception as exc:  # noqa: BLE001 - re-raised on every rank below
            failure = (type(exc).__name__, str(exc), None, None)
    if comm.size > 1:
        value, failure = comm.bcast((value, failure), root=0)
    if failure is not None:
        kind, message, step, details = failure
        if kind == "WindowError":
            raise WindowError(message, step=step, **details)
        if kind == "ConvergenceError":
            raise ConvergenceError(message, step=step)
        raise RuntimeError(f"{kind} on rank 0: {message}")
    return value


def increment_targets(operators: ContactOperators, state: ContactState, normal, tangential
                      ) -> tuple[np.ndarray, np.ndarray]:
    """The prescribed value of each obstacle component and whether it is a force, after ``normal`` and
    ``tangential`` (as :meth:`~dolfinx_fretting.problem.FrettingProblem.solve`); components not given keep
    ``state``'s. Motions and forces along a held direction are refused."""
    dim = operators.dim
    targets = (state.targets if state.targets is not None else state.obstacle).astype(float).copy()
    controlled = (state.force_controlled.copy() if state.force_controlled is not None
                  else np.zeros(targets.size, dtype=bool))

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
            targets[c] = finite(f"{name}", v)
            controlled[c] = kind_force

    for zone, item in per_zone(operators, normal, "normal"):
        parse(item, [dim * zone], "normal")
    for zone, item in per_zone(operators, tangential, "tangential"):
        parse(item, list(range(dim * zone + 1, dim * (zone + 1))), "tangential")
    operators.check_held(targets, controlled)
    return targets, controlled


def target_items(operators: ContactOperators, targets: np.ndarray, controlled: np.ndarray) -> tuple[Any, Any]:
    """The ``normal`` and ``tangential`` arguments of :meth:`~dolfinx_fretting.problem.FrettingProblem.solve` that
    prescribe ``targets`` with their controls (with several zones: one item per zone, keyed by its Contact)."""
    zones, dim = operators.contact.zones, operators.dim
    normal, tangential = {}, {}
    for i, zone in enumerate(zones):
        first = dim * i
        normal[zone] = (Force if controlled[first] else Displacement)(targets[first])
        tangential[zone] = tangential_item(targets[first + 1:first + dim], controlled[first + 1:first + dim])
    if len(zones) == 1:
        return normal[zones[0]], tangential[zones[0]]
    return normal, tangential


def per_zone(operators: ContactOperators, value, name: str) -> list[tuple[int, Any]]:
    """(zone index, item) of a ``normal`` or ``tangential`` argument: with one zone a bare value is its item;
    with several a mapping from each zone's :class:`~dolfinx_fretting.contact.Contact` to its item (zones not
    named keep their obstacle's prescribed values)."""
    zones = operators.contact.zones
    if isinstance(value, Mapping):
        items = []
        for key, item in value.items():
            zone = operators.zone_of(key)
            if zone is None:
                raise ValueError(f"{name}: a key is not one of this problem's contact zones ({key!r}): name each "
                                 "zone by the Contact given to FrettingProblem")
            items.append((zone, item))
        return items
    if value is None:
        return []
    if len(zones) > 1:
        raise ValueError(f"{name} = {value!r}: this problem has {len(zones)} contact zones: give one item per zone, "
                         f"{name}={{contact: value, ...}} (zones not named keep their obstacle's prescribed value)")
    return [(0, value)]


def solve_contact(operators: ContactOperators, solver: LocalSolver, state: ContactState, targets: np.ndarray,
                  controlled: np.ndarray, factors: np.ndarray, q_body: np.ndarray | None = None,
                  W: np.ndarray | None = None, r_warm: np.ndarray | None = None) -> IncrementResult:
    """The local problem with its load control, on rank 0, broadcast; raises ConvergenceError on all ranks.
    ``q_body`` and ``W`` replace the loads' response and the elastic W (the Newton loop's). Collective."""
    return on_rank0(operators.comm, lambda: _local_with_control(operators, solver, state, targets, controlled,
                                                                factors, q_body, W, r_warm))


def _local_with_control(operators: ContactOperators, solver: LocalSolver, state: ContactState,
                        targets: np.ndarray, controlled: np.ndarray, factors: np.ndarray,
                        q_body: np.ndarray | None, W: np.ndarray | None,
                        r_warm: np.ndarray | None) -> IncrementResult:
    contact_set = operators.contact.contact_set
    dim = contact_set.dim
    Wm = operators.W if W is None else W
    steps = operators.block_steps if Wm is operators.W else None  # held with the operators' W (else computed)
    d = state.obstacle.astype(float).copy()
    warm = [state.forces.copy() if r_warm is None else r_warm.copy()]
    count = {"solves": 0, "iterations": 0}
    last: dict[str, Any] = {}
    mu = friction.coefficients(operators.contact, state)   # held over the increment (explicit update)
    # 2D node-to-segment finite sliding: every local solve first tries its warm start's contact pattern as an exact
    # linear solve, as the compiled finite-sliding loop does (cycling.warm_pattern_solve): the same rule on both
    # paths keeps their answers the same.
    pairing = state.pairing
    pattern_first = (W is None and dim == 2 and pairing is not None and pairing.master_faces is not None
                     and isinstance(Wm, np.ndarray) and steps is not None)

    def local(trial: np.ndarray) -> np.ndarray:
        if not np.all(np.isfinite(trial)):
            # The load control's bracketing doubles its step while the force stays put: a prescribed force that
            # no finite obstacle displacement gives (e.g. one so small that no contact closes) ends here, not in
            # the local solver's "q: contains non-finite values".
            k = int(np.flatnonzero(~np.isfinite(trial))[0])
            raise ConvergenceError(trial_not_finite_message(names[k], targets[k]))
        q, q_abs = operators.q(trial, factors, state.positions, state.wear_gap, q_body)
        solved = _warm_pattern(Wm, q, mu, steps, solver.tol, warm[0]) if pattern_first else None
        if solved is None:
            solved = local_solvers.solve(Wm, q, mu, dim, method=solver.method, tol=solver.tol,
                                         max_iter=solver.max_iter, r0=warm[0], block_steps=steps)
        count["solves"] += 1
        count["iterations"] += solved.iterations
        if not solved.converged:
            raise ConvergenceError(f"local solver did not converge: {solved.message}")
        warm[0] = solved.r
        last.update(solved=solved, d=trial.copy(), q_abs=q_abs, F=operators.contact.obstacle_forces(solved.r))
        return last["F"]

    d[~controlled] = targets[~controlled]
    names = force_names(operators)
    try:
        F = local(d)
        # Tolerance relative to the loads in play (a zero tangential target is held to the normal force).
        scale = max(np.abs(targets[controlled]).max(initial=0.0), np.abs(F).max(), 1e-300)
        ftol = solver.force_tol * scale
        for _sweep in range(FORCE_SWEEPS):
            if np.all(np.abs(F - targets)[controlled] <= ftol):
                break
            for k in np.flatnonzero(controlled):
                def force_k(v: float, k: int = k) -> float:
                    trial = d.copy()
                    trial[k] = v
                    return local(trial)[k]
                d_old, F_old = d[k], F[k]
                try:  # a flat force makes the root finder's secant 0/0: caught as a non-finite trial in local()
                    with np.errstate(divide="ignore", invalid="ignore"):
                        d[k], _, _ = find_displacement(force_k, targets[k], d[k], operators.stiffness[k], ftol,
                                                       name=names[k])
                except LoadControlError as exc:
                    raise ConvergenceError(load_control_message(operators, k, targets, controlled, last["F"], mu,
                                                                str(exc))) from None
                F = last["F"]  # the root finder's last evaluation is at the returned d[k]
                if d[k] != d_old and F[k] != F_old:
                    operators.stiffness[k] = abs((F[k] - F_old) / (d[k] - d_old))
        else:
            raise ConvergenceError(sweeps_message(np.abs(F - targets)[controlled], ftol))
    except LoadControlError as exc:
        raise ConvergenceError(str(exc)) from None
    solved = last["solved"]
    y = Wm @ solved.r + last["q_abs"]
    return IncrementResult(solved.r.copy(), solved.x.copy(), y, last["d"].copy(), factors.copy(), False,
                           count["iterations"], targets.copy(), controlled.copy(), solved.error, count["solves"])


def _warm_pattern(W: np.ndarray, q: np.ndarray, mu: np.ndarray, steps: np.ndarray, tol: float, r0: np.ndarray
                  ) -> local_solvers.LocalResult | None:
    """The 2D local problem solved exactly on its warm start's contact pattern (:func:`~dolfinx_fretting.cycling.
    warm_pattern_solve`, as the compiled finite-sliding loop tries it), or None where that answer misses ``tol``
    or no contact penetrates (``local_solvers.solve`` then answers r = 0 at once, as the loop does)."""
    if not np.any(q[0::2] < 0.0):
        return None
    r, x = np.array(r0, dtype=float), np.empty(q.size)
    accepted, error, tried = warm_pattern_solve(W, np.ascontiguousarray(q, dtype=float),
                                                np.ascontiguousarray(mu, dtype=float), steps, tol, r, x)
    if not accepted:
        return None
    return local_solvers.LocalResult(r, x, 0, error, True, "pattern",
                                     f"warm start's contact pattern solved exactly ({tried} tried), error {error:.3e}")


def force_names(operators: ContactOperators) -> list[str]:
    """The name of each obstacle component's force in the load control's messages."""
    dim = operators.dim
    names = ["normal force"] + [f"tangential force (t{k})" for k in range(1, dim)]
    zones = len(operators.contact.zones)
    if zones > 1:
        names = [f"contact[{zone}] {name}" for zone in range(zones) for name in names]
    return names


def trial_not_finite_message(name: str, target: float) -> str:
    """The load control's message when a trial obstacle displacement is not finite."""
    return (f"{name}: prescribed value {target:.6g} not reached: the load control's trial obstacle displacement is "
            "not finite (the force did not change between its trials): a load this far below the model's scale is "
            "degenerate")


def sweeps_message(residual: np.ndarray, ftol: float) -> str:
    """The load control's message when its sweeps over the controlled components did not meet the targets."""
    return f"prescribed forces not reached after {FORCE_SWEEPS} sweeps (residual {residual}, tolerance {ftol:.3g})"


def load_control_message(operators: ContactOperators, k: int, targets: np.ndarray, controlled: np.ndarray,
                         forces: np.ndarray, mu: np.ndarray, message: str) -> str:
    """A root finder's failure on component ``k``: the physical reason when a tangential force is beyond friction
    (:func:`_beyond_friction`), else ``message``."""
    return _beyond_friction(operators, k, targets, controlled, forces, mu) or message


def _beyond_friction(operators: ContactOperators, k: int, targets: np.ndarray, controlled: np.ndarray,
                     forces: np.ndarray, mu: np.ndarray) -> str | None:
    """The physical reason a prescribed tangential force (component ``k``) cannot be reached, with its numbers:
    ``|Q| >= mu P``, the most friction the zone's normal force can carry (None if ``k`` is a normal component or
    ``|Q|`` is below that bound: then the load control's own message stands)."""
    dim = operators.dim
    zone, component = divmod(k, dim)
    if component == 0:
        return None
    tangential = np.arange(dim * zone + 1, dim * (zone + 1))
    tangential = tangential[controlled[tangential]]
    magnitude = float(np.linalg.norm(targets[tangential]))
    normal = float(forces[dim * zone])
    mu = np.asarray(mu[operators.contact.zone_slice(zone)], dtype=float)   # the increment's coefficients
    mu_max = float(mu.max(initial=0.0))
    if magnitude < mu_max * max(normal, 0.0):
        return None
    unit = "N/mm" if dim == 2 else "N"
    uniform = mu.size == 0 or float(mu.min()) == mu_max
    name = "mu" if uniform else "max(mu)"
    friction = f"{name} x P = {mu_max:g} x {normal:.6g} = {mu_max * max(normal, 0.0):.6g} {unit}"
    zone_text = f"contact[{zone}] " if len(operators.contact.zones) > 1 else ""
    return (f"{zone_text}tangential force |Q| = {magnitude:.6g} {unit} cannot be reached: it must stay below "
            f"{friction}, the friction the normal force P of this increment can carry (at or beyond mu P the "
            "contact slides and no displacement gives Q)")


def solve_plastic(operators: ContactOperators, solver: LocalSolver, body: ElastoplasticBody, state: ContactState,
                  targets: np.ndarray, controlled: np.ndarray, factors: np.ndarray, in_cycle: bool) -> IncrementResult:
    """An elastic–plastic increment: Newton with the contact solve inside every iteration (the paper's Fig. 4),
    full Newton once more if the adaptive tangent fails. Collective."""
    load_plastic(body, state.plastic)
    scale = body.set_loads([(operators.vectors[i], factors[i]) for i in range(len(operators.load_names))])
    warm = [state.forces]
    total = {"iterations": 0, "solves": 0}

    def local_solve(q_body, W):
        solved = solve_contact(operators, solver, state, targets, controlled, factors, q_body, W,
                               warm[0])
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
    points = body.state
    history = PlasticHistory(body._trial.x.array.copy(), points.trial_sigma.copy(), points.trial_eps_p.copy(),
                             points.trial_p.copy())
    return replace(solved, in_cycle=in_cycle, newton=info, plastic=history,
                   iterations=total["iterations"], local_solves=total["solves"])

def load_plastic(body: ElastoplasticBody, history: PlasticHistory | None) -> None:
    """Make ``history`` the body's committed state (a state may be solved from more than once)."""
    if history is None:
        raise ValueError("this elastic-plastic problem needs a state with its plastic history "
                         "(from initial_state() or commit())")
    body.u.x.array[:] = history.u
    points = body.state
    points.sigma, points.eps_p, points.p = history.sigma.copy(), history.eps_p.copy(), history.p.copy()


def advance(operators: ContactOperators, solve: Callable[..., IncrementResult],
            commit: Callable[[ContactState, IncrementResult], ContactState], state: ContactState, normal=None,
            tangential=None, loads=None, *, in_cycle: bool = False, max_cutbacks: int = 0,
            check: Callable[[ContactState], None] | None = None) -> tuple[ContactState, dict[str, Any]]:
    """Solve and commit one increment, halving it on failure (elastic–plastic bodies).

    A failed try is halved up to ``max_cutbacks`` times (default: ``Plasticity.max_cutbacks``, 0 for
    elastic bodies); each converged sub-increment is committed (wear and plastic history) and the last
    one's record carries the energy and wear added by the earlier ones. Sub-steps interpolate the
    prescribed values (displacements, forces, load factors) between ``state.targets`` and the new ones.

    Args:
        operators: The problem's operators.
        solve, commit: The problem's :meth:`~dolfinx_fretting.problem.FrettingProblem.solve` and
            :meth:`~dolfinx_fretting.problem.FrettingProblem.commit`.
        state, normal, tangential, loads, in_cycle: As :meth:`~dolfinx_fretting.problem.FrettingProblem.solve`.
        max_cutbacks: Halvings allowed.
        check: Called with every committed (sub-)increment's state; an exception it raises aborts the
            increment (the caller keeps ``state``).

    Returns:
        (the new state, the increment's solver columns :data:`~dolfinx_fretting.state.SOLVER_COLUMNS`).

    Raises:
        ConvergenceError: no convergence after the cut-backs (``state`` itself is unchanged).
        WindowError: a node outside the candidate window penetrated (no cut-back: ``state`` is unchanged).
    """
    end_targets, end_controlled = increment_targets(operators, state, normal, tangential)
    end_factors = operators.factors(state, loads)
    start_targets = (state.targets if state.targets is not None else state.obstacle).astype(float)
    start_factors = state.load_factors.copy()
    names = [n for n in operators.load_names if n != "dirichlet values"]
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
        sub_normal, sub_tangential = target_items(operators, targets, end_controlled)
        sub_loads = {n: factors[operators.load_names.index(n)] for n in names}
        try:
            result = solve(current, sub_normal, sub_tangential, sub_loads, in_cycle=in_cycle)
        except WindowError:
            raise  # a smaller step does not widen the window: the caller's (state unchanged)
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
        committed = commit(current, result)
        if check is not None:
            check(committed)
        if done < 1.0:
            current = committed
            sums += (current.record["dissipated_energy"], current.record["wear_area_increment"])
            continue
        info = solver_columns(result, newton_iterations=newton, local_iterations=local_its, cutbacks=cuts)
        record = {**committed.record, **info}
        record["dissipated_energy"] += sums[0]
        record["wear_area_increment"] += sums[1]
        # The sub-increments count as one increment of the caller's path.
        new = replace(committed, record=record, increment=state.increment + 1,
                      local_iterations=state.local_iterations + local_its)
        return new, info
