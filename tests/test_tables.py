"""The sweeps' CSV tables (``study.csv``, ``map.csv``) through ``dolfinx_fretting.tables``: what a cell holds and
what reading it back gives (issue 27's audit of the newer code: a table that read a failed point's blank cell as 0,
or wrote a flag as 1, passed every sweep test).

The references are the cell format the module documents: 6 significant digits (Python's ``.6g``), a blank cell for
None or a non-finite number, ``True``/``False`` for a flag; reading: floats (a blank cell NaN), the named text, flag
and integer columns as such. Pure Python: no DOLFINx.
"""

import math

import numpy as np

from dolfinx_fretting.tables import cell_text, read_rows, write_rows


def test_a_cell_holds_six_significant_digits_flags_and_blanks():
    assert cell_text(2.0 / 3.0) == "0.666667" and cell_text(np.float64(123456789.0)) == "1.23457e+08"
    assert cell_text(True) == "True" and cell_text(np.bool_(False)) == "False"   # a flag, not the integer 1 or 0
    assert cell_text(7) == "7" and cell_text(np.int64(-3)) == "-3"
    for blank in (None, math.nan, math.inf, -np.inf):
        assert cell_text(blank) == ""
    assert cell_text("gross") == "gross"


def test_rows_read_back_as_written(tmp_path):
    """A converged point and a failed one (no numbers: blank cells) written and read back: the numbers to their 6
    digits, the failed point's numbers NaN (never 0: a study would show a failed run as a run with no wear), the
    flags as bools, the integers as ints, the text as written; a key not among the fields is not written."""
    fields = ("label", "converged", "cycles", "max_wear_depth", "energy_ratio", "regime")
    rows = [{"label": "P=100 d=0.004", "converged": True, "cycles": 3, "max_wear_depth": 1.234567891e-4,
             "energy_ratio": 0.25, "regime": "gross", "ignored": "x"},
            {"label": "P=200 d=0.004", "converged": False, "cycles": 0, "max_wear_depth": None,
             "energy_ratio": math.nan, "regime": ""}]
    path = write_rows(tmp_path / "table.csv", rows, fields)
    assert path.read_text().splitlines()[0] == ",".join(fields)
    back = read_rows(path, text=("label", "regime"), flags=("converged",), integers=("cycles",))
    assert [row["label"] for row in back] == ["P=100 d=0.004", "P=200 d=0.004"]
    assert [row["converged"] for row in back] == [True, False]
    assert [row["cycles"] for row in back] == [3, 0] and all(type(row["cycles"]) is int for row in back)
    assert back[0]["max_wear_depth"] == 1.23457e-4 and back[0]["energy_ratio"] == 0.25   # the 6 digits exactly
    assert math.isnan(back[1]["max_wear_depth"]) and math.isnan(back[1]["energy_ratio"])
    assert back[0]["regime"] == "gross" and back[1]["regime"] == ""
    assert "ignored" not in back[0]
