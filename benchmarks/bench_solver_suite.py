"""Every local solver method on every FCLIB problem and on synthetic half-plane problems, side by side.

Methods: ``uzawa`` (the paper's algorithm), ``nsgs`` (Gauss-Seidel with exact one-contact solves),
``newton`` (safeguarded semismooth Newton on the Alart-Curnier function) and ``auto`` (NSGS, then Newton
when NSGS is slow). All stop on the same natural-map error, ``tol`` (default 1e-10), from ``r = 0``.
Iteration caps (``--max-sweeps`` for uzawa/nsgs, ``--max-newton`` for newton/auto, which count Newton steps
plus NSGS sweeps) keep the whole run within a few minutes; a run that hits its cap is reported as not
converged with the error it reached.

Sections: the FCLIB problems (``$DOLFINX_FRETTING_FCLIB``, default ``<repo>/../shared/fclib``); cold solves
of the half-plane problems of ``bench_local_solvers.py``; and a warm-started sequence (the tangential shift
of the half-plane problem raised in steps, each solve starting from the previous forces), the situation of
the fretting simulation. If ``import siconos`` works, Siconos NSGS is timed on the FCLIB problems.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_solver_suite.py [--sizes 100 400 1600]
        [--max-sweeps 20000] [--max-newton 2000] [--repeat 3] [--skip-fclib] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shlex
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

from bench_local_solvers import fmt_siconos, halfplane_problem, machine_info, sn, time_siconos  # noqa: E402

from dolfinx_fretting import fclib, local_solvers  # noqa: E402

METHODS = ("uzawa", "nsgs", "newton", "auto")


def run(W, q, mu, dim, method, tol, max_iter, repeat, r0=None):
    """Best-of-``repeat`` timing (one run if it takes more than 0.5 s): (result, seconds)."""
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = local_solvers.solve(W, q, mu, dim, method=method, tol=tol, max_iter=max_iter, r0=r0)
        best = min(best, time.perf_counter() - t0)
        if best > 0.5:
            break
    return res, best


def fmt_time(t: float) -> str:
    return f"{t * 1e3:.1f} ms" if t < 1 else f"{t:.2f} s"


def cell(rec: dict, ref: dict | None) -> str:
    """``its (sweeps/steps), time, ×ratio`` with the error when not converged."""
    its = str(rec["iterations"])
    if rec["method"] in ("newton", "auto"):
        its += f" ({rec['sweeps']}+{rec['newton_steps']}N)"
    out = f"{its}, {fmt_time(rec['time_s'])}"
    if ref is not None and rec["method"] != "uzawa":
        out += f", ×{rec['time_s'] / ref['time_s']:.2g}"
    if not rec["converged"]:
        out = f"**✗** {out}, err {rec['error']:.0e}"
    return out


def table(rows: list[list[dict]], label: str, extra_cols=()) -> list[str]:
    """One row per problem: ``label``, the extra columns (functions of the records by method), the methods."""
    head = "| " + " | ".join([label, *[c for c, _ in extra_cols], *METHODS]) + " |"
    sep = "|" + "---|" * (1 + len(extra_cols) + len(METHODS))
    lines = [head, sep]
    for recs in rows:
        by = {r["method"]: r for r in recs}
        cols = [recs[0]["problem"], *[f(by) for _, f in extra_cols],
                *[cell(by[m], by["uzawa"]) for m in METHODS]]
        lines.append("| " + " | ".join(cols) + " |")
    return lines


def summary(rows: list[list[dict]]) -> list[str]:
    """Converged counts, geometric-mean time ratio vs uzawa where both converged, total time."""
    lines = ["| method | converged | newly converged (uzawa did not) | geo-mean time / uzawa (both conv.) | "
             "total time |", "|---|---:|---|---:|---:|"]
    for m in METHODS:
        conv = new = 0
        logs, total, newly = [], 0.0, []
        for recs in rows:
            by = {r["method"]: r for r in recs}
            rec, ref = by[m], by["uzawa"]
            conv += rec["converged"]
            total += rec["time_s"]
            if rec["converged"] and not ref["converged"]:
                new += 1
                newly.append(rec["problem"])
            if rec["converged"] and ref["converged"] and ref["time_s"] > 0:
                logs.append(math.log(rec["time_s"] / ref["time_s"]))
        gm = f"{math.exp(np.mean(logs)):.2g}" if logs and m != "uzawa" else "1"
        lines.append(f"| {m} | {conv}/{len(rows)} | {', '.join(newly) or '–'} | {gm} | {fmt_time(total)} |")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[100, 400, 1600],
                    help="numbers of contacts of the synthetic half-plane problems")
    ap.add_argument("--tol", type=float, default=1e-10, help="tolerance on the natural-map error")
    ap.add_argument("--max-sweeps", type=int, default=20000, help="iteration cap of uzawa and nsgs")
    ap.add_argument("--max-newton", type=int, default=2000,
                    help="iteration cap of newton and auto (Newton steps + NSGS sweeps)")
    ap.add_argument("--repeat", type=int, default=3, help="timings per case, best kept (one if > 0.5 s)")
    ap.add_argument("--warm-nc", type=int, default=400, help="contacts of the warm-started sequence")
    ap.add_argument("--warm-steps", type=int, default=20, help="steps of the warm-started sequence")
    ap.add_argument("--fclib", type=Path,
                    default=Path(os.environ.get("DOLFINX_FRETTING_FCLIB",
                                                HERE.parent.parent / "shared" / "fclib")),
                    help="folder of FCLIB .npz problems (with index.json)")
    ap.add_argument("--skip-fclib", action="store_true", help="only the synthetic problems")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "solver_suite.md", help="markdown report "
                    "(the JSON records go next to it, same name with .json)")
    args = ap.parse_args(argv)
    command = ("OPENBLAS_NUM_THREADS=" + os.environ.get("OPENBLAS_NUM_THREADS", "<unset>") + " "
               ".venv/bin/python benchmarks/bench_solver_suite.py" + "".join(
                   " " + shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv)))
    cap = {"uzawa": args.max_sweeps, "nsgs": args.max_sweeps, "newton": args.max_newton,
           "auto": args.max_newton}
    t_start = time.perf_counter()

    # JIT compilation (cached on disk after the first run) is not part of the timings.
    t0 = time.perf_counter()
    import scipy.sparse as sp
    for m in METHODS:
        _, W, q = halfplane_problem(4)
        local_solvers.solve(W, q, 0.3, 2, method=m)
        local_solvers.solve(sp.csr_matrix(W), q, 0.3, 2, method=m)
        local_solvers.solve(np.diag([2.0, 1.0, 1.5]), np.array([-1.0, 0.5, 0.2]), 0.3, 3, method=m)
    warmup = time.perf_counter() - t0

    records: list[dict] = []

    def record(section, name, kind, dim, nc, method, res, t, dx=None, extra=None):
        rec = dict(section=section, problem=name, kind=kind, dim=dim, nc=nc, method=method,
                   iterations=res.iterations, sweeps=res.sweeps, newton_steps=res.newton_steps,
                   error=res.error, converged=res.converged, time_s=t, dx=dx, max_iter=cap[method],
                   message=res.message, **(extra or {}))
        records.append(rec)
        return rec

    lines = ["# Local solver suite: uzawa, nsgs, newton, auto", "", f"Command: `{command}`", "",
             *machine_info(), f"- first-call JIT/cache load: {warmup:.2f} s (excluded below)",
             f"- tol {args.tol:g} on the natural-map error (same measure for every method), start r = 0; "
             f"caps: uzawa/nsgs {args.max_sweeps} sweeps, newton/auto {args.max_newton} iterations "
             "(Newton steps + "
             f"NSGS sweeps); best of {args.repeat} timings (one when a run takes > 0.5 s)", "",
             "Cells: `iterations (NSGS sweeps + Newton steps), time, ×time ratio to uzawa`; **✗** = not "
             "converged within the cap, with the error reached.", ""]

    # ---- FCLIB -----------------------------------------------------------------------------------------
    fc_rows: list[list[dict]] = []
    sic_notes = []
    if not args.skip_fclib:
        if not (args.fclib / "index.json").is_file():
            ap.error(f"--fclib {args.fclib}: no index.json there (use --skip-fclib to run without it)")
        for path in fclib.list_problems(args.fclib):
            P = fclib.load(path)
            recs = []
            for m in METHODS:
                res, t = run(P.W, P.q, P.mu, P.dim, m, args.tol, cap[m], 1 if P.m > 1000 else args.repeat)
                dx = None
                if P.x_ref is not None:
                    dx = float(np.linalg.norm(res.x - P.x_ref) / max(np.linalg.norm(P.x_ref),
                                                                      np.linalg.norm(P.q)))
                recs.append(record("fclib", P.name, P.kind, P.dim, P.nc, m, res, t, dx))
            fc_rows.append(recs)
            line = table([recs], "problem")[-1]
            print(line, flush=True)
            if sn is not None and P.m <= 4000:
                sic = time_siconos(P.W, P.q, P.mu, P.dim, args.tol, args.max_sweeps)
                sic_notes.append(f"| {P.name} | {fmt_siconos(sic)} |")

        lines += [f"## FCLIB problems ({args.fclib})", "", *summary(fc_rows), "",
                  "dx = |x - x_ref| / max(|x_ref|, |q|) against the Siconos reference where there is one "
                  "(OneObject-i1028-138 has several solutions; rank-deficient multibody W amplify the "
                  "residual in x).", ""]
        extra = [("kind", lambda by: by["auto"]["kind"]), ("dim", lambda by: str(by["auto"]["dim"])),
                 ("nc", lambda by: str(by["auto"]["nc"])),
                 ("dx (auto)", lambda by: "–" if by["auto"]["dx"] is None else f"{by['auto']['dx']:.0e}")]
        lines += table(fc_rows, "problem", extra) + [""]
        if sn is not None:
            lines += ["### Siconos NSGS on the same problems", "", "| problem | Siconos NSGS |", "|---|---|",
                      *sic_notes, ""]
        else:
            lines += ["Siconos column omitted: `import siconos` fails here (not installed).", ""]

    # ---- synthetic half-plane, cold -------------------------------------------------------------------
    hp_rows = []
    for nc in args.sizes:
        _, W, q = halfplane_problem(nc)
        recs = []
        for m in METHODS:
            res, t = run(W, q, 0.3, 2, m, args.tol, cap[m], args.repeat)
            st = np.bincount(local_solvers.contact_states(res.r, res.x, 0.3, 2), minlength=3)
            recs.append(record("halfplane", f"half-plane nc={nc}", "synthetic", 2, nc, m, res, t,
                               extra=dict(states=st.tolist())))
        hp_rows.append(recs)
        print(table([recs], "problem")[-1], flush=True)
    lines += ["## Synthetic half-plane problems (2D, mu = 0.3, cold start)", "",
              "Cylinder R = 6 mm on an elastic half-plane, indentation 4.5 µm, tangential shift 0.4 µm "
              "(`bench_local_solvers.halfplane_problem`): SPD W with n-t coupling, open/stick/slip mix.", "",
              *table(hp_rows, "problem",
                     [("open/stick/slip (auto)", lambda by: "/".join(map(str, by["auto"]["states"])))]),
              ""]

    # ---- warm-started sequence ------------------------------------------------------------------------
    nc = args.warm_nc
    _, W, q0 = halfplane_problem(nc, shift=0.0)
    shifts = np.linspace(0.0, 0.6e-3, args.warm_steps + 1)[1:]
    seq = []
    for m in METHODS:
        r = None
        its = sweeps = steps = 0
        t_tot = 0.0
        ok = True
        for s in shifts:
            q = q0.copy()
            q[1::2] = -s
            t0 = time.perf_counter()
            res = local_solvers.solve(W, q, 0.3, 2, method=m, tol=args.tol, max_iter=cap[m], r0=r)
            t_tot += time.perf_counter() - t0
            ok &= res.converged
            its += res.iterations
            sweeps += res.sweeps
            steps += res.newton_steps
            r = res.r
        seq.append(dict(method=m, iterations=its, sweeps=sweeps, newton_steps=steps, time_s=t_tot,
                        converged=ok))
        records.append(dict(section="warm-sequence", problem=f"half-plane nc={nc}, {len(shifts)} shifts",
                            **seq[-1]))
        print(seq[-1], flush=True)
    uz = seq[0]
    lines += [f"## Warm-started sequence (half-plane nc = {nc}, {len(shifts)} tangential shifts up to "
              "0.6 µm)", "", "Each solve starts from the previous forces, as in the fretting simulation.",
              "",
              "| method | all converged | iterations (sweeps + Newton steps) | time | time / uzawa |",
              "|---|---|---:|---:|---:|"]
    for s in seq:
        lines.append(f"| {s['method']} | {'yes' if s['converged'] else '**no**'} | {s['iterations']} "
                     f"({s['sweeps']} + {s['newton_steps']}) | {fmt_time(s['time_s'])} | "
                     f"{s['time_s'] / uz['time_s']:.2g} |")

    # ---- NSGS relaxation --------------------------------------------------------------------------------
    relax = [0.6, 0.8, 1.0, 1.2, 1.4]
    cases = [(f"half-plane nc={n}", *halfplane_problem(n)[1:], np.full(n, 0.3), 2) for n in (100, 400)]
    if not args.skip_fclib:
        for name in ("getfem_hertz2d_frictionless", "getfem_hertz2d_mu0.9", "FrictionContactProblem00727",
                     "Spheres-i099-356-679", "Box_Stacks-i0122-82-5", "KaplasTower-i1061-4"):
            if (args.fclib / f"{name}.npz").is_file():
                P = fclib.load(args.fclib / f"{name}.npz")
                cases.append((name, P.W, P.q, P.mu, P.dim))
    lines += ["", "## NSGS relaxation (`method=\"nsgs\", rho=omega`): sweeps to tol, cap "
              f"{args.max_sweeps}", "", "| problem | " + " | ".join(f"omega = {w:g}" for w in relax) + " |",
              "|---|" + "---:|" * len(relax)]
    for name, W, q, mu, dim in cases:
        cells = []
        for w in relax:
            res = local_solvers.solve(W, q, mu, dim, method="nsgs", tol=args.tol, max_iter=args.max_sweeps,
                                      rho=w)
            cells.append(str(res.iterations) if res.converged else f"✗ {res.iterations}")
            records.append(dict(section="nsgs-relaxation", problem=name, omega=w, iterations=res.iterations,
                                converged=res.converged, error=res.error))
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
        print(lines[-1], flush=True)

    lines += ["", f"Total benchmark wall time: {time.perf_counter() - t_start:.0f} s."]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines) + "\n")
    meta = dict(command=command, machine=machine_info(), tol=args.tol, caps=cap, records=records)
    args.out.with_suffix(".json").write_text(json.dumps(meta, indent=1, default=float) + "\n")
    print(f"wrote {args.out} and {args.out.with_suffix('.json')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
