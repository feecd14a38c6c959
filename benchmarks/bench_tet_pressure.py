"""Issue 23: the pressure a user reads on unstructured tetrahedra, recoveries side by side.

A sphere's cap in gmsh tetrahedra (tests/support/tet_sphere.py: quarter model, cap height 9a, top clamped, contact
zone h = a / (a/h) within 1.5a) pressed frictionless on a rigid plane through the public API (Contact,
FrettingProblem). The contact problem (node-to-rigid, W = H K^-1 H^T) is solved once per mesh; every recovery
below reads the same nodal forces r_n:

- ``nodal``: r_n / A (A the lumped tributary area), what was reported before.
- ``l2-consistent``: the consistent L2 projection onto P1, M p = r_n, M the P1 mass matrix of the candidate facets;
  ``l2-loaded``: the same over the loaded nodes only (M_LL p_L = r_L, p = 0 at open nodes).
- ``patch``: sum of r_n over the node and its facet neighbours over the sum of their A.
- ``smoothed-1``, ``smoothed-2`` (the package's ``"smoothed"``), ``smoothed-3``: 1, 2, 3 sweeps of the lumped L2
  projection over the loaded facets (dolfinx_fretting.pressure.smoothed_tractions).
- the rigid plane as a mortar master (dual multipliers): not solved; its D_jj and weighted gaps are compared with
  the node-to-rigid ones (if equal, its constraint and its multiplier are the nodal ones).

Errors against Hertz (p0 = 3P/(2 pi a^2)): the peak (max p / p0 - 1), the RMS of p - p_H over the nodes within
0.8a, the largest single-node error there, the resultant (sum A p over the contact force - 1).

Usage:
    OPENBLAS_NUM_THREADS=1 nice -n 5 .venv/bin/python benchmarks/bench_tet_pressure.py --a-over-h 8 12 16 \
        --meshers frontal-delaunay delaunay --out benchmarks/results/tet_pressure
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from datetime import date
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parent / "tests"))

from _machine import cpu_model  # noqa: E402  (benchmarks/ is on sys.path when a script runs)

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import contact as contact_module  # noqa: E402
from dolfinx_fretting.mortar import mortar_matrices, weighted_relative_displacement  # noqa: E402
from dolfinx_fretting.pressure import smoothed_tractions  # noqa: E402
from support.tet_sphere import SURFACE, hertz_errors, pressed, tet_cap_problem  # noqa: E402

METHODS = ("nodal", "l2-consistent", "l2-loaded", "patch", "smoothed-1", "smoothed-2", "smoothed-3")


def recoveries(forces_n: np.ndarray, tributary: np.ndarray, mass: sp.csr_matrix) -> dict[str, tuple]:
    """Each method's pressure and its time per evaluation (s)."""
    out = {}

    def timed(name, run):
        start = time.perf_counter()
        value = run()
        out[name] = (value, time.perf_counter() - start)

    has = np.flatnonzero(np.asarray(mass.sum(axis=1)).ravel() > 0)
    loaded = np.flatnonzero(forces_n > 0)
    neighbours = (mass != 0).astype(float)

    def consistent(nodes):
        p = np.zeros_like(forces_n)
        p[nodes] = spl.spsolve(mass[nodes][:, nodes].tocsc(), forces_n[nodes])
        return p

    forces = np.column_stack([forces_n, np.zeros((forces_n.size, 2))])
    timed("nodal", lambda: forces_n / tributary)
    timed("l2-consistent", lambda: consistent(has))
    timed("l2-loaded", lambda: consistent(loaded))
    timed("patch", lambda: (neighbours @ forces_n) / (neighbours @ tributary))
    for sweeps in (1, 2, 3):
        timed(f"smoothed-{sweeps}", lambda s=sweeps: smoothed_tractions(forces, tributary, mass, sweeps=s)[:, 0])
    return out


def mortar_check(problem, contact) -> dict[str, float]:
    """The rigid plane z = 0 as a mortar master (a square of two triangles under the contact zone), the candidate
    facets the slave: D_jj against the tributary areas and the weighted gap along the plane's normal over D_jj against
    the nodal gap, at the nodes whose every facet is a candidate facet (the others' D_jj is partial)."""
    contact_set = contact.contact_set
    nodes, xs, _, inside = contact_module._boundary_faces(problem.V, contact.facets)
    labels = contact_set.global_nodes
    keep = np.all(np.isin(nodes, labels) | (nodes < 0), axis=1)
    nodes, xs, inside = nodes[keep], xs[keep], inside[keep]
    extent = 10 * np.abs(contact_set.coords[:, :2]).max()
    corners = {10**9 + k: np.array([x, y, 0.0]) for k, (x, y) in enumerate([(-1, -1), (1, -1), (1, 1), (-1, 1)])}
    corners = {label: extent * point for label, point in corners.items()}
    first = 10**9   # labels apart from the slave's
    master_nodes = np.array([[first, first + 1, first + 2, -1], [first, first + 2, first + 3, -1]])
    square = np.array([[corners[k] for k in (first, first + 1, first + 2, first + 2)],
                       [corners[k] for k in (first, first + 2, first + 3, first + 3)]])
    below = square[:, :3].mean(axis=1) - [0, 0, 1.0]
    mortar = mortar_matrices(nodes, xs, inside, master_nodes, square, below, reference_tangent=np.array([1.0, 0, 0]))
    position = {g: i for i, g in enumerate(labels)}
    index = np.array([position[g] for g in mortar.slave_nodes])
    D = mortar.D.diagonal()
    # nodes whose every facet is a candidate facet: their lumped area over those facets is the tributary area
    lumped = np.asarray(contact_set.surface_mass.sum(axis=1)).ravel()[index]
    interior = np.isclose(lumped, contact_set.tributary[index], rtol=1e-12) & (D > 0)
    master_points = np.array([corners[k] for k in mortar.master_nodes])
    normal = np.broadcast_to([0.0, 0.0, 1.0], (mortar.slave_nodes.size, 3))
    gaps = weighted_relative_displacement(mortar, contact_set.coords[index], master_points, normal)
    nodal_gap = contact_set.gap0[index]
    return {"nodes_compared": int(interior.sum()),
            "D_over_tributary_minus_1": float(np.abs(D[interior] / contact_set.tributary[index][interior] - 1).max()),
            "weighted_gap_minus_nodal_over_a": float(np.abs(gaps[interior] / D[interior]
                                                            - nodal_gap[interior]).max())}


def run(a_over_h: float, mesher: str) -> dict:
    start = time.perf_counter()
    problem, contact, a, p0, h = tet_cap_problem(a_over_h, mesher=mesher, pressure_recovery="nodal")
    setup = time.perf_counter() - start
    start = time.perf_counter()
    smoothed_contact = dfr.Contact(problem.V, (contact.surface[0], SURFACE), contact.obstacle, mu=0.0,
                                   bcs=contact.bcs, window=contact.window, pressure_recovery="smoothed")
    contact_smoothed = time.perf_counter() - start
    start = time.perf_counter()
    dfr.Contact(problem.V, (contact.surface[0], SURFACE), contact.obstacle, mu=0.0, bcs=contact.bcs,
                window=contact.window, pressure_recovery="nodal")
    contact_nodal = time.perf_counter() - start
    start = time.perf_counter()
    state = pressed(problem)
    solve = time.perf_counter() - start
    contact_set = contact.contact_set
    mass = smoothed_contact.contact_set.surface_mass
    assert np.array_equal(smoothed_contact.contact_set.global_nodes, contact_set.global_nodes)
    forces_n = state.forces[0::3]
    rows = {}
    for name, (pressure, seconds) in recoveries(forces_n, contact_set.tributary, mass).items():
        errors = hertz_errors(contact_set.coords, pressure, a, p0)
        errors["resultant"] = float((pressure * contact_set.tributary).sum() / forces_n.sum() - 1)
        errors["min_over_p0"] = float(pressure.min() / p0)
        errors["seconds"] = seconds
        rows[name] = errors
    check = mortar_check(problem, smoothed_contact)
    result = {"a_over_h": a_over_h, "mesher": mesher, "dofs": problem.n_dofs, "contacts": contact_set.nc,
              "loaded": int((forces_n > 0).sum()), "setup_s": setup, "contact_nodal_s": contact_nodal,
              "contact_smoothed_s": contact_smoothed, "press_s": solve, "methods": rows, "mortar": check}
    problem.destroy()
    return result


def render(results: list[dict], command: str) -> str:
    lines = [f"# Pressure read on unstructured tetrahedra: recoveries side by side (issue 23)", "",
             f"`{command}`", "", f"{date.today().isoformat()}, {cpu_model()}, shared 2-core machine (times are "
             "indicative).", "",
             "Quarter sphere cap (R = 10 mm, E = 210 GPa, nu = 0.3, P = 100 N on the whole cap, a = "
             "0.148 mm) in gmsh tetrahedra, frictionless on a rigid plane, node-to-rigid contact solved once per "
             "mesh; every recovery reads the same nodal forces. Errors in % of p0: peak = max p / p0 - 1, RMS and "
             "max |p - p_H| over the nodes within 0.8a, resultant = sum A p / P - 1, min = the smallest p / p0.", ""]
    lines += ["| a/h | mesher | dofs | loaded | method | peak % | RMS % | max % | resultant % | min | recovery ms |",
              "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in results:
        for name in METHODS:
            m = r["methods"][name]
            lines.append(f"| {r['a_over_h']:g} | {r['mesher']} | {r['dofs']} | {r['loaded']} | {name} | "
                         f"{100 * m['peak']:+.2f} | {100 * m['rms']:.2f} | {100 * m['max_inner']:.2f} | "
                         f"{100 * m['resultant']:+.3f} | {m['min_over_p0']:+.3f} | {1e3 * m['seconds']:.2f} |")
    lines += ["", "Set-up cost of the smoothed recovery (the surface mass matrix of the candidate facets, built once "
              "per contact set) and the rigid plane as a mortar master (dual multipliers, the candidate facets the "
              "slave: its D_jj and weighted gap along the plane's normal against the node-to-rigid ones, at the nodes "
              "whose facets are all candidates):", "",
              "| a/h | mesher | Contact nodal s | Contact smoothed s | press s | nodes | max abs(D_jj / A - 1) | "
              "max abs(g_j / D_jj - g_node) mm |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in results:
        c = r["mortar"]
        lines.append(f"| {r['a_over_h']:g} | {r['mesher']} | {r['contact_nodal_s']:.2f} | "
                     f"{r['contact_smoothed_s']:.2f} | {r['press_s']:.2f} | {c['nodes_compared']} | "
                     f"{c['D_over_tributary_minus_1']:.1e} | {c['weighted_gap_minus_nodal_over_a']:.1e} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--a-over-h", type=float, nargs="+", default=[8, 12, 16])
    parser.add_argument("--meshers", nargs="+", default=["frontal-delaunay", "delaunay"])
    parser.add_argument("--out", default=str(HERE / "results" / "tet_pressure"))
    args = parser.parse_args()
    results = []
    for a_over_h in args.a_over_h:
        for mesher in args.meshers:
            results.append(run(a_over_h, mesher))
            print(f"a/h {a_over_h:g} {mesher}: " + ", ".join(
                f"{k} {100 * v['peak']:+.2f}/{100 * v['rms']:.2f}" for k, v in results[-1]["methods"].items()),
                flush=True)
    command = "OPENBLAS_NUM_THREADS=1 nice -n 5 .venv/bin/python benchmarks/bench_tet_pressure.py " + " ".join(
        sys.argv[1:])
    Path(args.out + ".json").write_text(json.dumps(results, indent=1))
    Path(args.out + ".md").write_text(render(results, command))


if __name__ == "__main__":
    main()
