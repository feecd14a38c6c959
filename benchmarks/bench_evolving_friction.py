"""What friction that evolves (``EvolvingFriction``) costs in the compiled cycle loop, in one process.

A law of the cycles holds mu over a cycle, so the loop runs the cycle in one compiled call; a law of the energy
changes mu after every increment: a table of it runs inside the compiled loop too (one call per cycle, mu, the
energy and the wear rate updated in the loop), the user's function of it runs one increment per call with them
updated in Python between the calls. For each scene (default sizes, through the scene runner's model; the
cylinder under a prescribed approach) this script measures one compiled cycle of the scene's path after a warm-up
cycle, in CPU seconds (``time.process_time``; BLAS and numba single-threaded), with four friction laws of the same
constant coefficient (so each does the same arithmetic on the same values), the laws alternated within each of
``--repeat`` rounds (so the machine's load falls on all alike; best and median over the rounds):

- ``contact.mu`` (Coulomb, the reference);
- ``contact.mu_table`` constant, ``mu_variable = "cycles"`` (one call per cycle);
- ``contact.mu_table`` constant, ``mu_variable = "energy"`` (one call per cycle: the table inside the loop);
- the same table as a Python function of the energy (``np.interp``; one call per increment).

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_evolving_friction.py [--scenes cylinder-flat]
        [--repeat 5] [--out benchmarks/results/evolving_friction]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path
from unittest import mock

import numpy as np
from mpi4py import MPI

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import dolfinx_fretting as dfr  # noqa: E402
from _machine import cpu_model  # noqa: E402
from dolfinx_fretting.scenes import ContactSettings, load_scene  # noqa: E402
from dolfinx_fretting.simulation import ContactModel, _cycle_path  # noqa: E402

#: Displacement control, so that the cycles run in the compiled loop (a scene's prescribed force runs increment by
#: increment); the cylinder's approach is tests/test_cycle_jump.py's.
EXTRA = {"cylinder-flat": ["loading.normal_force=none", "loading.normal_displacement=0.0045"]}
LAWS = {"coulomb": [], "table of the cycles": ["contact.mu_variable='cycles'"],
        "table of the energy": ["contact.mu_variable='energy'"],
        "function of the energy": ["contact.mu_variable='energy'"]}


def function_law(settings: ContactSettings) -> dfr.EvolvingFriction:
    """The scene's table as the user's Python function of the energy (what the compiled loop cannot call)."""
    abscissae, values = np.array(settings.mu_table, dtype=float).T
    return dfr.EvolvingFriction(lambda energy: np.interp(energy, abscissae, values), variable="energy")


def prepare(name: str, law: str):
    """(problem, state after the preload and a warm-up cycle, the cycle's path, the model) of one law."""
    base = load_scene(name, EXTRA.get(name, []))
    mu = base.contact.mu
    table = [] if law == "coulomb" else [f"contact.mu_table=[[0, {mu}], [1, {mu}]]"]
    scene = load_scene(name, ["output.xdmf=false", "output.plots=false", *EXTRA.get(name, []), *table, *LAWS[law]])
    if law == "function of the energy":
        with mock.patch.object(ContactSettings, "friction_law", function_law):
            model = ContactModel(scene, MPI.COMM_WORLD)
    else:
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
    return problem, state, path, model


def measure(name: str, repeat: int) -> list[dict]:
    """Each law's cycle, the laws alternated in each of ``repeat`` rounds (CPU seconds: best and median)."""
    prepared = {law: prepare(name, law) for law in LAWS}
    times: dict[str, list[float]] = {law: [] for law in LAWS}
    results = {}
    for _ in range(repeat):
        for law, (problem, state, path, _model) in prepared.items():
            t0 = time.process_time()
            results[law] = problem.run_cycle(state, path)
            times[law].append(time.process_time() - t0)
    rows = []
    for law, (problem, _state, path, model) in prepared.items():
        result = results[law]
        rows.append({"scene": name, "law": law, "contacts": model.contact.nc,
                     "increments_per_cycle": int(path.increments), "compiled": bool(result.compiled),
                     "cycle_s": min(times[law]), "cycle_s_median": statistics.median(times[law]),
                     "local_iterations": int(result.records["local_iterations"].sum())})
        problem.destroy()
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", nargs="+", default=["cylinder-flat", "stromberg-block"])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--out", default=None, help="stem of the .json and .md written (default: print only)")
    args = parser.parse_args()
    rows = [row for name in args.scenes for row in measure(name, args.repeat)]
    lines = [f"`OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_evolving_friction.py --scenes "
             f"{' '.join(args.scenes)} --repeat {args.repeat} --out benchmarks/results/evolving_friction`, "
             f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {cpu_model()} (one process, CPU time, the laws "
             "alternated in each round)", "",
             "| scene | contacts | increments | friction | compiled cycle, best (CPU s) | median | / Coulomb (best) | "
             "local iterations |", "|" + " --- |" * 8]
    reference, per_increment = {}, {}
    for r in rows:
        if r["law"] == "coulomb":
            reference[r["scene"]] = r["cycle_s"]
        if r["law"] == "function of the energy":
            per_increment[r["scene"]] = r
        ratio = r["cycle_s"] / reference[r["scene"]]
        lines.append(f"| {r['scene']} | {r['contacts']} | {r['increments_per_cycle']} | {r['law']} | "
                     f"{r['cycle_s']:.4f} | {r['cycle_s_median']:.4f} | {ratio:.2f} | {r['local_iterations']} |")
    lines.append("")
    for r in rows:
        if r["law"] == "table of the energy":
            other = per_increment[r["scene"]]
            lines.append(f"- {r['scene']}: the table inside the loop against the function per increment: "
                         f"{other['cycle_s'] / r['cycle_s']:.2f}x faster (best), "
                         f"{other['cycle_s_median'] / r['cycle_s_median']:.2f}x (median).")
    lines += ["", "A table of the energy (or of the cycles) runs the cycle in one compiled call, as Coulomb; the "
              "user's function of the energy runs one increment per call (mu, the energy and the wear rate updated "
              "in Python between the calls): its difference to Coulomb over the cycle's increments is that overhead "
              "per increment."]
    table = "\n".join(lines)
    print(table)
    if args.out:
        Path(args.out).with_suffix(".json").write_text(json.dumps(rows, indent=1))
        Path(args.out).with_suffix(".md").write_text(table + "\n")


if __name__ == "__main__":
    main()
