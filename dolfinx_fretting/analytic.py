"""Closed-form references used by the tests and the reports: line contact (plane strain) and sphere (3D).

Sources: K. L. Johnson, *Contact Mechanics* (CUP, 1985), sections 4.2 (Hertz line contact), 7.2 (Cattaneo-Mindlin
partial slip of a cylinder and of a sphere) and 7.3 (Mindlin-Deresiewicz: the oscillating tangential force);
M. Ciavarella, D. A. Hills and G. Monno, *The influence of rounded edges on indentation by a flat punch*, Proc.
IMechE C 212 (1998) (the flat punch with rounded edges on a half-plane);
R. D. Mindlin and H. Deresiewicz, *Elastic spheres in contact under varying oblique forces*, J. Appl. Mech. 20
(1953) 327-344. The 3D forms hold for elastically similar bodies (Dundurs' beta = 0: the tangential traction does
not change the pressure) and take the traction parallel to Q (Mindlin's approximation; exact for nu = 0).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["plane_strain_modulus", "hertz_line_contact", "hertz_pressure", "hertz_sphere",
           "cattaneo_mindlin_stick_half_width", "cattaneo_mindlin_shear", "rounded_punch_load",
           "rounded_punch_half_width", "rounded_punch_pressure", "hertz_sphere_pressure", "mindlin_shear_modulus",
           "cattaneo_mindlin_stick_radius", "cattaneo_mindlin_sphere_traction", "mindlin_tangential_displacement",
           "mindlin_deresiewicz_energy", "worn_sphere_volume", "worn_sphere_contact_radius"]


def plane_strain_modulus(E1: float, nu1: float, E2: float | None = None, nu2: float | None = None) -> float:
    """Contact modulus E* with 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2; a rigid second body if E2 is None."""
    inv = (1.0 - nu1**2) / E1
    if E2 is not None:
        inv += (1.0 - (nu2 if nu2 is not None else nu1) ** 2) / E2
    return 1.0 / inv


def hertz_line_contact(P: float, R: float, E_star: float) -> tuple[float, float]:
    """Half-width a and peak pressure p0 of a cylinder pressed by P per unit length (Johnson eq. 4.43).

    a = sqrt(4 P R / (pi E*)),  p0 = 2 P / (pi a).
    """
    a = np.sqrt(4.0 * P * R / (np.pi * E_star))
    # p0 = sqrt(P E* / (pi R)), the same as 2 P / (pi a) for P > 0 and 0 (not 0/0) for an open contact (P = 0)
    return float(a), float(np.sqrt(P * E_star / (np.pi * R)))


def hertz_pressure(x: np.ndarray, P: float, R: float, E_star: float, x0: float = 0.0) -> np.ndarray:
    """Hertz pressure p(x) = p0 sqrt(1 - ((x - x0)/a)^2) inside ``|x - x0| < a``, zero outside."""
    a, p0 = hertz_line_contact(P, R, E_star)
    s = 1.0 - ((np.asarray(x) - x0) / a) ** 2
    return p0 * np.sqrt(np.clip(s, 0.0, None))


def hertz_sphere(P: float, R: float, E_star: float) -> tuple[float, float]:
    """Hertz's sphere on a flat (Johnson, *Contact Mechanics*, 1985, eqs 4.22-4.23): contact radius
    ``a = (3 P R / (4 E*))^(1/3)`` and peak pressure ``p0 = 3 P / (2 pi a^2)``.

    Args:
        P: Normal force (N, > 0).
        R: Sphere radius (mm); against a sphere of radius R2, the relative radius.
        E_star: Contact modulus (MPa): ``E/(1 - nu^2)`` on a rigid flat, ``E/(2 (1 - nu^2))`` for two
            identical bodies.
    """
    a = (3.0 * P * R / (4.0 * E_star)) ** (1.0 / 3.0)
    return a, 3.0 * P / (2.0 * math.pi * a * a)


def hertz_sphere_pressure(r: np.ndarray, P: float, R: float, E_star: float) -> np.ndarray:
    """Hertz's pressure of a sphere on a flat at distances ``r`` from the centre (Johnson eq. 3.39):
    ``p = p0 sqrt(1 - r^2/a^2)`` inside the contact radius a, zero outside; a and p0 of :func:`hertz_sphere`."""
    a, p0 = hertz_sphere(P, R, E_star)
    return p0 * np.sqrt(np.clip(1.0 - (np.asarray(r, dtype=float) / a) ** 2, 0.0, None))


def cattaneo_mindlin_stick_half_width(a: float, Q: float, mu: float, P: float) -> float:
    """Stick-zone half-width c = a sqrt(1 - Q/(mu P)) for a tangential force Q < mu P (Johnson eq. 7.30)."""
    if not 0 <= Q < mu * P:
        raise ValueError(f"Q = {Q} must satisfy 0 <= Q < mu*P = {mu * P}")
    return float(a * np.sqrt(1.0 - Q / (mu * P)))


def cattaneo_mindlin_shear(x: np.ndarray, P: float, R: float, E_star: float, Q: float, mu: float) -> np.ndarray:
    """Magnitude of the shear traction of a cylinder under a tangential force ``0 <= Q < mu P`` grown from 0 at
    constant P, elastically similar bodies (Johnson section 7.2): ``q(x) = mu p0 [sqrt(1 - x^2/a^2) - (c/a)
    sqrt(1 - x^2/c^2)]``, the second term only inside the stick zone ``|x| < c``
    (:func:`cattaneo_mindlin_stick_half_width`), zero outside ``|x| < a``; a and p0 of :func:`hertz_line_contact`. It
    carries Q: its integral over x is Q."""
    a, p0 = hertz_line_contact(P, R, E_star)
    c = cattaneo_mindlin_stick_half_width(a, Q, mu, P)
    x = np.asarray(x, dtype=float)
    corrective = c / a * np.sqrt(np.clip(1.0 - (x / c) ** 2, 0.0, None)) if c > 0 else np.zeros_like(x)
    return mu * p0 * (np.sqrt(np.clip(1.0 - (x / a) ** 2, 0.0, None)) - corrective)


# Flat punch with rounded edges (line contact) -----------------------------------------------------------------
def _punch_angle(a: float, b: float) -> float:
    if not 0 <= b < a:
        raise ValueError(f"rounded punch: the flat half-width b = {b} must satisfy 0 <= b < a = {a} (the contact "
                         "half-width)")
    return math.asin(b / a)


def rounded_punch_load(a: float, b: float, R: float, E_star: float) -> float:
    """Normal force per unit length that presses a flat punch with rounded edges (flat over ``|x| <= b``, edges of
    radius R beyond, their profile ``(|x| - b)^2 / (2R)``) into a half-plane over ``|x| < a`` (frictionless;
    Ciavarella, Hills & Monno 1998): ``P = (E* a^2 / (4R)) (pi - 2 phi0 - sin 2 phi0)``, ``sin phi0 = b/a``.
    b = 0 is Hertz's cylinder (:func:`hertz_line_contact`)."""
    phi0 = _punch_angle(a, b)
    return E_star * a * a / (4.0 * R) * (math.pi - 2.0 * phi0 - math.sin(2.0 * phi0))


def rounded_punch_half_width(P: float, b: float, R: float, E_star: float) -> float:
    """Contact half-width a > b of the rounded punch under ``P > 0``: the root of :func:`rounded_punch_load`
    ``= P`` (increasing in a from 0 at a = b), found by bisection to 1e-14 relative."""
    if not (P > 0 and b >= 0 and R > 0 and E_star > 0):
        raise ValueError(f"rounded_punch_half_width: P = {P} > 0, b = {b} >= 0, R = {R} > 0, E_star = {E_star} > 0 "
                         "needed")
    lower, upper = b, max(2.0 * b, hertz_line_contact(P, R, E_star)[0])   # Hertz's a (b = 0) is an upper bound
    while rounded_punch_load(upper, b, R, E_star) < P:
        upper *= 2.0
    while upper - lower > 1e-14 * upper:
        middle = 0.5 * (lower + upper)
        lower, upper = (middle, upper) if rounded_punch_load(middle, b, R, E_star) < P else (lower, middle)
    return 0.5 * (lower + upper)


def rounded_punch_pressure(x: np.ndarray, P: float, b: float, R: float, E_star: float) -> np.ndarray:
    """Pressure under the rounded punch of :func:`rounded_punch_load` (Ciavarella, Hills & Monno 1998), the
    half-plane inversion of the gap's slope ``h'(t) = sign(t) max(|t| - b, 0) / R`` bounded at both ends, integrated
    in closed form; with ``x = a sin phi``, ``b = a sin phi0``::

        p = (E* a / (2 pi R)) [(pi - 2 phi0) cos phi
                               + (sin phi - sin phi0) ln|cos((phi + phi0)/2) / sin((phi - phi0)/2)|
                               - (sin phi + sin phi0) ln|cos((phi - phi0)/2) / sin((phi + phi0)/2)|],

    zero outside ``|x| < a``; finite at ``x = +-b`` (the logarithms' poles are multiplied by zero there: the limit is
    taken). b = 0 gives Hertz's pressure (:func:`hertz_pressure`)."""
    a = rounded_punch_half_width(P, b, R, E_star)
    phi0 = _punch_angle(a, b)
    x = np.asarray(x, dtype=float)
    inside = np.abs(x) < a
    phi = np.arcsin(np.where(inside, x / a, 0.0))

    def weighted_log(weight, numerator, denominator):
        """weight * ln|numerator / denominator|, 0 where weight is 0 (the pole at |x| = b)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            value = weight * np.log(np.abs(numerator / denominator))
        return np.where(weight == 0.0, 0.0, value)

    bracket = ((math.pi - 2.0 * phi0) * np.cos(phi)
               + weighted_log(np.sin(phi) - math.sin(phi0), np.cos((phi + phi0) / 2), np.sin((phi - phi0) / 2))
               - weighted_log(np.sin(phi) + math.sin(phi0), np.cos((phi - phi0) / 2), np.sin((phi + phi0) / 2)))
    return np.where(inside, E_star * a / (2.0 * math.pi * R) * bracket, 0.0)


# Sphere (3D) ------------------------------------------------------------------------------------------------
def mindlin_shear_modulus(E1: float, nu1: float, E2: float | None = None, nu2: float | None = None) -> float:
    """Tangential contact modulus G* of Johnson's §7.2, 1/G* = (2 - nu1)/G1 + (2 - nu2)/G2 with G = E/(2(1 + nu));
    a rigid second body if E2 is None (then Dundurs' beta is not 0: the sphere's forms below only approximate the
    stick zone and the energy). The convention: the initial tangential stiffness of a circular contact of
    radius a is dQ/d delta = 8 a G* (the slope of :func:`mindlin_tangential_displacement` at Q = 0)."""
    inv = (2.0 - nu1) * 2.0 * (1.0 + nu1) / E1
    if E2 is not None:
        nu2 = nu1 if nu2 is None else nu2
        inv += (2.0 - nu2) * 2.0 * (1.0 + nu2) / E2
    return 1.0 / inv


def _load_ratio(Q: float, mu: float, P: float) -> float:
    if not 0 <= abs(Q) < mu * P:
        raise ValueError(f"|Q| = {abs(Q)} must be below mu*P = {mu * P}")
    return abs(Q) / (mu * P)


def cattaneo_mindlin_stick_radius(a: float, Q: float, mu: float, P: float) -> float:
    """Stick radius c = a (1 - Q/(mu P))^(1/3) of a sphere under a tangential force ``|Q| < mu P`` growing from 0 at
    constant P (Johnson §7.2)."""
    return float(a * (1.0 - _load_ratio(Q, mu, P)) ** (1.0 / 3.0))


def cattaneo_mindlin_sphere_traction(r: np.ndarray, Q: float, mu: float, P: float, R: float,
                                     E_star: float) -> np.ndarray:
    """The tangential traction (along Q, magnitude) of a sphere under a tangential force ``|Q| < mu P`` growing from
    0 at constant P (Johnson eqs 7.38-7.40, Mindlin's approximation): ``mu p0 sqrt(1 - r^2/a^2)`` in the slip
    annulus ``c <= r < a``, less ``mu p0 (c/a) sqrt(1 - r^2/c^2)`` inside the stick radius c
    (:func:`cattaneo_mindlin_stick_radius`); a and p0 of :func:`hertz_sphere`. Its integral over the contact is
    ``mu P (1 - (c/a)^3) = |Q|``."""
    a, p0 = hertz_sphere(P, R, E_star)
    c = cattaneo_mindlin_stick_radius(a, Q, mu, P)
    r = np.asarray(r, dtype=float)
    stick = np.sqrt(np.clip(1.0 - (r / c) ** 2, 0.0, None)) if c > 0 else np.zeros_like(r)
    return mu * (hertz_sphere_pressure(r, P, R, E_star) - p0 * (c / a) * stick)


def mindlin_tangential_displacement(Q: float, mu: float, P: float, a: float, G_star: float) -> float:
    """Tangential displacement of one sphere relative to the other under Q growing from 0 at constant P (Johnson
    eq. 7.42): delta = (3 mu P / (16 a G*)) [1 - (1 - Q/(mu P))^(2/3)], G* of :func:`mindlin_shear_modulus`."""
    return float(np.sign(Q) * 3.0 * mu * P / (16.0 * a * G_star) * (1.0 - (1.0 - _load_ratio(Q, mu, P)) ** (2.0 / 3.0)))


def mindlin_deresiewicz_energy(Q_amplitude: float, mu: float, P: float, a: float, G_star: float) -> float:
    """Frictional energy dissipated in one steady cycle of a tangential force oscillating between -Q* and +Q*
    (``|Q*| < mu P``) at constant P (Mindlin & Deresiewicz 1953; Johnson eq. 7.60):

        W = (9 mu^2 P^2 / (10 a G*)) [1 - (1 - phi)^(5/3) - (5 phi / 6) (1 + (1 - phi)^(2/3))],  phi = Q*/(mu P),

    with G* of :func:`mindlin_shear_modulus`. It is the area of the loop that Masing's rule makes of
    :func:`mindlin_tangential_displacement` (each unloading branch is the loading curve of twice the force change,
    doubled): W = 4 Q* delta(Q*) - 8 int_0^Q* delta(Q) dQ. Small phi (its series): W = Q*^3 / (36 a G* mu P).
    """
    phi = _load_ratio(Q_amplitude, mu, P)
    rest = 1.0 - phi
    return float(9.0 * mu**2 * P**2 / (10.0 * a * G_star)
                 * (1.0 - rest ** (5.0 / 3.0) - 5.0 * phi / 6.0 * (1.0 + rest ** (2.0 / 3.0))))


#: gamma of :func:`worn_sphere_volume`: the mean surface displacement of a uniform pressure p on a circle of radius
#: c, 16 p c / (3 pi E*), less its value at the edge, 4 p c / (pi E*) (Johnson eq. 3.32), in units of p c / E*.
_UNIFORM_DISC_SAG = 16.0 / (3.0 * math.pi) - 4.0 / math.pi


def worn_sphere_volume(c: float, P: float, R: float, E_star: float) -> float:
    """The worn volume (mm^3) at which a sphere worn flat in gross slip touches a flat over a radius ``c``.

    The model: in gross slip every contact point slides the same distance, so Archard's wear is fastest where the
    pressure is highest until the pressure is uniform, ``p = P / (pi c^2)``: the worn contact carries a uniform
    pressure. The gap closes inside c: the wear depth there is the initial gap r^2/(2R) and the surfaces'
    elastic approach under that pressure measured from the edge (Johnson eq. 3.32: the displacement of a uniform
    pressure is ``(4 p c / (pi E*)) E(r/c)``, 2 p c / E* at the centre, 4 p c / (pi E*) at the edge, its mean over
    the disc 16 p c / (3 pi E*)), so the worn volume is

        V(c) = pi c^4 / (4 R) - (4 / (3 pi)) P c / E*

    (the rigid cap's pi c^4 / (4 R), less the elastic sag of the loaded disc below its edge). Measured on the
    ``sphere-flat`` scene (R = 10 mm, P = 100 N, E* = 115 GPa, a/4 cubes): after 4768 cycles its worn volume
    3.397e-4 mm^3 gives c = 0.2735 mm here and 0.2748 mm on the mesh (the equivalent radius of the loaded area).

    Args:
        c: Contact radius of the worn sphere (mm).
        P: Normal force (N).
        R: Sphere radius (mm).
        E_star: Contact modulus (MPa), as in :func:`hertz_sphere`.
    """
    return math.pi * c**4 / (4.0 * R) - _UNIFORM_DISC_SAG * P * c / E_star


def worn_sphere_contact_radius(volume: float, P: float, R: float, E_star: float) -> float:
    """The contact radius (mm) of a sphere on a flat after wearing ``volume`` (mm^3) in gross slip: the root of
    :func:`worn_sphere_volume` ``= volume``, and at least Hertz's radius a (:func:`hertz_sphere`, the unworn
    contact; the uniform-pressure model gives more than a once ``volume > 0.219 a^4 / R``).

    ``V(c)`` falls from 0 to a minimum at ``c^3 = gamma P R / (pi E*)`` and then grows without bound: the root
    beyond the minimum is unique, found by bisection to 1e-12 relative.

    Args:
        volume: Worn volume, both bodies' (mm^3, >= 0).
        P: Normal force (N, > 0).
        R: Sphere radius (mm, > 0).
        E_star: Contact modulus (MPa, > 0).
    """
    if not (volume >= 0 and P > 0 and R > 0 and E_star > 0):
        raise ValueError(f"worn_sphere_contact_radius: volume = {volume} >= 0, P = {P}, R = {R}, "
                         f"E_star = {E_star} > 0 needed")
    lower = (_UNIFORM_DISC_SAG * P * R / (math.pi * E_star)) ** (1.0 / 3.0)  # the minimum of V(c)
    upper = 2.0 * lower
    while worn_sphere_volume(upper, P, R, E_star) < volume:
        upper *= 2.0
    while upper - lower > 1e-12 * upper:
        middle = 0.5 * (lower + upper)
        lower, upper = (middle, upper) if worn_sphere_volume(middle, P, R, E_star) < volume else (lower, middle)
    return max(hertz_sphere(P, R, E_star)[0], 0.5 * (lower + upper))
