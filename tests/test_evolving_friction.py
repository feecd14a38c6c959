"""Friction that evolves (``dolfinx_fretting.EvolvingFriction``): mu of the cycles committed or of each contact's
accumulated dissipated energy density, against independent references.

- A constant table is Coulomb: the same forces, slip and wear to the bit (same process, same arithmetic), in the
  compiled loop (one increment per call under the energy variable) and increment by increment.
- mu(N) a step at cycle 2: in every gross-slip increment the tangential force is mu(N) times the normal force
  (Coulomb's Q = mu P, the closed form of gross slip), with mu(N) the table at the cycles committed before it.
- mu(E): each contact's energy follows the hand-integrated recurrence E <- E + mu(E) r_n |dx_t| / A over the
  kept increments (the explicit update: mu from the energy at the increment's start), and every sliding
  contact's tangential force is mu(E) r_n.
- Fouvry's energy law with mu(E): the worn area is still alpha times the dissipated energy.
- A checkpoint holds the cycles and the energy (round trip), and refuses another table; bad tables are refused.
"""

import numpy as np
import pytest
from mpi4py import MPI  # noqa: F401  (before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs)

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import friction  # noqa: E402
from support.blocks import elasticity, plane_above, two_blocks  # noqa: E402

ALPHA = 2e-6   # 1/MPa, as tests/test_energy_wear.py
APPROACH, AMPLITUDE, INCREMENTS = 1e-3, 3e-3, 8   # gross slip: the amplitude is 3x the approach


def pressed_block(mu, wear=None, compiled=True):
    """The left block of ``two_blocks`` under a plane above it, pressed by APPROACH: (problem, contact, state)."""
    V, tags, bcs = two_blocks()
    contact = dfr.Contact(V, (tags, 1), plane_above(), mu=mu, bcs=bcs)
    problem = dfr.FrettingProblem(elasticity(V), contact, bcs, wear=wear,
                                  solver=dfr.LocalSolver(tol=1e-12, compiled_cycles=compiled))
    state, _ = problem.advance(problem.initial_state(), normal=APPROACH)
    return problem, contact, state


def rub(problem, state, cycles, keep=False, amplitude=AMPLITUDE):
    """``cycles`` cycles from ``state`` (gross slip at mu = 0.2): (final state, each cycle's (state it started from,
    result))."""
    path = dfr.CyclePath.waveform(INCREMENTS, tangential=amplitude)
    runs = []
    for _ in range(cycles):
        result = problem.run_cycle(state, path, keep=keep)
        runs.append((state, result))
        state = problem.commit(state, result)
    return state, runs


@pytest.mark.parametrize("variable", ["cycles", "energy"])
@pytest.mark.parametrize("compiled", [True, False])
def test_constant_table_is_coulomb(variable, compiled):
    """A table that stays at 0.5 gives Coulomb(0.5)'s forces, slip and wear exactly: the same arithmetic on the
    same values in one process (the energy variable runs the compiled loop one increment per call)."""
    table = [(0.0, 0.5), (1.0, 0.5)]
    results = []
    for mu in (0.5, dfr.EvolvingFriction(table, variable=variable)):
        problem, _, state = pressed_block(mu, wear=dfr.EnergyWear(ALPHA), compiled=compiled)
        state, runs = rub(problem, state, 2)
        assert runs[-1][1].compiled == compiled
        results.append((state.forces, state.slip, state.wear_gap, state.dissipated_energy, state.cycles))
        problem.destroy()
    coulomb, evolving = results
    assert coulomb[2].max() > 0 and coulomb[4] == evolving[4] == 2.0
    for a, b in zip(coulomb, evolving):
        assert np.array_equal(a, b)


def gross_slip_rows(records):
    """The increments of a cycle in which every loaded contact slid (no stick)."""
    return (records["n_stick"] == 0) & (records["n_slip"] > 0)


@pytest.mark.parametrize("compiled", [True, False])
def test_step_in_cycles_gives_q_equal_mu_p(compiled):
    """mu(N) = 0.2 for N < 2, 0.8 from N = 2 on (linear between the breakpoints 1 and 2, which whole cycles never
    sit between). In gross slip every contact carries mu r_n, so the tangential force is mu(N) P (to 1e-9: the
    local solver's 1e-12 tolerance on forces of order P, summed over ~7 contacts)."""
    law = dfr.EvolvingFriction([(0, 0.2), (1, 0.2), (2, 0.8)], variable="cycles")
    problem, _, state = pressed_block(law, compiled=compiled)
    state, runs = rub(problem, state, 4, amplitude=6 * AMPLITUDE)   # gross slip at mu = 0.8 too
    assert state.cycles == 4.0
    for expected, (start, result) in zip([0.2, 0.2, 0.8, 0.8], runs):
        rows = gross_slip_rows(result.records)
        assert rows.sum() >= 2   # the waveform's peaks slide the whole contact
        Q, P = np.abs(result.records["tangential_force"][rows]), result.records["normal_force"][rows]
        assert Q == pytest.approx(expected * P, rel=1e-9)
        assert np.all(friction.coefficients(problem.contact, start) == expected)
    problem.destroy()


@pytest.mark.parametrize("compiled", [True, False])
def test_energy_follows_the_hand_integrated_recurrence(compiled):
    """mu(E) from 0.2 at E = 0 to 0.8 at E = 0.15 N/mm (a few increments of sliding). Over the kept increments of two
    cycles, each contact's energy is integrated by hand, E_{j+1} = E_j + mu(E_j) r_n |dx_t| / A (mu from the energy
    at the increment's start: the explicit update), and every sliding contact carries |r_t| = mu(E_j) r_n. The
    committed energy (the work -r_t . dx_t) matches the recurrence and the forces mu r_n to 1e-9: the local
    solver's 1e-12 tolerance holds r_t on the cone to ~1e-11 of the forces (measured 4e-12 relative)."""
    table = [(0.0, 0.2), (0.15, 0.8)]
    law = dfr.EvolvingFriction(table, variable="energy")
    problem, contact, state = pressed_block(law, compiled=compiled)
    tributary = contact.contact_set.tributary
    energy = state.friction_energy.copy()
    _, runs = rub(problem, state, 2, keep=True)
    sliding_checked = 0
    for start, result in runs:
        assert start.friction_energy == pytest.approx(energy, rel=1e-9, abs=1e-15)
        forces, slip, _, _, status = result.kept
        for r, x, code in zip(forces, slip, status):
            mu = np.interp(energy, *np.array(table).T)
            rn, rt, xt = r[0::2], r[1::2], x[1::2]
            sliding = code == 2
            assert np.abs(rt[sliding]) == pytest.approx(mu[sliding] * rn[sliding], rel=1e-9)
            sliding_checked += int(sliding.sum())
            energy = energy + mu * rn * np.abs(xt) / tributary
    final = problem.commit(runs[-1][0], runs[-1][1])
    assert sliding_checked > 20 and energy.max() > 0.15   # mu reached its last value somewhere
    assert final.friction_energy == pytest.approx(energy, rel=1e-9, abs=1e-15)
    assert friction.coefficients(contact, final).max() == 0.8
    problem.destroy()


@pytest.mark.parametrize("compiled", [True, False])
def test_energy_wear_identity_with_evolving_mu(compiled):
    """Fouvry's law wears alpha mu p |dx_t| while the contact dissipates mu p |dx_t| per unit area, whatever mu
    is at that increment: the worn area is alpha times the dissipated energy (1e-10, as in test_energy_wear)."""
    law = dfr.EvolvingFriction([(0.0, 0.2), (0.3, 0.8)], variable="energy")
    problem, contact, state = pressed_block(law, wear=dfr.EnergyWear(ALPHA), compiled=compiled)
    state, _ = rub(problem, state, 2)
    area = float(state.wear_gap @ contact.contact_set.tributary)
    mu = friction.coefficients(contact, state)
    assert mu.min() < mu.max() or mu.max() > 0.2   # mu evolved
    assert area == pytest.approx(ALPHA * state.dissipated_energy, rel=1e-10)
    problem.destroy()


def test_checkpoint_round_trip_and_refusal(tmp_path):
    """The cycles and the energy come back (the same token: the same contact data); another table is refused,
    naming both laws."""
    law = dfr.EvolvingFriction([(0.0, 0.2), (0.3, 0.8)], variable="energy")
    problem, _, state = pressed_block(law)
    state, _ = rub(problem, state, 1)
    path = tmp_path / "state.npz"
    problem.save_state(state, path)
    loaded, _ = problem.load_state(path)
    assert loaded.cycles == state.cycles == 1.0
    assert np.array_equal(loaded.friction_energy, state.friction_energy) and state.friction_energy.max() > 0
    assert loaded.token == state.token
    problem.destroy()
    other, _, _ = pressed_block(dfr.EvolvingFriction([(0.0, 0.2), (0.5, 0.8)], variable="energy"))
    with pytest.raises(ValueError, match=r"friction law: saved mu\(energy\) from table \[\[0, 0.2\], \[0.3, 0.8\]\]"):
        other.load_state(path)
    other.destroy()


def test_constant_until_and_at():
    law = dfr.EvolvingFriction([(0, 0.2), (4, 0.2), (5, 0.8)])
    assert law.at(np.array([-1.0, 0.0, 4.5, 9.0])) == pytest.approx([0.2, 0.2, 0.5, 0.8], rel=1e-15)
    # flat up to 4, sloped between 4 and 5, flat past 5
    assert law.constant_until(np.array([1.0, 4.5, 6.0])).tolist() == [4.0, 4.5, np.inf]
    assert dfr.EvolvingFriction(lambda n: 0.2 + 0 * n).constant_until(np.array([3.0])).tolist() == [3.0]
    assert law.coefficients(3).tolist() == [0.2, 0.2, 0.2]


@pytest.mark.parametrize("table, message", [
    ([(0, 0.2), (0, 0.8)], r"row 1 has x = 0: allowed x > 0"),
    ([(0, 0.2), (1, -0.1)], r"row 1 has mu = -0.1: allowed mu >= 0"),
    ([(0, float("nan"))], r"rows \[x, mu\] of two finite numbers"),
    ([], r"rows \[x, mu\] of two finite numbers"),
    ("0.2", r"rows \[x, mu\] of two finite numbers"),
])
def test_bad_tables_are_refused(table, message):
    with pytest.raises(ValueError, match=r"EvolvingFriction\.mu = .*" + message):
        dfr.EvolvingFriction(table)


def test_bad_variable_and_function_are_refused():
    with pytest.raises(ValueError, match="EvolvingFriction.variable = 'time': allowed cycles, energy"):
        dfr.EvolvingFriction([(0, 0.2)], variable="time")
    with pytest.raises(ValueError, match="the function gave .*finite coefficient >= 0"):
        dfr.EvolvingFriction(lambda n: -0.1 + 0 * n)
