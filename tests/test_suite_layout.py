"""The test suite's own layout (issue 25): fixtures shared between test files live in ``tests/conftest.py``,
plain helpers (model builders, constants, checks) in the ``tests/support`` package, and no test module imports
another one, neither directly (``from test_x import ...``, ``import tests.test_x``, ``importlib``) nor in the
script of a child process it starts. Before: no conftest.py, ``tests/_sphere_model.py`` beside the tests, and
seven test files reaching into their siblings (``test_plots``, ``test_fclib``, ``test_local_solvers``,
``test_meshes``)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

TESTS = Path(__file__).resolve().parent
TEST_FILES = sorted(TESTS.glob("test_*.py"))
#: What may not import a test module: the tests, conftest.py and the helpers.
SCANNED = TEST_FILES + sorted(TESTS.glob("conftest.py")) + sorted((TESTS / "support").glob("*.py"))
#: An import of a test module in the source of a child process (a string the test writes or passes to ``-c``).
CHILD_IMPORT = re.compile(r"^\s*(?:from\s+(?:tests\.)?test_\w+[\w.]*\s+import\b|import\s+(?:[\w.]+\s*,\s*)*"
                          r"(?:tests\.)?test_\w+)", re.MULTILINE)
#: Calls that import a module named by a string.
IMPORTERS = {"import_module", "__import__", "spec_from_file_location", "run_path", "SourceFileLoader"}


def _is_test_module(name: str | None) -> bool:
    """``test_x``, ``tests.test_x``, ``test_x.y`` or a path ending in ``test_x.py``."""
    if not name:
        return False
    return any(part.startswith("test_") for part in re.split(r"[./\\]", name.removesuffix(".py")))


def _test_module_imports(source: str, filename: str = "<source>") -> list[str]:
    """Every place in ``source`` that imports a test module, as ``line: what``."""
    found = []
    for node in ast.walk(ast.parse(source, filename)):
        if isinstance(node, ast.Import):
            found += [f"{node.lineno}: import {a.name}" for a in node.names if _is_test_module(a.name)]
        elif isinstance(node, ast.ImportFrom):
            if _is_test_module(node.module):
                found.append(f"{node.lineno}: from {node.module} import ...")
            elif node.level or node.module == "tests":  # from . import test_x, from tests import test_x
                found += [f"{node.lineno}: from {'.' * node.level}{node.module or ''} import {a.name}"
                          for a in node.names if _is_test_module(a.name)]
        elif isinstance(node, ast.Call):
            func = node.func
            name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", None)
            if name in IMPORTERS:
                found += [f"{node.lineno}: {name}({a.value!r})" for a in node.args
                          if isinstance(a, ast.Constant) and isinstance(a.value, str)
                          and _is_test_module(a.value)]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            found += [f"{node.lineno}: in a child's script: {m.group(0).strip()}"
                      for m in CHILD_IMPORT.finditer(node.value)]
    return found


def test_there_are_test_files():
    assert len(TEST_FILES) > 40, TEST_FILES  # the glob found the suite (no empty folder passing vacuously)


def test_conftest_holds_the_shared_fixtures():
    assert (TESTS / "conftest.py").is_file(), "tests/conftest.py is missing"
    assert (TESTS / "support" / "__init__.py").is_file(), "tests/support/ (the shared helpers) is missing"


def test_no_test_module_imports_another():
    offences = {str(p.relative_to(TESTS)): found for p in SCANNED
                if (found := _test_module_imports(p.read_text(), str(p)))}
    assert not offences, ("test modules imported (move what is shared to tests/conftest.py if it is a "
                          f"fixture, to tests/support/ otherwise): {offences}")


def test_only_tests_and_conftest_beside_the_tests():
    """A helper module in tests/ itself (``_sphere_model.py``) is one a test file imports by a bare name: the
    helpers are in the ``support`` package."""
    others = sorted(p.name for p in TESTS.glob("*.py")
                    if p.name != "conftest.py" and not p.name.startswith("test_"))
    assert not others, f"helpers beside the tests (move them to tests/support/): {others}"


def test_the_check_sees_every_form():
    """The parser above catches each way a test module could be imported (so a pass is not a blind spot)."""
    # written with T_ for test_ so that this file's own scan does not find the probe's script below
    source = """
import T_a
import os, tests.T_b
from T_c import x
from tests.T_d import y
from tests import T_e
from . import T_f
importlib.import_module("T_g")
spec_from_file_location("h", "tests/T_h.py")
SCRIPT = '''
    import sys
    import T_i as t
'''
import testing, contest
from support.sphere import sphere_model
""".replace("T_", "test_")
    found = [f.split(": ", 1)[1] for f in _test_module_imports(source)]
    assert len(found) == 9, found
    assert [f for f in found if "test_i" in f] == ["in a child's script: import test_i"]

