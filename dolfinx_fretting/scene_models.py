"""From a scene's geometry to what the public API takes: one builder per geometry, one data object out.

Each builder meshes (or reads) the body, writes the user-side model a FEniCSx user would write by hand
(vector P1 space, the elasticity form, Dirichlet conditions, named loads) and says how the contact is set up
(surface, obstacle, candidate window and its policy). The driver (:mod:`dolfinx_fretting.simulation`) reads
only the :class:`SceneModel` it gets: it has no branch on the geometry.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
from mpi4py import MPI

from .contact import ElasticBody, RigidPlane
from .meshes import BODY_CELL_TAG, BodyMesh
from .scenes import Scene

__all__ = ["SceneModel", "build_scene_model", "read_msh", "read_xdmf", "PRESSURE_LOAD", "BOUNDARY_DISPLACEMENT",
           "BOUNDARY_PRESSURE"]

#: Name of the face-pressure load of a scene (``loading.tangential_pressure``), factor in MPa.
PRESSURE_LOAD = "face_pressure"
#: Names of the ``[boundary]`` loads of a mesh file's scene (ramped with the preload, then held).
BOUNDARY_DISPLACEMENT = "boundary_displacement"
BOUNDARY_PRESSURE = "boundary_pressure"


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


def _elasticity(scene: Scene, V, quadrature_degree: int | None):
    """The user's model: plane-strain linear elasticity and its von Mises stress."""
    import ufl

    from .materials import LinearElastic

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
    from dolfinx import fem
    from petsc4py import PETSc

    fdim = V.mesh.topology.dim - 1
    zero = np.zeros(V.mesh.geometry.dim, dtype=PETSc.ScalarType)
    return [fem.dirichletbc(zero, fem.locate_dofs_topological(V, fdim, body.facets(name)), V) for name in names]


def _pressure_load(V, body: BodyMesh, face: str):
    """A unit pressure on a named face, pushing into the body (traction -n)."""
    import ufl

    ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=body.facet_tags)
    return -ufl.dot(ufl.FacetNormal(V.mesh), ufl.TestFunction(V)) * ds(body.tags[face])


def expected_contact_size(scene: Scene) -> float:
    """The contact half-width (cylinder) or radius (sphere) a built-in geometry expects (mm), before any mesh.

    Hertz under a normal force; under an approach d, the geometric ``sqrt(2 R d)`` (cylinder) or ``sqrt(R d)``
    (sphere; against the flat the two bodies share d, ``sqrt(R d / 2)`` is then an underestimate by 2^(1/2) of
    nothing: the mesh's uniform zone (1.5 a) holds either).
    """
    from .analytic import hertz_line_contact
    from .analytic import hertz_sphere

    g, lo = scene.geometry, scene.loading
    sphere = g.kind == "sphere"
    if lo.normal_force is not None:
        return float((hertz_sphere if sphere else hertz_line_contact)(lo.normal_force, g.radius,
                                                                       scene.contact_modulus)[0])
    return float(np.sqrt((1.0 if sphere else 2.0) * g.radius * lo.normal_displacement))


def sphere_mesh_size(scene: Scene) -> float:
    """The edge h (mm) of a sphere's cubes under the contact: ``geometry.contact_mesh_size`` if the scene sets
    it, else a quarter of the expected contact radius a; at most a."""
    g = scene.geometry
    a = expected_contact_size(scene)
    h = g.contact_mesh_size if "contact_mesh_size" in g.model_fields_set else a / 4.0
    return min(h, a)


def candidate_window(scene: Scene, zone: float, h: float) -> tuple[float, bool]:
    """The initial candidate half-width (mm) of a half-cylinder or sphere scene, and whether it is automatic.

    Automatic for elastic bodies without ``contact.candidate_half_width`` (an elastic-plastic body cannot grow
    its window, and plasticity widens the contact beyond the elastic estimate, so it keeps the refined zone):
    ``1.5 a + 3 h`` with a from :func:`expected_contact_size`, at most the refined ``zone``. Finite sliding
    cannot grow its window either (its surface compliance is built for one): the zone, or the given width if
    wider.

    Args:
        scene: The scene.
        zone: Half-width of the mesh's refined (uniform) contact zone (mm).
        h: Contact element size (mm).
    """
    given = scene.contact.candidate_half_width
    if scene.contact.sliding == "finite":  # the surface compliance is built for one window: the whole zone
        return float(max(zone, given or 0.0)), False
    automatic = given is None and scene.material.model == "elastic"
    if automatic:
        return float(min(zone, 1.5 * expected_contact_size(scene) + 3 * h)), True
    return (given if given is not None else zone), False


def build_scene_model(scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD, *,
                      applies_model_fraction: bool = False) -> SceneModel:
    """Mesh the scene's geometry and write its model. Collective.

    Args:
        scene: The validated scene.
        comm: Communicator of the mesh.
        applies_model_fraction: The caller prescribes :attr:`SceneModel.model_fraction` times the scene's forces
            and divides the totals it reports by it. A model of a fraction of the bodies (a half model) is refused
            to a caller that does not: its forces would be the whole contact's on half of it.

    Raises:
        ValueError: a name of the scene is not in the mesh (the message lists the names it holds), or a half
            model for a caller that does not apply its fraction.
    """
    g = scene.geometry
    if g.kind == "sphere" and g.half_model and not applies_model_fraction:
        raise ValueError("geometry.half_model = true: this caller does not scale the scene's forces to the half "
                         "model (SceneModel.model_fraction = 0.5) yet; run the whole sphere with "
                         "geometry.half_model = false, or build the model with applies_model_fraction=True")
    return _BUILDERS[g.kind](scene, comm)


def _half_cylinder(scene: Scene, comm: MPI.Comm) -> SceneModel:
    """A half-cylinder on a rigid plane, or on an elastic flat (two bodies, one mesh)."""
    from . import meshes

    g, m = scene.geometry, scene.material
    two_body = scene.contact.obstacle == "elastic_flat"
    t0 = time.perf_counter()
    build = meshes.cylinder_on_flat if two_body else meshes.half_cylinder
    extra = (g.flat_width, g.flat_height) if two_body else ()
    body = build(comm, g.radius, *extra, contact_mesh_size=g.contact_mesh_size,
                 contact_half_width=g.refined_half_width, coarse_mesh_size=g.coarse_mesh_size,
                 quadrilateral=g.quadrilateral)
    mesh_s = time.perf_counter() - t0
    V, form, von_mises, bcs, loads = _model(scene, body, ["top", "flat_bottom"] if two_body else ["top"])
    plane = _plane(scene, body)
    E_star = scene.contact_modulus
    window, automatic = candidate_window(scene, g.refined_half_width, g.contact_mesh_size)
    elastic_cells = display_cells = None
    if two_body:
        obstacle = _elastic_flat(scene, body, plane, g.refined_half_width, g.contact_mesh_size)
        display_cells = body.cell_tags.find(body.regions["cylinder"])
        if m.model == "elastoplastic" and m.plastic_body != "both":
            other = "flat" if m.plastic_body == "cylinder" else "cylinder"
            elastic_cells = body.cell_tags.find(body.regions[other])
    else:
        obstacle = plane
    label = ("two identical elastic bodies: E* = E/(2(1-nu^2))" if two_body
             else "rigid plane, frictionless: E* = E/(1-nu^2)")
    text = f", each paired with a point of the elastic flat (node-to-segment, {_PAIRING[scene.contact.sliding]})" \
        if two_body else ", against a rigid plane"
    return SceneModel(body, V, form, bcs, _surface(scene, body), obstacle, loads, g.contact_mesh_size, window,
                      g.refined_half_width, automatic, True, elastic_cells, display_cells,
                      (g.radius, E_star, label), two_body and scene.contact.sliding == "small", text, von_mises,
                      {"mesh_s": mesh_s})


def _sphere(scene: Scene, comm: MPI.Comm) -> SceneModel:
    """A sphere's cap on an elastic flat of the same material (two bodies, one mesh) or on a rigid plane, 3D:
    structured hexahedra sized from the Hertz contact radius (:func:`~dolfinx_fretting.meshes_3d.sphere_on_flat`),
    a half model about y = 0 by default (a roller there)."""
    from dolfinx import fem

    from .meshes_3d import sphere_on_flat

    g, m = scene.geometry, scene.material
    two_body = scene.contact.obstacle == "elastic_flat"
    a = expected_contact_size(scene)
    h = sphere_mesh_size(scene)
    t0 = time.perf_counter()
    body = sphere_on_flat(comm, g.radius, a, h, half=g.half_model, flat=two_body)
    mesh_s = time.perf_counter() - t0
    V, form, von_mises, bcs, loads = _model(scene, body, ["top", "flat_bottom"] if two_body else ["top"])
    if g.half_model:  # the symmetry plane y = 0: a roller (u_y = 0) on both bodies' faces there
        V_y, _ = V.sub(1).collapse()
        faces = np.concatenate([body.facets(n) for n in body.tags if n.endswith("symmetry")])
        bcs.append(fem.dirichletbc(fem.Function(V_y), fem.locate_dofs_topological((V.sub(1), V_y), 2, faces),
                                   V.sub(1)))
    plane = _plane(scene, body)
    zone = body.contact_half_width
    window, automatic = candidate_window(scene, zone, h)
    elastic_cells = display_cells = None
    if two_body:
        obstacle = _elastic_flat(scene, body, plane, zone, h)
        display_cells = body.cell_tags.find(body.regions["sphere"])
        if m.model == "elastoplastic" and m.plastic_body != "both":
            other = "flat" if m.plastic_body == "cylinder" else "sphere"
            elastic_cells = body.cell_tags.find(body.regions[other])
    else:
        obstacle = plane
    text = (f", each paired with the closest point of the elastic flat's faces (node-to-face, "
            f"{_PAIRING[scene.contact.sliding]})" if two_body else ", against a rigid plane") \
        + (", half model (roller on y = 0)" if g.half_model else "")
    # hertz = None: the driver's reference is the line contact's; the sphere's is analytic.hertz_sphere.
    return SceneModel(body, V, form, bcs, _surface(scene, body), obstacle, loads, h, window, zone, automatic, True,
                      elastic_cells, display_cells, None, two_body and scene.contact.sliding == "small", text,
                      von_mises, {"mesh_s": mesh_s},
                      model_fraction=0.5 if g.half_model else 1.0, held_tangential=(2,) if g.half_model else ())


#: How each sliding model pairs the two bodies, in the model's description.
_PAIRING = {"small": "fixed pairing", "finite": "paired anew as the bodies slide"}


def _elastic_flat(scene: Scene, body, plane, zone: float, h: float) -> ElasticBody:
    """The flat as the master body. Finite sliding reaches, from every cylinder (or ball) candidate, twice a
    prescribed stroke plus three elements (the relative slip stays below the stroke); under force control, whose
    stroke is not known beforehand, the refined zone (where the mesh is fine enough for contact at all)."""
    c, lo = scene.contact, scene.loading
    stroke = lo.tangential_displacement
    reach = 2 * abs(stroke) + 3 * h if stroke is not None else zone
    return ElasticBody((body.facet_tags, body.tags["flat_top"]), plane.normal, sliding=c.sliding,
                       repair_slip=c.repair_slip, reach=reach)


def _rectangle(scene: Scene, comm: MPI.Comm) -> SceneModel:
    """A block on a rigid plane (the paper's Example 1), its top fixed."""
    from . import meshes

    g = scene.geometry
    t0 = time.perf_counter()
    body = meshes.rectangle(comm, g.width, g.height, g.nx, g.ny, quadrilateral=g.quadrilateral)
    mesh_s = time.perf_counter() - t0
    V, form, von_mises, bcs, loads = _model(scene, body, ["top"])
    window = scene.contact.candidate_half_width
    return SceneModel(body, V, form, bcs, _surface(scene, body), _plane(scene, body), loads, body.contact_mesh_size,
                      window, None, False, False, None, None, None, False, ", against a rigid plane", von_mises,
                      {"mesh_s": mesh_s})


def _model(scene: Scene, body: BodyMesh, fixed: list[str]):
    from . import _dolfinx as dfx

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


def _surface(scene: Scene, body: BodyMesh) -> tuple:
    name = scene.contact.surface
    if name not in body.tags:
        raise ValueError(f"contact.surface = {name!r} is not a boundary of the {scene.geometry.kind} mesh; "
                         f"allowed: {', '.join(sorted(body.tags))}")
    return body.facet_tags, body.tags[name]


def _plane(scene: Scene, body: BodyMesh) -> RigidPlane:
    # Against an elastic flat this plane is the flat's top: its frame gives the directions of the flat's rigid
    # motion D, so loads and total forces read as against a rigid plane.
    return RigidPlane(np.array(scene.contact.plane_point), np.array(scene.contact.plane_normal))


def read_msh(path: str, comm: MPI.Comm, gdim: int = 2) -> tuple[BodyMesh, dict[str, int]]:
    """A gmsh ``.msh`` file as a :class:`BodyMesh` (facet tags = its physical curves in 2D). Collective.

    The file is read on rank 0; the physical names (not carried by DOLFINx's reader) are read there too and
    broadcast. Returns the body (facet names in ``tags``) and the names of the cell groups.
    """
    from . import _dolfinx as dfx

    import gmsh

    names = failure = None
    if comm.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        try:
            gmsh.open(path)
            groups = gmsh.model.getPhysicalGroups()
            names = {dim: {gmsh.model.getPhysicalName(dim, tag) or str(tag): tag for d, tag in groups if d == dim}
                     for dim in (gdim - 1, gdim)}
        except Exception as exc:  # noqa: BLE001 - gmsh raises plain Exceptions with its log
            failure = f"geometry.path = {path!r}: gmsh cannot read it ({exc})"
            gmsh.finalize()
    names, failure = comm.bcast((names, failure), root=0)
    if failure is not None:
        raise ValueError(failure)
    try:
        msh, cell_tags, facet_tags = dfx.model_to_mesh(gmsh.model, comm, 0, gdim)
    finally:
        if comm.rank == 0:
            gmsh.finalize()
    if msh.geometry.dim != gdim:
        raise ValueError(f"geometry.path = {path!r}: a {msh.geometry.dim}D mesh; the scene runner takes 2D meshes "
                         "(3D models run through the Python API, dolfinx_fretting.FrettingProblem)")
    body = BodyMesh(msh, facet_tags, cell_tags, dict(names[gdim - 1]), 0.0, None, {}, dict(names[gdim]))
    return body, names[gdim]


#: XDMF topology types of the cells of a 2D mesh and of its facets.
_XDMF_CELLS_2D, _XDMF_FACETS_2D = ("Triangle", "Quadrilateral"), ("PolyLine",)


def _xdmf_grids(path: str) -> list[tuple[str, str, bool]]:
    """(name, topology type, has an attribute) of every grid of an XDMF file (its XML alone)."""
    import xml.etree.ElementTree as ET

    grids = []
    for grid in ET.parse(path).getroot().iter("Grid"):
        topology = grid.find("Topology")
        if topology is None or grid.get("GridType") == "Collection":
            continue
        grids.append((grid.get("Name", ""), topology.get("TopologyType", topology.get("Type", "")),
                      grid.find("Attribute") is not None))
    return grids


def read_xdmf(path: str, comm: MPI.Comm, groups: dict[str, int] | None = None) -> tuple[BodyMesh, dict[str, int]]:
    """A DOLFINx XDMF mesh with its facet meshtags as a :class:`BodyMesh`. Collective.

    The file holds one 2D mesh grid and one grid of facet markers (as ``XDMFFile.write_mesh`` and
    ``write_meshtags`` write them); the grids are found by their topology. XDMF carries no names for the marker
    values: ``groups`` names them (``{"face": 1, "top": 2}``); a value not named there is called by its number
    (``"3"``). Returns the body and the names of the cell groups (all cells one group ``"body"`` unless the file
    has cell markers).
    """
    from dolfinx import mesh as dmesh
    from dolfinx.io import XDMFFile

    found = failure = None
    if comm.rank == 0:
        try:
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
        except (OSError, ValueError) as exc:  # ValueError covers xml.etree's ParseError
            failure = f"geometry.path = {path!r}: not a readable XDMF file ({exc})"
    found, failure = comm.bcast((found, failure), root=0)
    if failure is not None:
        raise ValueError(failure)
    mesh_name, facet_name, cell_name = found
    with XDMFFile(comm, path, "r") as xdmf:
        msh = xdmf.read_mesh(name=mesh_name)
        tdim = msh.topology.dim
        if msh.geometry.dim != 2:  # a 2D mesh written with three coordinates: the plane-strain forms need two
            raise ValueError(f"geometry.path = {path!r}: the mesh has {msh.geometry.dim} coordinates; the scene "
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
            raise ValueError(f"geometry.groups.{name} = {value} is not a facet marker of {path}; its markers: "
                             f"{', '.join(str(int(v)) for v in values) or 'none'}")
        names.pop(str(value), None)
        names[name] = int(value)
    body = BodyMesh(msh, facet_tags, cell_tags, names, 0.0, None, {}, regions)
    return body, regions


def _check_names(scene: Scene, facet_names: dict[str, int]) -> None:
    """Every boundary name the scene uses must be a physical group of the file (before any work)."""
    used = [("contact.surface", scene.contact.surface), *scene.boundary.names]
    if scene.loading.tangential_kind == "pressure":
        used.append(("loading.pressure_face", scene.loading.pressure_face))
    for key, name in used:
        if name not in facet_names:
            raise ValueError(f"{key} = {name!r} is not a physical group of {scene.geometry.path}; the file's "
                             f"boundary groups: {', '.join(sorted(facet_names)) or 'none'}"
                             + (" (an XDMF file's markers are named by geometry.groups, else by their numbers)"
                                if scene.geometry.path.endswith(".xdmf") else ""))


def _facet_length(V, facets: np.ndarray) -> float:
    """Median length of the owned facets of a 2D boundary (the contact element size of a user's mesh)."""
    msh = V.mesh
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, 0)
    owned = facets[facets < msh.topology.index_map(fdim).size_local]
    from . import _dolfinx as dfx

    nodes = dfx.entities_to_geometry(msh, fdim, owned)
    x = msh.geometry.x
    lengths = np.linalg.norm(x[nodes[:, 1]] - x[nodes[:, 0]], axis=1) if owned.size else np.zeros(0)
    everything = np.concatenate(msh.comm.allgather(lengths))
    return float(np.median(everything))


def _file(scene: Scene, comm: MPI.Comm) -> SceneModel:
    """The user's mesh file with boundary conditions by physical name."""
    import ufl
    from dolfinx import fem

    g, bd = scene.geometry, scene.boundary
    t0 = time.perf_counter()
    body, _ = (read_xdmf(g.path, comm, g.groups) if g.path.endswith(".xdmf") else read_msh(g.path, comm))
    _check_names(scene, body.tags)
    mesh_s = time.perf_counter() - t0
    V, form, von_mises, bcs, loads = _model(scene, body, list(bd.fixed))
    gdim = body.mesh.geometry.dim
    fdim = gdim - 1
    for name in bd.symmetry:  # zero normal displacement on a plane face normal to a coordinate axis
        axis = _axis_normal(V, body.facets(name), name)
        Vi, _ = V.sub(axis).collapse()
        dofs = fem.locate_dofs_topological((V.sub(axis), Vi), fdim, body.facets(name))
        bcs.append(fem.dirichletbc(fem.Function(Vi), dofs, V.sub(axis)))
    prescribed = {}
    if bd.displacement:
        conditions = []
        for name, vector in bd.displacement.items():
            value = fem.Function(V)
            value.x.array.reshape(-1, V.dofmap.index_map_bs)[:, :gdim] = np.asarray(vector, dtype=float)
            conditions.append(fem.dirichletbc(value, fem.locate_dofs_topological(V, fdim, body.facets(name))))
        prescribed[BOUNDARY_DISPLACEMENT] = conditions
    if bd.pressure:
        ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=body.facet_tags)
        n, v = ufl.FacetNormal(V.mesh), ufl.TestFunction(V)
        loads[BOUNDARY_PRESSURE] = sum(-value * ufl.dot(n, v) * ds(body.tags[name]) for name, value in bd.pressure.items())
    surface = _surface(scene, body)
    h = _facet_length(V, body.facets(scene.contact.surface))
    body = BodyMesh(body.mesh, body.facet_tags, body.cell_tags, body.tags, h, None, {}, body.regions)
    return SceneModel(body, V, form, bcs, surface, _plane(scene, body), loads, h, scene.contact.candidate_half_width,
                      None, False, False, None, None, None, False, ", against a rigid plane", von_mises,
                      {"mesh_s": mesh_s}, prescribed, [n for n in (BOUNDARY_DISPLACEMENT, BOUNDARY_PRESSURE)
                                                       if n in prescribed or n in loads])


def _axis_normal(V, facets: np.ndarray, name: str) -> int:
    """The coordinate axis normal to a plane boundary (for a roller condition on one component)."""
    msh = V.mesh
    fdim = msh.topology.dim - 1
    from . import _dolfinx as dfx

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


_BUILDERS: dict[str, Callable[[Scene, MPI.Comm], SceneModel]] = {
    "half_cylinder": _half_cylinder, "rectangle": _rectangle, "file": _file, "sphere": _sphere,
}
