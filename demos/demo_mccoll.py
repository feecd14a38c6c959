# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: light
# ---

# # McColl's fretting test: a Ti-6Al-4V cylinder rubbing on a flat for 18 000 cycles
#
# McColl, Ding and Leen (*Wear* 256, 2004, 1114–1127) pressed a cylinder of radius $R = 6$ mm on a flat with
# 185 N over a 10 mm wide specimen ($P = 18.5$ N/mm in plane strain) and rubbed it with a stroke of
# $\delta = \pm 25$ µm, $\mu = 0.9$, for 18 000 cycles. The flat's scar was about 2.9 µm deep and 0.55–0.60 mm
# wide; their finite-element reproduction, with Archard coefficients $k_f = 2.9\times10^{-8}$ and
# $k_c = 1.9\times10^{-8}$ MPa$^{-1}$ for the flat and the cylinder, gave 0.37, 1.12, 1.81 and 2.71 µm at
# 1 000, 5 000, 10 000 and 18 000 cycles, in 4.7 CPU-hours.
#
# Here both bodies are meshed (`contact.obstacle = "elastic_flat"`), both wear (`wear.k_slave`,
# `wear.k_master`), the bodies are paired anew as they slide (`contact.sliding = "finite"`: the flat's wear stays
# on the flat's own nodes, so its scar spans the contact plus the stroke, as on the specimen), and each
# simulated cycle stands for 25 physical ones (`wear.acceleration = 25`, under the
# explicit update's stability limit $0.37\,h/(k\,\delta\,E^*) \approx 47$ cycles at $h = 10$ µm). In gross slip
# under a constant force, once the scar is much wider than the stroke, the total wear depth follows the
# wear-in asymptote
#
# $$ h(N) = \left[\frac{3\,k\,\delta\,P\,N}{\sqrt{2R}}\right]^{2/3}, \qquad k = k_f + k_c, $$
#
# of which the flat takes the share $k_f/k$.

# +
import csv
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from mpi4py import MPI

from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import run_scene

acceleration = 25            # physical cycles per simulated cycle
cycles = 720                 # simulated cycles (x 25 = 18 000)
contact_mesh_size = 0.01     # mm
out = Path("results/demo_mccoll")
published_fe = {1000: 0.37e-3, 5000: 1.12e-3, 10000: 1.81e-3, 18000: 2.71e-3}   # mm, flat
published_test = (2.9e-3, (0.55, 0.60))                                          # depth (mm), width (mm)
if "CI" in os.environ:       # CI-sized: a coarse contact mesh and 100 physical cycles
    cycles, contact_mesh_size = 4, 0.02
snapshots = sorted({c for c in (40, 200, 400, cycles) if c <= cycles})
rank0 = MPI.COMM_WORLD.rank == 0  # under mpirun every rank runs the scene; rank 0 reads, prints and draws
# -

# Run the scene (its inputs are in `dolfinx_fretting/builtin_scenes/mccoll.toml`).

scene = load_scene("mccoll", [f"loading.cycles={cycles}", f"wear.acceleration={acceleration}",
                              f"geometry.contact_mesh_size={contact_mesh_size}",
                              f"output.snapshot_cycles={snapshots}", "output.progress=false"])
summary = run_scene(scene, out, quiet=True, overwrite=True)  # a rerun replaces its own run
share = summary["wear_k_master"] / summary["wear_k"]          # the flat's part of the wear gap
if rank0:
    print(f"{summary['cycles']} simulated cycles = {summary['equivalent_cycles']:.0f} physical, "
          f"{summary['wall_time_s']:.0f} s; flat's max wear depth {summary['max_wear_depth_master'] * 1e3:.3f} um")

# The flat's worn profile at each snapshot: its depth at its own nodes at the end of the cycle
# (`flat_profiles.csv`). The scar's width is where the flat has lost more than 2 % of its maximum depth. Rank 0
# reads the finished run's files and reports.


def scar_width(x, depth):
    worn = x[depth > 0.02 * depth.max()]
    return float(worn.max() - worn.min()) if worn.size else 0.0


def flat_profiles():
    """{snapshot cycle: (position, the flat's worn depth)} at the end of each snapshot cycle."""
    with open(out / "flat_profiles.csv") as f:
        rows = list(csv.DictReader(f))
    profiles = {}
    for c in snapshots:
        sel = [r for r in rows if int(r["cycle"]) == c]
        x = np.array([float(r["position"]) for r in sel])
        order = np.argsort(x)
        profiles[c] = (x[order], np.array([float(r["wear"]) for r in sel])[order])
    return profiles


k, P, delta, R = summary["wear_k"], 18.5, 0.025, 6.0


def asymptote(N):
    return share * (3 * k * delta * P * np.asarray(N, dtype=float) / np.sqrt(2 * R)) ** (2 / 3)


if rank0:
    profiles = flat_profiles()
    table = ["| physical cycles | flat depth here (µm) | McColl FE (µm) | wear-in asymptote, flat (µm) | "
             "scar width here (mm) |", "| --- | --- | --- | --- | --- |"]
    for c in snapshots:
        N = c * acceleration
        x, depth = profiles[c]
        fe = f"{published_fe[N] * 1e3:.2f}" if N in published_fe else "–"
        table.append(f"| {N} | {depth.max() * 1e3:.3f} | {fe} | {asymptote(N) * 1e3:.3f} | "
                     f"{scar_width(x, depth):.3f} |")
    table.append(f"| test (18 000) | measured {published_test[0] * 1e3:.1f} µm deep, {published_test[1][0]}–"
                 f"{published_test[1][1]} mm wide | | | |")
    print("\n".join(table))
    (out / "mccoll_table.md").write_text("\n".join(table) + "\n")

# Two pictures: the flat's worn profile at the snapshots, and its depth against the number of cycles beside
# the published values and the asymptote.

# +
if rank0:
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    for c in snapshots:
        x, depth = profiles[c]
        ax1.plot(x, -depth * 1e3, label=f"{c * acceleration} cycles")
    ax1.set(xlabel="x (mm)", ylabel="flat surface (µm)", title="Flat's worn profile")
    ax1.legend()
    with open(out / "cycles.csv") as f:
        cyc = list(csv.DictReader(f))
    N = np.array([float(r["equivalent_cycles"]) for r in cyc])
    ax2.plot([c * acceleration for c in snapshots], [profiles[c][1].max() * 1e3 for c in snapshots], "o-",
             label="here (snapshots)")
    ax2.plot(N, asymptote(N) * 1e3, "--", label="wear-in asymptote")
    ax2.plot(list(published_fe), [v * 1e3 for v in published_fe.values()], "s", label="McColl et al. FE")
    ax2.plot([18000], [published_test[0] * 1e3], "k*", markersize=10, label="McColl et al. test")
    ax2.set(xlabel="cycles", ylabel="flat's max wear depth (µm)", title="Wear growth")
    ax2.legend()
    fig.tight_layout()
    fig.savefig(out / "mccoll.png", dpi=120)
    print("wrote", out / "mccoll.png")
# -
