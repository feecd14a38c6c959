"""Fouvry's energy wear law (``dolfinx_fretting.EnergyWear``): the worn volume is alpha times the dissipated
frictional energy, against that identity and against Archard's law it reduces to.

- Two blocks rubbed in gross slip with different friction coefficients (0.5 and 0.4) under one energy law: the
  worn area of the whole contact equals alpha times the energy dissipated (an identity of the committed
  increments' arithmetic: 1e-10), in the compiled cycle loop and increment by increment. Archard's law with one
  k would fail it: its worn area is (k / mu) times the energy, with a different mu in each zone.
- One friction coefficient: ``EnergyWear(alpha)`` wears exactly as ``Archard(alpha mu)`` (the same rate at every
  sliding contact, tau = mu p: equal to rounding).
- The per-body shares and the refusals.
"""

import numpy as np
import pytest
from mpi4py import MPI  # noqa: F401  (before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs)

import dolfinx_fretting as dfr  # noqa: E402
from support.blocks import elasticity, plane_above, two_blocks  # noqa: E402

ALPHA = 2e-6  # 1/MPa (mm^3 per N mm): large enough to wear visibly in one cycle, small beside a 1 mm block


def rubbed_blocks(wear, compiled: bool = True, mu=(0.5, 0.4)):
    """Both blocks of ``two_blocks`` under planes above them, pressed then rubbed one gross-slip cycle."""
    V, tags, bcs = two_blocks()
    zones = [dfr.Contact(V, (tags, marker), plane_above(), mu=value, bcs=bcs) for marker, value in zip((1, 2), mu)]
    problem = dfr.FrettingProblem(elasticity(V), zones, bcs, wear=wear,
                                  solver=dfr.LocalSolver(tol=1e-12, compiled_cycles=compiled))
    state, _ = problem.advance(problem.initial_state(), normal={zones[0]: 1e-3, zones[1]: 1e-3})
    path = dfr.CyclePath.waveform(8, tangential={zones[0]: 3e-3, zones[1]: 3e-3})
    state = problem.commit(state, problem.run_cycle(state, path))
    return problem, state


@pytest.mark.parametrize("compiled", [True, False])
def test_worn_area_is_alpha_times_the_dissipated_energy(compiled):
    """Each sliding contact wears alpha mu p |dx_t| while dissipating mu p |dx_t| per unit area, so the worn area
    is alpha times the energy over the preload and the cycle, whatever each zone's mu (to 1e-10: rounding of
    sums over ~30 contacts and 9 increments)."""
    problem, state = rubbed_blocks(dfr.EnergyWear(ALPHA), compiled)
    area = float(state.wear_gap @ problem.contact.contact_set.tributary)
    assert state.dissipated_energy > 0 and area > 0
    assert area == pytest.approx(ALPHA * state.dissipated_energy, rel=1e-10)
    # the rate per contact is alpha mu: two values, so the problem has no single coefficient
    mu = problem.contact.mu
    assert np.array_equal(problem.wear_coefficients(False), ALPHA * mu)
    with pytest.raises(ValueError, match="wear coefficients differ"):
        problem.wear_coefficient(False)
    problem.destroy()


def test_archard_with_one_k_does_not_satisfy_the_energy_identity():
    """The identity above is the energy law's, not any law's: Archard's k = alpha x 0.45 (between the zones'
    mu) wears (k / mu_zone) times each zone's energy, off alpha times the total by several per cent."""
    problem, state = rubbed_blocks(dfr.Archard(ALPHA * 0.45))
    area = float(state.wear_gap @ problem.contact.contact_set.tributary)
    assert abs(area / (ALPHA * state.dissipated_energy) - 1) > 0.02
    problem.destroy()


def test_energy_law_is_archard_with_k_alpha_mu():
    """One friction coefficient (0.4 in both zones): the energy law's rate alpha mu at every contact is Archard's
    k = alpha mu, so the wear gaps agree to rounding (1e-13 of the largest: the product alpha mu is formed
    once per contact in one law and once in the other)."""
    energy_problem, energy_state = rubbed_blocks(dfr.EnergyWear(ALPHA, acceleration=3.0), mu=(0.4, 0.4))
    archard_problem, archard_state = rubbed_blocks(dfr.Archard(ALPHA * 0.4, acceleration=3.0), mu=(0.4, 0.4))
    assert energy_problem.wear_coefficient(True) == pytest.approx(3.0 * ALPHA * 0.4, rel=1e-15)
    scale = archard_state.wear_gap.max()
    assert scale > 0
    assert np.abs(energy_state.wear_gap - archard_state.wear_gap).max() <= 1e-13 * scale
    energy_problem.destroy()
    archard_problem.destroy()


def test_shares_and_refusals():
    law = dfr.EnergyWear(alpha_slave=1e-6, alpha_master=3e-6)
    assert law.alpha_total == pytest.approx(4e-6) and law.slave_share == pytest.approx(0.25)
    assert law.body_coefficients == (1e-6, 3e-6)
    assert dfr.EnergyWear(1e-6).slave_share == 1.0
    assert dfr.EnergyWear(1e-6, acceleration=10).coefficients(True, np.array([0.5, 0.2])) == pytest.approx(
        [5e-6, 2e-6], rel=1e-15)
    with pytest.raises(ValueError, match="alpha_slave and alpha_master"):
        dfr.EnergyWear(alpha_slave=1e-6)
    with pytest.raises(ValueError, match="not both"):
        dfr.EnergyWear(1e-6, alpha_slave=1e-6, alpha_master=1e-6)
    with pytest.raises(ValueError, match="alpha .* required"):
        dfr.EnergyWear()
    with pytest.raises(ValueError, match="EnergyWear.alpha"):
        dfr.EnergyWear(float("nan"))
    with pytest.raises(ValueError, match="EnergyWear.acceleration"):
        dfr.EnergyWear(1e-6, acceleration=0.5)


# Through the scene runner -------------------------------------------------------------------------------------
SMALL_BLOCK = ["geometry.nx=20", "geometry.ny=20", "output.xdmf=false", "output.plots=false", "loading.cycles=3",
               "solver.local_tol=1e-13"]


def test_a_scene_wears_by_the_energy_law(tmp_path):
    """Example 1 (stromberg-block, coarse, 3 cycles) with ``wear.law = "energy"``: the worn area is alpha times the
    dissipated energy (1e-10: an identity of the committed increments up to the local tolerance 1e-13 at sticking
    contacts, as tests/test_wear.py's Archard identity), and the run equals the one with Archard's k = alpha mu
    (1e-10 of the wear: the same rate at every contact, solved to 1e-13)."""
    from dolfinx_fretting.scenes import load_scene
    from dolfinx_fretting.simulation import run_scene

    archard_scene = load_scene("stromberg-block", SMALL_BLOCK)
    mu, k = archard_scene.contact.mu, archard_scene.wear.k
    alpha = k / mu
    energy_scene = load_scene("stromberg-block", SMALL_BLOCK + ["wear.law='energy'", "wear.k=none",
                                                                f"wear.alpha={alpha!r}"])
    energy = run_scene(energy_scene, tmp_path / "energy", quiet=True)
    archard = run_scene(archard_scene, tmp_path / "archard", quiet=True)
    assert energy["converged"] and energy["wear_area"] > 0
    assert energy["wear_law"] == "energy" and energy["wear_k"] == pytest.approx(alpha, rel=1e-15)
    assert energy["wear_area"] == pytest.approx(alpha * energy["dissipated_energy"], rel=1e-10)
    assert energy["max_wear_depth"] == pytest.approx(archard["max_wear_depth"], rel=1e-10)
    assert energy["wear_k_effective"] == pytest.approx(archard["wear_k_effective"], rel=1e-14)


@pytest.mark.parametrize("overrides, message", [
    (["wear.law='energy'", "wear.k=none"], "wear.alpha = 0.0 is out of range; allowed: alpha > 0 (1/MPa) with wear.law = 'energy'"),
    (["wear.law='energy'", "wear.alpha=1e-6"], "wear.k = 1e-05 is given but wear.law = 'energy'"),
    (["wear.alpha=1e-6"], "wear.alpha = 1e-06 is given but wear.law = 'archard'"),
    (["wear.law='energy'", "wear.k=none", "wear.alpha_slave=1e-6"], "give both wear.alpha_slave and"),
])
def test_energy_law_keys_are_checked(overrides, message):
    from dolfinx_fretting.scenes import SceneError, load_scene

    with pytest.raises(SceneError) as info:
        load_scene("stromberg-block", overrides)
    assert message in str(info.value)


def test_a_scene_s_energy_law_per_body_and_its_rates():
    """The scene's ``[wear]`` section as the runner reads it (``WearSettings``): per-body alphas give each body its
    own coefficient (the wear gap's alpha their sum, the slave's share alpha_slave / (alpha_slave + alpha_master) =
    1e-8 / 4e-8 = 0.25), and ``rate_coefficient(mu)``, the rate without the acceleration that the sphere's
    worn-radius sizing multiplies by the acceleration itself, is alpha mu; the law's in-cycle rate is acceleration
    times that. Exact closed forms of the inputs (1e-15 relative: one product or sum in floating point)."""
    from dolfinx_fretting.scenes import WearSettings

    wear = WearSettings(law="energy", alpha_slave=1e-8, alpha_master=3e-8, acceleration=10.0)
    law = wear.wear_law()
    assert isinstance(law, dfr.EnergyWear)
    assert law.body_coefficients == pytest.approx((1e-8, 3e-8), rel=1e-15)
    assert wear.coefficient_total == pytest.approx(4e-8, rel=1e-15)
    assert wear.slave_share == pytest.approx(0.25, rel=1e-15)
    mu = 0.6
    assert wear.rate_coefficient(mu) == pytest.approx(4e-8 * mu, rel=1e-15)   # without the acceleration
    in_cycle = law.coefficients(True, np.array([mu, 0.3]))
    assert in_cycle == pytest.approx(10.0 * 4e-8 * np.array([mu, 0.3]), rel=1e-15)
    single = WearSettings(law="energy", alpha=2e-8, acceleration=5.0)
    assert single.rate_coefficient(0.5) == pytest.approx(1e-8, rel=1e-15) and single.slave_share == 1.0
