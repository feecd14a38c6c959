"""From a scene to what the public API takes: the data object :class:`SceneModel`, and the parts of the model
every geometry kind's ``build`` (:mod:`dolfinx_fretting.geometries`) is written with.

A kind's build meshes (or reads) the body and writes with these parts the user-side model a FEniCSx user would
write by hand (vector P1 space, the elasticity form, Dirichlet conditions, named loads) and how the contact is set
up (surface, obstacle, candidate window and its policy). The driver (``dolfinx_fretting.simulation``) reads
only the :class:`SceneModel` it gets: it has no branch on the geometry.

DOLFINx, UFL, PETSc and gmsh are imported inside the functions that use them: the geometry kinds import this
module, the scene schema and the size estimate import the kinds, and neither may load DOLFINx (a scene is
validated and sized before anything is built). The scene (``dolfinx_fretting.scenes.Scene``) is named in the
annotations, not imported: the schema sits above the kinds, which sit above this module.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
from mpi4py import MPI

from .contact import ElasticBody, RigidPlane
from .interrupts import keep_handlers
from .laws import EvolvingFriction
from .meshes import BODY_CELL_TAG, BodyMesh

__all__ = ["SceneModel", "FurtherZone", "further_zones", "elastic_model", "contact_surface", "rigid_plane",
           "elastic_flat", "pairing_text", "two_body_cells", "roller", "displacement_conditions", "boundary_pressure",
           "facet_length", "axis_normal", "read_msh", "read_xdmf", "MeshFileError", "check_file_exists", "PAIRING",
           "PRESSURE_LOAD", "BULK_STRESS_LOAD", "BOUNDARY_DISPLACEMENT", "BOUNDARY_PRESSURE"]

#: Name of the face-pressure load of a scene (``loading.tangential_pressure``), factor in MPa.
PRESSURE_LOAD = "face_pressure"
#: Name of the bulk-stress load of the fretting-fatigue rig (``geometry.kind = "pad_specimen"``, a unit tension
#: on the specimen's end), factor: ``loading.bulk_stress`` in MPa.
BULK_STRESS_LOAD = "bulk_stress"
#: Names of the ``[boundary]`` loads of a mesh file's scene (ramped with the preload, then held).
BOUNDARY_DISPLACEMENT = "boundary_displacement"
BOUNDARY_PRESSURE = "boundary_pressure"


@dataclass(frozen=True)
class FurtherZone:
    """A further contact zone of a scene (its second or later ``[[contact]]`` table) as the API takes it.

    Attributes:
        name: The surface's name (the mesh file's physical group).
        surface: ``(facet_tags, marker)`` of the surface.
        obstacle: The zone's rigid plane.
        mu: Its friction coefficient, or its evolving law (``mu_table``).
        window: Its candidate half-width (None: the whole surface).
        approach: The plane's approach along its normal, reached with the preload and held (mm).
    """

    name: str
    surface: tuple
    obstacle: RigidPlane
    mu: float | EvolvingFriction
    window: float | None
    approach: float


def further_zones(scene: Scene, body: BodyMesh) -> tuple[FurtherZone, ...]:
    """The scene's further contact zones on ``body`` (its named facet groups; the names checked before)."""
    return tuple(FurtherZone(zone.surface, (body.facet_tags, body.tags[zone.surface]),
                             RigidPlane(np.array(zone.plane_point), np.array(zone.plane_normal)), zone.friction_law(),
                             zone.candidate_half_width, zone.approach) for zone in scene.zones)


@dataclass
class SceneModel:
    """What the driver needs of a scene's geometry.

    Attributes:
        body: Mesh with named facet and cell tags.
        V: Vector P1 displacement space.
        form: Bilinear form of K (plane strain in 2D).
        bcs: Dirichlet conditions.
        surface: ``(facet_tags, marker)`` of the contact surface.
        obstacle: The rigid plane, or the elastic counter-body.
        loads: Named linear forms (the face pressure, factor = the pressure in MPa).
        element_size: Contact element size (one value: wear-step guard, window growth, sliding limit).
        window: Initial candidate half-width (None: the whole surface).
        window_limit: How far the window may grow (None: it may not).
        window_automatic: The window came from the Hertz estimate (not from the scene).
        window_edges_matter: The window's ends are not the body's edges: load there means a truncated contact.
        elastic_cells: Cells that stay elastic in an elastic–plastic run (the other body of a pair).
        display_cells: Cells drawn moved by the obstacle's reverse motion -D (two bodies: the paper's set-up,
            the cylinder moved and the flat held).
        hertz: (radius, E*, label) for a Hertz reference in the summary, or None.
        small_sliding: The pairing is fixed (two bodies): the run warns past half an element of slip.
        contact_text: How the contact is modelled, for the summary's ``modelled``.
        von_mises: UFL von Mises stress of a displacement (plane strain: with sigma_zz).
        timings: Wall times of the mesh.
        prescribed: Named sets of Dirichlet conditions with non-zero values (see ``FrettingProblem``).
        ramped: Loads and prescribed sets whose factor ramps from 0 to 1 with the normal preload, then stays 1.
        zones: The scene's further contact zones (:class:`FurtherZone`; a mesh file's ``[[contact]]`` tables after
            the first, which ``surface``, ``obstacle`` and ``window`` describe).
    """

    body: BodyMesh
    V: Any
    form: Any
    bcs: list
    surface: tuple
    obstacle: RigidPlane | ElasticBody
    loads: dict[str, Any]
    element_size: float
    window: float | None
    window_limit: float | None
    window_automatic: bool
    window_edges_matter: bool
    elastic_cells: np.ndarray | None
    display_cells: np.ndarray | None
    hertz: tuple[float, float, str] | None
    small_sliding: bool
    contact_text: str
    von_mises: Callable
    timings: dict[str, float] = field(default_factory=dict)
    prescribed: dict[str, list] = field(default_factory=dict)
    ramped: list[str] = field(default_factory=list)
    #: The fraction of the bodies the model holds (0.5: a half model about a symmetry plane): the scene's
    #: forces are the whole contact's, so a driver prescribes ``model_fraction`` times them and reports forces,
    #: energies and volumes divided by it.
    model_fraction: float = 1.0
    #: Tangential directions of the obstacle frame (1: t1, 2: t2) that the conditions hold on some contacts (the
    #: half model's roller on y = 0 holds t2): the API refuses a force along them, so a driver prescribes a zero
    #: displacement there when the scene's tangential load (along t1) is a force.
    held_tangential: tuple[int, ...] = ()
    zones: tuple[FurtherZone, ...] = ()


def _elasticity(scene: Scene, V, quadrature_degree: int | None):
    """The user's model: plane-strain linear elasticity and its von Mises stress."""
    import ufl  # lazy: see the module docstring

    from .materials import LinearElastic  # lazy: numba, which the schema's and the size estimate's imports avoid too

    lmbda, mu = LinearElastic(scene.material.E, scene.material.nu).lame
    gdim = V.mesh.geometry.dim
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    sigma = lambda w: lmbda * ufl.tr(eps(w)) * ufl.Identity(gdim) + 2.0 * mu * eps(w)  # noqa: E731
    # An elastic-plastic body integrates its stresses with a fixed rule: K then uses the same one, so that W
    # and the elastic iteration matrix are exact where nothing yields.
    dx = ufl.dx if quadrature_degree is None else ufl.dx(metadata={"quadrature_degree": quadrature_degree,
                                                                  "quadrature_scheme": "default"})
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    form = ufl.inner(sigma(u), eps(v)) * dx

    def von_mises(w):
        s = sigma(w)
        if gdim == 2:  # plane strain: sigma_zz = lambda tr(eps)
            szz = lmbda * ufl.tr(eps(w))
            mean = (ufl.tr(s) + szz) / 3.0
            dev = s - mean * ufl.Identity(2)
            return ufl.sqrt(1.5 * (ufl.inner(dev, dev) + (szz - mean) ** 2))
        dev = ufl.dev(s)
        return ufl.sqrt(1.5 * ufl.inner(dev, dev))

    return form, von_mises


def _clamped(V, body: BodyMesh, names: list[str]) -> list:
    from dolfinx import fem  # lazy: see the module docstring
    from petsc4py import PETSc

    fdim = V.mesh.topology.dim - 1
    zero = np.zeros(V.mesh.geometry.dim, dtype=PETSc.ScalarType)
    return [fem.dirichletbc(zero, fem.locate_dofs_topological(V, fdim, body.facets(name)), V) for name in names]


def _pressure_load(V, body: BodyMesh, face: str):
    """A unit pressure on a named face, pushing into the body (traction -n)."""
    import ufl  # lazy: see the module docstring

    ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=body.facet_tags)
    return -ufl.dot(ufl.FacetNormal(V.mesh), ufl.TestFunction(V)) * ds(body.tags[face])


#: How each sliding model pairs the two bodies, in the model's description.
PAIRING = {"small": "fixed pairing", "finite": "paired anew as the bodies slide"}


def pairing_text(obstacle: ElasticBody, dim: int) -> str:
    """How the two bodies are paired, for the run's description: the built master body's formulation and pairing
    (read from the object the contact uses, so the description cannot disagree with the model)."""
    if obstacle.formulation == "mortar":
        return f"dual mortar, {PAIRING[obstacle.sliding]}"
    return f"{'node-to-face' if dim == 3 else 'node-to-segment'}, {PAIRING[obstacle.sliding]}"


def elastic_flat(scene: Scene, body: BodyMesh, plane: RigidPlane, zone: float, h: float) -> ElasticBody:
    """The flat as the master body. Finite sliding reaches, from every cylinder (or ball) candidate, twice a
    prescribed stroke plus three elements (the relative slip stays below the stroke); under force control, whose
    stroke is not known beforehand, the refined zone (where the mesh is fine enough for contact at all)."""
    contact = scene.contact
    stroke = scene.loading.tangential_displacement
    reach = 2 * abs(stroke) + 3 * h if stroke is not None else zone
    return ElasticBody((body.facet_tags, body.tags["flat_top"]), plane.normal, sliding=contact.sliding,
                       repair_slip=contact.repair_slip, reach=reach, formulation=contact.formulation)


def two_body_cells(scene: Scene, body: BodyMesh, curved: str) -> tuple[np.ndarray, np.ndarray | None]:
    """The cells of a two-body mesh (regions ``curved`` and ``"flat"``): those drawn moved by the obstacle's reverse
    motion (the curved body), and those that stay elastic in an elastic-plastic run (the body that
    ``material.plastic_body`` does not name; None if both may yield)."""
    material = scene.material
    display_cells = body.cell_tags.find(body.regions[curved])
    elastic_cells = None
    if material.model == "elastoplastic" and material.plastic_body != "both":
        other = "flat" if material.plastic_body == "cylinder" else curved
        elastic_cells = body.cell_tags.find(body.regions[other])
    return display_cells, elastic_cells


def elastic_model(scene: Scene, body: BodyMesh, fixed: list[str]) -> tuple[Any, Any, Callable, list, dict[str, Any]]:
    """The user's model of a body: (V, the bilinear form of K, its von Mises stress, the faces ``fixed`` clamped,
    the face-pressure load of ``loading.tangential_pressure`` if the scene has one).

    Raises:
        ValueError: ``loading.pressure_face`` is not a face of the mesh.
    """
    from . import _dolfinx as dfx  # lazy: see the module docstring

    quadrature_degree = scene.solver.quadrature_degree
    if quadrature_degree is None and scene.material.model == "elastoplastic":
        quadrature_degree = 2  # 2 x 2 Gauss points per quadrilateral carry the plastic state
    V = dfx.vector_space(body.mesh)
    form, von_mises = _elasticity(scene, V, quadrature_degree)
    loads = {}
    if scene.loading.tangential_kind == "pressure":
        face = scene.loading.pressure_face
        if face not in body.tags:
            raise ValueError(f"loading.pressure_face = {face!r} is not a boundary of the mesh; allowed: "
                             f"{', '.join(sorted(body.tags))}")
        loads[PRESSURE_LOAD] = _pressure_load(V, body, face)
    return V, form, von_mises, _clamped(V, body, fixed), loads


def contact_surface(scene: Scene, body: BodyMesh) -> tuple:
    """``(facet_tags, marker)`` of ``contact.surface``.

    Raises:
        ValueError: the name is not a boundary of the mesh (the message lists those it has).
    """
    name = scene.contact.surface
    if name not in body.tags:
        raise ValueError(f"contact.surface = {name!r} is not a boundary of the {scene.geometry.kind} mesh; "
                         f"allowed: {', '.join(sorted(body.tags))}")
    return body.facet_tags, body.tags[name]


def rigid_plane(scene: Scene) -> RigidPlane:
    """The scene's rigid plane. Against an elastic flat this plane is the flat's top: its frame gives the directions
    of the flat's rigid motion D, so loads and total forces read as against a rigid plane."""
    return RigidPlane(np.array(scene.contact.plane_point), np.array(scene.contact.plane_normal))


def roller(V, facets: np.ndarray, axis: int):
    """A roller on a plane face normal to the coordinate ``axis``: the displacement component along it is zero."""
    from dolfinx import fem  # lazy: see the module docstring

    fdim = V.mesh.topology.dim - 1
    component, _ = V.sub(axis).collapse()
    dofs = fem.locate_dofs_topological((V.sub(axis), component), fdim, facets)
    return fem.dirichletbc(fem.Function(component), dofs, V.sub(axis))


def displacement_conditions(V, body: BodyMesh, displacements: dict[str, list[float]]) -> list:
    """Dirichlet conditions prescribing a displacement vector (mm) on each named face."""
    from dolfinx import fem  # lazy: see the module docstring

    gdim = body.mesh.geometry.dim
    fdim = gdim - 1
    conditions = []
    for name, vector in displacements.items():
        value = fem.Function(V)
        value.x.array.reshape(-1, V.dofmap.index_map_bs)[:, :gdim] = np.asarray(vector, dtype=float)
        conditions.append(fem.dirichletbc(value, fem.locate_dofs_topological(V, fdim, body.facets(name))))
    return conditions


def boundary_pressure(V, body: BodyMesh, pressures: dict[str, float]):
    """The load of pressures (MPa) on named faces, pushing into the body (traction -p n)."""
    import ufl  # lazy: see the module docstring

    ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=body.facet_tags)
    n, v = ufl.FacetNormal(V.mesh), ufl.TestFunction(V)
    return sum(-value * ufl.dot(n, v) * ds(body.tags[name]) for name, value in pressures.items())


class MeshFileError(ValueError):
    """A mesh file (``geometry.kind = "file"``) that cannot be the scene's body: missing, unreadable, of another
    dimension or of mixed cells, without the groups the scene names, or under loads its size makes implausible. Bad
    input: the message names the file (its absolute path) and the scene's key; the scene runner reports it as a
    scene error (the command line's exit code 2)."""


def check_file_exists(path: str, what: str = "geometry.path") -> Path:
    """The absolute path of a mesh file that exists, is a file and is not empty.

    Raises:
        MeshFileError: naming ``what`` and the absolute path.
    """
    resolved = Path(path).resolve()
    if not resolved.exists():
        raise MeshFileError(f"{what} = {str(resolved)!r}: no such file (a relative path is taken from the scene "
                            "file's folder, or given by --set, from the working directory)")
    if not resolved.is_file():
        raise MeshFileError(f"{what} = {str(resolved)!r}: a folder, not a mesh file")
    if resolved.stat().st_size == 0:
        raise MeshFileError(f"{what} = {str(resolved)!r}: the file is empty")
    return resolved


#: gmsh's names of the element types a 2D DOLFINx mesh may have (one of them per mesh), by gmsh type number.
_GMSH_CELLS = {2: "triangles", 3: "quadrilaterals", 9: "6-node triangles", 10: "9-node quadrilaterals",
               16: "8-node quadrilaterals", 21: "10-node triangles"}


def _msh_failure(path: str, gdim: int) -> str | None:
    """What makes the gmsh model just opened from ``path`` unfit for DOLFINx's reader (rank 0, gmsh open), or None:
    no mesh, elements of a higher dimension or nodes off the plane z = 0, no physical group of cells or of
    boundary curves, cells of several types in the physical groups (DOLFINx's mesh has one cell type, and its
    reader crashes on a mix), two groups of one dimension with the same name."""
    import gmsh  # lazy: see the module docstring

    where = f"geometry.path = {path!r}"
    _, xyz, _ = gmsh.model.mesh.getNodes()
    if len(xyz) == 0:
        return f"{where}: holds no mesh nodes (not a gmsh .msh file, or the model was saved before meshing)"
    x = np.asarray(xyz).reshape(-1, 3)
    solid = [gmsh.model.mesh.getElementProperties(t)[0] for t in gmsh.model.mesh.getElementTypes(dim=gdim + 1)]
    extent = float(np.ptp(x, axis=0).max())
    if solid or (gdim == 2 and np.ptp(x[:, 2]) > 1e-9 * max(extent, 1e-300)):
        found = f"{', '.join(solid)} cells" if solid else f"nodes at z from {x[:, 2].min():g} to {x[:, 2].max():g}"
        return (f"{where}: a 3D mesh ({found}); the scene runner takes 2D meshes in the plane z = 0 (3D models run "
                "through the Python API, dolfinx_fretting.FrettingProblem)")
    groups = gmsh.model.getPhysicalGroups()
    for dim, kind in ((gdim, "surface (the body's cells)"), (gdim - 1, "curve (boundaries)")):
        if not any(d == dim for d, _ in groups):
            return (f"{where}: the file has no physical {kind} group; DOLFINx reads the cells and facets of "
                    "physical groups only (gmsh: Physical Surface and Physical Curve, with names)")
    types: dict[int, int] = {}
    for _, tag in [g for g in groups if g[0] == gdim]:
        for entity in gmsh.model.getEntitiesForPhysicalGroup(gdim, tag):
            element_types, element_tags, _ = gmsh.model.mesh.getElements(gdim, entity)
            for kind, tags in zip(element_types, element_tags):
                types[int(kind)] = types.get(int(kind), 0) + len(tags)
    if len(types) > 1:
        mix = " and ".join(f"{n} {_GMSH_CELLS.get(t, gmsh.model.mesh.getElementProperties(t)[0])}"
                           for t, n in sorted(types.items()))
        return (f"{where}: the body mixes {mix}; a DOLFINx mesh has one cell type: mesh it with triangles only, or "
                "with quadrilaterals only (gmsh: Mesh.RecombineAll = 1 and recombine every surface)")
    for dim in (gdim - 1, gdim):
        names = [gmsh.model.getPhysicalName(d, tag) or str(tag) for d, tag in groups if d == dim]
        repeated = sorted({name for name in names if names.count(name) > 1})
        if repeated:
            tags = [tag for d, tag in groups if d == dim and (gmsh.model.getPhysicalName(d, tag) or str(tag))
                    == repeated[0]]
            return (f"{where}: the name {repeated[0]!r} is given to {len(tags)} physical groups of dimension {dim} "
                    f"(tags {', '.join(map(str, tags))}); a scene names each group once: rename them or merge them")
    return None


def read_msh(path: str, comm: MPI.Comm, gdim: int = 2) -> tuple[BodyMesh, dict[str, int]]:
    """A gmsh ``.msh`` file as a :class:`~dolfinx_fretting.meshes.BodyMesh` (facet tags = its physical curves in
    2D). Collective.

    The file is read on rank 0 and checked there before DOLFINx sees it (:class:`MeshFileError` on every rank: no
    such file, a folder, empty, no mesh, 3D, no physical groups, mixed cell types, a name given to two groups); the
    physical names (not carried by DOLFINx's reader) are read there too and broadcast. Returns the body (facet
    names in ``tags``) and the names of the cell groups.
    """
    from . import _dolfinx as dfx  # lazy: see the module docstring

    with keep_handlers():  # gmsh 4.8 sets SIGINT to its default action (kill, no clean-up) when imported
        import gmsh  # lazy: see the module docstring

    names = failure = None
    if comm.rank == 0:
        try:
            path = str(check_file_exists(path))
        except MeshFileError as exc:
            failure = str(exc)
        if failure is None:
            with keep_handlers():  # ... and gmsh 4.11+ when initialised: a run's handlers stay
                gmsh.initialize(readConfigFiles=False)  # no user gmshrc: the file read the same on every machine
            gmsh.option.setNumber("General.Terminal", 0)
            try:
                gmsh.open(path)
                failure = _msh_failure(path, gdim)
                groups = gmsh.model.getPhysicalGroups()
                names = {dim: {gmsh.model.getPhysicalName(dim, tag) or str(tag): tag for d, tag in groups if d == dim}
                         for dim in (gdim - 1, gdim)}
            except Exception as exc:  # noqa: BLE001 - gmsh raises plain Exceptions with its log
                failure = f"geometry.path = {path!r}: gmsh cannot read it ({exc})"
            if failure is not None:
                with keep_handlers():  # finalize restores the handler gmsh found (not necessarily the run's)
                    gmsh.finalize()
    names, failure = comm.bcast((names, failure), root=0)
    if failure is not None:
        raise MeshFileError(failure)
    try:
        msh, cell_tags, facet_tags = dfx.model_to_mesh(gmsh.model, comm, 0, gdim)
    finally:
        if comm.rank == 0:
            with keep_handlers():
                gmsh.finalize()
    body = BodyMesh(msh, facet_tags, cell_tags, dict(names[gdim - 1]), 0.0, None, {}, dict(names[gdim]))
    return body, names[gdim]


#: XDMF topology types of the cells of a 2D mesh and of its facets.
_XDMF_CELLS_2D, _XDMF_FACETS_2D = ("Triangle", "Quadrilateral"), ("PolyLine",)


def _xdmf_grids(path: str) -> list[tuple[str, str, bool]]:
    """(name, topology type, has an attribute) of every grid of an XDMF file (its XML alone)."""
    grids = []
    for grid in ET.parse(path).getroot().iter("Grid"):
        topology = grid.find("Topology")
        if topology is None or grid.get("GridType") == "Collection":
            continue
        grids.append((grid.get("Name", ""), topology.get("TopologyType", topology.get("Type", "")),
                      grid.find("Attribute") is not None))
    return grids


def _xdmf_missing_data(path: str) -> str | None:
    """The first HDF5 data file an XDMF file names (``DataItem Format="HDF"``: ``file.h5:/dataset``, relative to the
    XDMF file's folder) that does not exist, as an absolute path; None if all exist."""
    folder = Path(path).parent
    for item in ET.parse(path).getroot().iter("DataItem"):
        if item.get("Format", "").upper() == "HDF" and item.text and ":" in item.text:
            data = (folder / item.text.strip().split(":", 1)[0]).resolve()
            if not data.is_file():
                return str(data)
    return None


def read_xdmf(path: str, comm: MPI.Comm, groups: dict[str, int] | None = None) -> tuple[BodyMesh, dict[str, int]]:
    """A DOLFINx XDMF mesh with its facet meshtags as a :class:`~dolfinx_fretting.meshes.BodyMesh`. Collective.

    The file holds one 2D mesh grid and one grid of facet markers (as ``XDMFFile.write_mesh`` and
    ``write_meshtags`` write them); the grids are found by their topology. XDMF carries no names for the marker
    values: ``groups`` names them (``{"face": 1, "top": 2}``); a value not named there is called by its number
    (``"3"``). Returns the body and the names of the cell groups (all cells one group ``"body"`` unless the file
    has cell markers).
    """
    from dolfinx import mesh as dmesh  # lazy: see the module docstring
    from dolfinx.io import XDMFFile

    found = failure = None
    if comm.rank == 0:
        try:
            path = str(check_file_exists(path))
            grids = _xdmf_grids(path)
            meshes = [g for g in grids if g[1] in _XDMF_CELLS_2D and not g[2]]
            facets = [g for g in grids if g[1] in _XDMF_FACETS_2D and g[2]]
            cells = [g for g in grids if g[1] in _XDMF_CELLS_2D and g[2]]
            listing = ", ".join(f"{n!r} ({t}{', markers' if a else ''})" for n, t, a in grids) or "none"
            if len(meshes) != 1 or len(facets) != 1:
                failure = (f"geometry.path = {path!r}: needs one 2D mesh grid and one grid of facet markers "
                           f"(XDMFFile.write_mesh and write_meshtags); the file holds: {listing}")
            else:
                found = (meshes[0][0], facets[0][0], cells[0][0] if len(cells) == 1 else None)
                missing = _xdmf_missing_data(path)
                if missing:
                    failure = (f"geometry.path = {path!r}: its data file {missing!r} is missing (an XDMF file keeps "
                               "its arrays in the .h5 file written beside it: copy both)")
        except MeshFileError as exc:
            failure = str(exc)
        except (OSError, ValueError) as exc:  # ValueError covers xml.etree's ParseError
            failure = f"geometry.path = {path!r}: not a readable XDMF file ({exc})"
    found, failure = comm.bcast((found, failure), root=0)
    if failure is not None:
        raise MeshFileError(failure)
    path = str(Path(path).resolve())
    mesh_name, facet_name, cell_name = found
    with XDMFFile(comm, path, "r") as xdmf:
        msh = xdmf.read_mesh(name=mesh_name)
        tdim = msh.topology.dim
        if msh.geometry.dim != 2:  # a 2D mesh written with three coordinates: the plane-strain forms need two
            raise MeshFileError(f"geometry.path = {path!r}: the mesh has {msh.geometry.dim} coordinates; the scene "
                             "runner takes 2D meshes with 2 (3D models run through the Python API)")
        msh.topology.create_connectivity(tdim - 1, tdim)
        facet_tags = xdmf.read_meshtags(msh, facet_name)
        cell_tags = xdmf.read_meshtags(msh, cell_name) if cell_name is not None else None
    if cell_tags is None:
        cells = np.arange(msh.topology.index_map(tdim).size_local, dtype=np.int32)
        cell_tags = dmesh.meshtags(msh, tdim, cells, np.full(cells.size, BODY_CELL_TAG, dtype=np.int32))
        regions = {"body": BODY_CELL_TAG}
    else:
        values = np.unique(np.concatenate(comm.allgather(np.asarray(cell_tags.values))))
        regions = {str(v): int(v) for v in values}
    values = np.unique(np.concatenate(comm.allgather(np.asarray(facet_tags.values))))
    names = {str(int(v)): int(v) for v in values}
    for name, value in (groups or {}).items():
        if value not in values:
            raise MeshFileError(f"geometry.groups.{name} = {value} is not a facet marker of {path}; its markers: "
                             f"{', '.join(str(int(v)) for v in values) or 'none'}")
        names.pop(str(value), None)
        names[name] = int(value)
    body = BodyMesh(msh, facet_tags, cell_tags, names, 0.0, None, {}, regions)
    return body, regions


def facet_length(V, facets: np.ndarray) -> float:
    """Median length of the owned facets of a 2D boundary (the contact element size of a user's mesh)."""
    msh = V.mesh
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, 0)
    owned = facets[facets < msh.topology.index_map(fdim).size_local]
    from . import _dolfinx as dfx  # lazy: see the module docstring

    nodes = dfx.entities_to_geometry(msh, fdim, owned)
    x = msh.geometry.x
    lengths = np.linalg.norm(x[nodes[:, 1]] - x[nodes[:, 0]], axis=1) if owned.size else np.zeros(0)
    everything = np.concatenate(msh.comm.allgather(lengths))
    return float(np.median(everything))


def axis_normal(V, facets: np.ndarray, name: str) -> int:
    """The coordinate axis normal to a plane boundary (for a roller condition on one component)."""
    msh = V.mesh
    fdim = msh.topology.dim - 1
    from . import _dolfinx as dfx  # lazy: see the module docstring

    owned = facets[facets < msh.topology.index_map(fdim).size_local]
    x = msh.geometry.x[dfx.entities_to_geometry(msh, fdim, owned).ravel(), :msh.geometry.dim] if owned.size else \
        np.zeros((0, msh.geometry.dim))
    points = np.concatenate(msh.comm.allgather(x))
    spread = np.ptp(points, axis=0) if points.size else np.zeros(msh.geometry.dim)
    scale = max(spread.max(initial=0.0), 1e-300)
    flat = np.flatnonzero(spread <= 1e-9 * scale)
    if flat.size != 1:
        raise ValueError(f"boundary.symmetry = {name!r}: the face is not a plane normal to a coordinate axis (its "
                         f"extents are {spread.tolist()}); a roller on an oblique face is not supported")
    return int(flat[0])

