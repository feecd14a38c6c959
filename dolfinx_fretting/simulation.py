"""The scene runner: a scene file in, results on disk out, through the public API.

``run_scene`` is a user of :mod:`dolfinx_fretting.problem` like any script: the scene's geometry kind
(:mod:`dolfinx_fretting.geometries`) writes the model (space, form, conditions, loads, contact set-up), a
:class:`~dolfinx_fretting.contact.Contact` and a :class:`~dolfinx_fretting.problem.FrettingProblem` are built
from it, and the run walks the load path of the scene:

1. the preload (and, without cycles, a monotonic tangential load), increment by increment
   (``problem.advance``: solve, commit; elastic–plastic increments are cut back on failure);
2. the cycles, one ``problem.run_cycle`` each (the compiled loop for elastic cycles, force-controlled
   ones included), each checked (contact at the candidate window's edge, wear step) before it is committed;
   with ``wear.cycle_jump`` a simulated cycle is followed by a jump (:mod:`dolfinx_fretting.cycle_jump`);
3. the outputs: tables and fields as the run goes, checkpoints, the summary, plots and pictures.

What a checkpoint holds is the problem's state (``problem.save_state``) and the run's :class:`Progress`;
``run_scene(..., resume=True)`` continues from it with the uninterrupted run's results. A failed increment
stops the run with its cycle and step; the failed cycle leaves no trace in the wear gap, the tables or the
checkpoint (its state is simply not committed).
"""

from __future__ import annotations

import json
import math
import os
import signal
import sys
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI
from tqdm import tqdm

from . import friction
from .commit import acceleration
from .analytic import hertz_line_contact
from .contact import Contact
from .contact_output import write_contact_xdmf
from .cycle_jump import (PlasticCycle, analyse_cycle, analyse_plastic_cycle, choose_jump, cycle_wear,
                         extrapolate_plastic_history, hertz_jump_limit, jump_error, local_jump_error,
                         plastic_jump_error, plastic_jump_limit, propagate_error, tolerance_jump_limit)
from .fatigue_outputs import FATIGUE_TABLE, FATIGUE_XDMF, FatigueOutputs
from .interrupts import Interrupted, RunSignals, stage_hook
from .io import FRICTION_CYCLE_FIELDS, non_finite_keys, write_json_atomic
from .materials import J2Plasticity, elastic_stiffness
from .output import FrettingWriter, RunDescription, contact_measures
from .pictures import PICTURES, draw_in_subprocess
from .plots import plot_run
from .units import Units
from .scene_paths import LoadStep, cycle_path, monotonic_path, preload_path
from .problem import (Archard, ContactState, ConvergenceError, CyclePath, CycleResult,
                      Displacement, Force, FrettingProblem, LocalSolver, PlasticHistory, Plasticity, WindowError)
from .outdir import RUN_FILES, OutputFolderError, OutputLock, claim_output_folder, folder_lost, load_checkpoint
from .geometries import build_scene_model
from .scene_models import BULK_STRESS_LOAD, PRESSURE_LOAD, MeshFileError, SceneModel
from .scenes import Scene, SceneError, describe_differences, scene_differences
from .sizes import SizeEstimate, check_size

__all__ = ["ContactModel", "Progress", "SimulationError", "RunInterrupted", "OutputFolderLost", "run_scene",
           "read_checkpoint", "CHECKPOINT"]

#: The run's files (:data:`~dolfinx_fretting.outdir.RUN_FILES`) as a set, for the check after each write.
_RUN_FILE_NAMES = frozenset(RUN_FILES)

#: Checkpoint file name in the output folder.
CHECKPOINT = "checkpoint.npz"
# Scene sections that may change between a checkpoint and its resume (they do not change the physics).
_RESUMABLE_SECTIONS = ("solver", "output")
# Scene keys that may change too: labels of the run, not physics.
_RENAMEABLE_KEYS = ("name", "description")
# The differences a refused resume spells out with both values (the others by key).
_SHOWN_DIFFERENCES = 6


class SimulationError(RuntimeError):
    """An increment could not be solved, or a run cannot be resumed; the message says which, and why."""


#: What to change when an increment does not converge (the scene keys of the solvers).
_HINT = ("; raise solver.local_max_iter or loosen solver.local_tol (local solver), solver.newton_max_iter or "
         "solver.max_cutbacks or use more increments (Newton), then resume")


class OutputFolderLost(SimulationError):
    """The output folder was deleted or replaced during the run (found before a write): the run stopped and wrote
    nothing more (nothing into a folder of the same name either); the message says which and when."""


class RunInterrupted(RuntimeError):
    """SIGINT or SIGTERM stopped a run cleanly, whatever it was doing (building the model, the increments and
    cycles, the outputs): the lock released, a checkpoint (in the cycles) and a summary marked interrupted that
    lists what is missing are on disk, and the message says what to do. ``exit_code`` is 130 (SIGINT) or 143
    (SIGTERM)."""

    def __init__(self, message: str, signum: int):
        super().__init__(message)
        self.signum = signum
        self.exit_code = 128 + signum


class _Stop(Exception):
    """Internal: a signal arrived; the run stops at the end of the current increment or cycle."""


class _WindowTooSmall(Exception):
    """The contact reached the candidate window's edge and the window can grow (internal: caught by the run)."""


class ContactModel:
    """A scene's model and its :class:`~dolfinx_fretting.problem.FrettingProblem`. Collective to build.

    Attributes:
        setup: The geometry's :class:`~dolfinx_fretting.scene_models.SceneModel`.
        problem: The fretting problem (K factorised, W built).
        timings: Wall times of mesh, assembly + factorisation + W.
    """

    def __init__(self, scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD, window: float | None = None):
        self.scene = scene
        self.comm = comm
        try:
            self.setup: SceneModel = build_scene_model(scene, comm, applies_model_fraction=True)
        except MeshFileError as exc:  # bad input (the file or what the scene asks of it), before any assembly
            raise SceneError(str(exc)) from None
        except (ValueError, KeyError) as exc:
            raise SimulationError(str(exc).strip("'\"")) from None
        s, sv, m = self.setup, scene.solver, scene.material
        self.half_width = s.window if window is None else window
        try:
            all_bcs = s.bcs + [bc for conditions in s.prescribed.values() for bc in conditions]
            recovery = scene.contact.pressure_recovery
            contact = Contact(s.V, s.surface, s.obstacle, scene.contact.friction_law(), all_bcs, self.half_width,
                              pressure_recovery=recovery)
            # further zones (a mesh file's [[contact]] tables): each its surface, plane, friction and window
            zones = [Contact(s.V, zone.surface, zone.obstacle, zone.mu, all_bcs, zone.window, pressure_recovery=recovery)
                     for zone in s.zones]
        except ValueError as exc:
            raise SimulationError(str(exc)) from None
        #: The zones as given to the problem (the API's keys of their targets), the scene's first table first.
        self.contacts = (contact, *zones)
        wear = scene.wear.wear_law()
        plasticity = None
        if m.model == "elastoplastic":
            plasticity = Plasticity(J2Plasticity(m.E, m.nu, m.yield_stress, m.plastic_modulus),
                                    quadrature_degree=sv.quadrature_degree or 2, tangent=sv.newton_tangent,
                                    max_iter=sv.newton_max_iter, residual_tol=sv.newton_residual_tol,
                                    displacement_tol=sv.newton_displacement_tol, max_cutbacks=sv.max_cutbacks,
                                    elastic_cells=s.elastic_cells)
        stage_hook("delassus")  # a test's signal while K is factorised and W built (interrupts.TEST_HOOK)
        solver = LocalSolver(method=sv.local_method, tol=sv.local_tol, max_iter=sv.local_max_iter,
                             force_tol=sv.force_tol, compiled_cycles=sv.cycle_kernel, warm_start=sv.warm_start,
                             pattern_reuse=sv.pattern_reuse)
        try:  # the API's refusals of the model the scene made (e.g. a boundary.displacement of 1e-300: zero values)
            self.problem = FrettingProblem(s.form, list(self.contacts) if zones else contact, s.bcs, wear=wear,
                                           loads=s.loads, prescribed=s.prescribed,
                                           petsc_options=sv.petsc_options, delassus_method=sv.delassus_method,
                                           solver=solver, plasticity=plasticity,
                                           options_prefix="dolfinx_fretting_delassus_")
        except ValueError as exc:
            raise SimulationError(str(exc)) from None
        self.timings = {**s.timings, **self.problem.operators.timings}

    # What tests and benchmarks read -----------------------------------------------------------------
    @property
    def body(self):
        return self.setup.body

    @property
    def contact(self):
        """The :class:`~dolfinx_fretting.contact.ContactSet` (nodes, frames, H)."""
        return self.problem.contact.contact_set

    @property
    def W(self) -> np.ndarray:
        return self.problem.operators.W

    @property
    def plastic(self):
        """The elastic–plastic body (Newton), or None."""
        return self.problem.body

    @property
    def n_dofs(self) -> int:
        return self.problem.n_dofs

    @property
    def window_edges_matter(self) -> bool:
        """Load on the first zone's outermost candidates means a truncated contact: the geometry says its window's
        ends are not the body's edges, and some node of the surface lies outside the window (a window that holds the
        whole surface ends at the surface's own ends)."""
        return self.setup.window_edges_matter and self.problem.contacts[0].outside is not None

    @property
    def window_can_grow(self) -> bool:
        s = self.setup
        return (self.problem.body is None and self.problem.operators.surface_compliance is None and s.window_limit is not None
                and self.half_width is not None and self.half_width < s.window_limit)

    def grow_window(self, state: ContactState) -> ContactState:
        """Widen the first zone's window by half (at least 3 elements, at most its limit); the state carried over.
        (Only the built-in geometries' windows grow, and they have one zone.)"""
        s = self.setup
        new = min(s.window_limit, max(1.5 * self.half_width, self.half_width + 3 * s.element_size))
        state = self.problem.set_window(state, new, zone=0)
        self.half_width = new
        return state


@dataclass
class Progress:
    """The run's own bookkeeping beside the problem's state (checkpointed with it)."""

    cycle: int = 0                                   #: Cycles completed (physical, jumps included).
    last_row: dict[str, Any] | None = None            #: The last history row.
    last_cycle_row: dict[str, Any] | None = None
    window_growths: list[dict[str, Any]] = field(default_factory=list)
    max_relative_tangential: float = 0.0              #: Largest |mean relative tangential position|.
    sliding_warned: bool = False
    newton_fallbacks: int = 0
    plastic_regime: str = "none"                      #: The last simulated cycle's (elastic-plastic bodies).
    #: ``[fatigue]``: what its outputs need to resume (``fatigue_outputs.FatigueOutputs.saved``).
    fatigue: dict[str, Any] | None = None
    jump: dict[str, Any] = field(default_factory=lambda: {
        # error: the run's wear-gap error estimate (max |propagated| + carried); error_sum: the jumps' bounds summed
        # (not propagated); error_vector: the propagated error per contact after the last jump (rank 0's decision);
        # error_carried: what a contact-set change folded out of it (no longer propagated)
        "rate": None, "last": 1, "free": 1, "simulated": 0, "jumps": 0, "largest": 1, "error": 0.0,
        "error_sum": 0.0, "error_vector": None, "error_carried": 0.0,
        "bound": "none", "stability_limit": math.inf, "monotone_limit": math.inf, "exceeded": 0,
        "min_stability_limit": math.inf, "plastic_error": 0.0, "plastic_error_pending": 0.0, "plastic_net": 0.0,
        "plastic_flow": 0.0})


#: Elastic-plastic jumps: a cycle after a jump is a rate to jump on if its plastic changes differ from those of
#: the cycle before the jump by at most this fraction of themselves at every point (else one more cycle).
SETTLED_RATE_CHANGE = 0.5


def read_checkpoint(path: str | Path) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """A checkpoint's run progress (``cycle``, ``jump``, ``window_growths`` ...; plus the state's ``increment``)
    and the state's arrays (``wear_gap``, ``forces``, ``positions`` ...), for inspection."""
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files if k != "state"}
        info = json.loads(str(data["state"]))
    return {**info["meta"]["progress"], "increment": info["increment"]}, arrays


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


def _target(force_controlled: bool, value, model_fraction: float):
    """A scene's obstacle target for the API: a force is the whole contact's, so a model of a fraction of the
    bodies (a half model) is given that fraction of it; a displacement is the same for any fraction."""
    return Force(np.asarray(value) * model_fraction) if force_controlled else Displacement(np.asarray(value))


def _tangential_target(force_controlled: bool, value, setup: SceneModel):
    """A scene's tangential target (along t1) for the API. A force in a model whose conditions hold a tangential
    direction (:attr:`SceneModel.held_tangential`: the half model's t2) is one item per component: the force
    along t1, a zero displacement along a held direction (the API refuses a force there), a zero force along
    any other. ``value`` is a number (an increment) or an array (a cycle's increments)."""
    if not (force_controlled and setup.held_tangential):
        return _target(force_controlled, value, setup.model_fraction)
    zero = np.zeros_like(np.asarray(value, dtype=float))
    return tuple(_target(True, value, setup.model_fraction) if k == 1
                 else Displacement(zero) if k in setup.held_tangential else Force(zero)
                 for k in range(1, setup.V.mesh.geometry.dim))


def _step_targets(step: LoadStep, model: ContactModel, normal_increments: int) -> dict[str, Any]:
    """The API's arguments of a scene's load step (the geometry's ramped loads follow the preload)."""
    loads = {PRESSURE_LOAD: step.pressure} if PRESSURE_LOAD in model.problem.load_names else {}
    if BULK_STRESS_LOAD in model.problem.load_names:
        loads[BULK_STRESS_LOAD] = step.bulk_stress
    for name in model.setup.ramped:
        loads[name] = min(1.0, step.increment / normal_increments) if step.stage == "normal" else 1.0
    fraction = model.setup.model_fraction
    normal = _target(step.normal_force_controlled, step.normal, fraction)
    tangential = _tangential_target(step.tangential_force_controlled, step.tangential, model.setup)
    if len(model.contacts) > 1:  # [loading] drives the first zone; the others reach their approach with the preload
        ramp = min(1.0, step.increment / normal_increments) if step.stage == "normal" else 1.0
        first, *others = model.contacts
        normal = {first: normal, **{contact: Displacement(ramp * zone.approach)
                                    for contact, zone in zip(others, model.setup.zones)}}
        tangential = {first: tangential}
    return {"normal": normal, "tangential": tangential, "loads": loads}


def _cycle_path(scene: Scene, model: ContactModel) -> CyclePath:
    """The targets of every cycle of the scene (the same each cycle: built once); with several zones the first
    zone's (the others keep their approach: a zone not named keeps its targets)."""
    steps = cycle_path(scene.loading, 1)
    first = steps[0]
    setup = model.setup
    pressures = np.array([s.pressure for s in steps])
    loads = {PRESSURE_LOAD: pressures} if PRESSURE_LOAD in model.problem.load_names else {}
    if BULK_STRESS_LOAD in model.problem.load_names:
        loads[BULK_STRESS_LOAD] = np.array([s.bulk_stress for s in steps])
    normal = _target(first.normal_force_controlled, [s.normal for s in steps], setup.model_fraction)
    tangential = _tangential_target(first.tangential_force_controlled, [s.tangential for s in steps], setup)
    if len(model.contacts) > 1:
        normal, tangential = {model.contacts[0]: normal}, {model.contacts[0]: tangential}
    return CyclePath(normal, tangential, loads)


def _description(scene: Scene, model: ContactModel, path: CyclePath | None) -> RunDescription:
    """The scene's run described for the folder's readers (``run.json``)."""
    loading, hertz = scene.loading, model.setup.hertz
    return RunDescription.of(
        model.problem, scene.name, path=path, cycles=loading.cycles, preload_increments=loading.normal_increments,
        plane_point=scene.contact.plane_point, tangential_control=loading.tangential_kind,
        tangential_amplitude=float(loading.tangential_amplitude or 0.0),
        pressure_face=loading.pressure_face if loading.tangential_kind == "pressure" else None,
        wear_acceleration=scene.wear.acceleration, hertz=hertz[:2] if hertz is not None else None,
        track_positions=tuple(scene.output.track_positions), loop_cycles=tuple(scene.output.loop_cycles),
        model_fraction=model.setup.model_fraction, units=Units.mm_N_MPa(),
        surfaces=[scene.contact.surface, *(zone.surface for zone in scene.zones)])


def _writer_resume(meta: dict[str, Any]) -> dict[str, Any]:
    """What the writer resumes from (:meth:`FrettingWriter.checkpoint_info` as checkpointed): the tables' sizes,
    the XDMF state and its time steps (``None`` from a checkpoint of a version that did not count them)."""
    steps = meta.get("fields_steps")
    return {"sizes": {k: int(v) for k, v in meta["sizes"].items()}, "xdmf_started": bool(meta["xdmf_started"]),
            "fields_steps": int(steps) if steps is not None else None}


class _Run:
    """One run of a scene: the load path, the checks, the outputs and the checkpoints. Collective."""

    def __init__(self, scene: Scene, out_dir: Path, comm: MPI.Comm, quiet: bool, resume: bool,
                 size_estimate: SizeEstimate | None = None, lock: OutputLock | None = None,
                 signals: RunSignals | None = None):
        self.scene = scene
        self.size_estimate = size_estimate
        self.out = out_dir
        self.comm = comm
        #: The output folder's lock (its folder checked before every write: :meth:`check_folder`).
        self.lock = lock
        self._fresh: set[int] = set()
        self.signals = signals if signals is not None else RunSignals()
        self.rank0 = comm.rank == 0
        self.say = (lambda msg: print(msg, flush=True)) if (self.rank0 and not quiet) else (lambda msg: None)
        self.t_start = time.perf_counter()
        meta = self._read_checkpoint_meta() if resume else None
        # the model as checkpointed: a mesh sized from loading.cycles (a sphere's uniform zone) is not resized
        sized = meta.get("mesh_cycles", scene.loading.cycles) if meta else scene.loading.cycles
        built = scene.model_copy(update={"loading": scene.loading.model_copy(update={"cycles": sized})})
        self.model = ContactModel(built, comm, window=meta["window"] if meta else None)
        self.signals.reinstall()  # gmsh may have reset SIGINT's handler while it meshed
        self.problem = self.model.problem
        self.snapshots = _snapshot_cycles(scene)
        self.progress = Progress()
        #: The last simulated cycle's plastic changes (elastic-plastic jumps: the next jump's error needs them).
        self._plastic_previous: PlasticCycle | None = None
        #: After a settling cycle: (the cycle the jump was taken from, the jump, the settling cycle).
        self._plastic_pending: tuple[PlasticCycle, int, PlasticCycle] | None = None
        if meta is None:
            self.state = self.problem.initial_state()
        else:
            self.state = self._restore(meta)
        self.path = _cycle_path(scene, self.model) if scene.loading.cycles > 0 else None
        self.check_folder("before its first write")  # the writer would create a folder deleted while it meshed
        self.writer = FrettingWriter(
            self.problem, out_dir, _description(scene, self.model, self.path), profiles=scene.output.contact_profiles,
            fields=scene.output.xdmf, von_mises=self.model.setup.von_mises, pressure_load=PRESSURE_LOAD,
            shifted_cells=self.model.setup.display_cells,
            resume=_writer_resume(meta) if meta is not None else None)
        self.note_written()
        #: ``[fatigue]``: the evaluations, fatigue.csv and Miner's sum (a region without points refused here).
        self.fatigue: FatigueOutputs | None = None
        if scene.fatigue.enabled:
            try:
                self.fatigue = FatigueOutputs(scene, self.problem, out_dir, self.progress.fatigue if meta else None,
                                              self.state)
            except ValueError as exc:
                raise SimulationError(str(exc)) from None
            self.note_written()
        # proof of a resume in the summary: where it started, and the cycles this process simulated
        self.resumed_from_cycle = self.progress.cycle if meta is not None else None
        self.last_checkpoint = time.perf_counter()
        self.say(f"[{scene.name}] {self.problem.n_dofs} dofs, {self.model.contact.nc} contact candidates, "
                 f"W by {self.problem.operators.delassus_route} in {self.model.timings['delassus_s']:.3f} s"
                 + (" (the Schur route's second factor would not fit in the memory available)"
                    if self.problem.operators.delassus.stats.get("auto_schur_skipped_for_memory") else "")
                 + (f"; resumed after increment {self.state.increment} (cycle {self.progress.cycle})"
                    if meta is not None else ""))

    # Checkpoints ------------------------------------------------------------------------------------
    def _read_checkpoint_meta(self) -> dict[str, Any]:
        path = self.out / CHECKPOINT
        try:  # a damaged file, tables shorter than it records
            ck = load_checkpoint(path)
        except OutputFolderError as exc:
            raise SimulationError(f"--resume: {exc}") from None
        # The scene before the cycle count: another scene is told so, not only that its loading.cycles is short.
        # name and description are labels, not physics: a run may be renamed when it is resumed.
        saved, now = json.loads(ck["meta"]["identity"]), json.loads(_scene_identity(self.scene))
        changed = scene_differences(saved, now, ignore=_RENAMEABLE_KEYS)
        meta = ck["meta"]
        if changed:
            shown = describe_differences(saved, now, ignore=list(_RENAMEABLE_KEYS) + changed[_SHOWN_DIFFERENCES:],
                                         names=("checkpoint", "this scene"))
            more = (f"; and {len(changed) - _SHOWN_DIFFERENCES} more: {', '.join(changed[_SHOWN_DIFFERENCES:])}"
                    if len(changed) > _SHOWN_DIFFERENCES else "")
            names = (f" (checkpointed: {saved.get('name')!r}, this scene: {now.get('name')!r})"
                     if saved.get("name") != now.get("name") else "")
            raise SimulationError(f"--resume: the scene{names} differs from the one checkpointed in {path} beyond "
                                  f"the sections {', '.join(_RESUMABLE_SECTIONS)} and loading.cycles: {shown}{more}; "
                                  "resume with the same scene, or start afresh in a new folder")
        done = int(meta["cycle"])
        if self.scene.loading.cycles < done:
            raise SimulationError(f"--resume: loading.cycles = {self.scene.loading.cycles} is below the {done} cycles "
                                  f"the checkpoint {path} has done; allowed: loading.cycles >= {done}")
        return meta

    def _restore(self, meta: dict[str, Any]) -> ContactState:
        try:
            state, _ = self.problem.load_state(self.out / CHECKPOINT)
        except ValueError as exc:
            raise SimulationError(f"--resume: {exc}") from None
        progress = dict(meta["progress"])
        progress["jump"] = {**Progress().jump, **progress["jump"]}  # keys a checkpoint of an older version lacks
        # a settling cycle's estimate awaited its successor's rate, whose per-point changes are not checkpointed
        progress["jump"]["plastic_error"] += progress["jump"]["plastic_error_pending"]
        progress["jump"]["plastic_error_pending"] = 0.0
        for key in ("rate", "error_vector"):
            value = progress["jump"].get(key)
            progress["jump"][key] = np.array(value) if value is not None else None
        self.progress = Progress(**progress)
        return state

    def check_folder(self, when: str) -> None:
        """Collective: stop (:class:`OutputFolderLost`) if the output folder was deleted or replaced since the run
        took its lock. Called before every write and after it: nothing is left in whatever now has its name (a
        file written by path in the instant between a check and the folder's replacement is taken back)."""
        message = folder_lost(self.lock, self.comm) if self.lock is not None else None
        fresh, self._fresh = self._fresh, set()
        if message is not None:
            if self.rank0 and self.lock.replaced():
                self._take_back(fresh)
            raise OutputFolderLost(f"{message}; the run stopped {when} and writes nothing more (what it wrote there "
                                   "is gone with the folder): start it again")

    def note_written(self) -> None:
        """Rank 0, after a write: the files of the run now in the folder (by inode), until the next check. One
        listing of the folder (its entries carry their inodes), not a stat per run file: it follows every
        cycle's write."""
        if self.rank0 and self.lock is not None:
            try:
                with os.scandir(self.out) as entries:
                    self._fresh.update(entry.inode() for entry in entries if entry.name in _RUN_FILE_NAMES)
            except OSError:   # the folder is gone: nothing of the run is there to take back
                pass

    def _take_back(self, fresh: set[int]) -> None:
        """The folder was replaced: delete from the new one the files this run wrote there since its last check
        (the inodes :meth:`note_written` saw; none of the new folder's own)."""
        for name in RUN_FILES:
            path = self.out / name
            try:
                if os.stat(path).st_ino in fresh:
                    path.unlink()
            except OSError:
                pass

    def _done_so_far(self) -> str:
        return f"after increment {self.state.increment} (cycle {self.progress.cycle})"

    def checkpoint(self) -> None:
        self.check_folder(f"{self._done_so_far()}, before its checkpoint")
        if self.fatigue is not None:
            self.progress.fatigue = self.fatigue.saved()
        progress = asdict(self.progress)
        for key in ("rate", "error_vector"):
            value = self.progress.jump[key]
            progress["jump"][key] = value.tolist() if value is not None else None
        meta = {"identity": _scene_identity(self.scene), **self.writer.checkpoint_info(),
                "window": self.model.half_width, "mesh_cycles": self.model.scene.loading.cycles, "progress": progress,
                "written": time.strftime("%Y-%m-%dT%H:%M:%S")}
        try:
            self.problem.save_state(self.state, self.out / CHECKPOINT, meta=meta)
        except RuntimeError as exc:  # rank 0's write failed, raised on every rank (checkpoint.save_state)
            self.check_folder(f"{self._done_so_far()}, while it wrote its checkpoint")  # gone since the check?
            raise OSError(f"{self.out / CHECKPOINT} not written: {exc}") from None  # e.g. a full disk
        self.note_written()
        self.last_checkpoint = time.perf_counter()

    def _raise_if_lost(self, when: str) -> None:
        """After a write failed on this rank: :class:`OutputFolderLost` if the folder went while it wrote (not
        collective: the rank holding the lock decides alone, as for any failed write)."""
        message = self.lock.lost() if self.lock is not None else None
        if message is not None:
            raise OutputFolderLost(f"{message}; the run stopped {self._done_so_far()}, {when}, and writes nothing "
                                   "more (what it wrote there is gone with the folder): start it again") from None

    # Checks before a state is accepted ---------------------------------------------------------------
    def _where(self, increment: int, cycle: int = 0, step: int = 0, stage: str = "") -> str:
        return f"increment {increment}" + (f" (cycle {cycle}, step {step})" if cycle else f" ({stage})" if stage
                                           else "")

    def _check_window_edge(self, forces: np.ndarray, where: str) -> None:
        """The window's ends carry load: a truncated contact. Grow the window, or stop with a message."""
        rn = forces[0::self.model.contact.dim][:self.problem.contacts[0].nc]   # the first zone's (it grows)
        if self.model.window_edges_matter and (rn[0] > 0 or rn[-1] > 0):
            self._window_edge_reached(where)

    def _window_edge_reached(self, where: str, outside: WindowError | None = None) -> None:
        model, contact = self.model, self.model.contact
        if outside is not None and outside.zone > 0:  # a further [[contact]] table's window (it does not grow)
            zone = self.scene.zones[outside.zone - 1]
            raise SimulationError(
                f"{where}: {outside.positions.shape[0]} node(s) of contact[{outside.zone}] (surface "
                f"{zone.surface!r}) outside its candidate window penetrate its plane (by up to "
                f"{outside.penetration:.3g} mm); the window needed is {outside.window_needed:.4g} mm: widen "
                f"contact[{outside.zone}].candidate_half_width (now {zone.candidate_half_width:.4g} mm) or leave it "
                "out (its whole surface)")
        if model.window_can_grow:
            raise _WindowTooSmall(where)
        if self.scene.geometry.kind == "sphere":
            # A sphere's uniform zone is sized from the contact radius expected after wear (geometries.sphere);
            # the window may reach past it onto the graded cells.
            advice = (f"widen contact.candidate_half_width (now {model.half_width:.4g} mm; the mesh's uniform zone "
                      f"ends at {model.setup.window_limit:.4g} mm, beyond it the cells grow) or "
                      "geometry.contact_half_width (the uniform zone)")
        elif model.setup.window_limit is None or self.scene.geometry.kind == "file":  # no refined zone
            advice = (f"widen contact.candidate_half_width (now {model.half_width:.4g} mm) or leave it out (the "
                      "whole surface)")
        else:
            advice = (f"widen contact.candidate_half_width (now {model.half_width:.4g} mm) and "
                      "geometry.contact_half_width (the refined zone, now "
                      f"{self.scene.geometry.refined_half_width} mm)")
        what = (f"the outermost contact candidates (x = {contact.abscissa[0]:.4g} .. {contact.abscissa[-1]:.4g} mm) "
                "carry load: "
                "the contact reaches the edge of the candidate window and would be truncated" if outside is None else
                f"the contact reaches the edge of the candidate window and beyond: {outside.positions.shape[0]} "
                f"node(s) outside it penetrate the obstacle (by up to {outside.penetration:.3g} mm, the deepest at "
                f"{(np.round(outside.positions[0], 6) + 0.0).tolist()}); the window needed is {outside.window_needed:.4g} mm")
        raise SimulationError(f"{where}: {what}; {advice}")

    def _check_wear_step(self, cycle: int, gw_old: np.ndarray, gw_new: np.ndarray) -> None:
        """Refuse a cycle that wears more than the contact element size at some contact: the wear gap is
        explicit over a cycle, and such steps make oscillating edge spikes (the run stops instead)."""
        h = self.model.setup.element_size
        dw = float(np.max(gw_new - gw_old, initial=0.0))
        if not dw <= h:  # (a NaN wear step is refused too)
            raise SimulationError(
                f"cycle {cycle}: the wear gap grew by up to {dw:.3g} mm in one cycle, more than the contact element "
                f"size {h:.3g} mm; the explicit wear update is unstable there. Lower wear.acceleration (now "
                f"{self.scene.wear.acceleration:g}) or wear.k (now {self.scene.wear.k:g} 1/MPa)")

    def _grow_window(self, where: str, outside: WindowError | None = None) -> None:
        before = self.model.half_width
        self.state = self.model.grow_window(self.state)
        new = self.model.half_width
        self.progress.window_growths.append({"at": where, "from": before, "to": new,
                                             "contacts": self.model.contact.nc})
        why = ("the contact reached the edge of the candidate window" if outside is None else
               f"{outside.positions.shape[0]} node(s) outside the candidate window penetrated the obstacle (by up to "
               f"{outside.penetration:.3g} mm; window needed {outside.window_needed:.4g} mm)")
        self.say(f"[{self.scene.name}] WARNING: {where}: {why} (half-width {before:.4g} mm); grown to {new:.4g} mm "
                 f"({self.model.contact.nc} candidates) and the increment solved again")

    def _outside_penetrated(self, exc: WindowError, where: str) -> None:
        """Nodes outside the window penetrated (the problem's check): grow the window and solve again, or stop
        with the problem's message and the scene's keys. The runner grows by its own rule (by half, at least three
        elements, up to the refined zone), not straight to ``exc.window_needed``: its windows stay the ones an
        edge-triggered growth makes (the same checkpoints, summaries and reference runs), and the increment solved
        again is checked again, so a window still too small grows again."""
        if not self.model.window_can_grow or exc.zone != 0:
            self._window_edge_reached(where, exc)
        self._grow_window(where, exc)

    def _check_small_sliding(self, relative_tangential: np.ndarray) -> None:
        """Two bodies: warn once when the relative slip exceeds half a contact element (pairing is fixed)."""
        p = self.progress
        p.max_relative_tangential = max(p.max_relative_tangential,
                                        float(np.abs(relative_tangential).max(initial=0.0)))
        h = self.model.setup.element_size
        if self.model.setup.small_sliding and not p.sliding_warned and p.max_relative_tangential > 0.5 * h:
            p.sliding_warned = True
            self.say(f"[{self.scene.name}] WARNING: relative slip {p.max_relative_tangential:.3g} mm exceeds half "
                     f"a contact element ({0.5 * h:.3g} mm): the contact pairs are fixed in the reference "
                     "configuration (small sliding), so the flat's displacement is taken up to "
                     f"{p.max_relative_tangential / h:.2g} elements away from the point facing each cylinder node. "
                     "Pressure and wear stay consistent; the flat's worn profile is attached to the reference pairing.")

    # Increments -----------------------------------------------------------------------------------------
    def _increment(self, step: LoadStep) -> None:
        """Solve and commit one increment of the preload or monotonic stage."""
        where = self._where(step.increment, stage=step.stage)
        while True:
            try:
                state, info = self.problem.advance(
                    self.state, **_step_targets(step, self.model, self.scene.loading.normal_increments),
                    check=lambda s: self._check_window_edge(s.forces, where))
                break
            except _WindowTooSmall as edge:
                self._grow_window(str(edge))  # nothing of the increment was committed: solve it again
            except WindowError as exc:
                self._outside_penetrated(exc, where)
            except ConvergenceError as exc:
                raise SimulationError(f"{where}: {exc}" + _HINT) from None
        self.progress.newton_fallbacks += int(info.get("full_newton_fallbacks", 0))
        self.state = state

    def _say_increment(self, h: dict[str, Any]) -> None:
        self.say(f"[{self.scene.name}] inc {h['increment']:4d} {h['stage']:10s} P = {h['normal_force']:.6g} "
                 f"Q = {h['tangential_force']:.6g} p_max = {h['max_pressure']:.6g} it = {h['local_iterations']}")

    def run_stepwise(self, steps) -> None:
        """Preload and monotonic stages: every increment written (history, profile, fields)."""
        for step in steps:
            if step.increment <= self.state.increment:
                continue  # done before the checkpoint
            self._increment(step)
            self.check_folder(f"after increment {self.state.increment}, before writing it")
            hist = self.writer.write_increment(self.state, stage=step.stage)
            self.note_written()
            self.progress.last_row = hist
            self._check_small_sliding(np.array([hist["mean_relative_tangential"]]))
            self._say_increment(hist)
            self._stop_if_signalled()

    # Cycles ------------------------------------------------------------------------------------------------
    def _cycle(self, cycle: int, keep: bool, path: CyclePath) -> CycleResult:
        """Solve cycle ``cycle`` (not committed), growing the window and solving it again if its contact
        reaches the window's edge."""
        while True:
            start = self.state
            first = start.increment + 1

            def check(s: ContactState) -> None:  # increment by increment (the stepwise path)
                j = s.increment - start.increment
                self._check_window_edge(s.forces, self._where(first + j - 1, cycle, j))
                self._check_wear_step(cycle, start.wear_gap, s.wear_gap)

            try:
                result = self.problem.run_cycle(start, path, keep=keep, check=check)
                # The compiled loop: the window's edge first (a truncated contact concentrates load and wear at
                # the end node: grow the window rather than refuse the wear), then the wear step.
                edge = result.records["edge_loaded"] > 0
                if result.compiled and self.model.window_edges_matter and edge.any():
                    j = int(np.flatnonzero(edge)[0])
                    self._window_edge_reached(self._where(first + j, cycle, j + 1))
                self._check_wear_step(cycle, start.wear_gap, result.final.wear_gap)
                return result
            except _WindowTooSmall as edge:
                self._grow_window(str(edge))
            except WindowError as exc:
                self._outside_penetrated(exc, self._where(first + (exc.step or 1) - 1, cycle, exc.step or 1))
            except ConvergenceError as exc:
                raise SimulationError(f"{self._where(first + exc.step - 1, cycle, exc.step)}: {exc}"
                                      + _HINT) from None

    def run_cycles(self) -> None:
        scene = self.scene
        loading = scene.loading
        N = loading.cycles
        every = scene.output.history_every
        loop_cycles = set(scene.output.loop_cycles)
        t_report = time.perf_counter()
        progress_bar = None
        if self.rank0 and scene.output.progress and sys.stderr.isatty():
            progress_bar = tqdm(total=N, initial=self.progress.cycle, unit="cycle", desc=scene.name, leave=False,
                                mininterval=1.0)
        jumping = scene.wear.cycle_jump
        # A jump lands on (never skips) the cycles whose outputs are asked for, and on the last one.
        landings = sorted((self.snapshots | {c for c in loop_cycles if 1 <= c <= N}) | {N})
        path = self.path
        cycle = self.progress.cycle + 1
        while cycle <= N:
            t0 = time.perf_counter()
            keep = cycle in self.snapshots
            write_history = keep or cycle == 1 or cycle % every == 0 or cycle in loop_cycles
            growths = len(self.progress.window_growths)
            fatigue_due = self.fatigue is not None and self.fatigue.due(cycle)
            # (several zones: the writer reads each zone's columns from every increment's forces)
            result = self._cycle(cycle, keep or jumping or len(self.model.contacts) > 1 or fatigue_due, path)
            self.cycle_mode = "compiled" if result.compiled else "python"
            start = self.state
            new_state = self.problem.commit(start, result)
            plastic = self._plastic_cycle(start, new_state)  # collective; None for elastic bodies
            jump = {}
            if jumping:
                room = next(c for c in landings if c > cycle) - cycle if cycle < N else 1
                new_state, jump = self._jump(cycle, start, new_state, result, room,
                                             len(self.progress.window_growths) > growths, plastic)
            if plastic is not None:
                jump = {**jump, "plastic_regime": plastic.regime, "plastic_flow": plastic.flow,
                        "plastic_net": plastic.net}
                self.progress.plastic_regime = plastic.regime
            if fatigue_due:   # the cycle's states (before it is committed: a refusal leaves no trace of it)
                try:         # the block of cycles the evaluation stands for ends with the cycle's jump
                    self.fatigue.evaluate(cycle, result, cycle + jump.get("jump", 1) - 1)
                except ValueError as exc:
                    raise SimulationError(str(exc)) from None
            self.state = new_state
            self.progress.newton_fallbacks += int(result.records.get("full_newton_fallbacks", np.zeros(1)).sum())
            self._check_small_sliding(result.records["mean_relative_tangential"])
            self.check_folder(f"after cycle {cycle}, before writing it")
            crow = self.writer.write_cycle(cycle, start, result, history=write_history, profiles=keep,
                                           wall=time.perf_counter() - t0, jump=jump, end=new_state)
            if fatigue_due:
                self.fatigue.write()
            self.note_written()
            self.progress.cycle = cycle + jump.get("jump", 1) - 1
            self.progress.last_cycle_row = crow
            self.progress.last_row = self.writer.cycle_end_row(cycle, start, result)
            if progress_bar is not None:
                progress_bar.update(self.progress.cycle - cycle + 1)
            now = time.perf_counter()
            due = now - self.last_checkpoint >= scene.output.checkpoint_interval
            if self.comm.size > 1:  # clocks differ between ranks: rank 0 decides for all (collective below)
                due = self.comm.bcast(due, root=0)
            if keep or cycle == N or due:
                self.checkpoint()
            self._stop_if_signalled()
            if progress_bar is None and (keep or now - t_report > 10.0):
                t_report = now
                self.say(f"[{scene.name}] cycle {cycle}/{N}: max wear depth {crow['max_wear_depth']:.4g} mm, "
                         f"energy {crow['dissipated_energy']:.4g}, {crow['regime']}, p_max(end) "
                         f"{crow['max_pressure_end']:.4g} MPa"
                         + (f", {crow['plastic_regime']}" if plastic is not None else "")
                         + (f", jump {crow['jump']} ({crow['jump_bound']})" if jumping else ""))
            cycle = self.progress.cycle + 1
        if progress_bar is not None:
            progress_bar.close()

    def _stop_if_signalled(self) -> None:
        """Collective: stop after this increment or cycle if a signal reached any rank (mpirun forwards it to
        all; the allreduce makes every rank stop at the same point)."""
        signum = self.signals.received
        if self.comm.size > 1:
            signum = self.comm.allreduce(signum, op=MPI.MAX)
        if signum:
            self.signals.received = signum
            raise _Stop()

    # Cycle jumps -----------------------------------------------------------------------------------
    def _plastic_cycle(self, start: ContactState, new: ContactState) -> PlasticCycle | None:
        """What a simulated cycle did to an elastic-plastic body's state: its regime (elastic shakedown,
        plastic shakedown, ratcheting; ``material.shakedown_tolerance``) and changes. Collective; None for an
        elastic body."""
        if new.plastic is None or start.plastic is None:
            return None
        a, b = start.plastic, new.plastic
        return analyse_plastic_cycle(a.eps_p, a.p, b.eps_p, b.p, self.scene.material.shakedown_strain, self.comm)

    def _plastic_bounds(self, plastic: PlasticCycle | None) -> tuple[float, bool]:
        """An elastic-plastic body's jump bound (:func:`~dolfinx_fretting.cycle_jump.plastic_jump_limit`) and
        whether this cycle must settle (no jump from it); updates the plastic error estimate. Collective.

        The cycle after a jump of a still-flowing body may not be a rate: it carries the plastic state's
        relaxation back onto its cyclic path (a fast mode, gone within a cycle), which a jump would amplify dN
        times, with a flip of sign (explicit Euler on a stiff mode). Unless its plastic changes are within
        :data:`SETTLED_RATE_CHANGE` of themselves of the cycle before the jump at every point, it *settles*: the
        run simulates the next cycle before jumping again.

        The jump's error on the plastic strains (the larger of eps_p's equivalent and p's, per point) is, as for
        the wear gap, ``(dN - 1) max |change after - change before|``, with "after" the first cycle that is a
        rate: the settling cycle's successor, plus the settling cycle's own departure from it (the relaxation,
        once). Until that successor is simulated the estimate holds the bound from the settling cycle itself
        (``plastic_error_pending``), which is also what stays if the run ends or is resumed in between.
        """
        if plastic is None:
            return math.inf, False
        m, jumps = self.scene.material, self.progress.jump
        limit = plastic_jump_limit(plastic, self.scene.wear.jump_plastic_fraction, m.yield_stress, m.E,
                                   m.plastic_modulus)
        previous, last, pending = self._plastic_previous, jumps["last"], self._plastic_pending
        self._plastic_previous, self._plastic_pending = plastic, None
        settling = False
        if pending is not None:  # the cycle after a settling cycle: the jump's estimate from the settled rate
            before, jump, settling_cycle = pending
            error = ((jump - 1) * max(plastic_jump_error(before, plastic, 2, self.comm))
                     + max(plastic_jump_error(plastic, settling_cycle, 2, self.comm)))
            jumps.update(plastic_error=jumps["plastic_error"] + error, plastic_error_pending=0.0)
        elif last > 1:  # the cycle after a jump
            if previous is None:  # resumed: the changes per point are not checkpointed; bound them by their maxima
                error = (last - 1) * max(plastic.net + jumps["plastic_net"],
                                         plastic.flow + jumps["plastic_flow"])
                settled = False
            else:
                change_eps, change_p = plastic_jump_error(previous, plastic, 2, self.comm)  # per cycle
                error = (last - 1) * max(change_eps, change_p)
                settled = (change_eps <= SETTLED_RATE_CHANGE * plastic.net
                           and change_p <= SETTLED_RATE_CHANGE * plastic.flow)
            settling = (not settled and plastic.regime != "elastic_shakedown"
                        and self.scene.wear.jump_forced is None)
            if settling and previous is not None:
                self._plastic_pending = (previous, last, plastic)
                jumps["plastic_error_pending"] = error
            else:
                jumps["plastic_error"] += error
        jumps.update(plastic_net=plastic.net, plastic_flow=plastic.flow)
        return limit, settling

    def _jump(self, cycle: int, start: ContactState, new: ContactState, result: CycleResult, room: int,
              regrown: bool, plastic: PlasticCycle | None = None) -> tuple[ContactState, dict[str, Any]]:
        """After simulated cycle ``cycle``: the error of the previous jump, the next jump dN and the wear gap
        extrapolated over its dN - 1 cycles (:mod:`dolfinx_fretting.cycle_jump`). Decided on rank 0,
        broadcast; raises SimulationError (before anything is committed) if a forced jump would wear more
        than a contact element. ``regrown``: the candidate window grew during the cycle (new contact set).
        ``plastic``: an elastic-plastic body's cycle (:meth:`_plastic_cycle`): the jump is bounded by the
        plastic state's change too, and the plastic history is extrapolated with the wear gap."""
        scene, contact, jumps = self.scene, self.model.contact, self.progress.jump
        contact_zones = self.problem.contact
        w = scene.wear
        h_e = self.model.setup.element_size
        # the simulated cycle's rate (its friction coefficients'; after a window growth ``start`` is of the old
        # contact set: the new state's)
        k = self._wear_rate(new if regrown else start)
        out_r, out_x, _, _, out_status = result.kept
        plastic_limit, settling = self._plastic_bounds(plastic)  # collective: before rank 0 decides
        if regrown:  # (the window grows only for elastic bodies: plastic is None here)
            # The contact set changed: no per-contact rate to compare with or to extrapolate from. The previous
            # jump's error is bounded by (dN - 1) times the larger rate (each rate is >= 0), and this cycle
            # stands for itself; jumps restart from one. The propagated error cannot follow the contacts: its
            # maximum is carried, no longer propagated.
            this = float(cycle_wear(self.problem.wear_coefficients(True, new), contact.tributary, out_r, out_x,
                                    out_status, contact.dim).max(initial=0.0))
            old = float(jumps["rate"].max(initial=0.0)) if jumps["rate"] is not None else 0.0
            err = (jumps["last"] - 1) * max(old, this)
            vector = jumps["error_vector"]
            carried = jumps["error_carried"] + err + (float(np.abs(vector).max(initial=0.0)) if vector is not None
                                                      else 0.0)
            jumps.update(rate=None, last=1, free=1, simulated=jumps["simulated"] + 1, error=carried,
                         error_sum=jumps["error_sum"] + err, error_vector=None, error_carried=carried,
                         bound="window_grown")
            return new, {"jump": 1, "bound": "window_grown", "stability_limit": jumps["stability_limit"],
                         "error": err, "error_total": jumps["error"]}
        decided = None
        if self.rank0:
            a = analyse_cycle(self.problem.operators.W, contact.dim, contact.tributary, out_status, out_x, out_r,
                              start.wear_gap, new.wear_gap, scene.loading.normal_force_controlled)
            err = jump_error(jumps["rate"], a.rate, jumps["last"]) if jumps["rate"] is not None else 0.0
            local = (local_jump_error(jumps["rate"], a.rate, jumps["last"]) if jumps["rate"] is not None
                     else np.zeros(a.rate.size))
            before = jumps["error_vector"] if jumps["error_vector"] is not None else np.zeros(a.rate.size)
            # No drift from cycle 1 to the next: cycle 1 starts from the preload (its wear is not the cycles' rate),
            # and the doubling from one cycle holds the first jump.
            drifted_from = jumps["rate"] if cycle - jumps["last"] > 1 else None
            tolerance_limit = (math.inf if w.jump_tolerance is None
                               else tolerance_jump_limit(drifted_from, a.rate, jumps["last"], w.jump_tolerance))
            dN, bound, free = choose_jump(a, k, h_e, w.jump_wear_fraction,
                                          w.jump_pressure_change if w.jump_tolerance is None else None, w.jump_max,
                                          jumps["free"], room, plastic_limit, tolerance_limit)
            if w.jump_forced is not None:
                dN, bound, free = min(w.jump_forced, room), "forced", w.jump_forced
            if cycle == 1:  # it starts from the preload, not from a cycle: its wear is not the cycles' rate
                dN, bound = 1, "first_cycle"
            elif settling:
                dN, bound, free = 1, "plastic_settling", jumps["free"]
            # The jump extrapolates this cycle's wear rate, which holds only for its friction coefficients.
            friction_bound = friction.jump_limit(contact_zones, start, new, acceleration(self.problem.wear_laws))
            if dN > friction_bound:
                dN, bound = int(friction_bound), "friction_evolving"
            # The error at this cycle's start (the last jump's local error added), carried over this cycle and its
            # jump (decided above; error_vector: the error after it, the next cycle's start but for that jump's own)
            vector = propagate_error(before + local, a, k, dN)
            decided = (a.rate, err, dN, bound, free, a.stability_limit(k), a.monotone_limit(k), vector)
        if self.comm.size > 1:
            decided = self.comm.bcast(decided, root=0)
        rate, err, dN, bound, free, stab, mono, vector = decided
        added = dN * float(rate.max(initial=0.0))
        if added > h_e:
            raise SimulationError(
                f"cycle {cycle}: a jump of {dN} cycles would wear up to {added:.3g} mm, more than the contact "
                f"element size {h_e:.3g} mm (the explicit update is unstable there); lower wear.jump_forced "
                f"(now {w.jump_forced}; stability limit here {stab:.4g} cycles)")
        if dN > 1:
            extra = dN - 1
            new = replace(new, wear_gap=new.wear_gap + extra * rate,
                          increment=new.increment + extra * scene.loading.increments_per_cycle,
                          dissipated_energy=new.dissipated_energy
                          + extra * float(result.records["dissipated_energy"].sum()),
                          # the jumped cycles count for an evolving friction law (mu held over them: bound above)
                          cycles=new.cycles + extra * acceleration(self.problem.wear_laws),
                          friction_energy=None if new.friction_energy is None else
                          new.friction_energy + extra * (new.friction_energy - start.friction_energy))
            if plastic is not None and plastic.regime != "elastic_shakedown":  # eps_p and p follow the wear gap
                before, after, m = start.plastic, new.plastic, scene.material
                sigma, eps_p, p = extrapolate_plastic_history(after.sigma, before.eps_p, after.eps_p, before.p,
                                                              after.p, dN, elastic_stiffness(m.E, m.nu))
                new = replace(new, plastic=PlasticHistory(after.u, sigma, eps_p, p))
        jumps.update(rate=rate, last=dN, free=free, simulated=jumps["simulated"] + 1,
                     jumps=jumps["jumps"] + (dN > 1), largest=max(jumps["largest"], dN),
                     error=jumps["error_carried"] + float(np.abs(vector).max(initial=0.0)),
                     error_sum=jumps["error_sum"] + err, error_vector=vector,
                     bound=bound, stability_limit=stab, monotone_limit=mono, exceeded=jumps["exceeded"] + (dN > stab),
                     min_stability_limit=min(jumps["min_stability_limit"], stab))
        if dN > stab and jumps["exceeded"] == 1:
            self.say(f"[{scene.name}] WARNING: cycle {cycle}: forced jump {dN} exceeds the stability limit "
                     f"{stab:.4g} cycles: expect oscillating edge spikes")
        return new, {"jump": dN, "bound": bound, "stability_limit": stab, "error": err,
                     "error_total": jumps["error"],
                     "plastic_error_total": jumps["plastic_error"] + jumps["plastic_error_pending"]}

    # Outputs at the end ---------------------------------------------------------------------------------
    def summary(self, error: str | None) -> dict[str, Any]:
        scene, model, state, progress = self.scene, self.model, self.state, self.progress
        problem = self.problem
        summary: dict[str, Any] = {
            "scene": scene.name, "dofs": problem.n_dofs, "contacts": model.contact.nc,
            "delassus_method": problem.operators.delassus_route, **{k: round(v, 6) for k, v in model.timings.items()},
            "increments": state.increment, "cycles": progress.cycle, "converged": error is None,
            "resumed_from_cycle": self.resumed_from_cycle,
            "cycles_this_run": progress.cycle - (self.resumed_from_cycle or 0),
            "local_iterations": state.local_iterations, "wall_time_s": round(time.perf_counter() - self.t_start, 6),
            "wear_law": scene.wear.law, "wear_k": scene.wear.coefficient_total, "wear_acceleration": scene.wear.acceleration,
            "wear_k_effective": self._wear_rate(),
            "equivalent_cycles": progress.cycle * scene.wear.acceleration,
            "dissipated_energy": state.dissipated_energy / model.setup.model_fraction,
            "material_model": scene.material.model,
            "obstacle": "rigid plane (the flat is rigid)" if scene.contact.obstacle == "rigid_plane"
            else f"elastic flat (two deformable bodies of the same material, {scene.contact.sliding}-sliding pairing)",
        }
        if model.contact.two_body:
            share = problem.wear.slave_share if problem.wear is not None else 1.0
            worn = problem.body_wear(state)
            summary.update({"wear_k_slave": scene.wear.coefficient_total * share,
                            "wear_k_master": scene.wear.coefficient_total * (1 - share),
                            "max_wear_depth_slave": float(worn["slave"].max(initial=0.0)),
                            "max_wear_depth_master": float(worn["master"].max(initial=0.0)),
                            "max_relative_tangential": progress.max_relative_tangential,
                            "small_sliding_warning": progress.sliding_warned, "sliding": scene.contact.sliding})
            if problem.operators.surface_compliance is not None:
                loaded = worn["master"] > 0
                along = worn["master_coordinates"][loaded] @ problem.contact.frame[1]
                summary.update({"repairs": problem.sliding.repairs,
                                "master_scar_width": float(np.ptp(along)) if along.size else 0.0})
        if problem.body is not None:
            ps = problem.plastic_state(state)
            local = np.array([ps.p.max(initial=0.0), ps.von_mises().max(initial=0.0)])
            gmax = np.empty(2)
            self.comm.Allreduce(local, gmax, op=MPI.MAX)  # elementwise (the pickle-based max is not)
            summary.update({"max_equivalent_plastic_strain": float(gmax[0]), "max_von_mises": float(gmax[1]),
                            "newton_tangent": scene.solver.newton_tangent,
                            "newton_full_fallbacks": progress.newton_fallbacks,
                            "tangent_refactorizations": problem.body.refactorizations})
            # elastic_shakedown, plastic_shakedown or ratcheting (cycles.csv: every cycle's)
            if scene.loading.cycles > 0:
                summary["plastic_regime_last_cycle"] = progress.plastic_regime
        if scene.loading.cycles > 0:
            summary["cycle_path"] = getattr(self, "cycle_mode", "python")
            if scene.wear.cycle_jump:
                summary["cycle_jump"] = self._jump_summary()
            counts = problem.operators.pattern_counts
            if counts is not None and self.rank0:
                summary["pattern_solves"] = {"accepted": int(counts[0]), "rejected": int(counts[1]),
                                             "factorizations": int(counts[2])}
        if progress.last_row:
            r = progress.last_row
            summary.update({k: r[k] for k in ("normal_force", "tangential_force", "max_pressure", "contact_width",
                                              "stick_width", "max_wear_depth", "wear_area")})
            summary.update({k: int(r[k]) for k in ("n_open", "n_stick", "n_slip")})
            summary["edge_loaded"] = bool(r.get("edge_loaded", 0))
            summary.update(contact_measures(problem, state, model.setup.model_fraction))
            if len(model.contacts) > 1:  # each zone's forces in its own frame (the totals above sum every zone)
                names = [scene.contact.surface, *(zone.surface for zone in scene.zones)]
                summary["zones"] = [{"surface": name, **{k: r[f"zone{i}_{k}"] for k in (
                    "normal_displacement", "normal_force", "tangential_force", "max_pressure", "wear_area")}}
                    for i, name in enumerate(names)]
        if progress.last_cycle_row:
            summary["regime"] = progress.last_cycle_row["regime"]
            if self.writer.description.evolving_friction:   # the coefficient at the last cycle's end (cycles.csv)
                row = progress.last_cycle_row
                summary["friction"] = {key: row[key] for key in row if key in FRICTION_CYCLE_FIELDS or (
                    key.startswith("zone") and key.split("_", 1)[-1] in FRICTION_CYCLE_FIELDS)}
        if model.setup.hertz is not None and progress.last_row:
            radius, E_star, label = model.setup.hertz
            a, p0 = hertz_line_contact(progress.last_row["normal_force"], radius, E_star)
            summary.update({"hertz_reference": label, "hertz_half_width": a, "hertz_max_pressure": p0})
        summary["contact_window"] = model.half_width
        summary["window_growths"] = progress.window_growths
        summary["modelled"] = self._modelled()
        summary["units"] = self.writer.description.units.to_json(model.contact.dim)
        if self.fatigue is not None:
            summary["fatigue"] = self.fatigue.summary()
        if self.size_estimate is not None:  # the estimate made before meshing, to compare with what was built
            summary["size_estimate"] = self.size_estimate.as_dict()
        if error is not None:
            summary["error"] = error
        return summary

    def _jump_summary(self) -> dict[str, Any]:
        """The jumps taken, the error estimate and the stability limits (``summary.cycle_jump``)."""
        scene, jumps = self.scene, self.progress.jump
        finite = lambda v: v if math.isfinite(v) else None  # noqa: E731 - JSON has no infinity
        out = {"simulated_cycles": jumps["simulated"], "jumps": jumps["jumps"],
               "largest_jump": jumps["largest"],
               "wear_error_estimate": jumps["error"], "wear_error_sum_of_bounds": jumps["error_sum"],
               "last_bound": jumps["bound"],
               "stability_limit_last": finite(jumps["stability_limit"]),
               "monotone_limit_last": finite(jumps["monotone_limit"]),
               "stability_limit_min": finite(jumps["min_stability_limit"]),
               "jumps_past_stability_limit": jumps["exceeded"], "forced": scene.wear.jump_forced,
               "bounds": {"wear_fraction": scene.wear.jump_wear_fraction,
                          "pressure_change": scene.wear.jump_pressure_change if scene.wear.jump_tolerance is None
                          else None, "tolerance": scene.wear.jump_tolerance, "max_jump": scene.wear.jump_max}}
        if self.problem.body is not None:
            out["plastic_error_estimate"] = jumps["plastic_error"] + jumps["plastic_error_pending"]
            out["bounds"]["plastic_fraction"] = scene.wear.jump_plastic_fraction
            out["shakedown_strain"] = scene.material.shakedown_strain
        k = self._wear_rate()
        if self.model.setup.hertz is not None and scene.loading.tangential_kind == "displacement" and k > 0:
            _, E_star, _ = self.model.setup.hertz
            out["hertz_estimate_0.37h/(k delta E*)"] = hertz_jump_limit(
                self.model.setup.element_size, k, abs(scene.loading.tangential_amplitude), E_star)
        return out

    def _wear_rate(self, state: ContactState | None = None) -> float:
        """The cycles' wear rate c of ``dg = c p |dx_t|`` (Archard's k or the energy law's alpha mu, times the
        acceleration) of a cycle solved from ``state`` (default: the run's; an evolving friction law's mu there):
        the largest over the contacts, which bounds a jump's stability (the fastest-wearing contact) where zones'
        friction differs under the energy law."""
        state = self.state if state is None else state
        return float(self.problem.wear_coefficients(True, state).max(initial=0.0))

    def _modelled(self) -> dict[str, str]:
        """What this run assembled and iterated, and what it skipped (the scene decides)."""
        scene, model = self.scene, self.model
        contact, body, setup = model.contact, self.problem.body, model.setup
        window = model.half_width
        growths = self.progress.window_growths
        two_body = contact.two_body
        newton = body.describe() if body is not None else None
        return {
            "material": ("J2 plasticity: Newton with the contact inside each iteration, tangent "
                         f"'{scene.solver.newton_tangent}', {newton['iteration']}"
                         if body is not None else "linear elastic: no Newton loop, no plastic state"),
            "delassus": "W of the elastic K built once" + (f"; {newton['delassus']}" if body is not None else ""),
            "friction": self.problem.contacts[0].friction.describe()
                        if scene.contact.mu > 0 or scene.contact.mu_table is not None else
                        "frictionless (mu = 0): normal-only contact, the local problem solved on the normal rows of "
                        "W alone",
            "wear": (self.problem.wear.describe()
                     + (f" (cylinder {scene.wear.slave_share:.3g}, flat {1 - scene.wear.slave_share:.3g} of the "
                        "wear gap)"
                        if two_body else "")
                     + ((", cycle jumps (wear gap and plastic state extrapolated between simulated cycles)"
                         if body is not None else ", cycle jumps (wear gap extrapolated between simulated cycles)")
                        if scene.wear.cycle_jump else "")
                     if scene.wear.law != "none" else "none (wear gap stays zero)"),
            "contact": f"{contact.nc} candidate nodes" + (f" within {window:.4g} mm of the first contact point"
                                                     + (" (automatic: Hertz estimate plus margin"
                                                        + (f", grown {len(growths)} time(s)" if growths else "") + ")"
                                                        if setup.window_automatic else "")
                                                     if window is not None else " (whole contact face)")
                       + setup.contact_text,
            "loads": (f"{scene.loading.cycles} cycles ({getattr(self, 'cycle_mode', 'python')} path)"
                      if scene.loading.cycles > 0 else "preload and a monotonic tangential load")
                     + ("; face pressure load" if PRESSURE_LOAD in self.problem.load_names else "")
                     + ("; bulk stress on the specimen's end" if BULK_STRESS_LOAD in self.problem.load_names else ""),
        }


def run_scene(scene: Scene, out_dir: str | Path, comm: MPI.Comm = MPI.COMM_WORLD, quiet: bool = False,
              resume: bool = False, overwrite: bool = False, ignore_size: bool = False) -> dict[str, Any]:
    """Run a scene and write its outputs into ``out_dir``. Collective.

    Args:
        scene: A validated scene.
        out_dir: Output folder.
        comm: Communicator.
        quiet: Print nothing.
        resume: Continue from ``out_dir/checkpoint.npz`` (the scene may differ only in its ``solver`` and
            ``output`` sections, ``loading.cycles``, ``name`` and ``description``).
        overwrite: Delete the run ``out_dir`` holds first (its files only; :mod:`dolfinx_fretting.outdir`).
        ignore_size: Run even if the size estimate (:func:`dolfinx_fretting.sizes.check_size`) exceeds the
            memory available.

    Returns:
        The summary (also written to ``out_dir/summary.json``).

    Raises:
        SizeError: before any work: the estimated model does not fit in the memory available (and not
            ``ignore_size``); the message names the keys that set its size.
        OutputFolderError: before any work: ``out_dir`` is a file, not writable, locked by another run, or
            holds a run and neither ``resume`` nor ``overwrite`` is given.
        SimulationError: when an increment fails or a result is not finite; the outputs of the converged
            increments (of the last complete cycle in a cyclic run), a checkpoint to resume from and a summary
            with ``converged = false`` and the diagnostic are on disk.
        OutputFolderLost: ``out_dir`` was deleted or replaced during the run (a
            :class:`SimulationError`): found before a write, the run stopped and wrote nothing more.
        RunInterrupted: SIGINT or SIGTERM (main thread only), at any stage: see :mod:`dolfinx_fretting.interrupts`.
    """
    signals = RunSignals()
    signals.install()
    try:
        try:
            with signals.raising():  # nothing to save yet: a signal stops the run at once
                size = check_size(scene, comm, ignore=ignore_size)  # before any mesh: a typo must not eat the machine
        except Interrupted as exc:
            raise RunInterrupted(f"interrupted by {exc} before the run started; nothing was written",
                                 exc.signum) from None
        if comm.rank == 0 and not quiet:
            print(f"[{scene.name}] {size.describe()}", flush=True)
        with claim_output_folder(out_dir, comm, resume=resume, overwrite=overwrite) as lock:  # held to the end
            return _run_scene(scene, Path(out_dir), comm, quiet, resume, size, lock, signals)
    finally:
        signals.restore()


#: The optional outputs drawn after the summary, skipped after a signal (``summary.missing`` lists them):
#: matplotlib's plots (:func:`~dolfinx_fretting.plots.plot_run`) and pyvista's pictures.
PLOTS = "plots"


def _scene_outputs(scene: Scene) -> list[str]:
    """The outputs a run of ``scene`` writes (file names, and :data:`PLOTS` for the plots)."""
    out, cyclic = scene.output, scene.loading.cycles > 0
    names = ["history.csv", *(["cycles.csv", CHECKPOINT] if cyclic else []),
             *(["contact_profiles.csv"] if out.contact_profiles else []), *(["fields.xdmf"] if out.xdmf else []),
             *(["worn_profiles.csv"] if scene.wear.law != "none" else []),
             *([FATIGUE_TABLE] if scene.fatigue.enabled else []),
             *([FATIGUE_XDMF] if scene.fatigue.enabled and out.xdmf else []),
             *(["contact.xdmf"] if out.xdmf and out.contact_profiles else []), *([PLOTS] if out.plots else []),
             *(PICTURES if out.plots and out.xdmf else ())]
    return names


def _interrupted_while_building(scene: Scene, out: Path, comm: MPI.Comm, lock: OutputLock, resume: bool,
                                signum: int) -> RunInterrupted:
    """A signal while the model was built: nothing computed. A fresh run's summary says so and lists every output
    as missing; a resumed run's folder is left as it was (its summary still describes its checkpoint)."""
    name = signal.Signals(signum).name
    error = f"interrupted by {name} while the model was built (mesh, K, W): nothing was computed"
    if resume:
        error += f"; the checkpoint {out / CHECKPOINT} is untouched: continue with --resume"
    else:
        error += f"; start again with --overwrite (summary.json in {out} lists what is missing)"
        if comm.rank == 0 and lock.lost() is None:
            write_json_atomic(out / "summary.json", {
                "scene": scene.name, "increments": 0, "cycles": 0, "converged": False, "error": error,
                "interrupted": name, "interrupted_during": "model", "missing": _scene_outputs(scene)})
    return RunInterrupted(error, signum)


def _run_scene(scene: Scene, out: Path, comm: MPI.Comm, quiet: bool, resume: bool,
               size: SizeEstimate | None, lock: OutputLock, signals: RunSignals) -> dict[str, Any]:
    try:
        with signals.raising():  # meshing, K's factorisation, W: nothing to save, a signal stops at once
            stage_hook("model", signals)  # a test's signal here (interrupts.TEST_HOOK)
            run = _Run(scene, out, comm, quiet, resume, size, lock, signals)
    except Interrupted as exc:
        raise _interrupted_while_building(scene, out, comm, lock, resume, exc.signum) from None
    try:
        return _finish_run(run, scene, out, comm, signals)
    except OutputFolderLost:
        run.writer.close()  # the tables' files went with the folder (or are the replaced folder's: not touched)
        run.problem.destroy()
        raise


def _finish_run(run: _Run, scene: Scene, out: Path, comm: MPI.Comm, signals: RunSignals) -> dict[str, Any]:
    """The load path, then the outputs, with the run's answer to a failed increment, a signal (SIGINT/SIGTERM:
    noted from here on, acted on at the end of an increment or cycle; a signal during the outputs skips the
    plots and pictures) or an output folder that is gone."""
    error = None
    interrupted_during = None
    try:
        run.run_stepwise(preload_path(scene.loading) if scene.loading.cycles > 0 else monotonic_path(scene.loading))
        if scene.loading.cycles > 0:
            run.run_cycles()
    except OutputFolderLost:
        raise
    except SimulationError as exc:
        error = str(exc)
        run.say(f"[{scene.name}] STOPPED: {error}")
        if scene.loading.cycles > 0 and run.state.increment >= scene.loading.normal_increments:
            run.checkpoint()  # the last complete cycle: resume from it with other solver settings
    except _Stop:
        interrupted_during = "increments"
        error = (f"interrupted by {signals.name} after increment {run.state.increment} (cycle {run.progress.cycle}); "
                 "continue with --resume")
        run.checkpoint()
    if run.fatigue is not None and scene.output.xdmf:  # collective: before rank 0's further outputs
        try:
            run.fatigue.write_xdmf()
        except (OSError, RuntimeError, ValueError) as exc:  # fatigue.csv, which it shows, is on disk
            run.say(f"[{scene.name}] WARNING: {FATIGUE_XDMF} not written: {type(exc).__name__}: {exc}")
    run.check_folder(f"{run._done_so_far()}, before its summary")
    summary = run.summary(error)
    if error is None and non_finite_keys(summary):  # never a success with an inf or a NaN in it
        error = f"non-finite results: {', '.join(non_finite_keys(summary))}"
        summary = run.summary(error)
    if signals.received:
        summary["interrupted"] = signals.name
        summary["interrupted_during"] = interrupted_during
    try:
        run.writer.write_summary(summary)
    except OSError:
        run._raise_if_lost("while it wrote its summary")
        raise
    run.note_written()
    if signals.received:
        stage_hook("stopping", signals)  # a test's second signal while the run stops (interrupts.TEST_HOOK)
    missing = _write_further_outputs(run, scene, out, signals) if run.rank0 else []
    run.note_written()
    run.writer.close()
    # Every rank ends alike: a signal on any rank, the folder as rank 0 finds it at the end (rank 0 wrote last).
    signum = comm.allreduce(signals.received, op=MPI.MAX) if comm.size > 1 else signals.received
    run.check_folder(f"{run._done_so_far()}, while it finished its outputs")
    missing = comm.bcast(missing, root=0) if comm.size > 1 else missing
    if signum and not interrupted_during:  # a signal once the results were complete: only outputs are missing
        interrupted_during = "outputs"
        name = signal.Signals(signum).name
        error = error or (f"interrupted by {name} while the outputs were written: the results are complete "
                          f"(summary.json); not written: {', '.join(missing) or 'none'}"
                          + (f"; draw the pictures with python -m dolfinx_fretting.pictures {out}"
                             if any(m in PICTURES for m in missing) else ""))
    if signum or missing:  # what a signal left out, said in the summary (the results' own keys unchanged)
        summary.update(interrupted=signal.Signals(signum).name if signum else None,
                       interrupted_during=interrupted_during, missing=missing)
        if run.rank0:
            run.writer.write_summary(summary)
    force = "N/mm" if run.problem.contact.dim == 2 else "N"
    sizes = (f"contact width = {summary.get('contact_width', 0):.4g} mm, stick width = "
             f"{summary.get('stick_width', 0):.4g} mm" if run.problem.contact.dim == 2 else
             f"contact radius = {summary.get('contact_radius', 0):.4g} mm, stick radius = "
             f"{summary.get('stick_radius', 0):.4g} mm")
    run.say(f"[{scene.name}] {'done' if error is None else 'FAILED'}: {summary['increments']} increments, "
            f"{summary['cycles']} cycles, P = {summary.get('normal_force', 0):.6g} {force}, "
            f"Q = {summary.get('tangential_force', 0):.6g} {force}, p_max = {summary.get('max_pressure', 0):.6g} MPa, "
            f"{sizes}, max wear depth = {summary.get('max_wear_depth', 0):.4g} mm, "
            f"{summary['wall_time_s']:.2f} s -> {out}")
    run.problem.destroy()
    if signum:
        raise RunInterrupted(error, signum)
    if error is not None:
        raise SimulationError(error)
    return summary


def _write_further_outputs(run: _Run, scene: Scene, out: Path, signals: RunSignals) -> list[str]:
    """Rank 0, after the summary: the worn profiles and ``contact.xdmf`` (quick, from the tables), then the plots
    and pictures unless a signal came (or comes while they are drawn: the pictures' process is stopped).
    Nothing is written once the folder is gone (the caller's collective check then stops every rank).

    Returns:
        The outputs the scene asks for that were skipped (:func:`_scene_outputs`' names).
    """
    lost = run.lock.lost if run.lock is not None else (lambda: None)
    if lost() is not None:
        return []
    if scene.wear.law != "none":
        run.writer.write_worn_profiles(run.state)
    if scene.output.xdmf and scene.output.contact_profiles:
        try:
            for zone in range(len(run.model.contacts)):  # contact.xdmf, then contact_zone<i>.xdmf of other zones
                write_contact_xdmf(out, zone)
        except Exception as exc:  # noqa: BLE001 - the CSV it comes from is on disk whatever happens here
            run.say(f"[{scene.name}] WARNING: contact.xdmf not written: {type(exc).__name__}: {exc}")
    if not (scene.output.plots and run.progress.last_row):
        return []
    drawn = scene.output.xdmf
    if signals.received or lost() is not None:
        return [PLOTS, *(PICTURES if drawn else ())]
    try:
        plot_run(out, run.writer.description)
    except Exception as exc:  # noqa: BLE001 - a failed picture must not lose a finished run
        run.say(f"[{scene.name}] WARNING: plots failed: {type(exc).__name__}: {exc}")
    if not drawn:
        return []
    if signals.received or lost() is not None:
        return list(PICTURES)
    stage_hook("pictures", signals, wait=False)  # a test's signal while they are drawn (interrupts.TEST_HOOK)
    # pyvista pictures, in a child process: a VTK failure costs only them; a signal stops it
    pictures = draw_in_subprocess(out, scene.contact.plane_point, scene.contact.plane_normal,
                                  stop=lambda: bool(signals.received) or lost() is not None)
    run.say(f"[{scene.name}] {pictures}")
    return list(PICTURES) if signals.received else []
