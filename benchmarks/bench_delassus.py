"""Delassus benchmark: cost of building W = H K^-1 H^T by each route, against mesh size.

For each mesh the package's own objects are built (``load_scene`` + ``ContactModel``: gmsh half-cylinder
of the ``hertz`` scene at several ``geometry.contact_mesh_size``, optionally a structured rectangle with
every bottom node a contact candidate), then:

* K is factorised ``--repeat`` times (``DelassusOperator.factorize``, symbolic + numeric; the median is
  the unit of time). ``refactorize()`` is not timed: in this version it returns without refactorising
  (``KSP.setUp`` on an already set-up KSP is a no-op), so there is nothing to measure;
* W is built by each route (``columns``, ``block``, ``selected_inverse``): one untimed warm-up build
  whose W is kept for the checks, then ``--repeat`` timed builds, routes interleaved; the median
  ``last_build_time`` is reported **as a ratio to one factorisation**, so that the machine's speed
  cancels out;
* the routes' W are compared (max |W_a - W_b| / max |W_b| over all pairs), and W is checked for
  symmetry (raw asymmetry before the package symmetrises it) and positive definiteness (smallest
  eigenvalue, relative to the largest).

The ``columns`` route is skipped when its time, extrapolated from the last mesh where it ran (time per
column per factor entry), exceeds ``--columns-limit`` seconds.

Collective: every rank makes the same calls; times are the maximum over ranks; rank 0 prints and writes
``OUT.md`` and ``OUT.json``. Usage (from the repository root)::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_delassus.py
    OPENBLAS_NUM_THREADS=1 mpirun -n 2 .venv/bin/python benchmarks/bench_delassus.py \\
        --sizes 0.04 0.02 0.01 0.005 --rect 80 160 --out benchmarks/results/delassus_np2
"""

from __future__ import annotations

import argparse
import datetime
import gc
import json
import os
import platform
import shlex
import subprocess
import sys
import time
from pathlib import Path

from _machine import cpu_model  # benchmarks/ is on sys.path when a script runs

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from mpi4py import MPI  # noqa: E402
from petsc4py import PETSc  # noqa: E402

from dolfinx_fretting.delassus_routes import ROUTES  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import ContactModel  # noqa: E402

COMM = MPI.COMM_WORLD
RANK0 = COMM.rank == 0


def say(*args) -> None:
    if RANK0:
        print(*args, flush=True)


def tmax(t: float) -> float:
    """Wall time of a collective operation: the slowest rank."""
    return float(COMM.allreduce(t, op=MPI.MAX))


# Machine -----------------------------------------------------------------------------------------------
def _mumps_version() -> str:
    for header in ("/usr/include/dmumps_c.h", "/usr/include/mumps/dmumps_c.h"):
        try:
            for line in Path(header).read_text().splitlines():
                if line.startswith("#define MUMPS_VERSION"):
                    return line.split()[-1].strip('"')
        except OSError:
            continue
    try:
        out = subprocess.run(["dpkg-query", "-W", "-f", "${Version}", "libmumps-5.5"], capture_output=True,
                             text=True, timeout=10)
        return out.stdout.strip() or "unknown"
    except Exception:  # noqa: BLE001
        return "unknown"


def machine_info() -> dict:
    import dolfinx
    import scipy

    try:
        blas = os.path.realpath("/usr/lib/x86_64-linux-gnu/libblas.so.3")
    except OSError:
        blas = "unknown"
    return {
        "cpu": cpu_model(),
        "logical_cpus": os.cpu_count(),
        "host": platform.node(),
        "os": f"{platform.system()} {platform.release()}",
        "mpi_ranks": COMM.size,
        "mpi": MPI.Get_library_version().splitlines()[0].split(",")[0].strip(),
        "petsc": ".".join(str(v) for v in PETSc.Sys.getVersion()),
        "mumps": _mumps_version(),
        "dolfinx": dolfinx.__version__,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "blas": blas,
        "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS", "unset"),
        "load_average_start": list(os.getloadavg()),
    }


# One mesh ----------------------------------------------------------------------------------------------
def scene_for(case: dict):
    if case["kind"] == "half_cylinder":
        return load_scene("hertz", [f"geometry.contact_mesh_size={case['h']}", 'output.xdmf=false',
                                    'output.plots=false'])
    n = case["n"]
    data = {
        "name": f"rectangle_{n}",
        "geometry": {"kind": "rectangle", "width": 50.0, "height": 50.0, "nx": n, "ny": n},
        "contact": {"surface": "bottom", "mu": 0.3},
        "loading": {"normal_displacement": 1e-3},
        "output": {"xdmf": False, "plots": False},
    }
    return load_scene(data)


def median(values: list[float]) -> float:
    return float(np.median(values)) if values else float("nan")


def run_case(case: dict, repeat: int, columns_limit: float, col_rate: float | None) -> tuple[dict, float | None]:
    """Measure one mesh. ``col_rate``: seconds per column per factor entry of the last columns run."""
    t0 = time.perf_counter()
    model = ContactModel(scene_for(case), COMM)  # also factorises once and builds W by "auto" (warm-up)
    setup = tmax(time.perf_counter() - t0)
    d = model.problem.operators.delassus
    H = model.contact.H
    m = H.shape[0]
    S = np.unique(H.tocsr().indices).size
    rec: dict = {
        "case": case["label"], "kind": case["kind"], **{k: v for k, v in case.items() if k in ("h", "n")},
        "dofs": model.n_dofs, "contacts": model.contact.nc, "rows_H": m, "dofs_touched": int(S),
        "auto_route": d.method, "model_setup_s": setup,
        "mesh_s": tmax(model.timings["mesh_s"]), "assemble_s": tmax(model.timings["assemble_s"]),
    }

    fact = []
    for _ in range(repeat):
        d.factorize()
        fact.append(tmax(d.last_factorize_time))
    tf = median(fact)
    rec.update(factorize_s=tf, factorize_all_s=fact,
               factor_entries=int(d.stats.get("factor_entries", 0)),
               mumps_memory_mb=int(COMM.allreduce(d.stats.get("mumps_memory_mb", 0), op=MPI.MAX)))

    # Which routes run.
    routes = list(ROUTES)
    est = None
    if col_rate is not None:
        est = col_rate * m * max(rec["factor_entries"], 1)
        rec["columns_estimate_s"] = est
        if est > columns_limit:
            routes.remove("columns")
    W: dict[str, np.ndarray] = {}
    asym: dict[str, float] = {}
    times: dict[str, list[float]] = {r: [] for r in routes}
    errors: dict[str, str] = {}
    for r in routes:  # warm-up build, kept for the checks
        try:
            W[r] = d.build(H, method=r)
            times[r].append(tmax(d.last_build_time))  # not counted in the median unless it is the only one
            asym[r] = float(d.stats.get("asymmetry", np.nan))
        except Exception as exc:  # noqa: BLE001 - the package raises on every rank together
            errors[r] = f"{type(exc).__name__}: {exc}"
    warm = {r: times[r][0] for r in routes if times[r]}
    timed = {r: [] for r in warm}
    W_last: dict[str, np.ndarray] = {}
    for _ in range(repeat):
        for r in warm:
            # A slow route (one build > 10 s) keeps its warm-up timing only.
            if warm[r] > 10.0:
                continue
            W_last[r] = d.build(H, method=r)
            timed[r].append(tmax(d.last_build_time))
    # The same route later in the sequence (after the other routes ran on the same factor) must give the
    # same W: a route leaving MUMPS in a wrong state would show here.
    rec["repeat_rel_diff"] = {r: float(np.abs(W_last[r] - W[r]).max() / max(np.abs(W[r]).max(), 1e-300))
                              for r in W_last}
    build_s = {r: median(timed[r] or [warm[r]]) for r in warm}
    rec["build_s"] = build_s
    rec["build_all_s"] = {r: timed[r] or [warm[r]] for r in warm}
    rec["warmup_build_s"] = warm
    rec["ratio_to_factorize"] = {r: build_s[r] / tf for r in build_s}
    rec["skipped"] = {r: f"estimated {est:.0f} s > {columns_limit:g} s" for r in ROUTES if r not in routes}
    rec["errors"] = errors
    rec["fastest"] = min(build_s, key=build_s.get) if build_s else None

    # Checks (identical W on every rank: compute everywhere, report rank 0's).
    names = list(W)
    diffs = {}
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            diffs[f"{a}/{b}"] = float(np.abs(W[a] - W[b]).max() / max(np.abs(W[b]).max(), 1e-300))
    rec["max_rel_diff"] = diffs
    rec["max_rel_diff_all"] = max([*diffs.values(), *rec["repeat_rel_diff"].values()] or [float("nan")])
    rec["raw_asymmetry"] = asym
    if names:
        ev = np.linalg.eigvalsh(W[names[-1]])
        rec["eig_min"], rec["eig_max"] = float(ev[0]), float(ev[-1])
        rec["eig_min_rel"] = float(ev[0] / ev[-1])
        rec["spd"] = bool(ev[0] > 0)
    new_rate = None
    if "columns" in build_s:
        new_rate = build_s["columns"] / (m * max(rec["factor_entries"], 1))
    model.problem.destroy()
    del model, d, W
    gc.collect()
    return rec, new_rate


# Report ------------------------------------------------------------------------------------------------
def fmt_ratio(rec: dict, r: str) -> str:
    if r in rec["ratio_to_factorize"]:
        return f"{rec['ratio_to_factorize'][r]:.3g}"
    if r in rec["skipped"]:
        return f"skipped (est. {rec.get('columns_estimate_s', float('nan')) / rec['factorize_s']:.0f})"
    if r in rec["errors"]:
        return "**failed**"
    return "–"


def markdown(command: str, info: dict, records: list[dict], args) -> str:
    lines = [f"# Delassus benchmark ({info['mpi_ranks']} MPI rank{'s' if info['mpi_ranks'] > 1 else ''})", "",
             f"Command (from the repository root): `{command}`", "",
             f"- date: {info['date']}",
             f"- machine: {info['cpu']}, {info['logical_cpus']} logical CPUs, {info['os']}; "
             f"load average at start {info['load_average_start'][0]:.2f}, at end {info['load_average_end'][0]:.2f}",
             f"- PETSc {info['petsc']}, MUMPS {info['mumps']}, DOLFINx {info['dolfinx']}, {info['mpi']}, "
             f"numpy {info['numpy']}, BLAS {info['blas']}, OPENBLAS_NUM_THREADS={info['OPENBLAS_NUM_THREADS']}",
             f"- K: MUMPS Cholesky (SYM=1), package defaults; times are the max over ranks, median of "
             f"{args.repeat} (after one warm-up build per route); columns skipped above an estimated "
             f"{args.columns_limit:g} s",
             f"- total wall time of this run: {info['total_s']:.0f} s", "",
             "Build time of W by each route **divided by the time of one factorisation of K** (symbolic + "
             "numeric) on the same mesh; smaller is better. `hertz h=…`: the built-in `hertz` scene "
             "(half-cylinder R = 6 mm, candidates within 0.25 mm) at `geometry.contact_mesh_size = h` mm; "
             "`rect n`: 50x50 mm block, n x n quads, top fixed, every bottom node a candidate.", "",
             "| mesh | dofs | contacts | rows of H | factorise | columns | block | "
             "selected_inverse | fastest | auto | max rel diff | min eig / max eig | raw asymmetry |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---|---|---:|---:|---:|"]
    for rec in records:
        asym = max(rec["raw_asymmetry"].values()) if rec["raw_asymmetry"] else float("nan")
        lines.append(
            f"| {rec['case']} | {rec['dofs']} | {rec['contacts']} | {rec['rows_H']} | "
            f"{rec['factorize_s'] * 1e3:.1f} ms | "
            + " | ".join(fmt_ratio(rec, r) for r in ROUTES)
            + f" | {rec['fastest']} | {rec['auto_route']} | {rec['max_rel_diff_all']:.1e} | "
            f"{rec.get('eig_min_rel', float('nan')):.2e} | {asym:.1e} |")
    lines += ["", "Absolute build times (median, s):", "",
              "| mesh | factor entries | MUMPS MB | columns | block | selected_inverse |",
              "|---|---:|---:|---:|---:|---:|"]
    for rec in records:
        cells = [f"{rec['build_s'][r]:.4g}" if r in rec["build_s"] else "–" for r in ROUTES]
        lines.append(f"| {rec['case']} | {rec['factor_entries']} | {rec['mumps_memory_mb']} | " + " | ".join(cells)
                     + " |")
    failed = [f"- {rec['case']} {r}: {msg}" for rec in records for r, msg in rec["errors"].items()]
    if failed:
        lines += ["", "Failures:", "", *failed]
    lines += ["", "`max rel diff`: max over route pairs of max|W_a - W_b| / max|W_b| (the routes must agree to "
              "~1e-10), and over each route's first and last build (other routes ran in between). `min eig / max eig`: extreme eigenvalues of W (positive: SPD). `raw asymmetry`: "
              "max|W - W^T| / max|W| before the package symmetrises W (worst route). Raw numbers, including "
              "every repeat, are in the .json file next to this one."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=float, nargs="*", default=[0.04, 0.02, 0.01, 0.005, 0.0025],
                    help="geometry.contact_mesh_size (mm) of the hertz half-cylinder")
    ap.add_argument("--rect", type=int, nargs="*", default=[80, 160, 320],
                    help="n of n x n rectangle meshes (every bottom node a candidate); none: --rect")
    ap.add_argument("--repeat", type=int, default=5, help="timed repeats per route (median kept)")
    ap.add_argument("--columns-limit", type=float, default=60.0,
                    help="skip the columns route above this estimated time (s)")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "delassus",
                    help="output stem: writes STEM.md and STEM.json")
    args = ap.parse_args(argv)
    argv_used = sys.argv[1:] if argv is None else argv
    command = ("OPENBLAS_NUM_THREADS=1 " + (f"mpirun -n {COMM.size} " if COMM.size > 1 else "")
               + ".venv/bin/python benchmarks/bench_delassus.py" + "".join(" " + shlex.quote(a) for a in argv_used))

    info = machine_info()
    info["date"] = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
    say(f"# {command}\n# {info}")
    cases = [{"kind": "half_cylinder", "h": h, "label": f"hertz h={h:g}"} for h in args.sizes]
    cases += [{"kind": "rectangle", "n": n, "label": f"rect {n}"} for n in args.rect]
    t_all = time.perf_counter()
    records, rate = [], None
    for case in cases:
        rec, new_rate = run_case(case, args.repeat, args.columns_limit, rate)
        rate = new_rate if new_rate is not None else rate
        records.append(rec)
        say(f"{rec['case']}: dofs {rec['dofs']}, contacts {rec['contacts']}, factorise {rec['factorize_s']:.4f} s, "
            f"build/factorise " + ", ".join(f"{r} {fmt_ratio(rec, r)}" for r in ROUTES)
            + f", max rel diff {rec['max_rel_diff_all']:.1e}, min eig/max {rec.get('eig_min_rel', np.nan):.2e}"
            + (f", errors {rec['errors']}" if rec["errors"] else ""))
    info["total_s"] = tmax(time.perf_counter() - t_all)
    info["load_average_end"] = list(os.getloadavg())

    if RANK0:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        md = args.out.with_suffix(".md")
        md.write_text(markdown(command, info, records, args))
        js = args.out.with_suffix(".json")
        js.write_text(json.dumps({"command": command, "date": info["date"], "machine": info,
                                  "settings": {"repeat": args.repeat, "columns_limit_s": args.columns_limit,
                                               "routes": list(ROUTES)},
                                  "results": records}, indent=1) + "\n")
        print(f"wrote {md} and {js}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
