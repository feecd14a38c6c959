"""Closed-form references used by the tests and the reports (line contact, plane strain).

Sources: K. L. Johnson, *Contact Mechanics* (CUP, 1985), sections 4.2 (Hertz line contact) and 7.2
(Cattaneo-Mindlin partial slip of a cylinder).
"""

from __future__ import annotations

import numpy as np

__all__ = ["plane_strain_modulus", "hertz_line_contact", "hertz_pressure", "cattaneo_mindlin_stick_half_width"]


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
    return float(a), float(2.0 * P / (np.pi * a))


def hertz_pressure(x: np.ndarray, P: float, R: float, E_star: float, x0: float = 0.0) -> np.ndarray:
    """Hertz pressure p(x) = p0 sqrt(1 - ((x - x0)/a)^2) inside |x - x0| < a, zero outside."""
    a, p0 = hertz_line_contact(P, R, E_star)
    s = 1.0 - ((np.asarray(x) - x0) / a) ** 2
    return p0 * np.sqrt(np.clip(s, 0.0, None))


def cattaneo_mindlin_stick_half_width(a: float, Q: float, mu: float, P: float) -> float:
    """Stick-zone half-width c = a sqrt(1 - Q/(mu P)) for a tangential force Q < mu P (Johnson eq. 7.30)."""
    if not 0 <= Q < mu * P:
        raise ValueError(f"Q = {Q} must satisfy 0 <= Q < mu*P = {mu * P}")
    return float(a * np.sqrt(1.0 - Q / (mu * P)))
