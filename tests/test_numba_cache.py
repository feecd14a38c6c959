"""The numba cache folder (``dolfinx_fretting._numba_cache_dir``) cannot hand a run stale or foreign machine code.

Numba revalidates a cached function against its own source file and numba's version only. The package keys
the whole cache folder on the sources of every module with compiled functions (a compiled caller keeps its
callee's old code when only the callee's file changes) and on the interpreter and the numerical build (the
suite runs two stacks from one home: Debian's numpy 1.24 and the wheel stack's numpy 2; a venv with the same
Python and another numpy would otherwise load the other's code). Pure Python: no DOLFINx.
"""

from __future__ import annotations

import importlib.metadata
import os
import re
import sys
from pathlib import Path

import dolfinx_fretting

PACKAGE = Path(dolfinx_fretting.__file__).resolve().parent
#: A numba-compiled function: ``@numba.njit``, ``@numba.jit``, ``@njit``, ``@jit`` (with or without arguments).
COMPILED_DECORATOR = re.compile(r"^\s*@(numba\.)?n?jit\b", re.MULTILINE)


def test_every_module_with_compiled_functions_keys_the_cache():
    """Before: finite sliding's compiled re-pairing (sliding.py) calls contact.py's compiled closest-segment search,
    and neither file was in the key: a change to that search left the re-pairing's cached code calling the old
    one."""
    compiled = sorted(str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py")
                      if COMPILED_DECORATOR.search(p.read_text()))
    assert len(compiled) >= 6, compiled  # the scan finds the kernels (no vacuous pass)
    missing = sorted(set(compiled) - set(dolfinx_fretting._COMPILED))
    assert not missing, f"modules with numba-compiled functions not in dolfinx_fretting._COMPILED: {missing}"


def test_the_folder_is_one_per_interpreter_and_numerical_build(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    here = dolfinx_fretting._numba_cache_dir()
    assert Path(here).parent == tmp_path and Path(here).is_dir()
    assert dolfinx_fretting._numba_cache_dir() == here  # the same interpreter and build: the same code

    monkeypatch.setattr(sys, "prefix", str(tmp_path / "another-venv"))
    other_venv = dolfinx_fretting._numba_cache_dir()
    monkeypatch.undo()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))

    real_version = importlib.metadata.version
    monkeypatch.setattr(importlib.metadata, "version",
                        lambda name: "0.0.0-other" if name == "numpy" else real_version(name))
    other_numpy = dolfinx_fretting._numba_cache_dir()
    assert len({here, other_venv, other_numpy}) == 3, (here, other_venv, other_numpy)


def test_a_folder_inherited_from_another_stack_is_not_nested(tmp_path, monkeypatch):
    """A child started by a process of the other stack inherits that process's keyed folder in NUMBA_CACHE_DIR
    (tests/test_stacks.py starts both): the child keys its own folder beside it, under the same base."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "0123456789abcdef"))
    mine = dolfinx_fretting._numba_cache_dir()
    assert Path(mine).parent == tmp_path and re.fullmatch(r"[0-9a-f]{16}", Path(mine).name)
    assert os.access(mine, os.W_OK)
