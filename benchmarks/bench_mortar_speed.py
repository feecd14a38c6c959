"""What mortar contact costs against node-to-segment/face pairing: set-up and per increment, side by side (issue 23).

Cases (each built and run in this process with ``contact.formulation`` / ``ElasticBody.formulation`` = ``"node"``
then ``"mortar"``, alternated, ``--repeats`` times after one untimed warm-up of each formulation):

* the built-in two-body scenes at their default sizes: ``cylinder-flat`` (2D), ``mccoll`` (2D; with
  ``contact.sliding = "small"``: mortar pairs once, and McColl's default finite sliding is node-to-segment only)
  and ``sphere-flat`` (3D half model), through the scene runner's own model (``simulation.ContactModel``: its
  mesh, its Contact and FrettingProblem) and its load path: the preload increment by increment
  (``FrettingProblem.advance``, force control), then the first cycle as the runner runs it (``run_cycle``: the
  compiled loop, with the normal force held by its force control);
* the non-matching 3D validation case: the sphere on an identical flat whose contact elements are 1.37 times the
  sphere's (a/h = 6 on the sphere, the depth-graded mesh; ``tests/support/sphere.py``), pressed by P and loaded by
  Q = 0.25 P (mu = 0.5) in two increments each (Hertz, then Cattaneo-Mindlin).

Timed for each: the contact (``Contact``: the pairing or the mortar integrals, frames, gaps, H), the problem
(``FrettingProblem``: K assembled and factorised, W = H K^-1 H^T), the preload's increments and the cycle's (per
increment, mean; the sphere case: its four increments by ``solve`` and ``commit``). CPU
time (``time.process_time``: the machine is shared, so the ratios are read from it) and wall time.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_mortar_speed.py [--repeats 3] \
        [--cases cylinder-flat mccoll sphere-flat sphere-non-matching] [--out benchmarks/results/mortar_speed]
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parent / "tests"))   # the validation's sphere model (tests/support/sphere.py)

from _machine import cpu_model  # noqa: E402  benchmarks/ is on sys.path when a script runs
from mpi4py import MPI  # noqa: E402  (first: the 0.11 wheel needs the MPI library mpi4py loads)

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import simulation  # noqa: E402
from dolfinx_fretting.scene_paths import cycle_path, preload_path  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from support.sphere import P, pressed, sphere_model  # noqa: E402

FORMULATIONS = ("node", "mortar")
SCENES = {"cylinder-flat": [], "mccoll": ["contact.sliding=small"], "sphere-flat": []}
CASES = (*SCENES, "sphere-non-matching")


class Clock:
    """CPU and wall seconds since the last :meth:`lap`."""

    def __init__(self) -> None:
        self.cpu, self.wall = time.process_time(), time.perf_counter()

    def lap(self) -> tuple[float, float]:
        cpu, wall = time.process_time(), time.perf_counter()
        out = (cpu - self.cpu, wall - self.wall)
        self.cpu, self.wall = cpu, wall
        return out


@contextlib.contextmanager
def timing(module, name: str, spent: list[float]):
    """``module.name`` (a class or function looked up at call time) timed while inside: its CPU and wall seconds
    added to ``spent``."""
    original = getattr(module, name)

    def timed(*args, **kwargs):
        clock = Clock()
        out = original(*args, **kwargs)
        cpu, wall = clock.lap()
        spent[0] += cpu
        spent[1] += wall
        return out

    setattr(module, name, timed)
    try:
        yield
    finally:
        setattr(module, name, original)


def scene_case(name: str, formulation: str, increments: int | None) -> dict:
    """One scene: the model built, then the preload and the first cycle (the first ``increments`` of them)."""
    scene = load_scene(name, [*SCENES[name], f"contact.formulation={formulation}", "output.progress=false"])
    clock, spent = Clock(), [0.0, 0.0]
    with timing(simulation, "Contact", spent):   # the runner's ContactModel builds its Contact by this name
        model = simulation.ContactModel(scene)
    model_cpu, model_wall = clock.lap()
    steps = preload_path(scene.loading)
    steps = steps[:increments] if increments else steps
    state, problem = model.problem.initial_state(), model.problem
    clock.lap()
    for step in steps:
        state, _ = problem.advance(state, **simulation._step_targets(step, model, scene.loading.normal_increments))
    cpu, wall = clock.lap()
    out = {"nc": problem.contact.nc, "dofs": problem.n_dofs, "contact_cpu": spent[0], "contact_wall": spent[1],
           "model_cpu": model_cpu, "model_wall": model_wall, "increments": len(steps),
           "increment_cpu": cpu / len(steps), "increment_wall": wall / len(steps)}
    if not increments:   # the first cycle as the runner runs it (the compiled loop where it applies)
        cycle = problem.run_cycle(state, simulation._cycle_path(scene, model))
        cpu, wall = clock.lap()
        state = problem.commit(state, cycle)
        n = scene.loading.increments_per_cycle
        out.update(cycle_increments=n, cycle_compiled=bool(cycle.compiled), cycle_increment_cpu=cpu / n,
                   cycle_increment_wall=wall / n)
    out["max_pressure"] = float(problem.contact_fields(state)["pressure"].max())
    problem.destroy()
    return out


def sphere_case(formulation: str) -> dict:
    """The non-matching sphere on a flat (a/h = 6, the flat's a/h 4.38): Hertz then Cattaneo-Mindlin."""
    clock, spent = Clock(), [0.0, 0.0]
    mu, phi = 0.5, 0.5
    with timing(dfr, "Contact", spent):   # the support module builds it as dfr.Contact
        body, problem, a, p0, h = sphere_model(6, 9.0, 1.5, flat=True, flat_mesh_size=4.38, formulation=formulation,
                                               mu=mu, depth_growth=1.5, coarsening=2)
    model_cpu, model_wall = clock.lap()
    state = pressed(problem, P / 2)
    for fraction in (0.5, 1.0):
        state = problem.commit(state, problem.solve(state, tangential=(dfr.Force(fraction * phi * mu * P / 2),
                                                                       dfr.Displacement(0.0))))
    cpu, wall = clock.lap()
    out = {"nc": problem.contact.nc, "dofs": problem.n_dofs, "contact_cpu": spent[0], "contact_wall": spent[1],
           "model_cpu": model_cpu, "model_wall": model_wall, "increments": 4,
           "increment_cpu": cpu / 4, "increment_wall": wall / 4,
           "max_pressure": float(problem.contact_fields(state)["pressure"].max())}
    problem.destroy()
    return out


def run_case(case: str, formulation: str, increments: int | None = None) -> dict:
    return sphere_case(formulation) if case == "sphere-non-matching" \
        else scene_case(case, formulation, increments)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=CASES)
    parser.add_argument("--out", default=str(HERE / "results" / "mortar_speed"))
    args = parser.parse_args()
    for formulation in FORMULATIONS:   # untimed: numba's kernels compiled, DOLFINx's forms and modules loaded
        run_case("cylinder-flat", formulation)
    runs: dict[str, list[dict]] = {}
    for case in args.cases:
        for _ in range(args.repeats):
            for formulation in FORMULATIONS:
                result = run_case(case, formulation)
                runs.setdefault(f"{case}|{formulation}", []).append(result)
                print(case, formulation, {k: round(v, 4) if isinstance(v, float) else v for k, v in result.items()},
                      flush=True)
    load = os.getloadavg()
    command = ("OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_mortar_speed.py "
               f"--repeats {args.repeats} --cases {' '.join(args.cases)}")
    lines = ["## Mortar against node-to-segment/face: set-up and per-increment cost", "",
             f"Command: `{command}`", "",
             f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}; machine: {cpu_model()}, "
             f"{platform.machine()}, {os.cpu_count()} cores; load average at the end {load[0]:.2f} / {load[1]:.2f} / "
             f"{load[2]:.2f}. Node then mortar, alternated, {args.repeats} of each after one untimed warm-up; medians "
             "of CPU seconds (wall in brackets); ratios mortar / node of the CPU medians, and each repeat's ratio.", "",
             "| case | nc | dofs | contact (pairing/integrals + H): node | mortar | mortar / node (repeats) | "
             "model (mesh + contact + K + W): node | mortar | ratio | preload, per increment (ms): node | mortar | "
             "ratio (repeats) | cycle, per increment (ms): node | mortar | ratio (repeats) | "
             "max pressure node / mortar (MPa) |",
             "| --- | ---: | ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | --- | ---: | ---: | --- "
             "| --- |"]
    for case in args.cases:
        node, mortar = runs[f"{case}|node"], runs[f"{case}|mortar"]

        def med(rows, key):
            return statistics.median(r[key] for r in rows)

        def each(key):
            return ", ".join(f"{m[key] / n[key]:.2f}" for n, m in zip(node, mortar))

        lines.append(
            f"| {case}{' (compiled cycle)' if node[0].get('cycle_compiled') else ''} | "
            f"{node[0]['nc']} / {mortar[0]['nc']} | {node[0]['dofs']} | "
            f"{med(node, 'contact_cpu'):.3f} ({med(node, 'contact_wall'):.2f}) | "
            f"{med(mortar, 'contact_cpu'):.3f} ({med(mortar, 'contact_wall'):.2f}) | "
            f"{med(mortar, 'contact_cpu') / med(node, 'contact_cpu'):.2f} ({each('contact_cpu')}) | "
            f"{med(node, 'model_cpu'):.2f} ({med(node, 'model_wall'):.1f}) | "
            f"{med(mortar, 'model_cpu'):.2f} ({med(mortar, 'model_wall'):.1f}) | "
            f"{med(mortar, 'model_cpu') / med(node, 'model_cpu'):.2f} | "
            f"{1e3 * med(node, 'increment_cpu'):.1f} ({1e3 * med(node, 'increment_wall'):.0f}) | "
            f"{1e3 * med(mortar, 'increment_cpu'):.1f} ({1e3 * med(mortar, 'increment_wall'):.0f}) | "
            f"{med(mortar, 'increment_cpu') / med(node, 'increment_cpu'):.2f} ({each('increment_cpu')}) | "
            + (f"{1e3 * med(node, 'cycle_increment_cpu'):.2f} ({1e3 * med(node, 'cycle_increment_wall'):.0f}) | "
               f"{1e3 * med(mortar, 'cycle_increment_cpu'):.2f} ({1e3 * med(mortar, 'cycle_increment_wall'):.0f}) | "
               f"{med(mortar, 'cycle_increment_cpu') / med(node, 'cycle_increment_cpu'):.2f} "
               f"({each('cycle_increment_cpu')}) | " if "cycle_increment_cpu" in node[0] else "— | — | — | ")
            + f"{node[0]['max_pressure']:.1f} / {mortar[0]['max_pressure']:.1f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    Path(args.out).with_suffix(".md").write_text(text)
    Path(args.out).with_suffix(".json").write_text(json.dumps(runs, indent=1))


if __name__ == "__main__":
    main()
