"""What friction that evolves (``EvolvingFriction``) costs in the compiled cycle loop, in one process.

A law of the cycles holds mu over a cycle, so the loop still runs the cycle in one compiled call; a law of the
energy changes mu after every increment, so the loop runs one increment per call with each contact's energy, mu
and the wear rate updated in Python between the calls. For each scene (default sizes, through the scene runner's
model; the cylinder under a prescribed approach) this script measures one compiled cycle of the scene's path after a warm-up cycle, in CPU seconds
(``time.process_time``, best of ``--repeat``; BLAS and numba single-threaded), with three friction laws of the
same constant coefficient (so each does the same arithmetic on the same values):

- ``contact.mu`` (Coulomb, the reference);
- ``contact.mu_table`` constant, ``mu_variable = "cycles"`` (one call per cycle);
- ``contact.mu_table`` constant, ``mu_variable = "energy"`` (one call per increment).

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_evolving_friction.py [--scenes cylinder-flat]
        [--repeat 5] [--out benchmarks/results/evolving_friction]
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
from _machine import cpu_model  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import ContactModel, _cycle_path  # noqa: E402

#: Displacement control, so that the cycles run in the compiled loop (a scene's prescribed force runs increment by
#: increment); the cylinder's approach is tests/test_cycle_jump.py's.
EXTRA = {"cylinder-flat": ["loading.normal_force=none", "loading.normal_displacement=0.0045"]}
LAWS = {"coulomb": [], "table of the cycles": ["contact.mu_variable='cycles'"],
        "table of the energy": ["contact.mu_variable='energy'"]}


def best_of(fn, repeat: int) -> tuple[object, float]:
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t0)
    return out, best


def measure(name: str, law: str, repeat: int) -> dict:
    base = load_scene(name, EXTRA.get(name, []))
    mu = base.contact.mu
    table = [] if law == "coulomb" else [f"contact.mu_table=[[0, {mu}], [1, {mu}]]"]
    scene = load_scene(name, ["output.xdmf=false", "output.plots=false", *EXTRA.get(name, []), *table, *LAWS[law]])
    model = ContactModel(scene, MPI.COMM_WORLD)
    problem, setup = model.problem, model.setup
    lo = scene.loading
    state = problem.initial_state()
    for k in range(1, lo.normal_increments + 1):
        target = (dfr.Force(lo.normal_force * k / lo.normal_increments * setup.model_fraction)
                  if lo.normal_force is not None else dfr.Displacement(lo.normal_displacement * k / lo.normal_increments))
        state, _ = problem.advance(state, normal=target)
    path = _cycle_path(scene, model)
    state = problem.commit(state, problem.run_cycle(state, path))   # the first cycle compiles and warms up
    result, seconds = best_of(lambda: problem.run_cycle(state, path), repeat)
    row = {"scene": name, "law": law, "contacts": model.contact.nc, "increments_per_cycle": int(path.increments),
           "compiled": bool(result.compiled), "cycle_s": seconds,
           "local_iterations": int(result.records["local_iterations"].sum())}
    problem.destroy()
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", nargs="+", default=["cylinder-flat", "stromberg-block"])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--out", default=None, help="stem of the .json and .md written (default: print only)")
    args = parser.parse_args()
    rows = [measure(name, law, args.repeat) for name in args.scenes for law in LAWS]
    lines = [f"`OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_evolving_friction.py --scenes "
             f"{' '.join(args.scenes)} --repeat {args.repeat} --out benchmarks/results/evolving_friction`, "
             f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {cpu_model()} (one process, CPU time)", "",
             "| scene | contacts | increments | friction | compiled cycle (CPU s) | / Coulomb | local iterations |",
             "|" + " --- |" * 7]
    reference = {}
    for r in rows:
        if r["law"] == "coulomb":
            reference[r["scene"]] = r["cycle_s"]
        ratio = r["cycle_s"] / reference[r["scene"]]
        lines.append(f"| {r['scene']} | {r['contacts']} | {r['increments_per_cycle']} | {r['law']} | "
                     f"{r['cycle_s']:.4f} | {ratio:.2f} | {r['local_iterations']} |")
    lines += ["", "A table of the energy runs the compiled loop one increment per call (mu, the energy and the wear rate "
              "updated in Python between calls): the difference to Coulomb over the cycle's increments is that "
              "overhead per increment. A table of the cycles runs one call per cycle, as Coulomb."]
    table = "\n".join(lines)
    print(table)
    if args.out:
        Path(args.out).with_suffix(".json").write_text(json.dumps(rows, indent=1))
        Path(args.out).with_suffix(".md").write_text(table + "\n")


if __name__ == "__main__":
    main()
