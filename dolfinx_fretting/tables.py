"""The small CSV tables of the sweeps (``study.csv``, ``map.csv``) and of a run's fatigue (``fatigue.csv``): one way
to write a cell, to write or append rows and to read them back.

A number is written with 6 significant digits (a non-finite one as a blank cell), a flag as ``True``/``False``;
reading gives floats (blank: NaN), the named text, flag and integer columns as such.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Collection, Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["cell_text", "write_rows", "append_rows", "write_table", "read_rows"]


def cell_text(value: Any) -> str:
    """One table cell: blank for None or a non-finite number, 6 significant digits for a float."""
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return "" if not math.isfinite(value) else f"{float(value):.6g}"
    return str(value)


def write_rows(path: str | Path, rows: Sequence[dict[str, Any]], fields: Sequence[str]) -> Path:
    """Write ``rows`` (missing keys blank, others ignored) as a CSV table with the columns ``fields``."""
    path = Path(path)
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(fields), extrasaction="ignore")
        writer.writeheader()
        for row in rows:
            writer.writerow({key: cell_text(row.get(key)) for key in fields})
    return path


def append_rows(path: str | Path, rows: Sequence[dict[str, Any]], fields: Sequence[str]) -> Path:
    """Append ``rows`` to a table of :func:`write_rows` with the columns ``fields`` (its header already written)."""
    path = Path(path)
    with open(path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(fields), extrasaction="ignore")
        for row in rows:
            writer.writerow({key: cell_text(row.get(key)) for key in fields})
    return path


def write_table(out: str | Path, stem: str, rows: Sequence[dict[str, Any]], fields: Sequence[str],
                markdown: str) -> tuple[Path, Path]:
    """Write ``<stem>.csv`` (:func:`write_rows`) and ``<stem>.md`` (``markdown``) into ``out`` (created if
    missing); returns their paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    md_path = out / f"{stem}.md"
    csv_path = write_rows(out / f"{stem}.csv", rows, fields)
    md_path.write_text(markdown + "\n")
    return csv_path, md_path


def read_rows(path: str | Path, text: Collection[str] = (), flags: Collection[str] = (),
              integers: Collection[str] = ()) -> list[dict[str, Any]]:
    """A table of :func:`write_rows` back: the ``text`` columns as written, ``flags`` as bools, ``integers`` as
    ints, every other column a float (blank: NaN)."""
    rows = []
    with open(path, newline="") as f:
        for record in csv.DictReader(f):
            row: dict[str, Any] = {}
            for key, value in record.items():
                if key in text:
                    row[key] = value
                elif key in flags:
                    row[key] = value == "True"
                elif key in integers:
                    row[key] = int(value)
                else:
                    row[key] = float(value) if value not in ("", None) else math.nan
            rows.append(row)
    return rows
