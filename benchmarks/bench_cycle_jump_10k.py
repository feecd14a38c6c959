"""Cycle jumps over 10^4 sphere-flat cycles: the run's error estimate against the same run with the bounds / 4.

No every-cycle reference at 10^4 cycles (hours): the default scene with ``loading.cycles=10000
wear.cycle_jump=true`` is compared, contact by contact at the last cycle, with the same run with the accuracy
bounds divided by 4 (f_w 0.025, f_p 0.0125). Prints each run's simulated cycles, wall time, estimate and sum of
bounds, and max |g_default - g_bounds/4| (results/cycle_jump.md, section "sphere-flat, 10^4 cycles").

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_cycle_jump_10k.py
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import CHECKPOINT, read_checkpoint, run_scene  # noqa: E402

QUIET = ["output.xdmf=false", "output.plots=false", "output.progress=false", "output.contact_profiles=false",
         "loading.cycles=10000", "wear.cycle_jump=true"]
RUNS = (("default", []), ("bounds/4", ["wear.jump_wear_fraction=0.025", "wear.jump_pressure_change=0.0125"]))


def main() -> int:
    out = {}
    with tempfile.TemporaryDirectory() as tmpdir:
        for name, extra in RUNS:
            folder = Path(tmpdir) / name.replace("/", "_")
            t0 = time.perf_counter()
            summary = run_scene(load_scene("sphere-flat", QUIET + extra), folder, quiet=True)
            wall = time.perf_counter() - t0
            out[name] = (summary, read_checkpoint(folder / CHECKPOINT)[1]["wear_gap"])
            jump = summary["cycle_jump"]
            print(name, "simulated", jump["simulated_cycles"], "estimate", jump["wear_error_estimate"],
                  "sum of bounds", jump["wear_error_sum_of_bounds"], "wall", wall, "max wear depth",
                  summary["max_wear_depth"], flush=True)
    (s0, g0), (s1, g1) = out["default"], out["bounds/4"]
    difference = float(np.abs(g0 - g1).max())
    print("max|g_default - g_bounds/4|", difference, "max wear depth difference",
          abs(s0["max_wear_depth"] - s1["max_wear_depth"]), "estimate / difference",
          s0["cycle_jump"]["wear_error_estimate"] / difference, "sum of bounds / difference",
          s0["cycle_jump"]["wear_error_sum_of_bounds"] / difference)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
