"""Fatigue parameters of a :class:`~dolfinx_fretting.problem.FrettingProblem` over one load cycle (DOLFINx glue).

:func:`fatigue_over_cycle` takes the user's problem and the committed states of one cycle (or a cycle's result
kept with ``run_cycle(..., keep=True)``, :func:`cycle_states`), reads the stress and strain of every state at the
points of a near-surface region and hands the histories to the pure kernels of :mod:`dolfinx_fretting.fatigue`:

* the points: the quadrature points of the owned cells (elastic bodies: the rule of ``quadrature_degree``, 1 by
  default, one point at each cell's midpoint; elastic–plastic bodies: the points that carry the plastic state);
* the stress and strain: elastic bodies, the strain of :meth:`~dolfinx_fretting.problem.FrettingProblem.displacement`
  and Hooke's law of ``material`` (plane strain in 2D: ``eps_zz = 0``, ``sigma_zz = nu (sigma_xx + sigma_yy)``);
  elastic–plastic bodies, the state's committed stress (``sigma_zz`` included) and the total strain of its
  displacement;
* the body evaluated (``body``): the slave (the body whose contact nodes the contact set holds; the only one
  against a rigid obstacle) or, with two deformable bodies, the master (the flat: on the fretting-fatigue rig the
  specimen, where fretting-fatigue cracks start; Hills & Nowell 1994, Madge et al. 2007);
* the depth of a point: its distance below that body's contact surface. The slave: along the contact normal of
  the nearest contact node (exact for a flat surface; the candidate nodes of the problem's contact set). The
  master: along the outward normal of the closest point of the master's contact facets
  (:class:`~dolfinx_fretting.contact.MasterSurface`, every facet the pairing searched on). A depth region holds
  the points at 0 <= depth <= region: the other body lies above the surface (negative depth) in the reference
  configuration, so its points are left out;
* Ruiz's parameter at the contact nodes, from each state's shear traction and relative tangential displacement
  (:meth:`~dolfinx_fretting.problem.FrettingProblem.contact_fields`: relative quantities, the same magnitudes on
  both surfaces, so the slave nodes' values serve either body) and ``sigma_xx`` at the region's point nearest to
  the node's place on the evaluated body (a point of the first cells below the surface, not the surface itself):
  the slave node itself, or (master) its paired point on the master surface, whose coordinates are then
  ``ruiz_coordinates`` and ``ruiz_x``.

Collective: every rank calls it with the same arguments; each rank holds its own points' arrays, the summary (the
largest SWT and where, ...) is the same on every rank.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Mapping, Sequence

import basix
import numpy as np
import ufl
from mpi4py import MPI
from dolfinx.io import XDMFFile
from scipy.spatial import cKDTree

from . import _dolfinx as dfx
from . import readers
from ._dolfinx import fem
from .fatigue import (POINT_COLUMNS, BasquinCoffinManson, CriticalDistance, CriticalPlanes, FatemiSocie,
                      critical_distance, critical_planes, depth_profile, mandel_to_tensor, ruiz_parameter)
from .state import ContactState, CycleResult

__all__ = ["BODIES", "FatigueResult", "fatigue_over_cycle", "cycle_states", "write_fatigue_xdmf"]


@dataclass(frozen=True)
class FatigueResult:
    """The fatigue parameters of one cycle (:func:`fatigue_over_cycle`).

    Per-point arrays are this rank's points (owned cells); :meth:`columns` gives them under the names of
    :data:`~dolfinx_fretting.fatigue.POINT_COLUMNS` and :meth:`gather` every rank's on one.

    Attributes:
        coordinates: (P, 3) the points (reference configuration).
        depth: (P,) their depth below the contact surface (length units).
        sigma_xx: (P,) the largest sigma_xx over the cycle (MPa).
        swt, swt_angle: (P,) the Smith–Watson–Topper parameter on the critical plane (MPa) and its normal's angle
            (degrees; in 3D the azimuth, with ``planes.swt_phi`` the angle from z).
        fs, fs_angle: (P,) the Fatemi–Socie parameter and its plane (NaN without Fatemi–Socie constants).
        life: (P,) cycles to crack initiation by SWT (inf without ``strain_life`` constants).
        planes: The critical planes of this rank's points (:class:`~dolfinx_fretting.fatigue.CriticalPlanes`).
        ruiz: (nc,) Ruiz's parameter at each contact node (every rank), ``ruiz_coordinates`` (nc, dim) where it
            is on the evaluated body's surface (the slave nodes, or their paired points on the master surface).
        summary: :data:`~dolfinx_fretting.fatigue.SUMMARY_FIELDS` (every rank the same; ``life_min`` None without
            constants, the others NaN where nothing was computed).
        times: The number of states of the cycle.
        body: The body evaluated, ``"slave"`` or ``"master"``.
        cells: (P,) the local index of the owned cell each point lies in (:func:`write_fatigue_xdmf`).
    """

    coordinates: np.ndarray
    depth: np.ndarray
    sigma_xx: np.ndarray
    swt: np.ndarray
    swt_angle: np.ndarray
    fs: np.ndarray
    fs_angle: np.ndarray
    life: np.ndarray
    planes: CriticalPlanes
    ruiz: np.ndarray
    ruiz_coordinates: np.ndarray
    summary: dict[str, Any]
    times: int
    body: str = "slave"
    cells: np.ndarray | None = None

    def columns(self) -> dict[str, np.ndarray]:
        """This rank's points under the names of :data:`~dolfinx_fretting.fatigue.POINT_COLUMNS` (``x`` the
        first coordinate)."""
        values = {"x": self.coordinates[:, 0]}
        return {name: values[name] if name in values else getattr(self, name) for name in POINT_COLUMNS}

    def gather(self, comm: MPI.Comm, root: int = 0) -> dict[str, np.ndarray] | None:
        """Every rank's :meth:`columns` on ``root`` (rank order), None elsewhere. Collective."""
        parts = comm.gather(self.columns(), root=root)
        if comm.rank != root:
            return None
        return {name: np.concatenate([part[name] for part in parts]) for name in POINT_COLUMNS}


def cycle_states(problem, result: CycleResult) -> list[ContactState]:
    """The states of each increment of a cycle run with ``run_cycle(..., keep=True)`` (elastic bodies): the
    final state with each increment's forces, relative positions, obstacle and load factors, which is all that
    :meth:`~dolfinx_fretting.problem.FrettingProblem.displacement` and ``contact_fields`` read."""
    if result.kept is None:
        raise ValueError("cycle_states: the cycle was run without keep=True (run_cycle(state, path, keep=True))")
    if problem.body is not None:
        raise ValueError("cycle_states: an elastic-plastic cycle keeps no plastic history per increment; pass the "
                         "committed states of the cycle (advance increment by increment)")
    forces, slip, positions, wear_gap, status = result.kept
    return [replace(result.final, forces=forces[i], slip=slip[i], positions=positions[i], wear_gap=wear_gap[i],
                    status=status[i], obstacle=result.obstacle[i], load_factors=result.load_factors[i])
            for i in range(forces.shape[0])]


#: The bodies :func:`fatigue_over_cycle` evaluates: the contact set's slave, or the deformable master body.
BODIES = ("slave", "master")


def _check_inputs(problem, states, region, material, quadrature_degree, body) -> tuple[list, Any]:
    """The states as a list and the elastic constants; every error before any work (the same on every rank)."""
    if body not in BODIES:
        raise ValueError(f"fatigue_over_cycle: body = {body!r}: one of {', '.join(map(repr, BODIES))}")
    if isinstance(states, CycleResult):
        states = cycle_states(problem, states)
    states = list(states)
    if not states or not all(isinstance(state, ContactState) for state in states):
        raise ValueError("fatigue_over_cycle: states must be a non-empty list of ContactState (the cycle's "
                         "committed states) or a CycleResult kept with keep=True")
    if body == "master" and not problem.contact_set_of(states[0]).two_body:
        raise ValueError("fatigue_over_cycle: body = 'master' needs a deformable master body (two bodies in "
                         "contact); against a rigid obstacle the slave is the only body: body = 'slave'")
    if isinstance(region, tuple):
        if len(region) != 2 or not hasattr(region[0], "find"):
            raise ValueError(f"fatigue_over_cycle: region = {region!r}: a depth (> 0) or (cell_tags, marker)")
    elif not (isinstance(region, (int, float)) and np.isfinite(region) and region > 0):
        raise ValueError(f"fatigue_over_cycle: region = {region!r}: a depth (> 0, length units) or "
                         "(cell_tags, marker)")
    if problem.body is not None:
        law = problem.plasticity.law
        if material is not None and (material.E, material.nu) != (law.E, law.nu):
            raise ValueError(f"fatigue_over_cycle: material (E = {material.E}, nu = {material.nu}) differs from the "
                             f"plastic law's (E = {law.E}, nu = {law.nu}); leave it None")
        if quadrature_degree not in (None, problem.plasticity.quadrature_degree):
            raise ValueError(f"fatigue_over_cycle: quadrature_degree = {quadrature_degree!r}: an elastic-plastic "
                             f"body's points are its plastic state's (degree {problem.plasticity.quadrature_degree})")
        missing = [i for i, state in enumerate(states) if state.plastic is None]
        if missing:
            raise ValueError(f"fatigue_over_cycle: states{missing} have no plastic history (committed states of this "
                             "elastic-plastic problem are needed)")
        return states, law
    if material is None or not (hasattr(material, "E") and hasattr(material, "nu")):
        raise ValueError("fatigue_over_cycle: material (with E and nu, e.g. materials.LinearElastic) is required "
                         "for an elastic problem: the stress is Hooke's law of the displacement's strain")
    if not (material.E > 0 and -1 < material.nu < 0.5):
        raise ValueError(f"fatigue_over_cycle: material E = {material.E}, nu = {material.nu}: E > 0, -1 < nu < 0.5")
    if quadrature_degree is not None and not (isinstance(quadrature_degree, int) and quadrature_degree >= 1):
        raise ValueError(f"fatigue_over_cycle: quadrature_degree = {quadrature_degree!r}: an integer >= 1")
    return states, material


def _hooke(strain: np.ndarray, E: float, nu: float) -> np.ndarray:
    """Isotropic stress of (..., 3, 3) strains (3D law; in plane strain eps_zz = 0 gives sigma_zz)."""
    lmbda, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    trace = np.trace(strain, axis1=-2, axis2=-1)
    return lmbda * trace[..., None, None] * np.eye(3) + 2 * mu * strain


def _surface_depth(points: np.ndarray, contact_set) -> np.ndarray:
    """Depth below the contact surface along the normal of the nearest contact node (module docstring)."""
    dim = contact_set.dim
    if points.shape[0] == 0:
        return np.zeros(0)
    _, nearest = cKDTree(contact_set.coords[:, :dim]).query(points[:, :dim])
    normals = contact_set.frames[nearest, 0, :]   # n points from the obstacle into the body
    return np.einsum("pi,pi->p", points[:, :dim] - contact_set.coords[nearest, :dim], normals)


def _master_depth(points: np.ndarray, surface) -> np.ndarray:
    """Depth below the master's contact facets: along the outward normal of each point's closest facet point
    (module docstring). In chunks: the pairing is dense (points x facets)."""
    dim = surface.dim
    depth = np.zeros(points.shape[0])
    chunk = max(1, 2_000_000 // max(1, surface.x.shape[0]))   # ~2e6 point-facet pairs at a time
    for start in range(0, points.shape[0], chunk):
        part = points[start:start + chunk, :dim]
        paired = surface.pair(part)
        depth[start:start + chunk] = -np.einsum("pi,pi->p", part - paired["point"][:, :dim],
                                                paired["normal"][:, :dim])   # normal: out of the master
    return depth


def _best(comm: MPI.Comm, values: np.ndarray, extras: Sequence[np.ndarray], largest: bool = True):
    """The largest (``largest=False``: smallest) of ``values`` over every rank, and ``extras`` at that point (ties:
    the lowest rank, then the first point); NaN where no rank has a value that is not NaN. Collective."""
    usable = ~np.isnan(values)
    mine = (False, -np.inf, [np.nan] * len(extras))
    if usable.any():
        keys = np.where(usable, values if largest else -values, -np.inf)
        index = int(np.argmax(keys))
        mine = (True, float(keys[index]), [float(extra[index]) for extra in extras])
    found = [item for item in comm.allgather(mine) if item[0]]
    if not found:
        return np.nan, [np.nan] * len(extras)
    _, key, at = max(found, key=lambda item: item[1])   # max keeps the first (lowest rank) of equals
    return (key if largest else -key), at


def fatigue_over_cycle(problem, states: Sequence[ContactState] | CycleResult, region: float | tuple,
                       material=None, *, fatemi_socie: FatemiSocie | None = None,
                       strain_life: BasquinCoffinManson | None = None, angle_step: float | None = None,
                       quadrature_degree: int | None = None,
                       critical: CriticalDistance | None = None, body: str = "slave") -> FatigueResult:
    """The fatigue parameters of one load cycle at the points of a near-surface region (module docstring).
    Collective.

    Args:
        problem: The :class:`~dolfinx_fretting.problem.FrettingProblem`.
        states: The committed states of one cycle, in order (e.g. every ``advance`` of the cycle, or the
            states of :func:`cycle_states`), or the :class:`~dolfinx_fretting.state.CycleResult` of
            ``run_cycle(..., keep=True)``.
        region: A depth (> 0): the points at most that far below the contact surface; or ``(cell_tags, marker)``:
            the points of the cells so tagged.
        material: Elastic bodies: the elastic constants (``E``, ``nu``; e.g.
            :class:`~dolfinx_fretting.materials.LinearElastic`) of the user's form. Elastic–plastic bodies: None
            (the plastic law's).
        fatemi_socie: The Fatemi–Socie constants (None: SWT only).
        strain_life: The strain-life constants for the life by SWT (None: life inf, ``life_min`` None).
        angle_step: The plane search's step in degrees (default 1 in 2D, 5 in 3D).
        quadrature_degree: Elastic bodies: the rule of the points (default 1: the cells' midpoints).
        critical: A critical distance: the summary also holds
            :data:`~dolfinx_fretting.fatigue.CRITICAL_DISTANCE_FIELDS`, SWT by its point or line method on the
            profile in depth below the SWT hot spot (:func:`~dolfinx_fretting.fatigue.depth_profile` of every
            rank's points within its band) and the life it gives.
        body: The body evaluated: ``"slave"`` (default: the body of the contact set's nodes, the only one
            against a rigid obstacle) or ``"master"`` (two deformable bodies: the master body, e.g. the
            fretting-fatigue rig's specimen; the depth below its contact facets, Ruiz's parameter placed at the
            slave nodes' paired points on its surface).

    Returns:
        The per-point arrays of this rank and the summary of all (:class:`FatigueResult`).
    """
    if critical is not None and not isinstance(critical, CriticalDistance):
        raise ValueError(f"fatigue_over_cycle: critical = {critical!r}: a fatigue.CriticalDistance or None")
    states, elastic = _check_inputs(problem, states, region, material, quadrature_degree, body)
    comm = problem.comm
    V = problem.V
    msh = V.mesh
    gdim = msh.geometry.dim
    cells = np.arange(msh.topology.index_map(msh.topology.dim).size_local, dtype=np.int32)
    plastic = problem.body is not None
    degree = problem.plasticity.quadrature_degree if plastic else (quadrature_degree or 1)
    reference_points, _ = basix.make_quadrature(dfx.basix_cell(msh), degree)
    n_per_cell = reference_points.shape[0]
    # Every rank compiles the same expressions (a JIT compilation may be collective).
    coordinates = dfx.eval_expression(dfx.expression(ufl.SpatialCoordinate(msh), reference_points), msh,
                                      cells).reshape(-1, gdim)
    coordinates = np.column_stack([coordinates, np.zeros((coordinates.shape[0], 3 - gdim))])
    contact_set = problem.contact_set_of(states[0])
    if body == "master":
        depth = _master_depth(coordinates, contact_set.master_surface)
        # where each contact's values sit on the master's surface: the slave node's paired point
        surface_points = np.asarray(contact_set.master_points, dtype=float)[:, :contact_set.dim]
    else:
        depth = _surface_depth(coordinates, contact_set)
        surface_points = contact_set.coords[:, :contact_set.dim]
    if isinstance(region, tuple):
        tags, marker = region
        chosen = np.repeat(np.isin(cells, tags.find(marker)), n_per_cell)
    else:
        chosen = (depth >= 0) & (depth <= float(region))
    if comm.allreduce(int(chosen.sum()), op=MPI.SUM) == 0:
        raise ValueError(f"fatigue_over_cycle: region = {region!r} holds no point of the mesh")
    displacement = fem.Function(V)
    strain_expression = dfx.expression(ufl.sym(ufl.grad(displacement)), reference_points)
    stress_history = np.zeros((len(states), int(chosen.sum()), 3, 3))
    strain_history = np.zeros_like(stress_history)
    # the states' displacements a batch at a time: one multiple right-hand-side solve each (elastic bodies),
    # copied in turn into the function the strain expression reads
    batch = readers.batch_size(problem.operators)
    solved = [fem.Function(V) for _ in range(min(batch, len(states)))]
    for time, state in enumerate(states):
        if time % batch == 0:   # collective: every rank, every batch
            part = states[time:time + batch]
            problem.displacements(part, outs=solved[:len(part)])
        displacement.x.array[:] = solved[time % batch].x.array
        strain = np.zeros((coordinates.shape[0], 3, 3))
        strain[:, :gdim, :gdim] = dfx.eval_expression(strain_expression, msh, cells).reshape(-1, gdim, gdim)
        strain_history[time] = strain[chosen]
        if plastic:
            stress_history[time] = mandel_to_tensor(state.plastic.sigma)[chosen]
        else:
            stress_history[time] = _hooke(strain[chosen], elastic.E, elastic.nu)
    planes = critical_planes(stress_history, strain_history, gdim, angle_step, fatemi_socie)
    life = strain_life.life_swt(planes.swt) if strain_life is not None else np.full(planes.swt.shape, np.inf)
    points = coordinates[chosen]
    sigma_xx = stress_history[:, :, 0, 0].max(axis=0)
    ruiz = _ruiz(comm, problem, states, surface_points, points, stress_history[:, :, 0, 0])

    swt_max, (swt_x, swt_depth, swt_angle) = _best(comm, planes.swt, (points[:, 0], depth[chosen],
                                                                      planes.swt_theta))
    fs_max, _ = _best(comm, planes.fs, ())
    life_min, _ = _best(comm, life, (), largest=False)   # inf (no crack) is a value: NaN only without points
    ruiz_index = int(np.argmax(ruiz)) if ruiz.size else None
    # (the keys of SUMMARY_FIELDS, in its order: tests/test_fatigue.py checks it)
    summary = {"swt_max": swt_max, "swt_x": swt_x, "swt_depth": swt_depth, "swt_angle": swt_angle,
               "fs_max": fs_max if fatemi_socie is not None else np.nan,
               "ruiz_max": float(ruiz[ruiz_index]) if ruiz_index is not None else np.nan,
               "ruiz_x": float(surface_points[ruiz_index, 0]) if ruiz_index is not None else np.nan,
               "life_min": float(life_min) if strain_life is not None else None}
    if critical is not None:
        swt_critical = _swt_at_critical_distance(comm, critical, points[:, 0], depth[chosen], planes.swt, swt_x,
                                                 swt_depth)
        summary["swt_critical"] = swt_critical
        summary["life_critical"] = float(strain_life.life_swt(swt_critical)) if strain_life is not None else None
    return FatigueResult(points, depth[chosen], sigma_xx, planes.swt, planes.swt_theta, planes.fs,
                         planes.fs_theta, life, planes, ruiz, surface_points.copy(), summary, len(states), body,
                         np.repeat(cells, n_per_cell)[chosen])


def _swt_at_critical_distance(comm: MPI.Comm, critical: CriticalDistance, x: np.ndarray, depth: np.ndarray,
                              swt: np.ndarray, hot_x: float, hot_depth: float) -> float:
    """SWT by the critical distance's method below the hot spot, from every rank's points in its band (the same
    gathered data, so the same answer or error, on every rank). Collective."""
    band = critical.band if critical.band is not None else hot_depth
    inside = np.abs(x - hot_x) <= band
    parts = comm.allgather((x[inside], depth[inside], swt[inside]))
    gathered = [np.concatenate([part[i] for part in parts]) for i in range(3)]
    levels, values = depth_profile(*gathered, hot_x, band)
    return float(critical_distance(levels, values, critical.distance, critical.method))


def _reduced(comm: MPI.Comm, values: np.ndarray, op) -> np.ndarray:
    """Element-wise reduction of a float array of the same shape on every rank. Collective."""
    values = np.ascontiguousarray(values, dtype=float)
    out = np.empty_like(values)
    comm.Allreduce(values, out, op=op)
    return out


def _ruiz(comm: MPI.Comm, problem, states, nodes: np.ndarray, points: np.ndarray, sigma_xx: np.ndarray) -> np.ndarray:
    """Ruiz's parameter at the contact nodes: sigma_xx the mean over the region's points nearest to the node's
    place ``nodes`` (nc, dim) on the evaluated body (all those at the smallest distance, on every rank: a node
    midway between two cells' midpoints takes both, whatever the partition), shear traction and relative
    tangential displacement of each state. Collective."""
    dim = nodes.shape[1]
    distance = np.full(nodes.shape[0], np.inf)
    tree = cKDTree(points[:, :dim]) if points.shape[0] else None
    if tree is not None:
        distance, _ = tree.query(nodes)
    nearest = _reduced(comm, distance, MPI.MIN)
    total = np.zeros((len(states), nodes.shape[0]))
    count = np.zeros(nodes.shape[0])
    if tree is not None:
        # equal distances up to rounding of the coordinates: 1e-9 of the distance (and of the nodes' spread)
        reach = nearest * (1 + 1e-9) + 1e-12 * np.ptp(nodes, axis=0).max(initial=0.0)
        for node, near in enumerate(tree.query_ball_point(nodes, reach)):
            total[:, node] = sigma_xx[:, near].sum(axis=1)
            count[node] = len(near)
    surface_stress = _reduced(comm, total, MPI.SUM) / _reduced(comm, count, MPI.SUM)
    shear, slide = [], []
    for state in states:
        fields = problem.contact_fields(state)
        shear.append(fields["shear"])
        slide.append(fields["relative_tangential"])
    return ruiz_parameter(surface_stress, np.array(shear), np.array(slide))


def write_fatigue_xdmf(path: str | Path, problem, cells: np.ndarray,
                       series: Sequence[tuple[float, Mapping[str, np.ndarray]]]) -> Path:
    """Write fatigue fields over the near-surface region as ``path`` (XDMF + its ``.h5``), for ParaView: the
    region's cells as a mesh of their own (a submesh of the problem's) and one piecewise-constant (DG0) field per
    name, at each time of ``series``. Collective: every rank passes its own points (:attr:`FatigueResult.cells`)
    and their values, the same names and times.

    Args:
        path: The ``.xdmf`` file (written anew).
        problem: The :class:`~dolfinx_fretting.problem.FrettingProblem` the points are of.
        cells: (P,) the owned cell of each of this rank's points (:attr:`FatigueResult.cells`); one point a cell
            (the midpoint rule, ``quadrature_degree`` 1: a DG0 field holds one value a cell).
        series: ``(time, {name: (P,) values})`` in time order, e.g. ``(cycle, result.columns())``.

    Returns:
        ``path``.

    Raises:
        ValueError: a cell holds several points, or the arrays do not match ``cells`` (on every rank).
    """
    comm = problem.comm
    cells = np.asarray(cells, dtype=np.int32)
    problem_text = None
    if np.unique(cells).size != cells.size:
        problem_text = ("a cell holds several points (quadrature_degree > 1): a DG0 field holds one value a cell; "
                        "evaluate with quadrature_degree=1")
    elif any(np.shape(values) != cells.shape for _, fields in series for values in fields.values()):
        problem_text = f"every field needs one value per point ({cells.size} on rank {comm.rank})"
    problems = [text for text in comm.allgather(problem_text) if text is not None]
    if problems:
        raise ValueError(f"write_fatigue_xdmf: {problems[0]}")
    submesh, parent_cells = dfx.cell_submesh(problem.V.mesh, cells)
    space = dfx.scalar_space(submesh, "DG", 0)
    dofs = dfx.cell_dofmap(space)[:, 0]
    # each submesh cell's point: the submesh holds exactly the points' cells (ghosts: filled by the scatter)
    point_of_cell = {int(cell): point for point, cell in enumerate(cells)}
    mine = np.array([i for i, parent in enumerate(parent_cells) if int(parent) in point_of_cell], dtype=np.int32)
    points = np.array([point_of_cell[int(parent_cells[i])] for i in mine], dtype=np.int64)
    names = list(series[0][1]) if series else []
    functions = {name: fem.Function(space, name=name) for name in names}
    path = Path(path)
    with XDMFFile(comm, str(path), "w") as xdmf:
        xdmf.write_mesh(submesh)
        for time, fields in series:
            for name in names:
                function = functions[name]
                function.x.array[dofs[mine]] = np.asarray(fields[name], dtype=float)[points]
                function.x.scatter_forward()
                xdmf.write_function(function, float(time))
    return path
