"""W under MPI: "all ranks share each solve" against "each rank solves for the columns it owns".

Both build W = H K^-1 H^T, identical on every rank, from the same distributed K (the package's own
``ContactModel``); each time below is **factorisation + W**, the slowest rank, because the two ways need
different factorisations:

``shared <route>``
    The package's way: one MUMPS factorisation distributed over all ranks (``DelassusOperator`` on
    COMM_WORLD), then W by ``route`` (``selected_inverse``: entries (K^-1)_SS of the distributed factor;
    ``block``: multiple right-hand sides), every solve shared by all ranks; rank 0 symmetrises and
    broadcasts.
``owned <route>``
    Every rank gathers the whole K (``MatCreateSubMatrices``; timed as ``gather``), factorises it alone
    (MUMPS on COMM_SELF, the ranks in parallel), computes only the columns W[:, J] for its share J of
    the rows of H (a contiguous split), by the selected inverse (entries (K^-1)_{S, S_J}) or by a block
    solve of H_J^T, and the columns are all-gathered.

The Ws of all ways must agree to ~1e-10 relative (checked). Usage (from the repository root)::

    OPENBLAS_NUM_THREADS=1 mpirun -n 2 .venv/bin/python benchmarks/bench_delassus_owned.py \\
        --rect 320x80 160x160 --hertz 0.0025 --out benchmarks/results/delassus_owned_np2
"""

from __future__ import annotations

import argparse
import ctypes
import datetime
import json
import os
import shlex
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from mpi4py import MPI  # noqa: E402
from petsc4py import PETSc  # noqa: E402

from bench_delassus import COMM, RANK0, machine_info, say, tmax  # noqa: E402,F401
from dolfinx_fretting.compliance import DelassusOperator, _petsc_c_api  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import ContactModel  # noqa: E402


def scene_for(case: str):
    kind, _, size = case.partition("=")
    if kind in ("hertz", "cylinder-flat"):
        return load_scene(kind, [f"geometry.contact_mesh_size={size}", "output.xdmf=false", "output.plots=false"])
    nx, ny = (int(v) for v in size.split("x"))
    return load_scene({"name": f"rectangle_{nx}x{ny}",
                       "geometry": {"kind": "rectangle", "width": 50.0, "height": 50.0, "nx": nx, "ny": ny},
                       "contact": {"surface": "bottom", "mu": 0.3}, "loading": {"normal_displacement": 1e-3},
                       "output": {"xdmf": False, "plots": False}})


def gather_K(K: PETSc.Mat) -> PETSc.Mat:
    """The whole K as a sequential matrix on every rank."""
    N = K.getSize()[0]
    iset = PETSc.IS().createStride(N, 0, 1, comm=PETSc.COMM_SELF)
    Kseq = K.createSubMatrices(iset)[0]
    iset.destroy()
    return Kseq


def owned_rows(m: int) -> np.ndarray:
    lo, hi = (m * COMM.rank) // COMM.size, (m * (COMM.rank + 1)) // COMM.size
    return np.arange(lo, hi)


def allgather_columns(Wj: np.ndarray, m: int) -> np.ndarray:
    """Columns W[:, J] of every rank -> W (m, m) on every rank (J contiguous, in rank order)."""
    counts = np.array(COMM.allgather(Wj.shape[1])) * m
    buf = np.empty(int(counts.sum()))
    COMM.Allgatherv(np.ascontiguousarray(Wj.T).ravel(), [buf, counts])
    return buf.reshape(m, m).T.copy()


def selected_inverse_columns(d: DelassusOperator, H: sp.csr_matrix, J: np.ndarray) -> np.ndarray:
    """W[:, J] = H_S (K^-1)_{S, S_J} H_J^T from a sequential factor (MUMPS entries of the inverse)."""
    S = np.unique(H.indices).astype(np.int64)
    HJ = H[J].tocsr()
    SJ = np.unique(HJ.indices).astype(np.int64)
    N = d.K.getSize()[0]
    s, sj = S.size, SJ.size
    indptr = np.zeros(N + 1, dtype=PETSc.IntType)
    indptr[SJ + 1] = s
    indptr = np.cumsum(indptr, dtype=PETSc.IntType)
    indices = np.tile(S.astype(PETSc.IntType), sj)
    Bt = PETSc.Mat().createAIJ(size=(N, N), csr=(indptr, indices, np.zeros(s * sj)), comm=PETSc.COMM_SELF)
    Bt.assemble()
    spRHS = PETSc.Mat().createTranspose(Bt)
    F = d.factor
    ierr = int(_petsc_c_api().MatMumpsGetInverse(ctypes.c_void_p(F.handle), ctypes.c_void_p(spRHS.handle)))
    F.setMumpsIcntl(30, 0)
    if ierr:
        raise RuntimeError(f"MatMumpsGetInverse failed: {ierr}")
    _, _, av = Bt.getValuesCSR()
    inv = av.reshape(sj, s)  # inv[b, a] = (K^-1)[S[a], SJ[b]]
    spRHS.destroy()
    Bt.destroy()
    return H[:, S] @ (HJ[:, SJ] @ inv).T


def block_columns(d: DelassusOperator, H: sp.csr_matrix, J: np.ndarray) -> np.ndarray:
    S = np.unique(H.indices).astype(np.int64)
    Y = d._solve_block(H[J].tocsr(), S)  # (|S|, |J|) on this rank's own factor
    return H[:, S] @ Y


def shared(model: ContactModel, route: str) -> tuple[np.ndarray, dict]:
    d = DelassusOperator(model.problem.operators.K, COMM, method=route, options_prefix="bench_shared_")
    COMM.barrier()
    t0 = time.perf_counter()
    d.factorize()
    t1 = time.perf_counter()
    W = d.build(model.contact.H)
    t2 = time.perf_counter()
    d.destroy()
    return W, {"factorize": tmax(t1 - t0), "W": tmax(t2 - t1), "total": tmax(t2 - t0)}


def owned(model: ContactModel, route: str) -> tuple[np.ndarray, dict]:
    H = sp.csr_matrix(model.contact.H)
    H.eliminate_zeros()
    m = H.shape[0]
    J = owned_rows(m)
    COMM.barrier()
    t0 = time.perf_counter()
    Kseq = gather_K(model.problem.operators.K)
    t1 = time.perf_counter()
    d = DelassusOperator(Kseq, MPI.COMM_SELF, method="block", options_prefix="bench_owned_")
    d.factorize()
    t2 = time.perf_counter()
    Wj = selected_inverse_columns(d, H, J) if route == "selected_inverse" else block_columns(d, H, J)
    W = allgather_columns(np.asarray(Wj), m)
    W = 0.5 * (W + W.T)
    t3 = time.perf_counter()
    d.destroy()
    Kseq.destroy()
    return W, {"gather": tmax(t1 - t0), "factorize": tmax(t2 - t1), "W": tmax(t3 - t2), "total": tmax(t3 - t0)}


WAYS = [("shared", "selected_inverse"), ("shared", "block"), ("owned", "selected_inverse"), ("owned", "block")]


def run_case(case: str, repeat: int) -> dict:
    model = ContactModel(scene_for(case), COMM)
    rec = {"case": case, "dofs": model.n_dofs, "contacts": model.contact.nc, "rows_H": model.contact.H.shape[0]}
    say(f"{case}: {rec['dofs']} dofs, {rec['contacts']} contacts")
    Ws, times = {}, {f"{a} {r}": [] for a, r in WAYS}
    for i in range(repeat + 1):  # the first round is a warm-up
        for a, r in WAYS:
            W, t = (shared if a == "shared" else owned)(model, r)
            if i == 0:
                Ws[f"{a} {r}"] = W
            else:
                times[f"{a} {r}"].append(t)
    ref = Ws["shared selected_inverse"]
    rec["max_rel_diff"] = max(float(np.abs(W - ref).max() / np.abs(ref).max()) for W in Ws.values())
    rec["times"] = times
    rec["median_total_s"] = {k: float(np.median([t["total"] for t in v])) for k, v in times.items()}
    for k, v in times.items():
        parts = ", ".join(f"{p} {np.median([t[p] for t in v]):.3f}" for p in v[0])
        say(f"  {k:24s} {parts}")
    model.problem.destroy()
    return rec


def run_rebuilds(case: str, repeat: int) -> dict:
    """W rebuilt after a numeric refactorisation of the same K (what a Newton loop with the consistent
    tangent does every iteration), by the package's routes ``selected_inverse`` (shared) and ``owned``
    (each rank refreshes and refactorises its own copy): the time of build() after refactorize()."""
    model = ContactModel(scene_for(case), COMM)
    d, H = model.problem.operators.delassus, model.contact.H
    rec = {"case": case, "dofs": model.n_dofs, "contacts": model.contact.nc}
    times: dict[str, list[float]] = {"selected_inverse": [], "owned": []}
    for r in times:  # warm-up: the owned copy is gathered and factorised here
        d.build(H, method=r)
    for _ in range(repeat):
        for r in times:
            d.refactorize()
            COMM.barrier()
            t0 = time.perf_counter()
            d.build(H, method=r)
            times[r].append(tmax(time.perf_counter() - t0))
    rec["rebuild_s"] = times
    rec["median_rebuild_s"] = {r: float(np.median(v)) for r, v in times.items()}
    say(f"{case}: {rec['dofs']} dofs, {rec['contacts']} contacts; W after refactorize, median s: "
        + ", ".join(f"{r} {v:.4f}" for r, v in rec["median_rebuild_s"].items()))
    model.problem.destroy()
    return rec


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rect", nargs="*", default=["320x80"], metavar="NXxNY")
    ap.add_argument("--hertz", type=float, nargs="*", default=[0.0025], metavar="H")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--rebuild", nargs="*", default=[], metavar="KIND=H",
                    help="also time W rebuilt after refactorize (Newton iterations), e.g. cylinder-flat=0.02")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "delassus_owned")
    args = ap.parse_args(argv)
    info = machine_info()
    t0 = time.perf_counter()
    cases = [f"rect={r}" for r in args.rect] + [f"hertz={h}" for h in args.hertz]
    records = [run_case(c, args.repeat) for c in cases]
    rebuilds = [run_rebuilds(c, 5 * args.repeat) for c in args.rebuild]
    info["load_average_end"] = list(os.getloadavg())
    if not RANK0:
        return 0
    cmd = (f"OPENBLAS_NUM_THREADS=1 mpirun -n {COMM.size} .venv/bin/python benchmarks/bench_delassus_owned.py "
           + shlex.join(sys.argv[1:]))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    data = {"command": cmd, "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "machine": info, "wall_s": time.perf_counter() - t0, "cases": records,
            "rebuilds": rebuilds}
    args.out.with_suffix(".json").write_text(json.dumps(data, indent=1) + "\n")
    names = [f"{a} {r}" for a, r in WAYS]
    lines = [f"# W under MPI ({COMM.size} ranks): shared solves vs each rank its own columns", "",
             f"Command (from the repository root): `{cmd}`", "",
             f"- date: {data['date']}; machine: {info['cpu']}, {info['logical_cpus']} logical CPUs, **shared with "
             f"other jobs** (load average {info['load_average_start'][0]:.2f} at start, "
             f"{info['load_average_end'][0]:.2f} at end); PETSc {info['petsc']}, MUMPS {info['mumps']}",
             f"- each time: factorisation + W (+ gathering K for `owned`), slowest rank, median of {args.repeat} "
             "after a warm-up; the ways interleaved so that machine load affects all alike",
             "- `shared`: one MUMPS factorisation distributed over the ranks, every solve shared (the package's "
             "`DelassusOperator`); `owned`: every rank gathers K, factorises it alone and computes the W "
             "columns of its share of the contacts, then all-gather", "",
             "| mesh | dofs | contacts | " + " | ".join(names) + " | fastest | max rel diff |",
             "|---|---:|---:|" + "---:|" * len(names) + "---|---:|"]
    if not records:
        lines = lines[:-3]  # no factorisation + W cases, only rebuilds
    for r in records:
        med = r["median_total_s"]
        best = min(med, key=med.get)
        lines.append(f"| {r['case']} | {r['dofs']} | {r['contacts']} | "
                     + " | ".join(f"{med[n]:.3f} s" for n in names) + f" | {best} | {r['max_rel_diff']:.1e} |")
    lines += ["", "Parts (median s): "] if records else []
    for r in records:
        for n, v in r["times"].items():
            lines.append(f"- {r['case']} {n}: " + ", ".join(f"{p} {np.median([t[p] for t in v]):.3f}" for p in v[0]))
    if rebuilds:
        lines += ["", "W rebuilt after a numeric refactorisation of K (each Newton iteration of an elastic-plastic "
                  f"run), median of {5 * args.repeat}, routes interleaved:", "",
                  "| mesh | dofs | contacts | shared selected_inverse | owned | ratio |", "|---|---:|---:|---:|---:|---:|"]
        for r in rebuilds:
            m = r["median_rebuild_s"]
            lines.append(f"| {r['case']} | {r['dofs']} | {r['contacts']} | {m['selected_inverse']:.4f} s | "
                         f"{m['owned']:.4f} s | {m['selected_inverse'] / m['owned']:.2f} |")
    args.out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("wrote", args.out.with_suffix(".md"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
