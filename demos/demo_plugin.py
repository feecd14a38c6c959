# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: light
# ---

# # Your own DOLFINx model: a flat punch with rounded edges, pressed and fretted
#
# This demo uses `dolfinx_fretting` as a plugin: the mesh, the function space, the elasticity form, the
# boundary conditions and the load loop are ours (plain DOLFINx); the package adds a `Contact` and a
# `FrettingProblem`.
#
# The body is a punch whose face is flat over $|x| \le b$ and rounded beyond by arcs of radius $R$, pressed
# on a rigid flat. On a half-plane (the body large against the contact) the frictionless contact half-width
# $a$ and the load $P$ (per unit thickness) are related by (Ciavarella, Hills & Monno 1998)
#
# $$ P = \frac{E^* a^2}{4R}\left(\pi - 2\varphi_0 - \sin 2\varphi_0\right), \qquad \sin\varphi_0 = \frac{b}{a},
# \qquad E^* = \frac{E}{1-\nu^2}, $$
#
# and the pressure follows from the half-plane inversion formula for a solution bounded at both ends,
#
# $$ p(x) = \frac{E^*}{2\pi}\sqrt{a^2-x^2}\;\mathrm{PV}\!\!\int_{-a}^{a}
#    \frac{h'(t)\,dt}{\sqrt{a^2-t^2}\,(t-x)}, \qquad h(t) = \frac{\max(|t|-b, 0)^2}{2R}, $$
#
# with $h$ the initial gap (the parabolic form of the arcs; the arcs differ from it by $s^4/(8R^3)$, $10^{-6}$ mm
# here). Then the punch is rubbed sideways through fretting cycles with Coulomb friction and Archard wear.

# +
import json
import os
from pathlib import Path

import gmsh
import numpy as np
from mpi4py import MPI  # first: the DOLFINx 0.11 wheel needs the MPI library that mpi4py loads
import ufl
from dolfinx import fem
from petsc4py import PETSc
from scipy.integrate import quad
from scipy.optimize import brentq

import dolfinx_fretting as dfr
# The two calls whose spelling changed between DOLFINx 0.5 and 0.11, from the package's public `compat` module
# (this demo runs on both; on one DOLFINx, write them directly: 0.11 `dolfinx.io.gmsh.model_to_mesh(...).mesh`
# and `fem.functionspace(msh, ("Lagrange", 1, (2,)))`).
from dolfinx_fretting.compat import model_to_mesh, vector_space

E, nu = 210000.0, 0.3            # MPa
b, R = 0.5, 10.0                 # flat half-width and edge radius (mm)
P = 3000.0                       # normal force (N/mm)
H, half_width = 20.0, 9.2        # punch height and half-width (mm): ~25 a and ~12 a
h = 0.01                         # element size in the contact zone (mm)
mu, k, stroke, cycles = 0.5, 1e-6, 0.01, 20
if "CI" in os.environ:           # CI-sized run
    h, cycles = 0.02, 3
out = Path("results/demo_plugin")
comm = MPI.COMM_WORLD
# -

# ## The user's model: mesh, space, form, boundary conditions

# +
theta = np.arcsin((half_width - b) / R)          # the arcs run from the flat's ends to the punch's sides
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
if comm.rank == 0:
    g = gmsh.model.geo
    c_r, c_l = g.addPoint(b, R, 0), g.addPoint(-b, R, 0)
    p = [g.addPoint(x, y, 0) for x, y in [(-b, 0), (b, 0), (half_width, R * (1 - np.cos(theta))),
                                          (half_width, H), (-half_width, H), (-half_width, R * (1 - np.cos(theta)))]]
    face = [g.addLine(p[0], p[1]), g.addCircleArc(p[1], c_r, p[2])]
    sides = [g.addLine(p[2], p[3]), g.addLine(p[3], p[4]), g.addLine(p[4], p[5])]
    face.append(g.addCircleArc(p[5], c_l, p[0]))
    g.addPlaneSurface([g.addCurveLoop([face[0], face[1], *sides, face[2]])])
    g.synchronize()
    gmsh.model.addPhysicalGroup(1, face, 1)        # the contact face
    gmsh.model.addPhysicalGroup(1, [sides[1]], 2)  # the top, clamped
    gmsh.model.addPhysicalGroup(2, [1], 1)
    dist = gmsh.model.mesh.field.add("Distance")
    gmsh.model.mesh.field.setNumbers(dist, "CurvesList", face)
    thr = gmsh.model.mesh.field.add("Threshold")
    for key, value in (("InField", dist), ("SizeMin", h), ("SizeMax", 1.0), ("DistMin", 0.02), ("DistMax", 8.0)):
        gmsh.model.mesh.field.setNumber(thr, key, value)
    box = gmsh.model.mesh.field.add("Box")     # keep h over the contact zone along the face
    for key, value in (("VIn", h), ("VOut", 1.0), ("XMin", -1.3), ("XMax", 1.3), ("YMin", -0.1), ("YMax", 0.05),
                       ("Thickness", 2.0)):
        gmsh.model.mesh.field.setNumber(box, key, value)
    both = gmsh.model.mesh.field.add("Min")
    gmsh.model.mesh.field.setNumbers(both, "FieldsList", [thr, box])
    gmsh.model.mesh.field.setAsBackgroundMesh(both)
    for opt in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
        gmsh.option.setNumber(opt, 0)
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    gmsh.option.setNumber("Mesh.RecombineAll", 1)
    gmsh.model.mesh.generate(2)
msh, cell_tags, facet_tags = model_to_mesh(gmsh.model, comm, 0, gdim=2)
gmsh.finalize()

V = vector_space(msh, 1)
u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
lmbda, G = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
a = ufl.inner(lmbda * ufl.tr(eps(u)) * ufl.Identity(2) + 2 * G * eps(u), eps(v)) * ufl.dx   # plane strain
top = fem.locate_dofs_topological(V, 1, facet_tags.find(2))
bcs = [fem.dirichletbc(np.zeros(2, dtype=PETSc.ScalarType), top, V)]
# -

# ## The plugin: a contact with a rigid flat, frictionless first
#
# The flat's normal $(0, 1)$ points into the punch; `normal=Force(P)` makes the flat's approach the unknown
# that gives the total normal force $P$.

# +
flat = dfr.RigidPlane(point=[0.0, 0.0], normal=[0.0, 1.0])
contact = dfr.Contact(V, (facet_tags, 1), flat, mu=0.0, bcs=bcs, window=1.2)
problem = dfr.FrettingProblem(a, contact, bcs)
state = problem.initial_state()
for fraction in (0.25, 0.5, 0.75, 1.0):
    state = problem.commit(state, problem.solve(state, normal=dfr.Force(fraction * P)))
fields = problem.contact_fields(state)
x, pressure = fields["coordinates"][:, 0], fields["pressure"]
# -

# ## The half-plane reference

# +
E_star = E / (1 - nu**2)
load = lambda a_: E_star * a_**2 / (4 * R) * (np.pi - 2 * np.arcsin(b / a_) - np.sin(2 * np.arcsin(b / a_)))  # noqa: E731
a_ref = brentq(lambda a_: load(a_) - P, b * (1 + 1e-12), 10 * b)
dh = lambda t: np.sign(t) * max(abs(t) - b, 0.0) / R  # noqa: E731


def p_ref(xi: float) -> float:
    """The inversion formula with t = a sin(s) (the end singularities absorbed); the Cauchy weight
    handles the principal value on the subinterval holding x."""
    f = lambda s: dh(a_ref * np.sin(s))  # integrand of PV int f(s) / (a sin s - x) ds  # noqa: E731
    sx = np.arcsin(xi / a_ref)
    kinks = sorted({-np.pi / 2, np.arcsin(-b / a_ref), np.arcsin(b / a_ref), np.pi / 2})
    total = 0.0
    for lo, hi in zip(kinks[:-1], kinks[1:]):
        if lo < sx < hi:   # 1/(a sin s - x) = [(s - sx)/(a sin s - x)] / (s - sx)
            g = lambda s: f(s) * (s - sx) / (a_ref * (np.sin(s) - np.sin(sx))) if s != sx else f(s) / (a_ref * np.cos(sx))  # noqa: E731
            total += quad(g, lo, hi, weight="cauchy", wvar=sx, limit=200)[0]
        else:
            total += quad(lambda s: f(s) / (a_ref * np.sin(s) - xi), lo, hi, limit=200)[0]
    return E_star / (2 * np.pi) * np.sqrt(a_ref**2 - xi**2) * total


grid = np.linspace(-a_ref, a_ref, 801)[1:-1]
p_grid = np.array([p_ref(xi) for xi in grid])
loaded = x[pressure > 0]
half_width_fe = 0.5 * (loaded.max() - loaded.min())
xs = np.sort(x)
h_contact = np.diff(xs)[np.searchsorted(xs, loaded.max()) - 1:][:2].max()   # node spacing at the contact edge
peak_fe, peak_ref = pressure.max(), p_grid.max()
if comm.rank == 0:
    print(f"half-plane: a = {a_ref:.4f} mm, peak pressure {peak_ref:.1f} MPa, "
          f"int p dx = {np.sum(0.5 * (p_grid[1:] + p_grid[:-1]) * np.diff(grid)):.1f} N/mm (P = {P})")
    print(f"computed:   half-width {half_width_fe:.4f} mm (element {h_contact:.4f} mm), "
          f"peak {peak_fe:.1f} MPa ({100 * (peak_fe / peak_ref - 1):+.2f} %), {contact.nc} contact nodes, "
          f"{problem.n_dofs} dofs")
# The checks the test suite relies on: half-width within one element, peak pressure within 2 %.
assert abs(half_width_fe - a_ref) <= h_contact, (half_width_fe, a_ref, h_contact)
assert abs(peak_fe / peak_ref - 1) <= 0.02, (peak_fe, peak_ref)
problem.destroy()
# -

# ## Fretting: friction, Archard wear, cycles
#
# The same model with $\mu = 0.5$ and Archard wear; the normal force is held while the flat moves
# sideways by $\pm\delta$ (a triangular cycle of 40 increments). Cycles run in the compiled loop. A
# `FrettingWriter` puts the states into the output folder as the scenes' runs do (`history.csv`, `cycles.csv`,
# `contact_profiles.csv`, `fields.xdmf`, `run.json`), and `plot_run` draws the same pictures from it.

# +
contact = dfr.Contact(V, (facet_tags, 1), flat, mu=mu, bcs=bcs, window=1.2)
problem = dfr.FrettingProblem(a, contact, bcs, wear=dfr.Archard(k))
state = problem.initial_state()
sigma = lambda w: lmbda * ufl.tr(eps(w)) * ufl.Identity(2) + 2 * G * eps(w)  # noqa: E731
von_mises = lambda w: ufl.sqrt(1.5 * ufl.inner(ufl.dev(sigma(w)), ufl.dev(sigma(w))))  # noqa: E731 (in-plane)
description = dfr.RunDescription.of(problem, "punch", cycles=cycles, preload_increments=4,
                                    increments_per_cycle=40, tangential_control="displacement",
                                    tangential_amplitude=stroke)
writer = dfr.FrettingWriter(problem, out, description, von_mises=von_mises)
for fraction in (0.25, 0.5, 0.75, 1.0):
    state = problem.commit(state, problem.solve(state, normal=dfr.Force(fraction * P), tangential=dfr.Force(0.0)))
    writer.write_increment(state, stage="normal")
path = dfr.CyclePath.waveform(40, normal=state.obstacle[0], tangential=stroke)
for cycle in range(1, cycles + 1):
    snapshot = cycle in (1, cycles)        # profiles and fields of the first and the last cycle
    result = problem.run_cycle(state, path, keep=snapshot)
    start, state = state, problem.commit(state, result)
    writer.write_cycle(cycle, start, result, profiles=snapshot)
fields = problem.contact_fields(state)
summary = {"normal_force": state.record["normal_force"], "max_pressure": state.record["max_pressure"],
           "max_wear_depth": float(fields["wear"].max()), "wear_area": state.record["wear_area"],
           "dissipated_energy": state.dissipated_energy, "cycles": cycles, "contacts": contact.nc,
           "frictionless_peak_pressure": float(peak_fe), "half_plane_peak_pressure": float(peak_ref),
           "frictionless_half_width": float(half_width_fe), "half_plane_half_width": float(a_ref)}
writer.write_summary(summary)
writer.write_worn_profiles(state)
writer.close()
if comm.rank == 0:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dfr.plot_run(out)   # wear_evolution.png, fretting_loops.png, ... from the folder alone
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6))
    ax1.plot(grid, p_grid, "k-", label="half-plane inversion")
    ax1.plot(x, pressure, "o", ms=3, label="dolfinx_fretting, frictionless")
    ax1.set(xlabel="x (mm)", ylabel="pressure (MPa)", title=f"P = {P} N/mm")
    ax1.legend()
    ax2.plot(x, 1e3 * fields["wear"], ".-")
    ax2.set(xlabel="x (mm)", ylabel="wear depth (µm)", title=f"after {cycles} cycles, ±{stroke} mm, µ = {mu}")
    fig.tight_layout()
    fig.savefig(out / "punch.png", dpi=120)
    print(f"after {cycles} cycles: max wear depth {summary['max_wear_depth']:.3e} mm, energy "
          f"{state.dissipated_energy:.4g} N mm/mm -> {out}")
problem.destroy()
# -
