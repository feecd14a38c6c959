"""Elastic-plastic bodies in frictional contact: Newton with the contact inside (paper Fig. 4)."""

import numpy as np
import pytest

from dolfinx_fretting import plasticity
from dolfinx_fretting import problem as problem_module
from dolfinx_fretting import simulation as sim
from dolfinx_fretting.plots import read_table
from dolfinx_fretting.scenes import SceneError, load_scene
from dolfinx_fretting.simulation import run_scene

# Cylinder on a rigid flat, coarse contact mesh, one short gross-slip cycle.
BASE = ["geometry.contact_mesh_size=0.02", "loading.normal_increments=2", "loading.cycles=1",
        "loading.increments_per_cycle=8", "output.xdmf=false", "output.plots=false",
        "output.contact_profiles=false", "wear.acceleration=1000"]
PLASTIC = ["material.model='elastoplastic'", "material.hardening_modulus=7230"]
KEYS = ("normal_force", "tangential_force", "max_pressure", "max_wear_depth", "wear_area", "dissipated_energy")


def test_huge_yield_stress_reproduces_the_elastic_run(tmp_path):
    """sigma_y far above any stress: the Newton path (quadrature-point stresses, residual, contact inside
    the loop) must give the elastic path's answer, to the local and load-control tolerances."""
    common = BASE + ["solver.local_tol=1e-12", "solver.force_tol=1e-11", "solver.quadrature_degree=2"]
    elastic = run_scene(load_scene("cylinder-flat", common), tmp_path / "e", quiet=True)
    plastic = run_scene(load_scene("cylinder-flat", common + PLASTIC + ["material.yield_stress=1e12"]),
                        tmp_path / "p", quiet=True)
    assert plastic["material_model"] == "elastoplastic" and plastic["max_equivalent_plastic_strain"] == 0.0
    for key in KEYS:
        assert plastic[key] == pytest.approx(elastic[key], rel=1e-7), key
    # An increment that stays elastic is solved exactly by the first iteration (residual at rounding).
    hist = read_table(tmp_path / "p" / "history.csv")
    assert np.all(hist["newton_iterations"] == 1)


def _cycle_ends(folder):
    """Pressure and wear profiles at the last increment of each cycle (contact_profiles.csv)."""
    t = read_table(folder / "contact_profiles.csv")
    ends = {}
    for cycle in np.unique(t["cycle"][t["cycle"] > 0]):
        last = t["increment"] == t["increment"][t["cycle"] == cycle].max()
        ends[int(cycle)] = (t["pressure"][last], t["wear"][last])
    return ends


def test_optimised_newton_equals_refactorising_full_newton(tmp_path, monkeypatch):
    """The default Newton iteration (condensed on the plastic zone: the tangent as a low-rank update of the
    elastic K; "adaptive": the first iteration with the last converged tangent) gives the answer of full
    Newton with K_T refactorised and W rebuilt at every iteration (``consistent``, the path before the
    condensation): peak pressure, pressure and wear profiles at the end of every cycle, and the plastic
    strain, within 1e-8 relative to their maxima. Also within 1e-8: full Newton condensed (the same iterates
    as the reference to rounding), and a run whose zone outgrows its limit when the first points yield,
    which switches to refactorisation there. All converge to delta_1 = 1e-8 with quadratic last steps; a
    Newton stop moved by one iteration at the threshold changes the answer by ~1e-10 (measured 3e-10 here,
    8e-10 on the 10 um mesh: benchmarks/results/plastic.md), far inside 1e-8; a wrong tangent or plastic
    force would not converge or would show at O(1e-3)."""
    overrides = [*BASE, *PLASTIC, "material.yield_stress=840", "loading.cycles=2", "output.contact_profiles=true",
                 "output.snapshot_cycles=[1, 2]"]
    consistent = overrides + ["solver.newton_tangent='consistent'"]
    default = run_scene(load_scene("cylinder-flat", overrides), tmp_path / "d", quiet=True)
    assert default["newton_tangent"] == "adaptive"
    condensed = run_scene(load_scene("cylinder-flat", consistent), tmp_path / "c", quiet=True)
    monkeypatch.setattr(plasticity.ElastoplasticBody, "condensed", False)
    full = run_scene(load_scene("cylinder-flat", consistent), tmp_path / "f", quiet=True)
    monkeypatch.setattr(plasticity.ElastoplasticBody, "condensed", True)
    monkeypatch.setattr(plasticity.ElastoplasticBody, "max_zone_dofs", 400)
    switched = run_scene(load_scene("cylinder-flat", consistent), tmp_path / "s", quiet=True)
    # Each path ran: no refactorisation when condensed, one per tangent otherwise.
    assert default["tangent_refactorizations"] == condensed["tangent_refactorizations"] == 0
    assert full["tangent_refactorizations"] > 20 and switched["tangent_refactorizations"] > 0
    ref = _cycle_ends(tmp_path / "f")
    assert sorted(ref) == [1, 2]
    for run, folder in ((default, "d"), (condensed, "c"), (switched, "s")):
        ends = _cycle_ends(tmp_path / folder)
        for cycle, (p_ref, w_ref) in ref.items():
            p, w = ends[cycle]
            assert abs(p.max() / p_ref.max() - 1) <= 1e-8, (folder, cycle)
            assert np.abs(p - p_ref).max() <= 1e-8 * p_ref.max(), (folder, cycle)
            assert np.abs(w - w_ref).max() <= 1e-8 * w_ref.max(), (folder, cycle)
        assert run["max_equivalent_plastic_strain"] == pytest.approx(full["max_equivalent_plastic_strain"], rel=1e-8)
    assert full["max_equivalent_plastic_strain"] > 1e-3


def test_plasticity_lowers_the_peak_pressure(tmp_path):
    """Gross slip at mu = 0.9 yields the surface layer (Table 2 material): the peak pressure at the end of
    the cycle falls below the elastic one, as in the paper's Fig. 13 (747 vs ~830 MPa there)."""
    elastic = run_scene(load_scene("cylinder-flat", BASE), tmp_path / "e", quiet=True)
    plastic = run_scene(load_scene("cylinder-flat", BASE + PLASTIC + ["material.yield_stress=840"]),
                        tmp_path / "p", quiet=True)
    assert plastic["max_equivalent_plastic_strain"] > 1e-3
    assert plastic["modelled"]["material"].startswith("J2 plasticity: Newton")
    assert "condensed on the plastic zone" in plastic["modelled"]["material"]
    assert "low-rank term" in plastic["modelled"]["delassus"]
    assert plastic["max_pressure"] < 0.95 * elastic["max_pressure"]
    hist = read_table(tmp_path / "p" / "history.csv")
    assert hist["yielded_points"].max() > 0 and hist["newton_iterations"].max() > 1


def test_cut_back_recovers_and_equals_small_increments(tmp_path, monkeypatch):
    """Every increment's first (full-size) Newton try is made to fail: each is cut in two halves, and the
    committed history equals a run with twice as many increments (the same load points)."""
    fresh = {"flag": False}
    increment = plasticity.ElastoplasticBody.increment
    # increments.advance as problem.py calls it: FrettingProblem.advance and each increment of a stepwise cycle
    advance = problem_module.advance

    def failing_first_try(self, local_solve, pressure):
        if fresh["flag"]:
            fresh["flag"] = False
            raise plasticity.NewtonError("deliberately too large")
        return increment(self, local_solve, pressure)

    def mark(*args, **kwargs):  # every increment of the run, preload and cycles, is one advance
        fresh["flag"] = True
        return advance(*args, **kwargs)

    # Full Newton: the adaptive tangent's fallback would retry the same full-size increment.
    yielding = BASE + PLASTIC + ["material.yield_stress=840", "solver.newton_tangent='consistent'"]
    small = run_scene(load_scene("cylinder-flat", [*yielding, "loading.normal_increments=4",
                                                   "loading.increments_per_cycle=16"]), tmp_path / "s", quiet=True)
    monkeypatch.setattr(plasticity.ElastoplasticBody, "increment", failing_first_try)
    monkeypatch.setattr(problem_module, "advance", mark)
    cut = run_scene(load_scene("cylinder-flat", yielding), tmp_path / "c", quiet=True)
    hist = read_table(tmp_path / "c" / "history.csv")
    assert np.all(hist["cutbacks"] == 1)
    for key in KEYS + ("max_equivalent_plastic_strain",):
        # Same sequence of load points, each solved to delta_1 = 1e-8: equal to ~1e-7.
        assert cut[key] == pytest.approx(small[key], rel=1e-6), key


def test_newton_failure_is_reported(tmp_path):
    scene = load_scene("cylinder-flat", BASE + PLASTIC + ["material.yield_stress=840", "solver.newton_max_iter=1",
                                                          "solver.max_cutbacks=1", "solver.newton_tangent=elastic"])
    with pytest.raises(sim.SimulationError, match=r"cycle 1, step \d+\): no convergence after 1 cut-backs"):
        run_scene(scene, tmp_path, quiet=True)


def test_plastic_scene_validation():
    with pytest.raises(SceneError, match="material.yield_stress .* is required"):
        load_scene("cylinder-flat", ["material.model='elastoplastic'", "material.hardening_modulus=1.0"])
    with pytest.raises(SceneError, match="exactly one of material.hardening_modulus"):
        load_scene("cylinder-flat", PLASTIC + ["material.yield_stress=840", "material.tangent_modulus=100"])
    with pytest.raises(SceneError, match="material.tangent_modulus"):
        load_scene("cylinder-flat", ["material.model='elastoplastic'", "material.yield_stress=840",
                                     "material.tangent_modulus=2e5"])
    with pytest.raises(SceneError, match="material.model = 'elastic'"):
        load_scene("cylinder-flat", ["material.yield_stress=840"])
    s = load_scene("cylinder-flat", ["material.model='elastoplastic'", "material.yield_stress=840",
                                     "material.tangent_modulus=6830.0"])
    # H = E E_t / (E - E_t)
    assert s.material.plastic_modulus == pytest.approx(115000 * 6830 / (115000 - 6830))
    assert s.solver.local_tol == 1e-12 and s.solver.force_tol == 1e-11


# The API on a small model of the test's own: a 2 x 1 block of 12 x 6 quadrilaterals, clamped on top, pressed
# onto a rigid plane (mu = 0.3) until its bottom corners yield, with two named loads on its sides.
def _block_problem(law, bottom_values=(0.0, 0.0), **plasticity_options):
    import ufl
    from dolfinx import fem, mesh
    from mpi4py import MPI
    from petsc4py import PETSc

    import dolfinx_fretting as dfr
    from dolfinx_fretting import _dolfinx as dfx

    msh = mesh.create_rectangle(MPI.COMM_WORLD, [[-1.0, 0.0], [1.0, 1.0]], [12, 6], mesh.CellType.quadrilateral)
    found = [mesh.locate_entities_boundary(msh, 1, f) for f in (
        lambda x: np.isclose(x[1], 0.0), lambda x: np.isclose(x[1], 1.0),
        lambda x: np.isclose(x[0], -1.0), lambda x: np.isclose(x[0], 1.0))]
    facets = np.concatenate(found)
    order = np.argsort(facets)
    marks = np.concatenate([np.full(f.size, i + 1, dtype=np.int32) for i, f in enumerate(found)])
    tags = mesh.meshtags(msh, 1, facets[order], marks[order])
    V = dfx.vector_space(msh, 1)
    top = fem.locate_dofs_topological(V, 1, tags.find(2))
    bcs = [fem.dirichletbc(np.array(bottom_values, dtype=PETSc.ScalarType), top, V)]
    contact = dfr.Contact(V, (tags, 1), dfr.RigidPlane([0.0, 0.0], [0.0, 1.0]), mu=0.3, bcs=bcs)
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    E, nu = law.E, law.nu
    lmbda, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    a = ufl.inner(lmbda * ufl.tr(eps(u)) * ufl.Identity(2) + 2 * mu * eps(u), eps(v)) * ufl.dx(
        metadata={"quadrature_degree": 2})
    ds = ufl.Measure("ds", domain=msh, subdomain_data=tags)
    loads = {"left": ufl.inner(ufl.as_vector([150.0, 0.0]), v) * ds(3),
             "right": ufl.inner(ufl.as_vector([0.0, 200.0]), v) * ds(4)}
    return dfr.FrettingProblem(a, contact, bcs, loads=loads, plasticity=dfr.Plasticity(law, **plasticity_options))


#: Approach of the plane and factors of the two loads: one load, both, the other alone, both at new factors.
LOAD_PATH = [(0.002, {}), (0.004, {}), (0.004, {"left": 1.0}), (0.004, {"left": 1.0, "right": 1.0}),
             (0.004, {"left": 0.0, "right": 2.0}), (0.003, {"left": 0.5, "right": 2.0})]


def _walk(problem):
    state = problem.initial_state()
    ends = []
    for normal, loads in LOAD_PATH:
        state = problem.commit(state, problem.solve(state, normal=normal, loads=loads))
        ends.append((state.forces.copy(), problem.displacement(state).x.array.copy(), state.plastic.p.copy()))
    return ends


def test_several_named_loads_condensed_equals_refactorising_newton(monkeypatch):
    """Two named loads switched on, combined and re-weighted along the path: the condensed iteration (one
    cached K^-1 response per load, combined with the load factors) takes every increment without handing
    one to refactorisation, and gives full Newton by refactorisation's contact forces, displacement and
    plastic strain at every step. Both are full Newton from the same start: the same iterates to rounding
    (measured 3e-13 relative), so 1e-10 catches any wrong load response (a stale one is O(1) wrong in the
    condensed iterate; it used to be caught only by the whole-body check, which refactorised instead)."""
    from dolfinx_fretting.materials import J2Plasticity

    law = J2Plasticity(200e3, 0.3, 300.0, 2000.0)
    condensed = _block_problem(law, tangent="consistent")
    ends = _walk(condensed)
    body = condensed.body
    assert body.condensed_unavailable is None
    assert body.refactorizations == 0 and body.condensed_fallbacks == 0 and body.tangent_updates > 0
    monkeypatch.setattr(plasticity.ElastoplasticBody, "condensed", False)
    reference = _block_problem(law, tangent="consistent")
    ref_ends = _walk(reference)
    assert reference.body.refactorizations > 0
    from mpi4py import MPI

    assert MPI.COMM_WORLD.allreduce(ref_ends[-1][2].max(initial=0.0), op=MPI.MAX) > 1e-2  # the corners flowed
    for (r, u, p), (r_ref, u_ref, p_ref) in zip(ends, ref_ends):
        assert np.abs(r - r_ref).max() <= 1e-10 * np.abs(r_ref).max()
        assert np.abs(u - u_ref).max() <= 1e-10 * np.abs(u_ref).max()
        assert np.abs(p - p_ref).max() <= 1e-10 * max(p_ref.max(), 1e-3)


def test_own_constitutive_update_is_used_and_refactorised():
    """A law with its own ``update`` (here J2Plasticity's attributes, but the radial return at twice the yield
    stress) runs through its update, by refactorisation (the condensed kernel is J2's radial return): its
    answer is J2Plasticity's at twice the yield stress (condensed), to rounding: both are full Newton, the
    same iterates (measured 3e-13 relative; 1e-10 as above). It used to be bypassed by the radial return at
    the attributes' yield stress, an O(1) difference."""
    from dolfinx_fretting.materials import J2Plasticity, return_mapping

    class DoubleYield(J2Plasticity):
        def update(self, strain, eps_p, p):
            return return_mapping(J2Plasticity(self.E, self.nu, 2 * self.sigma_y0, self.H), strain, eps_p, p)

    own = _block_problem(DoubleYield(200e3, 0.3, 150.0, 2000.0), tangent="consistent")
    assert own.body.condensed is False and "DoubleYield has its own update" in own.body.condensed_unavailable
    ends = _walk(own)
    assert own.body.refactorizations > 0
    plain = _block_problem(J2Plasticity(200e3, 0.3, 300.0, 2000.0), tangent="consistent")
    for (r, u, p), (r_ref, u_ref, p_ref) in zip(ends, _walk(plain)):
        assert np.abs(r - r_ref).max() <= 1e-10 * np.abs(r_ref).max()
        assert np.abs(p - p_ref).max() <= 1e-10 * max(p_ref.max(), 1e-3)


def test_nonzero_dirichlet_values_with_plasticity_are_refused():
    """The Newton loop holds the Dirichlet dofs at zero: non-zero values in ``bcs`` are refused before the
    factorisation (they used to end in a Newton failure after 60 iterations)."""
    from dolfinx_fretting.materials import J2Plasticity

    with pytest.raises(ValueError, match="non-zero Dirichlet values in bcs are not supported with plasticity"):
        _block_problem(J2Plasticity(200e3, 0.3, 300.0, 2000.0), bottom_values=(0.0, -0.002))
