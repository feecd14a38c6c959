"""dolfinx_fretting: fretting wear simulation with DOLFINx.

Frictional contact is solved on the Delassus (compliance) operator W = H K^-1 H^T by the Uzawa iteration
with De Saxce's bipotential projection onto the Coulomb cone; the Archard law updates the wear gap.
"""

import hashlib
import os
import sys
from pathlib import Path

__version__ = "0.1.0"


def _numba_cache_dir() -> str:
    """A numba cache folder keyed by the source of every compiled module of the package.

    Numba revalidates a cached function against its own file only: a compiled function that calls one of
    another module (the cycle loop calls the wear update and the contact kernels) keeps its stale machine
    code when only the callee's file changes, and silently computes with the old callee. Keying the whole
    cache on the sources of all the compiled modules makes any change start a fresh cache.
    """
    here = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for name in ("cycling.py", "local_solvers.py", "materials.py", "plasticity.py", "wear.py"):
        digest.update((here / name).read_bytes())
    base = os.environ.get("DOLFINX_FRETTING_NUMBA_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "dolfinx_fretting", "numba")
    return os.path.join(base, digest.hexdigest()[:16])


# Before any compiled module is imported (numba reads the setting when it decorates a function).
os.environ["NUMBA_CACHE_DIR"] = _numba_cache_dir()
if "numba" in sys.modules:
    sys.modules["numba"].config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]
