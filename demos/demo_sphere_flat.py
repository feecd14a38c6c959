# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: light
# ---

# # A steel ball on a steel flat: pressed, then rubbed (3D fretting through the API)
#
# The laboratory's standard fretting test: a sphere of radius $R$ pressed on a flat of the same material by a
# normal force $P$, then rubbed back and forth along $x$. The model is ours (plain DOLFINx: mesh, space, form,
# conditions); `dolfinx_fretting` adds the `Contact` (each node of the ball paired with the closest point of the
# flat's faces) and the `FrettingProblem`.
#
# By symmetry about the plane $y = 0$ that contains the sliding direction, half the ball and half the flat are
# meshed, with a roller ($u_y = 0$) on that plane: the half model carries $P/2$. The mesh
# (`dolfinx_fretting.meshes_3d.sphere_on_flat`) is a mapped block of trilinear hexahedra, cubes of edge $h$
# over the contact and graded away from it, sized from Hertz's contact radius for two identical bodies
# (Johnson, *Contact Mechanics*, §4.2)
#
# $$ a = \left(\frac{3PR}{4E^*}\right)^{1/3}, \qquad p_0 = \frac{3P}{2\pi a^2}, \qquad
# E^* = \frac{E}{2(1-\nu^2)}. $$
#
# Under a tangential force $Q < \mu P$ the contact sticks in a central disk of radius
# $c = a\,(1 - Q/\mu P)^{1/3}$ and slips in the annulus around it (Cattaneo 1938, Mindlin 1949; identical
# bodies: the normal and tangential problems uncouple). Rubbing beyond $\mu P$ slides the whole contact and
# wears it by Archard's law.

# +
import json
import os
from pathlib import Path

import numpy as np
from mpi4py import MPI  # first: the DOLFINx 0.11 wheel needs the MPI library that mpi4py loads
import ufl
from dolfinx import fem

import dolfinx_fretting as dfr
from dolfinx_fretting.analytic import hertz_sphere
from dolfinx_fretting.meshes_3d import sphere_on_flat
# The one call whose spelling changed between DOLFINx 0.5 and 0.11, from the package's public `compat` module
# (this demo runs on both; on one DOLFINx, write it directly: 0.11 `fem.functionspace(msh, ("Lagrange", 1, (3,)))`).
from dolfinx_fretting.compat import vector_space

E, nu = 210000.0, 0.3            # MPa: steel
R, P = 10.0, 100.0               # ball radius (mm), normal force on the whole ball (N)
mu, k = 0.8, 1e-7                # friction coefficient, Archard's coefficient (1/MPa)
phi = 0.5                        # partial slip: Q = phi mu P
stroke, cycles, increments = 0.02, 10, 40   # gross slip: +-stroke (mm) of the flat
a_over_h = 4                     # contact elements per Hertz radius
if "CI" in os.environ:           # CI-sized run
    a_over_h, cycles, increments = 2, 2, 16
out = Path("results/demo_sphere_flat")
comm = MPI.COMM_WORLD
E_star = E / (2 * (1 - nu**2))
a, p0 = hertz_sphere(P, R, E_star)
# -

# ## The user's model: mesh, space, form, boundary conditions
#
# The ball's top and the flat's bottom are clamped ($9a$ away from the contact: within 0.05 % of large bodies
# for the peak pressure); the symmetry plane gets its roller.

# +
body = sphere_on_flat(comm, R, a, a / a_over_h)          # half model, ball and flat, extent 9 a
msh = body.mesh
V = vector_space(msh, 1)
u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
lmbda, G = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
form = ufl.inner(lmbda * ufl.tr(eps(u)) * ufl.Identity(3) + 2 * G * eps(u), eps(v)) * ufl.dx
clamped = np.concatenate([body.facets("top"), body.facets("flat_bottom")])
V_y, _ = V.sub(1).collapse()
symmetry = np.concatenate([body.facets("symmetry"), body.facets("flat_symmetry")])
bcs = [fem.dirichletbc(np.zeros(3), fem.locate_dofs_topological(V, 2, clamped), V),
       fem.dirichletbc(fem.Function(V_y), fem.locate_dofs_topological((V.sub(1), V_y), 2, symmetry), V.sub(1))]
# -

# ## The plugin: the ball's face against the flat's, friction and wear
#
# `ElasticBody` pairs each node of the ball's face with the closest point of the flat's top (bilinear
# quadrilaterals). The obstacle's motion moves the flat rigidly in the frame of its normal $(0, 0, 1)$:
# `normal` is its approach, `tangential` its motion along $(x, y)$. The contacts on $y = 0$ cannot move across
# the plane (the roller): the problem keeps their force in $y$ at zero and prescribes no motion along $y$.

# +
flat = dfr.ElasticBody((body.facet_tags, body.tags["flat_top"]), normal=[0.0, 0.0, 1.0],
                       cells=body.cell_tags.find(body.regions["flat"]))
contact = dfr.Contact(V, (body.facet_tags, body.tags["surface"]), flat, mu=mu, bcs=bcs, window=1.4 * a + a / a_over_h)
problem = dfr.FrettingProblem(form, contact, bcs, wear=dfr.Archard(k))
state = problem.initial_state()
for fraction in (0.5, 1.0):                                  # press: P/2 on the half model
    state = problem.commit(state, problem.solve(state, normal=dfr.Force(fraction * P / 2)))
fields = problem.contact_fields(state)
tributary = contact.contact_set.tributary
loaded = fields["pressure"] > 0
a_fe = np.sqrt(2 * tributary[loaded].sum() / np.pi)          # radius of the loaded area (both halves)
h = body.contact_mesh_size
peak = fields["pressure"].max()
pressed = {"coordinates": fields["coordinates"].copy(), "pressure": fields["pressure"].copy()}
if comm.rank == 0:
    print(f"Hertz: a = {a:.4f} mm, p0 = {p0:.1f} MPa; computed: a = {a_fe:.4f} mm ({(a_fe - a) / h:+.2f} h), "
          f"peak {peak:.1f} MPa ({100 * (peak / p0 - 1):+.2f} %); {contact.nc} contacts, {problem.n_dofs} dofs")
# The checks the test suite relies on: a within one element, p0 within 2 %.
assert abs(a_fe - a) <= h and abs(peak / p0 - 1) <= 0.02, (a_fe, a, peak, p0)
# -

# ## Partial slip: Cattaneo–Mindlin
#
# $Q = \varphi\mu P$ by force along $x$ ($P$ held), with the flat held at $y = 0$. The stick zone's radius is
# read from the sticking nodes' area.

# +
Q = phi * mu * P
for fraction in (0.5, 1.0):
    state = problem.commit(state, problem.solve(state, tangential=(dfr.Force(fraction * Q / 2), dfr.Displacement(0.0))))
fields = problem.contact_fields(state)
stick = fields["status"] == 1
c_fe = np.sqrt(2 * tributary[stick].sum() / np.pi)
c_ref = a * (1 - phi) ** (1 / 3)
mindlin = {"coordinates": fields["coordinates"].copy(), "status": fields["status"].copy(),
           "shear": fields["shear"].copy(), "pressure": fields["pressure"].copy()}
if comm.rank == 0:
    print(f"Cattaneo-Mindlin: c = {c_ref:.4f} mm; computed {c_fe:.4f} mm ({(c_fe - c_ref) / h:+.2f} h), "
          f"{int(stick.sum())} sticking and {int((fields['status'] == 2).sum())} sliding contacts")
assert abs(c_fe - c_ref) <= 0.03 * c_ref + h, (c_fe, c_ref)
# -

# ## Gross slip: fretting cycles with wear
#
# Back to $Q = 0$, then the flat moves $\pm$`stroke` along $x$ with the approach held (triangular cycles;
# the compiled loop). Each cycle's frictional energy goes into Archard's wear, $\Delta V = (k/\mu)\,\Delta W$.

# +
state = problem.commit(state, problem.solve(state, tangential=(dfr.Force(0.0), dfr.Displacement(0.0))))
path = dfr.CyclePath.waveform(increments, normal=state.obstacle[0], tangential=[stroke, 0.0])
for cycle in range(1, cycles + 1):
    result = problem.run_cycle(state, path)
    state = problem.commit(state, result)
# The last cycle's fretting loop: the tangential force (whole ball: x 2) against the flat's motion, closed.
loop = (np.r_[result.obstacle[-1, 1], result.obstacle[:, 1]],
        2 * np.r_[result.records["tangential_force"][-1], result.records["tangential_force"]])
fields = problem.contact_fields(state)
worn = float(fields["wear"] @ tributary)
summary = {"normal_force": 2 * state.record["normal_force"], "tangential_force": 2 * state.record["tangential_force"],
           "max_pressure": state.record["max_pressure"], "max_wear_depth": float(fields["wear"].max()),
           "wear_area": 2 * worn, "dissipated_energy": 2 * state.dissipated_energy, "cycles": cycles,
           "contacts": contact.nc, "hertz_radius": a, "contact_radius": float(a_fe), "hertz_peak_pressure": p0,
           "peak_pressure": float(peak), "mindlin_stick_radius": c_ref, "stick_radius": float(c_fe)}
# Archard's identity over the whole run (both halves): worn volume = k/mu x dissipated energy.
assert abs(summary["wear_area"] - k / mu * summary["dissipated_energy"]) <= 1e-10 * summary["wear_area"]
u_final = problem.displacement(state)
if comm.rank == 0:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation

    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.json").write_text(json.dumps(summary, indent=1))

    def whole(xy, values, odd=False):
        """The half model's nodes and their mirror images across y = 0 (a y-component changes sign)."""
        mirror = xy[:, 1] > 1e-12 * a
        pts = np.vstack([xy, xy[mirror] * [1, -1]])
        return pts, np.concatenate([values, -values[mirror] if odd else values[mirror]])

    fig, axes = plt.subplots(2, 2, figsize=(10, 8.5))
    for ax, (title, xy, values, unit) in zip(axes.ravel()[:3], [
            ("pressure under P", pressed["coordinates"][:, :2], pressed["pressure"], "MPa"),
            (f"|shear| under Q = {phi:g} mu P", mindlin["coordinates"][:, :2],
             np.linalg.norm(mindlin["shear"], axis=1), "MPa"),
            (f"wear depth after {cycles} cycles", fields["coordinates"][:, :2], 1e6 * fields["wear"], "nm")]):
        pts, vals = whole(xy, values)
        tri = Triangulation(pts[:, 0] / a, pts[:, 1] / a)
        shade = ax.tricontourf(tri, vals, levels=20, cmap="viridis")
        fig.colorbar(shade, ax=ax, label=unit)
        ax.add_patch(plt.Circle((0, 0), 1.0, fill=False, color="w", ls="--"))
        ax.set(title=title, xlabel="x / a", ylabel="y / a", aspect="equal")
    stick_xy, _ = whole(mindlin["coordinates"][:, :2], mindlin["status"].astype(float))
    status = whole(mindlin["coordinates"][:, :2], mindlin["status"].astype(float))[1]
    axes[0, 1].plot(stick_xy[status == 1, 0] / a, stick_xy[status == 1, 1] / a, "w.", ms=4, label="stick")
    axes[0, 1].add_patch(plt.Circle((0, 0), c_ref / a, fill=False, color="r", label="Mindlin's c"))
    axes[0, 1].legend(loc="upper right", fontsize=8)
    axes[1, 1].plot(1e3 * loop[0], loop[1], ".-")
    axes[1, 1].set(xlabel="flat motion (µm)", ylabel="tangential force Q (N)",
                   title=f"fretting loop, cycle {cycles} (mu P = {mu * P:g} N)")
    fig.tight_layout()
    fig.savefig(out / "sphere_flat.png", dpi=110)
    print(f"after {cycles} cycles of +-{stroke} mm: max wear depth {summary['max_wear_depth']:.3e} mm, worn volume "
          f"{summary['wear_area']:.3e} mm^3, energy {summary['dissipated_energy']:.4g} N mm -> {out}")
problem.destroy()
# -
