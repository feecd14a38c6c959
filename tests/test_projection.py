"""Projection onto the Coulomb cone (paper eq. 24) and De Saxce's modified displacement (eq. 22).

Hand-computed cases for each branch, then properties that characterise the Euclidean projection: by Moreau's
decomposition theorem, ``p = P_K(r)`` iff ``p in K``, ``r - p in K°`` and ``p . (r - p) = 0``, with
``K° = {y : mu |y_t| <= -y_n}`` the polar cone of ``K_mu``. Ordering is ``(n, t1[, t2])``.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dolfinx_fretting.local_solvers import de_saxce_x, project_coulomb

# Results of a few flops on O(1) numbers: a few ulps; 1e-14 leaves room for the (1 + mu^2) division.
EXACT = dict(rtol=1e-14, atol=1e-14)


def paper_eq24_sliding(r: np.ndarray, mu: float) -> np.ndarray:
    """Eq. (24), sliding branch, transcribed literally (r_n first):
    r - (|r_t| - mu r_n)/(1+mu^2) (t - mu n)."""
    rn, rt = r[0], r[1:]
    nt = np.linalg.norm(rt)
    direction = np.concatenate([[-mu], rt / nt])
    return r - (nt - mu * rn) / (1.0 + mu**2) * direction


@pytest.mark.parametrize(
    "r, mu, expected",
    [
        # sticking, strictly inside: |r_t| = 0.5 <= mu r_n = 1
        ([2.0, 0.5], 0.5, [2.0, 0.5]),
        # sticking on the boundary |r_t| = mu r_n: unchanged
        ([2.0, -1.0], 0.5, [2.0, -1.0]),
        # separating: mu |r_t| = 0.25 <= -r_n = 2
        ([-2.0, 0.5], 0.5, [0.0, 0.0]),
        # separating on the polar cone's boundary: mu |r_t| = 1 = -r_n
        ([-1.0, 2.0], 0.5, [0.0, 0.0]),
        # sliding: a = (r_n + mu|r_t|)/(1+mu^2) = (1 + 1)/1.25 = 1.6, p = a (1, mu sign(r_t)) = (1.6, 0.8)
        ([1.0, 2.0], 0.5, [1.6, 0.8]),
        ([1.0, -2.0], 0.5, [1.6, -0.8]),
        # sliding with r_n < 0: a = (-0.5 + 1)/1.25 = 0.4 -> (0.4, 0.2)
        ([-0.5, 2.0], 0.5, [0.4, 0.2]),
        # frictionless: K is the ray r_t = 0, r_n >= 0
        ([3.0, 1.0], 0.0, [3.0, 0.0]),
        ([-1.0, 5.0], 0.0, [0.0, 0.0]),
        # frictionless, on the negative normal axis: 0 (the sticking test 0 <= 0 * r_n must not win)
        ([-1.0, 0.0], 0.0, [0.0, 0.0]),
        # mu = 1: a = (1 + 3)/2 = 2 -> (2, 2)
        ([1.0, 3.0], 1.0, [2.0, 2.0]),
        # zero stays zero
        ([0.0, 0.0], 0.3, [0.0, 0.0]),
    ],
)
def test_projection_2d_hand_cases(r, mu, expected):
    np.testing.assert_allclose(project_coulomb(np.array(r), mu), expected, **EXACT)


@pytest.mark.parametrize(
    "r, mu, expected",
    [
        # sticking: |r_t| = 0.5 <= 0.5 * 2
        ([2.0, 0.3, 0.4], 0.5, [2.0, 0.3, 0.4]),
        # separating: 0.5 * 0.5 <= 1
        ([-1.0, 0.3, 0.4], 0.5, [0.0, 0.0, 0.0]),
        # sliding: |r_t| = 2, a = (1 + 1)/1.25 = 1.6, r_t direction (0.6, 0.8), |p_t| = 0.8
        ([1.0, 1.2, 1.6], 0.5, [1.6, 0.48, 0.64]),
        # sliding, mu = 1, r_n = 0: a = 5/2, p_t = 2.5 (0.6, -0.8)
        ([0.0, 3.0, -4.0], 1.0, [2.5, 1.5, -2.0]),
    ],
)
def test_projection_3d_hand_cases(r, mu, expected):
    np.testing.assert_allclose(project_coulomb(np.array(r), mu), expected, **EXACT)


@pytest.mark.parametrize(
    "r, mu",
    [([1.0, 2.0], 0.1), ([1.0, 2.0], 0.5), ([-0.5, 2.0], 0.5), ([-0.5, 2.0], 2.0), ([1.0, 1.2, 1.6], 0.1),
     ([1.0, 1.2, 1.6], 0.5), ([0.2, -3.0, 0.5], 2.0), ([-0.1, 0.0, 0.7], 0.5), ([-0.1, 0.0, 0.7], 2.0)],
)
def test_sliding_branch_equals_paper_eq24(r, mu):
    r = np.array(r)
    nt = np.linalg.norm(r[1:])
    assert nt > mu * r[0] and mu * nt > -r[0], "case must be in the sliding branch"
    np.testing.assert_allclose(project_coulomb(r, mu), paper_eq24_sliding(r, mu), **EXACT)


def test_batched_rows_and_validation():
    rows = np.array([[2.0, 0.5], [-2.0, 0.5], [1.0, 2.0]])
    np.testing.assert_allclose(project_coulomb(rows, 0.5), [[2.0, 0.5], [0.0, 0.0], [1.6, 0.8]], **EXACT)
    with pytest.raises(ValueError, match="mu"):
        project_coulomb(np.array([1.0, 0.0]), -0.1)
    with pytest.raises(ValueError, match="r"):
        project_coulomb(np.array([1.0, 0.0, 0.0, 0.0]), 0.1)


def test_de_saxce_x():
    # x + mu |x_t| e_n: 2D, 3D (|x_t| = 5), several rows with one mu each.
    np.testing.assert_allclose(de_saxce_x(np.array([1.0, -2.0]), 0.5), [2.0, -2.0], **EXACT)
    np.testing.assert_allclose(de_saxce_x(np.array([0.0, 3.0, 4.0]), 0.2), [1.0, 3.0, 4.0], **EXACT)
    np.testing.assert_allclose(de_saxce_x(np.array([[0.0, 1.0], [-1.0, -4.0]]), np.array([1.0, 0.25])),
                               [[1.0, 1.0], [0.0, -4.0]], **EXACT)


# ---- properties ------------------------------------------------------------------------------------------
coord = st.floats(min_value=-1e3, max_value=1e3, allow_nan=False, allow_infinity=False)
mus = st.floats(min_value=0.0, max_value=10.0, allow_nan=False)


def in_cone(p, mu, scale):
    # Rounding of a few flops relative to |r|, times (1 + mu) for the products by mu.
    tol = 1e-13 * (1.0 + mu) * scale
    return p[0] >= -tol and np.linalg.norm(p[1:]) <= mu * p[0] + tol


def in_polar(y, mu, scale):
    tol = 1e-13 * (1.0 + mu) * scale
    return mu * np.linalg.norm(y[1:]) <= -y[0] + tol


@settings(max_examples=400, deadline=None)
@given(dim=st.sampled_from([2, 3]), data=st.data(), mu=mus)
def test_projection_is_euclidean(dim, data, mu):
    r = np.array(data.draw(st.lists(coord, min_size=dim, max_size=dim)))
    scale = max(1.0, np.linalg.norm(r))
    p = project_coulomb(r, mu)
    d = r - p
    # Moreau: p in K, r - p in the polar cone, p orthogonal to r - p  <=>  p = P_K(r).
    assert in_cone(p, mu, scale)
    assert in_polar(d, mu, scale)
    assert abs(p @ d) <= 1e-12 * (1.0 + mu) * scale**2  # cancellation in a dot product of size |r|^2
    # Nonexpansive with respect to the apex 0 = P(0).
    assert np.linalg.norm(p) <= np.linalg.norm(r) * (1 + 1e-14) + 1e-300


@settings(max_examples=300, deadline=None)
@given(dim=st.sampled_from([2, 3]), data=st.data(), mu=mus)
def test_projection_idempotent(dim, data, mu):
    r = np.array(data.draw(st.lists(coord, min_size=dim, max_size=dim)))
    p = project_coulomb(r, mu)
    # A boundary point may re-enter the sliding branch by one ulp: equal to rounding, not bitwise.
    atol = 1e-13 * (1 + mu) * max(1.0, np.abs(r).max())
    np.testing.assert_allclose(project_coulomb(p, mu), p, rtol=0, atol=atol)


@settings(max_examples=300, deadline=None)
@given(dim=st.sampled_from([2, 3]), data=st.data(), mu=st.floats(min_value=0.05, max_value=10.0))
def test_moreau_decomposition_with_dual_cone(dim, data, mu):
    """r = P_K(r) + P_{K°}(r), where K° = -K_{1/mu} (the polar of K_mu is the reflected dual cone)."""
    r = np.array(data.draw(st.lists(coord, min_size=dim, max_size=dim)))
    polar = -project_coulomb(-r, 1.0 / mu)
    np.testing.assert_allclose(project_coulomb(r, mu) + polar, r, rtol=0,
                               atol=1e-13 * (1 + mu + 1 / mu) * max(1.0, np.abs(r).max()))


@settings(max_examples=200, deadline=None)
@given(dim=st.sampled_from([2, 3]), data=st.data(), mu=mus)
def test_projection_beats_sampled_cone_points(dim, data, mu):
    """No point of a sampled set of K is closer to r than P_K(r) (direct check of the minimisation)."""
    r = np.array(data.draw(st.lists(coord, min_size=dim, max_size=dim)))
    p = project_coulomb(r, mu)
    rng = np.random.default_rng(0)
    rn = np.abs(rng.normal(size=200)) * max(1.0, np.abs(r).max())
    t = rng.normal(size=(200, dim - 1))
    t *= (mu * rn * rng.uniform(size=200) / np.maximum(np.linalg.norm(t, axis=1), 1e-300))[:, None]
    samples = np.column_stack([rn, t])
    dist = np.linalg.norm(samples - r, axis=1)
    assert np.linalg.norm(p - r) <= dist.min() * (1 + 1e-12) + 1e-12
