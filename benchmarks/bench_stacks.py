"""The two tested stacks side by side: Debian's DOLFINx 0.5.2 (.venv) and DOLFINx 0.11 from the wheel
(.venv-current), on the same jobs, alternated (debian, current, debian, current, ...) so that the shared
machine's load drifts over both alike.

Jobs (each a fresh process of the stack's own CLI or Python):

* ``main``: the main job, ``dolfinx-fretting run stromberg-block`` (9000 cycles; ``--cycles`` to shorten);
* ``W``: factorisation of K and W by the selected inverse on the 206k-dof block and the 32k-dof cylinder
  (``benchmarks/bench_schur.py``'s measurement, selected inverse only);
* ``np2``: ``hertz`` at h = 5 µm on 2 MPI ranks (Open MPI's ``mpirun`` for Debian's stack, the wheel's own
  ``mpiexec`` for 0.11);
* ``plastic``: one elastic–plastic fretting cycle, ``cylinder-flat`` with both bodies von Mises (the paper's
  Table 2: sigma_y0 = 840 MPa, H = 7230 MPa; ``PLASTIC_SETTINGS``): the preload and 80 increments of Newton
  with the contact solve inside every iteration, on the 10 µm contact mesh (``benchmarks/results/plastic.md``
  runs the same scene for 3 and 100 cycles).

Reported: wall time of each process (median over ``--repeat``), the run's own ``wall_time_s``, and the
largest relative difference between the stacks' summaries (results must agree, see tests/test_stacks.py).
Both stacks mesh with their own gmsh here (4.8.4 and 4.15), as a user would: the cylinder jobs' numbers
differ by the mesh, the block's not at all. Usage (from the repository root, any Python 3)::

    OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_stacks.py --out benchmarks/results/stacks
"""

from __future__ import annotations

import argparse
import csv
import datetime
import json
import os
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
STACKS = {"debian": {"venv": ROOT / ".venv", "launcher": ["mpirun", "--oversubscribe", "-n", "2"]},
          "current": {"venv": ROOT / ".venv-current", "launcher": [str(ROOT / ".venv-current/bin/mpiexec"), "-n", "2"]}}

#: The elastic–plastic job's scene: cylinder-flat (elastic flat by default) made elastic–plastic, one cycle.
PLASTIC_SETTINGS = ("material.model=elastoplastic", "material.yield_stress=840", "material.hardening_modulus=7230",
                    "loading.cycles=1", "output.plots=false")

_W_SCRIPT = r"""
import json, sys, time
sys.path.insert(0, "benchmarks")
from mpi4py import MPI
from bench_schur import scene_for
from dolfinx_fretting.simulation import ContactModel
out = {}
for case in ({"kind": "rectangle", "n": 320, "label": "rect 320"},
             {"kind": "half_cylinder", "h": 0.0025, "label": "hertz h=0.0025"}):
    m = ContactModel(scene_for(case), MPI.COMM_SELF)
    d, H = m.problem.operators.delassus, m.contact.H
    f, w = [], []
    for _ in range(3):
        d.factorize(); f.append(d.last_factorize_time)
        d.build(H, method="selected_inverse"); w.append(d.last_build_time)
    out[case["label"]] = {"dofs": m.n_dofs, "contacts": m.contact.nc, "factorize_s": sorted(f)[1],
                          "selected_inverse_s": sorted(w)[1]}
    m.problem.destroy()
print("RESULT " + json.dumps(out))
"""


def _versions(python: Path) -> dict:
    code = "import json; from dolfinx_fretting import _dolfinx as d; print(json.dumps(d.versions()))"
    out = subprocess.run([str(python), "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _env() -> dict:
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    return env


def run_job(stack: str, job: str, cycles: int, work: Path) -> dict:
    venv = STACKS[stack]["venv"]
    out = work / f"{stack}-{job}"
    if job == "main":
        cmd = [str(venv / "bin/dolfinx-fretting"), "run", "stromberg-block", "--out", str(out), "--quiet",
               "--set", f"loading.cycles={cycles}", "--set", "output.plots=false"]
    elif job == "plastic":
        cmd = [str(venv / "bin/dolfinx-fretting"), "run", "cylinder-flat", "--out", str(out), "--quiet"]
        for setting in PLASTIC_SETTINGS:
            cmd += ["--set", setting]
    elif job == "np2":
        cmd = [*STACKS[stack]["launcher"], str(venv / "bin/python"), "-m", "mpi4py", "-m", "dolfinx_fretting", "run",
               "hertz", "--out", str(out), "--quiet", "--set", "geometry.contact_mesh_size=0.005",
               "--set", "output.plots=false"]
    else:
        cmd = [str(venv / "bin/python"), "-c", _W_SCRIPT]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=_env(), cwd=ROOT, timeout=3600)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{stack} {job} failed:\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}")
    rec = {"wall_s": wall}
    if job == "W":
        rec["W"] = json.loads([ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")][-1][7:])
    else:
        rec["summary"] = json.loads((out / "summary.json").read_text())
    if job == "plastic":  # the Newton loop's work, summed over the increments of history.csv
        with open(out / "history.csv", newline="") as fh:
            rows = list(csv.DictReader(fh))
        rec["newton"] = {key: int(sum(float(r[key]) for r in rows)) for key in ("newton_iterations", "cutbacks")}
    return rec


def _max_rel_diff(a: dict, b: dict) -> tuple[float, str]:
    worst, where = 0.0, ""
    for key in ("normal_force", "tangential_force", "max_pressure", "max_wear_depth", "wear_area",
                "dissipated_energy", "contact_width", "stick_width", "max_equivalent_plastic_strain"):
        x, y = a.get(key), b.get(key)
        if isinstance(x, (int, float)) and isinstance(y, (int, float)) and max(abs(x), abs(y)) > 0:
            d = abs(x - y) / max(abs(x), abs(y))
            if d >= worst:
                worst, where = d, key
    return worst, where


def _plastic_line(rec: dict) -> str:
    """What the Newton loop did in the elastic–plastic job (its summary and history.csv) and where it ended."""
    s = rec["summary"]
    return (f"{s['dofs']} dofs, {s['contacts']} contacts, {s['increments']} increments, "
            f"{rec['newton']['newton_iterations']} Newton iterations, {s['tangent_refactorizations']} tangent "
            f"refactorisations, {s['newton_full_fallbacks']} full-Newton fallbacks, {rec['newton']['cutbacks']} "
            f"cut-backs; max equivalent plastic strain {s['max_equivalent_plastic_strain']:.6g}, peak pressure "
            f"{s['max_pressure']:.2f} MPa, max wear depth {s['max_wear_depth']:.6g} mm, run's wall_time_s "
            f"{s['wall_time_s']:.1f} (the run's own account: \"{s['modelled']['material']}\")")


def _median(values: list[float]) -> float:
    values = sorted(values)
    n = len(values)
    return values[n // 2] if n % 2 else 0.5 * (values[n // 2 - 1] + values[n // 2])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cycles", type=int, default=9000, help="cycles of the main job")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--jobs", nargs="*", default=["main", "W", "np2", "plastic"],
                    choices=["main", "W", "np2", "plastic"])
    ap.add_argument("--out", type=Path, default=HERE / "results" / "stacks")
    ap.add_argument("--report-from", type=Path, metavar="JSON",
                    help="measure nothing: write OUT.md again from the results of an earlier run")
    args = ap.parse_args(argv)
    if args.report_from:
        report = write_report(json.loads(args.report_from.read_text()), args.out)
        print(report)
        return 0
    argv_used = sys.argv[1:] if argv is None else argv
    command = "OPENBLAS_NUM_THREADS=1 python3 benchmarks/bench_stacks.py" + "".join(" " + shlex.quote(a) for a in argv_used)
    versions = {s: _versions(STACKS[s]["venv"] / "bin/python") for s in STACKS}
    load0 = os.getloadavg()
    t_all = time.perf_counter()
    results: dict = {job: {s: [] for s in STACKS} for job in args.jobs}
    with tempfile.TemporaryDirectory(prefix="bench_stacks_") as tmp:
        for i in range(args.repeat):
            for job in args.jobs:
                for stack in STACKS:
                    rec = run_job(stack, job, args.cycles, Path(tmp) / f"r{i}")
                    results[job][stack].append(rec)
                    print(f"[{i}] {job} {stack}: {rec['wall_s']:.1f} s", flush=True)
    total = time.perf_counter() - t_all
    data = {"command": command, "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
            "versions": versions, "load_average_start": list(load0), "load_average_end": list(os.getloadavg()),
            "total_s": total, "settings": vars(args) | {"out": str(args.out)}, "results": results}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.with_suffix(".json").write_text(json.dumps(data, indent=1, default=str) + "\n")
    print(write_report(data, args.out))
    return 0


def write_report(data: dict, out: Path) -> str:
    """OUT.md from the results of a run (``data`` as in OUT.json); returns its text."""
    command, total, versions, results = data["command"], data["total_s"], data["versions"], data["results"]
    load0 = data["load_average_start"]
    jobs, repeat, cycles = data["settings"]["jobs"], data["settings"]["repeat"], data["settings"]["cycles"]
    lines = ["# The two stacks side by side", "", f"Command (from the repository root): `{command}`", "",
             f"- date: {data['date']}; load average {load0[0]:.2f} at start, {data['load_average_end'][0]:.2f} at "
             f"end (2-core machine shared with other jobs: compare the two columns of one row, measured "
             f"alternately, not rows or runs); total {total:.0f} s",
             *[f"- {s}: DOLFINx {v['dolfinx']}, PETSc {v['petsc']}, numpy {v['numpy']}, {v['mpi'].split(',')[0]}, Python "
               f"{v['python']}" for s, v in versions.items()],
             f"- median of {repeat} alternated runs per job and stack", "",
             "| job | debian: wall s | current: wall s | current / debian | results: max rel diff |",
             "|---|---:|---:|---:|---|"]
    for job in jobs:
        deb, cur = results[job]["debian"], results[job]["current"]
        wd, wc = _median([r["wall_s"] for r in deb]), _median([r["wall_s"] for r in cur])
        if job == "W":
            diff = "(timings only)"
            label = "W: factorise + selected inverse, 206k- and 32k-dof meshes (process incl. meshing)"
        else:
            d, key = _max_rel_diff(deb[-1]["summary"], cur[-1]["summary"])
            diff = f"{d:.1e} ({key})"
            label = {"main": f"main job: stromberg-block, {cycles} cycles",
                     "np2": "hertz h = 5 µm on 2 ranks",
                     "plastic": "one elastic–plastic cycle: cylinder-flat, both bodies von Mises, 10 µm, "
                                "80 increments"}[job]
        lines.append(f"| {label} | {wd:.1f} | {wc:.1f} | {wc / wd:.2f} | {diff} |")
    if "main" in jobs or "np2" in jobs:
        lines += ["", "The runs' own `wall_time_s` (from start to end of the scene, excluding the interpreter "
                  "start and imports):", "", "| job | debian | current |", "|---|---:|---:|"]
        for job in [j for j in jobs if j != "W"]:
            cells = [f"{_median([r['summary']['wall_time_s'] for r in results[job][s]]):.2f}" for s in STACKS]
            lines.append(f"| {job} | " + " | ".join(cells) + " |")
    if "W" in jobs:
        lines += ["", "W in detail (median of 3 inside each process, then of the runs; ms):", "",
                  "| mesh | dofs | contacts | debian: factorise | debian: W | current: factorise | current: W |",
                  "|---|---:|---:|---:|---:|---:|---:|"]
        for mesh in results["W"]["debian"][0]["W"]:
            cells = []
            for s in STACKS:
                recs = [r["W"][mesh] for r in results["W"][s]]
                cells += [f"{_median([r['factorize_s'] for r in recs]) * 1e3:.1f}",
                          f"{_median([r['selected_inverse_s'] for r in recs]) * 1e3:.1f}"]
            r0 = results["W"]["debian"][0]["W"][mesh]
            lines.append(f"| {mesh} | {r0['dofs']} | {r0['contacts']} | " + " | ".join(cells) + " |")
    if "plastic" in jobs:
        lines += ["", "The elastic–plastic cycle in detail (last run of each stack): "
                  + "; ".join(f"{s}: {_plastic_line(results['plastic'][s][-1])}" for s in STACKS)
                  + f". Scene settings: `{' '.join('--set ' + x for x in PLASTIC_SETTINGS)}`."]
    lines += ["", "The cylinders (hertz, cylinder-flat) are meshed by each stack's own gmsh (4.8.4 / 4.15), so "
              "their results differ by the mesh; tests/test_stacks.py compares the stacks on identical meshes "
              "(<= 5e-13)."]
    text = "\n".join(lines) + "\n"
    out.with_suffix(".md").write_text(text)
    return text


if __name__ == "__main__":
    raise SystemExit(main())
