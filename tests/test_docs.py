"""The API reference builds without a single warning, and documents what the package exports.

``sphinx-build -W -n --keep-going`` turns every warning into a failure: a docstring that is not valid
reStructuredText, a reference (``:class:``, ``:func:``, a type hint) to an object of this package that the
reference does not document (nitpicky mode), a Markdown page with a broken link, a demo that jupytext
cannot read. The build imports the package and DOLFINx (autodoc), converts the demos without running them,
and takes ~10 s.

Sphinx comes with the ``docs`` extra, which ``scripts/setup.sh`` installs into ``.venv``. ``./tasks.sh
test`` sets ``DOLFINX_FRETTING_EXPECT_DOCS=1`` on the debian stack: a missing Sphinx then FAILS this test;
without it (a venv made without the extra, or the current stack, where tasks.sh does not run this file)
the test is skipped with the reason.
"""

from __future__ import annotations

import html
import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DEMOS = sorted((ROOT / "demos").glob("demo_*.py"))
#: The modules with a page in docs/reference (the issue's list, and those the others refer to).
MODULES = ("problem", "contact", "output", "plots", "scenes", "local_solvers", "wear", "cycling",
           "cycle_jump", "plasticity", "plastic_zone", "materials", "compliance", "loading", "io",
           "contact_output", "_dolfinx", "compat", "sizes")


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> tuple[Path, subprocess.CompletedProcess]:
    missing = [name for name in ("sphinx", "myst_parser", "jupytext")
               if importlib.util.find_spec(name) is None]
    if missing:
        reason = f"{', '.join(missing)} not installed (the docs extra: scripts/setup.sh installs it)"
        if os.environ.get("DOLFINX_FRETTING_EXPECT_DOCS", "0") not in ("", "0"):
            pytest.fail(f"DOLFINX_FRETTING_EXPECT_DOCS is set but {reason}")
        pytest.skip(reason)
    out = tmp_path_factory.mktemp("docs") / "html"
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "-n", "--keep-going", "-q", "-b", "html", str(ROOT / "docs"),
         str(out)],
        cwd=ROOT, capture_output=True, text=True, timeout=600,
        env=dict(os.environ, OPENBLAS_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1",
                 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1"))
    return out, proc


def test_reference_builds_without_warnings(built):
    out, proc = built
    # -W makes the first warning an error and the exit code non-zero; --keep-going lists them all first.
    assert proc.returncode == 0, f"sphinx-build failed:\n{proc.stderr[-6000:]}"
    assert "WARNING" not in proc.stderr and "ERROR" not in proc.stderr, proc.stderr[-6000:]
    assert (out / "index.html").is_file()


def test_every_export_and_module_is_documented(built):
    out, proc = built
    assert proc.returncode == 0, proc.stderr[-3000:]
    import dolfinx_fretting

    # Each name of the package's public API has its entry (an anchor with its full dotted name) on the page
    # of the module that defines it, and the page of exports links to it.
    index = (out / "reference" / "index.html").read_text()
    for name in dolfinx_fretting.__all__:
        module = dolfinx_fretting._API[name]
        page = (out / "reference" / f"{module}.html").read_text()
        anchor = f'id="dolfinx_fretting.{module}.{name}"'
        assert anchor in page, f"{name}: no entry {anchor} in reference/{module}.html"
        link = f'href="{module}.html#dolfinx_fretting.{module}.{name}"'
        assert link in index, f"{name}: not in the table of exports"
    for module in MODULES:
        page = (out / "reference" / f"{module}.html").read_text()
        assert f'id="module-dolfinx_fretting.{module}"' in page, module


def test_compat_helpers_are_documented(built):
    """The public module the demos build their meshes and spaces with documents every name it exports."""
    out, proc = built
    assert proc.returncode == 0, proc.stderr[-3000:]
    from dolfinx_fretting import compat

    page = (out / "reference" / "compat.html").read_text()
    assert compat.__all__
    for name in compat.__all__:
        assert f'id="dolfinx_fretting.compat.{name}"' in page, name


def test_demos_are_pages_with_their_code_and_text(built):
    out, proc = built
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert DEMOS
    for demo in DEMOS:
        page = (out / "demos" / f"{demo.stem}.html").read_text()
        text = demo.read_text()
        # the demo's title (its first Markdown heading) is the page's title
        title = re.search(r"^# # (.+)$", text, re.M).group(1)
        assert _text(re.search(r"<h1>(.*?)<a class=\"headerlink\"", page).group(1)) == title
        # all of its code is on the page, line by line (highlighted: compare the text only)
        shown = _text(page)
        code = [line for line in text.splitlines() if line.strip() and not line.startswith("#")]
        assert len(code) > 10
        for line in code:
            assert line in shown, (demo.name, line)
        # and the page says it was not executed
        assert "without running it" in _text(page)


def _text(page: str) -> str:
    """The text of HTML: no tags (Pygments splits a code line into many spans), entities decoded, Sphinx's
    typographic apostrophes back to ASCII."""
    return html.unescape(re.sub(r"<[^>]+>", "", page)).replace("\u2019", "'")
