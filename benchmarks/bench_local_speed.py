"""The local solve at 1000+ 3D contacts: sweeps on the working set, float32 sweeps, against the full sweeps.

Runs the sphere-flat problems written by ``make_sphere_flat_problems.py`` (W, q, mu and the warm start of the
preload's last increment and of a gross-slip increment, as the package forms them) through
``local_solvers.solve`` three ways, side by side in one process, alternating A/B/C within each repeat (the
machine is shared: medians of the repeats, and the load average is recorded):

* ``full``: every contact swept on the whole W (``working_set=False``: the solver before issue 26);
* ``working set``: the sweeps on the contacts with a force and those whose gap is below ``NEAR_MARGIN`` times
  the deepest penetration, on ``W_AA``, then a check on all contacts (``working_set=True``, the default);
* ``float32``: the same with the sweeps' incremental updates read from a float32 ``W_AA``
  (``float32_sweeps=True``).

For each: time (median, min), sweeps, passes, working-set size, joined contacts, the error reached and the
distance of the answer to the full sweeps' (``same bits`` when r and x are equal to the last bit). Then the
working set's margin: the gross-slip problem from zero and warm at several ``NEAR_MARGIN`` values.

Usage (from the repository root)::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/make_sphere_flat_problems.py --sizes 0.031 0.0155 0.0117 \
        --out /tmp/sphere_flat_problems
    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_local_speed.py /tmp/sphere_flat_problems
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import shlex
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from _machine import cpu_model  # noqa: E402  (benchmarks/ is on sys.path when a script runs)

from dolfinx_fretting import fclib, local_solvers  # noqa: E402

VARIANTS = {"full": {"working_set": False}, "working set": {"working_set": True},
            "float32": {"working_set": True, "float32_sweeps": True}}


def solve_timed(problem: dict, method: str, warm: bool, tol: float, options: dict
                ) -> tuple[local_solvers.LocalResult, float]:
    """The solve and its CPU time (one thread: the process's CPU time is the solve's, and it is far less
    disturbed than the wall clock by the other jobs on the machine)."""
    t0 = time.process_time()
    result = local_solvers.solve(problem["W"], problem["q"], problem["mu"], 3, method=method, tol=tol, max_iter=20000,
                                 r0=problem["r0"] if warm else None, block_steps=problem["steps"], **options)
    return result, time.process_time() - t0


def compare(problem: dict, method: str, warm: bool, tol: float, repeats: int) -> dict:
    times: dict[str, list[float]] = {name: [] for name in VARIANTS}
    results: dict[str, local_solvers.LocalResult] = {}
    for _ in range(repeats):
        for name, options in VARIANTS.items():  # alternating: the machine's load hits all alike
            results[name], t = solve_timed(problem, method, warm, tol, options)
            times[name].append(t)
    full = results["full"]
    out = {}
    for name, result in results.items():
        if not result.converged:
            raise RuntimeError(f"{problem['name']} {method} {name}: {result.message}")
        out[name] = {"median_s": float(np.median(times[name])), "min_s": float(np.min(times[name])),
                     "sweeps": result.sweeps, "passes": result.passes, "working_set": result.working_set,
                     "joined": result.joined, "error": result.error,
                     "dr": float(np.abs(result.r - full.r).max() / np.abs(full.r).max()),
                     "same_bits": bool(np.array_equal(result.r, full.r) and np.array_equal(result.x, full.x))}
    return out


def margins(problem: dict, method: str, tol: float, repeats: int, values: list[float]) -> list[dict]:
    rows = []
    saved = local_solvers.NEAR_MARGIN
    try:
        for warm in (True, False):
            reference, _ = solve_timed(problem, method, warm, tol, {"working_set": False})
            for value in values:
                local_solvers.NEAR_MARGIN = value
                times = []
                for _ in range(repeats):
                    result, t = solve_timed(problem, method, warm, tol, {})
                    times.append(t)
                rows.append({"warm": warm, "margin": value, "median_s": float(np.median(times)),
                             "sweeps": result.sweeps, "passes": result.passes, "working_set": result.working_set,
                             "joined": result.joined,
                             "same_bits": bool(np.array_equal(result.r, reference.r)),
                             "dr": float(np.abs(result.r - reference.r).max() / np.abs(reference.r).max())})
    finally:
        local_solvers.NEAR_MARGIN = saved
    return rows


def ms(t: float) -> str:
    return f"{1e3 * t:.3g} ms" if t < 1 else f"{t:.3g} s"


def markdown(command: str, info: dict, records: list[dict]) -> str:
    L = ["# The local solve at 1000+ 3D contacts: sweeps on the working set, float32 sweeps", "",
         f"Command (from the repository root): `{command}`", "",
         f"- date: {info['date']}; machine: {info['cpu']}, {info['logical_cpus']} logical CPUs shared with "
         f"other jobs; Python {info['python']}, numpy {info['numpy']}, numba {info['numba']}",
         f"- load average (1, 5, 15 min) at start {', '.join(f'{v:.2f}' for v in info['load_start'])}, at end "
         f"{', '.join(f'{v:.2f}' for v in info['load_end'])}",
         f"- tol {info['tol']:g} on the natural-map error (the scenes' `solver.local_tol`), cap 20000 sweeps; "
         f"{info['repeats']} repeats, the three variants alternating within each; median (min) CPU time of "
         "the call to `local_solvers.solve` (one thread; the machine's load makes the wall clock 2-10x longer)",
         "- problems (`benchmarks/make_sphere_flat_problems.py`, files kept out of the repository): `FE`, the "
         "sphere-flat scene's own (W of the FE model, q and the warm start formed by the package); `half-space`, a "
         "synthetic W of the same structure (two like elastic half-spaces, 1/r decay) with the scene's increments",
         "",
         "`full`: every contact swept on the whole W (the solver before); `working set`: the default, sweeps on the "
         "contacts with a force or a gap below NEAR_MARGIN x the deepest penetration, then a check on all; "
         "`float32`: the same with float32 incremental updates. `set`: working-set size at the end (+ joined "
         "during the solve, passes); `dr`: max |r - r_full| / max |r_full|.", ""]
    for method in info["methods"]:
        L += [f"## {method}", "", "| contacts | W | source | problem | start | full | working set | float32 "
              "| speed-up ws | speed-up f32 | sweeps full / ws / f32 | set (joined, passes) | dr ws | dr f32 |",
              "|---:|---:|---|---|---|---:|---:|---:|---:|---:|---|---|---|---:|"]
        for rec in records:
            for key, cmp in rec["compare"].items():
                if not key.startswith(method + " "):
                    continue
                start = key.split(" ", 1)[1]
                f, w, s = cmp["full"], cmp["working set"], cmp["float32"]
                L.append(f"| {rec['nc']} | {rec['W_mb']:.1f} MB | {rec['source']} | {rec['problem']} | {start} | "
                         f"{ms(f['median_s'])} ({ms(f['min_s'])}) | {ms(w['median_s'])} ({ms(w['min_s'])}) | "
                         f"{ms(s['median_s'])} ({ms(s['min_s'])}) | {f['median_s'] / w['median_s']:.1f} | "
                         f"{f['median_s'] / s['median_s']:.1f} | {f['sweeps']} / {w['sweeps']} / {s['sweeps']} | "
                         f"{w['working_set']} ({w['joined']}, {w['passes']}) | "
                         f"{'same bits' if w['same_bits'] else format(w['dr'], '.1e')} | {s['dr']:.1e} |")
        L.append("")
    L += ["## The working set's margin (gross-slip problem, uzawa)", "",
          "| contacts | source | start | NEAR_MARGIN | time | sweeps | set | joined | passes | answer |",
          "|---:|---|---|---:|---:|---:|---:|---:|---:|---|"]
    for rec in records:
        for row in rec.get("margins", []):
            answer = "same bits" if row["same_bits"] else f"dr {row['dr']:.1e}"
            L.append(f"| {rec['nc']} | {rec['source']} | {'warm' if row['warm'] else 'zero'} | {row['margin']:g} | "
                     f"{ms(row['median_s'])} | {row['sweeps']} | {row['working_set']} | {row['joined']} | "
                     f"{row['passes']} | {answer} |")
    return "\n".join(L) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("folder", type=Path, help="folder of the sphere_flat_*.npz problems")
    ap.add_argument("--methods", nargs="+", default=["uzawa", "nsgs"], choices=["uzawa", "nsgs"])
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--margins", type=float, nargs="*", default=[0.0, 0.01, 0.05, 0.2, 1.0])
    ap.add_argument("--max-contacts", type=int, default=0, help="skip problems above this many contacts (0: none)")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "local_speed")
    args = ap.parse_args(argv)
    argv_used = sys.argv[1:] if argv is None else argv
    command = ("OPENBLAS_NUM_THREADS=" + os.environ.get("OPENBLAS_NUM_THREADS", "<unset>") +
               " .venv/bin/python benchmarks/bench_local_speed.py" + "".join(" " + shlex.quote(a) for a in argv_used))
    import numba

    info = {"date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"), "cpu": cpu_model(),
            "logical_cpus": os.cpu_count(), "python": platform.python_version(), "numpy": np.__version__,
            "numba": numba.__version__, "load_start": list(os.getloadavg()), "tol": args.tol,
            "repeats": args.repeats, "methods": args.methods}
    files = sorted((p for p in args.folder.glob("*.npz") if p.stem.startswith(("sphere_flat_", "half_space_"))),
                   key=lambda p: (int(p.stem.split("_")[2]), p.stem))
    records = []
    for path in files:
        if args.max_contacts and int(path.stem.split("_")[2]) > args.max_contacts:
            continue
        loaded = fclib.load(path)
        with np.load(path) as extra:
            r0 = np.array(extra["r0"])
        W = np.ascontiguousarray(loaded.W)
        problem = {"name": path.stem, "W": W, "q": loaded.q, "mu": loaded.mu, "r0": r0,
                   "steps": local_solvers.block_rho(W, 3)}
        nc = loaded.q.size // 3
        kind = "gross slip" if "gross_slip" in path.stem else "preload"
        # JIT (cached on disk) and first touch of W out of the timings.
        for options in VARIANTS.values():
            solve_timed(problem, args.methods[0], True, args.tol, options)
        source = "FE" if path.stem.startswith("sphere_flat_") else "half-space"
        rec = {"file": path.name, "nc": nc, "problem": kind, "source": source, "W_mb": W.nbytes / 2**20, "compare": {}}
        for method in args.methods:
            for warm in (True, False):
                key = f"{method} {'warm' if warm else 'zero'}"
                rec["compare"][key] = compare(problem, method, warm, args.tol, args.repeats)
                c = rec["compare"][key]
                print(f"{path.stem} {key}: " + ", ".join(
                    f"{n} {ms(v['median_s'])} ({v['sweeps']} sw, set {v['working_set']}+{v['joined']}, "
                    f"dr {v['dr']:.1e})" for n, v in c.items()), flush=True)
        if kind == "gross slip" and args.margins:
            rec["margins"] = margins(problem, "uzawa", args.tol, max(1, args.repeats // 2), args.margins)
        records.append(rec)
        info["load_end"] = list(os.getloadavg())
        args.out.with_suffix(".json").write_text(json.dumps({"command": command, "machine": info,
                                                             "results": records}, indent=1) + "\n")
        args.out.with_suffix(".md").write_text(markdown(command, info, records))
    print(f"wrote {args.out.with_suffix('.md')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
