"""Sphere-on-flat in 3D: today's mesh (cubes a deep under the contact) against the depth-graded one
(``meshes_3d.sphere_on_flat(..., depth_growth=g, coarsening=c)``) at the same contact-face step h.

Both meshes have the same contact face (nodes h apart over the uniform zone, both bodies); the graded one has
layers h thick at the face growing by g and 3:1 lateral transitions with depth. For each a/h (Hertz radius over
h) and each mesh, alternated in one process so that the shared machine's load hits both alike:

* the two-body model of ``tests/support/sphere.py`` (steel ball R = 10 mm on a steel flat, P = 100 N, half
  model, mu = 0.5, Archard k = 1e-6 1/MPa, candidate window 1.4 a + h): dofs, contacts, wall time of the set-up
  (K's MUMPS factorisation and W by the package's route ``auto``, read from the Delassus operator's stats),
  MUMPS's factor memory (INFOG(22));
* Hertz (Johnson §4.2) pressed by P: peak nodal pressure over p0, the loaded area's equivalent radius and the
  farthest loaded node against a (in h);
* Cattaneo-Mindlin (Johnson §7.2), Q = 0.5 mu P by force from the pressed state: the sticking area's equivalent
  radius against c = a (1 - 0.5)^(1/3);
* gross slip from the pressed state: ``--cycles`` triangular cycles of +-20 um (16 increments): the worn volume;
* ``--field-cell`` the graded meshes' largest cell over a down to a (one graded mesh each);
* with ``--rigid``, the rigid-plane model too (the sphere alone): Hertz's peak and radius.

``--setup-only`` sizes build the two-body model and time its set-up only (no solve): the largest contact count
whose set-up fits in a minute.

Usage (from the repository root)::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_graded_3d.py --a-over-h 4 8 --rigid
    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_graded_3d.py --setup-only --a-over-h 16 20 24
"""

from __future__ import annotations

import argparse
import datetime
import gc
import json
import os
import shlex
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parent / "tests"))

from mpi4py import MPI  # noqa: E402  (first: the 0.11 wheel needs the MPI library mpi4py loads)

import dolfinx_fretting as dfr  # noqa: E402
from support.sphere import P, contact_radii, pressed, sphere_model  # noqa: E402

STROKE_MM = 0.02
INCREMENTS = 16


def log(*args) -> None:
    print(*args, flush=True)


def load_average() -> list[float]:
    return [round(v, 2) for v in os.getloadavg()]


def variants(args) -> list[tuple[str, dict]]:
    runs = [("uniform", {})]
    for field in args.field_cell:
        runs.append((f"graded g={args.depth_growth:g} c={args.coarsening} field={field:g}a",
                     {"depth_growth": args.depth_growth, "coarsening": args.coarsening, "field_cell": field}))
    return runs


def two_body(a_over_h: float, options: dict, args) -> dict:
    rec: dict = {"load_start": load_average()}
    start, cpu_start = time.perf_counter(), time.process_time()
    body, problem, a, p0, h = sphere_model(a_over_h, 9.0, 1.5, flat=True, mu=0.5, wear=dfr.Archard(1e-6),
                                           **options)
    state = problem.initial_state()
    # CPU time of this process (MUMPS and BLAS on one thread): less sensitive than wall time to the shared
    # machine's other jobs
    rec["model_s"], rec["model_cpu_s"] = time.perf_counter() - start, time.process_time() - cpu_start
    d = problem.operators.delassus
    rec.update(dofs=int(problem.n_dofs), contacts=int(problem.contact.nc),
               factorize_s=float(d.stats.get("factorize_time", np.nan)),
               W_s=float(d.stats.get("last_build_time", np.nan)), route=d.stats.get("last_build_route"),
               mumps_mb=float(d.stats.get("mumps_memory_mb", np.nan)),
               factor_entries=int(d.stats.get("factor_entries", 0)), a=a, h=h)
    rec["setup_s"] = rec["factorize_s"] + rec["W_s"]
    log(f"  {rec['dofs']} dofs, {rec['contacts']} contacts: factorise {rec['factorize_s']:.2f} s, W "
        f"{rec['W_s']:.2f} s ({rec['route']}), MUMPS {rec['mumps_mb']:.0f} MB, {rec['factor_entries']:.3g} factor "
        f"entries, model {rec['model_s']:.1f} s ({rec['model_cpu_s']:.1f} s CPU)")
    if not args.setup_only:
        pressed_state = pressed(problem, P / 2)
        a_eq, r_max, p_max = contact_radii(problem, pressed_state)
        rec.update(peak_over_p0=p_max / p0, a_eq_minus_a_over_h=(a_eq - a) / h, r_max_minus_a_over_h=(r_max - a) / h)
        state = pressed_state
        mu, phi = 0.5, 0.5
        for f in (0.5, 1.0):
            state = problem.commit(state, problem.solve(
                state, tangential=(dfr.Force(f * phi * mu * P / 2), dfr.Displacement(0.0))))
        fields = problem.contact_fields(state)
        stick = fields["status"] == 1
        c_ref = a * (1 - phi) ** (1 / 3)
        rec["stick_radius_over_c"] = float(np.sqrt(2 * problem.contact.contact_set.tributary[stick].sum() / np.pi)
                                           / c_ref)
        state = pressed_state
        start = time.perf_counter()
        for _ in range(args.cycles):
            cycle = problem.run_cycle(state, dfr.CyclePath.waveform(INCREMENTS, normal=state.obstacle[0],
                                                                    tangential=[STROKE_MM, 0.0]))
            state = problem.commit(state, cycle)
        rec["wear_s"] = time.perf_counter() - start
        rec["worn_volume"] = float(state.record["wear_area"]) * 2.0  # the whole ball (half model)
        rec["dissipated_last_cycle"] = 2.0 * float(cycle.records["dissipated_energy"].sum())
        rec["wear_peak"] = float(problem.contact_fields(state)["wear"].max())
        log(f"  Hertz peak/p0 {rec['peak_over_p0']:.5f}, (a_eq - a)/h {rec['a_eq_minus_a_over_h']:+.3f}, "
            f"(r_max - a)/h {rec['r_max_minus_a_over_h']:+.3f}; stick radius / c {rec['stick_radius_over_c']:.4f}; "
            f"worn volume {rec['worn_volume']:.6e} mm^3 (peak depth {rec['wear_peak']:.4e} mm) in "
            f"{rec['wear_s']:.1f} s")
    problem.destroy()
    del problem, body
    gc.collect()
    rec["load_end"] = load_average()
    return rec


def rigid(a_over_h: float, options: dict) -> dict:
    body, problem, a, p0, h = sphere_model(a_over_h, 9.0, 1.5, flat=False, **options)
    state = pressed(problem, P / 2)
    a_eq, r_max, p_max = contact_radii(problem, state)
    rec = dict(dofs=int(problem.n_dofs), peak_over_p0=p_max / p0,
               a_eq_minus_a_over_h=(a_eq - a) / h, r_max_minus_a_over_h=(r_max - a) / h)
    log(f"  rigid plane: {rec['dofs']} dofs, peak/p0 {rec['peak_over_p0']:.5f}, (a_eq - a)/h "
        f"{rec['a_eq_minus_a_over_h']:+.3f}, (r_max - a)/h {rec['r_max_minus_a_over_h']:+.3f}")
    problem.destroy()
    del problem, body
    gc.collect()
    return rec


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--a-over-h", type=float, nargs="+", default=[4.0, 8.0])
    parser.add_argument("--depth-growth", type=float, default=1.5)
    parser.add_argument("--coarsening", type=int, default=2)
    parser.add_argument("--field-cell", type=float, nargs="+", default=[0.125, 0.25])
    parser.add_argument("--cycles", type=int, default=2)
    parser.add_argument("--rigid", action="store_true", help="the rigid-plane Hertz model too")
    parser.add_argument("--setup-only", action="store_true", help="time the set-up only (no solve)")
    parser.add_argument("--graded-only", action="store_true", help="the graded mesh only (sizes too big for today's)")
    parser.add_argument("--out", default=None, help="append the records (JSON lines) to this file")
    args = parser.parse_args()
    command = "OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_graded_3d.py " + shlex.join(sys.argv[1:])
    log(command, datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"), load_average())
    records = []
    for n, a_over_h in enumerate(args.a_over_h):
        runs = variants(args)[1:] if args.graded_only else variants(args)
        if n % 2:  # alternate the order: neither mesh always runs first
            runs = runs[::-1]
        for name, options in runs:
            log(f"a/h = {a_over_h:g}, {name}")
            rec = {"a_over_h": a_over_h, "mesh": name, **two_body(a_over_h, options, args)}
            if args.rigid and not args.setup_only:
                rec["rigid"] = rigid(a_over_h, options)
            records.append(rec)
            if args.out:
                with open(args.out, "a") as out:
                    out.write(json.dumps({"command": command, **rec}) + "\n")


if __name__ == "__main__":
    main()
