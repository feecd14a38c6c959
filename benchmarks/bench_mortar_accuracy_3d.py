"""Where mortar's error on non-matching 3D faces comes from (issue 23, validation row 63): the sphere (R = 10 mm,
steel) on an identical flat, frictionless, half model, the depth-graded hexahedra of tests/test_mortar_3d.py (the
sphere at a/h = 6; the flat's contact elements at its own a/h), P = 100 N; the slave the sphere or the flat, node-to-
face or mortar (dual). Errors of the nodal pressure (the package's read) at the slave's nodes against Hertz, of p0:
the largest pressure's, RMS and largest inside r < 0.8 a.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_mortar_accuracy_3d.py [--only 0 1 ...] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI
from dolfinx import fem

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))
sys.path.insert(0, str(HERE.parent))

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import _dolfinx as dfx  # noqa: E402
from dolfinx_fretting import meshes_3d as m3  # noqa: E402
from dolfinx_fretting.analytic import hertz_sphere, hertz_sphere_pressure  # noqa: E402
from support.sphere import P, R, contact_modulus, elasticity, pressed  # noqa: E402


def run(sphere_a_over_h, flat_a_over_h, formulation, slave):
    E_star = contact_modulus(True)
    a, p0 = hertz_sphere(P, R, E_star)
    h = a / sphere_a_over_h
    # The flat as slave: a whole model (its frames are the sphere's normals at the closest points, which on the half
    # model's symmetry plane lean out of it, and the roller there would make the compliance singular)
    half = slave == "sphere"
    load = P / 2 if half else P
    body = m3.sphere_on_flat(MPI.COMM_WORLD, R, a, h, extent=9.0, growth=1.5, half=half, flat=True,
                             flat_mesh_size=None if flat_a_over_h is None else a / flat_a_over_h,
                             depth_growth=1.5, coarsening=2, field_cell=0.125)
    V = dfx.vector_space(body.mesh, 1)
    bcs = [fem.dirichletbc(np.zeros(3), fem.locate_dofs_topological(V, 2, body.facets(name)), V)
           for name in ("top", "flat_bottom")]
    if half:
        V1, _ = V.sub(1).collapse()
        sym = np.concatenate([body.facets(n) for n in body.tags if "symmetry" in n])
        bcs += [fem.dirichletbc(fem.Function(V1), fem.locate_dofs_topological((V.sub(1), V1), 2, sym), V.sub(1))]
    sphere_tag, flat_tag = body.tags["surface"], body.tags["flat_top"]
    slave_tag, master_tag, normal = (sphere_tag, flat_tag, [0.0, 0.0, 1.0]) if slave == "sphere" else \
        (flat_tag, sphere_tag, [0.0, 0.0, -1.0])
    contact = dfr.Contact(V, (body.facet_tags, slave_tag),
                          dfr.ElasticBody((body.facet_tags, master_tag), normal, formulation=formulation),
                          mu=0.0, bcs=bcs, window=1.4 * a + h)
    problem = dfr.FrettingProblem(elasticity(V), contact, bcs, solver=dfr.LocalSolver(tol=1e-10))
    state = pressed(problem, load)
    force = problem.total_force(state)[0]
    fields = problem.contact_fields(state)
    problem.destroy()
    r = np.linalg.norm(fields["coordinates"][:, :2], axis=1)
    pressure = fields["pressure"]
    error = (pressure - hertz_sphere_pressure(r, P, R, E_star)) / p0
    inner = r < 0.8 * a
    return {"sphere_a_over_h": sphere_a_over_h, "flat_a_over_h": flat_a_over_h, "formulation": formulation,
            "slave": slave, "force_error": force / load - 1, "half": half, "peak": float(pressure.max() / p0 - 1),
            "rms": float(np.sqrt(np.mean(error[inner] ** 2))), "largest": float(np.abs(error[inner]).max()),
            "nodes_inside": int(inner.sum())}


CASES = [  # (sphere a/h, flat a/h (None: matching), formulation, slave)
    (6, None, "node", "sphere"), (6, 4.38, "mortar", "sphere"), (6, 4.38, "mortar", "flat"),
    (4.38, None, "node", "sphere"), (6, 8.2, "mortar", "sphere"), (6, 8.2, "mortar", "flat"),
    (6, 4.38, "node", "flat"),
]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", type=int, nargs="*", default=None)
    parser.add_argument("--out", default=None, help="append the results to this JSON-lines file")
    args = parser.parse_args()
    for index, case in enumerate(CASES):
        if args.only is not None and index not in args.only:
            continue
        start = time.perf_counter()
        result = run(*case)
        print(f"{index} sphere a/h {case[0]} flat a/h {case[1]} {case[2]:6s} slave {case[3]:6s}: peak "
              f"{100 * result['peak']:+.2f} % RMS {100 * result['rms']:.2f} % largest {100 * result['largest']:.2f} % "
              f"(P {result['force_error']:.1e}, {result['nodes_inside']} nodes, {time.perf_counter() - start:.0f} s)",
              flush=True)
        if args.out:
            with open(args.out, "a") as stream:
                stream.write(json.dumps(result) + "\n")


if __name__ == "__main__":
    main()
