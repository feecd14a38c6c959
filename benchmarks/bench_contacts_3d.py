"""3D contacts: the local solve's cost and W's build against the number of contacts, on the sphere-flat scene.

Real 3D contact problems from the package itself: the built-in ``sphere-flat`` scene (steel ball R = 10 mm on
a steel flat, P = 100 N, mu = 0.8, gross slip +-20 um; half model, two bodies, structured hexahedra) at several
``geometry.contact_mesh_size`` h, i.e. several numbers of contacts nc (the candidate window stays ~1.5 a, so
nc grows like (a/h)^2 while the dofs grow like (a/h)^3). For each size:

* the size estimate (``dolfinx_fretting.sizes.estimate``) before meshing; a size whose estimated peak (with the
  extra factors the ``owned`` and ``schur`` routes hold) exceeds ``--memory-fraction`` of the available memory is
  skipped, and so is a route that would not fit;
* the model (``ContactModel``: mesh, K, one MUMPS factorisation, W by ``auto`` = selected inverse), timed;
* W = H K^-1 H^T built again by each route of ``dolfinx_fretting.delassus_routes.ROUTES`` (``columns`` skipped when
  nc*3 solves, timed from one solve, would exceed ``--columns-limit``), compared entry by entry with the
  selected inverse's; ``owned`` and ``schur`` include their own factorisation (reported apart) and are freed
  after;
* one solve with the factor (the cost of one product W v done matrix-free: H K^-1 H^T v) against one dense
  product W v;
* two local problems of the scene, rebuilt exactly as the package forms them (``FrettingProblem._q``): the
  preload's last increment (P/2 -> P, force controlled) and a gross-slip increment (the flat moved 10 -> 12 um
  along x, the scene's stroke and increment), each solved by every method of
  ``dolfinx_fretting.local_solvers.METHODS`` warm started (the previous increment's forces, as the package does)
  and from zero; time, sweeps / Newton steps, converged error, and the distance of every answer to the others;
* the structure of W that a replacement would exploit: how the 3x3 blocks W_ij decay with the distance between
  contacts i and j (power-law fit), the numerical rank of well-separated blocks (a hierarchical, H-matrix,
  compression of W at 1e-4 / 1e-6 / 1e-8, with its storage), and a sparse truncation of W to blocks within a
  cut-off distance solved with the sparse local solver (error of the forces and the total force).

The scaling in nc of each cost is fitted (log-log least squares) over the sizes run.

Usage (from the repository root; ``--sizes`` and ``--methods`` give a short form)::

    OPENBLAS_NUM_THREADS=1 nice -n 5 .venv/bin/python benchmarks/bench_contacts_3d.py
    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_contacts_3d.py --sizes 0.0466 0.031 --methods nsgs auto
"""

from __future__ import annotations

import argparse
import datetime
import gc
import json
import os
import platform
import resource
import shlex
import sys
import time
from pathlib import Path

from _machine import cpu_model  # benchmarks/ is on sys.path when a script runs
from bench_solver_suite import run as timed_solve  # noqa: E402

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from mpi4py import MPI  # noqa: E402  (first: the 0.11 wheel needs the MPI library mpi4py loads)
from petsc4py import PETSc  # noqa: E402
import scipy.sparse as sp  # noqa: E402

import dolfinx_fretting  # noqa: E402
from dolfinx_fretting import local_solvers, sizes  # noqa: E402
from dolfinx_fretting.delassus_routes import ROUTES  # noqa: E402
from dolfinx_fretting.problem import Displacement, Force  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import ContactModel  # noqa: E402

COMM = MPI.COMM_WORLD
DIM = 3
# The order the routes run in: the reference (selected inverse) first, the one that may be skipped last.
ROUTE_ORDER = ("selected_inverse", "block", "owned", "schur", "columns")
# The scene's gross-slip path: +-20 um in 40 increments a cycle (triangular) is 2 um an increment; mu P is reached
# at ~7 um, so the increment 10 -> 12 um slides the whole contact.
SLIP_STEP_MM = 0.002
SLIP_STEPS_BEFORE = 5


def log(*args) -> None:
    print(*args, flush=True)


def rss_mb() -> float:
    """Peak resident memory of this process so far (MB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


# Machine ----------------------------------------------------------------------------------------------------
def machine_info() -> dict:
    import dolfinx
    import numba
    import scipy

    cpu = cpu_model()
    available, source = sizes.available_memory()
    return {"cpu": cpu, "logical_cpus": os.cpu_count(), "host": platform.node(),
            "os": f"{platform.system()} {platform.release()}",
            "petsc": ".".join(str(v) for v in PETSc.Sys.getVersion()), "dolfinx": dolfinx.__version__,
            "python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
            "numba": numba.__version__, "package": str(Path(dolfinx_fretting.__file__).parent),
            "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS", "unset"),
            "memory_available_gb": available / 2**30, "memory_source": source,
            "load_average_start": list(os.getloadavg())}


# The scene ----------------------------------------------------------------------------------------------------
def scene_for(h: float, prep_method: str):
    """The built-in sphere-flat scene at contact mesh size h (mm); the preparation's local solves by
    ``prep_method`` (they only make the increments the benchmark then times)."""
    return load_scene("sphere-flat", [f"geometry.contact_mesh_size={h}", "output.xdmf=false",
                                      "output.plots=false", f"solver.local_method={prep_method}"])


def local_problems(model: ContactModel) -> list[dict]:
    """The preload's last increment and a gross-slip increment: (q, warm start, the package's answer).

    The package's own increments are run (``FrettingProblem.solve``, committed); each problem's q is formed
    exactly as the package formed it for the increment's last local solve (``FrettingProblem._q`` at the
    converged obstacle position), and its warm start is the committed forces of the increment before.
    """
    problem = model.problem
    half_load = model.scene.loading.normal_force * model.setup.model_fraction
    state = problem.initial_state()
    out = []

    def record(name: str, before, result) -> None:
        q, _ = problem.operators.q(result.obstacle, result.load_factors, before.positions, before.wear_gap)
        out.append({"name": name, "q": q, "warm": before.forces.copy(), "package_r": result.forces.copy(),
                    "package_error": float(result.error)})

    t0 = time.perf_counter()
    state = problem.commit(state, problem.solve(state, normal=Force(0.5 * half_load)))
    result = problem.solve(state, normal=Force(half_load))
    record("preload P/2 -> P", state, result)
    state = problem.commit(state, result)
    for k in range(1, SLIP_STEPS_BEFORE + 1):
        state = problem.commit(state, problem.solve(state, tangential=(Displacement(k * SLIP_STEP_MM),
                                                                       Displacement(0.0)), in_cycle=True))
    result = problem.solve(state, tangential=(Displacement((SLIP_STEPS_BEFORE + 1) * SLIP_STEP_MM),
                                              Displacement(0.0)), in_cycle=True)
    record(f"gross slip {1e3 * SLIP_STEPS_BEFORE * SLIP_STEP_MM:g} -> "
           f"{1e3 * (SLIP_STEPS_BEFORE + 1) * SLIP_STEP_MM:g} um", state, result)
    out[0]["prepare_s"] = out[1]["prepare_s"] = time.perf_counter() - t0
    return out


# W by each route ----------------------------------------------------------------------------------------------
def one_solve_time(d) -> float:
    """Wall time of one solve K y = b with the factor (median of 3): the cost of one matrix-free product."""
    b = d.K.createVecRight()
    b.setRandom()
    y = b.duplicate()
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        d.solve(b, y)
        times.append(time.perf_counter() - t0)
    b.destroy()
    y.destroy()
    return float(np.median(times))


def build_routes(model: ContactModel, routes: list[str], columns_limit: float, route_limit: float,
                 previous_ratios: dict[str, float], room_bytes: float, factor_bytes: float) -> dict:
    """W by each route, timed, compared with the selected inverse's; extra factors freed after their route.

    A route is skipped when its time, estimated as its ratio to one factorisation of K on the previous size times
    this size's factorisation, exceeds ``route_limit`` (s) (``columns``: nc dim solves of the timed one against
    ``columns_limit``), or when the extra factor it holds (``owned``, ``schur``) would not fit in ``room_bytes``.
    """
    d = model.problem.operators.delassus
    H = model.problem.contact.H_free
    m = H.shape[0]
    rec: dict = {"build_s": {}, "own_factorize_s": {}, "skipped": {}, "errors": {}, "rel_diff": {},
                 "raw_asymmetry": {}}
    t_solve = one_solve_time(d)
    rec["one_solve_s"] = t_solve
    W_ref = None
    for route in [r for r in ROUTE_ORDER if r in routes]:
        if route == "columns" and m * t_solve > columns_limit:
            rec["skipped"][route] = (f"{m} solves x {t_solve:.3g} s = {m * t_solve:.0f} s estimated > "
                                     f"--columns-limit {columns_limit:g} s")
            continue
        if route != "columns" and route in previous_ratios:
            guess = previous_ratios[route] * model.problem.operators.delassus.stats["factorize_time"]
            if guess > route_limit:
                rec["skipped"][route] = (f"estimated {guess:.0f} s ({previous_ratios[route]:.2f} factorisations on "
                                         f"the previous size) > --route-limit {route_limit:g} s")
                continue
        if route in ("owned", "schur") and factor_bytes > room_bytes:
            rec["skipped"][route] = (f"its own factor (~{factor_bytes / 2**30:.1f} GB estimated) does not fit in "
                                     f"the memory left ({room_bytes / 2**30:.1f} GB)")
            continue
        try:
            W = d.build(H, method=route)
        except Exception as exc:  # noqa: BLE001 - report the failure, go on with the other routes
            rec["errors"][route] = f"{type(exc).__name__}: {exc}"
            continue
        rec["build_s"][route] = d.last_build_time
        rec["raw_asymmetry"][route] = float(d.stats.get("asymmetry", np.nan))
        if route == "owned":
            rec["own_factorize_s"][route] = float(d.stats.get("own_factorize_time", np.nan))
            d._drop_own_factor()  # its whole second factor of K: free it before the next route
        if route == "schur":
            rec["own_factorize_s"][route] = float(d.stats.get("schur_factorize_time", np.nan))
            d._schur.destroy()
            d._schur = None
        if W_ref is None:
            W_ref = W
        else:
            rec["rel_diff"][route] = float(np.abs(W - W_ref).max() / np.abs(W_ref).max())
        del W
        gc.collect()
    # The selected inverse once more when it is quick: a second timing (the first build in the model is the warm-up).
    if "selected_inverse" in rec["build_s"] and rec["build_s"]["selected_inverse"] < 5.0:
        d.build(H, method="selected_inverse")
        rec["build_s_repeat_selected_inverse"] = d.last_build_time
    return rec


# Local solves --------------------------------------------------------------------------------------------------
def time_local(W, q, mu, method: str, r0, tol: float, max_iter: int) -> tuple[local_solvers.LocalResult, float]:
    """Best of two timings when a solve is short (< 0.5 s), else one (the solver suite's timing)."""
    return timed_solve(W, q, mu, DIM, method, tol, max_iter, 2, r0=r0)


def local_solves(W: np.ndarray, problems: list[dict], mu: float, methods: list[str], tol: float,
                 caps: dict[str, int]) -> list[dict]:
    rows = []
    for P in problems:
        answers = {}
        for start in ("warm", "zero"):
            for method in methods:
                r0 = P["warm"] if start == "warm" else None
                res, t = time_local(W, P["q"], mu, method, r0, tol, caps[method])
                states = np.bincount(local_solvers.contact_states(res.r, res.x, mu, DIM), minlength=3)
                answers[(start, method)] = res.r
                rows.append({"problem": P["name"], "start": start, "method": method, "time_s": t,
                             "iterations": res.iterations, "sweeps": res.sweeps, "newton_steps": res.newton_steps,
                             "error": res.error, "converged": bool(res.converged), "max_iter": caps[method],
                             "open_stick_slip": states.tolist()})
                log(f"    {P['name']:>24s} {start:>4s} {method:>6s}: {t * 1e3:9.2f} ms, {res.iterations:6d} it "
                    f"({res.sweeps} sw + {res.newton_steps} N), err {res.error:.1e}, o/st/sl {states.tolist()}")
        # Agreement: every answer against the package's own (converged) forces of that increment.
        scale = np.abs(P["package_r"]).max()
        for row in rows:
            if row["problem"] == P["name"]:
                row["dr_vs_package"] = float(np.abs(answers[(row["start"], row["method"])] - P["package_r"]).max()
                                             / scale)
        vals = list(answers.values())
        P["max_pairwise_dr"] = float(max(np.abs(a - b).max() for a in vals for b in vals) / scale)
    return rows


# The structure of W ----------------------------------------------------------------------------------------------
def block_norms(W: np.ndarray) -> np.ndarray:
    """Frobenius norm of each 3x3 block W_ij, shape (nc, nc)."""
    nc = W.shape[0] // DIM
    return np.sqrt((W.reshape(nc, DIM, nc, DIM) ** 2).sum(axis=(1, 3)))


def decay(W: np.ndarray, coords: np.ndarray, h: float) -> dict:
    """How |W_ij| falls with the distance r_ij: medians in bins of r/h, and a power-law fit beyond 2h."""
    B = block_norms(W)
    diag = np.sqrt(np.outer(np.diag(B), np.diag(B)))
    rel = B / diag
    dist = np.linalg.norm(coords[:, None, :] - coords[None, :, :], axis=2)
    iu = np.triu_indices(B.shape[0], 1)
    r, v = dist[iu] / h, rel[iu]
    edges = np.array([0.5, 1.5, 2.5, 4, 6, 8, 12, 16, 24, 32, 48, 64, 96])
    bins = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (r >= lo) & (r < hi)
        if sel.sum() >= 10:
            bins.append({"r_over_h": [float(lo), float(hi)], "pairs": int(sel.sum()),
                         "median_rel": float(np.median(v[sel])), "max_rel": float(v[sel].max())})
    far = r > 2.0
    slope, intercept = np.polyfit(np.log(r[far]), np.log(v[far]), 1)
    # How much of x = W r a far field carries: the row sums of |W_ij| beyond a radius against the whole row's.
    row_total = B.sum(axis=1)
    share = {}
    for c in (3, 6, 12):
        share[str(c)] = float(np.median((B * (dist > c * h)).sum(axis=1) / row_total))
    return {"bins": bins, "slope": float(slope), "prefactor": float(np.exp(intercept)),
            "far_share_of_row_abs_sum": share}


def cluster_tree(coords: np.ndarray, leaf: int) -> list:
    """Binary tree of contact index sets, split at the median of the widest coordinate: [idx, left, right]."""
    def split(idx):
        if idx.size <= leaf:
            return [idx, None, None]
        pts = coords[idx]
        axis = int(np.argmax(pts.max(axis=0) - pts.min(axis=0)))
        order = idx[np.argsort(pts[:, axis], kind="stable")]
        half = order.size // 2
        return [idx, split(order[:half]), split(order[half:])]
    return split(np.arange(coords.shape[0]))


def hmatrix_storage(W: np.ndarray, coords: np.ndarray, tols: tuple[float, ...], leaf: int = 32,
                    eta: float = 1.0) -> dict:
    """Storage of W as an H-matrix (standard admissibility min(diam) <= eta dist, blocks compressed by a
    truncated SVD at each relative tolerance), against dense; the ranks of the admissible blocks."""
    tree = cluster_tree(coords, leaf)

    def box(idx):
        p = coords[idx]
        return p.min(axis=0), p.max(axis=0)

    def diam(b):
        return float(np.linalg.norm(b[1] - b[0]))

    def dist(b1, b2):
        gap = np.maximum(0.0, np.maximum(b1[0] - b2[1], b2[0] - b1[1]))
        return float(np.linalg.norm(gap))

    dense_entries = 0
    lowrank = []   # (rows, cols, singular values) of admissible blocks, 3 rows/cols per contact
    stack = [(tree, tree)]
    while stack:
        s, t = stack.pop()
        bs, bt = box(s[0]), box(t[0])
        if min(diam(bs), diam(bt)) <= eta * dist(bs, bt):
            rows = (s[0][:, None] * DIM + np.arange(DIM)).ravel()
            cols = (t[0][:, None] * DIM + np.arange(DIM)).ravel()
            sv = np.linalg.svd(W[np.ix_(rows, cols)], compute_uv=False)
            lowrank.append((rows.size, cols.size, sv))
        elif s[1] is None or t[1] is None:
            dense_entries += (s[0].size * DIM) * (t[0].size * DIM)
        else:
            stack += [(s[1], t[1]), (s[1], t[2]), (s[2], t[1]), (s[2], t[2])]
    m = W.shape[0]
    out = {"leaf": leaf, "eta": eta, "admissible_blocks": len(lowrank), "dense_entries": int(dense_entries),
           "dense_share": dense_entries / m**2, "by_tol": {}}
    for tol in tols:
        stored = dense_entries
        ranks = []
        for nr, ncol, sv in lowrank:
            k = int(np.count_nonzero(sv > tol * sv[0])) if sv[0] > 0 else 0
            ranks.append(k)
            stored += min(k * (nr + ncol), nr * ncol)
        out["by_tol"][f"{tol:g}"] = {"stored_entries": int(stored), "ratio_to_dense": stored / m**2,
                                    "max_rank": int(max(ranks, default=0)),
                                    "median_rank": float(np.median(ranks)) if ranks else 0.0,
                                    "bytes": 8 * int(stored)}
    return out


def truncation(W: np.ndarray, coords: np.ndarray, h: float, problems: list[dict], mu: float, tol: float,
               cutoffs: tuple[float, ...], max_iter: int) -> list[dict]:
    """W kept only for blocks within ``c h`` (sparse), the gross-slip problem solved from zero by NSGS on it:
    kept share, time, and how far its forces are from the dense W's."""
    nc = coords.shape[0]
    dist = np.linalg.norm(coords[:, None, :] - coords[None, :, :], axis=2)
    P = problems[-1]
    ref = P["package_r"]
    rows = []
    for c in cutoffs:
        keep = np.repeat(np.repeat(dist <= c * h, DIM, axis=0), DIM, axis=1)
        Ws = sp.csc_matrix(np.where(keep, W, 0.0))
        t0 = time.perf_counter()
        res = local_solvers.solve(Ws, P["q"], mu, DIM, method="nsgs", tol=tol, max_iter=max_iter)
        t = time.perf_counter() - t0
        Fn = ref[0::DIM].sum()
        rows.append({"cutoff_over_h": c, "kept_share": Ws.nnz / W.size, "nnz": int(Ws.nnz), "time_s": t,
                     "sweeps": res.iterations, "converged": bool(res.converged), "error": res.error,
                     "dr_vs_dense": float(np.abs(res.r - ref).max() / np.abs(ref).max()),
                     "normal_force_rel_err": float(abs(res.r[0::DIM].sum() - Fn) / Fn)})
        log(f"    truncation {c:g} h: kept {Ws.nnz / W.size:.3f}, {t * 1e3:.1f} ms, {res.iterations} sweeps, "
            f"dr {rows[-1]['dr_vs_dense']:.2e}, normal force {rows[-1]['normal_force_rel_err']:.2e}")
    return rows


# One size --------------------------------------------------------------------------------------------------------
def run_size(h: float, args, caps: dict[str, int], previous_ratios: dict[str, float]) -> dict:
    scene = scene_for(h, args.prep_method)
    est = sizes.estimate(scene)
    available, _ = sizes.available_memory()
    rec: dict = {"h_mm": h, "estimate": {"dofs": est.dofs, "contacts": est.contacts,
                                        "total_bytes": est.total_bytes, "factor_bytes": est.memory.get("factor", 0),
                                        "describe": est.describe()}}
    log(f"h = {h:g} mm: {est.describe()}")
    budget = args.memory_fraction * available
    if est.total_bytes > budget:
        rec["skipped"] = (f"estimated peak {est.total_bytes / 2**30:.1f} GB > {args.memory_fraction:g} x available "
                          f"{available / 2**30:.1f} GB")
        log("  skipped:", rec["skipped"])
        return rec

    t0 = time.perf_counter()
    model = ContactModel(scene, COMM)
    rec["model_s"] = time.perf_counter() - t0
    rec["load_average"] = list(os.getloadavg())
    # The model's own build of W (route auto = selected inverse), without the load responses around it.
    rec["W_setup_build_s"] = model.problem.operators.delassus.last_build_time
    cs = model.contact
    d = model.problem.operators.delassus
    nc, m = cs.nc, cs.nc * DIM
    rec.update(dofs=model.n_dofs, contacts=nc, m=m, W_dense_mb=8.0 * m * m / 2**20,
               mesh_s=model.timings.get("mesh_s"), assemble_s=model.timings.get("assemble_s"),
               factorize_s=d.stats.get("factorize_time"), W_auto_s=model.timings.get("delassus_s"),
               factor_entries=int(d.stats.get("factor_entries", 0)),
               mumps_memory_mb=int(d.stats.get("mumps_memory_mb", 0)), mu=float(model.scene.contact.mu))
    log(f"  model {rec['model_s']:.1f} s: {model.n_dofs} dofs, {nc} contacts, factorise {rec['factorize_s']:.2f} s "
        f"(MUMPS {rec['mumps_memory_mb']} MB), W {rec['W_dense_mb']:.1f} MB")

    # Room for one more factor (owned, schur): what is left once this process's peak so far is counted.
    room = available - rss_mb() * 2**20 - 2 * 8.0 * m * m
    rec["routes"] = build_routes(model, args.routes, args.columns_limit, args.route_limit, previous_ratios, room,
                                 1.2 * est.memory.get("factor", 0))
    # Each route's cost in factorisations of K: what the next size's estimate starts from (kept for a skipped route).
    for route, t in rec["routes"]["build_s"].items():
        previous_ratios[route] = t / rec["factorize_s"]
    log("  W routes: " + ", ".join(f"{r} {t:.3g} s" for r, t in rec["routes"]["build_s"].items())
        + (f"; skipped {list(rec['routes']['skipped'])}" if rec["routes"]["skipped"] else "")
        + f"; max rel diff {max(rec['routes']['rel_diff'].values(), default=float('nan')):.1e}"
        + f"; one solve {rec['routes']['one_solve_s'] * 1e3:.1f} ms")

    W = model.W  # the problem's W: the held directions of the symmetry plane given their diagonal
    v = np.random.default_rng(0).standard_normal(m)
    t0 = time.perf_counter()
    for _ in range(5):
        W @ v
    rec["dense_matvec_s"] = (time.perf_counter() - t0) / 5

    problems = local_problems(model)
    rec["prepare_s"] = problems[0]["prepare_s"]
    mu = rec["mu"]
    rec["local"] = local_solves(W, problems, mu, args.methods, args.tol, caps)
    rec["problems"] = [{"name": P["name"], "package_error": P["package_error"],
                        "max_pairwise_dr": P["max_pairwise_dr"],
                        "loaded_contacts": int(np.count_nonzero(P["package_r"][0::DIM] > 0))} for P in problems]

    coords = cs.coords
    t0 = time.perf_counter()
    rec["decay"] = decay(W, coords, h)
    rec["hmatrix"] = hmatrix_storage(W, coords, (1e-4, 1e-6, 1e-8), leaf=args.leaf)
    rec["truncation"] = truncation(W, coords, h, problems, mu, args.tol, (3.0, 6.0, 12.0), caps["nsgs"])
    rec["structure_s"] = time.perf_counter() - t0
    log(f"  decay slope {rec['decay']['slope']:.2f}; H-matrix storage / dense at 1e-6 "
        f"{rec['hmatrix']['by_tol']['1e-06']['ratio_to_dense']:.3f}")
    rec["peak_rss_mb"] = rss_mb()
    model.problem.destroy()
    del model, W, problems
    gc.collect()
    return rec


def machine_limits(prep_method: str, a_over_h: tuple[float, ...]) -> list[dict]:
    """The size estimate (no mesh built) of the scene on finer meshes: where this machine's memory ends."""
    a = 0.187  # the scene's Hertz radius (mm): only picks the sizes; each estimate reads its own
    available, _ = sizes.available_memory()
    rows = []
    for k in a_over_h:
        h = round(a / k, 5)
        est = sizes.estimate(scene_for(h, prep_method))
        m = est.contacts * DIM
        rows.append({"h_mm": h, "dofs": est.dofs, "contacts": est.contacts, "factor_bytes": est.memory["factor"],
                     "W_bytes": 8 * m * m, "total_bytes": est.total_bytes, "fits": est.total_bytes < available})
    return rows


# Report -------------------------------------------------------------------------------------------------------
def fit(ncs: list[int], values: list[float]) -> float | None:
    """Exponent p of value ~ nc^p (log-log least squares), over at least three sizes."""
    pts = [(n, v) for n, v in zip(ncs, values) if v is not None and v > 0]
    if len(pts) < 3:
        return None
    x, y = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
    return float(np.polyfit(x, y, 1)[0])


def ms(t: float | None) -> str:
    if t is None:
        return "–"
    return f"{t * 1e3:.3g} ms" if t < 1 else f"{t:.3g} s"


def markdown(command: str, info: dict, records: list[dict], args) -> str:
    done = [r for r in records if "contacts" in r]
    L = ["# Local solve and W's build against the number of 3D contacts (sphere-flat)", "",
         f"Command (from the repository root): `{command}`", "",
         f"- date: {info['date']}",
         f"- machine: {info['cpu']}, {info['logical_cpus']} logical CPUs (shared with other jobs), {info['os']}, "
         f"{info['memory_available_gb']:.1f} GB available at start ({info['memory_source']})",
         f"- load average (1, 5, 15 min) at start {', '.join(f'{x:.2f}' for x in info['load_average_start'])}, "
         f"at end {', '.join(f'{x:.2f}' for x in info['load_average_end'])}",
         f"- PETSc {info['petsc']}, DOLFINx {info['dolfinx']}, Python {info['python']}, numpy {info['numpy']}, "
         f"scipy {info['scipy']}, numba {info['numba']}, OPENBLAS_NUM_THREADS={info['OPENBLAS_NUM_THREADS']}",
         f"- package imported from `{info['package']}`",
         f"- local solves: tol {args.tol:g} on the natural-map error; caps uzawa/nsgs {args.max_sweeps} sweeps, "
         f"newton/auto {args.max_newton} iterations; best of 2 timings (one when > 0.5 s)",
         f"- W routes: one timed build each (after the model's own build by the selected inverse); skipped when "
         f"estimated above --route-limit {args.route_limit:g} s (from its ratio to a factorisation on the previous "
         f"size) or, for columns, above --columns-limit {args.columns_limit:g} s (nc 3 solves); H-matrix leaves of "
         f"{args.leaf} contacts",
         f"- total wall time {info['total_s']:.0f} s", "",
         "Scene: built-in `sphere-flat` (steel ball R = 10 mm on a steel flat, P = 100 N, Hertz a = 0.187 mm, "
         "mu = 0.8, two bodies, half model, hexahedra) at `geometry.contact_mesh_size = h`; the candidate window "
         "stays ~1.5 a, so nc ~ (a/h)^2 and dofs ~ (a/h)^3. W of the problem (the symmetry plane's held "
         "directions get their diagonal), m = 3 nc rows.", ""]
    skipped = [r for r in records if "skipped" in r]
    for r in skipped:
        L.append(f"- h = {r['h_mm']:g} mm skipped: {r['skipped']} ({r['estimate']['describe']})")
    if skipped:
        L.append("")

    L += ["## The models and W's build by each route", "",
          "Build times of W (s) by route; `owned` and `schur` include their own factorisation of K (in brackets). "
          "`max diff`: max |W_route - W_selected_inverse| / max |W|.", "",
          "`set-up W`: the model's own build of W at set-up (route `auto` = selected inverse; the first build "
          "on that factor). `one K solve`: the cost of one product W v done matrix-free "
          "(H K^-1 H^T v); `dense W v`: the same product on the dense W.", "",
          "| h (mm) | dofs | contacts | W dense | MUMPS | factorise | set-up W | selected_inverse | block | owned | "
          "schur | columns | max diff | one K solve | dense W v |",
          "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in done:
        R = r["routes"]

        def cell(route):
            if route in R["build_s"]:
                own = R["own_factorize_s"].get(route)
                return f"{R['build_s'][route]:.3g}" + (f" ({own:.3g})" if own is not None else "")
            if route in R["skipped"]:
                return "skip"
            if route in R["errors"]:
                return "**failed**"
            return "–"
        setup_w = r.get("W_setup_build_s", r["W_auto_s"])  # runs before the field existed: the set-up's total
        L.append(f"| {r['h_mm']:g} | {r['dofs']} | {r['contacts']} | {r['W_dense_mb']:.1f} MB | "
                 f"{r['mumps_memory_mb']} MB | {r['factorize_s']:.3g} | {setup_w:.3g} | "
                 + " | ".join(cell(x) for x in ("selected_inverse", "block", "owned", "schur", "columns"))
                 + f" | {max(R['rel_diff'].values(), default=float('nan')):.1e} | {ms(R['one_solve_s'])} | "
                   f"{ms(r['dense_matvec_s'])} |")
    for r in done:
        for route, why in r["routes"]["skipped"].items():
            L.append(f"- h = {r['h_mm']:g}: {route} skipped: {why}")
        for route, why in r["routes"]["errors"].items():
            L.append(f"- h = {r['h_mm']:g}: {route} failed: {why}")
    L.append("")

    L += ["## Local solves", "",
          "Cells: `time, iterations` (uzawa/nsgs: sweeps; newton/auto: `sweeps+Newton steps`); **✗** not "
          "converged within the cap (with the error reached). `warm`: from the previous increment's forces; "
          "`zero`: from r = 0. `agree`: max over all methods and starts of |r_a - r_b| / max |r| on that "
          "problem.", ""]
    methods = args.methods
    for pname in dict.fromkeys(row["problem"] for r in done for row in r["local"]):
        L += [f"### {pname}", "",
              "| contacts | loaded | " + " | ".join(f"{m} warm | {m} zero" for m in methods) + " | agree |",
              "|---:|---:|" + "---:|" * (2 * len(methods)) + "---:|"]
        for r in done:
            rows = {(x["start"], x["method"]): x for x in r["local"] if x["problem"] == pname}
            P = next(p for p in r["problems"] if p["name"] == pname)
            cells = []
            for m in methods:
                for start in ("warm", "zero"):
                    x = rows[(start, m)]
                    its = (str(x["iterations"]) if m in ("uzawa", "nsgs")
                           else f"{x['sweeps']}+{x['newton_steps']}N")
                    c = f"{ms(x['time_s'])}, {its}"
                    if not x["converged"]:
                        c = f"**✗** {c}, err {x['error']:.0e}"
                    cells.append(c)
            L.append(f"| {r['contacts']} | {P['loaded_contacts']} | " + " | ".join(cells)
                     + f" | {P['max_pairwise_dr']:.1e} |")
        L.append("")

    L += ["Time per sweep (uzawa and nsgs, from zero, both problems pooled: total time / total sweeps) against "
          "the dense W's size; one sweep reads W once (O(m^2)). `load`: the 1-min load average when the size "
          "started (2 cores).", "",
          "| contacts | W dense | uzawa per sweep | nsgs per sweep | load |", "|---:|---:|---:|---:|---:|"]
    for r in done:
        cells = []
        for m in ("uzawa", "nsgs"):
            xs = [x for x in r["local"] if x["method"] == m and x["start"] == "zero"]
            sweeps = sum(x["sweeps"] for x in xs)
            cells.append(ms(sum(x["time_s"] for x in xs) / sweeps) if sweeps else "–")
        load = r.get("load_average")
        L.append(f"| {r['contacts']} | {r['W_dense_mb']:.1f} MB | {cells[0]} | {cells[1]} | "
                 f"{'–' if load is None else f'{load[0]:.1f}'} |")
    L.append("")
    ncs = [r["contacts"] for r in done]
    L += ["## Scaling with nc (exponent p of time ~ nc^p, log-log fit over the sizes run)", ""]
    if len(done) >= 3:
        fits = []
        for label, vals in [("factorisation of K", [r["factorize_s"] for r in done]),
                            ("W at set-up (selected inverse)", [r.get("W_setup_build_s", r["W_auto_s"])
                                                                for r in done]),
                            ("W by selected inverse", [r["routes"]["build_s"].get("selected_inverse") for r in done]),
                            ("W by block", [r["routes"]["build_s"].get("block") for r in done]),
                            ("one K solve (matrix-free W v)", [r["routes"]["one_solve_s"] for r in done]),
                            ("dense W v", [r["dense_matvec_s"] for r in done])]:
            p = fit(ncs, vals)
            fits.append(f"| {label} | {'–' if p is None else f'{p:.2f}'} |")
        for pname in dict.fromkeys(row["problem"] for r in done for row in r["local"]):
            for m in methods:
                for start in ("warm", "zero"):
                    vals = []
                    for r in done:
                        x = next(y for y in r["local"] if y["problem"] == pname and y["method"] == m
                                 and y["start"] == start)
                        vals.append(x["time_s"] if x["converged"] else None)
                    p = fit(ncs, vals)
                    fits.append(f"| {m} {start}, {pname} | {'–' if p is None else f'{p:.2f}'} |")
        L += ["| cost | p |", "|---|---:|", *fits, ""]
    else:
        L += ["(fewer than three sizes: no fit)", ""]

    L += ["## The structure of W", "",
          "Decay: |W_ij|_F / sqrt(|W_ii|_F |W_jj|_F) for the 3x3 blocks of contacts i, j at distance r; slope of a "
          "power-law fit over r > 2h (a half-space's compliance decays like 1/r: slope -1). `far share`: the "
          "median over rows of the share of sum_j |W_ij| carried by blocks beyond 3h / 6h / 12h.", "",
          "| contacts | slope | far share > 3h | > 6h | > 12h | H-matrix / dense at 1e-4 | 1e-6 | 1e-8 | "
          "median (max) rank at 1e-6 | dense (near-field) share |",
          "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in done:
        D, Hm = r["decay"], r["hmatrix"]
        bt = Hm["by_tol"]
        L.append(f"| {r['contacts']} | {D['slope']:.2f} | {D['far_share_of_row_abs_sum']['3']:.2f} | "
                 f"{D['far_share_of_row_abs_sum']['6']:.2f} | {D['far_share_of_row_abs_sum']['12']:.2f} | "
                 f"{bt['0.0001']['ratio_to_dense']:.3f} | {bt['1e-06']['ratio_to_dense']:.3f} | "
                 f"{bt['1e-08']['ratio_to_dense']:.3f} | {bt['1e-06']['median_rank']:.0f} "
                 f"({bt['1e-06']['max_rank']}) | {Hm['dense_share']:.3f} |")
    if done:
        big = done[-1]
        L += ["", f"Decay on the largest W ({big['contacts']} contacts), median and max of the relative block norm "
              "by distance:", "", "| r / h | pairs | median | max |", "|---|---:|---:|---:|"]
        for b in big["decay"]["bins"]:
            L.append(f"| {b['r_over_h'][0]:g}-{b['r_over_h'][1]:g} | {b['pairs']} | {b['median_rel']:.2e} | "
                     f"{b['max_rel']:.2e} |")
    L += ["", "Sparse truncation: W kept only for blocks of contacts within c h, the gross-slip problem solved from "
          "zero by NSGS on the sparse W; `dr`: max |r - r_dense| / max |r_dense|; `normal force`: relative error of "
          "the total normal force.", "",
          "| contacts | c | kept | time | sweeps | dr | normal force |", "|---:|---:|---:|---:|---:|---:|---:|"]
    for r in done:
        for t in r["truncation"]:
            L.append(f"| {r['contacts']} | {t['cutoff_over_h']:g} | {t['kept_share']:.3f} | {ms(t['time_s'])} | "
                     f"{t['sweeps']}{'' if t['converged'] else ' ✗'} | {t['dr_vs_dense']:.1e} | "
                     f"{t['normal_force_rel_err']:.1e} |")
    limits = info.get("limits") or []
    if limits:
        L += ["", "## How far this machine goes (the size estimate alone, no model built)", "",
              "`dolfinx_fretting.sizes.estimate` on finer meshes of the same scene: the MUMPS factor of K against "
              f"the dense W (one copy), and the estimated peak against the {info['memory_available_gb']:.1f} GB "
              "available at start.", "",
              "| h (mm) | dofs | contacts | factor | W (one copy) | factor / W | peak | fits |",
              "|---:|---:|---:|---:|---:|---:|---:|---|"]
        for x in limits:
            L.append(f"| {x['h_mm']:g} | {x['dofs']} | {x['contacts']} | {x['factor_bytes'] / 2**30:.2f} GB | "
                     f"{x['W_bytes'] / 2**30:.3f} GB | {x['factor_bytes'] / x['W_bytes']:.0f} | "
                     f"{x['total_bytes'] / 2**30:.1f} GB | {'yes' if x['fits'] else 'no'} |")
    L += ["", "Raw numbers (every route, method, start and the estimate) are in the .json file next to this one.", ""]
    return "\n".join(L)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[0.0466, 0.031, 0.0233, 0.0187, 0.0155, 0.0133],
                    help="geometry.contact_mesh_size values (mm) of the sphere-flat scene")
    ap.add_argument("--methods", nargs="+", default=list(local_solvers.METHODS), choices=local_solvers.METHODS,
                    help="local solver methods")
    ap.add_argument("--routes", nargs="+", default=list(ROUTES), choices=ROUTES, help="routes that build W")
    ap.add_argument("--tol", type=float, default=1e-10, help="natural-map tolerance of the local solves")
    ap.add_argument("--max-sweeps", type=int, default=20000, help="cap of uzawa and nsgs")
    ap.add_argument("--max-newton", type=int, default=2000, help="cap of newton and auto (sweeps + Newton steps)")
    ap.add_argument("--columns-limit", type=float, default=60.0, help="skip the columns route above this (s)")
    ap.add_argument("--route-limit", type=float, default=100.0,
                    help="skip a route (not columns) whose estimated build time exceeds this (s)")
    ap.add_argument("--memory-fraction", type=float, default=0.7,
                    help="skip a size whose estimated peak exceeds this share of the available memory")
    ap.add_argument("--leaf", type=int, default=16, help="contacts per leaf of the H-matrix cluster tree")
    ap.add_argument("--prep-method", default="auto", choices=local_solvers.METHODS,
                    help="local method of the package's own increments that make the problems")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "contacts_3d", help="stem of OUT.md, OUT.json")
    ap.add_argument("--render", type=Path, default=None,
                    help="only rewrite OUT.md from this results .json (its command, machine and numbers)")
    args = ap.parse_args(argv)
    if args.render is not None:
        data = json.loads(args.render.read_text())
        saved = argparse.Namespace(**data["settings"])
        out = args.render.with_suffix(".md")
        out.write_text(markdown(data["command"], data["machine"], data["results"], saved))
        log(f"wrote {out} from {args.render}")
        return 0
    argv_used = sys.argv[1:] if argv is None else argv
    command = ("OPENBLAS_NUM_THREADS=" + os.environ.get("OPENBLAS_NUM_THREADS", "<unset>") + " nice -n 5 "
               ".venv/bin/python benchmarks/bench_contacts_3d.py" + "".join(" " + shlex.quote(a) for a in argv_used))
    caps = {"uzawa": args.max_sweeps, "nsgs": args.max_sweeps, "newton": args.max_newton, "auto": args.max_newton}

    info = machine_info()
    info["date"] = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
    log(f"# {command}\n# {info}")
    # JIT compilation (cached on disk after the first run) is not part of the timings.
    t0 = time.perf_counter()
    for method in local_solvers.METHODS:
        Wt = np.diag([2.0, 1.0, 1.5, 2.0, 1.0, 1.5])
        local_solvers.solve(Wt, np.array([-1.0, 0.5, 0.2, -1.0, 0.1, 0.0]), 0.8, DIM, method=method)
        local_solvers.solve(sp.csc_matrix(Wt), np.array([-1.0, 0.5, 0.2, -1.0, 0.1, 0.0]), 0.8, DIM, method=method)
    info["jit_warmup_s"] = time.perf_counter() - t0

    info["limits"] = machine_limits(args.prep_method, (16, 20, 24, 28, 32, 40))
    t_all = time.perf_counter()
    records = []
    previous_ratios: dict[str, float] = {}
    for h in args.sizes:
        records.append(run_size(h, args, caps, previous_ratios))
        info["load_average_end"] = list(os.getloadavg())
        info["total_s"] = time.perf_counter() - t_all
        # Written after every size: a long run that is stopped keeps what it measured.
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.with_suffix(".json").write_text(json.dumps(
            {"command": command, "date": info["date"], "machine": info, "settings": {
                k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()}, "results": records},
            indent=1, default=float) + "\n")
        args.out.with_suffix(".md").write_text(markdown(command, info, records, args))
    log(f"wrote {args.out.with_suffix('.md')} and {args.out.with_suffix('.json')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
