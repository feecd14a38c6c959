"""The bookkeeping of a converged increment, with the wear law in its rate form (pure NumPy/numba, no mesh).

After an increment converges (paper eq. 5, backward Euler in the pressure)::

    g_w^a  <-  g_w^a + k p_n^a |dx_t^a|,      p_n^a = r_n^a / A^a,

with ``dx_t`` the slip increment of the increment (the tangential rows of the local solution x), ``A^a`` the
tributary length (2D) or area (3D) of contact ``a`` and ``k`` the wear law's coefficient of the increment at
that contact (:meth:`dolfinx_fretting.laws.WearLaw.coefficients`: Archard's k or Fouvry's alpha mu, times the
wear acceleration in cycles). The wear gap enters the next increment's initial normal gap (paper eqs. 3, 8).
Wear is applied to sliding contacts only: at a sticking contact the exact ``dx_t`` is
zero (what the solver returns there is its residual), at an open one ``p_n = 0``.

Identities the outputs satisfy (and the tests check): the wear area added, ``sum_a A^a dg_w^a =
k sum_slip r_n |dx_t|``, equals ``(k / mu)`` times the frictional energy dissipated, ``-sum_a r_t . dx_t``,
because ``r_t = -mu r_n dx_t/|dx_t|`` at a sliding contact.

:func:`commit_increment` does the whole update in one compiled call; both the per-increment Python path
and the compiled cycle loop (:mod:`dolfinx_fretting.cycling`) use it, so they cannot drift apart.
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["ROW", "ROW_FIELDS", "commit_increment", "wear_area"]

#: Names of the entries of the per-increment output row filled by :func:`commit_increment`.
ROW_FIELDS = (
    "normal_force",        # sum r_n (N/mm in 2D)
    "tangential_force",    # sum r_t1
    "max_pressure",        # max r_n / A (MPa); the smoothed pressure's peak with pressure_recovery "smoothed"
    "dissipated_energy",   # -sum r_t . dx_t in this increment (N mm / mm in 2D)
    "wear_area_increment",  # sum A dg_w in this increment (mm^2 in 2D)
    "max_wear_depth",      # max g_w after the increment (mm)
    "wear_area",           # sum A g_w after the increment (mm^2 in 2D)
    "n_open", "n_stick", "n_slip",
    "contact_width",       # span of the loaded contacts along the surface (mm)
    "stick_width",         # span of the sticking contacts (mm)
    "mean_relative_tangential",  # mean total tangential relative position of all contacts (mm)
    "edge_loaded",         # 1 if the first or last contact (the ends of the candidate window) carries load
    "contact_area",        # sum A of the loaded contacts: length (2D, mm) or area (3D, mm^2)
    "stick_area",          # sum A of the sticking contacts
)
#: Index of each field in the row.
ROW = {name: i for i, name in enumerate(ROW_FIELDS)}

_OPEN, _STICK, _SLIP = 0, 1, 2
_STATE_TOL = 1e-6  # same relative tests as local_solvers.contact_states


@numba.njit(cache=True)
def commit_increment(r: np.ndarray, x: np.ndarray, y: np.ndarray, mu: np.ndarray, dim: int,
                     tributary: np.ndarray, abscissa: np.ndarray, k: np.ndarray, wear_gap: np.ndarray,
                     states: np.ndarray, row: np.ndarray) -> None:
    """Classify the contacts of a converged increment, apply Archard's law to ``wear_gap`` and fill ``row``.

    Args:
        r: Contact forces ``(n, t...)`` per contact.
        x: Local solution ``W r + q``: gaps (normal rows) and slip increments (tangential rows).
        y: Total relative position (tangential rows: accumulated tangential relative displacement).
        mu: Friction coefficient per contact.
        dim: 2 or 3.
        tributary: Tributary length/area per contact.
        abscissa: Position of each contact along the surface (for widths).
        k: Wear coefficient per contact (1/MPa; each contact zone's wear law's); 0 disables wear there.
        wear_gap: Wear gap per contact, updated in place.
        states: Output, contact state codes (0 open, 1 stick, 2 slip).
        row: Output, ``len(ROW_FIELDS)`` values (see :data:`ROW_FIELDS`).
    """
    nc = mu.size
    scale = 0.0
    for a in range(nc):
        s = 0.0
        for c in range(dim):
            s += r[a * dim + c] ** 2
        scale = max(scale, math.sqrt(s))
    fn = ft = pmax = energy = dwear = 0.0
    n_open = n_stick = n_slip = 0
    lo_c, hi_c, lo_s, hi_s = np.inf, -np.inf, np.inf, -np.inf
    ysum = 0.0
    nloaded = 0
    area_loaded = area_stick = 0.0
    for a in range(nc):
        o = a * dim
        ysum += y[o + 1]
        rn = r[o]
        rt2 = 0.0
        xt2 = 0.0
        rx = 0.0
        for c in range(1, dim):
            rt2 += r[o + c] ** 2
            xt2 += x[o + c] ** 2
            rx += r[o + c] * x[o + c]
        rt = math.sqrt(rt2)
        fn += rn
        ft += r[o + 1]
        energy -= rx
        if rn <= _STATE_TOL * scale or scale == 0.0:
            states[a] = _OPEN
            n_open += 1
            continue
        p = rn / tributary[a]
        pmax = max(pmax, p)
        lo_c = min(lo_c, abscissa[a])
        hi_c = max(hi_c, abscissa[a])
        nloaded += 1
        area_loaded += tributary[a]
        if rt >= (1.0 - _STATE_TOL) * mu[a] * rn:
            states[a] = _SLIP
            n_slip += 1
            if k[a] > 0.0:
                dg = k[a] * p * math.sqrt(xt2)
                wear_gap[a] += dg
                dwear += dg * tributary[a]
        else:
            states[a] = _STICK
            n_stick += 1
            area_stick += tributary[a]
            lo_s = min(lo_s, abscissa[a])
            hi_s = max(hi_s, abscissa[a])
    wmax = 0.0
    warea = 0.0
    for a in range(nc):
        wmax = max(wmax, wear_gap[a])
        warea += wear_gap[a] * tributary[a]
    row[0] = fn
    row[1] = ft
    row[2] = pmax
    row[3] = energy
    row[4] = dwear
    row[5] = wmax
    row[6] = warea
    row[7] = n_open
    row[8] = n_stick
    row[9] = n_slip
    row[10] = hi_c - lo_c if n_stick + n_slip > 0 else 0.0
    row[11] = hi_s - lo_s if n_stick > 0 else 0.0
    row[12] = ysum / nc if nc > 0 else 0.0
    row[13] = 1.0 if nc > 0 and (states[0] != _OPEN or states[nc - 1] != _OPEN) else 0.0
    row[14] = area_loaded
    row[15] = area_stick


def wear_area(wear_gap: np.ndarray, tributary: np.ndarray) -> float:
    """Worn area (2D, mm^2 per mm of thickness) or volume (3D): the lumped integral of the wear gap."""
    return float(np.dot(wear_gap, tributary))
