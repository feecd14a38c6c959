"""From a validated scene to results: mesh, K, contact set, W, then the increments and cycles.

Each increment solves the local problem x = W r + q on the replicated contact set (paper eq. 28): the
normal rows of x are gaps, the tangential rows slip increments, so

    q_n = g_0 + g_w - n.D + s (H K^-1 f)_n,     q_t = -t.D + s (H K^-1 f)_t - y_t(previous),

where D is the obstacle's rigid displacement, s the face pressure and f the load of a unit face pressure,
and ``y = W r + q_abs`` the total relative position of the last converged increment. K is factorised
once and W built once; an increment costs local solves only. After each converged increment the Archard
law updates the wear gap g_w (:mod:`dolfinx_fretting.wear`), which enters the next increment's gap.

Two ways through the increments give the same answer:

* the Python path (:class:`IncrementSolver`), one local solve per increment or several when a force is
  prescribed (the obstacle position is then an unknown found by :func:`~dolfinx_fretting.loading.find_displacement`);
* the compiled path (:mod:`dolfinx_fretting.cycling`), a whole cycle per call, used for cycles whose loads
  are all displacements or face pressures; it warm-starts every increment from the same increment of the
  previous cycle.

The local problem is solved on rank 0 and its result broadcast, so every rank holds the same contact
state whatever the partition.

With ``wear.cycle_jump`` a simulated cycle is followed by a jump: the wear gap is extrapolated over the
cycles :mod:`dolfinx_fretting.cycle_jump` allows (the tables then have one row per simulated cycle, the
counters count physical cycles and increments).

A cyclic run writes a checkpoint (``checkpoint.npz``) every ``output.checkpoint_interval`` seconds, at
snapshot cycles and at the end; ``run_scene(..., resume=True)`` continues from it with the same results
as an uninterrupted run. A failed increment is reported with its cycle and step; the failed cycle leaves
no trace in the wear gap, the tables or the checkpoint.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from . import local_solvers
from .analytic import hertz_line_contact
from .io import _jsonable, non_finite_keys
from .contact import ContactSet, RigidPlane, find_candidates, find_pairs
from .loading import LoadControlError, LoadStep, cycle_path, find_displacement, monotonic_path, preload_path, waveform
from .outdir import OutputFolderError, claim_output_folder, load_checkpoint
from .scenes import Scene, describe_differences
from .wear import ROW, ROW_FIELDS, commit_increment

__all__ = ["ContactModel", "IncrementSolver", "RunState", "SimulationError", "run_scene", "CHECKPOINT"]

#: Checkpoint file name in the output folder.
CHECKPOINT = "checkpoint.npz"
# Scene sections that may change between a checkpoint and its resume (they do not change the physics).
_RESUMABLE_SECTIONS = ("solver", "output")


class SimulationError(RuntimeError):
    """An increment could not be solved, or a run cannot be resumed; the message says which, and why."""


class _WindowTooSmall(Exception):
    """The contact reached the candidate window's edge and the window can grow (internal: caught by the run)."""


class ContactModel:
    """The discretised scene: body, stiffness, contact set and Delassus matrix. Collective to build.

    Args:
        scene: A validated scene.
        comm: MPI communicator.
    """

    def __init__(self, scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD):
        from . import meshes
        from .materials import LinearElastic
        from .mechanics import ElasticProblem

        self.scene = scene
        self.comm = comm
        self.timings: dict[str, float] = {}
        g = scene.geometry
        t0 = time.perf_counter()
        self.two_body = scene.contact.obstacle == "elastic_flat"
        if self.two_body:
            self.body = meshes.cylinder_on_flat(comm, g.radius, g.flat_width, g.flat_height,
                                                contact_mesh_size=g.contact_mesh_size,
                                                contact_half_width=g.refined_half_width,
                                                coarse_mesh_size=g.coarse_mesh_size, quadrilateral=g.quadrilateral)
        elif g.kind == "half_cylinder":
            self.body = meshes.half_cylinder(comm, g.radius, contact_mesh_size=g.contact_mesh_size,
                                             contact_half_width=g.refined_half_width,
                                             coarse_mesh_size=g.coarse_mesh_size, quadrilateral=g.quadrilateral)
        else:
            self.body = meshes.rectangle(comm, g.width, g.height, g.nx, g.ny, quadrilateral=g.quadrilateral)
        # Two bodies: the cylinder's top and the flat's bottom are held; the loads move the flat rigidly
        # (a rigid motion of a body held at one face only is stress-free, so it enters the contact as the
        # rigid plane's motion does, through q = -G D).
        fixed = ["top", "flat_bottom"] if self.two_body else ["top"]
        self.timings["mesh_s"] = time.perf_counter() - t0

        surface = scene.contact.surface
        if surface not in self.body.tags:
            raise SimulationError(f"contact.surface = {surface!r} is not a boundary of the "
                                  f"{g.kind} mesh; allowed: {', '.join(sorted(self.body.tags))}")
        # Against an elastic flat this plane is the flat's top (y = 0): its frame gives the directions of the
        # flat's rigid motion D, so loads and total forces read as against a rigid plane.
        self.obstacle = RigidPlane(np.array(scene.contact.plane_point), np.array(scene.contact.plane_normal))

        material = LinearElastic(scene.material.E, scene.material.nu)
        self.quadrature_degree = scene.solver.quadrature_degree
        if self.quadrature_degree is None and scene.material.model == "elastoplastic":
            self.quadrature_degree = 2
        t0 = time.perf_counter()
        self.problem = ElasticProblem(self.body, material, fixed=fixed,
                                      delassus_method=scene.solver.delassus_method,
                                      petsc_options=scene.solver.petsc_options,
                                      quadrature_degree=self.quadrature_degree)
        self.timings["assemble_s"] = time.perf_counter() - t0

        self._contact_facets = self.body.facet_tags.find(self.body.tags[surface])
        #: Candidate window half-width (mm): the scene's, or automatic (see :meth:`automatic_window`);
        #: ``window_limit`` is how far it may grow (the refined zone of a half-cylinder).
        self.window_limit = g.refined_half_width if g.kind == "half_cylinder" else None
        # Elastic bodies only: an elastic-plastic body cannot grow its window (its W is not rebuilt), and
        # plasticity widens the contact beyond the elastic Hertz estimate, so it keeps the refined zone.
        self.window_automatic = (scene.contact.candidate_half_width is None and g.kind == "half_cylinder"
                                 and scene.material.model == "elastic")
        self.half_width = (self.automatic_window() if self.window_automatic else
                           scene.contact.candidate_half_width if scene.contact.candidate_half_width is not None
                           else self.window_limit)
        self._find_contact()

        t0 = time.perf_counter()
        self.problem.delassus.factorize()
        self.timings["factorize_s"] = time.perf_counter() - t0
        self.face_load = None
        if scene.loading.tangential_kind == "pressure":
            self.face_load = self.problem.face_pressure_load(scene.loading.pressure_face)
        t0 = time.perf_counter()
        self._contact_operators()
        self.timings["delassus_s"] = time.perf_counter() - t0
        self.delassus_method = self.problem.delassus.method

        # Elastic-plastic: Newton with the contact inside (plasticity.ElastoplasticBody); nothing plastic is
        # built for an elastic scene.
        self.plastic = None
        if scene.material.model == "elastoplastic":
            from .materials import J2Plasticity
            from .plasticity import ElastoplasticBody

            m, sv = scene.material, scene.solver
            law = J2Plasticity(m.E, m.nu, m.yield_stress, m.plastic_modulus)
            elastic_cells = None
            if self.two_body and m.plastic_body != "both":
                other = "flat" if m.plastic_body == "cylinder" else "cylinder"
                elastic_cells = self.body.cell_tags.find(self.body.regions[other])
            self.plastic = ElastoplasticBody(self.problem, law, self.contact.H, self.W, self.face_load,
                                             tangent=sv.newton_tangent, max_iter=sv.newton_max_iter,
                                             delta_1=sv.newton_residual_tol, delta_2=sv.newton_displacement_tol,
                                             quadrature_degree=self.quadrature_degree,
                                             elastic_cells=elastic_cells)

    def automatic_window(self) -> float:
        """Candidate half-width from the Hertz estimate of the contact half-width plus a margin (mm).

        ``1.5 a + 3 h``, at most the refined zone; a from the normal force (Hertz line contact with the
        scene's E*: one elastic body on a rigid plane, or two identical bodies) or, under a prescribed
        approach d, the geometric ``sqrt(2 R d)`` (an overestimate). The run grows the window if the
        contact reaches its edge (wear widens a scar).
        """
        sc, g = self.scene, self.scene.geometry
        m = sc.material
        E_star = m.E / (1 - m.nu**2) / (2.0 if self.two_body else 1.0)
        lo = sc.loading
        if lo.normal_force is not None:
            a, _ = hertz_line_contact(lo.normal_force, g.radius, E_star)
        else:
            a = float(np.sqrt(2 * g.radius * lo.normal_displacement))
        return float(min(self.window_limit, 1.5 * a + 3 * g.contact_mesh_size))

    def _find_contact(self) -> None:
        """Candidates (rigid plane) or slave-master pairs (elastic flat) within ``half_width``. Collective."""
        try:
            if self.two_body:
                self.contact: ContactSet = find_pairs(self.problem.V, self._contact_facets,
                                                      self.body.facets("flat_top"), self.half_width,
                                                      exclude_nodes=self.problem.fixed_nodes)
            else:
                self.contact = find_candidates(self.problem.V, self._contact_facets, self.obstacle, self.half_width,
                                               exclude_nodes=self.problem.fixed_nodes)
        except ValueError as exc:
            raise SimulationError(str(exc)) from None

    def _contact_operators(self) -> None:
        """W = H K^-1 H^T (one copy, broadcast: the local solve must see identical input on every rank) and
        q_f = H K^-1 f of a unit face pressure. Collective; K must be factorised."""
        W = self.problem.delassus.build(self.contact.H)
        self.W = self.comm.bcast(W if self.comm.rank == 0 else None, root=0)
        self.q_f = np.zeros(self.contact.nc * self.contact.dim)
        if self.face_load is not None:
            self.q_f = self.problem.local_response(self.contact.H, self.face_load)  # allreduced: replicated

    def set_window(self, half_width: float) -> None:
        """Rebuild the contact set, W and q_f for another candidate window (elastic bodies). Collective.

        All or nothing: if the rebuild fails, the model keeps its window, contact set and W.
        """
        if self.plastic is not None:
            raise SimulationError("the candidate window of an elastic-plastic body cannot change during a run")
        saved = (self.half_width, self.contact, self.W, self.q_f)
        self.half_width = float(half_width)
        try:
            self._find_contact()
            self._contact_operators()
        except Exception:
            self.half_width, self.contact, self.W, self.q_f = saved
            raise

    @property
    def n_dofs(self) -> int:
        V = self.problem.V
        return V.dofmap.index_map.size_global * V.dofmap.index_map_bs


@dataclass
class Solved:
    """A converged increment from the Python path (before the wear update)."""

    r: np.ndarray
    x: np.ndarray
    y: np.ndarray
    d: np.ndarray       #: Obstacle displacement (normal, tangential).
    iterations: int
    error: float
    load_solves: int


class IncrementSolver:
    """Solves increments on the local problem, with displacement or force control of the obstacle.

    Rank-local: call on one rank; the caller broadcasts.
    """

    def __init__(self, model: ContactModel):
        s = model.scene
        self.model = model
        self.cs = model.contact
        self.W = model.W
        self.dim = self.cs.dim
        self.mu = s.contact.mu
        self.tol = s.solver.local_tol
        self.max_iter = s.solver.local_max_iter
        self.method = s.solver.local_method
        self.force_tol = s.solver.force_tol
        self.frame = model.obstacle.frame
        self.G = self.cs.rigid_modes
        self.q_f = model.q_f
        nrows = self.cs.nc * self.dim
        self.normal_rows = np.arange(nrows) % self.dim == 0
        # Point stiffness of the closest node: a safe first guess of the load-displacement slope.
        k = int(np.argmin(self.cs.gap0))
        blk = slice(k * self.dim, (k + 1) * self.dim)
        self.stiffness = np.array([1.0 / self.W[blk, blk][0, 0], 1.0 / self.W[blk, blk][1, 1]])

    def _q(self, D: np.ndarray, pressure: float, y_prev: np.ndarray, gw: np.ndarray,
           q_body: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        # q_body: the contact displacement of the body before contact forces, H u_pred; elastic: s H K^-1 f.
        q_abs = -self.G @ D + (pressure * self.q_f if q_body is None else q_body)
        q_abs[self.normal_rows] += self.cs.gap0 + gw
        q = q_abs.copy()
        q[~self.normal_rows] -= y_prev[~self.normal_rows]
        return q, q_abs

    def solve(self, step: LoadStep, d_prev: np.ndarray, y_prev: np.ndarray, r_prev: np.ndarray,
              gw: np.ndarray, q_body: np.ndarray | None = None, W: np.ndarray | None = None) -> Solved:
        """Solve one increment from the converged state (``d_prev``, ``y_prev``, ``r_prev``, wear gap ``gw``).

        ``q_body`` and ``W`` replace the elastic body's contribution ``s H K^-1 f`` and Delassus matrix
        (a Newton iteration of an elastic-plastic body passes ``H (u - K^-1 R(u))`` and its W).

        Raises:
            SimulationError: local solver failure or unreachable prescribed force.
        """
        n, t = self.frame[0], self.frame[1]
        Wm = self.W if W is None else W
        d = np.array(d_prev, dtype=float)
        r_warm = r_prev.copy()
        count = {"solves": 0, "iterations": 0}
        last: dict[str, Any] = {}
        where = f"increment {step.increment}" + (f" (cycle {step.cycle}, step {step.step})" if step.cycle
                                                 else f" ({step.stage})")

        def local(dn: float, dt: float):
            nonlocal r_warm
            D = dn * n + dt * t
            q, q_abs = self._q(D, step.pressure, y_prev, gw, q_body)
            res = local_solvers.solve(Wm, q, self.mu, self.dim, method=self.method, tol=self.tol,
                                      max_iter=self.max_iter, r0=r_warm)
            count["solves"] += 1
            count["iterations"] += res.iterations
            if not res.converged:
                raise SimulationError(f"{where}: local solver did not converge: {res.message}; "
                                      "raise solver.local_max_iter or loosen solver.local_tol")
            r_warm = res.r
            F = self.cs.total_force(res.r)
            last.update(res=res, d=np.array([dn, dt]), q_abs=q_abs, F=np.array([F @ n, F @ t]))
            return last["F"]

        targets = np.array([step.normal, step.tangential])
        controlled = np.array([step.normal_force_controlled, step.tangential_force_controlled])
        d[~controlled] = targets[~controlled]
        try:
            F = local(*d)
            # Tolerance relative to the loads in play (a zero tangential target is held to the normal force).
            scale = max(np.abs(targets[controlled]).max(initial=0.0), np.abs(F).max(), 1e-300)
            ftol = self.force_tol * scale
            for _sweep in range(100):
                if np.all(np.abs(F - targets)[controlled] <= ftol):
                    break
                for k in np.flatnonzero(controlled):
                    def force_k(v: float, k: int = k) -> float:
                        dd = d.copy()
                        dd[k] = v
                        return local(*dd)[k]
                    d_old, F_old = d[k], F[k]
                    d[k], _, _ = find_displacement(force_k, targets[k], d[k], self.stiffness[k], ftol,
                                                   name=("loading.normal_force", "loading.tangential_force")[k])
                    F = last["F"]  # the root finder's last evaluation is at the returned d[k]
                    if d[k] != d_old and F[k] != F_old:
                        self.stiffness[k] = abs((F[k] - F_old) / (d[k] - d_old))
            else:
                raise SimulationError(f"{where}: prescribed forces not reached after 100 sweeps (residual "
                                      f"{np.abs(F - targets)[controlled]}, tolerance {ftol:.3g})")
        except LoadControlError as exc:
            raise SimulationError(f"{where}: {exc}") from None

        res = last["res"]
        y = Wm @ res.r + last["q_abs"]
        return Solved(res.r.copy(), res.x.copy(), y, last["d"].copy(), count["iterations"], res.error,
                      count["solves"])


@dataclass
class RunState:
    """Everything needed to continue a run (what a checkpoint holds), replicated on every rank.

    ``r_warm`` (forces of every increment of the last cycle, the compiled path's warm start) lives on
    rank 0 only.
    """

    increment: int            #: Increments done.
    cycle: int                #: Cycles completed.
    d: np.ndarray             #: Obstacle displacement (normal, tangential) of the last increment.
    y: np.ndarray             #: Total relative position of the last increment.
    r: np.ndarray             #: Contact forces of the last increment.
    gw: np.ndarray            #: Wear gap per contact.
    energy: float = 0.0       #: Cumulative dissipated energy.
    local_iterations: int = 0
    r_warm: np.ndarray | None = None
    last_row: dict[str, Any] | None = None
    last_cycle_row: dict[str, Any] | None = None

    @classmethod
    def initial(cls, model: ContactModel) -> RunState:
        cs = model.contact
        m = cs.nc * cs.dim
        y = np.zeros(m)
        y[0::cs.dim] = cs.gap0
        return cls(0, 0, np.zeros(2), y, np.zeros(m), np.zeros(cs.nc))


def _snapshot_cycles(scene: Scene) -> set[int]:
    N = scene.loading.cycles
    chosen = set(scene.output.snapshot_cycles)
    if not chosen and N > 0:
        decade = 1
        while decade <= N:
            chosen.update(c for c in (decade, 2 * decade, 5 * decade) if c <= N)
            decade *= 10
    if N > 0:
        chosen.add(N)
    return {c for c in chosen if 1 <= c <= N}


def _scene_identity(scene: Scene) -> str:
    data = scene.model_dump(mode="json")
    for key in _RESUMABLE_SECTIONS:
        data.pop(key, None)
    data["loading"].pop("cycles", None)  # a run may be extended by more cycles
    return json.dumps(data, sort_keys=True)


class _Run:
    """One run of a scene: the increment loops, the outputs and the checkpoints. Collective."""

    def __init__(self, scene: Scene, out_dir: Path, comm: MPI.Comm, quiet: bool, resume: bool):
        from .io import ResultWriter

        self.scene = scene
        self.out = out_dir
        self.comm = comm
        self.rank0 = comm.rank == 0
        self.say = (lambda msg: print(msg, flush=True)) if (self.rank0 and not quiet) else (lambda msg: None)
        self.t_start = time.perf_counter()
        checkpoint = self._read_checkpoint() if resume else None
        self.model = model = ContactModel(scene, comm)
        self.solver = IncrementSolver(model)
        cs = model.contact
        self.mu = np.full(cs.nc, scene.contact.mu)
        # The wear acceleration scales cycles only: the preload and a monotonic load happen once.
        self.k = scene.wear.k_effective
        self.k_once = scene.wear.k_total if scene.wear.law == "archard" else 0.0
        #: Largest |mean relative tangential position| of the contacts so far (small-sliding check).
        self.max_relative_tangential = 0.0
        self._sliding_warned = False
        self.window_growths: list[dict[str, Any]] = []
        self.snapshots = _snapshot_cycles(scene)
        # Cycle-jump bookkeeping (scene key wear.cycle_jump): the last simulated cycle's wear rate, the last
        # jump and the jump its bounds allowed, counts, the accumulated error estimate, the limits.
        self.jump_state: dict[str, Any] = {
            "rate": None, "last": 1, "free": 1, "simulated": 0, "jumps": 0, "largest": 1, "error": 0.0,
            "bound": "none", "stability_limit": math.inf, "monotone_limit": math.inf, "exceeded": 0,
            "min_stability_limit": math.inf}
        if checkpoint is None:
            self.state = RunState.initial(model)
            sizes, xdmf_started = None, False
        else:
            self.state, sizes, xdmf_started = self._restore(checkpoint)
        self.writer = ResultWriter(out_dir, comm, profiles=scene.output.contact_profiles, resume_sizes=sizes,
                                   xdmf_started=xdmf_started)
        self.resumed_from_cycle = self.state.cycle if checkpoint is not None else None  # summary: proof of resume
        self.last_checkpoint = time.perf_counter()
        self.say(f"[{scene.name}] {model.n_dofs} dofs, {cs.nc} contact candidates, "
                 f"W by {model.delassus_method} in {model.timings['delassus_s']:.3f} s"
                 + (f"; resumed after increment {self.state.increment} (cycle {self.state.cycle})"
                    if checkpoint is not None else ""))

    # Checkpoints ------------------------------------------------------------------------------------
    def _read_checkpoint(self) -> dict[str, Any]:
        path = self.out / CHECKPOINT
        try:  # a damaged file, tables shorter than it records, loading.cycles below the cycles done
            ck = load_checkpoint(path, self.scene.loading.cycles)
        except OutputFolderError as exc:
            raise SimulationError(f"--resume: {exc}") from None
        changed = describe_differences(json.loads(ck["meta"]["identity"]), json.loads(_scene_identity(self.scene)),
                                       names=("checkpoint", "this scene"))
        if changed:
            raise SimulationError(f"--resume: the scene differs from the one checkpointed in {path} beyond "
                                  f"the sections {', '.join(_RESUMABLE_SECTIONS)} and loading.cycles: {changed}; "
                                  "resume with the same scene, or start afresh in a new folder")
        return ck

    def _restore(self, ck: dict[str, Any]) -> tuple[RunState, dict[str, int], bool]:
        meta = ck["meta"]
        st = RunState(int(meta["increment"]), int(meta["cycle"]), ck["d"].copy(), ck["y"].copy(), ck["r"].copy(),
                      ck["gw"].copy(), float(meta["energy"]), int(meta["local_iterations"]),
                      ck["r_warm"].copy() if ck["r_warm"].size else None, meta.get("last_row"),
                      meta.get("last_cycle_row"))
        window = meta.get("window")
        if window is not None and window != self.model.half_width:
            self.model.set_window(window)  # the run had grown its window: the same contact set again
            self.solver = IncrementSolver(self.model)
            self.mu = np.full(self.model.contact.nc, self.scene.contact.mu)
        self.window_growths = list(meta.get("window_growths", []))
        if st.gw.size != self.model.contact.nc:
            raise SimulationError("--resume: the checkpoint's contact set does not match the scene's mesh")
        if meta.get("last_targets") is not None:
            self.last_targets = tuple(meta["last_targets"])
        if meta.get("jump") is not None:
            self.jump_state.update(meta["jump"])
            self.jump_state["rate"] = ck["jump_rate"].copy() if ck["jump_rate"].size else None
        body = self.model.plastic
        if body is not None:
            if meta.get("ranks") != self.comm.size:
                raise SimulationError(f"--resume: an elastic-plastic run checkpointed on {meta.get('ranks')} "
                                      f"rank(s) resumes on the same number (here {self.comm.size})")
            i = self.comm.rank
            body.u.x.array[:] = ck[f"u_{i}"]
            body.state.eps_p, body.state.p = ck[f"eps_p_{i}"].copy(), ck[f"p_{i}"].copy()
            body.state.sigma = body.state.sigma  # recomputed at the next update from eps and eps_p
        return st, {k: int(v) for k, v in meta["sizes"].items()}, bool(meta["xdmf_started"])

    def _plastic_arrays(self) -> dict[str, np.ndarray]:
        """Committed displacement and plastic state of every rank (on rank 0), for the checkpoint."""
        body = self.model.plastic
        if body is None:
            return {}
        parts = self.comm.gather((body.u.x.array.copy(), body.state.eps_p, body.state.p), root=0)
        if not self.rank0:
            return {}
        out = {}
        for i, (u, ep, p) in enumerate(parts):
            out[f"u_{i}"], out[f"eps_p_{i}"], out[f"p_{i}"] = u, ep, p
        return out

    def checkpoint(self) -> None:
        sizes = self.writer.sizes()
        plastic = self._plastic_arrays()
        if self.rank0:
            st = self.state
            meta = {"identity": _scene_identity(self.scene), "increment": st.increment, "cycle": st.cycle,
                    "energy": st.energy, "local_iterations": st.local_iterations, "sizes": sizes,
                    "xdmf_started": self.writer.xdmf_started, "last_row": st.last_row,
                    "last_cycle_row": st.last_cycle_row, "written": time.strftime("%Y-%m-%dT%H:%M:%S"),
                    "last_targets": getattr(self, "last_targets", None), "ranks": self.comm.size,
                    "window": self.model.half_width, "window_growths": self.window_growths,
                    "jump": {k: v for k, v in self.jump_state.items() if k != "rate"}}
            rate = self.jump_state["rate"]
            tmp = self.out / (CHECKPOINT + ".tmp.npz")
            np.savez(tmp, meta=json.dumps(meta, default=_jsonable), d=st.d, y=st.y, r=st.r, gw=st.gw,
                     r_warm=st.r_warm if st.r_warm is not None else np.zeros(0),
                     jump_rate=rate if rate is not None else np.zeros(0), **plastic)
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
            os.replace(tmp, self.out / CHECKPOINT)
        self.last_checkpoint = time.perf_counter()

    # Increments -----------------------------------------------------------------------------------------
    def _local(self, step: LoadStep, r_warm: np.ndarray, q_body: np.ndarray | None = None,
               W: np.ndarray | None = None) -> Solved:
        """The contact solve of an increment on rank 0, broadcast; raises SimulationError on failure."""
        st = self.state
        solved, failure = None, None
        if self.rank0:
            try:
                solved = self.solver.solve(step, st.d, st.y, r_warm, st.gw, q_body=q_body, W=W)
            except SimulationError as exc:
                failure = str(exc)
        if self.comm.size > 1:
            solved, failure = self.comm.bcast((solved, failure), root=0)
        if failure is not None:
            raise SimulationError(failure)
        return solved

    def _commit(self, step: LoadStep, solved: Solved, extra: dict[str, Any] | None = None,
                sums: np.ndarray | None = None) -> tuple[dict[str, Any], np.ndarray]:
        """Archard update and bookkeeping of a converged (sub-)increment; returns (history row, states)."""
        st = self.state
        cs = self.model.contact
        states = np.empty(cs.nc, dtype=np.int8)
        row = np.empty(len(ROW_FIELDS))
        gw = st.gw.copy()
        rn = solved.r[0::cs.dim]
        if self._window_edges_matter and (rn[0] > 0 or rn[-1] > 0):
            self._window_error(step.increment, step.cycle, step.step)
        commit_increment(solved.r, solved.x, solved.y, self.mu, cs.dim, cs.tributary, cs.abscissa,
                         self.k if step.cycle > 0 else self.k_once, gw, states, row)
        if step.cycle > 0 and getattr(self, "_cycle_gw0", None) is not None:
            self._check_wear_step(step.cycle, self._cycle_gw0, gw)  # as soon as the cycle wears too much
        st.d, st.y, st.r, st.gw = solved.d, solved.y, solved.r, gw
        st.energy += row[ROW["dissipated_energy"]]
        st.local_iterations += solved.iterations
        if sums is not None:  # energy and wear of the earlier sub-increments of a cut increment
            row[ROW["dissipated_energy"]] += sums[0]
            row[ROW["wear_area_increment"]] += sums[1]
        hist = {"increment": step.increment, "cycle": step.cycle, "step": step.step, "stage": step.stage,
                "normal_displacement": solved.d[0], "tangential_displacement": solved.d[1],
                "face_pressure": step.pressure, **dict(zip(ROW_FIELDS, row.tolist())),
                "local_iterations": solved.iterations, "local_error": solved.error,
                "load_solves": solved.load_solves, "newton_iterations": 1, "newton_delta_1": 0.0,
                "newton_delta_2": 0.0, "cutbacks": 0, "yielded_points": 0,
                **(extra or {})}
        st.last_row = hist
        return hist, states

    @property
    def _window_edges_matter(self) -> bool:
        """The ends of the candidate window are not body edges (half-cylinder): load there means the
        contact is truncated by the window."""
        return self.scene.geometry.kind == "half_cylinder"

    def _window_error(self, increment: int, cycle: int, step: int) -> None:
        cs, model = self.model.contact, self.model
        where = f"increment {increment}" + (f" (cycle {cycle}, step {step})" if cycle else "")
        if model.plastic is None and model.window_limit is not None and model.half_width < model.window_limit:
            raise _WindowTooSmall(where)
        raise SimulationError(
            f"{where}: the outermost contact candidates (x = {cs.abscissa[0]:.4g} .. {cs.abscissa[-1]:.4g} mm) "
            "carry load: the contact reaches the edge of the candidate window and would be truncated; widen "
            f"contact.candidate_half_width (now {model.half_width:.4g} mm) and "
            f"geometry.contact_half_width (the refined zone, now {self.scene.geometry.refined_half_width} mm)")

    def _check_wear_step(self, cycle: int, gw_old: np.ndarray, gw_new: np.ndarray) -> None:
        """Refuse a cycle that wears more than the contact element size at some contact: the wear gap is
        explicit over a cycle, and such steps make oscillating edge spikes (the run stops instead)."""
        h = self.model.body.contact_mesh_size
        dw = float(np.max(gw_new - gw_old, initial=0.0))
        if dw > h:
            raise SimulationError(
                f"cycle {cycle}: the wear gap grew by up to {dw:.3g} mm in one cycle, more than the contact element "
                f"size {h:.3g} mm; the explicit wear update is unstable there. Lower wear.acceleration (now "
                f"{self.scene.wear.acceleration:g}) or wear.k (now {self.scene.wear.k:g} 1/MPa)")

    def _python_increment(self, step: LoadStep) -> tuple[dict[str, Any], np.ndarray, np.ndarray, np.ndarray]:
        """Solve and commit one increment by the Python path; returns (history row, x, y, states)."""
        if self.model.plastic is not None:
            return self._plastic_increment(step)
        st = self.state
        while True:
            try:
                solved = self._local(step, st.r)
                hist, states = self._commit(step, solved)
                break
            except _WindowTooSmall as edge:
                if step.cycle > 0:
                    raise  # _python_cycle runs the whole cycle again
                self._grow_window(str(edge))  # nothing of the increment was committed: solve it again
        st.increment += 1
        self.last_targets = (step.normal, step.tangential, step.pressure)
        return hist, solved.x, solved.y, states

    def _plastic_increment(self, step: LoadStep) -> tuple[dict[str, Any], np.ndarray, np.ndarray, np.ndarray]:
        """Newton with the contact inside (paper Fig. 4); an increment that fails is halved up to
        ``solver.max_cutbacks`` times, each converged sub-increment committed (plastic state, wear)."""
        from dataclasses import replace

        from .plasticity import NewtonError

        body = self.model.plastic
        st = self.state
        start = getattr(self, "last_targets", None) or (0.0, 0.0, 0.0)
        end = (step.normal, step.tangential, step.pressure)
        done, size = 0.0, 1.0           # fraction of the increment committed, size of the next try
        cuts = newton = local_its = 0
        sums = np.zeros(2)
        while True:
            f = min(1.0, done + size)
            sub = replace(step, **{k: a + f * (b - a) for k, a, b in zip(("normal", "tangential", "pressure"),
                                                                        start, end)})
            r_warm = [st.r]

            def local_solve(q_body, W, sub=sub, r_warm=r_warm):
                solved = self._local(sub, r_warm[0], q_body, W)
                r_warm[0] = solved.r
                return solved

            try:
                try:
                    solved, info = body.increment(local_solve, sub.pressure)
                except NewtonError:
                    if body.tangent != "adaptive":
                        raise
                    # The adaptive matrix failed: full Newton on the same increment before cutting it.
                    body.tangent = "consistent"
                    try:
                        solved, info = body.increment(local_solve, sub.pressure)
                    finally:
                        body.tangent = "adaptive"
                    self.fallbacks = getattr(self, "fallbacks", 0) + 1
            except (NewtonError, SimulationError) as exc:
                if cuts >= self.scene.solver.max_cutbacks:
                    where = f"increment {step.increment}" + (f" (cycle {step.cycle}, step {step.step})"
                                                             if step.cycle else f" ({step.stage})")
                    loaded = self.model.contact.abscissa[st.r[0::self.model.contact.dim] > 0]
                    span = f"{loaded.min():.4g} .. {loaded.max():.4g} mm" if loaded.size else "none"
                    raise SimulationError(
                        f"{where}: no convergence after {cuts} cut-backs (last try: {done:.4g} -> {f:.4g} of the "
                        f"increment): {exc}. Loaded contacts of the last converged state: {loaded.size} "
                        f"({span}). Nothing of this increment is committed; raise solver.newton_max_iter or "
                        "solver.max_cutbacks, or use more increments") from None
                cuts += 1
                size *= 0.5
                continue
            body.commit()
            newton += info["newton_iterations"]
            local_its += solved.iterations
            done = f
            if done < 1.0:  # a sub-increment: commit its wear and state, keep its energy for the row
                self._commit(sub, solved)
                sums += (st.last_row["dissipated_energy"], st.last_row["wear_area_increment"])
                continue
            solved.iterations = local_its
            hist, states = self._commit(step, solved, {"newton_iterations": newton, "cutbacks": cuts,
                                                       "newton_delta_1": info["delta_1"],
                                                       "newton_delta_2": info["delta_2"],
                                                       "yielded_points": info["yielded_points"]}, sums)
            break
        st.increment += 1
        self.last_targets = end
        return hist, solved.x, solved.y, states

    def _profile(self, hist: dict[str, Any], x: np.ndarray, y: np.ndarray, r: np.ndarray, gw: np.ndarray,
                 states: np.ndarray) -> None:
        cs = self.model.contact
        dim = cs.dim
        self.writer.profile_block(hist["increment"], hist["cycle"], hist["step"], [
            cs.abscissa, y[0::dim], r[0::dim] / cs.tributary, r[1::dim] / cs.tributary, x[1::dim], y[1::dim],
            gw, states])

    def _fields(self, t: float, r: np.ndarray, pressure: float) -> None:
        if not self.scene.output.xdmf:
            return
        if self.model.plastic is not None:
            functions = self._plastic_fields()
        else:
            p = self.model.problem
            p.solve_contact_response(self.model.contact.H, r, self.model.face_load, pressure)
            functions = [p.u, p.von_mises()]
        if self.model.two_body:
            functions[0] = self._two_body_displacement(functions[0])
        self.writer.fields(t, functions)

    def _two_body_displacement(self, u):
        """The displacement as the paper loads it: the flat's bottom held, the cylinder moved by -D.

        The solve holds the cylinder's top and moves the flat rigidly by D (the same relative motion);
        subtracting D on the cylinder's nodes gives the picture of the paper's set-up. A copy: ``u`` may be
        Newton's state.
        """
        from dolfinx import fem

        if not hasattr(self, "_u_display"):
            V = u.function_space
            cells = self.model.body.cell_tags.find(self.model.body.regions["cylinder"])
            self._cylinder_nodes = fem.locate_dofs_topological(V, V.mesh.topology.dim, cells)
            self._u_display = fem.Function(V, name="displacement")
        frame = self.model.obstacle.frame
        D = self.state.d[0] * frame[0] + self.state.d[1] * frame[1]
        out = self._u_display
        out.x.array[:] = u.x.array
        bs = out.function_space.dofmap.index_map_bs
        values = out.x.array.reshape(-1, bs)
        values[self._cylinder_nodes, :D.size] -= D
        return out

    def _plastic_fields(self) -> list:
        """Displacement, cell-averaged von Mises stress and equivalent plastic strain (committed state)."""
        from dolfinx import fem

        body = self.model.plastic
        if not hasattr(self, "_dg0"):
            Q = fem.FunctionSpace(self.model.problem.mesh, ("DG", 0))
            self._dg0 = (fem.Function(Q, name="von_mises"), fem.Function(Q, name="equivalent_plastic_strain"))
        vm, peq = self._dg0
        ps = body.state
        n = ps.cells.size
        vm.x.array[:n] = ps.cell_average(ps.von_mises())
        peq.x.array[:n] = ps.cell_average(ps.p)
        vm.x.scatter_forward()
        peq.x.scatter_forward()
        return [body.u, vm, peq]

    def _say_increment(self, h: dict[str, Any]) -> None:
        self.say(f"[{self.scene.name}] inc {h['increment']:4d} {h['stage']:10s} P = {h['normal_force']:.6g} "
                 f"Q = {h['tangential_force']:.6g} p_max = {h['max_pressure']:.6g} it = {h['local_iterations']}")

    def run_stepwise(self, steps: list[LoadStep] | Any) -> None:
        """Preload and monotonic stages: every increment written (history, profile, fields)."""
        for step in steps:
            if step.increment <= self.state.increment:
                continue  # done before the checkpoint
            hist, x, y, states = self._python_increment(step)
            self._check_small_sliding(np.array([hist["mean_relative_tangential"]]))
            self.writer.rows("history", [hist])
            self._profile(hist, x, y, self.state.r, self.state.gw, states)
            self._fields(float(step.increment), self.state.r, step.pressure)
            self.writer.flush()
            self._say_increment(hist)

    def run_cycles(self) -> None:
        sc = self.scene
        lo = sc.loading
        N = lo.cycles
        n = lo.increments_per_cycle
        use_kernel = sc.solver.cycle_kernel and sc.solver.local_method == "uzawa" and not (
            lo.normal_force_controlled or lo.tangential_force_controlled or self.model.plastic is not None)
        self.cycle_mode = "compiled" if use_kernel else "python"
        every = sc.output.history_every
        loop_cycles = set(sc.output.loop_cycles)
        t_report = time.perf_counter()
        progress = None
        if self.rank0 and sc.output.progress and sys.stderr.isatty():
            from tqdm import tqdm
            progress = tqdm(total=N, initial=self.state.cycle, unit="cycle", desc=sc.name, leave=False,
                            mininterval=1.0)
        jumping = sc.wear.cycle_jump
        # A jump lands on (never skips) the cycles whose outputs are asked for, and on the last one.
        landings = sorted((self.snapshots | {c for c in loop_cycles if 1 <= c <= N}) | {N})
        cycle = self.state.cycle + 1
        while cycle <= N:
            t0 = time.perf_counter()
            keep = cycle in self.snapshots
            write_history = keep or cycle == 1 or cycle % every == 0 or cycle in loop_cycles
            st = self.state
            saved = (st.increment, st.d, st.y, st.r, st.gw, st.energy, st.local_iterations, st.last_row,
                     st.r_warm)
            growths = len(self.window_growths)
            if use_kernel:
                hists, keeps = self._kernel_cycle(cycle, keep or jumping)
            else:
                hists, keeps = self._python_cycle(cycle, keep or jumping)
            jump = {}
            if jumping:
                room = next(c for c in landings if c > cycle) - cycle if cycle < N else 1
                try:
                    jump = self._jump(cycle, hists, keeps, saved[4], room, len(self.window_growths) > growths)
                except SimulationError:  # the simulated cycle is not committed either
                    (st.increment, st.d, st.y, st.r, st.gw, st.energy, st.local_iterations, st.last_row,
                     st.r_warm) = saved
                    raise
            dt_cycle = time.perf_counter() - t0
            crow = self._cycle_row(cycle, hists, dt_cycle, jump)
            self._check_small_sliding(hists["mean_relative_tangential"])
            self.state.cycle = cycle + jump.get("jump", 1) - 1
            self.state.last_cycle_row = crow
            if write_history:
                self._write_history(cycle, hists)
            self.writer.rows("cycles", [crow])
            if keep:
                for k in keeps:
                    self._profile(*k)
                last = keeps[-1]
                self._fields(float(last[0]["increment"]), last[3], last[0]["face_pressure"])
            self.writer.flush()
            if progress is not None:
                progress.update(self.state.cycle - cycle + 1)
            now = time.perf_counter()
            due = now - self.last_checkpoint >= sc.output.checkpoint_interval
            if self.comm.size > 1:  # clocks differ between ranks: rank 0 decides for all (collective below)
                due = self.comm.bcast(due, root=0)
            if keep or cycle == N or due:
                self.checkpoint()
            if progress is None and (keep or now - t_report > 10.0):
                t_report = now
                self.say(f"[{sc.name}] cycle {cycle}/{N}: max wear depth {crow['max_wear_depth']:.4g} mm, "
                         f"energy {crow['dissipated_energy']:.4g}, {crow['regime']}, p_max(end) "
                         f"{crow['max_pressure_end']:.4g} MPa"
                         + (f", jump {crow['jump']} ({crow['jump_bound']})" if jumping else ""))
            cycle = self.state.cycle + 1
        if progress is not None:
            progress.close()

    def write_worn_profiles(self) -> None:
        """``worn_profiles.csv``: each body's worn depth along the contact (rank 0, at the end of a run).

        Both bodies see the same pressure and slip, so each wears its share ``k_body / k_total`` of the wear
        gap; the flat's depth is placed at the master point paired with each cylinder node.
        """
        import csv

        cs, share = self.model.contact, self.scene.wear.slave_share
        gw = self.state.gw
        master_x = cs.master_points[:, 0] if cs.two_body else np.full(cs.nc, np.nan)
        with open(self.out / "worn_profiles.csv", "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["position", "wear_gap", "cylinder_wear", "flat_position", "flat_wear"])
            for row in zip(cs.abscissa, gw, share * gw, master_x, (1 - share) * gw):
                w.writerow([f"{v:.12g}" for v in row])

    def _grow_window(self, where: str) -> None:
        """Widen the candidate window by half (at least 3 elements, at most the refined zone), rebuild the
        contact set and W, and carry the state over: new candidates start open and unworn; the relative
        positions y are recomputed from the forces (elastic: y = W r + q exactly). Collective."""
        model, st = self.model, self.state
        old = model.contact
        h = self.scene.geometry.contact_mesh_size
        before = model.half_width
        model.set_window(min(model.window_limit, max(1.5 * before, before + 3 * h)))
        new = model.contact
        where_old = {int(g): i for i, g in enumerate(old.global_nodes)}
        src = np.array([where_old.get(int(g), -1) for g in new.global_nodes])
        had = src >= 0
        dim = new.dim

        def carry(values: np.ndarray, per_contact: int) -> np.ndarray:
            lead = values.shape[:-1]
            out = np.zeros(lead + (new.nc, per_contact))
            out[..., had, :] = values.reshape(lead + (old.nc, per_contact))[..., src[had], :]
            return out.reshape(lead + (new.nc * per_contact,))

        st.gw = carry(st.gw, 1)
        st.r = carry(st.r, dim)
        if st.r_warm is not None:
            st.r_warm = carry(st.r_warm, dim)
        self.solver = IncrementSolver(model)
        self.mu = np.full(new.nc, self.scene.contact.mu)
        for attr in ("_kernel_data", "pattern_cache"):
            self.__dict__.pop(attr, None)
        frame = model.obstacle.frame
        D = st.d[0] * frame[0] + st.d[1] * frame[1]
        pressure = (getattr(self, "last_targets", None) or (0.0, 0.0, 0.0))[2]
        _, q_abs = self.solver._q(D, pressure, np.zeros(new.nc * dim), st.gw)
        st.y = model.W @ st.r + q_abs
        self.window_growths.append({"at": where, "from": before, "to": model.half_width, "contacts": new.nc})
        self.say(f"[{self.scene.name}] WARNING: {where}: the contact reached the edge of the candidate window "
                 f"(half-width {before:.4g} mm); grown to {model.half_width:.4g} mm ({new.nc} candidates) and the "
                 "increment solved again")

    def _check_small_sliding(self, relative_tangential: np.ndarray) -> None:
        """Two bodies: warn once when the relative slip exceeds half a master element (pairing is fixed)."""
        self.max_relative_tangential = max(self.max_relative_tangential,
                                           float(np.abs(relative_tangential).max(initial=0.0)))
        limit = 0.5 * self.scene.geometry.contact_mesh_size
        if self.model.two_body and not self._sliding_warned and self.max_relative_tangential > limit:
            self._sliding_warned = True
            self.say(f"[{self.scene.name}] WARNING: relative slip {self.max_relative_tangential:.3g} mm exceeds half "
                     f"a contact element ({limit:.3g} mm): the contact pairs are fixed in the reference "
                     "configuration (small sliding), so the flat's displacement is taken up to "
                     f"{self.max_relative_tangential / self.scene.geometry.contact_mesh_size:.2g} elements away "
                     "from the point facing each cylinder node. Pressure and wear stay consistent; the flat's "
                     "worn profile is attached to the reference pairing.")

    def _write_history(self, cycle: int, hists: dict[str, np.ndarray]) -> None:
        n = hists["increment"].size
        head = list(zip(hists["increment"].tolist(), [cycle] * n, hists["step"].tolist()))
        cols = ["normal_displacement", "tangential_displacement", "face_pressure", *ROW_FIELDS,
                "local_iterations", "local_error", "load_solves", "newton_iterations", "newton_delta_1",
                "newton_delta_2", "cutbacks", "yielded_points"]
        self.writer.history_block(head, np.column_stack([hists[c] for c in cols]), "cycle")

    def _cycle_row(self, cycle: int, h: dict[str, np.ndarray], wall: float,
                   jump: dict[str, Any] | None = None) -> dict[str, Any]:
        sc = self.scene
        Q = h["tangential_force"]
        disp = h["tangential_displacement"] if sc.loading.tangential_kind == "displacement" \
            else h["mean_relative_tangential"]
        E = float(h["dissipated_energy"].sum())
        Qa = 0.5 * (Q.max() - Q.min())
        da = 0.5 * (disp.max() - disp.min())
        loaded = (h["n_stick"] + h["n_slip"]) > 0
        min_stick = int(h["n_stick"][loaded].min()) if loaded.any() else 0
        gross = bool(np.any((h["n_stick"] == 0) & (h["n_slip"] > 0)))
        jump = jump or {}
        n_jump = jump.get("jump", 1)
        return {"cycle": cycle, "equivalent_cycles": (cycle + n_jump - 1) * sc.wear.acceleration,
                "jump": n_jump, "jump_bound": jump.get("bound", "none"),
                "jump_stability_limit": jump.get("stability_limit", 0.0),
                "jump_error_estimate": jump.get("error", 0.0),
                "wear_error_estimate": jump.get("error_total", 0.0), "dissipated_energy": E,
                "wear_area": float(h["wear_area"][-1]), "max_wear_depth": float(h["max_wear_depth"][-1]),
                "tangential_force_max": float(Q.max()), "tangential_force_min": float(Q.min()),
                "displacement_max": float(disp.max()), "displacement_min": float(disp.min()),
                "energy_ratio": E / (4 * Qa * da) if Qa * da > 0 else 0.0, "min_stick": min_stick,
                "regime": "gross_slip" if gross else ("partial_slip" if loaded.any() else "open"),
                "max_pressure_end": float(h["max_pressure"][-1]),
                "local_iterations": int(h["local_iterations"].sum()), "wall_time_s": round(wall, 6)}

    def _python_cycle(self, cycle: int, keep: bool):
        return self._cycle_growing_window(self._python_cycle_once, cycle, keep)

    def _cycle_growing_window(self, run_cycle, cycle: int, keep: bool):
        """Run a cycle; if the contact reaches the window's edge, grow it and run the cycle again (a cycle
        that stopped there was rolled back or not committed)."""
        while True:
            try:
                return run_cycle(cycle, keep)
            except _WindowTooSmall as edge:
                self._grow_window(str(edge))

    def _python_cycle_once(self, cycle: int, keep: bool):
        saved = (self.state.increment, self.state.d, self.state.y, self.state.r, self.state.gw, self.state.energy,
                 self.state.local_iterations, self.state.last_row)
        saved_targets = getattr(self, "last_targets", None)
        self._cycle_gw0 = self.state.gw.copy()
        rows, keeps = [], []
        try:
            for step in cycle_path(self.scene.loading, cycle):
                hist, x, y, states = self._python_increment(step)
                rows.append(hist)
                if keep:
                    keeps.append((hist, x, y, self.state.r, self.state.gw, states))
            self._check_wear_step(cycle, saved[4], self.state.gw)
        except (SimulationError, _WindowTooSmall):
            st = self.state
            st.increment, st.d, st.y, st.r, st.gw, st.energy, st.local_iterations, st.last_row = saved
            self.last_targets = saved_targets
            raise
        h = {k: np.array([r[k] for r in rows]) for k in rows[0] if k != "stage"}
        return h, keeps

    def _kernel_cycle(self, cycle: int, keep: bool):
        return self._cycle_growing_window(self._kernel_cycle_once, cycle, keep)

    def _kernel_cycle_once(self, cycle: int, keep: bool):
        from .cycling import N_ROW, run_increments

        sc, st, cs = self.scene, self.state, self.model.contact
        lo = sc.loading
        n = lo.increments_per_cycle
        m = cs.nc * cs.dim
        wave = lo.tangential_amplitude * waveform(lo.waveform, n)
        dn = np.full(n, lo.normal_displacement)
        dt = wave if lo.tangential_kind == "displacement" else np.zeros(n)
        s = wave if lo.tangential_kind == "pressure" else np.zeros(n)
        result, new_warm = None, None
        if self.rank0:
            if not hasattr(self, "_kernel_data"):
                from .cycling import ActivePatternCache
                W = np.ascontiguousarray(self.model.W.T)
                self._kernel_data = (W, local_solvers.block_rho(self.model.W, cs.dim))
                self.pattern_cache = ActivePatternCache(n, cs.nc, cs.dim)
            Wc, rho = self._kernel_data
            pc = self.pattern_cache
            active = pc.enabled and sc.solver.pattern_reuse
            warm = 1 if st.r_warm is not None and st.r_warm.shape == (n, m) and sc.solver.warm_start == "cycle" else 0
            r_warm = st.r_warm.copy() if warm else np.zeros((n, m))
            gw, y, r_last = st.gw.copy(), st.y.copy(), st.r.copy()
            shape_k = (n, m) if keep else (1, 1)
            out_r, out_x, out_y = np.zeros(shape_k), np.zeros(shape_k), np.zeros(shape_k)
            out_gw = np.zeros((n, cs.nc) if keep else (1, 1))
            out_states = np.zeros((n, cs.nc) if keep else (1, 1), dtype=np.int8)
            hist = np.zeros((n, N_ROW))
            done, status, err = run_increments(
                Wc, rho, self.mu, cs.dim, cs.gap0, gw, self.model.q_f, cs.tributary, cs.abscissa, dn, dt, s, y,
                r_last, r_warm, warm, self.k, sc.solver.local_tol, sc.solver.local_max_iter,
                local_solvers._REFRESH, keep, out_r, out_x, out_y, out_gw, out_states, hist, active, pc.pattern,
                pc.lu, pc.piv, pc.lu_ok, pc.counts)
            if done < n:
                step = done + 1
                result = ("fail", f"increment {st.increment + step} (cycle {cycle}, step {step}): local solver "
                          f"did not converge ({'non-finite values' if status == 2 else 'max_iter reached'}, "
                          f"error {err:.3e} >= tol {sc.solver.local_tol:.1e} after {sc.solver.local_max_iter} "
                          "sweeps); raise solver.local_max_iter or loosen solver.local_tol, then resume")
            else:
                result = ("ok", hist, gw, y, r_last, (out_r, out_x, out_y, out_gw, out_states) if keep else None)
                new_warm = r_warm  # kept only once the cycle is accepted (below)
        if self.comm.size > 1:  # (a serial bcast would still pickle every array)
            result = self.comm.bcast(result, root=0)
        if result[0] == "fail":
            raise SimulationError(result[1])
        _, hist, gw, y, r_last, outs = result
        first = st.increment + 1
        # The window's edge first (a truncated contact concentrates load and wear at the end node: grow the
        # window rather than refuse the wear), then the wear step, as on the per-increment path.
        edge = hist[:, ROW["edge_loaded"]] > 0
        if self._window_edges_matter and edge.any():
            j = int(np.flatnonzero(edge)[0])
            self._window_error(first + j, cycle, j + 1)
        self._check_wear_step(cycle, st.gw, gw)
        if self.rank0:
            st.r_warm = new_warm
        st.increment += n
        st.gw, st.y, st.r = gw, y, r_last
        st.d = np.array([dn[-1], dt[-1]])
        nf = len(ROW_FIELDS)
        st.energy += float(hist[:, ROW["dissipated_energy"]].sum())
        st.local_iterations += int(hist[:, nf].sum())
        h = {name: hist[:, i] for i, name in enumerate(ROW_FIELDS)}
        h.update(increment=np.arange(first, first + n), step=np.arange(1, n + 1), normal_displacement=dn,
                 tangential_displacement=dt, face_pressure=s, local_iterations=hist[:, nf].astype(int),
                 local_error=hist[:, nf + 1], load_solves=np.ones(n, dtype=int), newton_iterations=np.ones(n, dtype=int),
                 cutbacks=np.zeros(n, dtype=int), yielded_points=np.zeros(n, dtype=int),
                 newton_delta_1=np.zeros(n), newton_delta_2=np.zeros(n))
        st.last_row = {"increment": first + n - 1, "cycle": cycle, "step": n, "stage": "cycle",
                       **{k: (v[-1].item() if hasattr(v[-1], "item") else v[-1]) for k, v in h.items()
                          if k not in ("increment", "step")}}
        keeps = []
        if keep:
            out_r, out_x, out_y, out_gw, out_states = outs
            for j in range(n):
                row = {"increment": first + j, "cycle": cycle, "step": j + 1, "face_pressure": float(s[j])}
                keeps.append((row, out_x[j], out_y[j], out_r[j], out_gw[j], out_states[j]))
        return h, keeps

    # Cycle jumps -----------------------------------------------------------------------------------
    def _jump(self, cycle: int, h: dict[str, np.ndarray], keeps: list, gw_start: np.ndarray,
              room: int, regrown: bool = False) -> dict[str, Any]:
        """After simulated cycle ``cycle``: the error of the previous jump, the next jump dN and the wear gap
        extrapolated over its dN - 1 cycles (:mod:`dolfinx_fretting.cycle_jump`). Decided on rank 0,
        broadcast; raises SimulationError (before anything is committed) if a forced jump would wear more
        than a contact element. ``regrown``: the candidate window grew during the cycle (new contact set)."""
        from .cycle_jump import analyse_cycle, choose_jump, jump_error

        sc, st, cs, js = self.scene, self.state, self.model.contact, self.jump_state
        w = sc.wear
        h_e = self.model.body.contact_mesh_size
        if regrown:
            # The contact set changed: no per-contact rate to compare with or to extrapolate from. The previous
            # jump's error is bounded by (dN - 1) times the larger rate (each rate is >= 0), and this cycle
            # stands for itself; jumps restart from one.
            dim = cs.dim
            wear = [self.k * k[3][0::dim] / cs.tributary * np.abs(k[1][1::dim]) * (k[5] == 2) for k in keeps]
            new = float(np.sum(wear, axis=0).max(initial=0.0))  # this cycle's Archard wear per contact
            old = float(js["rate"].max(initial=0.0)) if js["rate"] is not None else 0.0
            err = (js["last"] - 1) * max(old, new)
            js.update(rate=None, last=1, free=1, simulated=js["simulated"] + 1, error=js["error"] + err,
                      bound="window_grown")
            return {"jump": 1, "bound": "window_grown", "stability_limit": js["stability_limit"], "error": err,
                    "error_total": js["error"]}
        result = None
        if self.rank0:
            a = analyse_cycle(self.model.W, cs.dim, cs.tributary, np.array([k[5] for k in keeps]),
                              np.array([k[1] for k in keeps]), np.array([k[3] for k in keeps]), gw_start, st.gw,
                              sc.loading.normal_force_controlled)
            err = jump_error(js["rate"], a.rate, js["last"]) if js["rate"] is not None else 0.0
            dN, bound, free = choose_jump(a, self.k, h_e, w.jump_wear_fraction, w.jump_pressure_change, w.jump_max,
                                          js["free"], room)
            if w.jump_forced is not None:
                dN, bound, free = min(w.jump_forced, room), "forced", w.jump_forced
            if cycle == 1:  # it starts from the preload, not from a cycle: its wear is not the cycles' rate
                dN, bound = 1, "first_cycle"
            result = (a.rate, err, dN, bound, free, a.stability_limit(self.k), a.monotone_limit(self.k))
        if self.comm.size > 1:
            result = self.comm.bcast(result, root=0)
        rate, err, dN, bound, free, stab, mono = result
        added = dN * float(rate.max(initial=0.0))
        if added > h_e:
            raise SimulationError(
                f"cycle {cycle}: a jump of {dN} cycles would wear up to {added:.3g} mm, more than the contact "
                f"element size {h_e:.3g} mm (the explicit update is unstable there); lower wear.jump_forced "
                f"(now {w.jump_forced}; stability limit here {stab:.4g} cycles)")
        if dN > 1:
            extra = dN - 1
            st.gw = st.gw + extra * rate
            st.increment += extra * sc.loading.increments_per_cycle
            st.energy += extra * float(h["dissipated_energy"].sum())
        js.update(rate=rate, last=dN, free=free, simulated=js["simulated"] + 1, jumps=js["jumps"] + (dN > 1),
                  largest=max(js["largest"], dN), error=js["error"] + err, bound=bound,
                  stability_limit=stab, monotone_limit=mono, exceeded=js["exceeded"] + (dN > stab),
                  min_stability_limit=min(js["min_stability_limit"], stab))
        if dN > stab and js["exceeded"] == 1:
            self.say(f"[{sc.name}] WARNING: cycle {cycle}: forced jump {dN} exceeds the stability limit "
                     f"{stab:.4g} cycles: expect oscillating edge spikes")
        return {"jump": dN, "bound": bound, "stability_limit": stab, "error": err, "error_total": js["error"]}

    # Summary ----------------------------------------------------------------------------------------
    def summary(self, error: str | None) -> dict[str, Any]:
        sc, model, st = self.scene, self.model, self.state
        g = sc.geometry
        summary: dict[str, Any] = {
            "scene": sc.name, "dofs": model.n_dofs, "contacts": model.contact.nc,
            "delassus_method": model.delassus_method, **{k: round(v, 6) for k, v in model.timings.items()},
            "increments": st.increment, "cycles": st.cycle, "converged": error is None,
            "resumed_from_cycle": self.resumed_from_cycle,
            "cycles_this_run": st.cycle - (self.resumed_from_cycle or 0),
            "local_iterations": st.local_iterations, "wall_time_s": round(time.perf_counter() - self.t_start, 6),
            "wear_law": sc.wear.law, "wear_k": sc.wear.k_total, "wear_acceleration": sc.wear.acceleration,
            "wear_k_effective": self.k, "equivalent_cycles": st.cycle * sc.wear.acceleration,
            "dissipated_energy": st.energy, "material_model": sc.material.model,
            "obstacle": "rigid plane (the flat is rigid)" if sc.contact.obstacle == "rigid_plane"
            else "elastic flat (two deformable bodies of the same material, small-sliding pairing)",
        }
        if model.two_body:
            share = sc.wear.slave_share
            summary.update({"wear_k_slave": sc.wear.k_total * share, "wear_k_master": sc.wear.k_total * (1 - share),
                            "max_wear_depth_slave": share * float(st.gw.max(initial=0.0)),
                            "max_wear_depth_master": (1 - share) * float(st.gw.max(initial=0.0)),
                            "max_relative_tangential": self.max_relative_tangential,
                            "small_sliding_warning": self._sliding_warned})
        if model.plastic is not None:
            ps = model.plastic.state
            local = np.array([ps.p.max(initial=0.0), ps.von_mises().max(initial=0.0)])
            gmax = np.empty(2)
            self.comm.Allreduce(local, gmax, op=MPI.MAX)  # elementwise (the pickle-based max is not)
            summary.update({"max_equivalent_plastic_strain": float(gmax[0]), "max_von_mises": float(gmax[1]),
                            "newton_tangent": sc.solver.newton_tangent,
                            "newton_full_fallbacks": getattr(self, "fallbacks", 0),
                            "tangent_refactorizations": model.plastic.refactorizations})
        if sc.loading.cycles > 0:
            summary["cycle_path"] = getattr(self, "cycle_mode", "python")
            if sc.wear.cycle_jump:
                summary["cycle_jump"] = self._jump_summary()
            if hasattr(self, "pattern_cache"):
                c = self.pattern_cache.counts
                summary["pattern_solves"] = {"accepted": int(c[0]), "rejected": int(c[1]), "factorizations": int(c[2])}
        if st.last_row:
            r = st.last_row
            summary.update({k: r[k] for k in ("normal_force", "tangential_force", "max_pressure", "contact_width",
                                              "stick_width", "max_wear_depth", "wear_area")})
            summary.update({k: int(r[k]) for k in ("n_open", "n_stick", "n_slip")})
            summary["edge_loaded"] = bool(st.last_row.get("edge_loaded", 0))
        if st.last_cycle_row:
            summary["regime"] = st.last_cycle_row["regime"]
        if g.kind == "half_cylinder" and st.last_row:
            E_star = sc.material.E / (1 - sc.material.nu**2) / (2.0 if model.two_body else 1.0)
            a, p0 = hertz_line_contact(st.last_row["normal_force"], g.radius, E_star)
            summary.update({"hertz_reference": ("two identical elastic bodies: E* = E/(2(1-nu^2))" if model.two_body
                                                else "rigid plane, frictionless: E* = E/(1-nu^2)"),
                            "hertz_half_width": a, "hertz_max_pressure": p0})
        summary["contact_window"] = model.half_width
        summary["window_growths"] = self.window_growths
        summary["modelled"] = self._modelled()
        if error is not None:
            summary["error"] = error
        return summary

    def _jump_summary(self) -> dict[str, Any]:
        """The jumps taken, the error estimate and the stability limits (``summary.cycle_jump``)."""
        from .cycle_jump import hertz_jump_limit

        sc, js = self.scene, self.jump_state
        finite = lambda v: v if math.isfinite(v) else None  # noqa: E731 - JSON has no infinity
        out = {"simulated_cycles": js["simulated"], "jumps": js["jumps"], "largest_jump": js["largest"],
               "wear_error_estimate": js["error"], "last_bound": js["bound"],
               "stability_limit_last": finite(js["stability_limit"]),
               "monotone_limit_last": finite(js["monotone_limit"]),
               "stability_limit_min": finite(js["min_stability_limit"]),
               "jumps_past_stability_limit": js["exceeded"], "forced": sc.wear.jump_forced,
               "bounds": {"wear_fraction": sc.wear.jump_wear_fraction,
                          "pressure_change": sc.wear.jump_pressure_change, "max_jump": sc.wear.jump_max}}
        lo, m = sc.loading, sc.material
        if sc.geometry.kind == "half_cylinder" and lo.tangential_kind == "displacement" and self.k > 0:
            E_star = m.E / (1 - m.nu**2) / (2.0 if self.model.two_body else 1.0)
            out["hertz_estimate_0.37h/(k delta E*)"] = hertz_jump_limit(
                self.model.body.contact_mesh_size, self.k, abs(lo.tangential_amplitude), E_star)
        return out

    def _modelled(self) -> dict[str, str]:
        """What this run assembled and iterated, and what it skipped (the scene decides)."""
        sc, model = self.scene, self.model
        cs = model.contact
        plastic = model.plastic
        window = model.half_width
        return {
            "material": ("J2 plasticity: Newton with the contact inside each iteration, tangent "
                         f"'{sc.solver.newton_tangent}', {plastic.refactorizations} tangent refactorisations"
                         if plastic is not None else "linear elastic: no Newton loop, no plastic state"),
            "delassus": ("W of the elastic K built once" + (", W of the tangent rebuilt at each refactorisation"
                                                          if plastic is not None else "")),
            "friction": f"Coulomb, mu = {sc.contact.mu}" if sc.contact.mu > 0 else "frictionless (mu = 0): "
                        "normal-only contact, the local problem solved on the normal rows of W alone",
            "wear": (f"Archard, k = {sc.wear.k_total} 1/MPa x acceleration {sc.wear.acceleration}"
                     + (f" (cylinder {sc.wear.slave_share:.3g}, flat {1 - sc.wear.slave_share:.3g} of the wear gap)"
                        if model.two_body else "")
                     + (", cycle jumps (wear gap extrapolated between simulated cycles)" if sc.wear.cycle_jump
                        else "")
                     if sc.wear.law == "archard" else "none (wear gap stays zero)"),
            "contact": f"{cs.nc} candidate nodes" + (f" within {window:.4g} mm of the first contact point"
                                                     + (" (automatic: Hertz estimate plus margin"
                                                        + (f", grown {len(self.window_growths)} time(s)"
                                                           if self.window_growths else "") + ")"
                                                        if model.window_automatic else "")
                                                     if window is not None else " (whole contact face)")
                       + (", each paired with a point of the elastic flat (node-to-segment, fixed pairing)"
                          if model.two_body else ", against a rigid plane"),
            "loads": (f"{sc.loading.cycles} cycles ({getattr(self, 'cycle_mode', 'python')} path)"
                      if sc.loading.cycles > 0 else "preload and a monotonic tangential load")
                     + ("; face pressure load" if model.face_load is not None else ""),
        }


def run_scene(scene: Scene, out_dir: str | Path, comm: MPI.Comm = MPI.COMM_WORLD, quiet: bool = False,
              resume: bool = False, overwrite: bool = False) -> dict[str, Any]:
    """Run a scene and write its outputs into ``out_dir``. Collective.

    Args:
        scene: A validated scene.
        out_dir: Output folder.
        comm: Communicator.
        quiet: Print nothing.
        resume: Continue from ``out_dir/checkpoint.npz`` (the scene may differ only in its ``solver`` and
            ``output`` sections and in ``loading.cycles``).
        overwrite: Delete the run ``out_dir`` holds first (its files only; :mod:`dolfinx_fretting.outdir`).

    Returns:
        The summary (also written to ``out_dir/summary.json``).

    Raises:
        OutputFolderError: before any work: ``out_dir`` is a file, not writable, locked by another run, or
            holds a run and neither ``resume`` nor ``overwrite`` is given.
        SimulationError: when an increment fails or a result is not finite; the outputs of the converged
            increments (of the last complete cycle in a cyclic run), a checkpoint to resume from and a summary
            with ``converged = false`` and the diagnostic are on disk.
    """
    with claim_output_folder(out_dir, comm, resume=resume, overwrite=overwrite):  # before the mesh; held to the end
        return _run_scene(scene, Path(out_dir), comm, quiet, resume)


def _run_scene(scene: Scene, out: Path, comm: MPI.Comm, quiet: bool, resume: bool) -> dict[str, Any]:
    run = _Run(scene, out, comm, quiet, resume)
    error = None
    try:
        run.run_stepwise(preload_path(scene.loading) if scene.loading.cycles > 0 else monotonic_path(scene.loading))
        if scene.loading.cycles > 0:
            run.run_cycles()
    except SimulationError as exc:
        error = str(exc)
        run.say(f"[{scene.name}] STOPPED: {error}")
        if scene.loading.cycles > 0 and run.state.increment >= scene.loading.normal_increments:
            run.checkpoint()  # the last complete cycle: resume from it with other solver settings
    summary = run.summary(error)
    if error is None and non_finite_keys(summary):  # never a success with an inf or a NaN in it
        error = f"non-finite results: {', '.join(non_finite_keys(summary))}"
        summary = run.summary(error)
    run.writer.summary(summary)
    if run.rank0 and scene.wear.law == "archard":
        run.write_worn_profiles()
    run.writer.close()
    if run.rank0 and scene.output.xdmf and scene.output.contact_profiles:
        from .contact_output import write_contact_xdmf
        try:
            write_contact_xdmf(out)
        except Exception as exc:  # noqa: BLE001 - the CSV it comes from is on disk whatever happens here
            run.say(f"[{scene.name}] WARNING: contact.xdmf not written: {type(exc).__name__}: {exc}")
    if run.rank0 and scene.output.plots and run.state.last_row:
        from .plots import plot_run
        try:
            plot_run(out, scene)
        except Exception as exc:  # noqa: BLE001 - a failed picture must not lose a finished run
            run.say(f"[{scene.name}] WARNING: plots failed: {type(exc).__name__}: {exc}")
        if scene.output.xdmf:  # pyvista pictures, in a child process: a VTK failure costs only them
            from .pictures import draw_in_subprocess
            pictures = draw_in_subprocess(out, scene.contact.plane_point, scene.contact.plane_normal)
            run.say(f"[{scene.name}] {pictures}")
    run.say(f"[{scene.name}] {'done' if error is None else 'FAILED'}: {summary['increments']} increments, "
            f"{summary['cycles']} cycles, P = {summary.get('normal_force', 0):.6g} N/mm, "
            f"Q = {summary.get('tangential_force', 0):.6g} N/mm, p_max = {summary.get('max_pressure', 0):.6g} MPa, "
            f"contact width = {summary.get('contact_width', 0):.4g} mm, stick width = "
            f"{summary.get('stick_width', 0):.4g} mm, max wear depth = {summary.get('max_wear_depth', 0):.4g} mm, "
            f"{summary['wall_time_s']:.2f} s -> {out}")
    if run.model.plastic is not None:
        run.model.plastic.destroy()
    run.model.problem.destroy()
    if error is not None:
        raise SimulationError(error)
    return summary
