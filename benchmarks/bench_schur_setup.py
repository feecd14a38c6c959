"""Set-up of the two-body sphere-flat model (``tests/support/sphere.py``) by W's route: the factorisation of K and
W = H K^-1 H^T by the selected inverse or by the Schur complement of [[K, H^T], [H, 0]] (route ``schur``).

Each (a/h, mesh, route) is built in a process of its own (a clean peak memory), one after the other, the routes of
one size alternated; the parent compares the routes' W at each size (max |W_a - W_b| / max |W_b|). Recorded: wall
and CPU time (this process; MUMPS and BLAS on one thread) of the whole model (mesh, assembly, factorisation, W and
the loads' responses), of the factorisation and of W's build; MUMPS's memory (INFOG(22)) of K's factor and of the
Schur route's own factor; the process's peak resident memory and its resident memory after the set-up; the 1-min load average. Usage (from the repository
root)::

    OPENBLAS_NUM_THREADS=1 nice -n 5 .venv/bin/python benchmarks/bench_schur_setup.py --a-over-h 16 20 \\
        --field-cell 0.25 --routes schur selected_inverse --out benchmarks/results/schur_setup.jsonl

``--field-cell 0`` is today's (uniform) mesh; a record per line is appended to ``--out``; ``--table FILE ...``
prints the records of earlier runs as the markdown table of ``results/schur_setup.md``.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def _resident_after_trim_mb() -> float:
    """Resident memory now (after the set-up: what the cycles start with), once glibc has handed its free heap
    back (malloc_trim): memory the process freed counts as freed, whatever the allocator kept for reuse."""
    ctypes.CDLL("libc.so.6").malloc_trim(0)
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def one_case(a_over_h: float, field_cell: float, route: str, save_W: str) -> dict:
    sys.path.insert(0, str(HERE.parent / "tests"))
    sys.path.insert(0, str(HERE.parent))
    from support.sphere import sphere_model

    from dolfinx_fretting import _dolfinx as dfx

    graded = {"depth_growth": 1.5, "coarsening": 2, "field_cell": field_cell} if field_cell > 0 else {}
    rec: dict = {"a_over_h": a_over_h, "mesh": f"graded f={field_cell:g}" if graded else "uniform", "route": route,
                 "load_start": round(os.getloadavg()[0], 2), "dolfinx": dfx.versions()["dolfinx"]}
    start, cpu_start = time.perf_counter(), time.process_time()
    _, problem, *_ = sphere_model(a_over_h, 9.0, 1.5, flat=True, mu=0.5, delassus_method=route, **graded)
    rec["model_s"], rec["model_cpu_s"] = time.perf_counter() - start, time.process_time() - cpu_start
    d = problem.operators.delassus
    stats = d.stats
    rec.update(dofs=int(problem.n_dofs), contacts=int(problem.contact.nc), rows=int(problem.contact.H_free.shape[0]),
               built_by=stats.get("last_build_route"),
               factorize_s=stats["factorize_time"], factorize_cpu_s=stats["factorize_cpu_time"],
               W_s=stats["last_build_time"], W_cpu_s=stats["last_build_cpu_time"],
               schur_factorize_s=stats.get("schur_factorize_time"), schur_size=stats.get("schur_size"),
               mumps_mb=stats["mumps_memory_mb"], schur_mumps_mb=stats.get("schur_memory_mb"),
               peak_rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
               rss_after_setup_mb=_resident_after_trim_mb(),
               operator_timings={k: round(v, 3) for k, v in problem.operators.timings.items()},  # wall (s)
               load_end=round(os.getloadavg()[0], 2))
    np.save(save_W, problem.operators.W)
    return rec


def table(records: list[dict]) -> str:
    """The records as a markdown table, sorted by mesh, contacts and route."""
    lines = ["| stack | mesh | a/h | dofs | contacts | rows of W | route | factorise CPU (s) | W CPU (s) "
             "| set-up CPU (s) | model CPU (s) | model wall (s) | MUMPS K (MB) | MUMPS Schur (MB) | peak RSS (MB) "
             "| load (1 min) | max rel diff |",
             "|---|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in sorted(records, key=lambda r: (r["dolfinx"], r["mesh"], r["contacts"], r["route"])):
        diff = next((v for k, v in r.items() if k.startswith("max_rel_diff")), None)
        schur_mb = r.get("schur_mumps_mb")
        lines.append(
            f"| {r['dolfinx']} | {r['mesh']} | {r['a_over_h']:g} | {r['dofs']} | {r['contacts']} | {r['rows']} "
            f"| {r['built_by']} | {r['factorize_cpu_s']:.1f} | {r['W_cpu_s']:.1f} "
            f"| {r['factorize_cpu_s'] + r['W_cpu_s']:.1f} | {r['model_cpu_s']:.1f} | {r['model_s']:.0f} "
            f"| {r['mumps_mb']} | {'–' if schur_mb is None else schur_mb} | {r['peak_rss_mb']:.0f} "
            f"| {r['load_start']:.1f}–{r['load_end']:.1f} | {'–' if diff is None else f'{diff:.1e}'} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--a-over-h", type=float, nargs="+", default=[16.0])
    ap.add_argument("--field-cell", type=float, default=0.25, help="graded mesh's field cell (units of a); 0: uniform")
    ap.add_argument("--routes", nargs="+", default=["schur", "selected_inverse"])
    ap.add_argument("--out", type=Path, default=HERE / "results" / "schur_setup.jsonl")
    ap.add_argument("--table", type=Path, nargs="+", help="JSON-lines files of earlier runs: print their table")
    ap.add_argument("--case", nargs=4, metavar=("A_OVER_H", "FIELD_CELL", "ROUTE", "SAVE_W"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.table:
        print(table([json.loads(line) for path in args.table for line in path.read_text().splitlines() if line]))
        return 0
    if args.case:
        a_over_h, field_cell, route, save_W = args.case
        print(json.dumps(one_case(float(a_over_h), float(field_cell), route, save_W)), flush=True)
        return 0
    command = " ".join(["OPENBLAS_NUM_THREADS=" + os.environ.get("OPENBLAS_NUM_THREADS", "unset"),
                        os.path.relpath(sys.executable), "benchmarks/bench_schur_setup.py", *sys.argv[1:]])
    with tempfile.TemporaryDirectory() as tmp:
        for a_over_h in args.a_over_h:
            Ws = {}
            for route in args.routes:
                path = os.path.join(tmp, f"W_{route}.npy")
                done = subprocess.run([sys.executable, __file__, "--case", str(a_over_h), str(args.field_cell),
                                       route, path], capture_output=True, text=True)
                if done.returncode:
                    print(done.stderr[-3000:], file=sys.stderr)
                    return done.returncode
                rec = json.loads(done.stdout.strip().splitlines()[-1])
                Ws[route] = np.load(path)
                others = [r for r in Ws if r != route]
                if others:
                    ref = Ws[others[0]]
                    rec["max_rel_diff_vs_" + others[0]] = float(np.abs(Ws[route] - ref).max() / np.abs(ref).max())
                rec["command"] = command
                print(json.dumps(rec), flush=True)
                with open(args.out, "a") as out:
                    out.write(json.dumps(rec) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
