"""dolfinx_fretting: fretting wear simulation with DOLFINx.

Frictional contact is solved on the Delassus (compliance) operator W = H K^-1 H^T by the Uzawa iteration
with De Saxce's bipotential projection onto the Coulomb cone; the Archard law updates the wear gap.
"""

import hashlib
import importlib.metadata
import os
import re
import sys
import tempfile
import warnings
from pathlib import Path

__version__ = "0.1.0"

#: The modules with numba-compiled functions (the cycle loop calls into the wear and solver modules; finite
#: sliding's compiled cycle, in sliding.py, calls the cycle loop and contact.py's closest-segment search).
_COMPILED = ("contact.py", "cycling.py", "local_solvers.py", "materials.py", "plastic_zone.py", "plasticity.py",
             "sliding.py", "wear.py")
#: The distributions whose build the machine code depends on besides the sources: numba's own index is keyed by
#: numba's version only, and the Python version only through the file names (two venvs with one Python and two
#: numpy builds would load each other's code).
_BUILD = ("numba", "llvmlite", "numpy")


def _numba_cache_dir() -> str:
    """A writable numba cache folder keyed by the source of every compiled module of the package.

    Numba revalidates a cached function against its own file only: a compiled function that calls one of
    another module (the cycle loop calls the wear update and the contact kernels) keeps its stale machine
    code when only the callee's file changes, and silently computes with the old callee. Keying the whole
    cache on the sources of all the compiled modules makes any change start a fresh cache. The key also holds
    the interpreter (``sys.prefix``: each venv, each stack, its own folder) and the versions of numba, llvmlite
    and numpy, so that two stacks sharing a home never load each other's machine code. The base is the
    user's ``NUMBA_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME`` or ``~/.cache``; an unwritable base falls
    back to the temporary folder (numba itself would silently fall back to the unkeyed ``__pycache__``).
    """
    here = Path(__file__).resolve().parent
    digest = hashlib.sha256(__version__.encode())
    digest.update(f"{sys.prefix}|{sys.version}".encode())
    for name in _BUILD:
        try:
            digest.update(f"|{name} {importlib.metadata.version(name)}".encode())
        except importlib.metadata.PackageNotFoundError:  # not installed: numba would not run either
            digest.update(f"|{name} missing".encode())
    for name in _COMPILED:
        try:
            digest.update((here / name).read_bytes())
        except OSError:  # a trimmed install: hash what exists
            digest.update(name.encode())
    key = digest.hexdigest()[:16]
    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "dolfinx_fretting",
        "numba")
    # Inherited from a parent process that set it: its key (another stack's, if the parent ran the other venv).
    if re.fullmatch(r"[0-9a-f]{16}", os.path.basename(os.path.normpath(base))):
        base = os.path.dirname(os.path.normpath(base))
    for folder in (os.path.join(base, key),
                   os.path.join(tempfile.gettempdir(), f"dolfinx_fretting-numba-{os.getuid()}", key)):
        try:
            os.makedirs(folder, exist_ok=True)
            if os.access(folder, os.W_OK):
                if not folder.startswith(base):
                    warnings.warn(f"numba cache: {base} is not writable; using {folder}", RuntimeWarning,
                                  stacklevel=3)
                return folder
        except OSError:
            continue
    return os.path.join(base, key)  # numba will say what it does with an unwritable folder


# Before any compiled module is imported (numba reads the setting when it decorates a function). If numba
# is already imported, change its config only: a new NUMBA_* variable would make numba re-read all of its
# settings from the environment and undo what the host program set in code.
if "numba" in sys.modules:
    sys.modules["numba"].config.CACHE_DIR = _numba_cache_dir()
else:
    os.environ["NUMBA_CACHE_DIR"] = _numba_cache_dir()


# The public API (docs/api.md), imported on first use so that the pure NumPy/numba modules (local solvers,
# wear, cycling) stay usable without importing DOLFINx.
_API = {
    "RigidPlane": "contact", "ElasticBody": "contact", "Contact": "contact",
    "FrettingProblem": "problem", "ContactState": "state", "IncrementResult": "state",
    "CycleResult": "state", "ConvergenceError": "state", "WindowError": "state", "CyclePath": "loading",
    "Displacement": "loading",
    "Force": "loading", "Archard": "laws", "EnergyWear": "laws", "EvolvingFriction": "laws",
    "LocalSolver": "settings", "Plasticity": "settings",
    "J2Plasticity": "materials", "FrettingWriter": "output", "RunDescription": "output", "plot_run": "plots",
    "Units": "units",
    "BasquinCoffinManson": "fatigue", "ShearStrainLife": "fatigue", "FatemiSocie": "fatigue",
    "CriticalDistance": "fatigue",
    "FatigueResult": "fatigue_fields", "fatigue_over_cycle": "fatigue_fields", "cycle_states": "fatigue_fields",
}
__all__ = sorted(_API)


def __getattr__(name: str):
    if name in _API:
        import importlib  # lazy: stdlib, needed only on the first use of an export (PEP 562)

        return getattr(importlib.import_module(f".{_API[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# On the DOLFINx wheel (0.11) DOLFINx and PETSc find their MPI library only once mpi4py has loaded it
# ("libmpi.so.12: cannot open shared object file" otherwise): load it before anything can import dolfinx, so
# that `import dolfinx_fretting` followed by `import dolfinx` works on every stack.
from mpi4py import MPI as _MPI  # noqa: E402,F401
