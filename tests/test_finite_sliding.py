"""Finite sliding of two deformable bodies (ElasticBody(sliding="finite"), contact.sliding = "finite").

References:
- W of a pairing formed from the surface compliance, L C L^T, against W built through the factorisation for the
  same pairing (the definition, W = H K^-1 H^T).
- Translation invariance: two elastically similar bodies (Dundurs' beta = 0, Johnson 1985 section 5.4) have no
  normal-tangential coupling, so the pressure of a cylinder sliding in gross slip over a long flat is its Hertz
  pressure wherever it is: after sliding several elements it must be the pressure before sliding, and the flat's
  indentation must have moved with the cylinder.
- Volume conservation (Archard, eq. 5): worn volume of both bodies = (k / mu) x the dissipated energy.
- The flat's scar in reciprocating gross slip spans the contact width plus the slip stroke.
"""

import copy
import dataclasses

import numpy as np
import pytest
from mpi4py import MPI  # noqa: F401  (before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs)

import dolfinx_fretting as dfr
from dolfinx_fretting import cycling, local_solvers, sliding
from dolfinx_fretting.analytic import hertz_line_contact
from dolfinx_fretting.checkpoint import _find_facets
from dolfinx_fretting.contact import (MasterSurface, _closest_segments, pair_with_segments, paired_contact_set,
                                      tangent_frame)
from dolfinx_fretting.scenes import SceneError, load_scene
from dolfinx_fretting.simulation import run_scene
from dolfinx_fretting.state import ConvergenceError
from support import finite_sliding as support_sliding
from support.finite_sliding import MU, P, pressed, sliding_problem


# Pure parts (no mesh) -------------------------------------------------------------------------------------
def _segment_surface(x_nodes):
    """A flat master y = 0 of segments between ``x_nodes`` (global nodes 100, 101, ...), body below."""
    n = x_nodes.size - 1
    nodes = np.column_stack([100 + np.arange(n), 101 + np.arange(n)])
    x = np.stack([np.column_stack([x_nodes[:-1], np.zeros(n)]), np.column_stack([x_nodes[1:], np.zeros(n)])], axis=1)
    inside = np.column_stack([0.5 * (x_nodes[:-1] + x_nodes[1:]), -np.ones(n)])
    return MasterSurface(nodes, x, np.full(n, 2), inside, tangent_frame([0.0, 1.0]))


def test_master_node_measures_add_up_to_the_surface():
    """Each node's share of the master's facets sums to the surface's length (2D) or area (3D, triangles and
    quadrilaterals): exact up to rounding."""
    x_nodes = np.cumsum(np.r_[0.0, np.random.default_rng(1).uniform(0.01, 0.05, 30)])
    surface = _segment_surface(x_nodes)
    nodes = np.unique(surface.nodes)
    assert sliding.master_node_areas(surface, nodes).sum() == pytest.approx(x_nodes[-1] - x_nodes[0], rel=1e-13)
    # 3D: a unit square z = 0 as one quadrilateral [0, .5]x[0, 1] and two triangles on [.5, 1]x[0, 1].
    quad = [[0, 0, 0], [0.5, 0, 0], [0.5, 1, 0], [0, 1, 0]]
    tri1 = [[0.5, 0, 0], [1, 0, 0], [1, 1, 0], [1, 1, 0]]
    tri2 = [[0.5, 0, 0], [1, 1, 0], [0.5, 1, 0], [0.5, 1, 0]]
    faces = MasterSurface(np.array([[0, 1, 2, 3], [1, 4, 5, -1], [1, 5, 2, -1]]), np.array([quad, tri1, tri2], float),
                          np.array([4, 3, 3]), np.array([[0.25, 0.5, -1], [0.8, 0.3, -1], [0.6, 0.7, -1]]),
                          tangent_frame([0.0, 0.0, 1.0]))
    assert sliding.master_node_areas(faces, np.arange(6)).sum() == pytest.approx(1.0, rel=1e-13)


def _slaves_on(surface, xs, gap=0.0):
    """Slave nodes at x = xs, y = gap, paired in the reference configuration."""
    coords = np.column_stack([xs, np.full(xs.size, gap)])
    pairs = surface.pair(coords)
    return paired_contact_set(surface, np.arange(xs.size), coords, np.full(xs.size, 0.02), xs.copy(),
                              pairs["face"], pairs["weights"], 2 * 200)


def _compliance(cs, surface):
    nodes = np.union1d(cs.global_nodes, surface.nodes.ravel())
    m = 2 * nodes.size
    return sliding.SurfaceCompliance(nodes, 2, np.eye(m), np.zeros((0, m)), np.arange(surface.nodes.shape[0]),
                                     sliding.master_node_areas(surface, nodes))


def test_repairing_after_a_rigid_slide_faces_the_translated_points():
    """The master translated by D (no deformation): each slave node pairs with the master's material point at
    X_s - D (exactly, the flat is straight), the gap and frames are unchanged and the new offsets are zero."""
    x_nodes = np.linspace(-0.5, 0.5, 51)                          # h = 0.02
    surface = _segment_surface(x_nodes)
    cs = _slaves_on(surface, np.linspace(-0.1, 0.1, 9) + 0.003, gap=0.001)
    comp = _compliance(cs, surface)
    u = np.zeros((comp.nodes.size, 2))
    D = np.array([0.067, 0.0])                                     # 3.35 elements
    assert sliding.offsets(cs, comp, u, D) == pytest.approx(np.full(cs.nc, 0.067 / 0.02), rel=1e-12)
    new = sliding.repair(cs, comp, u, D)
    assert np.allclose(new.master_points[:, 0], cs.coords[:, 0] - D[0], atol=1e-15)
    assert np.allclose(new.gap0, cs.gap0, atol=1e-15) and np.allclose(new.frames, cs.frames)
    assert sliding.offsets(new, comp, u, D).max() < 1e-12


def test_spread_master_wear_keeps_the_worn_volume():
    """Depths at paired points spread on the master's nodes: sum(depth_c A_c) = sum(area_j w_j) (1e-13), and a
    depth uniform along a run of contacts that covers whole facets reads back uniform inside it."""
    surface = _segment_surface(np.linspace(-0.5, 0.5, 51))
    cs = _slaves_on(surface, np.linspace(-0.2, 0.2, 21))           # on the master's nodes, tributary 0.02
    comp = _compliance(cs, surface)
    depth = np.random.default_rng(3).uniform(0, 1e-3, cs.nc)
    spread = sliding.spread_wear(cs, comp, depth)
    assert (spread * comp.master_areas).sum() == pytest.approx((depth * cs.tributary).sum(), rel=1e-13)
    uniform = sliding.interpolate_master(cs, comp, sliding.spread_wear(cs, comp, np.full(cs.nc, 2e-4)))
    assert uniform[1:-1] == pytest.approx(np.full(cs.nc - 2, 2e-4), rel=1e-12)


# Two bodies through the API -------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def cylinder_on_flat():
    """The cylinder-flat scene's model at h = 20 um (the cylinder R = 6 mm on a 20 x 10 mm flat)."""
    return support_sliding.cylinder_on_flat()


def test_repaired_delassus_is_the_factorised_one(cylinder_on_flat):
    """After sliding 3.5 elements the pairing has changed; its W = L C L^T and load responses equal W built by
    the factorisation for that pairing (a problem made with the pairing's contact set), to 1e-9 of max W."""
    problem = sliding_problem(cylinder_on_flat, "finite")
    state = pressed(problem)
    for d in np.linspace(0.0, 0.07, 8)[1:]:
        state = problem.commit(state, problem.solve(state, tangential=d))
    assert problem.sliding.repairs > 0
    assert not np.array_equal(state.pairing.master_faces, problem.operators.reference_pairing.master_faces)
    problem.operators.activate(state)
    direct = sliding_problem(cylinder_on_flat, "small")
    direct.operators.contact = direct.contact.with_pairing(state.pairing)
    direct.operators.build()
    assert np.abs(problem.operators.W - direct.operators.W).max() <= 1e-9 * np.abs(direct.operators.W).max()
    responses, direct_responses = problem.operators.responses, direct.operators.responses
    assert responses.shape == direct_responses.shape   # the scene's loads (none besides the obstacle)
    if direct_responses.size:
        assert np.abs(responses - direct_responses).max() <= 1e-9 * np.abs(direct_responses).max()


def test_a_cylinder_sliding_over_the_flat_keeps_its_hertz_pressure(cylinder_on_flat):
    """Gross slip over 5 elements: with finite sliding the pressure inside |x| <= 0.8 a is Hertz's (translation
    invariance, identical materials) within 2 % of p0, and the flat's deepest point has moved with the cylinder
    (within one element); the fixed pairing keeps the dent where it was.

    2 %: at h = 20 um the cylinder's nodes (19.6 um apart) do not match the flat's (20.5 um), and node-to-segment
    pressures oscillate with the offset: the pressed state itself is -2.0 % at the centre, the slid one +0.5 %
    (measured). The contact's edge nodes are left out: their lumped pressure depends on where the edge falls
    between nodes."""
    h, slide = 0.02, 0.1
    a, p0 = hertz_line_contact(P, 6.0, 115000.0 / (2 * (1 - 0.342**2)))
    deepest = {}
    for model in ("finite", "small"):
        problem = sliding_problem(cylinder_on_flat, model)
        state = pressed(problem)
        for d in np.linspace(0.0, slide, 21)[1:]:
            state = problem.commit(state, problem.solve(state, tangential=d))
        fields = problem.contact_fields(state)
        F = problem.total_force(state)
        assert F[1] == pytest.approx(MU * P, rel=1e-8)               # gross slip: Q = mu P
        if model == "finite":
            x = fields["coordinates"][:, 0]
            inside = np.abs(x) <= 0.8 * a
            hertz = p0 * np.sqrt(1 - (x[inside] / a) ** 2)
            assert np.abs(fields["pressure"][inside] - hertz).max() <= 0.02 * p0
        # The flat's surface: the nodes of the master facets, displaced by the elastic field (no rigid motion).
        surface = problem.operators.reference_pairing.master_surface
        nodes, first = np.unique(surface.nodes.ravel(), return_index=True)
        x = surface.x.reshape(-1, 2)[first]
        u = problem.displacement(state)
        values = _nodal_values(u, nodes)
        top = np.abs(x[:, 0]) < 0.5
        deepest[model] = x[top][np.argmin(values[top, 1])][0]
    # The flat moved by +slide under the cylinder, so the cylinder sits at x = -slide on the flat's material.
    assert abs(deepest["finite"] + slide) <= h
    assert abs(deepest["small"]) <= h


def _nodal_values(u, global_nodes):
    """Values of a vector P1 Function at global nodes (gathered on every rank)."""
    V = u.function_space
    imap = V.dofmap.index_map
    bs = V.dofmap.index_map_bs
    owned = imap.local_to_global(np.arange(imap.size_local, dtype=np.int32))
    values = u.x.array[:imap.size_local * bs].reshape(-1, bs)
    comm = V.mesh.comm
    g = np.concatenate(comm.allgather(owned))
    v = np.concatenate(comm.allgather(values))
    order = np.argsort(g)
    return v[order][np.searchsorted(g[order], global_nodes)]


def test_both_bodies_wear_the_dissipated_energy_and_the_flat_scar_spans_the_stroke(cylinder_on_flat):
    """Reciprocating gross slip, both bodies wearing (k_slave, k_master): the worn volume of the cylinder (per
    contact) plus the flat's (on its nodes) is (k / mu) x the dissipated energy (1e-10), and the flat's scar
    spans the contact width plus the relative slip stroke within two elements (the fixed pairing: the contact
    width alone)."""
    h, stroke = 0.02, 0.06
    k_slave, k_master = 2e-6, 3e-6
    widths = {}
    for model in ("finite", "small"):
        problem = sliding_problem(cylinder_on_flat, model, wear=dfr.Archard(k_slave=k_slave, k_master=k_master))
        state = pressed(problem)
        path = dfr.CyclePath.waveform(24, tangential=stroke)
        state = problem.commit(state, problem.run_cycle(state, path))
        state = problem.commit(state, problem.run_cycle(state, path))
        worn = problem.body_wear(state)
        cs = problem.contact.contact_set
        slave_volume = (worn["slave"] * cs.tributary).sum()
        if model == "finite":
            master_volume = (state.master_wear * problem.operators.surface_compliance.master_areas).sum()
        else:
            master_volume = (worn["master"] * cs.tributary).sum()
        assert slave_volume / master_volume == pytest.approx(k_slave / k_master, rel=1e-10)
        assert slave_volume + master_volume == pytest.approx((k_slave + k_master) / MU * state.dissipated_energy,
                                                             rel=1e-10)
        x = worn["master_coordinates"][worn["master"] > 0, 0]
        widths[model] = np.ptp(x)
        fields = problem.contact_fields(state)
        contact_width = np.ptp(fields["coordinates"][fields["pressure"] > 0, 0])
    # relative slip stroke: the obstacle's stroke less the elastic tangential compliance (measured by the run)
    assert widths["small"] <= contact_width + h + 1e-12
    assert widths["finite"] == pytest.approx(widths["small"] + 2 * stroke - 2 * MU * P * _tangential_compliance(
        cylinder_on_flat), abs=2 * h)


def _tangential_compliance(model):
    """Tangential displacement per unit tangential force of the stuck contact: from a problem with mu large."""
    problem = sliding_problem(model, "small")
    problem.contact.mu[:] = 100.0
    state = pressed(problem)
    state = problem.commit(state, problem.solve(state, tangential=1e-4))
    return 1e-4 / problem.total_force(state)[1]


def test_a_checkpoint_keeps_the_pairing_and_the_master_wear(cylinder_on_flat, tmp_path):
    """save_state / load_state of a re-paired, worn state: the next increment is the same, to the force
    control's tolerance (1e-8: its root finder starts from the slope the previous solve left, so two solves of
    one state agree to the tolerance, not to the bit; measured 1.7e-10)."""
    problem = sliding_problem(cylinder_on_flat, "finite", wear=dfr.Archard(k_slave=1e-6, k_master=1e-6))
    state = pressed(problem)
    for d in np.linspace(0.0, 0.05, 6)[1:]:
        state = problem.commit(state, problem.solve(state, tangential=d))
    problem.save_state(state, tmp_path / "state.npz")
    loaded, _ = problem.load_state(tmp_path / "state.npz")
    assert np.array_equal(loaded.pairing.master_faces, state.pairing.master_faces)
    a = problem.commit(state, problem.solve(state, tangential=0.06))
    b = problem.commit(loaded, problem.solve(loaded, tangential=0.06))
    for name in ("forces", "positions", "wear_gap", "master_wear"):
        assert np.allclose(getattr(a, name), getattr(b, name), rtol=0, atol=1e-8 * np.abs(getattr(a, name)).max())


def test_a_saved_master_facet_is_found_by_its_nodes_in_any_order():
    """A checkpoint's master facet (its nodes' input mesh indices, in the saved node order) is found in this
    problem's master surface by its node set, and its weights follow its nodes into this problem's node order (a
    2D segment's ends follow the local vertex numbers, which depend on the partition): a reversed segment, a
    rotated quadrilateral, a triangle with its padding; the paired point sum_i w_i X_i is then unchanged."""
    here = np.array([[10, 11, -1, -1], [12, 11, -1, -1], [4, 5, 6, 7], [5, 8, 9, -1]])
    saved = np.array([[11, 12, -1, -1], [6, 7, 4, 5], [9, 5, 8, -1]])
    weights = np.array([[0.3, 0.7, 0.0, 0.0], [0.1, 0.2, 0.3, 0.4], [0.5, 0.25, 0.25, 0.0]])
    faces, permuted = _find_facets(saved, weights, here, "state.npz")
    assert faces.tolist() == [1, 2, 3]
    assert permuted.tolist() == [[0.7, 0.3, 0.0, 0.0], [0.3, 0.4, 0.1, 0.2], [0.25, 0.25, 0.5, 0.0]]
    with pytest.raises(ValueError, match=r"contact 1 is on a master facet \(input mesh nodes \[4, 5, 6\]\)"):
        _find_facets(np.array([[10, 11, -1, -1], [4, 5, 6, -1]]), weights[:2], here, "state.npz")


def _rewritten(path, out, **changes):
    """A copy of the checkpoint ``path`` at ``out`` with arrays replaced (None: removed)."""
    with np.load(path) as npz:
        arrays = {k: npz[k] for k in npz.files}
    arrays.update(changes)
    np.savez(out, **{k: v for k, v in arrays.items() if v is not None})
    return out


def test_a_finite_sliding_checkpoint_is_refused_where_its_nodes_are_not_found(cylinder_on_flat, tmp_path):
    """A saved master facet or master wear node that is not this problem's is refused with a message naming it; a
    checkpoint of the earlier format (facet indices and DOLFINx's node numbers) still loads where they are the
    same (serially: the same numbers) and is refused where they differ."""
    problem = sliding_problem(cylinder_on_flat, "finite", wear=dfr.Archard(k_slave=1e-6, k_master=1e-6))
    state = pressed(problem)
    for d in np.linspace(0.0, 0.05, 6)[1:]:
        state = problem.commit(state, problem.solve(state, tangential=d))
    path = tmp_path / "state.npz"
    problem.save_state(state, path)
    with np.load(path) as npz:
        facet_nodes, wear_nodes = npz["pairing_facet_nodes"], npz["master_wear_nodes"]
    elsewhere = facet_nodes.copy()
    elsewhere[3, 0] = wear_nodes.max() + 10**6   # a node of no master facet
    with pytest.raises(ValueError, match="contact 3 is on a master facet"):
        problem.load_state(_rewritten(path, tmp_path / "facet.npz", pairing_facet_nodes=elsewhere))
    moved = wear_nodes.copy()
    moved[0] = wear_nodes.max() + 10**6
    with pytest.raises(ValueError, match="master wear is on .* surface nodes"):
        problem.load_state(_rewritten(path, tmp_path / "wear.npz", master_wear_nodes=moved))
    old = dict(pairing_facet_nodes=None, master_wear_nodes=None, pairing_faces=state.pairing.master_faces,
               pairing_nodes=state.pairing.master_nodes)
    loaded, _ = problem.load_state(_rewritten(path, tmp_path / "old.npz", **old))
    assert np.array_equal(loaded.pairing.master_nodes, state.pairing.master_nodes)
    assert np.array_equal(loaded.master_wear, state.master_wear)
    old["pairing_nodes"] = state.pairing.master_nodes + 1   # numbered otherwise: another partition's
    with pytest.raises(ValueError, match="the saved pairing or master wear does not fit"):
        problem.load_state(_rewritten(path, tmp_path / "renumbered.npz", **old))


def test_finite_sliding_is_refused_where_it_does_not_apply():
    with pytest.raises(SceneError, match="contact.sliding"):
        load_scene("hertz", ["contact.sliding='finite'"])
    with pytest.raises(SceneError, match="contact.sliding"):
        load_scene("cylinder-flat", ["contact.sliding='finite'", "material.model='elastoplastic'",
                                     "material.yield_stress=840", "material.hardening_modulus=7230"])
    with pytest.raises(SceneError, match="wear.cycle_jump"):
        load_scene("mccoll", ["wear.cycle_jump=true", "wear.acceleration=1"])
    with pytest.raises(ValueError, match="ElasticBody.sliding"):
        dfr.ElasticBody((None, 1), [0.0, 1.0], sliding="large")
    with pytest.raises(ValueError, match="ElasticBody.repair_slip"):
        dfr.ElasticBody((None, 1), [0.0, 1.0], sliding="finite", repair_slip=0.0)


def test_a_reach_shorter_than_the_reference_pairing_is_refused(cylinder_on_flat):
    with pytest.raises(ValueError, match="ElasticBody.reach"):
        sliding_problem(cylinder_on_flat, "finite", reach=1e-6)


def test_the_scene_runs_with_finite_sliding(tmp_path):
    """mccoll (both bodies wearing) with contact.sliding = 'finite': the summary reports the repairs and the
    flat's scar; the worn volumes add up to the wear-energy identity through the runner (1e-9)."""
    s = run_scene(load_scene("mccoll", ["contact.sliding='finite'", "geometry.contact_mesh_size=0.02",
                                        "loading.cycles=2", "loading.increments_per_cycle=16",
                                        "output.plots=false", "output.xdmf=false"]), tmp_path, quiet=True)
    assert s["sliding"] == "finite" and s["repairs"] > 0
    assert s["master_scar_width"] > s["contact_width"]
    # Both bodies' worn area (the flat's left behind by the slide included) = (k / mu) x energy: the runner's
    # summary sums the preload's and every cycle's energy with the wear acceleration (x25) of each cycle.
    assert s["wear_area"] == pytest.approx(s["wear_k_effective"] / 0.9 * s["dissipated_energy"], rel=1e-9)


# 3D ---------------------------------------------------------------------------------------------------------
def test_a_sphere_sliding_over_the_flat_in_3d():
    """The half ball on an identical flat (node-to-face, hexahedra, rollers on y = 0) slides 3 elements along x
    in gross slip: the re-paired W is the factorised one for that pairing (1e-9 of max W), the total force
    stays (P, mu P, ~0), the peak pressure stays within 3 % of the pressed one and the flat's deepest point has
    moved with the ball (within one element) while the fixed pairing keeps it in place.

    3 %: at a/h = 3 the nodal pressure's peak changes with where the ball's nodes face the flat's faces (both
    meshes' nodes match in the reference configuration, not after sliding)."""
    from support.sphere import P as P_ball, pressed, sphere_model

    deepest = {}
    for model in ("finite", "small"):
        body, problem, a, p0, h = sphere_model(3, 3.0, 1.4, flat=True, mu=MU, sliding=model, reach=2.0)
        state = pressed(problem, P_ball / 2)   # the half model carries half the ball's load
        peak = problem.contact_fields(state)["pressure"].max()
        slide = 3 * h
        for d in np.linspace(0.0, slide, 13)[1:]:
            state = problem.commit(state, problem.solve(state, tangential=(d, 0.0)))
        F = problem.total_force(state)
        # Gross slip: |q| = mu p at every node, along each node's slip, which turns slightly across x in a half
        # model (measured: Q_x 5e-8 below mu P/2, Q_y 2e-4 of it); the normal force is prescribed.
        assert F[0] == pytest.approx(P_ball / 2, rel=1e-8)
        assert F[1] == pytest.approx(MU * P_ball / 2, rel=1e-5) and abs(F[2]) <= 1e-3 * MU * P_ball / 2
        if model == "finite":
            assert problem.sliding.repairs > 0
            assert problem.contact_fields(state)["pressure"].max() == pytest.approx(peak, rel=0.03)
            direct = sphere_model(3, 3.0, 1.4, flat=True, mu=MU)[1]
            direct.operators.contact = direct.contact.with_pairing(state.pairing)
            direct.operators.build()
            problem.operators.activate(state)
            assert np.abs(problem.operators.W - direct.operators.W).max() <= 1e-9 * np.abs(direct.operators.W).max()
        surface = problem.operators.reference_pairing.master_surface
        nodes, first = np.unique(surface.nodes.ravel(), return_index=True)
        nodes, first = nodes[nodes >= 0], first[nodes >= 0]
        x = surface.x.reshape(-1, 3)[first]
        values = _nodal_values(problem.displacement(state), nodes)
        near = np.linalg.norm(x[:, :2], axis=1) < 2 * a
        deepest[model] = x[near][np.argmin(values[near, 2])][:2]
    assert np.linalg.norm(deepest["finite"] - [-slide, 0.0]) <= h
    assert np.linalg.norm(deepest["small"]) <= h


# Tests aimed at planted bugs (docs/validation-audit.md, issue 27) --------------------------------------------
def _quad_surface(n=10, h=0.1):
    """A flat 3D master z = 0 of n x n unit quadrilaterals of side h centred on the origin (global nodes 1000 + ...),
    body below, frame (n, t1, t2) = (z, x, y)."""
    coords = (np.arange(n + 1) - n / 2) * h
    index = lambda i, j: 1000 + i + (n + 1) * j  # noqa: E731
    nodes, x, inside = [], [], []
    for j in range(n):
        for i in range(n):
            corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]   # cyclic
            nodes.append([index(a, b) for a, b in corners])
            x.append([[coords[a], coords[b], 0.0] for a, b in corners])
            inside.append([coords[i] + h / 2, coords[j] + h / 2, -1.0])
    return MasterSurface(np.array(nodes), np.array(x), np.full(n * n, 4), np.array(inside),
                         tangent_frame([0.0, 0.0, 1.0]))


def test_a_stroke_along_t2_moves_the_paired_points_in_3d():
    """A rigid slide of the master along t2 (across the obstacle's t1) by D: every paired point has moved |D| from
    its slave node, |D| / h master elements (the quadrilaterals' size is h), as a slide along t1 does; after
    re-pairing each node faces the master's material point at X_s - D (exact on a flat master) and the offsets
    are zero. A measure along t1 only would see no motion at all, and never re-pair."""
    h = 0.1
    surface = _quad_surface(h=h)
    assert np.allclose(surface.reference_frame[2], [0.0, 1.0, 0.0])          # t2 = y
    xs, ys = np.meshgrid(np.linspace(-0.12, 0.12, 4) + 0.013, np.linspace(-0.12, 0.12, 4) + 0.007)
    coords = np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, 0.001)])
    pairs = surface.pair(coords)
    cs = paired_contact_set(surface, np.arange(xs.size), coords, np.full(xs.size, 0.01), coords[:, 0].copy(),
                            pairs["face"], pairs["weights"], 3 * 2000)
    nodes = np.union1d(cs.global_nodes, surface.nodes.ravel())
    m = 3 * nodes.size
    comp = sliding.SurfaceCompliance(nodes, 3, np.eye(m), np.zeros((0, m)), np.arange(surface.nodes.shape[0]),
                                     sliding.master_node_areas(surface, nodes))
    u = np.zeros((nodes.size, 3))
    for D in (np.array([0.0, 0.037, 0.0]), np.array([0.021, -0.028, 0.0])):   # along t2; oblique, |D| = 0.035
        assert sliding.offsets(cs, comp, u, D) == pytest.approx(np.full(cs.nc, np.linalg.norm(D) / h), rel=1e-12)
        new = sliding.repair(cs, comp, u, D)
        assert np.abs(new.master_points[:, :2] - (coords[:, :2] - D[:2])).max() < 1e-14
        assert sliding.offsets(new, comp, u, D).max() < 1e-12


def test_a_finite_reach_keeps_every_facet_within_it():
    """ElasticBody.reach: every master facet with a point within ``reach`` of a slave node enters the surface
    compliance (else a node sliding that far finds no facet), and none farther than reach plus the facet's own
    length. Distances here are exact (slave nodes on the line of a flat master of segments h = 0.02). reach =
    0.065 lies between the near ends (0.06 from the outermost slave node) and the centres (0.07) of the next
    facets out, so a facet whose centre is beyond reach while its near end is within must be kept."""
    h, reach = 0.02, 0.065
    x_nodes = np.linspace(-0.5, 0.5, 51)
    surface = _segment_surface(x_nodes)
    cs = _slaves_on(surface, np.linspace(-0.1, 0.1, 11))
    faces, nodes = sliding.surface_nodes(cs, reach)
    left, right = x_nodes[:-1], x_nodes[1:]
    # distance from each segment [left, right] to the nearest slave node (all on y = 0)
    distance = np.array([np.maximum(np.maximum(a - cs.coords[:, 0], cs.coords[:, 0] - b), 0.0).min()
                         for a, b in zip(left, right)])
    within = np.flatnonzero(distance <= reach)
    assert np.isin(within, faces).all(), f"facets within reach left out: {np.setdiff1d(within, faces)}"
    assert (distance[faces] <= reach + h * (1 + 1e-12)).all()
    assert np.isin(surface.nodes[within].ravel(), nodes).all() and np.isin(cs.global_nodes, nodes).all()
    assert np.array_equal(sliding.surface_nodes(cs, None)[0], np.arange(50))     # no reach: the whole master


def test_the_state_carried_into_a_new_pairing():
    """A committed state carried into the pairing of a rigid slide D of the master (no deformation): forces and
    slip are the same vectors (same frames on a flat master), the wear gap is the slave's own wear plus the
    master's wear read at the new points (the master's wear linear in x: a + b (X_s - D) exactly), and the
    relative positions are the new pairing's x = L u - G D + g0 + w: normal g0 + w, tangential -D (t1 = x)."""
    surface = _segment_surface(np.linspace(-0.5, 0.5, 51))
    xs = np.linspace(-0.1, 0.1, 9) + 0.003
    cs = _slaves_on(surface, xs, gap=0.001)
    comp = _compliance(cs, surface)
    u = np.zeros((comp.nodes.size, 2))
    D = np.array([0.067, 0.0])
    new = sliding.repair(cs, comp, u, D)
    rng = np.random.default_rng(7)
    forces, slip = rng.uniform(0.1, 1.0, 2 * cs.nc), rng.uniform(-1e-3, 1e-3, 2 * cs.nc)
    a, b = 2e-4, 1e-3
    x_master = np.r_[np.zeros(cs.nc), np.linspace(-0.5, 0.5, 51)]   # the compliance's nodes: slaves 0.., master 100..
    assert np.array_equal(comp.nodes, np.r_[np.arange(cs.nc), 100 + np.arange(51)])
    master_wear = np.where(comp.nodes >= 100, a + b * x_master, 0.0)
    own = rng.uniform(0.0, 1e-4, cs.nc)
    wear_gap = own + (a + b * xs)                                     # the master's share read at the old points
    assert sliding.interpolate_master(cs, comp, master_wear) == pytest.approx(a + b * xs, rel=1e-12)
    carried = sliding.carry_state(cs, new, comp, u, D, forces, slip, wear_gap, master_wear)
    assert carried["forces"] == pytest.approx(forces, rel=1e-14) and carried["slip"] == pytest.approx(slip, rel=1e-14)
    assert carried["wear_gap"] == pytest.approx(own + a + b * (xs - D[0]), rel=1e-12, abs=1e-18)
    assert carried["positions"][0::2] == pytest.approx(new.gap0 + carried["wear_gap"], rel=1e-12)
    assert carried["positions"][1::2] == pytest.approx(np.full(cs.nc, -D[0]), rel=1e-12)


def test_re_pairing_happens_once_a_point_has_moved_repair_slip_elements(cylinder_on_flat):
    """When re-pairing happens: gross slip in steps of 0.1 element (h = 20 um). After every commit no paired point
    is more than ElasticBody.repair_slip (0.25) elements from its slave node (the pairing is renewed as soon as one
    is), and it is renewed no more often than once per repair_slip of relative slide: about one re-pairing per
    2.5 steps, between slide / (repair_slip h) - 2 and slide / (0.1 h) (the steps; the stick phase slides less)."""
    h, step, repair_slip = 0.02, 0.002, 0.25
    problem = sliding_problem(cylinder_on_flat, "finite")
    assert problem.contact.obstacle.repair_slip == repair_slip
    state = pressed(problem)
    worst = 0.0
    steps = 30
    for d in step * np.arange(1, steps + 1):
        state = problem.commit(state, problem.solve(state, tangential=d))
        worst = max(worst, problem.relative_slip_ratio(state))
    assert worst <= repair_slip
    slide = steps * step                                 # the rigid stroke; the relative slide is a little less
    assert slide / (repair_slip * h) - 4 <= problem.sliding.repairs <= steps


# The re-pairing's fast parts against their definitions (issue 26: a re-pairing at almost every increment) -------
def _brute_closest(points, segments):
    """Closest point of each segment to each point, plainly: the first segment of least distance, its t."""
    faces, ts = [], []
    for p in points:
        best, best_t, best_d = -1, 0.0, np.inf
        for s, (a, b) in enumerate(segments):
            d_ab = b - a
            t = min(max(((p[0] - a[0]) * d_ab[0] + (p[1] - a[1]) * d_ab[1]) / (d_ab[0] ** 2 + d_ab[1] ** 2), 0.0), 1.0)
            e = p - (a + t * d_ab)
            d = np.sqrt(e[0] * e[0] + e[1] * e[1])
            if d < best_d:
                best, best_t, best_d = s, t, d
        faces.append(best)
        ts.append(best_t)
    return np.array(faces), np.array(ts)


def test_the_closest_segment_is_the_brute_force_one():
    """pair_with_segments (compiled search) against a plain loop over every segment: the same facet and weights
    (1e-15: the same formula, evaluated alike), on a wavy master of uneven segments with points off it, beyond
    its ends and on its nodes (two segments equally close up to rounding)."""
    rng = np.random.default_rng(11)
    x_nodes = np.sort(rng.uniform(-1.0, 1.0, 41))
    y_nodes = 1e-2 * np.sin(7 * x_nodes)
    ends = np.column_stack([x_nodes, y_nodes])
    segments = np.stack([ends[:-1], ends[1:]], axis=1)
    inside = segments.mean(axis=1) - [0.0, 1.0]
    points = np.vstack([np.column_stack([rng.uniform(-1.2, 1.2, 60), rng.normal(0.0, 0.02, 60)]), ends[5:9]])
    pairs = pair_with_segments(points, segments, inside)
    faces, ts = _brute_closest(points, segments)
    assert np.array_equal(pairs["face"], faces)
    assert np.abs(pairs["weights"][:, 1] - ts).max() <= 1e-15
    with pytest.raises(ValueError, match="no master segment"):
        pair_with_segments(points, segments[:0], inside[:0])


def test_the_pruned_closest_segment_search_is_the_full_one():
    """The re-pairing's search pruned from each node's previous facet (sliding._closest_segments_near) against the
    full search (contact._closest_segments): the same facet, t and distance to the bit, whatever the guess. Random
    points about a wavy master of uneven segments, each with a random previous facet (near or far), and ties:
    points on the master's nodes (two segments at distance 0), two identical copies of a segment (the first must win
    even when the guess is the second), points midway between two facets of a V (equal distances)."""
    rng = np.random.default_rng(5)
    x_nodes = np.sort(rng.uniform(-1.0, 1.0, 61))
    ends = np.column_stack([x_nodes, 1e-2 * np.sin(9 * x_nodes)])
    segments = np.stack([ends[:-1], ends[1:]], axis=1)
    segments = np.concatenate([segments, segments[20:23]])            # exact copies: ties by construction
    v = np.array([[[-1.0, 3.0], [0.0, 2.0]], [[0.0, 2.0], [1.0, 3.0]]])   # a V: on its axis x = 0 equidistant, exactly
    segments = np.concatenate([segments, v])
    on_axis = np.column_stack([np.zeros(5), [2.125, 2.25, 2.5, 2.75, 3.0]])   # dyadic: the distances are exact
    points = np.vstack([np.column_stack([rng.uniform(-1.3, 1.3, 400), rng.normal(0.0, 0.05, 400)]),
                        ends, segments[20:23].mean(axis=1), on_axis])
    A = np.ascontiguousarray(segments[:, 0])
    d = np.ascontiguousarray(segments[:, 1] - segments[:, 0])
    L2 = (d ** 2).sum(axis=1)
    n = points.shape[0]
    full = np.empty(n, dtype=np.int64), np.empty(n), np.empty(n)
    _closest_segments(points, A, d, L2, *full)
    ties = 0
    for guess in (rng.integers(0, A.shape[0], n), np.clip(full[0] + rng.integers(-2, 3, n), 0, A.shape[0] - 1),
                  np.where(np.isin(full[0], [20, 21, 22]), full[0] + 40, full[0]),   # the later copy
                  np.where(full[0] == A.shape[0] - 2, A.shape[0] - 1, full[0])):      # the V's other arm
        pruned = np.empty(n, dtype=np.int64), np.empty(n), np.empty(n)
        sliding._closest_segments_near(points, A, d, L2, guess.astype(np.int64), *pruned)
        for a, b in zip(pruned, full):
            assert np.array_equal(a, b)
        ties += int((guess != full[0]).sum())
    assert ties > 0
    # the copies and the V's axis are ties indeed: another segment at the same distance, the first one chosen
    copies = np.arange(n - 8, n - 5)
    assert np.array_equal(full[0][copies], [20, 21, 22])
    assert np.all(full[0][n - 5:] == A.shape[0] - 2)


@pytest.mark.parametrize("q_t, expected", [(0.05, "stick"), (0.5, "slip")])
def test_the_warm_pattern_solve_is_the_closed_form_of_one_contact(q_t, expected):
    """One 2D contact, ``x = W r + q`` with ``W = [[a, c], [c, b]]`` (normal-tangential coupling c), pressed
    (q_n < 0): stuck, ``r = -W^-1 q`` while ``|r_t| <= mu r_n``; sliding, ``r_t = s mu r_n`` with
    ``r_n = -q_n / (a + s c mu)`` and the slip ``x_t = c r_n + b r_t + q_t`` opposing r_t (s x_t < 0). From a zero
    warm start (every contact open) the pattern is corrected to the closed form's; the answer is the closed form to
    rounding (1e-14 of the forces: an LU of two unknowns) and x = W r + q."""
    a, b, c, mu = 2.0, 1.0, 0.3, 0.5
    W = np.array([[a, c], [c, b]])
    q = np.array([-1.0, q_t])
    stuck = -np.linalg.solve(W, q)
    if abs(stuck[1]) <= mu * stuck[0]:
        closed_form, state = stuck, "stick"
    else:
        sign = -np.sign(q_t)
        r_n = -q[0] / (a + sign * c * mu)
        closed_form, state = np.array([r_n, sign * mu * r_n]), "slip"
        assert sign * (c * r_n + b * sign * mu * r_n + q_t) < 0    # the slip opposes the friction force
    assert state == expected
    r, x = np.zeros(2), np.empty(2)
    rho = local_solvers.block_rho(W, 2)
    accepted, error, tried = cycling.warm_pattern_solve(W, q, np.array([mu]), rho, 1e-10, r, x)
    assert accepted and error < 1e-14 and tried >= 2                       # open first, then corrected
    assert np.allclose(r, closed_form, rtol=0, atol=1e-14 * np.abs(closed_form).max())
    assert np.allclose(x, W @ r + q, rtol=0, atol=1e-15)


def test_the_warm_pattern_solve_is_the_swept_solution_of_coupled_contacts():
    """Twelve coupled 2D contacts (W of a chain of springs, diagonally dominant and SPD; some open, some stuck, some
    sliding either way): from the Uzawa sweeps' solution at tol 1e-14 the answer is accepted on its pattern at once
    (from that solution perturbed by 1e-3, after at most two corrections), its natural-map error
    (``local_solvers.natural_map_error``, computed apart) below 1e-13, and it is the swept solution to 1e-9 of the
    forces (the sweeps' tolerance times cond(W) ~ 10 leaves 1e-12; the margin is for the sweeps' stopping point). A tolerance no answer meets (0) rejects every pattern and leaves
    the warm start untouched, bit for bit (the sweeps then start from it)."""
    rng = np.random.default_rng(7)
    nc = 12
    m = 2 * nc
    coupling = rng.uniform(-0.2, 0.2, (m, m))
    W = np.diag(rng.uniform(1.5, 2.5, m)) + 0.5 * (coupling + coupling.T) * (np.abs(np.subtract.outer(
        np.arange(m) // 2, np.arange(m) // 2)) <= 1)
    assert np.all(np.linalg.eigvalsh(W) > 0)
    q = np.empty(m)
    q[0::2] = rng.uniform(-1.0, 0.4, nc)          # a few open
    q[1::2] = rng.uniform(-1.0, 1.0, nc) * np.where(np.arange(nc) % 2, 1.0, 0.05)   # stuck or sliding either way
    mu = np.full(nc, 0.4)
    rho = local_solvers.block_rho(W, 2)
    swept = local_solvers.solve(W, q, mu, 2, tol=1e-14, max_iter=200000)
    assert swept.converged
    states = {"open": 0, "stick": 0, "slip": 0}
    for a in range(nc):
        rn, rt = swept.r[2 * a], swept.r[2 * a + 1]
        states["open" if rn <= 0 else "slip" if abs(rt) >= mu[a] * rn * (1 - 1e-9) else "stick"] += 1
    assert min(states.values()) >= 2, states       # every kind of contact is exercised
    for warm in (swept.r, swept.r * (1 + 1e-3 * rng.uniform(-1, 1, m))):   # its pattern; one near it
        r, x = warm.copy(), np.empty(m)
        accepted, error, tried = cycling.warm_pattern_solve(W, q, mu, rho, 1e-10, r, x)
        assert accepted and tried <= (1 if warm is swept.r else 3)
        assert local_solvers.natural_map_error(W, q, r, mu, 2, rho) < 1e-13
        assert np.abs(r - swept.r).max() <= 1e-9 * np.abs(swept.r).max()
    r = warm.copy()
    accepted, _, tried = cycling.warm_pattern_solve(W, q, mu, rho, 0.0, r, x)
    assert not accepted and np.array_equal(r, warm)


def test_the_finite_sliding_loop_solves_most_trials_on_the_warm_start_s_pattern(cylinder_on_flat):
    """In gross slip under a held normal force nearly every local solve of the compiled finite-sliding loop is its
    warm start's pattern solved exactly (cycling.warm_pattern_solve): of a cycle's 24 increments (3-5 load-control
    trials each) at most 2 sweep (measured: none; with 4 patterns tried instead of 8, the two stroke reversals),
    where the sweeps alone sweep at every trial (~50-130 sweeps a solve, benchmarks/results/sliding_speed.md)."""
    problem = sliding_problem(cylinder_on_flat, "finite", wear=dfr.Archard(k_slave=2e-6, k_master=3e-6))
    state = pressed(problem)
    path = dfr.CyclePath.waveform(24, normal=dfr.Force(P), tangential=0.06)
    result = problem.run_cycle(state, path)
    assert result.compiled
    swept = np.count_nonzero(result.records["local_iterations"])
    assert result.records["load_solves"].sum() >= 72 and swept <= 2, result.records["local_iterations"]


def test_the_contact_operator_maps_displacements_as_its_definition():
    """H of paired_contact_set (its CSR built row by row) applied to a displacement: frame . (u_s - sum_i w_i u_i)
    per contact (1e-14 relative), in 2D and in 3D with a triangle's padding; its rows' columns are sorted and hold
    no zero (a zero weight touches no column)."""
    rng = np.random.default_rng(5)
    surface = _segment_surface(np.linspace(-0.5, 0.5, 51))
    xs = np.r_[np.linspace(-0.1, 0.1, 9) + 0.003, -0.3]              # the last on a master node: a zero weight
    cs = _slaves_on(surface, xs, gap=0.001)
    quad = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    tri = [[1, 0, 0], [2, 0, 0], [1, 1, 0], [1, 1, 0]]
    faces3 = MasterSurface(np.array([[0, 1, 2, 3], [1, 4, 2, -1]]), np.array([quad, tri], float), np.array([4, 3]),
                           np.array([[0.5, 0.5, -1], [1.3, 0.3, -1]]), tangent_frame([0.0, 0.0, 1.0]))
    coords3 = np.array([[0.3, 0.6, 0.01], [1.2, 0.3, 0.02], [1.6, 0.1, 0.0]])
    pairs3 = faces3.pair(coords3)
    cs3 = paired_contact_set(faces3, np.array([10, 11, 12]), coords3, np.full(3, 0.1), coords3[:, 0].copy(),
                             pairs3["face"], pairs3["weights"], 3 * 20)
    for contact_set in (cs, cs3):
        dim = contact_set.dim
        u = rng.normal(size=contact_set.H.shape[1]).reshape(-1, dim)
        masters = contact_set.master_nodes
        relative = u[contact_set.global_nodes] - np.einsum(
            "ci,cij->cj", np.where(masters >= 0, contact_set.master_weights, 0.0), u[np.maximum(masters, 0)])
        expected = np.einsum("ckj,cj->ck", contact_set.frames, relative).ravel()
        assert np.abs(contact_set.H @ u.ravel() - expected).max() <= 1e-14 * np.abs(expected).max()
        H = contact_set.H
        assert H.has_sorted_indices and np.all(H.data != 0.0)
        assert all(np.all(np.diff(H.indices[H.indptr[i]:H.indptr[i + 1]]) > 0) for i in range(H.shape[0]))
    # normal rows (n = y): the slave's and the master nodes' y dofs; on a master node only that node's
    assert cs.H[0].nnz == 3 and cs.H[2 * (cs.nc - 1)].nnz == 2


def test_a_pairing_s_surface_operators_are_their_definitions():
    """SurfaceCompliance on a random symmetric C: L is H at the surface dofs (exactly: the same entries), the
    same object for the same pairing and its own for another; W = L C L^T (1e-13 of max W, against the dense
    product); the node rows those of :meth:`rows`; a pairing touching a node outside is refused."""
    rng = np.random.default_rng(9)
    surface = _segment_surface(np.linspace(-0.5, 0.5, 51))
    cs = _slaves_on(surface, np.linspace(-0.1, 0.1, 9) + 0.003, gap=0.001)
    nodes = np.union1d(cs.global_nodes, surface.nodes.ravel())
    m = 2 * nodes.size
    A = rng.normal(size=(m, m))
    comp = sliding.SurfaceCompliance(nodes, 2, A @ A.T / m, rng.normal(size=(1, m)),
                                     np.arange(surface.nodes.shape[0]), sliding.master_node_areas(surface, nodes))
    L = comp.restrict(cs)
    assert np.array_equal(L.toarray(), cs.H[:, comp.dofs].toarray())
    assert comp.restrict(cs) is L
    moved = sliding.repair(cs, comp, np.zeros((nodes.size, 2)), np.array([0.067, 0.0]))
    assert comp.restrict(moved) is not L and np.array_equal(comp.restrict(moved).toarray(),
                                                            moved.H[:, comp.dofs].toarray())
    W, responses = comp.operators(moved)
    dense = moved.H[:, comp.dofs].toarray()
    assert np.abs(W - dense @ comp.C @ dense.T).max() <= 1e-13 * np.abs(W).max()
    assert np.abs(responses - comp.responses @ dense.T).max() <= 1e-13 * np.abs(responses).max()
    slave_rows, master_rows = comp.pairing_rows(moved)
    assert np.array_equal(slave_rows, comp.rows(moved.global_nodes))
    assert np.array_equal(master_rows, comp.rows(moved.master_nodes))
    short = sliding.SurfaceCompliance(nodes[:-5], 2, np.eye(m - 10), np.zeros((0, m - 10)),
                                      np.arange(surface.nodes.shape[0]), np.zeros(nodes.size - 5))
    far = _slaves_on(surface, np.array([0.47]))                  # on a master facet whose nodes were cut off
    with pytest.raises(ValueError, match="ElasticBody.reach"):
        short.restrict(far)


def test_the_free_contact_operator_drops_the_fixed_columns(cylinder_on_flat):
    """Contact.H_free is H diag(free): the same entries at the free dofs, none at the fixed ones (exactly), with
    the x dofs of a few master nodes fixed besides the problem's conditions (so that H has fixed columns)."""
    problem = sliding_problem(cylinder_on_flat, "finite")
    contact = copy.copy(problem.contact)
    H = contact.contact_set.H.toarray()
    masters = np.unique(contact.contact_set.master_nodes)
    contact.fixed_global = np.union1d(contact.fixed_global, 2 * masters[:5])
    contact._use(contact.contact_set)
    free = np.ones(H.shape[1])
    free[contact.fixed_global] = 0.0
    assert np.abs(H[:, contact.fixed_global]).max() > 0
    assert np.array_equal(contact.H_free.toarray(), H * free)


# The compiled loop of finite sliding against increment by increment (issue 26) -------------------------------------
def _both_paths(problem, state, path, keep=False):
    """The cycle from ``state`` in the compiled loop and increment by increment (LocalSolver(compiled_cycles=
    False), the reference), each committed; the repairs each made. Both start from the same load control slopes
    (``operators.stiffness``, which a cycle updates: from others the first increment's root finder takes other
    trials and its answer moves by the force tolerance)."""
    out = {}
    stiffness = problem.operators.stiffness.copy()
    for compiled in (True, False):
        problem.solver = dataclasses.replace(problem.solver, compiled_cycles=compiled)
        problem.operators.stiffness[:] = stiffness
        before = problem.sliding.repairs
        result = problem.run_cycle(state, path, keep=keep)
        out[compiled] = (result, problem.commit(state, result), problem.sliding.repairs - before)
    return out


@pytest.mark.parametrize("normal", ["force", "displacement"])
def test_the_compiled_finite_sliding_cycle_is_the_stepwise_one(cylinder_on_flat, normal):
    """Two reciprocating gross-slip cycles of 3 elements' stroke (both bodies wearing, a re-pairing at most
    increments), the normal force held (force control, as McColl's scene) or the approach held: the compiled loop
    (sliding.run_sliding_increments) gives the stepwise path's increments, re-pairings and final state (forces,
    positions, slip, both bodies' wear, the pairing) to 1e-8 of each quantity's scale. Both paths make the same
    decisions and differ by the order of their sums only (measured: 1e-14 of the forces); 1e-8 is the issue's
    bound."""
    problem = sliding_problem(cylinder_on_flat, "finite", wear=dfr.Archard(k_slave=2e-6, k_master=3e-6))
    state = pressed(problem)
    held = dfr.Force(P) if normal == "force" else dfr.Displacement(float(state.obstacle[0]))
    path = dfr.CyclePath.waveform(24, normal=held, tangential=0.06)
    for _ in range(2):
        runs = _both_paths(problem, state, path)
        (compiled, fast, repairs), (stepwise, slow, repairs_slow) = runs[True], runs[False]
        assert compiled.compiled and not stepwise.compiled
        assert repairs == repairs_slow and repairs >= 12     # a 3-element stroke, re-paired every 0.25 element
        assert np.array_equal(fast.pairing.master_faces, slow.pairing.master_faces)
        for name in ("forces", "positions", "slip", "wear_gap", "master_wear", "obstacle"):
            a, b = getattr(fast, name), getattr(slow, name)
            assert np.abs(a - b).max() <= 1e-8 * np.abs(b).max(), name
        assert np.abs(fast.pairing.master_weights - slow.pairing.master_weights).max() <= 1e-8
        for name in ("normal_force", "tangential_force", "max_pressure", "dissipated_energy", "wear_area",
                     "max_wear_depth"):
            a, b = compiled.records[name], stepwise.records[name]
            assert np.abs(a - b).max() <= 1e-8 * np.abs(b).max(), name
        assert np.abs(compiled.obstacle - stepwise.obstacle).max() <= 1e-8 * np.abs(stepwise.obstacle).max()
        state = slow


def test_a_kept_compiled_finite_sliding_cycle_keeps_the_stepwise_increments(cylinder_on_flat):
    """A cycle whose increments are kept (a snapshot's, keep=True) also runs in the compiled loop: every increment's
    forces, slip, positions, wear gap and status, and the pairing they are expressed in (its facets and weights, one
    ContactSet per pairing held), are the stepwise path's to 1e-8 of each quantity's scale (the paths differ by the
    order of their sums only, as in the test above)."""
    problem = sliding_problem(cylinder_on_flat, "finite", wear=dfr.Archard(k_slave=2e-6, k_master=3e-6))
    state = pressed(problem)
    path = dfr.CyclePath.waveform(24, normal=dfr.Force(P), tangential=0.06)
    runs = _both_paths(problem, state, path, keep=True)
    (compiled, fast, repairs), (stepwise, slow, repairs_slow) = runs[True], runs[False]
    assert compiled.compiled and not stepwise.compiled
    assert repairs == repairs_slow and repairs >= 12
    for a, b, name in zip(compiled.kept, stepwise.kept, ("forces", "slip", "positions", "wear_gap", "status")):
        assert a.shape == b.shape == (24,) + getattr(slow, name).shape, name
        assert np.abs(a - b).max() <= 1e-8 * np.abs(b).max(), name
    assert len(compiled.kept_pairings) == len(stepwise.kept_pairings) == 24
    for j, (a, b) in enumerate(zip(compiled.kept_pairings, stepwise.kept_pairings)):
        assert np.array_equal(a.master_faces, b.master_faces), j
        assert np.abs(a.master_weights - b.master_weights).max() <= 1e-8, j
        assert np.abs(a.frames - b.frames).max() <= 1e-12 and np.abs(a.gap0 - b.gap0).max() <= 1e-8 * np.abs(
            b.gap0).max(), j
        # a pairing held over increments is one object, as the stepwise states share theirs
        if j and (stepwise.kept_pairings[j] is stepwise.kept_pairings[j - 1]):
            assert a is compiled.kept_pairings[j - 1], j
    assert compiled.kept_pairings[-1] is fast.pairing
    assert np.abs(fast.forces - slow.forces).max() <= 1e-8 * np.abs(slow.forces).max()


def test_a_failed_compiled_finite_sliding_cycle_raises_the_stepwise_message(cylinder_on_flat):
    """A tangential force beyond mu P fails in the compiled loop, which then solves the cycle increment by
    increment: the same message and step as the stepwise path."""
    problem = sliding_problem(cylinder_on_flat, "finite")
    state = pressed(problem)
    path = dfr.CyclePath.waveform(8, normal=dfr.Force(P), tangential=dfr.Force(1.5 * MU * P))
    messages = {}
    for compiled in (True, False):
        problem.solver = dataclasses.replace(problem.solver, compiled_cycles=compiled)
        stiffness = problem.operators.stiffness.copy()
        with pytest.raises(ConvergenceError) as failure:
            problem.run_cycle(state, path)
        messages[compiled] = (str(failure.value), failure.value.step)
        problem.operators.stiffness[:] = stiffness
    assert messages[True] == messages[False]
    assert "cannot be reached" in messages[True][0]
