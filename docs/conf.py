"""Sphinx configuration of the dolfinx_fretting reference.

Build (what ``./tasks.sh docs`` and ``tests/test_docs.py`` run)::

    .venv/bin/python -m sphinx -W -n --keep-going -b html docs docs/_build/html

The API pages are made by autodoc from the docstrings (Google style, read by napoleon), so the package and
DOLFINx must import: build with the venv of either stack. The demos (``demos/demo_*.py``, jupytext scripts)
are converted to Markdown pages here, at configuration time, with jupytext used as a library; they are
**not executed** (they need MPI and DOLFINx and run for minutes), so the pages show code and text, no output.
"""

import os
import re
import sys
from pathlib import Path

import jupytext
from sphinx.ext.napoleon.docstring import GoogleDocstring

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))  # the package of this checkout, whether or not it is installed

import dolfinx_fretting  # noqa: E402

project = "dolfinx_fretting"
author = "dolfinx_fretting developers"
copyright = "the dolfinx_fretting developers, MIT licence"  # noqa: A001 (Sphinx's name)
release = version = dolfinx_fretting.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "myst_parser",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build"]
templates_path: list[str] = []

# The theme: furo if it is installed (the docs extra), else Sphinx's own.
try:
    import furo  # noqa: F401

    html_theme = "furo"
except ImportError:  # pragma: no cover - the docs extra installs furo
    html_theme = "alabaster"
html_title = f"dolfinx_fretting {release}"

# MyST: the README and the docs/*.md pages as they are; $...$ and $$...$$ math in the demos.
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3

# autodoc: members in source order, type hints in the description (signatures stay readable).
autodoc_default_options = {"members": True, "member-order": "bysource", "show-inheritance": True,
                           # pydantic's own attributes of the scene sections
                           "exclude-members": "model_config,model_fields,model_computed_fields"}
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented_params"
autodoc_preserve_defaults = True
autosummary_generate = False  # the tables link to the module pages; no stub files
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_rtype = False
napoleon_attr_annotations = True


# Napoleon reads the first line of an attribute's or property's docstring as "type: description". This
# package's attribute docstrings open with a phrase, often followed by a colon ("Coulomb friction
# coefficient. At most 100: ..."), and their types come from the annotations: the whole text is the
# description.
def _inline_attribute_without_type(self) -> tuple[str, list[str]]:
    lines = [self._lines.next(), *self._dedent(self._consume_to_end())]
    return "", self.__class__(lines, self._config).lines()


GoogleDocstring._consume_inline_attribute = _inline_attribute_without_type

# Nitpicky mode (sphinx-build -n): every reference to this package must resolve. References to other
# packages cannot: there is no intersphinx inventory offline (the build needs no network), so the names of
# these packages' objects are accepted unresolved; everything of dolfinx_fretting is still checked.
_EXTERNAL = (r"numpy", r"np", r"numpy\.typing", r"npt", r"scipy", r"dolfinx", r"fem", r"mesh", r"ufl",
             r"petsc4py", r"PETSc", r"mpi4py", r"MPI", r"matplotlib", r"plt", r"pydantic", r"numba", r"h5py",
             r"gmsh", r"pathlib", r"os", r"typing", r"collections", r"collections\.abc", r"dataclasses",
             r"enum", r"io", r"json", r"types", r"contextlib", r"tqdm", r"basix", r"csv")
nitpick_ignore_regex = [
    (r"py:.*", rf"({'|'.join(_EXTERNAL)})\..*"),
    # builtins and typing names that Sphinx does not resolve without the Python inventory
    (r"py:(class|obj|data|exc)", r"(int|float|str|bool|bytes|dict|list|tuple|set|frozenset|object|type|None"
                                 r"|complex|slice|callable|Callable|Iterable|Iterator|Sequence|Mapping"
                                 r"|Any|Literal|Optional|Union|Self|ClassVar|Path|ndarray|optional"
                                 r"|[A-Za-z]*Error|[A-Za-z]*Exception|[A-Za-z]*Warning|Ellipsis|\.\.\.)"),
    # private helpers (a leading underscore) appear in signatures and base classes but are not documented
    (r"py:.*", r"(dolfinx_fretting\.)?([A-Za-z0-9_]+\.)*_[A-Za-z][A-Za-z0-9_]*"),
]
# The scenes' constrained number types (pydantic Annotated aliases), shown by name in the sections' fields.
nitpick_ignore = [("py:class", name) for name in ("Length", "FiniteFloat", "Cycle", "Mesh", "MeshTags_int32")]

# The demos as pages: jupytext reads each script (its header says its format) and writes Markdown that MyST
# renders. Written only when the text changed, so that an unchanged demo does not rebuild its page.
DEMO_FOLDER = DOCS / "demos"  # generated, ignored by git
DEMO_NOTE = """```{{note}}
This page is `demos/{name}` rendered by jupytext **without running it** (no outputs or pictures here): the
demo needs MPI and DOLFINx, and its full-size run takes minutes. Run it from the repository's root with
`.venv/bin/python demos/{name}` (`CI=1 .venv/bin/python demos/{name}` for the small version the tests
run; `mpirun -n 2 .venv/bin/python demos/{name}` in parallel); its results and pictures go to
`results/`. As a notebook: `jupytext --to ipynb demos/{name}`.
```

"""


def _demo_pages() -> list[str]:
    DEMO_FOLDER.mkdir(exist_ok=True)
    names = []
    for script in sorted((ROOT / "demos").glob("demo_*.py")):
        notebook = jupytext.read(script)
        text = jupytext.writes(notebook, fmt={"extension": ".md", "format_name": "markdown",
                                              "notebook_metadata_filter": "-all"})  # no YAML header
        title, _, body = text.partition("\n")  # the first cell opens with the demo's "# Title"
        if not title.startswith("# "):
            raise ValueError(f"{script}: the first cell must start with a '# Title' line, got {title!r}")
        page = f"{title}\n\n{DEMO_NOTE.format(name=script.name)}{body.lstrip()}"
        target = DEMO_FOLDER / f"{script.stem}.md"
        if not target.exists() or target.read_text() != page:
            tmp = target.with_suffix(f".md.{os.getpid()}")
            tmp.write_text(page)
            tmp.replace(target)  # atomic: a concurrent build never reads half a page
        names.append(script.stem)
    for stale in DEMO_FOLDER.glob("demo_*.md"):
        if stale.stem not in names:
            stale.unlink()
    return names


DEMOS = _demo_pages()


# Links from docs/*.md to files outside docs/ (the benchmark tables in benchmarks/results/) work on a
# repository browser; Sphinx would look for them as pages of the reference. The "path:" scheme makes MyST
# copy the file and link to the copy instead.
_OUTSIDE_LINK = re.compile(r"\]\((\.\./[^)\s]+\.md)\)")


def _link_outside_files(app, docname: str, source: list[str]) -> None:
    source[0] = _OUTSIDE_LINK.sub(r"](path:\1)", source[0])


def setup(app):
    app.connect("source-read", _link_outside_files)
