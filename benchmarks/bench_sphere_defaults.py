"""``sphere-flat``'s defaults before and after its uniform zone was sized from the wear of its cycles: whole
processes, each command run ``--repeat`` times, the two checkouts interleaved (so both meet the same load).

Two commands, each from the root of a checkout (``python -m dolfinx_fretting.cli``, so the checkout's own package
is imported; OPENBLAS_NUM_THREADS=1):

* ``default``: ``run sphere-flat`` as shipped (100 cycles, every cycle simulated, pictures and XDMF included);
* ``10k``: ``run sphere-flat --set loading.cycles=10000 --set wear.cycle_jump=true``, what a user types;
* ``10k-window-0.5`` (``--with-window``): the same with ``contact.candidate_half_width=0.5``, the key a user had
  to set by hand before.

For each run: wall time of the process, its CPU time (user + sys, from ``wait4``), the load average before it,
and from its ``summary.json`` the cycles done, whether it converged, dofs and contacts. Medians of the runs.

Usage::

    .venv/bin/python benchmarks/bench_sphere_defaults.py --before /path/to/old/checkout --after . \\
        [--repeat 3] [--work DIR] [--with-window] [--only default ...] [--json benchmarks/results/sphere_defaults.json]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import time
from pathlib import Path

COMMANDS = {
    "default": [],
    "10k": ["--set", "loading.cycles=10000", "--set", "wear.cycle_jump=true"],
    "10k-window-0.5": ["--set", "loading.cycles=10000", "--set", "wear.cycle_jump=true",
                       "--set", "contact.candidate_half_width=0.5"],
}


def run_once(repo: Path, label: str, out: Path) -> dict:
    """One whole process of ``COMMANDS[label]`` from the checkout ``repo``; its times and summary."""
    command = [str(repo / ".venv" / "bin" / "python"), "-m", "dolfinx_fretting.cli", "run", "sphere-flat",
               "--out", str(out), "--overwrite", *COMMANDS[label]]
    load = os.getloadavg()
    start = time.perf_counter()
    process = subprocess.Popen(command, cwd=repo, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    _, status, usage = os.wait4(process.pid, 0)
    wall = time.perf_counter() - start
    stderr = process.stderr.read().decode(errors="replace") if process.stderr else ""
    summary = json.loads((out / "summary.json").read_text()) if (out / "summary.json").is_file() else {}
    return {"command": " ".join(command), "cwd": str(repo), "exit_code": os.waitstatus_to_exitcode(status),
            "wall_s": wall, "cpu_s": usage.ru_utime + usage.ru_stime, "max_rss_mb": usage.ru_maxrss / 1024,
            "load_before": load, "cycles": summary.get("cycles"), "converged": summary.get("converged"),
            "dofs": summary.get("dofs"), "contacts": summary.get("contacts"),
            "error": summary.get("error") or (stderr.strip().splitlines()[-1] if stderr.strip() else None)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", type=Path, required=True, help="checkout of the old package (its .venv)")
    parser.add_argument("--after", type=Path, default=Path("."), help="checkout of the new package")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--work", type=Path, default=Path("/tmp/bench_sphere_defaults"))
    parser.add_argument("--with-window", action="store_true", help="also the 10^4 run with the window by hand")
    parser.add_argument("--only", choices=sorted(COMMANDS), nargs="+", help="these commands alone")
    parser.add_argument("--json", type=Path, default=None, help="write the runs and medians here")
    args = parser.parse_args()
    labels = args.only or ["default", "10k"] + (["10k-window-0.5"] if args.with_window else [])
    runs: dict[str, list[dict]] = {}
    for i in range(args.repeat):
        for label in labels:
            for side, repo in (("before", args.before.resolve()), ("after", args.after.resolve())):
                key = f"{side} {label}"
                result = run_once(repo, label, args.work / f"{side}_{label}_{i}")
                runs.setdefault(key, []).append(result)
                print(f"{key} #{i + 1}: wall {result['wall_s']:.1f} s, cpu {result['cpu_s']:.1f} s, cycles "
                      f"{result['cycles']}, converged {result['converged']}, load {result['load_before'][0]:.2f}",
                      flush=True)
    medians = {key: {"wall_s": statistics.median(r["wall_s"] for r in rs),
                     "cpu_s": statistics.median(r["cpu_s"] for r in rs),
                     "cycles": [r["cycles"] for r in rs], "converged": [r["converged"] for r in rs],
                     "dofs": rs[0]["dofs"], "contacts": rs[0]["contacts"]} for key, rs in runs.items()}
    print("\n| run | median wall (s) | median CPU (s) | cycles done | dofs | contacts |")
    print("| --- | ---: | ---: | --- | ---: | ---: |")
    for key, m in medians.items():
        print(f"| {key} | {m['wall_s']:.1f} | {m['cpu_s']:.1f} | {m['cycles']} | {m['dofs']} | {m['contacts']} |")
    if args.json is not None:
        args.json.write_text(json.dumps({"runs": runs, "medians": medians}, indent=1) + "\n")


if __name__ == "__main__":
    main()
