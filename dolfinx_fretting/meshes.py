"""Meshes of the bodies (units: mm), each returned as a :class:`BodyMesh` with named facet tags.

* :func:`half_cylinder`: the lower half of a disk (a 2D cylinder section) resting on y = 0, meshed with
  gmsh: uniform ``contact_mesh_size`` along the arc near the lowest point and in a structured sector
  under it, graded to ``coarse_mesh_size`` far away; quadrilaterals or triangles.
* :func:`rectangle`: a structured block from :func:`dolfinx.mesh.create_rectangle`.

Both builders are collective over ``comm``. The gmsh model exists on rank 0 only;
``gmshio.model_to_mesh`` distributes the cells, so every rank gets its part of one and the same mesh
whatever the number of ranks.

Index conventions (DOLFINx 0.5.2 and 0.11): facet and cell indices are process-local and include ghosts;
geometry nodes (``mesh.geometry.x``) and the nodes (blocks) of a P1 vector space are numbered
differently, so use :func:`boundary_nodes` for coordinates and :func:`facet_dofs` for boundary
conditions and contact operators. In both, the owned entries come first: a local index ``i`` is owned
by this rank iff ``i < index_map.size_local``; the others are ghost copies of nodes owned by another
rank (count only the owned ones when summing over ranks).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np
from mpi4py import MPI

from .interrupts import keep_handlers

# DOLFINx (and _dolfinx, which imports it) and gmsh are imported inside the functions that mesh: the geometries
# registry and the size estimate import this module (the meshers' defaults, BodyMesh) without DOLFINx or gmsh.
if TYPE_CHECKING:
    from dolfinx.cpp.mesh import MeshTags_int32
    from dolfinx.mesh import Mesh

__all__ = ["BodyMesh", "half_cylinder", "cylinder_on_flat", "rectangle", "boundary_nodes", "facet_dofs",
           "HALF_CYLINDER_TAGS", "CYLINDER_ON_FLAT_TAGS", "CYLINDER_ON_FLAT_REGIONS", "RECTANGLE_TAGS"]

#: Facet tag values of :func:`half_cylinder` (the flat loading face and the whole curved face).
HALF_CYLINDER_TAGS: dict[str, int] = {"top": 1, "surface": 2}
#: Facet tag values of :func:`rectangle`.
RECTANGLE_TAGS: dict[str, int] = {"bottom": 1, "right": 2, "top": 3, "left": 4}
#: Facet tag values of :func:`cylinder_on_flat` (the half-cylinder's, then the flat's faces).
CYLINDER_ON_FLAT_TAGS: dict[str, int] = {"top": 1, "surface": 2, "flat_top": 3, "flat_bottom": 4,
                                         "flat_sides": 5}
#: Cell tag value of the (single) body.
BODY_CELL_TAG = 1
#: Cell tag values of :func:`cylinder_on_flat`'s two bodies.
CYLINDER_ON_FLAT_REGIONS: dict[str, int] = {"cylinder": 1, "flat": 2}


@dataclass(frozen=True, eq=False)
class BodyMesh:
    """A meshed body and its named boundaries.

    Attributes:
        mesh: The distributed DOLFINx mesh (2D, first order).
        facet_tags: Facet markers; every exterior facet carries exactly one value of ``tags``.
        cell_tags: Cell markers, one value per body (see ``regions``).
        tags: Boundary name -> value in ``facet_tags``; these boundaries are disjoint and cover the
            whole boundary.
        contact_mesh_size: Element edge length (mm) along the refined contact boundary (half-cylinder:
            the arc within ``contact_half_width`` of the lowest point; rectangle: ``width / nx``).
        contact_half_width: Half-width (mm) of the refined contact zone measured along x from the
            lowest point (half-cylinder), ``None`` for the rectangle.
        zones: Further named facet subsets that may overlap ``tags`` (half-cylinder: ``"contact_zone"``,
            the facets of the refined arc, a subset of ``"surface"``), as sorted local facet indices.
    """

    mesh: Mesh
    facet_tags: MeshTags_int32
    cell_tags: MeshTags_int32
    tags: dict[str, int]
    contact_mesh_size: float
    contact_half_width: float | None = None
    zones: dict[str, np.ndarray] = field(default_factory=dict)
    #: Body name -> value in ``cell_tags`` (one body: ``{"body": 1}``).
    regions: dict[str, int] = field(default_factory=lambda: {"body": BODY_CELL_TAG})

    @property
    def names(self) -> list[str]:
        """All facet set names accepted by :meth:`facets` (tags first, then zones)."""
        return list(self.tags) + [z for z in self.zones if z not in self.tags]

    def facets(self, name: str) -> np.ndarray:
        """Sorted local indices (owned and ghost) of the facets of a tag or zone.

        Raises:
            KeyError: if ``name`` is neither a tag nor a zone, listing the allowed names.
        """
        if name in self.tags:
            return np.asarray(self.facet_tags.find(self.tags[name]), dtype=np.int32)
        if name in self.zones:
            return self.zones[name]
        raise KeyError(f"unknown boundary {name!r}; allowed: {', '.join(self.names)}")


# Input checks ---------------------------------------------------------------------------------------------
def _check(name: str, value: float, ok: bool, allowed: str) -> None:
    if not ok:
        raise ValueError(f"{name} = {value!r} is out of range: {allowed}")


def _is_real(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool) \
        and math.isfinite(float(value))


def _check_point(name: str, value: Sequence[float]) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {value!r} is out of range: a pair of finite numbers (x, y)") from None
    _check(name, value, math.isfinite(x) and math.isfinite(y), "a pair of finite numbers (x, y)")
    return x, y


def _cylinder_sizes(radius, contact_mesh_size, contact_half_width, coarse_mesh_size) -> tuple[float, ...]:
    """Checked radius R, contact size h, refined half-width a and coarse size H (mm), defaults filled in."""
    R = radius
    _check("radius", R, _is_real(R) and R > 0, "radius > 0 (mm)")
    R = float(R)
    h = contact_mesh_size
    _check("contact_mesh_size", h, _is_real(h) and 0 < h < R, f"0 < contact_mesh_size < radius = {R} mm")
    h = float(h)
    # Default: R/15 or ten elements, capped at R/2 (but never below h) for coarse meshes.
    a = max(min(max(R / 15.0, 10.0 * h), R / 2.0), h) if contact_half_width is None else contact_half_width
    _check("contact_half_width", a, _is_real(a) and h <= a < R,
           f"contact_mesh_size = {h} mm <= contact_half_width < radius = {R} mm")
    a = float(a)
    H = max(R / 10.0, h) if coarse_mesh_size is None else coarse_mesh_size
    _check("coarse_mesh_size", H, _is_real(H) and h <= H < R,
           f"contact_mesh_size = {h} mm <= coarse_mesh_size < radius = {R} mm")
    H = float(H)
    return R, h, a, H


def _refined_depth(R: float, h: float, a: float) -> float:
    """Default depth t (mm) of the size-h sector under the refined arc (and in the flat): a/4, at least 2h, at
    most R/2 (also read by :mod:`dolfinx_fretting.sizes` to count the nodes before meshing)."""
    return min(max(a / 4.0, 2.0 * h), R / 2.0)


# Half-cylinder ---------------------------------------------------------------------------------------------
def half_cylinder(comm: MPI.Comm, radius: float, contact_mesh_size: float = 0.01,
                  contact_half_width: float | None = None, coarse_mesh_size: float | None = None,
                  quadrilateral: bool = True, center: Sequence[float] | None = None, *,
                  refined_depth: float | None = None, growth: float = 0.2,
                  verbose: bool = False) -> BodyMesh:
    """Mesh the lower half of a disk whose lowest point is the contact point. Collective.

    The body is ``{|p - c| <= R, y <= c_y}`` with ``c = center``; with the default centre ``(0, R)`` the
    lowest point is the origin and the flat top face lies at y = R. Boundaries (facet tags): ``"top"``
    (the flat face, length 2R, where the load is applied) and ``"surface"`` (the whole arc, length pi R);
    zone ``"contact_zone"`` (see :attr:`BodyMesh.zones`): the arc facets with
    ``|x - c_x| <= contact_half_width``.

    Mesh, first order:

    * The arc is split at the lowest point (so it is a mesh node) and at ``x = c_x +- a``; each half of
      the refined arc (length ``R asin(a/R)``) gets ``round(R asin(a/R) / h)`` equal segments, so the
      node spacing there is h up to that rounding and mirror-symmetric about the lowest point.
    * Under the refined arc, the annular sector of depth ``refined_depth`` has size h: structured
      quadrilaterals (radial layers of thickness about h) or, for triangles, unstructured triangles
      (structured triangle patterns made the P1 nodal contact pressure oscillate by several %).
    * Elsewhere gmsh's frontal-Delaunay algorithm (6) with a Distance + Threshold size field: h at the
      sector, growing by ``growth`` per unit distance up to ``coarse_mesh_size``.
    * Quadrilaterals: Blossom recombination of those triangles. For the size combinations where it
      leaves triangles, the model is meshed again at twice the sizes and every cell is subdivided into
      quadrilaterals (``Mesh.SubdivisionAlgorithm = 1``); the refined arc then has an even number of
      segments per half, still about h long.

    For R = 6 mm, a = 0.4 mm and the default rest, h = 10 µm gives about 1.9k quadrilaterals (2k nodes).

    Args:
        comm: Communicator over which the mesh is distributed (the gmsh model lives on its rank 0).
        radius: Radius R (mm), > 0.
        contact_mesh_size: Element size h (mm) along the refined arc and in the sector, 0 < h < R.
            Default 10 µm.
        contact_half_width: Half-width a (mm) of the refined arc, measured along x, h <= a < R. Default
            ``max(R/15, 10 h)`` capped at ``max(R/2, h)``: 0.4 mm for R = 6 mm, about four Hertz
            half-widths at 200 N/mm for the paper's material.
        coarse_mesh_size: Largest element size (mm), far from the contact, h <= size < R. Default
            ``max(R/10, h)``.
        quadrilateral: Four-node quadrilaterals if True, three-node triangles otherwise.
        center: Centre c of the disk (mm). Default ``(0, R)``.
        refined_depth: Depth t (mm) of the size-h sector under the refined arc, 0 < t <= R/2. Default
            ``a/4`` (at least 2h, at most R/2): 0.1 mm for the defaults, the Hertz half-width at
            200 N/mm. The sector holds about ``2 (a/h) (t/h)`` cells.
        growth: Size gradient outside the sector, 0 < growth <= 1 (0.2: neighbouring elements differ by
            about 20 %; smaller is smoother and larger).
        verbose: Let gmsh print its log.

    Returns:
        The body with ``tags = {"top": 1, "surface": 2}``, ``zones = {"contact_zone": ...}``,
        ``contact_mesh_size = h`` and ``contact_half_width = a``.

    Raises:
        ValueError: if an argument is out of range (the message names it and the allowed range); raised
            on every rank before any collective call.
        RuntimeError: if gmsh fails (raised on every rank).
    """
    R, h, a, H = _cylinder_sizes(radius, contact_mesh_size, contact_half_width, coarse_mesh_size)
    t = _refined_depth(R, h, a) if refined_depth is None else refined_depth
    _check("refined_depth", t, _is_real(t) and 0 < t <= R / 2.0,
           f"0 < refined_depth <= radius / 2 = {R / 2.0} mm")
    t = float(t)
    _check("growth", growth, _is_real(growth) and 0 < growth <= 1, "0 < growth <= 1")
    cx, cy = (0.0, R) if center is None else _check_point("center", center)
    geometry = dict(R=R, h=h, a=a, H=H, t=t, growth=float(growth), cx=cx, cy=cy)

    def build(gmsh) -> None:
        _half_cylinder_model(gmsh, **geometry, quadrilateral=quadrilateral, split=1)
        if quadrilateral and _cell_node_counts(gmsh) != {4}:
            # Blossom could not pair every triangle (it happens for some size combinations): mesh at
            # twice the sizes and split every cell into quadrilaterals instead, which always works.
            gmsh.model.remove()
            gmsh.model.add("body")
            _half_cylinder_model(gmsh, **geometry, quadrilateral=True, split=2)
        found = _cell_node_counts(gmsh)
        if found != {4 if quadrilateral else 3}:
            raise RuntimeError(f"gmsh produced cells with {sorted(found)} nodes")

    msh, cell_tags, facet_tags = _gmsh_to_dolfinx(comm, build, verbose)

    # The refined arc's facets: their midpoints lie within a of the axis (the split points sit exactly
    # at |x - c_x| = a, so no facet straddles the limit; the tolerance absorbs rounding only).
    surface = np.asarray(facet_tags.find(HALF_CYLINDER_TAGS["surface"]), dtype=np.int32)
    mid = _facet_midpoints(msh, surface)
    contact_zone = surface[np.abs(mid[:, 0] - cx) <= a * (1 + 1e-9)]
    return BodyMesh(msh, facet_tags, cell_tags, dict(HALF_CYLINDER_TAGS), h, a,
                    {"contact_zone": np.sort(contact_zone)})


def cylinder_on_flat(comm: MPI.Comm, radius: float, flat_width: float, flat_height: float,
                     contact_mesh_size: float = 0.01, contact_half_width: float | None = None,
                     coarse_mesh_size: float | None = None, quadrilateral: bool = True, *,
                     growth: float = 0.2, verbose: bool = False) -> BodyMesh:
    """Two bodies in one mesh: the half-cylinder of :func:`half_cylinder` resting on a flat block. Collective.

    The cylinder's lowest point is the origin; the flat is ``[-W/2, W/2] x [-H_f, 0]``. The two bodies
    touch at the origin but share no node (two gmsh surfaces with their own points, so DOLFINx gets two
    disconnected pieces and one stiffness matrix K that is block-diagonal between them). Both contact
    faces are refined to ``contact_mesh_size`` within ``contact_half_width`` of x = 0, over a structured
    sector of the same depth in each body, and graded to ``coarse_mesh_size`` away from it.

    Args:
        comm: Communicator over which the mesh is distributed.
        radius: Cylinder radius R (mm).
        flat_width: Width W of the flat (mm), > 2 contact_half_width.
        flat_height: Height H_f of the flat (mm), > the refined depth.
        contact_mesh_size, contact_half_width, coarse_mesh_size, quadrilateral, growth, verbose: As in
            :func:`half_cylinder` (the same h, a and sizes are used in both bodies).

    Returns:
        The bodies with tags :data:`CYLINDER_ON_FLAT_TAGS` (``"top"``, ``"surface"``: the cylinder's loaded
        face and arc; ``"flat_top"``, ``"flat_bottom"``, ``"flat_sides"``), regions
        :data:`CYLINDER_ON_FLAT_REGIONS` and zones ``"contact_zone"`` (the refined arc) and
        ``"flat_contact_zone"`` (the refined segment of the flat's top).

    Raises:
        ValueError: if an argument is out of range (the message names it and the allowed range).
        RuntimeError: if gmsh fails (raised on every rank).
    """
    R, h, a, H = _cylinder_sizes(radius, contact_mesh_size, contact_half_width, coarse_mesh_size)
    t = _refined_depth(R, h, a)
    _check("flat_width", flat_width, _is_real(flat_width) and flat_width > 2 * a,
           f"flat_width > 2 contact_half_width = {2 * a} mm")
    _check("flat_height", flat_height, _is_real(flat_height) and flat_height > t,
           f"flat_height > the refined depth {t} mm")
    _check("growth", growth, _is_real(growth) and 0 < growth <= 1, "0 < growth <= 1")
    W, Hf = float(flat_width), float(flat_height)

    def model(gmsh, split: int) -> None:
        # Two bodies that touch at one point: the geo kernel must not merge their coincident points.
        gmsh.option.setNumber("Geometry.AutoCoherence", 0)
        cyl = _half_cylinder_geometry(gmsh, R, h, a, t, 0.0, R, quadrilateral, split)
        flat = _flat_geometry(gmsh, W, Hf, h, a, t, 0.0, 0.0, quadrilateral, split)
        # Mesh constraints after the last synchronize (a geo synchronize drops earlier ones).
        cyl["structure"]()
        flat["structure"]()
        _size_field_and_mesh(gmsh, cyl["refined_curves"] + flat["refined_curves"],
                             [cyl["sector"], flat["sector"]], split * h, split * H, growth, quadrilateral,
                             split, max(cyl["n_points"], flat["n_points"]))
        regions = CYLINDER_ON_FLAT_REGIONS
        gmsh.model.addPhysicalGroup(2, cyl["surfaces"], regions["cylinder"])
        gmsh.model.addPhysicalGroup(2, flat["surfaces"], regions["flat"])
        for name, value in regions.items():
            gmsh.model.setPhysicalName(2, value, name)
        tags = CYLINDER_ON_FLAT_TAGS
        for name, curves in (("top", cyl["top"]), ("surface", cyl["surface"]), ("flat_top", flat["top"]),
                             ("flat_bottom", flat["bottom"]), ("flat_sides", flat["sides"])):
            gmsh.model.addPhysicalGroup(1, curves, tags[name])
            gmsh.model.setPhysicalName(1, tags[name], name)
        gmsh.model.mesh.generate(2)

    def build(gmsh) -> None:
        model(gmsh, 1)
        if quadrilateral and _cell_node_counts(gmsh) != {4}:
            gmsh.model.remove()  # see half_cylinder: subdivide a mesh at twice the sizes instead
            gmsh.model.add("body")
            model(gmsh, 2)
        found = _cell_node_counts(gmsh)
        if found != {4 if quadrilateral else 3}:
            raise RuntimeError(f"gmsh produced cells with {sorted(found)} nodes")

    msh, cell_tags, facet_tags = _gmsh_to_dolfinx(comm, build, verbose)
    zones = {}
    for zone, tag in (("contact_zone", "surface"), ("flat_contact_zone", "flat_top")):
        facets = np.asarray(facet_tags.find(CYLINDER_ON_FLAT_TAGS[tag]), dtype=np.int32)
        mid = _facet_midpoints(msh, facets)
        zones[zone] = np.sort(facets[np.abs(mid[:, 0]) <= a * (1 + 1e-9)])
    return BodyMesh(msh, facet_tags, cell_tags, dict(CYLINDER_ON_FLAT_TAGS), h, a, zones,
                    dict(CYLINDER_ON_FLAT_REGIONS))


def _half_cylinder_model(gmsh, R: float, h: float, a: float, H: float, t: float, growth: float, cx: float,
                         cy: float, quadrilateral: bool, split: int) -> None:
    """Build and mesh the half-cylinder in the current (empty) gmsh model.

    ``split = 2``: mesh at sizes 2h, 2H and subdivide every cell into quadrilaterals (gmsh
    ``Mesh.SubdivisionAlgorithm = 1``), which halves the sizes back; the curve node counts are chosen so
    that the result has the same spacing rules (an even number of segments per half refined arc).
    """
    cyl = _half_cylinder_geometry(gmsh, R, h, a, t, cx, cy, quadrilateral, split)
    cyl["structure"]()
    _size_field_and_mesh(gmsh, cyl["refined_curves"], [cyl["sector"]], split * h, split * H, growth,
                         quadrilateral, split, cyl["n_points"])
    gmsh.model.addPhysicalGroup(2, cyl["surfaces"], BODY_CELL_TAG)
    gmsh.model.setPhysicalName(2, BODY_CELL_TAG, "body")
    tags = HALF_CYLINDER_TAGS
    gmsh.model.addPhysicalGroup(1, cyl["top"], tags["top"])
    gmsh.model.addPhysicalGroup(1, cyl["surface"], tags["surface"])
    for name, value in tags.items():
        gmsh.model.setPhysicalName(1, value, name)
    gmsh.model.mesh.generate(2)


def _half_cylinder_geometry(gmsh, R: float, h: float, a: float, t: float, cx: float, cy: float,
                            quadrilateral: bool, split: int) -> dict[str, list[int] | int]:
    """Add the half-cylinder's points, curves and two surfaces (refined sector, rest) to the geo model.

    Returns the entity tags: ``surfaces``, ``sector``, ``top`` and ``surface`` (curve lists) and
    ``refined_curves`` (the sector's inner boundary, from which the element size grows), and
    ``structure``, which sets the structured-mesh constraints: call it after the model's last
    ``geo.synchronize()`` (a synchronize drops them).
    """
    geo = gmsh.model.geo
    theta = math.asin(a / R)
    r_in = R - t
    # Equal segments along each half of the refined arc (length R theta) and through the depth t.
    n_seg = max(1, round(R * theta / (split * h)))
    n_layers = max(1, round(t / (split * h)))

    def on_circle(radius: float, angle: float) -> int:
        # Angle measured from the downward vertical, positive towards +x.
        return geo.addPoint(cx + radius * math.sin(angle), cy - radius * math.cos(angle), 0.0)

    c = geo.addPoint(cx, cy, 0.0)
    bottom, right_a, left_a = on_circle(R, 0.0), on_circle(R, theta), on_circle(R, -theta)
    inner_mid, inner_right, inner_left = on_circle(r_in, 0.0), on_circle(r_in, theta), on_circle(r_in, -theta)
    right, left = geo.addPoint(cx + R, cy, 0.0), geo.addPoint(cx - R, cy, 0.0)

    # Boundary, counter-clockwise: bottom -> +a -> right end -> top face -> left end -> -a -> bottom.
    centre_right = geo.addCircleArc(bottom, c, right_a)
    outer_right = geo.addCircleArc(right_a, c, right)
    top = geo.addLine(right, left)
    outer_left = geo.addCircleArc(left, c, left_a)
    centre_left = geo.addCircleArc(left_a, c, bottom)
    # Sector under the refined arc (|angle| <= theta, depth t). Quadrilaterals: structured, so the
    # cells carrying the contact are regular and symmetric about the lowest point (on the
    # unstructured sector the Hertz nodal pressure oscillated by up to 4.5 % at h = 20 µm).
    side_right = geo.addLine(right_a, inner_right)
    inner_right_arc = geo.addCircleArc(inner_right, c, inner_mid)
    inner_left_arc = geo.addCircleArc(inner_mid, c, inner_left)
    side_left = geo.addLine(inner_left, left_a)
    sector = geo.addPlaneSurface([geo.addCurveLoop(
        [centre_right, side_right, inner_right_arc, inner_left_arc, side_left, centre_left])])
    rest = geo.addPlaneSurface([geo.addCurveLoop(
        [outer_right, top, outer_left, -side_left, -inner_left_arc, -inner_right_arc, -side_right])])
    geo.synchronize()

    # Triangles stay unstructured (frontal) in the sector at size h: on structured triangles
    # ("Left", "Alternate") the P1 nodal contact forces oscillated by 4-8 % on a Hertz contact.
    structure = _structured_sector(gmsh, (centre_right, centre_left, inner_right_arc, inner_left_arc), n_seg,
                                   (side_right, side_left), n_layers, sector,
                                   [left_a, right_a, inner_right, inner_left], quadrilateral)

    return dict(structure=structure, surfaces=[sector, rest], sector=sector, top=[top], n_points=2 * max(n_seg, n_layers) + 20,
                surface=[centre_right, outer_right, outer_left, centre_left],
                refined_curves=[side_right, inner_right_arc, inner_left_arc, side_left])


def _flat_geometry(gmsh, width: float, height: float, h: float, a: float, t: float, cx: float, y_top: float,
                   quadrilateral: bool, split: int) -> dict[str, list[int] | int]:
    """Add a flat block ``[cx - width/2, cx + width/2] x [y_top - height, y_top]`` to the geo model.

    Its top face is split at ``x = cx +- a``; the refined segment gets ``2 round(a / h)`` equal pieces and a
    sector of depth t under it has size h (structured quadrilaterals, like the half-cylinder's). The
    cylinder's arc is divided by arc length, so the two bodies' contact nodes are about, not exactly, one
    above the other (the node-to-segment pairing does not need them to match).

    Returns the entity tags: ``surfaces``, ``sector``, ``top``, ``bottom``, ``sides`` (curve lists),
    ``refined_curves`` and ``structure`` (as in :func:`_half_cylinder_geometry`).
    """
    geo = gmsh.model.geo
    n_seg = max(1, round(a / (split * h)))
    n_layers = max(1, round(t / (split * h)))
    x0, x1, y0 = cx - width / 2.0, cx + width / 2.0, y_top - height
    p = {name: geo.addPoint(x, y, 0.0) for name, (x, y) in {
        "bl": (x0, y0), "br": (x1, y0), "tr": (x1, y_top), "tl": (x0, y_top),
        "ta_r": (cx + a, y_top), "ta_l": (cx - a, y_top), "tc": (cx, y_top),
        "ia_r": (cx + a, y_top - t), "ia_l": (cx - a, y_top - t), "ic": (cx, y_top - t)}.items()}
    bottom = geo.addLine(p["bl"], p["br"])
    right = geo.addLine(p["br"], p["tr"])
    top_right = geo.addLine(p["tr"], p["ta_r"])
    centre_right = geo.addLine(p["ta_r"], p["tc"])
    centre_left = geo.addLine(p["tc"], p["ta_l"])
    top_left = geo.addLine(p["ta_l"], p["tl"])
    left = geo.addLine(p["tl"], p["bl"])
    side_left = geo.addLine(p["ta_l"], p["ia_l"])
    inner_left = geo.addLine(p["ia_l"], p["ic"])
    inner_right = geo.addLine(p["ic"], p["ia_r"])
    side_right = geo.addLine(p["ia_r"], p["ta_r"])
    sector = geo.addPlaneSurface([geo.addCurveLoop(
        [side_left, inner_left, inner_right, side_right, centre_right, centre_left])])
    rest = geo.addPlaneSurface([geo.addCurveLoop(
        [bottom, right, top_right, -side_right, -inner_right, -inner_left, -side_left, top_left, left])])
    geo.synchronize()

    structure = _structured_sector(gmsh, (centre_right, centre_left, inner_left, inner_right), n_seg,
                                   (side_left, side_right), n_layers, sector,
                                   [p["ta_l"], p["ia_l"], p["ia_r"], p["ta_r"]], quadrilateral)

    return dict(structure=structure, surfaces=[sector, rest], sector=sector, bottom=[bottom], sides=[left, right],
                n_points=2 * max(2 * n_seg, n_layers) + 20,
                top=[top_right, centre_right, centre_left, top_left],
                refined_curves=[side_left, inner_left, inner_right, side_right])


def _structured_sector(gmsh, along: Sequence[int], n_seg: int, across: Sequence[int], n_layers: int, sector: int,
                       corners: list[int], quadrilateral: bool) -> Callable[[], None]:
    """The structured-mesh constraints of a refined sector, to apply after the model's last synchronize:
    ``n_seg`` equal segments on the curves ``along`` the surface, ``n_layers`` on those ``across`` it, and
    a transfinite (structured) quadrilateral sector."""
    def structure() -> None:
        mesh = gmsh.model.mesh
        for curve in along:
            mesh.setTransfiniteCurve(curve, n_seg + 1)
        for curve in across:
            mesh.setTransfiniteCurve(curve, n_layers + 1)
        if quadrilateral:
            mesh.setTransfiniteSurface(sector, "Left", corners)
    return structure


def _size_field_and_mesh(gmsh, refined_curves: list[int], sectors: list[int], hs: float, Hs: float,
                         growth: float, quadrilateral: bool, split: int, n_points: int) -> None:
    """Size h in the sectors; outside, h at the sectors growing linearly with the distance up to H."""
    mesh = gmsh.model.mesh
    fields = mesh.field
    dist = fields.add("Distance")
    fields.setNumbers(dist, "CurvesList", refined_curves)
    # Distances are measured to sample points: sample finer than h so the size field is smooth.
    fields.setNumber(dist, "NumPointsPerCurve", n_points)
    thr = fields.add("Threshold")
    fields.setNumber(thr, "InField", dist)
    fields.setNumber(thr, "SizeMin", hs)
    fields.setNumber(thr, "SizeMax", Hs)
    fields.setNumber(thr, "DistMin", 0.0)
    fields.setNumber(thr, "DistMax", (Hs - hs) / growth)
    inside = fields.add("MathEval")
    fields.setString(inside, "F", repr(hs))
    in_sector = fields.add("Restrict")
    fields.setNumber(in_sector, "InField", inside)
    fields.setNumbers(in_sector, "SurfacesList", sectors)
    size = fields.add("Min")
    fields.setNumbers(size, "FieldsList", [thr, in_sector])
    fields.setAsBackgroundMesh(size)
    for opt in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
        gmsh.option.setNumber(opt, 0)
    gmsh.option.setNumber("Mesh.Algorithm", 6)  # 8 + recombination segfaults in gmsh 4.8.4
    gmsh.option.setNumber("Mesh.RecombineAll", 1 if quadrilateral else 0)
    gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 1)  # Blossom; the full-quad variants abort in 4.8
    gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 1 if split == 2 else 0)
    gmsh.option.setNumber("Mesh.ElementOrder", 1)


def _cell_node_counts(gmsh) -> set[int]:
    """Numbers of nodes per 2D cell present in the current gmsh mesh (DOLFINx needs one cell type)."""
    types, _, _ = gmsh.model.mesh.getElements(2)
    return {gmsh.model.mesh.getElementProperties(t)[3] for t in types}


def _gmsh_to_dolfinx(comm: MPI.Comm, build: Callable, verbose: bool):
    """Run ``build(gmsh)`` on rank 0 in a fresh gmsh session, then distribute the mesh. Collective.

    gmsh is initialised and finalised here (so do not call this inside an open gmsh session of your
    own). A failure on rank 0 is broadcast before ``model_to_mesh`` so that no rank is left waiting.
    """
    with keep_handlers():  # gmsh 4.8 sets SIGINT to its default action (no clean-up) when imported
        import gmsh  # lazy: heavy, only to mesh (see the note at the imports)

    from ._dolfinx import model_to_mesh  # lazy: DOLFINx

    root = 0
    error = None
    if comm.rank == root:
        initialized = False
        try:
            with keep_handlers():  # ... and gmsh 4.11+ when initialised: a run's handlers stay
                gmsh.initialize(readConfigFiles=False)  # no user gmshrc: the same mesh on every machine
            initialized = True
            gmsh.option.setNumber("General.Terminal", 1 if verbose else 0)
            gmsh.option.setNumber("General.NumThreads", 1)  # single-threaded meshing is reproducible
            gmsh.model.add("body")
            build(gmsh)
        except Exception as exc:  # reported on every rank below
            error = f"{type(exc).__name__}: {exc}"
            if initialized:
                with keep_handlers():  # finalize restores the handler gmsh found (not necessarily the run's)
                    gmsh.finalize()
    error = comm.bcast(error, root=root)
    if error is not None:
        raise RuntimeError(f"mesh generation failed: {error}")
    try:
        msh, cell_tags, facet_tags = model_to_mesh(gmsh.model, comm, root, gdim=2)
    finally:
        if comm.rank == root:
            with keep_handlers():
                gmsh.finalize()
    msh.name = "body"
    return msh, cell_tags, facet_tags


def _facet_midpoints(msh, facets: np.ndarray) -> np.ndarray:
    """(n, 3) midpoints of the given local facets."""
    from dolfinx.mesh import compute_midpoints  # lazy: DOLFINx (see the note at the imports)

    msh.topology.create_connectivity(msh.topology.dim - 1, 0)
    if facets.size == 0:
        return np.zeros((0, 3))
    return compute_midpoints(msh, msh.topology.dim - 1, facets)


# Rectangle -----------------------------------------------------------------------------------------------
def rectangle(comm: MPI.Comm, width: float, height: float, nx: int, ny: int, quadrilateral: bool = True,
              origin: Sequence[float] = (0.0, 0.0)) -> BodyMesh:
    """A structured ``nx`` x ``ny`` block ``[x0, x0 + width] x [y0, y0 + height]``. Collective.

    Args:
        comm: Communicator.
        width: Size along x (mm), > 0.
        height: Size along y (mm), > 0.
        nx: Cells along x, >= 1.
        ny: Cells along y, >= 1.
        quadrilateral: Quadrilaterals if True, else triangles (each rectangle cut along a diagonal).
        origin: Bottom-left corner (x0, y0) (mm).

    Returns:
        The body with tags ``{"bottom": 1, "right": 2, "top": 3, "left": 4}``; ``contact_mesh_size`` is
        ``width / nx`` (the spacing along the bottom).

    Raises:
        ValueError: if an argument is out of range (the message names it and the allowed range).
    """
    from dolfinx import mesh as dmesh  # lazy: DOLFINx (see the note at the imports)

    _check("width", width, _is_real(width) and width > 0, "width > 0 (mm)")
    _check("height", height, _is_real(height) and height > 0, "height > 0 (mm)")
    for name, n in (("nx", nx), ("ny", ny)):
        _check(name, n, isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n >= 1,
               "an integer >= 1")
    x0, y0 = _check_point("origin", origin)
    x1, y1 = x0 + float(width), y0 + float(height)

    cell = dmesh.CellType.quadrilateral if quadrilateral else dmesh.CellType.triangle
    msh = dmesh.create_rectangle(comm, [np.array([x0, y0]), np.array([x1, y1])], [int(nx), int(ny)],
                                 cell_type=cell)
    msh.name = "body"
    tdim = msh.topology.dim
    fdim = tdim - 1
    # Node-on-side tests with a tolerance relative to the cell size (coordinates carry rounding).
    tol_x, tol_y = 1e-8 * width / nx, 1e-8 * height / ny
    sides: dict[str, Callable] = {
        "bottom": lambda p: np.abs(p[1] - y0) <= tol_y,
        "right": lambda p: np.abs(p[0] - x1) <= tol_x,
        "top": lambda p: np.abs(p[1] - y1) <= tol_y,
        "left": lambda p: np.abs(p[0] - x0) <= tol_x,
    }
    indices, values = [], []
    for name, marker in sides.items():
        found = dmesh.locate_entities_boundary(msh, fdim, marker)
        indices.append(found)
        values.append(np.full(found.size, RECTANGLE_TAGS[name], dtype=np.int32))
    indices = np.concatenate(indices).astype(np.int32)
    values = np.concatenate(values)
    # meshtags in 0.5.2 needs sorted, unique indices: sort; each facet lies on one side only (the
    # corners are vertices), so the four sets are disjoint.
    order = np.argsort(indices, kind="stable")
    indices, values = indices[order], values[order]
    facet_tags = dmesh.meshtags(msh, fdim, indices, values)
    facet_tags.name = "Facet tags"
    cells = np.arange(msh.topology.index_map(tdim).size_local + msh.topology.index_map(tdim).num_ghosts,
                      dtype=np.int32)
    cell_tags = dmesh.meshtags(msh, tdim, cells, np.full(cells.size, BODY_CELL_TAG, dtype=np.int32))
    cell_tags.name = "Cell tags"
    return BodyMesh(msh, facet_tags, cell_tags, dict(RECTANGLE_TAGS), float(width) / nx, None, {})


# Boundary nodes ---------------------------------------------------------------------------------------------
def boundary_nodes(body: BodyMesh, tag_name: str, owned_only: bool = False) -> np.ndarray:
    """Local indices of the geometry nodes (rows of ``body.mesh.geometry.x``) on a named boundary.

    Use these for coordinates only; they are not dof indices (see :func:`facet_dofs`).

    Args:
        body: The body.
        tag_name: A tag or zone name of ``body``.
        owned_only: Keep only nodes owned by this rank (``i < geometry.index_map().size_local``), so that
            concatenating over ranks lists every node once; otherwise ghost nodes are included.

    Returns:
        Sorted unique int32 indices.
    """
    from ._dolfinx import entities_to_geometry  # lazy: DOLFINx (see the note at the imports)

    msh = body.mesh
    fdim = msh.topology.dim - 1
    facets = body.facets(tag_name)
    msh.topology.create_connectivity(fdim, msh.topology.dim)
    if facets.size == 0:
        return np.zeros(0, dtype=np.int32)
    nodes = np.unique(entities_to_geometry(msh, fdim, facets)).astype(np.int32)
    if owned_only:
        nodes = nodes[nodes < msh.geometry.index_map().size_local]
    return nodes


def facet_dofs(V, body: BodyMesh, tag_name: str, owned_only: bool = False) -> np.ndarray:
    """Block (node) indices of a function space on a named boundary.

    For a vector P1 space these are node indices ``k`` (the dofs are ``bs * k + i``), as returned by
    ``fem.locate_dofs_topological(V, fdim, facets)``; ``V.tabulate_dof_coordinates()[k]`` is the node's
    position. This ordering differs from the geometry's (:func:`boundary_nodes`).

    Args:
        V: A function space on ``body.mesh`` (not a subspace).
        body: The body.
        tag_name: A tag or zone name of ``body``.
        owned_only: Keep only blocks owned by this rank (``k < V.dofmap.index_map.size_local``).

    Returns:
        Sorted unique int32 block indices (owned and, unless ``owned_only``, ghost).
    """
    from dolfinx import fem  # lazy: DOLFINx (see the note at the imports)

    msh = body.mesh
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, msh.topology.dim)
    dofs = np.asarray(fem.locate_dofs_topological(V, fdim, body.facets(tag_name)), dtype=np.int32)
    if owned_only:
        dofs = dofs[dofs < V.dofmap.index_map.size_local]
    return dofs
