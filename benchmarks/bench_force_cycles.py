"""Force-controlled cycles in the compiled loop against increment by increment, McColl's scene, side by side.

McColl's cycles hold the normal force (``loading.normal_force``): each increment finds the approach by the load
control. Runs ``dolfinx-fretting run mccoll`` with the fixed pairing (``contact.sliding = "small"``: finite sliding
re-pairs between increments and stays increment by increment) through the compiled loop (the default) and with
``solver.cycle_kernel = false`` (the stepwise path) in turn (A, B, A, B, ...), each run's CPU time (user + system of
the child, ``resource.getrusage``) and wall time recorded, and the same pair with one cycle, whose CPU (the model's
set-up and one cycle) is subtracted to give the cycles' own. On a shared machine the wall time follows the other
jobs; the CPU time much less, so the ratios are read from it.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_force_cycles.py [--cycles 20] [--repeats 3] \
        [--work /tmp/bench_force_cycles] [--out benchmarks/results/force_cycles]
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
ROUTES = {"compiled": [], "stepwise": ["--set", "solver.cycle_kernel=false"]}
ANSWERS = ("max_wear_depth", "dissipated_energy", "max_pressure", "normal_force", "tangential_force")


def run(route: str, cycles: int, work: Path) -> dict:
    """One McColl run (fixed pairing) by ``route``; its CPU and wall seconds and the summary's answers."""
    out = work / f"{route}-{cycles}"
    command = [str(Path(sys.executable).parent / "dolfinx-fretting"), "run", "mccoll", "--out", str(out),
               "--overwrite", "--set", "output.progress=false", "--set", "contact.sliding='small'",
               "--set", f"loading.cycles={cycles}", "--set", "output.plots=false", "--set", "output.xdmf=false",
               *ROUTES[route]]
    cpu, wall = run_tree(command, TREE)
    summary = json.loads((out / "summary.json").read_text())
    return {"cpu_s": cpu, "wall_s": wall, "cycle_path": summary["cycle_path"],
            **{key: summary[key] for key in ANSWERS}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cycles", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--work", default="/tmp/bench_force_cycles")
    parser.add_argument("--out", default=str(HERE / "results" / "force_cycles"))
    args = parser.parse_args()
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    for route in ROUTES:   # untimed: numba's cache filled, the mesh module imported once
        run(route, 1, work)
    runs: dict[str, list[dict]] = {}
    for _ in range(args.repeats):
        for cycles in (args.cycles, 1):
            for route in ROUTES:
                runs.setdefault(f"{route}|{cycles}", []).append(run(route, cycles, work))
    load = os.getloadavg()
    command = ("OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_force_cycles.py "
               f"--cycles {args.cycles} --repeats {args.repeats}"
               + (f" --work {args.work}" if args.work != parser.get_default("work") else "")
               + (f" --out {args.out}" if args.out != parser.get_default("out") else ""))
    med = {key: {k: statistics.median(r[k] for r in rows) for k in ("cpu_s", "wall_s")} for key, rows in runs.items()}
    lines = [f"## Force-controlled cycles: compiled loop against increment by increment, McColl (fixed pairing), "
             f"{args.cycles} simulated cycles", "",
             f"Command: `{command}`", "",
             f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}; machine: {platform.machine()}, "
             f"{os.cpu_count()} cores; load average at the end {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f}. "
             f"Runs alternated (compiled, stepwise; {args.cycles} cycles then 1), {args.repeats} of each after one "
             "untimed run of each; medians. Cycles' CPU: the run's minus the 1-cycle run's (set-up and one cycle), "
             f"so {args.cycles - 1} cycles.", "",
             "| route | CPU run (s) | CPU 1-cycle run (s) | CPU of the cycles (s) | per cycle (ms) | wall run (s) | "
             "per-repeat CPU (s) | cycle_path |",
             "| --- | ---: | ---: | ---: | ---: | ---: | --- | --- |"]
    cycles_cpu = {}
    for route in ROUTES:
        full, one = med[f"{route}|{args.cycles}"], med[f"{route}|1"]
        cycles_cpu[route] = full["cpu_s"] - one["cpu_s"]
        per_repeat = ", ".join(f"{r['cpu_s']:.2f}" for r in runs[f"{route}|{args.cycles}"])
        lines.append(f"| {route} | {full['cpu_s']:.2f} | {one['cpu_s']:.2f} | {cycles_cpu[route]:.2f} | "
                     f"{1000 * cycles_cpu[route] / max(args.cycles - 1, 1):.1f} | {full['wall_s']:.1f} | {per_repeat} "
                     f"| {runs[f'{route}|{args.cycles}'][0]['cycle_path']} |")
    fast, slow = runs[f"compiled|{args.cycles}"][0], runs[f"stepwise|{args.cycles}"][0]
    deviation = {k: abs(fast[k] - slow[k]) / max(abs(slow[k]), 1e-300) for k in ANSWERS}
    lines += ["", f"Whole run, stepwise / compiled (CPU): "
              f"{med[f'stepwise|{args.cycles}']['cpu_s'] / med[f'compiled|{args.cycles}']['cpu_s']:.2f}; "
              f"the cycles alone: {cycles_cpu['stepwise'] / max(cycles_cpu['compiled'], 1e-9):.2f}.", "",
              "The summaries' answers, compiled against stepwise (relative): "
              + ", ".join(f"{k} {v:.1e}" for k, v in deviation.items()) + "."]
    text = "\n".join(lines) + "\n"
    print(text)
    Path(args.out).with_suffix(".md").write_text(text)
    Path(args.out).with_suffix(".json").write_text(json.dumps(runs, indent=1))


if __name__ == "__main__":
    main()
