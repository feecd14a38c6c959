"""Material laws: isotropic linear elasticity and small-strain J2 plasticity (pure NumPy/numba, no mesh).

Tensor convention (fixed, other modules code against it): symmetric second-order tensors are 6-component
**Mandel** vectors ``[xx, yy, zz, sqrt(2) yz, sqrt(2) xz, sqrt(2) xy]``, so the dot product of two vectors is
the full contraction ``a : b`` and fourth-order tensors with minor symmetries are ordinary symmetric 6x6
matrices (``sigma = C @ eps``). Plane strain uses the same six components with ``eps_zz = eps_yz = eps_xz = 0``
imposed by the caller; ``sigma_zz`` then comes out of the constitutive update.

J2 plasticity (von Mises, associative, linear isotropic hardening)::

    f(sigma, p) = q(sigma) - (sigma_y0 + H p),      q = sqrt(3/2) |dev sigma|,

with ``p`` the cumulative (equivalent) plastic strain, ``dp = sqrt(2/3) |d eps_p|``, and ``H`` the
*plastic* modulus. The update is the classical radial return (de Souza Neto, Peric & Owen, *Computational
Methods for Plasticity*, 2008, Box 7.4 and eq. 7.120 for the consistent tangent).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

__all__ = [
    "LinearElastic",
    "J2Plasticity",
    "elastic_stiffness",
    "plastic_modulus_from_tangent",
    "radial_return_kernel",
    "return_mapping",
    "von_mises",
]


@dataclass(frozen=True)
class LinearElastic:
    """Isotropic linear elasticity (MPa). In 2D the formulation is plane strain.

    Args:
        E: Young's modulus (MPa), > 0.
        nu: Poisson's ratio, -1 < nu < 0.5.
    """

    E: float
    nu: float

    def __post_init__(self) -> None:
        if not self.E > 0:
            raise ValueError(f"material.E = {self.E} must be > 0 MPa")
        if not -1.0 < self.nu < 0.5:
            raise ValueError(f"material.nu = {self.nu} must satisfy -1 < nu < 0.5")

    @property
    def lame(self) -> tuple[float, float]:
        """(lambda, mu) of the 3D law; with eps_zz = 0 it is also the plane-strain law."""
        lmbda = self.E * self.nu / ((1 + self.nu) * (1 - 2 * self.nu))
        return lmbda, self.E / (2 * (1 + self.nu))

    @property
    def plane_strain_modulus(self) -> float:
        """The contact modulus E* = E / (1 - nu^2) against a rigid flat."""
        return self.E / (1 - self.nu**2)


# ---------------------------------------------------------------------------------------------------------
# J2 plasticity
# ---------------------------------------------------------------------------------------------------------

#: Relative tolerance of the elastic check: f_trial <= _YIELD_RTOL * sigma_y(p_old) is elastic.
_YIELD_RTOL = 1e-12


@dataclass(frozen=True)
class J2Plasticity:
    """Small-strain von Mises plasticity with linear isotropic hardening (MPa).

    Yield stress ``sigma_y(p) = sigma_y0 + H p``. ``H`` is the plastic modulus (slope of stress against
    *plastic* strain in a uniaxial test), not the tangent modulus ``E_t`` of the stress-strain curve; convert
    with :func:`plastic_modulus_from_tangent`. ``H = 0`` is perfect plasticity.

    Args:
        E: Young's modulus (MPa), > 0.
        nu: Poisson's ratio, -1 < nu < 0.5.
        sigma_y0: Initial yield stress (MPa), > 0.
        H: Linear isotropic hardening (plastic) modulus (MPa), 0 <= H < inf.

    Raises:
        ValueError: A parameter is out of its range (the message names the field and the range).
    """

    E: float
    nu: float
    sigma_y0: float
    H: float

    def __post_init__(self) -> None:
        if not (self.E > 0 and math.isfinite(self.E)):
            raise ValueError(f"material.E = {self.E} must be finite and > 0 MPa")
        if not -1.0 < self.nu < 0.5:
            raise ValueError(f"material.nu = {self.nu} must satisfy -1 < nu < 0.5")
        if not self.sigma_y0 > 0:  # +inf is allowed: a law that never yields
            raise ValueError(f"material.sigma_y0 = {self.sigma_y0} must be > 0 MPa")
        if not (self.H >= 0 and math.isfinite(self.H)):
            raise ValueError(f"material.H = {self.H} must satisfy 0 <= H < inf MPa")

    @property
    def lame(self) -> tuple[float, float]:
        """(lambda, mu) of the elastic part; mu is the shear modulus G."""
        return LinearElastic(self.E, self.nu).lame

    @property
    def bulk(self) -> float:
        """Bulk modulus K = E / (3 (1 - 2 nu))."""
        return self.E / (3.0 * (1.0 - 2.0 * self.nu))

    @property
    def elastic(self) -> LinearElastic:
        """The elastic part as a :class:`LinearElastic`."""
        return LinearElastic(self.E, self.nu)

    def update(self, strain: np.ndarray, eps_p: np.ndarray, p: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The constitutive update of :class:`dolfinx_fretting.settings.Plasticity`: the radial return with
        its consistent tangent (:func:`return_mapping`); returns ``(stress, eps_p, p, tangent, yielded)``."""
        return return_mapping(self, strain, eps_p, p, tangent=True)


def plastic_modulus_from_tangent(E: float, E_t: float) -> float:
    """Plastic modulus H of linear isotropic hardening from the tangent modulus E_t of a uniaxial curve.

    In a uniaxial stress test past yield ``d eps = d sigma / E + d sigma / H``, so the slope of the bilinear
    stress-strain curve is ``E_t = E H / (E + H)``; inverting, ``H = E E_t / (E - E_t)``.

    Args:
        E: Young's modulus (MPa), > 0.
        E_t: Tangent (elasto-plastic) modulus of the uniaxial stress-strain curve (MPa), 0 <= E_t < E.

    Returns:
        H (MPa), >= 0 (0 for E_t = 0: perfect plasticity).

    Raises:
        ValueError: E <= 0 or E_t outside [0, E).
    """
    if not (E > 0 and math.isfinite(E)):
        raise ValueError(f"E = {E} must be finite and > 0 MPa")
    if not 0 <= E_t < E:
        raise ValueError(f"tangent modulus E_t = {E_t} must satisfy 0 <= E_t < E = {E} MPa")
    return E * E_t / (E - E_t)


def elastic_stiffness(E: float, nu: float) -> np.ndarray:
    """Isotropic elasticity tensor as a 6x6 Mandel matrix: ``K 1(x)1 + 2G I_dev``.

    Args:
        E: Young's modulus (MPa).
        nu: Poisson's ratio.

    Returns:
        (6, 6) symmetric array; ``sigma = C @ eps`` for Mandel vectors.
    """
    K = E / (3.0 * (1.0 - 2.0 * nu))
    G = E / (2.0 * (1.0 + nu))
    m = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
    return K * np.outer(m, m) + 2.0 * G * (np.eye(6) - np.outer(m, m) / 3.0)


def von_mises(sigma: np.ndarray) -> np.ndarray:
    """Von Mises equivalent stress ``q = sqrt(3/2) |dev sigma|`` of Mandel stress vectors.

    Args:
        sigma: (..., 6) Mandel stresses.

    Returns:
        (...) array of q.
    """
    sigma = np.asarray(sigma, dtype=float)
    if sigma.shape[-1] != 6:
        raise ValueError(f"von_mises expects Mandel vectors (..., 6), got shape {sigma.shape}")
    s = sigma.copy()
    s[..., :3] -= sigma[..., :3].mean(axis=-1, keepdims=True)
    return np.sqrt(1.5 * np.einsum("...i,...i->...", s, s))


@numba.njit(cache=True)
def _radial_return(E, nu, sy0, H, eps, eps_p_old, p_old, sigma, eps_p, p, C, yielded, want_tangent):
    """Radial return over n integration points, written into preallocated outputs (numba kernel).

    Args:
        E, nu, sy0, H: Material parameters (floats), see :class:`J2Plasticity`.
        eps: (n, 6) total strains (Mandel).
        eps_p_old: (n, 6) committed plastic strains.
        p_old: (n,) committed cumulative plastic strains.
        sigma: (n, 6) output stresses.
        eps_p: (n, 6) output plastic strains.
        p: (n,) output cumulative plastic strains.
        C: (n, 6, 6) output consistent tangents; ignored (may be (0, 6, 6)) if not want_tangent.
        yielded: (n,) bool output, True where the step was plastic.
        want_tangent: 0 (False): no tangent; 1 (True): C is the consistent tangent; 2: C is the consistent
            tangent minus the elastic stiffness, computed directly (exactly 0 at an elastic point, and no
            cancellation where a point yields: what a low-rank update of the elastic stiffness needs).

    Each point reads all of its inputs before writing, so ``eps_p`` may be ``eps_p_old`` and ``p`` may be
    ``p_old`` (an in-place commit) without changing the result.
    """
    n = eps.shape[0]
    G = E / (2.0 * (1.0 + nu))
    K = E / (3.0 * (1.0 - 2.0 * nu))
    ee = np.empty(6)
    s = np.empty(6)
    epo = np.empty(6)
    for i in range(n):
        for k in range(6):
            epo[k] = eps_p_old[i, k]
            ee[k] = eps[i, k] - epo[k]
        pi = p_old[i]
        tr = ee[0] + ee[1] + ee[2]
        mean = K * tr  # hydrostatic stress, always elastic
        # Trial deviatoric stress s = 2G dev(eps_e).
        for k in range(6):
            s[k] = 2.0 * G * ee[k]
        for k in range(3):
            s[k] -= 2.0 * G * tr / 3.0
        snorm = 0.0
        for k in range(6):
            snorm += s[k] * s[k]
        snorm = math.sqrt(snorm)
        q_tr = math.sqrt(1.5) * snorm
        sy = sy0 + H * pi
        f_tr = q_tr - sy
        if f_tr <= _YIELD_RTOL * sy:
            yielded[i] = False
            for k in range(6):
                sigma[i, k] = s[k]
                eps_p[i, k] = epo[k]
            for k in range(3):
                sigma[i, k] += mean
            p[i] = pi
            if want_tangent:
                for a in range(6):
                    for b in range(6):
                        C[i, a, b] = 0.0
                if want_tangent != 2:
                    for a in range(6):
                        C[i, a, a] = 2.0 * G
                    for a in range(3):
                        for b in range(3):
                            C[i, a, b] += K - 2.0 * G / 3.0
        else:
            yielded[i] = True
            dp = f_tr / (3.0 * G + H)
            scale = 1.0 - 3.0 * G * dp / q_tr
            fac = 1.5 * dp / q_tr
            for k in range(6):
                sigma[i, k] = scale * s[k]
                eps_p[i, k] = epo[k] + fac * s[k]
            for k in range(3):
                sigma[i, k] += mean
            p[i] = pi + dp
            if want_tangent:
                # de Souza Neto et al. eq. 7.120:
                # C = K 1(x)1 + 2G scale I_dev + 6G^2 (dp/q_tr - 1/(3G+H)) n(x)n,  n = s_tr/|s_tr|;
                # minus C_e = K 1(x)1 + 2G I_dev: 2G (scale - 1) I_dev + the same n(x)n term.
                g2 = 2.0 * G * (scale - 1.0) if want_tangent == 2 else 2.0 * G * scale
                bulk = 0.0 if want_tangent == 2 else K
                cn = 6.0 * G * G * (dp / q_tr - 1.0 / (3.0 * G + H)) / (snorm * snorm)
                for a in range(6):
                    for b in range(6):
                        C[i, a, b] = cn * s[a] * s[b]
                    C[i, a, a] += g2
                for a in range(3):
                    for b in range(3):
                        C[i, a, b] += bulk - g2 / 3.0


#: Public name of the numba kernel ``_radial_return``, for callers that preallocate outputs.
radial_return_kernel = _radial_return


def _as_points(a: np.ndarray, name: str, shape: tuple[int, ...]) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=np.float64)
    if a.shape != shape:
        raise ValueError(f"{name} has shape {a.shape}, expected {shape}")
    return a


def return_mapping(
    law: J2Plasticity,
    eps: np.ndarray,
    eps_p_old: np.ndarray,
    p_old: np.ndarray,
    tangent: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]:
    """J2 radial return (backward Euler, exact for linear hardening) at n integration points.

    Elastic predictor ``sigma_tr = C_e : (eps - eps_p_old)``; if ``f_tr <= 1e-12 sigma_y(p_old)`` the step is
    elastic, otherwise ``dp = f_tr / (3G + H)``, ``s = (1 - 3G dp / q_tr) s_tr``,
    ``eps_p = eps_p_old + (3/2) dp s_tr / q_tr``, ``p = p_old + dp``. The inputs are not modified: the caller
    commits ``eps_p`` and ``p`` once the global increment has converged.

    Args:
        law: Material parameters.
        eps: (n, 6) total strains (Mandel: ``[xx, yy, zz, sqrt2 yz, sqrt2 xz, sqrt2 xy]``).
        eps_p_old: (n, 6) plastic strains at the start of the increment.
        p_old: (n,) cumulative plastic strains at the start of the increment.
        tangent: Whether to compute the consistent tangent.

    Returns:
        ``(sigma, eps_p, p, C, yielded)``: stresses (n, 6), plastic strains (n, 6), cumulative plastic
        strains (n,), consistent tangents (n, 6, 6) in Mandel form (``None`` if ``tangent`` is False) and a
        (n,) bool mask of the points that yielded in this step.

    Raises:
        ValueError: Inconsistent shapes.
    """
    eps = np.asarray(eps, dtype=np.float64)
    if eps.ndim != 2 or eps.shape[1] != 6:
        raise ValueError(f"eps has shape {eps.shape}, expected (n, 6) Mandel vectors")
    n = eps.shape[0]
    eps = np.ascontiguousarray(eps)
    eps_p_old = _as_points(eps_p_old, "eps_p_old", (n, 6))
    p_old = _as_points(p_old, "p_old", (n,))
    sigma = np.empty((n, 6))
    eps_p = np.empty((n, 6))
    p = np.empty(n)
    C = np.empty((n if tangent else 0, 6, 6))
    yielded = np.empty(n, dtype=np.bool_)
    _radial_return(float(law.E), float(law.nu), float(law.sigma_y0), float(law.H), eps, eps_p_old, p_old,
                   sigma, eps_p, p, C, yielded, int(bool(tangent)))
    return sigma, eps_p, p, (C if tangent else None), yielded
