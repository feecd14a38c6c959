"""Fatigue parameters over a load cycle: critical planes, Ruiz's parameter, life (pure NumPy, no mesh).

The input is a stress and strain *history at points*: arrays shaped ``(n_times, n_points, 3, 3)``, symmetric
tensors in the global frame (MPa and mm/mm; :func:`mandel_to_tensor` converts the package's Mandel vectors). In
2D (plane strain) give the full 3 x 3 tensors: ``sigma_zz`` belongs to the stress, ``eps_zz = 0``. Tension is
positive.

The critical-plane search samples plane normals: in 2D the normals of the x-y plane, ``n(theta) = (cos theta,
sin theta, 0)`` with ``theta`` from -90 degrees (included) to 90 degrees (excluded) at ``angle_step`` degrees; in 3D
the half sphere of normals ``n = (sin phi cos theta, sin phi sin theta, cos phi)``, ``phi`` from 0 to 90 degrees,
``theta`` from -180 to 180 degrees, at about ``angle_step`` degrees apart (a ring of ``phi`` has the
``theta`` count that keeps the spacing along it). On each plane:

* Smith–Watson–Topper: ``SWT = sigma_n,max * delta eps_n / 2``, ``sigma_n = n.sigma.n`` its largest value over the
  cycle and ``delta eps_n`` the range (max - min) of ``eps_n = n.eps.n`` (MPa);
* Fatemi–Socie: ``FS = delta gamma / 2 * (1 + k sigma_n,max / sigma_y)``, ``delta gamma`` the range of the
  engineering shear strain ``gamma = 2 n.eps.d`` along the shear direction ``d`` of the plane where it is largest:
  the diameter of the path of the shear-strain vector on the plane (exact, no sampling of ``d``);

the critical plane maximises each parameter (its normal's angle is reported; ties go to the first sampled).
The value at the sampled maximum is below the true maximum by a relative error of order ``c (h/2)^2``, ``h`` the
step in radians and ``c`` the parameter's curvature in the angle: uniaxial SWT has ``c = 2 + nu``, so a 1 degree
step is within 2e-4 of it (docs/api.md).

Ruiz's fretting parameter (:func:`ruiz_parameter`) is ``kappa = (sigma_xx)_max * (tau delta)_max`` at surface
points; life to crack initiation inverts the strain-life curves of :class:`BasquinCoffinManson` (SWT) and
:class:`ShearStrainLife` (FS) by bisection in log(2N) (monotone: b, c < 0); :func:`critical_distance` applies
Taylor's point or line method to a parameter sampled along lines into the body.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["POINT_COLUMNS", "SUMMARY_FIELDS", "DEFAULT_ANGLE_STEP", "BasquinCoffinManson", "ShearStrainLife",
           "FatemiSocie", "PlaneSet", "CriticalPlanes", "mandel_to_tensor", "plane_normals", "critical_planes",
           "ruiz_parameter", "critical_distance", "CriticalDistance", "depth_profile", "CRITICAL_DISTANCE_FIELDS",
           "MinerSum", "MINER_FIELDS"]

#: Per-point columns of a fatigue evaluation (one declaration: the result object and any table writer read it).
#: ``x`` the point's x coordinate, ``depth`` below the contact surface, ``sigma_xx`` its largest value over the
#: cycle, ``swt``/``fs`` the critical-plane values and their normals' angles (degrees), ``life`` cycles to crack
#: initiation (inf where no constants are given or the parameter is not positive).
POINT_COLUMNS = ("x", "depth", "sigma_xx", "swt", "swt_angle", "fs", "fs_angle", "life")
#: Summary numbers of a fatigue evaluation (the largest SWT, where and on which plane; the largest FS; the
#: largest Ruiz parameter and where; the shortest life).
SUMMARY_FIELDS = ("swt_max", "swt_x", "swt_depth", "swt_angle", "fs_max", "ruiz_max", "ruiz_x", "life_min")
#: Summary numbers added with a critical distance: SWT by the point or line method below the SWT hot spot, and
#: the life it gives (None without strain-life constants).
CRITICAL_DISTANCE_FIELDS = ("swt_critical", "life_critical")
#: Summary numbers of Miner's sum over a run (:class:`MinerSum`): the largest damage, the (equivalent) cycle at
#: which the first point's damage reached 1 (None: not within the run) and that point's x and depth.
MINER_FIELDS = ("miner_damage_max", "initiation_cycles", "initiation_x", "initiation_depth")
#: The default step (degrees) of the plane search: 1 in 2D (180 planes); 5 in 3D (about 800 planes).
DEFAULT_ANGLE_STEP = {2: 1.0, 3: 5.0}

_SQ2 = math.sqrt(2.0)
#: Bisection steps in log10(2N) over at most [0, 400]: 400 / 2^64 ~ 2e-17, below rounding.
_BISECTIONS = 64
#: log10(2N) beyond which a life is reported as infinite (2N = 1e300).
_LOG_REVERSALS_MAX = 300.0


def _positive(owner: str, name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{owner}: {name} = {value!r} must be finite and > 0")
    return value


def _negative(owner: str, name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value < 0):
        raise ValueError(f"{owner}: {name} = {value!r} must be finite and < 0 (a strain-life exponent)")
    return value


def _invert(curve, value: np.ndarray) -> np.ndarray:
    """Cycles N with ``curve(N) = value`` for a curve decreasing in N (vectorised bisection in log10(2N)).

    ``value`` above ``curve(1/2)`` (failure within the first reversal) gives N = 1/2; ``value <= 0`` or below
    ``curve`` at 2N = 1e300 gives inf.
    """
    value = np.asarray(value, dtype=float)
    low = np.zeros(value.shape)
    high = np.full(value.shape, _LOG_REVERSALS_MAX)
    for _ in range(_BISECTIONS):
        middle = 0.5 * (low + high)
        above = curve(0.5 * 10.0 ** middle) > value  # the curve at middle is still above: the root is further
        low = np.where(above, middle, low)
        high = np.where(above, high, middle)
    cycles = 0.5 * 10.0 ** (0.5 * (low + high))
    cycles = np.where(value >= curve(np.full(value.shape, 0.5)), 0.5, cycles)
    return np.where((value > 0) & (value > curve(np.full(value.shape, 0.5 * 10.0 ** _LOG_REVERSALS_MAX))),
                    cycles, np.inf)


@dataclass(frozen=True)
class BasquinCoffinManson:
    """Uniaxial strain-life constants: ``eps_a = sigma_f / E (2N)^b + eps_f (2N)^c`` (Basquin, Coffin–Manson).

    Args:
        sigma_f: Fatigue strength coefficient sigma'_f (MPa), > 0.
        b: Fatigue strength exponent, < 0.
        eps_f: Fatigue ductility coefficient eps'_f, > 0.
        c: Fatigue ductility exponent, < 0.
        E: Young's modulus (MPa), > 0.

    Raises:
        ValueError: a constant is not finite or out of its range (the message names it).
    """

    sigma_f: float
    b: float
    eps_f: float
    c: float
    E: float

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for name in ("sigma_f", "eps_f", "E"):
            object.__setattr__(self, name, _positive(owner, name, getattr(self, name)))
        for name in ("b", "c"):
            object.__setattr__(self, name, _negative(owner, name, getattr(self, name)))

    def swt(self, cycles) -> np.ndarray:
        """SWT = sigma'_f^2 / E (2N)^(2b) + sigma'_f eps'_f (2N)^(b+c) at ``cycles`` N (MPa)."""
        reversals = 2.0 * np.asarray(cycles, dtype=float)
        return (self.sigma_f ** 2 / self.E * reversals ** (2 * self.b)
                + self.sigma_f * self.eps_f * reversals ** (self.b + self.c))

    def life_swt(self, swt) -> np.ndarray:
        """Cycles N to crack initiation at ``swt`` (the inverse of :meth:`swt`; inf for swt <= 0)."""
        return _invert(self.swt, swt)


@dataclass(frozen=True)
class ShearStrainLife:
    """Shear strain-life constants of the Fatemi–Socie life: ``FS = tau_f / G (2N)^b0 + gamma_f (2N)^c0``.

    Args:
        tau_f: Shear fatigue strength coefficient tau'_f (MPa), > 0.
        b0: Shear fatigue strength exponent, < 0.
        gamma_f: Shear fatigue ductility coefficient gamma'_f, > 0.
        c0: Shear fatigue ductility exponent, < 0.
        G: Shear modulus (MPa), > 0.

    Raises:
        ValueError: a constant is not finite or out of its range (the message names it).
    """

    tau_f: float
    b0: float
    gamma_f: float
    c0: float
    G: float

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for name in ("tau_f", "gamma_f", "G"):
            object.__setattr__(self, name, _positive(owner, name, getattr(self, name)))
        for name in ("b0", "c0"):
            object.__setattr__(self, name, _negative(owner, name, getattr(self, name)))

    @classmethod
    def from_uniaxial(cls, constants: BasquinCoffinManson, nu: float) -> "ShearStrainLife":
        """The von Mises estimate from uniaxial constants (Socie & Marquis, *Multiaxial Fatigue*, 2000):
        tau'_f = sigma'_f / sqrt 3, gamma'_f = sqrt 3 eps'_f, b0 = b, c0 = c, G = E / (2 (1 + nu))."""
        if not -1.0 < float(nu) < 0.5:
            raise ValueError(f"ShearStrainLife.from_uniaxial: nu = {nu!r} must satisfy -1 < nu < 0.5")
        return cls(constants.sigma_f / math.sqrt(3.0), constants.b, math.sqrt(3.0) * constants.eps_f, constants.c,
                   constants.E / (2.0 * (1.0 + float(nu))))

    def fs(self, cycles) -> np.ndarray:
        """FS = tau'_f / G (2N)^b0 + gamma'_f (2N)^c0 at ``cycles`` N."""
        reversals = 2.0 * np.asarray(cycles, dtype=float)
        return self.tau_f / self.G * reversals ** self.b0 + self.gamma_f * reversals ** self.c0

    def life_fs(self, fs) -> np.ndarray:
        """Cycles N to crack initiation at ``fs`` (the inverse of :meth:`fs`; inf for fs <= 0)."""
        return _invert(self.fs, fs)


@dataclass(frozen=True)
class FatemiSocie:
    """The normal-stress sensitivity of the Fatemi–Socie parameter ``delta gamma / 2 (1 + k sigma_n,max / sigma_y)``.

    Args:
        k: Material constant, >= 0 (about 0.3 to 1 for metals; 0: the shear strain amplitude alone).
        sigma_y: Yield stress (MPa), > 0.

    Raises:
        ValueError: a constant is not finite or out of its range (the message names it).
    """

    k: float
    sigma_y: float

    def __post_init__(self) -> None:
        k = float(self.k)
        if not (math.isfinite(k) and k >= 0):
            raise ValueError(f"FatemiSocie: k = {self.k!r} must be finite and >= 0")
        object.__setattr__(self, "k", k)
        object.__setattr__(self, "sigma_y", _positive("FatemiSocie", "sigma_y", self.sigma_y))


def mandel_to_tensor(values) -> np.ndarray:
    """Symmetric 3 x 3 tensors from Mandel vectors ``[xx, yy, zz, sqrt2 yz, sqrt2 xz, sqrt2 xy]`` (the package's
    convention, :mod:`dolfinx_fretting.materials`): shape (..., 6) to (..., 3, 3)."""
    values = np.asarray(values, dtype=float)
    if values.shape[-1:] != (6,):
        raise ValueError(f"mandel_to_tensor: the last axis has {values.shape[-1:]} components; 6 expected")
    tensor = np.empty(values.shape[:-1] + (3, 3))
    for i in range(3):
        tensor[..., i, i] = values[..., i]
    for component, (i, j) in zip((3, 4, 5), ((1, 2), (0, 2), (0, 1))):
        tensor[..., i, j] = tensor[..., j, i] = values[..., component] / _SQ2
    return tensor


@dataclass(frozen=True)
class PlaneSet:
    """The sampled planes of a critical-plane search.

    Attributes:
        normals: (K, 3) unit normals.
        shear_directions: (K, 2, 3) an orthonormal basis of each plane (2D: the in-plane direction
            ``(-sin theta, cos theta, 0)``, then ``e_z``).
        theta: (K,) the normal's azimuth in the x-y plane (degrees, from the x axis, counter-clockwise).
        phi: (K,) the normal's angle from the z axis (degrees; 90 for every 2D plane).
        step: The angular step (degrees).
    """

    normals: np.ndarray
    shear_directions: np.ndarray
    theta: np.ndarray
    phi: np.ndarray
    step: float


def plane_normals(dim: int, angle_step: float | None = None) -> PlaneSet:
    """The planes of the search (module docstring): 2D, normals in the x-y plane; 3D, a half sphere.

    Args:
        dim: 2 or 3.
        angle_step: Degrees between neighbouring normals, 0 < step <= 45 (default :data:`DEFAULT_ANGLE_STEP`).
    """
    if dim not in (2, 3):
        raise ValueError(f"plane_normals: dim = {dim!r}: allowed 2, 3")
    step = DEFAULT_ANGLE_STEP[dim] if angle_step is None else float(angle_step)
    if not (math.isfinite(step) and 0 < step <= 45):
        raise ValueError(f"plane_normals: angle_step = {angle_step!r} degrees: allowed 0 < angle_step <= 45")
    if dim == 2:
        count = int(round(180.0 / step))
        theta = -90.0 + 180.0 * np.arange(count) / count
        phi = np.full(count, 90.0)
    else:
        rings = int(round(90.0 / step))
        theta_parts, phi_parts = [np.zeros(1)], [np.zeros(1)]  # the pole: one normal
        for ring in range(1, rings + 1):
            polar = 90.0 * ring / rings
            # Along the ring the spacing is step * sin(phi); the equator's ring needs only half the circle
            # (n and -n are one plane).
            span = 180.0 if ring == rings else 360.0
            count = max(1, int(round(span * math.sin(math.radians(polar)) / step)))
            theta_parts.append(-180.0 + span * np.arange(count) / count if span == 360.0
                               else -90.0 + 180.0 * np.arange(count) / count)
            phi_parts.append(np.full(count, polar))
        theta, phi = np.concatenate(theta_parts), np.concatenate(phi_parts)
    t, p = np.radians(theta), np.radians(phi)
    # (2D: sin and cos of 90 degrees written exactly, so that a plane-strain history has exactly no shear along
    # e_z and the Fatemi-Socie shear path is a line: its range, not the T^2 diameter search)
    sin_p, cos_p = (np.ones_like(p), np.zeros_like(p)) if dim == 2 else (np.sin(p), np.cos(p))
    normals = np.column_stack([sin_p * np.cos(t), sin_p * np.sin(t), cos_p])
    # The plane's basis: e_theta (horizontal), then n x e_theta (e_z in 2D); at the pole they are e_y and -e_x.
    first = np.column_stack([-np.sin(t), np.cos(t), np.zeros_like(t)])
    second = np.cross(normals, first)
    if dim == 2:
        second = np.tile([0.0, 0.0, 1.0], (t.size, 1))
    return PlaneSet(normals, np.stack([first, second], axis=1), theta, phi, step)


@dataclass(frozen=True)
class CriticalPlanes:
    """The critical planes of each point (:func:`critical_planes`).

    Attributes:
        swt: (P,) the largest Smith–Watson–Topper parameter over the planes (MPa).
        swt_theta, swt_phi: (P,) its plane normal's angles (degrees; :class:`PlaneSet`).
        swt_normal: (P, 3) its plane's normal.
        fs: (P,) the largest Fatemi–Socie parameter (NaN without :class:`FatemiSocie` constants).
        fs_theta, fs_phi, fs_normal: Its plane, likewise (NaN without constants).
        sigma_n_max: (P,) the largest normal stress over the cycle on the SWT plane (MPa).
        strain_amplitude: (P,) half the range of the normal strain on the SWT plane.
        shear_strain_range: (P,) the shear strain range on the FS plane (NaN without constants).
        planes: The planes searched.
    """

    swt: np.ndarray
    swt_theta: np.ndarray
    swt_phi: np.ndarray
    swt_normal: np.ndarray
    fs: np.ndarray
    fs_theta: np.ndarray
    fs_phi: np.ndarray
    fs_normal: np.ndarray
    sigma_n_max: np.ndarray
    strain_amplitude: np.ndarray
    shear_strain_range: np.ndarray
    planes: PlaneSet


def _check_history(name: str, values) -> np.ndarray:
    values = np.asarray(values, dtype=float)
    if values.ndim != 4 or values.shape[2:] != (3, 3):
        raise ValueError(f"critical_planes: {name} has shape {values.shape}; (n_times, n_points, 3, 3) expected")
    if values.shape[0] < 1:
        raise ValueError(f"critical_planes: {name} has no time (n_times = 0)")
    if not np.all(np.isfinite(values)):
        raise ValueError(f"critical_planes: {name} has non-finite values")
    return values


def _path_diameter(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """The largest distance between two times of the path (first(t), second(t)), over axis 0."""
    if not np.any(second):  # the path lies on one line (2D plane strain: no shear along e_z): its range
        return first.max(axis=0) - first.min(axis=0)
    largest = np.zeros(first.shape[1:])
    for time in range(first.shape[0] - 1):
        distance = np.hypot(first[time + 1:] - first[time], second[time + 1:] - second[time]).max(axis=0)
        largest = np.maximum(largest, distance)
    return largest


def critical_planes(stress, strain, dim: int, angle_step: float | None = None,
                    fatemi_socie: FatemiSocie | None = None, chunk_size: int = 4_000_000) -> CriticalPlanes:
    """The SWT and Fatemi–Socie critical planes of each point over a cycle's history (module docstring).

    Args:
        stress: (n_times, n_points, 3, 3) stress history (MPa), global frame, tension positive.
        strain: (n_times, n_points, 3, 3) total strain history, same times and points.
        dim: 2 (normals in the x-y plane) or 3 (a half sphere).
        angle_step: The plane search's step in degrees (default :data:`DEFAULT_ANGLE_STEP`).
        fatemi_socie: The Fatemi–Socie constants; None computes SWT only (FS columns NaN).
        chunk_size: Largest number of (time, point, plane) values held at once (memory: 8 bytes each, a few
            arrays); the points are taken in chunks of that size.

    Returns:
        The critical planes of every point.
    """
    stress = _check_history("stress", stress)
    strain = _check_history("strain", strain)
    if stress.shape != strain.shape:
        raise ValueError(f"critical_planes: stress {stress.shape} and strain {strain.shape} differ in shape")
    planes = plane_normals(dim, angle_step)
    n_times, n_points = stress.shape[:2]
    normals, bases = planes.normals, planes.shear_directions
    n_planes = normals.shape[0]
    # Each projection is a linear form of the tensor's nine components: n.T.n = T : (n n), 2 n.T.d = T : 2 (n d),
    # so a chunk's projections on every plane are one matrix product (time x point, 9) @ (9, planes).
    normal_forms = np.einsum("ki,kj->ijk", normals, normals).reshape(9, n_planes)
    shear_forms = [2.0 * np.einsum("ki,kj->ijk", normals, bases[:, axis]).reshape(9, n_planes) for axis in (0, 1)]
    per_chunk = max(1, int(chunk_size) // (n_times * n_planes))
    out = {name: np.full(n_points, np.nan) for name in ("swt", "swt_index", "fs", "fs_index", "sigma_n_max",
                                                           "strain_amplitude", "shear_strain_range")}
    for start in range(0, n_points, per_chunk):
        points = slice(start, min(start + per_chunk, n_points))
        stress_rows = stress[:, points].reshape(-1, 9)
        strain_rows = strain[:, points].reshape(-1, 9)
        shape = (n_times, -1, n_planes)
        sigma_n = (stress_rows @ normal_forms).reshape(shape)                      # (t, p, k)
        eps_n = (strain_rows @ normal_forms).reshape(shape)
        sigma_n_max = sigma_n.max(axis=0)
        amplitude = 0.5 * (eps_n.max(axis=0) - eps_n.min(axis=0))
        swt = sigma_n_max * amplitude                                              # (p, k)
        best = np.argmax(swt, axis=1)
        rows = np.arange(best.size)
        out["swt"][points] = swt[rows, best]
        out["swt_index"][points] = best
        out["sigma_n_max"][points] = sigma_n_max[rows, best]
        out["strain_amplitude"][points] = amplitude[rows, best]
        if fatemi_socie is not None:
            gamma_first = (strain_rows @ shear_forms[0]).reshape(shape)
            gamma_second = (strain_rows @ shear_forms[1]).reshape(shape)
            shear_range = _path_diameter(gamma_first, gamma_second)
            fs = 0.5 * shear_range * (1.0 + fatemi_socie.k * sigma_n_max / fatemi_socie.sigma_y)
            best = np.argmax(fs, axis=1)
            out["fs"][points] = fs[rows, best]
            out["fs_index"][points] = best
            out["shear_strain_range"][points] = shear_range[rows, best]
    swt_index = out["swt_index"].astype(int)
    nan3 = np.full((n_points, 3), np.nan)
    if fatemi_socie is not None:
        fs_index = out["fs_index"].astype(int)
        fs_angles = (planes.theta[fs_index], planes.phi[fs_index], normals[fs_index])
    else:
        fs_angles = (np.full(n_points, np.nan), np.full(n_points, np.nan), nan3)
    return CriticalPlanes(out["swt"], planes.theta[swt_index], planes.phi[swt_index], normals[swt_index],
                          out["fs"], *fs_angles, out["sigma_n_max"], out["strain_amplitude"],
                          out["shear_strain_range"], planes)


def ruiz_parameter(sigma_xx, shear_traction, tangential_displacement) -> np.ndarray:
    """Ruiz's fretting damage parameter at surface points: ``kappa = (sigma_xx)_max * (tau delta)_max``.

    ``(sigma_xx)_max`` is the largest surface stress along the surface over the cycle (tension positive; a
    compressive maximum gives a negative kappa, kept as such), ``delta`` the local slip amplitude (half the range
    of the relative tangential displacement over the cycle; with two tangential components half the diameter of
    its path) and ``(tau delta)_max`` the largest ``|tau| delta`` over the cycle (Ruiz, Boddington & Chen, Exp.
    Mech. 24, 1984). Units: MPa x MPa x length.

    Args:
        sigma_xx: (n_times, n_points) the stress along the surface (MPa).
        shear_traction: (n_times, n_points) the surface shear traction (MPa), or (n_times, n_points, k) its
            components (its magnitude is used).
        tangential_displacement: (n_times, n_points) the relative tangential displacement (length), or
            (n_times, n_points, k) its components.

    Returns:
        (n_points,) kappa.
    """
    stress = np.asarray(sigma_xx, dtype=float)
    shear = np.asarray(shear_traction, dtype=float)
    slip = np.asarray(tangential_displacement, dtype=float)
    shear = shear[..., None] if shear.ndim == 2 else shear
    slip = slip[..., None] if slip.ndim == 2 else slip
    for name, values, ndim in (("sigma_xx", stress, 2), ("shear_traction", shear, 3),
                               ("tangential_displacement", slip, 3)):
        if values.ndim != ndim or values.shape[:2] != stress.shape or stress.shape[0] < 1:
            raise ValueError(f"ruiz_parameter: {name} has shape {values.shape}; (n_times, n_points[, k]) expected "
                             f"with the times and points of sigma_xx {stress.shape}")
        if not np.all(np.isfinite(values)):
            raise ValueError(f"ruiz_parameter: {name} has non-finite values")
    if slip.shape[2] not in (1, 2):
        raise ValueError(f"ruiz_parameter: tangential_displacement has {slip.shape[2]} components; 1 or 2")
    # (one component: the path's range, what _path_diameter gives when the second is zero)
    amplitude = 0.5 * _path_diameter(slip[..., 0], slip[..., 1] if slip.shape[2] == 2 else np.zeros(stress.shape))
    return stress.max(axis=0) * (np.linalg.norm(shear, axis=2).max(axis=0) * amplitude)


def critical_distance(depths, values, distance: float, method: str = "point") -> np.ndarray:
    """Taylor's theory of critical distances on a parameter sampled along lines into the body.

    Point method: the parameter at ``distance`` below the surface (linear interpolation in depth). Line method:
    its mean over the depths 0 to 2 ``distance`` (the trapezoidal rule on the samples, the end interpolated).

    Args:
        depths: (n_depths,) increasing depths below the surface, the first 0 (length units).
        values: (n_depths,) or (n_lines, n_depths) the parameter at those depths along each line.
        distance: The critical distance (> 0; 2 ``distance`` for the line method must not exceed the last depth).
        method: ``"point"`` or ``"line"``.

    Returns:
        The parameter of each line (a float for one line).
    """
    depths = np.asarray(depths, dtype=float)
    values = np.asarray(values, dtype=float)
    single = values.ndim == 1
    values = np.atleast_2d(values)
    if method not in ("point", "line"):
        raise ValueError(f"critical_distance: method = {method!r}: allowed 'point', 'line'")
    if depths.ndim != 1 or depths.size < 2 or depths[0] != 0.0 or np.any(np.diff(depths) <= 0):
        raise ValueError("critical_distance: depths must be increasing, at least two, starting at 0")
    if values.ndim != 2 or values.shape[1] != depths.size:
        raise ValueError(f"critical_distance: values has shape {values.shape}; (n_lines, {depths.size}) expected")
    reach = float(distance) * (2.0 if method == "line" else 1.0)
    if not (math.isfinite(float(distance)) and distance > 0 and reach <= depths[-1]):
        raise ValueError(f"critical_distance: distance = {distance!r} must be > 0 with the {method} method's "
                         f"reach {reach!r} within the sampled depths (0 to {depths[-1]!r})")
    if method == "point":
        result = np.array([np.interp(reach, depths, line) for line in values])
    else:
        inside = depths < reach
        grid = np.append(depths[inside], reach)
        sampled = np.stack([np.interp(grid, depths, line) for line in values])
        # the trapezoidal rule written out (numpy 1.24 has np.trapz only, numpy 2 renames it)
        result = (0.5 * (sampled[:, 1:] + sampled[:, :-1]) * np.diff(grid)).sum(axis=1) / reach
    return float(result[0]) if single else result


@dataclass(frozen=True)
class CriticalDistance:
    """Taylor's critical distance applied below the hot spot (:func:`depth_profile`, :func:`critical_distance`).

    Args:
        distance: The critical distance L (length units), > 0 (e.g. the El Haddad length
            (1/pi) (delta K_th / delta sigma_e)^2).
        method: ``"point"`` (the parameter at depth L) or ``"line"`` (its mean over depths 0 to 2L).
        band: Half-width of the band of points (along x) whose values make the profile below the hot spot; None:
            the hot spot's own depth (about half an element for a hot spot in the first row of cells).

    Raises:
        ValueError: a value out of its range (the message names it).
    """

    distance: float
    method: str = "point"
    band: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "distance", _positive("CriticalDistance", "distance", self.distance))
        if self.method not in ("point", "line"):
            raise ValueError(f"CriticalDistance: method = {self.method!r}: allowed 'point', 'line'")
        if self.band is not None:
            object.__setattr__(self, "band", _positive("CriticalDistance", "band", self.band))


def depth_profile(x, depth, values, x0: float, band: float) -> tuple[np.ndarray, np.ndarray]:
    """A parameter's profile in depth below the surface point ``x0``, from scattered points.

    The points with ``|x - x0| <= band`` are taken; those at one depth (to 1e-9 of the deepest) are averaged; the
    profile is extended to depth 0 by the straight line through its two shallowest samples (exact for a
    parameter linear in depth), as :func:`critical_distance` wants it.

    Args:
        x, depth, values: (P,) the points' positions along the surface, depths (>= 0) and parameter values.
        x0: Where the line into the body starts (e.g. the hot spot's x).
        band: Half-width of the band of points taken (> 0).

    Returns:
        (depths, values) of the profile, the depths increasing from 0.

    Raises:
        ValueError: fewer than two distinct depths in the band.
    """
    x, depth, values = (np.asarray(a, dtype=float).ravel() for a in (x, depth, values))
    inside = np.abs(x - float(x0)) <= float(band)
    depths, samples = depth[inside], values[inside]
    if depths.size == 0:
        raise ValueError(f"depth_profile: no point within band = {band!r} of x0 = {x0!r}")
    tolerance = 1e-9 * np.abs(depths).max()
    order = np.argsort(depths, kind="stable")
    depths, samples = depths[order], samples[order]
    starts = np.flatnonzero(np.concatenate([[True], np.diff(depths) > tolerance]))
    levels = np.add.reduceat(depths, starts) / np.diff(np.append(starts, depths.size))
    means = np.add.reduceat(samples, starts) / np.diff(np.append(starts, depths.size))
    if levels.size < 2:
        raise ValueError(f"depth_profile: the points within band = {band!r} of x0 = {x0!r} lie at one depth; a "
                         "wider band (or a finer mesh) is needed")
    if levels[0] > tolerance:
        surface = means[0] - levels[0] * (means[1] - means[0]) / (levels[1] - levels[0])
        levels, means = np.concatenate([[0.0], levels]), np.concatenate([[surface], means])
    else:
        levels[0] = 0.0
    return levels, means


@dataclass(frozen=True)
class MinerSum:
    """Miner's linear damage sum over blocks of cycles, per point (Madge et al. 2007, Wear 262, 1159-1170:
    contact-evolution based fretting fatigue life): ``D = sum_i n_i / N_i``, block i's ``n_i`` cycles at the life
    ``N_i`` its evaluated cycle gives; a crack initiates where D reaches 1.

    Attributes:
        damage: (P,) D at each point after the blocks added.
        cycles: The cycles summed (the blocks' lengths).
        initiation: The cycle at which the first point's D reached 1, inside its block by the block's constant
            rate (``cycles before the block + (1 - D before) N_i``); inf while no point has.
        initiation_point: That point's index (-1 while none).
    """

    damage: np.ndarray
    cycles: float = 0.0
    initiation: float = math.inf
    initiation_point: int = -1

    @classmethod
    def start(cls, points: int) -> "MinerSum":
        """No damage at ``points`` points."""
        return cls(np.zeros(int(points)))

    def add(self, lives, block: float) -> "MinerSum":
        """The sum after a block of ``block`` cycles (> 0) at the lives ``lives`` (P,) (inf: no damage).

        Raises:
            ValueError: ``block`` not finite and > 0, or ``lives`` not (P,) values > 0.
        """
        block = _positive("MinerSum.add", "block", block)
        lives = np.asarray(lives, dtype=float)
        if lives.shape != self.damage.shape or np.isnan(lives).any() or (lives <= 0).any():
            raise ValueError(f"MinerSum.add: lives of shape {lives.shape} (> 0, inf allowed) for the "
                             f"{self.damage.size} points of the sum")
        damage = self.damage + block / lives
        initiation, point = self.initiation, self.initiation_point
        if not math.isfinite(initiation):
            crossing = (self.damage < 1.0) & (damage >= 1.0)
            if crossing.any():
                when = np.where(crossing, self.cycles + (1.0 - self.damage) * lives, np.inf)
                point = int(np.argmin(when))
                initiation = float(when[point])
        return MinerSum(damage, self.cycles + block, initiation, point)
