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

__all__ = ["SPHERE_ON_FLAT_TAGS", "SPHERE_ON_FLAT_REGIONS", "COARSEN_AT", "graded_coordinates", "uniform_zone_steps",
           "graded_depth", "field_cell_size", "layer_kinds", "lateral_levels",
           "layered_node_count", "sphere_on_flat_grid", "grid_node_count", "sphere_on_flat"]

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


#: Lateral coarsening of a depth-graded mesh (:func:`sphere_on_flat` with ``depth_growth``): a layer whose
#: thickness reaches this many lateral steps of the zone's cells becomes a pair of 3:1 transition layers (x, then
#: y), so the cells under the transitions are never much flatter than about one to two.
COARSEN_AT = 2.0


def uniform_zone_steps(contact_radius: float, step: float, zone: float, coarsening: int = 0) -> int:
    """The number of cubes of edge ``step`` across the uniform zone's half-width: ``zone a`` rounded up to whole
    cubes, and to a multiple of ``3^coarsening`` (each lateral coarsening groups steps by 3)."""
    n = max(1, math.ceil(zone * contact_radius / step - 1e-9))
    return 3**coarsening * math.ceil(n / 3**coarsening)


def _grid_axes(contact_radius: float, step: float, *, zone: float, depth_zone: float, extent: float, growth: float,
               half: bool, depth_growth: float | None = None, coarsening: int = 0, field_cell: float = 0.125
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The grid coordinates x, y and depth of one body of :func:`sphere_on_flat_grid` (also read by
    :mod:`dolfinx_fretting.sizes` to count the nodes before meshing). With ``depth_growth`` the depth axis is
    :func:`graded_depth`'s, and the uniform zone's steps along x and y come in multiples of ``3^coarsening``."""
    a = float(contact_radius)
    zone_steps = uniform_zone_steps(a, step, zone, coarsening if depth_growth is not None else 0)
    along = graded_coordinates(step, zone_steps * step, extent * a, growth)
    x = _mirror(along)
    y = along if half else _mirror(along)
    if depth_growth is None:
        depth = graded_coordinates(step, depth_zone * a, extent * a, growth)
    else:
        depth = graded_depth(step, field_cell_size(a, step, field_cell), depth_zone * a, extent * a, depth_growth)
    return x, y, depth


def field_cell_size(contact_radius: float, step: float, field_cell: float) -> float:
    """The largest cell (lateral step and layer thickness) of a depth-graded body down to ``depth_zone a``:
    ``field_cell`` times a, at least the contact face's step."""
    return max(float(step), field_cell * float(contact_radius))


def graded_depth(step: float, cap: float, capped_depth: float, total: float, growth: float) -> np.ndarray:
    """Depth coordinates from 0 to ``total``: layers ``step`` thick at 0 growing by ``growth`` each, at most
    ``cap`` thick down to ``capped_depth`` (the whole layer that reaches it included), then growing on by about
    ``growth`` from there to ``total`` exactly (:func:`graded_coordinates`'s ratio adjustment)."""
    depth, thickness = [0.0], float(step)
    while depth[-1] < capped_depth * (1 - 1e-9) and depth[-1] + min(thickness, cap) < total * (1 - 1e-9):
        depth.append(depth[-1] + min(thickness, cap))
        thickness *= growth
    last = depth[-1] - depth[-2] if len(depth) > 1 else float(step)
    rest = total - depth[-1]
    tail = graded_coordinates(last, last, rest, growth)[1:] if rest > last * (1 + 1e-9) else np.array([rest])
    return np.concatenate([depth, depth[-1] + tail])


def layer_kinds(depth: np.ndarray, step: float, coarsening: int, cap: float = math.inf,
                capped_depth: float = 0.0) -> list[str]:
    """The kind of each depth interval of a depth-graded body: ``"regular"`` (a tensor layer), ``"x"`` or ``"y"``
    (a 3:1 transition along that axis). From the contact face down, an interval at least ``COARSEN_AT`` times the
    current lateral step thick (and with another below it) starts an x then a y transition, ``coarsening`` times
    at most; each multiplies the lateral step by 3, which must stay at most ``cap`` above ``capped_depth``."""
    kinds: list[str] = []
    lateral, level, i = float(step), 0, 0
    while i < depth.size - 1:
        thickness = depth[i + 1] - depth[i]
        allowed = 3.0 * lateral <= cap * (1 + 1e-9) or depth[i] >= capped_depth * (1 - 1e-9)
        if (allowed and level < coarsening and i + 2 < depth.size
                and thickness >= COARSEN_AT * lateral * (1 - 1e-9)):
            kinds += ["x", "y"]
            lateral, level, i = 3.0 * lateral, level + 1, i + 2
        else:
            kinds.append("regular")
            i += 1
    return kinds


def _levels(kinds: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """The coarsening level along x and along y of the node layer at each depth node (0 at the contact face)."""
    level_x, level_y = [0], [0]
    for kind in kinds:
        level_x.append(level_x[-1] + (kind == "x"))
        level_y.append(level_y[-1] + (kind == "y"))
    return np.asarray(level_x), np.asarray(level_y)


def lateral_levels(size: int, zone_first: int, zone_last: int, levels: int) -> list[np.ndarray]:
    """The node indices along one axis at each coarsening level 0 .. ``levels``: every node outside the uniform
    zone (indices ``zone_first`` .. ``zone_last``, a multiple of ``3^levels`` steps), and every ``3^k``-th
    inside it at level k: only the zone's cubes coarsen; the graded cells around them are already coarse."""
    index = np.arange(size)
    outside = (index < zone_first) | (index > zone_last)
    return [index[outside | ((index - zone_first) % 3**k == 0)] for k in range(levels + 1)]


def _axis_levels(x: np.ndarray, y: np.ndarray, zone_steps: int, half: bool,
                 levels: int) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """:func:`lateral_levels` of a body's x axis (mirrored about 0) and y axis (from 0 in a half model)."""
    middle_x = x.size // 2
    middle_y = 0 if half else y.size // 2
    return (lateral_levels(x.size, middle_x - zone_steps, middle_x + zone_steps, levels),
            lateral_levels(y.size, max(middle_y - zone_steps, 0), middle_y + zone_steps, levels))


def _layered_nodes(levels_x: list[np.ndarray], levels_y: list[np.ndarray], kinds: Sequence[str]) -> np.ndarray:
    """Which nodes exist: a boolean array over (x index, y index, half-depth index) where half-depth index 2i is
    depth node i and 2i + 1 the mid-depth of interval i (a transition layer's inner nodes)."""
    level_x, level_y = _levels(kinds)
    exists = np.zeros((levels_x[0].size, levels_y[0].size, 2 * len(kinds) + 1), dtype=bool)
    for i in range(len(kinds) + 1):
        exists[np.ix_(levels_x[level_x[i]], levels_y[level_y[i]], [2 * i])] = True
    for i, kind in enumerate(kinds):
        if kind == "x":  # inner nodes: the fine x lines that the coarser level drops
            inner = np.setdiff1d(levels_x[level_x[i]], levels_x[level_x[i] + 1])
            exists[np.ix_(inner, levels_y[level_y[i]], [2 * i + 1])] = True
        elif kind == "y":
            inner = np.setdiff1d(levels_y[level_y[i]], levels_y[level_y[i] + 1])
            exists[np.ix_(levels_x[level_x[i]], inner, [2 * i + 1])] = True
    return exists


def layered_node_count(levels_x: list[np.ndarray], levels_y: list[np.ndarray], kinds: Sequence[str]) -> int:
    """Nodes of one depth-graded body (exact, without building it)."""
    level_x, level_y = _levels(kinds)
    sizes_x, sizes_y = [v.size for v in levels_x], [v.size for v in levels_y]
    count = sum(sizes_x[level_x[i]] * sizes_y[level_y[i]] for i in range(len(kinds) + 1))
    for i, kind in enumerate(kinds):
        kx, ky = level_x[i], level_y[i]
        if kind == "x":
            count += (sizes_x[kx] - sizes_x[kx + 1]) * sizes_y[ky]
        elif kind == "y":
            count += (sizes_y[ky] - sizes_y[ky + 1]) * sizes_x[kx]
    return int(count)


# The 3:1 transition in a plane (lateral l, depth d), four quadrilaterals in tensor order (q00, q10, q01, q11):
# (lateral offset in fine steps 0..3, level 0 = top, 1 = mid-depth, 2 = bottom). Fine nodes 0..3 on top, inner
# nodes 1, 2 at mid-depth, coarse nodes 0 and 3 at the bottom; each quadrilateral turns counter-clockwise in
# (l, d), so its extrusion along the third axis is positively oriented in (x, y, depth).
_TRANSITION_QUADS = (((0, 0), (1, 0), (0, 2), (1, 1)),   # left
                     ((1, 0), (2, 0), (1, 1), (2, 1)),   # middle
                     ((2, 0), (3, 0), (2, 1), (3, 2)),   # right
                     ((1, 1), (2, 1), (0, 2), (3, 2)))   # bottom (a trapezoid)


def _transition_hexahedra(ids: np.ndarray, fine: np.ndarray, coarse: np.ndarray, across: np.ndarray,
                          depth_index: int, along_x: bool) -> list[np.ndarray]:
    """The cells of one transition layer from the ``fine`` to the ``coarse`` node indices along x
    (``along_x``) or y, extruded over the consecutive pairs of ``across`` (the other axis's indices): a 3:1
    template where a coarse step spans three fine ones, a plain hexahedron through the layer where it spans one."""
    top, mid, bottom = 2 * depth_index, 2 * depth_index + 1, 2 * depth_index + 2
    levels = (top, mid, bottom)
    position = np.searchsorted(fine, coarse)
    span = np.diff(position)
    groups, plain = position[:-1][span == 3], position[:-1][span == 1]

    def hexahedra(lateral: list[np.ndarray], level: list[int]) -> np.ndarray:
        """Quadrilateral (q00, q10, q01, q11) in (lateral, depth), extruded along the other axis."""
        G, B = np.meshgrid(np.arange(lateral[0].size), np.arange(across.size - 1), indexing="ij")
        G, B = G.ravel(), B.ravel()
        B0, B1 = across[B], across[B + 1]
        q = [lateral[n][G] for n in range(4)]
        if along_x:  # (x, y, depth) = (quad's lateral, extrusion, quad's depth)
            return np.column_stack([ids[q[0], B0, level[0]], ids[q[1], B0, level[1]], ids[q[0], B1, level[0]],
                                    ids[q[1], B1, level[1]], ids[q[2], B0, level[2]], ids[q[3], B0, level[3]],
                                    ids[q[2], B1, level[2]], ids[q[3], B1, level[3]]])
        return np.column_stack([ids[B0, q[0], level[0]], ids[B1, q[0], level[0]], ids[B0, q[1], level[1]],
                                ids[B1, q[1], level[1]], ids[B0, q[2], level[2]], ids[B1, q[2], level[2]],
                                ids[B0, q[3], level[3]], ids[B1, q[3], level[3]]])

    cells = [hexahedra([fine[plain], fine[plain + 1], fine[plain], fine[plain + 1]], [top, top, bottom, bottom])]
    for quad in _TRANSITION_QUADS:
        cells.append(hexahedra([fine[groups + offset] for offset, _ in quad], [levels[level] for _, level in quad]))
    return cells


def _layered_hexahedra(ids: np.ndarray, levels_x: list[np.ndarray], levels_y: list[np.ndarray],
                       kinds: Sequence[str]) -> np.ndarray:
    """Hexahedra (DOLFINx's tensor order in (x, y, depth)) of a depth-graded body; ``ids`` numbers the nodes
    of :func:`_layered_nodes` (-1 where none)."""
    level_x, level_y = _levels(kinds)
    cells = []
    for i, kind in enumerate(kinds):
        X, Y = levels_x[level_x[i]], levels_y[level_y[i]]
        if kind == "regular":
            I, J = (A.ravel() for A in np.meshgrid(np.arange(X.size - 1), np.arange(Y.size - 1), indexing="ij"))
            I0, I1, J0, J1 = X[I], X[I + 1], Y[J], Y[J + 1]
            top, bottom = 2 * i, 2 * i + 2
            cells.append(np.column_stack([ids[I0, J0, top], ids[I1, J0, top], ids[I0, J1, top], ids[I1, J1, top],
                                          ids[I0, J0, bottom], ids[I1, J0, bottom], ids[I0, J1, bottom],
                                          ids[I1, J1, bottom]]))
        elif kind == "x":
            cells += _transition_hexahedra(ids, X, levels_x[level_x[i] + 1], Y, i, True)
        else:
            cells += _transition_hexahedra(ids, Y, levels_y[level_y[i] + 1], X, i, False)
    out = np.concatenate(cells)
    if (out < 0).any():  # the templates' own consistency, not the user's input
        raise RuntimeError("a hexahedron's vertex is not a node of the layered mesh")
    return out


def _body_kinds(depth: np.ndarray, step: float, contact_radius: float, depth_zone: float, coarsening: int,
                field_cell: float) -> list[str]:
    """:func:`layer_kinds` of a depth-graded body: coarser than :func:`field_cell_size` only below
    ``depth_zone a``."""
    return layer_kinds(depth, step, coarsening, field_cell_size(contact_radius, step, field_cell),
                       depth_zone * contact_radius)


def _layered_body(x: np.ndarray, y: np.ndarray, depth: np.ndarray, kinds: list[str], zone_steps: int, half: bool,
                  coarsening: int, offset: int) -> tuple[np.ndarray, np.ndarray]:
    """Lateral and depth coordinates (N, 3) of a depth-graded body's nodes and its hexahedra (numbered from
    ``offset``, positively oriented in (x, y, depth))."""
    levels_x, levels_y = _axis_levels(x, y, zone_steps, half, coarsening)
    exists = _layered_nodes(levels_x, levels_y, kinds)
    ids = np.full(exists.shape, -1, dtype=np.int64)
    ids[exists] = np.arange(np.count_nonzero(exists))
    half_depth = np.empty(exists.shape[2])
    half_depth[0::2] = depth
    half_depth[1::2] = 0.5 * (depth[:-1] + depth[1:])
    I, J, K = np.nonzero(exists)  # the order of ids
    coordinates = np.column_stack([x[I], y[J], half_depth[K]])
    return coordinates, offset + _layered_hexahedra(ids, levels_x, levels_y, kinds)


def sphere_on_flat_grid(radius: float, contact_radius: float, contact_mesh_size: float, *, zone: float = 1.5,
                        depth_zone: float = 1.0, extent: float = 9.0, growth: float = 1.5, half: bool = True,
                        flat: bool = True, flat_mesh_size: float | None = None, depth_growth: float | None = None,
                        coarsening: int = 0, field_cell: float = 0.125) -> dict[str, np.ndarray]:
    """Points and hexahedra of :func:`sphere_on_flat` (pure NumPy; the arguments are described there).

    Returns:
        ``points`` (N, 3), ``cells`` (M, 8) in DOLFINx's hexahedron order, ``regions`` (M,) (the values of
        :data:`SPHERE_ON_FLAT_REGIONS`), the grid coordinates ``x``, ``y``, ``depth`` (sphere) and
        ``flat_x``, ``flat_y``, ``flat_depth``, and the sizes ``L`` (lateral half-size), ``height`` (cap and
        flat), ``zone_half_width``; with ``depth_growth``, ``kinds`` and ``flat_kinds``, the bodies' depth
        intervals (:func:`layer_kinds`).
    """
    R, a, h = float(radius), float(contact_radius), float(contact_mesh_size)
    L = extent * a
    height = extent * a
    b = uniform_zone_steps(a, h, zone, coarsening if depth_growth is not None else 0) * h

    def axes(step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return _grid_axes(a, step, zone=zone, depth_zone=depth_zone, extent=extent, growth=growth, half=half,
                          depth_growth=depth_growth, coarsening=coarsening, field_cell=field_cell)

    x, y, depth = axes(h)
    out = {"x": x, "y": y, "depth": depth}
    if depth_growth is None:
        X, Y, D = np.meshgrid(x, y, depth, indexing="ij")
        X, Y, D = (A.transpose(2, 1, 0).ravel() for A in (X, Y, D))   # i fastest, as _hexahedra numbers them
        sphere_cells = _hexahedra(x.size, y.size, depth.size)
    else:
        out["kinds"] = _body_kinds(depth, h, a, depth_zone, coarsening, field_cell)
        lateral, sphere_cells = _layered_body(x, y, depth, out["kinds"], round(b / h), half, coarsening, 0)
        X, Y, D = lateral.T
    f = R - np.sqrt(R * R - X * X - Y * Y)
    # The cap: the lower face on the sphere, the top flat; each vertical line of nodes keeps its spacing
    # scaled by (H - f)/H, so the layers under the contact are h thick to within f/H.
    Z = f + D * (height - f) / height
    points = [np.column_stack([X, Y, Z])]
    cells = [sphere_cells]
    regions = [np.full(cells[0].shape[0], SPHERE_ON_FLAT_REGIONS["sphere"], dtype=np.int32)]
    if flat:
        step = flat_mesh_size if flat_mesh_size is not None else h
        fx, fy, fd = axes(step)
        offset = points[0].shape[0]
        if depth_growth is None:
            Xf, Yf, Df = np.meshgrid(fx, fy, -fd[::-1], indexing="ij")   # z from -H up to 0
            Xf, Yf, Zf = (A.transpose(2, 1, 0).ravel() for A in (Xf, Yf, Df))
            flat_cells = _hexahedra(fx.size, fy.size, fd.size, offset)
        else:
            out["flat_kinds"] = _body_kinds(fd, step, a, depth_zone, coarsening, field_cell)
            zone_steps = uniform_zone_steps(a, step, zone, coarsening)
            lateral, flat_cells = _layered_body(fx, fy, fd, out["flat_kinds"], zone_steps, half, coarsening, offset)
            Xf, Yf, Zf = lateral[:, 0], lateral[:, 1], -lateral[:, 2]
            # z = -depth turns (x, y, depth) left-handed: swap the cells' two depth faces to keep them positive
            flat_cells = flat_cells[:, [4, 5, 6, 7, 0, 1, 2, 3]]
        points.append(np.column_stack([Xf, Yf, Zf]))
        cells.append(flat_cells)
        regions.append(np.full(cells[1].shape[0], SPHERE_ON_FLAT_REGIONS["flat"], dtype=np.int32))
        out.update(flat_x=fx, flat_y=fy, flat_depth=fd)
    out.update(points=np.concatenate(points), cells=np.concatenate(cells).astype(np.int64),
               regions=np.concatenate(regions), L=L, height=height, zone_half_width=b)
    return out


def grid_node_count(contact_radius: float, contact_mesh_size: float, *, zone: float = 1.5,
                    depth_zone: float = 1.0, extent: float = 9.0, growth: float = 1.5, half: bool = True,
                    flat: bool = True, depth_growth: float | None = None, coarsening: int = 0,
                    field_cell: float = 0.125) -> int:
    """The nodes :func:`sphere_on_flat_grid` makes (both bodies, the flat at the sphere's step), counted from its
    axes without building it (the size estimate's)."""
    x, y, depth = _grid_axes(contact_radius, contact_mesh_size, zone=zone, depth_zone=depth_zone, extent=extent,
                             growth=growth, half=half, depth_growth=depth_growth, coarsening=coarsening,
                             field_cell=field_cell)
    if depth_growth is None:
        per_body = x.size * y.size * depth.size
    else:
        kinds = _body_kinds(depth, contact_mesh_size, contact_radius, depth_zone, coarsening, field_cell)
        zone_steps = uniform_zone_steps(contact_radius, contact_mesh_size, zone, coarsening)
        per_body = layered_node_count(*_axis_levels(x, y, zone_steps, half, coarsening), kinds)
    return int(per_body * (2 if flat else 1))


# DOLFINx ---------------------------------------------------------------------------------------------------
def sphere_on_flat(comm: MPI.Comm, radius: float, contact_radius: float, contact_mesh_size: float | None = None,
                   *, zone: float = 1.5, depth_zone: float = 1.0, extent: float = 9.0, growth: float = 1.5,
                   half: bool = True, flat: bool = True, flat_mesh_size: float | None = None,
                   depth_growth: float | None = None, coarsening: int = 0, field_cell: float = 0.125) -> BodyMesh:
    """A sphere's cap on a flat (or alone, for a rigid plane), structured trilinear hexahedra. Collective.

    Sized from the expected Hertz contact radius a (:func:`~dolfinx_fretting.analytic.hertz_sphere`): cubes of edge ``h`` over
    ``|x|, |y| <= zone a`` (rounded up to whole cells) and ``depth_zone a`` deep, then steps growing by about
    ``growth`` up to ``extent a`` in every direction: the cap is ``extent a`` high with its top meant to be
    held (``extent = 9``: within 0.05 % of a large body for the peak pressure), the flat ``extent a`` deep.
    The flat's top nodes lie under the sphere's (same x, y) unless ``flat_mesh_size`` differs.

    With R = 10 mm, a = 0.15 mm, h = a/4 and the defaults, a half model has 29 x 15 x 13 nodes per body
    (5655 nodes, 17 k dofs each).

    Opt-in, a mesh whose size follows the contact face rather than the volume (``depth_growth``): the same
    contact face (cubes' faces of edge h over the uniform zone, both bodies), but the layers under it h thick at
    the face and growing by ``depth_growth`` each (no uniform depth zone), and, ``coarsening`` times, a layer at
    least ``COARSEN_AT`` lateral steps thick replaced by two conforming 3:1 transition layers (a plane template
    of four quadrilaterals, extruded: first along y, coarsening x, then along x, coarsening y), so the lateral
    step triples with depth. The tensor grid's steps along x and y then come in multiples of
    ``3^coarsening`` (the uniform zone rounded up to them). Its cost: see benchmarks/results/contacts_3d.md.

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
        depth_growth: None (the default: cubes ``depth_zone a`` deep under the contact), or the ratio
            1 < g <= 2 of neighbouring layers from the contact face down (``depth_zone`` is then unused).
        coarsening: Lateral 3:1 coarsenings with depth, 0 to 3 (> 0 needs ``depth_growth``).
        field_cell: With ``depth_growth``, the largest cell (lateral step and layer thickness) over a down to
            ``depth_zone a``, 0 < field_cell <= 1 (at least h): Hertz's field varies over a; measured on the
            rigid-plane Hertz model at a/h = 12 (peak nodal pressure over p0; today's mesh +0.04 %): 0.125 gives
            +0.12 % with 63 % of today's dofs, 0.25 +0.61 % with 31 % (benchmarks/results/contacts_3d.md).

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
    if depth_growth is not None:
        _check("depth_growth", depth_growth, _is_real(depth_growth) and 1 < depth_growth <= 2,
               "None or 1 < depth_growth <= 2")
    _check("coarsening", coarsening, isinstance(coarsening, (int, np.integer)) and not isinstance(coarsening, bool)
           and 0 <= coarsening <= (3 if depth_growth is not None else 0),
           "an integer 0 <= coarsening <= 3, and 0 unless depth_growth is set")
    _check("field_cell", field_cell, _is_real(field_cell) and 0 < field_cell <= 1, "0 < field_cell <= 1")

    grid = sphere_on_flat_grid(radius, a, float(h), zone=zone, depth_zone=depth_zone, extent=extent,
                               growth=growth, half=half, flat=flat, flat_mesh_size=flat_mesh_size,
                               depth_growth=depth_growth, coarsening=coarsening, field_cell=field_cell)
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
