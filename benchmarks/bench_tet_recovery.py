"""Issue 23: the pressure read on gmsh tetrahedra against an elastic body, and the smoothed shear.

Two measurements of the two recoveries of :mod:`dolfinx_fretting.pressure` (``"nodal"``, force over tributary
measure; ``"smoothed"``, two sweeps of the lumped L2 projection over the loaded facets), each read from the same
solved state (the contact is built with ``pressure_recovery="smoothed"``; the nodal values are ``r / A`` of the same
forces):

- ``elastic``: the quarter cap in gmsh tetrahedra (tests/support/tet_sphere.py) pressed frictionless by P/4 on an
  identical elastic flat in gmsh tetrahedra of its own size (the faces never match), ``ElasticBody(...,
  formulation=)`` node-to-face and mortar; Hertz's pressure with the pair's E* = E / (2 (1 - nu^2)) (Johnson
  eqs 3.39, 4.22-4.23). Errors over p0: the peak (max p / p0 - 1), RMS and largest |p - p_H| within 0.8a.
- ``shear``: the half cap (y >= 0, a roller on y = 0: x = 0 is no symmetry plane of a load along x) on the rigid
  plane, mu = 0.5, pressed by P/2, then Q = 0.5 mu P/2 by force along x in two increments (y held at 0);
  Cattaneo-Mindlin's x traction (Johnson §7.2, ``analytic.cattaneo_mindlin_sphere_traction``, E* of the rigid
  plane: Mindlin's uncoupled solution; the elastic sphere on a rigid plane has Dundurs' beta = 0.29, a bias shared
  by both recoveries). Errors over mu p0: the peak (max t_x - max of the closed form), RMS and largest within 0.8a;
  and the largest |shear| / (mu p) - 1 over the loaded nodes (Coulomb's cone, each recovery).

Usage (the runs of benchmarks/results/tet_pressure.md's section "Against an elastic flat, and the smoothed shear"):
    OPENBLAS_NUM_THREADS=1 nice -n 5 .venv/bin/python benchmarks/bench_tet_recovery.py --a-over-h 8 12 16 \
        --meshers frontal-delaunay delaunay --cases elastic --out benchmarks/results/tet_recovery_elastic
    OPENBLAS_NUM_THREADS=1 nice -n 5 .venv/bin/python benchmarks/bench_tet_recovery.py --a-over-h 8 12 \
        --cases shear --shear-obstacles rigid node mortar --out benchmarks/results/tet_recovery_shear
    (``--render JSON COMMAND``: the .md again from a run's JSON, no run.)
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from datetime import date
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parent / "tests"))

from _machine import cpu_model  # noqa: E402  (benchmarks/ is on sys.path when a script runs)

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting.analytic import cattaneo_mindlin_sphere_traction  # noqa: E402
from support.tet_sphere import E_STAR, E_STAR_PAIR, P, R, hertz_errors, pressed, tet_cap_problem  # noqa: E402

MU, PHI = 0.5, 0.5   # Coulomb's coefficient; Q / (mu P)


def both_tractions(problem, state) -> dict[str, np.ndarray]:
    """(nc, 3) each contact's traction in global x, y, z, read ``"smoothed"`` (the problem's) and ``"nodal"``."""
    contact_set = problem.contact.contact_set
    assert contact_set.surface_mass is not None
    frames = contact_set.frames
    forces = state.forces.reshape(contact_set.nc, 3)
    local = {"smoothed": contact_set.tractions(state.forces), "nodal": forces / contact_set.tributary[:, None]}
    return {name: np.einsum("ik,ikj->ij", value, frames) for name, value in local.items()}


def elastic(a_over_h: float, flat_ratio: float, formulation: str, mesher: str) -> dict:
    """The cap on the elastic flat (the flat's a/h = a_over_h * flat_ratio), both recoveries against Hertz."""
    start = time.perf_counter()
    problem, contact, a, p0, h = tet_cap_problem(a_over_h, mesher=mesher, flat_a_over_h=a_over_h * flat_ratio,
                                                 formulation=formulation, pressure_recovery="smoothed")
    setup = time.perf_counter() - start
    start = time.perf_counter()
    state = pressed(problem)
    solve = time.perf_counter() - start
    contact_set = contact.contact_set
    tractions = both_tractions(problem, state)
    rows = {}
    for name, traction in tractions.items():
        errors = hertz_errors(contact_set.coords, traction[:, 2], a, p0)
        errors["min_over_p0"] = float(traction[:, 2].min() / p0)
        rows[name] = errors
    result = {"case": "elastic", "a_over_h": a_over_h, "flat_ratio": flat_ratio, "formulation": formulation,
              "mesher": mesher, "dofs": problem.n_dofs, "contacts": contact_set.nc,
              "loaded": int((state.forces[0::3] > 0).sum()),
              "force_error": float(problem.total_force(state)[0] / (P / 4) - 1),
              "setup_s": setup, "press_s": solve, "methods": rows}
    problem.destroy()
    return result


def shear(a_over_h: float, mesher: str, obstacle: str) -> dict:
    """The half cap under Cattaneo-Mindlin loading on the rigid plane (``obstacle = "rigid"``) or on the identical
    flat (``"node"``, ``"mortar"``: the flat's a/h the cap's), both recoveries of the x traction."""
    flat = obstacle != "rigid"
    start = time.perf_counter()
    problem, contact, a, p0, h = tet_cap_problem(a_over_h, mesher=mesher, half=True, mu=MU,
                                                 flat_a_over_h=a_over_h if flat else None,
                                                 formulation=obstacle if flat else "node",
                                                 pressure_recovery="smoothed")
    setup = time.perf_counter() - start
    start = time.perf_counter()
    state = pressed(problem, share=0.5)
    pressed_shear = both_tractions(problem, state)["nodal"][:, 0]
    Q = PHI * MU * P
    for fraction in (0.5, 1.0):
        state = problem.commit(state, problem.solve(
            state, tangential=(dfr.Force(fraction * Q / 2), dfr.Displacement(0.0))))
    solve = time.perf_counter() - start
    contact_set = contact.contact_set
    r = np.linalg.norm(contact_set.coords[:, :2], axis=1)
    expected = cattaneo_mindlin_sphere_traction(r, Q, MU, P, R, E_STAR_PAIR if flat else E_STAR)
    inner = r < 0.8 * a
    rows = {}
    for name, traction in both_tractions(problem, state).items():
        error = (traction[:, 0] - expected) / (MU * p0)
        loaded = traction[:, 2] > 0
        cone = np.linalg.norm(traction[loaded, :2], axis=1) / (MU * traction[loaded, 2]) - 1
        rows[name] = {"peak": float((traction[:, 0].max() - expected.max()) / (MU * p0)),
                      "rms": float(np.sqrt(np.mean(error[inner] ** 2))),
                      "max_inner": float(np.abs(error[inner]).max()),
                      "centre": float(error[np.argmin(r)]),
                      "cone": float(cone.max()),
                      "pressure_rms": hertz_errors(contact_set.coords, traction[:, 2], a, p0)["rms"]}
    status = problem.contact_fields(state)["status"]
    result = {"case": "shear", "obstacle": obstacle, "a_over_h": a_over_h, "mesher": mesher, "dofs": problem.n_dofs,
              "contacts": contact_set.nc, "loaded": int((state.forces[0::3] > 0).sum()),
              "sliding": int((status == 2).sum()),
              "pressed_shear_rms": float(np.sqrt(np.mean(pressed_shear[inner] ** 2)) / (MU * p0)),
              "tangential_error": float(problem.total_force(state)[1] / (Q / 2) - 1),
              "setup_s": setup, "press_s": solve, "methods": rows}
    problem.destroy()
    return result


def render(results: list[dict], command: str) -> str:
    lines = [f"## Against an elastic flat, and the smoothed shear ({date.today().isoformat()})", "",
             f"`{command}`", "", f"{cpu_model()}, shared 2-core machine (times are indicative). Script: "
             "`benchmarks/bench_tet_recovery.py` (its docstring states the models).", "",
             "The quarter cap (as above, a from the pair's E* = E / (2 (1 - nu^2)): a = 0.187 mm) pressed "
             "frictionless by P/4 on an identical flat in gmsh tetrahedra (9a deep and wide, bottom clamped), the "
             "flat's own element size a / (flat a/h) in the contact zone; both recoveries of the same state. Errors "
             "in % of p0: peak, RMS and largest |p - p_H| within 0.8a, min = the smallest p / p0.", "",
             "| a/h | flat a/h | formulation | mesher | dofs | loaded | method | peak % | RMS % | max % | min | "
             "P error | set-up s | press s |", "| --- " * 14 + "|"]
    if not any(r["case"] == "elastic" for r in results):
        lines = lines[:-4]   # no elastic case run: no table
    for r in (r for r in results if r["case"] == "elastic"):
        for name in ("nodal", "smoothed"):
            m = r["methods"][name]
            lines.append(f"| {r['a_over_h']:g} | {r['a_over_h'] * r['flat_ratio']:g} | {r['formulation']} | "
                         f"{r['mesher']} | {r['dofs']} | {r['loaded']} | {name} | {100 * m['peak']:+.2f} | "
                         f"{100 * m['rms']:.2f} | {100 * m['max_inner']:.2f} | {m['min_over_p0']:+.3f} | "
                         f"{r['force_error']:.1e} | {r['setup_s']:.1f} | {r['press_s']:.1f} |")
    lines += ["", "Cattaneo-Mindlin: the half cap, mu = 0.5, P then Q = 0.5 mu P along x by force, on the rigid plane "
              "or on the identical flat (its a/h the cap's); the x traction of both recoveries of the same state "
              "against Mindlin's (E* of the pair). Errors in % of mu p0: peak = max t_x - max t_CM, RMS and largest "
              "within 0.8a, at the centre node; cone = the largest |shear| / (mu p) - 1 over the loaded nodes (<= 0: "
              "Coulomb kept); the pressure's RMS in % of p0; pressed t_x = the RMS of the nodal x traction within "
              "0.8a after pressing, before any Q (Mindlin's has none: on the rigid plane it is the radial friction "
              "of the normal load, Dundurs' beta = 0.29; on the identical flat beta = 0).", "",
              "| obstacle | a/h | mesher | dofs | loaded | sliding | method | peak % | RMS % | max % | centre % | "
              "cone | pressure RMS % | pressed t_x RMS % | Q error | press + shear s |", "| --- " * 16 + "|"]
    if not any(r["case"] == "shear" for r in results):
        lines = lines[:-4]   # no shear case run: no table
    for r in (r for r in results if r["case"] == "shear"):
        for name in ("nodal", "smoothed"):
            m = r["methods"][name]
            lines.append(f"| {r['obstacle']} | {r['a_over_h']:g} | {r['mesher']} | {r['dofs']} | {r['loaded']} | "
                         f"{r['sliding']} | {name} | {100 * m['peak']:+.2f} | {100 * m['rms']:.2f} | "
                         f"{100 * m['max_inner']:.2f} | {100 * m['centre']:+.2f} | {m['cone']:+.1e} | "
                         f"{100 * m['pressure_rms']:.2f} | {100 * r['pressed_shear_rms']:.2f} | "
                         f"{r['tangential_error']:.1e} | {r['press_s']:.1f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--a-over-h", type=float, nargs="+", default=[8, 12])
    parser.add_argument("--flat-ratio", type=float, nargs="+", default=[1.0],
                        help="the flat's a/h over the cap's (1: the same nominal size, two triangulations)")
    parser.add_argument("--formulations", nargs="+", default=["node", "mortar"])
    parser.add_argument("--meshers", nargs="+", default=["frontal-delaunay"])
    parser.add_argument("--cases", nargs="+", default=["elastic", "shear"], choices=["elastic", "shear"])
    parser.add_argument("--shear-obstacles", nargs="+", default=["rigid", "mortar"],
                        choices=["rigid", "node", "mortar"])
    parser.add_argument("--out", default=str(HERE / "results" / "tet_recovery"))
    parser.add_argument("--render", nargs=2, metavar=("JSON", "COMMAND"),
                        help="write OUT.md again from a run's JSON and the command that made it (no run)")
    args = parser.parse_args()
    if args.render:
        Path(args.out + ".md").write_text(render(json.loads(Path(args.render[0]).read_text()), args.render[1]))
        return
    results = []
    for a_over_h in args.a_over_h:
        for mesher in args.meshers:
            if "elastic" in args.cases:
                for ratio in args.flat_ratio:
                    for formulation in args.formulations:
                        results.append(elastic(a_over_h, ratio, formulation, mesher))
                        print(json.dumps(results[-1]), flush=True)
            if "shear" in args.cases:
                for obstacle in args.shear_obstacles:
                    results.append(shear(a_over_h, mesher, obstacle))
                    print(json.dumps(results[-1]), flush=True)
    command = "OPENBLAS_NUM_THREADS=1 nice -n 5 .venv/bin/python benchmarks/bench_tet_recovery.py " + " ".join(
        sys.argv[1:])
    Path(args.out + ".json").write_text(json.dumps(results, indent=1))
    Path(args.out + ".md").write_text(render(results, command))


if __name__ == "__main__":
    main()
