# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: light
# ---

# # One body, two contact zones: a pad in a corner, pressed on a floor, bearing on a wall, fretted along the floor
#
# Real fretting hardware touches in more than one place: a dovetail's two flanks, a key in its keyway, a
# bridge-type pad's two feet. Here a rectangular pad, clamped at its top, rests on a rigid floor (zone 1) and
# bears on a rigid wall beside it (zone 2, an interference fit). The floor is pressed up with a normal force
# $P$ and rubbed sideways (fretting cycles, Coulomb friction, Archard wear); the wall stays where it was put.
# Both zones are one problem: `FrettingProblem(a, [floor, wall], ...)`, one W = H K⁻¹ Hᵀ from one
# factorisation, so the floor's load changes the wall's contact and back.
#
# The check is an identity that needs no package code: the pad is in equilibrium, so the contact forces of the
# two zones (in the global frame) balance the clamp's reaction, computed here by plain DOLFINx from the
# displacement, $R = K_{\text{unconstrained}}\,u$ on the clamped dofs.

# +
import json
import os
from pathlib import Path

import numpy as np
from mpi4py import MPI  # first: the DOLFINx 0.11 wheel needs the MPI library that mpi4py loads
import ufl
import dolfinx.fem.petsc  # noqa: F401 (fem.petsc: the clamp's reaction below)
from dolfinx import fem, mesh
from petsc4py import PETSc

import dolfinx_fretting as dfr
from dolfinx_fretting.compat import vector_space

E, nu = 210000.0, 0.3            # MPa
width, height = 4.0, 2.0         # the pad (mm)
P, interference = 400.0, 2e-4    # floor force (N/mm), wall interference (mm)
mu_floor, mu_wall, k = 0.6, 0.3, 1e-6
stroke, cycles, n = 2e-3, 10, 80 # floor motion amplitude (mm), cycles, elements along the width
if "CI" in os.environ:           # CI-sized run
    cycles, n = 3, 40
out = Path("results/demo_two_zones")
comm = MPI.COMM_WORLD
# -

# ## The user's model: mesh, space, form, a clamped top
#
# The wall touches the pad's side above a relief at its foot (y ≥ 0.25 mm): a node in two zones that both have
# friction (the corner) would carry two frictional constraints on the same displacement, whose split is not
# unique (the problem warns; the local solver then converges slowly). A frictionless corner in two zones is
# exact (`tests/test_zones.py`).

# +
msh = mesh.create_rectangle(comm, [np.array([0.0, 0.0]), np.array([width, height])], [n, n // 2],
                            mesh.CellType.quadrilateral)
V = vector_space(msh, 1)
u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
lmbda, G = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
a = ufl.inner(lmbda * ufl.tr(eps(u)) * ufl.Identity(2) + 2 * G * eps(u), eps(v)) * ufl.dx   # plane strain
fdim = 1
faces = {1: mesh.locate_entities_boundary(msh, fdim, lambda x: np.isclose(x[1], 0.0)),      # the floor side
         2: mesh.locate_entities_boundary(msh, fdim, lambda x: np.isclose(x[0], width) & (x[1] >= 0.25)),
         3: mesh.locate_entities_boundary(msh, fdim, lambda x: np.isclose(x[1], height))}   # the clamped top
facets = np.concatenate(list(faces.values()))
markers = np.concatenate([np.full(f.size, m, dtype=np.int32) for m, f in faces.items()])
order = np.argsort(facets)
tags = mesh.meshtags(msh, fdim, facets[order], markers[order])
clamped = fem.locate_dofs_topological(V, fdim, tags.find(3))
bcs = [fem.dirichletbc(np.zeros(2, dtype=PETSc.ScalarType), clamped, V)]
# -

# ## The plugin: two zones, each with its obstacle and friction coefficient
#
# Each plane's normal points from the obstacle into the pad. The targets name the zone: `normal={floor:
# Force(P), wall: interference}` presses the floor with the force P and puts the wall at its interference; the
# cycle holds the floor at the approach found and moves it alone (`tangential={floor: ...}`), the wall keeping
# its place (a zone not named keeps its targets).

# +
floor = dfr.Contact(V, (tags, 1), dfr.RigidPlane([0.0, 0.0], [0.0, 1.0]), mu=mu_floor, bcs=bcs)
wall = dfr.Contact(V, (tags, 2), dfr.RigidPlane([width, 0.0], [-1.0, 0.0]), mu=mu_wall, bcs=bcs)
problem = dfr.FrettingProblem(a, [floor, wall], bcs, wear=dfr.Archard(k))
state = problem.initial_state()
for fraction in (0.25, 0.5, 0.75, 1.0):
    state, _ = problem.advance(state, normal={floor: dfr.Force(fraction * P), wall: fraction * interference})
preload = {name: problem.total_force(state, zone) for name, zone in (("floor", floor), ("wall", wall))}
path = dfr.CyclePath.waveform(40, normal={floor: state.obstacle[0]}, tangential={floor: stroke})
loops, energy = [], []
for cycle in range(1, cycles + 1):
    last = cycle == cycles
    result = problem.run_cycle(state, path, keep=last)
    start, state = state, problem.commit(state, result)
    energy.append(state.dissipated_energy - start.dissipated_energy)
    if last:   # the last cycle's loop: each zone's tangential force against the floor's motion
        rows = [problem.contact.zone_slice(i) for i in range(2)]
        forces = result.kept[0].reshape(40, -1, 2)
        loops = [(forces[:, rows[0], 1].sum(axis=1), forces[:, rows[1], 1].sum(axis=1))]
# -

# ## Equilibrium: the two zones against the clamp's reaction (plain DOLFINx)

# +
displacement = problem.displacement(state)
reaction = fem.petsc.assemble_vector(fem.form(ufl.action(a, displacement)))   # K u with no condition applied
reaction.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
owned = clamped[clamped < V.dofmap.index_map.size_local]
values = reaction.getArray(readonly=True).reshape(-1, 2)[owned].sum(axis=0)
clamp = comm.allreduce(values, op=MPI.SUM)
# Each zone's force on the pad in the global frame: its components along the zone's (n, t1).
on_pad = sum(problem.total_force(state, zone) @ zone.frame for zone in (floor, wall))
imbalance = np.abs(on_pad + clamp).max() / np.abs(clamp).max()
fields = {name: problem.contact_fields(state, zone) for name, zone in (("floor", floor), ("wall", wall))}
F_floor, F_wall = problem.total_force(state, floor), problem.total_force(state, wall)
if comm.rank == 0:
    print(f"{problem.contact.nc} contacts ({floor.nc} floor, {wall.nc} wall), "
          f"{problem.n_dofs} dofs")
    print(f"after the preload: floor (n, t) = {np.round(preload['floor'], 4).tolist()} N/mm, "
          f"wall (n, t) = {np.round(preload['wall'], 4).tolist()} N/mm")
    print(f"after {cycles} cycles: floor {np.round(F_floor, 4).tolist()}, wall {np.round(F_wall, 4).tolist()}; "
          f"contact forces + clamp reaction = {np.abs(on_pad + clamp).max():.2e} N/mm "
          f"({imbalance:.1e} of the reaction)")
# The identity: every force on the pad balances (rounding of the factorisation and the local tolerance 1e-10).
assert imbalance <= 1e-6, imbalance
assert abs(preload["floor"][0] / P - 1) <= 1e-7   # the floor's force control (LocalSolver.force_tol 1e-8)
# -

# ## Results

# +
summary = {"contacts": problem.contact.nc, "cycles": cycles, "normal_force": float(F_floor[0]),
           "wall_normal_force": float(F_wall[0]), "dissipated_energy": state.dissipated_energy,
           "max_wear_depth": float(max(f["wear"].max() for f in fields.values())),
           "wear_area": state.record["wear_area"], "equilibrium_imbalance": float(imbalance)}
if comm.rank == 0:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6))
    motion = path.tangential[floor].value
    ax1.plot(1e3 * motion, loops[0][0], "o-", ms=3, label="floor")
    ax1.plot(1e3 * motion, loops[0][1], "s-", ms=3, label="wall")
    ax1.set(xlabel="floor motion (µm)", ylabel="tangential force (N/mm)", title=f"cycle {cycles}")
    ax1.legend()
    ax2.plot(fields["floor"]["coordinates"][:, 0], 1e6 * fields["floor"]["wear"], ".-", label="floor (along x)")
    ax2.plot(fields["wall"]["coordinates"][:, 1], 1e6 * fields["wall"]["wear"], ".-", label="wall (along y)")
    ax2.set(xlabel="position (mm)", ylabel="wear depth (nm)", title=f"after {cycles} cycles")
    ax2.legend()
    fig.tight_layout()
    fig.savefig(out / "two_zones.png", dpi=120)
    print(f"energy per cycle {energy[-1]:.4g} N mm/mm, max wear depth {summary['max_wear_depth']:.3e} mm -> {out}")
problem.destroy()
# -
