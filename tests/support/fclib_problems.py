"""The shared FCLIB-like problems (``$DOLFINX_FRETTING_FCLIB``, default ``<repo>/../shared/fclib``) as the
test files that solve them see them: where they are, whether they must be there, their index and a loader.
Used by tests/test_fclib.py, tests/test_frictionless.py and tests/test_local_solver_suite.py."""

import json
import os
from pathlib import Path

import pytest

from dolfinx_fretting import fclib

FCLIB_DIR = Path(os.environ.get("DOLFINX_FRETTING_FCLIB",
                                Path(__file__).resolve().parents[2].parent / "shared" / "fclib"))
HAVE_FCLIB = (FCLIB_DIR / "index.json").is_file()
#: Set (to 1) where the problems must be there (./tasks.sh test, hence CI, which has shared/ beside the clone):
#: their absence then fails the suite instead of skipping the validation row silently.
EXPECT_FCLIB = os.environ.get("DOLFINX_FRETTING_EXPECT_FCLIB", "0") not in ("", "0")
needs_fclib = pytest.mark.skipif(not HAVE_FCLIB and not EXPECT_FCLIB,
                                 reason=f"FCLIB problems not found in {FCLIB_DIR} (set DOLFINX_FRETTING_FCLIB to "
                                 "the folder holding index.json)")
INDEX = {e["name"]: e for e in json.loads((FCLIB_DIR / "index.json").read_text())} if HAVE_FCLIB else {}
#: The problems condensed from a finite-element model (what the validation table's row rests on).
FE = sorted(n for n, e in INDEX.items() if e["kind"] == "FE-condensed")
# Frictional problems with several solutions: the solver reaches a verified solution (error 1e-14 when run
# further) whose x differs from Siconos's by 1.7 %; Siconos's x is also verified (tests/test_fclib.py).
NON_UNIQUE = {"OneObject-i1028-138"}


def problem(name):
    """The shared problem ``name`` (:func:`dolfinx_fretting.fclib.load`)."""
    return fclib.load(FCLIB_DIR / f"{name}.npz")
