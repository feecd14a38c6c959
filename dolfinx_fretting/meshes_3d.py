"""Three-dimensional meshes: a sphere's cap pressed on a flat, structured hexahedra (units: mm).

:func:`sphere_on_flat` builds a mapped block of trilinear hexahedra of its own (no gmsh): a tensor grid in
(x, y, depth) whose cells are uniform cubes of edge ``h`` in the contact zone and grow geometrically away from
it, the sphere's cap mapped onto it so that its lower face lies exactly on the sphere. Why structured
hexahedra: on a Hertz contact the peak nodal pressure of P1 tetrahedra rides node-to-node scatter (+2 to +5 %
at a/h = 11 to 33, converging slowly), while structured hexahedra give it within 0.1 % from a/h = 3
(measured: ``/work/shared/notes/3d-contact.md`` of the project; the numbers of this module's meshes are in
``tests/test_sphere.py``).

The pure-NumPy part (:func:`graded_coordinates`, :func:`sphere_on_flat_grid`) is apart from the DOLFINx glue
(:func:`sphere_on_flat`), which hands the cells to ``dolfinx.mesh.create_mesh`` on rank 0 (DOLFINx
distributes them) and tags the boundary from the geometry.

Geometry (the sphere's lowest point at the origin, z up, sliding along x):

* the sphere's cap: ``{|x| <= L, 0 <= y <= L (half) or |y| <= L (full), f(x, y) <= z <= H_s}`` with
  ``f = R - sqrt(R^2 - x^2 - y^2)`` its lower (contact) face, the top ``z = H_s`` flat;
* the flat: ``{|x| <= L, same y, -H_f <= z <= 0}``.

A half model is cut by the plane y = 0 that contains the sliding direction x: give its nodes a roller
(``u_y = 0``), the symmetry condition.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from mpi4py import MPI

from .meshes import BodyMesh, _check, _is_real

__all__ = ["SPHERE_ON_FLAT_TAGS", "SPHERE_ON_FLAT_REGIONS", "graded_coordinates", "sphere_on_flat_grid",
           "sphere_on_flat"]

#: Facet tag values of :func:`sphere_on_flat` (the sphere's cap, then the flat). Every exterior facet carries
#: exactly one; the ``symmetry`` tags exist in a half model only.
SPHERE_ON_FLAT_TAGS: dict[str, int] = {"top": 1, "surface": 2, "symmetry": 3, "sides": 4,
                                       "flat_top": 5, "flat_bottom": 6, "flat_symmetry": 7, "flat_sides": 8}
#: Cell tag values of the two bodies.
SPHERE_ON_FLAT_REGIONS: dict[str, int] = {"sphere": 1, "flat": 2}


# Pure NumPy --------------------------------------------------------------------------------------------------
def graded_coordinates(h: float, uniform: float, total: float, growth: float) -> np.ndarray:
    """Node coordinates from 0 to ``total``: equal steps ``h`` up to ``uniform`` (rounded up to a whole number
    of steps), then steps growing geometrically by about ``growth`` each up to ``total`` exactly.

    The graded part has the number of steps n that makes ``h (g + g^2 + ... + g^n)`` closest to the remaining
    length for ``g = growth``; its ratio is then adjusted (bisection) so that the steps end at ``total``.

    Args:
        h: Step of the uniform part (> 0).
        uniform: Length of the uniform part (>= 0, < total).
        total: Length covered (> 0).
        growth: Ratio of neighbouring steps in the graded part (>= 1).

    Returns:
        Increasing coordinates, first 0, last ``total``.
    """
    n_u = max(1, math.ceil(uniform / h - 1e-9))
    x = list(h * np.arange(n_u + 1))
    rest = total - x[-1]
    if rest <= 1e-9 * total:
        x[-1] = total
        return np.asarray(x)
    if growth == 1.0:
        n = max(1, round(rest / h))
        return np.concatenate([x, x[-1] + rest * np.arange(1, n + 1) / n])

    def length(g: float, n: int) -> float:
        return h * sum(g**k for k in range(1, n + 1))

    n = 1
    while length(growth, n + 1) <= rest or abs(length(growth, n + 1) - rest) < abs(length(growth, n) - rest):
        n += 1
    lower, upper = 1e-3, max(growth, 2.0)
    while length(upper, n) < rest:
        upper *= 2.0
    for _ in range(200):  # bisection on the ratio: the graded steps end at total
        mid = 0.5 * (lower + upper)
        lower, upper = (mid, upper) if length(mid, n) < rest else (lower, mid)
    g = 0.5 * (lower + upper)
    steps = h * g ** np.arange(1, n + 1)
    steps *= rest / steps.sum()
    return np.concatenate([x, x[-1] + np.cumsum(steps)])


def _mirror(c: np.ndarray) -> np.ndarray:
    """``-c[::-1] .. c`` for coordinates starting at 0 (0 once)."""
    return np.concatenate([-c[:0:-1], c])


def _hexahedra(nx: int, ny: int, nz: int, offset: int = 0) -> np.ndarray:
    """Cells of an ``nx x ny x nz`` grid of points numbered ``i + nx (j + ny k)``, vertices in DOLFINx's
    (tensor-product) order: (0,0,0) (1,0,0) (0,1,0) (1,1,0), then the same at k + 1."""
    i, j, k = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1), np.arange(nz - 1), indexing="ij")
    base = (i + nx * (j + ny * k)).transpose(2, 1, 0).ravel()  # k slowest, i fastest
    corners = [0, 1, nx, nx + 1]
    corners = corners + [c + nx * ny for c in corners]
    return offset + base[:, None] + np.asarray(corners)[None, :]


def _grid_axes(contact_radius: float, step: float, *, zone: float, depth_zone: float, extent: float, growth: float,
               half: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The grid coordinates x, y and depth of one body of :func:`sphere_on_flat_grid` (also read by
    :mod:`dolfinx_fretting.sizes` to count the nodes before meshing)."""
    a = float(contact_radius)
    along = graded_coordinates(step, zone * a, extent * a, growth)
    x = _mirror(along)
    y = along if half else _mirror(along)
    depth = graded_coordinates(step, depth_zone * a, extent * a, growth)
    return x, y, depth


def sphere_on_flat_grid(radius: float, contact_radius: float, contact_mesh_size: float, *, zone: float = 1.5,
                        depth_zone: float = 1.0, extent: float = 9.0, growth: float = 1.5, half: bool = True,
                        flat: bool = True, flat_mesh_size: float | None = None) -> dict[str, np.ndarray]:
    """Points and hexahedra of :func:`sphere_on_flat` (pure NumPy; the arguments are described there).

    Returns:
        ``points`` (N, 3), ``cells`` (M, 8) in DOLFINx's hexahedron order, ``regions`` (M,) (the values of
        :data:`SPHERE_ON_FLAT_REGIONS`), the grid coordinates ``x``, ``y``, ``depth`` (sphere) and
        ``flat_x``, ``flat_y``, ``flat_depth``, and the sizes ``L`` (lateral half-size), ``height`` (cap and
        flat), ``zone_half_width``.
    """
    R, a, h = float(radius), float(contact_radius), float(contact_mesh_size)
    L = extent * a
    height = extent * a
    b = math.ceil(zone * a / h - 1e-9) * h

    def axes(step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return _grid_axes(a, step, zone=zone, depth_zone=depth_zone, extent=extent, growth=growth, half=half)

    x, y, depth = axes(h)
    X, Y, D = np.meshgrid(x, y, depth, indexing="ij")
    X, Y, D = (A.transpose(2, 1, 0).ravel() for A in (X, Y, D))   # i fastest, as _hexahedra numbers them
    f = R - np.sqrt(R * R - X * X - Y * Y)
    # The cap: the lower face on the sphere, the top flat; each vertical line of nodes keeps its spacing
    # scaled by (H - f)/H, so the layers under the contact are h thick to within f/H.
    Z = f + D * (height - f) / height
    points = [np.column_stack([X, Y, Z])]
    cells = [_hexahedra(x.size, y.size, depth.size)]
    regions = [np.full(cells[0].shape[0], SPHERE_ON_FLAT_REGIONS["sphere"], dtype=np.int32)]
    out = {"x": x, "y": y, "depth": depth}
    if flat:
        fx, fy, fd = axes(flat_mesh_size if flat_mesh_size is not None else h)
        Xf, Yf, Df = np.meshgrid(fx, fy, -fd[::-1], indexing="ij")   # z from -H up to 0
        Xf, Yf, Zf = (A.transpose(2, 1, 0).ravel() for A in (Xf, Yf, Df))
        offset = points[0].shape[0]
        points.append(np.column_stack([Xf, Yf, Zf]))
        cells.append(_hexahedra(fx.size, fy.size, fd.size, offset))
        regions.append(np.full(cells[1].shape[0], SPHERE_ON_FLAT_REGIONS["flat"], dtype=np.int32))
        out.update(flat_x=fx, flat_y=fy, flat_depth=fd)
    out.update(points=np.concatenate(points), cells=np.concatenate(cells).astype(np.int64),
               regions=np.concatenate(regions), L=L, height=height, zone_half_width=b)
    return out


# DOLFINx ---------------------------------------------------------------------------------------------------
def sphere_on_flat(comm: MPI.Comm, radius: float, contact_radius: float, contact_mesh_size: float | None = None,
                   *, zone: float = 1.5, depth_zone: float = 1.0, extent: float = 9.0, growth: float = 1.5,
                   half: bool = True, flat: bool = True, flat_mesh_size: float | None = None) -> BodyMesh:
    """A sphere's cap on a flat (or alone, for a rigid plane), structured trilinear hexahedra. Collective.

    Sized from the expected Hertz contact radius a (:func:`~dolfinx_fretting.analytic.hertz_sphere`): cubes of edge ``h`` over
    ``|x|, |y| <= zone a`` (rounded up to whole cells) and ``depth_zone a`` deep, then steps growing by about
    ``growth`` up to ``extent a`` in every direction: the cap is ``extent a`` high with its top meant to be
    held (``extent = 9``: within 0.05 % of a large body for the peak pressure), the flat ``extent a`` deep.
    The flat's top nodes lie under the sphere's (same x, y) unless ``flat_mesh_size`` differs.

    With R = 10 mm, a = 0.15 mm, h = a/4 and the defaults, a half model has 29 x 15 x 13 nodes per body
    (5655 nodes, 17 k dofs each).

    Args:
        comm: Communicator over which the mesh is distributed (built on its rank 0).
        radius: Sphere radius R (mm), > 0.
        contact_radius: Expected contact radius a (mm), 0 < a, ``extent a < R``.
        contact_mesh_size: Edge h of the cubes in the contact zone (mm), 0 < h <= a; default a/4.
        zone: Half-width of the uniform zone over a (>= 1: it must hold the contact).
        depth_zone: Depth of the uniform zone over a (> 0).
        extent: Lateral half-size, cap height and flat depth over a (> zone and > depth_zone).
        growth: Ratio of neighbouring steps in the graded part, 1 <= growth <= 2.
        half: Half model (``y >= 0``, tags ``symmetry`` and ``flat_symmetry`` on y = 0) or full model.
        flat: Mesh the flat too (two bodies) or the sphere alone (for a rigid plane).
        flat_mesh_size: The flat's h (default: the sphere's): another value gives non-matching nodes.

    Returns:
        The bodies with tags :data:`SPHERE_ON_FLAT_TAGS` (those present), regions :data:`SPHERE_ON_FLAT_REGIONS`,
        zones ``"contact_zone"`` and ``"flat_contact_zone"`` (the contact faces' facets in the uniform zone),
        ``contact_mesh_size = h`` and ``contact_half_width`` the uniform zone's half-width.

    Raises:
        ValueError: an argument out of range (the message names it and the allowed range), on every rank before
            any collective call.
    """
    # Lazy: DOLFINx (and _dolfinx, which imports it) only to build; the geometries registry and the size
    # estimate import this module without DOLFINx
    from dolfinx import mesh as dmesh

    from . import _dolfinx as dfx

    _check("radius", radius, _is_real(radius) and radius > 0, "radius > 0 (mm)")
    _check("zone", zone, _is_real(zone) and zone >= 1, "zone >= 1 (the uniform zone must hold the contact)")
    _check("depth_zone", depth_zone, _is_real(depth_zone) and depth_zone > 0, "depth_zone > 0")
    _check("extent", extent, _is_real(extent) and extent > max(zone, depth_zone),
           f"extent > max(zone, depth_zone) = {max(zone, depth_zone)}")
    _check("contact_radius", contact_radius, _is_real(contact_radius) and 0 < contact_radius
           and extent * contact_radius * math.sqrt(2.0) < radius,
           f"0 < contact_radius and extent * contact_radius * sqrt(2) < radius = {radius} mm (the cap's corner "
           "stays on the sphere)")
    a = float(contact_radius)
    h = a / 4.0 if contact_mesh_size is None else contact_mesh_size
    _check("contact_mesh_size", h, _is_real(h) and 0 < h <= a, f"0 < contact_mesh_size <= contact_radius = {a} mm")
    if flat_mesh_size is not None:
        _check("flat_mesh_size", flat_mesh_size, _is_real(flat_mesh_size) and 0 < flat_mesh_size <= a,
               f"0 < flat_mesh_size <= contact_radius = {a} mm")
    _check("growth", growth, _is_real(growth) and 1 <= growth <= 2, "1 <= growth <= 2")

    grid = sphere_on_flat_grid(radius, a, float(h), zone=zone, depth_zone=depth_zone, extent=extent,
                               growth=growth, half=half, flat=flat, flat_mesh_size=flat_mesh_size)
    if comm.rank == 0:
        points, cells = grid["points"], grid["cells"]
    else:
        points, cells = np.zeros((0, 3)), np.zeros((0, 8), dtype=np.int64)
    msh = dfx.create_mesh(comm, cells, points, "hexahedron")
    msh.name = "body"

    tdim, fdim = 3, 2
    L, height, R = grid["L"], grid["height"], float(radius)
    msh.topology.create_connectivity(fdim, tdim)
    msh.topology.create_connectivity(tdim, fdim)
    n_cells = msh.topology.index_map(tdim).size_local + msh.topology.index_map(tdim).num_ghosts
    all_cells = np.arange(n_cells, dtype=np.int32)
    # Which body a cell belongs to: the sphere lies above z = 0, the flat below (cells meet at one point only).
    in_flat = dmesh.compute_midpoints(msh, tdim, all_cells)[:, 2] < 0.0
    regions = np.where(in_flat, SPHERE_ON_FLAT_REGIONS["flat"], SPHERE_ON_FLAT_REGIONS["sphere"]).astype(np.int32)
    cell_tags = dmesh.meshtags(msh, tdim, all_cells, regions)
    cell_tags.name = "Cell tags"

    boundary = np.sort(dmesh.locate_entities_boundary(msh, fdim, lambda p: np.full(p.shape[1], True)))
    f_to_c = msh.topology.connectivity(fdim, tdim)
    owner_cell = np.array([f_to_c.links(f)[0] for f in boundary], dtype=np.int32)
    flat_facet = in_flat[owner_cell] if boundary.size else np.zeros(0, dtype=bool)
    xyz = msh.geometry.x[dfx.entities_to_geometry(msh, fdim, boundary)] if boundary.size else np.zeros((0, 4, 3))
    tol = 1e-9 * max(L, height)
    X, Y, Z = xyz[..., 0], xyz[..., 1], xyz[..., 2]
    on_sphere = np.all(np.abs(Z - (R - np.sqrt(np.maximum(R * R - X * X - Y * Y, 0.0)))) <= tol, axis=1)
    symmetric = np.all(np.abs(Y) <= tol, axis=1) if half else np.zeros(boundary.size, dtype=bool)
    tags = SPHERE_ON_FLAT_TAGS
    values = np.full(boundary.size, tags["sides"], dtype=np.int32)
    # Sphere: top, symmetry, contact face, else sides. Flat: top (contact), bottom, symmetry, else sides.
    values[~flat_facet & np.all(np.abs(Z - height) <= tol, axis=1)] = tags["top"]
    values[~flat_facet & on_sphere] = tags["surface"]
    values[~flat_facet & symmetric] = tags["symmetry"]
    values[flat_facet] = tags["flat_sides"]
    values[flat_facet & np.all(np.abs(Z) <= tol, axis=1)] = tags["flat_top"]
    values[flat_facet & np.all(np.abs(Z + height) <= tol, axis=1)] = tags["flat_bottom"]
    values[flat_facet & symmetric] = tags["flat_symmetry"]
    facet_tags = dmesh.meshtags(msh, fdim, boundary.astype(np.int32), values)
    facet_tags.name = "Facet tags"
    present = {name: value for name, value in tags.items()
               if (half or "symmetry" not in name) and (flat or not name.startswith("flat"))}

    b = grid["zone_half_width"]
    mid = dmesh.compute_midpoints(msh, fdim, boundary) if boundary.size else np.zeros((0, 3))
    inside = (np.abs(mid[:, 0]) <= b * (1 + 1e-9)) & (np.abs(mid[:, 1]) <= b * (1 + 1e-9))
    zones = {"contact_zone": np.sort(boundary[inside & (values == tags["surface"])]).astype(np.int32)}
    if flat:
        zones["flat_contact_zone"] = np.sort(boundary[inside & (values == tags["flat_top"])]).astype(np.int32)
    regions_present = {k: v for k, v in SPHERE_ON_FLAT_REGIONS.items() if flat or k == "sphere"}
    return BodyMesh(msh, facet_tags, cell_tags, present, float(h), float(b), zones, regions_present)
