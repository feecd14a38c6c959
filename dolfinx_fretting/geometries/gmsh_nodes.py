"""The node count of a gmsh mesh under a Threshold size field, before meshing (pure NumPy): the model the size
estimate of a gmsh-meshed kind uses (:mod:`~dolfinx_fretting.geometries.half_cylinder`: the half-cylinder and the
flat under it).

gmsh's frontal-Delaunay mesher puts ``c / s^2`` nodes per unit area and ``b / s`` per unit length of boundary where
the size field is s; s is h in the refined region and grows by ``growth`` per unit distance from it up to the
coarse size H. The integral of these densities over the body (a polar grid about the contact) is the count;
c and b are calibrated on gmsh's meshes (:data:`GMSH_NODE_DENSITY`; the measured points are in
``benchmarks/results/size_estimate.md``).
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

__all__ = ["GMSH_NODE_DENSITY", "ON_BOUNDARY", "polar_grid", "segment_distance", "unstructured_nodes",
           "nodes_along"]

#: gmsh's frontal-Delaunay meshes (algorithm 6) under a size field s: (nodes per s^2 of area, nodes per s of
#: boundary), for quadrilaterals (Blossom recombination) and triangles; fitted on the half-cylinder and the
#: flat at h = 1.25 um to 40 um.
GMSH_NODE_DENSITY = {"quadrilateral": (1.19, 0.74), "triangle": (1.18, 1.14)}

#: Points within this fraction of the body's size of a region's boundary count as on it (inside). The boundary
#: samples of the half-cylinder (``half_cylinder._cylinder_boundary``) lie on the arc up to the rounding of a sine
#: and a cosine, which differs between numpy builds and CPUs (numpy 2's vectorised sin/cos on AVX-512 against numpy
#: 1.24's: 773 against 289 of the refined arc's samples counted inside with an exact ``rho <= R``). 1e-9 is ~10^7
#: roundings away from those samples and ~10^-6 of the finest element a scene accepts, so no grid point of the
#: integral moves.
ON_BOUNDARY = 1e-9


def polar_grid(r_max: float, r_min: float, n_r: int = 700, n_phi: int = 1440):
    """Midpoints and areas of a polar grid about the origin, radii geometric from ``r_min`` to ``r_max``."""
    edges = np.concatenate([[0.0], np.geomspace(r_min, r_max, n_r)])
    r = 0.5 * (edges[1:] + edges[:-1])
    dr = np.diff(edges)
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    radii, angles = np.meshgrid(r, phi, indexing="ij")
    area = (r * dr)[:, None] * (2 * np.pi / n_phi) * np.ones_like(angles)
    return radii * np.sin(angles), -radii * np.cos(angles), area  # x, y (phi from the downward vertical), area


def segment_distance(px, py, ax, ay, bx, by):
    """Distance of the points (px, py) to the segment from (ax, ay) to (bx, by)."""
    dx, dy = bx - ax, by - ay
    s = np.clip(((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0)
    return np.hypot(px - ax - s * dx, py - ay - s * dy)


def unstructured_nodes(regions: Callable, boundary: tuple, r_max: float, h: float, H: float, growth: float,
                       cell: str, include_sector: bool) -> float:
    """gmsh's nodes under its Threshold size field s (h at the sector growing by ``growth`` per unit distance up
    to H; h inside): ``c`` times the integral of 1 / s^2 over the body (outside its sector unless
    ``include_sector``) plus ``b`` times the integral of 1 / s along its boundary (:data:`GMSH_NODE_DENSITY`).

    Args:
        regions: ``(x, y) -> (inside the body, inside its refined sector, distance to the sector)``.
        boundary: ``(x, y, length)`` of the samples of the body's boundary.
        r_max: Radius of the polar grid about the origin that covers the body.
        h, H, growth: The size field: h in the sector, growing by ``growth`` per unit distance up to H.
        cell: ``"quadrilateral"`` or ``"triangle"``.
        include_sector: Count the sector's nodes too (else a structured count adds them).
    """
    c, b = GMSH_NODE_DENSITY[cell]
    x, y, area = polar_grid(r_max, min(h, r_max) / 8.0)
    inside, sector, d = regions(x, y)
    s = np.where(sector, h, np.minimum(h + growth * d, H))
    keep = inside if include_sector else inside & ~sector
    boundary_x, boundary_y, length = boundary
    _, on_sector, distance = regions(boundary_x, boundary_y)
    along = np.minimum(h + growth * distance, H)
    kept = np.ones(boundary_x.size, dtype=bool) if include_sector else ~on_sector
    return float(c * np.sum(area[keep] / s[keep] ** 2) + b * np.sum(length[kept] / along[kept]))


def nodes_along(length: float, h: float, H: float, growth: float) -> float:
    """Nodes along a line leaving the refined zone, spacing h + growth * distance up to H: the integral of
    1 / spacing over ``length`` (closed form)."""
    graded = min(length, (H - h) / growth) if growth > 0 else 0.0
    nodes = math.log1p(growth * graded / h) / growth if growth > 0 else 0.0
    return nodes + (length - graded) / (H if growth > 0 else h)
