"""The size of a scene's model before anything is meshed: nodes, dofs, contacts and memory.

:func:`estimate` counts what a validated :class:`~dolfinx_fretting.scenes.Scene` will build without importing
DOLFINx or building anything. The mesh is the geometry kind's to count (its ``mesh_size``,
:mod:`dolfinx_fretting.geometries`), from the same sizing rules its mesher uses:

* **nodes and dofs**: exact for the structured meshes (a rectangle, the sphere's hexahedra, the structured
  sectors under a half-cylinder's contact); for the rest of a half-cylinder or flat, meshed by gmsh with a size
  field, the node density ``c / s(d)^2`` integrated over the body, s the size field at distance d from the
  refined sector (h there, growing by ``growth`` per mm up to the coarse size) and c calibrated on gmsh's
  meshes (:data:`~dolfinx_fretting.geometries.gmsh_nodes.GMSH_NODE_DENSITY`); a mesh file: its node
  count read from the file's header.
* **contacts**: the nodes of the contact surface within the candidate window (exact on the structured contact
  zones).
* **memory** (bytes, the whole machine: every rank counted), one term per consumer:
  ``baseline`` (an interpreter with DOLFINx, PETSc and numba loaded, per rank), ``mesh`` (mesh, spaces, K,
  vectors, gmsh's own copy while it meshes: per dof), ``factor`` (the MUMPS factor of K: a nested-dissection
  fill model, ``n log2 n`` in 2D and ``n^(4/3)`` in 3D for n dofs, fitted to MUMPS's INFOG(22) on the built-in
  geometries; under MPI the ``owned`` route adds one whole factor per rank), ``schur_factor`` (when W is built
  by the Schur route, asked for or ``"auto"``'s choice by
  :func:`~dolfinx_fretting.delassus_routes.auto_route`, counted only where that peak fits in the memory
  available: its own factor of ``[[K, H^T], [H, 0]]``, alive beside K's while W is built,
  :data:`~dolfinx_fretting.delassus_routes.SCHUR_FACTOR_RATIO` times K's; its ``W_build`` is then the dense
  Schur complement's three copies), ``W`` (the dense Delassus matrix ``(nc dim)^2`` doubles, replicated on every rank,
  and the compiled loop's transposed copy), ``W_build`` (the
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

import math
from dataclasses import asdict, dataclass, field
from typing import Any

from .delassus_routes import SCHUR_FACTOR_RATIO, auto_route
from .geometries import GEOMETRIES, Geometry
from .geometries.base import MeshSize
from .geometries.gmsh_nodes import GMSH_NODE_DENSITY
from .geometries.mesh_file import msh_node_count, xdmf_node_count
from .memory import available_memory
from .scenes import Scene, SceneError

__all__ = ["SizeEstimate", "SizeError", "estimate", "available_memory", "check_size", "msh_node_count",
           "xdmf_node_count", "GMSH_NODE_DENSITY", "FACTOR_BYTES_2D", "FACTOR_BYTES_3D", "BASELINE_BYTES",
           "MESH_BYTES_PER_DOF"]

# Calibration (benchmarks/results/size_estimate.md has the measured points these come from) ------------------
# (gmsh's node density, GMSH_NODE_DENSITY, is the gmsh meshes' count: geometries/gmsh_nodes.py; the node counts
# of a mesh file's header, msh_node_count and xdmf_node_count: geometries/mesh_file.py. Both are re-exported.)
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
        sizing: How the geometry kind sized its contact zone from the scene (the sphere's uniform zone from the
            contact radius expected after wear), in words; "" if from the scene's keys alone.
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
    sizing: str = ""

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
        return text + (f"; {self.note}" if self.note else "") + (f"; {self.sizing}" if self.sizing else "")

    def as_dict(self) -> dict[str, Any]:
        """The estimate as JSON-ready data (``summary.json``'s ``size_estimate``), with ``total_bytes``."""
        return {**asdict(self), "total_bytes": self.total_bytes}


def _size(n: float) -> str:
    """Bytes in MB, GB or TB, three significant digits."""
    if n >= 1000 * _GB:
        return f"{n / 2**40:.3g} TB"
    return f"{n / _GB:.3g} GB" if n >= 0.1 * _GB else f"{n / 2**20:.3g} MB"


# The estimate ------------------------------------------------------------------------------------------------
def _drivers(scene: Scene, mesh: MeshSize, memory: dict[str, int]) -> dict[str, Any]:
    """The keys that set the size, with their values: the mesh's (the geometry kind's), then the contact window's
    and the cycle's when W, its build or the cycle cache weigh a tenth of the total or more."""
    keys = dict(mesh.drivers)
    total = sum(memory.values())
    if memory.get("W", 0) + memory.get("W_build", 0) >= 0.1 * total:
        window = scene.contact.candidate_half_width
        keys["contact.candidate_half_width"] = window if window is not None else mesh.window_default
    if memory.get("cycle_cache", 0) >= 0.1 * total:
        keys["loading.increments_per_cycle"] = scene.loading.increments_per_cycle
    return keys


def _plastic_zone_dofs(scene: Scene, geometry: Geometry, contacts: int | None) -> tuple[int, bool]:
    """Dofs X of the plastic zone's dense algebra: the cells under the expected contact (2a wide, a deep, with
    ``plastic_zone.ZONE_MARGIN`` layers around) in each plastic body, and the contact's dofs; at most
    ``plastic_zone.MAX_ZONE_DOFS``, past which the body refactorises K_T instead (a second factor). A mesh file
    or a rectangle (no expected contact size): the cap. Returns (the zone's dofs, whether the cap is reached)."""
    from .plastic_zone import MAX_ZONE_DOFS, ZONE_MARGIN  # lazy: plastic_zone imports numba, as only plastic runs do

    dim, a = scene.dim, geometry.contact_size(scene)
    if a is None:
        return MAX_ZONE_DOFS, True
    h = geometry.element_size(scene)
    across = 2 * a / h + 2 * ZONE_MARGIN + 1
    deep = a / h + ZONE_MARGIN + 1
    # 3D: the zone's width along y too, of which a half model holds its fraction
    nodes = across * deep * (across * geometry.model_fraction(scene) if dim == 3 else 1)
    two_body = scene.contact.obstacle == "elastic_flat"
    bodies = 2 if two_body and scene.material.plastic_body == "both" else 1
    zone = bodies * nodes * dim + (contacts or 0) * dim
    return int(min(MAX_ZONE_DOFS, zone)), zone >= MAX_ZONE_DOFS


def _compiled_2d_cycles(scene: Scene, dim: int) -> bool:
    """The 2D compiled cycle loop runs (and keeps its per-increment pattern LU factors): see
    FrettingProblem.run_cycle (displacement or pressure control, Uzawa, elastic, kernel on, pattern reuse on)."""
    sv, loading = scene.solver, scene.loading
    return (dim == 2 and loading.cycles > 0 and sv.cycle_kernel and sv.pattern_reuse and sv.local_method == "uzawa"
            and scene.material.model == "elastic" and not loading.normal_force_controlled
            and not loading.tangential_force_controlled and scene.contact.sliding == "small")


def _schur_route(scene: Scene, ranks: int, rows: int, dofs: int, schur_fits: bool) -> bool:
    """W is built by the Schur route (a second factor): asked for, or ``"auto"``'s choice for this size."""
    method = scene.solver.delassus_method
    # "schur" under MPI is refused before any build (compliance): no second factor to count
    return (ranks == 1 and method == "schur"
            or (method == "auto" and auto_route(ranks, rows, dofs, schur_fits) == "schur"))


def estimate(scene: Scene, ranks: int = 1, available: int | None = None) -> SizeEstimate:
    """Estimate the model of a validated scene before anything is built (pure: no mesh, no DOLFINx).

    Args:
        scene: The validated scene.
        ranks: MPI ranks that will run it (the memory terms are the whole machine's).
        available: Bytes of memory available (:func:`~dolfinx_fretting.memory.available_memory`), or None. Given,
            a W that ``"auto"`` would build by the Schur route is counted by the selected inverse when the Schur
            route's peak exceeds it. The build decides by its own reading (the second factor, 3 times K's measured
            one, against the memory available after K's factorisation:
            :func:`~dolfinx_fretting.delassus_routes.auto_route`'s ``schur_fits``), so near the limit the two may
            differ; the summary's ``delassus_method`` is the route taken.

    Returns:
        The estimate; counts the geometry cannot give cheaply are None, with a ``note``.
    """
    size = _estimate(scene, ranks, schur_fits=True)
    if (available is not None and 0 < available < size.total_bytes and "schur_factor" in size.memory
            and scene.solver.delassus_method == "auto"):
        return _estimate(scene, ranks, schur_fits=False)
    return size


def _estimate(scene: Scene, ranks: int, schur_fits: bool) -> SizeEstimate:
    """:func:`estimate` with ``"auto"``'s Schur route counted only if ``schur_fits``."""
    geometry = GEOMETRIES[scene.geometry.kind]
    dim = scene.dim
    mesh = geometry.mesh_size(scene)
    nodes, contacts = mesh.nodes, mesh.contacts
    dofs = None if nodes is None else nodes * dim
    memory = {"baseline": ranks * BASELINE_BYTES}
    if dofs is not None:
        memory["mesh"] = int(MESH_BYTES_PER_DOF[mesh.mesher] * dofs)
        one_factor = (FACTOR_BYTES_2D * dofs * math.log2(max(dofs, 2)) if dim == 2
                      else FACTOR_BYTES_3D * dofs ** (4.0 / 3.0))
        owned = ranks > 1 and scene.solver.delassus_method in ("auto", "owned")  # a whole factor on each rank
        memory["factor"] = int(one_factor * (1 + (ranks if owned else 0)))
        if contacts is not None and _schur_route(scene, ranks, contacts * dim, dofs, schur_fits):
            # the factor of [[K, H^T], [H, 0]], beside K's while W is built (the peak)
            memory["schur_factor"] = int(SCHUR_FACTOR_RATIO * one_factor)
        if scene.material.model == "elastoplastic":
            cell = mesh.cell
            cells = nodes * (1 if cell != "triangle" else 2)
            zone, capped = _plastic_zone_dofs(scene, geometry, contacts)
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
        if "schur_factor" in memory:
            # three dense m x m blocks at once: the factor's Schur block, PETSc's copy of it
            # (MatFactorCreateSchurComplement) and the package's copy, negated in place into W
            memory["W_build"] = 3 * 8 * m * m
        if scene.contact.sliding == "finite":
            # K^-1 on both surfaces, kept on every rank: the slave's dofs and the master's within reach (taken as
            # twice W's build set: the flat's nodes under the contact and under the stroke); its build replaces W's
            surface = 2 * s
            memory["surface_compliance"] = int(8 * surface * surface * ranks)
            memory["W_build"] = int(surface * surface * (12 + 12 + 8) + 8 * m * surface)
        if _compiled_2d_cycles(scene, dim):
            memory["cycle_cache"] = int(8 * m * m * scene.loading.increments_per_cycle)
    return SizeEstimate(scene.geometry.kind, nodes, dofs, contacts, dim, ranks, mesh.exact, memory,
                        _drivers(scene, mesh, memory), "; ".join(mesh.notes), mesh.sizing)


# The machine -------------------------------------------------------------------------------------------------
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
    available, source = available_memory()
    if comm is not None and comm.size > 1:
        available, source = comm.bcast((available, source), root=0)
    size = estimate(scene, ranks, available)
    if ignore or available <= 0 or size.total_bytes <= available:
        return size
    keys = ", ".join(f"{k} = {v!r}" for k, v in size.drivers.items())
    raise SizeError(
        f"the model would need ~{_size(size.total_bytes)} of memory, more than the {_size(available)} available "
        f"({source}).\n  {size.describe()}\n  Its size is set by {keys}: coarsen the mesh (or narrow the "
        "window), or run anyway with --ignore-size (API: run_scene(..., ignore_size=True)).")
