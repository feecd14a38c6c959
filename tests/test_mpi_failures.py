"""Under MPI an error on any rank stops every rank with one message within seconds, never a hang: input errors
(every rank refuses the same scene), a solver failure (decided on rank 0, raised on every rank), an output error
on rank 0 alone (only rank 0 writes the tables: a full disk) and a bug on the last rank alone. 2 and 3 ranks.

Each case starts ``mpiexec -n N python driver.py CASE -- CLI ARGS``: the driver injects the fault (on one rank
where the case says so) and calls :func:`dolfinx_fretting.cli.main` as ``dolfinx-fretting`` does.
"""

import subprocess
import sys
import time

import pytest

from dolfinx_fretting._dolfinx import mpiexec

SMALL = ["stromberg-block", "--set", "geometry.nx=16", "--set", "geometry.ny=16", "--set", "loading.cycles=3",
         "--set", "output.plots=false", "--set", "output.xdmf=false", "--quiet"]
#: A run of SMALL takes ~10 s on 3 ranks here; a hang is caught by the timeout, a slow stop by STOP_SECONDS.
TIMEOUT = 240

DRIVER = r'''
import errno, sys
from mpi4py import MPI
case, argv = sys.argv[1], sys.argv[sys.argv.index("--") + 1:]
rank, size = MPI.COMM_WORLD.rank, MPI.COMM_WORLD.size
if case == "disk_full" and rank == 0:  # only rank 0 holds the tables: its fifth write finds the disk full
    from dolfinx_fretting import io
    original, calls = io.ResultWriter._write, [0]
    def full(self, name, lines):
        calls[0] += 1
        if calls[0] > 5:
            raise OSError(errno.ENOSPC, "No space left on device", name)
        return original(self, name, lines)
    io.ResultWriter._write = full
# Importing the API initialises PETSc, which is collective (as importing dolfinx is): every rank imports it.
from dolfinx_fretting import problem
if case == "bug_last_rank" and rank == size - 1:  # a defect on one rank, in the middle of the run
    original_commit, commits = problem.FrettingProblem.commit, [0]
    def broken(self, *args, **kwargs):
        commits[0] += 1
        if commits[0] > 3:
            raise ZeroDivisionError("injected on the last rank")
        return original_commit(self, *args, **kwargs)
    problem.FrettingProblem.commit = broken
from dolfinx_fretting.cli import main
sys.exit(main(argv))
'''

#: case: (CLI arguments after ``run``, expected exit code or None for "non-zero", words the output must hold
#: exactly once, whether the ranks stop by MPI_Abort).
CASES = {
    "bad_input": (SMALL + ["--set", "contact.mu=inf"], 2, "contact.mu", False),
    "solver_failure": (SMALL + ["--set", "solver.local_max_iter=2"], 1, "run failed", False),
    "disk_full": (SMALL, None, "No space left on device", True),
    "bug_last_rank": (SMALL, None, "ZeroDivisionError: injected", True),
}

#: Seconds from the fault to the end of all ranks: the meeting's wait (cli.MEET_SECONDS, 5 s) plus MPI's
#: teardown; the runs themselves take ~10 s, so a stop within this bound is a stop "within seconds".
STOP_SECONDS = 60


#: The rank count each case runs on by default; the other one is ``slow`` (3-10 s each: the ranks' start-up
#: and, for a lone rank's fault, the 5 s meeting). The collective errors (every rank refuses or fails alike)
#: on 2 ranks; a fault on one rank alone on 3, where a third rank neither faults nor is rank 0.
DEFAULT_RANKS = {"bad_input": 2, "solver_failure": 2, "disk_full": 3, "bug_last_rank": 3}


@pytest.mark.mpi
@pytest.mark.parametrize("case, ranks", [pytest.param(case, ranks, marks=[] if ranks == DEFAULT_RANKS[case]
                                                      else [pytest.mark.slow], id=f"{case}-{ranks}")
                                         for case in sorted(CASES) for ranks in (2, 3)])
def test_an_error_on_any_rank_stops_all_ranks(tmp_path, case, ranks, mpirun_env):
    args, code, words, aborts = CASES[case]
    driver = tmp_path / "driver.py"
    driver.write_text(DRIVER)
    cmd = [*mpiexec(ranks), sys.executable, str(driver), case, "--", "run", *args, "--out", str(tmp_path / "out")]
    t0 = time.monotonic()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=mpirun_env, timeout=TIMEOUT)
    elapsed = time.monotonic() - t0
    output = proc.stdout + proc.stderr
    if code is None:
        assert proc.returncode != 0, output
    else:
        assert proc.returncode == code, output
    # One message, not one per rank: collective failures are printed by rank 0, a lone rank's by itself.
    assert output.count(words) == 1, output
    assert ("alone: stopping all" in output or "stopping all" in output) == aborts, output
    assert elapsed < STOP_SECONDS, (elapsed, output)
