"""Never a silent wrong answer: no run reports success with a non-finite number, every JSON written is valid
JSON, and the command line answers bad input and failed runs with a message and an exit code."""

import json
import math
import os
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

from dolfinx_fretting.io import finite_json, write_json_atomic
from dolfinx_fretting.outdir import LOCK_NAME, RUN_FILES
from dolfinx_fretting.scenes import SceneError, load_scene
from dolfinx_fretting.simulation import SimulationError, run_scene

SMALL_BLOCK = ["geometry.nx=20", "geometry.ny=20", "output.xdmf=false", "output.plots=false",
               "output.progress=false"]


def _strict_json(path):
    """json.loads that refuses NaN and Infinity (RFC 8259), as a non-Python reader would."""
    def refuse(name):
        raise ValueError(f"not JSON: {name}")
    return json.loads(path.read_text(), parse_constant=refuse)


def test_write_json_atomic_writes_null_and_names_non_finite_keys(tmp_path):
    data = {"a": 1.0, "b": math.inf, "c": {"d": [1.0, np.float32("nan"), 2]}, "e": np.array([np.inf, 0.0]),
            "f": np.float64(-np.inf), "g": "text", "h": None}
    write_json_atomic(tmp_path / "x.json", data)
    back = _strict_json(tmp_path / "x.json")
    assert back["b"] is None and back["c"]["d"] == [1.0, None, 2] and back["e"] == [None, 0.0] and back["f"] is None
    assert back["non_finite_keys"] == ["b", "c.d[1]", "e[0]", "f"]
    assert back["a"] == 1.0 and back["g"] == "text" and back["h"] is None
    write_json_atomic(tmp_path / "y.json", {"a": 1.0})
    assert "non_finite_keys" not in _strict_json(tmp_path / "y.json")
    assert finite_json({"x": [1, 2]}) == ({"x": [1, 2]}, [])


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")  # inf - inf: the point of the test
def test_a_run_with_a_non_finite_result_is_not_a_success(tmp_path, monkeypatch):
    """wear.k = inf got through validation once and the run ended 'converged' with max_wear_depth inf (and
    NaN written into summary.json). The scene refuses it now, and so does the API (Archard); behind both (an
    infinite coefficient forced into the problem and the per-cycle wear guard skipped, as a future bug could),
    the run itself must refuse to call such a result converged."""
    from dolfinx_fretting import simulation
    from dolfinx_fretting.laws import Archard

    with pytest.raises(SceneError, match=r"wear.k = inf"):
        load_scene("stromberg-block", SMALL_BLOCK + ["wear.k=inf"])
    with pytest.raises(ValueError, match=r"Archard.k = inf"):
        Archard(math.inf)
    scene = load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=2", "output.contact_profiles=false"])
    monkeypatch.setattr(Archard, "coefficient", lambda self, in_cycle: math.inf)  # the law: every path reads it
    monkeypatch.setattr(simulation._Run, "_check_wear_step", lambda self, *args: None)
    with pytest.raises(SimulationError, match=r"non-finite results: .*max_wear_depth"):
        run_scene(scene, tmp_path, quiet=True)
    s = _strict_json(tmp_path / "summary.json")  # valid JSON
    assert s["converged"] is False and "non-finite results" in s["error"]
    assert "max_wear_depth" in s["non_finite_keys"] and s["max_wear_depth"] is None


def _cli(*args, timeout=300):
    return subprocess.run([sys.executable, "-m", "dolfinx_fretting", *args], capture_output=True, text=True,
                          timeout=timeout)


@pytest.mark.parametrize("override, words", [
    ("wear.k=inf", "wear.k = inf"),
    ("loading.normal_force=inf", "loading.normal_force = inf"),
    ("loading.tangential_pressure=nan", "loading.tangential_pressure = nan"),
    ("material.E=inf", "material.E = inf"),
])
def test_cli_refuses_the_user_sweeps_values_before_any_work(tmp_path, override, words):
    out = tmp_path / "out"
    proc = _cli("run", "stromberg-block", "--out", str(out), "--set", override)
    assert proc.returncode == 2 and words in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
    assert not out.exists()


def test_cli_petsc_failure_is_a_message(tmp_path):
    """An option that passes validation but that MUMPS refuses when it factorises (1 MB of working memory):
    exit code 1 and the MUMPS error, no traceback."""
    proc = _cli("run", "hertz", "--out", str(tmp_path / "out"), "--quiet", "--set", "geometry.contact_mesh_size=0.02",
                "--set", "output.xdmf=false", "--set", "output.plots=false",
                "--set", "solver.petsc_options={mat_mumps_icntl_23=1}")
    assert proc.returncode == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    assert "run failed: PETSc/MUMPS: MUMPS factorize failed: INFOG(1)=-19" in proc.stderr
    assert "mat_mumps_icntl_23" in proc.stderr and len(proc.stderr.splitlines()) == 1


def test_cli_bad_petsc_option_refused_up_front(tmp_path):
    proc = _cli("run", "hertz", "--out", str(tmp_path / "out"), "--set", "solver.petsc_options={pc_type='jacobi'}")
    assert proc.returncode == 2 and "solver.petsc_options.pc_type = 'jacobi'" in proc.stderr
    assert not (tmp_path / "out").exists()


def test_study_refuses_a_non_finite_sweep_up_front(tmp_path):
    proc = _cli("study", "stromberg-block", "--out", str(tmp_path / "s"), "--sweep", "wear.k=1e-5,inf",
                "--set", "loading.cycles=2")
    assert proc.returncode == 2 and "wear.k = inf" in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
    assert not (tmp_path / "s" / "runs").exists()


def test_study_never_records_a_non_finite_point_as_converged(tmp_path):
    """A point whose summary says converged but holds a non-finite value (null + non_finite_keys, or a NaN in
    its profile) is recorded as failed, with NaN errors."""
    from dolfinx_fretting.study import point_errors

    ref = tmp_path / "ref"
    run_scene(load_scene("stromberg-block", SMALL_BLOCK + ["loading.cycles=1", "output.snapshot_cycles=[1]"]), ref,
              quiet=True)
    good = point_errors(ref, ref)
    assert good["converged"] is True and good["err_max_wear"] == 0.0
    bad = tmp_path / "bad"
    bad.mkdir()
    for name in ("summary.json", "cycles.csv", "history.csv", "contact_profiles.csv"):
        (bad / name).write_bytes((ref / name).read_bytes())
    s = json.loads((ref / "summary.json").read_text())
    s["max_wear_depth"] = math.inf
    write_json_atomic(bad / "summary.json", s)  # null, listed in non_finite_keys
    row = point_errors(bad, ref)
    assert row["converged"] is False and "max_wear_depth" in row["error"]
    # a NaN in the worn profile, the summary finite
    write_json_atomic(bad / "summary.json", json.loads((ref / "summary.json").read_text()))
    lines = (bad / "contact_profiles.csv").read_text().splitlines()
    head = lines[0].split(",")
    last = lines[-1].split(",")
    last[head.index("wear")] = "nan"
    (bad / "contact_profiles.csv").write_text("\n".join(lines[:-1] + [",".join(last)]) + "\n")
    row = point_errors(bad, ref)
    assert row["converged"] is False and "contact_profiles.csv wear" in row["error"]


# A full disk -------------------------------------------------------------------------------------------------
@pytest.fixture
def small_disk(tmp_path):
    """A 1 MB tmpfs (a real file system that fills: ENOSPC from the kernel, as on a full disk). Needs root and
    ``mount``; skipped elsewhere (tests/test_mpi_failures.py's disk_full case injects the error instead)."""
    mount = tmp_path / "disk"
    mount.mkdir()
    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("a tmpfs needs root and mount")
    made = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(mount)], capture_output=True)
    if made.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {made.stderr.decode().strip()}")
    try:
        yield mount
    finally:
        subprocess.run(["umount", str(mount)], check=True)


def _fill(disk, leave: int) -> None:
    """Fill ``disk`` up, then free ``leave`` bytes (tmpfs counts 4 KiB pages)."""
    with open(disk / "filler", "wb", buffering=0) as f:
        try:
            while True:
                f.write(b"\0" * 4096)
        except OSError:
            pass
    size = (disk / "filler").stat().st_size
    os.truncate(disk / "filler", max(0, size - leave))


SMALL_DRAWN = ["stromberg-block", "--quiet", "--set", "geometry.nx=16", "--set", "geometry.ny=16",
               "--set", "loading.cycles=3", "--set", "output.progress=false"]


def test_a_full_disk_at_the_first_write_is_one_line(small_disk):
    """Nothing free: the lock file cannot be written; one line (exit 2), and no empty lock file left behind
    (before: a 0-byte lock file stayed)."""
    _fill(small_disk, 0)
    proc = _cli("run", *SMALL_DRAWN, "--out", str(small_disk / "out"))
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip() == f"dolfinx-fretting: --out {small_disk / 'out'}: No space left on device"
    assert os.listdir(small_disk / "out") == []


@pytest.mark.parametrize("leave_kib", [16, 40])
def test_a_full_disk_at_the_first_writes_is_one_line(small_disk, leave_kib):
    """Room for the lock, not for the first fields (~30 kB here) or the tables' first flush: before, the first
    XDMF write dumped HDF5's error stack (~60 lines) and a RuntimeError traceback (DOLFINx 0.5), or aborted the
    process in HDF5 (the current wheel: exit 134). Now: one line naming the file (exit 1), no lock left."""
    _fill(small_disk, leave_kib * 1024)
    out = small_disk / "out"
    proc = _cli("run", *SMALL_DRAWN, "--out", str(out))
    assert proc.returncode == 1, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "HDF5" not in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
    written = re.fullmatch(rf"dolfinx-fretting: run failed: writing the outputs: \[Errno 28\] {out}/(\S+) "
                           r"(\(and its .h5\) )?not written: (.*)", lines[0])
    assert written and written[1] in RUN_FILES, lines
    assert "free on its file system" in written[3], lines
    assert LOCK_NAME not in os.listdir(out)
