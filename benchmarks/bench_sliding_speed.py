"""What finite sliding costs against the fixed pairing on McColl's scene, side by side, and against another tree.

Runs ``dolfinx-fretting run mccoll`` with ``contact.sliding = "finite"`` and ``"small"`` in turn (A, B, A, B, ...),
each run's CPU time (user + system of the child, ``resource.getrusage``) and wall time recorded; with
``--reference-tree`` the same pair also from another source tree (``PYTHONPATH``), alternated with this one. On a
shared machine the wall time follows the other jobs; the CPU time much less, so the ratios are read from it.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_sliding_speed.py [--cycles 40] [--repeats 3] \
        [--reference-tree /work/main] [--work /tmp/bench_sliding_speed] [--out benchmarks/results/sliding_speed]
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import statistics
import sys
from pathlib import Path

from _machine import run_tree  # benchmarks/ is on sys.path when a script runs

HERE = Path(__file__).resolve().parent
TREE = HERE.parent


def run(tree: Path, sliding: str, cycles: int, work: Path) -> dict:
    """One McColl run from the sources in ``tree``; its CPU and wall seconds and the summary's answers."""
    out = work / f"{tree.name}-{sliding}"
    command = [str(Path(sys.executable).parent / "dolfinx-fretting"), "run", "mccoll", "--out", str(out),
               "--overwrite", "--set", "output.progress=false", "--set", f"contact.sliding={sliding}",
               "--set", f"loading.cycles={cycles}", "--set", "output.plots=false", "--set", "output.xdmf=false"]
    cpu, wall = run_tree(command, tree)
    summary = json.loads((out / "summary.json").read_text())
    return {"cpu_s": cpu, "wall_s": wall, "repairs": summary.get("repairs"),
            "max_wear_depth": summary["max_wear_depth"], "dissipated_energy": summary["dissipated_energy"],
            "max_pressure": summary["max_pressure"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cycles", type=int, default=40)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--reference-tree", default=None, help="another source tree (e.g. /work/main) run alike")
    parser.add_argument("--work", default="/tmp/bench_sliding_speed")
    parser.add_argument("--out", default=str(HERE / "results" / "sliding_speed"))
    args = parser.parse_args()
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    trees = [TREE] + ([Path(args.reference_tree).resolve()] if args.reference_tree else [])
    runs: dict[str, list[dict]] = {}
    for tree in trees:   # untimed: numba's cache of each tree filled, the mesh module imported once
        for sliding in ("finite", "small"):
            run(tree, sliding, 1, work)
    for _ in range(args.repeats):
        for tree in trees:
            for sliding in ("finite", "small"):
                runs.setdefault(f"{tree}|{sliding}", []).append(run(tree, sliding, args.cycles, work))
            for sliding in ("finite", "small"):   # the set-up and one cycle, to read the cycles' own cost
                runs.setdefault(f"{tree}|{sliding}|1", []).append(run(tree, sliding, 1, work))
    load = os.getloadavg()
    command = ("OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_sliding_speed.py "
               f"--cycles {args.cycles} --repeats {args.repeats}"
               + (f" --reference-tree {args.reference_tree}" if args.reference_tree else ""))
    lines = [f"## Finite sliding against the fixed pairing, McColl, {args.cycles} simulated cycles", "",
             f"Command: `{command}`", "",
             f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}; machine: {platform.machine()}, "
             f"{os.cpu_count()} cores; load average at the end {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f}. "
             f"Runs alternated (tree by tree, finite then fixed, then the same with 1 cycle), {args.repeats} of each "
             "after one untimed run of each (1 cycle); medians. The cycles' CPU: the run's median minus the 1-cycle "
             "runs' (the set-up and one cycle).", "",
             "| tree | CPU finite (s) | CPU fixed (s) | finite / fixed (CPU) | wall finite (s) | wall fixed (s) | "
             "finite / fixed (wall) | per-repeat CPU ratios | repairs | CPU 1-cycle runs finite / fixed (s) | "
             f"the {args.cycles - 1} cycles' CPU finite / fixed (s) | their ratio |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: |"]
    for tree in trees:
        finite, small = runs[f"{tree}|finite"], runs[f"{tree}|small"]
        one = [statistics.median(r["cpu_s"] for r in runs[f"{tree}|{s}|1"]) for s in ("finite", "small")]
        med = {k: (statistics.median(r[k] for r in finite), statistics.median(r[k] for r in small))
               for k in ("cpu_s", "wall_s")}
        ratios = ", ".join(f"{a['cpu_s'] / b['cpu_s']:.2f}" for a, b in zip(finite, small))
        cycles = (med["cpu_s"][0] - one[0], med["cpu_s"][1] - one[1])
        lines.append(f"| `{tree}` | {med['cpu_s'][0]:.1f} | {med['cpu_s'][1]:.1f} | "
                     f"{med['cpu_s'][0] / med['cpu_s'][1]:.2f} | {med['wall_s'][0]:.1f} | {med['wall_s'][1]:.1f} | "
                     f"{med['wall_s'][0] / med['wall_s'][1]:.2f} | {ratios} | {finite[0]['repairs']} | "
                     f"{one[0]:.2f} / {one[1]:.2f} | {cycles[0]:.1f} / {cycles[1]:.1f} | {cycles[0] / cycles[1]:.2f} |")
    if len(trees) == 2:
        here, there = runs[f"{trees[0]}|finite"], runs[f"{trees[1]}|finite"]
        same = all(a[k] == b[k] for a, b in zip(here, there)
                   for k in ("repairs", "max_wear_depth", "dissipated_energy", "max_pressure"))
        # how far apart, where they differ (a change of the local solve moves them at its tolerance's level)
        apart = ", ".join(f"{k} {max(abs(a[k] - b[k]) / abs(b[k]) for a, b in zip(here, there)):.1e}"
                          for k in ("max_wear_depth", "dissipated_energy", "max_pressure"))
        lines += ["", f"The finite-sliding summaries of both trees (repairs, max_wear_depth, dissipated_energy, "
                  f"max_pressure): {'identical' if same else 'DIFFERENT'}; largest relative differences: {apart}; "
                  f"repairs {here[0]['repairs']} / {there[0]['repairs']}."]
    text = "\n".join(lines) + "\n"
    print(text)
    Path(args.out).with_suffix(".md").write_text(text)
    Path(args.out).with_suffix(".json").write_text(json.dumps({k: v for k, v in runs.items()}, indent=1))


if __name__ == "__main__":
    main()
