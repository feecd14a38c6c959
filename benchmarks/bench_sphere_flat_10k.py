"""10 000 gross-slip cycles of ``sphere-flat`` (3D, elastic, the default mesh) within 15 minutes, and its error.

Three parts, each a plain ``dolfinx-fretting`` command (printed in the results file):

1. **Every cycle** (the scene as written, ``loading.cycles = 100``), timed with ``/usr/bin/time -v``: the cost
   of a cycle, from which the every-cycle 10^4 is extrapolated.
2. **The 10^4-cycle run**, timed with ``/usr/bin/time -v``: the scene as written plus the package's own speed
   controls, ``wear.cycle_jump = true`` (its default bounds), and ``contact.candidate_half_width = 0.5``. The
   wider candidate window is not a speed control but it is needed: the worn contact grows from the Hertz
   radius (0.187 mm) to ~0.32 mm, past the default window (the mesh's uniform zone, 0.28 mm), where a run stops
   (measured: cycle 4769 of 10^4); the window then reaches onto the graded cells beyond the zone.
3. **Its error** by ``dolfinx-fretting study``, against two finer references:

   * ``short``: 500 physical cycles, reference every cycle with 80 increments a cycle (the scene: 40),
     ``local_tol`` 1e-12 and ``force_tol`` 1e-10 on the same mesh: isolates what the jumps, the increments and
     the tolerances cost (and wear acceleration x10, x100, for comparison);
   * ``long``: the whole 10^4 cycles, reference on contact cubes of a/8 (the scene: a/4; 93k dofs, 513
     contacts), 80 increments, the tight tolerances and cycle jumps with their default bounds (every cycle on
     that mesh would take ~10 h here; with bounds halved, ~1 h under the load it met, more than this
     benchmark's budget); points: the 10^4 run's settings, a/6 cubes, jumps with bounds / 4, x100 wear
     acceleration instead of jumps, ``solver.preset = "fast"`` (a/2 cubes), and the reference's numerics on
     the default mesh (its mesh error alone). The jumps' own error is the short study's.

The errors are those a tribologist reads, relative to the reference at the end of the run: maximum wear depth,
worn volume, energy dissipated in the last simulated cycle (energy per cycle) and over all physical cycles,
contact radius (equivalent radius of the loaded area at the end), peak pressure (largest nodal pressure over
the last cycle's kept increments, the study's) and the worn map (relative L2 distance of the wear gap over the
contact plane, :func:`dolfinx_fretting.study.map_l2_error`, the study's ``err_wear_l2`` for a 3D contact since
that was fixed: before, it was a profile along x through the scattered nodes).

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_sphere_flat_10k.py [--work DIR]
        [--skip-studies] [--skip-timed] [--only-timed] [--no-write]

``--skip-studies`` / ``--skip-timed`` reuse the folders already in ``--work`` (the analysis reads only the
output folders); ``--only-timed`` runs the two timed runs and stops. ``DOLFINX_FRETTING`` names another
``dolfinx-fretting`` executable (default: the repository's ``.venv``). Writes
``benchmarks/results/sphere_flat_10k.json`` and prints the tables of ``sphere_flat_10k.md`` (whose text is
written by hand around them).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import re
import shlex
import subprocess
import sys
import time
from pathlib import Path

from _machine import cpu_model  # benchmarks/ is on sys.path when a script runs

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
EXE = os.environ.get("DOLFINX_FRETTING", str(ROOT / ".venv" / "bin" / "dolfinx-fretting"))

SCENE = "sphere-flat"
#: The candidate window that holds the worn contact (see the module docstring).
WINDOW = "contact.candidate_half_width=0.5"
#: The scene's own numerics, written out so that a study point can return to them from its reference.
AS_WRITTEN = ["loading.increments_per_cycle=40", "solver.local_tol=1e-10", "solver.force_tol=1e-8"]
#: The 10^4-cycle run: the scene as written, cycle jumps with their default bounds, the wider window.
TEN_K = ["loading.cycles=10000", "wear.cycle_jump=true", WINDOW]
EVERY_CYCLE_CYCLES = 100
TIGHT = ["solver.local_tol=1e-12", "solver.force_tol=1e-10"]


def _sets(items: list[str], option: str = "--set") -> list[str]:
    return [arg for item in items for arg in (option, item)]


def _point(items: list[str]) -> list[str]:
    return ["--point", " ".join(items)]


#: The default bounds of a cycle jump, written out (the long study's reference and points set them).
default_jumps = ["wear.jump_wear_fraction=0.1", "wear.jump_pressure_change=0.05"]


def study_args(kind: str, out: Path) -> list[str]:
    """The ``dolfinx-fretting study`` arguments of the ``short`` (500 cycles) or ``long`` (10^4) study."""
    if kind == "short":
        return ([SCENE, "--out", str(out)] + _sets(["loading.cycles=500", WINDOW])
                + _sets(["loading.increments_per_cycle=80", *TIGHT], "--reference")
                + ["--sweep", "wear.cycle_jump=true", "--sweep", "wear.acceleration=10,100"]
                + _point([*AS_WRITTEN, "wear.cycle_jump=true"]))
    return ([SCENE, "--out", str(out)] + _sets(["loading.cycles=10000", WINDOW, "wear.cycle_jump=true"])
            + _sets(["geometry.contact_mesh_size=0.0233", "loading.increments_per_cycle=80", *TIGHT,
                     *default_jumps], "--reference")
            + ["--sweep", "geometry.contact_mesh_size=0.0467"]
            + _point(["geometry.contact_mesh_size=none", *AS_WRITTEN, *default_jumps])
            + _point(["geometry.contact_mesh_size=0.0311", *AS_WRITTEN, *default_jumps])
            + _point(["geometry.contact_mesh_size=none", *AS_WRITTEN, "wear.jump_wear_fraction=0.025",
                      "wear.jump_pressure_change=0.0125"])
            + _point(["geometry.contact_mesh_size=none", *AS_WRITTEN, "wear.cycle_jump=false",
                      "wear.acceleration=100"])
            + _point(["solver.preset=fast", "geometry.contact_mesh_size=none", "loading.increments_per_cycle=none",
                      "solver.local_tol=none", "solver.force_tol=none", *default_jumps]))


def describe(key: str, value: str) -> str:
    """What a study point is, from its swept key and value (a ``--point``'s value is its overrides)."""
    if key == "reference":
        return "reference"
    if key != "point":
        return {"wear.cycle_jump": "cycle jumps (default bounds), the reference's numerics",
                "wear.acceleration": f"wear acceleration x{value}, the reference's numerics",
                "geometry.contact_mesh_size": f"contact cubes {value} mm, the reference's numerics"}.get(key,
                                                                                                  f"{key} = {value}")
    if "preset=fast" in value:
        return "`solver.preset = fast` (a/2 cubes) + cycle jumps"
    if "acceleration=100" in value:
        return "scene as written + wear acceleration x100 (no jumps)"
    if "jump_wear_fraction=0.025" in value:
        return "scene as written + cycle jumps, bounds / 4"
    if "contact_mesh_size=0.0311" in value:
        return "a/6 cubes (0.0311 mm), 40 increments + cycle jumps"
    return "**the 10^4 run's settings**: scene as written + cycle jumps"


# Machine and timing ---------------------------------------------------------------------------------------
def machine() -> dict:
    """Date, processor, cores, memory and load average of this machine."""
    model = cpu_model()
    mem = ""
    try:
        kb = int(re.search(r"MemTotal:\s+(\d+)", Path("/proc/meminfo").read_text()).group(1))
        mem = f"{kb / 2**20:.0f} GiB"
    except (OSError, AttributeError):
        pass
    return {"date": datetime.datetime.now().isoformat(timespec="seconds"), "processor": model,
            "cores": os.cpu_count(), "memory": mem, "loadavg": [round(x, 2) for x in os.getloadavg()]}


def _time_v(text: str) -> dict:
    """Wall, user, system seconds and peak resident memory from ``/usr/bin/time -v``'s report."""
    def grab(pattern: str) -> str:
        m = re.search(pattern, text)
        return m.group(1) if m else ""

    wall = grab(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): ([\d:.]+)")
    parts = [float(p) for p in wall.split(":")] if wall else []
    seconds = sum(p * 60**i for i, p in enumerate(reversed(parts))) if parts else math.nan
    return {"wall_s": seconds, "user_s": float(grab(r"User time \(seconds\): ([\d.]+)") or "nan"),
            "sys_s": float(grab(r"System time \(seconds\): ([\d.]+)") or "nan"),
            "max_rss_mb": float(grab(r"Maximum resident set size \(kbytes\): (\d+)") or "nan") / 1024}


def timed_run(name: str, sets: list[str], work: Path, skip: bool) -> dict:
    """``/usr/bin/time -v dolfinx-fretting run sphere-flat --out DIR --set ...`` (its log beside DIR)."""
    out = work / name
    command = ["/usr/bin/time", "-v", EXE, "run", SCENE, "--out", str(out), "--overwrite"] + _sets(sets)
    log = work / f"{name}.log"
    record = {"command": "OPENBLAS_NUM_THREADS=1 " + shlex.join(command)}
    if not skip:
        record["loadavg_before"] = [round(x, 2) for x in os.getloadavg()]
        with open(log, "w") as f:
            subprocess.run(command, stdout=f, stderr=subprocess.STDOUT, check=False,
                           env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
        record["loadavg_after"] = [round(x, 2) for x in os.getloadavg()]
        (work / f"{name}.load.json").write_text(json.dumps(record))
    elif (work / f"{name}.load.json").exists():
        record.update(json.loads((work / f"{name}.load.json").read_text()))
    record.update(_time_v(log.read_text()))
    summary = json.loads((out / "summary.json").read_text())
    cycles = _table(out / "cycles.csv")
    record.update(converged=summary["converged"], cycles=summary["cycles"], simulated=int(cycles["cycle"].size),
                  in_run_wall_s=summary["wall_time_s"], cycle_jump=summary.get("cycle_jump"),
                  dofs=summary["dofs"], contacts=summary["contacts"], **quantities(out))
    return record


def run_study(kind: str, work: Path, skip: bool) -> dict:
    out = work / f"study_{kind}"
    args = study_args(kind, out)
    command = [EXE, "study", *args, "--overwrite"]
    record = {"command": "OPENBLAS_NUM_THREADS=1 " + shlex.join(command)}
    if not skip:
        record["loadavg_before"] = [round(x, 2) for x in os.getloadavg()]
        t0 = time.perf_counter()
        with open(work / f"study_{kind}.log", "w") as f:
            subprocess.run(command, stdout=f, stderr=subprocess.STDOUT, check=True,
                           env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
        record["total_s"] = time.perf_counter() - t0
        record["loadavg_after"] = [round(x, 2) for x in os.getloadavg()]
        (work / f"study_{kind}.load.json").write_text(json.dumps(record))
    elif (work / f"study_{kind}.load.json").exists():
        record.update(json.loads((work / f"study_{kind}.load.json").read_text()))
    record["rows"] = analyse_study(out)
    return record


# Quantities and errors ------------------------------------------------------------------------------------
def _table(path: Path) -> np.ndarray:
    return np.atleast_1d(np.genfromtxt(path, names=True, delimiter=",", dtype=None, encoding="utf-8"))


def quantities(folder: Path) -> dict:
    """What a tribologist reads of a run, from its output folder (whole-contact values of the half model)."""
    s = json.loads((folder / "summary.json").read_text())
    cycles = _table(folder / "cycles.csv")
    return {"max_wear_depth": s["max_wear_depth"], "wear_volume": s["wear_volume"],
            "energy_per_cycle": float(cycles["dissipated_energy"][-1]), "contact_radius": s["contact_radius"],
            "max_pressure_end": s["max_pressure"], "equivalent_cycles": s["equivalent_cycles"]}


def wear_map(folder: Path) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) of the contact nodes and their wear gap at the run's last kept increment."""
    prof = _table(folder / "contact_profiles.csv")
    last = prof["increment"] == prof["increment"].max()
    return np.column_stack([prof["position"][last], prof["position_2"][last]]), prof["wear"][last]


ERRORS = ("max_wear_depth", "wear_volume", "energy_per_cycle", "energy_total", "contact_radius", "peak_pressure",
          "wear_map_l2")


def analyse_study(folder: Path) -> list[dict]:
    """Every row of a study with the quantities above and their relative errors against its reference."""
    from dolfinx_fretting.study import map_l2_error, read_study_csv

    rows = read_study_csv(folder / "study.csv")
    ref_folder = folder / "runs" / "reference"
    ref = quantities(ref_folder)
    ref["energy_total"] = rows[0]["dissipated_energy"]
    ref["peak_pressure"] = rows[0]["peak_pressure"]
    xy_ref, w_ref = wear_map(ref_folder)
    out = []
    for r in rows:
        run = folder / "runs" / r["label"]
        q = quantities(run)
        q["energy_total"], q["peak_pressure"] = r["dissipated_energy"], r["peak_pressure"]
        xy, w = wear_map(run)
        summary = json.loads((run / "summary.json").read_text())
        errors = {f"err_{k}": abs(q[k] - ref[k]) / abs(ref[k]) for k in ERRORS if k != "wear_map_l2"}
        errors["err_wear_map_l2"] = map_l2_error(xy, w, xy_ref, w_ref)
        out.append({"label": r["label"], "what": describe(r["key"], r["value"]), "overrides": r["overrides"],
                    "simulated_cycles": int(r["cycles"]), "equivalent_cycles": r["equivalent_cycles"],
                    "wall_time_s": r["wall_time_s"], "speedup": r["speedup"], "dofs": summary["dofs"],
                    "contacts": summary["contacts"], "converged": r["converged"],
                    "jump_wear_error_estimate": (summary.get("cycle_jump") or {}).get("wear_error_estimate"),
                    **q, **errors})
    return out


def run_errors(folder: Path, reference_row: dict, reference_folder: Path) -> dict:
    """The errors of a run outside a study (the timed 10^4 run) against a study's reference, as above."""
    from dolfinx_fretting.study import point_errors

    q = quantities(folder)
    study = point_errors(folder, reference_folder)  # peak pressure of the last cycle, physical-cycle energy, map
    q["energy_total"], q["peak_pressure"] = study["dissipated_energy"], study["peak_pressure"]
    errors = {f"err_{k}": abs(q[k] - reference_row[k]) / abs(reference_row[k]) for k in ERRORS if k != "wear_map_l2"}
    errors["err_wear_map_l2"] = study["err_wear_l2"]
    return {**q, **errors}


# Report ---------------------------------------------------------------------------------------------------
def _pct(v: float) -> str:
    if v is None or not math.isfinite(v):
        return "–"
    return "0" if v == 0 else f"{100 * v:.2g} %" if v >= 1e-4 else f"{v:.1e}"


def study_table(rows: list[dict]) -> list[str]:
    head = ("| point | simulated / physical cycles | dofs, contacts | wall (s) | max wear depth | worn volume | "
            "energy / cycle | energy, all cycles | contact radius | peak pressure | wear map (L2) |")
    lines = [head, "|" + " --- |" * 11]
    for r in rows:
        if r["label"] == "reference":
            vals = (f"{r['max_wear_depth'] * 1e3:.4g} µm", f"{r['wear_volume']:.4g} mm³",
                    f"{r['energy_per_cycle']:.4g} N·mm", f"{r['energy_total']:.5g} N·mm",
                    f"{r['contact_radius']:.4g} mm", f"{r['peak_pressure']:.4g} MPa", "–")
        else:
            vals = tuple(_pct(r[f"err_{k}"]) for k in ERRORS)
        lines.append(f"| {r['what']} | {r['simulated_cycles']} / {r['equivalent_cycles']:.0f} | {r['dofs']}, "
                     f"{r['contacts']} | {r['wall_time_s']:.1f} | " + " | ".join(vals) + " |")
    return lines


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--work", default="/tmp/bench_sphere_flat_10k", help="folder for the runs")
    ap.add_argument("--skip-studies", action="store_true", help="analyse the studies already in --work")
    ap.add_argument("--skip-timed", action="store_true", help="analyse the timed runs already in --work")
    ap.add_argument("--only-timed", action="store_true", help="run the two timed runs and stop (no studies)")
    ap.add_argument("--no-write", action="store_true", help="print, do not write benchmarks/results")
    args = ap.parse_args()
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    command = "OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_sphere_flat_10k.py " + shlex.join(sys.argv[1:])
    start = machine()
    every = timed_run("every_cycle", [f"loading.cycles={EVERY_CYCLE_CYCLES}", "output.xdmf=false",
                                      "output.plots=false"], work, args.skip_timed)
    ten_k = timed_run("ten_k", TEN_K, work, args.skip_timed)
    if args.only_timed:
        print(json.dumps({"every_cycle": every, "ten_k": ten_k}, indent=1, default=float))
        return 0
    studies = {kind: run_study(kind, work, args.skip_studies) for kind in ("short", "long")}
    # The results file starts with what made it: every command, the date, the machine and its load.
    result = {"commands": [every["command"], ten_k["command"], studies["short"]["command"],
                           studies["long"]["command"], command],
              "machine_at_start": start, "machine_at_end": machine(),
              "loadavg": {name: {k: rec.get(k) for k in ("loadavg_before", "loadavg_after", "note")}
                          for name, rec in [("every_cycle", every), ("ten_k", ten_k),
                                            ("study_short", studies["short"]), ("study_long", studies["long"])]},
              "every_cycle": every, "ten_k": ten_k, "studies": studies}
    ten_k["errors_against_long_reference"] = run_errors(work / "ten_k", studies["long"]["rows"][0],
                                                        work / "study_long" / "runs" / "reference")
    tables = []
    for kind, study in studies.items():
        tables += [f"## {kind}", "", *study_table(study["rows"]), ""]
    e = ten_k["errors_against_long_reference"]
    tables += ["## the timed 10^4 run against the long study's reference", "",
               " | ".join(f"{k}: {_pct(e[f'err_{k}'])}" for k in ERRORS), ""]
    (work / "tables.md").write_text("\n".join(tables))
    print("\n".join(tables))
    text = json.dumps(result, indent=1, default=float)
    if args.no_write:
        print(text)
        return 0
    (HERE / "results" / "sphere_flat_10k.json").write_text(text + "\n")
    print(f"wrote {HERE / 'results' / 'sphere_flat_10k.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
