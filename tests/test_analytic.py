"""The sphere's closed forms of :mod:`dolfinx_fretting.analytic` against what they are defined by: the Mindlin-
Deresiewicz energy is the area of the loop Masing's rule makes of Mindlin's load-displacement curve (integrated
here numerically, branch by branch), its series for small loads, and G* the initial tangential stiffness 8 a G*."""

import numpy as np
import pytest

from dolfinx_fretting.analytic import (cattaneo_mindlin_sphere_traction, cattaneo_mindlin_stick_radius,
                                       hertz_sphere, hertz_sphere_pressure, mindlin_deresiewicz_energy,
                                       mindlin_shear_modulus, mindlin_tangential_displacement, plane_strain_modulus)

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
    from scipy.integrate import quad
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
