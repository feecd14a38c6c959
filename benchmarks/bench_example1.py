"""Example 1 (stromberg-block, 9000 cycles): wall time of the cycle paths and the accuracy of the fast one.

Side by side in one run, on the built-in scene's defaults (51 contacts, 80 increments a cycle):

* ``straightforward``: the paper's algorithm as written: the per-increment Python path, each increment's
  Uzawa solve warm-started from the previous increment, fixed tolerance ``local_tol = 1e-10``;
* ``compiled``: the same solves in the compiled cycle loop (no pattern reuse), warm start from the
  previous increment, then from the same increment of the previous cycle;
* ``default``: the compiled loop with the previous cycle's contact pattern tried first (an LU solve
  accepted only if it meets the tolerance), the package default.

The slow modes run ``--probe-cycles`` cycles (their time per cycle is steady; the total is extrapolated
to 9000 and marked so); the default runs all 9000. Accuracy: maximum wear depth and the wear profile (L2)
at the end against a tight-tolerance run (``local_tol = 1e-13``) of the default path, and the
straightforward mode's wear after the probe cycles against the default's at the same cycle.

Usage::

    .venv/bin/python benchmarks/bench_example1.py [--probe-cycles 100] [--cycles 9000] [--out FILE]
"""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import shlex
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from dolfinx_fretting.plots import read_table  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import run_scene  # noqa: E402

QUIET = ["output.xdmf=false", "output.plots=false", "output.progress=false"]


def run(tmp: Path, name: str, cycles: int, extra: list[str]) -> dict:
    out = tmp / name
    snap = f"output.snapshot_cycles=[{cycles}]"
    scene = load_scene("stromberg-block", QUIET + [f"loading.cycles={cycles}", snap,
                                                   f"output.loop_cycles=[{cycles}]"] + extra)
    t0 = time.perf_counter()
    s = run_scene(scene, out, quiet=True)
    wall = time.perf_counter() - t0
    prof = read_table(out / "contact_profiles.csv")
    last = prof["increment"] == prof["increment"].max()
    cyc = read_table(out / "cycles.csv")
    return {"name": name, "cycles": cycles, "wall_s": wall,
            "cycle_s": float(np.sum(cyc["wall_time_s"])) / cycles,
            "max_wear_depth": s["max_wear_depth"], "wear": prof["wear"][last].tolist(),
            "local_iterations": s["local_iterations"], "pattern_solves": s.get("pattern_solves")}


def errors(a: dict, ref: dict) -> tuple[float, float]:
    wa, wr = np.array(a["wear"]), np.array(ref["wear"])
    return (abs(a["max_wear_depth"] - ref["max_wear_depth"]) / ref["max_wear_depth"],
            float(np.linalg.norm(wa - wr) / np.linalg.norm(wr)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--probe-cycles", type=int, default=100)
    ap.add_argument("--cycles", type=int, default=9000)
    ap.add_argument("--out", default=str(HERE / "results" / "example1.md"))
    args = ap.parse_args(argv)
    N, n = args.cycles, args.probe_cycles
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        # Warm-up: numba compilation and DOLFINx form JIT are not part of any timing below.
        run(tmp, "warmup", 2, [])
        modes = [
            run(tmp, "straightforward", n, ["solver.cycle_kernel=false"]),
            run(tmp, "compiled, warm start: previous increment", n,
                ["solver.warm_start=increment", "solver.pattern_reuse=false"]),
            run(tmp, "compiled, warm start: previous cycle", n, ["solver.pattern_reuse=false"]),
            run(tmp, "default (compiled, previous cycle, pattern reuse)", n, []),
        ]
        full = run(tmp, "default, full run", N, [])
        tight = run(tmp, "default, local_tol = 1e-13, full run", N, ["solver.local_tol=1e-13"])
        loose = run(tmp, "default, local_tol = 1e-8, full run", N, ["solver.local_tol=1e-8"])
    base = modes[0]["cycle_s"]
    lines = [
        "# Example 1 (stromberg-block): speed of the cycle paths and accuracy of the default",
        "",
        f"Command: `{' '.join(shlex.quote(a) for a in [sys.executable, *sys.argv])}`  ",
        f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}, machine: {platform.processor() or platform.machine()}, "
        f"{platform.node()}; times exclude compilation (a warm-up run comes first).",
        "",
        f"## Time per cycle ({n} cycles each, side by side)",
        "",
        "| mode | s / cycle | speed-up vs straightforward | 9000 cycles (extrapolated) | local iterations / increment |",
        "| --- | ---: | ---: | ---: | ---: |",
    ]
    for m in modes:
        lines.append(f"| {m['name']} | {m['cycle_s']:.5f} | {base / m['cycle_s']:.1f} | {m['cycle_s'] * 9000:.0f} s | "
                     f"{m['local_iterations'] / (m['cycles'] * 80 + 1):.1f} |")
    e_sf = errors(modes[0], modes[3])
    lines += [
        "",
        f"Straightforward vs default after {n} cycles: max wear depth differs by {e_sf[0]:.2e} (relative), "
        f"wear profile by {e_sf[1]:.2e} (L2, relative).",
        "",
        f"## The full {N} cycles",
        "",
        "| run | wall time (s, whole run) | s / cycle | max wear depth (mm) | error in max wear vs tight | error in wear profile (L2) vs tight |",
        "| --- | ---: | ---: | ---: | ---: | ---: |",
    ]
    for m in (full, loose, tight):
        e = errors(m, tight)
        lines.append(f"| {m['name']} | {m['wall_s']:.1f} | {m['cycle_s']:.5f} | {m['max_wear_depth']:.6e} | "
                     f"{e[0]:.2e} | {e[1]:.2e} |")
    lines += ["", f"Pattern solves of the default full run: {full['pattern_solves']}.",
              f"Speed-up of the default full run over the straightforward mode (extrapolated to {N} cycles): "
              f"{base * N / full['wall_s']:.0f}x.", ""]
    text = "\n".join(lines)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(text)
    Path(args.out).with_suffix(".json").write_text(json.dumps(
        {"command": sys.argv, "modes": [{k: v for k, v in m.items() if k != "wear"} for m in modes],
         "full": {k: v for k, v in full.items() if k != "wear"}, "tight": {k: v for k, v in tight.items() if k != "wear"},
         "loose": {k: v for k, v in loose.items() if k != "wear"}}, indent=2))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
