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

import tomllib
from types import SimpleNamespace

import numpy as np
import pytest
from mpi4py import MPI  # noqa: F401  (before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs)

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import cycles as cycles_module  # noqa: E402
from dolfinx_fretting import friction  # noqa: E402
from dolfinx_fretting.scenes import SceneError, builtin_scenes, load_scene  # noqa: E402
from dolfinx_fretting.simulation import run_scene  # noqa: E402
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


def _one_zone(law, nc):
    """What friction.jump_limit reads of a contact: its zones' laws and their rows."""
    return SimpleNamespace(zones=(SimpleNamespace(friction=law),), zone_slice=lambda zone: slice(0, nc),
                           mu=np.full(nc, 0.2))


def test_jump_limit_keeps_mu_constant_over_the_jumped_cycles():
    """A jump extrapolates the simulated cycle's rate, so it may not carry the variable past where mu changes.
    Cycles: mu flat up to 10, from cycle 4 (acceleration 2) the jump may reach 1 + (10 - 4) / 2 = 4 cycles; on the
    slope, 1. Energy: per-cycle energies 0.01 and 0.02 from 0.02 and 0.04 below the flat's end 0.1: the extrapolated
    cycles' energy must stay <= 0.1: floor(min(0.08 / 0.01, 0.06 / 0.02)) = 3. Coulomb: no bound."""
    cycles_law = dfr.EvolvingFriction([(0, 0.2), (10, 0.2), (20, 0.8)], variable="cycles")
    start = SimpleNamespace(cycles=4.0, friction_energy=None)
    assert friction.jump_limit(_one_zone(cycles_law, 2), start, None, 2.0) == 4.0
    assert friction.jump_limit(_one_zone(cycles_law, 2), SimpleNamespace(cycles=12.0), None, 1.0) == 1.0
    assert friction.jump_limit(_one_zone(cycles_law, 2), SimpleNamespace(cycles=25.0), None, 1.0) == np.inf
    energy_law = dfr.EvolvingFriction([(0, 0.2), (0.1, 0.2), (0.2, 0.8)], variable="energy")
    start = SimpleNamespace(cycles=0.0, friction_energy=np.array([0.02, 0.04, 0.0]))
    end = SimpleNamespace(cycles=1.0, friction_energy=np.array([0.03, 0.06, 0.0]))   # the third does not slide
    assert friction.jump_limit(_one_zone(energy_law, 3), start, end, 1.0) == 3.0
    assert friction.jump_limit(_one_zone(0.2, 3), start, end, 1.0) == np.inf
    function_law = dfr.EvolvingFriction(lambda n: 0.2 + 0 * n, variable="cycles")
    assert friction.jump_limit(_one_zone(function_law, 1), SimpleNamespace(cycles=3.0), None, 1.0) == 1.0


def test_scene_tables():
    """``contact.mu_table`` and ``contact.mu_variable`` make the contact's law; ``contact.mu`` becomes the table's
    starting coefficient (the cylinder-flat scene sets mu = 0.9: a table starting elsewhere needs contact.mu too); bad
    tables name the key, the value and the allowed range."""
    scene = load_scene("cylinder-flat", ["contact.mu=0.2", "contact.mu_table=[[0, 0.2], [5, 0.8]]",
                                 "contact.mu_variable='energy'"])
    assert scene.contact.mu == 0.2
    data = tomllib.loads(builtin_scenes()["cylinder-flat"].read_text(encoding="utf-8"))
    data["contact"] = {key: value for key, value in data["contact"].items() if key != "mu"}
    unset = load_scene({**data, "contact": {**data["contact"], "mu_table": [[1.0, 0.3], [5.0, 0.8]]}})
    assert unset.contact.mu == 0.3   # filled in: the table's coefficient at x = 0 (held below its first row)
    law = scene.contact.friction_law()
    assert isinstance(law, dfr.EvolvingFriction) and law.variable == "energy"
    assert law.at(np.array([2.5])) == pytest.approx([0.5], rel=1e-15)
    assert load_scene("cylinder-flat").contact.friction_law() == load_scene("cylinder-flat").contact.mu
    for override, message in [  # (with contact.mu unset below: the table is checked first)
        ("contact.mu_table=[[0, 0.2], [0, 0.8]]", r"contact\.mu_table = .*row 1 has x = 0: allowed x > 0"),
        ("contact.mu_table=[[0, 0.2], [1, -0.8]]", r"contact\.mu_table = .*row 1 has mu = -0\.8: allowed mu >= 0"),
        ("contact.mu_table=[[0, 0.2, 1]]", r"contact\.mu_table = .*rows \[x, mu\] of two finite numbers"),
    ]:
        with pytest.raises(SceneError, match=message):
            load_scene("cylinder-flat", ["contact.mu=0.2", override])
    with pytest.raises(SceneError, match=r"contact\.mu = 0\.9 is out of range; allowed: unset, or 0\.2"):
        load_scene("cylinder-flat", ["contact.mu_table=[[0, 0.2], [5, 0.8]]"])
    with pytest.raises(SceneError, match=r"contact\.mu_variable"):
        load_scene("cylinder-flat", ["contact.mu=0.2", "contact.mu_table=[[0, 0.2], [5, 0.8]]", "contact.mu_variable='time'"])


def test_scene_run_with_jumps_holds_mu_over_each_jump(tmp_path):
    """A cylinder on a rigid flat in gross slip (the compiled loop), mu(N) = 0.5 up to cycle 3, 0.9 from cycle 4,
    with forced jumps of 4: cycle 1 is simulated (never jumped from), cycle 2 jumps only 3 (to cycle 4, the last
    with mu(3) = 0.5: ``jump_bound = friction_evolving``), cycle 5 is simulated with mu(4) = 0.9 and jumps to the
    last cycle. In every gross-slip increment of history.csv, |Q| = mu(N) P (1e-6: the scene's local solver
    tolerance, 1e-8 relative on the forces, summed over the contact)."""
    scene = load_scene("cylinder-flat", [
        "loading.normal_force=none", "loading.normal_displacement=0.0045", "geometry.contact_mesh_size=0.04",
        "loading.increments_per_cycle=8", "loading.cycles=8", "wear.k=8.5e-8", "wear.cycle_jump=true",
        "wear.jump_forced=4", "output.xdmf=false", "output.plots=false", "output.history_every=1",
        "contact.mu=0.5", "contact.mu_table=[[0, 0.5], [3, 0.5], [4, 0.9]]"])
    summary = run_scene(scene, tmp_path / "run", quiet=True)
    assert summary["converged"] and summary["cycles"] == 8
    cycles = np.genfromtxt(tmp_path / "run" / "cycles.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    jumps = dict(zip(cycles["cycle"].tolist(), zip(cycles["jump"].tolist(), cycles["jump_bound"].tolist())))
    assert jumps == {1: (1, "first_cycle"), 2: (3, "friction_evolving"), 5: (3, "forced"), 8: (1, "forced")}
    history = np.genfromtxt(tmp_path / "run" / "history.csv", delimiter=",", names=True, dtype=None,
                            encoding="utf-8")
    checked = 0
    for cycle, mu in ((1, 0.5), (2, 0.5), (5, 0.9), (8, 0.9)):
        rows = (history["cycle"] == cycle) & (history["n_stick"] == 0) & (history["n_slip"] > 0)
        assert rows.sum() >= 2
        ratio = np.abs(history["tangential_force"][rows]) / history["normal_force"][rows]
        assert ratio == pytest.approx(mu, rel=1e-6)
        checked += int(rows.sum())
    assert checked >= 8
    # cycles.csv: mu at each row's end (the cycle and its jump: equivalent_cycles), uniform over the zone, the table
    # interpolated by hand (exact: the table's values at integer cycles)
    table_mu = np.interp(cycles["equivalent_cycles"], [0.0, 3.0, 4.0], [0.5, 0.5, 0.9])
    assert table_mu.tolist() == [0.5, 0.9, 0.9, 0.9]
    for name in ("mu_mean", "mu_min", "mu_max"):
        assert cycles[name] == pytest.approx(table_mu, rel=1e-12), name
    assert summary["friction"] == pytest.approx({"mu_mean": 0.9, "mu_min": 0.9, "mu_max": 0.9}, rel=1e-12)


def test_cycles_table_gives_mu_at_each_cycles_end(tmp_path):
    """mu(E) through FrettingWriter: each cycles.csv row has the coefficients at its cycle's end, over the contacts
    with a normal force: the table interpolated by hand at each contact's accumulated energy, their min, max and
    mean weighted by the normal force (1e-9: the table's 10 digits); by default the cycle's own end (result.final,
    the state commit returns). A constant law writes no mu column (its cycles.csv is unchanged)."""
    table = [(0.0, 0.2), (0.1, 0.5), (0.3, 0.8)]
    problem, _, state = pressed_block(dfr.EvolvingFriction(table, variable="energy"))
    end, runs = rub(problem, state, 2)
    writer = dfr.FrettingWriter(problem, tmp_path / "evolving", profiles=False, fields=False)
    ends = [runs[1][0], end]
    writer.write_cycle(1, *runs[0], end=ends[0])
    writer.write_cycle(2, *runs[1])   # default: result.final
    writer.close()
    rows = np.genfromtxt(tmp_path / "evolving" / "cycles.csv", delimiter=",", names=True, dtype=None,
                         encoding="utf-8")
    x, mu = np.array(table).T
    for row, state_at_end in zip(rows, ends):
        normal = state_at_end.forces.reshape(-1, 2)[:, 0]
        loaded = normal > 0
        coefficients = np.interp(state_at_end.friction_energy, x, mu)[loaded]
        assert loaded.any() and np.ptp(coefficients) > 0.01   # mu differs over the contact
        assert row["mu_min"] == pytest.approx(coefficients.min(), rel=1e-9)
        assert row["mu_max"] == pytest.approx(coefficients.max(), rel=1e-9)
        assert row["mu_mean"] == pytest.approx((coefficients * normal[loaded]).sum() / normal[loaded].sum(), rel=1e-9)
    problem.destroy()
    problem, _, state = pressed_block(0.2)
    end, runs = rub(problem, state, 1)
    writer = dfr.FrettingWriter(problem, tmp_path / "constant", profiles=False, fields=False)
    writer.write_cycle(1, *runs[0])
    writer.close()
    header = (tmp_path / "constant" / "cycles.csv").read_text().splitlines()[0]
    assert "mu_mean" not in header
    problem.destroy()


def test_window_change_carries_the_energy_by_node():
    """Another window carries each contact's accumulated energy by node: narrowed, the kept nodes keep theirs;
    widened again, the nodes back in start at 0 (as a new candidate: it has dissipated nothing here), and mu
    follows the law at the carried values (exact: copies)."""
    law = dfr.EvolvingFriction([(0.0, 0.2), (0.15, 0.8)], variable="energy")
    problem, _, state = pressed_block(law)
    state, _ = rub(problem, state, 1)
    nodes = problem.contact.contact_set.global_nodes.tolist()
    before = dict(zip(nodes, state.friction_energy.tolist()))
    assert min(before.values()) > 0
    narrow = problem.set_window(state, 0.3)
    kept = dict(zip(problem.contact.contact_set.global_nodes.tolist(), narrow.friction_energy.tolist()))
    assert 0 < len(kept) < len(before) and all(kept[node] == before[node] for node in kept)
    wide = problem.set_window(narrow, None)
    back = dict(zip(problem.contact.contact_set.global_nodes.tolist(), wide.friction_energy.tolist()))
    assert back == {node: kept.get(node, 0.0) for node in nodes}
    assert np.array_equal(friction.coefficients(problem.contact, wide), law.at(wide.friction_energy))
    problem.destroy()


def test_scene_tables_of_further_zones_and_force_control():
    """A further ``[[contact]]`` table takes its own table (messages name ``contact[i]``); a prescribed tangential
    force must stay below the table's smallest coefficient times P (it must be carried all along)."""
    data = {"name": "corner", "geometry": {"kind": "file", "path": "block.msh"}, "boundary": {"fixed": ["top"]},
            "contact": [{"surface": "floor", "mu": 0.5},
                        {"surface": "wall", "plane_point": [1.0, 0.0], "plane_normal": [-1.0, 0.0],
                         "mu_table": [[0, 0.3], [2, 0.1], [1, 0.2]]}],
            "loading": {"normal_force": 1.0, "normal_increments": 1},
            "output": {"xdmf": False, "plots": False, "progress": False}}
    with pytest.raises(SceneError, match=r"contact\[1\]\.mu_table = .*row 2 has x = 1: allowed x > 2"):
        load_scene(data)
    data["contact"][1]["mu_table"] = [[0, 0.1], [2, 0.3]]
    data["contact"][1]["mu_variable"] = "energy"
    zone = load_scene(data).zones[0]
    assert zone.mu == 0.1 and zone.friction_law() == dfr.EvolvingFriction([[0, 0.1], [2, 0.3]], "energy")
    # hertz: Q = 89.658 N/mm under P = 199.24 N/mm: 0.9 carries it, a table falling to 0.2 would not
    with pytest.raises(SceneError, match=r"\|Q\| < min\(contact\.mu_table's mu\) x loading\.normal_force = 0\.2 x"):
        load_scene("hertz", ["contact.mu_table=[[0, 0.9], [5, 0.2]]"])


def _interp_function(table):
    """The table as the user's function of the energy (np.interp, the table's own arithmetic): the per-increment
    path (one compiled call per increment, mu updated in Python)."""
    abscissae, values = np.array(table, dtype=float).T

    def mu_of_energy(energy):
        return np.interp(energy, abscissae, values)
    return mu_of_energy


def test_a_subclassed_wear_law_keeps_the_table_per_increment(monkeypatch):
    """The compiled loop computes the wear rate as k0 + k1 mu, which holds for the shipped laws themselves; a user's
    subclass may compute it otherwise, so with one the cycle runs one call per increment (as with a function of the
    energy), not one call a cycle."""
    class OwnArchard(dfr.Archard):
        pass

    calls = []
    real = cycles_module.run_increments
    monkeypatch.setattr(cycles_module, "run_increments", lambda *args: calls.append(1) or real(*args))
    problem, _, state = pressed_block(dfr.EvolvingFriction([(0.0, 0.2), (0.15, 0.8)], variable="energy"),
                                      wear=OwnArchard(k=1e-5))
    try:
        problem.run_cycle(state, dfr.CyclePath.waveform(INCREMENTS, tangential=AMPLITUDE), keep=True)
    finally:
        problem.destroy()
    assert len(calls) == INCREMENTS


@pytest.mark.parametrize("control", ["displacement", "force"])
@pytest.mark.parametrize("wear", [None, "energy", "archard"])
def test_energy_table_runs_inside_the_compiled_cycle(monkeypatch, control, wear):
    """mu(E) of a table runs inside the compiled loop: one call for the cycle (counted), against the same law as
    the user's function, which runs one call per increment with mu, the energy and the wear rate updated in
    Python between the calls (the path kept for functions). The same arithmetic in the same order but for the
    local solves' starts (within a call the loop starts a solve from the x of the one before, x + q - q_before; a
    call per increment forms its first from W: their last bits differ): forces, wear gap, energy and the rows to
    1e-12 of each quantity's largest value (measured: 5e-15), the final slip (rounding at the cycle's last
    increment, ~1e-15 of the relative positions) to 1e-12 of the relative positions' largest value.
    Under force control (Q* = 0.15 P, partial slip at mu >= 0.2) the load control's root finder runs inside too.
    The table's first breakpoint is crossed during the cycles (mu from 0.2 past 0.3), so a mu held over the cycle or
    an energy update out of step would differ at the 1e-2 level."""
    table = [(0.0, 0.2), (0.005, 0.3), (0.15, 0.8)]
    laws = {"energy": dfr.EnergyWear(ALPHA), "archard": dfr.Archard(k=1e-5), None: None}
    calls = {"run_increments": 0, "run_force_increments": 0}
    for name in calls:
        real = getattr(cycles_module, name)

        def counting(*args, _real=real, _name=name):
            calls[_name] += 1
            return _real(*args)
        monkeypatch.setattr(cycles_module, name, counting)
    results, counted = [], []
    for law in (dfr.EvolvingFriction(table, variable="energy"),
                dfr.EvolvingFriction(_interp_function(table), variable="energy")):
        problem, contact, state = pressed_block(law, wear=laws[wear])
        if control == "force":
            P = abs(state.record["normal_force"])
            path = dfr.CyclePath.waveform(INCREMENTS, tangential=dfr.Force(0.15 * P))
        else:
            path = dfr.CyclePath.waveform(INCREMENTS, tangential=AMPLITUDE)
        for key in calls:
            calls[key] = 0
        runs = []
        for _ in range(3):
            result = problem.run_cycle(state, path, keep=True)
            assert result.compiled
            runs.append(result)
            state = problem.commit(state, result)
        counted.append(sum(calls.values()))
        results.append((state.forces, state.slip, state.wear_gap, state.friction_energy,
                        np.array([r.kept[0] for r in runs]), np.array([r.kept[1] for r in runs]),
                        np.array([r.records["dissipated_energy"] for r in runs]),
                        np.array([r.records["tangential_force"] for r in runs])))
        mu = friction.coefficients(contact, state)
        problem.destroy()
    assert counted == [3, 3 * INCREMENTS]   # one call a cycle (table), one an increment (function)
    assert mu.max() > 0.3 and state.friction_energy.max() > 0.005   # a breakpoint was crossed
    positions = np.abs(results[1][5]).max()   # the relative positions x kept over the cycles
    for quantity, (compiled, stepwise) in enumerate(zip(*results)):
        scale = positions if quantity == 1 else max(np.abs(stepwise).max(), 1e-300)   # 1: the final slip
        assert np.abs(compiled - stepwise).max() <= 1e-12 * scale
