"""The layout table (docs/architecture.md's "Who owns what", which the README links to) names every module of
the package once, and nothing else: a module added, renamed or removed without its row fails here (issue 25:
the README's table had drifted, listing ``_dolfinx`` twice and missing seven modules; the README is now a
front page and the table lives in docs/architecture.md alone). A subpackage's modules are named
``package.module`` (its ``__init__`` as ``package``)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "dolfinx_fretting"
SUBPACKAGES = sorted(folder for folder in PACKAGE.iterdir() if (folder / "__init__.py").is_file())
MODULES = sorted([p.stem for p in PACKAGE.glob("*.py") if p.stem not in ("__init__", "__main__")]
                 + [folder.name if p.stem == "__init__" else f"{folder.name}.{p.stem}"
                    for folder in SUBPACKAGES for p in folder.glob("*.py")])
ARCHITECTURE = ROOT / "docs" / "architecture.md"


def _table_modules(path: Path, heading: str) -> list[str]:
    """The module names in the first column of the table under ``heading`` (a cell may name several:
    ``io``, ``plots``)."""
    text = path.read_text()
    lines = text[text.index(heading):].splitlines()[1:]
    start = next(i for i, line in enumerate(lines) if line.startswith("|"))
    end = next((i for i in range(start, len(lines)) if not lines[i].startswith("|")), len(lines))
    rows = lines[start:end]  # the first table under the heading
    names: list[str] = []
    for row in rows[2:]:  # the header and its rule
        first = row.split("|")[1]
        names += re.findall(r"`([A-Za-z_0-9.]+)`", first)
    return names


def test_layout_table_names_every_module_once():
    names = _table_modules(ARCHITECTURE, "## Who owns what")
    assert len(names) == len(set(names)), f"named twice: {sorted({n for n in names if names.count(n) > 1})}"
    assert sorted(names) == MODULES, (f"{ARCHITECTURE.name}: missing {sorted(set(MODULES) - set(names))}, "
                                      f"not modules {sorted(set(names) - set(MODULES))}")


def test_readme_links_to_the_layout_table():
    """The README keeps no second copy of the table (the one that drifted) and points to this one."""
    readme = (ROOT / "README.md").read_text()
    assert "docs/architecture.md" in readme
    copy = re.search(r"^\| module \|", readme, re.M)
    assert not copy, "a module table in README.md: keep the one of docs/architecture.md"
