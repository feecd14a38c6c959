"""The size estimate before meshing (dolfinx_fretting.sizes) against what is built and what a run uses.

Two tables, each point in a child process of its own:

* **calibration**: each built-in geometry family at several mesh sizes, the model built (mesh, K factorised by
  MUMPS, W), its nodes, dofs, contacts and MUMPS's INFOG(22) (memory effectively used by the factorisation,
  MB) against the estimate's counts and factor term;
* **runs**: whole short runs (``dolfinx-fretting run``, a few cycles, the numba cache warm) at 2-3 mesh sizes
  each; their peak resident memory (``ru_maxrss`` of the child, from ``os.wait4``) against the estimate's
  peak (``summary.json``'s ``size_estimate.total_bytes``).

Usage::

    .venv/bin/python benchmarks/bench_sizes.py [--out benchmarks/results/size_estimate] [--skip-calibration]
        [--markdown-only]

Writes ``OUT.json`` and ``OUT.md``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.sizes import estimate  # noqa: E402

QUIET = ["output.xdmf=false", "output.plots=false", "output.contact_profiles=false", "output.progress=false"]
#: (scene, overrides) of the calibration table: the model only (no run).
CALIBRATION = [
    *[("hertz", [f"geometry.contact_mesh_size={h}"]) for h in (0.04, 0.02, 0.01, 0.005, 0.0025, 0.00125)],
    *[("cylinder-flat", [f"geometry.contact_mesh_size={h}"]) for h in (0.04, 0.02, 0.01, 0.005, 0.0025, 0.00125)],
    *[("cylinder-flat", [f"geometry.contact_mesh_size={h}", "geometry.quadrilateral=false"]) for h in (0.02, 0.005)],
    *[("hertz", [f"geometry.contact_mesh_size={h}", "geometry.quadrilateral=false"]) for h in (0.02, 0.005)],
    *[("mccoll", [f"geometry.contact_mesh_size={h}"]) for h in (0.02, 0.005)],
    *[("stromberg-block", [f"geometry.nx={n}", f"geometry.ny={n}"]) for n in (25, 50, 100, 200, 400, 800)],
    ("stromberg-block", ["geometry.nx=200", "geometry.ny=200", "geometry.quadrilateral=false"]),
    *[("sphere-flat", [f"geometry.contact_mesh_size={h}"]) for h in (0.09, 0.0466, 0.031, 0.0233, 0.0187, 0.0155)],
]
#: (scene, overrides) of the whole runs (a few cycles each: the cycle cache is filled in the first ones).
SHORT_2D = ["loading.cycles=3", "output.snapshot_cycles=[3]", "output.loop_cycles=[3]"]
SHORT_3D = ["loading.cycles=1", "loading.increments_per_cycle=8", "output.snapshot_cycles=[1]",
            "output.loop_cycles=[1]"]
#: The elastic-plastic Example 2 (benchmarks/bench_plastic.py's material), one cycle.
PLASTIC = ["loading.cycles=1", "output.snapshot_cycles=[1]", "output.loop_cycles=[1]", "material.model=elastoplastic",
           "material.yield_stress=840", "material.hardening_modulus=7230"]
RUNS = [
    *[("hertz", [f"geometry.contact_mesh_size={h}", "loading.tangential_increments=4"]) for h in (0.01, 0.005, 0.0025)],
    *[("cylinder-flat", [f"geometry.contact_mesh_size={h}", *SHORT_2D]) for h in (0.01, 0.005, 0.0025)],
    *[("cylinder-flat", [f"geometry.contact_mesh_size={h}", *PLASTIC]) for h in (0.01, 0.005)],
    *[("mccoll", [f"geometry.contact_mesh_size={h}", *SHORT_2D]) for h in (0.01, 0.005)],
    # nx = 100 needs more than 20 000 local sweeps at an increment of the first cycle: the mesh grows through ny
    *[("stromberg-block", ["geometry.nx=50", f"geometry.ny={n}", *SHORT_2D]) for n in (50, 200, 400)],
    *[("sphere-flat", [*([f"geometry.contact_mesh_size={h}"] if h else []), *SHORT_3D]) for h in (None, 0.031, 0.0233)],
]

PROBE = r"""
import json, sys
from mpi4py import MPI
from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import ContactModel
scene = load_scene(sys.argv[1], sys.argv[2:])
m = ContactModel(scene, MPI.COMM_WORLD)
F = m.problem.operators.delassus.factor
print(json.dumps({"dofs": m.problem.n_dofs, "contacts": m.contact.nc, "infog22_MB": F.getMumpsInfog(22),
                  "nnz": m.problem.operators.K.getInfo()["nz_used"]}))
m.problem.destroy()
"""


def _env() -> dict[str, str]:
    return dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")


def _label(name: str, overrides: list[str]) -> str:
    keep = [o for o in overrides if o.startswith(("geometry.", "material.model"))]
    return " ".join([name, *(o.removeprefix("geometry.") for o in keep)])


def calibrate(name: str, overrides: list[str]) -> dict:
    out = subprocess.run([sys.executable, "-c", PROBE, name, *overrides], capture_output=True, text=True,
                         env=_env(), check=True, cwd=ROOT).stdout
    built = json.loads(out.strip().splitlines()[-1])
    est = estimate(load_scene(name, overrides))
    return {"case": _label(name, overrides), "dofs": built["dofs"], "dofs_estimated": est.dofs,
            "contacts": built["contacts"], "contacts_estimated": est.contacts,
            "factor_MB": built["infog22_MB"], "factor_MB_estimated": est.memory["factor"] / 2**20}


def run(name: str, overrides: list[str], folder: Path) -> dict:
    """One run in a child process: its peak RSS (os.wait4's ru_maxrss) and its summary's size estimate."""
    cmd = [sys.executable, "-m", "dolfinx_fretting", "run", name, "--out", str(folder), "--quiet",
           *[x for o in [*overrides, *QUIET] for x in ("--set", o)]]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, env=_env(), cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    err = proc.stderr.read().decode()
    proc.stderr.close()
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}): {err[-2000:]}")
    summary = json.loads((folder / "summary.json").read_text())
    size = summary["size_estimate"]
    rss = usage.ru_maxrss * 1024  # kB on Linux
    return {"case": _label(name, overrides), "dofs": summary["dofs"], "dofs_estimated": size["dofs"],
            "contacts": summary["contacts"], "contacts_estimated": size["contacts"],
            "rss_MB": rss / 2**20, "estimate_MB": size["total_bytes"] / 2**20,
            "ratio": size["total_bytes"] / rss,
            "terms_MB": {k: round(v / 2**20, 1) for k, v in size["memory"].items()}, "wall_s": round(wall, 1)}


def _markdown(result: dict) -> str:
    lines = [
        "# Size estimate before meshing vs what is built and what a run uses",
        "",
        f"Command: `{result['command']}`  ",
        f"Machine: {result['machine']}; {result['date']}",
        "",
        "`dolfinx_fretting.sizes.estimate` counts the model from the scene alone (no mesh, no DOLFINx). Each "
        "row below is a child process.",
        "",
    ]
    if result["calibration"]:
        lines += [
            "## Calibration: the model built (mesh, K factorised, W) against the estimate",
            "",
            "Factor: MUMPS INFOG(22), the memory effectively used by the factorisation (MB), against "
            "`FACTOR_BYTES_2D` n log2 n or `FACTOR_BYTES_3D` n^(4/3).",
            "",
            "| case | dofs | estimated | error | contacts | estimated | factor MB | estimated | ratio |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for r in result["calibration"]:
            lines.append(f"| {r['case']} | {r['dofs']} | {r['dofs_estimated']} | "
                         f"{r['dofs_estimated'] / r['dofs'] - 1:+.1%} | {r['contacts']} | {r['contacts_estimated']} | "
                         f"{r['factor_MB']} | {r['factor_MB_estimated']:.0f} | "
                         f"{r['factor_MB_estimated'] / max(r['factor_MB'], 1):.2f} |")
        lines.append("")
    lines += [
        "## Whole runs: peak resident memory against the estimate's peak",
        "",
        "Short runs (hertz: the monotonic load, 4 tangential increments; 2D cyclic scenes: 3 cycles; elastic-plastic "
        "cylinder-flat: 1 cycle; sphere: 1 cycle of 8 increments), numba's cache warm. Measured: `ru_maxrss` of the child (`os.wait4`). Ratio = "
        "estimate / measured (above 1: the estimate is on the safe side).",
        "",
        "| case | dofs | est. dofs | contacts | measured MB | estimated MB | ratio | largest terms (MB) | wall s |",
        "|---|---:|---:|---:|---:|---:|---:|---|---:|",
    ]
    for r in result["runs"]:
        terms = ", ".join(f"{k} {v:g}" for k, v in sorted(r["terms_MB"].items(), key=lambda kv: -kv[1])[:4])
        lines.append(f"| {r['case']} | {r['dofs']} | {r['dofs_estimated']} | {r['contacts']} | {r['rss_MB']:.0f} | "
                     f"{r['estimate_MB']:.0f} | {r['ratio']:.2f} | {terms} | {r['wall_s']} |")
    ratios = [r["ratio"] for r in result["runs"]]
    lines += ["", f"Ratio estimate / measured: {min(ratios):.2f} to {max(ratios):.2f}.", ""]
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=str(HERE / "results" / "size_estimate"))
    p.add_argument("--skip-calibration", action="store_true")
    p.add_argument("--markdown-only", action="store_true", help="rewrite OUT.md from OUT.json")
    args = p.parse_args()
    if args.markdown_only:
        Path(args.out + ".md").write_text(_markdown(json.loads(Path(args.out + ".json").read_text())))
        return
    import numba
    import petsc4py

    result = {"command": shlex.join([Path(sys.executable).as_posix(), *sys.argv]),
              "machine": f"{platform.node()} {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
                         f"Python {platform.python_version()}, petsc4py {petsc4py.__version__}, numba {numba.__version__}",
              "date": datetime.date.today().isoformat(), "calibration": [], "runs": []}
    with tempfile.TemporaryDirectory() as tmp:
        # warm the numba cache (a fresh clone compiles on its first run: not what the estimate is about)
        for name in ("stromberg-block", "cylinder-flat", "sphere-flat"):
            over = ["loading.cycles=1", "output.snapshot_cycles=[1]", "output.loop_cycles=[1]"]
            run(name, over + (["loading.increments_per_cycle=8"] if name == "sphere-flat" else []),
                Path(tmp) / f"warm-{name}")
        if not args.skip_calibration:
            for name, over in CALIBRATION:
                result["calibration"].append(calibrate(name, over))
                print(json.dumps(result["calibration"][-1]), flush=True)
        for i, (name, over) in enumerate(RUNS):
            result["runs"].append(run(name, over, Path(tmp) / f"run{i}"))
            print(json.dumps(result["runs"][-1]), flush=True)
    Path(args.out + ".json").write_text(json.dumps(result, indent=1) + "\n")
    Path(args.out + ".md").write_text(_markdown(result))
    print(f"wrote {args.out}.json, {args.out}.md")


if __name__ == "__main__":
    main()
