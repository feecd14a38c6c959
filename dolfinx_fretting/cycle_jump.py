"""Error-controlled cycle jumping: simulate a cycle, extrapolate the wear gap over ``dN`` cycles, repeat.

Pure NumPy, no mesh. Over many cycles the wear gap follows the cycle map::

    g(N + 1) = g(N) + dg(g(N)),      dg_a = k sum_j p_a^j |dx_t,a^j|     (Archard summed over a cycle),

and a jump is its explicit Euler step of length ``dN``: ``g <- g + dN dg``, with ``dg`` from the cycle just
simulated with the real k (that cycle is the first of the ``dN`` it stands for).

**Stability.** On the loaded contacts A_j of increment j the gaps are closed, x_n = W_AA r_n + q_n = 0, and
the wear gap enters q_n, so the pressure responds to a wear-gap perturbation as ::

    dp^j / dg = -T_A^-1 (W_AA^j)^-1          (T the tributary lengths; normal-normal block of W),

(under normal force control, the uniform approach of the obstacle is an unknown too and the rigid mode
is projected out: ``W^-1 - W^-1 e e^T W^-1 / (e^T W^-1 e)``). With the slip of each sliding contact held,
a perturbation ``e`` of g changes the cycle's wear by ``-k L e``, ::

    L = sum_j S^j T^-1 (W_AA^j)^-1,          S^j = diag(|dx_t^j|) on the sliding contacts,

so a jump multiplies ``e`` by ``I - dN k L``. Every mode decays without changing sign for
``dN <= 1 / (k rho(L))`` (the *monotone limit*, which the automatic choice never exceeds); past
``2 / (k rho(L))`` (the *stability limit*) the mode of L's largest eigenvalue, a node-to-node zigzag of
the pressure concentrated where the contact is stiffest (the edges), grows at every jump: the spurious
oscillating edge spikes. For a cylinder on an elastic half-space that mode is the pressure
``cos(pi x / h)`` with ``dp/dg = pi E* / (2 h)``, and a gross-slip triangular cycle slides ``4 delta``, so
``2 / (k rho) ~ h / (pi k delta E*) = 0.32 h / (k delta E*)``: the 0.37 h/(k delta E*) of the literature.

**Step.** ``dN`` is the largest whole number with: wear added by the jump ``dN max(dg) <= f_w h`` (contact
element size h), predicted pressure change ``dN max_j |dp^j/dg dg| <= f_p max p``, ``dN <= 1/(k rho(L))``,
``dN <= 2 dN_previous`` (the rate is known only at the start of a jump), ``dN <= max_jump``, and landing on
the next cycle that must be simulated (snapshots, the last cycle).

**Error tolerance** (``wear.jump_tolerance``, :func:`tolerance_jump_limit`). Instead of the pressure bound, the
jump can be chosen from the error estimate below: the rate's drift per cycle over the last jump,
``d = |rate - rate_before| / dN_previous``, predicts a jump's local error ``(dN - 1) dN max(d)`` (quadratic in dN),
held to ``tolerance`` times the wear the jump adds, ``dN max(rate)`` (linear in dN), so
``dN <= 1 + tolerance max(rate) / max(d)``: long jumps where the rate is steady, short ones where it moves. The
other bounds stay (wear per jump, monotone limit, doubling, landings, ``max_jump``, plastic). No drift is read
from cycle 1 to the next (cycle 1 starts from the preload): the doubling holds the first jump.

The first cycle is never jumped from: it starts from the preload's tangential state, so its slip path,
and its wear, differ from those of the cycles that follow.

**Error estimate.** The next simulated cycle gives the rate at the end of the jump. If each contact's rate
moves monotonically between the two ends, the Euler step misses at most ``(dN - 1) |dg_end - dg_start|``
over the ``dN - 1`` extrapolated cycles (twice the trapezoidal correction, which is the exact error for a
rate linear in N): the jump's *local error* ``e = (dN - 1)(dg_start - dg_end)`` per contact, signed (the jumped
gap minus the true one, at worst). Its maximum over the contacts is the jump's error estimate
(:func:`jump_error`); their sum over the jumps bounds the accumulated error in the wear gap only if errors
neither cancel nor heal, and measured they heal: a contact worn too deep carries less pressure and wears less
afterwards (the same feedback as the stability analysis). That sum was 7-70x the measured error on the
built-in scenes. The run's estimate (:func:`propagate_error`) therefore carries the accumulated error
``E`` per contact through the linearised map, ::

    E <- (I - dN k L) (E + e)        at each simulated cycle (its L, its jump dN; e: the jump before it),

what a wear-gap error does over the dN cycles the jump stands for (the simulated cycle among them), and reports
``max |E|``. It keeps e's worst case (not the trapezoidal half), and a uniform error (under normal force control
a mode that does not heal, L e = 0) stays whole. Measured against every-cycle runs it stays above the error and
within 10x of it (``benchmarks/results/cycle_jump.md``). When the contact set changes (a window growth) the
per-contact E cannot follow: its maximum and the jump's bound are added to a part that is no longer propagated.


**Elastic–plastic bodies** (the runner, ``simulation._Run._jump``, calls :func:`analyse_plastic_cycle` after
every simulated cycle). A jump extrapolates the plastic internal variables as it does the wear gap: the
plastic strain and accumulated plastic strain at the end of the simulated cycle plus dN - 1 times the
cycle's change, with the same error estimate on their rates; the stress moves by the plastic strain added
and the displacement is kept (:func:`extrapolate_plastic_history`); in elastic shakedown nothing plastic
is extrapolated. Three regimes, by the cycle's largest
plastic flow (increase of the accumulated plastic strain p) and net plastic strain (change of eps_p over the
cycle) against a tolerance: *elastic shakedown* (no flow: nothing to extrapolate, and the elastic W of the
stability limit is the body's exact compliance), *plastic shakedown* (flow, but a closed loop of eps_p: p
grows, and with it the yield stress under hardening) and *ratcheting* (eps_p drifts every cycle). The jump
is bounded so that the extrapolated net plastic strain stays within a fraction of the yield strain and the
hardening within the same fraction of the yield stress (:func:`plastic_jump_limit`). Ratcheting is not
refused: its jumps are held by that bound (on the paper's Example 2 at 10 um, to 20-120 cycles once the first
cycles' flow has decayed), and the jump's error on the plastic strains (:func:`plastic_jump_error`) is
accumulated and reported beside the wear gap's. In elastic shakedown the plastic state does not bound the
jump: only the wear does. After a jump of a flowing body the runner simulates a settling cycle before the
next jump unless the plastic changes match those before the jump (``simulation._Run._plastic_bounds``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from mpi4py import MPI

__all__ = ["CycleAnalysis", "PlasticCycle", "analyse_cycle", "analyse_plastic_cycle", "choose_jump",
           "cycle_wear", "extrapolate", "extrapolate_plastic_history", "jump_error", "hertz_jump_limit",
           "local_jump_error", "plastic_jump_error", "plastic_jump_limit", "propagate_error",
           "tolerance_jump_limit"]

_OPEN = 0
_SLIP = 2


@dataclass
class CycleAnalysis:
    """What a simulated cycle says about the next jump.

    Attributes:
        rate: Wear-gap increment of the cycle per contact (mm per cycle).
        rho: Spectral radius of the linearised wear map L (1/MPa^-1 per cycle: ``k rho`` is per cycle).
        pressure_rate: Largest predicted pressure change per cycle over the contacts and increments (MPa).
        peak_pressure: Largest pressure of the cycle (MPa).
        wear_map: The linearised wear map L (nc x nc, k factored out: a wear-gap change e changes the cycle's
            wear by ``-k L e``); None: not formed.
    """

    rate: np.ndarray
    rho: float
    pressure_rate: float
    peak_pressure: float
    wear_map: np.ndarray | None = None

    def monotone_limit(self, k: float) -> float:
        """Largest jump with no sign change of any mode, ``1 / (k rho)`` (inf without wear)."""
        return 1.0 / (k * self.rho) if k * self.rho > 0 else math.inf

    def stability_limit(self, k: float) -> float:
        """Largest jump that does not amplify the zigzag mode, ``2 / (k rho)`` (inf without wear)."""
        return 2.0 / (k * self.rho) if k * self.rho > 0 else math.inf


def _normal_compliance_inverse(Wnn: np.ndarray, active: np.ndarray, force_controlled: bool) -> np.ndarray:
    """(W_AA)^-1 on the loaded contacts, with the uniform approach projected out under force control."""
    S = np.linalg.inv(Wnn[np.ix_(active, active)])
    if force_controlled:
        Se = S.sum(axis=1)
        S = S - np.outer(Se, Se) / Se.sum()
    return S


def analyse_cycle(W: np.ndarray, dim: int, tributary: np.ndarray, states: np.ndarray, x: np.ndarray,
                  r: np.ndarray, gw_start: np.ndarray, gw_end: np.ndarray,
                  normal_force_controlled: bool = False) -> CycleAnalysis:
    """Linearised wear map of a simulated cycle: its spectral radius and the pressure change it drives.

    Args:
        W: Delassus matrix (nc dim x nc dim), normal rows first in each contact block.
        dim: 2 or 3.
        tributary: Tributary length (area) per contact.
        states: Contact states per increment of the cycle, shape (n, nc) (0 open, 1 stick, 2 slip).
        x: Local solutions per increment, shape (n, nc dim) (tangential rows: slip increments).
        r: Contact forces per increment, shape (n, nc dim).
        gw_start: Wear gap before the cycle.
        gw_end: Wear gap after the cycle.
        normal_force_controlled: The normal load is a prescribed force (the approach is free).

    Returns:
        The cycle's :class:`CycleAnalysis`.
    """
    nc = tributary.size
    Wnn = W[0::dim, 0::dim]
    rate = np.asarray(gw_end - gw_start, dtype=float)
    L = np.zeros((nc, nc))
    dp_max = 0.0
    cache: dict[bytes, np.ndarray] = {}
    for j in range(states.shape[0]):
        active = states[j] != _OPEN
        if not active.any():
            continue
        key = active.tobytes()
        S = cache.get(key)
        if S is None:
            S = cache[key] = _normal_compliance_inverse(Wnn, active, normal_force_controlled)
        idx = np.flatnonzero(active)
        sliding = states[j, idx] == _SLIP
        slip = np.linalg.norm(x[j].reshape(nc, dim)[idx, 1:], axis=1) * sliding
        # Row a of L: the change of contact a's wear per unit wear gap elsewhere (k factored out).
        L[np.ix_(idx, idx)] += (slip / tributary[idx])[:, None] * S
        dp = (S @ rate[idx]) / tributary[idx]
        dp_max = max(dp_max, float(np.abs(dp).max(initial=0.0)))
    rho = float(np.abs(np.linalg.eigvals(L)).max(initial=0.0)) if L.any() else 0.0
    p = r[:, 0::dim] / tributary
    return CycleAnalysis(rate, rho, dp_max, float(p.max(initial=0.0)), L)


def choose_jump(analysis: CycleAnalysis, k: float, element_size: float, wear_fraction: float,
                pressure_fraction: float | None, max_jump: int, previous: int, room: int,
                plastic_limit: float = math.inf, tolerance_limit: float = math.inf) -> tuple[int, str, int]:
    """The jump after a simulated cycle: the largest ``dN`` within every bound (see the module docstring).

    Args:
        analysis: The simulated cycle's analysis.
        k: Wear coefficient of a simulated cycle (1/MPa).
        element_size: Contact element size h (mm).
        wear_fraction: f_w, wear per jump as a fraction of h.
        pressure_fraction: f_p, pressure change per jump as a fraction of the cycle's peak pressure (None: no
            pressure bound; the error tolerance's bound takes its place).
        max_jump: Upper bound on ``dN``.
        previous: The previous jump (``dN`` may at most double).
        room: Cycles until the next cycle that must be simulated (``dN <= room``).
        plastic_limit: An elastic–plastic body's bound (:func:`plastic_jump_limit`; inf: none).
        tolerance_limit: The error tolerance's bound (:func:`tolerance_jump_limit`; inf: none).

    Returns:
        ``(dN, bound, free)``: the jump (>= 1), the name of the bound that set it, and the jump the bounds
        other than ``room`` allow (the next call's ``previous``, so that landing on a snapshot does not
        restart the growth).
    """
    wmax = float(analysis.rate.max(initial=0.0))
    bounds = {
        "wear": wear_fraction * element_size / wmax if wmax > 0 else math.inf,
        "pressure": pressure_fraction * analysis.peak_pressure / analysis.pressure_rate
        if pressure_fraction is not None and analysis.pressure_rate > 0 else math.inf,
        "tolerance": float(tolerance_limit),
        "stability": analysis.monotone_limit(k),
        "growth": 2.0 * max(previous, 1),
        "max_jump": float(max_jump),
        "plastic": float(plastic_limit),
    }
    free_name = min(bounds, key=bounds.get)
    free = max(1, int(math.floor(bounds[free_name] * (1 + 1e-12))))
    if room < free:
        return max(1, room), "landing", free
    return free, free_name, free


def tolerance_jump_limit(rate_before: np.ndarray | None, rate: np.ndarray, previous: int,
                         tolerance: float) -> float:
    """Largest jump whose predicted local error is at most ``tolerance`` times the wear it adds (the error
    tolerance's bound of :func:`choose_jump`; inf when no drift of the rate is known yet or none is seen).

    The rate of each contact drifted by ``|rate - rate_before|`` over the ``previous`` cycles between the two
    simulated cycles; at that drift per cycle ``d`` a jump of ``dN`` cycles has the local error
    (:func:`local_jump_error`) ``(dN - 1) dN d`` at worst (its rate at the end has moved by ``dN d``), and the
    jump adds ``dN max(rate)``. So ``(dN - 1) max(d) <= tolerance max(rate)``:
    ``dN <= 1 + tolerance max(rate) / max(d)``: the error grows with the square of the jump, the wear it adds
    linearly. Each jump's estimated error is then a fraction ``tolerance`` of the wear it adds, and their sum over
    the run at most ``tolerance`` times the sum over the jumps of the largest wear each adds (the deepest wear
    when the deepest contact wears fastest); the run's propagated estimate heals below that.

    Args:
        rate_before: Wear-gap increment per contact of the previous simulated cycle (None: none, e.g. after a
            window growth).
        rate: That of the cycle just simulated.
        previous: The jump taken from the previous simulated cycle (the cycles between the two).
        tolerance: The allowed local error per jump as a fraction of the wear the jump adds.
    """
    if rate_before is None:
        return math.inf
    drift = float(np.abs(np.asarray(rate, dtype=float) - np.asarray(rate_before, dtype=float)).max(initial=0.0))
    drift /= max(previous, 1)
    wear = float(np.max(rate, initial=0.0))
    if drift <= 0.0 or wear <= 0.0:
        return math.inf
    return 1.0 + tolerance * wear / drift


def jump_error(rate_start: np.ndarray, rate_end: np.ndarray, jump: int) -> float:
    """Error bound of a jump of ``jump`` cycles (mm) for rates monotone over it:
    ``(jump - 1) max |rate_end - rate_start|``."""
    if jump <= 1:
        return 0.0
    return (jump - 1) * float(np.abs(rate_end - rate_start).max(initial=0.0))


def cycle_wear(coefficients: np.ndarray, tributary: np.ndarray, forces: np.ndarray, solutions: np.ndarray,
               states: np.ndarray, dim: int) -> np.ndarray:
    """The wear-gap increment of a simulated cycle per contact from its kept increments, by the wear law in its
    rate form: the sum over the increments of ``c p |dx_t|`` at the sliding contacts, ``dx_t`` *both* tangential
    rows in 3D (a stroke along t2 or a diagonal wears as one along t1).

    Args:
        coefficients: Each contact's rate ``c`` in cycles (Archard's k or the energy law's alpha mu, with the
            acceleration: :meth:`~dolfinx_fretting.problem.FrettingProblem.wear_coefficients`).
        tributary: Tributary length (area) per contact.
        forces, solutions: Contact forces r and local solutions x per increment, shape (n, nc dim) (tangential rows
            of x: the slip increments).
        states: Contact states per increment, (n, nc) (2: slip).
        dim: 2 or 3.
    """
    n, nc = states.shape
    slip = np.asarray(solutions, dtype=float).reshape(n, nc, dim)[:, :, 1:]
    pressure = np.asarray(forces, dtype=float)[:, 0::dim] / tributary
    wear = np.asarray(coefficients, dtype=float) * pressure * np.linalg.norm(slip, axis=-1)
    return (wear * (states == _SLIP)).sum(axis=0)


def local_jump_error(rate_start: np.ndarray, rate_end: np.ndarray, jump: int) -> np.ndarray:
    """A jump's local error per contact, signed, at worst for rates monotone over it (mm): the jumped wear gap minus
    the true one, ``(jump - 1) (rate_start - rate_end)`` (:func:`jump_error` is its maximum magnitude)."""
    if jump <= 1:
        return np.zeros(np.shape(rate_end))
    return (jump - 1) * (np.asarray(rate_start, dtype=float) - np.asarray(rate_end, dtype=float))


def propagate_error(error: np.ndarray, analysis: CycleAnalysis, k: float, jump: int) -> np.ndarray:
    """An accumulated wear-gap error per contact carried over a simulated cycle and its jump of ``jump`` cycles:
    ``(I - jump k L) error`` (``L``: the cycle's :attr:`CycleAnalysis.wear_map`), the change the explicit update
    makes to a perturbation of the gap (the cycle is the first of the ``jump``). Within the monotone limit every
    mode of L shrinks without changing sign; its kernel (a uniform error under normal force control) stays."""
    error = np.asarray(error, dtype=float)
    if analysis.wear_map is None or k == 0.0 or not analysis.wear_map.any():
        return error.copy()
    return error - (jump * k) * (analysis.wear_map @ error)


def hertz_jump_limit(element_size: float, k: float, slip_amplitude: float, E_star: float) -> float:
    """The literature's estimate of the jump past which edge spikes appear, ``0.37 h / (k delta E*)``."""
    return 0.37 * element_size / (k * slip_amplitude * E_star)


# Elastic-plastic bodies ----------------------------------------------------------------------------------
_SQRT_2_3 = math.sqrt(2.0 / 3.0)


@dataclass
class PlasticCycle:
    """What a simulated cycle did to the plastic state.

    Attributes:
        flow: Largest increase of the accumulated equivalent plastic strain p over the cycle (every rank's
            points when analysed with a communicator).
        net: Largest equivalent net plastic strain of the cycle, ``sqrt(2/3) |eps_p(end) - eps_p(start)|``
            (Mandel vectors: the tensor norm; a uniaxial plastic strain e gives e).
        regime: ``"elastic_shakedown"`` (flow <= tol), ``"plastic_shakedown"`` (net <= tol < flow: a closed
            loop of plastic strain) or ``"ratcheting"`` (net > tol).
        d_eps_p: This rank's change of eps_p over the cycle per point, (n, 6).
        d_p: This rank's change of p over the cycle per point, (n,).
    """

    flow: float
    net: float
    regime: str
    d_eps_p: np.ndarray
    d_p: np.ndarray


def _global_max(value: float, comm) -> float:
    return float(value if comm is None or comm.size == 1 else comm.allreduce(value, op=MPI.MAX))


def analyse_plastic_cycle(eps_p_start: np.ndarray, p_start: np.ndarray, eps_p_end: np.ndarray,
                          p_end: np.ndarray, tol: float, comm=None) -> PlasticCycle:
    """The plastic regime of a simulated cycle from the committed plastic state at its start and its end.

    The runner calls it after each simulated cycle of an elastic–plastic body (with the committed
    quadrature-point arrays of ``ContactState.plastic``), extrapolates the plastic history over a jump with
    :func:`extrapolate_plastic_history`, bounds the jump with :func:`plastic_jump_limit`
    (``choose_jump(..., plastic_limit=...)``), adds :func:`plastic_jump_error` to the run's plastic error and
    writes the regime into ``cycles.csv``; collective when ``comm`` has several ranks.

    Args:
        eps_p_start, p_start: Plastic strain (n, 6) and accumulated plastic strain (n,) at the cycle's start.
        eps_p_end, p_end: The same at its end.
        tol: Plastic strain below which a change counts as none (e.g. 1e-3 x the yield strain).
        comm: Communicator of a distributed state (None: these arrays are all the points).

    Returns:
        The cycle's :class:`PlasticCycle`.
    """
    d_eps_p = np.asarray(eps_p_end, dtype=float) - np.asarray(eps_p_start, dtype=float)
    d_p = np.asarray(p_end, dtype=float) - np.asarray(p_start, dtype=float)
    flow = _global_max(float(d_p.max(initial=0.0)), comm)
    net = _global_max(_SQRT_2_3 * float(np.linalg.norm(d_eps_p, axis=1).max(initial=0.0)), comm)
    regime = "elastic_shakedown" if flow <= tol else ("plastic_shakedown" if net <= tol else "ratcheting")
    return PlasticCycle(flow, net, regime, d_eps_p, d_p)


def plastic_jump_limit(cycle: PlasticCycle, fraction: float, yield_stress: float, E: float,
                       hardening: float) -> float:
    """Largest jump whose extrapolated plastic state moves by at most ``fraction`` of the yield point: net
    plastic strain ``dN net <= fraction sigma_y / E`` and hardening ``dN H flow <= fraction sigma_y``
    (inf in elastic shakedown).

    Args:
        cycle: The simulated cycle's :class:`PlasticCycle`.
        fraction: The allowed move per jump, as a fraction of the yield strain and stress.
        yield_stress, E, hardening: sigma_y0, Young's modulus, the linear isotropic hardening modulus H.
    """
    if cycle.regime == "elastic_shakedown":
        return math.inf
    strain = fraction * yield_stress / E / cycle.net if cycle.net > 0 else math.inf
    harden = fraction * yield_stress / (hardening * cycle.flow) if hardening * cycle.flow > 0 else math.inf
    return min(strain, harden)


def extrapolate(start: np.ndarray, end: np.ndarray, jump: int) -> np.ndarray:
    """A field at the end of the simulated cycle plus ``jump - 1`` times its change over it: the explicit Euler
    step of a jump of ``jump`` cycles (the simulated cycle is the first of them), as for the wear gap."""
    end = np.asarray(end, dtype=float)
    return end + (jump - 1) * (end - np.asarray(start, dtype=float))


def extrapolate_plastic_history(sigma_end: np.ndarray, eps_p_start: np.ndarray, eps_p_end: np.ndarray,
                                p_start: np.ndarray, p_end: np.ndarray, jump: int,
                                stiffness: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The plastic history after a jump: the internal variables eps_p and p by the explicit Euler step of
    :func:`extrapolate`, and the stress moved by the plastic strain added, ``sigma - C d_eps_p`` (the strain kept).

    Only the variables with a memory are extrapolated. The displacement and the stress's elastic part follow the
    loads, the wear gap and eps_p; extrapolating them too (as the wear gap) amplifies by ``jump - 1`` the
    re-equilibration the cycle after each jump makes, with a flip of sign: a run of 43- to 48-cycle jumps in
    elastic shakedown on the paper's Example 2 grew it until Newton failed (4346 points yielding at once, cycle
    7746). Kept, the next cycle's first Newton iteration restores equilibrium.

    Args:
        sigma_end: Stress at the end of the simulated cycle, (n, 6) Mandel.
        eps_p_start, eps_p_end: Plastic strain at its start and end, (n, 6) Mandel.
        p_start, p_end: Accumulated plastic strain at its start and end, (n,).
        jump: The jump (cycles; the simulated cycle is the first).
        stiffness: The elasticity matrix C, (6, 6) Mandel (``materials.elastic_stiffness``).

    Returns:
        (sigma, eps_p, p) after the jump.
    """
    added = (jump - 1) * (np.asarray(eps_p_end, dtype=float) - np.asarray(eps_p_start, dtype=float))
    return (np.asarray(sigma_end, dtype=float) - added @ np.asarray(stiffness).T, eps_p_end + added,
            extrapolate(p_start, p_end, jump))


def plastic_jump_error(previous: PlasticCycle, current: PlasticCycle, jump: int, comm=None) -> tuple[float, float]:
    """Error bounds of a jump for rates monotone over it, as :func:`jump_error` for the wear gap: the
    equivalent plastic strain ``(jump - 1) max sqrt(2/3) |d_eps_p(end) - d_eps_p(start)|`` and the accumulated
    plastic strain ``(jump - 1) max |d_p(end) - d_p(start)|`` (``previous``: the cycle simulated before the
    jump, ``current``: the one after it)."""
    if jump <= 1:
        return 0.0, 0.0
    de = _SQRT_2_3 * float(np.linalg.norm(current.d_eps_p - previous.d_eps_p, axis=1).max(initial=0.0))
    dp = float(np.abs(current.d_p - previous.d_p).max(initial=0.0))
    return (jump - 1) * _global_max(de, comm), (jump - 1) * _global_max(dp, comm)
