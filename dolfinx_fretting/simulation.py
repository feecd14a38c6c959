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

A cyclic run writes a checkpoint (``checkpoint.npz``) every ``output.checkpoint_interval`` seconds, at
snapshot cycles and at the end; ``run_scene(..., resume=True)`` continues from it with the same results
as an uninterrupted run. A failed increment is reported with its cycle and step; the failed cycle leaves
no trace in the wear gap, the tables or the checkpoint.
"""

from __future__ import annotations

import json
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
from .io import _jsonable
from .contact import ContactSet, RigidPlane, find_candidates
from .loading import LoadControlError, LoadStep, cycle_path, find_displacement, monotonic_path, preload_path, waveform
from .scenes import Scene
from .wear import ROW, ROW_FIELDS, commit_increment

__all__ = ["ContactModel", "IncrementSolver", "RunState", "SimulationError", "run_scene", "CHECKPOINT"]

#: Checkpoint file name in the output folder.
CHECKPOINT = "checkpoint.npz"
# Scene sections that may change between a checkpoint and its resume (they do not change the physics).
_RESUMABLE_SECTIONS = ("solver", "output")


class SimulationError(RuntimeError):
    """An increment could not be solved, or a run cannot be resumed; the message says which, and why."""


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
        if g.kind == "half_cylinder":
            self.body = meshes.half_cylinder(comm, g.radius, contact_mesh_size=g.contact_mesh_size,
                                             contact_half_width=g.refined_half_width,
                                             coarse_mesh_size=g.coarse_mesh_size, quadrilateral=g.quadrilateral)
        else:
            self.body = meshes.rectangle(comm, g.width, g.height, g.nx, g.ny, quadrilateral=g.quadrilateral)
        fixed = ["top"]
        self.timings["mesh_s"] = time.perf_counter() - t0

        surface = scene.contact.surface
        if surface not in self.body.tags:
            raise SimulationError(f"contact.surface = {surface!r} is not a boundary of the "
                                  f"{g.kind} mesh; allowed: {', '.join(sorted(self.body.tags))}")
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

        facets = self.body.facet_tags.find(self.body.tags[surface])
        half_width = scene.contact.candidate_half_width
        if half_width is None and g.kind == "half_cylinder":
            half_width = g.refined_half_width
        try:
            self.contact: ContactSet = find_candidates(self.problem.V, facets, self.obstacle, half_width,
                                                       exclude_nodes=self.problem.fixed_nodes)
        except ValueError as exc:
            raise SimulationError(str(exc)) from None

        t0 = time.perf_counter()
        self.problem.delassus.factorize()
        self.timings["factorize_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        W = self.problem.delassus.build(self.contact.H)
        # One copy decides: the local solve must see identical input on every rank.
        self.W = comm.bcast(W if comm.rank == 0 else None, root=0)
        self.timings["delassus_s"] = time.perf_counter() - t0
        self.delassus_method = self.problem.delassus.method

        # A face pressure reaches the contact through q_f = H K^-1 f (one more solve with the same factor).
        self.face_load = None
        self.q_f = np.zeros(self.contact.nc * self.contact.dim)
        if scene.loading.tangential_kind == "pressure":
            self.face_load = self.problem.face_pressure_load(scene.loading.pressure_face)
            self.q_f = self.problem.local_response(self.contact.H, self.face_load)  # allreduced: replicated

        # Elastic-plastic: Newton with the contact inside (plasticity.ElastoplasticBody); nothing plastic is
        # built for an elastic scene.
        self.plastic = None
        if scene.material.model == "elastoplastic":
            from .materials import J2Plasticity
            from .plasticity import ElastoplasticBody

            m, sv = scene.material, scene.solver
            law = J2Plasticity(m.E, m.nu, m.yield_stress, m.plastic_modulus)
            self.plastic = ElastoplasticBody(self.problem, law, self.contact.H, self.W, self.face_load,
                                             tangent=sv.newton_tangent, max_iter=sv.newton_max_iter,
                                             delta_1=sv.newton_residual_tol, delta_2=sv.newton_displacement_tol,
                                             quadrature_degree=self.quadrature_degree)

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
        self.k_once = scene.wear.k if scene.wear.law == "archard" else 0.0
        self.snapshots = _snapshot_cycles(scene)
        if checkpoint is None:
            self.state = RunState.initial(model)
            sizes, xdmf_started = None, False
        else:
            self.state, sizes, xdmf_started = self._restore(checkpoint)
        self.writer = ResultWriter(out_dir, comm, profiles=scene.output.contact_profiles, resume_sizes=sizes,
                                   xdmf_started=xdmf_started)
        self.last_checkpoint = time.perf_counter()
        self.say(f"[{scene.name}] {model.n_dofs} dofs, {cs.nc} contact candidates, "
                 f"W by {model.delassus_method} in {model.timings['delassus_s']:.3f} s"
                 + (f"; resumed after increment {self.state.increment} (cycle {self.state.cycle})"
                    if checkpoint is not None else ""))

    # Checkpoints ------------------------------------------------------------------------------------
    def _read_checkpoint(self) -> dict[str, Any]:
        path = self.out / CHECKPOINT
        if not path.is_file():
            raise SimulationError(f"--resume: no checkpoint {path}; run without --resume to start afresh")
        with np.load(path, allow_pickle=False) as data:
            ck = {k: data[k] for k in data.files}
        meta = json.loads(str(ck["meta"]))
        if meta["identity"] != _scene_identity(self.scene):
            raise SimulationError(f"--resume: the scene differs from the one checkpointed in {path} beyond "
                                  f"the sections {', '.join(_RESUMABLE_SECTIONS)} and loading.cycles; "
                                  "resume with the same scene, or start afresh in a new folder")
        ck["meta"] = meta
        return ck

    def _restore(self, ck: dict[str, Any]) -> tuple[RunState, dict[str, int], bool]:
        meta = ck["meta"]
        st = RunState(int(meta["increment"]), int(meta["cycle"]), ck["d"].copy(), ck["y"].copy(), ck["r"].copy(),
                      ck["gw"].copy(), float(meta["energy"]), int(meta["local_iterations"]),
                      ck["r_warm"].copy() if ck["r_warm"].size else None, meta.get("last_row"),
                      meta.get("last_cycle_row"))
        if st.gw.size != self.model.contact.nc:
            raise SimulationError("--resume: the checkpoint's contact set does not match the scene's mesh")
        if meta.get("last_targets") is not None:
            self.last_targets = tuple(meta["last_targets"])
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
                    "last_targets": getattr(self, "last_targets", None), "ranks": self.comm.size}
            tmp = self.out / (CHECKPOINT + ".tmp.npz")
            np.savez(tmp, meta=json.dumps(meta, default=_jsonable), d=st.d, y=st.y, r=st.r, gw=st.gw,
                     r_warm=st.r_warm if st.r_warm is not None else np.zeros(0), **plastic)
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
        cs = self.model.contact
        where = f"increment {increment}" + (f" (cycle {cycle}, step {step})" if cycle else "")
        raise SimulationError(
            f"{where}: the outermost contact candidates (x = {cs.abscissa[0]:.4g} .. {cs.abscissa[-1]:.4g} mm) "
            "carry load: the contact reaches the edge of the candidate window and would be truncated; widen "
            f"contact.candidate_half_width (now {self.scene.contact.candidate_half_width} mm) and "
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
        solved = self._local(step, st.r)
        hist, states = self._commit(step, solved)
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
            self.writer.fields(t, self._plastic_fields())
            return
        p = self.model.problem
        p.solve_contact_response(self.model.contact.H, r, self.model.face_load, pressure)
        self.writer.fields(t, [p.u, p.von_mises()])

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
        for cycle in range(self.state.cycle + 1, N + 1):
            t0 = time.perf_counter()
            keep = cycle in self.snapshots
            write_history = keep or cycle == 1 or cycle % every == 0 or cycle in loop_cycles
            if use_kernel:
                hists, keeps = self._kernel_cycle(cycle, keep)
            else:
                hists, keeps = self._python_cycle(cycle, keep)
            dt_cycle = time.perf_counter() - t0
            crow = self._cycle_row(cycle, hists, dt_cycle)
            self.state.cycle = cycle
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
                progress.update(1)
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
                         f"{crow['max_pressure_end']:.4g} MPa")
        if progress is not None:
            progress.close()

    def _write_history(self, cycle: int, hists: dict[str, np.ndarray]) -> None:
        n = hists["increment"].size
        head = list(zip(hists["increment"].tolist(), [cycle] * n, hists["step"].tolist()))
        cols = ["normal_displacement", "tangential_displacement", "face_pressure", *ROW_FIELDS,
                "local_iterations", "local_error", "load_solves", "newton_iterations", "newton_delta_1",
                "newton_delta_2", "cutbacks", "yielded_points"]
        self.writer.history_block(head, np.column_stack([hists[c] for c in cols]), "cycle")

    def _cycle_row(self, cycle: int, h: dict[str, np.ndarray], wall: float) -> dict[str, Any]:
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
        return {"cycle": cycle, "equivalent_cycles": cycle * sc.wear.acceleration, "dissipated_energy": E,
                "wear_area": float(h["wear_area"][-1]), "max_wear_depth": float(h["max_wear_depth"][-1]),
                "tangential_force_max": float(Q.max()), "tangential_force_min": float(Q.min()),
                "displacement_max": float(disp.max()), "displacement_min": float(disp.min()),
                "energy_ratio": E / (4 * Qa * da) if Qa * da > 0 else 0.0, "min_stick": min_stick,
                "regime": "gross_slip" if gross else ("partial_slip" if loaded.any() else "open"),
                "max_pressure_end": float(h["max_pressure"][-1]),
                "local_iterations": int(h["local_iterations"].sum()), "wall_time_s": round(wall, 6)}

    def _python_cycle(self, cycle: int, keep: bool):
        saved = (self.state.increment, self.state.d, self.state.y, self.state.r, self.state.gw, self.state.energy,
                 self.state.local_iterations, self.state.last_row)
        self._cycle_gw0 = self.state.gw.copy()
        rows, keeps = [], []
        try:
            for step in cycle_path(self.scene.loading, cycle):
                hist, x, y, states = self._python_increment(step)
                rows.append(hist)
                if keep:
                    keeps.append((hist, x, y, self.state.r, self.state.gw, states))
            self._check_wear_step(cycle, saved[4], self.state.gw)
        except SimulationError:
            st = self.state
            st.increment, st.d, st.y, st.r, st.gw, st.energy, st.local_iterations, st.last_row = saved
            raise
        h = {k: np.array([r[k] for r in rows]) for k in rows[0] if k != "stage"}
        return h, keeps

    def _kernel_cycle(self, cycle: int, keep: bool):
        from .cycling import N_ROW, run_increments

        sc, st, cs = self.scene, self.state, self.model.contact
        lo = sc.loading
        n = lo.increments_per_cycle
        m = cs.nc * cs.dim
        wave = lo.tangential_amplitude * waveform(lo.waveform, n)
        dn = np.full(n, lo.normal_displacement)
        dt = wave if lo.tangential_kind == "displacement" else np.zeros(n)
        s = wave if lo.tangential_kind == "pressure" else np.zeros(n)
        result = None
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
                st.r_warm = r_warm
                result = ("ok", hist, gw, y, r_last, (out_r, out_x, out_y, out_gw, out_states) if keep else None)
        if self.comm.size > 1:  # (a serial bcast would still pickle every array)
            result = self.comm.bcast(result, root=0)
        if result[0] == "fail":
            raise SimulationError(result[1])
        _, hist, gw, y, r_last, outs = result
        first = st.increment + 1
        self._check_wear_step(cycle, st.gw, gw)
        edge = hist[:, ROW["edge_loaded"]] > 0
        if self._window_edges_matter and edge.any():
            j = int(np.flatnonzero(edge)[0])
            self._window_error(first + j, cycle, j + 1)
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

    # Summary ----------------------------------------------------------------------------------------
    def summary(self, error: str | None) -> dict[str, Any]:
        sc, model, st = self.scene, self.model, self.state
        g = sc.geometry
        summary: dict[str, Any] = {
            "scene": sc.name, "dofs": model.n_dofs, "contacts": model.contact.nc,
            "delassus_method": model.delassus_method, **{k: round(v, 6) for k, v in model.timings.items()},
            "increments": st.increment, "cycles": st.cycle, "converged": error is None,
            "local_iterations": st.local_iterations, "wall_time_s": round(time.perf_counter() - self.t_start, 6),
            "wear_law": sc.wear.law, "wear_k": sc.wear.k, "wear_acceleration": sc.wear.acceleration,
            "wear_k_effective": self.k, "equivalent_cycles": st.cycle * sc.wear.acceleration,
            "dissipated_energy": st.energy, "material_model": sc.material.model,
            "obstacle": "rigid plane (the flat is rigid: two deformable bodies are not modelled yet)"
            if sc.contact.obstacle == "rigid_plane" else sc.contact.obstacle,
        }
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
            a, p0 = hertz_line_contact(st.last_row["normal_force"], g.radius,
                                       sc.material.E / (1 - sc.material.nu**2))
            summary.update({"hertz_reference": "rigid plane, frictionless: E* = E/(1-nu^2)",
                            "hertz_half_width": a, "hertz_max_pressure": p0})
        summary["modelled"] = self._modelled()
        if error is not None:
            summary["error"] = error
        return summary

    def _modelled(self) -> dict[str, str]:
        """What this run assembled and iterated, and what it skipped (the scene decides)."""
        sc, model = self.scene, self.model
        cs = model.contact
        plastic = model.plastic
        window = sc.contact.candidate_half_width
        if window is None and sc.geometry.kind == "half_cylinder":
            window = sc.geometry.refined_half_width
        return {
            "material": ("J2 plasticity: Newton with the contact inside each iteration, tangent "
                         f"'{sc.solver.newton_tangent}', {plastic.refactorizations} tangent refactorisations"
                         if plastic is not None else "linear elastic: no Newton loop, no plastic state"),
            "delassus": ("W of the elastic K built once" + (", W of the tangent rebuilt at each refactorisation"
                                                          if plastic is not None else "")),
            "friction": f"Coulomb, mu = {sc.contact.mu}" if sc.contact.mu > 0 else "frictionless (mu = 0)",
            "wear": (f"Archard, k = {sc.wear.k} 1/MPa x acceleration {sc.wear.acceleration}"
                     if sc.wear.law == "archard" else "none (wear gap stays zero)"),
            "contact": f"{cs.nc} candidate nodes" + (f" within {window} mm of the first contact point"
                                                     if window is not None else " (whole contact face)"),
            "loads": (f"{sc.loading.cycles} cycles ({getattr(self, 'cycle_mode', 'python')} path)"
                      if sc.loading.cycles > 0 else "preload and a monotonic tangential load")
                     + ("; face pressure load" if model.face_load is not None else ""),
        }


def run_scene(scene: Scene, out_dir: str | Path, comm: MPI.Comm = MPI.COMM_WORLD, quiet: bool = False,
              resume: bool = False) -> dict[str, Any]:
    """Run a scene and write its outputs into ``out_dir``. Collective.

    Args:
        scene: A validated scene.
        out_dir: Output folder.
        comm: Communicator.
        quiet: Print nothing.
        resume: Continue from ``out_dir/checkpoint.npz`` (the scene may differ only in its ``solver`` and
            ``output`` sections and in ``loading.cycles``).

    Returns:
        The summary (also written to ``out_dir/summary.json``).

    Raises:
        SimulationError: when an increment fails; the outputs of the converged increments (of the last
            complete cycle in a cyclic run), a checkpoint to resume from and a summary with
            ``converged = false`` and the diagnostic are on disk.
    """
    out = Path(out_dir)
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
    run.writer.summary(summary)
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
