"""``sphere-flat`` at ten elements across the Hertz radius: the 10^4-cycle run's time and its error (issue 26).

Two steps, each a plain ``dolfinx-fretting run`` (the command is printed and stored with its record):

1. ``run``: ``dolfinx-fretting run sphere-flat --set loading.cycles=10000 --set wear.cycle_jump=true`` (what a
   user types; pictures and XDMF as the scene has them unless ``--terse``) with ``geometry.contact_mesh_size =
   a / A_OVER_H`` (none: the scene's default) and the mesh family chosen by ``--grading`` (the depth grading of
   ``geometries.sphere.DEPTH_GRADING`` as ``depth_growth,coarsening,field_cell``, or ``uniform``: today's mesh; the
   module's constants are set in the child process before the CLI runs, so the command is the CLI's own). Timed
   in a child process: wall and CPU (user + system, the child and its own children: the pictures' process); the
   load average before and after; the run's own timings from ``summary.json`` (mesh, assembly, factorisation, W,
   the whole run). ``--scene-cycles``: the scene as written instead (100 cycles, every one simulated).
2. ``compare``: each run's errors against a reference run's folder: the worn map (the wear gap of the last kept
   increment over the contact plane; :func:`dolfinx_fretting.study.map_l2_error`, the relative L2 distance on a
   301 x 301 grid, the study's ``err_wear_l2``; and the largest difference on that grid over the reference's
   deepest wear), the worn volume (``summary.json``'s ``wear_volume``), the peak pressure of the last cycle (the
   study's: the largest nodal pressure over the last cycle's kept increments) and the deepest wear.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_sphere_resolution.py run --label L --work DIR \\
        [--a-over-h N] [--grading uniform | G,C,F] [--set KEY=VALUE ...] [--terse] [--scene-cycles] [--nice N]
    .venv/bin/python benchmarks/bench_sphere_resolution.py compare --work DIR --reference LABEL [--json FILE]

Records (JSON lines) go to ``DIR/records.jsonl``; ``compare`` prints a markdown table and writes ``--json``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENE_RUN = ["run", "sphere-flat", "--set", "loading.cycles=10000", "--set", "wear.cycle_jump=true"]
TERSE = ["--set", "output.xdmf=false", "--set", "output.plots=false"]


def _hertz_radius() -> float:
    sys.path.insert(0, str(ROOT))
    from dolfinx_fretting.geometries import GEOMETRIES
    from dolfinx_fretting.scenes import load_scene

    return GEOMETRIES["sphere"].contact_size(load_scene("sphere-flat"))


def child(argv: list[str]) -> int:
    """In the child: set the sphere's mesh family, then the CLI itself."""
    grading, cli_args = argv[0], argv[1:]
    sys.path.insert(0, str(ROOT))
    from dolfinx_fretting import cli
    from dolfinx_fretting.geometries import sphere

    if grading == "uniform":
        sphere.GRADED_FROM = math.inf
    elif grading != "default":
        growth, coarsening, field = grading.split(",")
        sphere.DEPTH_GRADING = {"depth_growth": float(growth), "coarsening": int(coarsening),
                                "field_cell": float(field)}
        sphere.GRADED_FROM = 0.0
    return int(cli.main(cli_args) or 0)


def run(args: argparse.Namespace) -> None:
    work = Path(args.work).resolve()
    out = work / args.label
    cli_args = [*(SCENE_RUN[:2] if args.scene_cycles else SCENE_RUN), "--out", str(out), "--overwrite"]
    if args.a_over_h is not None:
        cli_args += ["--set", f"geometry.contact_mesh_size={_hertz_radius() / args.a_over_h:.6g}"]
    for item in args.set or []:
        cli_args += ["--set", item]
    if args.terse:
        cli_args += TERSE
    command = [sys.executable, "-u", str(Path(__file__).resolve()), "_child", args.grading, *cli_args]
    if args.nice:
        command = ["nice", "-n", str(args.nice), *command]
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    load_before = os.getloadavg()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    started = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    with open(work / f"{args.label}.log", "w") as log:  # written as it runs (tail it)
        process = subprocess.run(command, env=env, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    summary = json.loads((out / "summary.json").read_text()) if (out / "summary.json").exists() else {}
    record = {"label": args.label, "a_over_h": args.a_over_h, "grading": args.grading, "started": started,
              "command": " ".join(command), "returncode": process.returncode, "wall_s": round(wall, 2),
              "cpu_s": round(cpu, 2), "maxrss_mb": round(after.ru_maxrss / 1024, 1),
              "load_before": load_before, "load_after": os.getloadavg(),
              "summary": {key: summary.get(key) for key in (
                  "converged", "error", "cycles", "equivalent_cycles", "dofs", "contacts", "contact_window",
                  "max_wear_depth", "wear_volume", "contact_radius", "max_pressure", "dissipated_energy",
                  "delassus_method", "window_growths", "increments", "local_iterations")},
              "timings": {key: value for key, value in summary.items() if key.endswith("_s")},
              "simulated_cycles": _simulated_cycles(out)}
    with open(work / "records.jsonl", "a") as handle:
        handle.write(json.dumps(record) + "\n")
    print(json.dumps(record, indent=1))


def _simulated_cycles(folder: Path) -> int | None:
    path = folder / "cycles.csv"
    if not path.exists():
        return None
    return max(0, sum(1 for _ in path.open()) - 1)


def map_errors(folder: Path, reference: Path, n: int = 301) -> dict[str, float]:
    """The worn map's relative L2 distance and largest difference (over the reference's deepest wear) on one
    n x n grid (both maps interpolated linearly on their own nodes, zero outside their hull)."""
    from scipy.interpolate import LinearNDInterpolator

    from dolfinx_fretting.study import _outcome, map_l2_error

    p, r = _outcome(folder), _outcome(reference)
    lower = np.minimum(p.position.min(axis=0), r.position.min(axis=0))
    upper = np.maximum(p.position.max(axis=0), r.position.max(axis=0))
    gx, gy = np.meshgrid(np.linspace(lower[0], upper[0], n), np.linspace(lower[1], upper[1], n))
    grid = np.column_stack([gx.ravel(), gy.ravel()])
    a = LinearNDInterpolator(p.position, p.wear, fill_value=0.0)(grid)
    b = LinearNDInterpolator(r.position, r.wear, fill_value=0.0)(grid)
    return {"map_l2": map_l2_error(p.position, p.wear, r.position, r.wear, n),
            "map_max": float(np.max(np.abs(a - b)) / np.max(np.abs(b))),
            "peak_pressure": p.peak_pressure, "peak_pressure_ref": r.peak_pressure}


def compare(args: argparse.Namespace) -> None:
    sys.path.insert(0, str(ROOT))
    work = Path(args.work).resolve()
    records = [json.loads(line) for line in (work / "records.jsonl").read_text().splitlines() if line.strip()]
    latest = {record["label"]: record for record in records}
    reference = latest[args.reference]
    ref_folder = work / args.reference
    rows = []
    for label, record in latest.items():
        if label == args.reference or record["returncode"] != 0:
            continue
        errors = map_errors(work / label, ref_folder)
        s, rs = record["summary"], reference["summary"]
        row = {"label": label, "a_over_h": record["a_over_h"], "grading": record["grading"],
               "dofs": s["dofs"], "contacts": s["contacts"], "simulated": record["simulated_cycles"],
               "wall_s": record["wall_s"], "cpu_s": record["cpu_s"], "load_before": record["load_before"][0],
               "load_after": record["load_after"][0],
               "err_map_l2": errors["map_l2"], "err_map_max": errors["map_max"],
               "err_volume": abs(s["wear_volume"] / rs["wear_volume"] - 1),
               "err_peak_pressure": abs(errors["peak_pressure"] / errors["peak_pressure_ref"] - 1),
               "err_max_wear": abs(s["max_wear_depth"] / rs["max_wear_depth"] - 1)}
        rows.append(row)
    header = ("| run | a/h | mesh | dofs | contacts | simulated cycles | wall (s) | CPU (s) | load (1 min) "
              "| worn map L2 | worn map max | worn volume | peak pressure | deepest wear |")
    print(header)
    print("|" + " ---: |" * (header.count("|") - 1))
    for row in rows:
        print(f"| {row['label']} | {row['a_over_h']} | {row['grading']} | {row['dofs']} | {row['contacts']} | "
              f"{row['simulated']} | {row['wall_s']:.1f} | {row['cpu_s']:.1f} | {row['load_before']:.1f}-"
              f"{row['load_after']:.1f} | {100 * row['err_map_l2']:.2f} % | {100 * row['err_map_max']:.2f} % | "
              f"{100 * row['err_volume']:.3f} % | {100 * row['err_peak_pressure']:.2f} % | "
              f"{100 * row['err_max_wear']:.2f} % |")
    if args.json:
        Path(args.json).write_text(json.dumps({"reference": reference, "rows": rows, "records": records}, indent=1))


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "_child":
        sys.exit(child(sys.argv[2:]))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="step", required=True)
    r = sub.add_parser("run")
    r.add_argument("--label", required=True)
    r.add_argument("--work", required=True)
    r.add_argument("--a-over-h", type=float, default=None)
    r.add_argument("--grading", default="default", help="default, uniform, or depth_growth,coarsening,field_cell")
    r.add_argument("--set", action="append")
    r.add_argument("--terse", action="store_true")
    r.add_argument("--scene-cycles", action="store_true", help="the scene's own cycles (100, every one), no jumps")
    r.add_argument("--nice", type=int, default=0)
    c = sub.add_parser("compare")
    c.add_argument("--work", required=True)
    c.add_argument("--reference", required=True)
    c.add_argument("--json")
    args = parser.parse_args()
    (Path(args.work)).mkdir(parents=True, exist_ok=True)
    run(args) if args.step == "run" else compare(args)


if __name__ == "__main__":
    main()
