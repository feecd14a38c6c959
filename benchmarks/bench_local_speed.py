"""The local solve at 1000+ 3D contacts: sweeps on the working set, its block held between solves, float32.

Runs the sphere-flat problems written by ``make_sphere_flat_problems.py`` (W, q, mu and the warm start of the
preload's last increment and of a gross-slip increment, as the package forms them) through
``local_solvers.solve`` several ways, side by side in one process, alternating within each repeat (the machine is
shared: medians of the repeats, and the load average is recorded):

* ``full``: every contact swept on the whole W (``working_set=False``: the solver before issue 26);
* ``working set``: the sweeps on the contacts with a force and those whose gap is below ``NEAR_MARGIN`` times
  the deepest penetration, on ``W_AA``, then a check on all contacts, ``W_AA`` gathered and W checked at every
  solve (``hold_block=False``: the default before the block was held);
* ``held``: the same with ``W_AA`` and W's check held from the previous solve on the same W and block_steps
  arrays (the default);
* ``float32 held``: the same with the sweeps' incremental updates read from a float32 ``W_AA``
  (``float32_sweeps=True``);
* ``held rho=F`` (``--rho F``): the held route with the Uzawa step (NSGS relaxation) times F: over-relaxation.

For each: time (median, min), sweeps, passes, working-set size, joined contacts, solves on the held block, and the
distance of the answer to the full sweeps' (``same bits`` when r and x are equal to the last bit). ``--cycle N``
adds a fretting cycle of N gross-slip increments on each half-space problem (the increments a run sweeps one after
the other, where the block is held from one to the next). Then the working set's margin.

Usage (from the repository root)::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/make_sphere_flat_problems.py --sizes 0.031 0.0155 0.0117 \
        --out /tmp/sphere_flat_problems
    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_local_speed.py /tmp/sphere_flat_problems --cycle 40
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

# The routes compared, side by side: the keyword arguments of local_solvers.solve (besides the problem's).
VARIANTS = {"full": {"working_set": False, "hold_block": False},
            "working set": {"hold_block": False},
            "held": {},
            "float32 held": {"float32_sweeps": True}}
REFERENCE = "full"


def solve_timed(problem: dict, method: str, warm: bool, tol: float, options: dict, q: np.ndarray | None = None,
                r0: np.ndarray | None = None) -> tuple[local_solvers.LocalResult, float]:
    """The solve and its CPU time (one thread: the process's CPU time is the solve's, and it is far less
    disturbed than the wall clock by the other jobs on the machine)."""
    start = r0 if r0 is not None else (problem["r0"] if warm else None)
    t0 = time.process_time()
    result = local_solvers.solve(problem["W"], problem["q"] if q is None else q, problem["mu"], 3, method=method,
                                 tol=tol, max_iter=20000, r0=start, block_steps=problem["steps"], **options)
    return result, time.process_time() - t0


def summary(result: local_solvers.LocalResult, reference: local_solvers.LocalResult, times: list[float]) -> dict:
    return {"median_s": float(np.median(times)), "min_s": float(np.min(times)), "sweeps": result.sweeps,
            "passes": result.passes, "working_set": result.working_set, "joined": result.joined,
            "error": result.error, "dr": float(np.abs(result.r - reference.r).max() / np.abs(reference.r).max()),
            "same_bits": bool(np.array_equal(result.r, reference.r) and np.array_equal(result.x, reference.x))}


def compare(problem: dict, method: str, warm: bool, tol: float, repeats: int, variants: dict) -> dict:
    times: dict[str, list[float]] = {name: [] for name in variants}
    held: dict[str, int] = {name: 0 for name in variants}
    results: dict[str, local_solvers.LocalResult] = {}
    for _ in range(repeats):
        for name, options in variants.items():  # alternating: the machine's load hits all alike
            results[name], t = solve_timed(problem, method, warm, tol, options)
            times[name].append(t)
            held[name] += results[name].block_held
    out = {}
    for name, result in results.items():
        if not result.converged:
            raise RuntimeError(f"{problem['name']} {method} {name}: {result.message}")
        out[name] = summary(result, results[REFERENCE], times[name]) | {"held": held[name]}
    return out


def cycle(problem: dict, method: str, tol: float, increments: int, variants: dict) -> dict:
    """A fretting cycle of gross-slip increments on a half-space problem, each warm started from the variant's own
    increment before (the variants alternating increment by increment): the tangential part of q (a uniform -slip
    along x, ``support.local_problems.sphere_flat_q``) goes as s cos(2 pi k / n), s the file's slip, the normal part
    as the file's. Per variant: CPU time per increment (median, total), increments that used the held block, mean
    sweeps, and the answers against the reference's."""
    slip = -float(problem["q"][1])
    qs = []
    for k in range(increments + 1):
        q = problem["q"].copy()
        q[1::3] = -slip * np.cos(2.0 * np.pi * k / increments)
        qs.append(q)
    r = {name: solve_timed(problem, method, True, tol, options, q=qs[0])[0].r for name, options in variants.items()}
    times: dict[str, list[float]] = {name: [] for name in variants}
    sweeps: dict[str, list[int]] = {name: [] for name in variants}
    held = {name: 0 for name in variants}
    same = {name: True for name in variants}
    dr = {name: 0.0 for name in variants}
    for q in qs[1:]:
        results = {}
        for name, options in variants.items():
            result, t = solve_timed(problem, method, True, tol, options, q=q, r0=r[name])
            if not result.converged:
                raise RuntimeError(f"{problem['name']} cycle {name}: {result.message}")
            r[name] = result.r
            results[name] = result
            times[name].append(t)
            sweeps[name].append(result.sweeps)
            held[name] += result.block_held
        reference = results[REFERENCE]
        for name, result in results.items():
            same[name] &= bool(np.array_equal(result.r, reference.r) and np.array_equal(result.x, reference.x))
            dr[name] = max(dr[name], float(np.abs(result.r - reference.r).max() / np.abs(reference.r).max()))
    return {name: {"median_s": float(np.median(times[name])), "total_s": float(np.sum(times[name])),
                   "max_s": float(np.max(times[name])), "held": held[name], "sweeps": float(np.mean(sweeps[name])),
                   "increments": increments, "same_bits": same[name], "dr": dr[name]} for name in variants}


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


def answer(row: dict) -> str:
    return "same bits" if row["same_bits"] else f"dr {row['dr']:.1e}"


def markdown(command: str, info: dict, records: list[dict]) -> str:
    names = info["variants"]
    others = [n for n in names if n != REFERENCE]
    L = ["# The local solve at 1000+ 3D contacts: sweeps on the working set, its block held between solves", "",
         f"Command (from the repository root): `{command}`", "",
         f"- date: {info['date']}; machine: {info['cpu']}, {info['logical_cpus']} logical CPUs shared with "
         f"other jobs; Python {info['python']}, numpy {info['numpy']}, numba {info['numba']}",
         f"- load average (1, 5, 15 min) at start {', '.join(f'{v:.2f}' for v in info['load_start'])}, at end "
         f"{', '.join(f'{v:.2f}' for v in info['load_end'])}",
         f"- tol {info['tol']:g} on the natural-map error (the scenes' `solver.local_tol`), cap 20000 sweeps; "
         f"{info['repeats']} repeats, the variants alternating within each; median (min) CPU time of "
         "the call to `local_solvers.solve` (one thread; the machine's load makes the wall clock longer)",
         "- problems (`benchmarks/make_sphere_flat_problems.py`, files kept out of the repository): `FE`, the "
         "sphere-flat scene's own (W of the FE model, q and the warm start formed by the package); `half-space`, a "
         "synthetic W of the same structure (two like elastic half-spaces, 1/r decay) with the scene's increments",
         "",
         "Variants (keyword arguments of `local_solvers.solve`): "
         + "; ".join(f"`{n}`: `{info['variant_options'][n]}`" for n in names) + ". `full`: every contact swept on "
         "the whole W; `working set`: sweeps on the contacts with a force or a gap below NEAR_MARGIN x the deepest "
         "penetration, W_AA gathered and W checked at every solve (the default before); `held`: the same with "
         "W_AA (and W's check) held from the previous solve on this W and block_steps (the default now; `held` "
         "column: solves of the repeats that used the held block); `float32 held`: float32 incremental updates "
         "on the held float32 copy; `rho=`: the Uzawa step (or NSGS relaxation) factor. `set`: working-set size at "
         "the end (joined during the solve, passes); answers against `full`: `same bits`, or dr = "
         "max |r - r_full| / max |r_full|.", ""]
    for method in info["methods"]:
        L += [f"## {method}", "", "| contacts | W | source | problem | start | " + " | ".join(names) + " | "
              + " | ".join(f"speed-up {n}" for n in others) + " | sweeps | set (joined, passes) | held | "
              + " | ".join(f"answer {n}" for n in others) + " |",
              "|---:|---:|---|---|---|" + "---:|" * (len(names) + len(others)) + "---|---|---|" + "---|" * len(others)]
        for rec in records:
            for key, cmp in rec["compare"].items():
                if not key.startswith(method + " "):
                    continue
                start = key.split(" ", 1)[1]
                f = cmp[REFERENCE]
                last = cmp[names[-1]]
                L.append(f"| {rec['nc']} | {rec['W_mb']:.1f} MB | {rec['source']} | {rec['problem']} | {start} | "
                         + " | ".join(f"{ms(cmp[n]['median_s'])} ({ms(cmp[n]['min_s'])})" for n in names) + " | "
                         + " | ".join(f"{f['median_s'] / cmp[n]['median_s']:.1f}" for n in others) + " | "
                         + " / ".join(str(cmp[n]["sweeps"]) for n in names) + " | "
                         + f"{last['working_set']} ({last['joined']}, {last['passes']}) | "
                         + " / ".join(str(cmp[n]["held"]) for n in names) + " | "
                         + " | ".join(answer(cmp[n]) for n in others) + " |")
        L.append("")
    cycles = [rec for rec in records if rec.get("cycle")]
    if cycles:
        L += ["## A fretting cycle of increments (half-space, uzawa, each warm from the one before)", "",
              "| contacts | increments | " + " | ".join(f"{n}: median (max) per increment" for n in names)
              + " | mean sweeps | increments on the held block | " + " | ".join(f"answer {n}" for n in others) + " |",
              "|---:|---:|" + "---:|" * len(names) + "---|---|" + "---|" * len(others)]
        for rec in cycles:
            c = rec["cycle"]
            L.append(f"| {rec['nc']} | {c[REFERENCE]['increments']} | "
                     + " | ".join(f"{ms(c[n]['median_s'])} ({ms(c[n]['max_s'])})" for n in names) + " | "
                     + " / ".join(f"{c[n]['sweeps']:.1f}" for n in names) + " | "
                     + " / ".join(str(c[n]["held"]) for n in names) + " | "
                     + " | ".join(answer(c[n]) for n in others) + " |")
        L.append("")
    margin_rows = [(rec, row) for rec in records for row in rec.get("margins", [])]
    if margin_rows:
        L += ["## The working set's margin (gross-slip problem, uzawa)", "",
              "| contacts | source | start | NEAR_MARGIN | time | sweeps | set | joined | passes | answer |",
              "|---:|---|---|---:|---:|---:|---:|---:|---:|---|"]
        for rec, row in margin_rows:
            L.append(f"| {rec['nc']} | {rec['source']} | {'warm' if row['warm'] else 'zero'} | {row['margin']:g} | "
                     f"{ms(row['median_s'])} | {row['sweeps']} | {row['working_set']} | {row['joined']} | "
                     f"{row['passes']} | {answer(row)} |")
    return "\n".join(L) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("folder", type=Path, help="folder of the sphere_flat_*.npz problems")
    ap.add_argument("--methods", nargs="+", default=["uzawa", "nsgs"], choices=["uzawa", "nsgs"])
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--margins", type=float, nargs="*", default=[0.0, 0.01, 0.05, 0.2, 1.0])
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS),
                    help=f"routes compared ({REFERENCE!r} is always run: the answers are checked against it)")
    ap.add_argument("--rho", type=float, nargs="*", default=[],
                    help="also the held route with these step (uzawa) or relaxation (nsgs) factors: over-relaxation")
    ap.add_argument("--cycle", type=int, default=0,
                    help="also a fretting cycle of this many gross-slip increments on each half-space problem")
    ap.add_argument("--methods-only", action="store_true", help="skip the single-problem comparisons (cycle only)")
    ap.add_argument("--max-contacts", type=int, default=0, help="skip problems above this many contacts (0: none)")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "local_speed")
    args = ap.parse_args(argv)
    argv_used = sys.argv[1:] if argv is None else argv
    command = ("OPENBLAS_NUM_THREADS=" + os.environ.get("OPENBLAS_NUM_THREADS", "<unset>") +
               " .venv/bin/python benchmarks/bench_local_speed.py" + "".join(" " + shlex.quote(a) for a in argv_used))
    import numba

    variants = {REFERENCE: VARIANTS[REFERENCE]} | {n: VARIANTS[n] for n in args.variants}
    variants |= {f"held rho={factor:g}": {"rho": factor} for factor in args.rho}
    info = {"date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"), "cpu": cpu_model(),
            "logical_cpus": os.cpu_count(), "python": platform.python_version(), "numpy": np.__version__,
            "numba": numba.__version__, "load_start": list(os.getloadavg()), "tol": args.tol,
            "repeats": args.repeats, "methods": args.methods, "variants": list(variants),
            "variant_options": {n: ", ".join(f"{k}={v}" for k, v in o.items()) or "defaults"
                                for n, o in variants.items()}}
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
        for options in variants.values():
            solve_timed(problem, args.methods[0], True, args.tol, options)
        source = "FE" if path.stem.startswith("sphere_flat_") else "half-space"
        rec = {"file": path.name, "nc": nc, "problem": kind, "source": source, "W_mb": W.nbytes / 2**20, "compare": {}}
        for method in [] if args.methods_only else args.methods:
            for warm in (True, False):
                key = f"{method} {'warm' if warm else 'zero'}"
                rec["compare"][key] = compare(problem, method, warm, args.tol, args.repeats, variants)
                c = rec["compare"][key]
                print(f"{path.stem} {key}: " + ", ".join(
                    f"{n} {ms(v['median_s'])} ({v['sweeps']} sw, set {v['working_set']}+{v['joined']}, "
                    f"held {v['held']}, dr {v['dr']:.1e})" for n, v in c.items()), flush=True)
        if args.cycle and source == "half-space" and kind == "gross slip":
            rec["cycle"] = cycle(problem, "uzawa", args.tol, args.cycle, variants)
            print(f"{path.stem} cycle: " + ", ".join(
                f"{n} {ms(v['median_s'])} ({v['sweeps']:.1f} sw, held {v['held']}, dr {v['dr']:.1e})"
                for n, v in rec["cycle"].items()), flush=True)
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
