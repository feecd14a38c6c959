"""The writers of a problem with several contact zones: each zone's columns in ``history.csv`` and ``cycles.csv``, a
``zone`` column in the profiles, every zone in ``run.json``, and the plots drawn from the folder.

The model is two independent blocks in one mesh (tests/support/blocks.py), each pressed and rubbed by its own rigid
plane: zone A under a normal force, zone B at a fixed approach. The references are independent of the writer: the
problem's own readers (``total_force``, ``contact_fields``) on the states of the same cycle solved increment by
increment, and the identities the columns must satisfy (the zones' energies and worn areas sum to the totals, the
largest zone pressure is the peak pressure).

Tolerances: the tables print 10 significant digits (``%.10g``: a relative rounding of 5e-11 per value), and the
compiled cycle agrees with the increment-by-increment one to 1e-14 (tests/test_zones.py, measured), so a written
value is compared with its reference to 1e-9 of the quantity's scale.
"""

import json
import warnings

import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting.contact_output import read_profiles, read_table  # noqa: E402
from dolfinx_fretting.io import ZONE_CYCLE_FIELDS, history_fields, zone_columns, zone_history_fields  # noqa: E402
from dolfinx_fretting.output import FrettingWriter, RunDescription, ZoneDescription  # noqa: E402
from dolfinx_fretting.plots import plot_run  # noqa: E402
from support.blocks import elasticity, plane_above, two_blocks  # noqa: E402

#: Zone A's normal force (N/mm), zone B's approach (mm), each zone's stroke along its t1 (mm), increments per cycle.
P_A, D_B, STROKE_A, STROKE_B, STEPS = 100.0, 5e-4, 4e-3, -2e-3, 8
#: Printing at 10 significant digits (5e-11 relative) and compiled vs stepwise (1e-14): 1e-9 of the scale.
TOL = 1e-9


def problem_of(compiled: bool):
    V, tags, bcs = two_blocks(4)
    a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.3, bcs=bcs)
    b = dfr.Contact(V, (tags, 2), plane_above(), mu=0.2, bcs=bcs)
    solver = dfr.LocalSolver(tol=1e-12, compiled_cycles=compiled)
    return dfr.FrettingProblem(elasticity(V), [a, b], bcs, solver=solver, wear=dfr.Archard(1e-6)), a, b


def path_of(a, b, approach: float):
    """The cycle: zone A held at the preload's approach (a displacement: the compiled loop runs it), both planes
    rubbed along their t1."""
    return dfr.CyclePath.waveform(STEPS, normal={a: approach}, tangential={a: STROKE_A, b: STROKE_B})


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """Two compiled cycles written (the second with its profiles), the states each increment of them reaches solved
    increment by increment, and the folder."""
    folder = tmp_path_factory.mktemp("zones")
    problem, a, b = problem_of(compiled=True)
    state, _ = problem.advance(problem.initial_state(), normal={a: dfr.Force(P_A), b: D_B})
    approach = float(state.obstacle[0])
    description = RunDescription.of(problem, "two blocks", path=path_of(a, b, approach), cycles=2,
                                    preload_increments=1, surfaces=["top_a", "top_b"])
    writer = FrettingWriter(problem, folder, description, fields=False)
    writer.write_increment(state, stage="normal")
    for cycle in (1, 2):
        result = problem.run_cycle(state, path_of(a, b, approach), keep=True)
        assert result.compiled
        start, state = state, problem.commit(state, result)
        writer.write_cycle(cycle, start, result, profiles=cycle == 2)
    writer.write_worn_profiles(state)
    writer.close()
    # the reference: the same two cycles increment by increment, every committed state kept
    reference, ra, rb = problem_of(compiled=False)
    states = []
    ref_state, _ = reference.advance(reference.initial_state(), normal={ra: dfr.Force(P_A), rb: D_B})
    states.append(ref_state)
    for _ in (1, 2):
        result = reference.run_cycle(ref_state, path_of(ra, rb, approach), check=states.append)
        assert not result.compiled
        ref_state = reference.commit(ref_state, result)
    return {"folder": folder, "problem": problem, "zones": (a, b), "state": state, "approach": approach,
            "reference": reference, "ref_zones": (ra, rb), "states": states}


def test_each_zone_s_columns_are_its_total_force(written):
    """Every history row (the preload and each cycle increment): each zone's normal and tangential force are
    ``total_force(state, zone)`` of the state solved increment by increment, its obstacle position the state's."""
    hist = read_table(written["folder"] / "history.csv")
    reference, states = written["reference"], written["states"]
    assert hist["increment"].tolist() == [s.increment for s in states] == list(range(1, 2 * STEPS + 2))
    scale = P_A
    for i, zone in enumerate(written["ref_zones"]):
        forces = np.array([reference.total_force(s, zone) for s in states])
        assert np.abs(hist[f"zone{i}_normal_force"] - forces[:, 0]).max() <= TOL * scale
        assert np.abs(hist[f"zone{i}_tangential_force"] - forces[:, 1]).max() <= TOL * scale
        obstacle = np.array([s.obstacle[2 * i:2 * i + 2] for s in states])
        assert np.abs(hist[f"zone{i}_normal_displacement"] - obstacle[:, 0]).max() <= TOL * D_B
        assert np.abs(hist[f"zone{i}_tangential_displacement"] - obstacle[:, 1]).max() <= TOL * abs(STROKE_A)
    # the preload's force control of the driven zone holds (the local solver's force tolerance, 1e-8 of P)
    assert hist["zone0_normal_force"][0] == pytest.approx(P_A, rel=1e-7)
    # zone A slides at the stroke's ends (gross slip: |Q| = mu P at every loaded node), and both zones dissipate
    ends = np.abs(hist["zone0_tangential_force"]).argmax()
    assert abs(hist["zone0_tangential_force"][ends]) == pytest.approx(0.3 * hist["zone0_normal_force"][ends], rel=1e-7)
    assert hist["zone1_dissipated_energy"].sum() > 0 and hist["zone0_dissipated_energy"].sum() > 0


def test_the_zones_sum_to_the_totals(written):
    """Each zone's energy and worn area sum to the table's totals, the largest zone pressure is the peak pressure
    (the same bookkeeping restricted to each zone's contacts: equal up to the printing, 1e-9 of the scale)."""
    hist = read_table(written["folder"] / "history.csv")
    for name in ("dissipated_energy", "wear_area"):
        parts = hist[f"zone0_{name}"] + hist[f"zone1_{name}"]
        assert np.abs(parts - hist[name]).max() <= TOL * np.abs(hist[name]).max()
    assert np.abs(np.maximum(hist["zone0_max_pressure"], hist["zone1_max_pressure"]) - hist["max_pressure"]).max() \
        <= TOL * hist["max_pressure"].max()
    cycles = read_table(written["folder"] / "cycles.csv")
    assert cycles["cycle"].tolist() == [1, 2]
    assert np.abs(cycles["zone0_dissipated_energy"] + cycles["zone1_dissipated_energy"]
                  - cycles["dissipated_energy"]).max() <= TOL * cycles["dissipated_energy"].max()
    # a cycle's zone energy is the sum of its increments' (history), its extremes those of the history's
    for i in (0, 1):
        for c in (1, 2):
            rows = hist["cycle"] == c
            assert cycles[f"zone{i}_dissipated_energy"][c - 1] == pytest.approx(
                hist[f"zone{i}_dissipated_energy"][rows].sum(), rel=1e-8)
            assert cycles[f"zone{i}_tangential_force_max"][c - 1] == hist[f"zone{i}_tangential_force"][rows].max()
    # the final worn area of each zone is that of the state (wear gap x tributary lengths of its nodes)
    problem, state = written["problem"], written["state"]
    for i, zone in enumerate(written["zones"]):
        fields = problem.contact_fields(state, zone)
        worn = fields["wear"] @ problem.contact.contact_set.tributary[problem.contact.zone_slice(i)]
        assert worn > 0
        assert cycles[f"zone{i}_wear_area"][-1] == pytest.approx(worn, rel=TOL)


def test_the_columns_are_declared_once(written):
    """run.json's table columns are the ones written, each zone's generated from one declaration; the zones are
    described (kind, plane, frame, marker, surface name) and read back."""
    folder = written["folder"]
    run = json.loads((folder / "run.json").read_text())
    for table, columns in run["tables"].items():
        assert (folder / table).read_text().splitlines()[0].split(",") == columns, table
    assert run["tables"]["history.csv"] == history_fields(2, 2)
    assert run["tables"]["history.csv"][-2 * len(zone_history_fields(2)):] == \
        zone_columns(zone_history_fields(2), 2)
    assert run["tables"]["cycles.csv"][-2 * len(ZONE_CYCLE_FIELDS):] == zone_columns(ZONE_CYCLE_FIELDS, 2)
    assert [(z["zone"], z["kind"], z["normal"], z["marker"], z["surface"]) for z in run["zones"]] == \
        [(0, "rigid_plane", [0.0, -1.0], 1, "top_a"), (1, "rigid_plane", [0.0, -1.0], 2, "top_b")]
    back = RunDescription.from_json(run)
    assert back.zones == (ZoneDescription("rigid_plane", (0.0, 1.0), (0.0, -1.0), tuple(written["zones"][0].frame[1]),
                                          1, "top_a"),
                          ZoneDescription("rigid_plane", (0.0, 1.0), (0.0, -1.0), tuple(written["zones"][1].frame[1]),
                                          2, "top_b"))
    assert json.loads(json.dumps(back.to_json())) == run
    # the first zone's motion is the run's tangential control (the loops' abscissa)
    assert (back.tangential_control, back.tangential_amplitude, back.increments_per_cycle) == \
        ("displacement", abs(STROKE_A), STEPS)


def test_each_zone_s_profile(written):
    """contact_profiles.csv: each zone's nodes numbered from 0 with its zone; a zone read alone is the state's
    contact fields of that zone (printing: 1e-9 of the largest pressure)."""
    problem, state = written["problem"], written["state"]
    for i, zone in enumerate(written["zones"]):
        prof = read_profiles(written["folder"], zone=i)
        fields = problem.contact_fields(state, zone)
        assert prof.nodes.size == zone.nc == fields["pressure"].size
        last = prof.index(state.increment)
        abscissa = problem.contact.contact_set.abscissa[problem.contact.zone_slice(i)]
        order = np.argsort(abscissa)   # a zone's profile is by position along its own surface, ascending
        assert np.abs(prof.position - abscissa[order]).max() <= TOL
        assert np.abs(prof.values["pressure"][last] - fields["pressure"][order]).max() \
            <= TOL * fields["pressure"].max()
    worn = read_table(written["folder"] / "worn_profiles.csv")
    assert worn["zone"].tolist() == [0] * written["zones"][0].nc + [1] * written["zones"][1].nc


def test_the_plots_draw_the_driven_zone(written):
    """plot_run draws from the folder alone, without a warning: the fretting loop of zone 0 (its own tangential
    force, with zone 1's dashed), the profiles of zone 0."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        written_files = {p.name for p in plot_run(written["folder"])}
    assert {"fretting_loops.png", "profiles.png", "wear_growth.png"} <= written_files


def test_a_cycle_without_its_increments_is_refused(written, tmp_path):
    """Several zones' columns need every increment's forces: a cycle solved without keep=True is refused with a
    message that says so (before anything is written)."""
    problem, (a, b) = written["problem"], written["zones"]
    writer = FrettingWriter(problem, tmp_path, fields=False, profiles=False)
    result = problem.run_cycle(written["state"], path_of(a, b, written["approach"]))
    with pytest.raises(ValueError, match="keep=True"):
        writer.write_cycle(3, written["state"], result)
    writer.close()
    assert len((tmp_path / "history.csv").read_text().splitlines()) == 1   # the header only
