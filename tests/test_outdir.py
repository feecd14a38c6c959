"""Output folders (dolfinx_fretting.outdir): checked before any work, locked while a run uses them, replaced
only with --overwrite and then only of the package's files; --resume refuses a folder it cannot resume from."""

import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from dolfinx_fretting._dolfinx import mpiexec
from dolfinx_fretting.io import ResultWriter, TableError
from dolfinx_fretting.outdir import (LOCK_NAME, RUN_FILES, OutputFolderError, check_output_folder,
                                     claim_output_folder, clear_run_files, load_checkpoint, lock_holder)
from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import CHECKPOINT, SimulationError, read_checkpoint, run_scene

SMALL_BLOCK = ["geometry.nx=20", "geometry.ny=20", "output.xdmf=false", "output.plots=false",
               "output.contact_profiles=false", "output.progress=false"]
#: A folder that exists and cannot be written even by root (sysfs is mounted read-only for files we create).
READ_ONLY_DIR = "/sys/kernel"


def test_out_that_is_a_file_under_a_file_or_read_only(tmp_path):
    f = tmp_path / "a_file"
    f.write_text("not a folder")
    with pytest.raises(OutputFolderError, match=r"is a file, not a folder"):
        check_output_folder(f)
    with pytest.raises(OutputFolderError, match=rf"is under {f}, which is a file"):
        check_output_folder(f / "sub" / "dir")
    assert os.path.isdir(READ_ONLY_DIR)
    with pytest.raises(OutputFolderError, match="is not writable"):
        check_output_folder(READ_ONLY_DIR)
    with pytest.raises(OutputFolderError, match="give one"):
        check_output_folder(tmp_path / "x", resume=True, overwrite=True)
    # a folder not there yet is checked where it would be created, and not created: a run refused later (a mesh
    # file's fault) must leave nothing behind; the run's claim creates it
    assert check_output_folder(tmp_path / "new" / "folder") == tmp_path / "new" / "folder"
    assert sorted(os.listdir(tmp_path)) == ["a_file"]  # nor the write probe
    with pytest.raises(OutputFolderError, match=f"cannot be created in {READ_ONLY_DIR}: "):
        check_output_folder(Path(READ_ONLY_DIR) / "new")
    with pytest.raises(OutputFolderError, match="no checkpoint"):
        check_output_folder(tmp_path / "new", resume=True)
    with claim_output_folder(tmp_path / "new" / "folder", MPI.COMM_WORLD):
        assert os.listdir(tmp_path / "new" / "folder") == [LOCK_NAME]  # the write probe is gone
    assert not (tmp_path / "new").exists()  # the claim created it (and its parent): left empty, it is deleted


def test_a_second_run_into_a_locked_folder_is_refused_with_the_holders_pid(tmp_path):
    """Another process holds the lock: refused, naming its pid. When it is killed (-9), the kernel drops its
    flock; the lock file it leaves, with its dead pid, is taken over."""
    out = tmp_path / "run"
    holder = subprocess.Popen([sys.executable, "-c",
                               "import sys, time\n"
                               "from dolfinx_fretting.outdir import claim_output_folder\n"
                               f"lock = claim_output_folder({str(out)!r})\n"
                               "print('locked', flush=True)\n"
                               "time.sleep(600)\n"], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(OutputFolderError, match=rf"in use by another run \(pid {holder.pid} on"):
            claim_output_folder(out, MPI.COMM_WORLD)
        # the same through run_scene: refused before the mesh (nothing else is written)
        with pytest.raises(OutputFolderError, match=rf"pid {holder.pid}"):
            run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=1"]), out, quiet=True)
        assert sorted(os.listdir(out)) == [LOCK_NAME]
    finally:
        holder.kill()
        holder.wait()
    assert lock_holder(out)["pid"] == holder.pid  # the dead run's lock file is still there ...
    with claim_output_folder(out, MPI.COMM_WORLD) as lock:  # ... and is taken over
        assert lock.previous_holder["pid"] == holder.pid
        assert lock_holder(out)["pid"] == os.getpid()
        # a second claim in this very process is refused too (flock is per open file)
        with pytest.raises(OutputFolderError, match=rf"pid {os.getpid()}"):
            claim_output_folder(out, MPI.COMM_WORLD)
    assert not (out / LOCK_NAME).exists()  # released: the file is gone


def test_a_folder_holding_a_run_is_refused_unless_resume_or_overwrite(tmp_path):
    scene = load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=1"])
    first = run_scene(scene, tmp_path, quiet=True)
    (tmp_path / "notes.txt").write_text("mine")
    (tmp_path / "mine.png").write_bytes(b"png")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "history.csv").write_text("foreign")
    before = (tmp_path / "history.csv").read_text()
    with pytest.raises(OutputFolderError, match=r"already holds a run \(summary.json, run.json, checkpoint.npz, history.csv, "
                                                r"cycles.csv\); continue it with --resume, replace it with "
                                                r"--overwrite"):
        run_scene(scene, tmp_path, quiet=True)
    assert (tmp_path / "history.csv").read_text() == before  # untouched
    # --overwrite deletes the old run (its checkpoint included) and runs again; foreign files stay
    (tmp_path / "wear_growth.png").write_bytes(b"an old picture of the old run")
    again = run_scene(scene, tmp_path, quiet=True, overwrite=True)
    assert again["max_wear_depth"] == first["max_wear_depth"] and again["resumed_from_cycle"] is None
    assert not (tmp_path / "wear_growth.png").exists()
    assert (tmp_path / "notes.txt").read_text() == "mine" and (tmp_path / "mine.png").read_bytes() == b"png"
    assert (tmp_path / "sub" / "history.csv").read_text() == "foreign"
    # clear_run_files deletes exactly the package's names
    removed = clear_run_files(tmp_path)
    assert set(removed) <= set(RUN_FILES) and "summary.json" in removed and "checkpoint.npz" in removed
    assert sorted(os.listdir(tmp_path)) == ["mine.png", "notes.txt", "sub"]


def _three_cycles(folder):
    run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=3"]), folder, quiet=True)


def test_resume_refuses_a_table_shorter_than_the_checkpoint(tmp_path):
    """Before: truncate(size) on a shorter file padded it with NUL bytes and the resume went on."""
    _three_cycles(tmp_path)
    cycles = tmp_path / "cycles.csv"
    text = cycles.read_text()
    cycles.write_text(text[: len(text) // 2])
    with pytest.raises(SimulationError,
                       match=rf"--resume: {cycles} holds \d+ bytes, fewer than the \d+ the checkpoint"):
        run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=4"]), tmp_path, quiet=True, resume=True)
    assert b"\x00" not in cycles.read_bytes()
    cycles.unlink()
    with pytest.raises(SimulationError, match=rf"{cycles} is missing but the checkpoint"):
        run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=4"]), tmp_path, quiet=True, resume=True)


def test_result_writer_refuses_a_short_table_itself(tmp_path):
    """The writer's own guard (the runner checks the checkpoint first; the writer must not pad with NULs)."""
    (tmp_path / "history.csv").write_text("increment\n1\n")
    (tmp_path / "cycles.csv").write_text("cycle\n")
    with pytest.raises(TableError, match=r"history.csv holds 12 bytes, fewer than the 400"):
        ResultWriter(tmp_path, MPI.COMM_WORLD, profiles=False, resume_sizes={"history": 400, "cycles": 6})
    assert (tmp_path / "history.csv").read_bytes() == b"increment\n1\n"


@pytest.mark.parametrize("damage", ["not_a_zip", "truncated", "no_meta"])
def test_resume_refuses_a_checkpoint_that_does_not_load(tmp_path, damage):
    _three_cycles(tmp_path)
    ck = tmp_path / CHECKPOINT
    data = ck.read_bytes()
    if damage == "not_a_zip":
        ck.write_bytes(b"garbage" * 100)
    elif damage == "truncated":
        ck.write_bytes(data[: len(data) // 2])
    else:
        with np.load(ck) as z:
            arrays = {k: z[k] for k in z.files if k != "state"}  # the record is gone
        np.savez(ck, **arrays)
    with pytest.raises(SimulationError, match=rf"--resume: the checkpoint {ck} cannot be read \("):
        run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=4"]), tmp_path, quiet=True, resume=True)


def test_resume_refuses_fewer_cycles_than_done(tmp_path):
    _three_cycles(tmp_path)
    with pytest.raises(SimulationError, match=r"loading.cycles = 2 is below the 3 cycles the checkpoint .* has done; "
                                              r"allowed: loading.cycles >= 3"):
        run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=2"]), tmp_path, quiet=True, resume=True)
    ck = load_checkpoint(tmp_path / CHECKPOINT, 3)  # the same count: allowed (nothing left to run)
    assert ck["meta"]["cycle"] == 3


def test_resume_with_a_changed_material_names_the_key(tmp_path):
    _three_cycles(tmp_path)
    with pytest.raises(SimulationError) as info:
        run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=4", "material.E=200000",
                                                                 "solver.local_tol=1e-12"]),
                  tmp_path, quiet=True, resume=True)
    msg = str(info.value)
    assert "material.E = 210000.0 (checkpoint), 200000.0 (this scene)" in msg
    assert "solver" not in msg.split("loading.cycles:")[1]  # the allowed changes are not listed


def test_cli_output_folder_errors(tmp_path, capsys):
    """The command line says what is wrong with --out (exit 2), before it imports DOLFINx or meshes."""
    from dolfinx_fretting.cli import main

    f = tmp_path / "file"
    f.write_text("x")
    base = ["run", "stromberg-block", "--quiet"] + [a for o in SMALL_BLOCK + ["loading.cycles=1"] for a in ("--set", o)]
    for out, words in ((f, "is a file"), (f / "sub", "which is a file"), (READ_ONLY_DIR, "is not writable")):
        assert main(base + ["--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert words in err and str(out) in err
    good = tmp_path / "run"
    assert main(base + ["--out", str(good)]) == 0
    assert main(base + ["--out", str(good)]) == 2
    assert "already holds a run" in capsys.readouterr().err
    assert main(base + ["--out", str(good), "--overwrite"]) == 0
    assert main(base + ["--out", str(good), "--overwrite", "--resume"]) == 2
    assert "give one" in capsys.readouterr().err
    assert main(base + ["--out", str(tmp_path / "empty"), "--resume"]) == 2
    assert "--resume: no checkpoint" in capsys.readouterr().err


def test_cli_compare_and_study_out_that_is_a_file(tmp_path):
    """compare --out FILE and study --out FILE: a message and exit code 2, no traceback."""
    f = tmp_path / "file"
    f.write_text("x")
    run = tmp_path / "run"
    run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=1"]), run, quiet=True)
    for cmd in (["compare", str(run), "--out", str(f)],
                ["study", "stromberg-block", "--out", str(f / "sub"), "--set", "loading.cycles=1"]):
        proc = subprocess.run([sys.executable, "-m", "dolfinx_fretting", *cmd], capture_output=True, text=True,
                              timeout=300)
        assert proc.returncode == 2, proc.stderr
        assert "Traceback" not in proc.stderr and "is a file" in proc.stderr, proc.stderr
    assert json.loads((run / "summary.json").read_text())["converged"] is True


# A folder that goes during the run ---------------------------------------------------------------------------
#: A run of 3000 cycles (minutes): long enough to lose its folder after its second checkpoint.
LONG = ["stromberg-block", "--quiet", "--set", "loading.cycles=3000", "--set", "output.checkpoint_interval=0.01",
        *(a for o in SMALL_BLOCK for a in ("--set", o))]


def _checkpointed_cycle(out) -> int:
    try:
        return read_checkpoint(out / CHECKPOINT)[0]["cycle"]
    except Exception:  # noqa: BLE001 - not there yet, or being replaced
        return 0


def _lose_folder_mid_run(out, lose, launcher=()) -> subprocess.CompletedProcess:
    """Start a run into ``out``, call ``lose(out)`` after its second checkpoint, return the finished process."""
    proc = subprocess.Popen([*launcher, sys.executable, "-m", "dolfinx_fretting", "run", *LONG, "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, OPENBLAS_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1",
                                     OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMPI_MCA_rmaps_base_oversubscribe="1"))
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None and _checkpointed_cycle(out) < 2:
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before its folder could be taken away"
    lose(out)
    stdout, stderr = proc.communicate(timeout=300)
    return subprocess.CompletedProcess(proc.args, proc.returncode, stdout, stderr)


def _delete(out):
    while out.exists():  # the run may add a file (a checkpoint's temporary) while the tree is deleted
        shutil.rmtree(out, ignore_errors=True)


def test_a_deleted_output_folder_stops_the_run(tmp_path):
    """Before: ``rm -rf`` of --out during the cycles went unnoticed; the run recreated the folder and exited 0
    with ``converged: true`` (history, cycles, run.json gone). Now it stops at its next write with exit 1 and
    one line, and writes nothing more: no folder is recreated, no summary says anything."""
    out = tmp_path / "run"
    done = _lose_folder_mid_run(out, _delete)
    assert done.returncode == 1, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    # rm -rf deletes the files first: the run may find its lock file gone before the folder
    assert re.match(rf"dolfinx-fretting: run failed: --out {out}( was deleted|: the run's lock file "
                    rf"{LOCK_NAME} was deleted)", lines[0]), lines
    assert "writes nothing more" in lines[0]
    assert not out.exists()


def test_a_replaced_output_folder_stops_the_run_and_is_left_alone(tmp_path):
    """--out moved away and a new empty folder made in its place: the run stops (exit 1, one line), writes
    nothing into the new folder and takes its lock file out of the old one; the old one keeps what was written
    (its tables) and no summary."""
    out, old = tmp_path / "run", tmp_path / "moved"

    def replace(folder):
        folder.rename(old)
        folder.mkdir()

    done = _lose_folder_mid_run(out, replace)
    assert done.returncode == 1, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    # the rename and the mkdir are two steps: the run may look in between (then the folder is gone)
    assert re.search(rf"--out {out} was (replaced|deleted \(or moved away\)) during the run", lines[0]), lines
    assert os.listdir(out) == []
    assert LOCK_NAME not in os.listdir(old) and "summary.json" not in os.listdir(old)
    assert (old / "cycles.csv").read_text().count("\n") >= 3  # header and the cycles before the move


def test_a_deleted_lock_file_stops_the_run(tmp_path):
    """The lock file deleted (the folder kept): another run could take the folder; this one stops (exit 1)."""
    done = _lose_folder_mid_run(tmp_path / "run", lambda out: (out / LOCK_NAME).unlink())
    assert done.returncode == 1 and f"lock file {LOCK_NAME} was deleted or replaced" in done.stderr, done.stderr
    assert json.loads((tmp_path / "run" / "run.json").read_text())  # the folder's files are left as they were
    assert not (tmp_path / "run" / "summary.json").exists()


@pytest.mark.mpi  # 3-10 s here (26 s on a machine loaded by other jobs), as test_mpi_failures.py's cases
def test_a_deleted_output_folder_stops_every_rank(tmp_path):
    """Under ``mpirun -n 2``: rank 0 finds the folder gone and says so to every rank (one message, not one
    traceback per rank), exit 1, nothing recreated."""
    out = tmp_path / "run"
    done = _lose_folder_mid_run(out, _delete, launcher=mpiexec(2))
    output = done.stdout + done.stderr
    assert done.returncode == 1, output
    assert output.count(f"--out {out}") == 1 and output.count("was deleted") == 1, output
    assert "Traceback" not in output and "stopping all" not in output, output
    assert not out.exists()


def test_files_written_into_a_replacement_folder_are_taken_back(tmp_path):
    """The run's bookkeeping of what it wrote since its last folder check (simulation._Run.note_written) and its
    taking back of those files when the folder turned out to be replaced (_Run._take_back): a run file written
    after the replacement is deleted; the new folder's other files, and a run file it creates after the run's
    write, stay (inodes, not names, say whose a file is)."""
    from types import SimpleNamespace

    from dolfinx_fretting.simulation import _Run

    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("the new folder's own")
    (out / "history.csv").write_text("a row the run wrote after the folder was replaced")
    run = SimpleNamespace(rank0=True, lock=object(), out=out, _fresh=set())
    _Run.note_written(run)
    (out / "summary.json").write_text("{}")   # the new folder's owner writes a run file of its own afterwards
    _Run._take_back(run, run._fresh)
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "summary.json"]
    _Run.note_written(SimpleNamespace(rank0=True, lock=object(), out=tmp_path / "gone", _fresh=set()))  # no folder
