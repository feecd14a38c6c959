"""Several contact zones in one problem (``FrettingProblem(a, [contact_1, contact_2], ...)``), against closed forms.

- A block pressed by two rigid planes at once, on its top and on its side, the corner node in both zones,
  frictionless, rollers on the other two faces: the exact field is homogeneous plane strain, linear, so P1 holds it
  exactly; each zone's force and the displacement field are checked, under displacement and force control.
- Two independent blocks in one mesh, each pressed by its own plane: uniaxial plane-strain stress in each, the
  zones independent (W has no coupling between the bodies), one zone sliding (Q = mu P) while the other sticks.
- A compiled cycle with two zones against the same cycle increment by increment; an elastic-plastic body with two
  zones; a zone's window grown on its own; the errors of a problem with several zones.
"""

import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

from dolfinx import mesh  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import compat  # noqa: E402
from support.blocks import (E, E_PLANE, LEFT_X, LMBDA, MU_LAME, NU, TIGHT, component, elasticity,  # noqa: E402
                            plane_above, tagged, two_blocks, unit_squares)


# A corner touching two walls ---------------------------------------------------------------------------------
def corner_problem(**kw):
    """The unit square (4 x 4 quadrilaterals), rollers on its left (u_x = 0) and bottom (u_y = 0) faces; zone
    ``top`` a rigid plane above it, zone ``side`` one on its right; the node (1, 1) in both."""
    msh = mesh.create_unit_square(MPI.COMM_WORLD, 4, 4, mesh.CellType.quadrilateral)
    V = compat.vector_space(msh, 1)
    tags = tagged(msh, {1: lambda x: np.isclose(x[1], 1.0), 2: lambda x: np.isclose(x[0], 1.0)})
    bcs = [component(V, 0, lambda x: np.isclose(x[0], 0.0)), component(V, 1, lambda x: np.isclose(x[1], 0.0))]
    top = dfr.Contact(V, (tags, 1), dfr.RigidPlane([0.0, 1.0], [0.0, -1.0]), mu=0.0, bcs=bcs)
    side = dfr.Contact(V, (tags, 2), dfr.RigidPlane([1.0, 0.0], [-1.0, 0.0]), mu=0.0, bcs=bcs)
    return dfr.FrettingProblem(elasticity(V), [top, side], bcs, solver=TIGHT, **kw), top, side


def corner_forces(d_top: float, d_side: float) -> tuple[float, float]:
    """The closed form: u = (-d_side x, -d_top y), homogeneous plane strain; the compressive forces on the top and
    side faces (unit lengths)."""
    eps_xx, eps_yy = -d_side, -d_top
    sigma_xx = (LMBDA + 2 * MU_LAME) * eps_xx + LMBDA * eps_yy
    sigma_yy = LMBDA * eps_xx + (LMBDA + 2 * MU_LAME) * eps_yy
    return -sigma_yy, -sigma_xx


def test_a_corner_pressed_by_two_planes_is_the_homogeneous_field():
    """Displacement control of both zones. P1 holds the linear field exactly: the forces agree to 1e-8 (the local
    solver converged to 1e-12 of the natural map; measured 1.6e-13) and the displacement to 1e-8 of its largest
    value (measured 4e-12); every node of a zone carries the same pressure, the corner's in both."""
    problem, top, side = corner_problem()
    assert problem.contacts == (top, side) and problem.contact.nc == top.nc + side.nc == 10
    d_top, d_side = 1e-3, 4e-4
    state = problem.commit(problem.initial_state(), problem.solve(
        problem.initial_state(), normal={top: d_top, side: dfr.Displacement(d_side)}))
    F_top, F_side = corner_forces(d_top, d_side)
    assert problem.total_force(state, top) == pytest.approx([F_top, 0.0], rel=1e-8, abs=1e-8 * F_top)
    assert problem.total_force(state, side) == pytest.approx([F_side, 0.0], rel=1e-8, abs=1e-8 * F_top)
    for zone, force in ((top, F_top), (side, F_side)):
        fields = problem.contact_fields(state, zone)
        assert np.allclose(fields["pressure"], force, rtol=1e-8)
        assert (np.isclose(fields["coordinates"], [1.0, 1.0]).all(axis=1)).sum() == 1   # the corner in each
    u = problem.displacement(state)
    x = problem.V.tabulate_dof_coordinates()[:, :2]
    exact = np.column_stack([-d_side * x[:, 0], -d_top * x[:, 1]])
    values = u.x.array.reshape(-1, 2)
    assert np.abs(values - exact).max() <= 1e-8 * d_top
    # the obstacle vector: (n, t1) of each zone in turn
    assert state.obstacle.tolist() == [d_top, 0.0, d_side, 0.0]


def test_a_corner_under_two_forces_finds_both_approaches():
    """Force control of both zones at once (two unknown obstacle positions): the forces of the closed form give
    back its approaches, to the force tolerance (1e-8 of the force: the approach to ~1e-8 relative, measured 8e-9;
    1e-7 allowed for the coupled sweeps' last step)."""
    problem, top, side = corner_problem()
    d_top, d_side = 6e-4, 1e-3
    F_top, F_side = corner_forces(d_top, d_side)
    state, _ = problem.advance(problem.initial_state(), normal={top: dfr.Force(F_top), side: dfr.Force(F_side)})
    assert state.obstacle[[0, 2]] == pytest.approx([d_top, d_side], rel=1e-7)
    assert problem.total_force(state, top)[0] == pytest.approx(F_top, rel=1e-8)
    assert problem.total_force(state, side)[0] == pytest.approx(F_side, rel=1e-8)
    # A zone not named keeps its prescribed value (here the side's force) while the top moves to an approach.
    state, _ = problem.advance(state, normal={top: dfr.Displacement(d_top / 2)})
    assert state.force_controlled.tolist() == [False, False, True, False]
    F_top, F_side = corner_forces(d_top / 2, state.obstacle[2])
    assert problem.total_force(state, side)[0] == pytest.approx(F_side, rel=1e-8)
    assert problem.total_force(state, top)[0] == pytest.approx(F_top, rel=1e-7)


# Two blocks in one mesh (support.blocks) -----------------------------------------------------------------------
def test_two_blocks_each_pressed_by_its_own_plane_are_uniaxial_stress():
    """Frictionless: in each block sigma_yy = -E/(1 - nu^2) d, sigma_xx = 0, exact in P1 (the roller bottom lets it
    expand). Block A by a displacement, block B by a force: P_A = E' d_A and d_B = P_B / E' (unit widths), to 1e-8
    (the force tolerance; the local solver to 1e-12). W couples nothing between the bodies."""
    V, tags, bcs = two_blocks()
    a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.0, bcs=bcs)
    b = dfr.Contact(V, (tags, 2), plane_above(), mu=0.0, bcs=bcs)
    problem = dfr.FrettingProblem(elasticity(V), [a, b], bcs, solver=TIGHT)
    W, rows_a, rows_b = problem.operators.W, slice(0, 2 * a.nc), slice(2 * a.nc, 2 * (a.nc + b.nc))
    assert np.abs(W[rows_a, rows_b]).max() <= 1e-12 * np.abs(W).max()   # disconnected bodies: K^-1 block-diagonal
    d_a, P_b = 2e-3, 150.0
    state, _ = problem.advance(problem.initial_state(), normal={a: d_a, b: dfr.Force(P_b)})
    assert problem.total_force(state, a)[0] == pytest.approx(E_PLANE * d_a, rel=1e-8)
    assert problem.total_force(state, b)[0] == pytest.approx(P_b, rel=1e-8)
    assert state.obstacle[2] == pytest.approx(P_b / E_PLANE, rel=1e-7)
    assert np.allclose(problem.contact_fields(state, a)["pressure"], E_PLANE * d_a, rtol=1e-8)


def test_one_zone_slides_while_the_other_sticks():
    """Both blocks pressed by P, then both planes moved along x. Block A (mu = 0.3) driven far past sliding: every
    loaded node slips the same way, so Q_A = mu P_A exactly (to the solver's tolerance). Block B (mu = 2, a small
    motion) sticks at every loaded node, and, the bodies being independent, its answer is that of a problem with
    zone B alone on the same mesh (to 1e-8: two solves converged to 1e-12; measured 3.5e-12 on the force, 2.5e-11
    on the nodal shear). B's largest shear-to-pressure ratio is 0.42 (measured), far below its mu."""
    V, tags, bcs = two_blocks()
    a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.3, bcs=bcs)
    b = dfr.Contact(V, (tags, 2), plane_above(), mu=2.0, bcs=bcs)
    problem = dfr.FrettingProblem(elasticity(V), [a, b], bcs, solver=TIGHT)
    P = 100.0
    state, _ = problem.advance(problem.initial_state(), normal={a: dfr.Force(P), b: dfr.Force(P)})
    state, _ = problem.advance(state, tangential={a: 5e-3, b: 1e-5})
    F_a, F_b = problem.total_force(state, a), problem.total_force(state, b)
    assert F_a[0] == pytest.approx(P, rel=1e-8) and F_b[0] == pytest.approx(P, rel=1e-8)
    assert abs(F_a[1]) == pytest.approx(0.3 * P, rel=1e-8)
    status_a, status_b = (problem.contact_fields(state, zone)["status"] for zone in (a, b))
    assert (status_a == 2).all()    # STATUS_NAMES: 2 slip, 1 stick
    assert (status_b == 1).all()
    alone = dfr.FrettingProblem(elasticity(V), b, bcs, solver=TIGHT)
    single, _ = alone.advance(alone.initial_state(), normal=dfr.Force(P))
    single, _ = alone.advance(single, tangential=1e-5)
    assert F_b == pytest.approx(alone.total_force(single), rel=1e-8)
    assert problem.contact_fields(state, b)["shear"] == pytest.approx(alone.contact_fields(single)["shear"],
                                                                      rel=1e-8, abs=1e-8 * P)


def test_a_cycle_of_two_zones_compiled_is_the_cycle_increment_by_increment():
    """A fretting cycle moving zone A's plane (zone B held where it is), with Archard wear: the compiled loop (each
    zone's translation against its block of G) gives the increment-by-increment answer, to 1e-8 (both to the local
    tolerance 1e-12; measured 1.3e-14 on the wear gap, 3.6e-15 on the forces)."""
    V, tags, bcs = two_blocks()
    a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.5, bcs=bcs)
    b = dfr.Contact(V, (tags, 2), plane_above(), mu=0.5, bcs=bcs)
    answers = []
    for compiled in (True, False):
        solver = dfr.LocalSolver(tol=1e-12, compiled_cycles=compiled)
        problem = dfr.FrettingProblem(elasticity(V), [a, b], bcs, solver=solver, wear=dfr.Archard(1e-6))
        state, _ = problem.advance(problem.initial_state(), normal={a: 1e-3, b: 5e-4})
        result = problem.run_cycle(state, dfr.CyclePath.waveform(8, tangential={a: 3e-3}))
        assert result.compiled is compiled
        state = problem.commit(state, result)
        answers.append(state)
    compiled_state, stepwise_state = answers
    assert compiled_state.wear_gap.max() > 0
    assert compiled_state.wear_gap == pytest.approx(stepwise_state.wear_gap, rel=1e-8, abs=1e-8 *
                                                    compiled_state.wear_gap.max())
    scale = np.abs(stepwise_state.forces).max()
    assert np.abs(compiled_state.forces - stepwise_state.forces).max() <= 1e-8 * scale
    assert compiled_state.obstacle.tolist() == [1e-3, 0.0, 5e-4, 0.0]


def test_a_zone_s_window_grows_on_its_own(tmp_path):
    """Zone B with a window narrower than its block: pressing it raises WindowError for zone 1 (the window check
    watches each zone's outside nodes); with grow_window the problem widens zone B's window alone and the answer
    is the one without windows (to 1e-8); its checkpoint reads back to the bit."""
    V, tags, bcs = two_blocks()
    a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.3, bcs=bcs)
    narrow = dfr.Contact(V, (tags, 2), plane_above(), mu=0.3, bcs=bcs, window=0.2)
    problem = dfr.FrettingProblem(elasticity(V), [a, narrow], bcs, solver=TIGHT)
    with pytest.raises(dfr.WindowError, match=r"contact\[1\]: window = 0.2") as caught:
        problem.solve(problem.initial_state(), normal={a: 1e-3, narrow: 1e-3})
    assert caught.value.zone == 1
    growing = dfr.Contact(V, (tags, 2), plane_above(), mu=0.3, bcs=bcs, window=0.2, grow_window=True)
    problem = dfr.FrettingProblem(elasticity(V), [a, growing], bcs, solver=TIGHT)
    with pytest.warns(RuntimeWarning, match=r"contact\[1\]: candidate window grown from 0.2"):
        state, _ = problem.advance(problem.initial_state(), normal={a: 1e-3, growing: 1e-3})
    assert problem.contacts[0] is a and problem.contacts[1].window > 0.5
    # The zone keeps its name: the Contact given (``growing``) still names the zone rebuilt for the wider window.
    assert problem.total_force(state, growing)[0] > 0
    whole = dfr.FrettingProblem(elasticity(V), [a, dfr.Contact(V, (tags, 2), plane_above(), mu=0.3, bcs=bcs)], bcs,
                                solver=TIGHT)
    reference, _ = whole.advance(whole.initial_state(), normal={a: 1e-3, whole.contacts[1]: 1e-3})
    assert problem.total_force(state, problem.contacts[1]) == pytest.approx(
        whole.total_force(reference, whole.contacts[1]), rel=1e-8)
    path = tmp_path / "state.npz"
    problem.save_state(state, path)
    loaded, _ = problem.load_state(path)
    assert np.array_equal(loaded.forces, state.forces) and np.array_equal(loaded.obstacle, state.obstacle)


def test_several_zones_refuse_what_is_ambiguous():
    """A bare target, a reader without its zone, a key that is no zone, the same Contact twice, finite sliding in
    one of several zones: each refused with a message that says what to write."""
    V, tags, bcs = two_blocks(2)
    a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.3, bcs=bcs)
    b = dfr.Contact(V, (tags, 2), plane_above(), mu=0.3, bcs=bcs)
    problem = dfr.FrettingProblem(elasticity(V), [a, b], bcs)
    state = problem.initial_state()
    assert state.obstacle.shape == (4,)
    with pytest.raises(ValueError, match=r"2 contact zones: give one item per zone, normal=\{contact: value"):
        problem.solve(state, normal=1e-3)
    with pytest.raises(ValueError, match="a key is not one of this problem's contact zones"):
        problem.solve(state, normal={dfr.Contact(V, (tags, 1), plane_above(), mu=0.3, bcs=bcs): 1e-3})
    with pytest.raises(ValueError, match=r"name one, total_force\(state, contact\)"):
        problem.total_force(state)
    with pytest.raises(ValueError, match="the same Contact is listed twice"):
        dfr.FrettingProblem(elasticity(V), [a, a], bcs)
    with pytest.raises(ValueError, match="contact = \\[\\]"):
        dfr.FrettingProblem(elasticity(V), [], bcs)
    with pytest.raises(TypeError, match=r"contact\[1\] must be a Contact"):
        dfr.FrettingProblem(elasticity(V), [a, "b"], bcs)
    finite = dfr.Contact(V, (tags, 2), dfr.ElasticBody((tags, 1), [0.0, 1.0], sliding="finite"), mu=0.3, bcs=bcs)
    with pytest.raises(ValueError, match=r"contact\[1\] has ElasticBody\(sliding='finite'\)"):
        dfr.FrettingProblem(elasticity(V), [a, finite], bcs)
    # A node in two frictional zones: warned (its forces are not unique); two frictionless zones are not.
    tilted = dfr.Contact(V, (tags, 1), dfr.RigidPlane([0.0, 1.0], [0.6, -0.8]), mu=0.3, bcs=bcs)
    with pytest.warns(RuntimeWarning, match="contacts of two zones that both have friction"):
        dfr.FrettingProblem(elasticity(V), [a, tilted], bcs)
    # One zone in a list is the single Contact (its problem's arithmetic unchanged).
    assert dfr.FrettingProblem(elasticity(V), [a], bcs).contact is a


def test_an_elastic_plastic_body_with_two_zones():
    """Newton with the contact inside (elastic-plastic, J2, yield 400 MPa) on the two blocks: block A, pressed by
    1e-3 and rubbed by 2e-3 (its friction shear makes it yield), block B under P = 200 N/mm, below yield. The
    blocks are independent, so B's answer is the elastic problem's (to 1e-8: Newton and the local solver converged
    far below it; measured 1.4e-16 on the force, 0 on the approach), and A, having yielded, carries less than
    elastic."""
    V, tags, bcs = two_blocks()
    answers = []
    for plasticity in (None, dfr.Plasticity(dfr.J2Plasticity(E, NU, 400.0, 1000.0))):
        a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.3, bcs=bcs)
        b = dfr.Contact(V, (tags, 2), plane_above(), mu=0.3, bcs=bcs)
        problem = dfr.FrettingProblem(elasticity(V), [a, b], bcs, solver=TIGHT, plasticity=plasticity)
        state, _ = problem.advance(problem.initial_state(), normal={a: 1e-3, b: dfr.Force(200.0)})
        state, _ = problem.advance(state, tangential={a: 2e-3})
        yielded = problem.plastic_state(state).p.max() if plasticity is not None else 0.0
        answers.append((problem.total_force(state, a), problem.total_force(state, b), state.obstacle, yielded))
    elastic, plastic = answers
    assert plastic[3] > 1e-4                                 # A yielded
    assert plastic[0][0] < elastic[0][0]                     # and carries less at the same approach
    assert plastic[1] == pytest.approx(elastic[1], rel=1e-8)  # B: the elastic answer
    assert plastic[2][2] == pytest.approx(elastic[2][2], rel=1e-8)



def test_an_elastic_plastic_checkpoint_is_matched_by_coordinates(tmp_path):
    """An elastic-plastic state saved and loaded into a new problem on the same mesh: the displacement and every
    quadrature point's history come back equal to the bit (matched by the input mesh's node index and the points'
    coordinates, issue 27: a state moves between rank counts, tests/test_parallel.py, tests/test_mpi.py); a problem with another quadrature rule (other points) refuses it, naming
    why, instead of loading stresses into the wrong points."""
    V, tags, bcs = two_blocks()

    def problem_of(degree):
        a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.3, bcs=bcs)
        b = dfr.Contact(V, (tags, 2), plane_above(), mu=0.3, bcs=bcs)
        plasticity = dfr.Plasticity(dfr.J2Plasticity(E, NU, 400.0, 1000.0), quadrature_degree=degree)
        return dfr.FrettingProblem(elasticity(V), [a, b], bcs, solver=TIGHT, plasticity=plasticity), a, b

    problem, a, b = problem_of(2)
    state, _ = problem.advance(problem.initial_state(), normal={a: 1e-3, b: dfr.Force(200.0)})
    state, _ = problem.advance(state, tangential={a: 2e-3})
    assert state.plastic.p.max() > 1e-4   # A yielded: a history worth carrying
    problem.save_state(state, tmp_path / "plastic.npz")
    fresh, *_ = problem_of(2)
    loaded, _ = fresh.load_state(tmp_path / "plastic.npz")
    for name in ("u", "sigma", "eps_p", "p"):
        assert np.array_equal(getattr(loaded.plastic, name), getattr(state.plastic, name)), name
    other, *_ = problem_of(4)   # 3 x 3 Gauss points (degrees 2 and 3 both give 2 x 2)
    with pytest.raises(ValueError, match="does not fit this mesh"):
        other.load_state(tmp_path / "plastic.npz")


def test_an_elastic_plastic_checkpoint_refuses_a_mesh_with_a_moved_node(tmp_path):
    """The same blocks with one interior node of block A moved by a tenth of an element: the same nodes (the
    displacement's keys all match) but the quadrature points of the four cells around it elsewhere. The saved
    history belongs to the saved points; loading it onto the moved ones would give those cells another cell's
    stress without a word, so every point must find its own (within 1e-9 of the extent), not only one of them."""
    def problem_on(V, tags, bcs):
        a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.3, bcs=bcs)
        b = dfr.Contact(V, (tags, 2), plane_above(), mu=0.3, bcs=bcs)
        plasticity = dfr.Plasticity(dfr.J2Plasticity(E, NU, 400.0, 1000.0))
        return dfr.FrettingProblem(elasticity(V), [a, b], bcs, solver=TIGHT, plasticity=plasticity), a, b

    problem, a, b = problem_on(*two_blocks())
    state, _ = problem.advance(problem.initial_state(), normal={a: 1e-3, b: dfr.Force(200.0)})
    problem.save_state(state, tmp_path / "plastic.npz")
    V, tags, bcs = two_blocks()
    x = V.mesh.geometry.x
    centre = np.isclose(x[:, 0], LEFT_X + 0.5) & np.isclose(x[:, 1], 0.5)   # block A's centre node (every copy)
    assert MPI.COMM_WORLD.allreduce(int(centre.sum())) >= 1
    x[centre, 0] += 0.1 / 6                                                      # 1/10 of the 1/6 element
    moved, *_ = problem_on(V, tags, bcs)
    with pytest.raises(ValueError, match="does not fit this mesh"):
        moved.load_state(tmp_path / "plastic.npz")

def test_each_zone_wears_by_its_own_law():
    """Both blocks rubbed in gross slip, each zone with its Archard coefficient (block B's four times A's), and a
    zone left out of the mapping that does not wear. Archard's wear-energy identity holds zone by zone: the worn
    area of a zone is (k / mu) times the energy its contacts dissipate (to 1e-10: an identity of the committed
    increments' arithmetic, as tests/test_wear.py checks for one zone); the compiled cycle equals the cycle
    increment by increment with the laws per zone (1e-8)."""
    V, tags, bcs = two_blocks()
    a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.5, bcs=bcs)
    b = dfr.Contact(V, (tags, 2), plane_above(), mu=0.4, bcs=bcs)
    laws = {a: dfr.Archard(1e-6), b: dfr.Archard(4e-6)}
    finals = []
    for compiled in (True, False):
        problem = dfr.FrettingProblem(elasticity(V), [a, b], bcs, wear=laws,
                                      solver=dfr.LocalSolver(tol=1e-12, compiled_cycles=compiled))
        state, _ = problem.advance(problem.initial_state(), normal={a: 1e-3, b: 1e-3})
        result = problem.run_cycle(state, dfr.CyclePath.waveform(8, tangential={a: 3e-3, b: 3e-3}), keep=True)
        forces, slips = result.kept[0], result.kept[1]
        start, state = state, problem.commit(state, result)
        finals.append(state)
        # each zone's dissipated energy, -sum r_t . dx_t over its contacts and the cycle's increments
        for zone, mu in ((a, 0.5), (b, 0.4)):
            rows = problem.contact.zone_slice(problem.contacts.index(zone))
            r_t = forces.reshape(8, -1, 2)[:, rows, 1]
            dx_t = slips.reshape(8, -1, 2)[:, rows, 1]
            energy = -float((r_t * dx_t).sum())
            added = problem.contact_fields(state, zone)["wear"] - problem.contact_fields(start, zone)["wear"]
            worn = float(added @ problem.contact.contact_set.tributary[rows])   # over the cycle (the preload slid)
            assert energy > 0 and worn == pytest.approx(laws[zone].k / mu * energy, rel=1e-10)
    assert finals[0].wear_gap == pytest.approx(finals[1].wear_gap, rel=1e-8, abs=1e-8 * finals[1].wear_gap.max())
    # a zone not named does not wear
    problem = dfr.FrettingProblem(elasticity(V), [a, b], bcs, wear={a: dfr.Archard(1e-6)})
    state, _ = problem.advance(problem.initial_state(), normal={a: 1e-3, b: 1e-3})
    state, _ = problem.advance(state, tangential={a: 3e-3, b: 3e-3})
    assert problem.contact_fields(state, a)["wear"].max() > 0 and not problem.contact_fields(state, b)["wear"].any()
    with pytest.raises(ValueError, match="accelerations"):
        dfr.FrettingProblem(elasticity(V), [a, b], bcs, wear={a: dfr.Archard(1e-6, acceleration=10.0),
                                                               b: dfr.Archard(1e-6)})
    with pytest.raises(TypeError, match=r"wear\[contact\[1\]\] = float"):
        dfr.FrettingProblem(elasticity(V), [a, b], bcs, wear={a: dfr.Archard(1e-6), b: 1e-6})


def test_a_rigid_plane_zone_and_an_elastic_body_zone():
    """Block A under a rigid plane (zone 0) and, beside it, block D on block C (zone 1, node-to-segment on matching
    faces, C the master moved by its zone's approach), frictionless, rollers on A's and C's bottoms and on D's top.
    Uniaxial plane-strain stress everywhere: zone 0 carries E' d_0, zone 1, the stack of two unit heights, E' d_1 / 2,
    uniform along its face (matching faces pass the patch test: to 1e-8, the local tolerance 1e-12; measured 1.7e-13
    and 8e-14 on the forces)."""
    msh = unit_squares([(0.0, 0.0), (1.5, 0.0), (1.5, 1.0)], 4)
    V = compat.vector_space(msh, 1)
    fdim = 1
    msh.topology.create_connectivity(fdim, 2)
    faces = mesh.locate_entities_boundary(msh, fdim, lambda x: np.isclose(x[1], 1.0))
    cell_y = np.array([mesh.compute_midpoints(msh, 2, msh.topology.connectivity(fdim, 2).links(f))[0, 1]
                       for f in faces])
    centre_x = mesh.compute_midpoints(msh, fdim, faces)[:, 0]
    markers = np.where(centre_x < 1.2, 1, np.where(cell_y > 1.0, 2, 3)).astype(np.int32)  # A top, D bottom, C top
    order = np.argsort(faces)
    tags = mesh.meshtags(msh, fdim, faces[order], markers[order])
    pins = [(0.0, 0.0), (1.5, 0.0), (1.5, 2.0)]
    bcs = [component(V, 1, lambda x: np.isclose(x[1], 0.0) | np.isclose(x[1], 2.0)),
           component(V, 0, lambda x: np.any([np.isclose(x[0], px) & np.isclose(x[1], py) for px, py in pins],
                                            axis=0))]
    rigid = dfr.Contact(V, (tags, 1), plane_above(), mu=0.0, bcs=bcs)
    stacked = dfr.Contact(V, (tags, 2), dfr.ElasticBody((tags, 3), [0.0, 1.0]), mu=0.0, bcs=bcs)
    problem = dfr.FrettingProblem(elasticity(V), [rigid, stacked], bcs, solver=TIGHT)
    d_rigid, d_stack = 1e-3, 6e-4
    state, _ = problem.advance(problem.initial_state(), normal={rigid: d_rigid, stacked: d_stack})
    assert problem.total_force(state, rigid)[0] == pytest.approx(E_PLANE * d_rigid, rel=1e-8)
    assert problem.total_force(state, stacked)[0] == pytest.approx(E_PLANE * d_stack / 2, rel=1e-8)
    assert np.allclose(problem.contact_fields(state, stacked)["pressure"], E_PLANE * d_stack / 2, rtol=1e-8)


def test_the_deepest_zone_names_the_window_to_widen():
    """Both zones' windows too narrow, zone 1 pressed deeper: the WindowError is zone 1's, and the penetrating
    positions it lists are all on zone 1's block (x > 1.2), none of zone 0's."""
    V, tags, bcs = two_blocks()
    a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.3, bcs=bcs, window=0.2)
    b = dfr.Contact(V, (tags, 2), plane_above(), mu=0.3, bcs=bcs, window=0.2)
    problem = dfr.FrettingProblem(elasticity(V), [a, b], bcs, solver=TIGHT)
    with pytest.raises(dfr.WindowError) as caught:
        problem.solve(problem.initial_state(), normal={a: 1e-3, b: 3e-3})
    assert caught.value.zone == 1 and (caught.value.positions[:, 0] > 1.2).all()


def test_a_corner_s_two_contacts_are_carried_into_a_new_window_each_in_its_zone():
    """set_window carries forces by (zone, node): the corner node's two contacts keep their own forces (a window
    holding the whole surface gives back the same contact set, so the state carries over unchanged)."""
    problem, top, side = corner_problem()
    state = problem.commit(problem.initial_state(), problem.solve(problem.initial_state(),
                                                                  normal={top: 1e-3, side: 4e-4}))
    carried = problem.set_window(state, 10.0, zone=1)
    assert np.array_equal(carried.forces, state.forces) and np.array_equal(carried.wear_gap, state.wear_gap)
