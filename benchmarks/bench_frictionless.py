"""Frictionless contact solved normal-only against the full-dimension solve, side by side in one process.

With ``mu = 0`` ``local_solvers.solve`` solves the LCP on the normal rows ``W_nn`` alone. This benchmark
times it against the full-dimension path (``local_solvers._solve_full``, what every ``mu = 0`` problem went
through before) on the same inputs:

1. local problems: the FE-condensed FCLIB Hertz problem and W exported from our scenes (``hertz`` at two
   contact mesh sizes, Example 1's block), each method, from ``r = 0``: time, iterations, difference in r;
2. the frictionless ``hertz`` run (force-controlled preload): the whole run with the normal-only path and
   with ``_solve_normal`` replaced by the full-dimension path (monkeypatched), time spent in the local
   solves and summary numbers;
3. optionally (``--before TREE``), a frictionless cyclic run (compiled loop) in a subprocess with the
   package from ``TREE`` (e.g. the main branch) against this tree, both with fresh numba caches and
   timed as the best of three runs after a first one that compiles.

Times are CPU times (``time.process_time``; BLAS and numba single-threaded), which a shared machine
disturbs far less than wall-clock times; each is the best of several.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_frictionless.py [--repeat 5] [--before /work/main]
        [--out benchmarks/results/frictionless]
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

from bench_local_solvers import machine_info  # noqa: E402

from dolfinx_fretting import fclib, local_solvers as ls  # noqa: E402

QUIET = ["output.xdmf=false", "output.plots=false"]
FCLIB_DIR = Path(os.environ.get("DOLFINX_FRETTING_FCLIB", HERE.parent.parent / "shared" / "fclib"))


def best_of(fn, repeat):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t0)
        if best > 1.0:
            break
    return out, best


def full_path(W, q, dim, method, tol, max_iter):
    W, q, mu, dim = ls._check_problem(W, q, 0.0, dim)
    c = ls._Counts()
    r, x, err, _, status = ls._solve_full(W, q, mu, dim, method, tol, max_iter, np.zeros(q.size), False, 1.0, c)
    return r, c.total, status == 1


def scene_problems():
    """(name, W, q, dim) from our scenes: W of the built model, q from a preload."""
    from mpi4py import MPI

    from dolfinx_fretting.scenes import load_scene
    from dolfinx_fretting.simulation import ContactModel

    out = []
    for h in (0.01, 0.005):
        m = ContactModel(load_scene("hertz", QUIET + [f"geometry.contact_mesh_size={h}"]), MPI.COMM_SELF)
        cs = m.contact
        q = np.zeros(cs.nc * cs.dim)
        # An approach that closes about 40 % of the candidates before elastic spreading.
        q[::cs.dim] = cs.gap0 - np.quantile(cs.gap0, 0.4)
        out.append((f"hertz h={h} ({cs.nc} contacts)", m.W, q, cs.dim))
    m = ContactModel(load_scene("stromberg-block", QUIET), MPI.COMM_SELF)
    cs = m.contact
    q = np.zeros(cs.nc * cs.dim)
    q[::cs.dim] = cs.gap0 - 1e-4  # Example 1's preload: every node pressed
    q[1::cs.dim] = 1e-3 * np.linspace(-1, 1, cs.nc)
    out.append((f"stromberg-block ({cs.nc} contacts)", m.W, q, cs.dim))
    return out


def local_section(repeat, tol, max_iter):
    problems = []
    path = FCLIB_DIR / "getfem_hertz2d_frictionless.npz"
    if path.is_file():
        P = fclib.load(path)
        problems.append((f"FCLIB getfem_hertz2d_frictionless ({P.nc} contacts)", P.W, P.q, P.dim))
    problems += scene_problems()
    rows = []
    for name, W, q, dim in problems:
        for method in ls.METHODS:
            res, t_n = best_of(lambda: ls.solve(W, q, 0.0, dim, method=method, tol=tol, max_iter=max_iter), repeat)
            (r_f, its_f, ok_f), t_f = best_of(lambda: full_path(W, q, dim, method, tol, max_iter), repeat)
            dr = float(np.abs(res.r - r_f).max() / max(np.abs(r_f).max(), 1e-300))
            rows.append(dict(problem=name, method=method, normal_s=t_n, normal_its=res.iterations,
                             normal_converged=res.converged, full_s=t_f, full_its=its_f, full_converged=ok_f,
                             speedup=t_f / t_n, r_diff=dr, closed=int(np.count_nonzero(res.r[::dim]))))
            print(f"{name:45s} {method:7s} normal {t_n * 1e3:8.2f} ms ({res.iterations:5d})  full "
                  f"{t_f * 1e3:8.2f} ms ({its_f:5d})  x{t_f / t_n:5.1f}  dr {dr:.1e}", flush=True)
    return rows


def run_section(repeat):
    from dolfinx_fretting.scenes import load_scene
    from dolfinx_fretting.simulation import run_scene

    real_solve, real_normal = ls.solve, ls._solve_normal
    spent = {"t": 0.0, "calls": 0}

    def timed_solve(*a, **k):
        t0 = time.process_time()
        try:
            return real_solve(*a, **k)
        finally:
            spent["t"] += time.process_time() - t0
            spent["calls"] += 1

    def as_full(W, q, dim, method, tol, max_iter, r, rho_factor, counts, rho_err=None):
        mu = np.zeros(q.size // dim)
        return ls._solve_full(W, q, mu, dim, method, tol, max_iter, r, True, rho_factor, counts, rho_err)

    rows = []
    for method in ("uzawa", "auto"):
        ov = QUIET + ["contact.mu=0.0", "loading.tangential_force=0.0", f"solver.local_method={method}"]
        res = {}
        for mode in ("normal-only", "full-dimension"):
            ls._solve_normal = real_normal if mode == "normal-only" else as_full
            ls.solve = timed_solve
            best = (np.inf, np.inf)
            try:
                for _ in range(repeat):
                    spent.update(t=0.0, calls=0)
                    t0 = time.process_time()
                    s = run_scene(load_scene("hertz", ov), tempfile.mkdtemp(), quiet=True)
                    wall = time.process_time() - t0
                    best = (min(best[0], spent["t"]), min(best[1], wall))
            finally:
                ls.solve, ls._solve_normal = real_solve, real_normal
            res[mode] = dict(local_s=best[0], wall_s=best[1], calls=spent["calls"],
                             **{k: s[k] for k in ("normal_force", "max_pressure", "contact_width", "n_slip",
                                                  "local_iterations")}, friction=s["modelled"]["friction"])
        a, b = res["normal-only"], res["full-dimension"]
        both = {f"{m}_{k}": v for m, d in (("normal", a), ("full", b)) for k, v in d.items()}
        rows.append(dict(method=method, **both,
                         local_speedup=b["local_s"] / a["local_s"], wall_speedup=b["wall_s"] / a["wall_s"],
                         max_pressure_diff=abs(a["max_pressure"] - b["max_pressure"]) / b["max_pressure"]))
        print(method, json.dumps(rows[-1]), flush=True)
    return rows


CYCLIC = ("import sys, tempfile, time, json\n"
          "import dolfinx_fretting.cycling as cyc\n"
          "from dolfinx_fretting.scenes import load_scene\n"
          "from dolfinx_fretting.simulation import run_scene\n"
          "inner, spent = cyc.run_increments, [0.0]\n"
          "def timed(*a):\n"
          "    t = time.process_time()\n"
          "    try:\n"
          "        return inner(*a)\n"
          "    finally:\n"
          "        spent[0] += time.process_time() - t\n"
          "cyc.run_increments = timed\n"
          "out = {}\n"
          "for reuse in ('true', 'false'):\n"
          "    best, best_loop = float('inf'), float('inf')\n"
          "    for k in range(4):\n"
          "        spent[0] = 0.0\n"
          "        t = time.process_time()\n"
          "        s = run_scene(load_scene('stromberg-block', ['output.xdmf=false', 'output.plots=false',\n"
          "            'loading.cycles=20', 'output.contact_profiles=false', 'contact.mu=0.0',\n"
          "            'solver.pattern_reuse=' + reuse]), tempfile.mkdtemp(), quiet=True)\n"
          "        if k:\n"
          "            best, best_loop = min(best, time.process_time() - t), min(best_loop, spent[0])\n"
          "    out[reuse] = dict(cpu_s=best, loop_s=best_loop, local_iterations=s['local_iterations'],\n"
          "                      max_wear_depth=s['max_wear_depth'], wear_area=s['wear_area'])\n"
          "print(json.dumps(out))\n")


def tree_commit(tree: str) -> str:
    p = subprocess.run(["git", "-C", tree, "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    return p.stdout.strip() or "unknown commit"


def cyclic_section(before: str):
    out = {}
    for label, tree in (("this tree", str(HERE.parent)), ("before", before)):
        env = dict(os.environ, PYTHONPATH=tree, NUMBA_CACHE_DIR=tempfile.mkdtemp())
        # cwd: not a package tree (``python -c`` puts the cwd before PYTHONPATH on sys.path)
        p = subprocess.run([sys.executable, "-c", CYCLIC], env=env, capture_output=True, text=True, check=True,
                           cwd=tempfile.gettempdir())
        out[label] = json.loads(p.stdout.strip().splitlines()[-1])
        print(label, out[label], flush=True)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("--max-iter", type=int, default=100000)
    ap.add_argument("--before", default=None, help="package tree for the cyclic comparison (e.g. /work/main)")
    ap.add_argument("--out", default=str(HERE / "results" / "frictionless"))
    a = ap.parse_args(argv)
    cmd = "OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_frictionless.py " + shlex.join(
        sys.argv[1:] if argv is None else argv)
    W = np.eye(4)
    t0 = time.process_time()
    for method in ls.METHODS:  # JIT / cache load, excluded
        ls.solve(W, np.array([-1.0, 0.0, 1.0, 0.0]), 0.0, 2, method=method)
        full_path(W, np.array([-1.0, 0.0, 1.0, 0.0]), 2, method, 1e-10, 100)
    jit = time.process_time() - t0
    local = local_section(a.repeat, a.tol, a.max_iter)
    runs = run_section(a.repeat)
    cyc = cyclic_section(a.before) if a.before else None
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out + ".json").write_text(json.dumps(dict(command=cmd, local=local, runs=runs, cyclic=cyc), indent=1))

    L = [f"# Frictionless contact: normal-only LCP vs the full-dimension solve", "", f"Command: `{cmd}`", "",
         *machine_info(), f"- first-call JIT/cache load: {jit:.2f} s (excluded)",
         "- the machine is shared (2 cores, load average ~11 during the run): times are CPU times of the "
         "process (`time.process_time`), best of several; compare ratios more than absolute times", "",
         f"## Local problems (tol {a.tol:g}, from r = 0, best of {a.repeat})", "",
         "| problem | method | normal-only | iterations | full-dimension | iterations | speed-up | max |dr|/max|r| |",
         "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in local:
        flag = "" if r["normal_converged"] and r["full_converged"] else " (not converged)"
        L.append(f"| {r['problem']} | {r['method']} | {r['normal_s'] * 1e3:.2f} ms | {r['normal_its']} | "
                 f"{r['full_s'] * 1e3:.2f} ms | {r['full_its']} | {r['speedup']:.1f}{flag} | {r['r_diff']:.1e} |")
    L += ["", f"## Frictionless `hertz` run (contact.mu=0, tangential_force=0; best of {a.repeat})",
          "", "Full-dimension: `local_solvers._solve_normal` monkeypatched to the full-dimension path, in the same "
          "process.", "",
          "| local_method | local solves | time in local solves: normal-only / full | speed-up | whole run (CPU): "
          "normal-only / full | speed-up | peak pressure, relative difference | iterations normal / full |",
          "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in runs:
        L.append(f"| {r['method']} | {r['normal_calls']} | {r['normal_local_s']:.3f} s / {r['full_local_s']:.3f} s | "
                 f"{r['local_speedup']:.1f} | {r['normal_wall_s']:.2f} s / {r['full_wall_s']:.2f} s | "
                 f"{r['wall_speedup']:.2f} | {r['max_pressure_diff']:.1e} | {r['normal_local_iterations']} / "
                 f"{r['full_local_iterations']} |")
    if runs:
        L += ["", f"Summary `modelled.friction`: \"{runs[0]['normal_friction']}\""]
    if cyc:
        L += ["", "## Frictionless cyclic run, compiled loop (`stromberg-block`, contact.mu=0, 20 cycles)", "",
              f"`this tree` ({tree_commit(str(HERE.parent))}, with uncommitted changes if any) against "
              f"`{a.before}` ({tree_commit(a.before)}) in subprocesses with fresh numba caches, best of 3 runs after a "
              "compiling one. The other tree may differ in more than the normal-only loop (e.g. the error scale: "
              "then the sweep counts differ too).", "",
              "| tree | pattern reuse | CPU time, whole run | CPU time in `run_increments` | local sweeps | "
              "max wear depth | wear area |",
              "| --- | --- | ---: | ---: | ---: | ---: | ---: |"]
        for label, d in cyc.items():
            for reuse, v in d.items():
                L.append(f"| {label} | {reuse} | {v['cpu_s']:.3f} s | {v['loop_s']:.3f} s | {v['local_iterations']} | "
                         f"{v['max_wear_depth']!r} | {v['wear_area']!r} |")
    Path(a.out + ".md").write_text("\n".join(L) + "\n")
    print("\n".join(L))
    return 0


if __name__ == "__main__":
    sys.exit(main())
