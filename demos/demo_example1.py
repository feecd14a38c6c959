# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: light
# ---

# # Wear of an elastic block rubbed on a rigid plate (the paper's Example 1, after Strömberg)
#
# An elastic block of $50 \times 50$ mm (plane strain, $E = 210$ GPa, $\nu = 0.3$) is fixed at its top.
# Its bottom face starts with an interference $u = 10^{-4}$ mm with a rigid plate (the preload), and its
# right face carries a pressure $q(t)$ that alternates between $+10$ and $-10$ MPa along a triangular path,
# 80 increments a cycle. Contact at the bottom nodes is Coulomb friction with $\mu = 0.4$: with the gap
# $x_n$ and the contact forces $(r_n, r_t)$ of a node,
#
# $$ x_n \ge 0, \quad r_n \ge 0, \quad x_n r_n = 0, \qquad |r_t| \le \mu r_n, \quad
#    |r_t| < \mu r_n \Rightarrow \Delta x_t = 0 , $$
#
# solved at every increment on the Delassus matrix $W = H K^{-1} H^T$ by the Uzawa iteration with De Saxcé's
# projection. The surface wears by Archard's law: the wear gap of a sliding node grows by
#
# $$ \Delta g_w = k \, p \, |\Delta x_t|, \qquad k = 10^{-5}\ \mathrm{MPa}^{-1}, $$
#
# with $p$ the contact pressure, and the worn gap enters the next increment's contact problem. Over 9000
# cycles the preload wears away: the edges first, then the whole face, and the pressure at $q = 0$ falls to
# zero (the paper's Figs. 6–9).

# +
import os
from pathlib import Path

from mpi4py import MPI

from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import run_scene

cycles = 9000                 # the paper's full run (about 20 s on one core)
elements = 50                 # n x n four-node elements (1 mm)
snapshots = [1, 10, 100, 500, 1000, 2000, 3000, 5000, 9000]
out = Path("results/demo_example1")
if "CI" in os.environ:        # CI-sized: a coarse mesh and 3 cycles
    cycles, elements, snapshots = 3, 20, [1, 3]
rank0 = MPI.COMM_WORLD.rank == 0
# -

# Run the built-in `stromberg-block` scene (Table 1's values) with these sizes.

scene = load_scene("stromberg-block", [f"loading.cycles={cycles}", f"geometry.nx={elements}",
                                       f"geometry.ny={elements}", f"output.snapshot_cycles={snapshots}",
                                       f"output.loop_cycles=[1, {cycles}]", "output.progress=false"])
summary = run_scene(scene, out, quiet=True, overwrite=True)  # a rerun replaces its own run

# The summary: contact forces at the last increment, the deepest wear and the worn area of the face, and the
# regime of the last cycle.

if rank0:
    print(f"{summary['cycles']} cycles: P = {summary['normal_force']:.5g} N/mm, "
          f"max wear depth = {summary['max_wear_depth']:.4e} mm (preload u = 1e-4 mm), "
          f"wear area = {summary['wear_area']:.4e} mm^2, regime: {summary['regime']}, "
          f"{summary['wall_time_s']:.1f} s")

# The figures are in the output folder: `wear_first_cycle.png` (Fig. 6: wear gap and pressure at the four
# quarter points of cycle 1), `wear_evolution.png` (Fig. 7: over the snapshot cycles), `node_history.png`
# (Figs. 8–9: states of an edge node and the centre node), `fretting_loops.png`, `wear_growth.png`, and the
# pyvista pictures `deformed_von_mises.png` and `worn_profile.png`; `fields.xdmf` and `contact.xdmf` open
# in ParaView.

if rank0:
    for png in sorted(out.glob("*.png")):
        print("wrote", png)
