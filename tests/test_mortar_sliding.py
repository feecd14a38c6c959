"""Finite sliding with mortar (issue 23): ``ElasticBody(..., formulation="mortar", sliding="finite")`` re-pairs by
recomputing the mortar matrices D and M in the current configuration from the surface compliance (no
refactorisation), with each body's share of the wear on its own nodes.

References:
- The contact patch test (Taylor & Papadopoulos, IJNME 31, 1991) carried through a finite slide: two blocks on
  non-matching meshes whose exact solution is a uniform stress state, linear in every element, at every increment
  of a gross-slip stroke of several elements (closed form below).
- Small slip: finite sliding's re-pairings move the weights by the slip over the element size, so the solution is
  the fixed pairing's to that order.
- Volume conservation (Archard): worn measure of both bodies = (k / mu) x the dissipated energy.
- W = L C L^T of a re-pairing against W built by the factorisation for the same pairing (the definition).
"""

import dataclasses

import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

import ufl  # noqa: E402
from dolfinx import fem, mesh  # noqa: E402
from petsc4py import PETSc  # noqa: E402
from support.blocks import E, E_PLANE, MU_LAME, NU, TIGHT, component, elasticity  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import compat, mortar  # noqa: E402
from dolfinx_fretting.contact import Contact, MasterSurface, mortar_contact_set, mortar_paired_set  # noqa: E402
from dolfinx_fretting.contact import tangent_frame  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import run_scene  # noqa: E402
from support.finite_sliding import P, cylinder_on_flat, pressed  # noqa: E402

DELTA = 6e-4                          # the approach
PRESSURE = E_PLANE * DELTA / 2        # uniaxial plane strain over the two unit heights
MU = 0.3
#: The slave's (upper) and the master's (lower, wider) element counts per unit length: 7 against 5, non-matching.
SLAVE_CELLS, MASTER_CELLS = 7, 5
MASTER_H = 1.0 / MASTER_CELLS
OVERHANG = 1.0                        # the master spans [-1, 2], the slave [0, 1]


def sliding_blocks(comm=MPI.COMM_WORLD):
    """The slave [0, 1] x [1, 2] (SLAVE_CELLS x 3 quadrilaterals) on the wider master [-1, 2] x [0, 1] (MASTER_CELLS
    per unit length, 3 rows), separate nodes. Contact tags: 1 the slave's bottom, 2 the master's top. Load tags: 3
    the slave's top, 4 the master's bottom, 5 every side, 100 + i the master's top facet i (from the left)."""
    lines = [(np.linspace(-OVERHANG, 1 + OVERHANG, int(round((1 + 2 * OVERHANG) * MASTER_CELLS)) + 1), 0.0),
             (np.linspace(0.0, 1.0, SLAVE_CELLS + 1), 1.0)]
    points, cells = [], []
    for xs, y0 in lines:
        first = sum(len(p) for p in points)
        X, Y = np.meshgrid(xs, np.linspace(y0, y0 + 1, 4), indexing="ij")
        points.append(np.column_stack([X.ravel(), Y.ravel()]))
        cells += [[first + i * 4 + j, first + (i + 1) * 4 + j, first + i * 4 + j + 1, first + (i + 1) * 4 + j + 1]
                  for i in range(len(xs) - 1) for j in range(3)]
    root = comm.rank == 0
    msh = compat.create_mesh(comm, np.array(cells) if root else np.zeros((0, 4), dtype=np.int64),
                             np.vstack(points) if root else np.zeros((0, 2)), "quadrilateral")
    fdim = 1
    msh.topology.create_connectivity(fdim, 2)
    boundary = mesh.exterior_facet_indices(msh.topology)
    middle = mesh.compute_midpoints(msh, fdim, boundary).reshape(-1, 3)
    f_to_c = msh.topology.connectivity(fdim, 2)
    cell_y = np.array([mesh.compute_midpoints(msh, 2, f_to_c.links(f))[0, 1] for f in boundary]).reshape(-1)
    upper = cell_y > 1.0
    horizontal = np.isclose(middle[:, 1], np.round(middle[:, 1]))
    interface = np.isclose(middle[:, 1], 1.0)
    contact = np.select([interface & upper, interface & ~upper], [1, 2], 0)
    top_index = np.floor((middle[:, 0] + OVERHANG) / MASTER_H).astype(np.int64)
    load = np.select([interface & ~upper, interface, horizontal & upper, horizontal & ~upper, ~horizontal],
                     [100 + top_index, 0, 3, 4, 5], 0)

    def tags(markers):
        keep = np.flatnonzero(markers > 0)
        keep = keep[np.argsort(boundary[keep])]
        return mesh.meshtags(msh, fdim, boundary[keep], markers[keep].astype(np.int32))

    return msh, tags(contact), tags(load)


def closed_form(k: int):
    """The exact state after increment k (0: pressed): shear stress tau, the obstacle's tangential position D.

    Uniform stress sigma_yy = -p, sigma_xx = 0, sigma_xy = tau in both blocks; the slave pinned at (0, 2) and the
    master at (0, 0) (plus D): u_x = e x + gamma (y - 2) on the slave, e x + gamma y + D on the master, e = nu (1 +
    nu) p / E the lateral (plane-strain) expansion, gamma = tau / G. The master slides along +x, so the friction on
    the slave is +mu p (tau = -mu p) after the first increment. The slave point X faces the master's material point
    X - (2 gamma + D) / (1 + e): D_k = (1 + e) k h_m - 2 gamma puts the slave's ends on master nodes, so that the
    master's free top (loaded with the same traction) is a set of whole facets."""
    tau = -MU * PRESSURE if k > 0 else 0.0
    expansion = NU * (1 + NU) * PRESSURE / E
    return tau, (1 + expansion) * k * MASTER_H - 2 * tau / MU_LAME


def sliding_patch_problem(formulation: str, increments: int, wear=None, sliding: str = "finite",
                          repair_slip: float = 0.05, mu: float = MU, with_loads: bool = True):
    """The sliding blocks with rollers (u_y = 0) on the slave's top and the master's bottom, u_x = 0 at (0, 2) and
    (0, 0); loads: "shear" (the outer faces' traction of sigma_xy = 1, per unit tau; only its x part on the
    rollers' faces), and "free_k" for each state k the increment k + 1 starts from: the traction (tau, -p) of
    increment k + 1 on the master's top outside the slave's extent in state k (the pairing an increment is solved
    with is its start's). ``with_loads=False``: none of them (the pins and the friction carry the shear)."""
    msh, tags, load_tags = sliding_blocks()
    V = compat.vector_space(msh, 1)
    ends = lambda x: np.isclose(x[1], 0.0) | np.isclose(x[1], 2.0)  # noqa: E731
    pins = lambda x: ends(x) & np.isclose(x[0], 0.0)  # noqa: E731
    bcs = [component(V, 1, ends), component(V, 0, pins)]
    ds = ufl.Measure("ds", domain=msh, subdomain_data=load_tags)
    v = ufl.TestFunction(V)
    n = ufl.FacetNormal(msh)
    unit_shear = fem.Constant(msh, PETSc.ScalarType(((0.0, 1.0), (1.0, 0.0))))
    loads = {"shear": ufl.inner(ufl.dot(unit_shear, n), v) * ds(5) + ufl.dot(unit_shear, n)[0] * v[0] * ds((3, 4))}
    master_facets = int(round((1 + 2 * OVERHANG) * MASTER_CELLS))
    pressure = fem.Constant(msh, PETSc.ScalarType((0.0, -PRESSURE)))
    unit_traction = fem.Constant(msh, PETSc.ScalarType((1.0, 0.0)))
    for k in range(increments):
        start = OVERHANG * MASTER_CELLS - k    # the slave's left end over master facet start in state k
        free = [100 + i for i in range(master_facets) if i < start or i >= start + MASTER_CELLS]
        loads[f"free_{k}"] = sum(ufl.inner(pressure, v) * ds(marker) for marker in free)
        loads[f"free_shear_{k}"] = sum(ufl.inner(unit_traction, v) * ds(marker) for marker in free)
    body = dfr.ElasticBody((tags, 2), [0.0, 1.0], sliding=sliding, formulation=formulation, repair_slip=repair_slip)
    contact = dfr.Contact(V, (tags, 1), body, mu=mu, bcs=bcs)
    problem = dfr.FrettingProblem(elasticity(V), contact, bcs, loads=loads if with_loads else None, wear=wear,
                                  solver=TIGHT)
    problem.sliding.warn = False   # a stride of one master element per increment, on purpose (the closed form's)
    return problem


def slide(problem, increments: int):
    """The pressed state and the states after each increment (gross slip along +x)."""
    def factors(k):   # increment k's loads: the free top of state k - 1 (the pairing's), tau of increment k
        tau = closed_form(k)[0]
        values = {name: 0.0 for name in problem.operators.load_names}
        values.update({"shear": tau, f"free_{max(k - 1, 0)}": 1.0, f"free_shear_{max(k - 1, 0)}": tau})
        return values

    states = [problem.advance(problem.initial_state(), normal=DELTA, loads=factors(0))[0]]
    for k in range(1, increments + 1):
        result = problem.solve(states[-1], normal=DELTA, tangential=closed_form(k)[1], loads=factors(k))
        states.append(problem.commit(states[-1], result))
    return states


def test_the_mortar_formulation_passes_the_patch_test_while_sliding():
    """The slave slides in gross slip over 4 master elements (5.6 slave elements), one master element per
    increment, re-paired after each: every nodal pressure (the multiplier) is p and the total forces are (p, mu p),
    to 1e-8, at every increment (local tolerance 1e-12; measured: pressures within 3.0e-9, forces 5.1e-12), and the
    weighted master point of every slave node is the closed form's, 4 master elements back on the master's material.

    Node-to-segment finite sliding on the same meshes and loads does not pass it: its nodal pressures scatter by
    6.6 % at every increment (measured 7.1 % pressed, 6.6 % at each of the four slid increments; total normal force
    +0.15 % to +0.20 %), asserted > 1e-2."""
    increments = 4
    scatter = {}
    for formulation in ("mortar", "node"):
        problem = sliding_patch_problem(formulation, increments)
        states = slide(problem, increments)
        errors = []
        for k, state in enumerate(states):
            pressure = problem.contact_fields(state)["pressure"]
            force = problem.total_force(state) / PRESSURE
            errors.append(max(np.abs(pressure / PRESSURE - 1).max(), abs(force[0] - 1),
                              abs(force[1] - (MU if k else 0.0))))
        scatter[formulation] = errors
        if formulation == "mortar":
            assert problem.sliding.repairs == increments
            pairing = states[-1].pairing
            assert np.allclose(pairing.master_points[:, 0], pairing.coords[:, 0] - increments * MASTER_H, rtol=0,
                               atol=1e-12)
        problem.destroy()
    assert max(scatter["mortar"]) < 1e-8, scatter
    assert min(scatter["node"]) > 1e-2, scatter


def test_re_pairing_recomputes_the_mortar_matrices_without_refactorising():
    """Four re-pairings of the sliding patch test: K is factorised once (the problem's construction) and neither
    refactorised nor solved with again (W and the load responses of each pairing are L C L^T and L S K^-1 f from
    the surface compliance); the last pairing's W and load responses are those the factorisation gives for that
    pairing (W = H K^-1 H^T built by a problem holding it), to 1e-9 of their largest entry (two routes' rounding)."""
    increments = 4
    problem = sliding_patch_problem("mortar", increments)
    built = dict(problem.operators.delassus.stats)
    states = slide(problem, increments)
    stats = problem.operators.delassus.stats
    assert problem.sliding.repairs == increments
    assert (stats["factorizations"], stats["refactorizations"]) == (1, 0)
    assert (stats["solves"], stats["builds"]) == (built["solves"], built["builds"])
    problem.operators.activate(states[-1])
    direct = sliding_patch_problem("mortar", increments, sliding="small")
    direct.operators.contact = direct.contact.with_pairing(states[-1].pairing)
    direct.operators.build()
    W, W_direct = problem.operators.W, direct.operators.W
    assert np.abs(W - W_direct).max() <= 1e-9 * np.abs(W_direct).max()
    responses, responses_direct = problem.operators.responses, direct.operators.responses
    assert np.abs(responses - responses_direct).max() <= 1e-9 * np.abs(responses_direct).max()
    direct.destroy()
    problem.destroy()


def test_small_slip_finite_sliding_is_the_fixed_pairing():
    """The cylinder on the flat (the cylinder-flat scene's model, h = 20 um, mortar) pressed to P and moved
    tangentially in partial slip by 1 to 4 um (0.05 to 0.2 elements), the finite sliding re-pairing whenever a
    weighted master point has moved 0.01 elements: before any re-pairing the states are the fixed pairing's to
    rounding (1e-12 of p0), and after re-pairings the nodal pressure and shear differ from the fixed pairing's by the
    geometric change the slip makes, first order in it: within 1e-2 of p0 while the largest relative tangential
    displacement stays below 0.062 elements (measured 2.1e-3, 4.8e-3 and 8.1e-3 of p0 at 0.032, 0.045 and 0.061
    elements); the total normal force is P to 1e-8 in both (force control)."""
    model = cylinder_on_flat()
    fields = {}
    for sliding in ("small", "finite"):
        obstacle = dataclasses.replace(model.obstacle, sliding=sliding, reach=0.3, formulation="mortar",
                                       repair_slip=0.01)
        problem = dfr.FrettingProblem(model.form, Contact(model.V, model.surface, obstacle, MU, model.bcs, 0.35),
                                      model.bcs, solver=dfr.LocalSolver(tol=1e-10))
        state = pressed(problem)
        fields[sliding] = []
        for d in (0.001, 0.002, 0.003, 0.004):
            state = problem.commit(state, problem.solve(state, tangential=d))
            values = problem.contact_fields(state)
            fields[sliding].append((values["pressure"], values["shear"][:, 0], values["relative_tangential"][:, 0]))
            assert problem.total_force(state)[0] == pytest.approx(P, rel=1e-8)
        if sliding == "finite":
            assert problem.sliding.repairs >= 3
            assert 0 < np.ptp(state.status) and np.any(state.status == 1)   # partial slip: stick and slip
        problem.destroy()
    p0 = fields["small"][0][0].max()
    h = 0.02
    for k, (fixed, finite) in enumerate(zip(fields["small"], fields["finite"])):
        difference = max(np.abs(fixed[0] - finite[0]).max(), np.abs(fixed[1] - finite[1]).max()) / p0
        assert difference <= (1e-12 if k == 0 else 1e-2), (k, difference)
        assert np.abs(finite[2]).max() / h < 0.062


def test_the_scene_runs_mortar_with_finite_sliding(tmp_path):
    """mccoll (both bodies wearing) with contact.formulation = 'mortar' and contact.sliding = 'finite' (refused before
    this was built): the run says so, re-pairs, and both bodies' worn area is (k / mu) x the dissipated energy
    through the runner (1e-9: the runner's sums over increments and cycles; measured 2e-16)."""
    s = run_scene(load_scene("mccoll", ["contact.sliding='finite'", "contact.formulation='mortar'",
                                        "geometry.contact_mesh_size=0.04", "loading.normal_increments=1",
                                        "loading.cycles=1", "loading.increments_per_cycle=8", "output.plots=false",
                                        "output.xdmf=false", "output.progress=false"]), tmp_path, quiet=True)
    assert "dual mortar, paired anew" in s["modelled"]["contact"]
    assert s["sliding"] == "finite" and s["repairs"] > 0
    assert s["wear_area"] == pytest.approx(s["wear_k_effective"] / 0.9 * s["dissipated_energy"], rel=1e-9)


def _flat_surface(xs, y, first_label, above):
    """A flat polyline at height y, nodes ``first_label``, ... (the body above or below) as a MasterSurface."""
    n = len(xs) - 1
    nodes = first_label + np.column_stack([np.arange(n), np.arange(1, n + 1)])
    x = np.stack([np.column_stack([xs[:-1], np.full(n, y)]), np.column_stack([xs[1:], np.full(n, y)])], axis=1)
    inside = x.mean(axis=1) + [0.0, 0.1 if above else -0.1]
    return MasterSurface(nodes, x, np.full(n, 2), inside, tangent_frame([0.0, 1.0]))


def test_a_re_pairing_keeps_the_reference_frames_and_refuses_a_node_off_the_master():
    """Pure: a slave of 3 segments over a wider master, paired anew with the master moved by 0.25 along x: the
    contacts keep their slave nodes, reference frames and coordinates; each row's weights sum to one and its
    weighted master point is the slave node's shifted by -0.25 (a flat interface: exact, 1e-14); D_jj is the slave
    hat's measure (1e-14). Moved by 0.8, the first slave node's hat faces no master any more: refused, naming it."""
    slave = _flat_surface(np.array([0.0, 0.3, 0.7, 1.0]), 0.0, 0, above=True)
    master = _flat_surface(np.linspace(-0.5, 1.5, 6), 0.0, 100, above=False)
    reference = mortar.mortar_matrices(slave.nodes, slave.x, slave.inside, master.nodes, master.x, master.inside)
    pairing = mortar_contact_set(reference, slave.nodes, slave.x, master, 300, slave_surface=slave)
    shift = np.array([0.25, 0.0])
    moved = mortar.mortar_matrices(slave.nodes, slave.x, slave.inside, master.nodes, master.x + shift,
                                   master.inside + shift, slave_reference_x=slave.x)
    new = mortar_paired_set(pairing, moved)
    assert np.array_equal(new.global_nodes, pairing.global_nodes) and np.array_equal(new.frames, pairing.frames)
    assert np.allclose(new.master_weights.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    assert np.allclose(new.master_points, pairing.coords - shift, rtol=0, atol=1e-14)
    assert np.allclose(new.tributary, [0.15, 0.35, 0.35, 0.15], rtol=0, atol=1e-14)
    assert np.allclose(new.gap0, 0.0, rtol=0, atol=1e-14)
    off = np.array([1.3, 0.0])
    beyond = mortar.mortar_matrices(slave.nodes, slave.x, slave.inside, master.nodes, master.x + off,
                                    master.inside + off, slave_reference_x=slave.x)
    with pytest.raises(ValueError, match=r"contact 0 \(at \[0.0, 0.0\].*no longer faces the master"):
        mortar_paired_set(pairing, beyond)
