"""Where mortar's error on non-matching 2D faces comes from (issue 23, validation row 59): the flat punch with
rounded edges on an identical flat, frictionless (tests/test_mortar_validation.py's model), every variant of one
question at a time:

- the meshes: the punch (contact elements ``h_punch``) and the flat (``h_flat``), matching, non-matching, nested
  (every flat node a punch node, or the reverse), both coarse;
- the formulation: ``node`` (node-to-segment) or ``mortar`` (dual multipliers);
- the order: the punch the slave (its nodes carry the pressure) or the flat;
- the pressure read: the package's (force over tributary measure: for mortar the dual multiplier lambda_j, the force
  D_jj lambda_j over D_jj) and the consistent L2 one, the slave's P1 mass matrix solved for the same nodal forces
  (``M p = r`` on the loaded nodes);
- the mortar integrals' quadrature (two Gauss points per overlap, exact for the quadratic integrands, against four);
- the multipliers: dual (the package's), standard (D the slave's consistent mass over the facing parts: H and the gap
  integrated anew here and put in the contact set) and, as an experiment, dual with the master's trace a cubic
  Hermite spline of its nodal values (``mortar-smooth``);
- a third read, through the master (the master's nodal forces over its hats' facing measures, interpolated back).

Errors of the pressure at the slave's nodes against Ciavarella, Hills & Monno's closed form, in units of its largest
value, inside |x| < 0.8 a: RMS, largest, and the largest pressure's error. ``--geometry cylinder``: the same for the
half-cylinder (R = 6, P = 199.24 N/mm, a = 0.153, h = a/15) on the flat against Hertz (row 58's pressure), the
"punch" columns then being the cylinder's arc. The summary and what it means: ``results/mortar_accuracy.md``.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_mortar_accuracy.py [--geometry cylinder] \
        [--out benchmarks/results/mortar_accuracy_punch]
"""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from mpi4py import MPI  # noqa: F401  (before dolfinx)

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import mortar  # noqa: E402
from dolfinx_fretting.analytic import (hertz_line_contact, hertz_pressure, rounded_punch_half_width,  # noqa: E402
                                       rounded_punch_load, rounded_punch_pressure)
from support.two_body_meshes import E_STAR, cylinder_on_graded_flat, elasticity, punch_on_graded_flat  # noqa: E402
from _machine import cpu_model  # noqa: E402

B, R = 0.1, 6.0
#: The cylinder (R = 6, the arc's elements h = a / 15): Hertz's pressure for P.
CYLINDER_P = 199.24
H = 0.01
#: (slave tag, master tag, the master's normal into the slave): tag 1 the punch's face, tag 2 the flat's top.
ORDERS = {"punch": (1, 2, [0.0, 1.0]), "flat": (2, 1, [0.0, -1.0])}


def consistent_pressure(x, force):
    """The P1 field p on the polyline of the loaded slave nodes (sorted by x, straight segments between them) whose
    consistent L2 load is the nodal forces: ``M p = r``, M the P1 mass matrix of the loaded nodes' segments."""
    order = np.argsort(x[:, 0])
    loaded = order[force[order] > 0]
    points = x[loaded]
    lengths = np.linalg.norm(np.diff(points, axis=0), axis=1)
    n = loaded.size
    diagonal = np.zeros(n)
    diagonal[:-1] += lengths / 3
    diagonal[1:] += lengths / 3
    mass = sp.diags([lengths / 6, diagonal, lengths / 6], [-1, 0, 1], format="csc")
    pressure = np.zeros(x.shape[0])
    pressure[loaded] = spla.spsolve(mass, force[loaded])
    return pressure


def mortar_rows(contact_set, multipliers):
    """H and the gap of ``contact_set``'s contacts (a mortar set) with the mortar matrices of ``multipliers``
    integrated anew from its slave and master surfaces: row (dim c + k) of contact c at slave node j is
    ``(sum_k' D_jk' e_k . u_k' - sum_l M_jl e_k . u_l) / d_j``, e_k the contact's frame and d_j the hat's measure
    over its facing part (the dual D_jj, D_std's row sum), so that the force r_j conjugate to the row is d_j times the
    multiplier's coefficient (the package's read, force over d_j, is the multiplier's nodal value either way)."""
    slave, master = contact_set.slave_surface, contact_set.master_surface
    matrices = mortar.mortar_matrices(slave.nodes, slave.x, slave.inside, master.nodes, master.x, master.inside,
                                      multipliers=multipliers)
    dim = contact_set.dim
    slave_x = np.zeros((matrices.slave_nodes.size, dim))
    slave_x[np.searchsorted(matrices.slave_nodes, slave.nodes.ravel())] = slave.x.reshape(-1, dim)
    master_x = np.zeros((matrices.master_nodes.size, dim))
    master_x[np.searchsorted(matrices.master_nodes, master.nodes.ravel())] = master.x.reshape(-1, dim)
    rows_of = np.searchsorted(matrices.slave_nodes, contact_set.global_nodes)
    D, M = matrices.D.tocsr()[rows_of], matrices.M.tocsr()[rows_of]
    measure = np.asarray(D.sum(axis=1)).ravel()
    data, rows, cols = [], [], []
    for block, nodes, sign in ((D.tocoo(), matrices.slave_nodes, 1.0), (M.tocoo(), matrices.master_nodes, -1.0)):
        for k in range(dim):
            for component in range(dim):
                data.append(sign * block.data * contact_set.frames[block.row, k, component] / measure[block.row])
                rows.append(dim * block.row + k)
                cols.append(dim * nodes[block.col] + component)
    H = sp.csr_matrix((np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))),
                      shape=contact_set.H.shape)
    normals = contact_set.frames[:, 0]
    gap = (np.einsum("ij,ij->i", D @ slave_x, normals) - np.einsum("ij,ij->i", M @ master_x, normals)) / measure
    return H, gap


def through_master(contact_set, force):
    """The pressure read through the master's mesh: the master's nodal forces ``f_l = sum_j w_jl r_j`` (what the
    contacts give it) over its hats' facing measures ``A_l = sum_j w_jl D_jj``, interpolated back to each slave node
    with the same weights, ``p_j = sum_l w_jl f_l / A_l``. A uniform multiplier stays uniform; sum_l f_l = sum_j r_j."""
    nodes, weights = contact_set.master_nodes, contact_set.master_weights
    real = nodes >= 0
    labels, column = np.unique(nodes[real], return_inverse=True)
    rows = np.nonzero(real)[0]
    W = sp.csr_matrix((weights[real], (rows, column)), shape=(nodes.shape[0], labels.size))
    master_force = W.T @ force
    master_measure = W.T @ contact_set.tributary
    return W @ np.divide(master_force, master_measure, out=np.zeros_like(master_force), where=master_measure > 0)


def smooth_master_matrices(contact_set, gauss=4):
    """2D dual mortar D and M with the master's trace reconstructed by a cubic Hermite (Catmull-Rom) spline of its
    nodal values (slopes by central differences over the neighbouring segments; one-sided at the surface's ends)
    instead of its hats: ``M_jl = integral psi_j Ntilde_l``, the Ntilde a partition of unity (the patch test holds)
    that reproduces linear functions and, on a uniform master, quadratics: a curved deformed interface is followed
    to O(h^3) between the master's nodes, so a finer slave does not feel the master's polygon. Returns (slave nodes,
    master nodes, D diagonal, M csr)."""
    slave, master = contact_set.slave_surface, contact_set.master_surface
    slave_out = mortar._segment_normals(slave.x, slave.inside)
    master_out = mortar._segment_normals(master.x, master.inside)
    seg, mseg, low, high = mortar._overlaps(slave.x, slave_out, master.x, master_out)
    points, weights = np.polynomial.legendre.leggauss(gauss)
    points, weights = 0.5 + points / 2, weights / 2
    slave_length = np.linalg.norm(slave.x[:, 1] - slave.x[:, 0], axis=1)
    xi = low[:, None] + (high - low)[:, None] * points[None, :]
    weight = (slave_length[seg] * (high - low))[:, None] * weights[None, :]
    slave_hats = np.stack([1.0 - xi, xi], axis=2)
    d_slave = slave.x[seg, 1] - slave.x[seg, 0]
    d_master = master.x[mseg, 1] - master.x[mseg, 0]
    offset = np.einsum("ij,ij->i", master.x[mseg, 0] - slave.x[seg, 0], d_slave)
    eta = (xi * np.einsum("ij,ij->i", d_slave, d_slave)[:, None] - offset[:, None]) \
        / np.einsum("ij,ij->i", d_master, d_slave)[:, None]
    n_seg = slave.x.shape[0]
    mass = np.zeros((n_seg, 2, 2))
    np.add.at(mass, seg, np.einsum("pg,pgi,pgk->pik", weight, slave_hats, slave_hats))
    used = np.zeros(n_seg, dtype=bool)
    used[seg] = True
    coefficients = np.zeros((n_seg, 2, 2))
    coefficients[used] = mass[used].sum(axis=2)[:, :, None] * np.linalg.inv(mass[used])
    psi = np.einsum("pik,pgk->pgi", coefficients[seg], slave_hats)
    # the master polyline's neighbours: the segment before (sharing node 0) and after (sharing node 1)
    labels = master.nodes
    lengths = np.linalg.norm(master.x[:, 1] - master.x[:, 0], axis=1)
    before, after = np.full(labels.shape[0], -1), np.full(labels.shape[0], -1)
    for f in range(labels.shape[0]):
        found = np.flatnonzero(labels[:, 1] == labels[f, 0])
        before[f] = found[0] if found.size else -1
        found = np.flatnonzero(labels[:, 0] == labels[f, 1])
        after[f] = found[0] if found.size else -1
    t = eta
    h00, h10, h01, h11 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t, -2 * t**3 + 3 * t**2, t**3 - t**2
    L = lengths[mseg][:, None]
    prev, nxt = before[mseg], after[mseg]
    has_prev, has_next = (prev >= 0)[:, None], (nxt >= 0)[:, None]
    length_prev = np.where(prev >= 0, lengths[np.maximum(prev, 0)], 0.0)[:, None]
    length_next = np.where(nxt >= 0, lengths[np.maximum(nxt, 0)], 0.0)[:, None]
    # slope at node 0 times L: (f1 - f_{-1}) L / (L + L_prev), or f1 - f0 at an end; at node 1 likewise
    c0 = np.where(has_prev, L / (L + length_prev), 1.0)
    c1 = np.where(has_next, L / (L + length_next), 1.0)
    w_prev = np.where(has_prev, -h10 * c0, 0.0)
    w0 = h00 + np.where(has_prev, 0.0, -h10 * c0) - h11 * c1
    w1 = h01 + h10 * c0 + np.where(has_next, 0.0, h11 * c1)
    w_next = np.where(has_next, h11 * c1, 0.0)
    node_prev = np.where(prev >= 0, labels[np.maximum(prev, 0), 0], labels[mseg, 0])
    node_next = np.where(nxt >= 0, labels[np.maximum(nxt, 0), 1], labels[mseg, 1])
    master_nodes = np.unique(labels)
    slave_nodes = np.unique(slave.nodes)
    row_of = np.searchsorted(slave_nodes, slave.nodes)
    data, rows, cols = [], [], []
    for node, w in ((node_prev, w_prev), (labels[mseg, 0], w0), (labels[mseg, 1], w1), (node_next, w_next)):
        local = np.einsum("pg,pgi,pg->pi", weight, psi, w)                       # (p, 2)
        for end in (0, 1):
            data.append(local[:, end])
            rows.append(row_of[seg, end])
            cols.append(np.searchsorted(master_nodes, node))
    M = sp.csr_matrix((np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(slave_nodes.size, master_nodes.size))
    return slave_nodes, master_nodes, np.asarray(M.sum(axis=1)).ravel(), M


def mortar_rows_smooth(contact_set):
    """:func:`mortar_rows` of :func:`smooth_master_matrices`."""
    slave, master = contact_set.slave_surface, contact_set.master_surface
    slave_nodes, master_nodes, diagonal, M = smooth_master_matrices(contact_set)
    dim = contact_set.dim
    master_x = np.zeros((master_nodes.size, dim))
    master_x[np.searchsorted(master_nodes, master.nodes.ravel())] = master.x.reshape(-1, dim)
    rows_of = np.searchsorted(slave_nodes, contact_set.global_nodes)
    M = M[rows_of]
    measure = diagonal[rows_of]
    block = M.tocoo()
    data, rows, cols = [], [], []
    for k in range(dim):
        for component in range(dim):
            data += [contact_set.frames[:, k, component], -block.data * contact_set.frames[block.row, k, component]
                     / measure[block.row]]
            rows += [dim * np.arange(contact_set.nc) + k, dim * block.row + k]
            cols += [dim * contact_set.global_nodes + component, dim * master_nodes[block.col] + component]
    H = sp.csr_matrix((np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))), shape=contact_set.H.shape)
    normals = contact_set.frames[:, 0]
    gap = np.einsum("ij,ij->i", contact_set.coords - (M @ master_x) / measure[:, None], normals)
    return H, gap, measure


def run(h_punch, h_flat, formulation, order, gauss=2, recovery="nodal", geometry="punch"):
    """One model: its errors (package's read and consistent read)."""
    if gauss != 2:
        points, weights = np.polynomial.legendre.leggauss(gauss)
        mortar.GAUSS_POINTS, mortar.GAUSS_WEIGHTS = 0.5 + points / 2, weights / 2
    try:
        if geometry == "punch":
            P = rounded_punch_load(0.195, B, R, E_STAR)
            a = rounded_punch_half_width(P, B, R, E_STAR)
            closed_form = lambda x: rounded_punch_pressure(x, P, B, R, E_STAR)  # noqa: E731
            largest = closed_form(np.linspace(-a, a, 4001)).max()
            V, tags, bcs = punch_on_graded_flat(h_punch, h_flat, B, R)
        else:
            P = CYLINDER_P
            a, largest = hertz_line_contact(P, R, E_STAR)
            closed_form = lambda x: hertz_pressure(x, P, R, E_STAR)  # noqa: E731
            V, tags, bcs = cylinder_on_graded_flat(h_punch, h_flat)
        surface, master, normal = ORDERS[order]
        multipliers = formulation.split("-")[1] if "-" in formulation else None
        contact = dfr.Contact(V, (tags, surface), dfr.ElasticBody((tags, master), normal,
                                                                  formulation=formulation.split("-")[0]),
                              mu=0.0, bcs=bcs, window=0.5, pressure_recovery=recovery)
        if multipliers == "smooth":   # the master's trace a cubic spline of its nodal values
            contact_set = contact.contact_set
            H, gap, measure = mortar_rows_smooth(contact_set)
            assert np.allclose(measure, contact_set.tributary, rtol=1e-10)
            contact_set.H, contact_set.gap0 = H, gap
            contact._use(contact_set)
        elif multipliers is not None:   # the rows integrated anew: dual (a check of the rebuild) or standard
            contact_set = contact.contact_set
            H, gap = mortar_rows(contact_set, multipliers)
            if multipliers == "dual":
                assert abs(H - contact_set.H).max() < 1e-12 and np.allclose(gap, contact_set.gap0, atol=1e-14), \
                    (abs(H - contact_set.H).max(), np.abs(gap - contact_set.gap0).max())
            contact_set.H, contact_set.gap0 = H, gap
            contact._use(contact_set)
        problem = dfr.FrettingProblem(elasticity(V), contact, bcs, solver=dfr.LocalSolver(tol=1e-10))
        state = problem.advance(problem.initial_state(), normal=dfr.Force(P), tangential=dfr.Force(0.0))[0]
        fields = problem.contact_fields(state)
        contact_set = problem.contact.contact_set
        x = fields["coordinates"]
        force = np.asarray(state.forces).reshape(-1, 2)[:, 0]   # the normal contact forces r_n
        total = problem.total_force(state)[0]
        problem.destroy()
    finally:
        mortar.GAUSS_POINTS = 0.5 + np.array([-0.5, 0.5]) / np.sqrt(3.0)
        mortar.GAUSS_WEIGHTS = np.array([0.5, 0.5])
    exact = closed_form(x[:, 0])
    inner = np.abs(x[:, 0]) < 0.8 * a
    result = {"h_punch": h_punch, "h_flat": h_flat, "formulation": formulation, "slave": order, "gauss": gauss,
              "recovery": recovery, "geometry": geometry,
              "force_error": total / P - 1, "nodes_inside": int(inner.sum())}
    readings = [("lumped", fields["pressure"]), ("consistent", consistent_pressure(x, force))]
    if formulation.startswith("mortar"):
        readings.append(("master", through_master(contact_set, force)))
    for name, pressure in readings:
        error = (pressure - exact) / largest
        result[name] = {"rms": float(np.sqrt(np.mean(error[inner] ** 2))), "largest": float(np.abs(error[inner]).max()),
                        "peak": float(pressure.max() / largest - 1)}
    result["profile"] = {"x": x[inner, 0].tolist(), "error": ((fields["pressure"] - exact) / largest)[inner].tolist()}
    return result


CASES = [  # (h_punch / H, h_flat / H, formulation, slave, gauss)
    (1.0, 1.0, "node", "punch", 2), (1.0, 1.0, "mortar", "punch", 2),
    (1.0, 0.73, "mortar", "punch", 2), (1.0, 1.37, "mortar", "punch", 2),
    (1.0, 1.37, "mortar", "punch", 4),
    (0.73, 0.73, "node", "punch", 2), (1.37, 1.37, "node", "punch", 2), (2.0, 2.0, "node", "punch", 2),
    (1.0, 0.73, "mortar", "flat", 2), (1.0, 1.37, "mortar", "flat", 2),
    (1.0, 0.73, "node", "flat", 2), (1.0, 1.37, "node", "flat", 2),
    (1.0, 2.0, "node", "punch", 2), (1.0, 2.0, "mortar", "punch", 2), (1.0, 2.0, "mortar", "flat", 2),
    (1.0, 0.5, "node", "punch", 2), (1.0, 0.5, "mortar", "punch", 2), (1.0, 0.5, "mortar", "flat", 2),
    (1.37, 1.0, "mortar", "punch", 2), (1.37, 1.0, "mortar", "flat", 2),
    (1.0, 1.37, "mortar-dual", "punch", 2), (1.0, 1.37, "mortar-standard", "punch", 2),
    (1.0, 1.37, "mortar-standard", "flat", 2), (1.0, 0.73, "mortar-standard", "punch", 2),
    (1.0, 1.0, "mortar-standard", "punch", 2),
    (1.0, 1.37, "mortar", "punch", 2, "smoothed"), (1.37, 1.37, "node", "punch", 2, "smoothed"),
    # b = 0.1 a node of both meshes (8 x 1.25 h, 12 x h / 1.2)
    (1.25, 1.25, "node", "punch", 2), (1.0, 1.25, "mortar", "punch", 2), (1.0, 1.25, "mortar", "flat", 2),
    (1 / 1.2, 1 / 1.2, "node", "punch", 2), (1.0, 1 / 1.2, "mortar", "punch", 2), (1.0, 1 / 1.2, "mortar", "flat", 2),
    # the master's trace a cubic spline (an experiment: mortar_rows_smooth)
    (1.0, 1.0, "mortar-smooth", "punch", 4), (1.0, 1.37, "mortar-smooth", "punch", 4),
    (1.0, 1.37, "mortar-smooth", "flat", 4), (1.0, 0.73, "mortar-smooth", "punch", 4),
    (1.0, 0.73, "mortar-smooth", "flat", 4), (1.0, 2.0, "mortar-smooth", "punch", 4),
    (1.0, 2.0, "mortar-smooth", "flat", 4), (1.0, 0.5, "mortar-smooth", "punch", 4),
    (1.0, 1.25, "mortar-smooth", "punch", 4), (1.0, 1.25, "mortar-smooth", "flat", 4),
]


def render(meta, results):
    """The results as a Markdown table (errors in % of the largest closed-form pressure)."""
    lines = [f"Command: `{meta['command']}`", "", f"Date: {meta['date']}; machine: {meta['machine']}; Python "
             f"{meta['python']}; geometry: {meta['geometry']}.", "",
             "| # | slave body's h | flat's h | formulation | slave | read | RMS % | largest % | peak % "
             "| consistent RMS % | through-master RMS % | nodes |", "|" + " --- |" * 12]
    for index, result in enumerate(results):
        lumped = result["lumped"]
        master = f"{100 * result['master']['rms']:.3f}" if "master" in result else "-"
        quadrature = "" if result["gauss"] == 2 else f" ({result['gauss']} Gauss points)"
        lines.append(f"| {result['index']} | {result['h_punch'] / H:.3g} h | {result['h_flat'] / H:.3g} h "
                     f"| {result['formulation']}{quadrature} | {result['slave']} | {result['recovery']} "
                     f"| {100 * lumped['rms']:.3f} | {100 * lumped['largest']:.2f} | {100 * lumped['peak']:+.2f} "
                     f"| {100 * result['consistent']['rms']:.3f} | {master} | {result['nodes_inside']} |")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=None, help="write OUT.json and OUT.md")
    parser.add_argument("--only", type=int, nargs="*", default=None, help="the cases' indices to run")
    parser.add_argument("--geometry", choices=("punch", "cylinder"), default="punch",
                        help="the rounded punch (row 59) or the cylinder (Hertz; row 58's pressure)")
    args = parser.parse_args()
    results = []
    for index, (punch, flat, formulation, order, gauss, *recovery) in enumerate(CASES):
        recovery = recovery or ["nodal"]
        if args.only is not None and index not in args.only:
            continue
        start = time.perf_counter()
        result = run(punch * H, flat * H, formulation, order, gauss, recovery[0], args.geometry)
        result["index"] = index
        results.append(result)
        lumped, consistent = result["lumped"], result["consistent"]
        print(f"{index:2d} {recovery[0]:8s} {args.geometry[0]} {punch:4.2f}h flat {flat:4.2f}h {formulation:15s} "
              f"slave {order:5s} gauss {gauss}: "
              f"RMS {100 * lumped['rms']:.3f} % largest {100 * lumped['largest']:.2f} % peak "
              f"{100 * lumped['peak']:+.2f} % | consistent {100 * consistent['rms']:.3f} % "
              f"{100 * consistent['largest']:.2f} % {100 * consistent['peak']:+.2f} % "
              + (f"| master {100 * result['master']['rms']:.3f} % {100 * result['master']['largest']:.2f} % "
                 f"{100 * result['master']['peak']:+.2f} % " if "master" in result else "")
              + 
              f"(P {result['force_error']:.1e}, {result['nodes_inside']} nodes, {time.perf_counter() - start:.0f} s)",
              flush=True)
    if args.out:
        meta = {"command": " ".join(["OPENBLAS_NUM_THREADS=1", Path(sys.executable).name] + sys.argv),
                "date": datetime.datetime.now().isoformat(timespec="seconds"), "machine": cpu_model(),
                "python": platform.python_version(), "geometry": args.geometry}
        Path(args.out + ".json").write_text(json.dumps({"meta": meta, "results": results}, indent=1))
        Path(args.out + ".md").write_text(render(meta, results))


if __name__ == "__main__":
    main()
