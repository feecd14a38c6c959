"""The set-up across MPI ranks on the 3D sphere-on-flat: per-rank CPU time, memory and MUMPS's own counts.

The machine this was written on has 2 cores shared by several other jobs, so wall-clock speed-up is not a clean
measurement there. What each rank did is: per step and per rank, the CPU time (``time.process_time``), the
resident memory after the step (``/proc/self/statm``) and the peak so far (``ru_maxrss``), reduced over the ranks
(max and sum); MUMPS's own counts of the distributed factorisation (per rank: INFO(22) MB used, INFO(16) MB
allocated, RINFO(3) flops of the elimination; global: INFOG(21) max MB, INFOG(22) total MB, INFOG(29) factor
entries, RINFOG(3) flops); and W's columns per rank. Wall times (slowest rank) are recorded too, with the load
average around each step.

Model: the two-body sphere on flat of ``tests/support/sphere.py`` (steel ball R = 10 mm on a steel flat,
P = 100 N, half model, candidate window 1.4 a + h) on ``meshes_3d.sphere_on_flat``, at a/h and mesh given as
``A:F`` (``F`` the depth-graded mesh's ``field_cell`` with depth_growth 1.5 and coarsening 2, or ``uniform``:
today's mesh). No ``FrettingProblem`` is made (it would factorise and build W once more): the steps are the
package's own objects, timed one by one:

``mesh``      mesh, space, Dirichlet conditions and the ``Contact`` (H)
``assemble``  K (DOLFINx, distributed by rows)
``factorize`` one MUMPS Cholesky of K distributed over all ranks (``DelassusOperator.factorize``)
``W_shared``  W by ``selected_inverse`` on that distributed factor (every solve shared; the serial default)
``W_owned``   (2+ ranks) W by ``owned``, the package's default under MPI: every rank gathers K, factorises it
              alone (``own factorize``, also reported apart) and computes its own columns, all-gathered
``sweep``     the local solve's inner product, a row sweep over dense W: W v on one rank (what the package does
              today: the local problem is solved on rank 0) against W distributed by rows (each rank W[rows] v,
              then an Allgatherv of the pieces): a measured prototype of a distributed sweep (median of 20)

Usage (from the repository root). One command runs every rank count (each an ``mpirun`` child of this
process) and writes the tables; ``--alternate N`` adds N alternated 1- and 2-rank runs of the first case for the
wall-clock ratio with its spread::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_mpi_scaling.py --ranks 1 2 3 \\
        --cases 4:0.25 6:uniform 8:0.25 12:0.25 --alternate 4 --out benchmarks/results/mpi_scaling

``results/mpi_scaling.md`` joins three such runs (their commands are in it) with ``--render A.json B.json ...``.

A single rank count, under mpirun yourself (what the driver runs)::

    OPENBLAS_NUM_THREADS=1 mpirun -n 2 .venv/bin/python -m mpi4py benchmarks/bench_mpi_scaling.py --worker \\
        --cases 8:0.25 --out /tmp/mpi_scaling_np2.json
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import resource
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from _machine import cpu_model  # benchmarks/ is on sys.path when a script runs

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

STEPS = ("mesh", "assemble", "factorize", "W_shared", "W_owned")


# Measurements on one rank ----------------------------------------------------------------------------------------
def rss_mb() -> float:
    """This process's resident memory now (MB)."""
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def maxrss_mb() -> float:
    """This process's peak resident memory so far (MB; Linux reports ru_maxrss in kB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


class Steps:
    """Per-step CPU time, wall time and memory of every rank, gathered on all ranks."""

    def __init__(self, comm):
        self.comm = comm
        self.records: dict[str, dict] = {}

    def run(self, name: str, work):
        self.comm.barrier()
        load = os.getloadavg()[0]
        cpu0, wall0 = time.process_time(), time.perf_counter()
        result = work()
        cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
        per_rank = self.comm.allgather({"cpu_s": cpu, "wall_s": wall, "rss_mb": rss_mb(), "maxrss_mb": maxrss_mb()})
        self.records[name] = {
            "cpu_s": [r["cpu_s"] for r in per_rank], "wall_s": [r["wall_s"] for r in per_rank],
            "rss_mb": [r["rss_mb"] for r in per_rank], "maxrss_mb": [r["maxrss_mb"] for r in per_rank],
            "load_1min": load}
        return result


# The model (as tests/support/sphere.py's sphere_model, without the FrettingProblem) ------------------------------
def parse_case(text: str) -> tuple[float, float | None]:
    a_over_h, _, field = text.partition(":")
    try:
        value = float(a_over_h)
        field_cell = None if field in ("", "uniform") else float(field)
    except ValueError:
        raise SystemExit(f"--cases: {text!r} is not A:F (a/h and the graded mesh's field_cell, or A:uniform)")
    if value <= 0 or (field_cell is not None and field_cell <= 0):
        raise SystemExit(f"--cases: {text!r}: a/h and field_cell must be > 0")
    return value, field_cell


def mumps_counts(factor, comm) -> dict:
    """MUMPS's counts of the factorisation: per rank (INFO, RINFO) and global (INFOG, RINFOG)."""
    local = {"info22_mb": factor.getMumpsInfo(22), "info16_mb": factor.getMumpsInfo(16),
             "rinfo3_flops": factor.getMumpsRinfo(3)}
    per_rank = comm.allgather(local)
    entries = factor.getMumpsInfog(29)
    return {"per_rank": {k: [r[k] for r in per_rank] for k in local},
            "infog21_max_mb": factor.getMumpsInfog(21), "infog22_total_mb": factor.getMumpsInfog(22),
            "infog29_entries": entries if entries >= 0 else -entries * 1_000_000,
            "rinfog3_flops": factor.getMumpsRinfog(3)}


def run_case(case: str, comm, sweep_repeats: int) -> dict:
    from dolfinx import fem  # noqa: F401  (the worker only: the driver must not initialise MPI)
    import ufl  # noqa: F401
    sys.path.insert(0, str(ROOT / "tests"))
    import dolfinx_fretting as dfr
    from dolfinx_fretting import _dolfinx as dfx
    from dolfinx_fretting import meshes_3d as m3
    from dolfinx_fretting.analytic import hertz_sphere
    from dolfinx_fretting.compliance import DelassusOperator
    from dolfinx_fretting._dolfinx import fem as dfx_fem
    from support.sphere import E, NU, P, R, elasticity

    a_over_h, field_cell = parse_case(case)
    a, _ = hertz_sphere(P, R, E / (1 - NU**2) / 2.0)
    h = a / a_over_h
    graded = {} if field_cell is None else {"depth_growth": 1.5, "coarsening": 2, "field_cell": field_cell}
    steps = Steps(comm)

    def mesh():
        body = m3.sphere_on_flat(comm, R, a, h, extent=9.0, growth=1.5, half=True, flat=True, **graded)
        V = dfx.vector_space(body.mesh, 1)
        clamp = [dfx_fem.dirichletbc(np.zeros(3), dfx_fem.locate_dofs_topological(V, 2, body.facets(name)), V)
                 for name in ("top", "flat_bottom")]
        V1, _ = V.sub(1).collapse()
        sym = np.concatenate([body.facets(n) for n in body.tags if "symmetry" in n])
        bcs = clamp + [dfx_fem.dirichletbc(dfx_fem.Function(V1),
                                           dfx_fem.locate_dofs_topological((V.sub(1), V1), 2, sym), V.sub(1))]
        obstacle = dfr.ElasticBody((body.facet_tags, body.tags["flat_top"]), [0.0, 0.0, 1.0])
        contact = dfr.Contact(V, (body.facet_tags, body.tags["surface"]), obstacle, mu=0.5, bcs=bcs,
                              window=1.4 * a + h)
        return body, V, bcs, contact

    body, V, bcs, contact = steps.run("mesh", mesh)

    def assemble():
        K = dfx_fem.petsc.assemble_matrix(dfx.compiled_form(elasticity(V)), bcs=bcs)
        K.assemble()
        return K

    K = steps.run("assemble", assemble)
    H = contact.H_free
    nc, m = contact.contact_set.nc, H.shape[0]
    rows_start, rows_stop = K.getOwnershipRange()
    mesh_name = "uniform" if field_cell is None else f"graded f={field_cell:g}"
    rec: dict = {"case": case, "a_over_h": a_over_h, "mesh": mesh_name,
                 "ranks": comm.size, "dofs": int(K.getSize()[0]), "contacts": int(nc), "rows_W": int(m),
                 "K_rows_per_rank": comm.allgather(rows_stop - rows_start),
                 "K_nonzeros_per_rank": comm.allgather(int(K.getInfo()["nz_used"])),
                 "W_dense_mb": 8.0 * m * m / 2**20}
    d = DelassusOperator(K, comm, method="selected_inverse", options_prefix="bench_mpi_scaling_")
    steps.run("factorize", d.factorize)
    rec["mumps"] = mumps_counts(d.factor, comm)
    W = steps.run("W_shared", lambda: d.build(H, method="selected_inverse"))
    if comm.size > 1:
        W_owned = steps.run("W_owned", lambda: d.build(H, method="owned"))
        rec["own_factorize_s"] = comm.allgather(float(d.stats.get("own_factorize_time", np.nan)))
        rec["W_owned_columns_per_rank"] = [(m * (r + 1)) // comm.size - (m * r) // comm.size for r in range(comm.size)]
        rec["W_owned_max_rel_diff"] = float(np.abs(W_owned - W).max() / np.abs(W).max())
        own = d._own_factor()  # already made by the build above: its counts, not a new factorisation
        rec["own_mumps_infog22_mb"] = comm.allgather(own.factor.getMumpsInfog(22))
        del W_owned
    rec["sweep"] = sweep(W, comm, sweep_repeats)
    rec["steps"] = steps.records
    rec["maxrss_end_mb"] = comm.allgather(maxrss_mb())
    d.destroy()
    K.destroy()
    del body, V, bcs, contact
    return rec


def sweep(W: np.ndarray, comm, repeats: int) -> dict:
    """One product W v on one rank against W distributed by rows (W[rows] v on each rank + Allgatherv).

    The first is one sweep of the local solve as the package runs it today (on rank 0, the whole W); the second a
    prototype of the sweep with W distributed by rows: its arithmetic and the collective that rejoins the pieces.
    Times: CPU per rank and wall (slowest rank), median of ``repeats`` after one warm-up.
    """
    from mpi4py import MPI  # the worker only (see run_case)

    m = W.shape[0]
    size, rank = comm.size, comm.rank
    bounds = [(m * r) // size for r in range(size + 1)]
    rows = np.ascontiguousarray(W[bounds[rank]:bounds[rank + 1]])
    counts = np.diff(bounds)
    v = np.random.default_rng(0).standard_normal(m)
    y = np.empty(m)

    def timed(work) -> tuple[float, float]:
        cpu, wall = [], []
        for i in range(repeats + 1):
            comm.barrier()
            c0, w0 = time.process_time(), time.perf_counter()
            work()
            if i:
                cpu.append(time.process_time() - c0)
                wall.append(comm.allreduce(time.perf_counter() - w0, op=MPI.MAX))
        return float(np.median(cpu)), float(np.median(wall))

    whole_cpu, whole_wall = timed(lambda: W @ v)
    split_cpu, split_wall = timed(lambda: comm.Allgatherv(rows @ v, [y, counts]))
    gather_cpu, gather_wall = timed(lambda: comm.Allgatherv(np.zeros(counts[rank]), [y, counts]))
    comm.Allgatherv(rows @ v, [y, counts])
    error = float(np.abs(y - W @ v).max() / np.abs(W @ v).max())
    return {"rows_per_rank": counts.tolist(), "whole_cpu_s": comm.allgather(whole_cpu), "whole_wall_s": whole_wall,
            "rows_cpu_s": comm.allgather(split_cpu), "rows_wall_s": split_wall,
            "allgather_cpu_s": comm.allgather(gather_cpu), "allgather_wall_s": gather_wall,
            "rows_rel_error": error, "repeats": repeats}


def worker(args) -> int:
    from mpi4py import MPI  # the worker only (see run_case)

    comm = MPI.COMM_WORLD
    records = []
    for case in args.cases:
        rec = run_case(case, comm, args.sweep_repeats)
        records.append(rec)
        if comm.rank == 0:
            s = rec["steps"]
            parts = ", ".join(f"{k} cpu {max(v['cpu_s']):.2f}/wall {max(v['wall_s']):.2f} s" for k, v in s.items())
            print(f"[np={comm.size}] {case}: {rec['dofs']} dofs, {rec['contacts']} contacts: {parts}; "
                  f"MUMPS total {rec['mumps']['infog22_total_mb']} MB", flush=True)
    if comm.rank == 0:
        Path(args.out).write_text(json.dumps({"ranks": comm.size, "records": records}, indent=1) + "\n")
    return 0


# The driver: one mpirun per rank count, then the tables ----------------------------------------------------------
def launch(ranks: int, cases: list[str], out: Path, sweep_repeats: int) -> dict:
    cmd = ["mpirun", "-n", str(ranks)] + (["--oversubscribe"] if ranks > (os.cpu_count() or 1) else []) + [
        sys.executable, "-m", "mpi4py", str(Path(__file__).resolve()), "--worker", "--cases", *cases,
        "--sweep-repeats", str(sweep_repeats), "--out", str(out)]
    env = dict(os.environ, OPENBLAS_NUM_THREADS=os.environ.get("OPENBLAS_NUM_THREADS", "1"))
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, env=env)
    data = json.loads(out.read_text())
    data["process_wall_s"] = time.perf_counter() - t0
    return data


def setup_wall(rec: dict) -> float:
    """The package's set-up (its route "auto"): factorisation + W by selected inverse serially, by owned under MPI."""
    s = rec["steps"]
    return max(s["factorize"]["wall_s"]) + max(s["W_owned" if rec["ranks"] > 1 else "W_shared"]["wall_s"])


def setup_cpu(rec: dict) -> float:
    s = rec["steps"]
    w = s["W_owned" if rec["ranks"] > 1 else "W_shared"]
    return max(np.add(s["factorize"]["cpu_s"], w["cpu_s"]))


def record_of(runs: dict[int, dict], ranks: int, case: str) -> dict | None:
    """The record of ``case`` at ``ranks`` ranks, or None if that rank count did not run it."""
    return next((r for r in runs.get(ranks, {"records": []})["records"] if r["case"] == case), None)


def fit_power(x, y) -> tuple[float, float]:
    """y = c x^p by least squares in logs: (p, c)."""
    p, logc = np.polyfit(np.log(x), np.log(y), 1)
    return float(p), float(np.exp(logc))


# The target of issue 26: a 3D model of 10^6 dofs and 10^4 contacts (the depth-graded sphere mesh, a/h ~ 57)
TARGET_DOFS, TARGET_CONTACTS = 1_000_000, 10_000
TARGET_RANKS = (1, 2, 4, 8, 16, 32, 64)


def extrapolate(runs: dict[int, dict]) -> list[str]:
    """Memory and time per rank at the target from the measured points: the fits of the 1-rank runs, the
    distributed factorisation's measured efficiency and memory growth at the largest rank count run (held beyond
    it: a lower bound of the memory, an upper bound of the speed), and the sweep's measured bytes per second."""
    one = runs[min(runs)]["records"]
    n, m = TARGET_DOFS, 3 * TARGET_CONTACTS
    beta, c_mb = fit_power([r["dofs"] for r in one], [r["mumps"]["infog22_total_mb"] for r in one])
    phi, c_fl = fit_power([r["dofs"] for r in one], [r["mumps"]["rinfog3_flops"] for r in one])
    rate = float(np.median([r["mumps"]["rinfog3_flops"] / max(r["steps"]["factorize"]["cpu_s"]) for r in one]))
    # one column of W by the selected inverse: a pruned pass over the factor, so per column and factor MB
    per_col_mb = [max(r["steps"]["W_shared"]["cpu_s"]) / r["rows_W"] / r["mumps"]["infog22_total_mb"] for r in one]
    c_col = float(np.median(per_col_mb))
    nz_per_dof = float(np.median([sum(r["K_nonzeros_per_rank"]) / r["dofs"] for r in one]))
    big = max(one, key=lambda r: r["rows_W"])
    sweep_bytes_s = 8.0 * big["rows_W"] ** 2 / max(big["sweep"]["whole_cpu_s"])
    # 2 ranks: the largest count with a core each on the 2-core machine these were measured on
    top = 2 if 2 in runs else min(runs)
    eff, growth, imbalance = 1.0, 1.0, 1.0
    if top > 1:
        pairs = [(a, record_of(runs, top, a["case"])) for a in one if record_of(runs, top, a["case"])]
        eff = float(np.median([max(a["steps"]["factorize"]["cpu_s"]) / (top * max(b["steps"]["factorize"]["cpu_s"]))
                               for a, b in pairs]))
        growth = float(np.median([b["mumps"]["infog22_total_mb"] / a["mumps"]["infog22_total_mb"] for a, b in pairs]))
        imbalance = float(np.median([max(b["mumps"]["per_rank"]["info22_mb"]) * top / b["mumps"]["infog22_total_mb"]
                                     for _, b in pairs]))
        allgather = float(np.median([max(b["sweep"]["allgather_cpu_s"]) for _, b in pairs]))
    else:
        allgather = 0.0
    factor_gb = c_mb * n**beta / 1024
    factor_cpu = c_fl * n**phi / rate
    col_s = c_col * factor_gb * 1024
    W_gb = 8.0 * m * m / 1e9
    K_gb = 12.0 * nz_per_dof * n / 1e9  # AIJ: a value (8 bytes) and a column index (4) per nonzero
    sweep_s = 8.0 * m * m / sweep_bytes_s
    # the other reading of the same points: W's cost in factorisations, fitted against the contacts
    ratio_p, ratio_c = fit_power([r["contacts"] for r in one], [max(r["steps"]["W_shared"]["cpu_s"])
                                                                / max(r["steps"]["factorize"]["cpu_s"]) for r in one])
    W_by_ratio = factor_cpu * ratio_c * TARGET_CONTACTS**ratio_p
    L = ["", f"## Extrapolation to {TARGET_DOFS:.0e} dofs and {TARGET_CONTACTS:.0e} contacts (m = {m} rows of W)", "",
         f"From the fits above and the {top}-rank runs: MUMPS's factor {c_mb:.3g} n^{beta:.2f} MB = {factor_gb:.1f} GB "
         f"and {c_fl:.3g} n^{phi:.2f} = {c_fl * n**phi:.3g} flops at {rate:.3g} flop/s per core (median of the 1-rank "
         f"factorisations) = {factor_cpu:.0f} s of CPU; one column of W by the selected inverse {c_col * 1e6:.1f} us "
         f"per MB of factor (median; {min(per_col_mb) * 1e6:.1f}-{max(per_col_mb) * 1e6:.1f}) = {col_s:.2f} s, W "
         f"{col_s * m:.0f} s on one core (W's cost in factorisations fitted against the contacts instead, "
         f"{ratio_c:.3g} nc^{ratio_p:.2f}, gives {W_by_ratio:.0f} s: the two readings bound the extrapolation); K "
         f"{nz_per_dof:.0f} nonzeros per dof = {K_gb:.2f} GB; dense W {W_gb:.1f} GB a copy; a sweep over the whole W "
         f"at {sweep_bytes_s / 1e9:.1f} GB/s (the largest W measured, {big['W_dense_mb']:.0f} MB) = {sweep_s:.2f} s. "
         f"The distributed factorisation at {top} ranks: efficiency {eff:.2f} (CPU of 1 rank / ({top} x the slowest "
         f"rank's)), MUMPS's total memory x{growth:.2f}, the largest rank {imbalance:.2f} x the mean; held beyond "
         f"{top} ranks (optimistic: both worsen with the rank count).", "",
         "| ranks | factor GB per rank (distributed) | + own whole factor and K (`owned`) "
         "| dense W today (replicated) |"
         " W by rows | factorize CPU s per rank | W `owned` CPU s per rank (own factorisation + its columns) |"
         " sweep today (rank 0) | sweep by rows (+ Allgatherv) |", "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for p in TARGET_RANKS:
        e, g, u = (1.0, 1.0, 1.0) if p == 1 else (eff, growth, imbalance)
        share = factor_gb * g * u / p
        fact = factor_cpu / (p * e)
        owned = factor_cpu + col_s * m / p if p > 1 else col_s * m
        L.append(f"| {p} | {share:.2f} | {factor_gb + K_gb:.1f} | {W_gb:.1f} | {W_gb / p:.2f} | {fact:.0f} | "
                 f"{owned:.0f} | {sweep_s:.2f} s | {sweep_s / p + (allgather if p > 1 else 0):.3f} s |")
    L += ["", "(1 rank: W by the selected inverse on the one factor, no own copy. Times are CPU seconds of this "
          "machine's cores; `sweep by rows` adds the Allgatherv measured at the largest rank count run, "
          f"{allgather * 1e3:.3f} ms, a lower bound of a cluster's.)"]
    return L


def report(runs: dict[int, dict], alternations: list[dict], info: dict, command: str) -> str:
    L = ["# The set-up across MPI ranks (3D sphere on flat): measured per rank", "",
         f"Command (from the repository root): `{command}`", "",
         f"- date: {info['date']}; machine: {info['cpu']}, {info['cpus']} logical CPUs, **shared**: 1-min load "
         f"average {info['load_start']:.1f} at start, {info['load_end']:.1f} at end (per step in the .json); "
         f"{info['stack']}; OPENBLAS_NUM_THREADS={info['openblas']}",
         "- every time is **CPU time per rank** (`time.process_time`, max over the ranks) unless it says wall; "
         "Open MPI's waiting ranks poll, so a rank's CPU time includes its waits in collectives; memory: resident "
         "memory after the step (`/proc/self/statm`), max over the ranks", ""]
    cases = runs[min(runs)]["records"]  # every case runs at the smallest rank count
    L += ["| case | dofs | contacts | rows of W | ranks | factorize CPU | W shared CPU | W owned CPU (own factor wall) "
          "|"
          " MUMPS MB per rank (INFO(22)) | MUMPS total MB | factor flops per rank | RSS MB per rank after W |"
          " K rows per rank |",
          "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for base in cases:
        for ranks, r in ((k, record_of(runs, k, base["case"])) for k in sorted(runs)):
            if r is None:
                continue
            s, mumps = r["steps"], r["mumps"]
            owned = (f"{max(s['W_owned']['cpu_s']):.2f} s ({max(r['own_factorize_s']):.2f} s)"
                     if "W_owned" in s else "–")
            last = s["W_owned" if "W_owned" in s else "W_shared"]
            L.append(f"| {r['case']} ({r['mesh']}) | {r['dofs']} | {r['contacts']} | {r['rows_W']} | {ranks} | "
                     f"{max(s['factorize']['cpu_s']):.2f} s | {max(s['W_shared']['cpu_s']):.2f} s | {owned} | "
                     f"{max(mumps['per_rank']['info22_mb'])} | {mumps['infog22_total_mb']} | "
                     f"{max(mumps['per_rank']['rinfo3_flops']):.3g} | {max(last['rss_mb']):.0f} | "
                     f"{'/'.join(str(n) for n in r['K_rows_per_rank'])} |")
    L += ["", "The set-up as the package does it (route `auto`: factorisation, then W by selected inverse on 1 rank, "
          "by `owned` on more): CPU time of the slowest rank (its factorisation and W), and what that is against "
          "1 rank:",
          "", "| case | dofs | contacts | " + " | ".join(f"{k} rank{'s' if k > 1 else ''}" for k in sorted(runs))
          + " | 1 rank / " + " | 1 rank / ".join(f"{k} ranks" for k in sorted(runs) if k > 1) + " |",
          "|---|---:|---:|" + "---:|" * (2 * len(runs) - 1)]
    for base in cases:
        cpu = [setup_cpu(r) if r else None for r in (record_of(runs, k, base["case"]) for k in sorted(runs))]
        L.append(f"| {base['case']} ({base['mesh']}) | {base['dofs']} | {base['contacts']} | "
                 + " | ".join(f"{c:.2f} s" if c else "–" for c in cpu) + " | "
                 + " | ".join(f"{cpu[0] / c:.2f}" if c else "–" for c in cpu[1:]) + " |")
    L += ["", "Wall times (slowest rank, s; on this load they say little) and the 1-min load average at each step:", "",
          "| case | ranks | mesh | assemble | factorize | W shared | W owned | load |",
          "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for base in cases:
        for ranks, r in ((k, record_of(runs, k, base["case"])) for k in sorted(runs)):
            if r is None:
                continue
            s = r["steps"]
            cells = [f"{max(s[k]['wall_s']):.2f}" if k in s else "–" for k in STEPS]
            L.append(f"| {r['case']} | {ranks} | " + " | ".join(cells) + f" | {s['factorize']['load_1min']:.1f} |")
    L += ["", "The local solve's sweep: one product W v, whole W on one rank (today) against W distributed by rows "
          "(each rank its rows, then Allgatherv): CPU per rank, median of the repeats:", "",
          "| case | rows of W | dense W MB (one copy) | ranks | whole W v | rows W v + Allgatherv (max rank) |"
          " Allgatherv alone | max rel error |", "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for base in cases:
        for ranks, r in ((k, record_of(runs, k, base["case"])) for k in sorted(runs)):
            if r is None:
                continue
            sw = r["sweep"]
            L.append(f"| {r['case']} | {r['rows_W']} | {r['W_dense_mb']:.1f} | {ranks} | "
                     f"{1e3 * max(sw['whole_cpu_s']):.2f} ms | {1e3 * max(sw['rows_cpu_s']):.2f} ms | "
                     f"{1e3 * max(sw['allgather_cpu_s']):.3f} ms | {sw['rows_rel_error']:.1e} |")
    # fits over the cases of the 1-rank run
    one = runs[min(runs)]["records"]
    dofs = [r["dofs"] for r in one]
    flops = [r["mumps"]["rinfog3_flops"] for r in one]
    mb = [r["mumps"]["infog22_total_mb"] for r in one]
    fcpu = [max(r["steps"]["factorize"]["cpu_s"]) for r in one]
    wcpu = [max(r["steps"]["W_shared"]["cpu_s"]) for r in one]
    ncs = [r["contacts"] for r in one]
    if len(one) >= 2:
        L += ["", "Power fits over the cases (1 rank, least squares in logs):", ""]
        for name, x, y, xn in (("factor flops (RINFOG(3))", dofs, flops, "dofs"),
                               ("factor MB (INFOG(22))", dofs, mb, "dofs"),
                               ("factorize CPU s", dofs, fcpu, "dofs"),
                               ("W (selected inverse) CPU s", ncs, wcpu, "contacts"),
                               ("W CPU s / factorize CPU s", ncs, np.divide(wcpu, fcpu), "contacts")):
            p, c = fit_power(x, y)
            L.append(f"- {name} = {c:.3g} x {xn}^{p:.2f}")
    if len(one) >= 2:
        L += extrapolate(runs)
    for case in dict.fromkeys(a["case"] for a in alternations):
        pairs = [a for a in alternations if a["case"] == case]
        ratios = [a["one"] / a["two"] for a in pairs]
        L += ["", f"Wall-clock set-up (factorisation + W by the package's route `auto`, slowest rank), {case}: 1-rank "
              f"and 2-rank runs alternated {len(pairs)} times (each pair's order swapped in turn):", "",
              "| pair | 1 rank wall s | 2 ranks wall s | ratio | 1 rank CPU s | 2 ranks CPU s (slowest rank) | load |",
              "|---:|---:|---:|---:|---:|---:|---:|"]
        for k, a in enumerate(pairs):
            L.append(f"| {k + 1} | {a['one']:.2f} | {a['two']:.2f} | {a['one'] / a['two']:.2f} | {a['one_cpu']:.2f} | "
                     f"{a['two_cpu']:.2f} | {a['load']:.1f} |")
        L.append(f"\nRatio (1 rank / 2 ranks) of the wall time: median {np.median(ratios):.2f}, "
                 f"range {min(ratios):.2f}-{max(ratios):.2f}.")
    return "\n".join(L) + "\n"


def driver(args) -> int:
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix="mpi_scaling_"))  # each child's JSON (all of it goes into --out's)
    load_start = os.getloadavg()[0]
    runs, alternations = {}, []
    for ranks in args.ranks:
        runs[ranks] = launch(ranks, args.cases, tmp / f"np{ranks}.json", args.sweep_repeats)
    for k in range(args.alternate):
        pair, load = {}, os.getloadavg()[0]
        for ranks, key in ((1, "one"), (2, "two")) if k % 2 == 0 else ((2, "two"), (1, "one")):
            data = launch(ranks, args.cases[:1], tmp / f"alt{k}_np{ranks}.json", 1)
            pair[key] = setup_wall(data["records"][0])
            pair[key + "_cpu"] = setup_cpu(data["records"][0])
        alternations.append({"case": args.cases[0], "load": load, **pair})
    import petsc4py  # noqa: F401  (versions only; no MPI initialised: petsc4py.PETSc is not imported)
    info = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"), "cpu": cpu_model(),
            "cpus": os.cpu_count(), "host": platform.node(), "load_start": load_start, "load_end": os.getloadavg()[0],
            "stack": f"petsc4py {petsc4py.__version__}, numpy {np.__version__}, Python {platform.python_version()}",
            "openblas": os.environ.get("OPENBLAS_NUM_THREADS", "unset (set to 1 for the children)")}
    command = "OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_mpi_scaling.py " + shlex.join(sys.argv[1:])
    out.with_suffix(".json").write_text(json.dumps({"command": command, "machine": info, "runs": runs,
                                                    "alternations": alternations}, indent=1) + "\n")
    out.with_suffix(".md").write_text(report(runs, alternations, info, command))
    print("wrote", out.with_suffix(".md"))
    return 0


def render(files: list[Path], out: Path) -> int:
    """The .md of several driver runs (e.g. small cases at 1-3 ranks, larger ones at 1-2): their cases side by side,
    each at the rank counts it ran, and all their alternated runs."""
    datas = [json.loads(f.read_text()) for f in files]
    ranks = sorted(set.union(*(set(int(k) for k in d["runs"]) for d in datas)))
    runs: dict[int, dict] = {k: {"records": []} for k in ranks}
    for d in datas:  # a case measured again at the same rank count (e.g. by an --alternate run): the first kept
        for k in ranks:
            for r in d["runs"].get(str(k), {"records": []})["records"]:
                if record_of(runs, k, r["case"]) is None:
                    runs[k]["records"].append(r)
    info = dict(datas[0]["machine"])
    info["load_end"] = datas[-1]["machine"]["load_end"]
    command = "; ".join([d["command"] for d in datas] + [
        "OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_mpi_scaling.py --render "
        + " ".join(str(f) for f in files) + f" --out {out}"])
    info["date"] = f"{datas[0]['machine']['date']} to {datas[-1]['machine']['date']} (the runs' ends)"
    alternations = [a for d in datas for a in d["alternations"]]
    out.with_suffix(".md").write_text(report(runs, alternations, info, command))
    print("wrote", out.with_suffix(".md"))
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", nargs="+", default=["8:0.25", "12:0.25", "16:0.25"], metavar="A:F",
                    help="a/h and the graded mesh's field_cell (over a), or A:uniform for today's mesh")
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2], help="rank counts (driver)")
    ap.add_argument("--alternate", type=int, default=0, help="alternated 1- and 2-rank runs of the first case")
    ap.add_argument("--sweep-repeats", type=int, default=20)
    ap.add_argument("--worker", action="store_true", help="run under mpirun: measure and write --out (JSON)")
    ap.add_argument("--out", default=str(HERE / "results" / "mpi_scaling"))
    ap.add_argument("--render", nargs="+", type=Path, metavar="FILE.json",
                    help="rewrite --out's .md from these driver .json files (their cases side by side, the first's "
                         "alternations and machine), no run")
    args = ap.parse_args(argv)
    for case in args.cases:
        parse_case(case)  # bad input before any launch
    if any(r < 1 for r in args.ranks) or args.alternate < 0 or args.sweep_repeats < 1:
        raise SystemExit(f"--ranks {args.ranks} must be >= 1, --alternate {args.alternate} >= 0, "
                         f"--sweep-repeats {args.sweep_repeats} >= 1")
    if args.render:
        return render(args.render, Path(args.out))
    return worker(args) if args.worker else driver(args)


if __name__ == "__main__":
    sys.exit(main())
