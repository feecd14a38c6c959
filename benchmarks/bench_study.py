"""The speed-vs-accuracy trade study (``dolfinx-fretting study``) on Example 1 and Example 2, elastic.

Scenes and their reductions (the full runs would not fit the ~40 min budget of this 2-core machine):

* ``stromberg-block`` (Example 1): 3000 of its 9000 cycles;
* ``cylinder-flat`` (Example 2, gross slip) and ``cylinder-flat-partial`` (partial slip): 40 of their 100
  cycles.

Each study runs the study's default reference (contact elements halved, twice the increments per cycle,
``local_tol`` 1e-12, force tolerance 1e-10 under force control; Example 1 keeps its 1 mm elements, see
:data:`REFERENCE`) and its default sweep (contact elements 2x
and 4x the reference's, a half and a quarter of its increments, ``local_tol`` 1e-8 and 1e-6) plus: the
scene as written, contact elements 8x the reference's, an eighth of its increments, and wear accelerations
(Example 1: 10, 100, 1000; Example 2: 2, 5, 10), every point compared at equal physical cycles.
``--presets`` runs instead the reference, the scene as written and the three ``solver.preset`` values
(with the scene's own numerics keys removed so that the preset supplies them).

Usage::

    .venv/bin/python benchmarks/bench_study.py [--scenes stromberg-block cylinder-flat cylinder-flat-partial]
        [--presets] [--work DIR]

Writes ``benchmarks/results/study_<scene>.md`` and ``.png`` (``study_<scene>_presets.*`` with
``--presets``) and the tables as ``.csv``.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import shlex
import shutil
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.study import (default_reference, default_sweep, format_markdown, plan_study,  # noqa: E402
                                    plot_study, read_study_csv, run_study)

#: Reduced cycle counts (the built-in scenes have 9000 and 100).
CYCLES = {"stromberg-block": 3000, "cylinder-flat": 40, "cylinder-flat-partial": 40}
#: Reference overrides replacing the default's (None: the default reference). Example 1 keeps its own 1 mm
#: elements: at nx = ny = 100 the compiled loop's Uzawa stalls at the first load reversal (step 40 of 80:
#: error 4e-2 after 20000 sweeps, at local_tol 1e-10 and 1e-12 alike, measured here).
REFERENCE = {"stromberg-block": ["geometry.nx=50", "geometry.ny=50", "loading.increments_per_cycle=160",
                                 "solver.local_tol=1e-12"]}
ACCELERATIONS = {"stromberg-block": (10, 100, 1000), "cylinder-flat": (2, 5, 10),
                 "cylinder-flat-partial": (2, 5, 10)}
#: The numerics keys a preset supplies, removed from the scene for the preset points.
PRESET_KEYS = {"half_cylinder": ["geometry.contact_mesh_size"], "rectangle": ["geometry.nx", "geometry.ny"]}
PRESET_KEYS_COMMON = ["loading.increments_per_cycle", "solver.local_tol", "solver.force_tol"]


def as_written(name: str) -> list[str]:
    """Overrides that bring the reference back to the scene's own numerics."""
    sc = load_scene(name)
    g, out = sc.geometry, []
    if g.kind == "half_cylinder":
        out.append(f"geometry.contact_mesh_size={g.contact_mesh_size:g}")
    else:
        out += [f"geometry.nx={g.nx}", f"geometry.ny={g.ny}"]
    out += [f"loading.increments_per_cycle={sc.loading.increments_per_cycle}",
            f"solver.local_tol={sc.solver.local_tol:g}", f"solver.force_tol={sc.solver.force_tol:g}"]
    return out


def reference_for(name: str, scene) -> list[str]:
    return REFERENCE.get(name) or default_reference(scene)


def entries_for(name: str, presets: bool) -> list:
    base = [f"loading.cycles={CYCLES[name]}"]
    scene = load_scene(name, base)
    ref = load_scene(name, base + reference_for(name, scene))
    written = ("scene", "as written", as_written(name))
    if presets:
        kind = ref.geometry.kind
        unset = [f"{k}=none" for k in PRESET_KEYS[kind] + PRESET_KEYS_COMMON]
        return [written] + [("solver.preset", p, unset + [f"solver.preset={p}"])
                            for p in ("accurate", "balanced", "fast")]
    # local_tol 1e-10 is the scenes' own (the "as written" point); the accelerations are set below
    entries = [e for e in default_sweep(ref) if e[0] != "wear.acceleration" and e[1:2] != ("1e-10",)]
    g, lo = ref.geometry, ref.loading
    if g.kind == "half_cylinder":
        h = f"{g.contact_mesh_size * 8:.6g}"
        entries.append(("geometry.contact_mesh_size", h, [f"geometry.contact_mesh_size={h}"]))
    else:
        entries.append(("geometry.nx", f"{g.nx // 8}", [f"geometry.nx={g.nx // 8}", f"geometry.ny={g.ny // 8}"]))
    n8 = max(4, 4 * round(lo.increments_per_cycle / 32))
    entries.append(("loading.increments_per_cycle", str(n8), [f"loading.increments_per_cycle={n8}"]))
    entries += [("wear.acceleration", str(s), [f"wear.acceleration={s}"]) for s in ACCELERATIONS[name]]
    return [written] + entries


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", nargs="+", default=list(CYCLES), choices=list(CYCLES))
    ap.add_argument("--presets", action="store_true", help="reference, scene as written and the three presets")
    ap.add_argument("--replot", action="store_true",
                    help="only redraw results/study_<scene>*.png from the .csv next to it")
    ap.add_argument("--work", default=None, help="folder for the runs (default: a temporary folder)")
    args = ap.parse_args()
    command = "OPENBLAS_NUM_THREADS=1 nice -n 10 .venv/bin/python benchmarks/bench_study.py " + shlex.join(sys.argv[1:])
    work = Path(args.work) if args.work else Path(tempfile.mkdtemp(prefix="bench_study_"))
    results = HERE / "results"
    results.mkdir(exist_ok=True)
    suffix = "_presets" if args.presets else ""
    if args.replot:
        for name in args.scenes:
            stem = results / f"study_{name}{suffix}"
            rows = read_study_csv(stem.with_suffix(".csv"))
            plot_study(rows, stem.with_suffix(".png"), title=f"{name}: wall time against error "
                                                             f"(reference: {rows[0]['wall_time_s']:.1f} s)")
            print(f"redrew {stem}.png")
        return 0
    for name in args.scenes:
        base = [f"loading.cycles={CYCLES[name]}"]
        plan = plan_study(name, base, reference_for(name, load_scene(name, base)),
                          entries=entries_for(name, args.presets))
        t0 = time.perf_counter()
        rows = run_study(plan, work / f"{name}{suffix}")
        total = time.perf_counter() - t0
        stem = results / f"study_{name}{suffix}"
        shutil.copyfile(work / f"{name}{suffix}" / "study.png", stem.with_suffix(".png"))
        shutil.copyfile(work / f"{name}{suffix}" / "study.csv", stem.with_suffix(".csv"))
        full = load_scene(name)
        lines = [
            f"# Trade study: `{name}`{' (presets)' if args.presets else ''}", "",
            f"Command: `{command}` (this scene's part: {total:.0f} s including the warm-up run)", "",
            f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}; machine: {platform.processor() or platform.machine()}, "
            f"{os.cpu_count()} cores, **shared** with other jobs while it ran (wall times are noisy; the "
            "speed-ups are ratios of runs made one after the other in one process).", "",
            f"Reduced: {CYCLES[name]} physical cycles (the scene has {full.loading.cycles}); elastic material. "
            "Errors are relative to the reference, at the end of the run and at equal physical cycles "
            "(a point with wear acceleration s simulates cycles/s); see `docs/study.md` for their "
            "definitions.", "",
            f"Reference overrides: `{' '.join(plan[0].overrides)}`", "",
            format_markdown(rows), "",
            f"![time vs error](study_{name}{suffix}.png)", "",
        ]
        stem.with_suffix(".md").write_text("\n".join(lines))
        print(f"wrote {stem}.md ({total:.0f} s)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
