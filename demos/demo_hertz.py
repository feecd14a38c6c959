# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: light
# ---

# # Hertz line contact and partial slip of a cylinder on a rigid flat
#
# An elastic half-cylinder (radius $R$) is pressed on a rigid plane by a total force $P$ per unit
# thickness, then pulled sideways by a tangential force $Q < \mu P$. Without friction the pressure is
# Hertz's
#
# $$ p(x) = p_0 \sqrt{1 - x^2/a^2}, \qquad a = \sqrt{\frac{4 P R}{\pi E^*}}, \qquad p_0 = \frac{2P}{\pi a},
# \qquad E^* = \frac{E}{1-\nu^2}. $$
#
# The contact is solved on the Delassus matrix $W = H K^{-1} H^T$ by the Uzawa iteration with De Saxcé's
# projection onto the Coulomb cone; see docs/method.md for the method.

# +
import os
from pathlib import Path

import numpy as np
from mpi4py import MPI

from dolfinx_fretting.analytic import hertz_line_contact
from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import run_scene

# Parameters (N, mm, MPa; forces per mm of thickness)
P = 199.24             # normal force
Q_over_muP = 0.5       # tangential force as a fraction of mu P
mu = 0.9
h = 0.01               # contact element size
if "CI" in os.environ:  # CI-sized run
    h = 0.02
out = Path("results/demo_hertz")
rank0 = MPI.COMM_WORLD.rank == 0  # under mpirun every rank runs the scene; rank 0 prints
# -

# Run the built-in `hertz` scene with these values.

scene = load_scene("hertz", [f"loading.normal_force={P}", f"loading.tangential_force={Q_over_muP * mu * P}",
                             f"contact.mu={mu}", f"geometry.contact_mesh_size={h}"])
summary = run_scene(scene, out, overwrite=True)  # a rerun replaces its own run

# Compare the end of the preload with Hertz (friction changes the rigid-flat answer by a few percent
# only; the test suite checks the frictionless case to 1 %).

a, p0 = hertz_line_contact(P, scene.geometry.radius, scene.material.E / (1 - scene.material.nu**2))
if rank0:
    print(f"Hertz: a = {a:.4f} mm, p0 = {p0:.1f} MPa; computed: "
          f"half-width = {summary['contact_width'] / 2:.4f} mm, p_max = {summary['max_pressure']:.1f} MPa, stick width = {summary['stick_width']:.4f} mm")
    print(f"pictures: {out / 'profiles.png'}; fields for ParaView: {out / 'fields.xdmf'}")
