"""Schur-complement route against the selected inverse: cost of W = H K^-1 H^T, serial, on either stack.

For each mesh (the ``hertz`` half-cylinder at several ``geometry.contact_mesh_size``, 50x50 mm blocks with every
bottom node a candidate) the package's objects are built (``ContactModel``), then, on the model's
``DelassusOperator``:

* ``factorize``: K's MUMPS Cholesky, symbolic + numeric (median of ``--repeat``), the unit of time;
* ``selected_inverse``: W from MUMPS entries of the inverse on the existing factor (median build time);
* ``schur (new)``: the ``schur`` route's first build for a contact set: its own factorisation of [[K, H^T],
  [H, 0]] with H's rows kept for last (symbolic + numeric) and the Schur complement, -W;
* ``schur (reuse)``: a later build with the same H (the Schur complement read again from the kept factor);
* after ``refactorize`` (K's values changed, as in a Newton iteration with the consistent tangent): the
  selected inverse's build on the refreshed factor, and the Schur route's build, which first refactorises its
  own factor numerically.

Builds are timed with the operator's ``last_build_time``; the routes' W are compared (max |W_a - W_b| /
max |W_b|). Usage (from the repository root), one run per stack, then the side-by-side table::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_schur.py --out benchmarks/results/schur_debian
    OPENBLAS_NUM_THREADS=1 .venv-current/bin/python benchmarks/bench_schur.py --out benchmarks/results/schur_current
    python3 benchmarks/bench_schur.py --combine benchmarks/results/schur_debian.json \\
        benchmarks/results/schur_current.json --out benchmarks/results/schur
"""

from __future__ import annotations

import argparse
import datetime
import gc
import json
import os
import platform
import re
import shlex
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))


def _median(values: list[float]) -> float:
    return float(np.median(values)) if values else float("nan")


def _mumps_version() -> str:
    """MUMPS version: the wheel's notices file, else Debian's header."""
    from petsc4py import PETSc

    here = Path(PETSc.__file__).resolve()
    for parent in here.parents:
        notices = parent / "dolfinx_solver" / "THIRD-PARTY-NOTICES"
        if notices.exists():
            found = re.search(r"MUMPS_(\d+\.\d+\.\d+)", notices.read_text(errors="replace"))
            return found.group(1) if found else "unknown"
    for header in ("/usr/include/dmumps_c.h", "/usr/include/mumps/dmumps_c.h"):
        try:
            for line in Path(header).read_text().splitlines():
                if line.startswith("#define MUMPS_VERSION"):
                    return line.split()[-1].strip('"')
        except OSError:
            continue
    return "unknown"


def scene_for(case: dict):
    from dolfinx_fretting.scenes import load_scene

    if case["kind"] == "half_cylinder":
        return load_scene("hertz", [f"geometry.contact_mesh_size={case['h']}", "output.xdmf=false",
                                    "output.plots=false"])
    n = case["n"]
    return load_scene({"name": f"rectangle_{n}",
                       "geometry": {"kind": "rectangle", "width": 50.0, "height": 50.0, "nx": n, "ny": n},
                       "contact": {"surface": "bottom", "mu": 0.3}, "loading": {"normal_displacement": 1e-3},
                       "output": {"xdmf": False, "plots": False}})


def run_case(case: dict, repeat: int) -> dict:
    from mpi4py import MPI

    from dolfinx_fretting.simulation import ContactModel

    model = ContactModel(scene_for(case), MPI.COMM_SELF)
    d = model.problem.operators.delassus
    H = model.contact.H
    rec: dict = {"case": case["label"], "dofs": model.n_dofs, "contacts": model.contact.nc, "rows_H": H.shape[0],
                 "dofs_touched": int(np.unique(H.tocsr().indices).size)}
    fact, refact = [], []
    for _ in range(repeat):
        d.factorize()
        fact.append(d.last_factorize_time)
    W_si = d.build(H, method="selected_inverse")  # warm-up
    si = []
    for _ in range(repeat):
        d.build(H, method="selected_inverse")
        si.append(d.last_build_time)
    new, reuse = [], []
    W_schur = None
    for _ in range(repeat):
        d._drop_schur()  # drop the kept factor: time a first build
        W_schur = d.build(H, method="schur")
        new.append(d.last_build_time)
        d.build(H, method="schur")
        reuse.append(d.last_build_time)
    # Numeric refactorisations (the same values), as in Newton iterations with the consistent tangent.
    si_after, schur_after = [], []
    for _ in range(repeat):
        # PETSc skips a refactorisation when K's object state is unchanged: mark it changed (as new values
        # would), so that both the main factor and the Schur route's own factor are recomputed numerically.
        model.problem.operators.K.stateIncrease()
        d.refactorize()
        refact.append(d.last_factorize_time)
        d.build(H, method="selected_inverse")
        si_after.append(d.last_build_time)
        W_after = d.build(H, method="schur")
        schur_after.append(d.last_build_time)
    scale = np.abs(W_si).max()
    rec.update(
        factorize_s=_median(fact), refactorize_s=_median(refact),
        selected_inverse_s=_median(si), schur_new_s=_median(new), schur_reuse_s=_median(reuse),
        selected_inverse_after_refactorize_s=_median(si_after), schur_after_refactorize_s=_median(schur_after),
        schur_size=int(d.stats.get("schur_size", 0)),
        max_rel_diff=float(max(np.abs(W_schur - W_si).max(), np.abs(W_after - W_si).max()) / scale),
        all={"factorize": fact, "refactorize": refact, "selected_inverse": si, "schur_new": new,
             "schur_reuse": reuse, "selected_inverse_after": si_after, "schur_after": schur_after})
    model.problem.destroy()
    del model, d
    gc.collect()
    return rec


def markdown_one(data: dict) -> str:
    info = data["machine"]
    lines = [f"# Schur complement vs selected inverse (DOLFINx {info['dolfinx']})", "",
             f"Command (from the repository root): `{data['command']}`", "",
             f"- date: {data['date']}; {info['cpu']}, {info['logical_cpus']} logical CPUs; load average "
             f"{info['load_average_start'][0]:.2f} at start, {info['load_average_end'][0]:.2f} at end",
             f"- DOLFINx {info['dolfinx']}, PETSc {info['petsc']}, MUMPS {info['mumps']}, numpy {info['numpy']}, "
             f"{info['mpi']}, Python {info['python']}; serial; median of {data['settings']['repeat']}",
             f"- total wall time of this run: {info['total_s']:.0f} s", "",
             "Times in ms; in brackets, divided by one factorisation of K on the same mesh.", "",
             "| mesh | dofs | contacts | Schur size | factorise | selected_inverse | schur (new) | schur (reuse) "
             "| refactorise | selected_inverse after | schur after | max rel diff |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in data["results"]:
        tf = r["factorize_s"]

        def cell(key: str) -> str:
            return f"{r[key] * 1e3:.3g} ({r[key] / tf:.2g})"
        lines.append(f"| {r['case']} | {r['dofs']} | {r['contacts']} | {r['schur_size']} | {tf * 1e3:.3g} | "
                     f"{cell('selected_inverse_s')} | {cell('schur_new_s')} | {cell('schur_reuse_s')} | "
                     f"{cell('refactorize_s')} | {cell('selected_inverse_after_refactorize_s')} | "
                     f"{cell('schur_after_refactorize_s')} | {r['max_rel_diff']:.1e} |")
    lines += ["", "`schur (new)`: first build for a contact set (its own symbolic + numeric factorisation of "
              "[[K, H^T], [H, 0]] with H's rows last, its Schur complement -W); `schur (reuse)`: the same dofs again; `… after`: the build "
              "after `refactorize()` (the Schur route then refactorises its own factor numerically; the main "
              "refactorisation, column `refactorise`, is paid by both). `max rel diff`: max|W_schur - W_si| / "
              "max|W_si|. Raw times of every repeat are in the .json file next to this one."]
    return "\n".join(lines) + "\n"


def combine(paths: list[Path], out: Path) -> None:
    runs = [json.loads(p.read_text()) for p in paths]
    lines = ["# Schur complement vs selected inverse on both stacks", "",
             "Each stack's run (serial, same meshes), its command and machine state are in the files named below; "
             "this table puts the build times of W side by side, **in units of that stack's factorisation of K** "
             "(the two runs were made one after the other on a shared 2-core machine: compare ratios, not "
             "milliseconds).", "",
             f"Combined by: `python3 benchmarks/bench_schur.py --combine {' '.join(str(p) for p in paths)} "
             f"--out {out}`", ""]
    for p, run in zip(paths, runs):
        info = run["machine"]
        lines.append(f"- `{p.name}`: DOLFINx {info['dolfinx']}, PETSc {info['petsc']}, MUMPS {info['mumps']}, "
                     f"numpy {info['numpy']}: `{run['command']}`")
    head = "| mesh | contacts |"
    rule = "|---|---:|"
    for run in runs:
        v = run["machine"]["dolfinx"]
        head += (f" {v}: factorise ms | {v}: selected_inverse | {v}: schur new | {v}: schur reuse "
                 f"| {v}: selected_inverse after | {v}: schur after |")
        rule += "---:|---:|---:|---:|---:|---:|"
    lines += ["", head, rule]
    by_case = [{r["case"]: r for r in run["results"]} for run in runs]
    for case in by_case[0]:
        row = f"| {case} | {by_case[0][case]['contacts']} |"
        for recs in by_case:
            r = recs.get(case)
            if r is None:
                row += " – | – | – | – | – | – |"
                continue
            tf = r["factorize_s"]
            row += (f" {tf * 1e3:.3g} | {r['selected_inverse_s'] / tf:.2g} | {r['schur_new_s'] / tf:.2g} | "
                    f"{r['schur_reuse_s'] / tf:.2g} | {r['selected_inverse_after_refactorize_s'] / tf:.2g} | "
                    f"{r['schur_after_refactorize_s'] / tf:.2g} |")
        lines.append(row)
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=float, nargs="*", default=[0.02, 0.01, 0.005, 0.0025])
    ap.add_argument("--rect", type=int, nargs="*", default=[80, 160, 320])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", type=Path, default=HERE / "results" / "schur")
    ap.add_argument("--combine", type=Path, nargs="*", help="JSON files of earlier runs: write the side-by-side table")
    args = ap.parse_args(argv)
    argv_used = sys.argv[1:] if argv is None else argv
    if args.combine:
        combine(args.combine, args.out)
        return 0

    from dolfinx_fretting import _dolfinx as dfx

    python = os.path.relpath(sys.executable, HERE.parent) if sys.executable.startswith(str(HERE.parent)) \
        else sys.executable
    command = f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')} {python} " \
              "benchmarks/bench_schur.py" + "".join(" " + shlex.quote(a) for a in argv_used)
    info = {**dfx.versions(), "mumps": _mumps_version(), "cpu": platform.processor() or "unknown",
            "logical_cpus": os.cpu_count(), "load_average_start": list(os.getloadavg())}
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                info["cpu"] = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    print(f"# {command}\n# {info}", flush=True)
    cases = [{"kind": "half_cylinder", "h": h, "label": f"hertz h={h:g}"} for h in args.sizes]
    cases += [{"kind": "rectangle", "n": n, "label": f"rect {n}"} for n in args.rect]
    t0 = time.perf_counter()
    results = []
    for case in cases:
        rec = run_case(case, args.repeat)
        results.append(rec)
        print(f"{rec['case']}: dofs {rec['dofs']}, factorise {rec['factorize_s'] * 1e3:.3g} ms, selected_inverse "
              f"{rec['selected_inverse_s'] * 1e3:.3g} ms, schur new {rec['schur_new_s'] * 1e3:.3g} ms, reuse "
              f"{rec['schur_reuse_s'] * 1e3:.3g} ms, after refactorize: si {rec['selected_inverse_after_refactorize_s'] * 1e3:.3g} "
              f"ms, schur {rec['schur_after_refactorize_s'] * 1e3:.3g} ms, max rel diff {rec['max_rel_diff']:.1e}",
              flush=True)
    info["total_s"] = time.perf_counter() - t0
    info["load_average_end"] = list(os.getloadavg())
    data = {"command": command, "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
            "machine": info, "settings": {"repeat": args.repeat}, "results": results}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.with_suffix(".json").write_text(json.dumps(data, indent=1) + "\n")
    args.out.with_suffix(".md").write_text(markdown_one(data))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
