"""SIGINT and SIGTERM stop a run cleanly: a final checkpoint, a summary marked interrupted, exit code 130/143,
and ``--resume`` continues to the uninterrupted run's answer (cyclic and monotonic runs); at any other stage
(the model's build, the pictures, a second signal while stopping) one line, the same codes, no lock left and a
summary that lists what is missing."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from dolfinx_fretting.interrupts import TEST_HOOK
from dolfinx_fretting.outdir import LOCK_NAME
from dolfinx_fretting.pictures import PICTURES
from dolfinx_fretting.simulation import CHECKPOINT, read_checkpoint

ENV = dict(os.environ, OPENBLAS_NUM_THREADS="1")
CLI = [sys.executable, "-m", "dolfinx_fretting", "run"]


def _run(args, out):
    subprocess.run(CLI + args + ["--out", str(out), "--quiet"], check=True, env=ENV, timeout=600)
    return json.loads((out / "summary.json").read_text())


def _interrupt(args, out, signum, ready) -> subprocess.CompletedProcess:
    """Start a run, send ``signum`` once ``ready()`` holds, return the finished process."""
    proc = subprocess.Popen(CLI + args + ["--out", str(out)], env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None and not ready():
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before it could be interrupted"
    proc.send_signal(signum)
    stdout, stderr = proc.communicate(timeout=300)
    return subprocess.CompletedProcess(proc.args, proc.returncode, stdout, stderr)


def _checkpointed_cycle(out) -> int:
    try:
        return read_checkpoint(out / CHECKPOINT)[0]["cycle"]
    except Exception:  # noqa: BLE001 - not there yet, or being replaced
        return 0


# SIGINT on the cyclic run is slow (7 s): one handler serves both signals (simulation._run_scene); by default
# the cyclic run meets it with SIGTERM (exit 143), and the monotonic run below with SIGINT (exit 130).
@pytest.mark.parametrize("signum, code", [pytest.param(signal.SIGINT, 130, marks=pytest.mark.slow),
                                          (signal.SIGTERM, 143)])
def test_cyclic_run_interrupted_then_resumed(tmp_path, signum, code):
    args = ["stromberg-block", "--set", "geometry.nx=20", "--set", "geometry.ny=20", "--set", "loading.cycles=3000",
            "--set", "output.xdmf=false", "--set", "output.plots=false", "--set", "output.contact_profiles=false",
            "--set", "output.checkpoint_interval=0.01", "--set", "output.progress=false"]
    out = tmp_path / "cut"
    done = _interrupt(args, out, signum, lambda: _checkpointed_cycle(out) >= 3)
    assert done.returncode == code, done.stderr[-2000:]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] == signum.name and summary["converged"] is False
    assert "continue with --resume" in summary["error"]
    stopped = summary["cycles"]
    assert 3 <= stopped < 3000 and read_checkpoint(out / CHECKPOINT)[0]["cycle"] == stopped
    # Resume to a shorter end than planned (the same scene otherwise): it continues from the checkpoint
    # and ends where an uninterrupted run to that cycle ends.
    end = stopped + 5
    short = [f"loading.cycles={end}" if a.startswith("loading.cycles=") else a for a in args]
    resumed = _run(short + ["--resume"], out)
    straight = _run(short, tmp_path / "straight")
    assert resumed["cycles"] == straight["cycles"] == end
    # The compiled loop's pattern cache restarts on resume: equal to the local tolerance, not bit for bit.
    assert resumed["max_wear_depth"] == pytest.approx(straight["max_wear_depth"], rel=1e-8)


def test_monotonic_run_interrupted_then_resumed(tmp_path):
    args = ["hertz", "--set", "geometry.contact_mesh_size=0.04", "--set", "loading.tangential_increments=400",
            "--set", "output.xdmf=false", "--set", "output.plots=false", "--set", "output.contact_profiles=false"]
    out = tmp_path / "cut"
    history = out / "history.csv"
    done = _interrupt(args, out, signal.SIGINT,
                      lambda: history.is_file() and history.read_text().count("\n") > 20)
    assert done.returncode == 130, done.stderr[-2000:]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] == "SIGINT" and 20 <= summary["increments"] < 404
    resumed = _run(args + ["--resume"], out)
    straight = _run(args, tmp_path / "straight")
    assert resumed["increments"] == straight["increments"] == 404
    # The same increments from the same committed state; only the force control's slope estimate (a solver
    # warm start, not state) restarts, so the converged points agree to its tolerance, force_tol = 1e-8
    # (measured 9e-12).
    for key in ("normal_force", "tangential_force", "max_pressure", "stick_width"):
        assert resumed[key] == pytest.approx(straight[key], rel=1e-8), key


# Signals outside the cycle loop ------------------------------------------------------------------------------
#: A short run that draws its plots and pictures (~15 s here): the pictures' stage is reached quickly.
DRAWN = ["stromberg-block", "--set", "geometry.nx=8", "--set", "geometry.ny=8", "--set", "loading.cycles=1",
         "--set", "loading.increments_per_cycle=8", "--set", "output.progress=false", "--quiet"]


def _interrupt_at(stage, args, out, signum) -> subprocess.CompletedProcess:
    """Start a run that stops at ``stage`` (the test hook, interrupts.TEST_HOOK: it says so on stderr and waits
    there), send ``signum`` once it is there, return the finished process."""
    env = dict(ENV, **{TEST_HOOK: stage})
    proc = subprocess.Popen(CLI + args + ["--out", str(out)], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    first = proc.stderr.readline()  # blocks until the hook speaks (or the run ends: then the assert says so)
    assert first.strip() == f"test hook: {stage}", first + proc.stderr.read()
    proc.send_signal(signum)
    stdout, stderr = proc.communicate(timeout=300)
    return subprocess.CompletedProcess(proc.args, proc.returncode, stdout, stderr)


@pytest.mark.parametrize("stage", ["model", "delassus"])
def test_a_signal_while_the_model_is_built_stops_with_a_message_and_a_summary(tmp_path, stage):
    """Before: SIGINT while W was built ended in a KeyboardInterrupt traceback and left the lock file. Now: exit
    130, one line, no lock, and a summary listing every output as missing; --overwrite starts afresh (the
    summary makes the folder a run's; there is no checkpoint, so --resume is not offered)."""
    out = tmp_path / "run"
    done = _interrupt_at(stage, DRAWN, out, signal.SIGINT)
    assert done.returncode == 130, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert lines[0].startswith("dolfinx-fretting: interrupted by SIGINT while the model was built"), lines
    assert sorted(os.listdir(out)) == ["summary.json"]  # no lock file left, nothing else written
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False and summary["interrupted"] == "SIGINT"
    assert summary["interrupted_during"] == "model" and summary["increments"] == 0
    assert {"history.csv", "checkpoint.npz", "plots", *PICTURES} <= set(summary["missing"])
    again = subprocess.run(CLI + DRAWN + ["--out", str(out)], env=ENV, capture_output=True, text=True, timeout=300)
    assert again.returncode == 2 and "no checkpoint to resume from" in again.stderr and "--resume" not in again.stderr


@pytest.mark.parametrize("signum, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_while_the_pictures_are_drawn(tmp_path, signum, code):
    """Before: SIGTERM while drawing killed the run (the lock left, a summary saying converged with the pictures
    missing), SIGINT ended in a traceback. Now: the drawing process is stopped, exit 130/143 with one line, no
    lock, and the summary (the results are complete: converged stays true) lists the pictures as missing."""
    out = tmp_path / "run"
    done = _interrupt_at("pictures", DRAWN, out, signum)
    assert done.returncode == code, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert f"interrupted by {signum.name} while the outputs were written" in lines[0]
    assert "python -m dolfinx_fretting.pictures" in lines[0]
    assert LOCK_NAME not in os.listdir(out)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is True and summary["cycles"] == 1  # the numbers are all there
    assert summary["interrupted"] == signum.name and summary["interrupted_during"] == "outputs"
    assert summary["missing"] == list(PICTURES)
    assert not any((out / name).exists() for name in PICTURES)
    assert (out / "profiles.png").is_file()  # the plots before them were drawn


def test_a_second_signal_while_stopping_is_only_noted(tmp_path):
    """Before: a second Ctrl-C while the run stopped (its handlers were gone once the cycles ended: summary,
    plots, pictures) was a KeyboardInterrupt traceback. Now it is noted: the run ends with its first signal's
    code and one line, and skips the plots and pictures (the summary lists them)."""
    args = ["stromberg-block", "--set", "geometry.nx=8", "--set", "geometry.ny=8", "--set", "loading.cycles=3000",
            "--set", "output.checkpoint_interval=0.01", "--set", "output.progress=false", "--quiet"]
    out = tmp_path / "run"
    proc = subprocess.Popen(CLI + args + ["--out", str(out)], env=dict(ENV, **{TEST_HOOK: "stopping"}),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None and _checkpointed_cycle(out) < 2:
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    first = proc.stderr.readline()  # the run stopped its cycles, wrote its summary and waits at the hook
    assert first.strip() == "test hook: stopping", first + proc.stderr.read()
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 130, stderr
    assert len(stderr.strip().splitlines()) == 1 and "Traceback" not in stderr, stderr
    assert "interrupted by SIGINT after increment" in stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] == "SIGINT" and summary["interrupted_during"] == "increments"
    assert summary["missing"] == ["plots", *PICTURES] and not (out / "profiles.png").exists()
    assert LOCK_NAME not in os.listdir(out)
