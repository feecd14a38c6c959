"""What a finite-sliding re-pairing costs with mortar against node-to-segment pairing, per increment, 2D.

The cylinder-flat scene's model (the cylinder R = 6 mm on the 20 x 10 mm flat, both elastic, contact elements of
``--mesh-size`` mm) as an API problem, ``ElasticBody(sliding="finite", formulation=...)``, pressed to P = 199.24
N/mm and slid in gross slip by a quarter element per increment (every increment re-pairs: ``repair_slip`` 0.1).
Measured in this process, CPU time (``time.process_time``) per increment, medians over the increments:

- ``solve``: ``problem.solve`` (the first solve on a new pairing forms its W = L C L^T and load responses there);
- ``commit``: ``problem.commit``, which re-pairs (node: the closest points; mortar: D and M integrated anew);
- and, on the last state, the re-pairing alone (``sliding.repair``) and the forming of W alone
  (``SurfaceCompliance.operators``), each repeated ``--repeats`` times (median).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_mortar_sliding.py [--increments 20] [--repeats 20] \
        [--mesh-size 0.02] [--out benchmarks/results/mortar_sliding]
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import dolfinx_fretting as dfr  # noqa: E402
from _machine import cpu_model  # noqa: E402
from dolfinx_fretting import sliding  # noqa: E402
from dolfinx_fretting.contact import Contact  # noqa: E402
from dolfinx_fretting.geometries import build_scene_model  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402

P, MU = 199.24, 0.3


def cpu(function, *args, **kwargs):
    """(the result, the CPU seconds of one call)."""
    start = time.process_time()
    result = function(*args, **kwargs)
    return result, time.process_time() - start


def measure(model, formulation: str, increments: int, repeats: int, h: float) -> dict:
    obstacle = dataclasses.replace(model.obstacle, sliding="finite", reach=0.4, formulation=formulation,
                                   repair_slip=0.1)
    contact = Contact(model.V, model.surface, obstacle, MU, model.bcs, 0.45)
    problem = dfr.FrettingProblem(model.form, contact, model.bcs, solver=dfr.LocalSolver(tol=1e-10))
    problem.sliding.warn = False
    state = problem.initial_state()
    for load in (0.5 * P, P):
        state = problem.commit(state, problem.solve(state, normal=dfr.Force(load)))
    # into gross slip first (not timed), then a quarter element per increment
    start = 4 * MU * P / 2e5 + 0.02
    state = problem.commit(state, problem.solve(state, tangential=start))
    solves, commits = [], []
    repairs_before = problem.sliding.repairs
    for k in range(1, increments + 1):
        result, seconds = cpu(problem.solve, state, tangential=start + 0.25 * h * k)
        solves.append(seconds)
        state, seconds = cpu(problem.commit, state, result)
        commits.append(seconds)
    operators = problem.operators
    compliance = operators.surface_compliance
    u = compliance.displacement(state.pairing, state.forces, state.load_factors)
    D = operators.obstacle_translation(state.obstacle)
    repair = statistics.median(cpu(sliding.repair, state.pairing, compliance, u, D)[1] for _ in range(repeats))
    forming = statistics.median(cpu(compliance.operators, state.pairing)[1] for _ in range(repeats))
    stats = operators.delassus.stats
    answer = {"contacts": int(state.pairing.nc), "surface_nodes": int(compliance.nodes.size),
              "master_nodes_per_contact": int(state.pairing.master_nodes.shape[1]),
              "repairs": problem.sliding.repairs - repairs_before, "increments": increments,
              "solve_s": statistics.median(solves), "commit_s": statistics.median(commits),
              "repair_alone_s": repair, "W_forming_s": forming,
              "factorizations": stats["factorizations"], "refactorizations": stats["refactorizations"],
              "total_force": problem.total_force(state).tolist()}
    problem.destroy()
    return answer


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--increments", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--mesh-size", type=float, default=0.02)
    parser.add_argument("--out", default=str(HERE / "results" / "mortar_sliding"))
    args = parser.parse_args()
    model = build_scene_model(load_scene("cylinder-flat", [f"geometry.contact_mesh_size={args.mesh_size}"]),
                              MPI.COMM_WORLD)
    results = {formulation: measure(model, formulation, args.increments, args.repeats, args.mesh_size)
               for formulation in ("node", "mortar")}
    load = os.getloadavg()
    command = ("OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_mortar_sliding.py "
               f"--increments {args.increments} --repeats {args.repeats} --mesh-size {args.mesh_size}")
    lines = [f"## Finite sliding: a re-pairing with mortar against node-to-segment (2D, cylinder on flat, "
             f"h = {args.mesh_size} mm)", "",
             f"Command: `{command}`", "",
             f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}; machine: {platform.machine()}, "
             f"{cpu_model()}, {os.cpu_count()} cores; Python {platform.python_version()}, numpy {np.__version__}; "
             f"load average at the end {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f}. CPU time of this process, "
             "medians per increment (gross slip, a quarter element per increment, every increment re-paired).", "",
             "| formulation | contacts | surface nodes | master nodes per contact | re-pairings / increments | "
             "solve (ms) | commit incl. re-pairing (ms) | re-pairing alone (ms) | W = L C Lᵀ (ms) | "
             "factorisations (refactorisations) |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for formulation, r in results.items():
        lines.append(f"| {formulation} | {r['contacts']} | {r['surface_nodes']} | {r['master_nodes_per_contact']} | "
                     f"{r['repairs']} / {r['increments']} | {1e3 * r['solve_s']:.2f} | {1e3 * r['commit_s']:.2f} | "
                     f"{1e3 * r['repair_alone_s']:.2f} | {1e3 * r['W_forming_s']:.2f} | "
                     f"{r['factorizations']} ({r['refactorizations']}) |")
    ratio = results["mortar"]["repair_alone_s"] / results["node"]["repair_alone_s"]
    lines += ["", f"Re-pairing alone, mortar / node: {ratio:.1f}x."]
    out = Path(args.out)
    out.with_suffix(".json").write_text(json.dumps({"command": command, "results": results}, indent=2) + "\n")
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
