"""J2 plasticity (radial return, linear isotropic hardening) against closed forms and exact properties.

Each reference is derived in the test's comment from the law itself, not from the kernel:
``f = q - (sigma_y0 + H p)``, ``q = sqrt(3/2)|s|``, ``sigma = K tr(eps_e) 1 + 2G dev(eps_e)``,
``d eps_p = (3/2) dp s / q``. For the proportional paths below (uniaxial stress, uniaxial strain, simple
shear) the deviatoric direction never changes, so backward Euler with linear hardening is exact and any
number of load steps must land on the closed form to round-off; the tolerance 1e-10 (relative) leaves
several decades of margin over double-precision round-off (~1e-15 per operation, a few hundred operations)
and still catches any wrong factor (errors of O(1e-2) or more).

Tensors are Mandel vectors [xx, yy, zz, sqrt2 yz, sqrt2 xz, sqrt2 xy].
"""

import math

import numpy as np
import pytest

from dolfinx_fretting.materials import (
    J2Plasticity,
    LinearElastic,
    elastic_stiffness,
    plastic_modulus_from_tangent,
    radial_return_kernel,
    return_mapping,
    von_mises,
)

E, NU, SY0, H = 200e3, 0.3, 300.0, 10e3  # steel-like, MPa
LAW = J2Plasticity(E, NU, SY0, H)
G = E / (2 * (1 + NU))
K = E / (3 * (1 - 2 * NU))
S2 = math.sqrt(2.0)
RTOL = 1e-10  # see the module docstring


def mandel(xx=0.0, yy=0.0, zz=0.0, yz=0.0, xz=0.0, xy=0.0) -> np.ndarray:
    return np.array([xx, yy, zz, S2 * yz, S2 * xz, S2 * xy])


def dev(a: np.ndarray) -> np.ndarray:
    d = np.array(a, dtype=float)
    d[..., :3] -= d[..., :3].mean(axis=-1, keepdims=True)
    return d


class State:
    """A single integration point driven step by step, committing after each step."""

    def __init__(self, law=LAW, n=1):
        self.law = law
        self.eps_p = np.zeros((n, 6))
        self.p = np.zeros(n)

    def step(self, eps, commit=True):
        out = return_mapping(self.law, np.atleast_2d(eps), self.eps_p, self.p)
        if commit:
            self.eps_p, self.p = out[1], out[2]
        return out


def rel(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


# --------------------------------------------------------------------------------------------------------
# 1. Uniaxial stress
# --------------------------------------------------------------------------------------------------------

def test_uniaxial_stress():
    """sigma_xx only. Past yield, d eps = d sigma/E + dp with dp = d sigma/H (plastic axial strain = p for
    uniaxial stress, since d eps_p = (3/2) dp s/q = dp diag(1, -1/2, -1/2)), hence
        sigma = sy0 + E H/(E + H) (eps - sy0/E),   p = (sigma - sy0)/H,
    and the lateral strain eps_yy = eps_zz = -nu sigma/E - p/2.
    The lateral strains are found by Newton on sigma_yy = sigma_zz = 0 with the kernel's own tangent
    (converged to |sigma_yy,zz| <= 1e-13 sy0, which moves sigma_xx by O(1e-13) relative)."""
    st = State()
    lat = np.zeros(2)
    eps_y = SY0 / E
    worst_s = worst_p = worst_l = 0.0
    for exx in np.linspace(0, 6.1 * eps_y, 25)[1:]:
        lat = lat.copy()
        for _ in range(30):
            eps = mandel(xx=exx, yy=lat[0], zz=lat[1])
            sig, _, _, C, _ = st.step(eps, commit=False)
            r = sig[0, 1:3]
            if np.max(np.abs(r)) <= 1e-13 * SY0:
                break
            lat -= np.linalg.solve(C[0, 1:3, 1:3], r)
        else:
            raise AssertionError("lateral Newton did not converge")
        sig, eps_p, p, _, yielded = st.step(mandel(xx=exx, yy=lat[0], zz=lat[1]))
        if exx <= eps_y:
            s_ref, p_ref = E * exx, 0.0
        else:
            s_ref = SY0 + E * H / (E + H) * (exx - eps_y)
            p_ref = (s_ref - SY0) / H
            assert yielded[0]
        worst_s = max(worst_s, abs(sig[0, 0] - s_ref) / s_ref)
        worst_p = max(worst_p, abs(p[0] - p_ref) / max(p_ref, 1e-300) if p_ref else abs(p[0]))
        lat_ref = -NU * s_ref / E - p_ref / 2
        worst_l = max(worst_l, abs(lat[0] - lat_ref) / abs(lat_ref), abs(lat[1] - lat_ref) / abs(lat_ref))
        np.testing.assert_allclose(eps_p[0], p_ref * np.array([1, -0.5, -0.5, 0, 0, 0]), rtol=0,
                                   atol=RTOL * max(p_ref, 1e-300))
    assert p[0] > 0.02 * eps_y  # well past yield
    assert worst_s < RTOL and worst_p < RTOL and worst_l < RTOL, (worst_s, worst_p, worst_l)


def test_tangent_modulus_conversion():
    """E_t = E H/(E + H) is the slope of the curve above (test 1); H = E E_t/(E - E_t) inverts it."""
    Et = E * H / (E + H)
    assert plastic_modulus_from_tangent(E, Et) == pytest.approx(H, rel=1e-14)
    assert plastic_modulus_from_tangent(E, 0.0) == 0.0
    for bad in (-1.0, E, 2 * E):
        with pytest.raises(ValueError, match=r"0 <= E_t < E"):
            plastic_modulus_from_tangent(E, bad)


# --------------------------------------------------------------------------------------------------------
# 2. Uniaxial strain
# --------------------------------------------------------------------------------------------------------

def test_uniaxial_strain():
    """eps = e (1, 0, 0). Volumetric part elastic: mean stress = K e (eps_p is deviatoric).
    Deviatoric: dev eps = e (2/3, -1/3, -1/3), |dev eps| = sqrt(2/3) e, so q_trial = sqrt(3/2) 2G sqrt(2/3) e
    = 2G e; first yield at e_y = sy0/(2G). Past yield (one step from the virgin state, exact as the direction
    is fixed): dp = (2G e - sy0)/(3G + H), q = sy0 + H dp, and s = q (2/3, -1/3, -1/3) (|.| = sqrt(2/3)),
        sigma_xx = K e + 2q/3,   sigma_yy = sigma_zz = K e - q/3,   p = dp.
    Deviatoric hardening slope: dq/de = 2G H/(3G + H) (elastic 2G); the volumetric slope K is unchanged."""
    e_y = SY0 / (2 * G)
    st = State()
    errs = []
    for e in np.linspace(0, 8.2 * e_y, 33)[1:]:
        sig, eps_p, p, _, yielded = st.step(mandel(xx=e))
        dp = max(2 * G * e - SY0, 0.0) / (3 * G + H)
        q = 2 * G * e - 3 * G * dp
        ref = np.array([K * e + 2 * q / 3, K * e - q / 3, K * e - q / 3, 0, 0, 0])
        errs.append(rel(sig[0], ref))
        assert yielded[0] == (e > e_y)
        if dp:
            assert abs(p[0] - dp) <= RTOL * dp
            assert abs(q - (SY0 + H * dp)) <= 1e-12 * q  # the reference itself is on the yield surface
    assert max(errs) < RTOL, max(errs)
    # Same end state in one step from the virgin state (path independence of a proportional path).
    one = return_mapping(LAW, mandel(xx=8.2 * e_y)[None], np.zeros((1, 6)), np.zeros(1))
    assert rel(one[0], sig) < RTOL and rel(one[2], p) < RTOL


# --------------------------------------------------------------------------------------------------------
# 3. Simple shear
# --------------------------------------------------------------------------------------------------------

def test_simple_shear():
    """eps_xy = gamma/2 (Mandel component sqrt2 gamma/2). Elastic: tau = sigma_xy = G gamma, s has two
    off-diagonal entries tau, |s| = sqrt2 tau, q = sqrt3 tau: yield at tau_y = sy0/sqrt3, gamma_y = tau_y/G.
    Plastic (direction fixed): dp = (sqrt3 G gamma - sy0)/(3G + H), q = sy0 + H dp, tau = q/sqrt3, p = dp.
    The plastic shear gamma_p = 2 eps_p_xy = 2 (3/2) dp tau/q = sqrt3 dp, so tau = G (gamma - gamma_p).
    Hardening slope: d tau/d gamma = G H/(3G + H) (= G (H/3)/(G + H/3): shear hardening modulus is H/3)."""
    g_y = SY0 / math.sqrt(3) / G
    st = State()
    prev = None
    for g in np.linspace(0, 5.1 * g_y, 21)[1:]:
        sig, eps_p, p, _, yielded = st.step(mandel(xy=g / 2))
        dp = max(math.sqrt(3) * G * g - SY0, 0.0) / (3 * G + H)
        tau = (SY0 + H * dp) / math.sqrt(3) if dp else G * g
        assert rel(sig[0], mandel(xy=tau)) < RTOL
        assert abs(p[0] - dp) <= RTOL * max(dp, 1e-300)
        assert abs(eps_p[0, 5] / S2 * 2 - math.sqrt(3) * dp) <= RTOL * max(dp, 1e-300)
        assert abs(sig[0, 5] / S2 - G * (g - eps_p[0, 5] * S2)) <= RTOL * tau
        if prev is not None and dp > 0 and prev[1] > 0:
            slope = (tau - prev[0]) / (g - prev[2])
            assert slope == pytest.approx(G * H / (3 * G + H), rel=1e-8)  # a difference of O(1e2) numbers
        prev = (tau, dp, g)
    assert yielded[0] and p[0] > g_y


# --------------------------------------------------------------------------------------------------------
# 4. Non-proportional path: exact properties of radial return
# --------------------------------------------------------------------------------------------------------

def test_non_proportional_path_properties():
    """Tension (uniaxial strain) past yield, then shear added at fixed tension, then a combined step,
    elastic unloading, and reloading. Radial return guarantees, at every plastic step:
    consistency f(sigma, p) = 0 (to round-off: 1e-10 relative), plastic incompressibility
    tr(eps_p) = 0 (each increment is a deviator; 1e-14 relative to |eps_p|), normality: the increment
    d eps_p = (3/2) dp s/q is parallel to the *final* deviatoric stress s (s_final = (1 - 3G dp/q_tr) s_tr),
    and |d eps_p| = sqrt(3/2) dp. Elastic steps leave eps_p and p untouched bit for bit."""
    e_y = SY0 / (2 * G)
    path = [mandel(xx=3 * e_y), mandel(xx=3 * e_y, xy=2 * e_y), mandel(xx=2 * e_y, xy=4 * e_y, yz=-e_y),
            mandel(xx=1.9 * e_y, xy=3.9 * e_y, yz=-e_y),  # small reversal: elastic unloading
            mandel(xx=-2 * e_y, yy=e_y, xy=3 * e_y)]
    st = State()
    kinds = []
    for eps in path:
        ep0, p0 = st.eps_p.copy(), st.p.copy()
        sig, eps_p, p, _, yielded = st.step(eps)
        kinds.append(bool(yielded[0]))
        if not yielded[0]:
            assert np.array_equal(eps_p, ep0) and np.array_equal(p, p0)
            assert von_mises(sig)[0] < SY0 + H * p[0]
            continue
        q = von_mises(sig)[0]
        sy = SY0 + H * p[0]
        assert abs(q - sy) <= RTOL * sy, "consistency"
        assert abs(eps_p[0, :3].sum()) <= 1e-14 * np.linalg.norm(eps_p[0]), "incompressibility"
        d = eps_p[0] - ep0[0]
        s = dev(sig[0])
        n = s / np.linalg.norm(s)
        assert np.linalg.norm(d - (d @ n) * n) <= 1e-12 * np.linalg.norm(d), "normality"
        assert d @ n > 0
        assert np.linalg.norm(d) == pytest.approx(math.sqrt(1.5) * (p[0] - p0[0]), rel=1e-12)
        # The elastic strain gives the stress back: sigma = C_e : (eps - eps_p).
        assert rel(sig[0], elastic_stiffness(E, NU) @ (eps - eps_p[0])) < 1e-12
    assert kinds == [True, True, True, False, True]


def test_elastic_split_independence():
    """The elastic part of a path may be split into any number of steps: elastic steps change neither eps_p
    nor p, and the trial state depends only on eps - eps_p_old, so loading to eps1 (below yield) in 1 or 4
    steps and then to eps2 (plastic) gives the same state as going to eps2 directly (to round-off)."""
    e_y = SY0 / (2 * G)
    eps1 = mandel(xx=0.6 * e_y, xy=0.2 * e_y)
    eps2 = mandel(xx=2.5 * e_y, xy=1.5 * e_y, zz=-0.3 * e_y)
    results = []
    for splits in ([], [eps1], [0.25 * eps1, 0.5 * eps1, 0.9 * eps1, eps1]):
        st = State()
        for e in splits:
            assert not st.step(e)[4][0]
        results.append(st.step(eps2))
    for r in results[1:]:
        for a, b in zip(r[:4], results[0][:4]):
            assert rel(a, b) < 1e-14
    assert results[0][4][0]


# --------------------------------------------------------------------------------------------------------
# 5. Consistent tangent
# --------------------------------------------------------------------------------------------------------

def test_consistent_tangent_vs_finite_differences():
    """C = d sigma / d eps of the return mapping (eps_p_old, p_old fixed) against central differences.
    Central FD error: h^2/6 |sigma'''| + eps_mach |sigma|/h. Here sigma''' ~ G/|eps_e|^2 ~ 1e5/1e-6 per unit
    strain^3 for strains of ~1e-3, so with h = 1e-7 truncation ~ 1e-14 * 1e11/6 ~ 2e-4 MPa and round-off
    ~ 1e-16 * 1e3 / 1e-7 ~ 1e-6 MPa, both <= ~1e-9 of |C| ~ 2e5 MPa. We assert 1e-6 relative (the usual
    ~sqrt(eps) FD accuracy bound), which is far above both and far below any wrong term (a missing n(x)n
    term changes C by ~G ~ 1e5, i.e. O(1) relative). Points within FD reach of the yield surface are
    dropped (the map has a kink there)."""
    rng = np.random.default_rng(1234)
    n = 40
    e_y = SY0 / E
    eps_p_old = dev(rng.normal(scale=2 * e_y, size=(n, 6)))
    p_old = np.linalg.norm(eps_p_old, axis=1) * math.sqrt(2 / 3) * rng.uniform(1, 3, n)
    eps = eps_p_old + rng.normal(scale=1.2 * e_y, size=(n, 6))
    sig, _, _, C, yielded = return_mapping(LAW, eps, eps_p_old, p_old)
    h = 1e-7
    Cfd = np.empty_like(C)
    same = np.ones(n, bool)
    for j in range(6):
        dE = np.zeros(6)
        dE[j] = h
        sp, *_, yp = return_mapping(LAW, eps + dE, eps_p_old, p_old, tangent=False)
        sm, *_, ym = return_mapping(LAW, eps - dE, eps_p_old, p_old, tangent=False)
        Cfd[:, :, j] = (sp - sm) / (2 * h)
        same &= (yp == yielded) & (ym == yielded)
    assert yielded[same].sum() >= 10 and (~yielded[same]).sum() >= 5  # both kinds tested
    err = np.abs(Cfd - C).max(axis=(1, 2)) / np.abs(C).max(axis=(1, 2))
    assert err[same].max() < 1e-6, err[same].max()
    # Symmetric (associative flow) and, for H >= 0, positive definite.
    assert np.abs(C - C.transpose(0, 2, 1)).max() <= 1e-12 * np.abs(C).max()
    assert np.linalg.eigvalsh(C).min() > 0
    # Perfect plasticity: C n = K (1.n) 1 = 0 along the (deviatoric) flow direction n.
    law0 = J2Plasticity(E, NU, SY0, 0.0)
    s0, _, _, C0, y0 = return_mapping(law0, eps, eps_p_old, np.zeros(n))
    nn = dev(s0)[y0]
    nn /= np.linalg.norm(nn, axis=1, keepdims=True)
    assert np.abs(np.einsum("nij,nj->ni", C0[y0], nn)).max() <= 1e-10 * 2 * G


# --------------------------------------------------------------------------------------------------------
# 6. Validation, inputs untouched, elastic range
# --------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, match", [
    (dict(E=0.0), r"material\.E = 0\.0 must be finite and > 0"),
    (dict(E=float("nan")), r"material\.E = nan"),
    (dict(nu=0.5), r"material\.nu = 0\.5 must satisfy -1 < nu < 0\.5"),
    (dict(nu=-1.0), r"material\.nu = -1\.0 must satisfy -1 < nu < 0\.5"),
    (dict(sigma_y0=0.0), r"material\.sigma_y0 = 0\.0 must be > 0"),
    (dict(sigma_y0=-5.0), r"material\.sigma_y0 = -5\.0 must be > 0"),
    (dict(H=-1.0), r"material\.H = -1\.0 must satisfy 0 <= H < inf"),
    (dict(H=float("inf")), r"material\.H = inf must satisfy 0 <= H < inf"),
])
def test_validation(kwargs, match):
    args = dict(E=E, nu=NU, sigma_y0=SY0, H=H) | kwargs
    with pytest.raises(ValueError, match=match):
        J2Plasticity(**args)


def test_moduli_and_shapes():
    lam, mu = LAW.lame
    assert LAW.lame == LinearElastic(E, NU).lame and mu == pytest.approx(G, rel=1e-15)
    assert LAW.bulk == pytest.approx(lam + 2 * mu / 3, rel=1e-14)
    with pytest.raises(ValueError, match=r"eps_p_old has shape \(2, 6\), expected \(3, 6\)"):
        return_mapping(LAW, np.zeros((3, 6)), np.zeros((2, 6)), np.zeros(3))
    with pytest.raises(ValueError, match=r"p_old has shape"):
        return_mapping(LAW, np.zeros((3, 6)), np.zeros((3, 6)), np.zeros(2))
    with pytest.raises(ValueError, match=r"eps has shape \(6,\)"):
        return_mapping(LAW, np.zeros(6), np.zeros((1, 6)), np.zeros(1))
    out = return_mapping(LAW, np.zeros((0, 6)), np.zeros((0, 6)), np.zeros(0))
    assert out[0].shape == (0, 6) and out[3].shape == (0, 6, 6)
    assert return_mapping(LAW, np.zeros((2, 6)), np.zeros((2, 6)), np.zeros(2), tangent=False)[3] is None
    # von Mises of uniaxial stress and pure shear (closed forms: q = |sigma|, q = sqrt3 |tau|).
    q = von_mises(np.array([mandel(xx=-7.0), mandel(xy=2.0), mandel(xx=1, yy=1, zz=1)]))
    np.testing.assert_allclose(q, [7.0, 2 * math.sqrt(3), 0.0], rtol=1e-15, atol=1e-15)


def test_inputs_not_modified_and_kernel_in_place():
    rng = np.random.default_rng(7)
    n = 20
    eps = rng.normal(scale=1e-3, size=(n, 6))
    eps_p_old = dev(rng.normal(scale=1e-3, size=(n, 6)))
    p_old = rng.uniform(0, 1e-2, n)
    copies = [a.copy() for a in (eps, eps_p_old, p_old)]
    ref = return_mapping(LAW, eps, eps_p_old, p_old)
    for a, b in zip((eps, eps_p_old, p_old), copies):
        assert np.array_equal(a, b)
    assert ref[4].any() and not ref[4].all()
    # The kernel with preallocated outputs, committing in place (eps_p is eps_p_old, p is p_old).
    sig, C, y = np.empty((n, 6)), np.empty((n, 6, 6)), np.empty(n, bool)
    radial_return_kernel(E, NU, SY0, H, eps, eps_p_old, p_old, sig, eps_p_old, p_old, C, y, True)
    for a, b in zip((sig, eps_p_old, p_old, C, y), ref):
        assert np.array_equal(a, b)


def test_kernel_tangent_minus_elastic():
    """``want_tangent = 2`` gives C_T - C_e computed directly (what the low-rank tangent of
    plasticity.ElastoplasticBody adds to K): the consistent tangent of ``want_tangent = 1`` minus
    ``elastic_stiffness`` to round-off (a few ulp of |C_e| ~ 3e5 MPa: 1e-12 relative is far above that and
    far below any wrong term, which would be O(G)), exactly zero at elastic points, and the same stresses
    and state, bit for bit."""
    rng = np.random.default_rng(11)
    n = 60
    e_y = SY0 / E
    eps_p_old = dev(rng.normal(scale=e_y, size=(n, 6)))
    p_old = np.linalg.norm(eps_p_old, axis=1) * math.sqrt(2 / 3) * rng.uniform(1, 2, n)
    # Half the points well inside the (hardened) yield surface, half well outside.
    eps = eps_p_old + rng.normal(scale=e_y, size=(n, 6)) * np.repeat([0.2, 3.0], n // 2)[:, None]
    outs = []
    for mode in (1, 2):
        out = [np.empty((n, 6)), np.empty((n, 6)), np.empty(n), np.empty((n, 6, 6)), np.empty(n, bool)]
        radial_return_kernel(E, NU, SY0, H, eps, eps_p_old, p_old, out[0], out[1], out[2], out[3], out[4], mode)
        outs.append(out)
    (sig, ep, p, C, y), (sig2, ep2, p2, dC, y2) = outs
    assert y.any() and not y.all()
    for a, b in ((sig, sig2), (ep, ep2), (p, p2), (y, y2)):
        assert np.array_equal(a, b)
    Ce = elastic_stiffness(E, NU)
    assert np.abs(dC - (C - Ce)).max() <= 1e-12 * np.abs(Ce).max()
    assert np.all(dC[~y] == 0.0) and np.abs(dC[y]).max(axis=(1, 2)).min() > 1e-3 * G


def test_elastic_below_yield_is_hooke():
    """Below yield sigma = lambda tr(eps) 1 + 2 mu eps (Hooke, written independently of the kernel's K/G
    split; the two differ only by round-off, ~1e-16 relative)."""
    rng = np.random.default_rng(3)
    eps = rng.normal(size=(50, 6))
    eps *= 0.9 * SY0 / von_mises(eps @ elastic_stiffness(E, NU))[:, None]  # q = 0.9 sy0
    lam, mu = LAW.lame
    hooke = 2 * mu * eps
    hooke[:, :3] += lam * eps[:, :3].sum(axis=1, keepdims=True)
    sig, eps_p, p, C, y = return_mapping(LAW, eps, np.zeros((50, 6)), np.zeros(50))
    assert not y.any() and not eps_p.any() and not p.any()
    assert np.abs(sig - hooke).max() <= 1e-14 * np.abs(hooke).max()
    assert np.abs(C - elastic_stiffness(E, NU)).max() <= 1e-14 * E
    # A huge (or infinite) yield stress: elastic at any strain.
    big = rng.normal(scale=1.0, size=(50, 6))
    hooke = 2 * mu * big
    hooke[:, :3] += lam * big[:, :3].sum(axis=1, keepdims=True)
    for sy in (1e30, float("inf")):
        s, ep, pp, _, yy = return_mapping(J2Plasticity(E, NU, sy, H), big, np.zeros((50, 6)), np.zeros(50))
        assert not yy.any() and not ep.any() and not pp.any()
        assert np.abs(s - hooke).max() <= 1e-14 * np.abs(hooke).max()


def test_yield_threshold():
    """Pure shear trials with q_trial = sy (1 + r): r <= 1e-12 is elastic (the documented tolerance),
    r = +1e-9 already yields with dp = r sy/(3G + H) (a tolerance even 1e3 times looser would miss it)."""
    p_old = 1e-3
    sy = SY0 + H * p_old
    r = np.array([-1e-9, 0.0, 5e-13, 1e-10, 1e-6])
    tau = sy * (1 + r) / math.sqrt(3)  # trial shear stress, q_tr = sqrt3 tau
    eps = np.array([mandel(xy=t / (2 * G)) for t in tau])
    sig, _, p, _, y = return_mapping(LAW, eps, np.zeros((5, 6)), np.full(5, p_old))
    assert list(y) == [False, False, False, True, True]
    dp = r[3:] * sy / (3 * G + H)
    np.testing.assert_allclose(p[3:] - p_old, dp, rtol=1e-4)  # f_tr = q - sy cancels: ~1e-16/1e-10 relative


# --------------------------------------------------------------------------------------------------------
# 7. Plane strain
# --------------------------------------------------------------------------------------------------------

def test_plane_strain():
    """eps_zz = eps_yz = eps_xz = 0. Elastic: sigma_zz = lambda tr eps = nu (sigma_xx + sigma_yy), since
    sigma_xx + sigma_yy = 2 (lambda + mu) tr eps and lambda/(2 (lambda + mu)) = nu. Plastic: sigma_zz is
    whatever keeps the total eps_zz = 0, i.e. sigma_zz = (C_e (eps - eps_p))_zz with eps_p_zz != 0."""
    rng = np.random.default_rng(11)
    n = 30
    eps = np.zeros((n, 6))
    eps[:, [0, 1, 5]] = rng.normal(size=(n, 3))
    eps *= 0.8 * SY0 / von_mises(eps @ elastic_stiffness(E, NU))[:, None]
    sig, _, _, C, y = return_mapping(LAW, eps, np.zeros((n, 6)), np.zeros(n))
    assert not y.any()
    np.testing.assert_allclose(sig[:, 2], NU * (sig[:, 0] + sig[:, 1]), rtol=1e-13, atol=1e-13 * SY0)
    assert np.abs(sig[:, 3:5]).max() == 0.0
    # Past yield: out-of-plane plastic flow, sigma_zz from the elastic strain, f = 0, no out-of-plane shear.
    sig, eps_p, p, _, y = return_mapping(LAW, 5 * eps, np.zeros((n, 6)), np.zeros(n))
    assert y.all() and np.abs(eps_p[:, 2]).min() > 0
    np.testing.assert_allclose(sig[:, 2], (elastic_stiffness(E, NU) @ (5 * eps - eps_p).T)[2], rtol=1e-12)
    np.testing.assert_allclose(von_mises(sig), SY0 + H * p, rtol=RTOL)
    assert np.abs(sig[:, 3:5]).max() == 0.0 and np.abs(eps_p[:, 3:5]).max() == 0.0
