# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: light
# ---

# # Cylinder on flat, elastic against elastic–plastic (the paper's Example 2)
#
# A cylinder of radius $R = 6$ mm (Table 2 material: $E = 115$ GPa, $\nu = 0.342$, $\mu = 0.9$) is pressed
# on a flat by $P = 199.24$ N/mm and rubbed by a triangular tangential displacement of amplitude
# $\delta$: 0.03 mm (gross slip, 80 increments a cycle) in the built-in scene `cylinder-flat`. Wear follows
# Archard's law $\dot g_w = k\,p\,|\dot x_t|$ with $k = 8.5\times 10^{-9}$ MPa$^{-1}$ and, as in the
# paper, a hundredfold "hypothetical" coefficient (`wear.acceleration = 100`) to see the trend of
# $100\times 100$ cycles.
#
# The elastic–plastic body is von Mises with linear isotropic hardening,
# $\sigma_y(p) = \sigma_{y0} + H p$ with $\sigma_{y0} = 840$ MPa and $H = 7230$ MPa. Each increment then
# runs Newton–Raphson on equilibrium with the contact problem $x = W r + q$ solved inside every iteration
# (paper Fig. 4); the wear gap is updated once the increment has converged.
#
# The flat is a second body of the same material, as in the paper (`contact.obstacle = "elastic_flat"`:
# the cylinder's contact nodes are paired with points of the flat's top, both bodies deform, and both yield
# in the elastic–plastic case). Hertz for two identical bodies gives $p_0 = 829.6$ MPa at this load.

# +
import os
from pathlib import Path

from mpi4py import MPI

from dolfinx_fretting.compare import compare_runs
from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import run_scene

cycles = 100                 # fretting cycles of each run
contact_mesh_size = 0.01     # mm
accelerations = [1, 100]     # the real and the hundredfold wear coefficient
plastic = ["material.model='elastoplastic'", "material.yield_stress=840", "material.hardening_modulus=7230"]
out = Path("results/demo_cylinder_flat")
rank0 = MPI.COMM_WORLD.rank == 0  # under mpirun every rank runs the scenes; rank 0 prints and compares
if "CI" in os.environ:       # CI-sized: a coarse contact mesh, 2 short cycles
    cycles, contact_mesh_size = 2, 0.02
    extra = ["loading.increments_per_cycle=8", "output.xdmf=false"]
else:
    extra = []
# -

# Run the four cases: elastic and elastic–plastic, each with both wear coefficients.

folders = []
for acc in accelerations:
    for name, material in (("elastic", []), ("elastic-plastic", plastic)):
        folder = out / f"{name}-k{acc}"
        scene = load_scene("cylinder-flat", [f"loading.cycles={cycles}",
                                             f"geometry.contact_mesh_size={contact_mesh_size}",
                                             f"wear.acceleration={acc}",
                                             f"output.snapshot_cycles=[1, {max(1, cycles // 2)}, {cycles}]",
                                             *material, *extra])
        summary = run_scene(scene, folder, quiet=True, overwrite=True)  # a rerun replaces its own run
        if rank0:
            print(f"{name:16s} k x{acc:<4d}: peak pressure {summary['max_pressure']:.1f} MPa, "
                  f"max wear depth {summary['max_wear_depth']:.3e} mm, {summary['wall_time_s']:.0f} s")
        folders.append(folder)

# Compare them as the paper's Figs. 13–16 do: wear gap and pressure after the first cycle and over the
# cycles, and the centre node's state history in the first cycle (Fig. 14).

if rank0:  # reads the finished runs' files: no MPI
    written = compare_runs(folders[:2], None, out / "real_k")
    written += compare_runs(folders[2:], None, out / "hundredfold_k")
    for path in written:
        print("wrote", path)
