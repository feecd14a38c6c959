"""Closed forms of the fretting-fatigue rig (a cylinder on a half-plane of the same material, partial slip under a
tangential force Q and a bulk stress sigma_B), the independent references of ``tests/test_pad_specimen.py``.

Sources: Hills & Nowell, *Mechanics of Fretting Fatigue* (Kluwer, 1994), ch. 2 and 4; Johnson, *Contact
Mechanics* (1985), sections 2.6 and 7.2; McEwen, Phil. Mag. 40 (1949) 454 (the stress field of a Hertzian
line load with sliding traction in closed form, written here after Hills & Nowell's eqs. 2.43-2.44).

Frame: x along the surface, z the depth into the body (z >= 0), the shear traction on the body pointing along +x.
Then the trailing edge (where the surface's tension peaks) is x = -a and the stick zone moves towards +x, the
leading edge, under a bulk tension.
"""

from __future__ import annotations

import numpy as np


def stick_zone(a: float, p0: float, P: float, Q: float, mu: float, sigma_bulk: float) -> tuple[float, float]:
    """Half-width c and offset e of the stick zone (Hills & Nowell, ch. 4): ``c = a sqrt(1 - |Q| / (mu P))``,
    ``e = sigma_B a / (4 mu p0)`` towards the leading edge; valid while ``|e| + c <= a``.

    Derivation (identical bodies, no normal-tangential coupling): in the stick zone the two surfaces strain alike,
    (4 / (pi E*')) ... the Hilbert transform of q equals sigma_B / 4, and q = mu p0 [sqrt(1 - x^2/a^2) - (c/a)
    sqrt(1 - (x - e)^2 / c^2)] gives mu p0 e / a = sigma_B / 4.
    """
    c = a * np.sqrt(1.0 - abs(Q) / (mu * P))
    e = sigma_bulk * a / (4.0 * mu * p0)
    if abs(e) + c > a:
        raise ValueError(f"|e| + c = {abs(e) + c:g} > a = {a:g}: one slip zone reverses (outside the closed form)")
    return float(c), float(e)


def _m_n(x: np.ndarray, z: np.ndarray, a: float) -> tuple[np.ndarray, np.ndarray]:
    """McEwen's m (>= 0) and n (the sign of x) of a semi-elliptical load of half-width a centred at x = 0."""
    s = a * a - x * x + z * z
    root = np.sqrt(s * s + 4.0 * x * x * z * z)
    m = np.sqrt(np.maximum(0.5 * (root + s), 0.0))
    n = np.sign(x) * np.sqrt(np.maximum(0.5 * (root - s), 0.0))
    return m, n


def sigma_xx_elliptical(x: np.ndarray, z: np.ndarray, a: float, p0: float, q0: float) -> np.ndarray:
    """sigma_xx under a pressure p0 sqrt(1 - x^2/a^2) and a shear q0 sqrt(1 - x^2/a^2) along +x (McEwen)."""
    x, z = np.asarray(x, float), np.asarray(z, float)
    m, n = _m_n(x, z, a)
    r2 = m * m + n * n
    edge = r2 == 0.0  # the load's edges on the surface, where m = n = 0: the ratios are multiplied by 0 there
    safe = np.where(edge, 1.0, r2)
    normal = -(p0 / a) * (m * (1.0 + np.where(edge, 0.0, (z * z + n * n) / safe)) - 2.0 * z)
    shear = (q0 / a) * (n * (2.0 - np.where(edge, 0.0, (z * z - m * m) / safe)) - 2.0 * x)
    return normal + shear


def sigma_xx_rig(x: np.ndarray, z: np.ndarray, a: float, p0: float, mu: float, c: float, e: float,
                 sigma_bulk: float) -> np.ndarray:
    """sigma_xx of the rig in partial slip (Hills & Nowell's superposition): Hertz pressure, full sliding shear
    mu p, minus the stick zone's corrective shear (half-width c, centred at e), plus the bulk stress."""
    x, z = np.asarray(x, float), np.asarray(z, float)
    full = sigma_xx_elliptical(x, z, a, p0, mu * p0)
    corrective = sigma_xx_elliptical(x - e, z, c, 0.0, mu * p0 * c / a)
    return full - corrective + sigma_bulk


def trailing_edge_stress(a: float, p0: float, mu: float, c: float, e: float, sigma_bulk: float) -> float:
    """The surface sigma_xx at the trailing edge x = -a: ``2 mu p0 [sqrt((a + e)^2 - c^2) - e] / a + sigma_B``;
    without offset (e = 0) Hills & Nowell's ``2 mu p0 sqrt(Q / (mu P)) + sigma_B``."""
    return float(2.0 * mu * p0 * (np.sqrt((a + e) ** 2 - c * c) - e) / a + sigma_bulk)
