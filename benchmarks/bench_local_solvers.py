"""Local solver benchmark: Uzawa time and sweeps vs number of contacts, and on the FCLIB problems.

Synthetic problems: an elastic half-plane (plane strain, E = 115 GPa, nu = 0.342) discretised into nc
uniformly loaded elements over [-0.4, 0.4] mm, pressed by a cylinder of radius 6 mm (indentation 4.5 µm)
and shifted tangentially by 0.4 µm with mu = 0.3: an SPD W with normal-tangential coupling and a mix of
open, stick and slip contacts, like the condensed FE problems.

If ``import siconos`` works (Debian's python3-siconos), Siconos NSGS is timed on the same (W, q, mu).

Usage::

    .venv/bin/python benchmarks/bench_local_solvers.py [--sizes 25 50 ...] [--max-iter N] [--skip-fclib]
                                                       [--out FILE]
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

from _machine import cpu_model  # benchmarks/ is on sys.path when a script runs

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from dolfinx_fretting import fclib, local_solvers  # noqa: E402

try:  # optional reference implementation
    import siconos.numerics as sn  # type: ignore
    SICONOS = f"siconos {getattr(sn, '__version__', '') or 'numerics'}"
except Exception as exc:  # noqa: BLE001 - any import failure means "not available"
    sn = None
    SICONOS = f"not available ({type(exc).__name__}: {exc})"


def halfplane_problem(nc: int, half_width: float = 0.4, E: float = 115e3, nu: float = 0.342,
                      radius: float = 6.0, indent: float = 4.5e-3, shift: float = 0.4e-3
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Delassus matrix and free displacement of a cylinder on an elastic half-plane (units mm, N/mm, MPa).

    Influence coefficients of uniform loads over elements of width h (Johnson, Contact Mechanics, ch. 2):
    normal-normal and tangential-tangential ``2(1-nu^2)/(pi E) (ln L_ref - mean ln|x_i - s|)`` with
    ``L_ref = 8 * half_width`` (the half-plane's displacement is defined up to a constant; this one keeps W
    positive definite), normal-tangential ``(1-2nu)(1+nu)/(2E) sgn(x_i - x_j)`` (antisymmetric kernel,
    symmetric W).

    Returns:
        (x nodes, W, q) with contacts ordered (n, t).
    """
    h = 2 * half_width / nc
    xs = -half_width + h * (np.arange(nc) + 0.5)
    d = xs[:, None] - xs[None, :]

    def antiderivative(t):  # of ln|t|
        safe = np.where(t == 0, 1.0, np.abs(t))
        return np.where(t == 0, 0.0, t * np.log(safe) - t)

    mean_log = (antiderivative(d + h / 2) - antiderivative(d - h / 2)) / h
    K = 2 * (1 - nu**2) / (np.pi * E) * (np.log(8 * half_width) - mean_log)
    S = (1 - 2 * nu) * (1 + nu) / (2 * E) * np.sign(d)
    W = np.zeros((2 * nc, 2 * nc))
    W[0::2, 0::2] = K
    W[1::2, 1::2] = K
    W[0::2, 1::2] = S
    W[1::2, 0::2] = S.T
    q = np.empty(2 * nc)
    q[0::2] = xs**2 / (2 * radius) - indent
    q[1::2] = -shift
    return xs, W, q


def time_uzawa(W, q, mu, dim, tol, max_iter, repeat):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = local_solvers.solve(W, q, mu, dim, tol=tol, max_iter=max_iter)
        best = min(best, time.perf_counter() - t0)
        if best > 2.0:  # long runs: one timing is precise enough
            break
    return res, best


def time_siconos(W, q, mu, dim, tol, max_iter):
    """Siconos NSGS on the same problem: (time, iterations, error, info) or None if unavailable."""
    if sn is None:
        return None
    W = W.toarray() if hasattr(W, "toarray") else np.asarray(W)
    mu = np.broadcast_to(np.asarray(mu, dtype=float), (q.size // dim,)).copy()
    try:
        problem = sn.FrictionContactProblem(dim, W, q, mu)
        solver_id = sn.SICONOS_FRICTION_2D_NSGS if dim == 2 else sn.SICONOS_FRICTION_3D_NSGS
        options = sn.SolverOptions(solver_id)
        options.iparam[sn.SICONOS_IPARAM_MAX_ITER] = max_iter
        options.dparam[sn.SICONOS_DPARAM_TOL] = tol
        r, u = np.zeros_like(q), np.zeros_like(q)
        driver = sn.fc2d_driver if dim == 2 else sn.fc3d_driver
        t0 = time.perf_counter()
        info = driver(problem, r, u, options)
        t = time.perf_counter() - t0
        return (t, int(options.iparam[sn.SICONOS_IPARAM_ITER_DONE]),
                float(options.dparam[sn.SICONOS_DPARAM_RESIDU]), info)
    except Exception as exc:  # noqa: BLE001 - report, do not abort the benchmark
        return f"failed: {type(exc).__name__}: {exc}"


def fmt_siconos(s):
    if s is None:
        return "–"
    if isinstance(s, str):
        return s
    t, its, err, info = s
    return f"{t * 1e3:.1f} ms, {its} it, err {err:.1e}{'' if info == 0 else f', info {info}'}"


def machine_info() -> list[str]:
    cpu = cpu_model()
    import numba
    import scipy
    return [f"- date: {datetime.datetime.now().isoformat(timespec='seconds')}",
            f"- machine: {platform.node()}, {platform.system()} {platform.release()}, {cpu}, "
            f"{os.cpu_count()} logical CPUs",
            f"- Python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
            f"numba {numba.__version__}",
            f"- Siconos: {SICONOS}",
            f"- OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}, "
            f"NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'unset')}"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[25, 50, 100, 200, 400, 800],
                    help="numbers of contacts of the synthetic problems")
    ap.add_argument("--tol", type=float, default=1e-10, help="tolerance on the natural-map error")
    ap.add_argument("--max-iter", type=int, default=20000, help="sweep limit")
    ap.add_argument("--repeat", type=int, default=3, help="timings per case (best kept)")
    ap.add_argument("--fclib", type=Path,
                    default=Path(os.environ.get("DOLFINX_FRETTING_FCLIB",
                                                HERE.parent.parent / "shared" / "fclib")),
                    help="folder of FCLIB .npz problems (with index.json)")
    ap.add_argument("--skip-fclib", action="store_true", help="only the synthetic problems")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "local_solvers.md", help="markdown report")
    args = ap.parse_args(argv)
    command = ".venv/bin/python benchmarks/bench_local_solvers.py" + "".join(
        " " + shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv))

    # JIT compilation (cached on disk after the first run) is not part of the timings.
    t0 = time.perf_counter()
    _, W, q = halfplane_problem(4)
    local_solvers.solve(W, q, 0.3, 2)
    local_solvers.solve(np.eye(3), np.array([-1.0, 0.5, 0.2]), 0.3, 3)
    import scipy.sparse as sp
    local_solvers.solve(sp.csr_matrix(W), q, 0.3, 2)
    warmup = time.perf_counter() - t0

    lines = ["# Local solver benchmark", "", f"Command: `{command}`", "", *machine_info(),
             f"- first-call JIT/cache load: {warmup:.2f} s (excluded below)",
             f"- Uzawa: tol {args.tol:g} on the natural-map error, max_iter {args.max_iter}, best of "
             f"{args.repeat} timings", ""]

    lines += ["## Synthetic half-plane problems (2D, mu = 0.3)", "",
              "| nc | open/stick/slip | sweeps | time | time/sweep | error | Siconos NSGS |",
              "|---:|---|---:|---:|---:|---:|---|"]
    for nc in args.sizes:
        _, W, q = halfplane_problem(nc)
        res, t = time_uzawa(W, q, 0.3, 2, args.tol, args.max_iter, args.repeat)
        st = np.bincount(local_solvers.contact_states(res.r, res.x, 0.3, 2), minlength=3)
        sic = time_siconos(W, q, 0.3, 2, args.tol, args.max_iter)
        conv = "" if res.converged else " (not converged)"
        lines.append(f"| {nc} | {st[0]}/{st[1]}/{st[2]} | {res.iterations}{conv} | {t * 1e3:.2f} ms | "
                     f"{t / max(res.iterations, 1) * 1e6:.1f} µs | {res.error:.1e} | {fmt_siconos(sic)} |")
        print(lines[-1], flush=True)

    if not args.skip_fclib and not (args.fclib / "index.json").is_file():
        ap.error(f"--fclib {args.fclib}: no index.json there (use --skip-fclib to run without it)")
    if not args.skip_fclib:
        index = {e["name"]: e for e in json.loads((args.fclib / "index.json").read_text())}
        lines += ["", f"## FCLIB problems ({args.fclib})", "",
                  "dx = |x - x_ref| / max(|x_ref|, |q|). Reference: Siconos 4.4 solver and sweeps from "
                  "index.json (its own error measure, tol 1e-10).", "",
                  "| problem | kind | dim | nc | mu | W | sweeps | time | error | converged | dx | "
                  "reference | Siconos NSGS here |",
                  "|---|---|---:|---:|---:|---|---:|---:|---:|---|---:|---|---|"]
        failures = []
        for path in fclib.list_problems(args.fclib):
            P = fclib.load(path)
            e = index.get(P.name, {})
            repeat = 1 if P.m > 1000 else args.repeat
            res, t = time_uzawa(P.W, P.q, P.mu, P.dim, args.tol, args.max_iter, repeat)
            dx = "–"
            if P.x_ref is not None:
                scale = max(np.linalg.norm(P.x_ref), np.linalg.norm(P.q))
                dx = f"{np.linalg.norm(res.x - P.x_ref) / scale:.1e}"
            ref = (f"{e['reference_solver']}, {e['reference_iterations']} it" if e.get("reference_solver")
                   else "none")
            wkind = f"CSR nnz {P.W.nnz}" if P.is_sparse else "dense"
            sic = time_siconos(P.W, P.q, P.mu, P.dim, args.tol, args.max_iter) if P.m <= 4000 else None
            mu = f"{P.mu.min():g}" if P.mu.min() == P.mu.max() else f"{P.mu.min():g}–{P.mu.max():g}"
            lines.append(f"| {P.name} | {P.kind} | {P.dim} | {P.nc} | {mu} | {wkind} | {res.iterations} | "
                         f"{t * 1e3:.1f} ms | {res.error:.1e} | {'yes' if res.converged else '**no**'} | "
                         f"{dx} | {ref} | {fmt_siconos(sic)} |")
            print(lines[-1], flush=True)
            if not res.converged:
                failures.append(f"- {P.name}: {res.message}")
        lines += ["", "### Not converged", "", *(failures or ["- none"])]

    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
