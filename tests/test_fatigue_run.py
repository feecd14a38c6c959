"""A scene's ``[fatigue]`` through the runner: Miner's sum (pure), the keys refused, fatigue.csv and the summary
against the API called on the same states, Miner's damage over the run, and a resume that neither loses nor
repeats a row."""

import json
import math
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

import h5py
import numpy as np
import pytest
from mpi4py import MPI
from scipy.spatial import cKDTree

from dolfinx_fretting import fatigue, fatigue_outputs
from dolfinx_fretting._dolfinx import mpiexec
from dolfinx_fretting.fatigue import MinerSum
from dolfinx_fretting.fatigue_fields import fatigue_over_cycle
from dolfinx_fretting.fatigue_outputs import FATIGUE_XDMF, TABLE_COLUMNS, fatigue_arguments, xdmf_fields
from dolfinx_fretting.scenes import SceneError, load_scene
from dolfinx_fretting.output import FrettingWriter, read_description
from dolfinx_fretting.plots import plot_fatigue_map
from dolfinx_fretting.simulation import CHECKPOINT, ContactModel, SimulationError, _cycle_path, run_scene
from dolfinx_fretting.tables import read_rows, write_rows

#: Example 1 on a 10 x 10 mesh, 20 increments a cycle, the per-increment path (a resumed run repeats the straight
#: run's arithmetic bit for bit: tests/test_cycles.py), wear accelerated 10 times (a cycle stands for 10).
SMALL = ["geometry.nx=10", "geometry.ny=10", "output.xdmf=false", "output.plots=false",
         "output.contact_profiles=false", "loading.increments_per_cycle=20", "solver.cycle_kernel=false",
         "wear.acceleration=10.0"]
#: Every cycle evaluated, within 10 mm of the contact (two rows of cells), Fatemi-Socie and made-up strain-life
#: constants that put the hot spot's life near 15 cycles (SWT ~ 3.4e-4 MPa here: sigma_f eps_f (2N)^(b+c) with
#: sigma_f = 1 MPa), so Miner's sum reaches 1 within the run's second block.
FATIGUE = ["fatigue.enabled=true", "fatigue.region=10.0", "fatigue.cycles=1", "fatigue.k=0.5",
           "fatigue.yield_stress=800.0", "fatigue.sigma_f=1.0", "fatigue.b=-0.1", "fatigue.eps_f=3.6e-3",
           "fatigue.c=-0.6"]
ACCELERATION = 10.0
#: fatigue.xdmf (and fields.xdmf at the snapshot cycles 1 and 2) written: output.xdmf, after SMALL's false.
WITH_XDMF = ["output.xdmf=true"]


def test_miner_sum_of_constant_and_of_two_blocks():
    """A constant life N: D after n cycles in k blocks is n/N (k additions of n/(k N): rounding ~k eps, 1e-10
    bounds it); two blocks of lives N1, N2: D = n1/N1 + n2/N2, and the first point to reach 1 does so at
    n1 + (1 - n1/N1) N2 (the second block's constant rate), its index reported; inf lives add nothing."""
    lives = np.array([250.0, 1e4, np.inf])
    total = MinerSum.start(3)
    for _ in range(100):
        total = total.add(lives, 2.0)
    assert total.damage == pytest.approx([200 / 250, 200 / 1e4, 0.0], rel=1e-10, abs=0)
    assert total.cycles == 200.0 and math.isinf(total.initiation) and total.initiation_point == -1
    n1, n2 = 30.0, 50.0
    first, second = np.array([40.0, 60.0, 1e6]), np.array([30.0, 20.0, 1e6])
    two = MinerSum.start(3).add(first, n1).add(second, n2)
    assert two.damage == pytest.approx(n1 / first + n2 / second, rel=1e-12)
    crossings = n1 + (1 - n1 / first) * second   # point 0 at 37.5, point 1 at 40
    assert two.initiation == pytest.approx(crossings[:2].min(), rel=1e-12) and two.initiation_point == 0
    # once initiated, the cycle stays the first crossing's
    assert two.add(second, 10.0).initiation == two.initiation
    with pytest.raises(ValueError, match="block = 0"):
        total.add(lives, 0.0)
    with pytest.raises(ValueError, match="lives of shape"):
        total.add(np.array([1.0, -1.0, 2.0]), 1.0)


@pytest.mark.parametrize("overrides, message", [
    (["fatigue.region=2.0"], "fatigue.region is given but fatigue.enabled = false"),
    (["fatigue.enabled=true"], "fatigue.region .* is required"),
    (["fatigue.enabled=true", "fatigue.region=-1.0"], "fatigue.region = -1.0"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "fatigue.cycles=0"], "fatigue.cycles = 0"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "fatigue.cycles='first'"], "fatigue.cycles = 'first'"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "fatigue.angle_step=90.0"], "fatigue.angle_step = 90.0.*<= 45"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "fatigue.b=0.1"], "fatigue.b = 0.1.*< 0"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "fatigue.k=0.5"], "fatigue.yield_stress is missing"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "fatigue.sigma_f=900.0"], "fatigue.b, fatigue.eps_f, fatigue.c"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "fatigue.method='line'"], "fatigue.method is given without"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "fatigue.method='area'"], "fatigue.method = 'area'"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "fatigue.regoin=1.0"], "unknown key 'fatigue.regoin'"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "loading.cycles=0"], "loading.cycles = 0.*fatigue.enabled"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "fatigue.body='pad'"], "fatigue.body = 'pad'.*'slave', 'master'"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "fatigue.body='master'"],
     "fatigue.body = 'master' is out of range; allowed: 'slave' with contact.obstacle = 'rigid_plane'"),
    (["fatigue.enabled=true", "fatigue.region=1.0", "material.model='elastoplastic'", "material.yield_stress=900.0",
      "material.hardening_modulus=0.0"], "material.model = 'elastoplastic'"),
])
def test_bad_fatigue_keys_are_refused_by_name(overrides, message):
    with pytest.raises(SceneError, match=message):
        load_scene("stromberg-block", overrides)


def test_a_scene_without_fatigue_dumps_as_before():
    """The section is left out of a scene's data while it is off: a checkpoint's identity (and ``show``) of the
    scenes before ``[fatigue]`` existed is unchanged."""
    assert "fatigue" not in load_scene("stromberg-block").model_dump(mode="json")
    assert load_scene("stromberg-block", FATIGUE).model_dump(mode="json")["fatigue"]["region"] == 10.0


def test_region_without_points_is_refused_before_the_cycles(tmp_path):
    scene = load_scene("stromberg-block", SMALL + FATIGUE + ["loading.cycles=1", "fatigue.region=1e-3"])
    with pytest.raises(SimulationError, match="region = 0.001 holds no point"):
        run_scene(scene, tmp_path, quiet=True)
    assert not (tmp_path / "cycles.csv").exists() or len((tmp_path / "cycles.csv").read_text().splitlines()) == 1


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """A straight 2-cycle run; a 1-cycle run (its checkpoint kept) resumed to 2 cycles, with a row appended to its
    fatigue.csv after the checkpoint (what a run killed after an evaluation, before its next checkpoint, leaves)."""
    root = tmp_path_factory.mktemp("fatigue_run")
    two = load_scene("stromberg-block", SMALL + FATIGUE + WITH_XDMF + ["loading.cycles=2"])
    straight = run_scene(two, root / "straight", quiet=True)
    one = run_scene(load_scene("stromberg-block", SMALL + FATIGUE + WITH_XDMF + ["loading.cycles=1"]), root / "cut",
                    quiet=True)
    shutil.copy(root / "cut" / CHECKPOINT, root / "cycle1.npz")
    with open(root / "cut" / "fatigue.csv", "a") as table:
        table.write("2,20" + ",1" * (len(TABLE_COLUMNS) - 2) + "\n")
    resumed = run_scene(two, root / "cut", quiet=True, resume=True)
    return {"scene": two, "root": root, "straight": straight, "one": one, "resumed": resumed}


def _table(folder):
    return read_rows(folder / "fatigue.csv", integers=("cycle",))


def _api_cycle_two(scene, checkpoint):
    """Cycle 2 through the public API from the state after cycle 1: run_cycle(keep=True), fatigue_over_cycle."""
    model = ContactModel(scene, MPI.COMM_WORLD)
    problem = model.problem
    state, _ = problem.load_state(checkpoint)
    result = problem.run_cycle(state, _cycle_path(scene, model), keep=True)
    return fatigue_over_cycle(problem, result, **fatigue_arguments(scene)), problem


def test_fatigue_csv_and_summary_equal_the_api_on_the_same_states(runs):
    """fatigue.csv has the declared columns, every region point once per evaluated cycle; summary.json's fatigue
    numbers are fatigue_over_cycle's on cycle 2's states, recomputed through the API from the checkpoint after
    cycle 1 (the same arithmetic: 1e-10 bounds rounding), and its rows the API's points (written to 6 digits:
    5e-6)."""
    s = runs["straight"]
    assert s["converged"]
    rows = _table(runs["root"] / "straight")
    assert tuple(rows[0]) == TABLE_COLUMNS
    points = s["fatigue"]["points"]
    assert points == 20   # two rows of ten 5 mm cells within 10 mm of the contact
    assert [r["cycle"] for r in rows] == [1] * points + [2] * points
    assert [r["equivalent_cycles"] for r in rows] == [10.0] * points + [20.0] * points
    api, problem = _api_cycle_two(runs["scene"], runs["root"] / "cycle1.npz")
    for key in fatigue.SUMMARY_FIELDS:
        assert s["fatigue"][key] == pytest.approx(api.summary[key], rel=1e-10, abs=1e-14), key
    assert s["fatigue"]["cycle"] == 2 and s["fatigue"]["evaluations"] == 2
    mine = [r for r in rows if r["cycle"] == 2]
    order = np.lexsort((api.coordinates[:, 1], api.coordinates[:, 0]))
    for name in fatigue.POINT_COLUMNS:
        table = np.array([r[name] for r in mine])
        assert table == pytest.approx(api.columns()[name][order], rel=5e-6, abs=1e-12), name
    problem.destroy()


def test_miner_damage_over_the_run(runs):
    """One block (the 1-cycle run): D = 10 cycles / N at every point, so its largest is 10 / life_min (1e-12: one
    division). Two blocks (the 2-cycle run): D = 10/N1 + 10/N2 per point, N1 from fatigue.csv (6 digits: 1e-5) and
    the initiation cycle where the first point's D reaches 1, 10 + (1 - 10/N1) N2 of that point."""
    one = runs["one"]["fatigue"]
    assert one["miner_damage_max"] == pytest.approx(ACCELERATION / one["life_min"], rel=1e-12)
    assert one["initiation_cycles"] is None   # the hot spot's life is above 10 cycles
    rows = _table(runs["root"] / "straight")
    first = np.array([r["life"] for r in rows if r["cycle"] == 1])
    second = np.array([r["life"] for r in rows if r["cycle"] == 2])
    damage = np.array([r["damage"] for r in rows if r["cycle"] == 2])
    expected = ACCELERATION / first + ACCELERATION / second
    assert damage == pytest.approx(expected, rel=1e-5)
    two = runs["straight"]["fatigue"]
    assert two["miner_damage_max"] == pytest.approx(expected.max(), rel=1e-5)
    assert two["miner_damage_max"] > 1   # the made-up constants: a crack within the run
    crossing = np.where(expected >= 1, ACCELERATION + (1 - ACCELERATION / first) * second, np.inf)
    at = int(np.argmin(crossing))
    assert two["initiation_cycles"] == pytest.approx(crossing[at], rel=1e-5)
    x = np.array([r["x"] for r in rows if r["cycle"] == 2])
    assert two["initiation_x"] == pytest.approx(x[at], rel=1e-6)


def test_a_resumed_run_neither_loses_nor_repeats_a_row(runs):
    """The run cut after cycle 1 and resumed: fatigue.csv the straight run's, byte for byte (the per-increment
    path repeats its arithmetic), and the same fatigue summary (but its times)."""
    straight, cut = runs["root"] / "straight", runs["root"] / "cut"
    assert (cut / "fatigue.csv").read_text() == (straight / "fatigue.csv").read_text()
    assert runs["resumed"]["resumed_from_cycle"] == 1
    drop = lambda summary: {k: v for k, v in summary["fatigue"].items()  # noqa: E731
                            if k not in ("wall_time_s", "cpu_time_s")}
    assert drop(runs["resumed"]) == drop(runs["straight"])
    on_disk = json.loads((cut / "summary.json").read_text())
    assert on_disk["fatigue"]["evaluations"] == 2


def _read_fatigue_xdmf(folder):
    """fatigue.xdmf through its XML and h5py (independent of DOLFINx's reader): the region's cell midpoints and,
    per time, each field's cell values {time: {name: (cells,)}}."""
    root = ElementTree.parse(folder / FATIGUE_XDMF).getroot()
    data = {}
    with h5py.File(folder / "fatigue.h5", "r") as h5:
        def dataset(item):
            return np.asarray(h5[item.text.strip().split(":", 1)[1]])
        mesh = next(grid for grid in root.iter("Grid") if grid.find("Topology") is not None
                    and grid.find("Topology").find("DataItem") is not None)
        topology = dataset(mesh.find("Topology").find("DataItem")).astype(int)
        geometry = dataset(mesh.find("Geometry").find("DataItem"))
        midpoints = geometry[topology].mean(axis=1)
        for grid in root.iter("Grid"):
            time, attribute = grid.find("Time"), grid.find("Attribute")
            if time is None or attribute is None:
                continue
            assert attribute.get("Center") == "Cell"
            values = dataset(attribute.find("DataItem")).reshape(-1)
            data.setdefault(float(time.get("Value")), {})[attribute.get("Name")] = values
    return midpoints, data


def test_the_fatigue_xdmf_holds_the_tables_values_at_its_points(runs):
    """fatigue.xdmf, read back with h5py: one cell per point of the region, one time per evaluated cycle (its
    equivalent cycles: 10, 20), SWT, FS, sigma_xx, life and damage; each cell's values are fatigue.csv's at the point
    of that cell (its midpoint's x and depth are the row's: 6 digits, 5e-6 of the region's size), the values the
    table's (parsed from it: 1e-12) and the API's of cycle 2 (the table's 6 digits: 5e-6). The resumed run's file
    is the straight run's (the same two times, no repeated one)."""
    folder = runs["root"] / "straight"
    midpoints, data = _read_fatigue_xdmf(folder)
    names = xdmf_fields(runs["scene"])
    assert names == ("sigma_xx", "swt", "fs", "life", "damage")
    assert sorted(data) == [10.0, 20.0] and all(sorted(fields) == sorted(names) for fields in data.values())
    assert midpoints.shape[0] == runs["straight"]["fatigue"]["points"]
    api, problem = _api_cycle_two(runs["scene"], runs["root"] / "cycle1.npz")
    problem.destroy()
    size = np.ptp(api.coordinates, axis=0).max()
    distance, nearest = cKDTree(api.coordinates[:, :2]).query(midpoints[:, :2])
    assert distance.max() < 1e-9 * size and np.unique(nearest).size == nearest.size
    order = np.lexsort((api.coordinates[:, 1], api.coordinates[:, 0]))   # the table's row order (x, then y)
    row_of_point = np.argsort(order)
    rows = _table(folder)
    for time, cycle in ((10.0, 1), (20.0, 2)):
        mine = [rows_ for rows_ in rows if rows_["cycle"] == cycle]
        table_rows = [mine[i] for i in row_of_point[nearest]]   # the row of each cell's point
        assert np.array([r["x"] for r in table_rows]) == pytest.approx(midpoints[:, 0], rel=0, abs=5e-6 * size)
        assert np.array([r["depth"] for r in table_rows]) == pytest.approx(api.depth[nearest], rel=0, abs=5e-6 * size)
        for name in names:
            table = np.array([r[name] for r in table_rows])
            assert data[time][name] == pytest.approx(table, rel=1e-12, abs=0), (time, name)
    for name in ("sigma_xx", "swt", "fs", "life"):
        assert data[20.0][name] == pytest.approx(api.columns()[name][nearest], rel=5e-6, abs=1e-12), name
    resumed_midpoints, resumed = _read_fatigue_xdmf(runs["root"] / "cut")
    assert sorted(resumed) == [10.0, 20.0]
    match = cKDTree(resumed_midpoints).query(midpoints)[1]
    for time in data:
        for name in names:
            assert resumed[time][name][match] == pytest.approx(data[time][name], rel=1e-12, abs=0), (time, name)


def test_the_fatigue_picture_is_drawn_from_the_table(runs, tmp_path):
    """fatigue.png from fatigue.csv (the last cycle's rows: SWT and, with constants, the damage); an empty table
    gives no picture."""
    folder = runs["root"] / "straight"
    run = read_description(folder)
    assert plot_fatigue_map(tmp_path / "fatigue.png", run, folder / "fatigue.csv") == tmp_path / "fatigue.png"
    assert (tmp_path / "fatigue.png").stat().st_size > 0
    empty = write_rows(tmp_path / "empty.csv", [], TABLE_COLUMNS)
    assert plot_fatigue_map(tmp_path / "none.png", run, empty) is None


def test_with_cycle_jumps_a_block_is_the_jumps_cycles(tmp_path):
    """Cycle jumps, every simulated cycle evaluated: each block is its cycle's jump (the equivalent cycles of
    consecutive evaluations differ by it: 1, 4, 8, ... and they end at the run's 60), so the blocks sum to the run's
    cycles and the damage is sum(block_i / N_i) over fatigue.csv's lives (6 digits: 1e-5)."""
    scene = load_scene("stromberg-block", [o for o in SMALL if o != "wear.acceleration=10.0"] + FATIGUE + [
        "loading.cycles=60", "wear.cycle_jump=true", "output.snapshot_cycles=[60]", "solver.cycle_kernel=true"])
    summary = run_scene(scene, tmp_path, quiet=True)
    assert summary["converged"] and summary["cycle_jump"]["jumps"] > 0
    rows = _table(tmp_path)
    cycles = sorted({r["cycle"] for r in rows})
    assert len(cycles) == summary["fatigue"]["evaluations"] == summary["cycle_jump"]["simulated_cycles"]
    ends = np.array([next(r["equivalent_cycles"] for r in rows if r["cycle"] == c) for c in cycles])
    blocks = np.diff(ends, prepend=0.0)
    assert ends[-1] == 60 and blocks.max() > 1
    # each evaluated cycle's block: from it to the cycle before the next simulated one
    assert np.array_equal(blocks, np.diff(np.append(cycles, 61)))
    lives = np.array([[r["life"] for r in rows if r["cycle"] == c] for c in cycles])
    damage = np.array([r["damage"] for r in rows if r["cycle"] == cycles[-1]])
    assert damage == pytest.approx((blocks[:, None] / lives).sum(axis=0), rel=1e-5)
    assert summary["fatigue"]["miner_damage_max"] == pytest.approx(damage.max(), rel=1e-5)


@pytest.mark.parametrize("fault", ["rows not written", "cycle failed after its evaluation"])
def test_miner_damage_counts_only_written_rows(tmp_path, monkeypatch, fault):
    """Cycle 2 evaluated, then its fatigue rows not written (the disk full) or the cycle failing after the
    evaluation: the fatigue summary, and what a checkpoint saves, stay at cycle 1, whose rows are the table's:
    one evaluation, Miner's largest damage the table's (6 digits: 1e-5), the one block's 10/N at every point
    (before the fix: cycle 2's, a damage > 1 for rows never written)."""
    created = []
    init = fatigue_outputs.FatigueOutputs.__init__

    def kept(self, *args, **kwargs):
        init(self, *args, **kwargs)
        created.append(self)

    monkeypatch.setattr(fatigue_outputs.FatigueOutputs, "__init__", kept)
    if fault == "rows not written":
        append_rows = fatigue_outputs.append_rows

        def disk_full_at_cycle_2(path, rows, columns):
            if rows and rows[0]["cycle"] == 2:
                raise OSError(28, f"{path} not written: No space left on device")
            append_rows(path, rows, columns)

        monkeypatch.setattr(fatigue_outputs, "append_rows", disk_full_at_cycle_2)
        raised = OSError
    else:
        write_cycle = FrettingWriter.write_cycle

        def failed_cycle_2(self, cycle, *args, **kwargs):
            if cycle == 2:
                raise SimulationError("cycle 2 failed after its evaluation")
            return write_cycle(self, cycle, *args, **kwargs)

        monkeypatch.setattr(FrettingWriter, "write_cycle", failed_cycle_2)
        raised = SimulationError
    with pytest.raises(raised, match="not written|after its evaluation"):
        run_scene(load_scene("stromberg-block", SMALL + FATIGUE + ["loading.cycles=2"]), tmp_path, quiet=True)
    rows = _table(tmp_path)
    assert {r["cycle"] for r in rows} == {1}
    written = np.array([r["damage"] for r in rows])
    lives = np.array([r["life"] for r in rows])
    assert written == pytest.approx(ACCELERATION / lives, rel=1e-5)
    outputs = created[0]
    reported = outputs.summary()
    assert reported["cycle"] == 1 and reported["evaluations"] == 1
    assert reported["miner_damage_max"] == pytest.approx(written.max(), rel=1e-5)
    saved = outputs.saved()
    assert saved["last_evaluated"] == 1 and saved["covered"] == 1 and saved["cycles_summed"] == ACCELERATION
    assert np.array(saved["damage"]) == pytest.approx(written, rel=1e-5)   # the rows' order is the sum's
    if fault == "cycle failed after its evaluation":   # the summary on disk: the runner's failure summary
        on_disk = json.loads((tmp_path / "summary.json").read_text())
        assert on_disk["converged"] is False and on_disk["fatigue"]["evaluations"] == 1
        assert on_disk["fatigue"]["miner_damage_max"] == pytest.approx(written.max(), rel=1e-5)


@pytest.mark.mpi
def test_two_ranks_write_the_serial_fatigue_outputs(runs, tmp_path, mpirun_env):
    """The 2-cycle run under mpirun -n 2 (the CLI): the fatigue summary is the serial run's (the same contact
    states to the factorisation's rounding: 1e-8, as tests/test_mpi.py), fatigue.csv has every point once per
    evaluation, in the serial order (the points sorted by their coordinates, not by rank), its values the serial
    ones to their 6 digits (a last digit may round the other way: 2e-5); fatigue.xdmf the serial one's, cell by
    cell (2e-5 likewise)."""
    cmd = [*mpiexec(2), sys.executable, "-m", "mpi4py", "-m", "dolfinx_fretting", "run", "stromberg-block",
           "--out", str(tmp_path), "--quiet"]
    for override in SMALL + FATIGUE + WITH_XDMF + ["loading.cycles=2"]:
        cmd += ["--set", override]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=mpirun_env, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    parallel = json.loads((tmp_path / "summary.json").read_text())["fatigue"]
    serial = runs["straight"]["fatigue"]
    for key in (*fatigue.SUMMARY_FIELDS, *fatigue.MINER_FIELDS):
        assert parallel[key] == pytest.approx(serial[key], rel=1e-8, abs=1e-14), key
    assert parallel["points"] == serial["points"] and parallel["evaluations"] == serial["evaluations"]
    mine, theirs = _table(tmp_path), _table(runs["root"] / "straight")
    assert len(mine) == len(theirs)
    for name in TABLE_COLUMNS:
        assert np.array([r[name] for r in mine]) == pytest.approx(np.array([r[name] for r in theirs]), rel=2e-5,
                                                                   abs=1e-12), name
    # fatigue.xdmf: each rank's cells get their own rows (rank order is not the table's): the serial file's values
    # at the same cells
    midpoints, fields = _read_fatigue_xdmf(tmp_path)
    serial_midpoints, serial_fields = _read_fatigue_xdmf(runs["root"] / "straight")
    distance, match = cKDTree(serial_midpoints).query(midpoints)
    assert midpoints.shape == serial_midpoints.shape and distance.max() < 1e-9 * np.ptp(midpoints, axis=0).max()
    assert sorted(fields) == sorted(serial_fields) == [10.0, 20.0]
    for time in fields:
        for name in xdmf_fields(runs["scene"]):
            assert fields[time][name] == pytest.approx(serial_fields[time][name][match], rel=2e-5, abs=1e-12), name
