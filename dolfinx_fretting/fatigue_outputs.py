"""The scene runner's fatigue outputs: a scene's ``[fatigue]`` evaluated over the run's cycles.

At each evaluated cycle (``fatigue.cycles``: the last, or every n-th and the last) the runner hands the cycle's
kept result to :func:`~dolfinx_fretting.fatigue_fields.fatigue_over_cycle` (the public API, the same call a
script makes) and :class:`FatigueOutputs`:

* appends one row per point of the near-surface region to ``fatigue.csv`` (:data:`TABLE_COLUMNS`: the cycle, its
  equivalent cycles, :data:`~dolfinx_fretting.fatigue.POINT_COLUMNS`, Miner's damage), rank 0, the points in one
  order whatever the partition (by their coordinates);
* with strain-life constants, adds (once those rows are written) the block of cycles since the previous
  evaluation to Miner's sum (:class:`~dolfinx_fretting.fatigue.MinerSum`): the block runs from the cycle after the
  previous evaluation's to the end of this cycle's jump (with cycle jumps: the jump's physical cycles), times
  ``wear.acceleration`` (each simulated cycle stands for that many), at the life this cycle gives;
* keeps the summary (``summary.json["fatigue"]``: :data:`~dolfinx_fretting.fatigue.SUMMARY_FIELDS`, with a
  critical distance :data:`~dolfinx_fretting.fatigue.CRITICAL_DISTANCE_FIELDS`, with constants
  :data:`~dolfinx_fretting.fatigue.MINER_FIELDS`; a value that is not finite, such as an infinite life, is null).

What a checkpoint needs (:meth:`FatigueOutputs.saved`: the damage per point, the cycles summed, ``fatigue.csv``'s
byte size) goes into the run's progress; a resume truncates ``fatigue.csv`` to that size, as the other tables
are, so no row is lost or written twice. Collective: every rank calls every method.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from .fatigue import (CRITICAL_DISTANCE_FIELDS, MINER_FIELDS, POINT_COLUMNS, SUMMARY_FIELDS, BasquinCoffinManson,
                      CriticalDistance, FatemiSocie, MinerSum)
from .fatigue_fields import FatigueResult, fatigue_over_cycle, write_fatigue_xdmf
from .geometries import GEOMETRIES
from .materials import LinearElastic
from .outdir import check_resume_tables
from .scenes import Scene
from .state import CycleResult
from .tables import append_rows, read_rows, write_rows

__all__ = ["FATIGUE_TABLE", "FATIGUE_XDMF", "TABLE_COLUMNS", "xdmf_fields", "FatigueOutputs", "fatigue_arguments",
           "evaluated"]

#: The per-point table of the evaluated cycles.
FATIGUE_TABLE = "fatigue.csv"
#: The same evaluations as fields over the region's cells, for ParaView (:meth:`FatigueOutputs.write_xdmf`).
FATIGUE_XDMF = "fatigue.xdmf"
#: Its columns: the cycle evaluated (simulated), the equivalent cycles reached (the end of its jump, times
#: ``wear.acceleration``), the point's :data:`~dolfinx_fretting.fatigue.POINT_COLUMNS` and Miner's damage
#: summed up to it (blank without strain-life constants).
TABLE_COLUMNS = ("cycle", "equivalent_cycles", *POINT_COLUMNS, "damage")


def xdmf_fields(scene: Scene) -> tuple[str, ...]:
    """The fields of ``fatigue.xdmf`` (columns of :data:`TABLE_COLUMNS`): ``sigma_xx`` and ``swt``; ``fs`` with
    Fatemi–Socie constants; ``life`` and ``damage`` with strain-life constants (without them they are blank)."""
    f = scene.fatigue
    return ("sigma_xx", "swt", *(("fs",) if f.k is not None else ()),
            *(("life", "damage") if f.strain_life else ()))


def fatigue_arguments(scene: Scene) -> dict[str, Any]:
    """The keyword arguments of :func:`~dolfinx_fretting.fatigue_fields.fatigue_over_cycle` a scene's
    ``[fatigue]`` gives (after the problem and the states): ``region``, ``material``, ``fatemi_socie``,
    ``strain_life``, ``angle_step``, ``critical``, ``body`` (``fatigue.body``, or the geometry kind's
    :attr:`~dolfinx_fretting.geometries.base.Geometry.fatigue_body`)."""
    f, m = scene.fatigue, scene.material
    return {"region": f.region, "material": LinearElastic(m.E, m.nu),
            "fatemi_socie": FatemiSocie(f.k, f.yield_stress) if f.k is not None else None,
            "strain_life": BasquinCoffinManson(f.sigma_f, f.b, f.eps_f, f.c, m.E) if f.strain_life else None,
            "angle_step": f.angle_step,
            "critical": CriticalDistance(f.critical_distance, f.method) if f.critical_distance is not None else None,
            "body": f.body if f.body is not None else GEOMETRIES[scene.geometry.kind].fatigue_body}


def evaluated(scene: Scene, cycle: int, last_evaluated: int) -> bool:
    """Whether simulated cycle ``cycle`` is evaluated: the run's last, or (``fatigue.cycles = n``) the first
    simulated cycle at or after the next multiple of n past ``last_evaluated`` (with jumps a multiple may be
    skipped over)."""
    every = scene.fatigue.cycles
    if cycle >= scene.loading.cycles:
        return True
    return every != "last" and cycle >= (last_evaluated // every + 1) * every


def _finite(value: Any) -> Any:
    """A summary number, None where it is not finite (JSON has no inf; an infinite life is no crack)."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def _canonical_order(coordinates: np.ndarray) -> np.ndarray:
    """The points sorted by x, then y, then z, rounded to 1e-9 of the region's extent: the same order whatever
    the partition (a cell's midpoint is computed from its vertices in the order its rank holds them)."""
    scale = float(np.ptp(coordinates, axis=0).max(initial=0.0)) or 1.0
    key = np.round(coordinates / (scale * 1e-9))
    return np.lexsort((key[:, 2], key[:, 1], key[:, 0]))


@dataclass(frozen=True)
class _Evaluation:
    """An evaluated cycle not yet written: its rows (rank 0's; empty elsewhere), Miner's sum with its block (rank
    0's; None without strain-life constants) and the summary it gives."""

    cycle: int
    cycle_end: int
    rows: list[dict[str, Any]]
    miner: MinerSum | None
    summary: dict[str, Any]


class FatigueOutputs:
    """A run's fatigue evaluations, its ``fatigue.csv``, Miner's sum and summary (module docstring). Collective.

    Args:
        scene: The scene (``[fatigue]`` enabled).
        problem: The run's :class:`~dolfinx_fretting.problem.FrettingProblem`.
        out: The output folder.
        saved: :meth:`saved` of the checkpoint resumed from (None: a fresh run, a new ``fatigue.csv``).
        check: The initial state: one call of ``fatigue_over_cycle`` on it refuses a region without points (and
            any other argument the API refuses) before the cycles start.

    Raises:
        ValueError: the region holds no point, or (resume) ``fatigue.csv`` is missing or shorter than the
            checkpoint records (on every rank).
    """

    def __init__(self, scene: Scene, problem, out: Path, saved: dict[str, Any] | None, check) -> None:
        self.scene = scene
        self.problem = problem
        self.comm: MPI.Comm = problem.comm
        self.rank0 = self.comm.rank == 0
        self.path = Path(out) / FATIGUE_TABLE
        self.arguments = fatigue_arguments(scene)
        self.acceleration = float(scene.wear.acceleration)
        started, cpu = time.perf_counter(), time.process_time()
        try:   # collective: the same error on every rank
            # the region's points and cells (fatigue.xdmf maps the table's rows back onto them)
            self.region = fatigue_over_cycle(problem, [check], **self.arguments)
        except ValueError as exc:
            raise ValueError(f"fatigue: {exc}") from None
        saved = dict(saved or {})
        self.last_evaluated = int(saved.get("last_evaluated", 0))
        self.covered = int(saved.get("covered", 0))        # simulated cycles summed into Miner's sum
        self.evaluations = int(saved.get("evaluations", 0))
        self.table_bytes = saved.get("table_bytes")
        self.wall_time = float(saved.get("wall_time_s", 0.0))
        self.cpu_time = float(saved.get("cpu_time_s", 0.0))
        self._summary: dict[str, Any] = dict(saved.get("summary") or {})
        self.miner: MinerSum | None = None
        if self.rank0 and saved.get("damage") is not None:
            initiation = saved.get("initiation")
            self.miner = MinerSum(np.array(saved["damage"], dtype=float), float(saved["cycles_summed"]),
                                  math.inf if initiation is None else float(initiation),
                                  int(saved["initiation_point"]))
        problem_text = None
        if self.rank0:
            if saved:
                problem_text = check_resume_tables(self.path.parent, {self.path.stem: int(self.table_bytes)})
                if problem_text is None:
                    with open(self.path, "r+") as table:
                        table.truncate(int(self.table_bytes))
            else:
                write_rows(self.path, [], TABLE_COLUMNS)
                self.table_bytes = self.path.stat().st_size
        if self.comm.size > 1:
            problem_text = self.comm.bcast(problem_text, root=0)
        if problem_text is not None:
            raise ValueError(f"--resume: {problem_text}")
        self.wall_time += time.perf_counter() - started
        self.cpu_time += time.process_time() - cpu
        #: The last evaluation, until :meth:`write` has written its rows (then counted).
        self._pending: _Evaluation | None = None

    def due(self, cycle: int) -> bool:
        """Whether simulated cycle ``cycle`` is evaluated (:func:`evaluated`)."""
        return evaluated(self.scene, cycle, self.last_evaluated)

    def evaluate(self, cycle: int, result: CycleResult, cycle_end: int) -> FatigueResult:
        """Evaluate simulated cycle ``cycle`` (its result kept, ``run_cycle(..., keep=True)``), whose jump ends at
        cycle ``cycle_end``: its rows, Miner's sum and the summary, held until :meth:`write` has written the rows
        (a cycle that fails, or rows that are not written, leave no damage in the summary or a checkpoint).
        Collective."""
        started, cpu = time.perf_counter(), time.process_time()
        result = fatigue_over_cycle(self.problem, result, **self.arguments)
        parts = self.comm.gather((result.coordinates, result.columns()), root=0)
        summary, miner, rows, error = None, None, [], None
        if self.rank0:
            try:
                summary, miner, rows = self._on_root(parts, result.summary, cycle, cycle_end)
            except ValueError as exc:   # (a resumed damage of another size): raised on every rank below
                error = str(exc)
        if self.comm.size > 1:
            summary, error = self.comm.bcast((summary, error), root=0)
        if error is not None:
            raise ValueError(f"fatigue, cycle {cycle}: {error}")
        self._pending = _Evaluation(cycle, cycle_end, rows, miner, summary)
        self.wall_time += time.perf_counter() - started
        self.cpu_time += time.process_time() - cpu
        return result

    def _on_root(self, parts, api_summary: dict[str, Any], cycle: int,
                 cycle_end: int) -> tuple[dict[str, Any], MinerSum | None, list[dict[str, Any]]]:
        """Rank 0: the points gathered in their canonical order; the summary, Miner's sum with this block and the
        rows (none of them kept yet: :meth:`write`)."""
        coordinates = np.concatenate([part[0] for part in parts])
        columns = {name: np.concatenate([part[1][name] for part in parts]) for name in POINT_COLUMNS}
        order = _canonical_order(coordinates)
        columns = {name: values[order] for name, values in columns.items()}
        summary = {"cycle": cycle, "equivalent_cycles": cycle_end * self.acceleration, "points": int(order.size),
                   **{key: _finite(api_summary[key]) for key in SUMMARY_FIELDS}}
        if self.arguments["critical"] is not None:
            summary.update({key: _finite(api_summary[key]) for key in CRITICAL_DISTANCE_FIELDS})
        damage = np.full(order.size, np.nan)
        miner = None
        if self.arguments["strain_life"] is not None:
            miner = self.miner if self.miner is not None else MinerSum.start(order.size)
            if miner.damage.size != order.size:
                raise ValueError(f"{order.size} points in the region, {miner.damage.size} in the damage "
                                 "resumed from the checkpoint (another mesh or partition rounding)")
            miner = miner.add(columns["life"], (cycle_end - self.covered) * self.acceleration)
            damage = miner.damage
            found = math.isfinite(miner.initiation)
            at = miner.initiation_point
            summary.update({"miner_damage_max": float(damage.max(initial=0.0)),
                            "initiation_cycles": miner.initiation if found else None,
                            "initiation_x": float(columns["x"][at]) if found else None,
                            "initiation_depth": float(columns["depth"][at]) if found else None})
        rows = [{"cycle": cycle, "equivalent_cycles": cycle_end * self.acceleration,
                 **{name: columns[name][i] for name in POINT_COLUMNS}, "damage": damage[i]} for i in range(order.size)]
        return summary, miner, rows

    def write(self) -> None:
        """Append the last evaluation's rows to ``fatigue.csv`` (rank 0; after the runner's folder check), then
        count the evaluation: Miner's sum, the summary and what a checkpoint saves include it from here on, so
        they never report damage for rows that were not written. Every rank calls it."""
        pending, self._pending = self._pending, None
        if pending is None:
            return
        if self.rank0:
            append_rows(self.path, pending.rows, TABLE_COLUMNS)   # an OSError: the previous evaluation stays counted
            self.table_bytes = self.path.stat().st_size
            self.miner = pending.miner if pending.miner is not None else self.miner
        self._summary = pending.summary
        self.last_evaluated, self.covered = pending.cycle, pending.cycle_end
        self.evaluations += 1

    def write_xdmf(self) -> Path | None:
        """Write ``fatigue.xdmf`` (+ ``.h5``) beside ``fatigue.csv``, from it: every evaluated cycle's rows as
        DG0 fields (:func:`xdmf_fields`) on the region's cells, at time = its equivalent cycles (an infinite life,
        blank in the table, is inf). Built anew from the whole table, so a resumed run's file holds every
        evaluation once. Collective: rank 0 reads the table and sends each rank its points' values (the rows
        of an evaluation are the points in :func:`_canonical_order`).

        Returns:
            Its path, or None when the table holds no evaluation yet.

        Raises:
            ValueError: an evaluation's rows are not the region's points (on every rank).
        """
        names = xdmf_fields(self.scene)
        parts = self.comm.gather(self.region.coordinates, root=0)
        chunks, error = None, None
        if self.rank0:
            try:
                chunks = self._rank_values(parts, names)
            except ValueError as exc:
                error = str(exc)
        if self.comm.size > 1:
            error = self.comm.bcast(error, root=0)
        if error is not None:
            raise ValueError(f"fatigue: {FATIGUE_XDMF}: {error}")
        times, values = self.comm.scatter(chunks, root=0) if self.comm.size > 1 else chunks[0]
        if not times:
            return None
        series = [(time, {name: values[name][k] for name in names}) for k, time in enumerate(times)]
        return write_fatigue_xdmf(self.path.with_name(FATIGUE_XDMF), self.problem, self.region.cells, series)

    def _rank_values(self, parts, names) -> list[tuple[list[float], dict[str, np.ndarray]]]:
        """Rank 0: ``fatigue.csv``'s evaluations split by rank: (times, {name: (evaluations, P_rank)}) each."""
        counts = [part.shape[0] for part in parts]
        order = _canonical_order(np.concatenate(parts))
        evaluations: dict[int, list[dict[str, Any]]] = {}
        for row in read_rows(self.path, integers=("cycle",)):
            evaluations.setdefault(row["cycle"], []).append(row)
        cycles = sorted(evaluations)
        times, table = [], {name: np.zeros((len(cycles), order.size)) for name in names}
        for k, cycle in enumerate(cycles):
            mine = evaluations[cycle]
            if len(mine) != order.size:
                raise ValueError(f"cycle {cycle} has {len(mine)} rows, the region {order.size} points")
            times.append(mine[0]["equivalent_cycles"])
            for name in names:
                canonical = np.array([row[name] for row in mine])
                if name == "life":   # blank: an infinite life (strain-life constants given)
                    canonical = np.where(np.isnan(canonical), np.inf, canonical)
                table[name][k, order] = canonical   # row i of the table is point order[i] in rank order
        ends = np.cumsum([0, *counts])
        return [(times, {name: table[name][:, ends[r]:ends[r + 1]] for name in names}) for r in range(len(counts))]

    def saved(self) -> dict[str, Any]:
        """What a checkpoint holds to resume (JSON; the damage and table size rank 0's)."""
        miner = self.miner
        return {"last_evaluated": self.last_evaluated, "covered": self.covered, "evaluations": self.evaluations,
                "table_bytes": self.table_bytes, "wall_time_s": self.wall_time, "cpu_time_s": self.cpu_time,
                "summary": self._summary,
                "damage": miner.damage.tolist() if miner is not None else None,
                "cycles_summed": miner.cycles if miner is not None else 0.0,
                "initiation": _finite(miner.initiation) if miner is not None else None,
                "initiation_point": miner.initiation_point if miner is not None else -1}

    def summary(self) -> dict[str, Any]:
        """``summary.json["fatigue"]``: the last evaluation's numbers (every rank the same), the body evaluated
        (``"slave"`` or ``"master"``), the evaluations made and the time they took (wall and this rank's CPU, s; the runs resumed from included)."""
        fields = [*SUMMARY_FIELDS, *(CRITICAL_DISTANCE_FIELDS if self.arguments["critical"] is not None else ()),
                  *(MINER_FIELDS if self.arguments["strain_life"] is not None else ())]
        values = {"cycle": None, "equivalent_cycles": None, "points": 0, **{key: None for key in fields},
                  **self._summary}
        return {**values, "body": self.arguments["body"], "evaluations": self.evaluations,
                "wall_time_s": round(self.wall_time, 6),
                "cpu_time_s": round(self.cpu_time, 6)}
