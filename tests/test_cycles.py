"""Cyclic runs: the paper's Example 1 in short, checkpoints and resume (after a kill -9 and by extension)."""

import dataclasses
import json
import os
import signal
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

import h5py
import numpy as np
import pytest

from dolfinx_fretting import simulation
from dolfinx_fretting.plots import read_table
from dolfinx_fretting.problem import FrettingProblem
from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import CHECKPOINT, SimulationError, read_checkpoint, run_scene

SMALL_BLOCK = ["geometry.nx=20", "geometry.ny=20", "output.xdmf=false", "output.plots=false"]


def test_example1_short(tmp_path):
    """The built-in `stromberg-block` scene (paper Example 1, Table 1) for 4 cycles on its default mesh."""
    scene = load_scene("stromberg-block", ["loading.cycles=4", "output.snapshot_cycles=[1, 4]",
                                           "output.loop_cycles=[1, 4]"])
    s = run_scene(scene, tmp_path, quiet=True)
    assert s["converged"] and s["cycles"] == 4 and s["increments"] == 1 + 4 * 80
    assert s["contacts"] == 51 and s["cycle_path"] == "compiled"
    # What was modelled: an elastic scene has no Newton loop and builds W once.
    assert s["modelled"]["material"].startswith("linear elastic: no Newton loop")
    assert s["modelled"]["delassus"] == "W of the elastic K built once"
    # +-10 MPa on a 50 mm face against mu P ~ 10 N/mm of friction: gross slip in every cycle.
    cyc = read_table(tmp_path / "cycles.csv")
    assert list(cyc["regime"]) == ["gross_slip"] * 4
    hist = read_table(tmp_path / "history.csv")
    # Coulomb's law summed over the contact: |Q| <= mu P at every increment (to the local tolerance).
    assert np.all(np.abs(hist["tangential_force"]) <= scene.contact.mu * hist["normal_force"] * (1 + 1e-8) + 1e-9)
    # Wear-energy identity over the run (see test_wear for the tight version).
    assert s["wear_area"] == pytest.approx(scene.wear.k / scene.contact.mu * s["dissipated_energy"], rel=1e-8)
    # The paper's Fig. 6-7 observation: the edges wear first.
    prof = read_table(tmp_path / "contact_profiles.csv")
    last = prof["increment"] == prof["increment"].max()
    wear, pos = prof["wear"][last], prof["position"][last]
    centre = np.abs(pos - 25.0) < 5.0
    assert wear[0] > 2 * wear[centre].max() and wear[-1] > 2 * wear[centre].max()
    for name in ("summary.json", "history.csv", "cycles.csv", "contact_profiles.csv", CHECKPOINT):
        assert (tmp_path / name).is_file(), name


def _comparable(folder):
    s = json.loads((folder / "summary.json").read_text())
    return s, read_table(folder / "cycles.csv"), (folder / "history.csv").read_text()


#: Run in a child process: the CLI, killed by SIGKILL (kill -9) at a known point: when cycle KILL_AT starts, after
#: the checkpoint of snapshot cycle CHECKPOINT_AT and after the rows of the cycles in between were flushed, so
#: the resume must truncate them. Deterministic: no timing, no race with a fast machine.
CHECKPOINT_AT, KILL_AT = 5, 9
#: The run's length: cycles after KILL_AT for the resume to run on past the cut rows (20 before: the three runs of
#: the per-increment path took 10-14 s a stack; 12 checks the same).
RESUME_END = 12
_KILLER = """
import os, signal, sys
from dolfinx_fretting import output
from dolfinx_fretting.cli import main
write_cycle = output.FrettingWriter.write_cycle
def write_cycle_or_die(self, cycle, *args, **kwargs):
    if cycle == {kill_at}:
        os.kill(os.getpid(), signal.SIGKILL)
    return write_cycle(self, cycle, *args, **kwargs)
output.FrettingWriter.write_cycle = write_cycle_or_die
sys.exit(main(sys.argv[1:]))
"""


def test_resume_after_kill_gives_the_uninterrupted_answer(tmp_path):
    """Kill -9 a run part-way (per-increment path), resume it, compare with a straight run: bit for bit, every
    row once, and the resumed run started from the checkpoint (cycle 5), not from cycle 0."""
    args = ["--set", "geometry.nx=20", "--set", "geometry.ny=20", "--set", "output.xdmf=false",
            "--set", "output.plots=false", "--set", f"loading.cycles={RESUME_END}",
            "--set", "solver.cycle_kernel=false", "--set", f"output.snapshot_cycles=[{CHECKPOINT_AT}, {RESUME_END}]",
            "--set", "output.checkpoint_interval=1e6",
            "--set", "output.contact_profiles=false", "--quiet"]
    cmd = [sys.executable, "-m", "dolfinx_fretting", "run", "stromberg-block"]
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    straight, cut = tmp_path / "straight", tmp_path / "cut"
    subprocess.run(cmd + ["--out", str(straight)] + args, check=True, env=env, timeout=600)

    proc = subprocess.run([sys.executable, "-c", _KILLER.format(kill_at=KILL_AT), "run", "stromberg-block",
                           "--out", str(cut)] + args, env=env, timeout=600)
    assert proc.returncode == -signal.SIGKILL  # really killed, mid-run
    assert not (cut / "summary.json").exists()
    assert read_checkpoint(cut / CHECKPOINT)[0]["cycle"] == CHECKPOINT_AT
    # the cycles after the checkpoint were written before the kill: the resume has rows to cut
    assert list(read_table(cut / "cycles.csv")["cycle"]) == list(range(1, KILL_AT))
    subprocess.run(cmd + ["--out", str(cut), "--resume"] + args, check=True, env=env, timeout=600)
    s1, c1, h1 = _comparable(straight)
    s2, c2, h2 = _comparable(cut)
    # The checkpoint was used: the resumed process ran the 7 cycles after it (a resume restarting from cycle 0
    # would report 12, or no resume at all).
    assert s2["resumed_from_cycle"] == CHECKPOINT_AT and s2["cycles_this_run"] == RESUME_END - CHECKPOINT_AT
    assert s1["resumed_from_cycle"] is None and s1["cycles_this_run"] == RESUME_END
    # Same arithmetic from the same checkpointed state: identical results, and every row once.
    for key in ("max_wear_depth", "wear_area", "dissipated_energy", "normal_force", "tangential_force",
                "increments", "cycles", "local_iterations"):
        assert s2[key] == s1[key], key
    assert h2 == h1
    assert np.array_equal(c1["cycle"], c2["cycle"]) and np.array_equal(c1["max_wear_depth"], c2["max_wear_depth"])


def test_resume_extends_a_finished_run(tmp_path):
    """3 cycles, then resume to 6: the same as 6 straight (compiled path; its pattern cache restarts, so
    equality is to the local tolerance)."""
    base = SMALL_BLOCK + ["solver.local_tol=1e-12", "output.contact_profiles=false"]
    six = run_scene(load_scene("stromberg-block", base + ["loading.cycles=6"]), tmp_path / "six", quiet=True)
    run_scene(load_scene("stromberg-block", base + ["loading.cycles=3"]), tmp_path / "ext", quiet=True)
    ext = run_scene(load_scene("stromberg-block", base + ["loading.cycles=6"]), tmp_path / "ext", quiet=True,
                    resume=True)
    assert ext["cycles"] == 6 and ext["increments"] == six["increments"]
    # the checkpoint was used: three cycles simulated after cycle 3 (not six from the start)
    assert ext["resumed_from_cycle"] == 3 and ext["cycles_this_run"] == 3
    for key in ("max_wear_depth", "wear_area", "dissipated_energy", "tangential_force"):
        assert ext[key] == pytest.approx(six[key], rel=1e-8), key
    assert len(read_table(tmp_path / "ext" / "cycles.csv")["cycle"]) == 6


def test_resume_refuses_another_scene(tmp_path):
    run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=1"]), tmp_path, quiet=True)
    with pytest.raises(SimulationError, match="the scene differs"):
        run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=2", "contact.mu=0.3"]), tmp_path,
                  quiet=True, resume=True)
    with pytest.raises(SimulationError, match="no checkpoint"):
        run_scene(load_scene("stromberg-block", SMALL_BLOCK), tmp_path / "empty", quiet=True, resume=True)


def test_resume_with_another_scene_says_the_scene_differs(tmp_path):
    """Another built-in scene resumed from a stromberg-block checkpoint: the message says the scene differs (by name
    and keys, the first six with both values); before issue 27 it said only "loading.cycles = 0 is below the 1
    cycles the checkpoint has done"."""
    run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=1"]), tmp_path, quiet=True)
    with pytest.raises(SimulationError) as info:
        run_scene(load_scene("hertz", ["output.xdmf=false", "output.plots=false"]), tmp_path, quiet=True, resume=True)
    message = str(info.value)
    assert message.startswith("--resume: the scene (checkpointed: 'stromberg-block', this scene: 'hertz') differs")
    assert "geometry.kind = 'rectangle' (checkpoint), 'half_cylinder' (this scene)" in message
    assert "more: " in message and "is below the" not in message


def test_resume_under_another_name(tmp_path):
    """name and description label a run, they are not physics: a renamed scene resumes (refused before issue 27)."""
    run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=1"]), tmp_path, quiet=True)
    summary = run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=2", "name='block-renamed'",
                                                                      "description='the same physics'"]),
                        tmp_path, quiet=True, resume=True)
    assert summary["scene"] == "block-renamed" and summary["resumed_from_cycle"] == 1 and summary["cycles"] == 2


@pytest.mark.parametrize("tangential", ["tangential_force=60.0", "tangential_displacement=0.01"])
def test_force_controlled_normal_load_during_cycles(tmp_path, tangential):
    """Cylinder under a constant normal force, cycled by a tangential force (partial slip, Q < mu P) or a
    displacement (gross slip): the prescribed forces hold at every increment (in the compiled loop)."""
    P, mu = 199.24, 0.9
    scene = load_scene("hertz", ["geometry.contact_mesh_size=0.02", "loading.tangential_force=none",
                                 f"loading.{tangential}",
                                 "loading.cycles=2", "loading.increments_per_cycle=8", "wear.law='archard'",
                                 "wear.k=1e-6", "output.xdmf=false", "output.plots=false"])
    s = run_scene(scene, tmp_path, quiet=True)
    assert s["cycle_path"] == "compiled" and s["cycles"] == 2
    hist = read_table(tmp_path / "history.csv")
    cyc = hist["cycle"] > 0
    # Force control to solver.force_tol = 1e-8 relative.
    assert np.allclose(hist["normal_force"][cyc], P, rtol=1e-7)
    if tangential.startswith("tangential_force"):
        target = 60.0 * np.interp(hist["step"][cyc] / 8, [0, 0.25, 0.75, 1], [0, 1, -1, 0])
        assert np.allclose(hist["tangential_force"][cyc], target, rtol=0, atol=1e-7 * P)
        assert list(read_table(tmp_path / "cycles.csv")["regime"]) == ["partial_slip"] * 2
    else:
        # 10 um against ~6 um of tangential compliance up to mu P (measured Q = 58 N/mm at 2 um): gross slip.
        assert list(read_table(tmp_path / "cycles.csv")["regime"]) == ["gross_slip"] * 2
        assert np.abs(hist["tangential_force"][cyc]).max() == pytest.approx(mu * P, rel=1e-6)
    assert s["wear_area"] > 0


def test_wear_acceleration_is_k_times_s_and_recorded(tmp_path):
    """wear.acceleration = s runs k*s per simulated cycle and says so; same wear as k' = k s."""
    base = SMALL_BLOCK + ["loading.cycles=3", "output.contact_profiles=false"]
    acc = run_scene(load_scene("stromberg-block", base + ["wear.acceleration=10"]), tmp_path / "acc", quiet=True)
    big = run_scene(load_scene("stromberg-block", base + ["wear.k=1e-4"]), tmp_path / "big", quiet=True)
    assert acc["wear_acceleration"] == 10 and acc["wear_k"] == 1e-5
    assert acc["wear_k_effective"] == pytest.approx(1e-4, rel=1e-15) and acc["equivalent_cycles"] == 30
    assert list(read_table(tmp_path / "acc" / "cycles.csv")["equivalent_cycles"]) == [10, 20, 30]
    # The preload happens once: it wears with k itself (a tenth of the k' = 10 k run's preload wear) ...
    pre_acc = read_table(tmp_path / "acc" / "history.csv")["wear_area"][0]
    pre_big = read_table(tmp_path / "big" / "history.csv")["wear_area"][0]
    assert pre_acc > 0 and pre_big == pytest.approx(10 * pre_acc, rel=1e-8)
    # ... and the cycles wear with k s: the same wear as k' = k s (the preload wear, 1e-8 of the preload
    # gap, is the only difference in their states).
    assert acc["wear_area"] - pre_acc == pytest.approx(big["wear_area"] - pre_big, rel=1e-6)


def test_failed_increment_is_reported_and_leaves_no_trace(tmp_path, monkeypatch):
    """A local solve that fails mid-cycle (cycle 3, step 30: 29 increments of that cycle have worn the surface)
    stops the run with a diagnostic naming it; the tables, the summary and the checkpoint stay at the last
    complete cycle (the checkpoint's wear gap bit for bit that of the cycle-2 checkpoint), and a resume with
    the solver restored then ends as an uninterrupted run does."""
    base = SMALL_BLOCK + ["output.contact_profiles=false", "solver.local_tol=1e-12", "solver.cycle_kernel=false"]
    straight = run_scene(load_scene("stromberg-block", base + ["loading.cycles=4"]), tmp_path / "straight", quiet=True)
    out = tmp_path / "run"
    two = run_scene(load_scene("stromberg-block", base + ["loading.cycles=2"]), out, quiet=True)
    gw_two = read_checkpoint(out / CHECKPOINT)[1]["wear_gap"].copy()
    solve = FrettingProblem.solve
    seen = {}

    def starved_at_cycle_3_step_30(self, state, *args, **kwargs):
        if state.increment == 190:  # increment 191 = cycle 3, step 30 (1 preload + 2 x 80 + 30)
            # one sweep cannot meet 1e-12 here: a genuine local failure
            seen["gw"] = state.wear_gap.copy()
            saved, self.solver = self.solver, dataclasses.replace(self.solver, max_iter=1)
            try:
                return solve(self, state, *args, **kwargs)
            finally:
                self.solver = saved
        return solve(self, state, *args, **kwargs)

    monkeypatch.setattr(FrettingProblem, "solve", starved_at_cycle_3_step_30)
    with pytest.raises(SimulationError, match=r"increment 191 \(cycle 3, step 30\): local solver did not converge"):
        run_scene(load_scene("stromberg-block", base + ["loading.cycles=4"]), out, quiet=True, resume=True)
    monkeypatch.setattr(FrettingProblem, "solve", solve)
    # the failure came after wear had accrued in cycle 3 ...
    assert seen["gw"].max() > gw_two.max()
    # ... and none of it is kept: summary, tables and the checkpoint's wear gap are cycle 2's
    s = json.loads((out / "summary.json").read_text())
    assert s["converged"] is False and "cycle 3, step 30" in s["error"]
    assert s["cycles"] == 2 and s["max_wear_depth"] == two["max_wear_depth"]
    assert list(read_table(out / "cycles.csv")["cycle"]) == [1, 2]
    meta, data = read_checkpoint(out / CHECKPOINT)
    assert meta["cycle"] == 2 and np.array_equal(data["wear_gap"], gw_two)
    done = run_scene(load_scene("stromberg-block", base + ["loading.cycles=4"]), out, quiet=True, resume=True)
    assert done["resumed_from_cycle"] == 2 and done["cycles_this_run"] == 2
    assert done["max_wear_depth"] == straight["max_wear_depth"]  # same path from the same state: bit for bit
    assert list(read_table(out / "cycles.csv")["cycle"]) == [1, 2, 3, 4]


LOCAL_METHODS_BASE = SMALL_BLOCK + ["loading.cycles=2", "solver.local_tol=1e-12",
                                    "output.contact_profiles=false"]


@pytest.fixture(scope="module")
def uzawa_run(tmp_path_factory):
    """The Uzawa run both local methods are compared with (run once for the module: a serial run is
    deterministic, so each method meets the same reference it would have run itself)."""
    return run_scene(load_scene("stromberg-block", LOCAL_METHODS_BASE), tmp_path_factory.mktemp("uzawa"),
                     quiet=True)


@pytest.mark.parametrize("method", ["newton", "auto"])
def test_local_methods_give_the_same_run(tmp_path, method, uzawa_run):
    """The scene's solver.local_method reaches the per-increment path and gives the Uzawa run's answer.
    (Plain NSGS cycles without converging at this scene's load reversal, cycle 1 step 40: natural-map error
    0.17 after 20000 sweeps; the run stops and says so — see test_nsgs_stall_is_reported.)"""
    base, ref = LOCAL_METHODS_BASE, uzawa_run
    other = run_scene(load_scene("stromberg-block", base + [f"solver.local_method='{method}'"]), tmp_path / method,
                      quiet=True)
    assert other["cycle_path"] == "python"
    for key in ("max_wear_depth", "wear_area", "dissipated_energy", "tangential_force"):
        assert other[key] == pytest.approx(ref[key], rel=1e-7), key


def test_nsgs_stall_is_reported(tmp_path):
    base = SMALL_BLOCK + ["loading.cycles=1", "solver.local_tol=1e-12", "solver.local_max_iter=2000",
                          "solver.local_method='nsgs'", "output.contact_profiles=false"]
    with pytest.raises(SimulationError, match=r"cycle 1, step \d+\): local solver did not converge"):
        run_scene(load_scene("stromberg-block", base), tmp_path, quiet=True)


class _Cut(BaseException):
    """A kill between a cycle's writes and its checkpoint (a BaseException: nothing in the run catches it)."""


def _field_times(folder):
    """Each function's Time values in ``fields.xdmf``, in file order (the XDMF's temporal collections)."""
    root = ElementTree.parse(folder / "fields.xdmf").getroot()
    return {grid.get("Name"): [float(time.get("Value")) for time in grid.iter("Time")]
            for grid in root.iter("Grid") if grid.get("CollectionType") == "Temporal"}


def test_resume_after_a_cut_between_fields_and_checkpoint_writes_each_field_time_once(tmp_path, monkeypatch):
    """A run cut after cycle 4's fields were written and before its checkpoint (the last at cycle 2), then
    resumed: fields.xdmf holds the same times as an uncut run, each once, and the re-written step's
    displacement is the uncut run's. (Before the fix the resume appended cycle 4's step again: DOLFINx 0.11
    listed its time twice, 0.5.2 failed to create the HDF5 dataset of a name that exists.)"""
    base = ["geometry.nx=20", "geometry.ny=20", "output.xdmf=true", "output.plots=false", "loading.cycles=5",
            "output.snapshot_cycles=[2, 4]", "output.checkpoint_interval=1e6", "output.contact_profiles=false",
            "solver.cycle_kernel=false"]
    scene = load_scene("stromberg-block", base)
    run_scene(scene, tmp_path / "straight", quiet=True)
    checkpoint = simulation._Run.checkpoint

    def cut_at_cycle_4(self):
        if self.progress.cycle == 4:
            raise _Cut()
        checkpoint(self)

    monkeypatch.setattr(simulation._Run, "checkpoint", cut_at_cycle_4)
    cut = tmp_path / "cut"
    with pytest.raises(_Cut):
        run_scene(scene, cut, quiet=True)
    monkeypatch.setattr(simulation._Run, "checkpoint", checkpoint)
    assert read_checkpoint(cut / CHECKPOINT)[0]["cycle"] == 2
    straight_times = _field_times(tmp_path / "straight")
    cut_times = _field_times(cut)["displacement"]
    # the cut came after cycle 4's fields: the preload's, cycle 2's (counted by the checkpoint) and cycle 4's (not)
    assert cut_times == straight_times["displacement"][:3] and len(straight_times["displacement"]) == 4
    done = run_scene(scene, cut, quiet=True, resume=True)
    assert done["resumed_from_cycle"] == 2 and done["converged"]
    resumed_times = _field_times(cut)
    assert resumed_times == straight_times
    for times in resumed_times.values():
        assert len(set(times)) == len(times)
    # Same arithmetic from the same checkpointed state (serial, same path): the last step's displacement is the
    # uncut run's to round-off (1e-12 relative: the values are written and read back as float64)
    with h5py.File(tmp_path / "straight" / "fields.h5") as a, h5py.File(cut / "fields.h5") as b:
        name = f"/Function/displacement/{straight_times['displacement'][-1]:g}"
        np.testing.assert_allclose(b[name][:], a[name][:], rtol=1e-12, atol=1e-12 * np.abs(a[name][:]).max())
