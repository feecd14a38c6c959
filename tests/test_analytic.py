"""Closed forms of :mod:`dolfinx_fretting.analytic` against what they are defined by: the Mindlin-Deresiewicz
energy is the area of the loop Masing's rule makes of Mindlin's load-displacement curve (integrated here
numerically, branch by branch), its series for small loads, and G* the initial tangential stiffness 8 a G*; the
cylinder's Cattaneo-Mindlin shear carries Q and is mu p in the slip zone; the rounded punch's pressure is the
half-plane inversion integral of its gap's slope (scipy's quadrature) and carries P."""

import numpy as np
import pytest
from scipy.integrate import quad

from dolfinx_fretting.analytic import (cattaneo_mindlin_shear, cattaneo_mindlin_sphere_traction,
                                       cattaneo_mindlin_stick_half_width, cattaneo_mindlin_stick_radius,
                                       hertz_line_contact, hertz_pressure, hertz_sphere, hertz_sphere_pressure,
                                       mindlin_deresiewicz_energy, mindlin_shear_modulus,
                                       mindlin_tangential_displacement, plane_strain_modulus,
                                       rounded_punch_half_width, rounded_punch_load, rounded_punch_pressure)

E, NU, MU, P, A = 210000.0, 0.3, 0.8, 100.0, 0.1866  # MPa, -, -, N, mm (sphere-flat's steel and Hertz radius)


def _masing_loop_area(Q_star, G_star, n=20001):
    """Area between the unloading branch from (delta*, Q*) and the reloading branch from (-delta*, -Q*): each is
    the virgin curve of half the force change, doubled (Masing), integrated by the trapezoid rule in Q."""
    virgin = np.vectorize(lambda q: mindlin_tangential_displacement(q, MU, P, A, G_star))
    Q = np.linspace(-Q_star, Q_star, n)
    delta_star = virgin(Q_star)
    unloading = delta_star - 2.0 * virgin((Q_star - Q) / 2.0)
    reloading = -delta_star + 2.0 * virgin((Q_star + Q) / 2.0)
    gap = unloading - reloading
    return float(np.sum(0.5 * (gap[1:] + gap[:-1]) * np.diff(Q)))


@pytest.mark.parametrize("phi", [0.1, 0.5, 0.8, 0.99])
def test_mindlin_deresiewicz_energy_is_the_masing_loop_area(phi):
    # The trapezoid rule on 2e4 intervals, second order: measured -2.5e-9 (phi = 0.1) ... -6.1e-9 (phi = 0.99,
    # where the virgin curve's slope (1 - q/(mu P))^(-1/3) grows near Q*), -2.5e-7 ... -6.1e-7 on 2e3: 1e-7.
    G_star = mindlin_shear_modulus(E, NU, E, NU)
    assert mindlin_deresiewicz_energy(phi * MU * P, MU, P, A, G_star) == pytest.approx(
        _masing_loop_area(phi * MU * P, G_star), rel=1e-7)


def test_mindlin_forms_at_small_loads_and_their_modulus():
    G = E / (2 * (1 + NU))
    G_star = mindlin_shear_modulus(E, NU, E, NU)
    assert G_star == pytest.approx(G / (2 * (2 - NU)), rel=1e-15)  # two identical bodies
    assert mindlin_shear_modulus(E, NU) == pytest.approx(G / (2 - NU), rel=1e-15)  # on a rigid body
    Q = 1e-4 * MU * P
    # the initial stiffness of a circular contact: 8 a G* (delta's series to first order, relative error ~Q/(mu P))
    assert Q / mindlin_tangential_displacement(Q, MU, P, A, G_star) == pytest.approx(8 * A * G_star, rel=1e-3)
    # the energy's series: Q*^3 / (36 a G* mu P) (to relative order Q*/(mu P))
    assert mindlin_deresiewicz_energy(Q, MU, P, A, G_star) == pytest.approx(Q**3 / (36 * A * G_star * MU * P),
                                                                             rel=1e-3)
    assert cattaneo_mindlin_stick_radius(A, 0.875 * MU * P, MU, P) == pytest.approx(0.5 * A, rel=1e-14)
    assert cattaneo_mindlin_stick_radius(A, 0.0, MU, P) == A
    for bad in (MU * P, -1.5 * MU * P):
        with pytest.raises(ValueError, match="below mu"):
            mindlin_deresiewicz_energy(bad, MU, P, A, G_star)


def test_worn_sphere_volume_is_the_integral_of_its_wear_profile():
    """The worn sphere's volume V(c) = pi c^4/(4R) - (4/(3 pi)) P c / E* against the integral of the profile it
    is defined by: under a uniform pressure p = P/(pi c^2) the surfaces' approach is (4 p c/(pi E*)) E(r/c)
    (Johnson eq. 3.32, E the complete elliptic integral of the second kind; scipy's ``ellipe`` takes m = (r/c)^2),
    and the wear depth closes the gap from the edge: w(r) = (c^2 - r^2)/(2R) + u(c) - u(r). Adaptive quadrature to
    1e-12: the two agree to 1e-9 (measured 1e-15)."""
    from scipy.special import ellipe

    from dolfinx_fretting.analytic import plane_strain_modulus, worn_sphere_volume

    E_star, R = plane_strain_modulus(E, NU, E, NU), 10.0
    for c in (0.2, 0.33, 0.57):
        p = P / (np.pi * c * c)
        u = lambda r: 4 * p * c / (np.pi * E_star) * ellipe((r / c) ** 2)  # noqa: E731
        depth = lambda r: (c * c - r * r) / (2 * R) + u(c) - u(r)  # noqa: E731
        integral, _ = quad(lambda r: 2 * np.pi * r * depth(r), 0.0, c, epsabs=0, epsrel=1e-12)
        assert worn_sphere_volume(c, P, R, E_star) == pytest.approx(integral, rel=1e-9)


def test_worn_sphere_contact_radius_inverts_the_volume_and_starts_at_hertz():
    from dolfinx_fretting.analytic import (hertz_sphere, plane_strain_modulus, worn_sphere_contact_radius,
                                           worn_sphere_volume)

    E_star, R = plane_strain_modulus(E, NU, E, NU), 10.0
    a, _ = hertz_sphere(P, R, E_star)
    assert worn_sphere_contact_radius(0.0, P, R, E_star) == a  # unworn: Hertz
    assert worn_sphere_contact_radius(0.1 * a**4 / R, P, R, E_star) == a  # below 0.219 a^4 / R: still Hertz
    for volume in (1e-4, 8e-4, 8e-3, 0.08):  # the bisection's root, to its 1e-12
        c = worn_sphere_contact_radius(volume, P, R, E_star)
        assert c > a and worn_sphere_volume(c, P, R, E_star) == pytest.approx(volume, rel=1e-9)
    # large wear: the rigid cap's radius (4 R V / pi)^(1/4), the elastic sag a vanishing share of the volume
    # (its share (4/(3 pi)) P c / (E* V) is 1.2e-4 at V = 10 mm^3, c = 3.4 mm; c moves by a quarter of it)
    assert worn_sphere_contact_radius(10.0, P, R, E_star) == pytest.approx((4 * R * 10.0 / np.pi) ** 0.25, rel=2e-4)
    with pytest.raises(ValueError, match="volume = -1"):
        worn_sphere_contact_radius(-1.0, P, R, E_star)


# Line contact: Cattaneo-Mindlin's shear, the rounded punch ---------------------------------------------------------
#: Two identical bodies of the paper's material (MPa): E* = E / (2 (1 - nu^2)).
E_PAIR = plane_strain_modulus(115000.0, 0.342, 115000.0, 0.342)


@pytest.mark.parametrize("ratio", [0.0, 0.5, 0.9])
def test_cattaneo_mindlin_shear_carries_Q(ratio):
    """q(x) of a cylinder (R = 6, P = 199.24, mu = 0.9) under Q = ratio mu P: its integral is Q (the trapezoidal rule
    on 2e5 intervals: 1e-6, the square-root ends' O(n^-1.5)), it is mu p outside the stick zone |x| < c (1e-12) and
    below it inside, and 0 under no tangential force."""
    R, P, mu = 6.0, 199.24, 0.9
    Q = ratio * mu * P
    a, _ = hertz_line_contact(P, R, E_PAIR)
    c = cattaneo_mindlin_stick_half_width(a, Q, mu, P)
    where = np.linspace(-a, a, 200001)
    shear = cattaneo_mindlin_shear(where, P, R, E_PAIR, Q, mu)
    friction = mu * hertz_pressure(where, P, R, E_PAIR)
    assert np.sum((shear[1:] + shear[:-1]) / 2 * np.diff(where)) == pytest.approx(Q, rel=1e-6, abs=1e-9)
    slip = np.abs(where) >= c
    assert np.allclose(shear[slip], friction[slip], rtol=1e-12, atol=1e-12)
    assert np.all(shear[~slip] < friction[~slip])
    assert np.all(cattaneo_mindlin_shear(np.array([a, 1.1 * a]), P, R, E_PAIR, Q, mu) == 0.0)


def test_rounded_punch_closed_form():
    """:func:`~dolfinx_fretting.analytic.rounded_punch_pressure` against what defines it: it carries P (the
    trapezoidal rule on 2e5 intervals: 1e-6, the square-root ends' O(n^-1.5)), vanishes at |x| = a, is Hertz's
    pressure when b = 0 (1e-12) and equals the half-plane inversion integral of the gap's slope (the demo_plugin
    quadrature, scipy's Cauchy weight; to 1e-9 at points in the flat, at x = b and on the rounded edges); the
    half-width is the root of the load (1e-12)."""
    b, R = 0.1, 6.0
    P = rounded_punch_load(0.195, b, R, E_PAIR)
    a = rounded_punch_half_width(P, b, R, E_PAIR)
    assert a == pytest.approx(0.195, rel=1e-12)
    where = np.linspace(-a, a, 200001)
    pressure = rounded_punch_pressure(where, P, b, R, E_PAIR)
    assert np.sum((pressure[1:] + pressure[:-1]) / 2 * np.diff(where)) == pytest.approx(P, rel=1e-6)
    assert pressure[0] == 0.0 and pressure[-1] == 0.0 and pressure.min() >= 0.0
    some = np.array([0.0, 0.05, 0.13, 0.19, 0.3])
    assert np.allclose(rounded_punch_pressure(some, 150.0, 0.0, R, E_PAIR), hertz_pressure(some, 150.0, R, E_PAIR),
                       rtol=1e-12, atol=1e-12)

    def inversion(x):
        """p(x) = (E*/(2 pi)) sqrt(a^2 - x^2) PV int h'(t) / (sqrt(a^2 - t^2) (t - x)) dt with t = a sin s."""
        slope = lambda s: np.sign(s) * max(abs(a * np.sin(s)) - b, 0.0) / R  # noqa: E731
        at = np.arcsin(x / a)
        total = 0.0
        kinks = [-np.pi / 2, -np.arcsin(b / a), np.arcsin(b / a), np.pi / 2]
        for low, high in zip(kinks[:-1], kinks[1:]):
            if low < at < high:   # 1/(a sin s - x) = [(s - at)/(a (sin s - sin at))] / (s - at)
                regular = lambda s: slope(s) * ((s - at) / (a * (np.sin(s) - np.sin(at))) if s != at  # noqa: E731
                                                else 1.0 / (a * np.cos(at)))
                total += quad(regular, low, high, weight="cauchy", wvar=at, limit=200)[0]
            else:
                total += quad(lambda s: slope(s) / (a * np.sin(s) - x), low, high, limit=200)[0]
        return E_PAIR / (2 * np.pi) * np.sqrt(a * a - x * x) * total

    points = np.array([0.0, 0.04, b, -0.13, 0.17, 0.19])
    assert np.allclose(rounded_punch_pressure(points, P, b, R, E_PAIR), [inversion(x) for x in points],
                       rtol=1e-9, atol=0)
    with pytest.raises(ValueError, match="b = 0.3 must satisfy 0 <= b < a = 0.2"):
        rounded_punch_load(0.2, 0.3, R, E_PAIR)


@pytest.mark.parametrize("phi", [0.0, 0.3, 0.9])
def test_sphere_pressure_and_traction_integrate_to_the_forces(phi):
    """Hertz's pressure integrates to P and Mindlin's traction to Q = phi mu P over the contact (2 pi r dr by the
    midpoint rule in theta, r = a sin(theta), which takes the square roots' infinite slope at r = a away; 2e5 points,
    measured 8e-12 for the pressure, 4.4e-9 for the traction, whose kink at the stick radius remains: bound 1e-7);
    the traction is mu p outside c and below it inside, the pressure zero beyond a."""
    R = 10.0
    E_star = plane_strain_modulus(E, NU, E, NU)
    a, p0 = hertz_sphere(P, R, E_star)
    theta = (np.arange(200000) + 0.5) * (np.pi / 2) / 200000
    r, dr = a * np.sin(theta), a * np.cos(theta) * (np.pi / 2) / 200000
    pressure = hertz_sphere_pressure(r, P, R, E_star)
    assert np.sum(pressure * 2 * np.pi * r * dr) == pytest.approx(P, rel=1e-7)
    assert pressure.max() == pytest.approx(p0, rel=1e-9) and hertz_sphere_pressure(1.01 * a, P, R, E_star) == 0.0
    traction = cattaneo_mindlin_sphere_traction(r, phi * MU * P, MU, P, R, E_star)
    assert np.sum(traction * 2 * np.pi * r * dr) == pytest.approx(phi * MU * P, rel=1e-7, abs=1e-9 * P)
    c = cattaneo_mindlin_stick_radius(a, phi * MU * P, MU, P)
    assert np.allclose(traction[r >= c], MU * pressure[r >= c], rtol=1e-14, atol=0)
    assert np.all(traction[r < c] <= MU * pressure[r < c])
