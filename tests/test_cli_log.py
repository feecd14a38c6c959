"""A run's own lines are not buried under the form compiler's build log (FFCx 0.5 prints a dozen
``INFO:root:running build_ext`` / gcc command lines per compiled form); ``--verbose`` shows it."""

import os
import subprocess
import sys

import pytest

import ffcx

#: Whether this stack's form compiler prints a build log at all: FFCx 0.5 calls logging.basicConfig() on import
#: and its cffi build logs at INFO; FFCx 0.9+ (DOLFINx 0.11) compiles silently, nothing to hide or show.
COMPILER_LOGS = tuple(int(x) for x in ffcx.__version__.split(".")[:2]) < (0, 6)

TINY = ["stromberg-block", "--set", "geometry.nx=8", "--set", "geometry.ny=8", "--set", "loading.cycles=1",
        "--set", "output.plots=false", "--set", "output.xdmf=false", "--set", "output.contact_profiles=false"]


@pytest.mark.parametrize("verbose", [False, True])
def test_form_compiler_log_only_with_verbose(tmp_path, verbose):
    if verbose and not COMPILER_LOGS:
        pytest.skip("this stack's form compiler prints no build log (FFCx > 0.5)")
    # An empty form cache (XDG_CACHE_HOME) makes the run compile its forms, so the log would be there.
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path / "cache"), OPENBLAS_NUM_THREADS="1")
    cmd = [sys.executable, "-m", "dolfinx_fretting", "run", *TINY, "--out", str(tmp_path / "out")]
    proc = subprocess.run(cmd + (["--verbose"] if verbose else []), capture_output=True, text=True, env=env,
                          timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert any((tmp_path / "cache" / "fenics").iterdir())  # the forms were compiled in this run
    output = proc.stdout + proc.stderr
    assert ("running build_ext" in output) == verbose, output
    assert "[stromberg-block] done:" in proc.stdout
