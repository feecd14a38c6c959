"""The size of a scene's model before anything is meshed: nodes, dofs, contacts and memory.

:func:`estimate` counts what a validated :class:`~dolfinx_fretting.scenes.Scene` will build, from the same
sizing rules the meshers use (``meshes._cylinder_sizes`` and ``meshes._refined_depth``, the sphere's
``meshes_3d._grid_axes``, ``scene_models.candidate_window``), without importing DOLFINx or building
anything:

* **nodes and dofs**: exact for the structured meshes (a rectangle, the sphere's hexahedra, the structured
  sectors under a half-cylinder's contact); for the rest of a half-cylinder or flat, meshed by gmsh with a size
  field, the node density ``c / s(d)^2`` integrated over the body, s the size field at distance d from the
  refined sector (h there, growing by ``growth`` per mm up to the coarse size) and c calibrated on gmsh's
  meshes (:data:`GMSH_NODE_DENSITY`); a mesh file: its node count read from the file's header.
* **contacts**: the nodes of the contact surface within the candidate window (exact on the structured contact
  zones).
* **memory** (bytes, the whole machine: every rank counted), one term per consumer:
  ``baseline`` (an interpreter with DOLFINx, PETSc and numba loaded, per rank), ``mesh`` (mesh, spaces, K,
  vectors, gmsh's own copy while it meshes: per dof), ``factor`` (the MUMPS factor of K: a nested-dissection
  fill model, ``n log2 n`` in 2D and ``n^(4/3)`` in 3D for n dofs, fitted to MUMPS's INFOG(22) on the built-in
  geometries; under MPI the ``owned`` route adds one whole factor per rank), ``W`` (the dense Delassus matrix
  ``(nc dim)^2`` doubles, replicated on every rank, and the compiled loop's transposed copy), ``W_build`` (the
  selected-inverse request pattern, values and dense block of ``(K^-1)_SS``, freed once W is built),
  ``cycle_cache`` (the 2D compiled loop's contact-pattern LU factors, one ``(nc dim)^2`` block per increment of
  a cycle) and ``plastic`` (the Gauss-point state of an elastic-plastic body, the dense ``(K^-1)_XX`` on its
  plastic zone X, from the expected contact size and capped like the body caps it, and the tangent's second
  factor past that cap). The peak is the sum of the terms that live together: W's build working set and the cycle cache
  never do.

The calibration points and the estimate-to-measurement ratios of whole runs are in
``benchmarks/results/size_estimate.md`` (``benchmarks/bench_sizes.py``).

:func:`check_size` compares the estimate with the memory available (``MemAvailable`` of ``/proc/meminfo``,
or a container's cgroup limit if lower) and raises :class:`SizeError` (a :class:`~dolfinx_fretting.scenes.SceneError`:
bad input, exit code 2 in the CLI) when it does not fit, before any mesh is built; ``ignore=True`` (the CLI's
``--ignore-size``) lets the run through. Under MPI rank 0's reading decides for every rank.
"""

from __future__ import annotations

import inspect
import math
import os
import re
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .geometries import GEOMETRIES
from .scenes import Scene, SceneError

__all__ = ["SizeEstimate", "SizeError", "estimate", "available_memory", "check_size", "msh_node_count",
           "xdmf_node_count", "GMSH_NODE_DENSITY", "FACTOR_BYTES_2D", "FACTOR_BYTES_3D", "BASELINE_BYTES",
           "MESH_BYTES_PER_DOF"]

# Calibration (benchmarks/results/size_estimate.md has the measured points these come from) ------------------
#: gmsh's frontal-Delaunay meshes (algorithm 6) under a size field s: (nodes per s^2 of area, nodes per s of
#: boundary), for quadrilaterals (Blossom recombination) and triangles; fitted on the half-cylinder and the
#: flat at h = 1.25 um to 40 um.
GMSH_NODE_DENSITY = {"quadrilateral": (1.19, 0.74), "triangle": (1.18, 1.14)}
#: MUMPS factor memory (INFOG(22), bytes) per ``n log2 n`` (2D) and per ``n^(4/3)`` (3D), n the dofs: the upper
#: envelope of the built-in geometries' measured points (2D: 53-62, 3D: 138-187 bytes).
FACTOR_BYTES_2D = 64.0
FACTOR_BYTES_3D = 190.0
#: Resident memory of one rank of a run on a tiny mesh: Python, DOLFINx, PETSc, gmsh, numba and its compiled
#: kernels (the force-control solvers' alone weigh ~170 MB on the Debian stack). Measured 230-405 MB (DOLFINx
#: 0.5.2), 270-315 MB (0.11): the largest, rounded up.
BASELINE_BYTES = 420 * 2**20
#: Resident memory per dof besides the factor and W: mesh, dofmaps, K (CSR), vectors; a gmsh mesh costs more
#: (gmsh's own copy of the mesh lives until DOLFINx has it), hexahedra more again (K has ~80 entries a row).
#: Measured 450-750 (gmsh), 280-370 (rectangle), 450-1000 (hexahedra) bytes.
MESH_BYTES_PER_DOF = {"gmsh": 750.0, "rectangle": 400.0, "hexahedra": 1100.0}
#: Bytes per Gauss point of an elastic-plastic body (stress, plastic strain, p, committed and trial, and the
#: consistent tangent), and Gauss points per cell of its quadrature degree 2 (2 x 2 on quadrilaterals, 3 on
#: triangles, 2 x 2 x 2 on hexahedra).
PLASTIC_BYTES_PER_POINT = 8 * 40
_GAUSS_POINTS = {"quadrilateral": 4, "triangle": 3, "hexahedron": 8}
#: The plastic zone's dense algebra, bytes per (zone dofs)^2: Z = (K^-1)_XX and its selected-inverse request
#: (pattern, read-back and values: 32), Z itself and the low-rank tangent's blocks (8 + ...). Measured 820 MB
#: above the baseline on the elastic-plastic cylinder-flat at h = 5 um, whose zone reaches the cap below.
ZONE_BYTES_PER_DOF_SQUARED = 40

_GB = 2.0**30


class SizeError(SceneError):
    """The scene's model would not fit in the machine's memory; the message names the keys that drive it."""


@dataclass(frozen=True)
class SizeEstimate:
    """What a scene will build, estimated before meshing.

    Attributes:
        kind: ``geometry.kind``.
        nodes: Mesh nodes (both bodies), or None when not estimated (see ``note``).
        dofs: Displacement dofs (nodes x dim), or None.
        contacts: Contact candidates (the W of ``(contacts x dim)^2``), or None.
        dim: 2 or 3.
        ranks: MPI ranks counted in the memory terms.
        exact: The node count follows from the mesh's construction (structured); otherwise a model of gmsh's
            meshing, within ~10 %.
        memory: Bytes per consumer: ``baseline``, ``mesh``, ``factor``, ``W``, ``W_build``, ``cycle_cache``,
            ``plastic`` (see the module's docstring).
        drivers: The scene keys that set the size, with their values (for the refusal's message).
        note: What was not estimated, and why ("" if everything was).
    """

    kind: str
    nodes: int | None
    dofs: int | None
    contacts: int | None
    dim: int
    ranks: int
    exact: bool
    memory: dict[str, int] = field(default_factory=dict)
    drivers: dict[str, Any] = field(default_factory=dict)
    note: str = ""

    @property
    def total_bytes(self) -> int:
        """The estimated peak: everything but the W build's working set and the cycle cache, plus the larger of
        the two (the working set is freed before the cycles start)."""
        m = self.memory
        rest = sum(v for k, v in m.items() if k not in ("W_build", "cycle_cache"))
        return int(rest + max(m.get("W_build", 0), m.get("cycle_cache", 0)))

    def breakdown(self) -> str:
        """The memory terms in words, largest first: ``"factor 1.2 GB, mesh 0.3 GB, ..."``."""
        parts = sorted(self.memory.items(), key=lambda kv: -kv[1])
        return ", ".join(f"{name} {_size(value)}" for name, value in parts if value > 0)

    def describe(self) -> str:
        """One line: ``size estimate: 9.9k dofs (4959 nodes, ~), 69 contacts, peak memory ~0.26 GB (...)``."""
        def count(n: int | None) -> str:
            return "?" if n is None else f"{n:,}"
        approx = "" if self.exact else "~"
        text = (f"size estimate: {approx}{count(self.dofs)} dofs ({approx}{count(self.nodes)} nodes), "
                f"{count(self.contacts)} contacts, peak memory ~{_size(self.total_bytes)} "
                f"({self.breakdown()}{f'; {self.ranks} ranks' if self.ranks > 1 else ''})")
        return text + (f"; {self.note}" if self.note else "")

    def as_dict(self) -> dict[str, Any]:
        """The estimate as JSON-ready data (``summary.json``'s ``size_estimate``), with ``total_bytes``."""
        return {**asdict(self), "total_bytes": self.total_bytes}


def _size(n: float) -> str:
    """Bytes in MB, GB or TB, three significant digits."""
    if n >= 1000 * _GB:
        return f"{n / 2**40:.3g} TB"
    return f"{n / _GB:.3g} GB" if n >= 0.1 * _GB else f"{n / 2**20:.3g} MB"


# Nodes of the gmsh meshes -------------------------------------------------------------------------------------
def _polar_grid(r_max: float, r_min: float, n_r: int = 700, n_phi: int = 1440):
    """Midpoints and areas of a polar grid about the origin, radii geometric from ``r_min`` to ``r_max``."""
    edges = np.concatenate([[0.0], np.geomspace(r_min, r_max, n_r)])
    r = 0.5 * (edges[1:] + edges[:-1])
    dr = np.diff(edges)
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    R_, P_ = np.meshgrid(r, phi, indexing="ij")
    area = (r * dr)[:, None] * (2 * np.pi / n_phi) * np.ones_like(P_)
    return R_ * np.sin(P_), -R_ * np.cos(P_), area  # x, y (phi from the downward vertical), area


def _segment_distance(px, py, ax, ay, bx, by):
    dx, dy = bx - ax, by - ay
    s = np.clip(((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0)
    return np.hypot(px - ax - s * dx, py - ay - s * dy)


#: Points within this fraction of the body's size of a region's boundary count as on it (inside). The boundary
#: samples of :func:`_cylinder_boundary` lie on the arc up to the rounding of a sine and a cosine, which differs
#: between numpy builds and CPUs (numpy 2's vectorised sin/cos on AVX-512 against numpy 1.24's: 773 against 289
#: of the refined arc's samples counted inside with an exact ``rho <= R``). 1e-9 is ~10^7 roundings away from
#: those samples and ~10^-6 of the finest element a scene accepts, so no grid point of the integral moves.
_ON_BOUNDARY = 1e-9


def _cylinder_regions(x, y, R: float, a: float, t: float):
    """Inside the half-cylinder (lowest point at the origin), inside its refined sector, distance to the sector.
    Points on a boundary (within :data:`_ON_BOUNDARY` R) are inside it."""
    rho = np.hypot(x, R - y)
    phi = np.arctan2(x, R - y)  # from the downward vertical, positive towards +x
    theta = math.asin(a / R)
    tol = _ON_BOUNDARY * R
    inside = (rho <= R + tol) & (y <= R + tol)
    sector = inside & (rho >= R - t - tol) & (np.abs(phi) <= theta + _ON_BOUNDARY)
    side = np.sign(phi) * theta
    ux, uy = np.sin(side), -np.cos(side)
    d_side = _segment_distance(x, y, (R - t) * ux, R + (R - t) * uy, R * ux, R + R * uy)
    d = np.where(np.abs(phi) <= theta, np.maximum(R - t - rho, 0.0), d_side)
    return inside, sector, d


def _flat_regions(x, y, width: float, height: float, a: float, t: float):
    """Inside the flat (top at y = 0, centred), inside its refined sector, distance to the sector. Points on a
    boundary (within :data:`_ON_BOUNDARY` of the width) are inside it."""
    tol = _ON_BOUNDARY * width
    inside = (np.abs(x) <= width / 2 + tol) & (y <= tol) & (y >= -height - tol)
    sector = inside & (np.abs(x) <= a + tol) & (y >= -t - tol)
    d = np.hypot(np.maximum(np.abs(x) - a, 0.0), np.maximum(-t - y, 0.0))
    return inside, sector, d


def _cylinder_boundary(R: float, n: int = 20000):
    """Points and lengths of the half-cylinder's boundary (the arc and the top face)."""
    phi = (np.arange(n) + 0.5) * np.pi / n - np.pi / 2
    x = np.concatenate([R * np.sin(phi), (np.arange(n) + 0.5) * 2 * R / n - R])
    y = np.concatenate([R - R * np.cos(phi), np.full(n, R)])
    return x, y, np.concatenate([np.full(n, np.pi * R / n), np.full(n, 2 * R / n)])


def _flat_boundary(width: float, height: float, n: int = 20000):
    """Points and lengths of the flat's boundary (top, bottom, sides)."""
    u = (np.arange(n) + 0.5) / n
    x = np.concatenate([(u - 0.5) * width, (u - 0.5) * width, np.full(n, -width / 2), np.full(n, width / 2)])
    y = np.concatenate([np.zeros(n), np.full(n, -height), -u * height, -u * height])
    return x, y, np.concatenate([np.full(2 * n, width / n), np.full(2 * n, height / n)])


def _unstructured_nodes(regions, boundary, r_max: float, h: float, H: float, growth: float, cell: str,
                        include_sector: bool) -> float:
    """gmsh's nodes under its Threshold size field s (h at the sector growing by ``growth`` per unit distance up
    to H; h inside): ``c`` times the integral of 1 / s^2 over the body (outside its sector unless
    ``include_sector``) plus ``b`` times the integral of 1 / s along its boundary (:data:`GMSH_NODE_DENSITY`)."""
    c, b = GMSH_NODE_DENSITY[cell]
    x, y, area = _polar_grid(r_max, min(h, r_max) / 8.0)
    inside, sector, d = regions(x, y)
    s = np.where(sector, h, np.minimum(h + growth * d, H))
    keep = inside if include_sector else inside & ~sector
    bx, by, length = boundary
    _, b_sector, b_d = regions(bx, by)
    b_s = np.minimum(h + growth * b_d, H)
    b_keep = np.ones(bx.size, dtype=bool) if include_sector else ~b_sector
    return float(c * np.sum(area[keep] / s[keep] ** 2) + b * np.sum(length[b_keep] / b_s[b_keep]))


def _nodes_along(length: float, h: float, H: float, growth: float) -> float:
    """Nodes along a line leaving the refined zone, spacing h + growth * distance up to H: the integral of
    1 / spacing over ``length`` (closed form)."""
    graded = min(length, (H - h) / growth) if growth > 0 else 0.0
    nodes = math.log1p(growth * graded / h) / growth if growth > 0 else 0.0
    return nodes + (length - graded) / (H if growth > 0 else h)


def _default(function, name: str):
    return inspect.signature(function).parameters[name].default


def _half_cylinder(scene: Scene) -> tuple[int, int, bool]:
    """Nodes (both bodies), contacts, and whether the count is exact, of a half-cylinder scene."""
    from . import meshes

    g = scene.geometry
    R, h, a, H = meshes._cylinder_sizes(g.radius, g.contact_mesh_size, g.refined_half_width, g.coarse_mesh_size)
    t = meshes._refined_depth(R, h, a)
    growth = _default(meshes.half_cylinder, "growth")
    cell = "quadrilateral" if g.quadrilateral else "triangle"
    theta = math.asin(a / R)
    # The structured sectors (meshes._half_cylinder_geometry, _flat_geometry): equal segments along the refined
    # arc (each half R theta long) and the flat's refined segment (each half a long), layers through t.
    n_arc, n_flat, n_layers = max(1, round(R * theta / h)), max(1, round(a / h)), max(1, round(t / h))
    structured = g.quadrilateral

    def body(regions, boundary, r_max: float, n_along: int) -> float:
        exact = (2 * n_along + 1) * (n_layers + 1) if structured else 0
        return exact + _unstructured_nodes(regions, boundary, r_max, h, H, growth, cell, include_sector=not structured)

    nodes = body(lambda x, y: _cylinder_regions(x, y, R, a, t), _cylinder_boundary(R), math.sqrt(2) * R, n_arc)
    if scene.contact.obstacle == "elastic_flat":
        W, Hf = g.flat_width, g.flat_height
        nodes += body(lambda x, y: _flat_regions(x, y, W, Hf, a, t), _flat_boundary(W, Hf), math.hypot(W / 2, Hf),
                      n_flat)
    window, _ = GEOMETRIES["half_cylinder"].candidate_window(scene, g.refined_half_width, g.contact_mesh_size)
    # Candidates: the arc's nodes within the window of the lowest one (measured along the plane).
    k = np.arange(n_arc + 1)
    within = R * np.sin(k * theta / n_arc) <= window * (1 + 1e-12)
    contacts = 2 * int(within.sum()) - 1
    if window > a:  # beyond the refined arc the spacing grows with the distance from it
        length = R * (math.asin(min(window, R) / R) - theta)
        contacts += 2 * int(_nodes_along(length, h, H, growth))
    return int(round(nodes)), contacts, False


def _sphere(scene: Scene) -> tuple[int, int, bool]:
    """Nodes (both bodies), contacts, exact, of a sphere scene (the structured hexahedra of meshes_3d)."""
    from .meshes_3d import _grid_axes, sphere_on_flat

    g = scene.geometry
    sphere = GEOMETRIES["sphere"]
    a, h = sphere.contact_size(scene), sphere.element_size(scene)
    options = {k: _default(sphere_on_flat, k) for k in ("zone", "depth_zone", "extent", "growth")}
    x, y, depth = _grid_axes(a, h, **options, half=g.half_model)
    bodies = 2 if scene.contact.obstacle == "elastic_flat" else 1
    nodes = bodies * x.size * y.size * depth.size
    zone = math.ceil(options["zone"] * a / h - 1e-9) * h  # the uniform zone's half-width (sphere_on_flat_grid)
    window, _ = sphere.candidate_window(scene, zone, h)
    X, Y = np.meshgrid(x, y, indexing="ij")
    contacts = int(np.count_nonzero(np.hypot(X, Y) <= window * (1 + 1e-12)))
    return int(nodes), contacts, True


def _rectangle(scene: Scene) -> tuple[int, int, bool]:
    g, c = scene.geometry, scene.contact
    nodes = (g.nx + 1) * (g.ny + 1)
    along = g.nx if c.surface in ("bottom", "top") else g.ny
    step = (g.width / g.nx) if c.surface in ("bottom", "top") else (g.height / g.ny)
    contacts = along + 1
    if c.candidate_half_width is not None:
        contacts = min(contacts, 2 * int(c.candidate_half_width * (1 + 1e-12) / step) + 1)
    return nodes, contacts, True


def msh_node_count(path: str | Path) -> int | None:
    """The node count in a gmsh ``.msh`` file's ``$Nodes`` header (formats 2 and 4, ASCII or binary), without
    reading the nodes; None if the file has no readable header."""
    try:
        with open(path, "rb") as f:
            head = f.read(1 << 16)
            m = re.search(rb"\$MeshFormat\s+(\S+)\s+(\d)\s+(\d+)", head)
            if m is None:
                return None
            version, binary, size_t = float(m.group(1)), m.group(2) == b"1", int(m.group(3))
            buffer, offset = head, 0
            while b"$Nodes" not in buffer:  # the $Entities section may be long: read on in chunks
                chunk = f.read(1 << 20)
                if not chunk:
                    return None
                offset += len(buffer) - 16
                buffer = buffer[-16:] + chunk
            start = buffer.index(b"$Nodes") + len(b"$Nodes")
            f.seek(offset + start)
            rest = f.read(4096)
    except OSError:
        return None
    rest = rest.lstrip(b"\r\n")
    if version >= 4 and binary:
        return int(np.frombuffer(rest[:4 * size_t], dtype=f"<u{size_t}")[1])
    fields = rest.split()
    try:
        return int(fields[1] if version >= 4 else fields[0])
    except (IndexError, ValueError):
        return None


def xdmf_node_count(path: str | Path) -> int | None:
    """The node count of an XDMF file's 2D mesh grid (its Geometry's dimensions), None if not found."""
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return None
    for grid in root.iter("Grid"):
        if grid.find("Attribute") is not None:
            continue  # a grid of markers
        item = grid.find("Geometry/DataItem")
        if item is not None and item.get("Dimensions"):
            return int(item.get("Dimensions").split()[0])
    return None


def _file(scene: Scene) -> tuple[int | None, None, bool]:
    path = scene.geometry.path
    nodes = xdmf_node_count(path) if path.endswith(".xdmf") else msh_node_count(path)
    return nodes, None, True


# The estimate ------------------------------------------------------------------------------------------------
def _drivers(scene: Scene, memory: dict[str, int]) -> dict[str, Any]:
    """The keys that set the size, with their values: the mesh's, then the contact window's and the cycle's
    when W, its build or the cycle cache weigh a tenth of the total or more."""
    g, c = scene.geometry, scene.contact
    if g.kind == "half_cylinder":
        keys = {"geometry.contact_mesh_size": g.contact_mesh_size,
                "geometry.contact_half_width": g.refined_half_width,
                "geometry.coarse_mesh_size": g.coarse_mesh_size if g.coarse_mesh_size is not None else g.radius / 10}
    elif g.kind == "rectangle":
        keys = {"geometry.nx": g.nx, "geometry.ny": g.ny}
    elif g.kind == "sphere":
        keys = {"geometry.contact_mesh_size": g.contact_mesh_size if "contact_mesh_size" in g.model_fields_set
                else "a/4 (default)", "geometry.radius": g.radius, "geometry.half_model": g.half_model}
    else:
        keys = {"geometry.path": g.path}
    total = sum(memory.values())
    if memory.get("W", 0) + memory.get("W_build", 0) >= 0.1 * total:
        default = "the whole surface" if g.kind in ("rectangle", "file") else "automatic"
        keys["contact.candidate_half_width"] = c.candidate_half_width if c.candidate_half_width is not None \
            else default
    if memory.get("cycle_cache", 0) >= 0.1 * total:
        keys["loading.increments_per_cycle"] = scene.loading.increments_per_cycle
    return keys


def _plastic_zone_dofs(scene: Scene, contacts: int | None) -> tuple[int, bool]:
    """Dofs X of the plastic zone's dense algebra: the cells under the expected contact (2a wide, a deep, with
    ``plastic_zone.ZONE_MARGIN`` layers around) in each plastic body, and the contact's dofs; at most
    ``plastic_zone.MAX_ZONE_DOFS``, past which the body refactorises K_T instead (a second factor). A mesh file
    or a rectangle (no expected contact size): the cap. Returns (the zone's dofs, whether the cap is reached)."""
    from .plastic_zone import MAX_ZONE_DOFS, ZONE_MARGIN  # (numba, as the elastic-plastic run itself)

    g, dim = scene.geometry, scene.dim
    if g.kind not in ("half_cylinder", "sphere"):
        return MAX_ZONE_DOFS, True
    geometry = GEOMETRIES[g.kind]
    a = geometry.contact_size(scene)
    h = geometry.element_size(scene)
    across = 2 * a / h + 2 * ZONE_MARGIN + 1
    deep = a / h + ZONE_MARGIN + 1
    nodes = across * deep * ((across / 2 if g.half_model else across) if dim == 3 else 1)
    two_body = scene.contact.obstacle == "elastic_flat"
    bodies = 2 if two_body and scene.material.plastic_body == "both" else 1
    zone = bodies * nodes * dim + (contacts or 0) * dim
    return int(min(MAX_ZONE_DOFS, zone)), zone >= MAX_ZONE_DOFS


def _compiled_2d_cycles(scene: Scene, dim: int) -> bool:
    """The 2D compiled cycle loop runs (and keeps its per-increment pattern LU factors): see
    FrettingProblem.run_cycle (displacement or pressure control, Uzawa, elastic, kernel on, pattern reuse on)."""
    sv, lo = scene.solver, scene.loading
    return (dim == 2 and lo.cycles > 0 and sv.cycle_kernel and sv.pattern_reuse and sv.local_method == "uzawa"
            and scene.material.model == "elastic" and not lo.normal_force_controlled
            and not lo.tangential_force_controlled and scene.contact.sliding == "small")


def estimate(scene: Scene, ranks: int = 1) -> SizeEstimate:
    """Estimate the model of a validated scene before anything is built (pure: no mesh, no DOLFINx).

    Args:
        scene: The validated scene.
        ranks: MPI ranks that will run it (the memory terms are the whole machine's).

    Returns:
        The estimate; counts the geometry cannot give cheaply are None, with a ``note``.
    """
    g = scene.geometry
    dim = scene.dim
    counter = {"half_cylinder": _half_cylinder, "sphere": _sphere, "rectangle": _rectangle, "file": _file}[g.kind]
    nodes, contacts, exact = counter(scene)
    notes = []
    if nodes is None:
        notes.append(f"nodes not estimated (no node count in the header of {g.path})")
    if contacts is None:
        notes.append("contacts not estimated (a mesh file's surface is not read before meshing): W not counted")
    dofs = None if nodes is None else nodes * dim
    memory = {"baseline": ranks * BASELINE_BYTES}
    if dofs is not None:
        mesher = {"half_cylinder": "gmsh", "file": "gmsh", "rectangle": "rectangle", "sphere": "hexahedra"}[g.kind]
        memory["mesh"] = int(MESH_BYTES_PER_DOF[mesher] * dofs)
        one_factor = (FACTOR_BYTES_2D * dofs * math.log2(max(dofs, 2)) if dim == 2
                      else FACTOR_BYTES_3D * dofs ** (4.0 / 3.0))
        owned = ranks > 1 and scene.solver.delassus_method in ("auto", "owned")  # a whole factor on each rank
        memory["factor"] = int(one_factor * (1 + (ranks if owned else 0)))
        if scene.material.model == "elastoplastic":
            cell = "hexahedron" if dim == 3 else ("quadrilateral" if g.quadrilateral or g.kind == "file" else
                                                  "triangle")
            cells = nodes * (1 if cell != "triangle" else 2)
            zone, capped = _plastic_zone_dofs(scene, contacts)
            # the Gauss-point state, the zone's dense algebra, and K_T's own factor once the zone outgrows its cap
            memory["plastic"] = int(cells * _GAUSS_POINTS[cell] * PLASTIC_BYTES_PER_POINT
                                    + ZONE_BYTES_PER_DOF_SQUARED * zone**2 + (one_factor if capped else 0))
    if contacts is not None:
        m = contacts * dim
        # S: the dofs H touches: the slave's, and as many of the master's (two bodies)
        s = m * (2 if scene.contact.obstacle == "elastic_flat" else 1)
        memory["W"] = int(8 * m * m * (ranks + 1))  # W on every rank, and the compiled loop's transposed copy
        # the request pattern (int32 + float64), its CSR read-back (a copy), and the dense block of (K^-1)_SS
        memory["W_build"] = int(s * s * (12 + 12 + 8) + 8 * m * s)
        if scene.contact.sliding == "finite":
            # K^-1 on both surfaces, kept on every rank: the slave's dofs and the master's within reach (taken as
            # twice W's build set: the flat's nodes under the contact and under the stroke); its build replaces W's
            surface = 2 * s
            memory["surface_compliance"] = int(8 * surface * surface * ranks)
            memory["W_build"] = int(surface * surface * (12 + 12 + 8) + 8 * m * surface)
        if _compiled_2d_cycles(scene, dim):
            memory["cycle_cache"] = int(8 * m * m * scene.loading.increments_per_cycle)
    return SizeEstimate(g.kind, nodes, dofs, contacts, dim, ranks, exact, memory, _drivers(scene, memory),
                        "; ".join(notes))


# The machine -------------------------------------------------------------------------------------------------
def available_memory() -> tuple[int, str]:
    """Bytes of memory available to a new run, and where the number comes from.

    ``MemAvailable`` of ``/proc/meminfo`` (what can be allocated without swapping), lowered to the room left
    under a cgroup v2 limit (``memory.max - memory.current``) in a container; without ``/proc``,
    ``os.sysconf``'s available physical pages.
    """
    value, source = None, ""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                value, source = int(line.split()[1]) * 1024, "MemAvailable"
                break
    except OSError:
        pass
    if value is None:
        try:
            value = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
            source = "sysconf(SC_AVPHYS_PAGES)"
        except (ValueError, OSError, AttributeError):
            return 0, "unknown"
    try:
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        if limit != "max":
            room = int(limit) - int(Path("/sys/fs/cgroup/memory.current").read_text().strip())
            if room < value:
                value, source = room, "the cgroup's memory.max - memory.current"
    except (OSError, ValueError):
        pass
    return int(value), source


def check_size(scene: Scene, comm=None, ignore: bool = False) -> SizeEstimate:
    """Estimate the scene's model and refuse it if it exceeds the memory available. Collective if ``comm``.

    Args:
        scene: The validated scene.
        comm: The run's communicator (every rank must call): rank 0's reading of the available memory is
            broadcast, so every rank decides the same. None: this process alone.
        ignore: Return the estimate even if it does not fit (the CLI's ``--ignore-size``).

    Returns:
        The estimate.

    Raises:
        SizeError: the estimated peak exceeds the available memory (the message names the keys that drive
            the size, the estimate's terms, the memory available and how to override), on every rank.
    """
    ranks = 1 if comm is None else comm.size
    size = estimate(scene, ranks)
    available, source = available_memory()
    if comm is not None and comm.size > 1:
        available, source = comm.bcast((available, source), root=0)
    if ignore or available <= 0 or size.total_bytes <= available:
        return size
    keys = ", ".join(f"{k} = {v!r}" for k, v in size.drivers.items())
    raise SizeError(
        f"the model would need ~{_size(size.total_bytes)} of memory, more than the {_size(available)} available "
        f"({source}).\n  {size.describe()}\n  Its size is set by {keys}: coarsen the mesh (or narrow the "
        "window), or run anyway with --ignore-size (API: run_scene(..., ignore_size=True)).")
