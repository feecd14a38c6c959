"""Write the sphere-flat scene's local problems (W, q, mu, warm start) at a given size as FCLIB-like .npz files.

The problems of ``bench_contacts_3d.py`` (the preload's last increment P/2 -> P and a gross-slip increment
10 -> 12 um, each formed exactly as the package forms it, with the previous increment's forces as warm start),
saved with ``dolfinx_fretting.fclib.save`` so that the local-solve benchmarks (``bench_local_speed.py``) can run
them again and again without rebuilding the model (the build takes minutes and several GB at ~1000 contacts; the
files are tens to hundreds of MB, so they go to a scratch folder, not into the repository).

Extra fields of each file: ``r0`` (the warm start), ``r_package`` (the package's answer), ``coords`` (contact
points), ``h_mm``, ``dofs``, ``build_s`` (the model's build: mesh, K, factorisation, W).

``--half-space N ...`` writes, instead of (or besides) the FE problems, the same two increments on a synthetic W
of the same structure at N x N contacts: two like elastic half-spaces (Boussinesq and Cerruti point-force
compliances, 1/r decay; ``tests/support/local_problems.half_space``, the tests' problem), a sphere whose contact
radius is a third of the grid's side (the scene's window of 1.5 a), mu = 0.8, the preload from r = 0 to the
approach d and a gross-slip increment 2.9 d -> 3.4 d (the scene's 10 -> 12 um over its 3.5 um approach), warm
started from the solution of the increment before. They cost seconds where the FE model costs minutes and GB, so
they reach contact counts the factorisation does not (``benchmarks/results/contacts_3d.md``).

Usage (from the repository root)::

    OPENBLAS_NUM_THREADS=1 nice -n 5 .venv/bin/python benchmarks/make_sphere_flat_problems.py \
        --sizes 0.0155 0.0117 --half-space 32 45 --out /tmp/sphere_flat_problems
"""

from __future__ import annotations

import argparse
import gc
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from bench_contacts_3d import COMM, local_problems, scene_for  # noqa: E402  (MPI first, as there)

from dolfinx_fretting import fclib, local_solvers, sizes  # noqa: E402
from dolfinx_fretting.simulation import ContactModel  # noqa: E402

sys.path.insert(0, str(HERE.parent / "tests"))  # the tests' half-space problem: one declaration of it
from support.local_problems import half_space, sphere_flat_q  # noqa: E402

MU = 0.8  # the sphere-flat scene's


def write_half_space(n_side: int, out: Path) -> None:
    """The preload (from r = 0) and gross-slip (warm) increments on the half-space W at n_side^2 contacts."""
    t0 = time.perf_counter()
    W, xy = half_space(n_side)
    approach = 1.0
    radius = (n_side / 3.0) ** 2 / approach  # Hertz's a^2 = R d: a contact radius of a third of the side
    nc = xy.shape[0]
    steps = local_solvers.block_rho(W, 3)
    preload = sphere_flat_q(xy, radius, approach, 0.0)
    before = local_solvers.solve(W, sphere_flat_q(xy, radius, approach, 2.9 * approach), MU, 3, method="nsgs",
                                 max_iter=20000, block_steps=steps, raise_on_failure=True)
    gross = sphere_flat_q(xy, radius, approach, 3.4 * approach)
    build_s = time.perf_counter() - t0
    for tag, q, r0 in (("preload", preload, np.zeros(3 * nc)), ("gross_slip", gross, before.r)):
        path = fclib.save(out / f"half_space_{nc}_{tag}.npz", W, q, MU, 3,
                          name=f"half-space sphere-flat {nc} contacts, {tag}",
                          source=f"benchmarks/make_sphere_flat_problems.py --half-space {n_side}", r0=r0,
                          coords=xy, build_s=build_s)
        print(f"  wrote {path}", flush=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=float, nargs="*", default=[], help="geometry.contact_mesh_size values (mm)")
    ap.add_argument("--half-space", type=int, nargs="*", default=[],
                    help="grid sides N of the synthetic half-space problems (N^2 contacts)")
    ap.add_argument("--out", type=Path, required=True, help="folder of the .npz files (a scratch folder)")
    ap.add_argument("--prep-method", default="uzawa", help="local method of the package's own increments")
    ap.add_argument("--memory-fraction", type=float, default=0.7,
                    help="skip a size whose estimated peak exceeds this share of the available memory")
    args = ap.parse_args(argv)
    for n_side in args.half_space:
        write_half_space(n_side, args.out)
    for h in args.sizes:
        scene = scene_for(h, args.prep_method)
        est = sizes.estimate(scene)
        available, _ = sizes.available_memory()
        print(f"h = {h:g} mm: {est.describe()}; available {available / 2**30:.1f} GB", flush=True)
        if est.total_bytes > args.memory_fraction * available:
            print(f"  skipped: estimated peak {est.total_bytes / 2**30:.1f} GB > {args.memory_fraction:g} x "
                  f"available", flush=True)
            continue
        t0 = time.perf_counter()
        model = ContactModel(scene, COMM)
        build_s = time.perf_counter() - t0
        contact = model.contact
        print(f"  model {build_s:.1f} s: {model.n_dofs} dofs, {contact.nc} contacts, "
              f"factorise {model.problem.operators.delassus.stats.get('factorize_time', float('nan')):.1f} s, "
              f"W {model.timings.get('delassus_s', float('nan')):.1f} s", flush=True)
        W = np.asarray(model.W)
        for k, problem in enumerate(local_problems(model)):
            tag = "preload" if k == 0 else "gross_slip"
            path = fclib.save(args.out / f"sphere_flat_{contact.nc}_{tag}.npz", W, problem["q"],
                              float(model.scene.contact.mu), 3, name=f"sphere-flat {contact.nc} contacts, "
                              f"{problem['name']}", source=f"benchmarks/make_sphere_flat_problems.py h={h}",
                              r0=problem["warm"], r_package=problem["package_r"], coords=np.asarray(contact.coords),
                              h_mm=h, dofs=model.n_dofs, build_s=build_s)
            print(f"  wrote {path}", flush=True)
        model.problem.destroy()
        del model, W
        gc.collect()
    return 0


if __name__ == "__main__":
    sys.exit(main())
