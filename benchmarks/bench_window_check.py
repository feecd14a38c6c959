"""What the window check (issue 22) costs, in one process: the outside rows' build and the check itself.

A ``Contact(..., window=w)`` watches the nodes of its surface outside the window (``operators.outside``): the
contact makes a second search of the whole surface (to know them), the operators form ``C = H_out K^-1 H^T`` from
entries of the one factor of K (``DelassusOperator.coupling``), and every increment (every increment of a compiled
cycle, in one product) is checked. For each scene (default sizes, through the scene runner's model) this script
measures, in CPU seconds (``time.process_time``, best of ``--repeat``; BLAS and numba single-threaded):

- the contact's construction with its window, and a search of the whole surface alone (``window=None``: what the
  second search costs);
- W and the load responses with the outside rows (the operators' build), and the outside rows alone;
- one compiled cycle of the scene's path and its check; one increment's check.

A scene without a window (``stromberg-block``: the main job) has nothing outside and nothing to measure.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_window_check.py [--scenes cylinder-flat sphere-flat]
        [--repeat 5] [--out benchmarks/results/window_check_inprocess]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import ContactModel, _cycle_path  # noqa: E402


def best_of(fn, repeat: int) -> tuple[object, float]:
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t0)
    return out, best


def measure(name: str, repeat: int) -> dict:
    scene = load_scene(name, ["output.xdmf=false", "output.plots=false"])
    model = ContactModel(scene, MPI.COMM_WORLD)
    problem, ops, setup = model.problem, model.problem.operators, model.setup
    row = {"scene": name, "window": model.half_width, "contacts": model.contact.nc,
           "outside": 0 if ops.outside is None else int(ops.outside.nodes.nc)}
    if ops.outside is None:
        return row
    bcs = setup.bcs + [bc for conditions in setup.prescribed.values() for bc in conditions]
    contact, row["contact_s"] = best_of(lambda: dfr.Contact(setup.V, setup.surface, setup.obstacle, scene.contact.mu,
                                                            bcs, model.half_width), repeat)
    _, row["whole_surface_search_s"] = best_of(lambda: contact.with_window(None), repeat)
    _, row["operators_build_s"] = best_of(ops.build, repeat)
    _, row["outside_rows_s"] = best_of(lambda: ops._watch_outside(ops.outside.responses), repeat)

    lo = scene.loading
    state = problem.initial_state()
    for k in range(1, lo.normal_increments + 1):
        target = (dfr.Force(lo.normal_force * k / lo.normal_increments * setup.model_fraction)
                  if lo.normal_force is not None else dfr.Displacement(lo.normal_displacement * k / lo.normal_increments))
        state, _ = problem.advance(state, normal=target)
    path = _cycle_path(scene, model)
    state = problem.commit(state, problem.run_cycle(state, path))   # the first cycle compiles and warms up
    result, row["cycle_s"] = best_of(lambda: problem.run_cycle(state, path, keep=True), repeat)
    forces = result.kept[0]
    obstacle, factors = result.obstacle, result.load_factors
    _, row["cycle_check_s"] = best_of(lambda: ops.check_window(forces, obstacle, factors, problem.solver.tol,
                                                               cycle=True), max(repeat, 50))
    _, row["increment_check_s"] = best_of(lambda: ops.check_window(forces[:1], obstacle[:1], factors[:1],
                                                                   problem.solver.tol), max(repeat, 50))
    row["increments_per_cycle"] = int(path.increments)
    row["cycle_check_share"] = row["cycle_check_s"] / row["cycle_s"]
    problem.destroy()
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", nargs="+", default=["stromberg-block", "hertz", "cylinder-flat", "sphere-flat"])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--out", default=None, help="stem of the .json and .md written (default: print only)")
    args = parser.parse_args()
    rows = [measure(name, args.repeat) for name in args.scenes]
    lines = ["| scene | window (mm) | contacts | outside nodes | Contact with window (s) | of which the whole-surface "
             "search (s) | W + responses + outside rows (s) | outside rows (s) | compiled cycle (s) | its check (s) | "
             "share | one increment's check (s) |", "|" + " --- |" * 12]
    for r in rows:
        if not r["outside"]:
            lines.append(f"| {r['scene']} | {r['window']} | {r['contacts']} | 0 | - | - | - | - | - | - | - | - |")
            continue
        lines.append(f"| {r['scene']} | {r['window']:.4g} | {r['contacts']} | {r['outside']} | {r['contact_s']:.3f} | "
                     f"{r['whole_surface_search_s']:.3f} | {r['operators_build_s']:.3f} | {r['outside_rows_s']:.3f} | "
                     f"{r['cycle_s']:.3f} ({r['increments_per_cycle']} inc.) | {r['cycle_check_s']:.2e} | "
                     f"{100 * r['cycle_check_share']:.2f} % | {r['increment_check_s']:.1e} |")
    table = "\n".join(lines)
    print(table)
    if args.out:
        Path(args.out).with_suffix(".json").write_text(json.dumps(rows, indent=1))
        Path(args.out).with_suffix(".md").write_text(table + "\n")


if __name__ == "__main__":
    main()
